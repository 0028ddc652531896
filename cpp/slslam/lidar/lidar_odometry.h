// LiDAR(-inertial) odometry, one sweep at a time: IMU prediction, deskewing, scan-to-map
// registration from the predicted pose, fixed-lag factor-graph smoothing with the IMU, and the
// bounded voxel-hash local map. Without IMU samples it runs as LiDAR-only odometry with a
// constant-velocity prediction.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "slslam/core/rigid3.h"
#include "slslam/inertial/imu_preintegration.h"
#include "slslam/lidar/deskew.h"
#include "slslam/lidar/lio_smoother.h"
#include "slslam/lidar/registration.h"
#include "slslam/lidar/scan_matcher.h"
#include "slslam/lidar/voxel_map.h"

namespace slslam::lidar {

struct LidarOdometryOptions {
  double min_range_m = 1.0;             ///< points nearer than this to the sensor are dropped [m]
  double max_range_m = 100.0;           ///< points farther are dropped [m]: a 16-beam sensor's
                                        ///< range; in a long roadway the far end walls are what
                                        ///< fixes the position along it where the walls are bare
  double source_voxel_m = 0.5;          ///< voxel of the points registered against the map [m]
  double map_voxel_m = 0.25;            ///< voxel of the points added to the map [m]
  double scan_period_s = 0.1;           ///< duration of one sweep [s]
  bool deskew = true;                   ///< motion-compensate sweeps with per-point times
  bool use_imu = true;                  ///< IMU prediction and smoothing (needs AddImu samples)
  double scan_information_scale = 0.1;  ///< scales the scan's information in the smoother: the
                                        ///< residuals of one scan are not independent [-]
  double gravity_window_s = 0.05;  ///< IMU time around the first sweep averaged for the initial
                                   ///< attitude; the robot must be at rest [s]
  Rigid3d body_from_sensor;        ///< the LiDAR in the IMU frame (T_body_sensor in Python)
  VoxelMapOptions map;
  ScanMatchOptions match;
  LioSmootherOptions smoother;
  ImuNoiseOptions imu;
  void Check() const;
};

struct OdometryResult {
  int64_t t_ns = 0;  ///< sweep start; the poses hold at this time
  Rigid3d world_from_sensor;
  Rigid3d world_from_body;
  Eigen::Vector3d velocity_world = Eigen::Vector3d::Zero();  ///< [m/s]
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();       ///< [rad/s]
  Eigen::Vector3d acc_bias = Eigen::Vector3d::Zero();        ///< [m/s^2]
  bool matched = false;   ///< registered against the map (false for the first sweep)
  int source_points = 0;  ///< points registered after downsampling
  int correspondences = 0;
  double fitness = 0.0;  ///< inlier fraction of the registration [-]
  double inlier_rmse_m = 0.0;
  double degeneracy = 0.0;  ///< smallest / largest translation information eigenvalue [-]
  int map_points = 0;
  double deskew_ms = 0.0, match_ms = 0.0, smoother_ms = 0.0, map_ms = 0.0, total_ms = 0.0;
};

class LidarOdometry {
 public:
  explicit LidarOdometry(const LidarOdometryOptions& options = {});
  ~LidarOdometry();

  // IMU samples (strictly increasing t_ns, gyro [rad/s], specific force [m/s^2], body frame),
  // appended to those given before. A sweep needs samples up to its end.
  void AddImu(const std::vector<int64_t>& t_ns,
              const Eigen::Matrix<double, Eigen::Dynamic, 3>& gyro,
              const Eigen::Matrix<double, Eigen::Dynamic, 3>& acc);

  // One sweep starting at t_ns: points N x 3|4 in the sensor frame (each at its own time),
  // point_time_s N times after t_ns [s] (empty: no per-point time, no deskewing).
  OdometryResult ProcessScan(int64_t t_ns, const PointMatrix& points,
                             const std::vector<double>& point_time_s);

  // The last sweep, deskewed to its start and voxelised at map_voxel_m, in the sensor frame.
  const std::vector<Eigen::Vector3d>& last_scan() const { return last_scan_; }
  std::vector<Eigen::Vector3d> MapPoints() const { return map_.Points(); }
  const LidarOdometryOptions& options() const { return options_; }

 private:
  ImuPreintegration Preintegrate(int64_t from_ns, int64_t to_ns, const ImuBias& bias) const;
  SweepMotion ImuSweepMotion(const LioState& start, int64_t t_ns) const;
  LioState InitialState(int64_t t_ns) const;

  LidarOdometryOptions options_;
  VoxelMap map_;
  std::unique_ptr<LioSmoother> smoother_;
  std::vector<int64_t> imu_t_ns_;
  std::vector<Eigen::Vector3d> imu_gyro_, imu_acc_;
  int64_t last_t_ns_ = 0;
  int scans_ = 0;
  Rigid3d world_from_sensor_;
  Rigid3d previous_from_current_;  ///< the last sweep-to-sweep motion (of the sensor)
  LioState state_;
  std::vector<Eigen::Vector3d> last_scan_;
};

}  // namespace slslam::lidar
