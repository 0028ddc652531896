// Camera intrinsics. Pixel convention: (u, v) = (column, row), origin at the centre of the
// top-left pixel, as OpenCV uses it.
#pragma once

#include <array>

#include <Eigen/Core>

namespace slslam {

// An ideal (undistorted or rectified) pinhole camera.
struct PinholeCamera {
  double fx = 0.0;  ///< focal length along u [px]
  double fy = 0.0;  ///< focal length along v [px]
  double cx = 0.0;  ///< principal point u [px]
  double cy = 0.0;  ///< principal point v [px]
  int width = 0;    ///< image width [px]
  int height = 0;   ///< image height [px]

  // Throws std::invalid_argument when a value is not finite or not positive where it must be.
  void Check() const;
  Eigen::Matrix3d K() const;
  // Projects a point in the camera frame (z forward) to pixels; z must be positive.
  Eigen::Vector2d Project(const Eigen::Vector3d& point_in_cam) const;
  // Ray through a pixel, normalised so that z = 1.
  Eigen::Vector3d Unproject(const Eigen::Vector2d& pixel) const;
};

// A pinhole camera with radial-tangential (plumb bob) distortion, as EuRoC's sensor.yaml gives it.
struct RadTanCamera {
  PinholeCamera pinhole;
  std::array<double, 4> distortion{0.0, 0.0, 0.0, 0.0};  ///< k1, k2, p1, p2 [-]

  void Check() const;
};

}  // namespace slslam
