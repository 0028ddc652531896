// Tracker, local mapping, triangulation and bundle adjustment on a synthetic roadway: points and
// segments on the walls of a 4.4 m x 3.2 m box, a stereo camera driving along it, pixel noise,
// descriptors that identify each landmark. Ground truth is exact, so the tests bound errors.
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "slslam/features/image_patch.h"
#include "slslam/geometry/rotation.h"
#include "slslam/mapping/triangulation.h"
#include "slslam/optimization/bundle_adjustment.h"
#include "slslam/place/vocabulary.h"
#include "slslam/tracking/tracker.h"

namespace slslam {
namespace {

StereoRig Rig() {
  PinholeCamera camera;
  camera.fx = 458.0;
  camera.fy = 458.0;
  camera.cx = 375.5;
  camera.cy = 239.5;
  camera.width = 752;
  camera.height = 480;
  return {camera, 0.11};
}

// A point on one of the four walls (x = +-2.2, y = +-1.6; y points down) at depth z.
Eigen::Vector3d WallPoint(std::mt19937& rng, double z) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  switch (rng() % 4) {
    case 0:
      return {-2.2, 1.6 * u(rng), z};
    case 1:
      return {2.2, 1.6 * u(rng), z};
    case 2:
      return {2.2 * u(rng), -1.6, z};
    default:
      return {2.2 * u(rng), 1.6, z};
  }
}

struct Scene {
  std::vector<Eigen::Vector3d> points;
  cv::Mat point_descriptors;  // CV_32F unit rows
  std::vector<std::array<Eigen::Vector3d, 2>> lines;
  cv::Mat line_descriptors;  // CV_8U, 32 bytes per line

  explicit Scene(unsigned seed = 7) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> depth(0.0, 30.0);
    std::normal_distribution<float> gauss(0.0f, 1.0f);
    const int n = 3000;
    point_descriptors.create(n, 32, CV_32F);
    for (int i = 0; i < n; ++i) {
      points.push_back(WallPoint(rng, depth(rng)));
      cv::Mat row = point_descriptors.row(i);
      for (int k = 0; k < 32; ++k) row.at<float>(k) = gauss(rng);
      row /= cv::norm(row);
    }
    // Vertical segments on the side walls (stereo triangulates them) and roof bars across the
    // roadway, which run along the image rows: stereo cannot fix them, two keyframes apart can.
    const int m = 120;
    line_descriptors.create(m, 32, CV_8U);
    std::uniform_int_distribution<int> byte(0, 255);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int j = 0; j < m; ++j) {
      const double x = (j % 2 ? 2.2 : -2.2);
      const double z = 1.0 + 29.0 * unit(rng);
      if (j % 3 == 0) {  // across the roof
        const double x0 = -1.8 + 1.0 * unit(rng);
        lines.push_back({Eigen::Vector3d(x0, -1.6, z), Eigen::Vector3d(x0 + 2.5, -1.6, z)});
      } else {
        lines.push_back({Eigen::Vector3d(x, -1.0, z), Eigen::Vector3d(x, 1.0, z + 0.1)});
      }
      for (int k = 0; k < 32; ++k) line_descriptors.at<uchar>(j, k) = static_cast<uchar>(byte(rng));
    }
  }
};

// True pose of frame k: 5 cm forward per frame with a gentle weave and yaw.
void TruePose(int k, Eigen::Matrix3d* R_cw, Eigen::Vector3d* t_cw) {
  const Eigen::Vector3d center(0.15 * std::sin(k / 10.0), 0.02 * std::sin(k / 7.0), 0.05 * k);
  const Eigen::Matrix3d R_wc =
      Eigen::AngleAxisd(0.06 * std::sin(k / 15.0), Eigen::Vector3d::UnitY()).toRotationMatrix();
  *R_cw = R_wc.transpose();
  *t_cw = -*R_cw * center;
}

bool Visible(const PinholeCamera& camera, const Eigen::Vector3d& x_c, Eigen::Vector2d* uv) {
  if (x_c.z() < 0.3) return false;
  *uv = camera.Project(x_c);
  return uv->x() >= 1.0 && uv->y() >= 1.0 && uv->x() < camera.width - 2 &&
         uv->y() < camera.height - 2;
}

// The stereo frame the camera sees at frame k (pixel noise sigma_px); empty when `blind`.
std::shared_ptr<StereoFrame> Render(const Scene& scene, int k, double sigma_px,
                                    bool blind = false) {
  const StereoRig rig = Rig();
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  TruePose(k, &R, &t);
  std::mt19937 rng(1000 + k);
  std::normal_distribution<double> noise(0.0, sigma_px);
  Keypoints left, right;
  std::vector<Eigen::Vector2f> lu, ru;
  std::vector<int> li, ri;
  LineFeatures ll, lr;
  std::vector<int> lli, lri;
  if (!blind) {
    for (size_t i = 0; i < scene.points.size(); ++i) {
      const Eigen::Vector3d x_c = R * scene.points[i] + t;
      Eigen::Vector2d uv = Eigen::Vector2d::Zero(), uv_r = Eigen::Vector2d::Zero();
      if (!Visible(rig.camera, x_c, &uv)) continue;
      lu.push_back((uv + Eigen::Vector2d(noise(rng), noise(rng))).cast<float>());
      li.push_back(static_cast<int>(i));
      if (Visible(rig.camera, x_c - Eigen::Vector3d(rig.baseline_m, 0, 0), &uv_r)) {
        ru.push_back((uv_r + Eigen::Vector2d(noise(rng), noise(rng))).cast<float>());
        ri.push_back(static_cast<int>(i));
      }
    }
    for (size_t j = 0; j < scene.lines.size(); ++j) {
      LineSegment sl, sr;
      bool in_left = true, in_right = true;
      for (int e = 0; e < 2; ++e) {
        const Eigen::Vector3d x_c = R * scene.lines[j][e] + t;
        Eigen::Vector2d uv = Eigen::Vector2d::Zero(), uv_r = Eigen::Vector2d::Zero();
        in_left = in_left && Visible(rig.camera, x_c, &uv);
        in_right =
            in_right && Visible(rig.camera, x_c - Eigen::Vector3d(rig.baseline_m, 0, 0), &uv_r);
        (e == 0 ? sl.start : sl.end) = (uv + Eigen::Vector2d(noise(rng), noise(rng))).cast<float>();
        (e == 0 ? sr.start : sr.end) =
            (uv_r + Eigen::Vector2d(noise(rng), noise(rng))).cast<float>();
      }
      if (!in_left || sl.Length() < 20.0f) continue;
      ll.segments.push_back(sl);
      lli.push_back(static_cast<int>(j));
      if (in_right) {
        lr.segments.push_back(sr);
        lri.push_back(static_cast<int>(j));
      }
    }
  }
  auto fill = [&](const std::vector<Eigen::Vector2f>& uv, const std::vector<int>& ids,
                  Keypoints* k_out) {
    k_out->uv.resize(static_cast<Eigen::Index>(uv.size()), 2);
    k_out->descriptors.create(static_cast<int>(uv.size()), 32, CV_32F);
    for (size_t i = 0; i < uv.size(); ++i) {
      k_out->uv.row(i) = uv[i].transpose();
      scene.point_descriptors.row(ids[i]).copyTo(k_out->descriptors.row(static_cast<int>(i)));
    }
    k_out->score = Eigen::VectorXf::Ones(static_cast<Eigen::Index>(uv.size()));
    k_out->octave = Eigen::VectorXi::Zero(static_cast<Eigen::Index>(uv.size()));
  };
  fill(lu, li, &left);
  fill(ru, ri, &right);
  auto describe = [&](const std::vector<int>& ids, LineFeatures* f) {
    f->descriptors.create(static_cast<int>(ids.size()), 32, CV_8U);
    for (size_t i = 0; i < ids.size(); ++i) {
      scene.line_descriptors.row(ids[i]).copyTo(f->descriptors.row(static_cast<int>(i)));
    }
  };
  describe(lli, &ll);
  describe(lri, &lr);
  return std::make_shared<StereoFrame>(
      MakeStereoFrame(k, NsFromSeconds(0.05 * k), left, right, &ll, &lr, rig));
}

