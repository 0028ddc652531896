// Keyframe pose graph on a synthetic drifting loop: odometry with a yaw and scale drift around a
// circle; one loop edge between the last and the first keyframe pulls the loop closed.
#include "slslam/lidar/pose_graph.h"

#include <cmath>
#include <cstdio>
#include <random>

#include <gtest/gtest.h>

#include "slslam/optimization/pose_graph.h"

namespace slslam::lidar {
namespace {

Eigen::Isometry3d OnCircle(double angle, double radius) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(angle + M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(radius * std::cos(angle), radius * std::sin(angle), 0.0);
  return T;
}

TEST(LidarPoseGraph, LoopEdgeRemovesDrift) {
  const int n = 60;
  const double radius = 20.0;
  std::vector<Eigen::Isometry3d> truth;
  for (int i = 0; i < n; ++i) truth.push_back(OnCircle(2 * M_PI * i / n, radius));
  // Odometry: true increments with 0.5 deg of extra yaw and 2 % extra length each.
  std::vector<Eigen::Matrix4d> drifted{truth[0].matrix()};
  std::vector<LidarPoseGraphEdge> edges;
  for (int i = 1; i < n; ++i) {
    Eigen::Isometry3d inc = truth[i - 1].inverse() * truth[i];
    inc.translation() *= 1.02;
    inc.linear() = inc.linear() *
                   Eigen::AngleAxisd(0.5 * M_PI / 180, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    Eigen::Isometry3d prev;
    prev.matrix() = drifted.back();
    drifted.push_back((prev * inc).matrix());
    LidarPoseGraphEdge e;
    e.a = i - 1;
    e.b = i;
    e.T_a_b = inc.matrix();
    edges.push_back(e);
  }
  LidarPoseGraphEdge loop;
  loop.a = 0;
  loop.b = n - 1;
  loop.T_a_b = (truth[0].inverse() * truth[n - 1]).matrix();
  loop.information *= 10.0;
  loop.loop = true;
  edges.push_back(loop);

  auto max_error = [&](const std::vector<Eigen::Matrix4d>& poses) {
    double worst = 0.0;
    for (int i = 0; i < n; ++i) {
      worst = std::max(worst, (poses[i].topRightCorner<3, 1>() - truth[i].translation()).norm());
    }
    return worst;
  };
  const double before = max_error(drifted);
  const LidarPoseGraphResult result = OptimizeLidarPoseGraph(drifted, edges);
  const double after = max_error(result.T_world_keyframe);
  EXPECT_GT(before, 5.0);  // the drift is real
  EXPECT_LT(after, 0.15 * before);
  EXPECT_LT(result.final_cost, result.initial_cost);
  // The first keyframe stays where it was.
  EXPECT_TRUE(result.T_world_keyframe[0].isApprox(drifted[0], 1e-12));
}

TEST(LidarPoseGraph, BadEdgeThrows) {
  LidarPoseGraphEdge e;
  e.a = 0;
  e.b = 3;
  EXPECT_THROW(
      OptimizeLidarPoseGraph({Eigen::Matrix4d::Identity(), Eigen::Matrix4d::Identity()}, {e}),
      std::invalid_argument);
}

// The shared solver (optimization/pose_graph.h) on this solver's edges converted as the binding
// converts them (poses inverted, information through LeftTangentInformation) finds the same poses
// up to the second-order difference of the two errors.
TEST(LidarPoseGraph, SharedSolverOnConvertedEdgesFindsTheSamePoses) {
  const int n = 30;
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Eigen::Isometry3d> truth;
  for (int i = 0; i < n; ++i) truth.push_back(OnCircle(2 * M_PI * i / n, 10.0));
  std::vector<Eigen::Matrix4d> drifted{truth[0].matrix()};
  std::vector<LidarPoseGraphEdge> edges;
  auto information = [&](double sigma) {
    Eigen::Matrix<double, 6, 6> A;
    for (int i = 0; i < 36; ++i) A(i) = u(rng);
    return Eigen::Matrix<double, 6, 6>(
        (A * A.transpose() + Eigen::Matrix<double, 6, 6>::Identity()) / (sigma * sigma));
  };
  for (int i = 1; i < n; ++i) {
    Eigen::Isometry3d inc = truth[i - 1].inverse() * truth[i];
    inc.translation() *= 1.01;
    inc.linear() = inc.linear() *
                   Eigen::AngleAxisd(0.3 * M_PI / 180, Eigen::Vector3d(0.2, 0.1, 1.0).normalized())
                       .toRotationMatrix();
    Eigen::Isometry3d prev;
    prev.matrix() = drifted.back();
    drifted.push_back((prev * inc).matrix());
    LidarPoseGraphEdge e;
    e.a = i - 1;
    e.b = i;
    e.T_a_b = inc.matrix();
    e.information = information(0.05);
    edges.push_back(e);
  }
  LidarPoseGraphEdge loop;
  loop.a = 0;
  loop.b = n - 1;
  loop.T_a_b = (truth[0].inverse() * truth[n - 1]).matrix();
  loop.information = information(0.05);
  loop.loop = true;
  edges.push_back(loop);
  const LidarPoseGraphResult former = OptimizeLidarPoseGraph(drifted, edges);

  std::vector<BaPose> poses;
  for (int i = 0; i < n; ++i) poses.push_back({Rigid3d::FromMatrix4(drifted[i]).Inverse(), i == 0});
  std::vector<PoseGraphEdge> shared;
  for (const LidarPoseGraphEdge& e : edges) {
    PoseGraphEdge s;
    s.a = e.a;
    s.b = e.b;
    s.a_from_b = Rigid3d::FromMatrix4(e.T_a_b);
    s.information = LeftTangentInformation(s.a_from_b, e.information);
    s.cauchy_scale = e.loop ? LidarPoseGraphOptions().loop_cauchy_scale : 0.0;
    shared.push_back(s);
  }
  PoseGraphOptions options;
  options.max_iterations = LidarPoseGraphOptions().max_iterations;
  ASSERT_TRUE(OptimizePoseGraph(&poses, shared, options).solved);
  double dp = 0.0, dr = 0.0, moved = 0.0;
  for (int i = 0; i < n; ++i) {
    const Eigen::Matrix4d T = poses[i].cam_from_world.Inverse().ToMatrix4();
    const Eigen::Matrix4d& F = former.T_world_keyframe[i];
    dp = std::max(dp, (T.topRightCorner<3, 1>() - F.topRightCorner<3, 1>()).norm());
    dr = std::max(dr, Eigen::AngleAxisd(Eigen::Matrix3d(T.topLeftCorner<3, 3>().transpose() *
                                                        F.topLeftCorner<3, 3>()))
                          .angle());
    moved = std::max(moved, (drifted[i].topRightCorner<3, 1>() - F.topRightCorner<3, 1>()).norm());
  }
  std::printf("former moved %.3f m; shared differs %.2e m / %.2e rad\n", moved, dp, dr);
  EXPECT_GT(moved, 1.0);
  EXPECT_LT(dp, 1e-3 * moved);
  EXPECT_LT(dr, 1e-3);
}

}  // namespace
}  // namespace slslam::lidar
