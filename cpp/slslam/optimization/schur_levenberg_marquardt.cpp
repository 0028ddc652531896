#include "slslam/optimization/schur_levenberg_marquardt.h"

#include <algorithm>
#include <array>
#include <cmath>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/LU>

#include "slslam/core/check.h"
#include "slslam/optimization/manifolds.h"

namespace slslam {

namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;
constexpr int kPointSize = 3;

// The ambient state of every block the solve touches, in arrays of its own: the candidate of a
// step is a second State, the blocks are written back once at the end.
struct State {
  std::vector<std::array<double, kPoseSize>> poses;
  std::vector<std::array<double, kPointSize>> points;
  std::vector<std::array<double, kLineSize>> lines;
};

// The Gauss-Newton normal equations in blocks: per free pose, per landmark, and per term the
// coupling of its free pose with its landmark (J_pose^T W J_landmark).
template <int D>
struct LandmarkEquations {
  std::vector<Eigen::Matrix<double, D, D>> information;
  std::vector<Eigen::Matrix<double, D, 1>> gradient;
  void Reset(size_t n) {
    information.assign(n, Eigen::Matrix<double, D, D>::Zero());
    gradient.assign(n, Eigen::Matrix<double, D, 1>::Zero());
  }
};

struct NormalEquations {
  std::vector<Matrix6d> pose_information;  ///< per free pose
  std::vector<Vector6d> pose_gradient;
  LandmarkEquations<3> points;
  LandmarkEquations<4> lines;
  std::vector<Eigen::Matrix<double, 6, 3>> point_coupling;  ///< per term (points' terms)
  std::vector<Eigen::Matrix<double, 6, 4>> line_coupling;   ///< per term (lines' terms)
  double cost = 0.0;
};

class Solver {
 public:
  Solver(const std::vector<SchurTerm>& terms, const SchurBlocks& blocks)
      : terms_(terms), blocks_(blocks) {
    free_index_.assign(blocks.poses.size(), -1);
    point_used_.assign(blocks.points.size(), false);
    line_used_.assign(blocks.lines.size(), false);
    for (const SchurTerm& t : terms) {
      if (!blocks.pose_fixed[t.pose] && free_index_[t.pose] < 0) {
        free_index_[t.pose] = num_free_++;
      }
      (t.line ? line_used_ : point_used_)[t.landmark] = true;
    }
    free_poses_.resize(num_free_);
    for (size_t i = 0; i < free_index_.size(); ++i) {
      if (free_index_[i] >= 0) free_poses_[free_index_[i]] = static_cast<int>(i);
    }
    // Per landmark, its terms (those with a free pose couple it to the reduced system).
    point_terms_.assign(blocks.points.size(), {});
    line_terms_.assign(blocks.lines.size(), {});
    slot_.assign(terms.size(), 0);
    int point_slots = 0, line_slots = 0;
    for (size_t i = 0; i < terms.size(); ++i) {
      const SchurTerm& t = terms[i];
      slot_[i] = t.line ? line_slots++ : point_slots++;
      (t.line ? line_terms_ : point_terms_)[t.landmark].push_back(static_cast<int>(i));
    }
    num_point_slots_ = point_slots;
    num_line_slots_ = line_slots;
    state_.poses.resize(blocks.poses.size());
    state_.points.resize(blocks.points.size());
    state_.lines.resize(blocks.lines.size());
    for (size_t i = 0; i < blocks.poses.size(); ++i) {
      std::copy(blocks.poses[i], blocks.poses[i] + kPoseSize, state_.poses[i].begin());
    }
    for (size_t i = 0; i < blocks.points.size(); ++i) {
      if (point_used_[i]) {
        std::copy(blocks.points[i], blocks.points[i] + kPointSize, state_.points[i].begin());
      }
    }
    for (size_t i = 0; i < blocks.lines.size(); ++i) {
      if (line_used_[i]) {
        std::copy(blocks.lines[i], blocks.lines[i] + kLineSize, state_.lines[i].begin());
      }
    }
  }

  SchurSolveSummary Run(int max_iterations, const std::atomic<bool>* abort,
                        const std::atomic<bool>* interrupt);

