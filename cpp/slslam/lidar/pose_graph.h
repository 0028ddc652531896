// Keyframe pose graph of the LiDAR SLAM back end: odometry edges between consecutive keyframes
// and loop edges from verified Scan Context matches, each a relative pose T_a_b with a 6x6
// information, optimised in Ceres (loops under a Cauchy loss, so one bad loop cannot bend the
// whole graph). The first keyframe is held fixed.
#pragma once

#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace slslam::lidar {

struct LidarPoseGraphEdge {
  int a = 0, b = 0;  ///< keyframe indices
  Eigen::Matrix4d T_a_b = Eigen::Matrix4d::Identity();
  // Information of the error (translation [m], rotation [rad]) in frame a; identity weights
  // both equally.
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Identity();
  bool loop = false;  ///< loop edges get the robust loss
};

struct LidarPoseGraphOptions {
  int max_iterations = 50;         ///< Levenberg-Marquardt iterations [-]
  double loop_cauchy_scale = 1.0;  ///< Cauchy scale of loop residuals (whitened units) [-]
  void Check() const;
};

struct LidarPoseGraphResult {
  std::vector<Eigen::Matrix4d> T_world_keyframe;
  double initial_cost = 0.0, final_cost = 0.0;
  int iterations = 0;
};

// Optimises T_world_keyframe (all but the first) under the edges. Throws std::invalid_argument on
// an edge index out of range or a non-rigid pose.
LidarPoseGraphResult OptimizeLidarPoseGraph(const std::vector<Eigen::Matrix4d>& T_world_keyframe,
                                            const std::vector<LidarPoseGraphEdge>& edges,
                                            const LidarPoseGraphOptions& options = {});

}  // namespace slslam::lidar
