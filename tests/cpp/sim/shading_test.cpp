#include "slslam/sim/shading.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>
#ifdef _OPENMP
#include <omp.h>
#endif

namespace slslam::sim {
namespace {

// Per-pixel hits of one image, owning its buffers.
struct Hits {
  int height = 0, width = 0;
  std::vector<float> points, normals;
  std::vector<uint8_t> material;

  ShadingInput Input() const {
    return {points.data(), normals.data(), material.data(), material.size()};
  }
  void Add(const Eigen::Vector3f& p, const Eigen::Vector3f& n, Material m) {
    points.insert(points.end(), {p.x(), p.y(), p.z()});
    normals.insert(normals.end(), {n.x(), n.y(), n.z()});
    material.push_back(static_cast<uint8_t>(m));
  }
};

// Camera at the origin looking along world +z (camera frame = world), a wall at z = depth.
Hits Wall(int height, int width, const ShadingCamera& camera, float depth, Material m) {
  Hits hits{height, width, {}, {}, {}};
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const float a = static_cast<float>((u - camera.cx) / camera.fx);
      const float b = static_cast<float>((v - camera.cy) / camera.fy);
      hits.Add(Eigen::Vector3f(a, b, 1.0f) * depth, Eigen::Vector3f(0, 0, 1), m);
    }
  }
  return hits;
}

ShadingCamera SmallCamera(int height, int width) {
  ShadingCamera c;
  c.fx = c.fy = 0.8 * width;
  c.cx = (width - 1) / 2.0;
  c.cy = (height - 1) / 2.0;
  return c;
}

Lighting ForwardHeadlamp() {
  Lighting l;
  l.headlamp.direction = Eigen::Vector3d(0, 0, 1);
  return l;
}

SensorModel Noiseless() {
  SensorModel s;
  s.noise = false;
  s.gamma = 1.0;
  s.vignetting = false;
  return s;
}

double Variance(const std::vector<float>& x) {
  double mean = 0.0, sq = 0.0;
  for (float v : x) mean += v;
  mean /= x.size();
  for (float v : x) sq += (v - mean) * (v - mean);
  return sq / x.size();
}

TEST(Shading, SameInputsGiveIdenticalImages) {
  const ShadingCamera camera = SmallCamera(48, 64);
  const Hits hits = Wall(48, 64, camera, 3.0f, Material::kRock);
  const SensorModel sensor;  // noise on
  const cv::Mat a = ShadeImage(hits.Input(), 48, 64, camera, ForwardHeadlamp(), sensor, 7);
  const cv::Mat b = ShadeImage(hits.Input(), 48, 64, camera, ForwardHeadlamp(), sensor, 7);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  const cv::Mat c = ShadeImage(hits.Input(), 48, 64, camera, ForwardHeadlamp(), sensor, 8);
  EXPECT_GT(cv::norm(a, c, cv::NORM_INF), 0.0) << "another frame must get other noise";
#ifdef _OPENMP
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const cv::Mat single = ShadeImage(hits.Input(), 48, 64, camera, ForwardHeadlamp(), sensor, 7);
  omp_set_num_threads(std::max(threads, 3));
  const cv::Mat multi = ShadeImage(hits.Input(), 48, 64, camera, ForwardHeadlamp(), sensor, 7);
  omp_set_num_threads(threads);
  EXPECT_EQ(cv::norm(single, multi, cv::NORM_INF), 0.0) << "output depends on the thread count";
#endif
}

