// Pose-graph optimisation of keyframe poses (ORB-SLAM's essential graph for loop closing and map
// merging): relative SE(3) constraints between keyframes (spanning tree, strong covisibility,
// loop edges), solved in Ceres with the poses as quaternion + translation.
//
// Stereo fixes the scale, so the graph is SE(3), not Sim(3) as in monocular ORB-SLAM.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "slslam/core/rigid3.h"
#include "slslam/optimization/bundle_adjustment.h"

namespace slslam {

// A measured relative pose between keyframes a and b: a_from_b = a_from_world * world_from_b
// (x_a = a_from_b * x_b).
struct PoseGraphEdge {
  int a = 0;  ///< index into the pose vector
  int b = 0;
  Rigid3d a_from_b;     ///< identity unless set
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

// a_from_b from two poses a_from_world, b_from_world: rotation R_aw R_bw^T, then translation
// t_aw - R_ab t_bw with the rotation just formed (not a_from_world * b_from_world.Inverse(), which
// rounds differently).
Rigid3d RelativePose(const Rigid3d& a_from_world, const Rigid3d& b_from_world);

}  // namespace slslam
