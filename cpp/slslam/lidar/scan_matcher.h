// Scan-to-map registration of LiDAR odometry: robust point-to-plane Gauss-Newton on a VoxelMap,
// started from a predicted pose (the IMU's) whose prior keeps the directions the scan leaves
// unconstrained (along a featureless corridor) where the prediction put them.
#pragma once

#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "slslam/core/rigid3.h"
#include "slslam/lidar/voxel_map.h"

namespace slslam::lidar {

struct ScanMatchOptions {
  bool point_to_plane = true;  ///< point-to-plane residuals (planes fitted in the map); false:
                               ///< point-to-point to the nearest map point (KISS-ICP's residual),
                               ///< which measured biased on sparse 16-beam rings (up to 2.5 cm,
                               ///< 0.3 deg against a ground-truth map, vs 1 cm, 0.09 deg)
  int max_iterations = 15;     ///< Gauss-Newton iterations [-]
  double max_correspondence_m = 1.0;   ///< a source point pairs with a plane nearer than this [m]
  int plane_neighbours = 5;            ///< map points a plane is fitted to [-]
  double plane_max_thickness_m = 0.1;  ///< every neighbour of a valid plane lies within this
                                       ///< distance of it [m]
  double robust_scale_m = 0.1;         ///< Geman-McClure scale of the point-to-plane residual [m]
  double convergence_translation_m = 1e-4;  ///< stop when a step is below this [m] ...
  double convergence_rotation_rad = 1e-5;   ///< ... and this [rad]
  double prior_translation_sigma_m = 0.0;   ///< std. dev. of the predicted position [m]; 0: no
                                            ///< prior (the smoother weighs the IMU instead)
  double prior_rotation_sigma_rad = 0.0;    ///< std. dev. of the predicted attitude [rad]; 0: none
  double inlier_m = 0.2;  ///< residuals below this count as inliers for fitness / RMSE [m]
  int num_threads = 1;    ///< OpenMP threads for the correspondence search; 0: all cores [-]
  void Check() const;
};

struct ScanMatchResult {
  Rigid3d world_from_sensor;
  // Gauss-Newton information of the scan alone (no prior) for the perturbation
  // R <- Exp(phi) R, p <- p + rho, ordered (rho, phi): [1/m^2] blocks, robust weights included,
  // divided by robust_scale_m^2.
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
  int iterations = 0;
  int correspondences = 0;     ///< source points with a plane at the last iteration
  double fitness = 0.0;        ///< fraction of source points that are inliers [-]
  double inlier_rmse_m = 0.0;  ///< RMSE of the inlier point-to-plane residuals [m]
  double degeneracy = 0.0;     ///< smallest / largest eigenvalue of the translation block [-]
};

// Registers `source_sensor` (points in the sensor frame, m) onto `map` from the predicted pose
// `world_from_predicted` (the sensor's).
ScanMatchResult MatchScanToMap(const std::vector<Eigen::Vector3d>& source_sensor,
                               const VoxelMap& map, const Rigid3d& world_from_predicted,
                               const ScanMatchOptions& options = {});

}  // namespace slslam::lidar