 private:
  bool Evaluate(const State& x, NormalEquations* out) const;
  bool EvaluateCost(const State& x, double* cost) const;
  template <int D>
  void EliminateLandmarks(const LandmarkEquations<D>& eq,
                          const std::vector<Eigen::Matrix<double, 6, D>>& coupling,
                          const std::vector<std::vector<int>>& landmark_terms,
                          const std::vector<bool>& used,
                          const std::vector<Eigen::Matrix<double, D, 1>>& scale, double radius,
                          Eigen::MatrixXd* reduced, Eigen::VectorXd* rhs,
                          std::vector<Eigen::Matrix<double, D, D>>* inverse) const;
  template <int D>
  void BackSubstitute(const LandmarkEquations<D>& eq,
                      const std::vector<Eigen::Matrix<double, 6, D>>& coupling,
                      const std::vector<std::vector<int>>& landmark_terms,
                      const std::vector<bool>& used,
                      const std::vector<Eigen::Matrix<double, D, D>>& inverse,
                      const Eigen::VectorXd& pose_step,
                      std::vector<Eigen::Matrix<double, D, 1>>* step) const;
  void Candidate(const NormalEquations& current, const Eigen::VectorXd& pose_step,
                 const std::vector<Eigen::Vector3d>& point_step,
                 const std::vector<Eigen::Vector4d>& line_step, State* candidate,
                 double* step_squared, double* state_squared, double* gd, double* dhd) const;
  void WriteBack() const;

