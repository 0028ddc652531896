// Poses through short visual outages from the IMU: a headlamp blackout, a wall of dust, a frame
// the camera cannot track. While the camera tracks, the recent poses and the IMU samples between
// them give the gyroscope bias, gravity in the map's world frame and the velocity (a linear
// least-squares fit, as visual-inertial initialisation does in VINS-Mono and ORB-SLAM3); when a
// frame cannot be tracked, its pose is the last tracked pose carried forward by the integrated
// IMU samples. Only for a short gap (`max_gap_s`): the error of dead reckoning grows with the
// square of the time.
//
// Frames: world = the map's world (not gravity-aligned; gravity is estimated in it), body = the
// IMU frame, cam = the rectified left camera. Samples are gyro [rad/s] and specific force
// [m/s^2] in the body frame, each held until the next sample's time.
#pragma once

#include <deque>

#include <Eigen/Core>

#include "slslam/core/rigid3.h"

namespace slslam {

struct InertialBridgeOptions {
  double window_s = 3.0;      ///< tracked poses the fit uses, before the last one [s]
  double min_window_s = 1.0;  ///< the fit needs tracked poses spanning at least this [s]
  double max_gap_s = 2.0;     ///< longest time after the last tracked pose that is bridged [s]
  double max_sample_gap_s = 0.05;  ///< IMU samples further apart than this: no bridge [s]
  double gravity_mps2 = 9.81;      ///< expected magnitude of gravity [m/s^2]
  double gravity_tolerance_mps2 = 0.5;  ///< a fitted gravity further off: no bridge [m/s^2]
  Rigid3d body_from_cam;                ///< the left camera in the IMU frame

  void Check() const;
};

class InertialBridge {
 public:
  explicit InertialBridge(const InertialBridgeOptions& options);

  // One IMU sample at t_s [s]; samples must come in increasing time (else std::invalid_argument).
  void AddImu(double t_s, const Eigen::Vector3d& gyro_radps, const Eigen::Vector3d& acc_mps2);
  // A pose the camera estimated at t_s (tracked or relocalised frame), in the current world.
  void AddPose(double t_s, const Rigid3d& cam_from_world);
  // Forgets the poses (the world changed: a new map, a relocalisation into another map, a loop
  // correction); samples stay.
  void ResetPoses();

  // The camera pose at t_s from the last pose and the IMU; false when it cannot be bridged: no
  // fit yet (too few poses or samples), a gap longer than max_gap_s, missing samples, or a fit
  // whose gravity is implausible.
  bool Predict(double t_s, Rigid3d* cam_from_world) const;

  // The fit of the latest Predict (for tests and diagnostics).
  struct Fit {
    Eigen::Vector3d gravity_world = Eigen::Vector3d::Zero();  ///< [m/s^2]
    Eigen::Vector3d velocity_world = Eigen::Vector3d::Zero();  ///< body, at the last pose [m/s]
    Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();       ///< [rad/s]
    double last_pose_s = -1.0;  ///< time of the pose it was made for [s]
    bool valid = false;
  };
  const Fit& fit() const { return fit_; }

 private:
  struct Sample {
    double t_s;
    Eigen::Vector3d gyro, acc;
  };
  struct Pose {
    double t_s;
    Eigen::Matrix3d R_world_body;
    Eigen::Vector3d p_world_body;
  };
  // Integrates the samples over [t0, t1] from rotation R0 (world from body at t0) with the gyro
  // bias removed: the rotation at t1 and the gravity-free velocity and position increments in
  // the world frame (dv = sum R a dt, dp = sum (dv dt + R a dt^2 / 2)). False when samples are
  // missing over the interval.
  bool Integrate(double t0, double t1, const Eigen::Matrix3d& R0, const Eigen::Vector3d& bias,
                 Eigen::Matrix3d* R1, Eigen::Vector3d* dv, Eigen::Vector3d* dp) const;
  bool MakeFit() const;

  InertialBridgeOptions options_;
  std::deque<Sample> samples_;
  std::deque<Pose> poses_;
  mutable Fit fit_;
};

}  // namespace slslam
