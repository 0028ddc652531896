#include "slslam/optimization/pose_optimizer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <vector>

#include <ceres/cost_function.h>
#include <ceres/loss_function.h>
#include <ceres/problem.h>
#include <ceres/sized_cost_function.h>
#include <ceres/solver.h>
#include <Eigen/Cholesky>

#include "slslam/core/check.h"
#include "slslam/optimization/cost_functions.h"
#include "slslam/optimization/manifolds.h"

namespace slslam {

namespace {

// Chi-square of one observation at the given pose; +inf when it cannot be evaluated.
double PointChi2(const StereoRig& rig, const Rigid3d& cam_from_world, const PointObservation& obs) {
  const double w = 1.0 / (obs.sigma_px * obs.sigma_px);
  if (obs.stereo) {
    Eigen::Vector3d e;
    if (!StereoPointResidual(rig, cam_from_world, obs.point_w, obs.observed, &e)) return INFINITY;
    return w * e.squaredNorm();
  }
  Eigen::Vector2d e;
  if (!PointResidual(rig.camera, cam_from_world, obs.point_w, obs.observed.head<2>(), &e)) {
    return INFINITY;
  }
  return w * e.squaredNorm();
}

double LineChi2(const StereoRig& rig, const Rigid3d& cam_from_world, const LineObservation& obs) {
  Eigen::Vector3d e;
  if (!LineResidual(rig.camera, cam_from_world, obs.line_w, obs.start_px, obs.end_px, 0.0, &e)) {
    return INFINITY;
  }
  // The line must also be in front of the camera: its point nearest to the segment's middle ray.
  const PluckerLine line_c = obs.line_w.Transformed(cam_from_world);
  const Eigen::Vector3d middle =
      line_c.ClosestPointToRay(rig.camera.Unproject(0.5 * (obs.start_px + obs.end_px)));
  if (!(middle.z() > 0.0)) return INFINITY;
  return e.head<2>().squaredNorm() / (obs.sigma_px * obs.sigma_px);
}

// One observation in the pose problem: its cost (pose, landmark), the landmark's parameters (held
// constant) and its loss: weight * Huber(huber) in robust rounds, weight * squared norm otherwise.
struct PoseTerm {
  std::unique_ptr<ceres::CostFunction> cost;
  const double* landmark = nullptr;
  double huber = 0.0;   ///< Huber threshold on the whitened residual's norm [-]
  double weight = 1.0;  ///< scale of the term's cost [-]
  bool line = false;    ///< the landmark is a line (orthonormal parameters)
  bool prior = false;   ///< the pose prior: no landmark, never a kernel
};

// The pose prior's whitened residual L^T d (information = L L^T) with d = Minus(pose, mean) in
// the left tangent; its Jacobian in the tangent is taken as L^T (d's own Jacobian is the
// identity at d = 0, and off it by terms of the order of d).
class PosePriorCost final : public ceres::SizedCostFunction<6, kPoseSize> {
 public:
  explicit PosePriorCost(const PosePrior& prior) {
    PoseToParameters(prior.mean, mean_.data());
    const Eigen::LLT<Eigen::Matrix<double, 6, 6>> llt(prior.information);
    sqrt_information_t_ = llt.matrixL().transpose();
  }
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    Eigen::Matrix<double, 6, 1> d;
    PoseManifold().Minus(parameters[0], mean_.data(), d.data());
    Eigen::Map<Eigen::Matrix<double, 6, 1>> r(residuals);
    r = sqrt_information_t_ * d;
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      Eigen::Map<Eigen::Matrix<double, 6, kPoseSize, Eigen::RowMajor>> j(jacobians[0]);
      j.setZero();
      j.leftCols<6>() = sqrt_information_t_;
    }
    return true;
  }

 private:
  std::array<double, kPoseSize> mean_;
  Eigen::Matrix<double, 6, 6> sqrt_information_t_;
};

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

