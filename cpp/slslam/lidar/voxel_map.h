// The local map of LiDAR odometry: points in a hash of voxels, each voxel holding a bounded number
// of points, and voxels far from the sensor dropped, so memory and query time stay bounded on runs
// of any length (the voxel-hash map of KISS-ICP, Vizzo et al. 2023, with plane fits for
// point-to-plane matching).
#pragma once

#include <cstdint>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

namespace slslam::lidar {

struct VoxelMapOptions {
  double voxel_m = 0.5;              ///< voxel edge [m]
  int max_points_per_voxel = 20;     ///< a full voxel takes no more points [-]
  double min_point_spacing_m = 0.1;  ///< a point nearer than this to one already in its voxel
                                     ///< is not added: repeated sweeps from one place would
                                     ///< stack copies that make plane fits degenerate [m]
  double max_distance_m = 100.0;     ///< voxels farther than this from the sensor are dropped
                                     ///< [m]; at least the odometry's max_range_m, or what the
                                     ///< sensor sees far away has nothing to match
  void Check() const;
};

// A plane through a point's neighbourhood: unit normal (of the neighbours' covariance) and a
// point on it (the neighbours' mean).
struct LocalPlane {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
};

// Hash of integer voxel coordinates: large primes (Teschner et al. 2003).
struct VoxelKeyHash {
  size_t operator()(const Eigen::Vector3i& v) const {
    return static_cast<size_t>(v.x()) * 73856093u ^ static_cast<size_t>(v.y()) * 19349669u ^
           static_cast<size_t>(v.z()) * 83492791u;
  }
};

class VoxelMap {
 public:
  explicit VoxelMap(const VoxelMapOptions& options = {});

  // Adds world points (N x 3, m); points beyond a full voxel, or within min_point_spacing_m of
  // a point of their voxel, are ignored.
  void Add(const std::vector<Eigen::Vector3d>& points_world);
  // Drops voxels whose first point is farther than max_distance_m from `origin_world`.
  void RemoveFar(const Eigen::Vector3d& origin_world);
  void Clear() { voxels_.clear(); }

  // Plane fitted to the `k` map points nearest `query` within `max_distance_m` of it, searched in
  // the 27 voxels around it (so at most about one voxel edge away), through their mean. False
  // when fewer than `k` points are near, the neighbours lie on a line, or one of them is farther
  // than `max_thickness_m` from the plane.
  bool FitPlane(const Eigen::Vector3d& query, int k, double max_distance_m, double max_thickness_m,
                LocalPlane* plane) const;

  // Nearest map point to `query` within `max_distance_m`, searched in the 27 voxels around it.
  bool Nearest(const Eigen::Vector3d& query, double max_distance_m, Eigen::Vector3d* nearest) const;

  size_t num_voxels() const { return voxels_.size(); }
  size_t num_points() const;
  std::vector<Eigen::Vector3d> Points() const;
  const VoxelMapOptions& options() const { return options_; }

 private:
  Eigen::Vector3i VoxelOf(const Eigen::Vector3d& p) const;
  // Calls visit(point) for every map point in the 27 voxels around `query`'s voxel.
  template <typename Visit>
  void VisitNeighbourhood(const Eigen::Vector3d& query, Visit&& visit) const {
    const Eigen::Vector3i centre = VoxelOf(query);
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = voxels_.find(centre + Eigen::Vector3i(dx, dy, dz));
          if (it == voxels_.end()) continue;
          for (const Eigen::Vector3d& p : it->second) visit(p);
        }
      }
    }
  }

  VoxelMapOptions options_;
  std::unordered_map<Eigen::Vector3i, std::vector<Eigen::Vector3d>, VoxelKeyHash> voxels_;
};

// First point per voxel of edge `voxel_m` (order kept), like a voxel grid without averaging.
std::vector<Eigen::Vector3d> VoxelDownsample(const std::vector<Eigen::Vector3d>& points,
                                             double voxel_m);

}  // namespace slslam::lidar
