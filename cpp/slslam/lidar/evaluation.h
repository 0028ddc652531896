// Ground truth for LiDAR registration: KITTI poses and calibration, 4x4 reference transforms, and
// the per-axis error of an estimated relative transform.
#pragma once

#include <map>
#include <string>

#include <Eigen/Core>

namespace slslam::lidar {

// Reads a 4x4 (or 3x4, last row implied) matrix of whitespace-separated numbers; lines starting
// with '#' are skipped. Throws std::invalid_argument on a missing file or a wrong count.
Eigen::Matrix4d ReadMatrix4(const std::string& path);

// KITTI calib "Tr" (velodyne -> cam0, T_cam_velo) from a file holding its 12 numbers, with or
// without the "Tr:" prefix; '#' lines are skipped.
Eigen::Matrix4d ReadKittiCalibTr(const std::string& path);

// KITTI poses T_world_cam0 keyed by frame: lines of 12 numbers (frame = line index) or of 14
// numbers "frame time r11 r12 r13 tx ... r33 tz"; '#' lines are skipped.
std::map<int, Eigen::Matrix4d> ReadKittiPoses(const std::string& path);

// T_target_source of two Velodyne scans from camera poses and T_cam_velo:
// inv(T_w_cam_t * T_cam_velo) * (T_w_cam_s * T_cam_velo).
Eigen::Matrix4d KittiRelativeVelo(const Eigen::Matrix4d& T_world_cam_target,
                                  const Eigen::Matrix4d& T_world_cam_source,
                                  const Eigen::Matrix4d& T_cam_velo);

// Error of `estimate` against `truth` (both T_target_source). Rotation: the residual rotation
// R_truth^T R_estimate as roll, pitch, yaw (x, y, z Euler angles, magnitudes) and its total angle;
// translation: |t_estimate - t_truth| per axis and its norm.
struct PoseError {
  double roll_deg = 0, pitch_deg = 0, yaw_deg = 0, rotation_deg = 0;
  double x_m = 0, y_m = 0, z_m = 0, translation_m = 0;
};
PoseError ComparePoses(const Eigen::Matrix4d& estimate, const Eigen::Matrix4d& truth);

}  // namespace slslam::lidar
