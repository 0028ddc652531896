#include "slslam/sim/ray_caster.h"

#include <embree3/rtcore.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "slslam/core/check.h"

namespace slslam::sim {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr uint8_t kNoHit = 255;
constexpr int kPacket = 16;   // rays per Embree packet (rtcIntersect16)
constexpr int kTileSide = 4;  // pixel tiles of 4 x 4 = one packet

void ThrowOnDeviceError(RTCDevice device, const char* what) {
  const RTCError error = rtcGetDeviceError(device);
  if (error != RTC_ERROR_NONE) {
    throw std::runtime_error(Message("Embree failed while ", what, " (error ", int(error), ")"));
  }
}

}  // namespace

void RayHits::Resize(std::size_t n) {
  t.assign(n, kInf);
  normal.assign(3 * n, 0.0f);
  point.assign(3 * n, 0.0f);
  material.assign(n, kNoHit);
}

struct RayCaster::Embree {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  ~Embree() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
};

RayCaster::RayCaster(const Vertices& vertices, const Triangles& triangles,
                     std::vector<uint8_t> material)
    : embree_(std::make_unique<Embree>()), material_(std::move(material)) {
  Require(triangles.rows() > 0, "the mesh has no triangles");
  SLSLAM_CHECK(static_cast<Eigen::Index>(material_.size()) == triangles.rows(), "material has ",
               material_.size(), " entries for ", triangles.rows(), " triangles");
  Require(vertices.allFinite(), "mesh vertices contain NaN or Inf");
  SLSLAM_CHECK(triangles.maxCoeff() < static_cast<uint32_t>(vertices.rows()), "a triangle index (",
               triangles.maxCoeff(), ") is out of range for ", vertices.rows(), " vertices");

  embree_->device = rtcNewDevice(nullptr);
  if (!embree_->device) throw std::runtime_error("could not create an Embree device");
  embree_->scene = rtcNewScene(embree_->device);
  rtcSetSceneBuildQuality(embree_->scene, RTC_BUILD_QUALITY_HIGH);
  RTCGeometry geometry = rtcNewGeometry(embree_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
  // Embree reads vertex buffers 16 bytes at a time: the shared buffers it allocates are padded.
  auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(
      geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), vertices.rows()));
  auto* f = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0,
                                                           RTC_FORMAT_UINT3, 3 * sizeof(uint32_t),
                                                           triangles.rows()));
  ThrowOnDeviceError(embree_->device, "allocating mesh buffers");
  std::copy(vertices.data(), vertices.data() + vertices.size(), v);
  std::copy(triangles.data(), triangles.data() + triangles.size(), f);
  rtcCommitGeometry(geometry);
  rtcAttachGeometry(embree_->scene, geometry);
  rtcReleaseGeometry(geometry);
  rtcCommitScene(embree_->scene);
  ThrowOnDeviceError(embree_->device, "building the BVH");
}

RayCaster::~RayCaster() = default;

namespace {

// Intersects one packet with `scene` and keeps, per lane, the nearer of the packet's hit and the
// hit already recorded in `hits` at `index[lane]`.
void IntersectWith(RTCScene scene, const std::vector<uint8_t>& material, RTCRayHit16& rh,
                   const int* valid, const int* index, RayHits* hits) {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  rtcIntersect16(valid, scene, &context, &rh);
  for (int lane = 0; lane < kPacket; ++lane) {
    if (!valid[lane] || rh.hit.geomID[lane] == RTC_INVALID_GEOMETRY_ID) continue;
    const std::size_t i = static_cast<std::size_t>(index[lane]);
    const float t = rh.ray.tfar[lane];
    if (!(t < hits->t[i])) continue;
    hits->t[i] = t;
    Eigen::Vector3f n(rh.hit.Ng_x[lane], rh.hit.Ng_y[lane], rh.hit.Ng_z[lane]);
    n.normalize();
    hits->normal[3 * i + 0] = n.x();
    hits->normal[3 * i + 1] = n.y();
    hits->normal[3 * i + 2] = n.z();
    hits->material[i] = material[rh.hit.primID[lane]];
  }
}

void ResetPacket(RTCRayHit16& rh) {
  for (int lane = 0; lane < kPacket; ++lane) {
    rh.ray.tnear[lane] = 0.0f;
    rh.ray.tfar[lane] = kInf;
    rh.ray.time[lane] = 0.0f;
    rh.ray.mask[lane] = 0xFFFFFFFFu;
    rh.ray.id[lane] = static_cast<unsigned>(lane);
    rh.ray.flags[lane] = 0;
    rh.hit.geomID[lane] = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0][lane] = RTC_INVALID_GEOMETRY_ID;
  }
}

void SetLane(RTCRayHit16& rh, int lane, const Eigen::Vector3f& o, const Eigen::Vector3f& d) {
  rh.ray.org_x[lane] = o.x();
  rh.ray.org_y[lane] = o.y();
  rh.ray.org_z[lane] = o.z();
  rh.ray.dir_x[lane] = d.x();
  rh.ray.dir_y[lane] = d.y();
  rh.ray.dir_z[lane] = d.z();
}

