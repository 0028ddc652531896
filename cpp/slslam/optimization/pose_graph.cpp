#include "slslam/optimization/pose_graph.h"

#include <cmath>

#include <ceres/autodiff_cost_function.h>
#include <ceres/loss_function.h>
#include <ceres/manifold.h>
#include <ceres/problem.h>
#include <ceres/rotation.h>
#include <ceres/solver.h>
#include <Eigen/Geometry>

#include "slslam/core/check.h"
#include "slslam/geometry/rotation.h"
#include "slslam/optimization/sqrt_information.h"

namespace slslam {

namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

// The whitened error of an estimated a_from_b (q_est, t_est) against an edge's measurement, in
// either of the two forms pose_graph.h describes (split error with scalar weights, or the left
// tangent with an information).
class EdgeError {
 public:
  EdgeError(const PoseGraphEdge& edge, const PoseGraphOptions& options)
      : q_ab_(edge.a_from_b.rotation), t_ab_(edge.a_from_b.translation) {
    if (edge.information) {
      left_tangent_ = true;
      sqrt_information_ = SqrtInformation<6>(*edge.information);
    } else {
      const double w = std::sqrt(edge.weight);
      rot_scale_ = w / options.rotation_sigma_rad;
      trans_scale_ = w / options.translation_sigma_m;
    }
  }

  template <typename T>
  void operator()(const Eigen::Quaternion<T>& q_est, const Eigen::Matrix<T, 3, 1>& t_est,
                  T* residual) const {
    Eigen::Map<Eigen::Matrix<T, 6, 1>> r(residual);
    if (left_tangent_) {
      const Eigen::Quaternion<T> dq = q_est * q_ab_.cast<T>().conjugate();  // Exp(omega)
      const T dq_wxyz[4] = {dq.w(), dq.x(), dq.y(), dq.z()};
      Eigen::Matrix<T, 6, 1> d;
      ceres::QuaternionToAngleAxis(dq_wxyz, d.data() + 3);
      d.template head<3>() = t_est - dq * t_ab_.cast<T>();
      r = sqrt_information_.cast<T>() * d;
      return;
    }
    const Eigen::Quaternion<T> dq = q_ab_.cast<T>().conjugate() * q_est;
    r.template head<3>() = T(trans_scale_) * (t_est - t_ab_.cast<T>());
    // 2 vec(dq) is the rotation error angle for small errors; the sign keeps dq near +1.
    const T sign = dq.w() < T(0) ? T(-1) : T(1);
    r.template tail<3>() = T(2.0 * rot_scale_) * sign * dq.vec();
  }

 private:
  Eigen::Quaterniond q_ab_;
  Eigen::Vector3d t_ab_;
  bool left_tangent_ = false;
  Matrix6d sqrt_information_ = Matrix6d::Zero();
  double rot_scale_ = 0.0, trans_scale_ = 0.0;
};

// 6 DoF. Parameter blocks: q_cw [x, y, z, w] (Eigen's order) and t_cw of a, then of b.
struct SixDofCost {
  template <typename T>
  bool operator()(const T* qa_raw, const T* ta_raw, const T* qb_raw, const T* tb_raw,
                  T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> qa(qa_raw), qb(qb_raw);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> ta(ta_raw), tb(tb_raw);
    // Estimated a_from_b = a_from_world * b_from_world^-1.
    const Eigen::Quaternion<T> q_est = qa * qb.conjugate();
    const Eigen::Matrix<T, 3, 1> t_est = ta - q_est * tb;
    error(q_est, t_est, residual);
    return true;
  }

  EdgeError error;
};

// 4 DoF. Parameter blocks: the yaw [rad] about `up` applied to the initial world_from_cam rotation
// (world_from_cam = Rot(up, yaw) * world_from_cam_0), and the camera centre in the world [m], of a,
// then of b.
struct FourDofCost {
  template <typename T>
  bool operator()(const T* yaw_a, const T* pa_raw, const T* yaw_b, const T* pb_raw,
                  T* residual) const {
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> pa(pa_raw), pb(pb_raw);
    const Eigen::Quaternion<T> q_wa = Yaw(yaw_a[0]) * q_wa0.cast<T>();
    const Eigen::Quaternion<T> q_wb = Yaw(yaw_b[0]) * q_wb0.cast<T>();
    const Eigen::Quaternion<T> q_est = q_wa.conjugate() * q_wb;
    const Eigen::Matrix<T, 3, 1> t_est = q_wa.conjugate() * (pb - pa);
    error(q_est, t_est, residual);
    return true;
  }