TrackerOptions Options(bool sequential = true, bool lines = true) {
  TrackerOptions options;
  options.rig = Rig();
  options.sequential = sequential;
  options.use_lines = lines;
  return options;
}

// Camera-centre error of a tracked pose against the truth (world = first camera, which is the
// true world frame here because frame 0 sits at the origin).
double CenterError(const TrackResult& r, int k) {
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  TruePose(k, &R, &t);
  return (r.cam_from_world.Center() - (-R.transpose() * t)).norm();
}

TEST(TrackerTest, TracksASyntheticRoadwayWithPointsAndLines) {
  const Scene scene;
  Tracker tracker(Options());
  double worst = 0.0;
  int keyframes = 0;
  for (int k = 0; k < 60; ++k) {
    const TrackResult r = tracker.Track(Render(scene, k, 0.5));
    ASSERT_EQ(r.state, TrackingState::kOk) << "frame " << k;
    worst = std::max(worst, CenterError(r, k));
    keyframes += r.keyframe;
    if (k > 0) {
      EXPECT_GT(r.inlier_points, 50) << "frame " << k;
      EXPECT_GT(r.inlier_lines, 2) << "frame " << k;
    }
  }
  // 3 m driven with 0.5 px noise on every keypoint (0.7 px on disparities: 7 % depth noise at
  // 5 m): the largest camera-centre error measured 1.8 cm; without optimisation it grows past it.
  EXPECT_LT(worst, 0.03);
  EXPECT_GT(keyframes, 1);
  EXPECT_LT(keyframes, 40);
  const MapExport map = tracker.ExportMap();
  EXPECT_GT(map.points.rows(), 300);
  EXPECT_GT(map.lines.rows(), 10);
  const LocalMappingStats stats = tracker.mapping_stats();
  EXPECT_EQ(stats.keyframes_processed, keyframes);
  // Horizontal segments cannot be triangulated by the stereo pair; keyframe pairs do.
  EXPECT_GT(stats.lines_triangulated, 0);
  // Map lines lie on the side walls (|x| = 2.2 m) or the roof (y = -1.6 m). Depth from a 0.11 m
  // baseline at 6 m with 0.5 px noise is good to about 5 %, so the bound is on most lines.
  int on_surface = 0;
  for (Eigen::Index i = 0; i < map.lines.rows(); ++i) {
    const double wall =
        std::abs(std::abs(map.lines(i, 0)) - 2.2) + std::abs(std::abs(map.lines(i, 3)) - 2.2);
    const double roof = std::abs(map.lines(i, 1) + 1.6) + std::abs(map.lines(i, 4) + 1.6);
    on_surface += std::min(wall, roof) < 0.2;
  }
  EXPECT_GT(on_surface, 0.8 * map.lines.rows());
}

// Bit for bit: every element of the two poses equal.
::testing::AssertionResult SamePose(const TrackResult& a, const TrackResult& b) {
  for (int i = 0; i < 9; ++i) {
    if (a.cam_from_world.rotation.data()[i] != b.cam_from_world.rotation.data()[i]) {
      return ::testing::AssertionFailure() << "rotation element " << i << " differs";
    }
  }
  for (int i = 0; i < 3; ++i) {
    if (a.cam_from_world.translation[i] != b.cam_from_world.translation[i]) {
      return ::testing::AssertionFailure() << "translation element " << i << " differs";
    }
  }
  return ::testing::AssertionSuccess();
}

TEST(TrackerTest, SequentialModeIsExactlyReproducible) {
  const Scene scene;
  Tracker a(Options()), b(Options());
  for (int k = 0; k < 30; ++k) {
    const auto frame = Render(scene, k, 0.5);
    const TrackResult ra = a.Track(frame);
    const TrackResult rb = b.Track(frame);
    ASSERT_EQ(ra.state, rb.state);
    ASSERT_TRUE(SamePose(ra, rb)) << "frame " << k;
  }
}

// mapping_overlap: each keyframe's local BA solves on its own thread and lands when the next
// keyframe comes; the landing point is fixed by the frames, so two runs agree bit for bit, and
// the frames tracked against the map before its BA stay as accurate as inline mapping's.
TEST(TrackerTest, OverlappedLocalMappingIsExactlyReproducible) {
  const Scene scene;
  TrackerOptions options = Options();
  options.mapping_overlap = true;
  Tracker a(options), b(options), inline_mapping(Options());
  double worst = 0.0;
  int keyframes = 0;
  bool differs = false;
  for (int k = 0; k < 40; ++k) {
    const auto frame = Render(scene, k, 0.5);
    const TrackResult ra = a.Track(frame);
    const TrackResult rb = b.Track(frame);
    const TrackResult ri = inline_mapping.Track(frame);
    ASSERT_EQ(ra.state, TrackingState::kOk) << "frame " << k;
    ASSERT_EQ(ra.state, rb.state);
    ASSERT_TRUE(SamePose(ra, rb)) << "frame " << k;
    differs = differs || ra.cam_from_world.translation != ri.cam_from_world.translation;
    worst = std::max(worst, CenterError(ra, k));
    keyframes += ra.keyframe;
  }
  EXPECT_TRUE(differs);  // the option reached local mapping: its frames saw another map
  EXPECT_LT(worst, 0.03);
  // Every keyframe's BA was applied, the last one by Flush.
  EXPECT_EQ(a.mapping_stats().keyframes_processed, keyframes - 1);
  a.Flush();
  EXPECT_EQ(a.mapping_stats().keyframes_processed, keyframes);
  EXPECT_GT(a.ExportMap().points.rows(), 300);
}

TEST(TrackerTest, ThreadedModeTracksToo) {
  const Scene scene;
  for (const bool brake : {false, true}) {  // with ORB-SLAM3's brake on keyframes too
    TrackerOptions options = Options(/*sequential=*/false);
    options.mapping_brake = brake;
    Tracker tracker(options);
    double worst = 0.0;
    for (int k = 0; k < 40; ++k) {
      const TrackResult r = tracker.Track(Render(scene, k, 0.5));
      ASSERT_EQ(r.state, TrackingState::kOk) << "frame " << k << " brake " << brake;
      worst = std::max(worst, CenterError(r, k));
    }
    tracker.Flush();
    EXPECT_LT(worst, 0.03) << "brake " << brake;
    EXPECT_GT(tracker.ExportMap().points.rows(), 300) << "brake " << brake;
    EXPECT_GE(tracker.mapping_stats().keyframes_processed, 2) << "brake " << brake;
    if (!brake) EXPECT_EQ(tracker.mapping_stats().ba_interrupted, 0);
  }
}

TEST(TrackerTest, AShortBlackoutIsRecentlyLostThenTrackingResumesInTheSameMap) {
  const Scene scene;
  Tracker tracker(Options(true, /*lines=*/false));
  std::vector<TrackResult> results;
  for (int k = 0; k < 40; ++k) {
    const bool blind = k >= 15 && k < 20;  // lamp out: no features at all
    results.push_back(tracker.Track(Render(scene, k, 0.5, blind)));
  }
  for (int k = 0; k < 15; ++k) EXPECT_EQ(results[k].state, TrackingState::kOk) << k;
  for (int k = 15; k < 20; ++k) EXPECT_EQ(results[k].state, TrackingState::kRecentlyLost) << k;
  // The prediction slows down while lost (decaying velocity): it never overtakes the truth.
  for (int k = 16; k < 20; ++k) {
    const double step =
        (results[k].cam_from_world.Center() - results[k - 1].cam_from_world.Center()).norm();
    EXPECT_LT(step, 0.05) << k;
  }
  for (int k = 20; k < 40; ++k) {
    EXPECT_EQ(results[k].state, TrackingState::kOk) << k;
    EXPECT_LT(CenterError(results[k], k), 0.05) << k;
  }
  EXPECT_EQ(tracker.num_maps(), 1);
}

