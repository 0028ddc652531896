#include "slslam/optimization/bundle_adjustment.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>

#include <ceres/iteration_callback.h>
#include <ceres/loss_function.h>
#include <ceres/ordered_groups.h>
#include <ceres/problem.h>
#include <ceres/solver.h>
#include <Eigen/Eigenvalues>

#include "slslam/core/check.h"
#include "slslam/optimization/cost_functions.h"
#include "slslam/optimization/inertial_factor.h"
#include "slslam/optimization/manifolds.h"
#include "slslam/optimization/schur_levenberg_marquardt.h"

namespace slslam {

namespace {

// Stops a solve once `abort` is set (checked after every iteration), discarding it, or once
// `interrupt` is set, keeping the last accepted iterate.
class StopCallback : public ceres::IterationCallback {
 public:
  StopCallback(const std::atomic<bool>* abort, const std::atomic<bool>* interrupt)
      : abort_(abort), interrupt_(interrupt) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    if (abort_ && abort_->load()) return ceres::SOLVER_ABORT;
    if (interrupt_ && interrupt_->load()) return ceres::SOLVER_TERMINATE_SUCCESSFULLY;
    return ceres::SOLVER_CONTINUE;
  }

 private:
  const std::atomic<bool>* abort_;
  const std::atomic<bool>* interrupt_;
};

struct Parameters {
  /// The poses', the lines' (each relative to its anchor) and then the speed-bias blocks'
  /// parameters in one buffer: all stay in the reduced system, one group of the elimination
  /// ordering, and Ceres orders a group's blocks by address; in one buffer that order is theirs,
  /// the same in every run.
  std::vector<double> reduced;
  int num_poses = 0;
  int num_lines = 0;
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3d> line_anchors;  ///< world points (LineCost's anchor)

  void Resize(size_t poses, size_t lines, size_t speed_biases) {
    num_poses = static_cast<int>(poses);
    num_lines = static_cast<int>(lines);
    num_speed_biases = static_cast<int>(speed_biases);
    reduced.assign(
        kPoseSize * poses + kLineSize * lines + kSpeedBiasSize * speed_biases + kGravitySize, 0.0);
  }
  int num_speed_biases = 0;
  /// The rotation of gravity's direction (CameraImuFactor's last block), after the speed-biases.
  double* gravity() { return speed_bias(num_speed_biases); }
  const double* gravity() const { return speed_bias(num_speed_biases); }
  double* speed_bias(int i) {
    return reduced.data() + kPoseSize * num_poses + kLineSize * num_lines + kSpeedBiasSize * i;
  }
  const double* speed_bias(int i) const {
    return reduced.data() + kPoseSize * num_poses + kLineSize * num_lines + kSpeedBiasSize * i;
  }
  double* pose(int i) { return reduced.data() + kPoseSize * i; }
  const double* pose(int i) const { return reduced.data() + kPoseSize * i; }
  double* line(int i) { return reduced.data() + kPoseSize * num_poses + kLineSize * i; }
  const double* line(int i) const { return reduced.data() + kPoseSize * num_poses + kLineSize * i; }
};

PluckerLine LineInWorld(const Parameters& p, int line) {
  PluckerLine world = ParametersToLine(p.line(line)).ToPlucker();
  world.n += p.line_anchors[line].cross(world.v);
  return world;
}

double PointChi2(const StereoRig& rig, const Parameters& p, const BaPointObservation& o) {
  Rigid3d cam_from_world;
  ParametersToPose(p.pose(o.pose), &cam_from_world);
  const double w = 1.0 / (o.sigma_px * o.sigma_px);
  if (o.stereo) {
    Eigen::Vector3d e;
    if (!StereoPointResidual(rig, cam_from_world, p.points[o.point], o.observed, &e)) {
      return INFINITY;
    }
    return w * e.squaredNorm();
  }
  Eigen::Vector2d e;
  if (!PointResidual(rig.camera, cam_from_world, p.points[o.point], o.observed.head<2>(), &e)) {
    return INFINITY;
  }
  return w * e.squaredNorm();
}

double LineChi2(const StereoRig& rig, const Parameters& p, const BaLineObservation& o) {
  Rigid3d cam_from_world;
  ParametersToPose(p.pose(o.pose), &cam_from_world);
  const PluckerLine line = LineInWorld(p, o.line);
  Eigen::Vector3d e;
  if (!LineResidual(rig.camera, cam_from_world, line, o.start_px, o.end_px, 0.0, &e)) {
    return INFINITY;
  }
  const Eigen::Vector3d middle =
      line.Transformed(cam_from_world)
          .ClosestPointToRay(rig.camera.Unproject(0.5 * (o.start_px + o.end_px)));
  if (!(middle.z() > 0.0)) return INFINITY;
  return e.head<2>().squaredNorm() / (o.sigma_px * o.sigma_px);
}

// The rotation of gravity's direction (kGravitySize) towards zero, whitened by 1 / sigma [rad].
class GravityPriorCost final : public ceres::SizedCostFunction<kGravitySize, kGravitySize> {
 public:
  explicit GravityPriorCost(double inverse_sigma) : inverse_sigma_(inverse_sigma) {}
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    for (int k = 0; k < kGravitySize; ++k) residuals[k] = inverse_sigma_ * parameters[0][k];
    if (jacobians && jacobians[0]) {
      for (int k = 0; k < kGravitySize * kGravitySize; ++k) {
        jacobians[0][k] = k % (kGravitySize + 1) == 0 ? inverse_sigma_ : 0.0;
      }
    }
    return true;
  }

