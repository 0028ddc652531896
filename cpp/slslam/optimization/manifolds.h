// Ceres manifolds for camera poses (SE(3), 7 ambient / 6 tangent) and map lines (orthonormal
// representation, 5 ambient / 4 tangent).
//
// The cost functions in cost_functions.h give analytic Jacobians with respect to the tangent
// increment directly, written into the first tangent-size columns of the ambient Jacobian (the rest
// zero). The manifolds' PlusJacobian is correspondingly [I; 0], so Ceres' product
// J_ambient * PlusJacobian is exactly the analytic tangent Jacobian. This is the usual way of
// feeding Lie-group Jacobians to Ceres; it means these manifolds only pair with these costs.
#pragma once

#include <ceres/manifold.h>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "slslam/core/rigid3.h"
#include "slslam/geometry/plucker_line.h"

namespace slslam {

// Pose parameter block layout: [tx, ty, tz, qx, qy, qz, qw] of cam_from_world (x_c = R x_w + t).
constexpr int kPoseSize = 7;
constexpr int kPoseTangentSize = 6;
// Line parameter block layout: [qx, qy, qz, qw, phi] of the orthonormal representation.
constexpr int kLineSize = 5;
constexpr int kLineTangentSize = 4;

void PoseToParameters(const Rigid3d& cam_from_world, double* params);
void ParametersToPose(const double* params, Rigid3d* cam_from_world);
void LineToParameters(const OrthonormalLine& line, double* params);
OrthonormalLine ParametersToLine(const double* params);

// Plus(x, delta): R <- Exp(omega) R, t <- Exp(omega) t + rho for delta = (rho, omega).
class PoseManifold final : public ceres::Manifold {
 public:
  int AmbientSize() const override { return kPoseSize; }
  int TangentSize() const override { return kPoseTangentSize; }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override;
  bool PlusJacobian(const double* x, double* jacobian) const override;
  bool Minus(const double* y, const double* x, double* y_minus_x) const override;
  bool MinusJacobian(const double* x, double* jacobian) const override;
};

// Plus(x, delta): U <- U Exp(theta), phi <- phi + dphi for delta = (theta, dphi).
class LineManifold final : public ceres::Manifold {
 public:
  int AmbientSize() const override { return kLineSize; }
  int TangentSize() const override { return kLineTangentSize; }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override;
  bool PlusJacobian(const double* x, double* jacobian) const override;
  bool Minus(const double* y, const double* x, double* y_minus_x) const override;
  bool MinusJacobian(const double* x, double* jacobian) const override;
};

// A line that moves only within a subspace of LineManifold's tangent: Plus(x, delta) =
// LineManifold::Plus(x, B delta) for the 4 x m orthonormal `basis` B (1 <= m <= 4), and
// Minus(y, x) = B^T LineManifold::Minus(y, x). PlusJacobian is [B; 0] (the costs' Jacobians are
// tangent Jacobians in the first four ambient columns, as for LineManifold). Bundle adjustment
// holds a line's directions that its observations leave undetermined with it
// (BundleAdjustmentOptions::line_min_information_per_rad2).
class LineSubspaceManifold final : public ceres::Manifold {
 public:
  using Basis = Eigen::Matrix<double, kLineTangentSize, Eigen::Dynamic>;
  explicit LineSubspaceManifold(const Basis& basis);
  int AmbientSize() const override { return kLineSize; }
  int TangentSize() const override { return static_cast<int>(basis_.cols()); }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override;
  bool PlusJacobian(const double* x, double* jacobian) const override;
  bool Minus(const double* y, const double* x, double* y_minus_x) const override;
  bool MinusJacobian(const double* x, double* jacobian) const override;

 private:
  Basis basis_;
};

}  // namespace slslam