// The camera's motion of TruePose as a function of time (frame k at 0.05 k s), for IMU samples.
Rigid3d TrueWorldFromCam(double t) {
  const double k = t / 0.05;
  const Eigen::Vector3d center(0.15 * std::sin(k / 10.0), 0.02 * std::sin(k / 7.0), 0.05 * k);
  const Eigen::Matrix3d R_wc =
      Eigen::AngleAxisd(0.06 * std::sin(k / 15.0), Eigen::Vector3d::UnitY()).toRotationMatrix();
  return Rigid3d(R_wc, center);
}

// IMU samples of a body on the camera (body_from_cam the identity) at 200 Hz over [0, duration]:
// white noise at EuRoC's densities, a constant bias; gravity along +y (down in the first
// camera's frame, the world).
void FeedTrueImu(double duration, Tracker* tracker) {
  const Eigen::Vector3d g_world(0.0, 9.81, 0.0);
  const InertialOptions noise;
  std::mt19937 rng(17);
  std::normal_distribution<double> unit(0.0, 1.0);
  const double dt = 0.005, h = 1e-3;
  const Eigen::Vector3d gyro_bias(0.002, -0.001, 0.003), acc_bias(0.03, 0.02, -0.04);
  for (int i = 0; i * dt <= duration + 1e-9; ++i) {
    const double t = i * dt;
    const Rigid3d pose = TrueWorldFromCam(t);
    const Eigen::Vector3d omega =
        LogSO3(Eigen::Quaterniond(TrueWorldFromCam(t - h).rotation.transpose() *
                                  TrueWorldFromCam(t + h).rotation)) /
        (2 * h);
    const Eigen::Vector3d a_world = (TrueWorldFromCam(t + h).translation - 2.0 * pose.translation +
                                     TrueWorldFromCam(t - h).translation) /
                                    (h * h);
    Eigen::Vector3d wn, an;
    for (int j = 0; j < 3; ++j) {
      wn(j) = unit(rng) * noise.gyro_noise_density / std::sqrt(dt);
      an(j) = unit(rng) * noise.acc_noise_density / std::sqrt(dt);
    }
    tracker->AddImu(NsFromSeconds(t), omega + gyro_bias + wn,
                    pose.rotation.transpose() * (a_world - g_world) + acc_bias + an);
  }
}

// 10 s lit (the IMU initialises after 1 s; the rest pins its biases down), 10 s with no feature
// at all (lamp out: 200 frames, 10 m driven), 2 s lit again. Camera-only the tracker is lost
// after recently_lost_frames; with the IMU every dark frame is INERTIAL, its position within 3
// sigma of the truth by the uncertainty it reports, and tracking resumes in the same map. With
// `local_ba_keyframes`, local BA also has the IMU between keyframes.
void TenSecondsWithoutAnyFeature(int local_ba_keyframes) {
  const Scene scene;
  TrackerOptions options = Options(true, /*lines=*/false);
  options.imu.local_ba_keyframes = local_ba_keyframes;
  Tracker tracker(options);
  FeedTrueImu(22.0, &tracker);
  std::vector<TrackResult> results;
  for (int k = 0; k < 440; ++k) {
    const bool blind = k >= 200 && k < 400;
    results.push_back(tracker.Track(Render(scene, k, 0.5, blind)));
  }
  for (int k = 0; k < 200; ++k) EXPECT_EQ(results[k].state, TrackingState::kOk) << k;
  EXPECT_TRUE(results[45].imu_initialised);
  for (int k = 200; k < 400; ++k) {
    EXPECT_EQ(results[k].state, TrackingState::kInertial) << k;
    EXPECT_TRUE(results[k].imu_initialised) << k;
  }
  const TrackResult& last_dark = results[399];
  const double error = CenterError(last_dark, 399);
  EXPECT_LT(error, 3.0 * last_dark.position_sigma_m)
      << "error " << error << " m, sigma " << last_dark.position_sigma_m << " m";
  EXPECT_LT(last_dark.position_sigma_m, 1.0);  // the lost bound: 10 % of the 10 m driven
  EXPECT_GT(last_dark.position_sigma_m, results[200].position_sigma_m);
  // Lit again 10 m on, where the map never reached: the first lit frame becomes a keyframe at
  // the IMU's pose (INERTIAL), the next ones track on its points, no further off than the IMU
  // had drifted.
  EXPECT_EQ(results[400].state, TrackingState::kInertial);
  EXPECT_TRUE(results[400].keyframe);
  for (int k = 405; k < 440; ++k) {
    EXPECT_EQ(results[k].state, TrackingState::kOk) << k;
    EXPECT_LT(CenterError(results[k], k), error + 0.05) << k;
  }
  EXPECT_EQ(tracker.num_maps(), 1);
  EXPECT_GE(tracker.stats().inertial_frames, 200);
  EXPECT_LE(tracker.stats().inertial_frames, 205);
  const Tracker::InertialReport report = tracker.inertial_report();
  EXPECT_TRUE(report.has_imu);
  ASSERT_TRUE(report.first_init_t_ns.has_value());
  EXPECT_GT(*report.first_init_t_ns, NsFromSeconds(0.9));
  EXPECT_LT(*report.first_init_t_ns, NsFromSeconds(2.0));
  EXPECT_EQ(report.first_pose_t_ns, 0);
  EXPECT_LT((report.gyro_bias - Eigen::Vector3d(0.002, -0.001, 0.003)).norm(), 1e-3);
  // The map knows gravity (+y in the first camera's frame): its loops correct in 4 DoF.
  Eigen::Vector3d g_map;
  ASSERT_TRUE(tracker.MapGravityDirection(0, &g_map));
  EXPECT_GT(g_map.dot(Eigen::Vector3d::UnitY()), std::cos(1.0 * M_PI / 180.0));
  if (local_ba_keyframes == 0) {
    EXPECT_EQ(tracker.mapping_stats().ba_inertial_factors, 0);
  } else {  // (each local BA after the initialisation has at least one)
    EXPECT_GT(tracker.mapping_stats().ba_inertial_factors,
              tracker.mapping_stats().keyframes_processed);
  }
}

TEST(TrackerTest, WithTheImuTenSecondsWithoutAnyFeatureStayInOneMap) {
  TenSecondsWithoutAnyFeature(0);
}

TEST(TrackerTest, WithTheImuInLocalBaTenSecondsWithoutAnyFeatureStayInOneMap) {
  TenSecondsWithoutAnyFeature(10);
}

