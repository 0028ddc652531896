// The LiDAR keyframe pose graph: a drifted square closed by a loop edge returns to the true poses;
// bad input is refused with its reason.
#include "slslam/lidar/keyframe_pose_graph.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>

#include <gtest/gtest.h>

#include "slslam/core/check.h"

namespace slslam::lidar {
namespace {

Eigen::Matrix4d Pose(double x, double y, double yaw_rad) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, 0.0);
  return T.matrix();
}

TEST(KeyframePoseGraph, LoopEdgeRemovesOdometryDrift) {
  // Eight keyframes around a 10 m square; true relative poses as edges, drifted initial poses.
  std::vector<Eigen::Matrix4d> truth;
  for (int i = 0; i < 8; ++i) {
    const double yaw = M_PI / 4 * i;
    truth.push_back(Pose(5 * std::cos(yaw), 5 * std::sin(yaw), yaw + M_PI / 2));
  }
  std::vector<int> a, b;
  std::vector<Eigen::Matrix4d> T_a_b;
  std::vector<bool> loop;
  for (int i = 0; i + 1 < 8; ++i) {
    a.push_back(i);
    b.push_back(i + 1);
    T_a_b.push_back(truth[i].inverse() * truth[i + 1]);
    loop.push_back(false);
  }
  a.push_back(7);
  b.push_back(0);
  T_a_b.push_back(truth[7].inverse() * truth[0]);
  loop.push_back(true);
  const std::vector<Eigen::Matrix<double, 6, 6>> information(
      a.size(), Eigen::Matrix<double, 6, 6>::Identity() * 100.0);

  std::vector<Eigen::Matrix4d> drifted = truth;
  for (int i = 1; i < 8; ++i) drifted[i] = drifted[i] * Pose(0.1 * i, -0.05 * i, 0.02 * i);

  const std::vector<Eigen::Matrix4d> out =
      OptimizeLidarPoseGraph(drifted, a, b, T_a_b, information, loop);
  ASSERT_EQ(out.size(), truth.size());
  EXPECT_TRUE(out[0].isApprox(truth[0], 1e-12));  // the first keyframe is held
  for (size_t i = 0; i < out.size(); ++i) {
    EXPECT_LT((out[i] - truth[i]).norm(), 1e-6) << "keyframe " << i;
  }
}

TEST(KeyframePoseGraph, RefusesBadInputWithTheReason) {
  const std::vector<Eigen::Matrix<double, 6, 6>> information(
      1, Eigen::Matrix<double, 6, 6>::Identity());
  Eigen::Matrix4d sheared = Eigen::Matrix4d::Identity();
  sheared(0, 1) = 0.5;
  try {
    OptimizeLidarPoseGraph({Eigen::Matrix4d::Identity(), sheared}, {0}, {1},
                           {Eigen::Matrix4d::Identity()}, information, {false});
    FAIL() << "a non-rigid pose was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("keyframe 1 is not a rigid transform"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(OptimizeLidarPoseGraph({Eigen::Matrix4d::Identity()}, {0, 1}, {1},
                                      {Eigen::Matrix4d::Identity()}, information, {false}),
               std::invalid_argument);
  LidarPoseGraphOptions options;
  options.max_iterations = 0;
  EXPECT_THROW(options.Check(), std::invalid_argument);
}

}  // namespace
}  // namespace slslam::lidar
