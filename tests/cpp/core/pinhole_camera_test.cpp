#include "slslam/core/pinhole_camera.h"

#include <limits>
#include <stdexcept>

#include <gtest/gtest.h>

namespace slslam {
namespace {

PinholeCamera EurocLikeCamera() { return {458.654, 457.296, 367.215, 248.375, 752, 480}; }

TEST(PinholeCamera, ProjectUnprojectRoundTrip) {
  const PinholeCamera camera = EurocLikeCamera();
  const Eigen::Vector3d point(0.3, -0.2, 2.5);
  const Eigen::Vector2d pixel = camera.Project(point);
  EXPECT_NEAR(pixel.x(), 458.654 * 0.3 / 2.5 + 367.215, 1e-12);
  const Eigen::Vector3d ray = camera.Unproject(pixel);
  EXPECT_TRUE(ray.isApprox(point / point.z(), 1e-12));
}

TEST(PinholeCamera, CheckRejectsBadValues) {
  PinholeCamera camera = EurocLikeCamera();
  camera.fx = -1.0;
  EXPECT_THROW(camera.Check(), std::invalid_argument);
  camera = EurocLikeCamera();
  camera.cy = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(camera.Check(), std::invalid_argument);
  camera = EurocLikeCamera();
  camera.width = 0;
  EXPECT_THROW(camera.Check(), std::invalid_argument);
}

TEST(PinholeCamera, ProjectBehindCameraThrows) {
  EXPECT_THROW(EurocLikeCamera().Project(Eigen::Vector3d(0, 0, -1)), std::invalid_argument);
}

}  // namespace
}  // namespace slslam
