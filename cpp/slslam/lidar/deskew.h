// Motion compensation of a spinning LiDAR sweep: every point is moved from the sensor frame at
// its own time into the sensor frame at the sweep's start, using the sensor's motion during the
// sweep (from the IMU and the velocity estimate, or a constant-velocity model).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "slslam/core/rigid3.h"

namespace slslam::lidar {

// Poses start_from_t of the sensor at increasing times t [s after the sweep start]: the sensor
// at t in the sensor frame at the start. Between samples the motion is interpolated (slerp and
// linear translation); before the first and after the last sample it is held.
struct SweepMotion {
  std::vector<double> time_s;
  std::vector<Rigid3d> start_from_t;

  // Pose at time t [s] (interpolated as above). Identity when empty.
  Rigid3d At(double t) const;
  // Constant velocity: the rotation Exp(t / period * Log(R_start_end)) and the translation along
  // the straight line to start_from_end's, sampled `samples` times.
  static SweepMotion ConstantVelocity(const Rigid3d& start_from_end, double period_s,
                                      int samples = 10);
};

// Points (sensor frame at each point's time, m) expressed in the sensor frame at the sweep
// start. `time_s` holds one time per point [s after the start]. Throws std::invalid_argument on a
// size mismatch, a non-finite time or motion samples out of order.
std::vector<Eigen::Vector3d> DeskewPoints(const std::vector<Eigen::Vector3d>& points,
                                          const std::vector<double>& time_s,
                                          const SweepMotion& motion);

}  // namespace slslam::lidar
