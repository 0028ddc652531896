#include "slslam/lidar/point_cloud_io.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>
#include <Eigen/LU>

#include "slslam/lidar/evaluation.h"

namespace slslam::lidar {
namespace {

const std::string kData = std::string(SLSLAM_SHARED_DATA_DIR) + "/lidar";

std::string TempPath(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("slslam_lidar_" + name)).string();
}

TEST(LidarIoTest, MissingFileThrowsWithThePath) {
  for (const char* path : {"/nonexistent/a.bin", "/nonexistent/a.pcd", "/nonexistent/a.ply"}) {
    try {
      ReadPointCloud(path);
      FAIL() << "no exception for " << path;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("no such file"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(ReadPointCloud("cloud.xyz"), std::invalid_argument);
  EXPECT_THROW(ReadRigid3d("/nonexistent/T.txt"), std::invalid_argument);
}

TEST(LidarIoTest, KittiBinRoundTripAndBadSize) {
  const std::string path = TempPath("roundtrip.bin");
  const float values[8] = {1, 2, 3, 0.5f, -4, 5, -6, 0.25f};
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(values), 32);
  const PointMatrix points = ReadKittiBin(path);
  ASSERT_EQ(points.rows(), 2);
  ASSERT_EQ(points.cols(), 4);
  EXPECT_EQ(points(1, 2), -6.0f);
  EXPECT_EQ(points(0, 3), 0.5f);

  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(values), 30);
  EXPECT_THROW(ReadKittiBin(path), std::invalid_argument);
  std::filesystem::remove(path);
}

TEST(LidarIoTest, CheckPointsRejectsBadShapesAndNaN) {
  PointMatrix good = PointMatrix::Random(50, 3);
  EXPECT_NO_THROW(CheckPoints(good, "source"));
  EXPECT_THROW(CheckPoints(PointMatrix::Random(50, 2), "source"), std::invalid_argument);
  EXPECT_THROW(CheckPoints(PointMatrix::Random(50, 5), "source"), std::invalid_argument);
  EXPECT_THROW(CheckPoints(PointMatrix::Random(5, 3), "source"), std::invalid_argument);
  good(7, 1) = std::numeric_limits<float>::quiet_NaN();
  try {
    CheckPoints(good, "target");
    FAIL() << "NaN accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("target"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("NaN"), std::string::npos);
  }
}

TEST(LidarIoTest, ReadsTheSharedKittiPcdAndPlyFiles) {
  if (!std::filesystem::exists(kData + "/gicp_pairs/small_gicp_source.ply")) {
    GTEST_SKIP() << "shared LiDAR data not found under " << kData;
  }
  const PointMatrix ply = ReadPly(kData + "/gicp_pairs/small_gicp_source.ply");
  EXPECT_EQ(ply.rows(), 69792);
  const PointMatrix pcd = ReadPcd(kData + "/gicp_pairs/fast_gicp_251370668.pcd");
  EXPECT_EQ(pcd.rows(), 69088);
  EXPECT_TRUE(pcd.allFinite());
  const PointMatrix bin = ReadPointCloud(kData + "/kitti00_scancontext/000094.bin");
  EXPECT_EQ(bin.rows(), 1945888 / 16);
  // The 14-column pose file and Tr give the README's velodyne poses.
  const auto poses = ReadKittiPoses(kData + "/kitti00_scancontext/poses_cam0_kitti_format.txt");
  const auto velo = ReadKittiPoses(kData + "/kitti00_scancontext/poses_velo_in_velo0frame.txt");
  const Rigid3d tr =
      ReadKittiCalibTr(kData + "/kitti00_scancontext/calib_Tr_velo_to_cam0_seq00.txt");
  const Rigid3d from_cam = KittiRelativeVelo(poses.at(94), poses.at(95), tr);
  const Rigid3d from_velo = velo.at(94).Inverse() * velo.at(95);
  EXPECT_LT((from_cam.ToMatrix4() - from_velo.ToMatrix4()).cwiseAbs().maxCoeff(), 1e-5);
  EXPECT_NEAR(from_cam.translation.x(), 0.474, 0.01);  // README: 94->95 moves ~0.47 m forward
}

}  // namespace
}  // namespace slslam::lidar