// The ten dark seconds above under a lost bound they pass (5 cm, 1 % of the distance): LOST part
// way through. With resume_map_after_lost the IMU dead-reckons on, and after
// new_map_after_lost_frames lit frames the map resumes at its pose (INERTIAL, a keyframe); no
// further off than the dead reckoning's own sigma allows. Without it a second map starts.
void LostInTheDarkThenLit(bool resume) {
  const Scene scene;
  TrackerOptions options = Options(true, /*lines=*/false);
  options.imu.lost_sigma_min_m = 0.05;
  options.imu.lost_sigma_fraction = 0.01;
  options.imu.resume_map_after_lost = resume;
  Tracker tracker(options);
  FeedTrueImu(22.0, &tracker);
  std::vector<TrackResult> results;
  for (int k = 0; k < 440; ++k) {
    results.push_back(tracker.Track(Render(scene, k, 0.5, /*blind=*/k >= 200 && k < 400)));
  }
  EXPECT_EQ(results[200].state, TrackingState::kInertial);
  EXPECT_EQ(results[399].state, TrackingState::kLost);
  const int wait = options.new_map_after_lost_frames;
  for (int k = 400; k < 400 + wait; ++k) EXPECT_EQ(results[k].state, TrackingState::kLost) << k;
  const TrackResult& back = results[400 + wait];
  EXPECT_TRUE(back.keyframe);
  for (int k = 402 + wait; k < 440; ++k) EXPECT_EQ(results[k].state, TrackingState::kOk) << k;
  if (!resume) {
    EXPECT_EQ(back.state, TrackingState::kNewMap);
    EXPECT_EQ(tracker.num_maps(), 2);
    EXPECT_EQ(tracker.stats().maps_resumed, 0);
    return;
  }
  EXPECT_EQ(back.state, TrackingState::kInertial);
  // (the LOST frames report the dead-reckoned state's sigma, grown past the bound; the resumed
  // state restarts it, and goes on without initialising again)
  const double sigma = results[399 + wait].position_sigma_m;
  EXPECT_GT(sigma, 0.05);
  EXPECT_LT(back.position_sigma_m, 0.5 * sigma);
  for (int k = 400 + wait; k < 440; ++k) EXPECT_TRUE(results[k].imu_initialised) << k;
  EXPECT_EQ(tracker.inertial_report().initialisations, 1);
  EXPECT_LT(CenterError(back, 400 + wait), 3.0 * sigma) << "sigma " << sigma;
  for (int k = 402 + wait; k < 440; ++k) {
    EXPECT_LT(CenterError(results[k], k), CenterError(back, 400 + wait) + 0.05) << k;
  }
  EXPECT_EQ(tracker.num_maps(), 1);
  EXPECT_EQ(tracker.stats().maps_resumed, 1);
  EXPECT_EQ(tracker.stats().maps_started, 1);
}

TEST(TrackerTest, WithTheImuAMapLostInTheDarkResumesAtTheImuPose) { LostInTheDarkThenLit(true); }

TEST(TrackerTest, WithTheImuAndNoResumeAMapLostInTheDarkEndsAndANewOneStarts) {
  LostInTheDarkThenLit(false);
}

TEST(TrackerTest, ALongBlackoutFreezesThePoseThenANewMapStarts) {
  // After the blackout the camera sees another place (other landmarks): nothing to recover.
  const Scene scene, elsewhere(99);
  const TrackerOptions options = Options(true, /*lines=*/false);
  Tracker tracker(options);
  std::vector<TrackResult> results;
  for (int k = 0; k < 50; ++k) {
    const bool blind = k >= 15 && k < 40;
    results.push_back(tracker.Track(Render(k < 40 ? scene : elsewhere, k, 0.5, blind)));
  }
  const int recently = options.recently_lost_frames;
  for (int k = 15; k < 15 + recently; ++k) {
    EXPECT_EQ(results[k].state, TrackingState::kRecentlyLost) << k;
  }
  for (int k = 15 + recently; k < 40; ++k) {
    EXPECT_EQ(results[k].state, TrackingState::kLost) << k;
    // Frozen: every lost frame has the pose of the first one.
    EXPECT_EQ(results[k].cam_from_world.translation,
              results[15 + recently].cam_from_world.translation)
        << k;
  }
  // No vocabulary: no relocalisation. The first new_map_after_lost_frames frames with features
  // still try the old map (and stay lost, frozen); the next one starts map 2 at the frozen pose,
  // and tracking goes on there.
  const int wait = options.new_map_after_lost_frames;
  ASSERT_TRUE(wait > 0 && 40 + wait < 49) << wait;
  for (int k = 40; k < 40 + wait; ++k) {
    EXPECT_EQ(results[k].state, TrackingState::kLost) << k;
    EXPECT_EQ(results[k].cam_from_world.translation, results[39].cam_from_world.translation) << k;
  }
  EXPECT_EQ(results[40 + wait].state, TrackingState::kNewMap);
  EXPECT_EQ(results[40 + wait].cam_from_world.translation, results[39].cam_from_world.translation);
  for (int k = 41 + wait; k < 50; ++k) EXPECT_EQ(results[k].state, TrackingState::kOk) << k;
  EXPECT_EQ(tracker.num_maps(), 2);
}

TEST(TrackerTest, WithoutAWaitTheFirstLitFrameAfterALongBlackoutStartsANewMap) {
  const Scene scene, elsewhere(99);
  TrackerOptions options = Options(true, /*lines=*/false);
  options.new_map_after_lost_frames = 0;
  Tracker tracker(options);
  std::vector<TrackResult> results;
  for (int k = 0; k < 45; ++k) {
    const bool blind = k >= 15 && k < 40;
    results.push_back(tracker.Track(Render(k < 40 ? scene : elsewhere, k, 0.5, blind)));
  }
  EXPECT_EQ(results[39].state, TrackingState::kLost);
  EXPECT_EQ(results[40].state, TrackingState::kNewMap);
  for (int k = 41; k < 45; ++k) EXPECT_EQ(results[k].state, TrackingState::kOk) << k;
  EXPECT_EQ(tracker.num_maps(), 2);
}

TEST(TrackerTest, ALongBlackoutRecoversAlongThePreLossMotionWithoutAVocabulary) {
  // 1.25 m driven in the dark; the frozen pose is behind, but the local map tried from poses
  // along the motion before the loss finds the old map's landmarks: tracking resumes in map 1
  // without a vocabulary.
  const Scene scene;
  Tracker tracker(Options(true, /*lines=*/false));
  std::vector<TrackResult> results;
  for (int k = 0; k < 50; ++k) {
    const bool blind = k >= 15 && k < 40;
    results.push_back(tracker.Track(Render(scene, k, 0.5, blind)));
  }
  EXPECT_EQ(results[39].state, TrackingState::kLost);
  for (int k = 40; k < 50; ++k) {
    EXPECT_EQ(results[k].state, TrackingState::kOk) << k;
    EXPECT_LT(CenterError(results[k], k), 0.08) << k;  // 6.3 cm measured
  }
  EXPECT_EQ(tracker.num_maps(), 1);
}

// A vocabulary trained on the scene's own descriptors, written to a temporary file.
std::string SceneVocabulary(const Scene& scene) {
  // Training "images" of 100 landmarks each: a word then occurs in a few of them, so its IDF
  // weight is positive (a word found in every training image weighs nothing).
  std::vector<cv::Mat> images;
  for (int i = 0; i + 100 <= scene.point_descriptors.rows; i += 100) {
    images.push_back(scene.point_descriptors.rowRange(i, i + 100));
  }
  VocabularyOptions options;
  options.branching = 8;
  options.levels = 3;
  // One file per test: ctest runs the tests in parallel processes, which must not share it.
  const std::string path = ::testing::TempDir() + "/tracker_test_vocabulary_" +
                           ::testing::UnitTest::GetInstance()->current_test_info()->name() +
                           ".slvoc";
  Vocabulary::Train(images, options).Save(path);
  return path;
}