 private:
  double inverse_sigma_;
};

// Per line, the tangent directions its observations determine (outliers left out, the poses
// held): the eigenvectors of its information sum_i J_i^T J_i (J_i: the line tangent Jacobian of
// observation i's residual, in sigmas) whose eigenvalue reaches `min_information`. All four:
// a 4 x 4 basis (the line is free as with LineManifold); none: 4 x 0 (the line is held).
std::vector<LineSubspaceManifold::Basis> DeterminedLineDirections(
    const StereoRig& rig, const Parameters& p, const BaProblem& ba,
    const std::vector<bool>& line_outlier, const BundleAdjustmentOptions& options) {
  std::vector<Eigen::Matrix4d> information(ba.lines.size(), Eigen::Matrix4d::Zero());
  double residual[3];
  std::array<double, 3 * kPoseSize> d_pose;
  std::array<double, 3 * kLineSize> d_line;
  double* jacobians[2] = {d_pose.data(), d_line.data()};
  for (size_t i = 0; i < ba.line_observations.size(); ++i) {
    if (line_outlier[i]) continue;
    const BaLineObservation& o = ba.line_observations[i];
    const LineCost cost(rig.camera, o.start_px, o.end_px, options.line_angle_weight, o.sigma_px,
                        p.line_anchors[o.line]);
    const double* parameters[2] = {p.pose(o.pose), p.line(o.line)};
    if (!cost.Evaluate(parameters, residual, jacobians)) continue;
    // (the tangent Jacobian sits in the first four of the five ambient columns)
    const Eigen::Matrix<double, 3, kLineTangentSize> j =
        Eigen::Map<const Eigen::Matrix<double, 3, kLineSize, Eigen::RowMajor>>(d_line.data())
            .leftCols<kLineTangentSize>();
    information[o.line] += j.transpose() * j;
  }
  std::vector<LineSubspaceManifold::Basis> determined(ba.lines.size());
  for (size_t l = 0; l < ba.lines.size(); ++l) {
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eigen(information[l]);
    int weak = 0;  // eigenvalues ascend
    while (weak < kLineTangentSize &&
           !(eigen.eigenvalues()(weak) >= options.line_min_information_per_rad2)) {
      ++weak;
    }
    determined[l] = eigen.eigenvectors().rightCols(kLineTangentSize - weak);
  }
  return determined;
}

// Every observation an outlier or not by its chi-square at the current estimate.
void ClassifyOutliers(const StereoRig& rig, const Parameters& params, const BaProblem& ba,
                      const BundleAdjustmentOptions& options, BundleAdjustmentReport* report) {
  for (size_t i = 0; i < ba.point_observations.size(); ++i) {
    const BaPointObservation& o = ba.point_observations[i];
    const double bound = o.stereo ? options.chi2_stereo : options.chi2_mono;
    report->point_outlier[i] = !(PointChi2(rig, params, o) <= bound);
  }
  for (size_t i = 0; i < ba.line_observations.size(); ++i) {
    report->line_outlier[i] =
        !(LineChi2(rig, params, ba.line_observations[i]) <= options.chi2_line);
  }
}

