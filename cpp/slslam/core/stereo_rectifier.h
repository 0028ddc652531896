// Stereo rectification of a calibrated, distorted stereo pair (EuRoC-style calibration).
//
// Frames: T_a_b maps coordinates of a point in frame b to frame a (p_a = T_a_b * p_b).
// "left"/"right" are the raw camera frames; "rect" is the rectified left frame, which is the camera
// frame the tracker estimates. R_rect_left rotates raw-left coordinates into it.
#pragma once

#include <utility>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "slslam/core/pinhole_camera.h"

namespace slslam {

class StereoRectifier {
 public:
  // `T_left_right`: pose of the right camera in the left camera frame (4x4 rigid transform,
  // metres). Throws std::invalid_argument on bad intrinsics, a non-rigid transform, differing image
  // sizes or a right camera that is not to the right of the left one (the tracker assumes
  // horizontal stereo).
  StereoRectifier(const RadTanCamera& left, const RadTanCamera& right,
                  const Eigen::Matrix4d& T_left_right);

  // The shared intrinsics of both rectified images.
  const PinholeCamera& rectified_camera() const { return rectified_; }
  // Distance between the rectified optical centres [m].
  double baseline_m() const { return baseline_m_; }
  // Rotation from the raw left camera frame to the rectified left frame.
  const Eigen::Matrix3d& R_rect_left() const { return R_rect_left_; }
  // Rotation from the raw right camera frame to the rectified right frame.
  const Eigen::Matrix3d& R_rectright_right() const { return R_rectright_right_; }

  // Undistorts and rectifies one image pair. Both must be 8-bit single channel with the
  // calibrated size; otherwise std::invalid_argument says which image is wrong.
  std::pair<cv::Mat, cv::Mat> Rectify(const cv::Mat& left, const cv::Mat& right) const;
  // Rectifies one image of the pair (`is_left` chooses the map).
  cv::Mat RectifyOne(const cv::Mat& image, bool is_left) const;

 private:
  PinholeCamera rectified_;
  double baseline_m_ = 0.0;
  Eigen::Matrix3d R_rect_left_ = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d R_rectright_right_ = Eigen::Matrix3d::Identity();
  cv::Mat left_map1_, left_map2_, right_map1_, right_map2_;
};

}  // namespace slslam
