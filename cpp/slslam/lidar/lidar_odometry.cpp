#include "slslam/lidar/lidar_odometry.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "slslam/core/check.h"
#include "slslam/core/time.h"

namespace slslam::lidar {

namespace {

// A sweep-to-sweep jump beyond this means registration diverged (100 m/s at 10 Hz) [m].
constexpr double kMaxJumpM = 10.0;

Rigid3d WorldFromBody(const NavState& nav) {
  return Rigid3d(nav.R_world_body.toRotationMatrix(), nav.p_world_body);
}

double MsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}

}  // namespace

void LidarOdometryOptions::Check() const {
  SLSLAM_CHECK(min_range_m >= 0 && max_range_m > min_range_m,
               "LidarOdometryOptions: need 0 <= min_range_m < max_range_m, got ", min_range_m,
               " and ", max_range_m);
  SLSLAM_CHECK(source_voxel_m > 0.01 && map_voxel_m > 0.01,
               "LidarOdometryOptions: source_voxel_m and map_voxel_m must be > 0.01 m");
  SLSLAM_CHECK(scan_period_s > 0 && scan_period_s <= 1.0,
               "LidarOdometryOptions.scan_period_s must be in (0, 1] s, got ", scan_period_s);
  SLSLAM_CHECK(scan_information_scale > 0,
               "LidarOdometryOptions.scan_information_scale must be > 0, got ",
               scan_information_scale);
  SLSLAM_CHECK(gravity_window_s > 0, "LidarOdometryOptions.gravity_window_s must be > 0 s");
  SLSLAM_CHECK(body_from_sensor.rotation.allFinite() && body_from_sensor.translation.allFinite() &&
                   (body_from_sensor.rotation.transpose() * body_from_sensor.rotation -
                    Eigen::Matrix3d::Identity())
                           .norm() < 1e-6,
               "LidarOdometryOptions.body_from_sensor (T_body_sensor) must be a rigid transform");
  map.Check();
  match.Check();
  smoother.Check();
  imu.Check();
}

LidarOdometry::LidarOdometry(const LidarOdometryOptions& options)
    : options_(options), map_((options.Check(), options.map)) {
  // The world frame is the body frame at the first sweep (gravity-aligned with the IMU).
  world_from_sensor_ = options_.body_from_sensor;
  if (options_.use_imu) {
    smoother_ =
        std::make_unique<LioSmoother>(options_.smoother, options_.imu, options_.body_from_sensor);
  }
}

LidarOdometry::~LidarOdometry() = default;

void LidarOdometry::AddImu(const std::vector<int64_t>& t_ns,
                           const Eigen::Matrix<double, Eigen::Dynamic, 3>& gyro,
                           const Eigen::Matrix<double, Eigen::Dynamic, 3>& acc) {
  SLSLAM_CHECK(gyro.rows() == static_cast<Eigen::Index>(t_ns.size()) && acc.rows() == gyro.rows(),
               "AddImu: ", t_ns.size(), " times, ", gyro.rows(), " gyro and ", acc.rows(),
               " accelerometer rows");
  SLSLAM_CHECK(gyro.allFinite() && acc.allFinite(), "AddImu: IMU samples must be finite");
  for (size_t k = 0; k < t_ns.size(); ++k) {
    SLSLAM_CHECK(imu_t_ns_.empty() || t_ns[k] > imu_t_ns_.back(),
                 "AddImu: IMU times must increase, got ", t_ns[k], " ns after ",
                 imu_t_ns_.empty() ? 0 : imu_t_ns_.back(), " ns");
    imu_t_ns_.push_back(t_ns[k]);
    imu_gyro_.push_back(gyro.row(k).transpose());
    imu_acc_.push_back(acc.row(k).transpose());
  }
}

ImuPreintegration LidarOdometry::Preintegrate(int64_t from_ns, int64_t to_ns,
                                              const ImuBias& bias) const {
  ImuPreintegration pre(bias, options_.imu);
  SLSLAM_CHECK(!imu_t_ns_.empty() && imu_t_ns_.front() <= from_ns,
               "LiDAR-inertial odometry: no IMU sample before t = ", from_ns, " ns");
  SLSLAM_CHECK(imu_t_ns_.back() >= to_ns, "LiDAR-inertial odometry: IMU samples end at ",
               imu_t_ns_.back(), " ns, before the sweep ending at ", to_ns, " ns");
  // Sample k holds over [t_k, t_k+1) (zero-order hold).
  size_t k = std::upper_bound(imu_t_ns_.begin(), imu_t_ns_.end(), from_ns) - imu_t_ns_.begin() - 1;
  int64_t t = from_ns;
  while (t < to_ns) {
    const int64_t next = k + 1 < imu_t_ns_.size() ? std::min(imu_t_ns_[k + 1], to_ns) : to_ns;
    if (next > t) pre.Integrate(imu_gyro_[k], imu_acc_[k], (next - t) * 1e-9);
    t = next;
    ++k;
  }
  return pre;
}

