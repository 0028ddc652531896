// Motion compensation of a spinning LiDAR sweep: every point is moved from the sensor frame at
// its own time into the sensor frame at the sweep's start, using the sensor's motion during the
// sweep (from the IMU and the velocity estimate, or a constant-velocity model).
#pragma once

#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace slslam::lidar {

// Poses T_start_t of the sensor at increasing times t [s after the sweep start] relative to its
// pose at the start. Between samples the motion is interpolated (slerp and linear translation);
// before the first and after the last sample it is held.
struct SweepMotion {
  std::vector<double> time_s;
  std::vector<Eigen::Isometry3d> T_start_t;

  // Pose at time t [s] (interpolated as above). Identity when empty.
  Eigen::Isometry3d At(double t) const;
  // Constant velocity: T_start_t = Exp(t / period * Log(T_start_end)), sampled `samples` times.
  static SweepMotion ConstantVelocity(const Eigen::Isometry3d& T_start_end, double period_s,
                                      int samples = 10);
};

// Points (sensor frame at each point's time, m) expressed in the sensor frame at the sweep
// start. `time_s` holds one time per point [s after the start]. Throws std::invalid_argument on a
// size mismatch, a non-finite time or motion samples out of order.
std::vector<Eigen::Vector3d> DeskewPoints(const std::vector<Eigen::Vector3d>& points,
                                          const std::vector<double>& time_s,
                                          const SweepMotion& motion);

}  // namespace slslam::lidar
