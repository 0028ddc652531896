// Small helpers shared by the tracker's source files (tracker*.cpp); not part of the API.
#pragma once

#include <chrono>
#include <cmath>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "slslam/core/pinhole_camera.h"
#include "slslam/features/image_patch.h"
#include "slslam/features/stereo_frame.h"

namespace slslam::tracker_detail {

using Clock = std::chrono::steady_clock;

// Milliseconds since `since`.
inline double Ms(Clock::time_point since) {
  return std::chrono::duration<double, std::milli>(Clock::now() - since).count();
}

// One descriptor row of the same type and width as the rows of `rows`.
inline bool SameKind(const cv::Mat& descriptor, const cv::Mat& rows) {
  return descriptor.rows == 1 && descriptor.cols == rows.cols && descriptor.type() == rows.type();
}

inline bool InImage(const PinholeCamera& camera, const Eigen::Vector2d& uv, double margin = 0.0) {
  return uv.x() >= -margin && uv.y() >= -margin && uv.x() <= camera.width - 1 + margin &&
         uv.y() <= camera.height - 1 + margin;
}

// (u_left, v, u_right) of keypoint k as an observation: at `refined` when that is finite (the
// stereo column moved by as much as the keypoint, a keypoint without one keeps -1), else as
// detected.
inline Eigen::Vector3d ObservedPixel(const StereoFrame& frame, int k,
                                     const Eigen::Vector2f& refined) {
  const double u = frame.keypoints.uv(k, 0), v = frame.keypoints.uv(k, 1);
  const double u_right = frame.u_right[k];
  if (!std::isfinite(refined.x())) return {u, v, u_right};
  return {refined.x(), refined.y(), u_right >= 0.0 ? u_right + (refined.x() - u) : u_right};
}

// (features/image_patch.h: the patches are sampled by local mapping too)
using ::slslam::SampleGrid;
using ::slslam::SamplePatch;

// Aligns `patch` (SamplePatch's, w from its size) to `image` around (u, v), the patch spanning
// `scale` image pixels per patch pixel: Gauss-Newton on the zero-mean difference (a brightness
// offset between the two drops out), at most 10 steps. True with (u, v) moved to the alignment
// when it converged on texture (both eigenvalues of the normal matrix large enough) and the two
// patches correlate (zero-mean NCC >= min_ncc).
bool AlignPatch(const cv::Mat& image, const cv::Mat& patch, double scale, double min_ncc, double* u,
                double* v);

// The offset (even integers within +-radius_px) of (u, v) where `patch` (SamplePatch's)
// correlates best with `image` (zero-mean NCC on every other patch pixel, the patch spanning
// `scale` image pixels per patch pixel): (u, v) moved there, the NCC returned (-1 when no offset
// fits the image or the patch is flat). A coarse start for AlignPatch when the prediction may be
// further off than its reach (TrackerOptions::projected_max_frames).
double SearchPatch(const cv::Mat& image, const cv::Mat& patch, double scale, int radius_px,
                   double* u, double* v);

}  // namespace slslam::tracker_detail