// The Gauss-Newton normal equations of the pose's 6-dim tangent, and the cost.
struct PoseNormalEquations {
  Matrix6d information = Matrix6d::Zero();  ///< J^T W J
  Vector6d gradient = Vector6d::Zero();     ///< J^T W r
  double cost = 0.0;
};

template <int Rows>
void AddToNormalEquations(const double* jacobian, const double* residual, double weight,
                          PoseNormalEquations* out) {
  const Eigen::Map<const Eigen::Matrix<double, Rows, kPoseSize, Eigen::RowMajor>> j(jacobian);
  const Eigen::Map<const Eigen::Matrix<double, Rows, 1>> r(residual);
  const auto tangent = j.template leftCols<6>();
  out->information.noalias() += (weight * tangent.transpose()) * tangent;
  out->gradient.noalias() += weight * (tangent.transpose() * r);
}

// The cost 1/2 sum weight * rho(|r|^2) at `pose` and its normal equations, each term reweighted
// by weight * rho'(|r|^2): what Ceres builds for a Huber loss, whose rho'' <= 0 makes its
// corrector a plain square-root reweighting. False when a term cannot be evaluated (a landmark
// behind the camera) or a value is not finite.
bool EvaluatePoseTerms(const std::vector<const PoseTerm*>& terms, bool robust, const double* pose,
                       PoseNormalEquations* out) {
  *out = PoseNormalEquations{};
  double residual[6];
  double jacobian[6 * kPoseSize];  // row-major rows x 7; the tangent is the first 6 columns
  for (const PoseTerm* term : terms) {
    const double* parameters[2] = {pose, term->landmark};
    double* jacobians[2] = {jacobian, nullptr};
    if (!term->cost->Evaluate(parameters, residual, jacobians)) return false;
    const int rows = term->cost->num_residuals();  // 2 or 3; 6 for the prior
    double squared = 0.0;
    for (int r = 0; r < rows; ++r) squared += residual[r] * residual[r];
    double rho = squared, rho1 = 1.0;
    if (robust && !term->prior && squared > term->huber * term->huber) {
      const double norm = std::sqrt(squared);
      rho = 2.0 * term->huber * norm - term->huber * term->huber;
      rho1 = term->huber / norm;
    }
    out->cost += 0.5 * term->weight * rho;
    const double w = term->weight * rho1;
    if (rows == 6) {
      AddToNormalEquations<6>(jacobian, residual, w, out);
    } else if (rows == 3) {
      AddToNormalEquations<3>(jacobian, residual, w, out);
    } else {
      AddToNormalEquations<2>(jacobian, residual, w, out);
    }
  }
  // A non-finite value fails the evaluation, as in Ceres.
  return std::isfinite(out->cost) && out->information.allFinite() && out->gradient.allFinite();
}

