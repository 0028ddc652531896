#include "slslam/optimization/pose_graph.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <utility>

#include <ceres/autodiff_cost_function.h>
#include <ceres/loss_function.h>
#include <ceres/manifold.h>
#include <ceres/problem.h>
#include <ceres/rotation.h>
#include <ceres/solver.h>
#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "slslam/geometry/rotation.h"

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
  e.weight = 1.0;
  e.information = Eigen::Matrix<double, 6, 6>::Identity();
  (*e.information)(2, 3) = std::nan("");
  EXPECT_THROW(OptimizePoseGraph(&poses, {e}), std::invalid_argument);
  e.information.reset();
  e.cauchy_scale = -1.0;
  EXPECT_THROW(OptimizePoseGraph(&poses, {e}), std::invalid_argument);
  PoseGraphOptions options;
  options.translation_sigma_m = 0.0;
  EXPECT_THROW(options.Check(), std::invalid_argument);
  options = PoseGraphOptions();
  options.gravity_in_world.setZero();
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

// --- Split-error edges: the visual loop closer's, bit for bit ---------------------------------

// The solver before edges could carry an information (the visual loop closer's): its cost and
// problem, kept as the reference that split-error edges must reproduce exactly.
struct FormerRelativePoseCost {
  template <typename T>
  bool operator()(const T* qa_raw, const T* ta_raw, const T* qb_raw, const T* tb_raw,
                  T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> qa(qa_raw), qb(qb_raw);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> ta(ta_raw), tb(tb_raw);
    const Eigen::Quaternion<T> q_est = qa * qb.conjugate();
    const Eigen::Matrix<T, 3, 1> t_est = ta - q_est * tb;
    const Eigen::Quaternion<T> dq = q_ab.cast<T>().conjugate() * q_est;
    Eigen::Map<Eigen::Matrix<T, 6, 1>> r(residual);
    r.template head<3>() = T(trans_scale) * (t_est - t_ab.cast<T>());
    const T sign = dq.w() < T(0) ? T(-1) : T(1);
    r.template tail<3>() = T(2.0 * rot_scale) * sign * dq.vec();
    return true;
  }

  Eigen::Quaterniond q_ab;
  Eigen::Vector3d t_ab;
  double rot_scale, trans_scale;
};

void SolveLikeTheFormerVisualGraph(std::vector<BaPose>* poses,
                                   const std::vector<PoseGraphEdge>& edges,
                                   const PoseGraphOptions& options) {
  const int n = static_cast<int>(poses->size());
  std::vector<Eigen::Quaterniond> q(n);
  std::vector<Eigen::Vector3d> t(n);
  for (int i = 0; i < n; ++i) {
    q[i] = Eigen::Quaterniond((*poses)[i].cam_from_world.rotation).normalized();
    t[i] = (*poses)[i].cam_from_world.translation;
  }
  ceres::Problem problem;
  for (const PoseGraphEdge& e : edges) {
    const double w = std::sqrt(e.weight);
    auto* cost = new ceres::AutoDiffCostFunction<FormerRelativePoseCost, 6, 4, 3, 4, 3>(
        new FormerRelativePoseCost{Eigen::Quaterniond(e.a_from_b.rotation), e.a_from_b.translation,
                                   w / options.rotation_sigma_rad,
                                   w / options.translation_sigma_m});
    problem.AddResidualBlock(cost, nullptr, q[e.a].coeffs().data(), t[e.a].data(),
                             q[e.b].coeffs().data(), t[e.b].data());
  }
  for (int i = 0; i < n; ++i) {
    problem.SetManifold(q[i].coeffs().data(), new ceres::EigenQuaternionManifold);
    if ((*poses)[i].fixed) {
      problem.SetParameterBlockConstant(q[i].coeffs().data());
      problem.SetParameterBlockConstant(t[i].data());
    }
  }
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.num_threads = 1;
  solver_options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);
  for (int i = 0; i < n; ++i) {
    if ((*poses)[i].fixed) continue;
    (*poses)[i].cam_from_world.rotation = q[i].normalized().toRotationMatrix();
    (*poses)[i].cam_from_world.translation = t[i];
  }
}

