// A smooth synthetic body motion with its exact IMU readings, for the inertial gtests.
#pragma once

#include <algorithm>
#include <cmath>

#include <Eigen/Core>

#include "slslam/core/rigid3.h"
#include "slslam/geometry/rotation.h"
#include "slslam/inertial/imu_preintegration.h"

namespace slslam::test {

// Gravity of the test's world, deliberately not along -z (the visual maps' worlds are not
// gravity-aligned) unless `z_up`.
inline Eigen::Vector3d TestGravity(bool z_up = false) {
  return z_up ? Eigen::Vector3d(0.0, 0.0, -9.81)
              : ExpSO3(Eigen::Vector3d(0.3, -0.2, 0.1)) * Eigen::Vector3d(0.0, 0.0, -9.81);
}

// What a body trajectory gives (Derived's Attitude, Position, Velocity, Acceleration and
// g_world): its exact IMU readings and navigation state.
template <typename Derived>
struct TrajectoryReadings {
  // Body angular velocity by a central difference of the attitude.
  Eigen::Vector3d Gyro(double t) const {
    const double h = 1e-5;
    return LogSO3(Eigen::Quaterniond(self().Attitude(t - h).transpose() * self().Attitude(t + h))) /
           (2 * h);
  }
  Eigen::Vector3d Accelerometer(double t) const {
    return self().Attitude(t).transpose() * (self().Acceleration(t) - self().g_world);
  }
  Rigid3d WorldFromBody(double t) const { return Rigid3d(self().Attitude(t), self().Position(t)); }
  NavState Nav(double t) const {
    NavState s;
    s.R_world_body = Eigen::Quaterniond(self().Attitude(t));
    s.p_world_body = self().Position(t);
    s.v_world_body = self().Velocity(t);
    return s;
  }

 private:
  const Derived& self() const { return static_cast<const Derived&>(*this); }
};

// Body motion: `amplitude` scales every motion (0: at rest, at a fixed tilted attitude).
struct SyntheticMotion : TrajectoryReadings<SyntheticMotion> {
  double amplitude = 1.0;
  Eigen::Vector3d g_world = TestGravity();

  Eigen::Matrix3d Attitude(double t) const {
    const double a = amplitude;
    return ExpSO3(Eigen::Vector3d(0.1 + a * 0.2 * std::sin(t), -0.05 + a * 0.3 * std::cos(0.5 * t),
                                  0.4 + a * 0.6 * t));
  }
  Eigen::Vector3d Position(double t) const {
    return amplitude * Eigen::Vector3d(2.0 * std::sin(0.5 * t), std::cos(0.7 * t), 0.3 * t * t);
  }
  Eigen::Vector3d Velocity(double t) const {
    return amplitude * Eigen::Vector3d(std::cos(0.5 * t), -0.7 * std::sin(0.7 * t), 0.6 * t);
  }
  Eigen::Vector3d Acceleration(double t) const {
    return amplitude * Eigen::Vector3d(-0.5 * std::sin(0.5 * t), -0.49 * std::cos(0.7 * t), 0.6);
  }
  // The IMU over [t0, t1] at `rate_hz`, midpoint samples, with `bias` added to the readings.
  ImuPreintegration Preintegrate(double t0, double t1, double rate_hz, const ImuBias& bias,
                                 const ImuBias& bias_hat = {},
                                 const ImuNoiseOptions& noise = {}) const {
    ImuPreintegration pre(bias_hat, noise);
    const int n = std::max(1, static_cast<int>(std::lround((t1 - t0) * rate_hz)));
    const double dt = (t1 - t0) / n;
    for (int k = 0; k < n; ++k) {
      const double t = t0 + (k + 0.5) * dt;
      pre.Integrate(Gyro(t) + bias.gyro, Accelerometer(t) + bias.acc, dt);
    }
    return pre;
  }
};

}  // namespace slslam::test
