#include "slslam/lidar/evaluation.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include <Eigen/Geometry>

#include "slslam/core/check.h"

namespace slslam::lidar {
namespace {

// Every number of every non-comment line, one vector per line.
std::vector<std::vector<double>> ReadNumberLines(const std::string& path) {
  SLSLAM_CHECK(std::filesystem::is_regular_file(path), path, ": no such file");
  std::ifstream in(path);
  std::vector<std::vector<double>> lines;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream tokens(line);
    std::vector<double> values;
    std::string token;
    while (tokens >> token) {
      if (token.back() == ':') continue;  // "Tr:" prefix of KITTI calib files
      try {
        values.push_back(std::stod(token));
      } catch (const std::exception&) {
        throw std::invalid_argument(Message(path, ": '", token, "' is not a number"));
      }
    }
    if (!values.empty()) lines.push_back(std::move(values));
  }
  return lines;
}

Rigid3d FromRowMajor12(const double* v) {
  Rigid3d T;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) T.rotation(r, c) = v[4 * r + c];
    T.translation(r) = v[4 * r + 3];
  }
  return T;
}

}  // namespace

Rigid3d ReadRigid3d(const std::string& path) {
  std::vector<double> all;
  for (const auto& line : ReadNumberLines(path)) all.insert(all.end(), line.begin(), line.end());
  SLSLAM_CHECK(all.size() == 12 || all.size() == 16, path,
               ": expected 12 or 16 numbers (3x4 or 4x4 matrix), got ", all.size());
  return FromRowMajor12(all.data());
}

Rigid3d ReadKittiCalibTr(const std::string& path) { return ReadRigid3d(path); }

std::map<int, Rigid3d> ReadKittiPoses(const std::string& path) {
  std::map<int, Rigid3d> poses;
  int index = 0;
  for (const auto& line : ReadNumberLines(path)) {
    if (line.size() == 12) {
      poses[index] = FromRowMajor12(line.data());
    } else {
      SLSLAM_CHECK(line.size() == 14, path, ": line ", index + 1, " has ", line.size(),
                   " numbers (expected 12, or 14 with frame and time)");
      poses[static_cast<int>(line[0])] = FromRowMajor12(line.data() + 2);
    }
    ++index;
  }
  return poses;
}

Rigid3d KittiRelativeVelo(const Rigid3d& world_from_cam_target,
                          const Rigid3d& world_from_cam_source, const Rigid3d& cam_from_velo) {
  return (world_from_cam_target * cam_from_velo).Inverse() *
         (world_from_cam_source * cam_from_velo);
}

PoseError ComparePoses(const Rigid3d& estimate, const Rigid3d& truth) {
  constexpr double kDeg = 180.0 / M_PI;
  const Eigen::Matrix3d residual = truth.rotation.transpose() * estimate.rotation;
  PoseError e;
  // Roll-pitch-yaw of residual = Rz(yaw) Ry(pitch) Rx(roll); small angles, so no wrap issues.
  e.roll_deg = std::abs(std::atan2(residual(2, 1), residual(2, 2))) * kDeg;
  e.pitch_deg = std::abs(std::asin(std::clamp(-residual(2, 0), -1.0, 1.0))) * kDeg;
  e.yaw_deg = std::abs(std::atan2(residual(1, 0), residual(0, 0))) * kDeg;
  e.rotation_deg = Eigen::AngleAxisd(residual).angle() * kDeg;
  const Eigen::Vector3d dt = estimate.translation - truth.translation;
  e.x_m = std::abs(dt.x());
  e.y_m = std::abs(dt.y());
  e.z_m = std::abs(dt.z());
  e.translation_m = dt.norm();
  return e;
}

}  // namespace slslam::lidar
