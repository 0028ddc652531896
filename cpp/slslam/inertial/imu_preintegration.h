// On-manifold IMU preintegration with bias (the LiDAR paper's eqs. 5-7; Forster et al., TRO
// 2017): the rotation, velocity and position increments between two keyframes, their covariance,
// and their first-order Jacobians with respect to the gyroscope and accelerometer biases, so a
// bias update corrects the increments without integrating the samples again.
//
// One implementation for the LiDAR-inertial smoother and the visual-inertial tracker.
//
// Frames: the IMU frame is the body frame B; in the world frame W gravity is g_W, by default
// (0, 0, -gravity_mps2) (z up, the LiDAR module's world) or any vector given to Predict (the
// visual maps' worlds are not gravity-aligned). Increments are expressed in B at the first
// sample (B_i):
//   delta_R = R_WBi^T R_WBj
//   delta_v = R_WBi^T (v_j - v_i - g dt)
//   delta_p = R_WBi^T (p_j - p_i - v_i dt - g dt^2 / 2)
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace slslam {

// Continuous-time IMU noise (Kalibr / EuRoC sensor.yaml conventions).
struct ImuNoiseOptions {
  double gyro_noise_density = 1.6968e-4;  ///< [rad/s/sqrt(Hz)]
  double acc_noise_density = 2.0e-3;      ///< [m/s^2/sqrt(Hz)]
  double gyro_random_walk = 1.9393e-5;    ///< [rad/s^2/sqrt(Hz)]
  double acc_random_walk = 3.0e-3;        ///< [m/s^3/sqrt(Hz)]
  double gravity_mps2 = 9.81;             ///< magnitude of gravity [m/s^2]

  // Throws std::invalid_argument naming the first out-of-range field.
  void Check() const;
};

struct ImuBias {
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero();  ///< [rad/s]
  Eigen::Vector3d acc = Eigen::Vector3d::Zero();   ///< [m/s^2]
};

// Navigation state of the body in the world frame.
struct NavState {
  Eigen::Quaterniond R_world_body = Eigen::Quaterniond::Identity();
  Eigen::Vector3d p_world_body = Eigen::Vector3d::Zero();  ///< [m]
  Eigen::Vector3d v_world_body = Eigen::Vector3d::Zero();  ///< [m/s]
};

class ImuPreintegration {
 public:
  // Linearisation point of the biases; the samples are corrected by it before integration.
  explicit ImuPreintegration(const ImuBias& bias_hat = {}, const ImuNoiseOptions& noise = {});

  // Adds one sample held for dt_s [s] (gyro [rad/s], acc specific force [m/s^2], body frame).
  // Throws std::invalid_argument on dt_s <= 0 or a non-finite value.
  void Integrate(const Eigen::Vector3d& gyro, const Eigen::Vector3d& acc, double dt_s);

  double dt_s() const { return dt_s_; }
  const ImuBias& bias_hat() const { return bias_hat_; }
  const Eigen::Matrix3d& delta_R() const { return delta_R_; }
  const Eigen::Vector3d& delta_v() const { return delta_v_; }
  const Eigen::Vector3d& delta_p() const { return delta_p_; }
  // Jacobians of the increments w.r.t. the biases at bias_hat (delta_R: of Log(delta_R_hat^T
  // delta_R(b))).
  const Eigen::Matrix3d& dR_dbg() const { return dR_dbg_; }
  const Eigen::Matrix3d& dv_dbg() const { return dv_dbg_; }
  const Eigen::Matrix3d& dv_dba() const { return dv_dba_; }
  const Eigen::Matrix3d& dp_dbg() const { return dp_dbg_; }
  const Eigen::Matrix3d& dp_dba() const { return dp_dba_; }
  // Covariance of (dtheta, dv, dp) from the white measurement noise [rad^2, (m/s)^2, m^2].
  const Eigen::Matrix<double, 9, 9>& covariance() const { return covariance_; }
  const ImuNoiseOptions& noise() const { return noise_; }
  Eigen::Vector3d gravity_world() const { return {0.0, 0.0, -noise_.gravity_mps2}; }

  // Increments for another bias, corrected to first order through the Jacobians.
  Eigen::Matrix3d CorrectedDeltaR(const ImuBias& bias) const;
  Eigen::Vector3d CorrectedDeltaV(const ImuBias& bias) const;
  Eigen::Vector3d CorrectedDeltaP(const ImuBias& bias) const;

  // State at the end of the integrated interval from the state at its start (gravity_world()).
  NavState Predict(const NavState& start, const ImuBias& bias) const;
  // The same under the gravity vector g_world [m/s^2] of another world frame.
  NavState Predict(const NavState& start, const ImuBias& bias,
                   const Eigen::Vector3d& g_world) const;

 private:
  ImuBias bias_hat_;
  ImuNoiseOptions noise_;
  double dt_s_ = 0.0;
  Eigen::Matrix3d delta_R_ = Eigen::Matrix3d::Identity();
  Eigen::Vector3d delta_v_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d delta_p_ = Eigen::Vector3d::Zero();
  Eigen::Matrix3d dR_dbg_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dv_dbg_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dv_dba_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dp_dbg_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dp_dba_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix<double, 9, 9> covariance_ = Eigen::Matrix<double, 9, 9>::Zero();
};

// Right Jacobian of SO(3) at w: Exp(w + d) ~= Exp(w) Exp(Jr(w) d).
Eigen::Matrix3d RightJacobianSO3(const Eigen::Vector3d& w);

}  // namespace slslam