// The most free poses the own solver takes: its reduced system is dense (6 per free pose).
constexpr int kOwnSolverMaxFreePoses = 64;

// What one pass of either solver did, as SolveBundleAdjustment needs it.
struct PassSummary {
  bool ran = false;                  ///< the pass had a residual to minimise
  bool aborted = false;              ///< the abort flag ended it: its result is not to be used
  bool interrupted_unmoved = false;  ///< the interrupt ended it before any step was taken
  bool usable = false;               ///< the solver's result is usable
  int steps = 0, rejected_steps = 0;
  double initial_cost = 0.0, final_cost = 0.0;
};

// One pass by the own solver (BundleAdjustmentOptions::own_solver): the same residuals and losses
// as the Ceres pass below, a stereo observation as one block of three rows in both passes.
PassSummary SolvePassOwn(const StereoRig& rig, const BaProblem& ba,
                         const BundleAdjustmentOptions& options, bool robust,
                         const std::atomic<bool>* interrupt, const std::atomic<bool>* abort,
                         Parameters* params, const BundleAdjustmentReport* report) {
  std::vector<std::unique_ptr<ceres::CostFunction>> costs;
  std::vector<SchurTerm> terms;
  costs.reserve(ba.point_observations.size() + ba.line_observations.size());
  terms.reserve(costs.capacity());
  for (size_t i = 0; i < ba.point_observations.size(); ++i) {
    if (report->point_outlier[i]) continue;
    const BaPointObservation& o = ba.point_observations[i];
    SchurTerm term;
    if (o.stereo) {
      costs.push_back(std::make_unique<StereoPointCost>(rig, o.observed, o.sigma_px));
      term.huber = robust ? std::sqrt(options.chi2_stereo) : 0.0;
    } else {
      costs.push_back(std::make_unique<PointCost>(rig.camera, o.observed.head<2>(), o.sigma_px));
      term.huber = robust ? std::sqrt(options.chi2_mono) : 0.0;
    }
    term.cost = costs.back().get();
    term.pose = o.pose;
    term.landmark = o.point;
    terms.push_back(term);
  }
  for (size_t i = 0; i < ba.line_observations.size(); ++i) {
    if (report->line_outlier[i] || options.line_weight <= 0.0) continue;
    const BaLineObservation& o = ba.line_observations[i];
    costs.push_back(std::make_unique<LineCost>(rig.camera, o.start_px, o.end_px,
                                               options.line_angle_weight, o.sigma_px,
                                               params->line_anchors[o.line]));
    SchurTerm term;
    term.cost = costs.back().get();
    term.pose = o.pose;
    term.landmark = o.line;
    term.line = true;
    term.huber = robust ? std::sqrt(options.chi2_line) : 0.0;
    term.weight = options.line_weight;
    terms.push_back(term);
  }
  PassSummary summary;
  if (terms.empty()) return summary;
  SchurBlocks blocks;
  for (size_t i = 0; i < ba.poses.size(); ++i) {
    blocks.poses.push_back(params->pose(static_cast<int>(i)));
    blocks.pose_fixed.push_back(ba.poses[i].fixed);
  }
  for (Eigen::Vector3d& point : params->points) blocks.points.push_back(point.data());
  for (size_t i = 0; i < ba.lines.size(); ++i) {
    blocks.lines.push_back(params->line(static_cast<int>(i)));
  }
  const int iterations = robust ? options.robust_iterations : options.refine_iterations;
  const SchurSolveSummary solved =
      SolveSchurLevenbergMarquardt(terms, blocks, iterations, abort, interrupt);
  summary.ran = true;
  summary.aborted = solved.aborted;
  summary.interrupted_unmoved = solved.interrupted && !solved.moved;
  summary.usable = solved.usable;
  summary.steps = solved.steps;
  summary.rejected_steps = solved.rejected_steps;
  summary.initial_cost = solved.initial_cost;
  summary.final_cost = solved.final_cost;
  return summary;
}

