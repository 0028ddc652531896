#include "slslam/sim/shading.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "slslam/core/check.h"

namespace slslam::sim {
namespace {

using Vec3 = Eigen::Vector3f;

constexpr float kPi = 3.14159265358979f;
constexpr uint8_t kMaxMaterialId = static_cast<uint8_t>(Material::kCart);

// ---------------------------------------------------------------------------------------------
// Hashes and solid noise. All pure functions of their arguments: no state, no thread dependence.

inline uint32_t Fmix32(uint32_t h) {
  h ^= h >> 16;
  h *= 0x85EBCA6Bu;
  h ^= h >> 13;
  h *= 0xC2B2AE35u;
  h ^= h >> 16;
  return h;
}

inline uint64_t SplitMix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

constexpr uint32_t kHx = 0x8DA6B343u, kHy = 0xD8163841u, kHz = 0xCB1AB31Fu;

inline uint32_t HashCell(int x, int y, int z, uint32_t salt) {
  const uint32_t hz = Fmix32(static_cast<uint32_t>(z) * kHz + salt);
  const uint32_t hy = Fmix32(hz + static_cast<uint32_t>(y) * kHy);
  return Fmix32(hy + static_cast<uint32_t>(x) * kHx);
}

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

// 3-D gradient noise (improved Perlin), roughly in [-1, 1], zero at lattice points. `salt`
// shifts the lattice, giving an independent-looking noise per salt.
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

// Fractal sum of `octaves` gradient-noise octaves from `frequency` [cycles/m] up by ~2x each,
// normalised by the total amplitude. Octaves fade out as their wavelength falls from 6 to 3
// footprints (anti-aliasing; also the main saving on distant surfaces).
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

inline float Fract(float x) { return x - static_cast<float>(FastFloor(x)); }

// Distance [m] from a coordinate to the nearest line of a grid with spacing `pitch` [m].
inline float GridDistance(float x, float pitch) {
  const float f = Fract(x / pitch);
  return std::min(f, 1.0f - f) * pitch;
}

// ---------------------------------------------------------------------------------------------
// Materials. Albedos are tuned for mid-gray rock (~0.3) and are clamped to [0.01, 0.98].

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

namespace {

void RequireKnownMaterials(const uint8_t* material, std::size_t count) {
  for (std::size_t i = 0; i < count; ++i) {
    const uint8_t m = material[i];
    if (m <= kMaxMaterialId || m == static_cast<uint8_t>(Material::kNone)) continue;
    // The message is built only on failure: this loop runs over every pixel.
    throw std::invalid_argument(
        Message("material id ", static_cast<int>(m), " at index ", i, " is unknown (0..9 or 255)"));
  }
}

inline Vec3 Load3(const float* data, std::size_t i) {
  return {data[3 * i], data[3 * i + 1], data[3 * i + 2]};
}

bool Finite(const Eigen::Vector3d& v) { return v.allFinite(); }

// Roof lamps in structure-of-arrays form so that the per-pixel sum vectorises (omp simd: the
// summation order is fixed at compile time, so results do not depend on threads). With a range
// R > 0 each lamp is windowed by (1 - (d/R)^4)^2 and exactly zero beyond R, so that a tile of
// pixels only visits the lamps within R of its points.
class RoofLamps {
 public:
  RoofLamps() = default;
  explicit RoofLamps(const Lighting& lighting)
      : power_(static_cast<float>(lighting.roof_lamp_power)),
        range_(static_cast<float>(lighting.roof_lamp_range_m)) {
    for (const Eigen::Vector3d& q : lighting.roof_lamp_positions) {
      Append(q.x(), q.y(), q.z());
    }
  }

  // Keeps in `out` the lamps within range of the box [lo, hi] (all lamps without a range).
  void Select(const Vec3& lo, const Vec3& hi, RoofLamps* out) const {
    out->x_.clear();
    out->y_.clear();
    out->z_.clear();
    out->power_ = power_;
    out->range_ = range_;
    if (lo.x() > hi.x()) return;  // empty box: no hit in the tile
    for (std::size_t k = 0; k < x_.size(); ++k) {
      const Vec3 q(x_[k], y_[k], z_[k]);
      if (range_ <= 0.0f || (q - q.cwiseMax(lo).cwiseMin(hi)).squaredNorm() < range_ * range_) {
        out->Append(x_[k], y_[k], z_[k]);
      }
    }
  }

