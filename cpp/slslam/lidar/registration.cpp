#include "slslam/lidar/registration.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

#include <pcl/common/io.h>
#include <pcl/common/transforms.h>
#include <pcl/features/fpfh_omp.h>
#include <pcl/features/normal_3d_omp.h>
#include <pcl/features/pfh.h>
#include <pcl/filters/statistical_outlier_removal.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/correspondence_rejection_one_to_one.h>
#include <pcl/registration/ia_ransac.h>
#include <pcl/registration/icp.h>
#include <pcl/registration/ndt.h>
#include <pcl/search/kdtree.h>

#include "slslam/core/check.h"

namespace slslam::lidar {
namespace {

using PointN = pcl::PointNormal;
using CloudN = pcl::PointCloud<PointN>;
using CloudXYZ = pcl::PointCloud<pcl::PointXYZ>;
using Tree = pcl::search::KdTree<PointN>;
using Clock = std::chrono::steady_clock;

double MsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// One scan after preprocessing: the fine and coarse levels of the voxel pyramid, with normals.
struct Prepared {
  CloudN::Ptr fine;
  CloudN::Ptr coarse;
  Tree::Ptr fine_tree;
  Tree::Ptr coarse_tree;
};

CloudXYZ::Ptr Crop(const PointMatrix& points, const RegistrationOptions& options) {
  auto cloud = std::make_shared<CloudXYZ>();
  cloud->reserve(points.rows());
  const double min2 = options.min_range_m * options.min_range_m;
  const double max2 = options.max_range_m > 0 ? options.max_range_m * options.max_range_m : 1e300;
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    const pcl::PointXYZ p(points(i, 0), points(i, 1), points(i, 2));
    const double r2 = double(p.x) * p.x + double(p.y) * p.y + double(p.z) * p.z;
    if (r2 >= min2 && r2 <= max2) cloud->push_back(p);
  }
  return cloud;
}

CloudXYZ::Ptr Downsample(const CloudXYZ::ConstPtr& cloud, double leaf_m) {
  pcl::VoxelGrid<pcl::PointXYZ> grid;
  grid.setInputCloud(cloud);
  const float leaf = static_cast<float>(leaf_m);
  grid.setLeafSize(leaf, leaf, leaf);
  auto out = std::make_shared<CloudXYZ>();
  grid.filter(*out);
  return out;
}

// Normals by k-NN PCA (oriented towards the sensor at the origin); drops degenerate points.
CloudN::Ptr WithNormals(const CloudXYZ::ConstPtr& cloud, const RegistrationOptions& options) {
  pcl::NormalEstimationOMP<pcl::PointXYZ, pcl::Normal> estimator(options.num_threads);
  estimator.setInputCloud(cloud);
  estimator.setSearchMethod(std::make_shared<pcl::search::KdTree<pcl::PointXYZ>>());
  estimator.setKSearch(options.normal_k);
  pcl::PointCloud<pcl::Normal> normals;
  estimator.compute(normals);
  auto out = std::make_shared<CloudN>();
  out->reserve(cloud->size());
  for (std::size_t i = 0; i < cloud->size(); ++i) {
    const pcl::Normal& n = normals[i];
    if (!std::isfinite(n.normal_x) || !std::isfinite(n.normal_y) || !std::isfinite(n.normal_z)) {
      continue;
    }
    PointN p;
    p.x = (*cloud)[i].x;
    p.y = (*cloud)[i].y;
    p.z = (*cloud)[i].z;
    p.normal_x = n.normal_x;
    p.normal_y = n.normal_y;
    p.normal_z = n.normal_z;
    p.curvature = n.curvature;
    out->push_back(p);
  }
  return out;
}

Prepared Preprocess(const PointMatrix& points, const RegistrationOptions& options,
                    const char* name) {
  CloudXYZ::Ptr cloud = Downsample(Crop(points, options), options.fine_voxel_m);
  if (options.outlier_k > 0 && static_cast<int>(cloud->size()) > options.outlier_k) {
    pcl::StatisticalOutlierRemoval<pcl::PointXYZ> sor;
    sor.setInputCloud(cloud);
    sor.setMeanK(options.outlier_k);
    sor.setStddevMulThresh(options.outlier_std_mul);
    auto kept = std::make_shared<CloudXYZ>();
    sor.filter(*kept);
    cloud = kept;
  }
  Require(static_cast<int>(cloud->size()) > options.normal_k,
          Message(name, ": only ", cloud->size(),
                  " points left after range crop, voxel grid and "
                  "outlier removal (need more than normal_k = ",
                  options.normal_k, ")"));
  Prepared out;
  out.fine = WithNormals(cloud, options);
  out.coarse = WithNormals(Downsample(cloud, options.coarse_voxel_m), options);
  Require(out.coarse->size() >= 10,
          Message(name, ": only ", out.coarse->size(), " points on the coarse level (voxel ",
                  options.coarse_voxel_m, " m); need at least 10"));
  out.fine_tree = std::make_shared<Tree>();
  out.fine_tree->setInputCloud(out.fine);
  out.coarse_tree = std::make_shared<Tree>();
  out.coarse_tree->setInputCloud(out.coarse);
  return out;
}

// Every `stride`-th coarse point: the keypoints that get descriptors (all of them for stride 1).
pcl::IndicesPtr Keypoints(const Prepared& scan, int max_keypoints) {
  const std::size_t n = scan.coarse->size();
  const std::size_t stride =
      max_keypoints > 0 ? std::max<std::size_t>(1, (n + max_keypoints - 1) / max_keypoints) : 1;
  auto indices = std::make_shared<pcl::Indices>();
  for (std::size_t i = 0; i < n; i += stride) indices->push_back(static_cast<pcl::index_t>(i));
  return indices;
}

// Descriptors of the keypoints `indices`, with the whole coarse level as support.
template <typename Feature>
typename pcl::PointCloud<Feature>::Ptr Describe(const Prepared& scan,
                                                const pcl::IndicesPtr& indices,
                                                const RegistrationOptions& options) {
  auto features = std::make_shared<pcl::PointCloud<Feature>>();
  if constexpr (std::is_same_v<Feature, pcl::FPFHSignature33>) {
    pcl::FPFHEstimationOMP<PointN, PointN, Feature> estimator(options.num_threads);
    estimator.setIndices(indices);
    estimator.setInputCloud(scan.coarse);
    estimator.setInputNormals(scan.coarse);
    estimator.setSearchMethod(scan.coarse_tree);
    estimator.setRadiusSearch(options.feature_radius_m);
    estimator.compute(*features);
  } else {
    pcl::PFHEstimation<PointN, PointN, Feature> estimator;
    estimator.setIndices(indices);
    estimator.setInputCloud(scan.coarse);
    estimator.setInputNormals(scan.coarse);
    estimator.setSearchMethod(scan.coarse_tree);
    estimator.setRadiusSearch(options.feature_radius_m);
    estimator.compute(*features);
  }
  return features;
}

// SAC-IA on the coarse level; returns the initial guess (identity when it does not converge).
template <typename Feature>
Eigen::Matrix4f CoarseAlign(const Prepared& source, const pcl::IndicesPtr& source_keypoints,
                            const Prepared& target,
                            const typename pcl::PointCloud<Feature>::Ptr& source_features,
                            const typename pcl::PointCloud<Feature>::Ptr& target_features,
                            const RegistrationOptions& options) {
  pcl::SampleConsensusInitialAlignment<PointN, PointN, Feature> sac;
  auto keypoints = std::make_shared<CloudN>(*source.coarse, *source_keypoints);
  sac.setInputSource(keypoints);
  sac.setSourceFeatures(source_features);
  sac.setInputTarget(target.coarse);
  sac.setSearchMethodTarget(target.coarse_tree, true);
  sac.setTargetFeatures(target_features);
  sac.setMinSampleDistance(static_cast<float>(options.sac_ia_min_sample_m));
  sac.setMaxCorrespondenceDistance(options.sac_ia_max_corr_m);
  sac.setMaximumIterations(options.sac_ia_iterations);
  sac.setNumberOfSamples(options.sac_ia_samples);
  sac.setCorrespondenceRandomness(options.sac_ia_randomness);
  CloudN aligned;
  sac.align(aligned);
  return sac.hasConverged() ? sac.getFinalTransformation() : Eigen::Matrix4f::Identity();
}

// Exposes the iteration counter PCL keeps protected.
template <typename Base>
class CountingIcp : public Base {
 public:
  int Iterations() const { return this->nr_iterations_; }
};

template <typename Icp>
void IcpLevel(const CloudN::Ptr& source, const CloudN::Ptr& target, const Tree::Ptr& target_tree,
              double max_corr_m, int iterations, const RegistrationOptions& options,
              Eigen::Matrix4f* transform, RegistrationResult* result) {
  CountingIcp<Icp> icp;
  icp.setInputSource(source);
  icp.setInputTarget(target);
  icp.setSearchMethodTarget(target_tree, true);
  icp.setMaxCorrespondenceDistance(max_corr_m);
  icp.setMaximumIterations(iterations);
  icp.setTransformationEpsilon(options.icp_transformation_epsilon);
  icp.setEuclideanFitnessEpsilon(options.icp_fitness_epsilon);
  if (options.icp_reject_one_to_one) {
    icp.addCorrespondenceRejector(
        std::make_shared<pcl::registration::CorrespondenceRejectorOneToOne>());
  }
  CloudN aligned;
  icp.align(aligned, *transform);
  *transform = icp.getFinalTransformation();
  result->iterations += icp.Iterations();
  result->converged = icp.hasConverged();
}

// Coarse-to-fine ICP from `guess`.
Eigen::Matrix4f FineAlign(const Prepared& source, const Prepared& target, Eigen::Matrix4f guess,
                          const RegistrationOptions& options, RegistrationResult* result) {
  using PointToPoint = pcl::IterativeClosestPoint<PointN, PointN>;
  using PointToPlane = pcl::IterativeClosestPointWithNormals<PointN, PointN>;
  const auto level = options.point_to_plane ? &IcpLevel<PointToPlane> : &IcpLevel<PointToPoint>;
  if (options.icp_iterations_coarse > 0) {
    level(source.coarse, target.coarse, target.coarse_tree, options.icp_max_corr_coarse_m,
          options.icp_iterations_coarse, options, &guess, result);
  }
  level(source.fine, target.fine, target.fine_tree, options.icp_max_corr_fine_m,
        options.icp_iterations_fine, options, &guess, result);
  return guess;
}

Eigen::Matrix4f NdtAlign(const Prepared& source, const Prepared& target,
                         const RegistrationOptions& options, RegistrationResult* result) {
  Eigen::Matrix4f transform = Eigen::Matrix4f::Identity();
  const CloudN::Ptr sources[] = {source.coarse, source.fine};
  const CloudN::Ptr targets[] = {target.coarse, target.fine};
  const double resolutions[] = {options.ndt_resolution_m, 0.5 * options.ndt_resolution_m};
  for (int level = 0; level < 2; ++level) {
    auto src = std::make_shared<CloudXYZ>();
    auto tgt = std::make_shared<CloudXYZ>();
    pcl::copyPointCloud(*sources[level], *src);
    pcl::copyPointCloud(*targets[level], *tgt);
    pcl::NormalDistributionsTransform<pcl::PointXYZ, pcl::PointXYZ> ndt;
    ndt.setResolution(static_cast<float>(resolutions[level]));
    ndt.setStepSize(options.ndt_step_m);
    ndt.setTransformationEpsilon(options.icp_transformation_epsilon);
    ndt.setMaximumIterations(options.ndt_iterations);
    ndt.setInputSource(src);
    ndt.setInputTarget(tgt);
    CloudXYZ aligned;
    ndt.align(aligned, transform);
    transform = ndt.getFinalTransformation();
    result->iterations += ndt.getFinalNumIteration();
    result->converged = ndt.hasConverged();
  }
  return transform;
}

// Fitness and inlier RMSE of the fine source level under `transform`.
void Score(const Prepared& source, const Prepared& target, const Eigen::Matrix4f& transform,
           double inlier_m, RegistrationResult* result) {
  CloudN moved;
  pcl::transformPointCloud(*source.fine, moved, transform);
  std::vector<int> index(1);
  std::vector<float> dist2(1);
  std::size_t inliers = 0;
  double sum2 = 0.0;
  for (const PointN& p : moved.points) {
    if (target.fine_tree->nearestKSearch(p, 1, index, dist2) == 1 &&
        dist2[0] <= inlier_m * inlier_m) {
      ++inliers;
      sum2 += dist2[0];
    }
  }
  result->fitness = moved.empty() ? 0.0 : double(inliers) / double(moved.size());
  result->inlier_rmse = inliers == 0 ? 0.0 : std::sqrt(sum2 / double(inliers));
}

}  // namespace

