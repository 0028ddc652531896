#include "slslam/sim/ray_caster.h"

#include <cmath>
#include <stdexcept>

#include <gtest/gtest.h>

namespace slslam::sim {
namespace {

// A square wall of half-size `half` in the plane x = `x`, as two triangles.
RayCaster Wall(float x, float half, uint8_t material) {
  RayCaster::Vertices v(4, 3);
  v << x, -half, -half, x, half, -half, x, half, half, x, -half, half;
  RayCaster::Triangles f(2, 3);
  f << 0, 1, 2, 0, 2, 3;
  return RayCaster(v, f, {material, material});
}

TEST(RayCaster, DistancesNormalsAndMaterialsOfAKnownWall) {
  const RayCaster wall = Wall(5.0f, 10.0f, 3);
  RayCaster::Vertices directions(3, 3);
  directions << 1, 0, 0, -1, 0, 0, 0.6f, 0.8f, 0;
  const RayHits hits = wall.Cast(Eigen::Vector3f(1, 0, 0), directions);
  EXPECT_NEAR(hits.t[0], 4.0f, 1e-5f);
  EXPECT_TRUE(std::isinf(hits.t[1]));
  EXPECT_EQ(hits.material[1], 255);
  EXPECT_NEAR(hits.t[2], 4.0f / 0.6f, 1e-4f);
  EXPECT_NEAR(std::abs(hits.normal[0]), 1.0f, 1e-6f);
  EXPECT_EQ(hits.material[0], 3);
  EXPECT_NEAR(hits.point[6], 5.0f, 1e-5f);  // x of the third hit
}

TEST(RayCaster, PinholeDepthIsTheWallDistanceEverywhere) {
  const RayCaster wall = Wall(4.0f, 50.0f, 0);
  // Camera looking along world +x: camera z = world x, camera x = world -y, camera y = world -z.
  Eigen::Matrix3d R_world_cam;
  R_world_cam << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  std::vector<float> depth;
  const RayHits hits = wall.CastPinhole(R_world_cam, Eigen::Vector3d::Zero(), 100, 100, 31.5, 23.5,
                                        64, 48, nullptr, &depth);
  ASSERT_EQ(depth.size(), 64u * 48u);
  for (float d : depth) EXPECT_NEAR(d, 4.0f, 1e-4f);
  // Pixel (u, v) = (0, 0) looks up-left: world +y and +z.
  EXPECT_GT(hits.point[1], 0.0f);
  EXPECT_GT(hits.point[2], 0.0f);
}

TEST(RayCaster, TheNearerOfStaticAndDynamicMeshesWins) {
  const RayCaster far_wall = Wall(8.0f, 10.0f, 0), near_box = Wall(3.0f, 0.5f, 8);
  RayCaster::Vertices directions(2, 3);
  directions << 1, 0, 0, 0.8f, 0.6f, 0.0f;
  const RayHits hits = far_wall.Cast(Eigen::Vector3f::Zero(), directions, &near_box);
  EXPECT_NEAR(hits.t[0], 3.0f, 1e-5f);
  EXPECT_EQ(hits.material[0], 8);
  EXPECT_NEAR(hits.t[1], 10.0f, 1e-4f);  // misses the small box, hits the far wall
  EXPECT_EQ(hits.material[1], 0);
}

TEST(RayCaster, RejectsBadMeshes) {
  RayCaster::Vertices v(3, 3);
  v << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  RayCaster::Triangles f(1, 3);
  f << 0, 1, 3;
  EXPECT_THROW(RayCaster(v, f, {0}), std::invalid_argument);  // index out of range
  f << 0, 1, 2;
  EXPECT_THROW(RayCaster(v, f, {0, 1}), std::invalid_argument);  // material count
  v(0, 0) = NAN;
  EXPECT_THROW(RayCaster(v, f, {0}), std::invalid_argument);
  EXPECT_THROW(RayCaster(v, RayCaster::Triangles(0, 3), {}), std::invalid_argument);
}

}  // namespace
}  // namespace slslam::sim
