#include "slslam/lidar/voxel_map.h"

#include <algorithm>
#include <cmath>
#include <unordered_set>

#include <Eigen/Eigenvalues>

#include "slslam/core/check.h"

namespace slslam::lidar {

void VoxelMapOptions::Check() const {
  SLSLAM_CHECK(voxel_m > 0.01 && voxel_m <= 10.0,
               "VoxelMapOptions.voxel_m must be in (0.01, 10] m, got ", voxel_m);
  SLSLAM_CHECK(max_points_per_voxel >= 1 && max_points_per_voxel <= 1000,
               "VoxelMapOptions.max_points_per_voxel must be in [1, 1000], got ",
               max_points_per_voxel);
  SLSLAM_CHECK(min_point_spacing_m >= 0 && min_point_spacing_m < voxel_m,
               "VoxelMapOptions.min_point_spacing_m must be in [0, voxel_m), got ",
               min_point_spacing_m);
  SLSLAM_CHECK(max_distance_m > voxel_m, "VoxelMapOptions.max_distance_m must exceed voxel_m, got ",
               max_distance_m);
}

VoxelMap::VoxelMap(const VoxelMapOptions& options) : options_(options) { options_.Check(); }

Eigen::Vector3i VoxelMap::VoxelOf(const Eigen::Vector3d& p) const {
  return (p / options_.voxel_m).array().floor().cast<int>();
}

void VoxelMap::Add(const std::vector<Eigen::Vector3d>& points_world) {
  const size_t cap = static_cast<size_t>(options_.max_points_per_voxel);
  const double min2 = options_.min_point_spacing_m * options_.min_point_spacing_m;
  for (const Eigen::Vector3d& p : points_world) {
    auto& voxel = voxels_[VoxelOf(p)];
    if (voxel.size() >= cap) continue;
    const bool crowded = std::any_of(voxel.begin(), voxel.end(), [&](const Eigen::Vector3d& q) {
      return (q - p).squaredNorm() < min2;
    });
    if (!crowded) voxel.push_back(p);
  }
}

void VoxelMap::RemoveFar(const Eigen::Vector3d& origin_world) {
  const double max2 = options_.max_distance_m * options_.max_distance_m;
  for (auto it = voxels_.begin(); it != voxels_.end();) {
    if (it->second.empty() || (it->second.front() - origin_world).squaredNorm() > max2) {
      it = voxels_.erase(it);
    } else {
      ++it;
    }
  }
}

size_t VoxelMap::num_points() const {
  size_t n = 0;
  for (const auto& [key, voxel] : voxels_) n += voxel.size();
  return n;
}

std::vector<Eigen::Vector3d> VoxelMap::Points() const {
  std::vector<Eigen::Vector3d> out;
  out.reserve(num_points());
  for (const auto& [key, voxel] : voxels_) out.insert(out.end(), voxel.begin(), voxel.end());
  return out;
}

namespace {
// Middle / largest eigenvalue of a plane's neighbours at least this: they span two directions.
constexpr double kMinSpread = 0.05;
}  // namespace

bool VoxelMap::FitPlane(const Eigen::Vector3d& query, int k, double max_distance_m,
                        double max_thickness_m, LocalPlane* plane) const {
  constexpr int kMaxNeighbours = 16;
  k = std::min(k, kMaxNeighbours);
  // The k nearest points, kept sorted by distance in a small fixed array.
  std::pair<double, const Eigen::Vector3d*> best[kMaxNeighbours];
  int found = 0;
  const double max2 = max_distance_m * max_distance_m;
  // The 27 voxels around the query: neighbours up to one voxel edge away are all found.
  VisitNeighbourhood(query, [&](const Eigen::Vector3d& p) {
    const double d2 = (p - query).squaredNorm();
    if (d2 > max2 || (found == k && d2 >= best[k - 1].first)) return;
    int i = found < k ? found++ : k - 1;
    while (i > 0 && best[i - 1].first > d2) {
      best[i] = best[i - 1];
      --i;
    }
    best[i] = {d2, &p};
  });
  if (found < k || k < 3) return false;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int i = 0; i < k; ++i) mean += *best[i].second;
  mean /= k;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int i = 0; i < k; ++i) {
    const Eigen::Vector3d d = *best[i].second - mean;
    cov += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(cov);
  const Eigen::Vector3d lambda = eig.eigenvalues();  // ascending
  // A plane, not a line: the neighbours of a sparse LiDAR often lie on one scan ring, and a
  // "plane" through a ring pulls the next sweep's ring onto it (a bias towards no motion).
  if (!(lambda(1) >= kMinSpread * lambda(2))) return false;
  const Eigen::Vector3d normal = eig.eigenvectors().col(0);
  // Flat in absolute terms: every neighbour within max_thickness_m of the plane. A relative
  // test (smallest / middle eigenvalue) rejected most planes of a small neighbourhood with
  // range noise (2 cm noise over a 0.1 m patch) and kept the wide, ring-shaped ones, which
  // measured biased along a corridor's axis (1.1 cm mean, 1.6 cm RMS against 0.3 cm RMS here,
  // ground-truth map of the simulated straight corridor).
  for (int i = 0; i < k; ++i) {
    if (std::abs(normal.dot(*best[i].second - mean)) > max_thickness_m) return false;
  }
  plane->normal = normal;
  // Through the neighbours' mean: unbiased on a flat patch; on a curved roof the mean lies off
  // the surface by the sagitta, under 5 mm for the few-neighbour patches (< 0.3 m) used here.
  plane->centre = mean;
  return true;
}

bool VoxelMap::Nearest(const Eigen::Vector3d& query, double max_distance_m,
                       Eigen::Vector3d* nearest) const {
  double best = max_distance_m * max_distance_m;
  const Eigen::Vector3d* found = nullptr;
  VisitNeighbourhood(query, [&](const Eigen::Vector3d& p) {
    const double d2 = (p - query).squaredNorm();
    if (d2 < best) {
      best = d2;
      found = &p;
    }
  });
  if (found) *nearest = *found;
  return found != nullptr;
}

std::vector<Eigen::Vector3d> VoxelDownsample(const std::vector<Eigen::Vector3d>& points,
                                             double voxel_m) {
  SLSLAM_CHECK(voxel_m > 0, "voxel size must be > 0 m, got ", voxel_m);
  std::unordered_set<Eigen::Vector3i, VoxelKeyHash> seen;
  seen.reserve(points.size());
  std::vector<Eigen::Vector3d> out;
  out.reserve(points.size() / 4);
  for (const Eigen::Vector3d& p : points) {
    if (seen.insert((p / voxel_m).array().floor().cast<int>()).second) out.push_back(p);
  }
  return out;
}

}  // namespace slslam::lidar