TEST(TrackerTest, RelocalisesAfterALongBlackoutIntoTheOldMap) {
  const Scene scene;
  TrackerOptions options = Options(true, /*lines=*/false);
  options.vocabulary_path = SceneVocabulary(scene);
  Tracker tracker(options);
  ASSERT_TRUE(tracker.has_vocabulary());
  std::vector<TrackResult> results;
  for (int k = 0; k < 50; ++k) {
    const bool blind = k >= 15 && k < 40;
    results.push_back(tracker.Track(Render(scene, k, 0.5, blind)));
  }
  EXPECT_EQ(results[39].state, TrackingState::kLost);
  // The robot drove 1.25 m in the dark; the view still overlaps the map: relocalised there.
  EXPECT_EQ(results[40].state, TrackingState::kRelocalised);
  // From 1.25 m past the last keyframe, with 0.5 px noise: 2.3 cm measured; the frames after it
  // track the relocalised map within 6 cm (5.6 cm measured on the first, 3 cm after).
  EXPECT_LT(CenterError(results[40], 40), 0.04);
  for (int k = 41; k < 50; ++k) {
    EXPECT_EQ(results[k].state, TrackingState::kOk) << k;
    EXPECT_LT(CenterError(results[k], k), 0.08) << k;
  }
  EXPECT_EQ(tracker.num_maps(), 1);
  EXPECT_EQ(tracker.stats().relocalisations, 1);
}

TEST(TrackerTest, RelocalisesAFrameAtAKnownKeyframePoseWithinOneCentimetre) {
  const Scene scene;
  TrackerOptions options = Options(true, /*lines=*/false);
  options.vocabulary_path = SceneVocabulary(scene);
  options.recently_lost_frames = 2;
  Tracker tracker(options);
  for (int k = 0; k < 30; ++k)
    ASSERT_EQ(tracker.Track(Render(scene, k, 0.5)).state, TrackingState::kOk);
  for (int k = 30; k < 34; ++k) tracker.Track(Render(scene, k, 0.5, /*blind=*/true));
  // Back at the start of the run (frame 0 was the first keyframe), with a later frame number.
  auto frame = Render(scene, 0, 0.5);
  frame->index = 34;
  frame->t_ns = NsFromSeconds(34 * 0.05);
  const TrackResult r = tracker.Track(frame);
  ASSERT_EQ(r.state, TrackingState::kRelocalised);
  EXPECT_LT(CenterError(r, 0), 0.01);
}

// The frame seen from the true pose `pose_k`, presented as input frame `index`.
std::shared_ptr<StereoFrame> RenderAt(const Scene& scene, int pose_k, int index, double sigma_px,
                                      bool blind = false) {
  auto frame = Render(scene, pose_k, sigma_px, blind);
  frame->index = index;
  frame->t_ns = NsFromSeconds(0.05 * index);
  return frame;
}

// Camera centre of true pose k in the frame of true pose `origin` (a map's world frame is its
// first keyframe's camera).
Eigen::Vector3d TrueCenterIn(int k, int origin) {
  Eigen::Matrix3d R, R0;
  Eigen::Vector3d t, t0;
  TruePose(k, &R, &t);
  TruePose(origin, &R0, &t0);
  return R0 * (-R.transpose() * t) + t0;
}

// Map 1 from 3.0-4.5 m along the roadway; a long blackout; the robot reappears at 0 m and drives
// forward again. Relocalisation is switched off (its inlier bar is out of reach), so a second map
// starts at the frozen pose, 4.5 m off; once its keyframes see map 1's landmarks, loop closing
// merges it into map 1, and every frame of the second stretch ends up at its true place in map
// 1's frame.
void ExpectASecondMapMergedIntoTheFirst(bool sequential, bool global_ba = true,
                                        bool overlap = false) {
  const Scene scene;
  TrackerOptions options = Options(sequential, /*lines=*/false);
  options.mapping_overlap = overlap;
  options.loop_closing.global_ba = global_ba;
  options.vocabulary_path = SceneVocabulary(scene);
  options.relocalisation.min_inliers = 1e9;
  options.new_map_after_lost_frames = 0;  // the first lit frame starts the second map
  Tracker tracker(options);
  for (int i = 0; i < 30; ++i) {
    ASSERT_EQ(tracker.Track(RenderAt(scene, 60 + i, i, 0.5)).state, TrackingState::kOk) << i;
  }
  for (int i = 30; i < 55; ++i) tracker.Track(RenderAt(scene, 0, i, 0.5, /*blind=*/true));
  const TrackResult first = tracker.Track(RenderAt(scene, 0, 55, 0.5));
  ASSERT_EQ(first.state, TrackingState::kNewMap);
  EXPECT_GT((first.cam_from_world.Center() - TrueCenterIn(0, 60)).norm(), 4.0);
  for (int i = 56; i < 145; ++i) {
    ASSERT_NE(tracker.Track(RenderAt(scene, i - 55, i, 0.5)).state, TrackingState::kLost) << i;
  }
  tracker.Flush();  // threaded: local mapping, loop closing and the global BA are done
  EXPECT_EQ(tracker.num_maps(), 2);
  EXPECT_EQ(tracker.live_maps(), 1);
  EXPECT_EQ(tracker.loop_stats().merges, 1);
  EXPECT_EQ(tracker.loop_stats().loops_accepted, 0);
  EXPECT_EQ(tracker.loop_stats().global_ba_runs, global_ba ? 1 : 0);
  // The welding BA runs where no global BA follows inline (threaded: it runs in the background).
  EXPECT_EQ(tracker.loop_stats().welding_ba_runs, !global_ba || !sequential ? 1 : 0);
  // The final trajectory: the second stretch sits where it truly was, in map 1's frame (1.6 cm
  // at most measured; the frozen start was 4.5 m off). Before the tracker followed the merge
  // (prediction and frame record from the merged keyframe), tracking was lost right after it.
  int second = 0;
  for (const FramePose& f : tracker.Trajectory()) {
    const int pose_k = f.index < 30 ? 60 + f.index : f.index - 55;
    const double error = (f.cam_from_world.Center() - TrueCenterIn(pose_k, 60)).norm();
    EXPECT_LT(error, 0.05) << "frame " << f.index;
    second += f.index >= 55;
  }
  EXPECT_EQ(second, 90);
}

TEST(TrackerTest, ASecondMapIsMergedIntoTheFirstWhereTheyOverlap) {
  ExpectASecondMapMergedIntoTheFirst(/*sequential=*/true);
}

// The same with each local BA overlapped with tracking: the merge moves the map while the merged
// keyframe's solve is pending, whose solution is then dropped (the map's correction epoch).
TEST(TrackerTest, AMergeWithAnOverlappedLocalBaPending) {
  ExpectASecondMapMergedIntoTheFirst(/*sequential=*/true, /*global_ba=*/true, /*overlap=*/true);
}

// The same in threaded mode: loop closing on the mapping thread, the global BA after the merge on
// its own thread while tracking goes on; frames and keyframes made meanwhile follow its
// correction, and Flush waits for it (Trajectory flushes).
TEST(TrackerTest, ThreadedModeMergesAndRunsTheGlobalBaInTheBackground) {
  ExpectASecondMapMergedIntoTheFirst(/*sequential=*/false);
}

// Without a global BA the welding BA over the seam (the merged keyframe's and the candidate's
// covisible keyframes) is what joins the two maps' landmarks after the essential graph.
TEST(TrackerTest, AWeldingBaJoinsTheSeamOfAMergeWithoutAGlobalBa) {
  ExpectASecondMapMergedIntoTheFirst(/*sequential=*/true, /*global_ba=*/false);
}