  template <typename T>
  Eigen::Quaternion<T> Yaw(const T& yaw) const {
    using std::cos;
    using std::sin;
    const T s = sin(T(0.5) * yaw);
    return Eigen::Quaternion<T>(cos(T(0.5) * yaw), s * T(up.x()), s * T(up.y()), s * T(up.z()));
  }

  EdgeError error;
  Eigen::Vector3d up;  ///< unit yaw axis in the world
  Eigen::Quaterniond q_wa0, q_wb0;
};

void CheckEdge(const PoseGraphEdge& e, int n) {
  SLSLAM_CHECK(e.a >= 0 && e.a < n && e.b >= 0 && e.b < n && e.a != e.b, "pose graph edge (", e.a,
               ", ", e.b, ") does not join two of the ", n, " poses");
  SLSLAM_CHECK(std::isfinite(e.weight) && e.weight > 0.0, "pose graph edge weight must be > 0");
  SLSLAM_CHECK(!e.information || e.information->allFinite(), "pose graph edge (", e.a, ", ", e.b,
               ") information is not finite");
  SLSLAM_CHECK(std::isfinite(e.cauchy_scale) && e.cauchy_scale >= 0.0, "pose graph edge (", e.a,
               ", ", e.b, ") cauchy_scale must be >= 0, got ", e.cauchy_scale);
}

ceres::LossFunction* EdgeLoss(const PoseGraphEdge& e) {
  return e.cauchy_scale > 0.0 ? new ceres::CauchyLoss(e.cauchy_scale) : nullptr;
}

// Solves the built problem; the report, and whether the parameters may be read back.
PoseGraphReport Solve(const PoseGraphOptions& options, ceres::Problem* problem) {
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.num_threads = 1;
  solver_options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, problem, &summary);
  PoseGraphReport report;
  report.initial_cost = summary.initial_cost;
  report.final_cost = summary.final_cost;
  report.iterations = static_cast<int>(summary.iterations.size());
  report.solved = summary.IsSolutionUsable();
  return report;
}

PoseGraphReport OptimizeSixDof(std::vector<BaPose>* poses, const std::vector<PoseGraphEdge>& edges,
                               const PoseGraphOptions& options) {
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
    auto* cost = new ceres::AutoDiffCostFunction<SixDofCost, 6, 4, 3, 4, 3>(
        new SixDofCost{EdgeError(e, options)});
    problem.AddResidualBlock(cost, EdgeLoss(e), q[e.a].coeffs().data(), t[e.a].data(),
                             q[e.b].coeffs().data(), t[e.b].data());
    used[e.a] = used[e.b] = true;
  }
  for (int i = 0; i < n; ++i) {
    if (!used[i]) continue;
    problem.SetManifold(q[i].coeffs().data(), new ceres::EigenQuaternionManifold);
    if ((*poses)[i].fixed) {
      problem.SetParameterBlockConstant(q[i].coeffs().data());
      problem.SetParameterBlockConstant(t[i].data());
    }
  }
  const PoseGraphReport report = Solve(options, &problem);
  if (!report.solved) return report;
  for (int i = 0; i < n; ++i) {
    if ((*poses)[i].fixed || !used[i]) continue;
    (*poses)[i].cam_from_world.rotation = q[i].normalized().toRotationMatrix();
    (*poses)[i].cam_from_world.translation = t[i];
  }
  return report;
}