// Levenberg-Marquardt on the pose alone, with Ceres' trust-region rules: first radius 1e4 (at most
// 1e16, the solve ends below 1e-32), Jacobi scaling, damping by the scaled information's diagonal
// clamped to [1e-6, 1e32], a step of quality above 1e-3 accepted, the radius grown by
// 1 / max(1/3, 1 - (2 quality - 1)^3) or cut by a doubling factor. It stops at a gradient of
// 1e-10 or a step of 1e-8 relative to the parameters (both in the 6-dim tangent; Ceres measures
// them in the 7 parameters), after a step that lowered the cost by at most 1e-6 of it (below), or
// after `max_iterations` steps, rejected ones included.
// The default (PoseOptimizerOptions::own_solver): on a 6-parameter problem most of Ceres' time
// goes to building the problem and its bookkeeping (heap, maps), on every frame's tracking; on
// the long dark sequences this solver's accuracy is within the spread of simulator seeds of
// Ceres' (benchmarks/log/realtime.md). Ceres solves by QR of the Jacobian, this by the normal
// equations, so steps differ in the last digits (pose_optimizer_test compares steps with Huber
// losses and with scaled lines, and the whole outlier rounds, with Ceres). When the starting pose
// cannot be evaluated the pose stays as given, as Ceres' failed solve leaves it.
void SolvePoseLevenbergMarquardt(const std::vector<const PoseTerm*>& terms, bool robust,
                                 int max_iterations, double* pose) {
  PoseNormalEquations current;
  if (!EvaluatePoseTerms(terms, robust, pose, &current)) return;
  const PoseManifold manifold;
  double radius = 1e4, decrease_factor = 2.0;
  std::array<double, kPoseSize> candidate_pose;
  PoseNormalEquations candidate;
  // Ceres' Jacobi scaling: columns scaled by 1 / (1 + their norm) at the start, the damping
  // and its clamp applied in the scaled coordinates.
  const Vector6d scale =
      (Vector6d::Ones() + current.information.diagonal().cwiseSqrt()).cwiseInverse();
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    if (current.gradient.cwiseAbs().maxCoeff() <= 1e-10) return;
    Matrix6d damped = scale.asDiagonal() * current.information * scale.asDiagonal();
    const Vector6d diagonal = damped.diagonal().cwiseMax(1e-6).cwiseMin(1e32);
    damped.diagonal() += diagonal / radius;
    const Vector6d step =
        scale.cwiseProduct(damped.ldlt().solve(-scale.cwiseProduct(current.gradient)));
    const double pose_norm = Eigen::Map<const Eigen::Matrix<double, kPoseSize, 1>>(pose).norm();
    if (step.allFinite() && step.norm() <= 1e-8 * (pose_norm + 1e-8)) return;
    const double model_decrease =
        -(current.gradient.dot(step) + 0.5 * step.dot(current.information * step));
    double quality = -1.0;
    if (step.allFinite() && model_decrease > 0.0) {
      manifold.Plus(pose, step.data(), candidate_pose.data());
      if (EvaluatePoseTerms(terms, robust, candidate_pose.data(), &candidate)) {
        quality = (current.cost - candidate.cost) / model_decrease;
      }
    }
    if (quality > 1e-3) {
      const double relative_decrease = (current.cost - candidate.cost) / current.cost;
      std::copy(candidate_pose.begin(), candidate_pose.end(), pose);
      current = candidate;
      radius = std::min(radius / std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * quality - 1.0, 3)), 1e16);
      decrease_factor = 2.0;
      // Converged: a step that lowered the cost by at most 1e-6 of it. Ceres stops at such a
      // candidate without taking it (and at a rise as small); this takes the lower cost. Taking
      // it or not moves later poses in the last digits, and those decide, through the long dark
      // runs' chaos, e.g. whether a camera-only blackout in test_tracking.py comes back into
      // its map (benchmarks/log/realtime.md).
      if (!(relative_decrease > 1e-6)) return;
    } else {
      radius /= decrease_factor;
      decrease_factor *= 2.0;
      if (radius < 1e-32) return;
    }
  }
}

// The same problem solved by Ceres (DENSE_QR), for PoseOptimizerOptions::own_solver false. The
// terms' costs stay theirs; the problem owns the losses.
void SolvePoseCeres(const std::vector<const PoseTerm*>& terms, bool robust, int max_iterations,
                    double* pose) {
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::TAKE_OWNERSHIP;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  problem.AddParameterBlock(pose, kPoseSize, new PoseManifold);
  for (const PoseTerm* term : terms) {
    if (term->prior) {
      problem.AddResidualBlock(term->cost.get(), nullptr, pose);
      continue;
    }
    ceres::LossFunction* loss = robust ? new ceres::HuberLoss(term->huber) : nullptr;
    if (term->weight != 1.0) {
      loss = new ceres::ScaledLoss(loss, term->weight, ceres::TAKE_OWNERSHIP);
    }
    // (the landmark is constant; Ceres only reads it)
    double* landmark = const_cast<double*>(term->landmark);
    problem.AddResidualBlock(term->cost.get(), loss, pose, landmark);
    problem.SetParameterBlockConstant(landmark);
    if (term->line) problem.SetManifold(landmark, new LineManifold);
  }
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_QR;
  solver_options.max_num_iterations = max_iterations;
  solver_options.num_threads = 1;
  solver_options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);
}

