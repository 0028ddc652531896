// Fixed-lag factor-graph smoother of LiDAR-inertial odometry (LIO-SAM's factor graph restricted
// to a sliding window, solved with Ceres): states (pose, velocity, biases) at the scan times,
// IMU preintegration factors with bias correction between consecutive states, bias random-walk
// factors, and a LiDAR odometry factor per state (the scan-to-map pose with the scan's own
// Gauss-Newton information, so a direction the scan cannot see is left to the IMU).
//
// Why Ceres and a window rather than GTSAM's iSAM2: Ceres is already the project's solver, the
// window keeps each update at a few milliseconds, and loop closures are handled by a separate
// keyframe pose graph (optimization/pose_graph.h) whose correction is applied to the odometry
// frame.
#pragma once

#include <deque>
#include <memory>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "slslam/core/rigid3.h"
#include "slslam/inertial/imu_preintegration.h"

namespace slslam::lidar {

struct LioSmootherOptions {
  int window = 50;  ///< states kept; the oldest is held fixed. 5 s at 10 Hz: the accelerometer
                    ///< bias is then estimated over metres of travel; with 2 s it followed each
                    ///< scan's error along a corridor and the velocity oscillated, the swing
                    ///< growing until the odometry was 4 m behind after 59 m (simulated straight
                    ///< corridor)
  int max_iterations = 10;                   ///< Levenberg-Marquardt iterations per update [-]
  double initial_velocity_sigma_mps = 0.05;  ///< prior on the first state's velocity [m/s]
  double initial_gyro_bias_sigma = 0.001;    ///< prior on the first gyro bias [rad/s]
  double initial_acc_bias_sigma = 0.01;      ///< prior on the first accelerometer bias [m/s^2]: a
                                             ///< loose one lets the bias absorb a roll error in a
                                             ///< corridor, where scans see roll weakly
  double initial_tilt_sigma_rad = 0.02;      ///< prior on the first roll and pitch (from gravity
                                             ///< alignment during a vibrating start) [rad]
  void Check() const;
};

struct LioState {
  NavState nav;
  ImuBias bias;
};

class LioSmoother {
 public:
  LioSmoother(const LioSmootherOptions& options, const ImuNoiseOptions& noise,
              const Rigid3d& body_from_sensor);
  ~LioSmoother();

  // The first state (pose from gravity alignment, velocity prior mean, zero biases).
  void Initialise(const LioState& state);
  bool initialised() const { return !states_.empty(); }

  // Adds the state reached through `imu` (integrated from the newest state with its bias) with
  // the LiDAR pose world_from_sensor and its 6x6 information (order rho, phi: perturbation
  // p <- p + rho, R <- Exp(phi) R), then optimises the window. Returns the newest state.
  LioState Update(const ImuPreintegration& imu, const Rigid3d& world_from_sensor,
                  const Eigen::Matrix<double, 6, 6>& information);

  const LioState& newest() const;
  // Shifts every state by new_from_old (a loop correction of the odometry frame).
  void Transform(const Rigid3d& new_from_old);

 private:
  struct Node;
  LioSmootherOptions options_;
  ImuNoiseOptions noise_;
  Rigid3d body_from_sensor_;
  std::deque<std::unique_ptr<Node>> states_;
  Eigen::Quaterniond first_q_ = Eigen::Quaterniond::Identity();
  Eigen::Vector3d first_p_ = Eigen::Vector3d::Zero();
};

}  // namespace slslam::lidar
