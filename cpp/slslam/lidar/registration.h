// Pairwise LiDAR scan registration (the LiDAR paper's): outlier removal, voxel pyramid, normals,
// FPFH on downsampled keypoints, SAC-IA coarse alignment and point-to-plane ICP fine alignment,
// plus the paper's comparison methods (NDT, PFH + SAC-IA + ICP, plain ICP) behind the same call.
//
// This header is PCL-free (Eigen in, Eigen out) so that the bindings and other modules can use it
// without PCL's include paths; the PCL work lives in registration*.cpp (registration_internal.h).
#pragma once

#include <string>

#include <Eigen/Core>

#include "slslam/core/rigid3.h"

namespace slslam::lidar {

// N x 3 (x, y, z) or N x 4 (x, y, z, intensity) points [m], row-major like a KITTI .bin file.
using PointMatrix = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

enum class Method {
  kFpfhSacIaIcp,  ///< FPFH + SAC-IA coarse, then coarse-to-fine ICP (the paper's pipeline)
  kNdt,           ///< Normal Distributions Transform from identity (pyramid: coarse then fine)
  kPfhSacIaIcp,   ///< PFH + SAC-IA coarse, then coarse-to-fine ICP
  kIcp,           ///< coarse-to-fine ICP from identity
};

// "fpfh_sac_ia_icp", "ndt", "pfh_sac_ia_icp", "icp".
std::string MethodName(Method method);
// Inverse of MethodName; throws std::invalid_argument on an unknown name.
Method MethodFromName(const std::string& name);

// Every parameter of the pipeline. Defaults are tuned for 64-beam outdoor scans (KITTI) and work
// for 16/32-beam scans with ranges of a few metres to tens of metres.
struct RegistrationOptions {
  // --- Preprocessing -------------------------------------------------------------------------
  double min_range_m = 2.0;     ///< drop points nearer than this to the sensor (vehicle body) [m]
  double max_range_m = 80.0;    ///< drop points farther than this [m]; <= 0: no limit
  double fine_voxel_m = 0.4;    ///< voxel edge of the fine level (last ICP level) [m]
  double coarse_voxel_m = 1.0;  ///< voxel edge of the coarse level (keypoints, first ICP level) [m]
  int outlier_k = 8;  ///< neighbours of the statistical outlier filter, which runs on the coarse
                      ///< level and drops the fine points of a dropped coarse voxel; 0: off [-]
  double outlier_std_mul = 2.0;  ///< drop points whose mean k-NN distance > mean + mul * std [-]
  int normal_k = 12;             ///< neighbours for normal estimation [-]

  // --- Descriptors and coarse alignment (SAC-IA) --------------------------------------------
  double feature_radius_m = 2.0;      ///< FPFH / PFH support radius on the coarse level [m]
  int sac_ia_iterations = 200;        ///< SAC-IA iteration bound [-]
  int sac_ia_source_keypoints = 400;  ///< source keypoints (evenly thinned coarse points) that get
                                      ///< descriptors and score hypotheses; 0: all [-]
  int sac_ia_samples = 3;             ///< correspondences sampled per SAC-IA hypothesis [-]
  int sac_ia_randomness = 4;          ///< sample among this many nearest descriptors [-]
  double sac_ia_min_sample_m = 2.0;   ///< minimum distance between sampled keypoints [m]
  double sac_ia_max_corr_m = 2.0;     ///< inlier distance of the SAC-IA error metric [m]
  double sac_ia_edge_similarity = 0.9;  ///< prerejection: a hypothesis is scored only when every
                                        ///< sampled edge has the same length in source and target
                                        ///< to this ratio; 0: score every hypothesis [-]
  double sac_ia_confidence = 0.99;  ///< stop SAC-IA once a better hypothesis would have been drawn
                                    ///< with this probability (adaptive RANSAC bound from the
                                    ///< best hypothesis' correspondence inlier ratio); 1: never [-]
  bool sac_ia_try_identity = true;  ///< also score the identity (no motion) as a hypothesis [-]

