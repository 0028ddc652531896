// Visual-inertial initialisation from metric poses and the IMU between them: gravity, biases and
// velocities recovered from a moving start, from a start at rest and from noisy poses; poses that
// disagree with the IMU are refused with the reason.
#include "slslam/inertial/inertial_initialization.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "synthetic_motion.h"

namespace slslam {
namespace {

using test::SyntheticMotion;

struct Input {
  std::vector<Rigid3d> poses;
  std::vector<ImuPreintegration> pre;
};

// Poses at 10 Hz over [0, duration] and the IMU between them at 1 kHz with `bias` in its
// readings (at 1 kHz the integration's own first-order error is well below what is checked).
Input MakeInput(const SyntheticMotion& motion, const ImuBias& bias, double duration,
                double position_noise_m = 0.0, double rotation_noise_rad = 0.0) {
  Input in;
  std::mt19937 rng(3);
  std::normal_distribution<double> unit(0.0, 1.0);
  const int n = static_cast<int>(std::lround(duration * 10.0)) + 1;
  for (int k = 0; k < n; ++k) {
    Rigid3d pose = motion.WorldFromBody(0.1 * k);
    pose.rotation = pose.rotation *
                    ExpSO3(rotation_noise_rad * Eigen::Vector3d(unit(rng), unit(rng), unit(rng)));
    pose.translation += position_noise_m * Eigen::Vector3d(unit(rng), unit(rng), unit(rng));
    in.poses.push_back(pose);
    if (k > 0) in.pre.push_back(motion.Preintegrate(0.1 * (k - 1), 0.1 * k, 1000.0, bias));
  }
  return in;
}

double AngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180.0 / M_PI;
}

ImuBias SomeBias() {
  ImuBias bias;
  bias.gyro = {0.004, -0.006, 0.003};
  bias.acc = {0.05, -0.05, 0.08};
  return bias;
}

TEST(InertialInitialisation, RecoversGravityBiasesAndVelocitiesFromMotion) {
  const SyntheticMotion motion;
  const ImuBias bias = SomeBias();
  const Input in = MakeInput(motion, bias, 3.0);
  const InertialInitResult r = InitialiseInertial(in.poses, in.pre);
  ASSERT_TRUE(r.success) << r.reason;
  EXPECT_LT(AngleDeg(r.g_world, motion.g_world), 0.1);
  EXPECT_NEAR(r.g_world.norm(), 9.81, 1e-9);
  EXPECT_LT((r.bias.gyro - bias.gyro).norm(), 2e-4);
  EXPECT_LT((r.bias.acc - bias.acc).norm(), 0.03);
  ASSERT_EQ(r.v_world.size(), in.poses.size());
  for (size_t k = 0; k < r.v_world.size(); ++k) {
    EXPECT_LT((r.v_world[k] - motion.Velocity(0.1 * k)).norm(), 0.02) << "pose " << k;
  }
}

TEST(InertialInitialisation, ANoisyStereoTrackStillGivesGravityAndVelocity) {
  // Poses with 3 mm and 1 mrad of noise, as tracked stereo frames have.
  const SyntheticMotion motion;
  const ImuBias bias = SomeBias();
  const Input in = MakeInput(motion, bias, 3.0, 0.003, 0.001);
  const InertialInitResult r = InitialiseInertial(in.poses, in.pre);
  ASSERT_TRUE(r.success) << r.reason;
  EXPECT_LT(AngleDeg(r.g_world, motion.g_world), 1.0);
  EXPECT_LT((r.bias.gyro - bias.gyro).norm(), 2e-3);
  EXPECT_LT((r.v_world.back() - motion.Velocity(3.0)).norm(), 0.1);
}

TEST(InertialInitialisation, AStartAtRestGivesGravityZeroVelocityAndTheGyroBias) {
  // At rest the accelerometer bias cannot be told from a tilt of gravity: the prior holds it near
  // zero, so gravity's direction is off by at most the bias over g (0.6 degrees here).
  SyntheticMotion motion;
  motion.amplitude = 0.0;
  const ImuBias bias = SomeBias();
  const Input in = MakeInput(motion, bias, 2.0);
  const InertialInitResult r = InitialiseInertial(in.poses, in.pre);
  ASSERT_TRUE(r.success) << r.reason;
  const double bound_deg = std::atan(bias.acc.norm() / 9.81) * 180.0 / M_PI;
  EXPECT_LT(AngleDeg(r.g_world, motion.g_world), bound_deg);
  EXPECT_LT((r.bias.gyro - bias.gyro).norm(), 2e-4);
  for (const Eigen::Vector3d& v : r.v_world) EXPECT_LT(v.norm(), 0.01);
}

TEST(InertialInitialisation, RefusesPosesThatDisagreeWithTheImu) {
  const SyntheticMotion motion;
  Input wrong_scale = MakeInput(motion, {}, 3.0);
  for (Rigid3d& pose : wrong_scale.poses) pose.translation *= 4.0;  // a monocular-like scale
  const InertialInitResult scaled = InitialiseInertial(wrong_scale.poses, wrong_scale.pre);
  EXPECT_FALSE(scaled.success);
  EXPECT_NE(scaled.reason.find("gravity"), std::string::npos) << scaled.reason;

  Input wrong_extrinsics = MakeInput(motion, {}, 3.0);
  const Eigen::Matrix3d flip = ExpSO3(Eigen::Vector3d(0.0, M_PI / 2, 0.0));
  for (Rigid3d& pose : wrong_extrinsics.poses) pose.rotation = pose.rotation * flip;
  const InertialInitResult rotated =
      InitialiseInertial(wrong_extrinsics.poses, wrong_extrinsics.pre);
  EXPECT_FALSE(rotated.success);
  EXPECT_FALSE(rotated.reason.empty());

  EXPECT_THROW(InitialiseInertial({Rigid3d()}, {}), std::invalid_argument);
  InertialInitOptions bad;
  bad.gravity_mps2 = -1.0;
  EXPECT_THROW(InitialiseInertial(wrong_scale.poses, wrong_scale.pre, bad), std::invalid_argument);
}

}  // namespace
}  // namespace slslam