// The scene's first 5 m of walls repeated every 5 m with the same descriptors: one arch after
// another, as in a roadway with steel sets.
Scene RepeatedScene() {
  Scene scene;
  Scene repeated = scene;
  repeated.points.clear();
  repeated.lines.clear();
  std::vector<int> point_rows, line_rows;
  for (int copy = 0; copy < 6; ++copy) {
    const Eigen::Vector3d shift(0.0, 0.0, 5.0 * copy);
    for (size_t i = 0; i < scene.points.size(); ++i) {
      if (scene.points[i].z() >= 5.0) continue;
      repeated.points.push_back(scene.points[i] + shift);
      point_rows.push_back(static_cast<int>(i));
    }
    for (size_t j = 0; j < scene.lines.size(); ++j) {
      if (std::max(scene.lines[j][0].z(), scene.lines[j][1].z()) >= 5.0) continue;
      repeated.lines.push_back({scene.lines[j][0] + shift, scene.lines[j][1] + shift});
      line_rows.push_back(static_cast<int>(j));
    }
  }
  repeated.point_descriptors.create(static_cast<int>(point_rows.size()), 32, CV_32F);
  for (size_t r = 0; r < point_rows.size(); ++r) {
    scene.point_descriptors.row(point_rows[r]).copyTo(repeated.point_descriptors.row(r));
  }
  repeated.line_descriptors.create(static_cast<int>(line_rows.size()), 32, CV_8U);
  for (size_t r = 0; r < line_rows.size(); ++r) {
    scene.line_descriptors.row(line_rows[r]).copyTo(repeated.line_descriptors.row(r));
  }
  return repeated;
}

TEST(TrackerTest, RepeatedArchesDoNotCloseAFalseLoop) {
  // Driving 10 m through walls that repeat every 5 m: a view 5 m on looks like one 5 m back, so
  // the bag of words proposes the older keyframes and PnP verifies them, 5 m off. No true loop
  // exists, and a 5 m correction after 5-10 m of travel cannot be drift: loop closing must
  // reject every such hypothesis and leave the trajectory alone.
  const Scene scene = RepeatedScene();
  TrackerOptions options = Options(true, /*lines=*/false);
  options.vocabulary_path = SceneVocabulary(scene);
  Tracker tracker(options);
  double worst = 0.0;
  for (int k = 0; k < 200; ++k) {
    const TrackResult r = tracker.Track(Render(scene, k, 0.5));
    ASSERT_EQ(r.state, TrackingState::kOk) << "frame " << k;
    worst = std::max(worst, CenterError(r, k));
  }
  const LoopClosingStats loops = tracker.loop_stats();
  // 13 hypotheses verified geometrically (local-map inliers >= 80), all rejected as implausible;
  // largest camera-centre error 4.7 cm measured.
  EXPECT_GT(loops.candidates_verified, 0);  // the aliasing was there to be rejected
  EXPECT_EQ(loops.loops_rejected, loops.candidates_verified);
  EXPECT_EQ(loops.loops_detected, 0);
  EXPECT_EQ(loops.loops_accepted, 0);
  EXPECT_EQ(loops.merges, 0);
  EXPECT_EQ(tracker.live_maps(), 1);
  EXPECT_LT(worst, 0.1);
}

// The scene with a mover: a 1.2 m x 1 m board of 200 textured points, 5 m down the roadway in the
// middle of the view, sliding sideways by `step_m` per frame (a cart crossing).
Scene WithMover(const Scene& scene, int k, double step_m) {
  Scene out = scene;
  std::mt19937 rng(4242);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<float> gauss(0.0f, 1.0f);
  const int n = 200;
  cv::Mat descriptors(n, 32, CV_32F);
  for (int i = 0; i < n; ++i) {
    const double x = -1.5 + 1.2 * unit(rng) + step_m * k;
    out.points.emplace_back(x, -0.2 + 1.0 * unit(rng), 5.0 + 0.1 * unit(rng));
    cv::Mat row = descriptors.row(i);
    for (int c = 0; c < 32; ++c) row.at<float>(c) = gauss(rng);
    row /= cv::norm(row);
  }
  cv::vconcat(scene.point_descriptors, descriptors, out.point_descriptors);
  return out;
}

TEST(TrackerTest, TheDynamicCellFilterKeepsAMoverOutOfTheMap) {
  // Map points inside the roadway (away from the walls, roof and floor) can only come from the
  // mover. With the filter the cells it crosses are invalidated once its matches disagree with
  // the frame's pose, so it makes (almost) no map points; without it every keyframe adds some.
  const Scene scene;
  int interior[2] = {0, 0}, masked[2] = {0, 0};
  double worst[2] = {0.0, 0.0};
  for (const bool on : {true, false}) {
    TrackerOptions options = Options(true, /*lines=*/false);
    options.dynamic_cells = on;
    Tracker tracker(options);
    for (int k = 0; k < 50; ++k) {
      const TrackResult r = tracker.Track(Render(WithMover(scene, k, 0.04), k, 0.5));
      ASSERT_EQ(r.state, TrackingState::kOk) << "frame " << k;
      masked[on] += r.masked_keypoints;
      worst[on] = std::max(worst[on], CenterError(r, k));
    }
    const MapExport map = tracker.ExportMap();
    for (Eigen::Index i = 0; i < map.points.rows(); ++i) {
      interior[on] += std::abs(map.points(i, 0)) < 1.9 && std::abs(map.points(i, 1)) < 1.3;
    }
  }
  // Measured: 15 interior map points with the filter, 2,155 without; the largest camera-centre
  // error 1.4 cm with it, 1.62 m without (the mover, near the vanishing point where keypoints
  // crowd, drags the pose along).
  EXPECT_EQ(masked[0], 0);
  EXPECT_GT(masked[1], 0);
  EXPECT_LT(20 * interior[1], interior[0]);
  EXPECT_LT(worst[1], 0.05);
  EXPECT_GT(worst[0], 0.2);
}

TEST(TrackerTest, LinesCountWhenPointsAreFew) {
  // A sparse scene: about 20-25 point inliers per frame, below min_inliers = 27 on their own,
  // and 12-16 line inliers: counted with the lines the frames are tracked, without them lost.
  Scene scene;
  scene.points.resize(150);
  scene.point_descriptors = scene.point_descriptors.rowRange(0, 150).clone();
  for (const double weight : {1.0, 0.0}) {
    TrackerOptions options = Options();
    options.line_inlier_weight = weight;
    options.min_init_points = 20;
    options.min_inliers = 27;
    Tracker tracker(options);
    int ok = 0;
    for (int k = 0; k < 20; ++k)
      ok += tracker.Track(Render(scene, k, 0.5)).state == TrackingState::kOk;
    if (weight > 0.0) {
      EXPECT_GE(ok, 18);
    } else {
      EXPECT_LE(ok, 5);
    }
  }
}

TEST(TrackerTest, AFirstBlindFrameIsNotInitialized) {
  const Scene scene;
  Tracker tracker(Options());
  EXPECT_EQ(tracker.Track(Render(scene, 0, 0.5, true)).state, TrackingState::kNotInitialized);
  EXPECT_EQ(tracker.Track(Render(scene, 1, 0.5)).state, TrackingState::kOk);
  EXPECT_THROW(tracker.Track(nullptr), std::invalid_argument);
}

TEST(TriangulationTest, TwoViewPointIsExact) {
  Eigen::Matrix3d R1, R2;
  Eigen::Vector3d t1, t2;
  TruePose(0, &R1, &t1);
  TruePose(20, &R2, &t2);
  const Eigen::Vector3d p(0.7, -0.4, 6.0);
  const Eigen::Vector3d c1 = R1 * p + t1, c2 = R2 * p + t2;
  Eigen::Vector3d q;
  ASSERT_TRUE(TriangulatePoint(Rigid3d(R1, t1), c1 / c1.z(), Rigid3d(R2, t2), c2 / c2.z(), &q));
  EXPECT_LT((q - p).norm(), 1e-9);
}