void FillPoints(const Eigen::Vector3f& origin, const float* directions, RayHits* hits,
                std::size_t i) {
  const float t = std::isfinite(hits->t[i]) ? hits->t[i] : 0.0f;
  for (int k = 0; k < 3; ++k) hits->point[3 * i + k] = origin[k] + t * directions[k];
}

}  // namespace

struct RayCaster::Packet {
  alignas(64) int valid[kPacket];  // -1: lane in use (Embree's convention), 0: unused
  int index[kPacket];              // ray index of each lane (0 for unused lanes)
  Eigen::Vector3f direction[kPacket];
};

void RayCaster::IntersectPacket(const Packet& packet, const Eigen::Vector3f& origin,
                                const RayCaster* dynamic, RayHits* hits) const {
  alignas(64) RTCRayHit16 rh;
  for (const RayCaster* caster : {this, dynamic}) {
    if (caster == nullptr) continue;
    ResetPacket(rh);
    for (int lane = 0; lane < kPacket; ++lane) SetLane(rh, lane, origin, packet.direction[lane]);
    IntersectWith(caster->embree_->scene, caster->material_, rh, packet.valid, packet.index, hits);
  }
  for (int lane = 0; lane < kPacket; ++lane) {
    if (packet.valid[lane]) {
      FillPoints(origin, packet.direction[lane].data(), hits, packet.index[lane]);
    }
  }
}

RayHits RayCaster::Cast(const Eigen::Vector3f& origin, const Vertices& directions,
                        const RayCaster* dynamic) const {
  Require(origin.allFinite(), "ray origin contains NaN or Inf");
  const std::size_t n = static_cast<std::size_t>(directions.rows());
  RayHits hits;
  hits.Resize(n);
  const std::ptrdiff_t packets = static_cast<std::ptrdiff_t>((n + kPacket - 1) / kPacket);
#pragma omp parallel for schedule(dynamic, 64)
  for (std::ptrdiff_t p = 0; p < packets; ++p) {
    Packet packet;
    for (int lane = 0; lane < kPacket; ++lane) {
      const std::size_t i = static_cast<std::size_t>(p) * kPacket + lane;
      packet.valid[lane] = i < n ? -1 : 0;
      packet.index[lane] = static_cast<int>(i < n ? i : 0);
      packet.direction[lane] = directions.row(i < n ? i : 0).transpose();
    }
    IntersectPacket(packet, origin, dynamic, &hits);
  }
  return hits;
}

RayHits RayCaster::CastPinhole(const Eigen::Matrix3d& R_world_cam, const Eigen::Vector3d& origin,
                               double fx, double fy, double cx, double cy, int width, int height,
                               const RayCaster* dynamic, std::vector<float>* depth) const {
  SLSLAM_CHECK(width > 0 && height > 0, "image size must be positive, got ", width, "x", height);
  Require(fx > 0 && fy > 0, "focal lengths must be > 0");
  Require(R_world_cam.allFinite() && origin.allFinite(), "camera pose contains NaN or Inf");
  const std::size_t n = static_cast<std::size_t>(width) * height;
  RayHits hits;
  hits.Resize(n);
  std::vector<float> direction_z(n, 0.0f);  // z of the unit ray in the camera frame
  const Eigen::Matrix3f R = R_world_cam.cast<float>();
  const Eigen::Vector3f o = origin.cast<float>();
  const int tiles_x = (width + kTileSide - 1) / kTileSide;
  const int tiles_y = (height + kTileSide - 1) / kTileSide;
#pragma omp parallel for schedule(dynamic, 16)
  for (int tile = 0; tile < tiles_x * tiles_y; ++tile) {
    const int u0 = (tile % tiles_x) * kTileSide, v0 = (tile / tiles_x) * kTileSide;
    Packet packet;
    for (int lane = 0; lane < kPacket; ++lane) {
      const int u = u0 + lane % kTileSide, v = v0 + lane / kTileSide;
      const bool inside = u < width && v < height;
      const std::size_t i = inside ? static_cast<std::size_t>(v) * width + u : 0;
      packet.valid[lane] = inside ? -1 : 0;
      packet.index[lane] = static_cast<int>(i);
      Eigen::Vector3f d_cam(static_cast<float>((u - cx) / fx), static_cast<float>((v - cy) / fy),
                            1.0f);
      d_cam.normalize();
      packet.direction[lane] = R * d_cam;
      if (inside) direction_z[i] = d_cam.z();
    }
    IntersectPacket(packet, o, dynamic, &hits);
  }
  if (depth != nullptr) {
    depth->resize(n);
    for (std::size_t i = 0; i < n; ++i) (*depth)[i] = hits.t[i] * direction_z[i];
  }
  return hits;
}

}  // namespace slslam::sim
