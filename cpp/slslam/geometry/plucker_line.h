// 3-D lines for the map (the SL-SLAM paper's line representation): Pluecker coordinates for
// initialisation, transformation and projection; the 4-DoF orthonormal representation (U, W) for
// optimisation.
//
// A Pluecker line L = (n, v): v is the direction, n = p x v for any point p on the line (the normal
// of the plane through the line and the origin, scaled by the line's distance to the origin times
// |v|). (n, v) and (s n, s v) are the same line for any s != 0.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "slslam/core/pinhole_camera.h"
#include "slslam/core/rigid3.h"

namespace slslam {

struct PluckerLine {
  Eigen::Vector3d n = Eigen::Vector3d::Zero();   ///< moment: p x v for a point p on the line
  Eigen::Vector3d v = Eigen::Vector3d::UnitX();  ///< direction

  // The line through two distinct points.
  static PluckerLine FromPoints(const Eigen::Vector3d& a, const Eigen::Vector3d& b);
  // The intersection of two planes pi = (normal, d) with normal . x + d = 0, through the dual
  // Pluecker matrix L* = pi1 pi2^T - pi2 pi1^T. Throws when the planes are (nearly) parallel.
  static PluckerLine FromPlanes(const Eigen::Vector4d& plane1, const Eigen::Vector4d& plane2);

  // The same line expressed in frame b, given the line in frame a and
  // x_b = b_from_a * x_a = R_ba x_a + t_ba.
  PluckerLine Transformed(const Rigid3d& b_from_a) const;
  // Scaled so that |v| = 1 (then |n| is the distance to the origin).
  PluckerLine Normalized() const;
  // Point of the line nearest to the origin.
  Eigen::Vector3d ClosestPointToOrigin() const;
  // Point of the line nearest to p (moves display endpoints onto a re-estimated line).
  Eigen::Vector3d ClosestPointTo(const Eigen::Vector3d& p) const;
  // Point of the line nearest to the ray {s * ray_direction, s > 0} from the origin (used to cut a
  // map line to the extent of an observed segment). Falls back to ClosestPointToOrigin for a ray
  // parallel to the line.
  Eigen::Vector3d ClosestPointToRay(const Eigen::Vector3d& ray_direction) const;
};

// Image line l = (l1, l2, l3), l1 u + l2 v + l3 = 0, of a line given in the camera frame: only n
// matters, l = K_L n with the line projection matrix K_L = [fy 0 0; 0 fx 0; -fy cx -fx cy fx fy].
Eigen::Matrix3d LineProjectionMatrix(const PinholeCamera& camera);

// The plane through the camera centre (origin of the camera frame) and an image segment, expressed
// in the world frame given the camera pose cam_from_world (x_c = R x_w + t). Used for two-view
// triangulation: the line of two such planes from two views is the 3-D line.
Eigen::Vector4d BackProjectedPlane(const PinholeCamera& camera, const Rigid3d& cam_from_world,
                                   const Eigen::Vector2d& start_px, const Eigen::Vector2d& end_px);

// Orthonormal representation: U in SO(3) (columns n/|n|, v/|v|, n x v / |n x v|) and
// W = [cos phi, -sin phi; sin phi, cos phi] with (cos phi, sin phi) = (|n|, |v|) / |(n, v)|.
// 4 DoF: an increment (theta, dphi) updates U <- U Exp(theta), phi <- phi + dphi.
struct OrthonormalLine {
  Eigen::Quaterniond U = Eigen::Quaterniond::Identity();
  double phi = 0.0;  ///< [rad], in (0, pi/2) for a line not through the origin

  // Throws std::invalid_argument for a line with v = 0 or non-finite values. A line through the
  // origin (n = 0) gets an arbitrary u1 perpendicular to v.
  static OrthonormalLine FromPlucker(const PluckerLine& line);
  PluckerLine ToPlucker() const;  ///< n = cos(phi) u1, v = sin(phi) u2 (|(n, v)| = 1)
  OrthonormalLine Plus(const Eigen::Vector4d& delta) const;
  // d(n, v) / d(delta) at delta = 0 (6 x 4), for the Plucker coordinates ToPlucker returns.
  Eigen::Matrix<double, 6, 4> PluckerJacobian() const;
};

}  // namespace slslam
