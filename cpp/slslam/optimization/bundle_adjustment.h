// Bundle adjustment over keyframe poses, points and lines (local BA of local mapping) with the
// unified point-line cost and Huber kernels: one robust pass, outlier removal by chi-square, one
// more pass without the outliers (ORB-SLAM3's LocalBundleAdjustment schedule).
#pragma once

#include <atomic>
#include <vector>

#include <Eigen/Core>

#include "slslam/core/rigid3.h"
#include "slslam/geometry/plucker_line.h"
#include "slslam/geometry/reprojection.h"
#include "slslam/inertial/imu_preintegration.h"

namespace slslam {

struct BaPose {
  Rigid3d cam_from_world;  ///< world -> camera
  bool fixed = false;
};

struct BaPointObservation {
  int pose = 0;                                        ///< index into BaProblem::poses
  int point = 0;                                       ///< index into BaProblem::points
  Eigen::Vector3d observed = Eigen::Vector3d::Zero();  ///< (u_left, v, u_right) [px]
  bool stereo = false;
  double sigma_px = 1.0;
};

struct BaLineObservation {
  int pose = 0;
  int line = 0;  ///< index into BaProblem::lines
  Eigen::Vector2d start_px = Eigen::Vector2d::Zero();
  Eigen::Vector2d end_px = Eigen::Vector2d::Zero();
  double sigma_px = 1.0;
};

/// A keyframe's velocity and IMU biases (the body = IMU frame).
struct BaSpeedBias {
  Eigen::Vector3d v_world_body = Eigen::Vector3d::Zero();  ///< [m/s]
  ImuBias bias;
  bool fixed = false;
};

/// The preintegrated IMU between two keyframes (optimization/inertial_factor.h), from pose_i's
/// time to pose_j's, with the speed-bias blocks of the two.
struct BaInertialFactor {
  int pose_i = 0, pose_j = 0;    ///< indices into BaProblem::poses
  int state_i = 0, state_j = 0;  ///< indices into BaInertial::states
  ImuPreintegration pre;
};

/// The IMU terms of a visual-inertial bundle adjustment (none: a visual one).
struct BaInertial {
  Rigid3d body_from_cam;                              ///< the left camera in the IMU frame
  Eigen::Vector3d g_world = Eigen::Vector3d::Zero();  ///< gravity in the world [m/s^2]
  /// Gravity's direction estimated with the rest (its magnitude kept), pulled towards g_world
  /// with this standard deviation per axis across it; 0: held [rad]. The solve writes the
  /// estimate back into g_world.
  double gravity_sigma_rad = 0.0;
  std::vector<BaSpeedBias> states;
  std::vector<BaInertialFactor> factors;
};

struct BaProblem {
  std::vector<BaPose> poses;
  std::vector<Eigen::Vector3d> points;
  std::vector<PluckerLine> lines;
  std::vector<BaPointObservation> point_observations;
  std::vector<BaLineObservation> line_observations;
  BaInertial inertial;
};

struct BundleAdjustmentOptions {
  int robust_iterations = 5;   ///< iterations of the robust pass [-]
  int refine_iterations = 10;  ///< iterations after outlier removal [-]
  double chi2_mono = 5.991;    ///< [-]
  /// outliers after each pass, and the robust pass's Huber bound, of a stereo observation (3
  /// degrees of freedom) [-]
  double chi2_stereo = 7.815;
  double chi2_line = 5.991;         ///< on the two endpoint distances [-]
  double line_angle_weight = 10.0;  ///< [px]
  double line_weight = 1.0;         ///< [-]
  /// Each line's pull towards its value at the start of each pass (in the refine pass: the
  /// robust pass's result), in the tangent of its orthonormal representation (LinePriorCost; the
  /// line anchored at the camera centre of its first observation) [1 / rad]; 0: none, lines
  /// relative to the world's origin. With lines, local BA's Levenberg-Marquardt rejects more than
  /// half its steps and runs to its iteration cap (points alone: almost none rejected, a few steps;
  /// the lines held fixed: almost none rejected): the full Gauss-Newton step raises the cost many
  /// times over, which the pull cures (likely cause: lines that their observers constrain in only
  /// two of four degrees of freedom, as a roadway edge driven along). With `dogleg_with_lines` a
  /// local BA then takes less time; but the pull biases each pass towards its start, and over
  /// three seeds of the hard sequences the drift grew on the dark loop or the bright one
  /// depending on the weight, so both stay off (benchmarks/log/realtime.md).
  double line_prior_weight = 0.0;
  /// Powell's dogleg instead of Levenberg-Marquardt when the problem has lines: a rejected step
  /// costs one evaluation, not a new linear solve (the Schur elimination, most of a solve). Use
  /// it with line_prior_weight > 0: without the pull its Gauss-Newton steps fail (above). Problems
  /// of points alone keep Levenberg-Marquardt [-]
  bool dogleg_with_lines = false;
  /// Each line moves only in the directions of its orthonormal tangent that its observations
  /// determine: the eigenvectors of its information (the sum of J^T J over its observations'
  /// residuals in sigmas, the poses held, recomputed at the start of each pass) with an
  /// eigenvalue of at least this; it is held in the others (LineSubspaceManifold) [1 / rad^2].
  /// Nearly every line of a local window has a direction its observers barely see (cameras
  /// driven along a roadway edge: the smallest eigenvalue is below 10 for almost all of them),
  /// and their free steps there make Levenberg-Marquardt reject most of its steps
  /// (benchmarks/log/realtime.md). 0: every line free in all four directions.
  double line_min_information_per_rad2 = 0.0;
  /// true: each pass solved by this library's own Levenberg-Marquardt with the landmarks
  /// eliminated (schur_levenberg_marquardt.h: Ceres' trust-region rules on the same costs, no
  /// Ceres problem, a dense reduced system over the free poses); false: by Ceres (SPARSE_SCHUR).
  /// On the local BAs of the dark dusty loop both take as many steps, to the same cost within
  /// 1e-6 in most, and the own solver takes several times less time (benchmarks/log/realtime.md).
  /// The own solver takes only problems of at most 64 free poses without the pull, the dogleg,
  /// held line directions above or IMU factors; Ceres solves the others (a large map's global
  /// BA) [-]
  bool own_solver = true;

