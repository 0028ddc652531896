// Internal to the shading_*.cpp files that implement shading.h: what the noise, the materials
// and the image formation share. Not part of the public API.
//
//   shading_noise.cpp      hashes, gradient noise, fractal sums, grid distances
//   shading_materials.cpp  the materials' solid textures (SurfaceAlbedo, SolidTexture)
//   shading.cpp            lights, sensor and the per-pixel kernel (ShadeImage), the Check()s
#pragma once

#include <cstddef>
#include <cstdint>

#include <Eigen/Core>

namespace slslam::sim::shading_detail {

using Vec3 = Eigen::Vector3f;

constexpr float kPi = 3.14159265358979f;

// A 64-bit mixing hash (SplitMix64's finaliser): the noise lattice's permutation and the sensor
// noise of a pixel. Pure; inline because the kernel calls it twice per pixel.
inline uint64_t SplitMix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// The point at index i of an N x 3 row-major array.
inline Vec3 Load3(const float* data, std::size_t i) {
  return {data[3 * i], data[3 * i + 1], data[3 * i + 2]};
}

// ---- shading_noise.cpp (all pure functions of their arguments)

// A 32-bit hash of the integer lattice cell (x, y, z), one stream per salt.
uint32_t HashCell(int x, int y, int z, uint32_t salt);

// 3-D gradient noise (improved Perlin), roughly in [-1, 1], zero at lattice points. `salt`
// shifts the lattice, giving an independent-looking noise per salt.
float GradientNoise(const Vec3& q, uint32_t salt);

// Fractal sum of `octaves` gradient-noise octaves from `frequency` [cycles/m] up by ~2x each,
// normalised by the total amplitude. Octaves fade out as their wavelength falls from 6 to 3
// footprints (anti-aliasing; also the main saving on distant surfaces).
float Fbm(const Vec3& p, float frequency, int octaves, float gain, uint32_t salt,
          float footprint_m);

// Distance [m] from a coordinate to the nearest line of a grid with spacing `pitch` [m].
float GridDistance(float x, float pitch);

// ---- shading_materials.cpp

// Throws std::invalid_argument naming the first id that is neither a Material nor kNone.
void RequireKnownMaterials(const uint8_t* material, std::size_t count);

}  // namespace slslam::sim::shading_detail
