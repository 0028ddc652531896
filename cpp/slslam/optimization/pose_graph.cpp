#include "slslam/optimization/pose_graph.h"

#include <cmath>

#include <ceres/autodiff_cost_function.h>
#include <ceres/manifold.h>
#include <ceres/problem.h>
#include <ceres/solver.h>
#include <Eigen/Geometry>

#include "slslam/core/check.h"

namespace slslam {

namespace {

// Parameter blocks: q_cw [x, y, z, w] (Eigen's order) and t_cw.
struct RelativePoseCost {
  RelativePoseCost(const Rigid3d& a_from_b, double rot_scale, double trans_scale)
      : q_ab(a_from_b.rotation),
        t_ab(a_from_b.translation),
        rot_scale(rot_scale),
        trans_scale(trans_scale) {}

  template <typename T>
  bool operator()(const T* qa_raw, const T* ta_raw, const T* qb_raw, const T* tb_raw,
                  T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> qa(qa_raw), qb(qb_raw);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> ta(ta_raw), tb(tb_raw);
    // Estimated a_from_b = a_from_world * b_from_world^-1.
    const Eigen::Quaternion<T> q_est = qa * qb.conjugate();
    const Eigen::Matrix<T, 3, 1> t_est = ta - q_est * tb;
    const Eigen::Quaternion<T> dq = q_ab.cast<T>().conjugate() * q_est;
    Eigen::Map<Eigen::Matrix<T, 6, 1>> r(residual);
    r.template head<3>() = T(trans_scale) * (t_est - t_ab.cast<T>());
    // 2 vec(dq) is the rotation error angle for small errors; the sign keeps dq near +1.
    const T sign = dq.w() < T(0) ? T(-1) : T(1);
    r.template tail<3>() = T(2.0 * rot_scale) * sign * dq.vec();
    return true;
  }

  Eigen::Quaterniond q_ab;
  Eigen::Vector3d t_ab;
  double rot_scale, trans_scale;
};

}  // namespace

void PoseGraphOptions::Check() const {
  SLSLAM_CHECK(max_iterations >= 1, "pose graph max_iterations must be >= 1, got ", max_iterations);
  SLSLAM_CHECK(std::isfinite(rotation_sigma_rad) && rotation_sigma_rad > 0.0,
               "pose graph rotation_sigma_rad must be > 0, got ", rotation_sigma_rad);
  SLSLAM_CHECK(std::isfinite(translation_sigma_m) && translation_sigma_m > 0.0,
               "pose graph translation_sigma_m must be > 0, got ", translation_sigma_m);
}

Rigid3d RelativePose(const Rigid3d& a_from_world, const Rigid3d& b_from_world) {
  Rigid3d a_from_b;
  a_from_b.rotation = a_from_world.rotation * b_from_world.rotation.transpose();
  a_from_b.translation = a_from_world.translation - a_from_b.rotation * b_from_world.translation;
  return a_from_b;
}

PoseGraphReport OptimizePoseGraph(std::vector<BaPose>* poses,
                                  const std::vector<PoseGraphEdge>& edges,
                                  const PoseGraphOptions& options) {
  Require(poses != nullptr, "OptimizePoseGraph needs poses");
  options.Check();
  PoseGraphReport report;
  const int n = static_cast<int>(poses->size());
  std::vector<Eigen::Quaterniond> q(n);
  std::vector<Eigen::Vector3d> t(n);
  for (int i = 0; i < n; ++i) {
    q[i] = Eigen::Quaterniond((*poses)[i].cam_from_world.rotation).normalized();
    t[i] = (*poses)[i].cam_from_world.translation;
  }
  ceres::Problem problem;
  std::vector<bool> used(n, false);
  for (const PoseGraphEdge& e : edges) {
    SLSLAM_CHECK(e.a >= 0 && e.a < n && e.b >= 0 && e.b < n && e.a != e.b, "pose graph edge (", e.a,
                 ", ", e.b, ") does not join two of the ", n, " poses");
    SLSLAM_CHECK(std::isfinite(e.weight) && e.weight > 0.0, "pose graph edge weight must be > 0");
    const double w = std::sqrt(e.weight);
    auto* cost =
        new ceres::AutoDiffCostFunction<RelativePoseCost, 6, 4, 3, 4, 3>(new RelativePoseCost(
            e.a_from_b, w / options.rotation_sigma_rad, w / options.translation_sigma_m));
    problem.AddResidualBlock(cost, nullptr, q[e.a].coeffs().data(), t[e.a].data(),
                             q[e.b].coeffs().data(), t[e.b].data());
    used[e.a] = used[e.b] = true;
  }
  if (edges.empty()) return report;
  for (int i = 0; i < n; ++i) {
    if (!used[i]) continue;
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
  report.initial_cost = summary.initial_cost;
  report.final_cost = summary.final_cost;
  report.iterations = static_cast<int>(summary.iterations.size());
  report.solved = summary.IsSolutionUsable();
  if (!report.solved) return report;
  for (int i = 0; i < n; ++i) {
    if ((*poses)[i].fixed || !used[i]) continue;
    (*poses)[i].cam_from_world.rotation = q[i].normalized().toRotationMatrix();
    (*poses)[i].cam_from_world.translation = t[i];
  }
  return report;
}

}  // namespace slslam
