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

Rigid3d Pose(double x, double y, double yaw_rad) {
  return Rigid3d(Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix(),
                 Eigen::Vector3d(x, y, 0.0));
}

TEST(KeyframePoseGraph, LoopEdgeRemovesOdometryDrift) {
  // Eight keyframes around a 10 m square; true relative poses as edges, drifted initial poses.
  std::vector<Rigid3d> truth;
  for (int i = 0; i < 8; ++i) {
    const double yaw = M_PI / 4 * i;
    truth.push_back(Pose(5 * std::cos(yaw), 5 * std::sin(yaw), yaw + M_PI / 2));
  }
  std::vector<int> a, b;
  std::vector<Rigid3d> a_from_b;
  std::vector<bool> loop;
  for (int i = 0; i + 1 < 8; ++i) {
    a.push_back(i);
    b.push_back(i + 1);
    a_from_b.push_back(truth[i].Inverse() * truth[i + 1]);
    loop.push_back(false);
  }
  a.push_back(7);
  b.push_back(0);
  a_from_b.push_back(truth[7].Inverse() * truth[0]);
  loop.push_back(true);
  const std::vector<Eigen::Matrix<double, 6, 6>> information(
      a.size(), Eigen::Matrix<double, 6, 6>::Identity() * 100.0);

  std::vector<Rigid3d> drifted = truth;
  for (int i = 1; i < 8; ++i) drifted[i] = drifted[i] * Pose(0.1 * i, -0.05 * i, 0.02 * i);

  const std::vector<Rigid3d> out =
      OptimizeLidarPoseGraph(drifted, a, b, a_from_b, information, loop);
  ASSERT_EQ(out.size(), truth.size());
  EXPECT_TRUE(out[0].ToMatrix4().isApprox(truth[0].ToMatrix4(), 1e-12));  // the first is held
  for (size_t i = 0; i < out.size(); ++i) {
    EXPECT_LT((out[i].ToMatrix4() - truth[i].ToMatrix4()).norm(), 1e-6) << "keyframe " << i;
  }
}

TEST(KeyframePoseGraph, RefusesBadInputWithTheReason) {
  const std::vector<Eigen::Matrix<double, 6, 6>> information(
      1, Eigen::Matrix<double, 6, 6>::Identity());
  Rigid3d sheared;
  sheared.rotation(0, 1) = 0.5;
  try {
    OptimizeLidarPoseGraph({Rigid3d(), sheared}, {0}, {1}, {Rigid3d()}, information, {false});
    FAIL() << "a non-rigid pose was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("keyframe 1 is not a rigid transform"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(OptimizeLidarPoseGraph({Rigid3d()}, {0, 1}, {1}, {Rigid3d()}, information, {false}),
               std::invalid_argument);
  LidarPoseGraphOptions options;
  options.max_iterations = 0;
  EXPECT_THROW(options.Check(), std::invalid_argument);
}

}  // namespace
}  // namespace slslam::lidar
