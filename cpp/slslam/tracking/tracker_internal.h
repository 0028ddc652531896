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

}  // namespace slslam::tracker_detail
