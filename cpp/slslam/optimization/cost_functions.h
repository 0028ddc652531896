// Ceres cost functions of the unified point-line cost (SL-SLAM paper, eq. 17) with analytic
// Jacobians. Residuals are whitened by 1 / sigma (pixels); pose blocks use PoseManifold, line
// blocks use LineManifold (see manifolds.h for the Jacobian layout). Evaluate returns false when a
// landmark falls behind the camera, which makes Ceres reject that step.
#pragma once

#include <array>

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

// One half of a stereo point observation: parameters pose (7), point (3); residual 2, half 0 =
// (u_left, v), half 1 = (u_right, 0). Both halves together are StereoPointCost's rows plus a zero
// row, the same least-squares problem; but every point block then has two rows, which lets Ceres'
// Schur eliminator use its fixed-size <2, 3, 6> kernel (blocks of 2 and 3 rows make it fall back
// to dynamic sizes, which made local BA's linear solver slower: benchmarks/log/realtime.md). A
// robust loss on each half would act on that half alone: bundle adjustment uses the halves
// without one (its refine pass).
class StereoPointHalfCost final : public ceres::SizedCostFunction<2, kPoseSize, 3> {
 public:
  StereoPointHalfCost(const StereoRig& rig, const Eigen::Vector3d& observed, double sigma_px,
                      int half);
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  StereoPointCost whole_;
  int row_;  ///< the first of the half's rows of StereoPointCost: 0 or 2
};

// Line segment: parameters pose (7), line (5); residual 3 (e1, e2, e3 of LineResidual).
// The line parameters hold the line as seen from `anchor_world` (a world point, the origin by
// default): the world line is that line moved by +anchor (n_world = n + anchor x v). Bundle
// adjustment with BundleAdjustmentOptions::line_prior_weight > 0 anchors each line at a camera
// that observes it, so the orthonormal representation's angle phi = atan(1 / distance) stays
// away from 0 wherever the map has gone, and the pull's tangent means about the same everywhere.
class LineCost final : public ceres::SizedCostFunction<3, kPoseSize, kLineSize> {
 public:
  LineCost(const PinholeCamera& camera, const Eigen::Vector2d& start_px,
           const Eigen::Vector2d& end_px, double angle_weight, double sigma_px,
           const Eigen::Vector3d& anchor_world = Eigen::Vector3d::Zero());
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  PinholeCamera camera_;
  Eigen::Vector2d start_;
  Eigen::Vector2d end_;
  double angle_weight_;
  double inv_sigma_;
  Eigen::Vector3d anchor_;
};

// A line's pull towards a reference value of its parameters, in the line manifold's tangent:
// residual 4 = weight * Minus(line, reference) [weight / rad]. Bundle adjustment gives every line
// one towards its value at the start of each pass when BundleAdjustmentOptions::line_prior_weight
// > 0: it bounds the Gauss-Newton step along directions the observations leave (nearly) free,
// which otherwise made most trust-region steps fail (benchmarks/log/realtime.md).
class LinePriorCost final : public ceres::SizedCostFunction<4, kLineSize> {
 public:
  LinePriorCost(const double* reference, double weight);
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  std::array<double, kLineSize> reference_;
  double weight_;
};

}  // namespace slslam