TEST(Shading, AlbedoIsInUnitRangeForEveryMaterial) {
  std::vector<float> points;
  for (int i = 0; i < 2000; ++i) {
    points.insert(points.end(), {0.37f * i - 200.0f, 0.011f * i * i - 5.0f, 0.013f * i - 3.0f});
  }
  for (int m = 0; m <= 9; ++m) {
    std::vector<uint8_t> material(2000, static_cast<uint8_t>(m));
    std::vector<float> albedo(2000, -1.0f);
    SolidTexture(points.data(), points.data(), material.data(), 2000, albedo.data());
    for (float a : albedo) {
      ASSERT_GE(a, 0.0f) << "material " << m;
      ASSERT_LE(a, 1.0f) << "material " << m;
    }
    EXPECT_GT(Variance(albedo), 0.0) << "material " << m << " has no texture at all";
  }
  std::vector<uint8_t> none(2000, 255);
  std::vector<float> albedo(2000, -1.0f);
  SolidTexture(points.data(), nullptr, none.data(), 2000, albedo.data());
  EXPECT_EQ(*std::max_element(albedo.begin(), albedo.end()), 0.0f);
}

TEST(Shading, ShotcreteIsMuchSmootherThanRock) {
  std::vector<float> points;
  for (int i = 0; i < 40; ++i) {
    for (int j = 0; j < 40; ++j)
      points.insert(points.end(), {12.0f + 0.025f * i, 2.5f, 1.0f + 0.025f * j});
  }
  const std::size_t n = points.size() / 3;
  std::vector<float> rock(n), shotcrete(n);
  std::vector<uint8_t> m(n, static_cast<uint8_t>(Material::kRock));
  SolidTexture(points.data(), nullptr, m.data(), n, rock.data());
  std::fill(m.begin(), m.end(), static_cast<uint8_t>(Material::kShotcrete));
  SolidTexture(points.data(), nullptr, m.data(), n, shotcrete.data());
  const double v_rock = Variance(rock), v_shotcrete = Variance(shotcrete);
  std::printf("[ albedo  ] std over a 1 m patch: rock %.4f, shotcrete %.4f\n", std::sqrt(v_rock),
              std::sqrt(v_shotcrete));
  EXPECT_LT(v_shotcrete * 10.0, v_rock);
}

TEST(Shading, HeadlampFollowsInverseSquare) {
  // One shotcrete point seen on-axis from 2 m and 4 m, the headlamp at the camera.
  const Eigen::Vector3f p(3.0f, -1.0f, 6.0f);
  Hits hits{1, 1, {}, {}, {}};
  hits.Add(p, Eigen::Vector3f(0, 0, -1), Material::kShotcrete);
  ShadingCamera camera{1e4, 1e4, 0.0, 0.0, Eigen::Vector3d::Zero()};
  Lighting lighting = ForwardHeadlamp();
  lighting.ambient = 0.0;
  SensorModel sensor = Noiseless();
  sensor.exposure = 0.5;
  const float albedo = SurfaceAlbedo(Material::kShotcrete, p);
  double dn[2];
  for (int k = 0; k < 2; ++k) {
    const double d = 2.0 * (k + 1);
    camera.position = p.cast<double>() - Eigen::Vector3d(0, 0, d);
    lighting.headlamp.position = camera.position;
    dn[k] = ShadeImage(hits.Input(), 1, 1, camera, lighting, sensor, 0).at<uint8_t>(0, 0);
    EXPECT_NEAR(dn[k], 255.0 * sensor.exposure * albedo * lighting.headlamp.power / (d * d), 0.5);
  }
  EXPECT_NEAR(dn[1] / dn[0], 0.25, 0.02);
}

TEST(Shading, HeadlampConeFallsOffSmoothly) {
  // Three points 3 m from the lamp at 0, 1.15 and 1.5 half-angles off its axis, facing it.
  Lighting lighting = ForwardHeadlamp();
  lighting.ambient = 0.0;
  lighting.headlamp.half_angle_rad = 0.3;
  Hits hits{1, 3, {}, {}, {}};
  for (double ratio : {0.0, 1.15, 1.5}) {
    const double angle = ratio * lighting.headlamp.half_angle_rad;
    const Eigen::Vector3f dir(static_cast<float>(std::sin(angle)), 0.0f,
                              static_cast<float>(std::cos(angle)));
    hits.Add(3.0f * dir, -dir, Material::kShotcrete);
  }
  SensorModel sensor = Noiseless();
  sensor.exposure = 0.8;
  const cv::Mat image = ShadeImage(hits.Input(), 1, 3, SmallCamera(1, 3), lighting, sensor, 0);
  const int inside = image.at<uint8_t>(0, 0), edge = image.at<uint8_t>(0, 1);
  EXPECT_GT(inside, 50);
  EXPECT_GT(edge, 0);
  EXPECT_LT(edge, 0.8 * inside);
  EXPECT_EQ(image.at<uint8_t>(0, 2), 0) << "outside the cone with no other light";
}

