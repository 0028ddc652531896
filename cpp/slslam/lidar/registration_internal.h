// Internal to the registration_*.cpp files that implement RegisterClouds (registration.h): the
// PCL types and the steps they share. Not part of the public API: registration.h stays PCL-free.
//
//   registration_neighbours.cpp   kd-tree, batch k-NN / radius queries, even index thinning
//   registration_preprocess.cpp   range crop, voxel pyramid, outlier removal, normals
//   registration_descriptors.cpp  FPFH / PFH descriptors and their nearest descriptors
//   registration_coarse.cpp       SAC-IA coarse alignment
//   registration_fine.cpp         coarse-to-fine ICP, NDT, fitness scoring
//   registration.cpp              RegisterClouds, the options' Check, method names
#pragma once

#include <memory>
#include <vector>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/flann_search.h>
#include <Eigen/Core>

#include "slslam/lidar/registration.h"

namespace slslam::lidar::registration_detail {

using PointN = pcl::PointNormal;
using CloudN = pcl::PointCloud<PointN>;
using CloudXYZ = pcl::PointCloud<pcl::PointXYZ>;
// PCL's FLANN kd-tree. Its batch queries answer a block of points per FLANN call: PCL's per-point
// calls (pcl::search::KdTree) cost about four times the search itself in call overhead.
using Tree = pcl::search::FlannSearch<PointN>;

// One scan after preprocessing: the fine and coarse levels of the voxel pyramid. Coarse points
// carry normals. Fine points get theirs on demand (fine_normal: 0 not yet, 1 valid, -1 degenerate),
// only on the target and only where ICP pairs a source point with them; only the target needs a
// fine kd-tree.
struct Prepared {
  CloudN::Ptr fine;
  CloudN::Ptr coarse;
  std::shared_ptr<Tree> fine_tree;
  std::shared_ptr<Tree> coarse_tree;
  std::vector<signed char> fine_normal;
};

// ---- registration_neighbours.cpp

// options.num_threads, or every processor for 0.
int Threads(const RegistrationOptions& options);

std::shared_ptr<Tree> MakeTree(const CloudN::Ptr& cloud);

// Neighbours in `tree` of the points `queries` (all of them when empty) of `cloud`: the k nearest
// (k > 0, sorted by distance) or those within radius_m (k = 0). One batch query per thread.
void Neighbours(const Tree& tree, const CloudN& cloud, const pcl::Indices& queries, int k,
                double radius_m, int threads, std::vector<pcl::Indices>* indices,
                std::vector<std::vector<float>>* dist2);

// The k nearest neighbours in `tree` of every point of `queries`, sorted by distance.
void NearestK(const Tree& tree, const CloudN& queries, int k, int threads,
              std::vector<pcl::Indices>* indices, std::vector<std::vector<float>>* dist2);

// Every `stride`-th index below n, at most max_count of them (all for max_count 0): an even
// thinning, since voxel-grid output is ordered along the grid.
pcl::IndicesPtr Thinned(std::size_t n, int max_count);

// ---- registration_preprocess.cpp

// pcl::VoxelGrid and NDT's voxel grid number voxels with a 32-bit int over the cloud's bounding
// box. A leaf too small for the extent overflows it: PCL then only warns, returns the input
// unfiltered, and a later vector::at fails with a message that names nothing. Checked here.
void CheckVoxelCount(const CloudXYZ& cloud, double leaf_m, const char* option, const char* name);

// Normals of the fine points `wanted` that have none yet, each from its normal_k nearest fine
// neighbours.
void AddFineNormals(const pcl::Indices& wanted, const RegistrationOptions& options, int threads,
                    Prepared* scan);

// Range crop, fine voxel grid, coarse voxel grid of the fine level; statistical outlier removal
// and normals on the coarse level from one k-NN query per point; fine points whose coarse voxel
// was dropped are dropped too. `name` ("source", "target") prefixes the error messages.
Prepared Preprocess(const PointMatrix& points, const RegistrationOptions& options, bool fine_tree,
                    int threads, const char* name);

// ---- registration_descriptors.cpp

// FPFH (Rusu et al. 2009) of the coarse points `keypoints`, with the whole coarse level as
// support.
pcl::PointCloud<pcl::FPFHSignature33>::Ptr Fpfh(const Prepared& scan, const pcl::Indices& keypoints,
                                                const RegistrationOptions& options, int threads);

// PFH (the paper's comparison) of the coarse points `indices` through PCL's estimator.
pcl::PointCloud<pcl::PFHSignature125>::Ptr Pfh(const Prepared& scan, const pcl::IndicesPtr& indices,
                                               const RegistrationOptions& options);

// For each source descriptor, the `k` nearest target descriptors (none for a descriptor with a
// non-finite bin). Instantiated for pcl::FPFHSignature33 and pcl::PFHSignature125.
template <typename Feature>
std::vector<std::vector<int>> SimilarFeatures(const pcl::PointCloud<Feature>& source,
                                              const pcl::PointCloud<Feature>& target, int k,
                                              int threads);

// ---- registration_coarse.cpp

// SAC-IA on the coarse level: the transform that moves the source keypoints (coarse indices
// `keypoints`, described by source_features row for row) onto the target; identity when no
// hypothesis beats it. Instantiated for pcl::FPFHSignature33 and pcl::PFHSignature125.
template <typename Feature>
Eigen::Matrix4f CoarseAlign(const Prepared& source, const pcl::Indices& keypoints,
                            const Prepared& target, const pcl::PointCloud<Feature>& source_features,
                            const pcl::PointCloud<Feature>& target_features,
                            const RegistrationOptions& options);

// ---- registration_fine.cpp

// Coarse-to-fine ICP from `guess`, each level on an even thinning of the source. Adds the target's
// fine normals that ICP pairs.
Eigen::Matrix4f FineAlign(const Prepared& source, Prepared* target, Eigen::Matrix4f guess,
                          const RegistrationOptions& options, RegistrationResult* result);

// NDT from identity, on the coarse level and then the fine one.
Eigen::Matrix4f NdtAlign(const Prepared& source, const Prepared& target,
                         const RegistrationOptions& options, RegistrationResult* result);

// Fitness and inlier RMSE of the fine source points under `transform`, into `result`.
void Score(const Prepared& source, const Prepared& target, const Eigen::Matrix4f& transform,
           double inlier_m, const RegistrationOptions& options, RegistrationResult* result);

}  // namespace slslam::lidar::registration_detail
