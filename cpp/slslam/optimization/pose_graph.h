// Pose-graph optimisation of keyframe poses: relative SE(3) constraints between keyframes, solved
// in Ceres. One solver for both back ends: the visual one (ORB-SLAM's essential graph for loop
// closing and map merging: spanning tree, strong covisibility and loop edges, one scalar weight
// each) and the LiDAR one (odometry and Scan Context loop edges, each with a 6x6 information and
// the loops under a Cauchy loss, bindings/bind_lidar_slam.cpp).
//
// Stereo and LiDAR fix the scale, so the graph is SE(3), not Sim(3) as in monocular ORB-SLAM.
// With PoseGraphOptions::yaw_and_position_only the poses move in 4 DoF only (ORB-SLAM3's
// visual-inertial essential graph: gravity makes roll and pitch observable, so they stay).
#pragma once

#include <optional>
#include <vector>

#include <Eigen/Core>

#include "slslam/core/rigid3.h"
#include "slslam/optimization/bundle_adjustment.h"

namespace slslam {

// A measured relative pose between keyframes a and b: a_from_b = a_from_world * world_from_b
// (x_a = a_from_b * x_b), and how much to trust it.
//
// The error of an edge compares the estimated a_from_b (from the two poses) with the measured one.
// Without `information` it is the split error (t_est - t_ab [m] in frame a, then the rotation error
// 2 vec(q_ab^-1 q_est) ~ Log(R_ab^T R_est) [rad] in frame b) weighted by sqrt(weight) /
// translation_sigma_m and sqrt(weight) / rotation_sigma_rad (the visual loop closer's edges). With
// `information` it is the left tangent d = (rho [m], omega [rad]) of the estimate against the
// measurement, both in frame a, translation first: estimated = [Exp(omega) | rho] * measured, i.e.
// omega = Log(R_est R_ab^T), rho = t_est - Exp(omega) t_ab (PoseManifold's Plus / Minus and the
// tracker's PosePrior use the same tangent), and the cost is 1/2 d^T information d.
// LeftTangentInformation converts an information of the split error to this one.
struct PoseGraphEdge {
  int a = 0;  ///< index into the pose vector
  int b = 0;
  Rigid3d a_from_b;     ///< identity unless set
  double weight = 1.0;  ///< information scale of the split error, without `information` [-]
  /// Information of the left tangent (rho, omega) [1/m^2, 1/(m rad), 1/rad^2]; symmetric
  /// positive semi-definite. Unset: the split error with `weight` and the options' sigmas.
  std::optional<Eigen::Matrix<double, 6, 6>> information;
  /// > 0: the edge's squared whitened error s goes through a Cauchy loss c^2 log(1 + s / c^2) of
  /// this scale c (whitened units), so one wrong loop cannot bend the graph; 0: least squares [-].
  double cauchy_scale = 0.0;
};

struct PoseGraphOptions {
  int max_iterations = 20;            ///< Levenberg-Marquardt iterations [-]
  double rotation_sigma_rad = 0.01;   ///< rotation error of one split-error edge [rad]
  double translation_sigma_m = 0.01;  ///< translation error of one split-error edge [m]
  /// 4 DoF: every free pose turns only about `gravity_in_world` (yaw) and moves in position; its
  /// roll and pitch (the gravity direction seen from the camera) stay at their initial values.
  /// false: 6 DoF.
  bool yaw_and_position_only = false;
  /// Gravity (or any vertical) direction in the world frame, for yaw_and_position_only; any
  /// length > 0 (only the axis counts) [-].
  Eigen::Vector3d gravity_in_world = Eigen::Vector3d(0.0, 0.0, -1.0);

  void Check() const;
};

struct PoseGraphReport {
  double initial_cost = 0.0;
  double final_cost = 0.0;
  int iterations = 0;
  bool solved = false;
};

// Optimises the non-fixed poses (cam_from_world each, or any sensor_from_world) in place. Edges
// must index valid poses; at least one pose should be fixed (otherwise the graph floats and only
// relative poses are meaningful). Throws std::invalid_argument on a bad edge or option.
PoseGraphReport OptimizePoseGraph(std::vector<BaPose>* poses,
                                  const std::vector<PoseGraphEdge>& edges,
                                  const PoseGraphOptions& options = {});

// a_from_b from two poses a_from_world, b_from_world: rotation R_aw R_bw^T, then translation
// t_aw - R_ab t_bw with the rotation just formed (not a_from_world * b_from_world.Inverse(), which
// rounds differently).
Rigid3d RelativePose(const Rigid3d& a_from_world, const Rigid3d& b_from_world);

// The information of an edge's left tangent (rho, omega) from an information of its split error
// e = (t_est - t_ab in frame a, Log(R_ab^T R_est)) (the LiDAR back end's edges, translation first):
// e = J d to first order with J = [I, -[t_ab]x; 0, R_ab^T], so the cost e^T information e is
// d^T (J^T information J) d.
Eigen::Matrix<double, 6, 6> LeftTangentInformation(
    const Rigid3d& a_from_b, const Eigen::Matrix<double, 6, 6>& split_information);

}  // namespace slslam
