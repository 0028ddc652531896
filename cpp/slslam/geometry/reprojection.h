// Reprojection residuals of points and lines with analytic Jacobians (the SL-SLAM paper's
// point-line cost, eqs. 13-17).
//
// Pose convention: cam_from_world (T_cw) maps world to camera, x_c = R x_w + t with R, t its
// rotation and translation. Pose increments are 6-vectors
// delta = (rho, omega) applied on the left: R <- Exp(omega) R, t <- Exp(omega) t + rho, so that
// x_c <- Exp(omega) x_c + rho and d x_c / d delta = [I, -[x_c]x] at delta = 0.
#pragma once

#include <Eigen/Core>

#include "slslam/core/pinhole_camera.h"
#include "slslam/core/rigid3.h"
#include "slslam/core/stereo_rig.h"
#include "slslam/geometry/plucker_line.h"

namespace slslam {

// Residual (u, v) - observed of a point seen by one camera. Returns false (residual and Jacobians
// untouched) when the point is not in front of the camera (z < min_depth).
bool PointResidual(const PinholeCamera& camera, const Rigid3d& cam_from_world,
                   const Eigen::Vector3d& point_w, const Eigen::Vector2d& observed_px,
                   Eigen::Vector2d* residual, Eigen::Matrix<double, 2, 6>* d_pose = nullptr,
                   Eigen::Matrix<double, 2, 3>* d_point = nullptr, double min_depth = 1e-6);

// Residual (u_left, v, u_right) - observed of a point seen by a stereo pair (as ORB-SLAM3's stereo
// edge): the right coordinate constrains depth.
bool StereoPointResidual(const StereoRig& rig, const Rigid3d& cam_from_world,
                         const Eigen::Vector3d& point_w, const Eigen::Vector3d& observed,
                         Eigen::Vector3d* residual, Eigen::Matrix<double, 3, 6>* d_pose = nullptr,
                         Eigen::Matrix<double, 3, 3>* d_point = nullptr, double min_depth = 1e-6);

// Line residual for an observed segment x1 -> x2 [px] (the SL-SLAM paper's):
//   e1, e2 = signed distances of x1, x2 to the projected line l' [px],
//   e3     = angle_weight * sin(angle between l' and the segment).
// The paper's e3 is a slope difference, which is unbounded for vertical lines (props, bolts,
// pipes); the sine is bounded and smooth. It equals (e2 - e1) / |x2 - x1|, so it adds no new
// information: it re-weights the direction error and is kept for fidelity to the paper's cost;
// angle_weight = 0 drops it. Returns false when the projected line is degenerate (the line passes
// through the camera centre).
bool LineResidual(const PinholeCamera& camera, const Rigid3d& cam_from_world,
                  const PluckerLine& line_w, const Eigen::Vector2d& start_px,
                  const Eigen::Vector2d& end_px, double angle_weight, Eigen::Vector3d* residual,
                  Eigen::Matrix<double, 3, 6>* d_pose = nullptr,
                  Eigen::Matrix<double, 3, 6>* d_plucker = nullptr);

// Pose cam_from_world perturbed by delta = (rho, omega) as described at the top of this file.
void PerturbPose(const Eigen::Matrix<double, 6, 1>& delta, Rigid3d* cam_from_world);

}  // namespace slslam
