// Image formation of the coal-mine roadway simulator: turns per-pixel ray hits (from a ray caster
// elsewhere, Open3D in Python) into an 8-bit gray image. Albedo comes from solid 3-D procedural
// textures evaluated at the world point (no seams, identical from every viewpoint); lighting is a
// headlamp cone plus roof lamps without shadows; the sensor adds vignetting, shot and read noise,
// gamma and 8-bit quantisation. Everything is deterministic: the noise of a pixel is a hash of
// (seed, frame index, pixel index), so the same inputs give byte-identical images on any number of
// threads.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace slslam::sim {

// Surface kinds; the values are the ids in the per-pixel material array (python/slslam/sim
// roadway.py mirrors them).
enum class Material : uint8_t {
  kRock = 0,       ///< bare rock: strong multi-scale contrast
  kCoal = 1,       ///< coal seam: dark, horizontal bedding streaks, sparse glints
  kShotcrete = 2,  ///< sprayed concrete: smooth, very low contrast
  kSteel = 3,      ///< arches, plates: mid albedo, slight noise
  kRoofMesh = 4,   ///< wire mesh on the roof (0.1 m grid in world x/y) over rock
  kFloor = 5,      ///< floor: darker gravel
  kPipe = 6,       ///< pipes: smooth mid gray
  kCable = 7,      ///< cables: dark
  kWorker = 8,     ///< clothing, mid gray with reflective stripes at fixed heights
  kCart = 9,       ///< mine cart: dark metal
  kNone = 255,     ///< no hit (void): black
};

// Albedo of a surface point in [0, 1]. `normal` (either orientation) selects the plane of the bolt
// plates (drawn on rock, shotcrete and roof mesh, one per 1.2 m cell); a zero normal draws none.
// `footprint_m` is the pixel footprint on the surface [m]: octaves fade out as their
// wavelength falls from 6 to 3 footprints (anti-aliasing, and speed); 0 keeps every octave.
float SurfaceAlbedo(Material material, const Eigen::Vector3f& point_world,
                    const Eigen::Vector3f& normal = Eigen::Vector3f::Zero(),
                    float footprint_m = 0.0f);

// Albedo of N points (N x 3 row-major, [m]) with their material ids; `normals` may be null (no
// bolt plates). Ids 255 give 0. Throws std::invalid_argument on an unknown id.
void SolidTexture(const float* points_world, const float* normals_world, const uint8_t* material,
                  std::size_t count, float* albedo);

// A fine relief on a surface (sprayed concrete's lumps): the height field
// h(p) = height_m * Fbm(p, 1 / wavelength_m, octaves, 0.5) (gradient noise in world coordinates,
// so every view sees the same relief) along the surface normal. Under a light near the camera it
// shades as a low-contrast texture that changes with the light's direction.
struct ReliefOptions {
  float height_m = 0.0f;      ///< scale of the height field [m] (its RMS is about a fifth)
  float wavelength_m = 0.1f;  ///< wavelength of the coarsest octave [m]; each next one ~half
  int octaves = 3;            ///< [-]

  void Check() const;
};

// Unit normals of N points (N x 3 row-major, [m]) on surfaces with unit normals `normals_world`
// once the relief is added: n' = normalize(n - grad_t h), grad_t the height's gradient in the
// tangent plane. `footprint_m` (N, may be null) is each point's pixel footprint [m]: octaves
// fade out below 3-6 footprints as the albedo's do (no aliasing into noise at distance).
void ReliefNormals(const float* points_world, const float* normals_world, const float* footprint_m,
                   std::size_t count, const ReliefOptions& options, float* normals_out);

// Per-pixel ray hits of one image, row-major (pixel index = row * width + column).
struct ShadingInput {
  const float* points_world = nullptr;   ///< N x 3 hit points [m] (ignored where no hit)
  const float* normals_world = nullptr;  ///< N x 3 unit normals [-], either orientation
  const uint8_t* material = nullptr;     ///< N material ids (Material); 255 = no hit
  std::size_t count = 0;                 ///< N = height * width