// A drifted loop with covisibility-like edges and random weights (every pose in an edge), solved
// by the shared solver and by the former one: the same bits.
TEST(PoseGraph, SplitErrorEdgesGiveTheFormerSolversResultsBitForBit) {
  const int n = 50;
  const std::vector<Rigid3d> truth = MakeCircle(n);
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::uniform_real_distribution<double> weight(0.2, 5.0);
  std::vector<BaPose> poses(n);
  poses[0] = {truth[0], true};
  std::vector<PoseGraphEdge> edges;
  const Eigen::Matrix3d bias =
      Eigen::AngleAxisd(0.3 * M_PI / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
  for (int i = 1; i < n; ++i) {
    PoseGraphEdge e;
    e.a = i - 1;
    e.b = i;
    e.a_from_b = RelativePose(truth[i - 1], truth[i]);
    e.a_from_b.rotation = e.a_from_b.rotation * bias;
    e.a_from_b.translation += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    e.weight = weight(rng);
    edges.push_back(e);
    poses[i].cam_from_world = e.a_from_b.Inverse() * poses[i - 1].cam_from_world;
  }
  for (int i = 2; i < n; i += 3) {
    PoseGraphEdge e;
    e.a = i - 2;
    e.b = i;
    e.a_from_b = RelativePose(truth[i - 2], truth[i]);
    e.weight = weight(rng);
    edges.push_back(e);
  }
  PoseGraphEdge loop;
  loop.a = 0;
  loop.b = n - 1;
  loop.a_from_b = RelativePose(truth[0], truth[n - 1]);
  edges.push_back(loop);
  PoseGraphOptions options;
  options.max_iterations = 15;
  const std::vector<BaPose> initial = poses;
  std::vector<BaPose> former = poses;
  SolveLikeTheFormerVisualGraph(&former, edges, options);
  ASSERT_TRUE(OptimizePoseGraph(&poses, edges, options).solved);
  for (int i = 0; i < n; ++i) {
    EXPECT_EQ(poses[i].cam_from_world.rotation, former[i].cam_from_world.rotation) << i;
    EXPECT_EQ(poses[i].cam_from_world.translation, former[i].cam_from_world.translation) << i;
  }
  // A real solve: the end of the loop moved.
  EXPECT_GT((poses[n - 1].cam_from_world.Center() - initial[n - 1].cam_from_world.Center()).norm(),
            0.1);
}

// --- Edges with an information and a robust loss (the LiDAR back end's graph) ---------------

using Matrix6d = Eigen::Matrix<double, 6, 6>;

BaPose KeyframeFromWorld(const Eigen::Isometry3d& world_from_keyframe, bool fixed = false) {
  return {Rigid3d::FromMatrix4(world_from_keyframe.matrix()).Inverse(), fixed};
}

// A 20 m circle of keyframes (world_from_keyframe), x forward, z up.
Eigen::Isometry3d OnCircle(double angle, double radius) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(angle + M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(radius * std::cos(angle), radius * std::sin(angle), 0.0);
  return T;
}

// Odometry with a yaw and scale drift round a circle; one loop edge between the last and the
// first keyframe (10x the odometry's information, under a Cauchy loss) pulls the loop closed.
TEST(PoseGraph, InformationLoopEdgeUnderCauchyLossRemovesDrift) {
  const int n = 60;
  std::vector<Eigen::Isometry3d> truth;
  for (int i = 0; i < n; ++i) truth.push_back(OnCircle(2 * M_PI * i / n, 20.0));
  // Odometry: true increments with 0.5 deg of extra yaw and 2 % extra length each.
  std::vector<Eigen::Isometry3d> drifted{truth[0]};
  std::vector<PoseGraphEdge> edges;
  for (int i = 1; i < n; ++i) {
    Eigen::Isometry3d inc = truth[i - 1].inverse() * truth[i];
    inc.translation() *= 1.02;
    inc.linear() = inc.linear() *
                   Eigen::AngleAxisd(0.5 * M_PI / 180, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    drifted.push_back(drifted.back() * inc);
    PoseGraphEdge e;
    e.a = i - 1;
    e.b = i;
    e.a_from_b = Rigid3d::FromMatrix4(inc.matrix());
    e.information = LeftTangentInformation(e.a_from_b, Matrix6d::Identity());
    edges.push_back(e);
  }
  PoseGraphEdge loop;
  loop.a = 0;
  loop.b = n - 1;
  loop.a_from_b = Rigid3d::FromMatrix4((truth[0].inverse() * truth[n - 1]).matrix());
  loop.information = LeftTangentInformation(loop.a_from_b, 10.0 * Matrix6d::Identity());
  loop.cauchy_scale = 1.0;
  edges.push_back(loop);
  std::vector<BaPose> poses;
  for (int i = 0; i < n; ++i) poses.push_back(KeyframeFromWorld(drifted[i], i == 0));

  auto max_error = [&](const std::vector<BaPose>& p) {
    double worst = 0.0;
    for (int i = 0; i < n; ++i) {
      worst = std::max(worst, (p[i].cam_from_world.Center() - truth[i].translation()).norm());
    }
    return worst;
  };
  const double before = max_error(poses);
  const BaPose first = poses[0];
  PoseGraphOptions options;
  options.max_iterations = 50;
  const PoseGraphReport report = OptimizePoseGraph(&poses, edges, options);
  ASSERT_TRUE(report.solved);
  EXPECT_GT(before, 5.0);  // the drift is real
  EXPECT_LT(max_error(poses), 0.15 * before);
  EXPECT_LT(report.final_cost, report.initial_cost);
  // The first keyframe stays where it was.
  EXPECT_EQ(poses[0].cam_from_world.rotation, first.cam_from_world.rotation);
  EXPECT_EQ(poses[0].cam_from_world.translation, first.cam_from_world.translation);
}

// The split error (t_est - t_ab, Log(R_ab^T R_est)) of an estimate against a measurement.
Eigen::Matrix<double, 6, 1> SplitError(const Rigid3d& estimated, const Rigid3d& measured) {
  Eigen::Matrix<double, 6, 1> e;
  e.head<3>() = estimated.translation - measured.translation;
  e.tail<3>() = LogSO3(Eigen::Quaterniond(measured.rotation.transpose() * estimated.rotation));
  return e;
}

// A symmetric positive definite 6x6 with cross terms, about 1/scale^2 on the diagonal.
Matrix6d RandomInformation(std::mt19937* rng, double scale) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Matrix6d A;
  for (int i = 0; i < 36; ++i) A(i) = u(*rng);
  return (A * A.transpose() + Matrix6d::Identity()) / (scale * scale);
}

TEST(PoseGraph, LeftTangentInformationIsTheSplitErrorsToFirstOrder) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Rigid3d measured(
      Eigen::AngleAxisd(0.8, Eigen::Vector3d(0.3, -1.0, 0.4).normalized()).toRotationMatrix(),
      Eigen::Vector3d(2.5, -1.0, 0.7));
  const Matrix6d split_information = RandomInformation(&rng, 0.1);
  const Matrix6d information = LeftTangentInformation(measured, split_information);
  EXPECT_LT((information - information.transpose()).norm(), 1e-9 * information.norm());
  for (const double size : {1e-3, 1e-5}) {
    Eigen::Matrix<double, 6, 1> d;
    for (int i = 0; i < 6; ++i) d(i) = size * u(rng);
    // estimated = [Exp(omega) | rho] * measured.
    const Rigid3d estimated = Rigid3d(ExpSO3(d.tail<3>()), d.head<3>()) * measured;
    const Eigen::Matrix<double, 6, 1> e = SplitError(estimated, measured);
    const double split_cost = e.dot(split_information * e);
    const double left_cost = d.dot(information * d);
    // Equal up to the second-order terms of e in d: relative difference O(|d| |t_ab|).
    EXPECT_NEAR(left_cost / split_cost, 1.0, 20.0 * size) << size;
  }
}