std::string MethodName(Method method) {
  switch (method) {
    case Method::kFpfhSacIaIcp:
      return "fpfh_sac_ia_icp";
    case Method::kNdt:
      return "ndt";
    case Method::kPfhSacIaIcp:
      return "pfh_sac_ia_icp";
    case Method::kIcp:
      return "icp";
  }
  throw std::invalid_argument(Message("unknown registration method ", static_cast<int>(method)));
}

Method MethodFromName(const std::string& name) {
  for (Method m : {Method::kFpfhSacIaIcp, Method::kNdt, Method::kPfhSacIaIcp, Method::kIcp}) {
    if (MethodName(m) == name) return m;
  }
  throw std::invalid_argument(Message("unknown registration method '", name,
                                      "' (expected fpfh_sac_ia_icp, ndt, pfh_sac_ia_icp or icp)"));
}

void RegistrationOptions::Check() const {
  Require(min_range_m >= 0, Message("min_range_m must be >= 0, got ", min_range_m));
  Require(max_range_m <= 0 || max_range_m > min_range_m,
          Message("max_range_m must be <= 0 (no limit) or > min_range_m, got ", max_range_m));
  Require(fine_voxel_m > 0, Message("fine_voxel_m must be > 0, got ", fine_voxel_m));
  Require(coarse_voxel_m >= fine_voxel_m,
          Message("coarse_voxel_m must be >= fine_voxel_m, got ", coarse_voxel_m));
  Require(outlier_k >= 0, Message("outlier_k must be >= 0, got ", outlier_k));
  Require(outlier_std_mul > 0, Message("outlier_std_mul must be > 0, got ", outlier_std_mul));
  Require(normal_k >= 3, Message("normal_k must be >= 3, got ", normal_k));
  Require(feature_radius_m > coarse_voxel_m,
          Message("feature_radius_m must be > coarse_voxel_m, got ", feature_radius_m));
  Require(sac_ia_iterations >= 1,
          Message("sac_ia_iterations must be >= 1, got ", sac_ia_iterations));
  Require(sac_ia_samples >= 3, Message("sac_ia_samples must be >= 3, got ", sac_ia_samples));
  Require(sac_ia_source_keypoints >= 0,
          Message("sac_ia_source_keypoints must be >= 0, got ", sac_ia_source_keypoints));
  Require(sac_ia_randomness >= 1,
          Message("sac_ia_randomness must be >= 1, got ", sac_ia_randomness));
  Require(sac_ia_min_sample_m >= 0,
          Message("sac_ia_min_sample_m must be >= 0, got ", sac_ia_min_sample_m));
  Require(sac_ia_max_corr_m > 0, Message("sac_ia_max_corr_m must be > 0, got ", sac_ia_max_corr_m));
  Require(icp_iterations_coarse >= 0,
          Message("icp_iterations_coarse must be >= 0, got ", icp_iterations_coarse));
  Require(icp_iterations_fine >= 1,
          Message("icp_iterations_fine must be >= 1, got ", icp_iterations_fine));
  Require(icp_max_corr_coarse_m > 0,
          Message("icp_max_corr_coarse_m must be > 0, got ", icp_max_corr_coarse_m));
  Require(icp_max_corr_fine_m > 0,
          Message("icp_max_corr_fine_m must be > 0, got ", icp_max_corr_fine_m));
  Require(icp_transformation_epsilon >= 0,
          Message("icp_transformation_epsilon must be >= 0, got ", icp_transformation_epsilon));
  Require(icp_fitness_epsilon >= 0,
          Message("icp_fitness_epsilon must be >= 0, got ", icp_fitness_epsilon));
  Require(ndt_resolution_m > 0, Message("ndt_resolution_m must be > 0, got ", ndt_resolution_m));
  Require(ndt_step_m > 0, Message("ndt_step_m must be > 0, got ", ndt_step_m));
  Require(ndt_iterations >= 1, Message("ndt_iterations must be >= 1, got ", ndt_iterations));
  Require(num_threads >= 0, Message("num_threads must be >= 0, got ", num_threads));
}

