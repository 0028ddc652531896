#include "slslam/geometry/reprojection.h"

#include <cmath>

#include "slslam/core/check.h"
#include "slslam/geometry/rotation.h"

namespace slslam {

namespace {

// d(u, v) / d x_c of the pinhole projection.
Eigen::Matrix<double, 2, 3> ProjectionJacobian(const PinholeCamera& camera,
                                               const Eigen::Vector3d& x_c) {
  const double inv_z = 1.0 / x_c.z();
  Eigen::Matrix<double, 2, 3> j;
  j << camera.fx * inv_z, 0.0, -camera.fx * x_c.x() * inv_z * inv_z, 0.0, camera.fy * inv_z,
      -camera.fy * x_c.y() * inv_z * inv_z;
  return j;
}

// d x_c / d delta for the left pose perturbation.
Eigen::Matrix<double, 3, 6> PointPoseJacobian(const Eigen::Vector3d& x_c) {
  Eigen::Matrix<double, 3, 6> j;
  j.leftCols<3>().setIdentity();
  j.rightCols<3>() = -Skew(x_c);
  return j;
}

}  // namespace

bool PointResidual(const PinholeCamera& camera, const Rigid3d& cam_from_world,
                   const Eigen::Vector3d& point_w, const Eigen::Vector2d& observed_px,
                   Eigen::Vector2d* residual, Eigen::Matrix<double, 2, 6>* d_pose,
                   Eigen::Matrix<double, 2, 3>* d_point, double min_depth) {
  const Eigen::Vector3d x_c = cam_from_world * point_w;
  if (!(x_c.z() > min_depth)) return false;
  *residual = camera.Project(x_c) - observed_px;
  if (d_pose || d_point) {
    const Eigen::Matrix<double, 2, 3> j_proj = ProjectionJacobian(camera, x_c);
    if (d_pose) *d_pose = j_proj * PointPoseJacobian(x_c);
    if (d_point) *d_point = j_proj * cam_from_world.rotation;
  }
  return true;
}

bool StereoPointResidual(const StereoRig& rig, const Rigid3d& cam_from_world,
                         const Eigen::Vector3d& point_w, const Eigen::Vector3d& observed,
                         Eigen::Vector3d* residual, Eigen::Matrix<double, 3, 6>* d_pose,
                         Eigen::Matrix<double, 3, 3>* d_point, double min_depth) {
  const PinholeCamera& cam = rig.camera;
  const Eigen::Vector3d x_c = cam_from_world * point_w;
  if (!(x_c.z() > min_depth)) return false;
  const Eigen::Vector2d uv = cam.Project(x_c);
  const double inv_z = 1.0 / x_c.z();
  const double u_right = uv.x() - cam.fx * rig.baseline_m * inv_z;
  *residual = Eigen::Vector3d(uv.x(), uv.y(), u_right) - observed;
  if (d_pose || d_point) {
    Eigen::Matrix<double, 3, 3> j_proj;
    j_proj.topRows<2>() = ProjectionJacobian(cam, x_c);
    j_proj.row(2) = j_proj.row(0);
    j_proj(2, 2) += cam.fx * rig.baseline_m * inv_z * inv_z;
    if (d_pose) *d_pose = j_proj * PointPoseJacobian(x_c);
    if (d_point) *d_point = j_proj * cam_from_world.rotation;
  }
  return true;
}

bool LineResidual(const PinholeCamera& camera, const Rigid3d& cam_from_world,
                  const PluckerLine& line_w, const Eigen::Vector2d& start_px,
                  const Eigen::Vector2d& end_px, double angle_weight, Eigen::Vector3d* residual,
                  Eigen::Matrix<double, 3, 6>* d_pose, Eigen::Matrix<double, 3, 6>* d_plucker) {
  const PluckerLine line_c = line_w.Transformed(cam_from_world);
  const Eigen::Matrix3d k_line = LineProjectionMatrix(camera);
  const Eigen::Vector3d l = k_line * line_c.n;
  const double norm_sq = l.x() * l.x() + l.y() * l.y();
  if (!(norm_sq > 1e-18)) return false;
  const double norm = std::sqrt(norm_sq);
  const Eigen::Vector3d x1(start_px.x(), start_px.y(), 1.0);
  const Eigen::Vector3d x2(end_px.x(), end_px.y(), 1.0);
  Eigen::Vector2d direction = end_px - start_px;
  const double length = direction.norm();
  direction = length > 0.0 ? Eigen::Vector2d(direction / length) : Eigen::Vector2d::Zero();
  const double s = direction.dot(l.head<2>());
  (*residual) << x1.dot(l) / norm, x2.dot(l) / norm, angle_weight * s / norm;
  if (!d_pose && !d_plucker) return true;

  // d e / d l (3 x 3).
  const double inv_norm3 = 1.0 / (norm_sq * norm);
  Eigen::Matrix3d d_l;
  for (int i = 0; i < 2; ++i) {
    const Eigen::Vector3d& x = i == 0 ? x1 : x2;
    const double xl = x.dot(l);
    d_l.row(i) << x.x() / norm - xl * l.x() * inv_norm3, x.y() / norm - xl * l.y() * inv_norm3,
        1.0 / norm;
  }
  d_l.row(2) << angle_weight * (direction.x() / norm - s * l.x() * inv_norm3),
      angle_weight * (direction.y() / norm - s * l.y() * inv_norm3), 0.0;
  const Eigen::Matrix3d d_nc = d_l * k_line;  // d e / d n_c

  if (d_pose) {
    // Left perturbation applied to the camera-frame line: n_c' = n_c + omega x n_c + rho x v_c.
    Eigen::Matrix<double, 3, 6> d_nc_pose;
    d_nc_pose.leftCols<3>() = -Skew(line_c.v);
    d_nc_pose.rightCols<3>() = -Skew(line_c.n);
    *d_pose = d_nc * d_nc_pose;
  }
  if (d_plucker) {
    // n_c = R n_w + [t]x R v_w.
    const Eigen::Matrix3d& R = cam_from_world.rotation;
    d_plucker->leftCols<3>() = d_nc * R;
    d_plucker->rightCols<3>() = d_nc * Skew(cam_from_world.translation) * R;
  }
  return true;
}

void PerturbPose(const Eigen::Matrix<double, 6, 1>& delta, Rigid3d* cam_from_world) {
  const Eigen::Matrix3d dR = ExpSO3(delta.tail<3>());
  cam_from_world->rotation = dR * cam_from_world->rotation;
  cam_from_world->translation = dR * cam_from_world->translation + delta.head<3>();
}

}  // namespace slslam