// Solver options of one Ceres pass over the used blocks (the ordering below).
ceres::Solver::Options CeresPassOptions(const BaProblem& ba, const BundleAdjustmentOptions& options,
                                        bool robust, const std::vector<bool>& point_used,
                                        const std::vector<bool>& pose_used,
                                        const std::vector<bool>& line_used,
                                        Parameters* parameters) {
  Parameters& params = *parameters;
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::SPARSE_SCHUR;
  if (options.dogleg_with_lines &&
      std::any_of(line_used.begin(), line_used.end(), [](bool used) { return used; })) {
    solver_options.trust_region_strategy_type = ceres::DOGLEG;
  }
  solver_options.max_num_iterations =
      robust ? options.robust_iterations : options.refine_iterations;
  solver_options.num_threads = 1;
  // The points are eliminated, the poses and lines kept in the reduced system. In the refine
  // pass every point block has two rows (above) and every pose tangent six, so Ceres' Schur
  // eliminator runs its fixed-size <2, 3, 6> kernel; blocks of 2 and 3 rows, or lines
  // eliminated with their tangent of four (what Ceres does left to itself), make it fall back to
  // dynamic sizes. The robust pass keeps each stereo observation whole: a Huber loss on half of
  // it would be another objective. The ordering names every parameter block, in two groups
  // (with a third group for the lines, Ceres' order of the reduced system makes local BA slower,
  // benchmarks/log/realtime.md); Parameters keeps the second group's order fixed.
  if (std::any_of(point_used.begin(), point_used.end(), [](bool used) { return used; })) {
    auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
    for (size_t i = 0; i < ba.points.size(); ++i) {
      if (point_used[i]) ordering->AddElementToGroup(params.points[i].data(), 0);
    }
    for (size_t i = 0; i < ba.poses.size(); ++i) {
      if (pose_used[i]) ordering->AddElementToGroup(params.pose(i), 1);
    }
    for (size_t i = 0; i < ba.lines.size(); ++i) {
      if (line_used[i]) ordering->AddElementToGroup(params.line(i), 1);
    }
    std::vector<bool> state_used(ba.inertial.states.size(), false);
    for (const BaInertialFactor& f : ba.inertial.factors) {
      state_used[f.state_i] = state_used[f.state_j] = true;
    }
    for (size_t i = 0; i < state_used.size(); ++i) {
      if (state_used[i]) ordering->AddElementToGroup(params.speed_bias(static_cast<int>(i)), 1);
    }
    if (!ba.inertial.factors.empty()) ordering->AddElementToGroup(params.gravity(), 1);
    solver_options.linear_solver_ordering = ordering;
  }
  return solver_options;
}

// A Ceres pass's summary as the pass's (stopped by `abort`: aborted).
PassSummary PassSummaryOf(const ceres::Solver::Summary& solved, const std::atomic<bool>* abort,
                          const std::atomic<bool>* interrupt) {
  PassSummary summary;
  summary.ran = true;
  if (abort && abort->load()) {
    summary.aborted = true;
    return summary;
  }
  // (iterations[0] is the start itself; Ceres counts it among the successful steps)
  const bool moved =
      solved.iterations.size() > 1 &&
      std::any_of(solved.iterations.begin() + 1, solved.iterations.end(),
                  [](const ceres::IterationSummary& it) { return it.step_is_successful; });
  summary.interrupted_unmoved = interrupt && interrupt->load() && !moved;
  // (iterations[0] is the start, not a step)
  summary.steps = std::max(static_cast<int>(solved.iterations.size()) - 1, 0);
  summary.rejected_steps = solved.num_unsuccessful_steps;
  summary.initial_cost = solved.initial_cost;
  summary.final_cost = solved.final_cost;
  summary.usable = solved.IsSolutionUsable();
  return summary;
}

