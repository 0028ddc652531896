#include "slslam/lidar/keyframe_pose_graph.h"

#include "slslam/core/check.h"
#include "slslam/optimization/pose_graph.h"

namespace slslam::lidar {
namespace {

// world_from_keyframe as the keyframe_from_world pose the shared solver works on.
BaPose KeyframeFromWorld(const Rigid3d& world_from_keyframe, size_t index) {
  const Eigen::Matrix3d& R = world_from_keyframe.rotation;
  SLSLAM_CHECK(R.allFinite() && world_from_keyframe.translation.allFinite() &&
                   (R.transpose() * R - Eigen::Matrix3d::Identity()).norm() < 1e-6,
               "pose graph: keyframe ", index, " is not a rigid transform");
  return {world_from_keyframe.Inverse(), index == 0};
}

}  // namespace

void LidarPoseGraphOptions::Check() const {
  SLSLAM_CHECK(max_iterations >= 1 && max_iterations <= 1000,
               "LidarPoseGraphOptions.max_iterations must be in [1, 1000], got ", max_iterations);
  SLSLAM_CHECK(loop_cauchy_scale > 0, "LidarPoseGraphOptions.loop_cauchy_scale must be > 0");
}

std::vector<Rigid3d> OptimizeLidarPoseGraph(
    const std::vector<Rigid3d>& world_from_keyframe, const std::vector<int>& a,
    const std::vector<int>& b, const std::vector<Rigid3d>& a_from_b,
    const std::vector<Eigen::Matrix<double, 6, 6>>& information, const std::vector<bool>& loop,
    const LidarPoseGraphOptions& options) {
  options.Check();
  SLSLAM_CHECK(a.size() == b.size() && a.size() == a_from_b.size() &&
                   a.size() == information.size() && a.size() == loop.size(),
               "pose graph: edge lists differ in length");
  std::vector<BaPose> poses;
  for (size_t i = 0; i < world_from_keyframe.size(); ++i) {
    poses.push_back(KeyframeFromWorld(world_from_keyframe[i], i));
  }
  std::vector<PoseGraphEdge> edges(a.size());
  for (size_t k = 0; k < a.size(); ++k) {
    edges[k].a = a[k];
    edges[k].b = b[k];
    edges[k].a_from_b = a_from_b[k];
    edges[k].information = LeftTangentInformation(edges[k].a_from_b, information[k]);
    edges[k].cauchy_scale = loop[k] ? options.loop_cauchy_scale : 0.0;
  }
  PoseGraphOptions graph_options;
  graph_options.max_iterations = options.max_iterations;
  OptimizePoseGraph(&poses, edges, graph_options);
  std::vector<Rigid3d> out;
  for (const BaPose& pose : poses) out.push_back(pose.cam_from_world.Inverse());
  return out;
}

}  // namespace slslam::lidar
