#include "slslam/lidar/registration.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <exception>
#include <future>
#include <limits>
#include <numeric>
#include <random>
#include <tuple>
#include <unordered_map>
#include <utility>
#include <vector>

#include <omp.h>
#include <pcl/common/centroid.h>
#include <pcl/common/io.h>
#include <pcl/features/feature.h>
#include <pcl/features/fpfh.h>
#include <pcl/features/normal_3d.h>
#include <pcl/features/pfh.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/ndt.h>
#include <pcl/search/flann_search.h>
#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include "slslam/core/check.h"

namespace slslam::lidar {
namespace {

using PointN = pcl::PointNormal;
using CloudN = pcl::PointCloud<PointN>;
using CloudXYZ = pcl::PointCloud<pcl::PointXYZ>;
// PCL's FLANN kd-tree. Its batch queries answer a block of points per FLANN call: PCL's per-point
// calls (pcl::search::KdTree) cost about four times the search itself in call overhead.
using Tree = pcl::search::FlannSearch<PointN>;
using Clock = std::chrono::steady_clock;

double MsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

int Threads(const RegistrationOptions& options) {
  return options.num_threads > 0 ? options.num_threads : std::max(1, omp_get_num_procs());
}

std::shared_ptr<Tree> MakeTree(const CloudN::Ptr& cloud) {
  auto tree = std::make_shared<Tree>();
  tree->setInputCloud(cloud);
  return tree;
}

// Neighbours in `tree` of the points `queries` (all of them when empty) of `cloud`: the k nearest
// (k > 0, sorted by distance) or those within radius_m (k = 0). One batch query per thread.
void Neighbours(const Tree& tree, const CloudN& cloud, const pcl::Indices& queries, int k,
                double radius_m, int threads, std::vector<pcl::Indices>* indices,
                std::vector<std::vector<float>>* dist2) {
  const int n = static_cast<int>(queries.empty() ? cloud.size() : queries.size());
  k = std::min<int>(k, static_cast<int>(tree.getInputCloud()->size()));
  indices->resize(n);
  dist2->resize(n);
  const int blocks = std::max(1, std::min(threads, n / 512));
#pragma omp parallel for num_threads(blocks) schedule(static, 1)
  for (int b = 0; b < blocks; ++b) {
    const int begin = int(std::int64_t(n) * b / blocks);
    const int end = int(std::int64_t(n) * (b + 1) / blocks);
    // The block as a cloud of its own: PCL 1.13's batch radius search mis-sizes its query matrix
    // when given indices.
    CloudN block;
    const CloudN* points = &cloud;
    if (!queries.empty() || blocks > 1) {
      block.resize(end - begin);
      for (int i = begin; i < end; ++i) block[i - begin] = cloud[queries.empty() ? i : queries[i]];
      points = &block;
    }
    std::vector<pcl::Indices> idx;
    std::vector<std::vector<float>> d2;
    if (k > 0) {
      tree.nearestKSearch(*points, pcl::Indices(), k, idx, d2);
    } else {
      tree.radiusSearch(*points, pcl::Indices(), radius_m, idx, d2);
    }
    std::move(idx.begin(), idx.end(), indices->begin() + begin);
    std::move(d2.begin(), d2.end(), dist2->begin() + begin);
  }
}

// The k nearest neighbours in `tree` of every point of `queries`, sorted by distance.
void NearestK(const Tree& tree, const CloudN& queries, int k, int threads,
              std::vector<pcl::Indices>* indices, std::vector<std::vector<float>>* dist2) {
  Neighbours(tree, queries, {}, k, 0.0, threads, indices, dist2);
}

// Runs first() and second(), on two threads when `concurrent`; rethrows what either threw.
template <typename First, typename Second>
auto Both(bool concurrent, First first, Second second) {
  using A = decltype(first());
  using B = decltype(second());
  if (!concurrent) {
    A a = first();
    return std::pair<A, B>(std::move(a), second());
  }
  std::future<A> a = std::async(std::launch::async, first);
  std::exception_ptr error;
  B b{};
  try {
    b = second();
  } catch (...) {
    error = std::current_exception();
  }
  A a_value = a.get();  // rethrows the first job's error
  if (error) std::rethrow_exception(error);
  return std::pair<A, B>(std::move(a_value), std::move(b));
}

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

// Range crop and voxel grid of a raw scan in one pass: the centroid of the points in each occupied
// voxel (voxel i covers [i, i + 1) * leaf on each axis), ordered by (z, y, x) voxel index as
// pcl::VoxelGrid orders them. pcl::VoxelGrid needs a copy of the cropped scan and a sort of every
// point's voxel index (120,000 on a KITTI scan); a hash map over the occupied voxels needs
// neither. Together with scoring on the ICP subset this took the FPFH pipeline on the KITTI pairs
// from 61 / 49 ms to 47 / 48 ms (benchmarks/lidar_registration.cpp, medians, back to back).
CloudXYZ::Ptr CropToVoxelCentroids(const PointMatrix& points, const RegistrationOptions& options) {
  const double min2 = options.min_range_m * options.min_range_m;
  const double max2 = options.max_range_m > 0 ? options.max_range_m * options.max_range_m : 1e300;
  const double inverse_leaf = 1.0 / options.fine_voxel_m;
  struct Voxel {
    std::array<std::int32_t, 3> ijk;
    Eigen::Vector3d sum;
    int count;
  };
  std::vector<Voxel> voxels;
  std::unordered_map<std::uint64_t, int> slot;
  slot.reserve(static_cast<std::size_t>(points.rows()) / 4);
  constexpr std::int64_t kOffset = 1 << 20;  // +-1M voxels per axis
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    const Eigen::Vector3d p(points(i, 0), points(i, 1), points(i, 2));
    const double r2 = p.squaredNorm();
    if (!(r2 >= min2 && r2 <= max2)) continue;
    std::array<std::int32_t, 3> ijk;
    std::uint64_t key = 0;
    for (int a = 0; a < 3; ++a) {
      // beyond +-kOffset voxels the key would clamp and merge far points into one voxel
      SLSLAM_CHECK(std::abs(p[a]) * inverse_leaf < kOffset - 1,
                   "fine_voxel_m = ", options.fine_voxel_m, " m is too small for a point ",
                   std::abs(p[a]), " m from the sensor along one axis (at most ", kOffset - 1,
                   " voxels each way); raise fine_voxel_m or lower max_range_m");
      ijk[a] = static_cast<std::int32_t>(std::floor(p[a] * inverse_leaf));
      const std::int64_t shifted = std::clamp<std::int64_t>(ijk[a] + kOffset, 0, 2 * kOffset - 1);
      key = (key << 21) | static_cast<std::uint64_t>(shifted);
    }
    const auto [it, inserted] = slot.try_emplace(key, static_cast<int>(voxels.size()));
    if (inserted) {
      voxels.push_back({ijk, p, 1});
    } else {
      voxels[it->second].sum += p;
      voxels[it->second].count += 1;
    }
  }
  std::sort(voxels.begin(), voxels.end(), [](const Voxel& a, const Voxel& b) {
    return std::tie(a.ijk[2], a.ijk[1], a.ijk[0]) < std::tie(b.ijk[2], b.ijk[1], b.ijk[0]);
  });
  auto cloud = std::make_shared<CloudXYZ>();
  cloud->reserve(voxels.size());
  for (const Voxel& v : voxels) {
    const Eigen::Vector3d c = v.sum / v.count;
    cloud->push_back(pcl::PointXYZ(static_cast<float>(c.x()), static_cast<float>(c.y()),
                                   static_cast<float>(c.z())));
  }
  return cloud;
}

// pcl::VoxelGrid and NDT's voxel grid number voxels with a 32-bit int over the cloud's bounding
// box. A leaf too small for the extent overflows it: PCL then only warns, returns the input
// unfiltered, and a later vector::at fails with a message that names nothing. Checked here.
void CheckVoxelCount(const CloudXYZ& cloud, double leaf_m, const char* option, const char* name) {
  if (cloud.empty()) return;
  Eigen::Array3d low = Eigen::Array3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Array3d high = -low;
  for (const auto& p : cloud.points) {
    const Eigen::Array3d q(p.x, p.y, p.z);
    low = low.min(q);
    high = high.max(q);
  }
  const Eigen::Array3d extent = high - low;
  const double voxels = ((extent / leaf_m).floor() + 1.0).prod();
  SLSLAM_CHECK(voxels <= std::numeric_limits<std::int32_t>::max(), name, ": ", option, " = ",
               leaf_m, " m is too small for the cloud's ", extent.x(), " x ", extent.y(), " x ",
               extent.z(), " m extent (", voxels, " voxels, PCL indexes at most 2^31)");
}

CloudXYZ::Ptr Downsample(pcl::VoxelGrid<pcl::PointXYZ>* grid, const CloudXYZ::ConstPtr& cloud,
                         double leaf_m) {
  grid->setInputCloud(cloud);
  const float leaf = static_cast<float>(leaf_m);
  grid->setLeafSize(leaf, leaf, leaf);
  auto out = std::make_shared<CloudXYZ>();
  grid->filter(*out);
  return out;
}

// PCA normal of the points `neighbours` of `cloud` (PCL's plane fit), oriented towards the sensor
// at the origin, written into `p`; false when the neighbourhood is degenerate.
bool FitNormal(const CloudN& cloud, const pcl::Indices& neighbours, PointN* p) {
  if (neighbours.size() < 3) return false;
  EIGEN_ALIGN16 Eigen::Matrix3f covariance;
  Eigen::Vector4f centroid;
  if (pcl::computeMeanAndCovarianceMatrix(cloud, neighbours, covariance, centroid) == 0) {
    return false;
  }
  float nx, ny, nz, curvature;
  pcl::solvePlaneParameters(covariance, nx, ny, nz, curvature);
  if (!std::isfinite(nx) || !std::isfinite(ny) || !std::isfinite(nz)) return false;
  pcl::flipNormalTowardsViewpoint(*p, 0.0f, 0.0f, 0.0f, nx, ny, nz);
  p->normal_x = nx;
  p->normal_y = ny;
  p->normal_z = nz;
  p->curvature = curvature;
  return true;
}

CloudN::Ptr WithoutNormals(const CloudXYZ& cloud) {
  auto out = std::make_shared<CloudN>();
  pcl::copyPointCloud(cloud, *out);
  return out;
}

// Normals of the fine points `wanted` that have none yet, each from its normal_k nearest fine
// neighbours.
void AddFineNormals(const pcl::Indices& wanted, const RegistrationOptions& options, int threads,
                    Prepared* scan) {
  pcl::Indices missing;
  for (pcl::index_t i : wanted) {
    if (scan->fine_normal[i] == 0) {
      scan->fine_normal[i] = -1;  // claimed; set to 1 below when the fit succeeds
      missing.push_back(i);
    }
  }
  if (missing.empty()) return;
  CloudN& fine = *scan->fine;
  std::vector<pcl::Indices> neighbours;
  std::vector<std::vector<float>> dist2;
  Neighbours(*scan->fine_tree, fine, missing, options.normal_k, 0.0, threads, &neighbours, &dist2);
  const int n = static_cast<int>(missing.size());
#pragma omp parallel for num_threads(n >= 1024 ? threads : 1) schedule(static)
  for (int i = 0; i < n; ++i) {
    if (FitNormal(fine, neighbours[i], &fine[missing[i]])) scan->fine_normal[missing[i]] = 1;
  }
}

// Range crop, fine voxel grid, coarse voxel grid of the fine level; statistical outlier removal
// and normals on the coarse level from one k-NN query per point; fine points whose coarse voxel
// was dropped are dropped too.
Prepared Preprocess(const PointMatrix& points, const RegistrationOptions& options, bool fine_tree,
                    int threads, const char* name) {
  pcl::VoxelGrid<pcl::PointXYZ> coarse_grid;
  const CloudXYZ::Ptr fine = CropToVoxelCentroids(points, options);
  SLSLAM_CHECK(static_cast<int>(fine->size()) > options.normal_k, name, ": only ", fine->size(),
               " points left after range crop and voxel grid (need more than normal_k = ",
               options.normal_k, ")");
  coarse_grid.setSaveLeafLayout(true);
  CheckVoxelCount(*fine, options.coarse_voxel_m, "coarse_voxel_m", name);
  const CloudN::Ptr coarse =
      WithoutNormals(*Downsample(&coarse_grid, fine, options.coarse_voxel_m));
  const int n = static_cast<int>(coarse->size());
  SLSLAM_CHECK(n > options.normal_k, name, ": only ", n, " points on the coarse level (voxel ",
               options.coarse_voxel_m, " m); need more than normal_k = ", options.normal_k);

  const std::shared_ptr<Tree> tree = MakeTree(coarse);
  std::vector<pcl::Indices> neighbours;
  std::vector<std::vector<float>> dist2;
  NearestK(*tree, *coarse, std::max(options.normal_k, options.outlier_k + 1), threads, &neighbours,
           &dist2);

  // Statistical outlier removal (as pcl::StatisticalOutlierRemoval: the point itself excluded).
  std::vector<char> keep(n, 1);
  if (options.outlier_k > 0) {
    std::vector<double> mean_distance(n, 0.0);
    double sum = 0.0, sum2 = 0.0;
    for (int i = 0; i < n; ++i) {
      const int k = std::min<int>(options.outlier_k + 1, static_cast<int>(dist2[i].size()));
      for (int j = 1; j < k; ++j) mean_distance[i] += std::sqrt(dist2[i][j]);
      mean_distance[i] /= std::max(1, k - 1);
      sum += mean_distance[i];
      sum2 += mean_distance[i] * mean_distance[i];
    }
    const double mean = sum / n;
    const double std_dev = std::sqrt(std::max(0.0, (sum2 - sum * mean) / std::max(1, n - 1)));
    const double limit = mean + options.outlier_std_mul * std_dev;
    for (int i = 0; i < n; ++i) keep[i] = mean_distance[i] <= limit;
  }
  // Normals from the normal_k nearest neighbours that survived the outlier filter.
  std::vector<char> valid(n, 0);
#pragma omp parallel for num_threads(threads) schedule(static)
  for (int i = 0; i < n; ++i) {
    if (!keep[i]) continue;
    pcl::Indices& nb = neighbours[i];
    nb.resize(std::min<std::size_t>(nb.size(), options.normal_k));
    nb.erase(std::remove_if(nb.begin(), nb.end(), [&](pcl::index_t j) { return !keep[j]; }),
             nb.end());
    valid[i] = FitNormal(*coarse, nb, &(*coarse)[i]);
  }

  Prepared out;
  out.coarse = std::make_shared<CloudN>();
  std::vector<int> kept_index(n, -1);
  for (int i = 0; i < n; ++i) {
    if (!valid[i]) continue;
    kept_index[i] = static_cast<int>(out.coarse->size());
    out.coarse->push_back((*coarse)[i]);
  }
  SLSLAM_CHECK(out.coarse->size() >= 10, name, ": only ", out.coarse->size(),
               " points on the coarse level (voxel ", options.coarse_voxel_m,
               " m) after outlier removal; need at least 10");
  out.coarse_tree = out.coarse->size() == coarse->size() ? tree : MakeTree(out.coarse);

  out.fine = std::make_shared<CloudN>();
  out.fine->reserve(fine->size());
  for (const pcl::PointXYZ& p : fine->points) {
    if (kept_index[coarse_grid.getCentroidIndex(p)] < 0) continue;
    PointN q;
    q.x = p.x;
    q.y = p.y;
    q.z = p.z;
    q.normal_x = q.normal_y = q.normal_z = q.curvature = 0.0f;
    out.fine->push_back(q);
  }
  out.fine_normal.assign(out.fine->size(), 0);
  if (fine_tree) out.fine_tree = MakeTree(out.fine);
  return out;
}

// Every `stride`-th index below n, at most max_count of them (all for max_count 0): an even
// thinning, since voxel-grid output is ordered along the grid.
pcl::IndicesPtr Thinned(std::size_t n, int max_count) {
  const std::size_t stride =
      max_count > 0 ? std::max<std::size_t>(1, (n + max_count - 1) / max_count) : 1;
  auto indices = std::make_shared<pcl::Indices>();
  for (std::size_t i = 0; i < n; i += stride) indices->push_back(static_cast<pcl::index_t>(i));
  return indices;
}

// FPFH (Rusu et al. 2009) of the coarse points `keypoints`, with the whole coarse level as
// support: PCL's SPFH and weighting steps, with the radius neighbourhoods found by batch queries
// and shared by both steps (pcl::FPFHEstimationOMP searches twice per point, a query at a time).
pcl::PointCloud<pcl::FPFHSignature33>::Ptr Fpfh(const Prepared& scan, const pcl::Indices& keypoints,
                                                const RegistrationOptions& options, int threads) {
  using Estimator = pcl::FPFHEstimation<PointN, PointN, pcl::FPFHSignature33>;
  const CloudN& cloud = *scan.coarse;
  const int n = static_cast<int>(cloud.size());
  std::vector<pcl::Indices> neighbours(n);
  std::vector<std::vector<float>> dist2(n);
  // Neighbourhoods of the keypoints, then of the rest of their neighbours: the SPFH support.
  std::vector<char> searched(n, 0);
  std::vector<pcl::Indices> found;
  std::vector<std::vector<float>> found2;
  const auto search = [&](const pcl::Indices& queries) {
    Neighbours(*scan.coarse_tree, cloud, queries, 0, options.feature_radius_m, threads, &found,
               &found2);
    for (std::size_t i = 0; i < queries.size(); ++i) {
      searched[queries[i]] = 1;
      neighbours[queries[i]] = std::move(found[i]);
      dist2[queries[i]] = std::move(found2[i]);
    }
  };
  search(keypoints);
  pcl::Indices support;
  std::vector<char> queued(searched);
  for (pcl::index_t key : keypoints) {
    for (pcl::index_t j : neighbours[key]) {
      if (!queued[j]) {
        queued[j] = 1;
        support.push_back(j);
      }
    }
  }
  search(support);
  const int bins = 11;  // PCL's default subdivisions per angle feature (33 bins in all)
  Eigen::MatrixXf f1 = Eigen::MatrixXf::Zero(n, bins), f2 = f1, f3 = f1;
  auto features = std::make_shared<pcl::PointCloud<pcl::FPFHSignature33>>();
  features->resize(keypoints.size());
#pragma omp parallel num_threads(threads)
  {
    Estimator estimator;
#pragma omp for schedule(dynamic, 64)
    for (int i = 0; i < n; ++i) {
      if (searched[i]) {
        estimator.computePointSPFHSignature(cloud, cloud, i, i, neighbours[i], f1, f2, f3);
      }
    }
    Eigen::VectorXf histogram(3 * bins);
#pragma omp for schedule(dynamic, 64)
    for (int i = 0; i < static_cast<int>(keypoints.size()); ++i) {
      const pcl::index_t key = keypoints[i];
      float* out = (*features)[i].histogram;
      if (neighbours[key].size() < 2) {
        std::fill(out, out + 3 * bins, std::numeric_limits<float>::quiet_NaN());
        continue;
      }
      histogram.setZero();
      estimator.weightPointSPFHSignature(f1, f2, f3, neighbours[key], dist2[key], histogram);
      std::copy(histogram.data(), histogram.data() + 3 * bins, out);
    }
  }
  return features;
}

// PFH (the paper's comparison) of the coarse points `indices` through PCL's estimator.
pcl::PointCloud<pcl::PFHSignature125>::Ptr Pfh(const Prepared& scan, const pcl::IndicesPtr& indices,
                                               const RegistrationOptions& options) {
  auto features = std::make_shared<pcl::PointCloud<pcl::PFHSignature125>>();
  pcl::PFHEstimation<PointN, PointN, pcl::PFHSignature125> estimator;
  estimator.setIndices(indices);
  estimator.setInputCloud(scan.coarse);
  estimator.setInputNormals(scan.coarse);
  estimator.setSearchMethod(scan.coarse_tree);
  estimator.setRadiusSearch(options.feature_radius_m);
  estimator.compute(*features);
  return features;
}

// Descriptors as matrix rows; a descriptor with a non-finite bin (too few neighbours) gets an
// infinite squared norm so that it never matches.
template <typename Feature>
void DescriptorMatrix(const pcl::PointCloud<Feature>& features, Eigen::MatrixXf* rows,
                      Eigen::VectorXf* squared_norms) {
  constexpr int kDim = sizeof(Feature::histogram) / sizeof(float);
  rows->resize(features.size(), kDim);
  squared_norms->resize(features.size());
  for (std::size_t i = 0; i < features.size(); ++i) {
    const Eigen::Map<const Eigen::Matrix<float, 1, kDim>> h(features[i].histogram);
    if (h.allFinite()) {
      rows->row(i) = h;
      (*squared_norms)(i) = h.squaredNorm();
    } else {
      rows->row(i).setZero();
      (*squared_norms)(i) = std::numeric_limits<float>::infinity();
    }
  }
}

// For each source descriptor, the `k` nearest target descriptors: exhaustive, as matrix-vector
// products (|s - t|^2 = |s|^2 + |t|^2 - 2 s.t).
template <typename Feature>
std::vector<std::vector<int>> SimilarFeatures(const pcl::PointCloud<Feature>& source,
                                              const pcl::PointCloud<Feature>& target, int k,
                                              int threads) {
  Eigen::MatrixXf s, t;
  Eigen::VectorXf s2, t2;
  DescriptorMatrix(source, &s, &s2);
  DescriptorMatrix(target, &t, &t2);
  k = std::min<int>(k, static_cast<int>(target.size()));
  std::vector<std::vector<int>> similar(source.size());
#pragma omp parallel num_threads(threads)
  {
    Eigen::VectorXf distance(target.size());
    std::vector<std::pair<float, int>> nearest;
#pragma omp for schedule(static)
    for (int i = 0; i < static_cast<int>(source.size()); ++i) {
      if (!std::isfinite(s2(i))) continue;
      distance.noalias() = t * s.row(i).transpose();
      distance = t2 - 2.0f * distance;  // + s2(i), the same for every target
      nearest.assign(k, {std::numeric_limits<float>::infinity(), -1});
      for (int j = 0; j < distance.size(); ++j) {
        if (distance(j) >= nearest.back().first) continue;
        int slot = k - 1;
        for (; slot > 0 && nearest[slot - 1].first > distance(j); --slot) {
          nearest[slot] = nearest[slot - 1];
        }
        nearest[slot] = {distance(j), j};
      }
      for (const auto& [d, j] : nearest) {
        if (j >= 0) similar[i].push_back(j);
      }
    }
  }
  return similar;
}

// SAC-IA (Rusu et al. 2009) on the coarse level: sample correspondences among similar descriptors,
// fit a rigid transform, keep the hypothesis with the lowest truncated error over the source
// keypoints. Beyond PCL's class: a hypothesis whose sampled edges differ in length between the two
// scans is not scored (prerejection, Buch et al. 2013), scoring stops as soon as the partial error
// exceeds the best one, and the iterations end when the best hypothesis' correspondence inlier
// ratio says a better one would have been drawn with sac_ia_confidence (adaptive RANSAC bound).
template <typename Feature>
Eigen::Matrix4f CoarseAlign(const Prepared& source, const pcl::Indices& keypoints,
                            const Prepared& target, const pcl::PointCloud<Feature>& source_features,
                            const pcl::PointCloud<Feature>& target_features,
                            const RegistrationOptions& options) {
  const std::vector<std::vector<int>> similar = SimilarFeatures(
      source_features, target_features, options.sac_ia_randomness, Threads(options));
  std::vector<int> usable;  // keypoints with at least one similar target descriptor
  for (std::size_t i = 0; i < keypoints.size(); ++i) {
    if (!similar[i].empty()) usable.push_back(static_cast<int>(i));
  }
  const CloudN& src = *source.coarse;
  const CloudN& tgt = *target.coarse;
  const auto point = [](const PointN& p) { return Eigen::Vector3f(p.x, p.y, p.z); };

  std::mt19937 rng(5489u);
  // Keypoints scored in a random order, so that a partial error is representative.
  CloudN scored(src, keypoints);
  std::shuffle(scored.begin(), scored.end(), rng);
  const float tau2 = static_cast<float>(options.sac_ia_max_corr_m * options.sac_ia_max_corr_m);
  constexpr int kBlock = 64;
  const auto error_of = [&](const Eigen::Matrix4f& transform, double bound) {
    double error = 0.0;
    CloudN moved;
    std::vector<pcl::Indices> index;
    std::vector<std::vector<float>> dist2;
    for (std::size_t begin = 0; begin < scored.size() && error <= bound; begin += kBlock) {
      const std::size_t end = std::min(scored.size(), begin + kBlock);
      moved.resize(end - begin);
      for (std::size_t i = begin; i < end; ++i) {
        moved[i - begin].getVector3fMap() =
            transform.topLeftCorner<3, 3>() * scored[i].getVector3fMap() +
            transform.topRightCorner<3, 1>();
      }
      target.coarse_tree->nearestKSearch(moved, pcl::Indices(), 1, index, dist2);
      for (const auto& d : dist2) error += std::min(d[0], tau2) / tau2;
    }
    return error;
  };
  // Fraction of (keypoint, similar descriptor) pairs that `transform` maps within the inlier
  // distance: the chance that one sampled correspondence is right.
  const auto inlier_ratio = [&](const Eigen::Matrix4f& transform) {
    std::size_t inliers = 0, total = 0;
    for (int i : usable) {
      const Eigen::Vector3f p = transform.topLeftCorner<3, 3>() * point(src[keypoints[i]]) +
                                transform.topRightCorner<3, 1>();
      for (int j : similar[i]) inliers += (point(tgt[j]) - p).squaredNorm() <= tau2;
      total += similar[i].size();
    }
    return total == 0 ? 0.0 : double(inliers) / double(total);
  };
  const int samples = options.sac_ia_samples;
  const auto needed_iterations = [&](double ratio) {
    const double all_right = std::pow(ratio, samples);
    if (options.sac_ia_confidence >= 1.0 || all_right <= 0.0) {
      return std::numeric_limits<double>::infinity();
    }
    if (all_right >= 1.0) return 0.0;
    return std::log(1.0 - options.sac_ia_confidence) / std::log(1.0 - all_right);
  };

  Eigen::Matrix4f best = Eigen::Matrix4f::Identity();
  double best_error = std::numeric_limits<double>::infinity();
  double stop_after = std::numeric_limits<double>::infinity();
  if (options.sac_ia_try_identity) {
    best_error = error_of(best, best_error);
    stop_after = needed_iterations(inlier_ratio(best));
  }
  if (static_cast<int>(usable.size()) < samples) return best;

  const float min_sample2 =
      static_cast<float>(options.sac_ia_min_sample_m * options.sac_ia_min_sample_m);
  const float tolerance = static_cast<float>(1.0 - options.sac_ia_edge_similarity);
  std::uniform_int_distribution<int> pick(0, static_cast<int>(usable.size()) - 1);
  Eigen::Matrix3Xf from(3, samples), to(3, samples);
  std::vector<int> chosen;
  for (int iteration = 0; iteration < options.sac_ia_iterations && iteration < stop_after;
       ++iteration) {
    // Keypoints at least sac_ia_min_sample_m apart (a bounded number of draws, as PCL).
    chosen.clear();
    for (int draw = 0; draw < 100 * samples && static_cast<int>(chosen.size()) < samples; ++draw) {
      const int candidate = usable[pick(rng)];
      const Eigen::Vector3f p = point(src[keypoints[candidate]]);
      bool far = true;
      for (int c : chosen) far = far && (point(src[keypoints[c]]) - p).squaredNorm() >= min_sample2;
      if (far) chosen.push_back(candidate);
    }
    if (static_cast<int>(chosen.size()) < samples) continue;
    for (int j = 0; j < samples; ++j) {
      const std::vector<int>& matches = similar[chosen[j]];
      const int match =
          matches[std::uniform_int_distribution<int>(0, static_cast<int>(matches.size()) - 1)(rng)];
      from.col(j) = point(src[keypoints[chosen[j]]]);
      to.col(j) = point(tgt[match]);
    }
    bool similar_edges = true;
    for (int a = 0; a < samples && similar_edges; ++a) {
      for (int b = a + 1; b < samples && similar_edges; ++b) {
        const float ds = (from.col(a) - from.col(b)).norm();
        const float dt = (to.col(a) - to.col(b)).norm();
        similar_edges = std::abs(ds - dt) <= tolerance * std::max(ds, dt);
      }
    }
    if (!similar_edges) continue;
    const Eigen::Matrix4f hypothesis = Eigen::umeyama(from, to, false);
    if (!hypothesis.allFinite()) continue;
    const double error = error_of(hypothesis, best_error);
    if (error < best_error) {
      best_error = error;
      best = hypothesis;
      stop_after = std::min(stop_after, iteration + 1 + needed_iterations(inlier_ratio(best)));
    }
  }
  return best;
}

// One ICP level: Gauss-Newton on the point-to-plane distance (or the closed-form point-to-point
// fit) of `source` points to their nearest `target` points within max_corr_m, from `transform`.
void IcpLevel(const CloudN& source, Prepared* target_scan, bool fine, double max_corr_m,
              int iterations, const RegistrationOptions& options, Eigen::Matrix4f* transform,
              RegistrationResult* result) {
  const CloudN& target = fine ? *target_scan->fine : *target_scan->coarse;
  const Tree& tree = fine ? *target_scan->fine_tree : *target_scan->coarse_tree;
  const int threads = Threads(options);
  const float max2 = static_cast<float>(max_corr_m * max_corr_m);
  const int n = static_cast<int>(source.size());
  CloudN moved(source);
  std::vector<pcl::Indices> index;
  std::vector<std::vector<float>> dist2;
  std::vector<int> best_source;
  double previous_mse = std::numeric_limits<double>::infinity();
  Eigen::Matrix4d previous_step = Eigen::Matrix4d::Identity();
  result->converged = false;
  for (int iteration = 0; iteration < iterations; ++iteration) {
    const Eigen::Matrix3f R = transform->topLeftCorner<3, 3>();
    const Eigen::Vector3f t = transform->topRightCorner<3, 1>();
    for (int i = 0; i < n; ++i) {
      moved[i].getVector3fMap() = R * source[i].getVector3fMap() + t;
    }
    NearestK(tree, moved, 1, threads, &index, &dist2);
    std::vector<char> inlier(n);
    for (int i = 0; i < n; ++i) inlier[i] = !dist2[i].empty() && dist2[i][0] <= max2;
    if (options.icp_reject_one_to_one) {  // keep the closest source point per target point
      best_source.assign(target.size(), -1);
      for (int i = 0; i < n; ++i) {
        if (!inlier[i]) continue;
        int& b = best_source[index[i][0]];
        if (b >= 0 && dist2[b][0] <= dist2[i][0]) {
          inlier[i] = 0;
        } else {
          if (b >= 0) inlier[b] = 0;
          b = i;
        }
      }
    }
    if (fine && options.point_to_plane) {
      pcl::Indices paired;
      for (int i = 0; i < n; ++i) {
        if (inlier[i]) paired.push_back(index[i][0]);
      }
      AddFineNormals(paired, options, threads, target_scan);
      for (int i = 0; i < n; ++i) {
        inlier[i] = inlier[i] && target_scan->fine_normal[index[i][0]] == 1;
      }
    }

    Eigen::Matrix4d step = Eigen::Matrix4d::Identity();
    double squared_error = 0.0;
    int count = 0;
    if (options.point_to_plane) {
      // Normal equations, summed per thread and then in thread order (deterministic).
      using Matrix6 = Eigen::Matrix<double, 6, 6>;
      using Vector6 = Eigen::Matrix<double, 6, 1>;
      const int teams = n > 2048 ? threads : 1;
      std::vector<Matrix6> Hs(teams, Matrix6::Zero());
      std::vector<Vector6> gs(teams, Vector6::Zero());
      std::vector<double> errors(teams, 0.0);
      std::vector<int> counts(teams, 0);
#pragma omp parallel for num_threads(teams) schedule(static, 1)
      for (int team = 0; team < teams; ++team) {
        for (int i = int(std::int64_t(n) * team / teams);
             i < int(std::int64_t(n) * (team + 1) / teams); ++i) {
          if (!inlier[i]) continue;
          const PointN& q = target[index[i][0]];
          const Eigen::Vector3d p = moved[i].getVector3fMap().cast<double>();
          const Eigen::Vector3d normal = q.getNormalVector3fMap().cast<double>();
          const double r = normal.dot(p - q.getVector3fMap().cast<double>());
          Vector6 J;
          J << p.cross(normal), normal;
          Hs[team].selfadjointView<Eigen::Upper>().rankUpdate(J);
          gs[team] += J * r;
          errors[team] += r * r;
          ++counts[team];
        }
      }
      Matrix6 H = Matrix6::Zero();
      Vector6 g = Vector6::Zero();
      for (int team = 0; team < teams; ++team) {
        H += Hs[team];
        g += gs[team];
        squared_error += errors[team];
        count += counts[team];
      }
      if (count < 6) break;
      H.triangularView<Eigen::Lower>() = H.transpose();
      const Vector6 delta = H.ldlt().solve(-g);
      if (!delta.allFinite()) break;
      const double angle = delta.head<3>().norm();
      if (angle > 0) {
        step.topLeftCorner<3, 3>() =
            Eigen::AngleAxisd(angle, delta.head<3>() / angle).toRotationMatrix();
      }
      step.topRightCorner<3, 1>() = delta.tail<3>();
    } else {
      Eigen::Matrix3Xf from(3, n), to(3, n);
      for (int i = 0; i < n; ++i) {
        if (!inlier[i]) continue;
        from.col(count) = moved[i].getVector3fMap();
        to.col(count) = target[index[i][0]].getVector3fMap();
        squared_error += dist2[i][0];
        ++count;
      }
      if (count < 3) break;
      step = Eigen::umeyama(from.leftCols(count), to.leftCols(count), false).cast<double>();
      if (!step.allFinite()) break;
    }
    *transform = (step * transform->cast<double>()).cast<float>();
    ++result->iterations;

    // Converged when a step is small, or when the last two steps cancel out (the iterations
    // alternate between two correspondence sets), or when the error stops changing.
    const auto small = [&](const Eigen::Matrix4d& T) {
      const double rotation = Eigen::AngleAxisd(Eigen::Matrix3d(T.topLeftCorner<3, 3>())).angle();
      const double translation = T.topRightCorner<3, 1>().norm();
      return rotation * rotation <= options.icp_transformation_epsilon &&
             translation * translation <= options.icp_transformation_epsilon;
    };
    const bool cycle = iteration > 0 && small(step * previous_step);
    previous_step = step;
    const double mse = squared_error / count;
    if (small(step) || cycle || std::abs(previous_mse - mse) <= options.icp_fitness_epsilon) {
      result->converged = true;
      break;
    }
    previous_mse = mse;
  }
}

// Coarse-to-fine ICP from `guess`, each level on an even thinning of the source.
Eigen::Matrix4f FineAlign(const Prepared& source, Prepared* target, Eigen::Matrix4f guess,
                          const RegistrationOptions& options, RegistrationResult* result) {
  if (options.icp_iterations_coarse > 0) {
    const CloudN coarse(*source.coarse,
                        *Thinned(source.coarse->size(), options.icp_source_points_coarse));
    IcpLevel(coarse, target, false, options.icp_max_corr_coarse_m, options.icp_iterations_coarse,
             options, &guess, result);
  }
  const CloudN fine(*source.fine, *Thinned(source.fine->size(), options.icp_source_points_fine));
  IcpLevel(fine, target, true, options.icp_max_corr_fine_m, options.icp_iterations_fine, options,
           &guess, result);
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
    CheckVoxelCount(*tgt, resolutions[level],
                    level == 0 ? "ndt_resolution_m" : "ndt_resolution_m / 2", "target");
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
// Fitness and inlier RMSE of the fine source points under `transform`. On the evenly thinned
// subset that fine ICP aligns (icp_source_points_fine), an unbiased estimate at a fraction of
// the nearest-neighbour queries.
void Score(const Prepared& source, const Prepared& target, const Eigen::Matrix4f& transform,
           double inlier_m, const RegistrationOptions& options, RegistrationResult* result) {
  const pcl::IndicesPtr subset = Thinned(source.fine->size(), options.icp_source_points_fine);
  CloudN moved;
  moved.reserve(subset->size());
  for (pcl::index_t i : *subset) {
    PointN p = (*source.fine)[i];
    p.getVector3fMap() =
        transform.topLeftCorner<3, 3>() * p.getVector3fMap() + transform.topRightCorner<3, 1>();
    moved.push_back(p);
  }
  std::vector<pcl::Indices> index;
  std::vector<std::vector<float>> dist2;
  NearestK(*target.fine_tree, moved, 1, Threads(options), &index, &dist2);
  std::size_t inliers = 0;
  double sum2 = 0.0;
  for (const auto& d : dist2) {
    if (!d.empty() && d[0] <= inlier_m * inlier_m) {
      ++inliers;
      sum2 += d[0];
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
  SLSLAM_CHECK(min_range_m >= 0, "min_range_m must be >= 0, got ", min_range_m);
  SLSLAM_CHECK(max_range_m <= 0 || max_range_m > min_range_m,
               "max_range_m must be <= 0 (no limit) or > min_range_m, got ", max_range_m);
  SLSLAM_CHECK(fine_voxel_m > 0, "fine_voxel_m must be > 0, got ", fine_voxel_m);
  SLSLAM_CHECK(coarse_voxel_m >= fine_voxel_m, "coarse_voxel_m must be >= fine_voxel_m, got ",
               coarse_voxel_m);
  SLSLAM_CHECK(outlier_k >= 0, "outlier_k must be >= 0, got ", outlier_k);
  SLSLAM_CHECK(outlier_std_mul > 0, "outlier_std_mul must be > 0, got ", outlier_std_mul);
  SLSLAM_CHECK(normal_k >= 3, "normal_k must be >= 3, got ", normal_k);
  SLSLAM_CHECK(feature_radius_m > coarse_voxel_m, "feature_radius_m must be > coarse_voxel_m, got ",
               feature_radius_m);
  SLSLAM_CHECK(sac_ia_iterations >= 1, "sac_ia_iterations must be >= 1, got ", sac_ia_iterations);
  SLSLAM_CHECK(sac_ia_samples >= 3, "sac_ia_samples must be >= 3, got ", sac_ia_samples);
  SLSLAM_CHECK(sac_ia_source_keypoints >= 0, "sac_ia_source_keypoints must be >= 0, got ",
               sac_ia_source_keypoints);
  SLSLAM_CHECK(sac_ia_randomness >= 1, "sac_ia_randomness must be >= 1, got ", sac_ia_randomness);
  SLSLAM_CHECK(sac_ia_min_sample_m >= 0, "sac_ia_min_sample_m must be >= 0, got ",
               sac_ia_min_sample_m);
  SLSLAM_CHECK(sac_ia_max_corr_m > 0, "sac_ia_max_corr_m must be > 0, got ", sac_ia_max_corr_m);
  SLSLAM_CHECK(sac_ia_edge_similarity >= 0 && sac_ia_edge_similarity < 1,
               "sac_ia_edge_similarity must be in [0, 1), got ", sac_ia_edge_similarity);
  SLSLAM_CHECK(sac_ia_confidence > 0 && sac_ia_confidence <= 1,
               "sac_ia_confidence must be in (0, 1], got ", sac_ia_confidence);
  SLSLAM_CHECK(icp_source_points_coarse >= 0, "icp_source_points_coarse must be >= 0, got ",
               icp_source_points_coarse);
  SLSLAM_CHECK(icp_source_points_fine >= 0, "icp_source_points_fine must be >= 0, got ",
               icp_source_points_fine);
  SLSLAM_CHECK(icp_iterations_coarse >= 0, "icp_iterations_coarse must be >= 0, got ",
               icp_iterations_coarse);
  SLSLAM_CHECK(icp_iterations_fine >= 1, "icp_iterations_fine must be >= 1, got ",
               icp_iterations_fine);
  SLSLAM_CHECK(icp_max_corr_coarse_m > 0, "icp_max_corr_coarse_m must be > 0, got ",
               icp_max_corr_coarse_m);
  SLSLAM_CHECK(icp_max_corr_fine_m > 0, "icp_max_corr_fine_m must be > 0, got ",
               icp_max_corr_fine_m);
  SLSLAM_CHECK(icp_transformation_epsilon >= 0, "icp_transformation_epsilon must be >= 0, got ",
               icp_transformation_epsilon);
  SLSLAM_CHECK(icp_fitness_epsilon >= 0, "icp_fitness_epsilon must be >= 0, got ",
               icp_fitness_epsilon);
  SLSLAM_CHECK(ndt_resolution_m > 0, "ndt_resolution_m must be > 0, got ", ndt_resolution_m);
  SLSLAM_CHECK(ndt_step_m > 0, "ndt_step_m must be > 0, got ", ndt_step_m);
  SLSLAM_CHECK(ndt_iterations >= 1, "ndt_iterations must be >= 1, got ", ndt_iterations);
  SLSLAM_CHECK(num_threads >= 0, "num_threads must be >= 0, got ", num_threads);
  // Every real-valued option finite: an infinite voxel or radius leaves one point, or makes every
  // point a neighbour of every other. Counts bounded where they size work or memory.
  const std::pair<const char*, double> reals[] = {
      {"min_range_m", min_range_m},
      {"max_range_m", max_range_m},
      {"fine_voxel_m", fine_voxel_m},
      {"coarse_voxel_m", coarse_voxel_m},
      {"outlier_std_mul", outlier_std_mul},
      {"feature_radius_m", feature_radius_m},
      {"sac_ia_min_sample_m", sac_ia_min_sample_m},
      {"sac_ia_max_corr_m", sac_ia_max_corr_m},
      {"icp_max_corr_coarse_m", icp_max_corr_coarse_m},
      {"icp_max_corr_fine_m", icp_max_corr_fine_m},
      {"icp_transformation_epsilon", icp_transformation_epsilon},
      {"icp_fitness_epsilon", icp_fitness_epsilon},
      {"ndt_resolution_m", ndt_resolution_m},
      {"ndt_step_m", ndt_step_m}};
  for (const auto& [option, value] : reals) CheckFinite(option, value);
  CheckInRange("outlier_k", outlier_k, 0, 10000);
  CheckInRange("normal_k", normal_k, 3, 10000);
  CheckInRange("sac_ia_samples", sac_ia_samples, 3, 10000);
  CheckInRange("sac_ia_randomness", sac_ia_randomness, 1, 10000);
  CheckInRange("num_threads", num_threads, 0, 4096);
}

void CheckPoints(const PointMatrix& points, const std::string& name, int min_points) {
  SLSLAM_CHECK(points.cols() == 3 || points.cols() == 4, name,
               ": expected an N x 3 or N x 4 matrix (x, y, z[, intensity]), got ", points.rows(),
               " x ", points.cols());
  SLSLAM_CHECK(points.rows() >= min_points, name, ": ", points.rows(), " points, need at least ",
               min_points);
  SLSLAM_CHECK(points.allFinite(), name, ": contains NaN or infinite values");
}

RegistrationResult RegisterClouds(const PointMatrix& source, const PointMatrix& target,
                                  const RegistrationOptions& options, Method method) {
  const Clock::time_point start = Clock::now();
  options.Check();
  CheckPoints(source, "source");
  CheckPoints(target, "target");
  RegistrationResult result;

  Clock::time_point stage = Clock::now();
  const int threads = Threads(options);
  const bool concurrent = threads >= 2;  // one thread per scan
  auto [src, tgt] = Both(
      concurrent, [&] { return Preprocess(source, options, false, 1, "source"); },
      [&] { return Preprocess(target, options, true, 1, "target"); });
  result.preprocess_ms = MsSince(stage);
  result.source_points = static_cast<int>(src.fine->size());
  result.source_keypoints = static_cast<int>(src.coarse->size());
  result.target_points = static_cast<int>(tgt.fine->size());
  result.target_keypoints = static_cast<int>(tgt.coarse->size());

  Eigen::Matrix4f guess = Eigen::Matrix4f::Identity();
  if (method == Method::kFpfhSacIaIcp || method == Method::kPfhSacIaIcp) {
    stage = Clock::now();
    const pcl::IndicesPtr keys = Thinned(src.coarse->size(), options.sac_ia_source_keypoints);
    const pcl::IndicesPtr all = Thinned(tgt.coarse->size(), 0);
    const int per_scan = concurrent ? 1 : threads;
    if (method == Method::kFpfhSacIaIcp) {
      const auto [fs, ft] = Both(
          concurrent, [&] { return Fpfh(src, *keys, options, per_scan); },
          [&] { return Fpfh(tgt, *all, options, per_scan); });
      result.features_ms = MsSince(stage);
      stage = Clock::now();
      guess = CoarseAlign(src, *keys, tgt, *fs, *ft, options);
    } else {
      const auto [fs, ft] = Both(
          concurrent, [&] { return Pfh(src, keys, options); },
          [&] { return Pfh(tgt, all, options); });
      result.features_ms = MsSince(stage);
      stage = Clock::now();
      guess = CoarseAlign(src, *keys, tgt, *fs, *ft, options);
    }
    result.coarse_ms = MsSince(stage);
  }

  stage = Clock::now();
  const Eigen::Matrix4f transform = method == Method::kNdt
                                        ? NdtAlign(src, tgt, options, &result)
                                        : FineAlign(src, &tgt, guess, options, &result);
  result.fine_ms = MsSince(stage);

  Score(src, tgt, transform, options.icp_max_corr_fine_m, options, &result);
  result.transform = transform.cast<double>();
  result.total_ms = MsSince(start);
  return result;
}

}  // namespace slslam::lidar