  const std::vector<SchurTerm>& terms_;
  const SchurBlocks& blocks_;
  std::vector<int> free_index_;  ///< per pose: its index among the free poses, or -1
  std::vector<int> free_poses_;  ///< per free pose: its pose
  int num_free_ = 0;
  std::vector<bool> point_used_, line_used_;
  std::vector<std::vector<int>> point_terms_, line_terms_;
  std::vector<int> slot_;  ///< per term: its index among the points' or the lines' terms
  int num_point_slots_ = 0, num_line_slots_ = 0;
  State state_;
};

// One term's rows into the normal equations: the loss as Ceres applies a Huber loss (rho'' <= 0:
// the corrector is a plain square-root reweighting, here the weight rho').
template <int Rows, int D>
void Accumulate(const double* residual, const double* jacobian_pose,
                const double* jacobian_landmark, int landmark_ambient, double w, int free,
                int landmark, int slot, NormalEquations* out, LandmarkEquations<D>* eq,
                std::vector<Eigen::Matrix<double, 6, D>>* coupling) {
  const Eigen::Map<const Eigen::Matrix<double, Rows, 1>> r(residual);
  const Eigen::Map<const Eigen::Matrix<double, Rows, kPoseSize, Eigen::RowMajor>> jp_full(
      jacobian_pose);
  const Eigen::Matrix<double, Rows, 6> jp = jp_full.template leftCols<6>();
  Eigen::Matrix<double, Rows, D> jl;
  for (int row = 0; row < Rows; ++row) {
    for (int c = 0; c < D; ++c) jl(row, c) = jacobian_landmark[row * landmark_ambient + c];
  }
  const Eigen::Matrix<double, D, Rows> wjl_t = w * jl.transpose();
  eq->information[landmark].noalias() += wjl_t * jl;
  eq->gradient[landmark].noalias() += wjl_t * r;
  if (free >= 0) {
    const Eigen::Matrix<double, 6, Rows> wjp_t = w * jp.transpose();
    out->pose_information[free].noalias() += wjp_t * jp;
    out->pose_gradient[free].noalias() += wjp_t * r;
    (*coupling)[slot].noalias() = wjp_t * jl;
  }
}

double Loss(const SchurTerm& t, double squared, double* rho1) {
  double rho = squared;
  *rho1 = 1.0;
  if (t.huber > 0.0 && squared > t.huber * t.huber) {
    const double norm = std::sqrt(squared);
    rho = 2.0 * t.huber * norm - t.huber * t.huber;
    *rho1 = t.huber / norm;
  }
  return t.weight * rho;
}

bool Solver::Evaluate(const State& x, NormalEquations* out) const {
  out->pose_information.assign(num_free_, Matrix6d::Zero());
  out->pose_gradient.assign(num_free_, Vector6d::Zero());
  out->points.Reset(blocks_.points.size());
  out->lines.Reset(blocks_.lines.size());
  out->point_coupling.resize(num_point_slots_);
  out->line_coupling.resize(num_line_slots_);
  out->cost = 0.0;
  double residual[3];
  double jacobian_pose[3 * kPoseSize];
  double jacobian_landmark[3 * kLineSize];
  double* jacobians[2] = {jacobian_pose, jacobian_landmark};
  for (size_t i = 0; i < terms_.size(); ++i) {
    const SchurTerm& t = terms_[i];
    const double* landmark = t.line ? x.lines[t.landmark].data() : x.points[t.landmark].data();
    const double* parameters[2] = {x.poses[t.pose].data(), landmark};
    if (!t.cost->Evaluate(parameters, residual, jacobians)) return false;
    const int rows = t.cost->num_residuals();
    double squared = 0.0;
    for (int r = 0; r < rows; ++r) squared += residual[r] * residual[r];
    double rho1 = 1.0;
    out->cost += 0.5 * Loss(t, squared, &rho1);
    const double w = t.weight * rho1;
    const int free = free_index_[t.pose];
    if (t.line) {
      Accumulate<3, 4>(residual, jacobian_pose, jacobian_landmark, kLineSize, w, free, t.landmark,
                       slot_[i], out, &out->lines, &out->line_coupling);
    } else if (rows == 3) {
      Accumulate<3, 3>(residual, jacobian_pose, jacobian_landmark, kPointSize, w, free, t.landmark,
                       slot_[i], out, &out->points, &out->point_coupling);
    } else {
      Accumulate<2, 3>(residual, jacobian_pose, jacobian_landmark, kPointSize, w, free, t.landmark,
                       slot_[i], out, &out->points, &out->point_coupling);
    }
  }
  // A non-finite value fails the evaluation, as in Ceres.
  return std::isfinite(out->cost);
}

bool Solver::EvaluateCost(const State& x, double* cost) const {
  *cost = 0.0;
  double residual[3];
  for (const SchurTerm& t : terms_) {
    const double* landmark = t.line ? x.lines[t.landmark].data() : x.points[t.landmark].data();
    const double* parameters[2] = {x.poses[t.pose].data(), landmark};
    if (!t.cost->Evaluate(parameters, residual, nullptr)) return false;
    double squared = 0.0;
    for (int r = 0; r < t.cost->num_residuals(); ++r) squared += residual[r] * residual[r];
    double rho1 = 1.0;
    *cost += 0.5 * Loss(t, squared, &rho1);
  }
  return std::isfinite(*cost);
}

// Jacobi scaling as Ceres': 1 / (1 + the column's norm), from the start's Jacobian.
template <int D>
Eigen::Matrix<double, D, 1> Scale(const Eigen::Matrix<double, D, D>& information) {
  return (Eigen::Matrix<double, D, 1>::Ones() + information.diagonal().cwiseSqrt()).cwiseInverse();
}

// Levenberg-Marquardt's damping of a block's diagonal, in the unscaled coordinates: Ceres adds
// clamp(s^2 h, 1e-6, 1e32) / radius to the scaled system's diagonal s^2 h (s: the scale).
template <int D>
Eigen::Matrix<double, D, 1> Damping(const Eigen::Matrix<double, D, D>& information,
                                    const Eigen::Matrix<double, D, 1>& scale, double radius) {
  const Eigen::Matrix<double, D, 1> s2 = scale.cwiseAbs2();
  return (s2.cwiseProduct(information.diagonal()).cwiseMax(1e-6).cwiseMin(1e32) / radius)
      .cwiseQuotient(s2);
}

template <int D>
void Solver::EliminateLandmarks(const LandmarkEquations<D>& eq,
                                const std::vector<Eigen::Matrix<double, 6, D>>& coupling,
                                const std::vector<std::vector<int>>& landmark_terms,
                                const std::vector<bool>& used,
                                const std::vector<Eigen::Matrix<double, D, 1>>& scale,
                                double radius, Eigen::MatrixXd* reduced, Eigen::VectorXd* rhs,
                                std::vector<Eigen::Matrix<double, D, D>>* inverse) const {
  inverse->resize(used.size());
  std::vector<Eigen::Matrix<double, 6, D>> y;  // per coupled term: W A^-1
  std::vector<int> free, coupled;  // per coupled term: its free pose, its coupling's slot
  for (size_t l = 0; l < used.size(); ++l) {
    if (!used[l]) continue;
    Eigen::Matrix<double, D, D> a = eq.information[l];
    a.diagonal() += Damping<D>(eq.information[l], scale[l], radius);
    (*inverse)[l] = a.inverse();
    y.clear();
    free.clear();
    coupled.clear();
    for (int t : landmark_terms[l]) {
      const int f = free_index_[terms_[t].pose];
      if (f < 0) continue;
      y.push_back(coupling[slot_[t]] * (*inverse)[l]);
      free.push_back(f);
      coupled.push_back(slot_[t]);
      // reduced right-hand side: -g_pose + W A^-1 g_landmark
      rhs->template segment<6>(6 * f).noalias() += y.back() * eq.gradient[l];
    }
    // S -= W_i A^-1 W_j^T over every pair of the landmark's coupled terms, lower triangle.
    for (size_t i = 0; i < y.size(); ++i) {
      for (size_t j = 0; j < y.size(); ++j) {
        if (free[i] < free[j]) continue;
        reduced->template block<6, 6>(6 * free[i], 6 * free[j]).noalias() -=
            y[i] * coupling[coupled[j]].transpose();
      }
    }
  }
}

template <int D>
void Solver::BackSubstitute(const LandmarkEquations<D>& eq,
                            const std::vector<Eigen::Matrix<double, 6, D>>& coupling,
                            const std::vector<std::vector<int>>& landmark_terms,
                            const std::vector<bool>& used,
                            const std::vector<Eigen::Matrix<double, D, D>>& inverse,
                            const Eigen::VectorXd& pose_step,
                            std::vector<Eigen::Matrix<double, D, 1>>* step) const {
  step->assign(used.size(), Eigen::Matrix<double, D, 1>::Zero());
  for (size_t l = 0; l < used.size(); ++l) {
    if (!used[l]) continue;
    Eigen::Matrix<double, D, 1> b = -eq.gradient[l];
    for (int t : landmark_terms[l]) {
      const int f = free_index_[terms_[t].pose];
      if (f >= 0) b.noalias() -= coupling[slot_[t]].transpose() * pose_step.segment<6>(6 * f);
    }
    (*step)[l].noalias() = inverse[l] * b;
  }
}

void Solver::WriteBack() const {
  for (int f = 0; f < num_free_; ++f) {
    const int i = free_poses_[f];
    std::copy(state_.poses[i].begin(), state_.poses[i].end(), blocks_.poses[i]);
  }
  for (size_t i = 0; i < blocks_.points.size(); ++i) {
    if (point_used_[i])
      std::copy(state_.points[i].begin(), state_.points[i].end(), blocks_.points[i]);
  }
  for (size_t i = 0; i < blocks_.lines.size(); ++i) {
    if (line_used_[i]) std::copy(state_.lines[i].begin(), state_.lines[i].end(), blocks_.lines[i]);
  }
}

// The largest absolute gradient entry of the used landmarks of one kind, or `at_least`.
template <int D>
double LargestGradient(const LandmarkEquations<D>& eq, const std::vector<bool>& used,
                       double at_least) {
  for (size_t l = 0; l < used.size(); ++l) {
    if (used[l]) at_least = std::max(at_least, eq.gradient[l].cwiseAbs().maxCoeff());
  }
  return at_least;
}

// One kind of landmark's part of a step (tangent size D, ambient size A, moved by `plus`): adds
// to the step's and the state's squared sizes and to the model's g^T d and d^T H d (the
// landmarks' own blocks; the cross terms come later), and writes the candidate's landmarks.
template <int D, size_t A, typename Plus>
void StepLandmarks(const LandmarkEquations<D>& eq, const std::vector<bool>& used,
                   const std::vector<Eigen::Matrix<double, D, 1>>& step,
                   const std::vector<std::array<double, A>>& state, const Plus& plus,
                   std::vector<std::array<double, A>>* candidate, double* step_squared,
                   double* state_squared, double* gd, double* dhd) {
  for (size_t l = 0; l < step.size(); ++l) {
    if (!used[l]) continue;
    const Eigen::Matrix<double, D, 1>& d = step[l];
    *step_squared += d.squaredNorm();
    *gd += eq.gradient[l].dot(d);
    *dhd += d.dot(eq.information[l] * d);
    for (double v : state[l]) *state_squared += v * v;
    plus(state[l].data(), d.data(), (*candidate)[l].data());
  }
}

// The candidate state_ + step (pose, point and line steps), with the step's and the state's
// squared norms and the terms g^T d and d^T H d of its model decrease -(g^T d + 1/2 d^T H d)
// (H undamped; the couplings' cross terms included).
void Solver::Candidate(const NormalEquations& current, const Eigen::VectorXd& pose_step,
                       const std::vector<Eigen::Vector3d>& point_step,
                       const std::vector<Eigen::Vector4d>& line_step, State* candidate,
                       double* step_squared, double* state_squared, double* gd, double* dhd) const {
  *step_squared = *state_squared = *gd = *dhd = 0.0;
  const PoseManifold pose_manifold;
  const LineManifold line_manifold;
  for (int f = 0; f < num_free_; ++f) {
    const Vector6d d = pose_step.segment<6>(6 * f);
    *step_squared += d.squaredNorm();
    *gd += current.pose_gradient[f].dot(d);
    *dhd += d.dot(current.pose_information[f] * d);
    const int i = free_poses_[f];
    for (double v : state_.poses[i]) *state_squared += v * v;
    pose_manifold.Plus(state_.poses[i].data(), d.data(), candidate->poses[i].data());
  }
  const auto point_plus = [](const double* x, const double* d, double* out) {
    for (int k = 0; k < kPointSize; ++k) out[k] = x[k] + d[k];
  };
  const auto line_plus = [&](const double* x, const double* d, double* out) {
    line_manifold.Plus(x, d, out);
  };
  StepLandmarks(current.points, point_used_, point_step, state_.points, point_plus,
                &candidate->points, step_squared, state_squared, gd, dhd);
  StepLandmarks(current.lines, line_used_, line_step, state_.lines, line_plus, &candidate->lines,
                step_squared, state_squared, gd, dhd);
  for (size_t i = 0; i < terms_.size(); ++i) {  // the couplings' cross terms, twice
    const SchurTerm& t = terms_[i];
    const int f = free_index_[t.pose];
    if (f < 0) continue;
    const Vector6d dp = pose_step.segment<6>(6 * f);
    *dhd += 2.0 * (t.line ? dp.dot(current.line_coupling[slot_[i]] * line_step[t.landmark])
                          : dp.dot(current.point_coupling[slot_[i]] * point_step[t.landmark]));
  }
}

SchurSolveSummary Solver::Run(int max_iterations, const std::atomic<bool>* abort,
                              const std::atomic<bool>* interrupt) {
  SchurSolveSummary summary;
  NormalEquations current;
  if (!Evaluate(state_, &current)) return summary;  // not usable: the blocks stay as given
  summary.usable = true;
  summary.initial_cost = summary.final_cost = current.cost;
  // Jacobi scaling from the start's Jacobian (Ceres computes it once per solve).
  std::vector<Vector6d> pose_scale(num_free_);
  for (int f = 0; f < num_free_; ++f) pose_scale[f] = Scale<6>(current.pose_information[f]);
  std::vector<Eigen::Vector3d> point_scale(blocks_.points.size(), Eigen::Vector3d::Ones());
  std::vector<Eigen::Vector4d> line_scale(blocks_.lines.size(), Eigen::Vector4d::Ones());
  for (size_t l = 0; l < point_scale.size(); ++l) {
    if (point_used_[l]) point_scale[l] = Scale<3>(current.points.information[l]);
  }
  for (size_t l = 0; l < line_scale.size(); ++l) {
    if (line_used_[l]) line_scale[l] = Scale<4>(current.lines.information[l]);
  }
  double radius = 1e4, decrease_factor = 2.0;
  const int n = 6 * num_free_;
  Eigen::MatrixXd reduced(n, n);
  Eigen::VectorXd rhs(n), pose_step(n);
  std::vector<Eigen::Matrix3d> point_inverse;
  std::vector<Eigen::Matrix4d> line_inverse;
  std::vector<Eigen::Vector3d> point_step;
  std::vector<Eigen::Vector4d> line_step;
  State candidate = state_;
  NormalEquations next;
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    if (abort && abort->load()) {
      summary.aborted = true;
      return summary;
    }
    if (interrupt && interrupt->load()) {
      summary.interrupted = true;
      break;
    }
    // Converged: the gradient's largest entry (Ceres: of x - Plus(x, -g)).
    double gradient_max = 0.0;
    for (const Vector6d& g : current.pose_gradient) {
      gradient_max = std::max(gradient_max, g.cwiseAbs().maxCoeff());
    }
    gradient_max = LargestGradient(current.points, point_used_, gradient_max);
    gradient_max = LargestGradient(current.lines, line_used_, gradient_max);
    if (gradient_max <= 1e-10) break;
    // The damped system, the landmarks eliminated.
    reduced.setZero();
    for (int f = 0; f < num_free_; ++f) {
      reduced.block<6, 6>(6 * f, 6 * f) = current.pose_information[f];
      reduced.block<6, 6>(6 * f, 6 * f).diagonal() +=
          Damping<6>(current.pose_information[f], pose_scale[f], radius);
      rhs.segment<6>(6 * f) = -current.pose_gradient[f];
    }
    EliminateLandmarks<3>(current.points, current.point_coupling, point_terms_, point_used_,
                          point_scale, radius, &reduced, &rhs, &point_inverse);
    EliminateLandmarks<4>(current.lines, current.line_coupling, line_terms_, line_used_, line_scale,
                          radius, &reduced, &rhs, &line_inverse);
    bool solved = true;
    if (n > 0) {
      const Eigen::LLT<Eigen::MatrixXd, Eigen::Lower> llt(reduced);
      solved = llt.info() == Eigen::Success;
      if (solved) pose_step = llt.solve(rhs);
    }
    BackSubstitute<3>(current.points, current.point_coupling, point_terms_, point_used_,
                      point_inverse, pose_step, &point_step);
    BackSubstitute<4>(current.lines, current.line_coupling, line_terms_, line_used_, line_inverse,
                      pose_step, &line_step);
    // The step's size, its model decrease -(g^T d + 1/2 d^T H d) (H undamped), the candidate.
    double step_squared = 0.0, state_squared = 0.0, gd = 0.0, dhd = 0.0;
    Candidate(current, pose_step, point_step, line_step, &candidate, &step_squared, &state_squared,
              &gd, &dhd);
    const bool finite = solved && std::isfinite(step_squared) && std::isfinite(dhd);
    ++summary.steps;
    if (finite && std::sqrt(step_squared) <= 1e-8 * (std::sqrt(state_squared) + 1e-8)) {
      --summary.steps;  // Ceres stops before trying a step this small
      break;
    }
    const double model_decrease = -(gd + 0.5 * dhd);
    double quality = -1.0;
    double candidate_cost = 0.0;
    const bool evaluated =
        finite && model_decrease > 0.0 && EvaluateCost(candidate, &candidate_cost);
    if (evaluated) quality = (current.cost - candidate_cost) / model_decrease;
    // Converged, as Ceres: a candidate whose cost differs from the current by at most 1e-6 of
    // it ends the solve without being taken or counted.
    if (evaluated && !(std::abs(current.cost - candidate_cost) > 1e-6 * current.cost)) {
      --summary.steps;
      break;
    }
    if (quality > 1e-3 && Evaluate(candidate, &next)) {
      // (the candidate keeps the old state: the next step overwrites every block it moves, and
      // the fixed poses are the same in both)
      std::swap(state_, candidate);
      std::swap(current, next);
      summary.moved = true;
      summary.final_cost = current.cost;
      radius = std::min(radius / std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * quality - 1.0, 3)), 1e16);
      decrease_factor = 2.0;
    } else {
      ++summary.rejected_steps;
      radius /= decrease_factor;
      decrease_factor *= 2.0;
      if (radius < 1e-32) break;
    }
  }
  WriteBack();
  return summary;
}

}  // namespace

SchurSolveSummary SolveSchurLevenbergMarquardt(const std::vector<SchurTerm>& terms,
                                               const SchurBlocks& blocks, int max_iterations,
                                               const std::atomic<bool>* abort,
                                               const std::atomic<bool>* interrupt) {
  Require(blocks.pose_fixed.size() == blocks.poses.size(), "Schur solver: one fixed flag per pose");
  for (const SchurTerm& t : terms) {
    Require(t.cost != nullptr && t.pose >= 0 && t.pose < static_cast<int>(blocks.poses.size()) &&
                t.landmark >= 0 &&
                t.landmark < static_cast<int>(t.line ? blocks.lines.size() : blocks.points.size()),
            "Schur solver: a term refers to a missing cost, pose or landmark");
  }
  Solver solver(terms, blocks);
  return solver.Run(max_iterations, abort, interrupt);
}

}  // namespace slslam
