// 2-D line segments in pixel coordinates and the geometry the line front end needs.
#pragma once

#include <cmath>
#include <vector>

#include <Eigen/Core>

namespace slslam {

struct LineSegment {
  Eigen::Vector2f start = Eigen::Vector2f::Zero();  ///< (u, v) [px]
  Eigen::Vector2f end = Eigen::Vector2f::Zero();    ///< (u, v) [px]

  float Length() const { return (end - start).norm(); }
  // Direction angle in [0, pi) [rad]: a segment and its reverse have the same angle.
  float Angle() const {
    float a = std::atan2(end.y() - start.y(), end.x() - start.x());
    if (a < 0.0f) a += static_cast<float>(M_PI);
    if (a >= static_cast<float>(M_PI)) a -= static_cast<float>(M_PI);
    return a;
  }
  // Line coefficients (A, B, C) with A u + B v + C = 0 and A^2 + B^2 = 1.
  Eigen::Vector3f Coefficients() const {
    const Eigen::Vector2f d = (end - start).normalized();
    const Eigen::Vector2f n(-d.y(), d.x());
    return {n.x(), n.y(), -n.dot(start)};
  }
  // Distance of a point to the infinite line through the segment [px].
  float DistanceToLine(const Eigen::Vector2f& p) const {
    const Eigen::Vector3f l = Coefficients();
    return std::abs(l.x() * p.x() + l.y() * p.y() + l.z());
  }
};

// Smallest difference of two line angles in [0, pi) (lines have no orientation) [rad].
inline float AngleDifference(float a, float b) {
  const float d = std::abs(a - b);
  return std::min(d, static_cast<float>(M_PI) - d);
}

using Segments = std::vector<LineSegment>;

}  // namespace slslam