  // --- Fine alignment (ICP, coarse-to-fine) ------------------------------------------------
  bool point_to_plane = true;           ///< point-to-plane (true) or point-to-point ICP objective
  int icp_iterations_coarse = 30;       ///< iteration bound on the coarse level [-]
  int icp_iterations_fine = 20;         ///< iteration bound on the fine level [-]
  int icp_source_points_coarse = 1000;  ///< source points (evenly thinned) aligned on the coarse
                                        ///< level; 0: all [-]
  int icp_source_points_fine = 3000;    ///< source points (evenly thinned) aligned on the fine
                                        ///< level; 0: all [-]
  double icp_max_corr_coarse_m = 2.0;   ///< correspondence rejection distance, coarse level [m]
  double icp_max_corr_fine_m = 0.6;     ///< correspondence rejection distance, fine level [m]
  double icp_transformation_epsilon = 1e-8;  ///< stop when the squared step falls below this in
                                             ///< translation [m^2] and rotation [rad^2]
  double icp_fitness_epsilon = 1e-6;   ///< stop when the mean squared error change is below [m^2]
  bool icp_reject_one_to_one = false;  ///< keep only the closest source per target point

  // --- NDT ---------------------------------------------------------------------------------
  double ndt_resolution_m = 2.0;  ///< NDT cell size on the coarse level (fine level: half) [m]
  double ndt_step_m = 0.3;        ///< More-Thuente maximum step length [m]
  int ndt_iterations = 35;        ///< iteration bound per level [-]

  // --- Runtime -----------------------------------------------------------------------------
  int num_threads = 0;  ///< threads (OpenMP) for preprocessing, descriptors, nearest-neighbour
                        ///< queries and ICP; 0: all cores [-]

  // Throws std::invalid_argument naming the first out-of-range field.
  void Check() const;
};

struct RegistrationResult {
  Rigid3d target_from_source;  ///< maps source points into the target frame
  double fitness = 0.0;        ///< fraction of fine source points with a target point within
                               ///< icp_max_corr_fine_m after alignment [-]
  double inlier_rmse = 0.0;    ///< RMSE of those inlier distances [m]
  int iterations = 0;          ///< fine-alignment iterations over all levels (ICP or NDT) [-]
  bool converged = false;      ///< the last fine-alignment level reported convergence
  int source_points = 0;       ///< source points on the fine / coarse level after preprocessing
  int source_keypoints = 0;
  int target_points = 0;  ///< target points on the fine / coarse level after preprocessing
  int target_keypoints = 0;
  double preprocess_ms = 0.0;  ///< range crop, voxel pyramid, outlier removal, normals [ms]
  double features_ms = 0.0;    ///< FPFH / PFH descriptors [ms]
  double coarse_ms = 0.0;      ///< SAC-IA [ms]
  double fine_ms = 0.0;        ///< ICP or NDT levels, with the target's fine normals that ICP pairs
                               ///< with (computed on demand) [ms]
  double total_ms = 0.0;       ///< the whole call, input conversion and scoring included [ms]
};

// Throws std::invalid_argument unless `points` is N x 3 or N x 4 with N >= min_points and every
// value finite. `name` prefixes the message ("source", "target", a file path).
void CheckPoints(const PointMatrix& points, const std::string& name, int min_points = 10);

// Registers `source` onto `target`: returns target_from_source, which maps source points into
// the target frame (inside, PCL's registration and Eigen::umeyama work on 4x4 float matrices, the
// type they take and give). Throws std::invalid_argument on bad input or options, or when
// preprocessing leaves too few points to register.
RegistrationResult RegisterClouds(const PointMatrix& source, const PointMatrix& target,
                                  const RegistrationOptions& options = {},
                                  Method method = Method::kFpfhSacIaIcp);

}  // namespace slslam::lidar
