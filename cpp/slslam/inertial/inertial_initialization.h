// Visual-inertial initialisation from stereo poses: the gyroscope bias, gravity in the poses'
// world, the accelerometer bias and the velocity at every pose, from a few seconds of tracked
// camera poses and the IMU samples between them (the inertial-only estimation of Campos et al.,
// ICRA 2020, with the scale known: stereo poses are metric).
//
// Steps: (1) the gyroscope bias that best aligns the preintegrated rotations with the poses'
// relative rotations (Gauss-Newton on the bias); (2) with it, the velocities, gravity and the
// accelerometer bias from the linear position and velocity increment equations (weighted by the
// increments' covariance plus the poses' own noise, the accelerometer bias held near zero by a
// prior so that a start at rest, where it cannot be told from a tilt of gravity, stays
// determined); (3) gravity's magnitude fixed to the known one and its direction, the velocities
// and the bias refined by Gauss-Newton on the same equations.
//
// Frames: world = the poses' world; body = the IMU frame.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "slslam/core/rigid3.h"
#include "slslam/inertial/imu_preintegration.h"

namespace slslam {

struct InertialInitOptions {
  double gravity_mps2 = 9.81;               ///< known magnitude of gravity [m/s^2]
  double gravity_tolerance_mps2 = 0.5;      ///< unconstrained fit further off: failure [m/s^2]
  double acc_bias_prior_mps2 = 1.0;         ///< standard deviation of the bias prior [m/s^2]
  double gyro_bias_prior_radps = 0.1;       ///< standard deviation of the bias prior [rad/s]
  double pose_sigma_m = 0.01;               ///< position noise of each pose [m]
  double pose_sigma_rad = 0.002;            ///< rotation noise of each pose [rad]
  double max_rotation_residual_rad = 0.02;  ///< RMS rotation misfit above: failure [rad]

  void Check() const;
};

struct InertialInitResult {
  bool success = false;
  std::string reason;                                 ///< why not, when success is false
  Eigen::Vector3d g_world = Eigen::Vector3d::Zero();  ///< gravity in the world [m/s^2]
  ImuBias bias;
  std::vector<Eigen::Vector3d> v_world;     ///< velocity of the body at each pose [m/s]
  double rotation_rms_rad = 0.0;            ///< rotation misfit after the gyro bias [rad]
  double unconstrained_gravity_mps2 = 0.0;  ///< |g| of step (2) [m/s^2]
};

// world_from_body: n >= 3 body poses in time order; preintegrated[k]: the IMU over
// (pose k, pose k+1), n - 1 of them, integrated with any bias_hat (corrected to the estimate).
InertialInitResult InitialiseInertial(const std::vector<Rigid3d>& world_from_body,
                                      const std::vector<ImuPreintegration>& preintegrated,
                                      const InertialInitOptions& options = {});

}  // namespace slslam
