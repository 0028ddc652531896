// Preprocessing of one scan for registration (registration_internal.h): range crop, voxel
// pyramid, statistical outlier removal, normals.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <tuple>
#include <unordered_map>
#include <vector>

#include <pcl/common/centroid.h>
#include <pcl/common/io.h>
#include <pcl/features/feature.h>
#include <pcl/features/normal_3d.h>
#include <pcl/filters/voxel_grid.h>
#include <Eigen/Core>

#include "slslam/core/check.h"
#include "slslam/lidar/registration_internal.h"

namespace slslam::lidar::registration_detail {
namespace {

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

}  // namespace

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

}  // namespace slslam::lidar::registration_detail
