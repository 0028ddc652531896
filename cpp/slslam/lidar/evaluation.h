// Ground truth for LiDAR registration: KITTI poses and calibration, reference transforms (4x4 or
// 3x4 matrices in text files), and the per-axis error of an estimated relative transform.
#pragma once

#include <map>
#include <string>

#include <Eigen/Core>

#include "slslam/core/rigid3.h"

namespace slslam::lidar {

// Reads a transform written as a 4x4 (or 3x4, last row implied) matrix of whitespace-separated
// numbers; lines starting with '#' are skipped. Throws std::invalid_argument on a missing file
// or a wrong count.
Rigid3d ReadRigid3d(const std::string& path);

// KITTI calib "Tr" (cam0_from_velo: velodyne -> cam0) from a file holding its 12 numbers, with
// or without the "Tr:" prefix; '#' lines are skipped.
Rigid3d ReadKittiCalibTr(const std::string& path);

// KITTI poses world_from_cam0 keyed by frame: lines of 12 numbers (frame = line index) or of 14
// numbers "frame time r11 r12 r13 tx ... r33 tz"; '#' lines are skipped.
std::map<int, Rigid3d> ReadKittiPoses(const std::string& path);

// target_from_source of two Velodyne scans from camera poses and cam_from_velo:
// (world_from_cam_target * cam_from_velo)^-1 * (world_from_cam_source * cam_from_velo).
Rigid3d KittiRelativeVelo(const Rigid3d& world_from_cam_target,
                          const Rigid3d& world_from_cam_source, const Rigid3d& cam_from_velo);

// Error of `estimate` against `truth` (both target_from_source). Rotation: the residual rotation
// R_truth^T R_estimate as roll, pitch, yaw (x, y, z Euler angles, magnitudes) and its total angle;
// translation: |t_estimate - t_truth| per axis and its norm.
struct PoseError {
  double roll_deg = 0, pitch_deg = 0, yaw_deg = 0, rotation_deg = 0;
  double x_m = 0, y_m = 0, z_m = 0, translation_m = 0;
};
PoseError ComparePoses(const Rigid3d& estimate, const Rigid3d& truth);

}  // namespace slslam::lidar
