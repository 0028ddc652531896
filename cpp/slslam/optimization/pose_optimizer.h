// Motion-only bundle adjustment (tracking): the pose of one stereo frame against fixed map points
// and map lines, with the unified point-line cost, Huber kernels and ORB-SLAM3's outlier rounds
// (optimise, classify every observation by its chi-square, drop outliers, optimise again; the
// kernel is removed in the last round).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "slslam/core/rigid3.h"
#include "slslam/geometry/plucker_line.h"
#include "slslam/geometry/reprojection.h"

namespace slslam {

struct PointObservation {
  Eigen::Vector3d point_w = Eigen::Vector3d::Zero();   ///< map point [m]
  Eigen::Vector3d observed = Eigen::Vector3d::Zero();  ///< (u_left, v, u_right) [px]
  bool stereo = false;                                 ///< false: u_right is ignored
  double sigma_px = 1.0;                               ///< measurement standard deviation [px]
};

struct LineObservation {
  PluckerLine line_w;                                  ///< map line (world frame)
  Eigen::Vector2d start_px = Eigen::Vector2d::Zero();  ///< observed segment, left image [px]
  Eigen::Vector2d end_px = Eigen::Vector2d::Zero();
  double sigma_px = 1.0;  ///< standard deviation of the endpoint distances [px]
};

struct PoseOptimizerOptions {
  int rounds = 4;                   ///< optimise-classify rounds [-]
  int iterations_per_round = 10;    ///< Levenberg-Marquardt iterations per round [-]
  int robust_rounds = 3;            ///< rounds that use the Huber kernel (the rest use none) [-]
  double chi2_mono = 5.991;         ///< inlier bound, 2 residuals (95 %, as ORB-SLAM3) [-]
  double chi2_stereo = 7.815;       ///< inlier bound, 3 residuals [-]
  double chi2_line = 5.991;         ///< inlier bound on the two endpoint distances [-]
  double line_angle_weight = 10.0;  ///< scale of the bounded angle term e3 [px]
  double line_weight = 1.0;         ///< weight of the line terms against the point terms [-]
  /// true: each round solved by this library's 6-parameter Levenberg-Marquardt (Ceres' rules on
  /// the same costs, faster: there is no problem to build); false: by Ceres. The two agree within
  /// the spread of simulator seeds on the long sequences (benchmarks/log/realtime.md).
  bool own_solver = true;

  void Check() const;
};

// A Gaussian prior on the pose (the visual-inertial tracker's IMU prediction): the cost
// 1/2 d^T information d with d the left tangent (rho, omega) of cam_from_world against `mean`
// (optimization/manifolds.h), added to every round without a robust kernel.
struct PosePrior {
  Rigid3d mean;  ///< cam_from_world
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
};

struct PoseOptimizerResult {
  Rigid3d cam_from_world;          ///< world -> camera
  std::vector<bool> point_inlier;  ///< per input point observation
  std::vector<bool> line_inlier;   ///< per input line observation
  int point_inliers = 0;
  int line_inliers = 0;
  bool success = false;  ///< false: too few usable observations, the pose is the initial one
  /// With a prior: the Gauss-Newton information of the left tangent at the result (the inlier
  /// observations without kernel, plus the prior); zero otherwise.
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
};

// Optimises cam_from_world from an initial guess. Observations of landmarks behind the camera at
// the start count as outliers. Deterministic (one thread). With a prior the pose is determined
// even by fewer than three observations (success then needs one inlier).
PoseOptimizerResult OptimizePose(const StereoRig& rig, const Rigid3d& cam_from_world,
                                 const std::vector<PointObservation>& points,
                                 const std::vector<LineObservation>& lines,
                                 const PoseOptimizerOptions& options = {},
                                 const PosePrior* prior = nullptr);

}  // namespace slslam
