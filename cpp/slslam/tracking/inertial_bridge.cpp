#include "slslam/tracking/inertial_bridge.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>
#include <Eigen/Geometry>

#include "slslam/core/check.h"

namespace slslam {

namespace {

Eigen::Matrix3d ExpSo3(const Eigen::Vector3d& w) {
  const double angle = w.norm();
  if (angle < 1e-12) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
}

Eigen::Vector3d LogSo3(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

}  // namespace

void InertialBridgeOptions::Check() const {
  CheckAboveInRange("tracking.imu.window_s", window_s, 0.0, 1e4);
  CheckAboveInRange("tracking.imu.min_window_s", min_window_s, 0.0, 1e4);
  SLSLAM_CHECK(min_window_s <= window_s, "tracking.imu.min_window_s (", min_window_s,
               ") must not exceed tracking.imu.window_s (", window_s, ")");
  CheckInRange("tracking.imu.max_gap_s", max_gap_s, 0.0, 1e4);
  CheckAboveInRange("tracking.imu.max_sample_gap_s", max_sample_gap_s, 0.0, 10.0);
  CheckAboveInRange("tracking.imu.gravity_mps2", gravity_mps2, 0.0, 100.0);
  CheckAboveInRange("tracking.imu.gravity_tolerance_mps2", gravity_tolerance_mps2, 0.0, 100.0);
  const Eigen::Matrix3d& R = body_from_cam.rotation;
  SLSLAM_CHECK(R.allFinite() && body_from_cam.translation.allFinite() &&
                   (R.transpose() * R - Eigen::Matrix3d::Identity()).norm() < 1e-6 &&
                   R.determinant() > 0.0,
               "tracking.imu.body_from_cam must be a finite rigid transform");
}

InertialBridge::InertialBridge(const InertialBridgeOptions& options) : options_(options) {
  options_.Check();
}

void InertialBridge::AddImu(double t_s, const Eigen::Vector3d& gyro_radps,
                            const Eigen::Vector3d& acc_mps2) {
  SLSLAM_CHECK(std::isfinite(t_s) && gyro_radps.allFinite() && acc_mps2.allFinite(),
               "IMU sample at t = ", t_s, " s is not finite");
  SLSLAM_CHECK(samples_.empty() || t_s > samples_.back().t_s, "IMU sample at t = ", t_s,
               " s does not follow the previous one (", samples_.back().t_s, " s)");
  samples_.push_back({t_s, gyro_radps, acc_mps2});
  // Keep what the fit window of the newest pose and a gap after it can need.
  const double keep_s = options_.window_s + options_.max_gap_s + 1.0;
  const double oldest_pose = poses_.empty() ? t_s : poses_.front().t_s;
  while (samples_.size() > 2 && samples_[1].t_s < std::min(t_s - keep_s, oldest_pose)) {
    samples_.pop_front();
  }
}

void InertialBridge::AddPose(double t_s, const Rigid3d& cam_from_world) {
  if (!poses_.empty() && t_s <= poses_.back().t_s) return;
  const Rigid3d world_from_body = cam_from_world.Inverse() * options_.body_from_cam.Inverse();
  poses_.push_back({t_s, world_from_body.rotation, world_from_body.translation});
  while (!poses_.empty() && poses_.front().t_s < t_s - options_.window_s) poses_.pop_front();
}

void InertialBridge::ResetPoses() {
  poses_.clear();
  fit_ = Fit{};
}

bool InertialBridge::Integrate(double t0, double t1, const Eigen::Matrix3d& R0,
                               const Eigen::Vector3d& bias, Eigen::Matrix3d* R1,
                               Eigen::Vector3d* dv, Eigen::Vector3d* dp) const {
  *R1 = R0;
  dv->setZero();
  dp->setZero();
  if (samples_.empty() || t1 < t0) return false;
  // The sample that holds at t0: the last one at or before it.
  auto it = std::upper_bound(samples_.begin(), samples_.end(), t0,
                             [](double t, const Sample& s) { return t < s.t_s; });
  if (it == samples_.begin()) return false;
  --it;
  double t = t0;
  while (t < t1) {
    const auto next = std::next(it);
    // Each sample holds until the next one; the newest one for at most max_sample_gap_s.
    const double end_of_sample =
        next != samples_.end() ? next->t_s : it->t_s + options_.max_sample_gap_s;
    if (end_of_sample - it->t_s > options_.max_sample_gap_s + 1e-9) return false;  // a hole
    if (next == samples_.end() && t1 > end_of_sample) return false;  // not yet measured
    const double dt = std::min(t1, end_of_sample) - t;
    if (dt > 0.0) {
      const Eigen::Vector3d a_world = (*R1) * it->acc;
      *dp += (*dv) * dt + 0.5 * a_world * dt * dt;
      *dv += a_world * dt;
      *R1 = (*R1) * ExpSo3((it->gyro - bias) * dt);
      t += dt;
    }
    if (next == samples_.end()) break;
    it = next;
  }
  return true;
}

bool InertialBridge::MakeFit() const {
  fit_ = Fit{};
  if (poses_.size() < 3) return false;
  fit_.last_pose_s = poses_.back().t_s;
  const Pose& first = poses_.front();
  if (poses_.back().t_s - first.t_s < options_.min_window_s) return false;

  // Gyroscope bias: the rotation the gyro integrates between two poses against the camera's,
  // Exp(-b dt) = R_gyro^T R_camera to first order, averaged over the window (weights dt).
  Eigen::Vector3d log_sum = Eigen::Vector3d::Zero();
  double dt_sum = 0.0;
  Eigen::Matrix3d R1;
  Eigen::Vector3d dv, dp;
  for (size_t j = 0; j + 1 < poses_.size(); ++j) {
    if (!Integrate(poses_[j].t_s, poses_[j + 1].t_s, poses_[j].R_world_body,
                   Eigen::Vector3d::Zero(), &R1, &dv, &dp)) {
      return false;
    }
    log_sum += LogSo3(R1.transpose() * poses_[j + 1].R_world_body);
    dt_sum += poses_[j + 1].t_s - poses_[j].t_s;
  }
  const Eigen::Vector3d bias = -log_sum / dt_sum;

  // p_j = p_0 + v_0 T_j + g T_j^2 / 2 + DP_j, with DP_j the gravity-free increment integrated
  // from the first pose (each segment from the camera's rotation at its start): linear in
  // (v_0, g), fitted by least squares.
  const size_t n = poses_.size();
  Eigen::MatrixXd A(3 * (n - 1), 6);
  Eigen::VectorXd b(3 * (n - 1));
  Eigen::Vector3d DV = Eigen::Vector3d::Zero(), DP = Eigen::Vector3d::Zero();
  for (size_t j = 1; j < n; ++j) {
    const double segment = poses_[j].t_s - poses_[j - 1].t_s;
    if (!Integrate(poses_[j - 1].t_s, poses_[j].t_s, poses_[j - 1].R_world_body, bias, &R1, &dv,
                   &dp)) {
      return false;
    }
    DP += DV * segment + dp;
    DV += dv;
    const double T = poses_[j].t_s - first.t_s;
    A.block<3, 3>(3 * (j - 1), 0) = T * Eigen::Matrix3d::Identity();
    A.block<3, 3>(3 * (j - 1), 3) = 0.5 * T * T * Eigen::Matrix3d::Identity();
    b.segment<3>(3 * (j - 1)) = poses_[j].p_world_body - first.p_world_body - DP;
  }
  const Eigen::Matrix<double, 6, 1> x = A.colPivHouseholderQr().solve(b);
  if (!x.allFinite()) return false;
  const Eigen::Vector3d gravity = x.tail<3>();
  // The accelerometer bias is not separated from gravity: over a short window it folds into the
  // fitted gravity, which is what the bridge needs. A fit far from |g| is a bad one.
  if (std::abs(gravity.norm() - options_.gravity_mps2) > options_.gravity_tolerance_mps2) {
    return false;
  }
  const double T_last = poses_.back().t_s - first.t_s;
  fit_.gravity_world = gravity;
  fit_.velocity_world = x.head<3>() + gravity * T_last + DV;
  fit_.gyro_bias = bias;
  fit_.valid = true;
  return true;
}

bool InertialBridge::Predict(double t_s, Rigid3d* cam_from_world) const {
  if (poses_.empty()) return false;
  const Pose& last = poses_.back();
  const double tau = t_s - last.t_s;
  if (!(tau >= 0.0 && tau <= options_.max_gap_s)) return false;
  if (fit_.last_pose_s != last.t_s) MakeFit();
  if (!fit_.valid) return false;
  Eigen::Matrix3d R;
  Eigen::Vector3d dv, dp;
  if (!Integrate(last.t_s, t_s, last.R_world_body, fit_.gyro_bias, &R, &dv, &dp)) return false;
  const Eigen::Vector3d p =
      last.p_world_body + fit_.velocity_world * tau + 0.5 * fit_.gravity_world * tau * tau + dp;
  const Rigid3d world_from_cam = Rigid3d(R, p) * options_.body_from_cam;
  *cam_from_world = world_from_cam.Inverse();
  return true;
}

}  // namespace slslam
