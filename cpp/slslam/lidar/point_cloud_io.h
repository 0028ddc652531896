// Point cloud files: KITTI Velodyne .bin, PCD and PLY (read through pcl::io), into PointMatrix.
#pragma once

#include <string>

#include "slslam/lidar/registration.h"

namespace slslam::lidar {

// KITTI Velodyne scan: little-endian float32 records (x, y, z, intensity). Returns N x 4. Throws
// std::invalid_argument on a missing file or a size that is not a multiple of 16 bytes.
PointMatrix ReadKittiBin(const std::string& path);

// PCD / PLY with x, y, z and, when present, an "intensity" field (0 otherwise). Returns N x 4.
// Points with a non-finite coordinate (organised clouds mark empty pixels with NaN) are dropped.
// Throws std::invalid_argument on a missing or unreadable file.
PointMatrix ReadPcd(const std::string& path);
PointMatrix ReadPly(const std::string& path);

// Picks the reader from the extension (.bin, .pcd, .ply; case-insensitive).
PointMatrix ReadPointCloud(const std::string& path);

}  // namespace slslam::lidar
