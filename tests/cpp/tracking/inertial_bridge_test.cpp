// The IMU bridge on an exact synthetic motion: a body that accelerates, turns about all three axes
// and carries a gyroscope bias, in a world frame that is not gravity-aligned. Camera poses at
// 20 Hz for 3 s, IMU at 200 Hz (each sample the mean rate over its interval), then a 1 s gap.
#include <cmath>
#include <stdexcept>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "slslam/tracking/inertial_bridge.h"

namespace slslam {
namespace {

const Eigen::Vector3d kGyroBias(0.01, -0.02, 0.015);  // [rad/s]

Eigen::Matrix3d Exp(const Eigen::Vector3d& w) {
  const double a = w.norm();
  return a < 1e-15 ? Eigen::Matrix3d::Identity()
                   : Eigen::AngleAxisd(a, w / a).toRotationMatrix();
}

Eigen::Vector3d Log(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

// World from body at t.
Eigen::Matrix3d Rotation(double t) {
  return Exp(Eigen::Vector3d(0.1 * std::sin(t), 0.2 * std::sin(0.7 * t), 0.4 * t));
}
Eigen::Vector3d Position(double t) {
  return {0.5 * t + 0.1 * std::sin(2.0 * t), 0.3 * std::sin(1.3 * t), 0.05 * std::sin(3.0 * t)};
}
Eigen::Vector3d Acceleration(double t) {
  return {-0.4 * std::sin(2.0 * t), -0.3 * 1.69 * std::sin(1.3 * t),
          -0.05 * 9.0 * std::sin(3.0 * t)};
}
// Gravity in the world frame: the map's world is the first camera's, not level.
Eigen::Vector3d Gravity() {
  return Exp(Eigen::Vector3d(0.3, -0.2, 0.1)) * Eigen::Vector3d(0.0, 0.0, -9.81);
}

Rigid3d BodyFromCam() {
  return Rigid3d(Exp(Eigen::Vector3d(-1.2, 0.05, -1.5)), Eigen::Vector3d(0.05, -0.02, 0.01));
}

Rigid3d CamFromWorld(double t) {
  return (Rigid3d(Rotation(t), Position(t)) * BodyFromCam()).Inverse();
}

// Samples on [t0, t1) at 200 Hz: the mean angular rate over each interval (so that holding it
// integrates to the true rotation) plus the bias, and the specific force at the interval's middle.
void AddSamples(InertialBridge* bridge, double t0, double t1) {
  const double dt = 1.0 / 200.0;
  for (double t = t0; t < t1 - 1e-9; t += dt) {
    const Eigen::Vector3d gyro = Log(Rotation(t).transpose() * Rotation(t + dt)) / dt + kGyroBias;
    const double tm = t + 0.5 * dt;
    const Eigen::Vector3d acc = Rotation(tm).transpose() * (Acceleration(tm) - Gravity());
    bridge->AddImu(t, gyro, acc);
  }
}

InertialBridgeOptions Options() {
  InertialBridgeOptions o;
  o.body_from_cam = BodyFromCam();
  return o;
}

TEST(InertialBridge, CarriesThePoseThroughAOneSecondGap) {
  InertialBridge bridge(Options());
  AddSamples(&bridge, 0.0, 4.5);
  for (int k = 0; k <= 60; ++k) bridge.AddPose(0.05 * k, CamFromWorld(0.05 * k));
  for (double t : {3.05, 3.5, 4.0}) {
    Rigid3d estimate;
    ASSERT_TRUE(bridge.Predict(t, &estimate)) << t;
    const Rigid3d truth = CamFromWorld(t);
    EXPECT_LT((estimate.Center() - truth.Center()).norm(), 0.02) << "t = " << t;
    EXPECT_LT(Log(estimate.rotation * truth.rotation.transpose()).norm(), 1e-3) << "t = " << t;
  }
  const InertialBridge::Fit& fit = bridge.fit();
  ASSERT_TRUE(fit.valid);
  EXPECT_LT((fit.gravity_world - Gravity()).norm(), 0.05);
  EXPECT_LT((fit.gyro_bias - kGyroBias).norm(), 1e-3);
}

TEST(InertialBridge, DeadReckoningIsWorseThanTheBridgeWithoutTheBiasFit) {
  // Without the bias the gyro turns the estimate away: the fit is what makes the bridge hold.
  InertialBridge bridge(Options());
  AddSamples(&bridge, 0.0, 4.5);
  for (int k = 0; k <= 60; ++k) bridge.AddPose(0.05 * k, CamFromWorld(0.05 * k));
  Rigid3d estimate;
  ASSERT_TRUE(bridge.Predict(4.0, &estimate));
  const double angle_error = Log(estimate.rotation * CamFromWorld(4.0).rotation.transpose()).norm();
  EXPECT_LT(angle_error, 0.1 * kGyroBias.norm());  // the bias alone turns 0.027 rad in 1 s
}

TEST(InertialBridge, RefusesWhatItCannotBridge) {
  InertialBridge bridge(Options());
  Rigid3d estimate;
  EXPECT_FALSE(bridge.Predict(1.0, &estimate));  // nothing yet
  AddSamples(&bridge, 0.0, 3.0);
  for (int k = 0; k <= 10; ++k) bridge.AddPose(0.05 * k, CamFromWorld(0.05 * k));
  EXPECT_FALSE(bridge.Predict(0.6, &estimate));  // 0.5 s of poses: under min_window_s
  for (int k = 11; k <= 40; ++k) bridge.AddPose(0.05 * k, CamFromWorld(0.05 * k));
  EXPECT_TRUE(bridge.Predict(2.5, &estimate));
  EXPECT_FALSE(bridge.Predict(3.5, &estimate));  // past the last sample
  EXPECT_FALSE(bridge.Predict(1.9, &estimate));  // before the last pose
  bridge.ResetPoses();
  EXPECT_FALSE(bridge.Predict(2.5, &estimate));

  // A hole in the samples.
  InertialBridge holed(Options());
  AddSamples(&holed, 0.0, 2.2);
  AddSamples(&holed, 2.5, 4.0);
  for (int k = 0; k <= 40; ++k) holed.AddPose(0.05 * k, CamFromWorld(0.05 * k));
  EXPECT_TRUE(holed.Predict(2.15, &estimate));
  EXPECT_FALSE(holed.Predict(2.6, &estimate));

  // Longer than max_gap_s.
  InertialBridgeOptions short_gap = Options();
  short_gap.max_gap_s = 0.5;
  InertialBridge brief(short_gap);
  AddSamples(&brief, 0.0, 4.0);
  for (int k = 0; k <= 40; ++k) brief.AddPose(0.05 * k, CamFromWorld(0.05 * k));
  EXPECT_TRUE(brief.Predict(2.4, &estimate));
  EXPECT_FALSE(brief.Predict(2.6, &estimate));
}

TEST(InertialBridge, RefusesAFitWhoseGravityIsImplausible) {
  // Specific force in units of g instead of m/s^2 (some drivers write that): the fitted gravity
  // is about 1, and nothing is bridged.
  InertialBridge bridge(Options());
  const double dt = 1.0 / 200.0;
  for (double t = 0.0; t < 4.0 - 1e-9; t += dt) {
    const Eigen::Vector3d gyro = Log(Rotation(t).transpose() * Rotation(t + dt)) / dt;
    const double tm = t + 0.5 * dt;
    const Eigen::Vector3d acc = Rotation(tm).transpose() * (Acceleration(tm) - Gravity());
    bridge.AddImu(t, gyro, acc / 9.81);
  }
  for (int k = 0; k <= 40; ++k) bridge.AddPose(0.05 * k, CamFromWorld(0.05 * k));
  Rigid3d estimate;
  EXPECT_FALSE(bridge.Predict(2.5, &estimate));
  EXPECT_FALSE(bridge.fit().valid);
}

TEST(InertialBridge, RejectsBadSamplesAndOptions) {
  InertialBridge bridge(Options());
  bridge.AddImu(1.0, Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, 9.81));
  EXPECT_THROW(bridge.AddImu(1.0, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()),
               std::invalid_argument);
  EXPECT_THROW(bridge.AddImu(2.0, Eigen::Vector3d(NAN, 0, 0), Eigen::Vector3d::Zero()),
               std::invalid_argument);
  InertialBridgeOptions bad = Options();
  bad.body_from_cam.rotation(0, 0) = 2.0;
  try {
    InertialBridge b(bad);
    ADD_FAILURE() << "a non-rigid extrinsic was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("tracking.imu.body_from_cam"), std::string::npos);
  }
}

}  // namespace
}  // namespace slslam