LioState LidarOdometry::InitialState(int64_t t_ns) const {
  // The robot starts at rest: the mean specific force points up in the body frame.
  const int64_t window_ns = NsFromSeconds(options_.gravity_window_s);
  const int64_t end = t_ns + window_ns;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  int n = 0;
  for (size_t k = 0; k < imu_t_ns_.size() && imu_t_ns_[k] <= end; ++k) {
    if (imu_t_ns_[k] + window_ns < t_ns) continue;
    mean += imu_acc_[k];
    ++n;
  }
  SLSLAM_CHECK(n > 0, "LiDAR-inertial odometry: no IMU sample near the first sweep (t = ", t_ns,
               " ns)");
  LioState state;
  state.nav.R_world_body = Eigen::Quaterniond::FromTwoVectors(mean / n, Eigen::Vector3d::UnitZ());
  return state;
}

SweepMotion LidarOdometry::ImuSweepMotion(const LioState& start, int64_t t_ns) const {
  // Body poses at the IMU sample times within the sweep, from the state at its start.
  const int64_t end = t_ns + NsFromSeconds(options_.scan_period_s);
  SLSLAM_CHECK(!imu_t_ns_.empty() && imu_t_ns_.front() <= t_ns,
               "LiDAR-inertial odometry: no IMU sample before the sweep at ", t_ns, " ns");
  const Rigid3d& body_from_sensor = options_.body_from_sensor;
  const Rigid3d start_from_world = (WorldFromBody(start.nav) * body_from_sensor).Inverse();
  SweepMotion motion;
  motion.time_s.push_back(0.0);
  motion.start_from_t.emplace_back();
  std::vector<int64_t> knots;
  for (size_t k = std::upper_bound(imu_t_ns_.begin(), imu_t_ns_.end(), t_ns) - imu_t_ns_.begin();
       k < imu_t_ns_.size() && imu_t_ns_[k] < end; ++k) {
    knots.push_back(imu_t_ns_[k]);
  }
  knots.push_back(end);
  ImuPreintegration pre(start.bias, options_.imu);
  int64_t t = t_ns;
  size_t k = std::upper_bound(imu_t_ns_.begin(), imu_t_ns_.end(), t_ns) - imu_t_ns_.begin() - 1;
  for (int64_t knot : knots) {
    pre.Integrate(imu_gyro_[k], imu_acc_[k], (knot - t) * 1e-9);
    t = knot;
    ++k;
    const NavState nav = pre.Predict(start.nav, start.bias);
    motion.time_s.push_back((knot - t_ns) * 1e-9);
    motion.start_from_t.push_back(start_from_world * WorldFromBody(nav) * body_from_sensor);
  }
  return motion;
}

