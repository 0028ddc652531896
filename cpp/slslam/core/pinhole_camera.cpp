#include "slslam/core/pinhole_camera.h"

#include <cmath>

#include "slslam/core/check.h"

namespace slslam {
namespace {
// What can still be a camera: a side OpenCV maps and remaps without overflow, a focal length
// below a 1e-7 rad pixel, radial-tangential coefficients an order beyond any real lens (a
// coefficient of 1e6 folds the image onto itself: nothing would be tracked).
constexpr int kMaxImageSidePx = 1 << 15;
constexpr double kMaxFocalPx = 1e7;
constexpr double kMaxDistortion = 100.0;
}  // namespace

void PinholeCamera::Check() const {
  CheckAboveInRange("camera fx", fx, 0.0, kMaxFocalPx);
  CheckAboveInRange("camera fy", fy, 0.0, kMaxFocalPx);
  SLSLAM_CHECK(std::isfinite(cx) && std::isfinite(cy),
               "camera principal point must be finite, got (", cx, ", ", cy, ")");
  SLSLAM_CHECK(width > 0 && height > 0 && width <= kMaxImageSidePx && height <= kMaxImageSidePx,
               "camera image size must be in [1, ", kMaxImageSidePx, "] per side, got ", width, "x",
               height);
}

Eigen::Matrix3d PinholeCamera::K() const {
  Eigen::Matrix3d k;
  k << fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0;
  return k;
}

Eigen::Vector2d PinholeCamera::Project(const Eigen::Vector3d& point_in_cam) const {
  SLSLAM_CHECK(point_in_cam.z() > 0.0, "cannot project a point with z = ", point_in_cam.z());
  return {fx * point_in_cam.x() / point_in_cam.z() + cx,
          fy * point_in_cam.y() / point_in_cam.z() + cy};
}

Eigen::Vector3d PinholeCamera::Unproject(const Eigen::Vector2d& pixel) const {
  return {(pixel.x() - cx) / fx, (pixel.y() - cy) / fy, 1.0};
}

void RadTanCamera::Check() const {
  pinhole.Check();
  for (double k : distortion)
    CheckInRange("camera distortion coefficient", k, -kMaxDistortion, kMaxDistortion);
}

}  // namespace slslam
