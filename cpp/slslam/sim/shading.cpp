#include "slslam/sim/shading.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "slslam/core/check.h"
#include "slslam/sim/shading_internal.h"

// Lights, sensor and the per-pixel kernel; the textures live in shading_materials.cpp and
// shading_noise.cpp (shading_internal.h).
namespace slslam::sim {
namespace {

using shading_detail::kPi;
using shading_detail::Load3;
using shading_detail::RequireKnownMaterials;
using shading_detail::SplitMix64;
using shading_detail::Vec3;

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

namespace {
// ShadeImage's arguments checked (each names what is wrong).
void CheckShadeImage(const ShadingInput& input, int height, int width, const ShadingCamera& camera,
                     const Lighting& lighting, const SensorModel& sensor, const uint8_t* image) {
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
}
}  // namespace

void ShadeImage(const ShadingInput& input, int height, int width, const ShadingCamera& camera,
                const Lighting& lighting, const SensorModel& sensor, uint64_t frame_index,
                uint8_t* image) {
  CheckShadeImage(input, height, width, camera, lighting, sensor, image);

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
