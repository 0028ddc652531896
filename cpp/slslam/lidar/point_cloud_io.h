// Point cloud files: KITTI Velodyne .bin, PCD and PLY (read through pcl::io), into PointMatrix.
#pragma once

#include <string>

#include "slslam/lidar/registration.h"

namespace slslam::lidar {

// KITTI Velodyne scan: little-endian float32 records (x, y, z, intensity). Returns N x 4. Throws
// std::invalid_argument on a missing file, a size that is not a multiple of 16 bytes or a
// non-finite value (naming the point).
PointMatrix ReadKittiBin(const std::string& path);

// PCD / PLY with x, y, z (any numeric type) and, when present, an "intensity" field (0
// otherwise). Returns N x 4. Points with a NaN coordinate in an organised cloud (height > 1: NaN
// marks an empty pixel) are dropped. Throws std::invalid_argument naming the file on a missing or
// unreadable file, a missing x, y or z field, or any other non-finite point (with its index).
PointMatrix ReadPcd(const std::string& path);
PointMatrix ReadPly(const std::string& path);

// Picks the reader from the extension (.bin, .pcd, .ply; case-insensitive).
PointMatrix ReadPointCloud(const std::string& path);

}  // namespace slslam::lidar
