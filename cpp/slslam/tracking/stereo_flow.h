// The camera's motion between two consecutive stereo frames from optical flow: corners of the
// previous left image tracked into its right image (depth) and into the current left image
// (pyramidal Lucas-Kanade, each track checked backwards), the motion from PnP RANSAC on them.
// It needs no descriptor to match, so it follows the faint, smooth shading of a lining's relief
// on which descriptor matching finds next to nothing (benchmarks/log/inertial.md, the relief
// branch). The inertial estimator takes it as the body's velocity while the tracker carries
// frames on the IMU.
#pragma once

#include <optional>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "slslam/core/rigid3.h"
#include "slslam/core/stereo_rig.h"

namespace slslam {

struct StereoFlowMotion {
  Rigid3d cur_from_prev;  ///< the current camera from the previous one
  /// of cur_from_prev: rotation (R -> Exp(dtheta) R) [rad^2], then translation [m^2]
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Identity();
  int inliers = 0;  ///< PnP inliers [-]
};

// The motion of the left camera from (left_prev, right_prev) to left_cur (8-bit grey, rectified,
// `rig`'s size); nullopt with fewer than `min_inliers` inliers or when a solve fails.
std::optional<StereoFlowMotion> MeasureStereoFlow(const cv::Mat& left_prev,
                                                  const cv::Mat& right_prev,
                                                  const cv::Mat& left_cur, const StereoRig& rig,
                                                  int min_inliers);

}  // namespace slslam