TEST(TriangulationTest, KeyframePairsAddPointsWithoutStereoAndHorizontalLines) {
  const Scene scene;
  const StereoRig rig = Rig();
  Map map;
  MutexLock lock(map.mutex());
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  // Frames rendered without the right image: nothing has stereo depth.
  auto mono = [&](int k) {
    auto f = Render(scene, k, 0.0);
    f->u_right.assign(f->u_right.size(), -1.0);
    f->depth.assign(f->depth.size(), -1.0);
    f->line_has_depth.assign(f->line_has_depth.size(), false);
    return f;
  };
  const auto frame0 = mono(0), frame20 = mono(20);
  // Keyframes 0 and 20 in `m`, linked in the covisibility graph by one shared point (returned).
  auto add_pair = [&](Map& m, int* b_id) {
    TruePose(0, &R, &t);
    auto ka = m.AddKeyFrame(Rigid3d(R, t), frame0);
    TruePose(20, &R, &t);
    auto kb = m.AddKeyFrame(Rigid3d(R, t), frame20);
    auto shared = m.AddPoint(Eigen::Vector3d::Zero(), cv::Mat::zeros(1, 32, CV_32F), ka->id);
    m.AddPointObservation(shared->id, ka->id, 0);
    m.AddPointObservation(shared->id, kb->id, 0);
    m.UpdateConnections(kb->id);
    *b_id = kb->id;
    return shared->id;
  };
  int b_id = -1;
  const int anchor_id = add_pair(map, &b_id);
  const TriangulationStats stats = CreateNewLandmarks(&map, b_id, rig);
  EXPECT_GT(stats.points, 200);
  EXPECT_GT(stats.lines, 5);
  // Without points (TriangulationOptions::points): the same lines, and no map point but the
  // shared one.
  TriangulationOptions lines_only;
  lines_only.points = false;
  Map copy;
  {
    MutexLock copy_lock(copy.mutex());
    int copy_b_id = -1;
    add_pair(copy, &copy_b_id);
    const TriangulationStats no_points = CreateNewLandmarks(&copy, copy_b_id, rig, lines_only);
    EXPECT_EQ(no_points.points, 0);
    EXPECT_EQ(copy.points().size(), 1u);
    EXPECT_EQ(no_points.lines, stats.lines);
  }
  // Every new point lies on a wall; every new line too.
  int on_wall = 0;
  for (const auto& [id, p] : map.points()) {
    if (id == anchor_id) continue;
    const Eigen::Vector3d& x = p->position;
    on_wall += std::abs(std::abs(x.x()) - 2.2) < 0.05 || std::abs(std::abs(x.y()) - 1.6) < 0.05;
  }
  EXPECT_EQ(on_wall, stats.points);
  for (const auto& [id, l] : map.lines()) {  // on a side wall or the roof, exactly
    (void)id;
    for (const Eigen::Vector3d& x : {l->start, l->end}) {
      EXPECT_LT(std::min(std::abs(std::abs(x.x()) - 2.2), std::abs(x.y() + 1.6)), 1e-3) << id;
    }
  }
}

// TriangulationOptions::patch_window_px: each triangulated point keeps the new keyframe's image
// around its keypoint there (what the tracker aligns later matches to) and its depth there;
// without the keyframe's image, or with 0, no patch. Local mapping releases the image after.
TEST(TriangulationTest, TriangulatedPointsKeepTheNewKeyframesPatch) {
  const Scene scene;
  const StereoRig rig = Rig();
  auto mono = [&](int k) {
    auto f = Render(scene, k, 0.0);
    f->u_right.assign(f->u_right.size(), -1.0);
    f->depth.assign(f->depth.size(), -1.0);
    return f;
  };
  const auto frame0 = mono(0), frame20 = mono(20);
  cv::Mat image(rig.camera.height, rig.camera.width, CV_8UC1);
  cv::randu(image, 0, 256);
  // Keyframes 0 and 20 linked by one shared point; the second (the new one) with `with_image`.
  auto make = [&](Map& m, bool with_image) {
    MutexLock lock(m.mutex());
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
    TruePose(0, &R, &t);
    auto ka = m.AddKeyFrame(Rigid3d(R, t), frame0);
    TruePose(20, &R, &t);
    auto kb = m.AddKeyFrame(Rigid3d(R, t), frame20);
    if (with_image) kb->left_image = image.clone();
    auto shared = m.AddPoint(Eigen::Vector3d::Zero(), cv::Mat::zeros(1, 32, CV_32F), ka->id);
    m.AddPointObservation(shared->id, ka->id, 0);
    m.AddPointObservation(shared->id, kb->id, 0);
    m.UpdateConnections(kb->id);
    return std::make_pair(kb->id, shared->id);
  };
  TriangulationOptions options;
  options.patch_window_px = 5;
  Map map;
  const auto [b_id, shared_id] = make(map, true);
  {
    MutexLock lock(map.mutex());
    ASSERT_GT(CreateNewLandmarks(&map, b_id, rig, options).points, 200);
    const KeyFrame& kb = *map.keyframe(b_id);
    int with_patch = 0;
    for (const auto& [id, p] : map.points()) {
      if (id == shared_id) continue;
      const int i = p->observations.at(b_id);
      const cv::Mat expected =
          SamplePatch(image, frame20->keypoints.uv(i, 0), frame20->keypoints.uv(i, 1), 5);
      ASSERT_EQ(p->patch.empty(), expected.empty()) << id;
      if (expected.empty()) continue;
      ++with_patch;
      EXPECT_EQ(cv::norm(p->patch, expected, cv::NORM_INF), 0.0) << id;
      const double depth =
          (kb.cam_from_world.rotation * p->position + kb.cam_from_world.translation).z();
      EXPECT_NEAR(p->patch_depth_m, depth, 1e-9) << id;
    }
    EXPECT_GT(with_patch, 200);
  }
  for (const bool with_image : {false, true}) {
    for (const int window : {0, 5}) {
      if (with_image && window == 5) continue;  // (above)
      TriangulationOptions o;
      o.patch_window_px = window;
      Map m;
      const auto [id, shared] = make(m, with_image);
      MutexLock lock(m.mutex());
      ASSERT_GT(CreateNewLandmarks(&m, id, rig, o).points, 200);
      for (const auto& [pid, p] : m.points()) EXPECT_TRUE(p->patch.empty()) << pid;
    }
  }
  // Local mapping triangulates with the patches and releases the image: inline, on its own
  // thread and with the solve overlapped (every layout the tracker runs).
  LocalMapperOptions mapping;
  mapping.triangulation.patch_window_px = 5;
  for (const auto& [sequential, overlap] : {std::pair{true, false}, {false, false}, {true, true}}) {
    LocalMapper mapper(rig, mapping, sequential, overlap);
    Map mapped;
    const int mapped_b = make(mapped, true).first;
    mapper.Insert(&mapped, mapped_b);
    mapper.Flush();
    MutexLock lock(mapped.mutex());
    EXPECT_TRUE(mapped.keyframe(mapped_b)->left_image.empty()) << sequential << overlap;
    int patched = 0;
    for (const auto& [pid, p] : mapped.points()) patched += !p->patch.empty();
    EXPECT_GT(patched, 100) << sequential << overlap;
  }
}