// One pass by Ceres (SPARSE_SCHUR; the pull, the dogleg, held line directions, large problems).
PassSummary SolvePassCeres(const StereoRig& rig, const BaProblem& ba,
                           const BundleAdjustmentOptions& options, bool robust,
                           const std::atomic<bool>* interrupt, const std::atomic<bool>* abort,
                           Parameters* parameters, const BundleAdjustmentReport* outliers) {
  Parameters& params = *parameters;
  const BundleAdjustmentReport& report = *outliers;
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem solver_problem(problem_options);
  std::vector<bool> pose_used(ba.poses.size(), false);
  std::vector<bool> line_used(ba.lines.size(), false);
  std::vector<bool> point_used(ba.points.size(), false);
  // Each line free in the directions its observations determine, held in the others.
  std::vector<LineSubspaceManifold::Basis> determined;
  if (options.line_min_information_per_rad2 > 0.0) {
    determined = DeterminedLineDirections(rig, params, ba, report.line_outlier, options);
  }
  int blocks = 0;
  for (size_t i = 0; i < ba.point_observations.size(); ++i) {
    if (report.point_outlier[i]) continue;
    const BaPointObservation& o = ba.point_observations[i];
    double* pose = params.pose(o.pose);
    double* point = params.points[o.point].data();
    if (o.stereo && robust) {
      solver_problem.AddResidualBlock(new StereoPointCost(rig, o.observed, o.sigma_px),
                                      new ceres::HuberLoss(std::sqrt(options.chi2_stereo)), pose,
                                      point);
    } else if (o.stereo) {
      // Without a loss, the same rows as two blocks of two (StereoPointHalfCost): see the
      // ordering below.
      for (int half = 0; half < 2; ++half) {
        solver_problem.AddResidualBlock(new StereoPointHalfCost(rig, o.observed, o.sigma_px, half),
                                        nullptr, pose, point);
      }
    } else {
      ceres::LossFunction* loss =
          robust ? new ceres::HuberLoss(std::sqrt(options.chi2_mono)) : nullptr;
      solver_problem.AddResidualBlock(new PointCost(rig.camera, o.observed.head<2>(), o.sigma_px),
                                      loss, pose, point);
    }
    point_used[o.point] = true;
    pose_used[o.pose] = true;
    ++blocks;
  }
  for (size_t i = 0; i < ba.line_observations.size(); ++i) {
    if (report.line_outlier[i] || options.line_weight <= 0.0) continue;
    const BaLineObservation& o = ba.line_observations[i];
    ceres::CostFunction* cost =
        new LineCost(rig.camera, o.start_px, o.end_px, options.line_angle_weight, o.sigma_px,
                     params.line_anchors[o.line]);
    ceres::LossFunction* loss =
        robust ? new ceres::HuberLoss(std::sqrt(options.chi2_line)) : nullptr;
    if (options.line_weight != 1.0) {
      loss = new ceres::ScaledLoss(loss, options.line_weight, ceres::TAKE_OWNERSHIP);
    }
    solver_problem.AddResidualBlock(cost, loss, params.pose(o.pose), params.line(o.line));
    if (!line_used[o.line]) {
      double* line = params.line(o.line);
      const int free =
          determined.empty() ? kLineTangentSize : static_cast<int>(determined[o.line].cols());
      if (free > 0 && free < kLineTangentSize) {
        solver_problem.SetManifold(line, new LineSubspaceManifold(determined[o.line]));
      } else {
        solver_problem.SetManifold(line, new LineManifold);
      }
      if (free == 0) solver_problem.SetParameterBlockConstant(line);
      if (options.line_prior_weight > 0.0) {
        solver_problem.AddResidualBlock(new LinePriorCost(line, options.line_prior_weight), nullptr,
                                        line);
      }
    }
    line_used[o.line] = true;
    pose_used[o.pose] = true;
    ++blocks;
  }
  // The IMU between keyframes: no loss (ORB-SLAM3's inertial edges are not robust either).
  std::vector<bool> state_added(ba.inertial.states.size(), false);
  for (const BaInertialFactor& f : ba.inertial.factors) {
    solver_problem.AddResidualBlock(
        new CameraImuFactor(f.pre, ba.inertial.g_world, ba.inertial.body_from_cam), nullptr,
        params.pose(f.pose_i), params.speed_bias(f.state_i), params.pose(f.pose_j),
        params.speed_bias(f.state_j), params.gravity());
    pose_used[f.pose_i] = pose_used[f.pose_j] = true;
    for (int state : {f.state_i, f.state_j}) {
      if (state_added[state]) continue;
      state_added[state] = true;
      if (ba.inertial.states[state].fixed) {
        solver_problem.SetParameterBlockConstant(params.speed_bias(state));
      }
    }
    ++blocks;
  }
  if (!ba.inertial.factors.empty()) {
    if (ba.inertial.gravity_sigma_rad > 0.0) {
      solver_problem.AddResidualBlock(new GravityPriorCost(1.0 / ba.inertial.gravity_sigma_rad),
                                      nullptr, params.gravity());
    } else {
      solver_problem.SetParameterBlockConstant(params.gravity());
    }
  }
  if (blocks == 0) return {};
  for (size_t i = 0; i < ba.poses.size(); ++i) {
    if (!pose_used[i]) continue;
    solver_problem.SetManifold(params.pose(i), new PoseManifold);
    if (ba.poses[i].fixed) solver_problem.SetParameterBlockConstant(params.pose(i));
  }

  ceres::Solver::Options solver_options =
      CeresPassOptions(ba, options, robust, point_used, pose_used, line_used, &params);
  solver_options.logging_type = ceres::SILENT;
  StopCallback stop_callback(abort, interrupt);
  if (abort || interrupt) solver_options.callbacks.push_back(&stop_callback);
  ceres::Solver::Summary solved;
  ceres::Solve(solver_options, &solver_problem, &solved);
  return PassSummaryOf(solved, abort, interrupt);
}

