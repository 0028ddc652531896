#include "slslam/optimization/pose_optimizer.h"

#include <array>
#include <random>
#include <vector>

#include <ceres/loss_function.h>
#include <ceres/problem.h>
#include <ceres/solver.h>
#include <gtest/gtest.h>

#include "../test_support.h"
#include "slslam/geometry/rotation.h"
#include "slslam/optimization/cost_functions.h"
#include "slslam/optimization/manifolds.h"

namespace slslam {
namespace {

using test::EurocLikeRig;

struct Scene {
  Eigen::Matrix3d R = ExpSO3(Eigen::Vector3d(0.05, -0.4, 0.1));
  Eigen::Vector3d t = Eigen::Vector3d(0.2, -0.1, 1.0);
  std::vector<PointObservation> points;
  std::vector<LineObservation> lines;
  std::vector<bool> corrupted_points;
  std::vector<bool> corrupted_lines;
};

// Landmarks 2-12 m in front of the true camera, observed with 0.5 px noise; a fraction of the
// observations are gross outliers (20-60 px off).
Scene MakeScene(int num_points, int num_lines, double outlier_fraction, unsigned seed) {
  const StereoRig rig = EurocLikeRig();
  Scene s;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uu(30.0, 720.0), vv(30.0, 450.0), depth(2.0, 12.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0), gross(20.0, 60.0);
  std::normal_distribution<double> noise(0.0, 0.5);
  const Eigen::Matrix3d R_wc = s.R.transpose();
  const Eigen::Vector3d t_wc = -R_wc * s.t;
  auto world_point = [&](double u, double v, double z) {
    return Eigen::Vector3d(R_wc * (z * rig.camera.Unproject(Eigen::Vector2d(u, v))) + t_wc);
  };
  for (int i = 0; i < num_points; ++i) {
    const double u = uu(rng), v = vv(rng), z = depth(rng);
    PointObservation obs;
    obs.point_w = world_point(u, v, z);
    obs.stereo = i % 2 == 0;
    obs.observed << u + noise(rng), v + noise(rng),
        u - rig.camera.fx * rig.baseline_m / z + noise(rng);
    const bool bad = unit(rng) < outlier_fraction;
    if (bad) obs.observed += Eigen::Vector3d(gross(rng), -gross(rng), gross(rng));
    s.points.push_back(obs);
    s.corrupted_points.push_back(bad);
  }
  for (int i = 0; i < num_lines; ++i) {
    const Eigen::Vector2d a(uu(rng), vv(rng)), b(uu(rng), vv(rng));
    const Eigen::Vector3d pa = world_point(a.x(), a.y(), depth(rng));
    const Eigen::Vector3d pb = world_point(b.x(), b.y(), depth(rng));
    LineObservation obs;
    obs.line_w = PluckerLine::FromPoints(pa, pb);
    obs.start_px = a + Eigen::Vector2d(noise(rng), noise(rng));
    obs.end_px = b + Eigen::Vector2d(noise(rng), noise(rng));
    const bool bad = unit(rng) < outlier_fraction;
    if (bad) obs.end_px += Eigen::Vector2d(gross(rng), gross(rng));
    s.lines.push_back(obs);
    s.corrupted_lines.push_back(bad);
  }
  return s;
}

double RotationErrorDeg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return LogSO3(Eigen::Quaterniond(a * b.transpose())).norm() * 180.0 / M_PI;
}

void PerturbedStart(const Scene& s, Eigen::Matrix3d* R, Eigen::Vector3d* t) {
  *R = s.R;
  *t = s.t;
  Eigen::Matrix<double, 6, 1> delta;
  delta << 0.08, -0.05, 0.1, 0.03, -0.02, 0.025;  // 8-10 cm, about 2.5 deg
  Rigid3d perturbed(*R, *t);
  PerturbPose(delta, &perturbed);
  *R = perturbed.rotation;
  *t = perturbed.translation;
}

Rigid3d PerturbedStartPose(const Scene& s) {
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  PerturbedStart(s, &R, &t);
  return Rigid3d(R, t);
}

double TranslationDifference(const Rigid3d& a, const Rigid3d& b) {
  return (a.translation - b.translation).norm();
}

TEST(PoseOptimizer, PointsWithOutliersRecoverPoseAndFlagOutliers) {
  const Scene s = MakeScene(150, 0, 0.2, 1);
  Eigen::Matrix3d R0;
  Eigen::Vector3d t0;
  PerturbedStart(s, &R0, &t0);
  const PoseOptimizerResult r = OptimizePose(EurocLikeRig(), Rigid3d(R0, t0), s.points, {});
  ASSERT_TRUE(r.success);
  EXPECT_LT((r.cam_from_world.translation - s.t).norm(), 0.01);
  EXPECT_LT(RotationErrorDeg(r.cam_from_world.rotation, s.R), 0.1);
  int agree = 0;
  for (size_t i = 0; i < s.points.size(); ++i) agree += r.point_inlier[i] != s.corrupted_points[i];
  EXPECT_GE(agree, static_cast<int>(0.97 * s.points.size()));
}

TEST(PoseOptimizer, LinesAloneRecoverPose) {
  const Scene s = MakeScene(0, 60, 0.1, 2);
  Eigen::Matrix3d R0;
  Eigen::Vector3d t0;
  PerturbedStart(s, &R0, &t0);
  const PoseOptimizerResult r = OptimizePose(EurocLikeRig(), Rigid3d(R0, t0), {}, s.lines);
  ASSERT_TRUE(r.success);
  EXPECT_LT((r.cam_from_world.translation - s.t).norm(), 0.02);
  EXPECT_LT(RotationErrorDeg(r.cam_from_world.rotation, s.R), 0.2);
  int flagged = 0;
  for (size_t i = 0; i < s.lines.size(); ++i) {
    if (s.corrupted_lines[i]) flagged += !r.line_inlier[i];
  }
  EXPECT_EQ(flagged, std::count(s.corrupted_lines.begin(), s.corrupted_lines.end(), true));
}

TEST(PoseOptimizer, PointsAndLinesTogether) {
  const Scene s = MakeScene(40, 30, 0.15, 3);
  Eigen::Matrix3d R0;
  Eigen::Vector3d t0;
  PerturbedStart(s, &R0, &t0);
  const PoseOptimizerResult r = OptimizePose(EurocLikeRig(), Rigid3d(R0, t0), s.points, s.lines);
  ASSERT_TRUE(r.success);
  EXPECT_LT((r.cam_from_world.translation - s.t).norm(), 0.01);
  EXPECT_LT(RotationErrorDeg(r.cam_from_world.rotation, s.R), 0.1);
  EXPECT_GT(r.line_inliers, 20);
}

TEST(PoseOptimizer, TooFewObservationsKeepsInitialPose) {
  const Scene s = MakeScene(2, 0, 0.0, 4);
  const PoseOptimizerResult r = OptimizePose(EurocLikeRig(), Rigid3d(s.R, s.t), s.points, {});
  EXPECT_FALSE(r.success);
  EXPECT_TRUE(r.cam_from_world.rotation.isApprox(s.R));
  Eigen::Matrix3d nan_r = s.R;
  nan_r(0, 0) = NAN;
  EXPECT_THROW(OptimizePose(EurocLikeRig(), Rigid3d(nan_r, s.t), s.points, {}),
               std::invalid_argument);
}

TEST(PoseOptimizer, Deterministic) {
  const Scene s = MakeScene(80, 20, 0.1, 5);
  Eigen::Matrix3d R0;
  Eigen::Vector3d t0;
  PerturbedStart(s, &R0, &t0);
  const PoseOptimizerResult a = OptimizePose(EurocLikeRig(), Rigid3d(R0, t0), s.points, s.lines);
  const PoseOptimizerResult b = OptimizePose(EurocLikeRig(), Rigid3d(R0, t0), s.points, s.lines);
  EXPECT_EQ(a.cam_from_world.translation, b.cam_from_world.translation);
  EXPECT_EQ(a.cam_from_world.rotation, b.cam_from_world.rotation);
}

// Both solvers recover the pose, flag the outliers and agree with each other.
TEST(PoseOptimizer, OwnSolverAgreesWithCeres) {
  const Scene s = MakeScene(150, 30, 0.2, 9);
  const Rigid3d start = PerturbedStartPose(s);
  PoseOptimizerOptions ceres, own;
  ceres.own_solver = false;
  own.own_solver = true;
  const PoseOptimizerResult a = OptimizePose(EurocLikeRig(), start, s.points, s.lines, ceres);
  const PoseOptimizerResult b = OptimizePose(EurocLikeRig(), start, s.points, s.lines, own);
  ASSERT_TRUE(a.success && b.success);
  EXPECT_EQ(a.point_inlier, b.point_inlier);
  EXPECT_EQ(a.line_inlier, b.line_inlier);
  EXPECT_LT(TranslationDifference(a.cam_from_world, b.cam_from_world), 1e-5);
  EXPECT_LT((b.cam_from_world.translation - s.t).norm(), 0.01);
}

// The same problem in Ceres, as OptimizePose built it before it had a solver of its own: every
// observation flagged in `use`, Huber losses when `robust`, line terms scaled by `line_weight`.
Rigid3d SolveWithCeres(const StereoRig& rig, const Scene& s, const Rigid3d& start,
                       const std::vector<bool>& use_points, const std::vector<bool>& use_lines,
                       bool robust, const PoseOptimizerOptions& o, int max_iterations, bool tight) {
  std::vector<Eigen::Vector3d> points;
  std::vector<std::array<double, kLineSize>> lines(s.lines.size());
  for (const PointObservation& obs : s.points) points.push_back(obs.point_w);
  ceres::Problem problem;
  std::array<double, kPoseSize> pose;
  PoseToParameters(start, pose.data());
  problem.AddParameterBlock(pose.data(), kPoseSize, new PoseManifold);
  for (size_t i = 0; i < s.points.size(); ++i) {
    if (!use_points[i]) continue;
    const PointObservation& obs = s.points[i];
    ceres::CostFunction* cost =
        obs.stereo ? static_cast<ceres::CostFunction*>(
                         new StereoPointCost(rig, obs.observed, obs.sigma_px))
                   : new PointCost(rig.camera, obs.observed.head<2>(), obs.sigma_px);
    ceres::LossFunction* loss =
        robust ? new ceres::HuberLoss(std::sqrt(obs.stereo ? o.chi2_stereo : o.chi2_mono))
               : nullptr;
    problem.AddResidualBlock(cost, loss, pose.data(), points[i].data());
    problem.SetParameterBlockConstant(points[i].data());
  }
  for (size_t i = 0; i < s.lines.size(); ++i) {
    if (!use_lines[i]) continue;
    const LineObservation& obs = s.lines[i];
    LineToParameters(OrthonormalLine::FromPlucker(obs.line_w), lines[i].data());
    ceres::LossFunction* loss = robust ? new ceres::HuberLoss(std::sqrt(o.chi2_line)) : nullptr;
    if (o.line_weight != 1.0) {
      loss = new ceres::ScaledLoss(loss, o.line_weight, ceres::TAKE_OWNERSHIP);
    }
    problem.AddResidualBlock(
        new LineCost(rig.camera, obs.start_px, obs.end_px, o.line_angle_weight, obs.sigma_px), loss,
        pose.data(), lines[i].data());
    problem.SetParameterBlockConstant(lines[i].data());
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = max_iterations;
  if (tight) {
    options.function_tolerance = 1e-14;
    options.gradient_tolerance = 1e-14;
    options.parameter_tolerance = 1e-14;
  }
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  EXPECT_TRUE(summary.IsSolutionUsable()) << summary.BriefReport();
  Rigid3d solved;
  ParametersToPose(pose.data(), &solved);
  return solved;
}

// The pose solver is our own Levenberg-Marquardt (building a Ceres problem cost more than solving
// it). Its last round has no robust kernel and its inliers are stable here, so its pose must be
// the least-squares optimum over the inliers it reports: the one Ceres finds, solved to the end.
TEST(PoseOptimizer, FinalPoseIsCeresLeastSquaresOptimumOverTheInliers) {
  const StereoRig rig = EurocLikeRig();
  const Scene s = MakeScene(120, 25, 0.15, 6);
  const Rigid3d start = PerturbedStartPose(s);
  PoseOptimizerOptions own;
  own.own_solver = true;
  const PoseOptimizerResult r = OptimizePose(rig, start, s.points, s.lines, own);
  ASSERT_TRUE(r.success);
  const Rigid3d ceres_pose =
      SolveWithCeres(rig, s, start, r.point_inlier, r.line_inlier, false, {}, 100, true);
  EXPECT_LT(TranslationDifference(r.cam_from_world, ceres_pose), 1e-5);
  EXPECT_LT(RotationErrorDeg(r.cam_from_world.rotation, ceres_pose.rotation), 1e-4);
  EXPECT_GT(r.point_inliers, 80);
  EXPECT_GT(r.line_inliers, 15);
}

// Step by step as Ceres: one round of 1 and of 3 Levenberg-Marquardt steps from 10 cm off, with
// Huber losses over points and lines with 20 % gross outliers (the reweighting, the Jacobi scaling,
// the damping and the trust region's growth), and a non-robust round with the lines' cost scaled
// by 0.3 (ScaledLoss before). One step must agree to round-off. After three, the non-robust round
// differs by the last step: its cost change is within the function tolerance, and Ceres leaves
// it untaken where this solver takes it (7e-5 m here).
TEST(PoseOptimizer, StepsEqualCeresWithHuberAndScaledLines) {
  const StereoRig rig = EurocLikeRig();
  const Scene s = MakeScene(100, 30, 0.2, 8);
  const Rigid3d start = PerturbedStartPose(s);
  const std::vector<bool> all_points(s.points.size(), true), all_lines(s.lines.size(), true);
  for (const bool robust : {true, false}) {
    PoseOptimizerOptions o;
    o.own_solver = true;
    o.rounds = 1;
    o.robust_rounds = robust ? 1 : 0;
    o.line_weight = robust ? 1.0 : 0.3;
    for (const int steps : {1, 3}) {
      o.iterations_per_round = steps;
      const PoseOptimizerResult r = OptimizePose(rig, start, s.points, s.lines, o);
      ASSERT_TRUE(r.success);
      const Rigid3d ceres_pose =
          SolveWithCeres(rig, s, start, all_points, all_lines, robust, o, steps, false);
      const double tolerance_m = steps == 1 ? 1e-9 : 1e-4;
      EXPECT_LT(TranslationDifference(r.cam_from_world, ceres_pose), tolerance_m)
          << "robust " << robust << ", steps " << steps;
      EXPECT_LT(RotationErrorDeg(r.cam_from_world.rotation, ceres_pose.rotation),
                tolerance_m * 10.0)
          << "robust " << robust << ", steps " << steps;
      // Not already at the optimum after one step: the comparison measures a step.
      if (steps == 1) EXPECT_GT(TranslationDifference(r.cam_from_world, start), 0.01);
    }
  }
}

}  // namespace
}  // namespace slslam

