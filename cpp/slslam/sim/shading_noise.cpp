// Hashes and solid noise of the simulator's textures (shading_internal.h). All pure functions of
// their arguments: no state, no thread dependence.
#include <algorithm>
#include <cstdint>
#include <utility>

#include "slslam/sim/shading_internal.h"

namespace slslam::sim::shading_detail {
namespace {

inline uint32_t Fmix32(uint32_t h) {
  h ^= h >> 16;
  h *= 0x85EBCA6Bu;
  h ^= h >> 13;
  h *= 0xC2B2AE35u;
  h ^= h >> 16;
  return h;
}

constexpr uint32_t kHx = 0x8DA6B343u, kHy = 0xD8163841u, kHz = 0xCB1AB31Fu;

// Improved-Perlin gradient set: the 12 cube edge directions, 4 repeated to fill 16 slots.
constexpr float kGrad[16][3] = {
    {1, 1, 0}, {-1, 1, 0}, {1, -1, 0}, {-1, -1, 0}, {1, 0, 1}, {-1, 0, 1}, {1, 0, -1}, {-1, 0, -1},
    {0, 1, 1}, {0, -1, 1}, {0, 1, -1}, {0, -1, -1}, {1, 1, 0}, {-1, 1, 0}, {0, -1, 1}, {0, -1, -1}};

inline float Grad(uint32_t h, float x, float y, float z) {
  const float* g = kGrad[h & 15u];
  return g[0] * x + g[1] * y + g[2] * z;
}

// floor() for |x| < 2^31, without a library call.
inline int FastFloor(float x) {
  const int i = static_cast<int>(x);
  return i - (x < static_cast<float>(i));
}

inline float Fade(float t) { return t * t * t * (t * (t * 6.0f - 15.0f) + 10.0f); }
inline float Lerp(float a, float b, float t) { return a + t * (b - a); }

// Permutation of 0..4095 (stored twice to skip index masks), shuffled once with a fixed seed:
// the lattice hash of the gradient noise, which repeats only every 4096 lattice cells.
constexpr int kPermSize = 4096, kPermMask = kPermSize - 1;

struct PermutationTable {
  uint16_t p[2 * kPermSize];
  PermutationTable() {
    for (int i = 0; i < kPermSize; ++i) p[i] = static_cast<uint16_t>(i);
    uint64_t state = 0x5151A3u;
    for (int i = kPermSize - 1; i > 0; --i) {
      state = SplitMix64(state);
      std::swap(p[i], p[state % static_cast<uint64_t>(i + 1)]);
    }
    for (int i = 0; i < kPermSize; ++i) p[kPermSize + i] = p[i];
  }
};
const PermutationTable kPerm;

inline float Fract(float x) { return x - static_cast<float>(FastFloor(x)); }

}  // namespace

uint32_t HashCell(int x, int y, int z, uint32_t salt) {
  const uint32_t hz = Fmix32(static_cast<uint32_t>(z) * kHz + salt);
  const uint32_t hy = Fmix32(hz + static_cast<uint32_t>(y) * kHy);
  return Fmix32(hy + static_cast<uint32_t>(x) * kHx);
}

float GradientNoise(const Vec3& q, uint32_t salt) {
  const int ix = FastFloor(q.x()), iy = FastFloor(q.y()), iz = FastFloor(q.z());
  const float x = q.x() - ix, y = q.y() - iy, z = q.z() - iz;
  const uint16_t* P = kPerm.p;
  const int X = (ix + static_cast<int>(salt * 1129u)) & kPermMask;
  const int Y = (iy + static_cast<int>(salt * 2713u)) & kPermMask;
  const int Z = (iz + static_cast<int>(salt * 3407u)) & kPermMask;
  const int A = P[X] + Y, AA = P[A] + Z, AB = P[A + 1] + Z;
  const int B = P[X + 1] + Y, BA = P[B] + Z, BB = P[B + 1] + Z;
  const float u = Fade(x), v = Fade(y), w = Fade(z);
  const float n000 = Grad(P[AA], x, y, z), n100 = Grad(P[BA], x - 1, y, z);
  const float n010 = Grad(P[AB], x, y - 1, z), n110 = Grad(P[BB], x - 1, y - 1, z);
  const float n001 = Grad(P[AA + 1], x, y, z - 1), n101 = Grad(P[BA + 1], x - 1, y, z - 1);
  const float n011 = Grad(P[AB + 1], x, y - 1, z - 1);
  const float n111 = Grad(P[BB + 1], x - 1, y - 1, z - 1);
  return Lerp(Lerp(Lerp(n000, n100, u), Lerp(n010, n110, u), v),
              Lerp(Lerp(n001, n101, u), Lerp(n011, n111, u), v), w);
}

float Fbm(const Vec3& p, float frequency, int octaves, float gain, uint32_t salt,
          float footprint_m) {
  float sum = 0.0f, amplitude = 1.0f, norm = 0.0f;
  for (int o = 0; o < octaves; ++o) {
    norm += amplitude;
    float weight = 1.0f;
    if (footprint_m > 0.0f) {
      weight =
          std::clamp((1.0f / frequency - 3.0f * footprint_m) / (3.0f * footprint_m), 0.0f, 1.0f);
    }
    if (weight > 0.0f) {
      sum += amplitude * weight * GradientNoise(p * frequency, salt + 0x9E3779B9u * o);
    }
    amplitude *= gain;
    frequency *= 2.03f;
  }
  return sum / norm;
}

float GridDistance(float x, float pitch) {
  const float f = Fract(x / pitch);
  return std::min(f, 1.0f - f) * pitch;
}

}  // namespace slslam::sim::shading_detail
