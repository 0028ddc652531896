#include "slslam/lidar/point_cloud_io.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <pcl/PCLPointCloud2.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>

#include "slslam/core/check.h"

namespace slslam::lidar {
namespace {

void RequireFile(const std::string& path) {
  SLSLAM_CHECK(std::filesystem::is_regular_file(path), path, ": no such file");
}

// One value of a field of any PCL numeric type, as double.
double ReadScalar(const std::uint8_t* at, std::uint8_t datatype) {
  auto get = [at](auto value) {
    std::memcpy(&value, at, sizeof(value));
    return static_cast<double>(value);
  };
  switch (datatype) {
    case pcl::PCLPointField::INT8:
      return get(std::int8_t{});
    case pcl::PCLPointField::UINT8:
      return get(std::uint8_t{});
    case pcl::PCLPointField::INT16:
      return get(std::int16_t{});
    case pcl::PCLPointField::UINT16:
      return get(std::uint16_t{});
    case pcl::PCLPointField::INT32:
      return get(std::int32_t{});
    case pcl::PCLPointField::UINT32:
      return get(std::uint32_t{});
    case pcl::PCLPointField::FLOAT64:
      return get(double{});
    default:
      return get(float{});  // FLOAT32 (other types are refused by FindField)
  }
}

const pcl::PCLPointField* FindField(const pcl::PCLPointCloud2& blob, const std::string& name,
                                    const std::string& path, bool required) {
  for (const auto& field : blob.fields) {
    if (field.name != name) continue;
    SLSLAM_CHECK(field.count >= 1 && field.datatype >= pcl::PCLPointField::INT8 &&
                     field.datatype <= pcl::PCLPointField::FLOAT64 &&
                     field.offset + pcl::getFieldSize(field.datatype) <= blob.point_step,
                 path, ": field '", name, "' has an unsupported type or layout");
    return &field;
  }
  SLSLAM_CHECK(!required, path, ": no '", name, "' field (a point cloud needs x, y and z)");
  return nullptr;
}

// x, y, z (required, any numeric type) and intensity (0 when absent) of every point. A point
// with a NaN coordinate in an organised cloud (height > 1) is an empty pixel and is dropped; any
// other non-finite coordinate is an error naming the point.
PointMatrix FromBlob(const pcl::PCLPointCloud2& blob, const std::string& path) {
  const pcl::PCLPointField* xyz[3] = {FindField(blob, "x", path, true),
                                      FindField(blob, "y", path, true),
                                      FindField(blob, "z", path, true)};
  const pcl::PCLPointField* intensity = FindField(blob, "intensity", path, false);
  const std::size_t rows = static_cast<std::size_t>(blob.width) * blob.height;
  SLSLAM_CHECK(blob.data.size() >= rows * blob.point_step, path, ": ", rows, " points of ",
               blob.point_step, " bytes announced, ", blob.data.size(), " bytes of data");
  const bool organised = blob.height > 1;
  PointMatrix out(static_cast<Eigen::Index>(rows), 4);
  Eigen::Index n = 0;
  for (std::size_t i = 0; i < rows; ++i) {
    const std::uint8_t* point = blob.data.data() + i * blob.point_step;
    double v[3];
    for (int a = 0; a < 3; ++a) v[a] = ReadScalar(point + xyz[a]->offset, xyz[a]->datatype);
    if (!(std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]))) {
      const bool empty_pixel = organised && std::isnan(v[0] + v[1] + v[2]) && !std::isinf(v[0]) &&
                               !std::isinf(v[1]) && !std::isinf(v[2]);
      if (empty_pixel) continue;
      ThrowInvalidArgument(Message(path, ": point ", i, " has a non-finite coordinate (", v[0],
                                   ", ", v[1], ", ", v[2], ")"));
    }
    double w = intensity ? ReadScalar(point + intensity->offset, intensity->datatype) : 0.0;
    out.row(n++) << static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2]),
        std::isfinite(w) ? static_cast<float>(w) : 0.0f;
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
  for (Eigen::Index i = 0; i < out.rows(); ++i) {
    SLSLAM_CHECK(out.row(i).allFinite(), path, ": point ", i, " has a non-finite value (",
                 out(i, 0), ", ", out(i, 1), ", ", out(i, 2), ", ", out(i, 3), ")");
  }
  return out;
}

PointMatrix ReadPcd(const std::string& path) {
  RequireFile(path);
  pcl::PCLPointCloud2 blob;
  SLSLAM_CHECK(pcl::io::loadPCDFile(path, blob) == 0, path, ": not a readable PCD file");
  return FromBlob(blob, path);
}

PointMatrix ReadPly(const std::string& path) {
  RequireFile(path);
  pcl::PCLPointCloud2 blob;
  SLSLAM_CHECK(pcl::io::loadPLYFile(path, blob) == 0, path, ": not a readable PLY file");
  return FromBlob(blob, path);
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