// The LiDAR back end's former solver (lidar/pose_graph.cpp, replaced by this one), kept as the
// reference its edges are converted against: poses world_from_keyframe (quaternion + position),
// the split error whitened by the square root of its information, loops under a Cauchy loss.
struct FormerLidarEdgeError {
  template <typename T>
  bool operator()(const T* qa_, const T* pa_, const T* qb_, const T* pb_, T* out) const {
    using V3 = Eigen::Matrix<T, 3, 1>;
    const Eigen::Map<const Eigen::Quaternion<T>> qa(qa_), qb(qb_);
    const Eigen::Map<const V3> pa(pa_), pb(pb_);
    const Eigen::Quaternion<T> qa_inv = qa.conjugate();
    const V3 t_est = qa_inv * (pb - pa);
    const Eigen::Quaternion<T> err = q_ab.cast<T>().conjugate() * (qa_inv * qb);
    T qe[4] = {err.w(), err.x(), err.y(), err.z()}, re[3];
    ceres::QuaternionToAngleAxis(qe, re);
    Eigen::Matrix<T, 6, 1> r;
    r.template head<3>() = t_est - t_ab.cast<T>();
    r.template tail<3>() = V3(re[0], re[1], re[2]);
    Eigen::Map<Eigen::Matrix<T, 6, 1>> residual(out);
    residual = sqrt_info.cast<T>() * r;
    return true;
  }

