#include "slslam/core/pinhole_camera.h"

#include <cmath>

#include "slslam/core/check.h"

namespace slslam {

void PinholeCamera::Check() const {
  SLSLAM_CHECK(std::isfinite(fx) && fx > 0.0, "camera fx must be finite and > 0, got ", fx);
  SLSLAM_CHECK(std::isfinite(fy) && fy > 0.0, "camera fy must be finite and > 0, got ", fy);
  SLSLAM_CHECK(std::isfinite(cx) && std::isfinite(cy),
               "camera principal point must be finite, got (", cx, ", ", cy, ")");
  SLSLAM_CHECK(width > 0 && height > 0, "camera image size must be positive, got ", width, "x",
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
  for (double k : distortion) {
    Require(std::isfinite(k), "camera distortion coefficients must be finite");
  }
}

}  // namespace slslam
