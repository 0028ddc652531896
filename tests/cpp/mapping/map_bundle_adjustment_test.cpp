#include "slslam/mapping/map_bundle_adjustment.h"

#include <atomic>
#include <string>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "../inertial/synthetic_motion.h"
#include "slslam/core/time.h"

namespace slslam {
namespace {

std::shared_ptr<StereoFrame> EmptyFrame() { return std::make_shared<StereoFrame>(); }

Eigen::Matrix3d Yaw(double deg) {
  return Eigen::AngleAxisd(deg * M_PI / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
}

// A correction of the world, after_from_before (x' = R x + t), applied to a pose
// cam_from_world: cam_from_world' = cam_from_world * after_from_before^-1.
struct World {
  Rigid3d after_from_before = Rigid3d(Yaw(4.0), Eigen::Vector3d(0.3, -0.1, 0.2));
  void Move(Rigid3d* cam_from_world) const {
    cam_from_world->rotation = cam_from_world->rotation * after_from_before.rotation.transpose();
    cam_from_world->translation =
        cam_from_world->translation - cam_from_world->rotation * after_from_before.translation;
  }
};

TEST(MapBundleAdjustment, WhatJoinedTheMapDuringTheSolveFollowsItsNearestSolvedKeyFrame) {
  for (const bool carry : {true, false}) {
    Map map;
    auto a = map.AddKeyFrame(Rigid3d(Yaw(0), Eigen::Vector3d(0, 0, 0)), EmptyFrame());
    auto b = map.AddKeyFrame(Rigid3d(Yaw(10), Eigen::Vector3d(-1, 0, 0.2)), EmptyFrame());
    b->parent = a->id;
    auto p = map.AddPoint(Eigen::Vector3d(0, 0, 5), cv::Mat(), a->id);
    p->observations[a->id] = 0;
    MapBundleAdjustment ba(map.correction_epoch());
    ba.AddPose(*a, /*fixed=*/true);
    ba.AddPose(*b, /*fixed=*/false);
    ba.AddPoint(map, *p, 1.0, [](int) { return -1; });
    EXPECT_EQ(ba.problem().poses.size(), 2u);

    // While the solve runs: local mapping adds a keyframe c (child of b), with a point and a
    // line that only c observes.
    auto c = map.AddKeyFrame(Rigid3d(Yaw(25), Eigen::Vector3d(-2, 0.1, 0.5)), EmptyFrame());
    c->parent = b->id;
    const Eigen::Vector3d q0(1, 1, 6), s0(2, -1, 7), e0(2, 1, 7);
    auto q = map.AddPoint(q0, cv::Mat(), c->id);
    q->observations[c->id] = 0;
    auto l = map.AddLine(PluckerLine::FromPoints(s0, e0), s0, e0, cv::Mat(), c->id);
    l->observations[c->id] = 0;
    const Rigid3d c0 = c->cam_from_world;

    // The solution: b's world moved by W, the point solved to a new place.
    const World w;
    BaPose b_after = ba.problem().poses[1];
    w.Move(&b_after.cam_from_world);
    ba.problem().poses[1] = b_after;
    ba.problem().points[0] = Eigen::Vector3d(0.1, 0, 5.2);
    BundleAdjustmentReport report;
    report.solved = true;
    EXPECT_EQ(ba.Apply(&map, report, carry), carry ? 1 : 0);

    EXPECT_TRUE(a->cam_from_world.rotation.isApprox(Yaw(0), 1e-12));  // fixed
    EXPECT_TRUE(b->cam_from_world.rotation.isApprox(b_after.cam_from_world.rotation, 1e-12));
    EXPECT_TRUE(b->cam_from_world.translation.isApprox(b_after.cam_from_world.translation, 1e-12));
    EXPECT_TRUE(p->position.isApprox(Eigen::Vector3d(0.1, 0, 5.2), 1e-12));
    if (carry) {  // c, its point and its line moved with b's world
      Rigid3d c_moved = c0;
      w.Move(&c_moved);
      EXPECT_TRUE(c->cam_from_world.rotation.isApprox(c_moved.rotation, 1e-12));
      EXPECT_LT((c->cam_from_world.translation - c_moved.translation).norm(), 1e-12);
      EXPECT_LT((q->position - w.after_from_before * q0).norm(), 1e-12);
      EXPECT_LT((l->start - w.after_from_before * s0).norm(), 1e-12);
      const Eigen::Vector3d e = w.after_from_before * e0;
      EXPECT_LT((l->line.ClosestPointTo(e) - e).norm(), 1e-9);
    } else {  // inline (nothing can join meanwhile): left as they are
      EXPECT_TRUE(c->cam_from_world.rotation.isApprox(c0.rotation, 1e-12));
      EXPECT_LT((q->position - q0).norm(), 1e-12);
      EXPECT_LT((l->start - s0).norm(), 1e-12);
    }
  }
}

StereoRig TestRig() {
  StereoRig rig;
  rig.camera = {400, 400, 320, 240, 640, 480};
  rig.baseline_m = 0.1;
  return rig;
}

// Two stereo views of 20 points; the free pose and the points start perturbed.
BaProblem TwoViewProblem(const StereoRig& rig, std::vector<Eigen::Vector3d>* truth = nullptr) {
  BaProblem problem;
  problem.poses.push_back({Rigid3d(), true});
  problem.poses.push_back(
      {Rigid3d(Eigen::Matrix3d::Identity(), Eigen::Vector3d(-0.2, 0, 0)), false});
  for (int i = 0; i < 20; ++i) {
    const Eigen::Vector3d x(0.3 * (i % 5) - 0.6, 0.2 * (i / 5) - 0.3, 4.0 + 0.1 * i);
    if (truth) truth->push_back(x);
    problem.points.push_back(x + Eigen::Vector3d(0.05, -0.03, 0.1));
    for (int k = 0; k < 2; ++k) {
      const Eigen::Vector3d xc = problem.poses[k].cam_from_world * x;
      BaPointObservation o;
      o.pose = k;
      o.point = i;
      o.stereo = true;
      const Eigen::Vector2d uv = rig.camera.Project(xc);
      o.observed << uv.x(), uv.y(), uv.x() - rig.camera.fx * rig.baseline_m / xc.z();
      problem.point_observations.push_back(o);
    }
  }
  return problem;
}

// Both solvers of local BA: Ceres and the own one (BundleAdjustmentOptions::own_solver).
class MapBundleAdjustmentSolver : public ::testing::TestWithParam<bool> {
 protected:
  BundleAdjustmentOptions Options() const {
    BundleAdjustmentOptions options;
    options.own_solver = GetParam();
    return options;
  }
};

TEST_P(MapBundleAdjustmentSolver, AnInterruptBeforeAnyStepLeavesTheProblemAsItWas) {
  const StereoRig rig = TestRig();
  std::vector<Eigen::Vector3d> truth;
  BaProblem problem = TwoViewProblem(rig, &truth);
  problem.point_observations[7].observed.x() += 40.0;  // a gross outlier

  // Not interrupted: solved, the outlier found and only it.
  const std::atomic<bool> no{false};
  BaProblem full = problem;
  const BundleAdjustmentReport done = SolveBundleAdjustment(rig, &full, Options(), nullptr, &no);
  EXPECT_TRUE(done.solved);
  EXPECT_FALSE(done.interrupted);
  for (size_t i = 0; i < done.point_outlier.size(); ++i) {
    EXPECT_EQ(done.point_outlier[i], i == 7) << "observation " << i;
  }
  EXPECT_LT((full.points[0] - truth[0]).norm(), 1e-3);

  // Interrupted before the first step (a newer keyframe already waiting): reported interrupted
  // and unsolved, so local mapping applies nothing and removes no observation judged on the
  // starting estimate (whose residuals exceed the bounds almost everywhere).
  const std::atomic<bool> yes{true};
  BaProblem cut = problem;
  const BundleAdjustmentReport report = SolveBundleAdjustment(rig, &cut, Options(), nullptr, &yes);
  EXPECT_TRUE(report.interrupted);
  EXPECT_FALSE(report.solved);
  for (size_t i = 0; i < truth.size(); ++i) EXPECT_EQ(cut.points[i], problem.points[i]);
}

TEST_P(MapBundleAdjustmentSolver, ASolveAskedToAbortReportsUnsolved) {
  const StereoRig rig = TestRig();
  const BaProblem problem = TwoViewProblem(rig);
  BaProblem copy = problem;
  EXPECT_TRUE(SolveBundleAdjustment(rig, &copy, Options()).solved);
  const std::atomic<bool> abort{true};
  copy = problem;
  EXPECT_FALSE(SolveBundleAdjustment(rig, &copy, Options(), &abort).solved);
  const std::atomic<bool> go_on{false};
  copy = problem;
  EXPECT_TRUE(SolveBundleAdjustment(rig, &copy, Options(), &go_on).solved);
}

INSTANTIATE_TEST_SUITE_P(CeresAndOwn, MapBundleAdjustmentSolver, ::testing::Bool(),
                         [](const ::testing::TestParamInfo<bool>& info) {
                           return info.param ? std::string("Own") : std::string("Ceres");
                         });

// A map's IMU chain in a window: the factor from the window's oldest keyframe's predecessor
// (joining as a fixed pose with a fixed state), none over an interval longer than the map's bound;
// the solve's velocities and biases written back to the window's keyframes only, each counted as
// refined, and the map's gravity (both copies) moved to the estimate.
TEST(MapBundleAdjustment, TheImuChainOfAWindowJoinsWithItsPredecessorFixed) {
  const test::SyntheticMotion motion;
  Map map;
  MutexLock lock(map.mutex());
  MapInertial imu;
  imu.g_world = motion.g_world;
  imu.gravity_sigma_rad = 0.01;
  map.set_inertial(imu);
  // Keyframes at 1.0, 1.5, 2.0, 2.5 s and one 4 s later (no factor to it).
  const std::vector<double> times = {1.0, 1.5, 2.0, 2.5, 6.5};
  std::vector<std::shared_ptr<KeyFrame>> kfs;
  for (size_t k = 0; k < times.size(); ++k) {
    const double t = times[k];
    auto kf = map.AddKeyFrame(motion.WorldFromBody(t).Inverse(), EmptyFrame());
    KeyFrameInertial state;
    state.t_ns = NsFromSeconds(t);
    state.v_world_body = motion.Velocity(t) + Eigen::Vector3d(0.2, -0.1, 0.1);  // (off)
    if (k > 0) {
      state.previous = kfs.back()->id;
      for (double s = times[k - 1]; s < t - 1e-9; s += 0.005) {
        state.samples_from_previous.Add(NsFromSeconds(s), motion.Gyro(s + 0.0025),
                                        motion.Accelerometer(s + 0.0025));
      }
    }
    kf->inertial = state;
    kfs.push_back(kf);
  }
  const Eigen::Vector3d v1_before = kfs[1]->inertial->v_world_body;
  MapBundleAdjustment ba;
  std::unordered_map<int, int> pose_index;
  const std::vector<int> window = {kfs[2]->id, kfs[3]->id, kfs[4]->id};
  for (int id : window) pose_index[id] = ba.AddPose(*map.keyframe(id), /*fixed=*/true);
  EXPECT_EQ(ba.AddInertialFactors(map, window, &pose_index), 2);     // 1 -> 2, 2 -> 3; not 3 -> 4
  ASSERT_EQ(ba.problem().poses.size(), 4u);                          // the predecessor joined,
  EXPECT_TRUE(ba.problem().poses[pose_index.at(kfs[1]->id)].fixed);  // held
  ASSERT_EQ(ba.problem().inertial.states.size(), 3u);
  EXPECT_TRUE(ba.problem().inertial.states[0].fixed);  // (its state, added first)
  StereoRig rig;
  rig.camera = {400, 400, 320, 240, 640, 480};
  rig.baseline_m = 0.1;
  BundleAdjustmentOptions options;
  options.robust_iterations = 20;
  options.refine_iterations = 20;
  const BundleAdjustmentReport report = SolveBundleAdjustment(rig, &ba.problem(), options);
  ASSERT_TRUE(report.solved);
  ba.Apply(&map, report);
  EXPECT_EQ(kfs[1]->inertial->v_world_body, v1_before);  // fixed: not written
  EXPECT_EQ(kfs[1]->inertial->refined, 0);
  for (int k : {2, 3}) {
    EXPECT_EQ(kfs[k]->inertial->refined, 1) << k;
    EXPECT_LT((kfs[k]->inertial->v_world_body - motion.Velocity(times[k])).norm(),
              (v1_before - motion.Velocity(times[1])).norm())
        << k;
  }
  EXPECT_EQ(kfs[4]->inertial->refined, 0);  // in no factor
  ASSERT_TRUE(map.gravity_direction().has_value());
  EXPECT_LT((*map.gravity_direction() - map.inertial()->g_world.normalized()).norm(), 1e-12);
}

// A correction moves a keyframe's world: its velocity turns with it.
TEST(MapBundleAdjustment, MoveKeyFrameTurnsTheVelocityWithThePose) {
  KeyFrame kf;
  kf.cam_from_world = Rigid3d(Yaw(10), Eigen::Vector3d(1, 0, 0));
  kf.inertial = KeyFrameInertial{};
  kf.inertial->v_world_body = Eigen::Vector3d(1.0, 0.0, 0.0);
  // The world turned by 90 degrees (about y, this file's Yaw) around the keyframe: cam_from_new =
  // cam_from_old * old_from_new.
  const Rigid3d moved = kf.cam_from_world * Rigid3d(Yaw(90), Eigen::Vector3d::Zero()).Inverse();
  MoveKeyFrame(&kf, moved);
  EXPECT_LT((kf.inertial->v_world_body - Eigen::Vector3d(0.0, 0.0, -1.0)).norm(), 1e-12);
  EXPECT_EQ(kf.cam_from_world.rotation, moved.rotation);
}

}  // namespace
}  // namespace slslam
