// Ceres cost functions of the unified point-line cost (SPEC A5 eq. 17) with analytic Jacobians.
// Residuals are whitened by 1 / sigma (pixels); pose blocks use PoseManifold, line blocks use
// LineManifold (see manifolds.h for the Jacobian layout). Evaluate returns false when a landmark
// falls behind the camera, which makes Ceres reject that step.
#pragma once

#include <ceres/sized_cost_function.h>
#include <Eigen/Core>

#include "slslam/geometry/reprojection.h"
#include "slslam/optimization/manifolds.h"

namespace slslam {

// Monocular point: parameters pose (7), point (3); residual 2.
class PointCost final : public ceres::SizedCostFunction<2, kPoseSize, 3> {
 public:
  PointCost(const PinholeCamera& camera, const Eigen::Vector2d& observed_px, double sigma_px);
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  PinholeCamera camera_;
  Eigen::Vector2d observed_;
  double inv_sigma_;
};

// Stereo point: parameters pose (7), point (3); residual 3 (u_left, v, u_right).
class StereoPointCost final : public ceres::SizedCostFunction<3, kPoseSize, 3> {
 public:
  StereoPointCost(const StereoRig& rig, const Eigen::Vector3d& observed, double sigma_px);
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  StereoRig rig_;
  Eigen::Vector3d observed_;
  double inv_sigma_;
};

// Line segment: parameters pose (7), line (5); residual 3 (e1, e2, e3 of LineResidual).
class LineCost final : public ceres::SizedCostFunction<3, kPoseSize, kLineSize> {
 public:
  LineCost(const PinholeCamera& camera, const Eigen::Vector2d& start_px,
           const Eigen::Vector2d& end_px, double angle_weight, double sigma_px);
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  PinholeCamera camera_;
  Eigen::Vector2d start_;
  Eigen::Vector2d end_;
  double angle_weight_;
  double inv_sigma_;
};

}  // namespace slslam