TEST(Shading, RoofLampsAddLightAndVoidIsBlack) {
  const ShadingCamera camera = SmallCamera(20, 30);
  Hits hits = Wall(20, 30, camera, 4.0f, Material::kRock);
  std::fill(hits.material.begin(), hits.material.begin() + 30, 255);  // top row: no hit
  Lighting lighting = ForwardHeadlamp();
  lighting.headlamp.power = 0.0;
  lighting.ambient = 0.0;
  const cv::Mat dark = ShadeImage(hits.Input(), 20, 30, camera, lighting, Noiseless(), 0);
  EXPECT_EQ(cv::countNonZero(dark), 0);
  lighting.roof_lamp_positions = {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(1, 0, 2)};
  const cv::Mat lit = ShadeImage(hits.Input(), 20, 30, camera, lighting, Noiseless(), 0);
  EXPECT_GT(cv::mean(lit)[0], 5.0);
  EXPECT_EQ(cv::countNonZero(lit.row(0)), 0);
}

TEST(Shading, BlackWithoutLightWhenNoiseIsOff) {
  const ShadingCamera camera = SmallCamera(24, 32);
  const Hits hits = Wall(24, 32, camera, 2.0f, Material::kShotcrete);
  Lighting lighting = ForwardHeadlamp();
  lighting.roof_lamp_positions = {Eigen::Vector3d(0, -1, 1)};
  lighting.light_level = 0.0;
  SensorModel sensor;
  sensor.noise = false;
  const cv::Mat image = ShadeImage(hits.Input(), 24, 32, camera, lighting, sensor, 0);
  EXPECT_EQ(cv::countNonZero(image), 0);
}

TEST(Shading, NoiseHasTheModelledSpread) {
  // A flat mid-gray field, linear output: the per-pixel spread matches shot + read noise.
  const ShadingCamera camera = SmallCamera(100, 100);
  Hits hits = Wall(100, 100, camera, 2.0f, Material::kPipe);
  Lighting lighting = ForwardHeadlamp();
  lighting.headlamp.half_angle_rad = 1.5;
  SensorModel sensor = Noiseless();
  const cv::Mat clean = ShadeImage(hits.Input(), 100, 100, camera, lighting, sensor, 0);
  sensor.noise = true;
  sensor.full_well_electrons = 2000;
  sensor.read_noise_dn = 2.0;
  const cv::Mat noisy = ShadeImage(hits.Input(), 100, 100, camera, lighting, sensor, 3);
  cv::Mat diff;
  cv::subtract(noisy, clean, diff, cv::noArray(), CV_32F);
  cv::Scalar mean, stddev;
  cv::meanStdDev(diff, mean, stddev);
  const double signal = cv::mean(clean)[0];
  const double expected = std::sqrt(255.0 * signal / sensor.full_well_electrons + 4.0 + 1.0 / 12);
  EXPECT_NEAR(mean[0], 0.0, 0.2);
  EXPECT_NEAR(stddev[0], expected, 0.15 * expected) << "signal " << signal << " DN";
}