  Eigen::Quaterniond q_ab;
  Eigen::Vector3d t_ab;
  Matrix6d sqrt_info;
};

struct SplitEdge {
  int a = 0, b = 0;
  Eigen::Isometry3d a_from_b;
  Matrix6d information;
  bool loop = false;
};

std::vector<Eigen::Isometry3d> SolveLikeTheFormerLidarGraph(std::vector<Eigen::Isometry3d> poses,
                                                            const std::vector<SplitEdge>& edges,
                                                            double cauchy_scale) {
  const int n = static_cast<int>(poses.size());
  std::vector<Eigen::Quaterniond> q(n);
  std::vector<Eigen::Vector3d> p(n);
  ceres::Problem problem;
  for (int i = 0; i < n; ++i) {
    q[i] = Eigen::Quaterniond(poses[i].linear()).normalized();
    p[i] = poses[i].translation();
    problem.AddParameterBlock(q[i].coeffs().data(), 4, new ceres::EigenQuaternionManifold);
    problem.AddParameterBlock(p[i].data(), 3);
  }
  for (const SplitEdge& e : edges) {
    const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(e.information);
    const Matrix6d sqrt_info =
        eig.eigenvalues().cwiseSqrt().asDiagonal() * eig.eigenvectors().transpose();
    auto* error = new FormerLidarEdgeError{Eigen::Quaterniond(e.a_from_b.linear()),
                                           e.a_from_b.translation(), sqrt_info};
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<FormerLidarEdgeError, 6, 4, 3, 4, 3>(error),
        e.loop ? new ceres::CauchyLoss(cauchy_scale) : nullptr, q[e.a].coeffs().data(),
        p[e.a].data(), q[e.b].coeffs().data(), p[e.b].data());
  }
  problem.SetParameterBlockConstant(q[0].coeffs().data());
  problem.SetParameterBlockConstant(p[0].data());
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  solver.max_num_iterations = 50;
  solver.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  for (int i = 0; i < n; ++i) {
    poses[i].linear() = q[i].normalized().toRotationMatrix();
    poses[i].translation() = p[i];
  }
  return poses;
}

// The worst position [m] and rotation [rad] difference between two trajectories.
std::pair<double, double> MaxDifference(const std::vector<Eigen::Isometry3d>& x,
                                        const std::vector<Eigen::Isometry3d>& y) {
  double dp = 0.0, dr = 0.0;
  for (size_t i = 0; i < x.size(); ++i) {
    dp = std::max(dp, (x[i].translation() - y[i].translation()).norm());
    dr = std::max(dr, Eigen::AngleAxisd(x[i].linear().transpose() * y[i].linear()).angle());
  }
  return {dp, dr};
}

