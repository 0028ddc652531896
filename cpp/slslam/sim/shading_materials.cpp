// The materials' solid textures (shading.h: SurfaceAlbedo, SolidTexture). Albedos are tuned for
// mid-gray rock (~0.3) and are clamped to [0.01, 0.98].
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>

#include "slslam/core/check.h"
#include "slslam/sim/shading.h"
#include "slslam/sim/shading_internal.h"

namespace slslam::sim {
namespace {

using shading_detail::Fbm;
using shading_detail::GradientNoise;
using shading_detail::GridDistance;
using shading_detail::HashCell;
using shading_detail::kPi;
using shading_detail::Load3;
using shading_detail::RequireKnownMaterials;
using shading_detail::Vec3;

constexpr uint8_t kMaxMaterialId = static_cast<uint8_t>(Material::kCart);

float RockAlbedo(const Vec3& p, float fp) {
  const float tone = GradientNoise(p * 0.35f, 11u);     // metre-scale patches
  const float detail = Fbm(p, 2.0f, 4, 0.6f, 12u, fp);  // multi-scale grain
  float a = 0.30f + 0.35f * tone + 0.9f * detail;
  const float crack = std::abs(GradientNoise(p * 2.2f, 13u));  // thin dark fissures
  if (crack < 0.035f) a *= 0.35f + 0.65f * crack / 0.035f;
  return a;
}

float CoalAlbedo(const Vec3& p, float fp) {
  const float warp = 2.5f * Fbm(p, 0.7f, 2, 0.5f, 21u, fp);
  const float bedding = std::sin(2.0f * kPi * p.z() / 0.07f + warp);  // horizontal streaks
  const float fine = std::sin(2.0f * kPi * p.z() / 0.019f + 0.5f * warp);
  float a = 0.09f + 0.035f * bedding + 0.015f * fine + 0.12f * Fbm(p, 5.0f, 3, 0.5f, 22u, fp);
  // Glints: rare bright 1.5 cm cells.
  const Vec3 c = p * 66.0f;
  const uint32_t h =
      HashCell(static_cast<int>(std::floor(c.x())), static_cast<int>(std::floor(c.y())),
               static_cast<int>(std::floor(c.z())), 23u);
  if ((h & 1023u) < 6u) a = 0.6f;
  return a;
}

float ShotcreteAlbedo(const Vec3& p, float fp) {
  return 0.55f + 0.12f * Fbm(p, 2.0f, 3, 0.5f, 31u, fp);
}

float SteelAlbedo(const Vec3& p, float fp) { return 0.42f + 0.3f * Fbm(p, 6.0f, 2, 0.5f, 41u, fp); }

// 6 mm wires on a 0.1 m grid in world x and y, over rock. Thin wires are widened to half a
// footprint with their brightness scaled down, so that distant mesh greys out instead of aliasing.
float RoofMeshAlbedo(const Vec3& p, float fp) {
  constexpr float kPitch = 0.1f, kHalfWidth = 0.003f, kWire = 0.6f;
  const float rock = RockAlbedo(p, fp);
  const float half = std::max(kHalfWidth, 0.5f * fp);
  const float d = std::min(GridDistance(p.x(), kPitch), GridDistance(p.y(), kPitch));
  if (d >= half) return rock;
  const float coverage = kHalfWidth / half;
  return rock + coverage * (kWire - rock);
}

float FloorAlbedo(const Vec3& p, float fp) {
  return 0.17f + 0.06f * GradientNoise(p * 0.5f, 51u) + 0.45f * Fbm(p, 9.0f, 4, 0.65f, 52u, fp);
}

float WorkerAlbedo(const Vec3& p, float fp) {
  // Reflective stripes at fixed heights above the floor (world z, floor at z = 0).
  const float z = p.z();
  if ((z > 0.95f && z < 1.03f) || (z > 0.40f && z < 0.46f)) return 0.92f;
  return 0.28f + 0.15f * Fbm(p, 5.0f, 2, 0.5f, 81u, fp);
}

// Bolt plates: a 0.15 m square at the centre of every 1.2 m cell, in the plane spanned by the two
// world axes that are least aligned with the normal.
bool OnBoltPlate(const Vec3& p, const Vec3& n) {
  constexpr float kCell = 1.2f, kHalf = 0.075f;
  const Vec3 an = n.cwiseAbs();
  if (an.maxCoeff() <= 0.0f) return false;
  int axis = 0;
  an.maxCoeff(&axis);
  for (int k = 0; k < 3; ++k) {
    if (k == axis) continue;
    const float centre = (std::floor(p[k] / kCell) + 0.5f) * kCell;
    if (std::abs(p[k] - centre) >= kHalf) return false;
  }
  return true;
}

}  // namespace

float SurfaceAlbedo(Material material, const Eigen::Vector3f& p, const Eigen::Vector3f& n,
                    float fp) {
  float a = 0.0f;
  switch (material) {
    case Material::kNone:
      return 0.0f;
    case Material::kRock:
      a = RockAlbedo(p, fp);
      break;
    case Material::kCoal:
      a = CoalAlbedo(p, fp);
      break;
    case Material::kShotcrete:
      a = ShotcreteAlbedo(p, fp);
      break;
    case Material::kSteel:
      a = SteelAlbedo(p, fp);
      break;
    case Material::kRoofMesh:
      a = RoofMeshAlbedo(p, fp);
      break;
    case Material::kFloor:
      a = FloorAlbedo(p, fp);
      break;
    case Material::kPipe:
      a = 0.50f + 0.1f * Fbm(p, 3.0f, 2, 0.5f, 61u, fp);
      break;
    case Material::kCable:
      a = 0.07f + 0.05f * Fbm(p, 10.0f, 2, 0.5f, 71u, fp);
      break;
    case Material::kWorker:
      a = WorkerAlbedo(p, fp);
      break;
    case Material::kCart:
      a = 0.13f + 0.2f * Fbm(p, 4.0f, 3, 0.5f, 91u, fp);
      break;
    default:
      SLSLAM_CHECK(false, "unknown material id ", static_cast<int>(material));
  }
  if ((material == Material::kRock || material == Material::kShotcrete ||
       material == Material::kRoofMesh) &&
      OnBoltPlate(p, n)) {
    a = 0.78f;
  }
  return std::clamp(a, 0.01f, 0.98f);
}

void SolidTexture(const float* points_world, const float* normals_world, const uint8_t* material,
                  std::size_t count, float* albedo) {
  if (count == 0) return;
  Require(points_world && material && albedo, "solid texture needs points, materials and output");
  RequireKnownMaterials(material, count);
  const long long n = static_cast<long long>(count);
#pragma omp parallel for schedule(static)
  for (long long i = 0; i < n; ++i) {
    const Vec3 normal = normals_world ? Load3(normals_world, i) : Vec3::Zero();
    albedo[i] = SurfaceAlbedo(static_cast<Material>(material[i]), Load3(points_world, i), normal);
  }
}

void ReliefOptions::Check() const {
  Require(std::isfinite(height_m) && height_m >= 0.0f && height_m <= 0.1f,
          "relief height_m must be in [0, 0.1] m");
  Require(std::isfinite(wavelength_m) && wavelength_m >= 1e-3f && wavelength_m <= 10.0f,
          "relief wavelength_m must be in [0.001, 10] m");
  Require(octaves >= 1 && octaves <= 8, "relief octaves must be in [1, 8]");
}

void ReliefNormals(const float* points_world, const float* normals_world, const float* footprint_m,
                   std::size_t count, const ReliefOptions& options, float* normals_out) {
  options.Check();
  if (count == 0) return;
  Require(points_world && normals_world && normals_out, "relief normals need points and normals");
  constexpr uint32_t kReliefSalt = 131u;
  const float frequency = 1.0f / options.wavelength_m;
  // Central differences over a step well below the finest octave's wavelength (the octaves
  // grow by 2.03 in Fbm).
  const float finest_m = options.wavelength_m / std::pow(2.03f, options.octaves - 1);
  const float step = 0.05f * finest_m;
  const float scale = options.height_m / (2.0f * step);
  const long long n = static_cast<long long>(count);
#pragma omp parallel for schedule(static)
  for (long long i = 0; i < n; ++i) {
    const Vec3 p = Load3(points_world, i);
    Vec3 normal = Load3(normals_world, i);
    const float fp = footprint_m ? footprint_m[i] : 0.0f;
    const auto h = [&](const Vec3& q) {
      return Fbm(q, frequency, options.octaves, 0.5f, kReliefSalt, fp);
    };
    Vec3 gradient;
    for (int k = 0; k < 3; ++k) {
      Vec3 d = Vec3::Zero();
      d[k] = step;
      gradient[k] = scale * (h(p + d) - h(p - d));
    }
    const Vec3 tangential = gradient - normal * normal.dot(gradient);
    Vec3 relief = normal - tangential;
    const float length = relief.norm();
    if (length > 1e-6f) normal = relief / length;
    for (int k = 0; k < 3; ++k) normals_out[3 * i + k] = normal[k];
  }
}

namespace shading_detail {

void RequireKnownMaterials(const uint8_t* material, std::size_t count) {
  for (std::size_t i = 0; i < count; ++i) {
    const uint8_t m = material[i];
    if (m <= kMaxMaterialId || m == static_cast<uint8_t>(Material::kNone)) continue;
    // The message is built only on failure: this loop runs over every pixel.
    throw std::invalid_argument(
        Message("material id ", static_cast<int>(m), " at index ", i, " is unknown (0..9 or 255)"));
  }
}

}  // namespace shading_detail
}  // namespace slslam::sim