  void Check() const;
};

// Pinhole intrinsics (for vignetting and the pixel footprint) and the optical centre.
struct ShadingCamera {
  double fx = 458.654;                                 ///< focal length along u [px]
  double fy = 457.296;                                 ///< focal length along v [px]
  double cx = 367.215;                                 ///< principal point u [px]
  double cy = 248.375;                                 ///< principal point v [px]
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  ///< optical centre in world [m]

  void Check() const;
};

// The robot's headlamp: a spot light with a flat cone that falls smoothly to zero between
// half_angle and falloff_ratio * half_angle.
struct HeadLamp {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();          ///< in world [m]
  Eigen::Vector3d direction = Eigen::Vector3d(1.0, 0.0, 0.0);  ///< unit forward axis [-]
  double power = 10.0;          ///< intensity [irradiance units * m^2]: E = power cos / d^2
  double half_angle_rad = 0.6;  ///< half-angle of the fully lit cone [rad], in (0, pi/2]
  double falloff_ratio = 1.3;   ///< the light reaches zero at this multiple of half_angle [-], > 1

  void Check() const;
};

// All light in the scene. Irradiance = sum of power * max(0, n.l) / d^2 over the lamps (headlamp
// times its cone, roof lamps times their range window) + ambient; radiance = albedo * irradiance *
// light_level. No shadows.
struct Lighting {
  HeadLamp headlamp;
  std::vector<Eigen::Vector3d> roof_lamp_positions;  ///< isotropic roof lamps in world [m]
  double roof_lamp_power = 2.0;  ///< intensity of each roof lamp [irradiance units * m^2]
  /// Range of a roof lamp [m]: its inverse square is windowed by (1 - (d/R)^4)^2 (0.997 at R/5,
  /// 0.88 at R/2, 0 beyond R), so the kernel only visits lamps near each tile. 0 = unlimited.
  double roof_lamp_range_m = 20.0;
  double light_level = 1.0;  ///< global factor [-] (OIVIO onboard light: 1.0 / 0.5 / 0.15)
  double ambient = 0.01;     ///< direction-less irradiance [irradiance units]

  void Check() const;
};

// Camera sensor. Linear signal s = radiance * vignetting * exposure is the fraction of the full
// well (clipped at 1); DN = gain * 255 * s; shot noise has variance = electrons = s * full_well;
// read noise is added in DN; then out = round(255 * (DN / 255)^gamma), clamped to [0, 255].
struct SensorModel {
  double exposure = 0.25;              ///< radiance -> full-well fraction [1 / radiance units]
  double gain = 1.0;                   ///< analog gain [-], > 0
  double gamma = 1.0 / 2.2;            ///< encoding exponent [-], > 0 (1 = linear)
  double full_well_electrons = 10000;  ///< electrons at full well [e-], sets the shot noise
  double read_noise_dn = 1.5;          ///< read noise sigma in linear 8-bit units [DN]
  bool vignetting = true;              ///< multiply by cos^4 of the off-axis angle
  bool noise = true;                   ///< add shot + read noise
  uint64_t seed = 0;                   ///< noise seed [-]

  void Check() const;
};

// Shades one image of height x width pixels into `image` (height * width bytes, row-major).
// Throws std::invalid_argument on inconsistent sizes or invalid options. Parallel (OpenMP) when
// built with it; the output does not depend on the number of threads.
void ShadeImage(const ShadingInput& input, int height, int width, const ShadingCamera& camera,
                const Lighting& lighting, const SensorModel& sensor, uint64_t frame_index,
                uint8_t* image);

// As above, returning a new CV_8UC1 height x width image.
cv::Mat ShadeImage(const ShadingInput& input, int height, int width, const ShadingCamera& camera,
                   const Lighting& lighting, const SensorModel& sensor, uint64_t frame_index);

}  // namespace slslam::sim