// Every observation and factor refers to entries the problem has.
void CheckIndices(const BaProblem& ba) {
  for (const auto& o : ba.point_observations) {
    Require(o.pose >= 0 && o.pose < static_cast<int>(ba.poses.size()) && o.point >= 0 &&
                o.point < static_cast<int>(ba.points.size()),
            "point observation refers to a missing pose or point");
  }
  for (const auto& o : ba.line_observations) {
    Require(o.pose >= 0 && o.pose < static_cast<int>(ba.poses.size()) && o.line >= 0 &&
                o.line < static_cast<int>(ba.lines.size()),
            "line observation refers to a missing pose or line");
  }

  for (const BaInertialFactor& f : ba.inertial.factors) {
    const int poses = static_cast<int>(ba.poses.size());
    const int states = static_cast<int>(ba.inertial.states.size());
    Require(f.pose_i >= 0 && f.pose_i < poses && f.pose_j >= 0 && f.pose_j < poses &&
                f.state_i >= 0 && f.state_i < states && f.state_j >= 0 && f.state_j < states,
            "IMU factor refers to a missing pose or speed-bias state");
  }
}

// The solver's parameters at the problem's estimate.
Parameters ParametersOf(const BaProblem& ba, const BundleAdjustmentOptions& options) {
  Parameters params;
  params.Resize(ba.poses.size(), ba.lines.size(), ba.inertial.states.size());
  for (size_t i = 0; i < ba.poses.size(); ++i) {
    PoseToParameters(ba.poses[i].cam_from_world, params.pose(i));
  }
  for (size_t i = 0; i < ba.inertial.states.size(); ++i) {
    const BaSpeedBias& state = ba.inertial.states[i];
    Eigen::Map<Eigen::Matrix<double, kSpeedBiasSize, 1>> vb(params.speed_bias(static_cast<int>(i)));
    vb << state.v_world_body, state.bias.gyro, state.bias.acc;
  }
  params.points = ba.points;
  // With the pull (line_prior_weight), each line anchored at the camera centre of its first
  // observation: the line as that camera's centre sees it, a few metres away, not as the world's
  // origin does, possibly far behind, so the pull's tangent means about the same everywhere.
  params.line_anchors.assign(ba.lines.size(), Eigen::Vector3d::Zero());
  if (options.line_prior_weight > 0.0) {
    std::vector<bool> anchored(ba.lines.size(), false);
    for (const auto& o : ba.line_observations) {
      if (anchored[o.line]) continue;
      params.line_anchors[o.line] = ba.poses[o.pose].cam_from_world.Center();
      anchored[o.line] = true;
    }
  }
  for (size_t i = 0; i < ba.lines.size(); ++i) {
    PluckerLine local = ba.lines[i];
    local.n -= params.line_anchors[i].cross(local.v);
    LineToParameters(OrthonormalLine::FromPlucker(local), params.line(i));
  }
  return params;
}

// The solver's parameters back into the problem.
void WriteBack(const Parameters& params, BaProblem* problem) {
  BaProblem& ba = *problem;
  for (size_t i = 0; i < ba.poses.size(); ++i) {
    ParametersToPose(params.pose(i), &ba.poses[i].cam_from_world);
  }
  ba.points = params.points;
  for (size_t i = 0; i < ba.lines.size(); ++i) {
    ba.lines[i] = LineInWorld(params, static_cast<int>(i));
  }
  if (!ba.inertial.factors.empty()) {
    ba.inertial.g_world = GravityDirection(
        ba.inertial.g_world, GravityTangentBasis(ba.inertial.g_world), params.gravity());
  }
  for (size_t i = 0; i < ba.inertial.states.size(); ++i) {
    const double* vb = params.speed_bias(static_cast<int>(i));
    BaSpeedBias& state = ba.inertial.states[i];
    state.v_world_body = Eigen::Map<const Eigen::Vector3d>(vb);
    state.bias.gyro = Eigen::Map<const Eigen::Vector3d>(vb + 3);
    state.bias.acc = Eigen::Map<const Eigen::Vector3d>(vb + 6);
  }
}

}  // namespace