// A small noisy 3-D graph in the LiDAR back end's terms (world_from_keyframe, split information
// with cross terms, two loops under a Cauchy loss): the shared solver on the converted edges
// (poses inverted, information through LeftTangentInformation) finds the former solver's poses up
// to the second-order difference of the two errors; without the conversion it does not.
TEST(PoseGraph, ConvertedLidarEdgesMatchTheFormerLidarSolver) {
  const int n = 12;
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<Eigen::Isometry3d> truth;
  for (int i = 0; i < n; ++i) {
    Eigen::Isometry3d T = OnCircle(2 * M_PI * i / n, 8.0);
    T.linear() = T.linear() * Eigen::AngleAxisd(0.1 * std::sin(i), Eigen::Vector3d::UnitX());
    T.translation().z() = 0.5 * std::cos(0.7 * i);
    truth.push_back(T);
  }
  auto noisy = [&](const Eigen::Isometry3d& T, double sigma_m, double sigma_rad) {
    Eigen::Isometry3d out = T;
    out.translation() += sigma_m * Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    out.linear() =
        out.linear() * ExpSO3(sigma_rad * Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
    return out;
  };
  std::vector<SplitEdge> edges;
  std::vector<Eigen::Isometry3d> initial{truth[0]};
  for (int i = 1; i < n; ++i) {
    SplitEdge e{i - 1, i, noisy(truth[i - 1].inverse() * truth[i], 0.01, 0.003),
                RandomInformation(&rng, 0.02), false};
    edges.push_back(e);
    initial.push_back(initial.back() * e.a_from_b);
  }
  for (const auto& [a, b] : {std::pair{0, n - 1}, std::pair{3, 9}}) {
    edges.push_back({a, b, noisy(truth[a].inverse() * truth[b], 0.01, 0.003),
                     RandomInformation(&rng, 0.02), true});
  }
  const double cauchy_scale = 1.0;
  const std::vector<Eigen::Isometry3d> former =
      SolveLikeTheFormerLidarGraph(initial, edges, cauchy_scale);

  auto solve_shared = [&](bool convert) {
    std::vector<BaPose> poses;
    for (int i = 0; i < n; ++i) poses.push_back(KeyframeFromWorld(initial[i], i == 0));
    std::vector<PoseGraphEdge> shared;
    for (const SplitEdge& e : edges) {
      PoseGraphEdge s;
      s.a = e.a;
      s.b = e.b;
      s.a_from_b = Rigid3d::FromMatrix4(e.a_from_b.matrix());
      s.information = convert ? LeftTangentInformation(s.a_from_b, e.information) : e.information;
      s.cauchy_scale = e.loop ? cauchy_scale : 0.0;
      shared.push_back(s);
    }
    PoseGraphOptions options;
    options.max_iterations = 50;
    EXPECT_TRUE(OptimizePoseGraph(&poses, shared, options).solved);
    std::vector<Eigen::Isometry3d> out;
    for (const BaPose& pose : poses) {
      out.emplace_back(pose.cam_from_world.Inverse().ToMatrix4());
    }
    return out;
  };
  const double moved_m = MaxDifference(initial, former).first;
  const auto [dp, dr] = MaxDifference(solve_shared(true), former);
  const auto [dp_raw, dr_raw] = MaxDifference(solve_shared(false), former);
  EXPECT_GT(moved_m, 0.05);  // the graph had something to do
  EXPECT_LT(dp, 1e-3);
  EXPECT_LT(dr, 2e-4);
  EXPECT_GT(dp_raw, 20.0 * dp);  // the conversion matters
}

// --- 4 DoF: yaw about gravity and position ---------------------------------------------------

// A drifted loop whose drift is a yaw about gravity and a position offset growing along it (what
// a visual-inertial odometry drifts in): world_from_cam_i = D_i * world_from_cam_true_i with
// D_i = [Rot(up, i * 0.4 deg) | i * (1.5, -1, 0.5) cm]. The odometry edges are the drifted poses'
// relative poses, the loop edge the true one.
struct YawDriftedLoop {
  std::vector<Rigid3d> truth;  ///< cam_from_world
  std::vector<BaPose> poses;   ///< drifted, the first fixed
  std::vector<PoseGraphEdge> edges;
};

double MeanCenterError(const std::vector<BaPose>& poses, const std::vector<Rigid3d>& truth) {
  double sum = 0.0;
  for (size_t i = 0; i < poses.size(); ++i) sum += CenterError(poses[i], truth[i]);
  return sum / poses.size();
}

YawDriftedLoop MakeYawDriftedLoop(int n, const Eigen::Vector3d& up) {
  YawDriftedLoop loop;
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * M_PI * i / n;
    // The camera rolls and pitches a little along the way (x forward along the tangent).
    const Eigen::Matrix3d R_wc =
        Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
        ExpSO3(Eigen::Vector3d(0.05 * std::sin(3 * a), 0.08 * std::cos(a), 0));
    const Eigen::Vector3d centre(10.0 * std::cos(a), 10.0 * std::sin(a), 0.3 * std::sin(2 * a));
    const Rigid3d world_from_cam(R_wc, centre);
    loop.truth.push_back(world_from_cam.Inverse());
    const Rigid3d drift(Eigen::AngleAxisd(i * 0.4 * M_PI / 180.0, up).toRotationMatrix(),
                        i * Eigen::Vector3d(0.015, -0.01, 0.005));
    loop.poses.push_back({(drift * world_from_cam).Inverse(), i == 0});
  }
  for (int i = 1; i < n; ++i) {
    PoseGraphEdge e;
    e.a = i - 1;
    e.b = i;
    e.a_from_b = RelativePose(loop.poses[i - 1].cam_from_world, loop.poses[i].cam_from_world);
    loop.edges.push_back(e);
  }
  PoseGraphEdge closing;
  closing.a = 0;
  closing.b = n - 1;
  closing.a_from_b = RelativePose(loop.truth[0], loop.truth[n - 1]);
  loop.edges.push_back(closing);
  return loop;
}

