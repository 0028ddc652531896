// The residual of one preintegrated IMU interval between two body states (Forster et al., TRO
// 2017, eq. 45; the bias random walk as in ORB-SLAM3's inertial edges), shared by the
// LiDAR-inertial smoother (body states as quaternion and position) and bundle adjustment (camera
// poses cam_from_world on PoseManifold, CameraImuFactor below).
//
// Frames: world W with gravity g_world in it; body B = the IMU frame. Residual (15), unwhitened:
//   r_R  = Log((delta_R Exp(dR_dbg dbg_i))^T R_WBi^T R_WBj)                  [rad]
//   r_v  = R_WBi^T (v_j - v_i - g dt) - (delta_v + dv_dbg dbg_i + dv_dba dba_i)  [m/s]
//   r_p  = R_WBi^T (p_j - p_i - v_i dt - g dt^2 / 2) - (delta_p + ...)        [m]
//   r_bg = bg_j - bg_i, r_ba = ba_j - ba_i
// with dbg_i = bg_i - bias_hat.gyro, dba_i = ba_i - bias_hat.acc (first-order bias correction).
#pragma once

#include <ceres/rotation.h>
#include <ceres/sized_cost_function.h>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "slslam/core/rigid3.h"
#include "slslam/inertial/imu_preintegration.h"
#include "slslam/optimization/manifolds.h"

namespace slslam {

using Matrix15d = Eigen::Matrix<double, 15, 15>;

// Square root of the interval's information: the increments' covariance (9 x 9) beside the bias
// random walks over its duration (pre.noise()), each variance floored at 1e-12 (noise-free data).
Matrix15d ImuIntervalSqrtInformation(const ImuPreintegration& pre);

// The unwhitened residual above. vb_* = (v [m/s], bg [rad/s], ba [m/s^2]).
template <typename T>
void ImuIntervalResidual(const ImuPreintegration& imu, const Eigen::Matrix<T, 3, 1>& g_world,
                         const Eigen::Quaternion<T>& qi, const Eigen::Matrix<T, 3, 1>& pi,
                         const T* vbi_, const Eigen::Quaternion<T>& qj,
                         const Eigen::Matrix<T, 3, 1>& pj, const T* vbj_,
                         Eigen::Matrix<T, 15, 1>* r) {
  using V3 = Eigen::Matrix<T, 3, 1>;
  const Eigen::Map<const V3> vi(vbi_), bgi(vbi_ + 3), bai(vbi_ + 6);
  const Eigen::Map<const V3> vj(vbj_), bgj(vbj_ + 3), baj(vbj_ + 6);
  const V3 dbg = bgi - imu.bias_hat().gyro.cast<T>();
  const V3 dba = bai - imu.bias_hat().acc.cast<T>();
  // Corrected rotation increment delta_R * Exp(dR_dbg dbg), as a quaternion.
  const V3 dtheta = imu.dR_dbg().cast<T>() * dbg;
  T aa[3] = {dtheta(0), dtheta(1), dtheta(2)}, qc[4];
  ceres::AngleAxisToQuaternion(aa, qc);  // w, x, y, z
  const Eigen::Quaternion<T> q_corr(qc[0], qc[1], qc[2], qc[3]);
  const Eigen::Quaternion<T> dq = Eigen::Quaterniond(imu.delta_R()).cast<T>() * q_corr;
  const Eigen::Quaternion<T> err = dq.conjugate() * qi.conjugate() * qj;
  T qe[4] = {err.w(), err.x(), err.y(), err.z()}, re[3];
  ceres::QuaternionToAngleAxis(qe, re);
  const double dt = imu.dt_s();
  const V3& g = g_world;
  const Eigen::Matrix<T, 3, 3> Rit = qi.conjugate().toRotationMatrix();
  const V3 dv =
      imu.delta_v().cast<T>() + imu.dv_dbg().cast<T>() * dbg + imu.dv_dba().cast<T>() * dba;
  const V3 dp =
      imu.delta_p().cast<T>() + imu.dp_dbg().cast<T>() * dbg + imu.dp_dba().cast<T>() * dba;
  r->template segment<3>(0) = V3(re[0], re[1], re[2]);
  r->template segment<3>(3) = Rit * (vj - vi - g * T(dt)) - dv;
  r->template segment<3>(6) = Rit * (pj - pi - vi * T(dt) - T(0.5 * dt * dt) * g) - dp;
  r->template segment<3>(9) = bgj - bgi;
  r->template segment<3>(12) = baj - bai;
}

// Size of a speed-bias parameter block: (v_world_body [m/s], gyro bias [rad/s], acc bias [m/s^2]).
constexpr int kSpeedBiasSize = 9;

// Size of the gravity block: a rotation of gravity's direction about the two axes across it
// (GravityDirection); its magnitude is known.
constexpr int kGravitySize = 2;

// Gravity after the rotation `delta` (kGravitySize) of the reference g0 about the two unit axes
// across it: Exp(B delta) g0, B = GravityTangentBasis(g0) (3 x 2).
Eigen::Matrix<double, 3, 2> GravityTangentBasis(const Eigen::Vector3d& g0);
template <typename T>
Eigen::Matrix<T, 3, 1> GravityDirection(const Eigen::Vector3d& g0,
                                        const Eigen::Matrix<double, 3, 2>& basis, const T* delta) {
  const Eigen::Matrix<T, 3, 1> w =
      basis.cast<T>() * Eigen::Map<const Eigen::Matrix<T, 2, 1>>(delta);
  const T aa[3] = {w(0), w(1), w(2)};
  const T g[3] = {T(g0(0)), T(g0(1)), T(g0(2))};
  T out[3];
  ceres::AngleAxisRotatePoint(aa, g, out);
  return {out[0], out[1], out[2]};
}

// The IMU interval between two keyframes of bundle adjustment. Parameters: pose_i (cam_from_world
// on PoseManifold, 7), speed-bias_i (9), pose_j (7), speed-bias_j (9), gravity (2: the rotation of
// g_world, GravityDirection; held constant where gravity is not estimated); residual 15,
// whitened by ImuIntervalSqrtInformation. The pose Jacobians are tangent Jacobians in the first
// six ambient columns (the layout of manifolds.h), by automatic differentiation through
// PoseManifold's Plus.
class CameraImuFactor final
    : public ceres::SizedCostFunction<15, kPoseSize, kSpeedBiasSize, kPoseSize, kSpeedBiasSize,
                                      kGravitySize> {
 public:
  CameraImuFactor(const ImuPreintegration& pre, const Eigen::Vector3d& g_world,
                  const Rigid3d& body_from_cam);
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

  // The residual at the parameters and a tangent step (delta_i, delta_j: PoseManifold tangents).
  template <typename T>
  bool Residual(const double* pose_i, const T* delta_i, const T* vb_i, const double* pose_j,
                const T* delta_j, const T* vb_j, const T* gravity, T* residual) const;

 private:
  ImuPreintegration pre_;
  Eigen::Vector3d g_world_;
  Eigen::Matrix<double, 3, 2> gravity_basis_;
  Eigen::Quaterniond q_cam_body_;
  Eigen::Vector3d t_cam_body_;
  Matrix15d sqrt_information_;
};

}  // namespace slslam
