// Deskewing with a known motion: points seen by a sensor turning and driving during the sweep
// come back to where the sensor saw them from at the sweep start.
#include "slslam/lidar/deskew.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "slslam/geometry/rotation.h"

namespace slslam::lidar {
namespace {

// start_from_t: 1 rad/s yaw and 1.5 m/s forward, 0.2 m/s up.
Rigid3d Motion(double t) {
  return Rigid3d(ExpSO3(Eigen::Vector3d(0, 0, 1.0 * t)), Eigen::Vector3d(1.5, 0.0, 0.2) * t);
}

TEST(Deskew, KnownMotionIsUndone) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> uni(-20.0, 20.0);
  const double period = 0.1;
  SweepMotion motion;
  for (int k = 0; k <= 20; ++k) {
    motion.time_s.push_back(k * period / 20);
    motion.start_from_t.push_back(Motion(k * period / 20));
  }
  std::vector<Eigen::Vector3d> truth, seen;
  std::vector<double> times;
  for (int i = 0; i < 500; ++i) {
    const Eigen::Vector3d p(uni(rng), uni(rng), 0.1 * uni(rng));  // in the start frame
    const double t = period * i / 500.0;
    truth.push_back(p);
    times.push_back(t);
    seen.push_back(Motion(t).Inverse() * p);  // what the sensor reports at time t
  }
  const std::vector<Eigen::Vector3d> fixed = DeskewPoints(seen, times, motion);
  double worst = 0.0, skew = 0.0;
  for (size_t i = 0; i < truth.size(); ++i) {
    worst = std::max(worst, (fixed[i] - truth[i]).norm());
    skew = std::max(skew, (seen[i] - truth[i]).norm());
  }
  // Slerp of a constant-rate yaw and linear translation are exact between samples.
  EXPECT_LT(worst, 1e-9);
  EXPECT_GT(skew, 0.5);  // the distortion was real: up to 0.1 rad at 20 m

  // The constant-velocity model built from the sweep's end pose gives the same answer.
  const SweepMotion cv = SweepMotion::ConstantVelocity(Motion(period), period, 11);
  const std::vector<Eigen::Vector3d> fixed_cv = DeskewPoints(seen, times, cv);
  double worst_cv = 0.0;
  for (size_t i = 0; i < truth.size(); ++i)
    worst_cv = std::max(worst_cv, (fixed_cv[i] - truth[i]).norm());
  EXPECT_LT(worst_cv, 1e-9);  // this motion turns at a constant rate on a straight line
}

TEST(Deskew, MismatchedTimesThrow) {
  SweepMotion motion;
  EXPECT_THROW(DeskewPoints({Eigen::Vector3d::Zero()}, {}, motion), std::invalid_argument);
  motion.time_s = {0.1, 0.05};
  motion.start_from_t = {Rigid3d(), Rigid3d()};
  EXPECT_THROW(DeskewPoints({Eigen::Vector3d::Zero()}, {0.0}, motion), std::invalid_argument);
}

}  // namespace
}  // namespace slslam::lidar
