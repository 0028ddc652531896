// The IMU in tracking: the estimator initialises from tracked poses, carries the pose through a
// stretch without vision within the uncertainty it reports, and declares itself untrustworthy
// when that uncertainty outgrows the distance driven; the tracker crosses 10 s without a single
// visual feature in one map.
#include "slslam/tracking/inertial_estimator.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "../inertial/synthetic_motion.h"

namespace slslam {
namespace {

using test::SyntheticMotion;

const Rigid3d kBodyFromCam(ExpSO3(Eigen::Vector3d(-1.2, 0.1, 0.3)),
                           Eigen::Vector3d(0.05, 0.0, -0.03));

// IMU samples at 1 kHz over [t0, t1] with white noise at EuRoC's densities and a constant bias
// (1 kHz: the synthetic motion accelerates to 6 m/s, and the first-order integration's own error
// at 200 Hz, which no noise model covers, would dominate the 10 s checked here), each given to
// `add(t_ns, gyro, acc)`.
template <typename Motion, typename Add>
void NoisyImu(const Motion& motion, double t0, double t1, const ImuBias& bias, unsigned seed,
              Add add) {
  const InertialOptions defaults;
  std::mt19937 rng(seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  const double dt = 0.001;
  for (int k = static_cast<int>(std::lround(t0 / dt)); k * dt <= t1 + 1e-9; ++k) {
    const double t = k * dt;
    Eigen::Vector3d wn, an;
    for (int i = 0; i < 3; ++i) {
      wn(i) = unit(rng) * defaults.gyro_noise_density / std::sqrt(dt);
      an(i) = unit(rng) * defaults.acc_noise_density / std::sqrt(dt);
    }
    add(NsFromSeconds(t), motion.Gyro(t) + bias.gyro + wn, motion.Accelerometer(t) + bias.acc + an);
  }
}

// ... over [0, duration] into the estimator.
template <typename Motion>
void FeedImu(const Motion& motion, double duration, const ImuBias& bias,
             InertialEstimator* estimator) {
  NoisyImu(motion, 0.0, duration, bias, 11,
           [&](int64_t t_ns, const Eigen::Vector3d& gyro, const Eigen::Vector3d& acc) {
             estimator->AddImu(t_ns, gyro, acc);
           });
}

template <typename Motion>
Rigid3d CameraPose(const Motion& motion, double t) {
  return CamFromWorld(motion.Nav(t), kBodyFromCam);
}

// Exact camera poses of frames 0..last_frame at 20 Hz, each with `information`.
template <typename Motion>
void TrackExactly(const Motion& motion, int last_frame, const Matrix6d& information,
                  InertialEstimator* estimator) {
  for (int k = 0; k <= last_frame; ++k) {
    estimator->AddVisualPose(NsFromSeconds(0.05 * k), CameraPose(motion, 0.05 * k), information,
                             /*with_prior=*/false);
  }
}

// Camera poses of frames 0..last_frame at 20 Hz, each off the truth by 1e-3 per component of its
// tangent (drawn from `unit` with `rng`), with `information`; fused with the prediction
// (with_prior false). Returns the first frame's time at which the estimator is initialised (-1:
// never).
template <typename Motion>
double TrackNoisily(const Motion& motion, int last_frame, const Matrix6d& information,
                    std::mt19937* rng, std::normal_distribution<double>* unit,
                    InertialEstimator* estimator) {
  double init_at = -1.0;
  for (int k = 0; k <= last_frame; ++k) {
    const double t = 0.05 * k;
    Vector6d noise;
    for (int i = 0; i < 6; ++i) noise(i) = 1e-3 * (*unit)(*rng);
    estimator->AddVisualPose(NsFromSeconds(t), LeftPlus(noise, CameraPose(motion, t)), information,
                             /*with_prior=*/false);
    if (init_at < 0.0 && estimator->initialised()) init_at = t;
  }
  return init_at;
}

// A ground vehicle: a circle of 10 m radius at 0.8 m/s, the body's x axis along the velocity,
// over a gentle bump (0.2 m high, 30 m long) it pitches with; body z up.
struct GroundMotion : test::TrajectoryReadings<GroundMotion> {
  double radius_m = 10.0;
  double speed_mps = 0.8;
  double bump_m = 0.1;  // half the bump's height
  Eigen::Vector3d g_world{0.0, 0.0, -9.81};

  double Yaw(double t) const { return speed_mps / radius_m * t; }
  double Z(double t) const { return bump_m * std::sin(2.0 * M_PI * speed_mps * t / 30.0); }
  double Zdot(double t) const {
    const double k = 2.0 * M_PI * speed_mps / 30.0;
    return bump_m * k * std::cos(k * t);
  }
  double Zddot(double t) const {
    const double k = 2.0 * M_PI * speed_mps / 30.0;
    return -bump_m * k * k * std::sin(k * t);
  }
  Eigen::Vector3d Position(double t) const {
    const double y = Yaw(t);
    return {radius_m * std::sin(y), radius_m * (1.0 - std::cos(y)), Z(t)};
  }
  Eigen::Vector3d Velocity(double t) const {
    const double y = Yaw(t);
    return {speed_mps * std::cos(y), speed_mps * std::sin(y), Zdot(t)};
  }
  Eigen::Vector3d Acceleration(double t) const {
    const double y = Yaw(t), w = speed_mps / radius_m;
    return {-speed_mps * w * std::sin(y), speed_mps * w * std::cos(y), Zddot(t)};
  }
  Eigen::Matrix3d Attitude(double t) const {  // x along the velocity, no roll
    const double pitch = -std::atan2(Zdot(t), speed_mps);
    return (Eigen::AngleAxisd(Yaw(t), Eigen::Vector3d::UnitZ()) *
            Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()))
        .toRotationMatrix();
  }
};

TEST(InertialEstimator, InitialisesThenCarriesTenSecondsWithinItsUncertainty) {
  // 10 s of tracked frames (the gyroscope bias is what decides the drift in the dark: an error of
  // b rad/s tilts gravity into g b t^3 / 6 of position), then 10 s without vision. The poses'
  // errors here are independent from frame to frame, so a loose gyroscope bias lets the frames
  // correct the initialisation's (a 1 s fit, 1.4e-3 rad/s off); the default holds it against a
  // map that turns (the next test).
  SyntheticMotion motion;
  motion.amplitude = 0.5;
  ImuBias bias;
  bias.gyro = {0.003, -0.002, 0.004};
  bias.acc = {0.04, -0.03, 0.05};
  InertialOptions options;
  options.body_from_cam = kBodyFromCam;
  options.gyro_bias_sigma_radps = 2e-3;
  InertialEstimator estimator(options);
  FeedImu(motion, 21.0, bias, &estimator);
  // Tracked frames at 20 Hz, each a pose with 1 mm / 1 mrad of information.
  Matrix6d information = Matrix6d::Identity();
  information.diagonal() << Eigen::Vector3d::Constant(1e6), Eigen::Vector3d::Constant(1e6);
  std::mt19937 rng(5);
  std::normal_distribution<double> unit(0.0, 1.0);
  // The camera's pose alone: the estimator fuses it with its prediction.
  const double init_at = TrackNoisily(motion, 200, information, &rng, &unit, &estimator);
  ASSERT_TRUE(estimator.initialised()) << estimator.report().last_failure;
  EXPECT_NEAR(init_at, options.min_window_s, 0.3);
  EXPECT_LT(estimator.g_world().normalized().dot(motion.g_world.normalized()), 1.0 + 1e-12);
  EXPECT_GT(estimator.g_world().normalized().dot(motion.g_world.normalized()),
            std::cos(1.0 * M_PI / 180.0));
  EXPECT_LT((estimator.state().nav.v_world_body - motion.Velocity(10.0)).norm(), 0.05);
  EXPECT_LT((estimator.state().bias.gyro - bias.gyro).norm(), 1e-3);
  // 10 s without vision: every frame propagated, still trustworthy, the error within 3 sigma.
  for (int k = 201; k <= 400; ++k) {
    const double t = 0.05 * k;
    ASSERT_TRUE(estimator.Propagate(NsFromSeconds(t))) << t;
    EXPECT_TRUE(estimator.Trustworthy()) << t << " s: sigma " << estimator.state().PositionSigma();
  }
  const double error = (estimator.state().nav.p_world_body - motion.Position(20.0)).norm();
  const double sigma = estimator.state().PositionSigma();
  EXPECT_LT(error, 3.0 * sigma) << "error " << error << " sigma " << sigma;
  EXPECT_GT(sigma, 0.01);
  EXPECT_LT(sigma, 1.0);
  EXPECT_NEAR(estimator.seconds_without_vision(), 10.0, 1e-9);
  // The motion goes every way (a drone's): never a ground vehicle's non-holonomic constraint.
  EXPECT_GT(estimator.report().travel_side_ratio, InertialOptions{}.nonholonomic_max_side_ratio);
  EXPECT_EQ(estimator.report().nonholonomic_updates, 0);
}

// A ground vehicle tracked for 10 s, then 15 s without vision, with an accelerometer bias the
// initialisation cannot separate from gravity's tilt in its window (0.05 m/s^2 each axis): the
// axis of travel learned while tracked holds the velocity across it, and the position after the
// blind stretch is much closer across the path than the IMU alone gets it, within the
// uncertainty reported.
TEST(InertialEstimator, AGroundVehicleHoldsItsVelocityToTheAxisOfTravelWithoutVision) {
  GroundMotion motion;
  ImuBias bias;
  bias.acc = {0.05, -0.05, 0.05};
  const auto run = [&](double max_side_ratio, InertialEstimator::Report* report) {
    InertialOptions options;
    options.body_from_cam = kBodyFromCam;
    options.nonholonomic_max_side_ratio = max_side_ratio;
    InertialEstimator estimator(options);
    FeedImu(motion, 25.5, bias, &estimator);
    std::mt19937 rng(5);
    std::normal_distribution<double> unit(0.0, 1.0);
    TrackNoisily(motion, 200, 1e6 * Matrix6d::Identity(), &rng, &unit, &estimator);
    EXPECT_TRUE(estimator.initialised()) << estimator.report().last_failure;
    for (int k = 201; k <= 500; ++k) EXPECT_TRUE(estimator.Propagate(NsFromSeconds(0.05 * k)));
    const Eigen::Vector3d e = estimator.state().nav.p_world_body - motion.Position(25.0);
    const double sigma = estimator.state().PositionSigma();
    EXPECT_LT(e.norm(), 3.0 * sigma) << "error " << e.norm() << " sigma " << sigma;
    *report = estimator.report();
    // Across the path (sideways and up): what the constraint holds; along it the speed is free.
    const Eigen::Vector3d along = motion.Velocity(25.0).normalized();
    return (e - e.dot(along) * along).norm();
  };
  InertialEstimator::Report held_report, free_report;
  const double held = run(InertialOptions{}.nonholonomic_max_side_ratio, &held_report);
  const double free = run(0.0, &free_report);
  EXPECT_GE(held_report.travel_side_ratio, 0.0);
  EXPECT_LT(held_report.travel_side_ratio, 0.05);
  EXPECT_EQ(held_report.nonholonomic_updates, 300);
  EXPECT_EQ(free_report.nonholonomic_updates, 0);
  // (measured: 0.13 m across against 0.93 m; along the path 0.52 m against 1.35 m)
  EXPECT_LT(held, 0.3 * free) << "held " << held << " m across, IMU alone " << free << " m";
}

// A state carried without vision stays a plausible one to resume a map from while its speed does
// (at most twice the last visual fix's); an accelerometer bias that turns 1 m/s^2 off after the
// tracked part runs the velocity away, and it is not.
TEST(InertialEstimator, AStateWhoseVelocityRanAwayIsNoPlaceToResumeAMap) {
  GroundMotion motion;
  ImuBias bias;
  bias.acc = {0.05, -0.05, 0.05};
  for (const double extra : {0.0, 1.0}) {
    InertialOptions options;
    options.body_from_cam = kBodyFromCam;
    InertialEstimator estimator(options);
    ImuBias later = bias;
    later.acc += extra * Eigen::Vector3d::Ones().normalized();  // (along travel: 0.58 m/s^2)
    const auto add = [&](int64_t t_ns, const Eigen::Vector3d& gyro, const Eigen::Vector3d& acc) {
      estimator.AddImu(t_ns, gyro, acc);
    };
    NoisyImu(motion, 0.0, 10.0, bias, 11, add);
    NoisyImu(motion, 10.001, 25.5, later, 12, add);
    std::mt19937 rng(5);
    std::normal_distribution<double> unit(0.0, 1.0);
    TrackNoisily(motion, 200, 1e6 * Matrix6d::Identity(), &rng, &unit, &estimator);
    ASSERT_TRUE(estimator.initialised()) << estimator.report().last_failure;
    EXPECT_TRUE(estimator.SpeedPlausible());
    for (int k = 201; k <= 500; ++k) ASSERT_TRUE(estimator.Propagate(NsFromSeconds(0.05 * k)));
    const double speed = estimator.state().nav.v_world_body.norm();
    EXPECT_EQ(estimator.SpeedPlausible(), extra == 0.0)
        << "speed " << speed << " m/s, truth " << motion.Velocity(25.0).norm();
  }
}

// The same glide of 15 s without vision, given the camera's motion between consecutive frames
// (from the truth, 1 mm noise per axis, every 20th frame an outlier 0.5 m ahead): the velocity it
// measures holds the position along the path that the axis of travel leaves to the IMU, and the
// outliers are refused.
TEST(InertialEstimator, TheCameraMotionOfFramesWithoutAPoseHoldsThePositionAlongThePath) {
  GroundMotion motion;
  ImuBias bias;
  bias.acc = {0.05, -0.05, 0.05};
  const auto run = [&](bool flow, InertialEstimator::Report* report) {
    InertialOptions options;
    options.body_from_cam = kBodyFromCam;
    options.flow_min_inliers = flow ? 30 : 0;
    InertialEstimator estimator(options);
    FeedImu(motion, 25.5, bias, &estimator);
    std::mt19937 rng(5);
    std::normal_distribution<double> unit(0.0, 1.0);
    TrackNoisily(motion, 200, 1e6 * Matrix6d::Identity(), &rng, &unit, &estimator);
    EXPECT_TRUE(estimator.initialised()) << estimator.report().last_failure;
    Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
    covariance.diagonal() << 1e-8, 1e-8, 1e-8, 1e-6, 1e-6, 1e-6;  // 0.1 mrad, 1 mm
    for (int k = 201; k <= 500; ++k) {
      const int64_t t_ns = NsFromSeconds(0.05 * k);
      EXPECT_TRUE(estimator.Propagate(t_ns));
      Rigid3d cur_from_prev =
          CameraPose(motion, 0.05 * k) * CameraPose(motion, 0.05 * (k - 1)).Inverse();
      for (int i = 0; i < 3; ++i) cur_from_prev.translation(i) += 1e-3 * unit(rng);
      if (k % 20 == 0) cur_from_prev.translation.z() += 0.5;  // (the camera looks ahead)
      const bool taken =
          estimator.AddCameraMotion(NsFromSeconds(0.05 * (k - 1)), t_ns, cur_from_prev, covariance);
      EXPECT_EQ(taken, flow && k % 20 != 0) << "frame " << k;
    }
    *report = estimator.report();
    const Eigen::Vector3d e = estimator.state().nav.p_world_body - motion.Position(25.0);
    const Eigen::Vector3d along = motion.Velocity(25.0).normalized();
    return std::abs(e.dot(along));
  };
  InertialEstimator::Report flow_report, imu_report;
  const double with_flow = run(true, &flow_report);
  const double imu_only = run(false, &imu_report);
  EXPECT_EQ(flow_report.flow_updates, 300 - 15);
  EXPECT_EQ(imu_report.flow_updates, 0);
  // A velocity within 0.05 m/s (flow_sigma_mps) a frame, 300 frames: its random walk's position
  // sigma 0.05 * 0.05 * sqrt(300) = 0.043 m, the IMU's own the accelerometer bias left
  EXPECT_LT(with_flow, 0.1) << "IMU alone " << imu_only << " m along the path";
  EXPECT_LT(with_flow, 0.5 * imu_only) << "with the flow " << with_flow << " m";
}

// Initialised on exact poses (no bias), then 8 s of poses from a map that turns slowly against the
// truth (2e-3 rad/s, what tracking through weak texture does): with the default
// gyro_bias_sigma_radps the bias estimate stays near the truth, so the state's rotation is the
// gyroscope's; with a loose one (2e-3 rad/s) the state takes most of the turn for a bias.
TEST(InertialEstimator, AHeldGyroBiasDoesNotTurnWithASlowlyTurningMap) {
  SyntheticMotion motion;
  motion.amplitude = 0.5;
  const Eigen::Vector3d turn_radps = Eigen::Vector3d(0.2, -0.5, 1.0).normalized() * 2e-3;
  const auto bias_error = [&](double sigma_radps) {
    InertialOptions options;
    options.body_from_cam = kBodyFromCam;
    options.gyro_bias_sigma_radps = sigma_radps;
    InertialEstimator estimator(options);
    FeedImu(motion, 10.5, {}, &estimator);
    // Tracking through weak texture: 3 mrad and 3 mm per frame.
    const Matrix6d information = 1e5 * Matrix6d::Identity();
    for (int k = 0; k <= 200; ++k) {
      const double t = 0.05 * k;
      const double turning_s = std::max(0.0, t - 2.0);
      // cam_from_world of a world turned by the map's drift: the camera's rotation off by it.
      Rigid3d pose = CameraPose(motion, t);
      pose = pose * Rigid3d(ExpSO3(turn_radps * turning_s), Eigen::Vector3d::Zero());
      estimator.AddVisualPose(NsFromSeconds(t), pose, information, /*with_prior=*/false);
    }
    EXPECT_TRUE(estimator.initialised()) << estimator.report().last_failure;
    return estimator.state().bias.gyro.norm();
  };
  const double held = bias_error(InertialOptions{}.gyro_bias_sigma_radps);
  const double loose = bias_error(2e-3);
  EXPECT_LT(held, 6e-4) << "loose " << loose;
  EXPECT_GT(loose, 1.5e-3) << "held " << held;
}

TEST(InertialEstimator, AtRestItInitialisesAndAnUncertaintyPastTheFloorIsLost) {
  SyntheticMotion motion;
  motion.amplitude = 0.0;
  InertialOptions options;
  options.body_from_cam = kBodyFromCam;
  options.lost_sigma_min_m = 0.05;
  options.zero_velocity_max_statistic = 0.0;  // (the next test: held at rest)
  InertialEstimator estimator(options);
  FeedImu(motion, 40.0, {}, &estimator);
  const Matrix6d information = 1e6 * Matrix6d::Identity();
  TrackExactly(motion, 40, information, &estimator);
  ASSERT_TRUE(estimator.initialised()) << estimator.report().last_failure;
  EXPECT_LT(estimator.state().nav.v_world_body.norm(), 0.02);
  // Standing still without vision: nothing is driven, so the floor decides.
  double lost_after = -1.0;
  for (int k = 41; k <= 800 && lost_after < 0.0; ++k) {
    ASSERT_TRUE(estimator.Propagate(NsFromSeconds(0.05 * k)));
    if (!estimator.Trustworthy()) lost_after = estimator.seconds_without_vision();
  }
  EXPECT_GT(lost_after, 0.5);
  EXPECT_LT(lost_after, 38.0);
  estimator.Reset();
  EXPECT_FALSE(estimator.initialised());
}

// Without vision at rest the IMU's samples show it (the rest statistic about 1): every frame is
// held at zero velocity and the position stays put for 30 s. Gliding at constant speed on a
// straight line without vibration looks the same to the IMU, but the state's velocity disagrees:
// no frame is held at zero.
TEST(InertialEstimator, AtRestWithoutVisionTheVelocityIsHeldAtZeroButNotWhileGliding) {
  const Matrix6d information = 1e6 * Matrix6d::Identity();
  {
    SyntheticMotion motion;
    motion.amplitude = 0.0;
    InertialOptions options;
    options.body_from_cam = kBodyFromCam;
    options.lost_sigma_min_m = 0.05;
    InertialEstimator estimator(options);
    FeedImu(motion, 32.5, {}, &estimator);
    TrackExactly(motion, 40, information, &estimator);
    ASSERT_TRUE(estimator.initialised()) << estimator.report().last_failure;
    for (int k = 41; k <= 640; ++k) {
      ASSERT_TRUE(estimator.Propagate(NsFromSeconds(0.05 * k)));
      ASSERT_TRUE(estimator.Trustworthy()) << 0.05 * k << " s";
    }
    EXPECT_EQ(estimator.report().zero_velocity_updates, 600);
    EXPECT_LT((estimator.state().nav.p_world_body - motion.Position(32.0)).norm(), 0.02);
    EXPECT_LT(estimator.state().nav.v_world_body.norm(), 0.01);
  }
  GroundMotion glide;
  glide.radius_m = 1e7;  // straight, 0.8 m/s
  glide.bump_m = 0.0;
  InertialOptions options;
  options.body_from_cam = kBodyFromCam;
  InertialEstimator estimator(options);
  FeedImu(glide, 8.5, {}, &estimator);
  TrackExactly(glide, 100, information, &estimator);
  ASSERT_TRUE(estimator.initialised()) << estimator.report().last_failure;
  // The samples alone look at rest (the gyroscope still, the specific force gravity's) ...
  ImuBuffer samples;
  NoisyImu(glide, 7.5, 8.0, {}, 2,
           [&](int64_t t_ns, const Eigen::Vector3d& gyro, const Eigen::Vector3d& acc) {
             samples.Add(t_ns, gyro, acc);
           });
  const std::optional<double> rest =
      samples.RestStatistic(NsFromSeconds(7.5), NsFromSeconds(8.0), {}, 9.81,
                            options.gyro_noise_density, options.acc_noise_density);
  ASSERT_TRUE(rest.has_value());
  EXPECT_LT(*rest, options.zero_velocity_max_statistic);
  // ... but the state's velocity disagrees.
  for (int k = 101; k <= 160; ++k) ASSERT_TRUE(estimator.Propagate(NsFromSeconds(0.05 * k)));
  EXPECT_EQ(estimator.report().zero_velocity_updates, 0);
  EXPECT_LT((estimator.state().nav.p_world_body - glide.Position(8.0)).norm(), 0.1);
}

TEST(InertialEstimator, APoseFromParallelLinesDoesNotMoveTheStateAlongThem) {
  // Initialised, then 3 s without vision; then a pose that differs from the truth by 0.5 m
  // along a world direction, with full information, given as unobserving that direction: the
  // state must not move along it (the images' Gaussian is marginalised over it), while the same
  // pose given as observing everything pulls the state most of the way.
  SyntheticMotion motion;
  motion.amplitude = 0.5;
  InertialOptions options;
  options.body_from_cam = kBodyFromCam;
  const Eigen::Vector3d along = Eigen::Vector3d(0.3, -0.2, 1.0).normalized();
  const Matrix6d information = 1e6 * Matrix6d::Identity();
  Eigen::Vector3d moved[2];
  for (int marginalised = 0; marginalised < 2; ++marginalised) {
    InertialEstimator estimator(options);
    FeedImu(motion, 6.0, {}, &estimator);
    TrackExactly(motion, 40, information, &estimator);
    ASSERT_TRUE(estimator.initialised()) << estimator.report().last_failure;
    for (int k = 41; k < 100; ++k) ASSERT_TRUE(estimator.Propagate(NsFromSeconds(0.05 * k)));
    const double t = 5.0;
    InertialState predicted;
    ASSERT_TRUE(estimator.Predict(NsFromSeconds(t), &predicted));
    // The true camera moved 0.5 m along the direction (world_from_cam translated).
    const Rigid3d truth = CameraPose(motion, t);
    Rigid3d shifted = truth;
    shifted.translation -= truth.rotation * (0.5 * along);
    estimator.AddVisualPose(NsFromSeconds(t), shifted, information, /*with_prior=*/false,
                            marginalised ? along : Eigen::Vector3d::Zero());
    moved[marginalised] = estimator.state().nav.p_world_body - predicted.nav.p_world_body;
  }
  EXPECT_GT(moved[0].dot(along), 0.25) << moved[0].transpose();
  EXPECT_LT(std::abs(moved[1].dot(along)), 0.01) << moved[1].transpose();
}

TEST(InertialEstimator, FollowsAWorldChangeAndRefusesBadOptions) {
  SyntheticMotion motion;
  InertialOptions options;
  options.body_from_cam = kBodyFromCam;
  InertialEstimator estimator(options);
  FeedImu(motion, 4.0, {}, &estimator);
  TrackExactly(motion, 40, 1e6 * Matrix6d::Identity(), &estimator);
  ASSERT_TRUE(estimator.initialised());
  const Rigid3d new_from_old(ExpSO3(Eigen::Vector3d(0.0, 0.0, 0.5)), Eigen::Vector3d(1, 2, 3));
  const Eigen::Vector3d p = estimator.state().nav.p_world_body;
  const Eigen::Vector3d g = estimator.g_world();
  estimator.ChangeWorld(new_from_old);
  EXPECT_LT((estimator.state().nav.p_world_body - new_from_old * p).norm(), 1e-12);
  EXPECT_LT((estimator.g_world() - new_from_old.rotation * g).norm(), 1e-12);
  // The camera pose in the new world is the old one composed with the change.
  const Rigid3d expected = CameraPose(motion, 2.0) * new_from_old.Inverse();
  EXPECT_LT((estimator.cam_from_world().translation - expected.translation).norm(), 1e-2);

  InertialOptions bad = options;
  bad.min_window_s = 10.0;  // above window_s
  EXPECT_THROW(InertialEstimator{bad}, std::invalid_argument);
  bad = options;
  bad.acc_noise_density = -1.0;
  EXPECT_THROW(InertialEstimator{bad}, std::invalid_argument);
  bad = options;
  bad.body_from_cam.rotation *= 2.0;
  EXPECT_THROW(InertialEstimator{bad}, std::invalid_argument);
}

}  // namespace
}  // namespace slslam