void CheckPoints(const PointMatrix& points, const std::string& name, int min_points) {
  Require(points.cols() == 3 || points.cols() == 4,
          Message(name, ": expected an N x 3 or N x 4 matrix (x, y, z[, intensity]), got ",
                  points.rows(), " x ", points.cols()));
  Require(points.rows() >= min_points,
          Message(name, ": ", points.rows(), " points, need at least ", min_points));
  Require(points.allFinite(), Message(name, ": contains NaN or infinite values"));
}

RegistrationResult RegisterClouds(const PointMatrix& source, const PointMatrix& target,
                                  const RegistrationOptions& options, Method method) {
  const Clock::time_point start = Clock::now();
  options.Check();
  CheckPoints(source, "source");
  CheckPoints(target, "target");
  RegistrationResult result;

  Clock::time_point stage = Clock::now();
  const Prepared src = Preprocess(source, options, "source");
  const Prepared tgt = Preprocess(target, options, "target");
  result.preprocess_ms = MsSince(stage);
  result.source_points = static_cast<int>(src.fine->size());
  result.source_keypoints = static_cast<int>(src.coarse->size());
  result.target_points = static_cast<int>(tgt.fine->size());
  result.target_keypoints = static_cast<int>(tgt.coarse->size());

  Eigen::Matrix4f guess = Eigen::Matrix4f::Identity();
  if (method == Method::kFpfhSacIaIcp || method == Method::kPfhSacIaIcp) {
    stage = Clock::now();
    const pcl::IndicesPtr keys = Keypoints(src, options.sac_ia_source_keypoints);
    const pcl::IndicesPtr all = Keypoints(tgt, 0);
    if (method == Method::kFpfhSacIaIcp) {
      using F = pcl::FPFHSignature33;
      auto fs = Describe<F>(src, keys, options);
      auto ft = Describe<F>(tgt, all, options);
      result.features_ms = MsSince(stage);
      stage = Clock::now();
      guess = CoarseAlign<F>(src, keys, tgt, fs, ft, options);
    } else {
      using F = pcl::PFHSignature125;
      auto fs = Describe<F>(src, keys, options);
      auto ft = Describe<F>(tgt, all, options);
      result.features_ms = MsSince(stage);
      stage = Clock::now();
      guess = CoarseAlign<F>(src, keys, tgt, fs, ft, options);
    }
    result.coarse_ms = MsSince(stage);
  }

  stage = Clock::now();
  const Eigen::Matrix4f transform = method == Method::kNdt
                                        ? NdtAlign(src, tgt, options, &result)
                                        : FineAlign(src, tgt, guess, options, &result);
  result.fine_ms = MsSince(stage);

  Score(src, tgt, transform, options.icp_max_corr_fine_m, &result);
  result.transform = transform.cast<double>();
  result.total_ms = MsSince(start);
  return result;
}

}  // namespace slslam::lidar
