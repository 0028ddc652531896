// The tracker's map-line helpers for long edges the camera drives along: the part of a line in
// front of the camera and inside the image, the direction parallel lines share, a map line
// refitted to the stereo endpoints of several keyframes, and its extent grown to a new segment.
#include <array>
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "slslam/tracking/tracker_internal.h"

namespace slslam {
namespace {

PinholeCamera Camera() {
  PinholeCamera camera;
  camera.fx = camera.fy = 450.0;
  camera.cx = 376.0;
  camera.cy = 240.0;
  camera.width = 752;
  camera.height = 480;
  return camera;
}

TEST(LineHelpers, ClipToImageKeepsThePartInside) {
  const PinholeCamera camera = Camera();
  LineSegment seg;
  seg.start = {-200.0f, 600.0f};  // below-left of the image
  seg.end = {300.0f, 100.0f};
  ASSERT_TRUE(tracker_detail::ClipToImage(camera, &seg));
  for (const Eigen::Vector2f& p : {seg.start, seg.end}) {
    EXPECT_GE(p.x(), -1e-3f);
    EXPECT_LE(p.x(), camera.width - 1 + 1e-3f);
    EXPECT_GE(p.y(), -1e-3f);
    EXPECT_LE(p.y(), camera.height - 1 + 1e-3f);
    // still on the line x + y = 400
    EXPECT_NEAR(p.x() + p.y(), 400.0f, 1e-2f);
  }
  EXPECT_NEAR(seg.end.x(), 300.0f, 1e-3f);  // the end inside is kept
  LineSegment outside;
  outside.start = {-50.0f, -10.0f};
  outside.end = {-10.0f, 900.0f};
  EXPECT_FALSE(tracker_detail::ClipToImage(camera, &outside));
}

TEST(LineHelpers, ClipToFrontCutsAtTheMinimumDepth) {
  const Rigid3d identity;
  Eigen::Vector3d s, e;
  ASSERT_TRUE(
      tracker_detail::ClipToFront(identity, {1.0, 0.5, -2.0}, {1.0, 0.5, 6.0}, 0.1, &s, &e));
  EXPECT_NEAR(s.z(), 0.1, 1e-12);
  EXPECT_NEAR(e.z(), 6.0, 1e-12);
  EXPECT_NEAR(s.x(), 1.0, 1e-12);
  EXPECT_FALSE(
      tracker_detail::ClipToFront(identity, {0.0, 0.0, -2.0}, {0.0, 0.0, 0.05}, 0.1, &s, &e));
}

TEST(LineHelpers, SharedDirectionOnlyForParallelLines) {
  std::vector<LineObservation> lines(2);
  lines[0].line_w = PluckerLine::FromPoints({-1.0, 1.0, 0.0}, {-1.0, 1.0, 5.0});
  lines[1].line_w = PluckerLine::FromPoints({1.0, 1.0, 5.0}, {1.05, 1.0, 0.0});  // reversed
  const Eigen::Vector3d d = tracker_detail::SharedDirection(lines, {true, true});
  EXPECT_GT(std::abs(d.z()), 0.99);
  EXPECT_NEAR(d.norm(), 1.0, 1e-12);
  lines[1].line_w = PluckerLine::FromPoints({0.0, 1.0, 2.0}, {0.0, -1.0, 2.0});  // vertical
  EXPECT_TRUE(tracker_detail::SharedDirection(lines, {true, true}).isZero());
  // an outlier does not count
  EXPECT_GT(std::abs(tracker_detail::SharedDirection(lines, {true, false}).z()), 0.99);
  EXPECT_TRUE(tracker_detail::SharedDirection(lines, {false, false}).isZero());
}

TEST(LineHelpers, RefitToStereoSupportRecoversTheEdgeDirection) {
  // A floor edge along world z at x = -1.5, y = 1.2 (camera frame at identity: y down). Ten
  // keyframes 0.5 m apart along z each see it from 1.5 to 6 m ahead with stereo depth noise
  // growing as depth squared; one pair alone tilts the line, the fit of all of them does not.
  std::mt19937 rng(3);
  std::normal_distribution<double> unit(0.0, 1.0);
  const double sigma_z_at_1m = 0.01;  // depth error at 1 m [m], x depth^2
  auto stereo_endpoints = [&]() {
    std::array<Eigen::Vector3d, 2> out;
    int i = 0;
    for (double depth : {1.5, 6.0}) {
      const Eigen::Vector3d truth(-1.5, 1.2, depth);
      const double z = depth + sigma_z_at_1m * depth * depth * unit(rng);
      out[i++] = truth * (z / depth);  // moved along the viewing ray
    }
    return out;
  };
  MapLine line;
  const std::array<Eigen::Vector3d, 2> first = stereo_endpoints();
  line.line = PluckerLine::FromPoints(first[0], first[1]);
  line.start = first[0];
  line.end = first[1];
  const double first_tilt = std::acos(std::abs(line.line.v.normalized().z()));
  for (int k = 1; k < 10; ++k) {
    Rigid3d world_from_cam;
    world_from_cam.translation = {0.0, 0.0, 0.5 * k};
    const std::array<Eigen::Vector3d, 2> endpoints = stereo_endpoints();
    std::array<Eigen::Vector3d, 2> in_cam;
    for (int i = 0; i < 2; ++i) in_cam[i] = endpoints[i];  // same view of the same edge
    if (k == 1) tracker_detail::AddStereoSupport(Rigid3d(), first, &line);
    tracker_detail::AddStereoSupport(world_from_cam, in_cam, &line);
    tracker_detail::RefitToSupport(&line);
  }
  const double tilt = std::acos(std::abs(line.line.v.normalized().z()));
  EXPECT_LT(tilt, 0.01) << "first pair's tilt " << first_tilt;
  EXPECT_GT(first_tilt, 2.0 * tilt);  // (the fit, not the first pair, is what is accurate)
  EXPECT_LT((line.line.ClosestPointTo({-1.5, 1.2, 4.0}) - Eigen::Vector3d(-1.5, 1.2, 4.0)).norm(),
            0.03);
}

TEST(LineHelpers, ExtendToSegmentGrowsAlongTheLine) {
  const PinholeCamera camera = Camera();
  MapLine line;
  line.line = PluckerLine::FromPoints({-1.5, 1.2, 2.0}, {-1.5, 1.2, 4.0});
  line.start = {-1.5, 1.2, 2.0};
  line.end = {-1.5, 1.2, 4.0};
  // The camera 1 m further along sees the edge from 1.5 to 6 m ahead of it.
  Rigid3d cam_from_world;
  cam_from_world.translation = {0.0, 0.0, -1.0};
  LineSegment seg;
  seg.start = camera.Project({-1.5, 1.2, 1.5}).cast<float>();
  seg.end = camera.Project({-1.5, 1.2, 6.0}).cast<float>();
  tracker_detail::ExtendToSegment(camera, cam_from_world, seg, /*max_depth_m=*/6.6, &line);
  EXPECT_NEAR(line.start.z(), 2.0, 1e-3);  // (1.5 ahead of the camera is 2.5 in the world)
  EXPECT_NEAR(line.end.z(), 7.0, 1e-2);
  EXPECT_NEAR(line.end.x(), -1.5, 1e-6);
  // Beyond max_depth_m the segment's far end is not taken.
  tracker_detail::ExtendToSegment(camera, cam_from_world, seg, /*max_depth_m=*/5.0, &line);
  EXPECT_NEAR(line.end.z(), 7.0, 1e-2);
}

}  // namespace
}  // namespace slslam