  // Sum of power * max(0, n.l) / d^2 (times the window) at point p with unit normal n.
  float Irradiance(const Vec3& p, const Vec3& n) const {
    const float px = p.x(), py = p.y(), pz = p.z(), nx = n.x(), ny = n.y(), nz = n.z();
    const float* x = x_.data();
    const float* y = y_.data();
    const float* z = z_.data();
    const int count = static_cast<int>(x_.size());
    const float inv_r2 = range_ > 0.0f ? 1.0f / (range_ * range_) : 0.0f;
    float sum = 0.0f;
#pragma omp simd reduction(+ : sum)
    for (int k = 0; k < count; ++k) {
      const float dx = x[k] - px, dy = y[k] - py, dz = z[k] - pz;
      const float d2 = std::max(dx * dx + dy * dy + dz * dz, 1e-4f);
      const float dot = std::max(nx * dx + ny * dy + nz * dz, 0.0f);
      const float q = d2 * inv_r2;
      const float window = std::max(1.0f - q * q, 0.0f);
      sum += dot * window * window / (d2 * std::sqrt(d2));
    }
    return power_ * sum;
  }

 private:
  template <typename T>
  void Append(T x, T y, T z) {
    x_.push_back(static_cast<float>(x));
    y_.push_back(static_cast<float>(y));
    z_.push_back(static_cast<float>(z));
  }

  std::vector<float> x_, y_, z_;
  float power_ = 0.0f, range_ = 0.0f;
};

// Maps linear DN in [0, 255] to round(255 * (DN / 255)^gamma) through the 255 decision
// thresholds: exact and much cheaper than pow() per pixel.
class GammaEncoder {
 public:
  explicit GammaEncoder(double gamma) {
    for (int c = 1; c <= 255; ++c) {
      thresholds_[c - 1] = static_cast<float>(255.0 * std::pow((c - 0.5) / 255.0, 1.0 / gamma));
    }
  }
  uint8_t operator()(float dn) const {
    return static_cast<uint8_t>(std::upper_bound(thresholds_, thresholds_ + 255, dn) - thresholds_);
  }

