// The LiDAR back end's keyframe pose graph: world_from_keyframe poses under relative-pose
// edges (odometry and Scan Context loops), solved by the shared pose-graph solver
// (optimization/pose_graph.h).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "slslam/core/rigid3.h"

namespace slslam::lidar {

// The solver's settings (slslam.lidar.slam mirrors them).
struct LidarPoseGraphOptions {
  int max_iterations = 50;         ///< Levenberg-Marquardt iterations [-]
  double loop_cauchy_scale = 1.0;  ///< Cauchy scale of loop edges (whitened units) [-]

  void Check() const;
};

// Keyframe poses (world_from_keyframe) optimised under edges a -> b: a_from_b with a 6x6
// information of its split error (translation t_est - t_ab in frame a, then Log(R_ab^T R_est)),
// loop edges under a Cauchy loss. The first keyframe is held. Throws std::invalid_argument on
// edge lists of different lengths, a non-rigid pose or options out of range.
std::vector<Rigid3d> OptimizeLidarPoseGraph(
    const std::vector<Rigid3d>& world_from_keyframe, const std::vector<int>& a,
    const std::vector<int>& b, const std::vector<Rigid3d>& a_from_b,
    const std::vector<Eigen::Matrix<double, 6, 6>>& information, const std::vector<bool>& loop,
    const LidarPoseGraphOptions& options = LidarPoseGraphOptions());

}  // namespace slslam::lidar