// The pose problem's terms, one per observation, built once for all rounds (the same analytic
// costs as local BA), over the landmarks' parameters (sized by the caller, filled here: the
// costs point into them).
void BuildPoseTerms(const StereoRig& rig, const std::vector<PointObservation>& points,
                    const std::vector<LineObservation>& lines, const PoseOptimizerOptions& options,
                    std::vector<Eigen::Vector3d>* point_params_out,
                    std::vector<std::array<double, kLineSize>>* line_params_out,
                    std::vector<PoseTerm>* point_terms_out, std::vector<PoseTerm>* line_terms_out) {
  std::vector<Eigen::Vector3d>& point_params = *point_params_out;
  std::vector<std::array<double, kLineSize>>& line_params = *line_params_out;
  for (size_t i = 0; i < points.size(); ++i) point_params[i] = points[i].point_w;
  for (size_t i = 0; i < lines.size(); ++i) {
    LineToParameters(OrthonormalLine::FromPlucker(lines[i].line_w), line_params[i].data());
  }
  // One term per observation, built once for all rounds (the same analytic costs as local BA).
  std::vector<PoseTerm>& point_terms = *point_terms_out;
  point_terms.resize(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    const PointObservation& obs = points[i];
    PoseTerm& term = point_terms[i];
    if (obs.stereo) {
      term.cost = std::make_unique<StereoPointCost>(rig, obs.observed, obs.sigma_px);
      term.huber = std::sqrt(options.chi2_stereo);
    } else {
      term.cost = std::make_unique<PointCost>(rig.camera, obs.observed.head<2>(), obs.sigma_px);
      term.huber = std::sqrt(options.chi2_mono);
    }
    term.landmark = point_params[i].data();
  }
  // (a line weight of 0 leaves the lines out of the problem; they are still classified)
  std::vector<PoseTerm>& line_terms = *line_terms_out;
  line_terms.resize(options.line_weight > 0.0 ? lines.size() : 0);
  for (size_t i = 0; i < line_terms.size(); ++i) {
    const LineObservation& obs = lines[i];
    PoseTerm& term = line_terms[i];
    term.cost = std::make_unique<LineCost>(rig.camera, obs.start_px, obs.end_px,
                                           options.line_angle_weight, obs.sigma_px);
    term.huber = std::sqrt(options.chi2_line);
    term.weight = options.line_weight;
    term.line = true;
    term.landmark = line_params[i].data();
  }
}

// The terms of the observations classified as inliers in `result`.
void ActiveTerms(const PoseOptimizerResult& result, const std::vector<PoseTerm>& point_terms,
                 const std::vector<PoseTerm>& line_terms, std::vector<const PoseTerm*>* active) {
  active->clear();
  for (size_t i = 0; i < point_terms.size(); ++i) {
    if (result.point_inlier[i]) active->push_back(&point_terms[i]);
  }
  for (size_t i = 0; i < line_terms.size(); ++i) {
    if (result.line_inlier[i]) active->push_back(&line_terms[i]);
  }
}

}  // namespace

void PoseOptimizerOptions::Check() const {
  CheckInRange("pose.rounds", rounds, 1, 100);
  CheckInRange("pose.iterations_per_round", iterations_per_round, 1, 10000);
  CheckInRange("pose.robust_rounds", robust_rounds, 0, rounds);
  CheckAboveInRange("pose.chi2_mono", chi2_mono, 0.0, 1e6);
  CheckAboveInRange("pose.chi2_stereo", chi2_stereo, 0.0, 1e6);
  CheckAboveInRange("pose.chi2_line", chi2_line, 0.0, 1e6);
  CheckInRange("pose.line_angle_weight", line_angle_weight, 0.0, 1e6);
  CheckInRange("pose.line_weight", line_weight, 0.0, 1e6);
}