void BundleAdjustmentOptions::Check() const {
  CheckInRange("ba.robust_iterations", robust_iterations, 0, 10000);
  CheckInRange("ba.refine_iterations", refine_iterations, 0, 10000);
  CheckAboveInRange("ba.chi2_mono", chi2_mono, 0.0, 1e6);
  CheckAboveInRange("ba.chi2_stereo", chi2_stereo, 0.0, 1e6);
  CheckAboveInRange("ba.chi2_line", chi2_line, 0.0, 1e6);
  CheckInRange("ba.line_angle_weight", line_angle_weight, 0.0, 1e6);
  CheckInRange("ba.line_weight", line_weight, 0.0, 1e6);
  CheckInRange("ba.line_prior_weight", line_prior_weight, 0.0, 1e6);
  CheckInRange("ba.line_min_information_per_rad2", line_min_information_per_rad2, 0.0, 1e12);
}

BundleAdjustmentReport SolveBundleAdjustment(const StereoRig& rig, BaProblem* problem,
                                             const BundleAdjustmentOptions& options,
                                             const std::atomic<bool>* abort,
                                             const std::atomic<bool>* interrupt) {
  rig.Check();
  options.Check();
  Require(problem != nullptr, "bundle adjustment needs a problem");
  BaProblem& ba = *problem;
  CheckIndices(ba);

  Parameters params = ParametersOf(ba, options);

  BundleAdjustmentReport report;
  report.point_outlier.assign(ba.point_observations.size(), false);
  report.line_outlier.assign(ba.line_observations.size(), false);
  for (size_t i = 0; i < ba.point_observations.size(); ++i) {
    report.point_outlier[i] = !std::isfinite(PointChi2(rig, params, ba.point_observations[i]));
  }
  for (size_t i = 0; i < ba.line_observations.size(); ++i) {
    report.line_outlier[i] = !std::isfinite(LineChi2(rig, params, ba.line_observations[i]));
  }

  // The own solver takes the default problem (no pull, no dogleg, every line direction free, no
  // IMU) with a reduced system small enough to be dense: a local BA window.
  const bool own =
      options.own_solver && options.line_prior_weight == 0.0 && ba.inertial.factors.empty() &&
      !options.dogleg_with_lines && options.line_min_information_per_rad2 == 0.0 &&
      std::count_if(ba.poses.begin(), ba.poses.end(),
                    [](const BaPose& pose) { return !pose.fixed; }) <= kOwnSolverMaxFreePoses;
  for (int pass = 0; pass < 2; ++pass) {
    const bool robust = pass == 0;
    const PassSummary summary =
        own ? SolvePassOwn(rig, ba, options, robust, interrupt, abort, &params, &report)
            : SolvePassCeres(rig, ba, options, robust, interrupt, abort, &params, &report);
    if (!summary.ran) return report;
    if (summary.aborted) {
      report.solved = false;
      return report;
    }
    // Interrupted before the first pass took a step: the estimate is the start, whose outliers
    // say nothing yet (ORB-SLAM's local BA returns untouched when its stop flag is already set).
    if (pass == 0 && summary.interrupted_unmoved) {
      report.solved = false;
      report.interrupted = true;
      return report;
    }
    report.iterations += summary.steps;
    report.rejected_steps += summary.rejected_steps;
    if (pass == 0) report.initial_cost = summary.initial_cost;
    report.final_cost = summary.final_cost;
    report.solved = summary.usable;

    ClassifyOutliers(rig, params, ba, options, &report);
    // Interrupted (a callback ended it, the parameters hold the last accepted iterate): no
    // further pass.
    if (interrupt && interrupt->load()) {
      report.interrupted = true;
      break;
    }
  }

  WriteBack(params, &ba);
  return report;
}

}  // namespace slslam
