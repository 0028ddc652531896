#include "slslam/lidar/point_cloud_io.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>

#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "slslam/core/check.h"

namespace slslam::lidar {
namespace {

void RequireFile(const std::string& path) {
  SLSLAM_CHECK(std::filesystem::is_regular_file(path), path, ": no such file");
}

PointMatrix FromPcl(const pcl::PointCloud<pcl::PointXYZI>& cloud) {
  PointMatrix out(static_cast<Eigen::Index>(cloud.size()), 4);
  Eigen::Index n = 0;
  for (const auto& p : cloud.points) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    out.row(n++) << p.x, p.y, p.z, std::isfinite(p.intensity) ? p.intensity : 0.0f;
  }
  out.conservativeResize(n, 4);
  return out;
}

std::string LowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

}  // namespace

PointMatrix ReadKittiBin(const std::string& path) {
  RequireFile(path);
  const std::uintmax_t bytes = std::filesystem::file_size(path);
  SLSLAM_CHECK(bytes % (4 * sizeof(float)) == 0, path, ": size ", bytes,
               " bytes is not a multiple of 16 (float32 x y z i)");
  PointMatrix out(static_cast<Eigen::Index>(bytes / (4 * sizeof(float))), 4);
  std::ifstream in(path, std::ios::binary);
  in.read(reinterpret_cast<char*>(out.data()), static_cast<std::streamsize>(bytes));
  SLSLAM_CHECK(static_cast<bool>(in), path, ": read failed");
  return out;
}

PointMatrix ReadPcd(const std::string& path) {
  RequireFile(path);
  pcl::PointCloud<pcl::PointXYZI> cloud;
  SLSLAM_CHECK(pcl::io::loadPCDFile(path, cloud) == 0, path, ": not a readable PCD file");
  return FromPcl(cloud);
}

PointMatrix ReadPly(const std::string& path) {
  RequireFile(path);
  pcl::PointCloud<pcl::PointXYZI> cloud;
  SLSLAM_CHECK(pcl::io::loadPLYFile(path, cloud) == 0, path, ": not a readable PLY file");
  return FromPcl(cloud);
}

PointMatrix ReadPointCloud(const std::string& path) {
  const std::string ext = LowerExtension(path);
  if (ext == ".bin") return ReadKittiBin(path);
  if (ext == ".pcd") return ReadPcd(path);
  if (ext == ".ply") return ReadPly(path);
  throw std::invalid_argument(
      Message(path, ": unknown point cloud extension '", ext, "' (expected .bin, .pcd or .ply)"));
}

}  // namespace slslam::lidar