  void Check() const;
};

struct BundleAdjustmentReport {
  std::vector<bool> point_outlier;  ///< per point observation, after the solve
  std::vector<bool> line_outlier;   ///< per line observation
  double initial_cost = 0.0;
  double final_cost = 0.0;
  bool solved = false;
  bool interrupted = false;  ///< `interrupt` stopped it early (the estimate is still usable)
  int iterations = 0;        ///< trust-region steps tried, both passes (Ceres' iterations) [-]
  int rejected_steps = 0;    ///< of which rejected: the cost rose, the step was undone [-]
};

// Optimises the problem in place (poses that are not fixed, every point and line observed at
// least once). Deterministic (single-threaded Ceres, Schur solver).
// `abort`, when given, is polled between iterations: once true the solve stops and the report is
// not solved (a background global BA that a newer correction made stale).
// `interrupt`, when given, is polled between iterations too: once true the current pass ends at
// its last accepted iterate, outliers are classified there and no further pass runs; the result
// is solved and usable (ORB-SLAM's stop flag of local BA: a newer keyframe is waiting). Set
// before the first pass took a step, the report is interrupted and not solved: nothing moved.
BundleAdjustmentReport SolveBundleAdjustment(const StereoRig& rig, BaProblem* problem,
                                             const BundleAdjustmentOptions& options = {},
                                             const std::atomic<bool>* abort = nullptr,
                                             const std::atomic<bool>* interrupt = nullptr);

}  // namespace slslam