TEST(PoseGraph, FourDofRemovesYawAndPositionDriftAndKeepsRollAndPitch) {
  const int n = 40;
  // A gravity off the world's z axis, so that nothing lines up by accident.
  const Eigen::Vector3d gravity = Eigen::Vector3d(0.1, -0.2, -1.0).normalized();
  for (const bool with_information : {false, true}) {
    SCOPED_TRACE(with_information ? "information edges" : "split-error edges");
    YawDriftedLoop loop = MakeYawDriftedLoop(n, -gravity);
    if (with_information) {
      for (PoseGraphEdge& e : loop.edges) e.information = 1e4 * Matrix6d::Identity();
    }
    const double drift_before = CenterError(loop.poses[n - 1], loop.truth[n - 1]);
    ASSERT_GT(drift_before, 0.5);
    const std::vector<BaPose> initial = loop.poses;
    PoseGraphOptions options;
    options.yaw_and_position_only = true;
    options.gravity_in_world = 3.0 * gravity;  // only the direction counts
    const PoseGraphReport report = OptimizePoseGraph(&loop.poses, loop.edges, options);
    ASSERT_TRUE(report.solved);
    EXPECT_LT(report.final_cost, 1e-3 * report.initial_cost);
    // The drift is what 4 DoF can move: the loop closes, the error along it shrinks.
    EXPECT_LT(CenterError(loop.poses[n - 1], loop.truth[n - 1]), 0.05 * drift_before);
    EXPECT_LT(MeanCenterError(loop.poses, loop.truth), 0.5 * MeanCenterError(initial, loop.truth));
    // Roll and pitch: the gravity direction seen from each camera, unchanged.
    double moved = 0.0;
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d g_before = initial[i].cam_from_world.rotation * gravity;
      const Eigen::Vector3d g_after = loop.poses[i].cam_from_world.rotation * gravity;
      EXPECT_LT((g_after - g_before).norm(), 1e-9) << i;
      moved = std::max(
          moved,
          (loop.poses[i].cam_from_world.rotation - initial[i].cam_from_world.rotation).norm());
    }
    EXPECT_GT(moved, 0.05);  // yet the rotations did turn
    EXPECT_EQ(loop.poses[0].cam_from_world.rotation, initial[0].cam_from_world.rotation);
    EXPECT_EQ(loop.poses[0].cam_from_world.translation, initial[0].cam_from_world.translation);
  }
}

TEST(PoseGraph, SixDofClosesTheSameYawDriftedLoop) {
  const int n = 40;
  const Eigen::Vector3d gravity = Eigen::Vector3d(0.1, -0.2, -1.0).normalized();
  YawDriftedLoop loop = MakeYawDriftedLoop(n, -gravity);
  const double drift_before = CenterError(loop.poses[n - 1], loop.truth[n - 1]);
  const PoseGraphReport report = OptimizePoseGraph(&loop.poses, loop.edges);
  ASSERT_TRUE(report.solved);
  EXPECT_LT(report.final_cost, 0.1 * report.initial_cost);
  EXPECT_LT(CenterError(loop.poses[n - 1], loop.truth[n - 1]), 0.05 * drift_before);
  const std::vector<BaPose> initial = MakeYawDriftedLoop(n, -gravity).poses;
  EXPECT_LT(MeanCenterError(loop.poses, loop.truth), 0.5 * MeanCenterError(initial, loop.truth));
  double tilt = 0.0;
  for (int i = 0; i < n; ++i) {
    tilt = std::max(tilt, (loop.poses[i].cam_from_world.rotation * gravity -
                           initial[i].cam_from_world.rotation * gravity)
                              .norm());
  }
  EXPECT_GT(tilt, 1e-3);  // 6 DoF moves roll and pitch too: what the 4-DoF mode prevents
}

}  // namespace
}  // namespace slslam