namespace slslam {
namespace {

// The pose prior (the visual-inertial tracker's IMU prediction): alone it gives its mean and
// information, a weak prior changes nothing, a strong one holds
// the pose, two observations that make a pose with it, and the posterior information.
TEST(PoseOptimizerPrior, APriorWithNoUsefulObservationGivesItsMeanAndInformation) {
  const Scene s = MakeScene(10, 0, 0.0, 4);
  PosePrior prior;
  prior.mean = Rigid3d(s.R, s.t);
  Eigen::Matrix<double, 6, 6> M = Eigen::Matrix<double, 6, 6>::Random();
  prior.information = M * M.transpose() + 6.0 * Eigen::Matrix<double, 6, 6>::Identity();
  // Evaluate the prior's cost through the optimiser on a prior-only problem: with one weak
  // observation far away the result is the prior's mean.
  PoseOptimizerOptions options;
  std::vector<PointObservation> one = {s.points[0]};
  one[0].sigma_px = 1e6;
  const PoseOptimizerResult r =
      OptimizePose(EurocLikeRig(), PerturbedStartPose(s), one, {}, options, &prior);
  ASSERT_TRUE(r.success);
  EXPECT_LT(TranslationDifference(r.cam_from_world, prior.mean), 1e-6);
  EXPECT_LT(RotationErrorDeg(r.cam_from_world.rotation, prior.mean.rotation), 1e-5);
  EXPECT_LT((r.information - prior.information).norm(), 1e-6 * prior.information.norm());
}

TEST(PoseOptimizerPrior, AWeakPriorChangesNothingAndAStrongOneHoldsThePose) {
  const Scene s = MakeScene(150, 20, 0.1, 5);
  const Rigid3d start = PerturbedStartPose(s);
  const PoseOptimizerResult free = OptimizePose(EurocLikeRig(), start, s.points, s.lines);
  PosePrior weak;
  weak.mean = start;  // 8-10 cm and 2.5 degrees off the truth
  weak.information = 1e-9 * Eigen::Matrix<double, 6, 6>::Identity();
  const PoseOptimizerResult with_weak =
      OptimizePose(EurocLikeRig(), start, s.points, s.lines, {}, &weak);
  EXPECT_LT(TranslationDifference(free.cam_from_world, with_weak.cam_from_world), 1e-6);
  EXPECT_EQ(free.point_inliers, with_weak.point_inliers);
  // The posterior information holds the observations' (a fraction of a mm on 150 points).
  EXPECT_GT(with_weak.information.diagonal().head<3>().minCoeff(), 1e4);
  PosePrior strong = weak;
  strong.information = 1e12 * Eigen::Matrix<double, 6, 6>::Identity();
  const PoseOptimizerResult held =
      OptimizePose(EurocLikeRig(), start, s.points, s.lines, {}, &strong);
  EXPECT_LT(TranslationDifference(held.cam_from_world, start), 1e-4);
}

TEST(PoseOptimizerPrior, TwoObservationsAndThePriorMakeAPose) {
  const Scene s = MakeScene(2, 0, 0.0, 6);
  const Rigid3d truth(s.R, s.t);
  const Rigid3d start = PerturbedStartPose(s);
  EXPECT_FALSE(OptimizePose(EurocLikeRig(), start, s.points, {}).success);
  PosePrior prior;
  prior.mean = start;
  prior.information = Eigen::Matrix<double, 6, 6>::Identity() * 1e2;  // 10 cm, 5.7 degrees
  const PoseOptimizerResult r = OptimizePose(EurocLikeRig(), start, s.points, {}, {}, &prior);
  EXPECT_TRUE(r.success);
  EXPECT_EQ(r.point_inliers, 2);
  // Pulled towards the truth by the two points.
  const double before = TranslationDifference(start, truth);
  const double after = TranslationDifference(r.cam_from_world, truth);
  EXPECT_LT(after, before);
  EXPECT_THROW(
      {
        PosePrior bad = prior;
        bad.information(0, 0) = NAN;
        OptimizePose(EurocLikeRig(), start, s.points, {}, {}, &bad);
      },
      std::invalid_argument);
}

}  // namespace
}  // namespace slslam
