// Small rotation helpers shared by the geometry and optimisation code: skew matrix and the SO(3)
// exponential / logarithm (Rodrigues).
#pragma once

#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace slslam {

// [w]x: Skew(w) * a == w.cross(a).
inline Eigen::Matrix3d Skew(const Eigen::Vector3d& w) {
  Eigen::Matrix3d s;
  s << 0.0, -w.z(), w.y(), w.z(), 0.0, -w.x(), -w.y(), w.x(), 0.0;
  return s;
}

// Rotation by the angle-axis vector w (|w| = angle [rad]).
inline Eigen::Matrix3d ExpSO3(const Eigen::Vector3d& w) {
  const double angle = w.norm();
  if (angle < 1e-10) return Eigen::Matrix3d::Identity() + Skew(w);
  return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
}

inline Eigen::Quaterniond ExpQuaternion(const Eigen::Vector3d& w) {
  const double angle = w.norm();
  if (angle < 1e-10) {
    return Eigen::Quaterniond(1.0, 0.5 * w.x(), 0.5 * w.y(), 0.5 * w.z()).normalized();
  }
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, w / angle));
}

// Angle-axis vector of a rotation (inverse of ExpSO3 for angles below pi).
inline Eigen::Vector3d LogSO3(const Eigen::Quaterniond& q) {
  Eigen::AngleAxisd aa(q.normalized());
  double angle = aa.angle();
  Eigen::Vector3d axis = aa.axis();
  if (angle > M_PI) {
    angle = 2.0 * M_PI - angle;
    axis = -axis;
  }
  return angle * axis;
}

}  // namespace slslam
