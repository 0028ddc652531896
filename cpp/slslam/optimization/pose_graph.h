// Pose-graph optimisation of keyframe poses (ORB-SLAM's essential graph for loop closing and map
// merging): relative SE(3) constraints between keyframes (spanning tree, strong covisibility,
// loop edges), solved in Ceres with the poses as quaternion + translation.
//
// Stereo fixes the scale, so the graph is SE(3), not Sim(3) as in monocular ORB-SLAM.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "slslam/optimization/bundle_adjustment.h"

namespace slslam {

// Measured T_a_b = T_a_w * T_w_b (x_a = R_ab x_b + t_ab) between keyframes a and b.
struct PoseGraphEdge {
  int a = 0;  ///< index into the pose vector
  int b = 0;
  Eigen::Matrix3d R_ab = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t_ab = Eigen::Vector3d::Zero();
  double weight = 1.0;  ///< information scale of the edge [-]
};

struct PoseGraphOptions {
  int max_iterations = 20;            ///< Levenberg-Marquardt iterations [-]
  double rotation_sigma_rad = 0.01;   ///< rotation error of one edge [rad]
  double translation_sigma_m = 0.01;  ///< translation error of one edge [m]

  void Check() const;
};

struct PoseGraphReport {
  double initial_cost = 0.0;
  double final_cost = 0.0;
  int iterations = 0;
  bool solved = false;
};

// Optimises the non-fixed poses (cam_from_world each) in place. Edges must index valid poses; at
// least one pose should be fixed (otherwise the graph floats and only relative poses are
// meaningful).
PoseGraphReport OptimizePoseGraph(std::vector<BaPose>* poses,
                                  const std::vector<PoseGraphEdge>& edges,
                                  const PoseGraphOptions& options = {});

// T_a_b from two poses T_a_w, T_b_w.
void RelativePose(const Eigen::Matrix3d& R_aw, const Eigen::Vector3d& t_aw,
                  const Eigen::Matrix3d& R_bw, const Eigen::Vector3d& t_bw, Eigen::Matrix3d* R_ab,
                  Eigen::Vector3d* t_ab);

}  // namespace slslam
