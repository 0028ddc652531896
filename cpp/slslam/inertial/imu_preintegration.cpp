#include "slslam/inertial/imu_preintegration.h"

#include <cmath>

#include "slslam/core/check.h"
#include "slslam/geometry/rotation.h"

namespace slslam {

void ImuNoiseOptions::Check() const {
  SLSLAM_CHECK(gyro_noise_density >= 0 && std::isfinite(gyro_noise_density),
               "ImuNoiseOptions.gyro_noise_density must be >= 0, got ", gyro_noise_density);
  SLSLAM_CHECK(acc_noise_density >= 0 && std::isfinite(acc_noise_density),
               "ImuNoiseOptions.acc_noise_density must be >= 0, got ", acc_noise_density);
  SLSLAM_CHECK(gyro_random_walk >= 0 && std::isfinite(gyro_random_walk),
               "ImuNoiseOptions.gyro_random_walk must be >= 0, got ", gyro_random_walk);
  SLSLAM_CHECK(acc_random_walk >= 0 && std::isfinite(acc_random_walk),
               "ImuNoiseOptions.acc_random_walk must be >= 0, got ", acc_random_walk);
  SLSLAM_CHECK(gravity_mps2 > 0 && gravity_mps2 < 20,
               "ImuNoiseOptions.gravity_mps2 must be in (0, 20), got ", gravity_mps2);
}

Eigen::Matrix3d RightJacobianSO3(const Eigen::Vector3d& w) {
  const double angle = w.norm();
  const Eigen::Matrix3d W = Skew(w);
  if (angle < 1e-6) return Eigen::Matrix3d::Identity() - 0.5 * W;
  const double a2 = angle * angle;
  return Eigen::Matrix3d::Identity() - (1.0 - std::cos(angle)) / a2 * W +
         (angle - std::sin(angle)) / (a2 * angle) * W * W;
}

ImuPreintegration::ImuPreintegration(const ImuBias& bias_hat, const ImuNoiseOptions& noise)
    : bias_hat_(bias_hat), noise_(noise) {
  noise_.Check();
}

void ImuPreintegration::Integrate(const Eigen::Vector3d& gyro, const Eigen::Vector3d& acc,
                                  double dt_s) {
  SLSLAM_CHECK(dt_s > 0 && std::isfinite(dt_s), "IMU sample interval must be > 0 s, got ", dt_s);
  SLSLAM_CHECK(gyro.allFinite() && acc.allFinite(), "IMU sample is not finite");
  const Eigen::Vector3d a = acc - bias_hat_.acc;
  const Eigen::Vector3d w = gyro - bias_hat_.gyro;
  const double dt2 = dt_s * dt_s;
  const Eigen::Matrix3d Ra = delta_R_ * Skew(a);
  const Eigen::Vector3d theta = w * dt_s;
  const Eigen::Matrix3d dR_inc = ExpSO3(theta);
  const Eigen::Matrix3d Jr = RightJacobianSO3(theta);

  // Noise propagation of (dtheta, dv, dp), before the increments move on.
  Eigen::Matrix<double, 9, 9> A = Eigen::Matrix<double, 9, 9>::Identity();
  A.block<3, 3>(0, 0) = dR_inc.transpose();
  A.block<3, 3>(3, 0) = -Ra * dt_s;
  A.block<3, 3>(6, 0) = -0.5 * Ra * dt2;
  A.block<3, 3>(6, 3) = Eigen::Matrix3d::Identity() * dt_s;
  Eigen::Matrix<double, 9, 3> Bg = Eigen::Matrix<double, 9, 3>::Zero();
  Bg.block<3, 3>(0, 0) = Jr * dt_s;
  Eigen::Matrix<double, 9, 3> Ba = Eigen::Matrix<double, 9, 3>::Zero();
  Ba.block<3, 3>(3, 0) = delta_R_ * dt_s;
  Ba.block<3, 3>(6, 0) = 0.5 * delta_R_ * dt2;
  // Discrete white noise of a sample held dt: density^2 / dt.
  const double var_g = noise_.gyro_noise_density * noise_.gyro_noise_density / dt_s;
  const double var_a = noise_.acc_noise_density * noise_.acc_noise_density / dt_s;
  covariance_ =
      A * covariance_ * A.transpose() + var_g * Bg * Bg.transpose() + var_a * Ba * Ba.transpose();

  // Bias Jacobians (Forster et al., appendix B), also with the increments before this sample.
  dp_dba_ += dv_dba_ * dt_s - 0.5 * delta_R_ * dt2;
  dp_dbg_ += dv_dbg_ * dt_s - 0.5 * Ra * dR_dbg_ * dt2;
  dv_dba_ -= delta_R_ * dt_s;
  dv_dbg_ -= Ra * dR_dbg_ * dt_s;
  dR_dbg_ = dR_inc.transpose() * dR_dbg_ - Jr * dt_s;

  delta_p_ += delta_v_ * dt_s + 0.5 * delta_R_ * a * dt2;
  delta_v_ += delta_R_ * a * dt_s;
  delta_R_ = delta_R_ * dR_inc;
  // Keep delta_R a rotation over thousands of samples.
  delta_R_ = Eigen::Quaterniond(delta_R_).normalized().toRotationMatrix();
  dt_s_ += dt_s;
}

Eigen::Matrix3d ImuPreintegration::CorrectedDeltaR(const ImuBias& bias) const {
  return delta_R_ * ExpSO3(dR_dbg_ * (bias.gyro - bias_hat_.gyro));
}

Eigen::Vector3d ImuPreintegration::CorrectedDeltaV(const ImuBias& bias) const {
  return delta_v_ + dv_dbg_ * (bias.gyro - bias_hat_.gyro) + dv_dba_ * (bias.acc - bias_hat_.acc);
}

Eigen::Vector3d ImuPreintegration::CorrectedDeltaP(const ImuBias& bias) const {
  return delta_p_ + dp_dbg_ * (bias.gyro - bias_hat_.gyro) + dp_dba_ * (bias.acc - bias_hat_.acc);
}

NavState ImuPreintegration::Predict(const NavState& start, const ImuBias& bias) const {
  return Predict(start, bias, gravity_world());
}

NavState ImuPreintegration::Predict(const NavState& start, const ImuBias& bias,
                                    const Eigen::Vector3d& g) const {
  const Eigen::Matrix3d R_i = start.R_world_body.toRotationMatrix();
  NavState end;
  end.R_world_body = Eigen::Quaterniond(R_i * CorrectedDeltaR(bias)).normalized();
  end.v_world_body = start.v_world_body + g * dt_s_ + R_i * CorrectedDeltaV(bias);
  end.p_world_body = start.p_world_body + start.v_world_body * dt_s_ + 0.5 * g * dt_s_ * dt_s_ +
                     R_i * CorrectedDeltaP(bias);
  return end;
}

}  // namespace slslam
