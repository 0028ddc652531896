// IMU preintegration against a known smooth motion: the increments match the integrated truth,
// and the bias Jacobians match finite differences of re-integrated increments.
#include "slslam/inertial/imu_preintegration.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "slslam/geometry/rotation.h"

namespace slslam {
namespace {

const Eigen::Vector3d kGravity(0.0, 0.0, -9.81);

Eigen::Matrix3d Attitude(double t) {
  return ExpSO3(Eigen::Vector3d(0.2 * std::sin(t), 0.3 * std::cos(0.5 * t), 0.8 * t));
}
Eigen::Vector3d Position(double t) {
  return {2.0 * std::sin(0.5 * t), std::cos(0.7 * t), 0.3 * t * t};
}
Eigen::Vector3d Velocity(double t) {
  return {std::cos(0.5 * t), -0.7 * std::sin(0.7 * t), 0.6 * t};
}
Eigen::Vector3d Acceleration(double t) {
  return {-0.5 * std::sin(0.5 * t), -0.49 * std::cos(0.7 * t), 0.6};
}
// Body angular velocity by a central difference of the attitude (error ~1e-10 at h = 1e-5).
Eigen::Vector3d Gyro(double t) {
  const double h = 1e-5;
  return LogSO3(Eigen::Quaterniond(Attitude(t - h).transpose() * Attitude(t + h))) / (2 * h);
}
Eigen::Vector3d Accelerometer(double t) {
  return Attitude(t).transpose() * (Acceleration(t) - kGravity);
}

struct Samples {
  std::vector<Eigen::Vector3d> gyro, acc;
  double dt;
};

// Samples at the midpoints of n intervals of [t0, t1] (midpoint rule: second-order accurate).
Samples Sample(double t0, double t1, int n) {
  Samples s;
  s.dt = (t1 - t0) / n;
  for (int k = 0; k < n; ++k) {
    const double t = t0 + (k + 0.5) * s.dt;
    s.gyro.push_back(Gyro(t));
    s.acc.push_back(Accelerometer(t));
  }
  return s;
}

ImuPreintegration Integrate(const Samples& s, const ImuBias& bias_hat, const ImuBias& added) {
  ImuPreintegration pre(bias_hat);
  for (size_t k = 0; k < s.gyro.size(); ++k) {
    pre.Integrate(s.gyro[k] + added.gyro, s.acc[k] + added.acc, s.dt);
  }
  return pre;
}

struct Errors {
  double R, v, p, predicted_p, predicted_v;
};

// Errors of the increments integrated from n samples against the true motion over [t0, t1].
Errors IncrementErrors(double t0, double t1, int n) {
  const ImuPreintegration pre = Integrate(Sample(t0, t1, n), {}, {});
  const Eigen::Matrix3d Ri = Attitude(t0), Rj = Attitude(t1);
  const double dt = t1 - t0;
  EXPECT_NEAR(pre.dt_s(), dt, 1e-12);
  const Eigen::Matrix3d dR_true = Ri.transpose() * Rj;
  const Eigen::Vector3d dv_true = Ri.transpose() * (Velocity(t1) - Velocity(t0) - kGravity * dt);
  const Eigen::Vector3d dp_true =
      Ri.transpose() * (Position(t1) - Position(t0) - Velocity(t0) * dt - 0.5 * kGravity * dt * dt);
  NavState start;
  start.R_world_body = Eigen::Quaterniond(Ri);
  start.p_world_body = Position(t0);
  start.v_world_body = Velocity(t0);
  const NavState end = pre.Predict(start, {});
  return {LogSO3(Eigen::Quaterniond(dR_true.transpose() * pre.delta_R())).norm(),
          (pre.delta_v() - dv_true).norm(), (pre.delta_p() - dp_true).norm(),
          (end.p_world_body - Position(t1)).norm(), (end.v_world_body - Velocity(t1)).norm()};
}

TEST(ImuPreintegration, IncrementsConvergeToTheTrueMotion) {
  // Forster's discretisation rotates each sample's specific force with the rotation at the start
  // of its interval, so the velocity and position increments converge at first order in dt.
  const Errors coarse = IncrementErrors(0.3, 0.8, 2000);  // 4 kHz
  const Errors fine = IncrementErrors(0.3, 0.8, 4000);
  EXPECT_LT(coarse.R, 1e-6);
  EXPECT_LT(coarse.v, 5e-4);  // 10 m/s^2 of specific force turning at 0.8 rad/s for 0.5 s
  EXPECT_LT(coarse.p, 1e-4);
  EXPECT_NEAR(coarse.v / fine.v, 2.0, 0.2);
  EXPECT_NEAR(coarse.p / fine.p, 2.0, 0.2);
  // Predict applies the increments to the start state: the same errors.
  EXPECT_NEAR(coarse.predicted_p, coarse.p, 1e-9);
  EXPECT_LT(coarse.predicted_v, 5e-4);
}

TEST(ImuPreintegration, BiasJacobiansMatchFiniteDifferences) {
  const Samples s = Sample(0.0, 0.6, 300);
  ImuBias bias_hat;
  bias_hat.gyro = {0.01, -0.02, 0.015};
  bias_hat.acc = {0.1, -0.05, 0.08};
  const ImuPreintegration pre = Integrate(s, bias_hat, bias_hat);  // biased samples, corrected
  const double eps = 1e-6;
  for (int axis = 0; axis < 6; ++axis) {
    ImuBias shifted = bias_hat;
    (axis < 3 ? shifted.gyro : shifted.acc)(axis % 3) += eps;
    const ImuPreintegration moved = Integrate(s, shifted, bias_hat);
    const Eigen::Vector3d dR =
        LogSO3(Eigen::Quaterniond(pre.delta_R().transpose() * moved.delta_R())) / eps;
    const Eigen::Vector3d dv = (moved.delta_v() - pre.delta_v()) / eps;
    const Eigen::Vector3d dp = (moved.delta_p() - pre.delta_p()) / eps;
    const int c = axis % 3;
    const Eigen::Vector3d jR =
        axis < 3 ? Eigen::Vector3d(pre.dR_dbg().col(c)) : Eigen::Vector3d::Zero();
    const Eigen::Vector3d jv = axis < 3 ? pre.dv_dbg().col(c) : pre.dv_dba().col(c);
    const Eigen::Vector3d jp = axis < 3 ? pre.dp_dbg().col(c) : pre.dp_dba().col(c);
    EXPECT_LT((dR - jR).norm(), 1e-4 * std::max(1.0, jR.norm())) << "axis " << axis;
    EXPECT_LT((dv - jv).norm(), 1e-4 * std::max(1.0, jv.norm())) << "axis " << axis;
    EXPECT_LT((dp - jp).norm(), 1e-4 * std::max(1.0, jp.norm())) << "axis " << axis;
    // The first-order correction predicts the re-integrated increments.
    EXPECT_LT((pre.CorrectedDeltaV(shifted) - moved.delta_v()).norm(), 1e-9);
  }
}

TEST(ImuPreintegration, CovarianceGrowsWithTimeAndBadInputThrows) {
  ImuPreintegration pre;
  pre.Integrate(Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, 9.81), 0.005);
  const double early = pre.covariance()(6, 6);
  for (int k = 0; k < 99; ++k)
    pre.Integrate(Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, 9.81), 0.005);
  EXPECT_GT(pre.covariance()(6, 6), 100 * early);
  EXPECT_THROW(pre.Integrate(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 0.0),
               std::invalid_argument);
  ImuNoiseOptions bad;
  bad.acc_noise_density = -1.0;
  EXPECT_THROW(ImuPreintegration({}, bad), std::invalid_argument);
}

}  // namespace
}  // namespace slslam
