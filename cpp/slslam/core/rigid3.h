// A rigid transform of 3-D space (rotation + translation), the type poses travel in.
//
// Naming follows COLMAP: a transform is named for the frames it maps between, `b_from_a`, and
// maps a point's coordinates in frame a to its coordinates in frame b:
//
//   x_b = b_from_a * x_a = b_from_a.rotation * x_a + b_from_a.translation.
//
// A camera pose is `cam_from_world` (world -> camera, the R_cw, t_cw of the older code and of the
// map file); `world_from_cam` is its inverse, whose translation is the camera centre in the world.
// Composition chains the frames: c_from_a = c_from_b * b_from_a.
//
// The rotation is kept as a matrix, not a quaternion: every operation below is the matrix
// expression the code used on separate R, t pairs, evaluated in the same order, so that results
// are bit-for-bit those of the code it replaced.
#pragma once

#include <Eigen/Core>

namespace slslam {

struct Rigid3d {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  ///< orthonormal, det +1 [-]
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();   ///< [m]

  Rigid3d() = default;
  Rigid3d(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) : rotation(R), translation(t) {}

  // x_b = rotation * x_a + translation.
  Eigen::Vector3d operator*(const Eigen::Vector3d& x_a) const {
    return rotation * x_a + translation;
  }

  // c_from_a = (*this = c_from_b) * b_from_a: rotation R_cb R_ba, translation R_cb t_ba + t_cb.
  Rigid3d operator*(const Rigid3d& b_from_a) const {
    return Rigid3d(rotation * b_from_a.rotation, rotation * b_from_a.translation + translation);
  }

  // a_from_b for b_from_a: rotation R^T, translation -R^T t, with R^T formed first (Eigen
  // multiplies a stored matrix in another order than the transposed expression, so this may
  // differ from Center() in the last bit).
  Rigid3d Inverse() const {
    const Eigen::Matrix3d R_inv = rotation.transpose();
    return Rigid3d(R_inv, -R_inv * translation);
  }

  // For cam_from_world: the camera centre in the world frame, -R^T t (the translation of
  // Inverse() up to rounding), as the product with the transposed expression.
  Eigen::Vector3d Center() const { return -rotation.transpose() * translation; }

  // The homogeneous 4 x 4 matrix [R t; 0 0 0 1].
  Eigen::Matrix4d ToMatrix4() const {
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    m.topLeftCorner<3, 3>() = rotation;
    m.topRightCorner<3, 1>() = translation;
    return m;
  }

  // From a homogeneous matrix; the bottom row is not checked.
  static Rigid3d FromMatrix4(const Eigen::Matrix4d& m) {
    return Rigid3d(m.topLeftCorner<3, 3>(), m.topRightCorner<3, 1>());
  }
};

}  // namespace slslam
