// Small helpers shared by the tracker's source files (tracker*.cpp); not part of the API.
#pragma once

#include <chrono>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "slslam/core/pinhole_camera.h"

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

// The (2w+1) x (2w+1) float patch of an 8-bit image centred on (u, v), bilinear, with `scale`
// pixels of the image per patch pixel; empty when it does not fit inside the image.
cv::Mat SamplePatch(const cv::Mat& image, double u, double v, int w, double scale = 1.0);

// Aligns `patch` (SamplePatch's, w from its size) to `image` around (u, v), the patch spanning
// `scale` image pixels per patch pixel: Gauss-Newton on the zero-mean difference (a brightness
// offset between the two drops out), at most 10 steps. True with (u, v) moved to the alignment
// when it converged on texture (both eigenvalues of the normal matrix large enough) and the two
// patches correlate (zero-mean NCC >= min_ncc).
bool AlignPatch(const cv::Mat& image, const cv::Mat& patch, double scale, double min_ncc,
                double* u, double* v);

}  // namespace slslam::tracker_detail
