#include "slslam/geometry/plucker_line.h"

#include <cmath>

#include "slslam/core/check.h"
#include "slslam/geometry/rotation.h"

namespace slslam {

PluckerLine PluckerLine::FromPoints(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  Require(a.allFinite() && b.allFinite(), "line points must be finite");
  Require((b - a).norm() > 1e-12, "a line needs two distinct points");
  PluckerLine line;
  line.v = b - a;
  line.n = a.cross(line.v);
  return line;
}

PluckerLine PluckerLine::FromPlanes(const Eigen::Vector4d& plane1, const Eigen::Vector4d& plane2) {
  Require(plane1.allFinite() && plane2.allFinite(), "planes must be finite");
  const Eigen::Matrix4d dual = plane1 * plane2.transpose() - plane2 * plane1.transpose();
  // L* = [[v]x, n; -n^T, 0] up to scale.
  PluckerLine line;
  line.v = Eigen::Vector3d(dual(2, 1), dual(0, 2), dual(1, 0));
  line.n = dual.block<3, 1>(0, 3);
  const double scale = plane1.head<3>().norm() * plane2.head<3>().norm();
  Require(scale > 0.0 && line.v.norm() > 1e-9 * scale,
          "planes are parallel: the line is not determined (too little parallax)");
  return line;
}

PluckerLine PluckerLine::Transformed(const Rigid3d& b_from_a) const {
  PluckerLine out;
  out.v = b_from_a.rotation * v;
  out.n = b_from_a.rotation * n + b_from_a.translation.cross(out.v);
  return out;
}

PluckerLine PluckerLine::Normalized() const {
  const double s = v.norm();
  Require(s > 0.0, "line direction is zero");
  return {n / s, v / s};
}

Eigen::Vector3d PluckerLine::ClosestPointToOrigin() const { return v.cross(n) / v.squaredNorm(); }

Eigen::Vector3d PluckerLine::ClosestPointTo(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d p0 = ClosestPointToOrigin();
  const Eigen::Vector3d d = v.normalized();
  return p0 + (p - p0).dot(d) * d;
}

Eigen::Vector3d PluckerLine::ClosestPointToRay(const Eigen::Vector3d& ray_direction) const {
  // Line p0 + s d, ray t r: the normal equations of min |p0 + s d - t r|^2 give
  // s (1 - b^2) = b (r . p0) - d . p0 with b = d . r (and d . p0 = 0 for this p0).
  const Eigen::Vector3d p0 = ClosestPointToOrigin();
  const Eigen::Vector3d d = v.normalized();
  const Eigen::Vector3d r = ray_direction.normalized();
  const double b = d.dot(r);
  const double denominator = 1.0 - b * b;
  if (denominator < 1e-9) return p0;
  const double s = (b * r.dot(p0) - d.dot(p0)) / denominator;
  return p0 + s * d;
}

Eigen::Matrix3d LineProjectionMatrix(const PinholeCamera& camera) {
  Eigen::Matrix3d k;
  k << camera.fy, 0.0, 0.0, 0.0, camera.fx, 0.0, -camera.fy * camera.cx, -camera.fx * camera.cy,
      camera.fx * camera.fy;
  return k;
}

Eigen::Vector4d BackProjectedPlane(const PinholeCamera& camera, const Rigid3d& cam_from_world,
                                   const Eigen::Vector2d& start_px, const Eigen::Vector2d& end_px) {
  // In the camera frame the plane goes through the origin with normal ray(start) x ray(end).
  const Eigen::Vector3d normal_c = camera.Unproject(start_px).cross(camera.Unproject(end_px));
  Require(normal_c.norm() > 1e-12, "degenerate image segment: its endpoints coincide");
  // n_c . x_c = 0 with x_c = R x_w + t  =>  (R^T n_c) . x_w + n_c . t = 0.
  Eigen::Vector4d plane;
  plane.head<3>() = cam_from_world.rotation.transpose() * normal_c;
  plane(3) = normal_c.dot(cam_from_world.translation);
  return plane;
}

OrthonormalLine OrthonormalLine::FromPlucker(const PluckerLine& line) {
  Require(line.n.allFinite() && line.v.allFinite(), "line coordinates must be finite");
  const double nn = line.n.norm();
  const double vn = line.v.norm();
  Require(vn > 0.0, "line direction is zero");
  const Eigen::Vector3d u2 = line.v / vn;
  Eigen::Vector3d u1;
  if (nn > 1e-12 * vn) {
    u1 = line.n / nn;
  } else {  // through the origin: any unit vector perpendicular to v
    u1 = u2.unitOrthogonal();
  }
  Eigen::Matrix3d u;
  u.col(0) = u1;
  u.col(1) = u2;
  u.col(2) = u1.cross(u2).normalized();
  // n is perpendicular to v by construction; re-orthogonalise against rounding.
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(u, Eigen::ComputeFullU | Eigen::ComputeFullV);
  u = svd.matrixU() * svd.matrixV().transpose();
  OrthonormalLine out;
  out.U = Eigen::Quaterniond(u).normalized();
  out.phi = std::atan2(vn, nn);
  return out;
}

PluckerLine OrthonormalLine::ToPlucker() const {
  const Eigen::Matrix3d u = U.toRotationMatrix();
  return {std::cos(phi) * u.col(0), std::sin(phi) * u.col(1)};
}

OrthonormalLine OrthonormalLine::Plus(const Eigen::Vector4d& delta) const {
  OrthonormalLine out;
  out.U = (U * ExpQuaternion(delta.head<3>())).normalized();
  out.phi = phi + delta(3);
  return out;
}

Eigen::Matrix<double, 6, 4> OrthonormalLine::PluckerJacobian() const {
  const Eigen::Matrix3d u = U.toRotationMatrix();
  const double w1 = std::cos(phi);
  const double w2 = std::sin(phi);
  // u1' = U Exp(theta) e1 = u1 + U (theta x e1) = u1 - theta2 u3 + theta3 u2, and
  // u2' = u2 + theta1 u3 - theta3 u1; (w1, w2)' = (w1 - w2 dphi, w2 + w1 dphi).
  Eigen::Matrix<double, 6, 4> j = Eigen::Matrix<double, 6, 4>::Zero();
  j.block<3, 1>(0, 1) = -w1 * u.col(2);
  j.block<3, 1>(0, 2) = w1 * u.col(1);
  j.block<3, 1>(0, 3) = -w2 * u.col(0);
  j.block<3, 1>(3, 0) = w2 * u.col(2);
  j.block<3, 1>(3, 2) = -w2 * u.col(0);
  j.block<3, 1>(3, 3) = w1 * u.col(1);
  return j;
}

}  // namespace slslam