PoseOptimizerResult OptimizePose(const StereoRig& rig, const Rigid3d& cam_from_world,
                                 const std::vector<PointObservation>& points,
                                 const std::vector<LineObservation>& lines,
                                 const PoseOptimizerOptions& options, const PosePrior* prior) {
  rig.Check();
  Require(cam_from_world.rotation.allFinite() && cam_from_world.translation.allFinite(),
          "initial pose is not finite");
  options.Check();

  PoseOptimizerResult result;
  result.cam_from_world = cam_from_world;
  result.point_inlier.assign(points.size(), false);
  result.line_inlier.assign(lines.size(), false);
  for (size_t i = 0; i < points.size(); ++i) {
    result.point_inlier[i] = std::isfinite(PointChi2(rig, cam_from_world, points[i]));
  }
  for (size_t i = 0; i < lines.size(); ++i) {
    result.line_inlier[i] = std::isfinite(LineChi2(rig, cam_from_world, lines[i]));
  }

  // Landmarks are constants of this problem: their parameters, read by the costs.
  std::vector<Eigen::Vector3d> point_params(points.size());
  std::vector<std::array<double, kLineSize>> line_params(lines.size());
  std::vector<PoseTerm> point_terms, line_terms;
  BuildPoseTerms(rig, points, lines, options, &point_params, &line_params, &point_terms,
                 &line_terms);

  PoseTerm prior_term;
  if (prior != nullptr) {
    Require(prior->information.allFinite() && prior->mean.rotation.allFinite() &&
                prior->mean.translation.allFinite(),
            "pose prior is not finite");
    prior_term.cost = std::make_unique<PosePriorCost>(*prior);
    prior_term.prior = true;
  }
  // With a prior one observation is enough to keep; without, three determine a pose.
  const size_t min_active = prior != nullptr ? 1 : 3;

  std::array<double, kPoseSize> pose;
  PoseToParameters(cam_from_world, pose.data());
  std::vector<const PoseTerm*> active;
  for (int round = 0; round < options.rounds; ++round) {
    const bool robust = round < options.robust_rounds;
    ActiveTerms(result, point_terms, line_terms, &active);
    // Three points (or an equivalent set of lines) determine a pose; fewer is not a pose.
    if (active.size() < min_active) {
      if (round == 0) return result;  // success stays false, pose stays the initial guess
      break;
    }
    if (prior != nullptr) active.push_back(&prior_term);
    if (options.own_solver) {
      SolvePoseLevenbergMarquardt(active, robust, options.iterations_per_round, pose.data());
    } else {
      SolvePoseCeres(active, robust, options.iterations_per_round, pose.data());
    }

    Rigid3d solved;
    ParametersToPose(pose.data(), &solved);
    // Reclassify every observation, outliers included (an outlier may come back).
    for (size_t i = 0; i < points.size(); ++i) {
      const double bound = points[i].stereo ? options.chi2_stereo : options.chi2_mono;
      result.point_inlier[i] = PointChi2(rig, solved, points[i]) <= bound;
    }
    for (size_t i = 0; i < lines.size(); ++i) {
      result.line_inlier[i] = LineChi2(rig, solved, lines[i]) <= options.chi2_line;
    }
  }

  ParametersToPose(pose.data(), &result.cam_from_world);
  result.point_inliers =
      static_cast<int>(std::count(result.point_inlier.begin(), result.point_inlier.end(), true));
  result.line_inliers =
      static_cast<int>(std::count(result.line_inlier.begin(), result.line_inlier.end(), true));
  result.success = result.point_inliers + result.line_inliers >= static_cast<int>(min_active);
  if (prior != nullptr) {
    // The posterior information at the result: the inliers without kernel and the prior.
    ActiveTerms(result, point_terms, line_terms, &active);
    active.push_back(&prior_term);
    PoseNormalEquations at_result;
    if (EvaluatePoseTerms(active, /*robust=*/false, pose.data(), &at_result)) {
      result.information = at_result.information;
    }
  }
  return result;
}

}  // namespace slslam