// Four stereo keyframes (the first fixed, the others perturbed) of the scene's first 400 points
// and 30 lines (those seen at least twice), the points and lines perturbed.
BaProblem PerturbedWindow(const Scene& scene, const StereoRig& rig,
                          std::vector<Eigen::Matrix3d>* true_R_out,
                          std::vector<Eigen::Vector3d>* true_t_out) {
  BaProblem problem;
  std::vector<Eigen::Matrix3d>& true_R = *true_R_out;
  std::vector<Eigen::Vector3d>& true_t = *true_t_out;
  const int frames[] = {0, 8, 16, 24};
  for (int k : frames) {
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
    TruePose(k, &R, &t);
    true_R.push_back(R);
    true_t.push_back(t);
    Eigen::Matrix<double, 6, 1> delta;
    delta << 0.03, -0.02, 0.04, 0.01, -0.01, 0.008;
    Rigid3d cam_from_world(R, t);
    if (k != 0) PerturbPose(delta, &cam_from_world);
    problem.poses.push_back({cam_from_world, k == 0});
  }
  std::mt19937 rng(3);
  std::normal_distribution<double> shift(0.0, 0.05);
  for (size_t i = 0; i < 400; ++i) {
    const Eigen::Vector3d& p = scene.points[i];
    int seen = 0;
    for (size_t f = 0; f < true_R.size(); ++f) {
      const Eigen::Vector3d x_c = true_R[f] * p + true_t[f];
      Eigen::Vector2d uv;
      if (!Visible(rig.camera, x_c, &uv)) continue;
      BaPointObservation o;
      o.pose = static_cast<int>(f);
      o.point = static_cast<int>(problem.points.size());
      o.stereo = true;
      o.observed << uv, uv.x() - rig.camera.fx * rig.baseline_m / x_c.z();
      problem.point_observations.push_back(o);
      ++seen;
    }
    if (seen) problem.points.push_back(p + Eigen::Vector3d(shift(rng), shift(rng), shift(rng)));
  }
  for (size_t j = 0; j < 30; ++j) {
    const auto& seg = scene.lines[j];
    int seen = 0;
    for (size_t f = 0; f < true_R.size(); ++f) {
      Eigen::Vector2d s, e;
      if (!Visible(rig.camera, true_R[f] * seg[0] + true_t[f], &s) ||
          !Visible(rig.camera, true_R[f] * seg[1] + true_t[f], &e)) {
        continue;
      }
      BaLineObservation o;
      o.pose = static_cast<int>(f);
      o.line = static_cast<int>(problem.lines.size());
      o.start_px = s;
      o.end_px = e;
      problem.line_observations.push_back(o);
      ++seen;
    }
    if (seen >= 2) {
      problem.lines.push_back(PluckerLine::FromPoints(seg[0] + Eigen::Vector3d(0.03, 0.0, 0.0),
                                                      seg[1] + Eigen::Vector3d(0.0, 0.02, 0.0)));
    } else {  // drop observations of lines seen once
      while (!problem.line_observations.empty() &&
             problem.line_observations.back().line == static_cast<int>(problem.lines.size())) {
        problem.line_observations.pop_back();
      }
    }
  }
  return problem;
}

TEST(BundleAdjustmentTest, RecoversPerturbedPosesPointsAndLines) {
  const Scene scene;
  const StereoRig rig = Rig();
  std::vector<Eigen::Matrix3d> true_R;
  std::vector<Eigen::Vector3d> true_t;
  const BaProblem problem = PerturbedWindow(scene, rig, &true_R, &true_t);
  ASSERT_GT(problem.lines.size(), 5u);
  // The defaults, and the lines' pull with the dogleg (the pull's bias towards the start of each
  // pass is too small here to keep the noise-free scene from being recovered).
  BundleAdjustmentOptions pulled;
  pulled.line_prior_weight = 10.0;
  pulled.dogleg_with_lines = true;
  // Lines held in the directions their observers leave undetermined (here, with many views of
  // each, every direction is determined above the bound: the same recovery).
  BundleAdjustmentOptions held;
  held.line_min_information_per_rad2 = 1.0;
  // The own solver (landmarks eliminated, dense reduced system) and Ceres.
  BundleAdjustmentOptions own, ceres;
  own.own_solver = true;
  ceres.own_solver = false;
  for (const BundleAdjustmentOptions& options : {own, ceres, pulled, held}) {
    SCOPED_TRACE(options.dogleg_with_lines                     ? "dogleg, pulled lines"
                 : options.line_min_information_per_rad2 > 0.0 ? "weak directions held"
                 : options.own_solver                          ? "own solver"
                                                               : "Ceres");
    BaProblem solved = problem;
    const BundleAdjustmentReport report = SolveBundleAdjustment(rig, &solved, options);
    ASSERT_TRUE(report.solved);
    EXPECT_LT(report.final_cost, 1e-6 * report.initial_cost);
    // The steps of both passes are counted, at most the caps, the rejected ones among them.
    EXPECT_GT(report.iterations, 0);
    EXPECT_LE(report.iterations, options.robust_iterations + options.refine_iterations);
    EXPECT_GE(report.rejected_steps, 0);
    EXPECT_LT(report.rejected_steps, report.iterations);
    for (size_t f = 0; f < true_R.size(); ++f) {
      const Eigen::Vector3d c = solved.poses[f].cam_from_world.Center();
      const Eigen::Vector3d c_true = -true_R[f].transpose() * true_t[f];
      EXPECT_LT((c - c_true).norm(), 1e-4) << "pose " << f;
    }
    for (bool outlier : report.point_outlier) EXPECT_FALSE(outlier);
    for (bool outlier : report.line_outlier) EXPECT_FALSE(outlier);
  }
}

// The own solver follows Ceres' Levenberg-Marquardt on the same problem: with pixel noise, mono
// observations and gross outliers, both passes take the same steps (accepted and rejected) to
// the same estimate, and classify the same observations as outliers.
TEST(BundleAdjustmentTest, OwnSolverFollowsCeresStepForStep) {
  const Scene scene;
  const StereoRig rig = Rig();
  std::vector<Eigen::Matrix3d> true_R;
  std::vector<Eigen::Vector3d> true_t;
  BaProblem problem = PerturbedWindow(scene, rig, &true_R, &true_t);
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, 0.7);
  for (size_t i = 0; i < problem.point_observations.size(); ++i) {
    BaPointObservation& o = problem.point_observations[i];
    for (int k = 0; k < 3; ++k) o.observed(k) += noise(rng);
    if (i % 5 == 0) o.stereo = false;
    if (i % 23 == 0) o.observed.x() += 25.0;  // gross outliers
  }
  for (BaLineObservation& o : problem.line_observations) {
    o.start_px += Eigen::Vector2d(noise(rng), noise(rng));
    o.end_px += Eigen::Vector2d(noise(rng), noise(rng));
  }
  BundleAdjustmentOptions own, ceres;
  own.own_solver = true;
  ceres.own_solver = false;
  BaProblem by_own = problem, by_ceres = problem;
  const BundleAdjustmentReport a = SolveBundleAdjustment(rig, &by_own, own);
  const BundleAdjustmentReport b = SolveBundleAdjustment(rig, &by_ceres, ceres);
  ASSERT_TRUE(a.solved);
  ASSERT_TRUE(b.solved);
  EXPECT_EQ(a.iterations, b.iterations);
  EXPECT_EQ(a.rejected_steps, b.rejected_steps);
  EXPECT_NEAR(a.initial_cost, b.initial_cost, 1e-9 * b.initial_cost);
  EXPECT_NEAR(a.final_cost, b.final_cost, 1e-6 * b.final_cost);
  EXPECT_EQ(a.point_outlier, b.point_outlier);
  EXPECT_EQ(a.line_outlier, b.line_outlier);
  int outliers = 0;
  for (bool outlier : a.point_outlier) outliers += outlier;
  EXPECT_GT(outliers, 0);  // the gross ones were found
  for (size_t f = 0; f < problem.poses.size(); ++f) {
    EXPECT_LT((by_own.poses[f].cam_from_world.Center() - by_ceres.poses[f].cam_from_world.Center())
                  .norm(),
              1e-7)
        << "pose " << f;
  }
  for (size_t i = 0; i < problem.points.size(); ++i) {
    EXPECT_LT((by_own.points[i] - by_ceres.points[i]).norm(), 1e-6) << "point " << i;
  }
  for (size_t i = 0; i < problem.lines.size(); ++i) {
    EXPECT_LT((by_own.lines[i].v.normalized() - by_ceres.lines[i].v.normalized()).norm(), 1e-6)
        << "line " << i;
  }
}

}  // namespace
}  // namespace slslam