TEST(Shading, BadInputsAndOptionsThrow) {
  const ShadingCamera camera = SmallCamera(4, 5);
  Hits hits = Wall(4, 5, camera, 2.0f, Material::kRock);
  const Lighting lighting = ForwardHeadlamp();
  const SensorModel sensor;
  EXPECT_THROW(ShadeImage(hits.Input(), 5, 5, camera, lighting, sensor, 0), std::invalid_argument);
  EXPECT_THROW(ShadeImage(hits.Input(), 0, 5, camera, lighting, sensor, 0), std::invalid_argument);
  ShadingInput no_normals = hits.Input();
  no_normals.normals_world = nullptr;
  EXPECT_THROW(ShadeImage(no_normals, 4, 5, camera, lighting, sensor, 0), std::invalid_argument);
  hits.material[3] = 42;
  EXPECT_THROW(ShadeImage(hits.Input(), 4, 5, camera, lighting, sensor, 0), std::invalid_argument);
  hits.material[3] = 0;

  Lighting bad = lighting;
  bad.headlamp.direction = Eigen::Vector3d(0, 0, 2);
  EXPECT_THROW(bad.Check(), std::invalid_argument);
  bad = lighting;
  bad.headlamp.half_angle_rad = 0.0;
  EXPECT_THROW(bad.Check(), std::invalid_argument);
  bad = lighting;
  bad.light_level = -1.0;
  EXPECT_THROW(ShadeImage(hits.Input(), 4, 5, camera, bad, sensor, 0), std::invalid_argument);
  bad = lighting;
  bad.roof_lamp_positions = {Eigen::Vector3d(0, std::nan(""), 0)};
  EXPECT_THROW(bad.Check(), std::invalid_argument);
  SensorModel bad_sensor;
  bad_sensor.gamma = 0.0;
  EXPECT_THROW(bad_sensor.Check(), std::invalid_argument);
  bad_sensor = sensor;
  bad_sensor.full_well_electrons = -1.0;
  EXPECT_THROW(ShadeImage(hits.Input(), 4, 5, camera, lighting, bad_sensor, 0),
               std::invalid_argument);
  ShadingCamera bad_camera = camera;
  bad_camera.fx = 0.0;
  EXPECT_THROW(ShadeImage(hits.Input(), 4, 5, bad_camera, lighting, sensor, 0),
               std::invalid_argument);
  EXPECT_NO_THROW(ShadeImage(hits.Input(), 4, 5, camera, lighting, sensor, 0));
}

// A 752 x 480 view down a roadway along world +x: an arched rock wall (radius 2.5 m) with a coal
// band, roof mesh above 1.5 m, a floor at z = -1.5 m, 20 roof lamps. Prints the median time.
TEST(Shading, BenchmarkEurocSizedRoadwayImage) {
  constexpr int kHeight = 480, kWidth = 752;
  ShadingCamera camera{458.654, 457.296, 367.215, 248.375, Eigen::Vector3d::Zero()};
  Hits hits{kHeight, kWidth, {}, {}, {}};
  for (int v = 0; v < kHeight; ++v) {
    for (int u = 0; u < kWidth; ++u) {
      // Camera frame (x right, y down, z forward) -> world (x forward, y left, z up).
      const Eigen::Vector3f d(1.0f, static_cast<float>(-(u - camera.cx) / camera.fx),
                              static_cast<float>(-(v - camera.cy) / camera.fy));
      const float t_wall = 2.5f / std::hypot(d.y(), d.z());
      const float t_floor = d.z() < 0.0f ? -1.5f / d.z() : 1e9f;
      if (std::min(t_wall, t_floor) * d.x() > 60.0f) {
        hits.Add(Eigen::Vector3f::Zero(), Eigen::Vector3f::UnitX(), Material::kNone);
      } else if (t_floor < t_wall) {
        hits.Add(d * t_floor, Eigen::Vector3f::UnitZ(), Material::kFloor);
      } else {
        const Eigen::Vector3f p = d * t_wall;
        const Eigen::Vector3f n = -Eigen::Vector3f(0.0f, p.y(), p.z()).normalized();
        const Material m = p.z() > 1.5f                      ? Material::kRoofMesh
                           : (p.z() > -0.4f && p.z() < 0.3f) ? Material::kCoal
                                                             : Material::kRock;
        hits.Add(p, n, m);
      }
    }
  }
  Lighting lighting;
  lighting.headlamp.position = Eigen::Vector3d(0.2, 0.0, -0.3);
  for (int k = 0; k < 20; ++k) lighting.roof_lamp_positions.emplace_back(2.0 + 5.0 * k, 0.0, 2.3);
  SensorModel sensor;
  std::vector<uint8_t> image(kHeight * kWidth);
  const auto median_ms = [&]() {
    std::vector<double> ms;
    for (int frame = 0; frame < 21; ++frame) {
      const auto start = std::chrono::steady_clock::now();
      ShadeImage(hits.Input(), kHeight, kWidth, camera, lighting, sensor, frame, image.data());
      const auto stop = std::chrono::steady_clock::now();
      if (frame > 0) ms.push_back(std::chrono::duration<double, std::milli>(stop - start).count());
    }
    std::sort(ms.begin(), ms.end());
    return ms[ms.size() / 2];
  };
  sensor.noise = false;
  const double no_noise = median_ms();
  const auto lamps = lighting.roof_lamp_positions;
  lighting.roof_lamp_positions.clear();
  const double no_lamps = median_ms();
  lighting.roof_lamp_positions = lamps;
  sensor.noise = true;
  const double full = median_ms();
  const cv::Mat view(kHeight, kWidth, CV_8UC1, image.data());
  std::printf(
      "[ shading ] 752x480, 20 roof lamps, noise on: median %.2f ms over 20 frames "
      "(noise off %.2f ms, also no roof lamps %.2f ms); mean gray %.1f\n",
      full, no_noise, no_lamps, cv::mean(view)[0]);
  EXPECT_GT(cv::mean(view)[0], 5.0);
}

