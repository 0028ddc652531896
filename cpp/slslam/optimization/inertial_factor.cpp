#include "slslam/optimization/inertial_factor.h"

#include <algorithm>

#include <ceres/autodiff_cost_function.h>

#include "slslam/optimization/sqrt_information.h"

namespace slslam {

Matrix15d ImuIntervalSqrtInformation(const ImuPreintegration& pre) {
  Matrix15d cov = Matrix15d::Zero();
  cov.topLeftCorner<9, 9>() = pre.covariance();
  const double dt = pre.dt_s();
  const ImuNoiseOptions& noise = pre.noise();
  cov.block<3, 3>(9, 9).diagonal().setConstant(noise.gyro_random_walk * noise.gyro_random_walk *
                                               dt);
  cov.block<3, 3>(12, 12).diagonal().setConstant(noise.acc_random_walk * noise.acc_random_walk *
                                                 dt);
  // A floor on every variance keeps the square root finite for noise-free data.
  cov.diagonal() = cov.diagonal().cwiseMax(1e-12);
  const Matrix15d info = cov.inverse();
  return SqrtInformation<15>(info);
}

CameraImuFactor::CameraImuFactor(const ImuPreintegration& pre, const Eigen::Vector3d& g_world,
                                 const Rigid3d& body_from_cam)
    : pre_(pre),
      g_world_(g_world),
      gravity_basis_(GravityTangentBasis(g_world)),
      sqrt_information_(ImuIntervalSqrtInformation(pre)) {
  const Rigid3d cam_from_body = body_from_cam.Inverse();
  q_cam_body_ = Eigen::Quaterniond(cam_from_body.rotation).normalized();
  t_cam_body_ = cam_from_body.translation;
}

Eigen::Matrix<double, 3, 2> GravityTangentBasis(const Eigen::Vector3d& g0) {
  const Eigen::Vector3d u = g0.normalized();
  // (the world axis least aligned with gravity, made orthogonal to it)
  Eigen::Index axis = 0;
  u.cwiseAbs().minCoeff(&axis);
  const Eigen::Vector3d a = (Eigen::Vector3d::Unit(axis) - u * u(axis)).normalized();
  Eigen::Matrix<double, 3, 2> basis;
  basis << a, u.cross(a);
  return basis;
}

template <typename T>
bool CameraImuFactor::Residual(const double* pose_i, const T* delta_i, const T* vb_i,
                               const double* pose_j, const T* delta_j, const T* vb_j,
                               const T* gravity, T* residual) const {
  using V3 = Eigen::Matrix<T, 3, 1>;
  // The body in the world of a camera pose after PoseManifold's Plus (R <- Exp(w) R,
  // t <- Exp(w) t + rho): R_wb = R_cw^T R_cb, p_wb = R_cw^T (t_cb - t_cw).
  const auto body = [&](const double* pose, const T* delta, Eigen::Quaternion<T>* q_wb, V3* p_wb) {
    T w[3] = {delta[3], delta[4], delta[5]}, qw[4];
    ceres::AngleAxisToQuaternion(w, qw);  // w, x, y, z
    const Eigen::Quaternion<T> q_step(qw[0], qw[1], qw[2], qw[3]);
    const Eigen::Quaternion<T> q_cw =
        q_step * Eigen::Map<const Eigen::Quaterniond>(pose + 3).normalized().cast<T>();
    const V3 t_cw = q_step * Eigen::Map<const Eigen::Vector3d>(pose).cast<T>() +
                    V3(delta[0], delta[1], delta[2]);
    *q_wb = q_cw.conjugate() * q_cam_body_.cast<T>();
    *p_wb = q_cw.conjugate() * (t_cam_body_.cast<T>() - t_cw);
  };
  Eigen::Quaternion<T> qi, qj;
  V3 pi, pj;
  body(pose_i, delta_i, &qi, &pi);
  body(pose_j, delta_j, &qj, &pj);
  Eigen::Matrix<T, 15, 1> r;
  ImuIntervalResidual(pre_, GravityDirection(g_world_, gravity_basis_, gravity), qi, pi, vb_i, qj,
                      pj, vb_j, &r);
  Eigen::Map<Eigen::Matrix<T, 15, 1>> whitened(residual);
  whitened = sqrt_information_.cast<T>() * r;
  return true;
}

namespace {

// The factor's residual as a function of the two poses' tangent steps at the current poses
// (AutoDiffCostFunction differentiates it at zero steps).
struct AtTangent {
  const CameraImuFactor* factor;
  const double* pose_i;
  const double* pose_j;
  template <typename T>
  bool operator()(const T* delta_i, const T* vb_i, const T* delta_j, const T* vb_j,
                  const T* gravity, T* residual) const {
    return factor->Residual(pose_i, delta_i, vb_i, pose_j, delta_j, vb_j, gravity, residual);
  }
};

}  // namespace

bool CameraImuFactor::Evaluate(double const* const* parameters, double* residuals,
                               double** jacobians) const {
  const double zero[kPoseTangentSize] = {0, 0, 0, 0, 0, 0};
  if (jacobians == nullptr) {
    return Residual(parameters[0], zero, parameters[1], parameters[2], zero, parameters[3],
                    parameters[4], residuals);
  }
  AtTangent local{this, parameters[0], parameters[2]};
  const ceres::AutoDiffCostFunction<AtTangent, 15, kPoseTangentSize, kSpeedBiasSize,
                                    kPoseTangentSize, kSpeedBiasSize, kGravitySize>
      autodiff(&local, ceres::DO_NOT_TAKE_OWNERSHIP);
  const double* local_parameters[5] = {zero, parameters[1], zero, parameters[3], parameters[4]};
  double d_pose_i[15 * kPoseTangentSize], d_pose_j[15 * kPoseTangentSize];
  double* local_jacobians[5] = {jacobians[0] ? d_pose_i : nullptr, jacobians[1],
                                jacobians[2] ? d_pose_j : nullptr, jacobians[3], jacobians[4]};
  if (!autodiff.Evaluate(local_parameters, residuals, local_jacobians)) return false;
  // Tangent Jacobians into the first six of the seven ambient columns (manifolds.h).
  const auto lift = [](const double* tangent, double* ambient) {
    for (int row = 0; row < 15; ++row) {
      std::copy(tangent + row * kPoseTangentSize, tangent + (row + 1) * kPoseTangentSize,
                ambient + row * kPoseSize);
      ambient[row * kPoseSize + kPoseTangentSize] = 0.0;
    }
  };
  if (jacobians[0]) lift(d_pose_i, jacobians[0]);
  if (jacobians[2]) lift(d_pose_j, jacobians[2]);
  return true;
}

}  // namespace slslam
