#include "slslam/lidar/pose_graph.h"

#include <ceres/ceres.h>
#include <ceres/rotation.h>
#include <Eigen/Eigenvalues>

#include "slslam/core/check.h"

namespace slslam::lidar {

void LidarPoseGraphOptions::Check() const {
  SLSLAM_CHECK(max_iterations >= 1 && max_iterations <= 1000,
               "LidarPoseGraphOptions.max_iterations must be in [1, 1000], got ", max_iterations);
  SLSLAM_CHECK(loop_cauchy_scale > 0, "LidarPoseGraphOptions.loop_cauchy_scale must be > 0");
}

namespace {

struct RelativePoseError {
  RelativePoseError(const Eigen::Isometry3d& T_a_b, const Eigen::Matrix<double, 6, 6>& sqrt_info)
      : q_ab(T_a_b.linear()), t_ab(T_a_b.translation()), sqrt_info(sqrt_info) {}

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
  Eigen::Matrix<double, 6, 6> sqrt_info;
};

}  // namespace

LidarPoseGraphResult OptimizeLidarPoseGraph(const std::vector<Eigen::Matrix4d>& T_world_keyframe,
                                            const std::vector<LidarPoseGraphEdge>& edges,
                                            const LidarPoseGraphOptions& options) {
  options.Check();
  const int n = static_cast<int>(T_world_keyframe.size());
  std::vector<Eigen::Quaterniond> q(n);
  std::vector<Eigen::Vector3d> p(n);
  for (int i = 0; i < n; ++i) {
    const Eigen::Matrix3d R = T_world_keyframe[i].topLeftCorner<3, 3>();
    SLSLAM_CHECK(T_world_keyframe[i].allFinite() &&
                     (R.transpose() * R - Eigen::Matrix3d::Identity()).norm() < 1e-6,
                 "pose graph: keyframe ", i, " is not a rigid transform");
    q[i] = Eigen::Quaterniond(R).normalized();
    p[i] = T_world_keyframe[i].topRightCorner<3, 1>();
  }
  ceres::Problem problem;
  for (int i = 0; i < n; ++i) {
    problem.AddParameterBlock(q[i].coeffs().data(), 4, new ceres::EigenQuaternionManifold);
    problem.AddParameterBlock(p[i].data(), 3);
  }
  for (size_t k = 0; k < edges.size(); ++k) {
    const LidarPoseGraphEdge& e = edges[k];
    SLSLAM_CHECK(e.a >= 0 && e.a < n && e.b >= 0 && e.b < n && e.a != e.b, "pose graph: edge ", k,
                 " joins keyframes ", e.a, " and ", e.b, " of ", n);
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eig(
        0.5 * (e.information + e.information.transpose()));
    const Eigen::Matrix<double, 6, 6> sqrt_info =
        eig.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal() * eig.eigenvectors().transpose();
    Eigen::Isometry3d T_ab;
    T_ab.matrix() = e.T_a_b;
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<RelativePoseError, 6, 4, 3, 4, 3>(
                                 new RelativePoseError(T_ab, sqrt_info)),
                             e.loop ? new ceres::CauchyLoss(options.loop_cauchy_scale) : nullptr,
                             q[e.a].coeffs().data(), p[e.a].data(), q[e.b].coeffs().data(),
                             p[e.b].data());
  }
  LidarPoseGraphResult result;
  if (n > 0) {
    problem.SetParameterBlockConstant(q[0].coeffs().data());
    problem.SetParameterBlockConstant(p[0].data());
  }
  if (n > 1 && !edges.empty()) {
    ceres::Solver::Options solver;
    solver.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    solver.max_num_iterations = options.max_iterations;
    solver.num_threads = 1;
    ceres::Solver::Summary summary;
    ceres::Solve(solver, &problem, &summary);
    result.initial_cost = summary.initial_cost;
    result.final_cost = summary.final_cost;
    result.iterations = static_cast<int>(summary.iterations.size());
  }
  for (int i = 0; i < n; ++i) {
    Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
    T.topLeftCorner<3, 3>() = q[i].normalized().toRotationMatrix();
    T.topRightCorner<3, 1>() = p[i];
    result.T_world_keyframe.push_back(T);
  }
  return result;
}

}  // namespace slslam::lidar