// The relief tilts unit normals by an amount that grows with its height, the same for every
// call (a property of the world point), and none at zero height; distant points (large pixel
// footprints) lose its octaves; bad options throw.
TEST(Relief, TiltGrowsWithHeightAndFadesWithFootprint) {
  const int n = 5000;
  std::vector<float> points, normals;
  for (int i = 0; i < n; ++i) {
    points.insert(points.end(), {0.013f * i, 1.5f, 0.7f + 0.0007f * i});
    normals.insert(normals.end(), {0.0f, -1.0f, 0.0f});
  }
  const auto rms_tilt = [&](float height_m, float footprint_m) {
    std::vector<float> out(3 * n), again(3 * n);
    const std::vector<float> footprint(n, footprint_m);
    ReliefOptions options;
    options.height_m = height_m;
    ReliefNormals(points.data(), normals.data(), footprint.data(), n, options, out.data());
    ReliefNormals(points.data(), normals.data(), footprint.data(), n, options, again.data());
    EXPECT_EQ(out, again);
    double sum = 0.0;
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3f v(out[3 * i], out[3 * i + 1], out[3 * i + 2]);
      EXPECT_NEAR(v.norm(), 1.0f, 1e-5f);
      const double angle = std::acos(std::clamp(-static_cast<double>(v.y()), -1.0, 1.0));
      sum += angle * angle;
    }
    return std::sqrt(sum / n);
  };
  EXPECT_EQ(rms_tilt(0.0f, 0.0f), 0.0);
  const double small = rms_tilt(0.002f, 0.0f), large = rms_tilt(0.006f, 0.0f);
  EXPECT_GT(small, 0.005);
  EXPECT_NEAR(large / small, 3.0, 0.3);  // the tilt is nearly linear in the height
  // A footprint of 2 cm (a pixel at about 9 m) fades the two finer octaves (2.4 and 4.9 cm).
  EXPECT_LT(rms_tilt(0.006f, 0.02f), 0.5 * large);
  ReliefOptions bad;
  bad.octaves = 0;
  EXPECT_THROW(bad.Check(), std::invalid_argument);
  bad = ReliefOptions{};
  bad.height_m = -1.0f;
  EXPECT_THROW(bad.Check(), std::invalid_argument);
}

}  // namespace
}  // namespace slslam::sim