 private:
  float thresholds_[255];
};

}  // namespace

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

void ShadingInput::Check() const {
  Require(count > 0, "shading input has no pixels");
  Require(points_world && normals_world && material,
          "shading input needs points, normals and materials");
}

void ShadingCamera::Check() const {
  SLSLAM_CHECK(std::isfinite(fx) && fx > 0.0, "camera fx must be finite and > 0, got ", fx);
  SLSLAM_CHECK(std::isfinite(fy) && fy > 0.0, "camera fy must be finite and > 0, got ", fy);
  Require(std::isfinite(cx) && std::isfinite(cy), "camera principal point must be finite");
  Require(Finite(position), "camera position must be finite");
}

void HeadLamp::Check() const {
  Require(Finite(position), "headlamp position must be finite");
  SLSLAM_CHECK(Finite(direction) && std::abs(direction.norm() - 1.0) < 1e-3,
               "headlamp direction must be a unit vector, got norm ", direction.norm());
  SLSLAM_CHECK(std::isfinite(power) && power >= 0.0, "headlamp power must be finite and >= 0, got ",
               power);
  SLSLAM_CHECK(half_angle_rad > 0.0 && half_angle_rad <= kPi / 2,
               "headlamp half_angle_rad must be in (0, pi/2], got ", half_angle_rad);
  SLSLAM_CHECK(std::isfinite(falloff_ratio) && falloff_ratio > 1.0,
               "headlamp falloff_ratio must be > 1, got ", falloff_ratio);
}

void Lighting::Check() const {
  headlamp.Check();
  for (const auto& p : roof_lamp_positions) Require(Finite(p), "roof lamp position must be finite");
  SLSLAM_CHECK(std::isfinite(roof_lamp_power) && roof_lamp_power >= 0.0,
               "roof_lamp_power must be finite and >= 0, got ", roof_lamp_power);
  SLSLAM_CHECK(std::isfinite(roof_lamp_range_m) && roof_lamp_range_m >= 0.0,
               "roof_lamp_range_m must be finite and >= 0, got ", roof_lamp_range_m);
  SLSLAM_CHECK(std::isfinite(light_level) && light_level >= 0.0,
               "light_level must be finite and >= 0, got ", light_level);
  SLSLAM_CHECK(std::isfinite(ambient) && ambient >= 0.0, "ambient must be finite and >= 0, got ",
               ambient);
}

void SensorModel::Check() const {
  SLSLAM_CHECK(std::isfinite(exposure) && exposure >= 0.0,
               "sensor exposure must be finite and >= 0, got ", exposure);
  SLSLAM_CHECK(std::isfinite(gain) && gain > 0.0, "sensor gain must be > 0, got ", gain);
  SLSLAM_CHECK(std::isfinite(gamma) && gamma > 0.0, "sensor gamma must be > 0, got ", gamma);
  SLSLAM_CHECK(std::isfinite(full_well_electrons) && full_well_electrons > 0.0,
               "sensor full_well_electrons must be > 0, got ", full_well_electrons);
  SLSLAM_CHECK(std::isfinite(read_noise_dn) && read_noise_dn >= 0.0,
               "sensor read_noise_dn must be >= 0, got ", read_noise_dn);
}

void ShadeImage(const ShadingInput& input, int height, int width, const ShadingCamera& camera,
                const Lighting& lighting, const SensorModel& sensor, uint64_t frame_index,
                uint8_t* image) {
  SLSLAM_CHECK(height > 0 && width > 0, "image size must be positive, got ", height, "x", width);
  input.Check();
  SLSLAM_CHECK(input.count == static_cast<std::size_t>(height) * static_cast<std::size_t>(width),
               "shading input has ", input.count, " pixels, image ", height, "x", width, " needs ",
               static_cast<std::size_t>(height) * width);
  Require(image != nullptr, "shading output buffer is null");
  camera.Check();
  lighting.Check();
  sensor.Check();
  RequireKnownMaterials(input.material, input.count);

  // Everything the inner loop needs, in float.
  const Vec3 cam = camera.position.cast<float>();
  const float inv_fx = static_cast<float>(1.0 / camera.fx);
  const float inv_fy = static_cast<float>(1.0 / camera.fy);
  const float inv_f = static_cast<float>(2.0 / (camera.fx + camera.fy));
  const float cx = static_cast<float>(camera.cx), cy = static_cast<float>(camera.cy);
  const HeadLamp& hl = lighting.headlamp;
  const Vec3 hl_pos = hl.position.cast<float>(), hl_dir = hl.direction.cast<float>();
  const float hl_power = static_cast<float>(hl.power);
  const float hl_inner = static_cast<float>(hl.half_angle_rad);
  const float hl_outer = static_cast<float>(hl.half_angle_rad * hl.falloff_ratio);
  const float cos_inner = std::cos(hl_inner);
  const float cos_outer = hl_outer >= kPi ? -1.0f : std::cos(hl_outer);
  const RoofLamps roof(lighting);
  const float ambient = static_cast<float>(lighting.ambient);
  const float level = static_cast<float>(lighting.light_level);
  const float exposure = static_cast<float>(sensor.exposure);
  const float dn_scale = static_cast<float>(sensor.gain * 255.0);
  const float shot_var_scale =
      static_cast<float>(sensor.gain * sensor.gain * 255.0 * 255.0 / sensor.full_well_electrons);
  const float read_var = static_cast<float>(sensor.read_noise_dn * sensor.read_noise_dn);
  const GammaEncoder encode(sensor.gamma);
  const bool use_gamma = sensor.gamma != 1.0;
  const uint64_t noise_key = SplitMix64(SplitMix64(sensor.seed) ^ frame_index);

  // Tiles of kTile x kTile pixels; each visits only the roof lamps in range of its hit points.
  constexpr int kTile = 16;
  const int tiles_x = (width + kTile - 1) / kTile, tiles_y = (height + kTile - 1) / kTile;
#pragma omp parallel
  {
    RoofLamps tile_lamps;
#pragma omp for schedule(dynamic, 2)
    for (int tile = 0; tile < tiles_x * tiles_y; ++tile) {
      const int row0 = (tile / tiles_x) * kTile, col0 = (tile % tiles_x) * kTile;
      const int row1 = std::min(row0 + kTile, height), col1 = std::min(col0 + kTile, width);
      Vec3 lo = Vec3::Constant(std::numeric_limits<float>::infinity()), hi = -lo;
      for (int row = row0; row < row1; ++row) {
        for (int col = col0; col < col1; ++col) {
          const std::size_t i = static_cast<std::size_t>(row) * width + col;
          const Vec3 p = Load3(input.points_world, i);
          if (input.material[i] == static_cast<uint8_t>(Material::kNone) || !p.allFinite()) {
            continue;
          }
          lo = lo.cwiseMin(p);
          hi = hi.cwiseMax(p);
        }
      }
      roof.Select(lo, hi, &tile_lamps);
      for (int row = row0; row < row1; ++row) {
        const float b = (static_cast<float>(row) - cy) * inv_fy;
        for (int col = col0; col < col1; ++col) {
          const std::size_t i = static_cast<std::size_t>(row) * width + col;
          const uint8_t id = input.material[i];
          const float a = (static_cast<float>(col) - cx) * inv_fx;
          const float off_axis2 = 1.0f + a * a + b * b;  // 1 / cos^2 of the off-axis angle
          float radiance = 0.0f;
          const Vec3 p = Load3(input.points_world, i);
          // A non-finite hit point shades as void.
          if (id != static_cast<uint8_t>(Material::kNone) && p.allFinite()) {
            Vec3 n = Load3(input.normals_world, i);
            const Vec3 to_cam = cam - p;
            if (n.dot(to_cam) < 0.0f) n = -n;
            // Footprint of one pixel on the surface, ignoring obliquity [m].
            const float footprint = to_cam.norm() * std::sqrt(off_axis2) * inv_f;
            const float albedo = SurfaceAlbedo(static_cast<Material>(id), p, n, footprint);
            float irradiance = ambient;
            {
              const Vec3 l = hl_pos - p;
              const float d2 = std::max(l.squaredNorm(), 1e-4f);
              const float inv_d = 1.0f / std::sqrt(d2);
              const float cos_i = n.dot(l) * inv_d;
              const float cos_axis = -hl_dir.dot(l) * inv_d;
              if (cos_i > 0.0f && cos_axis > cos_outer) {
                float cone = 1.0f;
                if (cos_axis < cos_inner) {
                  const float t =
                      (std::acos(std::min(cos_axis, 1.0f)) - hl_inner) / (hl_outer - hl_inner);
                  const float s = std::clamp(t, 0.0f, 1.0f);
                  cone = 1.0f - s * s * (3.0f - 2.0f * s);
                }
                irradiance += hl_power * cone * cos_i / d2;
              }
            }
            irradiance += tile_lamps.Irradiance(p, n);
            radiance = albedo * irradiance * level;
          }
          float s = radiance * exposure;
          if (sensor.vignetting) s /= off_axis2 * off_axis2;  // cos^4
          s = std::min(std::max(s, 0.0f), 1.0f);              // full well
          float dn = dn_scale * s;
          if (sensor.noise) {
            const uint64_t h = SplitMix64(noise_key ^ SplitMix64(i));
            // Irwin-Hall: the sum of four 16-bit uniforms, scaled to unit variance (tails cut at
            // 3.46 sigma); far cheaper than Box-Muller and plenty for sensor noise.
            const float sum4 = static_cast<float>((h & 0xFFFFu) + ((h >> 16) & 0xFFFFu) +
                                                  ((h >> 32) & 0xFFFFu) + (h >> 48));
            const float gauss = (sum4 * (1.0f / 65536.0f) - 2.0f) * 1.7320508f;
            dn += gauss * std::sqrt(shot_var_scale * s + read_var);
          }
          if (!(dn > 0.0f)) dn = 0.0f;  // also catches NaN
          dn = std::min(dn, 255.0f);
          image[i] = use_gamma ? encode(dn) : static_cast<uint8_t>(dn + 0.5f);
        }
      }
    }
  }
}

cv::Mat ShadeImage(const ShadingInput& input, int height, int width, const ShadingCamera& camera,
                   const Lighting& lighting, const SensorModel& sensor, uint64_t frame_index) {
  SLSLAM_CHECK(height > 0 && width > 0, "image size must be positive, got ", height, "x", width);
  cv::Mat image(height, width, CV_8UC1);
  ShadeImage(input, height, width, camera, lighting, sensor, frame_index, image.ptr<uint8_t>());
  return image;
}

}  // namespace slslam::sim
