#include "slslam/optimization/pose_graph.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

namespace slslam {
namespace {

// Ground truth: N camera poses (cam_from_world) round a circle of radius 10 m, the camera looking
// along the tangent. Odometry: the true relative poses with a small constant yaw bias (the drift).
std::vector<Rigid3d> MakeCircle(int n) {
  std::vector<Rigid3d> c;
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * M_PI * i / n;
    const Eigen::Matrix3d R_wc = Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    const Eigen::Vector3d p(10.0 * std::cos(a), 10.0 * std::sin(a), 0.0);
    c.emplace_back(R_wc.transpose(), -R_wc.transpose() * p);
  }
  return c;
}

double CenterError(const BaPose& pose, const Rigid3d& truth) {
  return (pose.cam_from_world.Center() - truth.Center()).norm();
}

TEST(PoseGraph, LoopEdgeRemovesDriftOfASyntheticLoop) {
  const int n = 60;
  const std::vector<Rigid3d> truth = MakeCircle(n);
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.002);
  // Dead reckoning with a yaw bias of 0.3 deg per step and noisy translations.
  std::vector<PoseGraphEdge> edges;
  std::vector<BaPose> poses(n);
  poses[0] = {truth[0], true};
  const Eigen::Matrix3d bias =
      Eigen::AngleAxisd(0.3 * M_PI / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
  for (int i = 1; i < n; ++i) {
    PoseGraphEdge e;
    e.a = i - 1;
    e.b = i;
    e.a_from_b = RelativePose(truth[i - 1], truth[i]);
    e.a_from_b.rotation = e.a_from_b.rotation * bias;
    e.a_from_b.translation += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    edges.push_back(e);
    // cam_i_from_world = (cam_{i-1}_from_cam_i)^-1 * cam_{i-1}_from_world
    poses[i].cam_from_world = e.a_from_b.Inverse() * poses[i - 1].cam_from_world;
  }
  const double drift_before = CenterError(poses[n - 1], truth[n - 1]);
  ASSERT_GT(drift_before, 0.5);  // the bias really drifts
  // The loop: the last pose seen from the first, exactly.
  PoseGraphEdge loop;
  loop.a = 0;
  loop.b = n - 1;
  loop.a_from_b = RelativePose(truth[0], truth[n - 1]);
  edges.push_back(loop);
  const PoseGraphReport report = OptimizePoseGraph(&poses, edges);
  ASSERT_TRUE(report.solved);
  EXPECT_LT(report.final_cost, 0.1 * report.initial_cost);
  double worst = 0.0;
  for (int i = 0; i < n; ++i) worst = std::max(worst, CenterError(poses[i], truth[i]));
  // The bias is spread over the loop: every pose within a fraction of the end drift.
  EXPECT_LT(CenterError(poses[n - 1], truth[n - 1]), 0.05 * drift_before);
  EXPECT_LT(worst, 0.35 * drift_before);
  // The fixed pose did not move.
  EXPECT_TRUE(poses[0].cam_from_world.rotation.isApprox(truth[0].rotation));
  EXPECT_TRUE(poses[0].cam_from_world.translation.isApprox(truth[0].translation));
}

TEST(PoseGraph, RejectsBadEdgesAndOptions) {
  std::vector<BaPose> poses(2);
  PoseGraphEdge e;
  e.a = 0;
  e.b = 2;
  EXPECT_THROW(OptimizePoseGraph(&poses, {e}), std::invalid_argument);
  e.b = 1;
  e.weight = std::nan("");
  EXPECT_THROW(OptimizePoseGraph(&poses, {e}), std::invalid_argument);
  PoseGraphOptions options;
  options.translation_sigma_m = 0.0;
  EXPECT_THROW(options.Check(), std::invalid_argument);
}

TEST(PoseGraph, RelativePoseIsAFromWorldTimesWorldFromB) {
  const Rigid3d a_from_world(
      Eigen::AngleAxisd(0.4, Eigen::Vector3d(1.0, 2.0, -0.5).normalized()).toRotationMatrix(),
      Eigen::Vector3d(0.3, -1.2, 2.0));
  const Rigid3d b_from_world(
      Eigen::AngleAxisd(-0.9, Eigen::Vector3d(0.2, 1.0, 0.7).normalized()).toRotationMatrix(),
      Eigen::Vector3d(-2.0, 0.5, 1.1));
  const Rigid3d a_from_b = RelativePose(a_from_world, b_from_world);
  const Rigid3d expected = a_from_world * b_from_world.Inverse();
  EXPECT_TRUE(a_from_b.rotation.isApprox(expected.rotation, 1e-12));
  EXPECT_LT((a_from_b.translation - expected.translation).norm(), 1e-12);
  // Its arithmetic, bit for bit: R_ab = R_aw R_bw^T, then t_aw - R_ab t_bw.
  const Eigen::Matrix3d R_ab = a_from_world.rotation * b_from_world.rotation.transpose();
  EXPECT_EQ(a_from_b.rotation, R_ab);
  const Eigen::Vector3d t_ab = a_from_world.translation - R_ab * b_from_world.translation;
  EXPECT_EQ(a_from_b.translation, t_ab);
  const Eigen::Vector3d x_b(0.7, -0.1, 4.0);
  EXPECT_LT((a_from_b * x_b - a_from_world * (b_from_world.Inverse() * x_b)).norm(), 1e-12);
}

}  // namespace
}  // namespace slslam
