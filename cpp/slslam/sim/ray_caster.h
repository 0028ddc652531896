// Ray casting against triangle meshes with Intel Embree (packets of 16 coherent camera rays).
//
// The simulator's hot path: every pixel of both cameras and every LiDAR beam is one ray. Open3D's
// RaycastingScene (also Embree) casts single rays and returns more than the simulator needs;
// casting 4x4 pixel packets with the coherent-ray flag here is several times faster.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>

namespace slslam::sim {

// Per-ray results, all of length N (N x 3 for vectors, row-major).
struct RayHits {
  std::vector<float> t;       ///< distance along the unit direction [m]; +inf where nothing is hit
  std::vector<float> normal;  ///< unit geometric normal (world), facing either way; 0 on a miss
  std::vector<float> point;   ///< hit point (world) [m]; the ray origin on a miss
  std::vector<uint8_t> material;  ///< material id of the hit triangle; 255 on a miss

  void Resize(std::size_t n);
  std::size_t size() const { return t.size(); }
};

// A static triangle mesh prepared for ray casting (the BVH is built once, in the constructor).
class RayCaster {
 public:
  using Vertices = Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor>;
  using Triangles = Eigen::Matrix<uint32_t, Eigen::Dynamic, 3, Eigen::RowMajor>;

  // `material` holds one id per triangle. Throws std::invalid_argument on an empty mesh, indices
  // out of range, non-finite vertices or a material count that differs from the triangle count.
  RayCaster(const Vertices& vertices, const Triangles& triangles, std::vector<uint8_t> material);
  ~RayCaster();
  RayCaster(const RayCaster&) = delete;
  RayCaster& operator=(const RayCaster&) = delete;

  std::size_t num_triangles() const { return material_.size(); }

  // Casts rays from one origin along unit `directions` (N x 3, world).
  RayHits Cast(const Eigen::Vector3f& origin, const Vertices& directions,
               const RayCaster* dynamic = nullptr) const;

  // Casts one ray per pixel of a pinhole camera at pose (R_world_cam, origin): pixel (u, v) looks
  // along R_world_cam * normalize((u - cx) / fx, (v - cy) / fy, 1). Results are row-major over
  // pixels. `depth` (optional, N) receives the z distance in the camera frame [m] (+inf on a
  // miss). `dynamic`, when given, is a second mesh (moving objects); the nearer hit wins.
  RayHits CastPinhole(const Eigen::Matrix3d& R_world_cam, const Eigen::Vector3d& origin, double fx,
                      double fy, double cx, double cy, int width, int height,
                      const RayCaster* dynamic = nullptr,
                      std::vector<float>* depth = nullptr) const;

 private:
  struct Embree;
  struct Packet;
  // Intersects one packet with this mesh and `dynamic` (if any); the nearer hit wins. Writes t,
  // normal, material and point of the packet's valid lanes into `hits`.
  void IntersectPacket(const Packet& packet, const Eigen::Vector3f& origin,
                       const RayCaster* dynamic, RayHits* hits) const;

  std::unique_ptr<Embree> embree_;
  std::vector<uint8_t> material_;
};

}  // namespace slslam::sim