PoseGraphReport OptimizeFourDof(std::vector<BaPose>* poses, const std::vector<PoseGraphEdge>& edges,
                                const PoseGraphOptions& options) {
  const int n = static_cast<int>(poses->size());
  const Eigen::Vector3d up = options.gravity_in_world.normalized();
  std::vector<Eigen::Quaterniond> q_wc0(n);  // initial world_from_cam rotations
  std::vector<double> yaw(n, 0.0);
  std::vector<Eigen::Vector3d> centre(n);
  for (int i = 0; i < n; ++i) {
    q_wc0[i] = Eigen::Quaterniond((*poses)[i].cam_from_world.rotation.transpose()).normalized();
    centre[i] = (*poses)[i].cam_from_world.Center();
  }
  ceres::Problem problem;
  std::vector<bool> used(n, false);
  for (const PoseGraphEdge& e : edges) {
    auto* cost = new ceres::AutoDiffCostFunction<FourDofCost, 6, 1, 3, 1, 3>(
        new FourDofCost{EdgeError(e, options), up, q_wc0[e.a], q_wc0[e.b]});
    problem.AddResidualBlock(cost, EdgeLoss(e), &yaw[e.a], centre[e.a].data(), &yaw[e.b],
                             centre[e.b].data());
    used[e.a] = used[e.b] = true;
  }
  for (int i = 0; i < n; ++i) {
    if (!used[i] || !(*poses)[i].fixed) continue;
    problem.SetParameterBlockConstant(&yaw[i]);
    problem.SetParameterBlockConstant(centre[i].data());
  }
  const PoseGraphReport report = Solve(options, &problem);
  if (!report.solved) return report;
  for (int i = 0; i < n; ++i) {
    if ((*poses)[i].fixed || !used[i]) continue;
    const Eigen::Matrix3d R_wc =
        (Eigen::Quaterniond(Eigen::AngleAxisd(yaw[i], up)) * q_wc0[i]).toRotationMatrix();
    (*poses)[i].cam_from_world.rotation = R_wc.transpose();
    (*poses)[i].cam_from_world.translation = -(R_wc.transpose() * centre[i]);
  }
  return report;
}

}  // namespace

void PoseGraphOptions::Check() const {
  SLSLAM_CHECK(max_iterations >= 1, "pose graph max_iterations must be >= 1, got ", max_iterations);
  SLSLAM_CHECK(std::isfinite(rotation_sigma_rad) && rotation_sigma_rad > 0.0,
               "pose graph rotation_sigma_rad must be > 0, got ", rotation_sigma_rad);
  SLSLAM_CHECK(std::isfinite(translation_sigma_m) && translation_sigma_m > 0.0,
               "pose graph translation_sigma_m must be > 0, got ", translation_sigma_m);
  SLSLAM_CHECK(gravity_in_world.allFinite() && gravity_in_world.norm() > 0.0,
               "pose graph gravity_in_world must be a finite non-zero direction");
}

Rigid3d RelativePose(const Rigid3d& a_from_world, const Rigid3d& b_from_world) {
  Rigid3d a_from_b;
  a_from_b.rotation = a_from_world.rotation * b_from_world.rotation.transpose();
  a_from_b.translation = a_from_world.translation - a_from_b.rotation * b_from_world.translation;
  return a_from_b;
}

Eigen::Matrix<double, 6, 6> LeftTangentInformation(
    const Rigid3d& a_from_b, const Eigen::Matrix<double, 6, 6>& split_information) {
  Matrix6d J = Matrix6d::Zero();
  J.topLeftCorner<3, 3>().setIdentity();
  J.topRightCorner<3, 3>() = -Skew(a_from_b.translation);
  J.bottomRightCorner<3, 3>() = a_from_b.rotation.transpose();
  return J.transpose() * split_information * J;
}

PoseGraphReport OptimizePoseGraph(std::vector<BaPose>* poses,
                                  const std::vector<PoseGraphEdge>& edges,
                                  const PoseGraphOptions& options) {
  Require(poses != nullptr, "OptimizePoseGraph needs poses");
  options.Check();
  const int n = static_cast<int>(poses->size());
  for (const PoseGraphEdge& e : edges) CheckEdge(e, n);
  if (edges.empty()) return {};
  return options.yaw_and_position_only ? OptimizeFourDof(poses, edges, options)
                                       : OptimizeSixDof(poses, edges, options);
}

}  // namespace slslam
