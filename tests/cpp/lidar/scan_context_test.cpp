// Scan Context: a rotated copy of a scan is found with the right yaw; an unrelated scan is not.
#include "slslam/lidar/scan_context.h"

#include <cmath>
#include <random>

#include <Eigen/Geometry>

#include <gtest/gtest.h>

namespace slslam::lidar {
namespace {

// A place: walls of a room with boxes, seen from the origin; `seed` changes the layout.
std::vector<Eigen::Vector3d> Place(int seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  std::vector<Eigen::Vector3d> pts;
  const double half_x = 6 + 10 * uni(rng), half_y = 3 + 6 * uni(rng);
  // Each wall is built of 8 panels of random height, so places differ in their height profile.
  double panel_top[4][8];
  for (auto& wall : panel_top) {
    for (double& top : wall) top = 3.0 * uni(rng) - 1.0;
  }
  for (int i = 0; i < 4000; ++i) {
    const double a = uni(rng);
    const double h = -1.5 + (panel_top[i % 4][static_cast<int>(a * 8)] + 1.5) * uni(rng);
    switch (i % 4) {
      case 0:
        pts.emplace_back(-half_x + 2 * half_x * a, half_y, h);
        break;
      case 1:
        pts.emplace_back(-half_x + 2 * half_x * a, -half_y, h);
        break;
      case 2:
        pts.emplace_back(half_x, -half_y + 2 * half_y * a, h);
        break;
      default:
        pts.emplace_back(-half_x, -half_y + 2 * half_y * a, h);
        break;
    }
  }
  for (int b = 0; b < 6; ++b) {  // boxes of random height
    const Eigen::Vector3d c(half_x * (2 * uni(rng) - 1), half_y * (2 * uni(rng) - 1), 0);
    const double top = 2.0 * uni(rng) - 1.0;
    for (int i = 0; i < 200; ++i) {
      pts.emplace_back(c.x() + uni(rng), c.y() + uni(rng), -1.5 + (top + 1.5) * uni(rng));
    }
  }
  return pts;
}

std::vector<Eigen::Vector3d> Rotated(const std::vector<Eigen::Vector3d>& pts, double yaw) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  std::vector<Eigen::Vector3d> out;
  for (const auto& p : pts) out.push_back(R.transpose() * p);  // the sensor turned by +yaw
  return out;
}

TEST(ScanContext, RotatedCopyIsFoundWithItsYaw) {
  ScanContextOptions options;
  options.exclude_recent = 0;
  ScanContextDatabase db(options);
  for (int seed = 0; seed < 20; ++seed) db.Add(Place(seed));
  const double yaw = 2 * M_PI * 17 / options.sectors;  // 102 deg: a whole number of sectors
  const int query = db.Add(Rotated(Place(7), yaw));
  const ScanContextMatch match = db.Query(query);
  EXPECT_EQ(match.index, 7);
  EXPECT_EQ(match.shift, 17);
  EXPECT_NEAR(match.yaw_rad, yaw, 1e-9);
  EXPECT_LT(match.distance, 0.05);
}

TEST(ScanContext, YawBetweenSectorsIsWithinASector) {
  const ScanContextOptions options;
  const std::vector<Eigen::Vector3d> place = Place(3);
  const double yaw = -0.9;  // not a whole number of sectors
  const ScanContextMatch m = CompareScanContexts(MakeScanContext(Rotated(place, yaw), options),
                                                 MakeScanContext(place, options));
  EXPECT_LT(std::abs(m.yaw_rad - yaw), 2 * M_PI / options.sectors);
}

TEST(ScanContext, UnrelatedPlaceIsRejected) {
  // Rectangular rooms of random size and panel heights all look somewhat alike to Scan Context
  // (the best unrelated distance measured 0.09, the rotated copy's 0.00x): the unrelated place
  // must be clearly farther than the copy, and a threshold between them rejects it.
  ScanContextOptions options;
  options.exclude_recent = 0;
  ScanContextDatabase db(options);
  for (int seed = 0; seed < 20; ++seed) db.Add(Place(seed));
  const double copy = db.Query(db.Add(Rotated(Place(7), 2 * M_PI * 17 / options.sectors))).distance;
  const int query = db.Add(Place(1000));
  const ScanContextMatch unrelated = db.Query(query);
  EXPECT_GT(unrelated.distance, 4.0 * copy);
  options.max_distance = 0.5 * (copy + unrelated.distance);
  ScanContextDatabase strict(options);
  for (int seed = 0; seed < 20; ++seed) strict.Add(Place(seed));
  EXPECT_EQ(strict.Query(strict.Add(Place(1000))).index, -1);
  EXPECT_EQ(strict.Query(strict.Add(Rotated(Place(7), 2 * M_PI * 17 / options.sectors))).index, 7);
  // The newest keyframes are never candidates.
  options.exclude_recent = 50;
  ScanContextDatabase recent(options);
  recent.Add(Place(7));
  EXPECT_EQ(recent.Query(recent.Add(Place(7))).index, -1);
}

}  // namespace
}  // namespace slslam::lidar