OdometryResult LidarOdometry::ProcessScan(int64_t t_ns, const PointMatrix& points,
                                          const std::vector<double>& point_time_s) {
  const auto start = std::chrono::steady_clock::now();
  CheckPoints(points, "LiDAR sweep", 1);
  SLSLAM_CHECK(point_time_s.empty() || point_time_s.size() == static_cast<size_t>(points.rows()),
               "LiDAR sweep at ", t_ns, " ns: ", points.rows(), " points but ", point_time_s.size(),
               " point times");
  SLSLAM_CHECK(scans_ == 0 || t_ns > last_t_ns_, "LiDAR sweep at ", t_ns,
               " ns is not after the previous one (", last_t_ns_, " ns)");
  const bool imu = options_.use_imu;
  OdometryResult result;
  result.t_ns = t_ns;

  // Prediction of the sensor pose at the sweep start and of the motion during the sweep.
  const Rigid3d& body_from_sensor = options_.body_from_sensor;
  Rigid3d world_from_predicted = world_from_sensor_;
  LioState predicted = state_;
  std::unique_ptr<ImuPreintegration> pre;
  if (imu && scans_ == 0) {
    predicted = InitialState(t_ns);
  } else if (imu) {
    pre = std::make_unique<ImuPreintegration>(Preintegrate(last_t_ns_, t_ns, state_.bias));
    predicted.nav = pre->Predict(state_.nav, state_.bias);
  } else {
    world_from_predicted = world_from_sensor_ * previous_from_current_;
  }
  if (imu) world_from_predicted = WorldFromBody(predicted.nav) * body_from_sensor;

  // Range crop and deskew into the sensor frame at the sweep start.
  auto t0 = std::chrono::steady_clock::now();
  std::vector<Eigen::Vector3d> raw;
  std::vector<double> times;
  raw.reserve(points.rows());
  const double min2 = options_.min_range_m * options_.min_range_m;
  const double max2 = options_.max_range_m * options_.max_range_m;
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    const Eigen::Vector3d p = points.row(i).head<3>().cast<double>().transpose();
    const double r2 = p.squaredNorm();
    if (r2 < min2 || r2 > max2) continue;
    raw.push_back(p);
    if (!point_time_s.empty()) times.push_back(point_time_s[i]);
  }
  SLSLAM_CHECK(raw.size() >= 10, "LiDAR sweep at ", t_ns, " ns: only ", raw.size(),
               " points between ", options_.min_range_m, " and ", options_.max_range_m, " m");
  std::vector<Eigen::Vector3d> deskewed = raw;
  if (options_.deskew && !times.empty()) {
    const double interval_s = scans_ > 0 ? (t_ns - last_t_ns_) * 1e-9 : options_.scan_period_s;
    const SweepMotion motion =
        imu ? ImuSweepMotion(predicted, t_ns)
            : SweepMotion::ConstantVelocity(previous_from_current_, interval_s, 10);
    deskewed = DeskewPoints(raw, times, motion);
  }
  const std::vector<Eigen::Vector3d> source = VoxelDownsample(deskewed, options_.source_voxel_m);
  last_scan_ = VoxelDownsample(deskewed, options_.map_voxel_m);
  result.source_points = static_cast<int>(source.size());
  result.deskew_ms = MsSince(t0);

  // Scan-to-map registration from the prediction.
  t0 = std::chrono::steady_clock::now();
  Rigid3d world_from_sensor = world_from_predicted;
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
  if (scans_ > 0 && map_.num_voxels() > 0) {
    ScanMatchOptions match = options_.match;
    if (!imu) match.prior_translation_sigma_m = match.prior_rotation_sigma_rad = 0.0;
    const ScanMatchResult m = MatchScanToMap(source, map_, world_from_predicted, match);
    world_from_sensor = m.world_from_sensor;
    information = m.information * options_.scan_information_scale;
    result.matched = true;
    result.correspondences = m.correspondences;
    result.fitness = m.fitness;
    result.inlier_rmse_m = m.inlier_rmse_m;
    result.degeneracy = m.degeneracy;
  }
  result.match_ms = MsSince(t0);

  // Smoothing with the IMU.
  t0 = std::chrono::steady_clock::now();
  if (imu && scans_ == 0) {
    smoother_->Initialise(predicted);
    state_ = predicted;
  } else if (imu) {
    state_ = smoother_->Update(*pre, world_from_sensor, information);
    world_from_sensor = WorldFromBody(state_.nav) * body_from_sensor;
  }
  result.smoother_ms = MsSince(t0);

  // Map update.
  t0 = std::chrono::steady_clock::now();
  std::vector<Eigen::Vector3d> world(last_scan_.size());
  for (size_t i = 0; i < world.size(); ++i) world[i] = world_from_sensor * last_scan_[i];
  map_.Add(world);
  map_.RemoveFar(world_from_sensor.translation);
  result.map_points = static_cast<int>(map_.num_points());
  result.map_ms = MsSince(t0);

  if (!world_from_sensor.rotation.allFinite() || !world_from_sensor.translation.allFinite() ||
      (scans_ > 0 &&
       (world_from_sensor.translation - world_from_sensor_.translation).norm() > kMaxJumpM)) {
    throw std::runtime_error(Message("LiDAR odometry lost track at the sweep of ", t_ns,
                                     " ns: the pose is not finite or jumped more than ", kMaxJumpM,
                                     " m"));
  }
  if (scans_ > 0) previous_from_current_ = world_from_sensor_.Inverse() * world_from_sensor;
  world_from_sensor_ = world_from_sensor;
  last_t_ns_ = t_ns;
  ++scans_;
  result.world_from_sensor = world_from_sensor;
  result.world_from_body = world_from_sensor * body_from_sensor.Inverse();
  result.velocity_world = state_.nav.v_world_body;
  result.gyro_bias = state_.bias.gyro;
  result.acc_bias = state_.bias.acc;
  result.total_ms = MsSince(start);
  return result;
}

}  // namespace slslam::lidar
