#include "slslam/optimization/pose_optimizer.h"

#include <algorithm>
#include <array>
#include <cmath>

#include <ceres/loss_function.h>
#include <ceres/problem.h>
#include <ceres/solver.h>

#include "slslam/core/check.h"
#include "slslam/optimization/cost_functions.h"
#include "slslam/optimization/manifolds.h"

namespace slslam {

namespace {

// Chi-square of one observation at the given pose; +inf when it cannot be evaluated.
double PointChi2(const StereoRig& rig, const Rigid3d& cam_from_world,
                 const PointObservation& obs) {
  const double w = 1.0 / (obs.sigma_px * obs.sigma_px);
  if (obs.stereo) {
    Eigen::Vector3d e;
    if (!StereoPointResidual(rig, cam_from_world, obs.point_w, obs.observed, &e)) return INFINITY;
    return w * e.squaredNorm();
  }
  Eigen::Vector2d e;
  if (!PointResidual(rig.camera, cam_from_world, obs.point_w, obs.observed.head<2>(), &e)) {
    return INFINITY;
  }
  return w * e.squaredNorm();
}

double LineChi2(const StereoRig& rig, const Rigid3d& cam_from_world,
                const LineObservation& obs) {
  Eigen::Vector3d e;
  if (!LineResidual(rig.camera, cam_from_world, obs.line_w, obs.start_px, obs.end_px, 0.0, &e)) {
    return INFINITY;
  }
  // The line must also be in front of the camera: its point nearest to the segment's middle ray.
  const PluckerLine line_c = obs.line_w.Transformed(cam_from_world);
  const Eigen::Vector3d middle = line_c.ClosestPointToRay(
      rig.camera.Unproject(0.5 * (obs.start_px + obs.end_px)));
  if (!(middle.z() > 0.0)) return INFINITY;
  return e.head<2>().squaredNorm() / (obs.sigma_px * obs.sigma_px);
}

}  // namespace

void PoseOptimizerOptions::Check() const {
  CheckInRange("pose.rounds", rounds, 1, 100);
  CheckInRange("pose.iterations_per_round", iterations_per_round, 1, 10000);
  CheckInRange("pose.robust_rounds", robust_rounds, 0, rounds);
  CheckAboveInRange("pose.chi2_mono", chi2_mono, 0.0, 1e6);
  CheckAboveInRange("pose.chi2_stereo", chi2_stereo, 0.0, 1e6);
  CheckAboveInRange("pose.chi2_line", chi2_line, 0.0, 1e6);
  CheckInRange("pose.line_angle_weight", line_angle_weight, 0.0, 1e6);
  CheckInRange("pose.line_weight", line_weight, 0.0, 1e6);
}

PoseOptimizerResult OptimizePose(const StereoRig& rig, const Rigid3d& cam_from_world,
                                 const std::vector<PointObservation>& points,
                                 const std::vector<LineObservation>& lines,
                                 const PoseOptimizerOptions& options) {
  rig.Check();
  Require(cam_from_world.rotation.allFinite() && cam_from_world.translation.allFinite(),
          "initial pose is not finite");
  options.Check();

  PoseOptimizerResult result;
  result.cam_from_world = cam_from_world;
  result.point_inlier.assign(points.size(), false);
  result.line_inlier.assign(lines.size(), false);
  for (size_t i = 0; i < points.size(); ++i) {
    result.point_inlier[i] = std::isfinite(PointChi2(rig, cam_from_world, points[i]));
  }
  for (size_t i = 0; i < lines.size(); ++i) {
    result.line_inlier[i] = std::isfinite(LineChi2(rig, cam_from_world, lines[i]));
  }

  // Landmarks are constants of this problem: copies in parameter blocks marked constant.
  std::vector<Eigen::Vector3d> point_params(points.size());
  std::vector<std::array<double, kLineSize>> line_params(lines.size());
  for (size_t i = 0; i < points.size(); ++i) point_params[i] = points[i].point_w;
  for (size_t i = 0; i < lines.size(); ++i) {
    LineToParameters(OrthonormalLine::FromPlucker(lines[i].line_w), line_params[i].data());
  }

  std::array<double, kPoseSize> pose;
  PoseToParameters(cam_from_world, pose.data());
  const double line_scale = std::sqrt(std::max(options.line_weight, 0.0));

  for (int round = 0; round < options.rounds; ++round) {
    ceres::Problem::Options problem_options;
    problem_options.manifold_ownership = ceres::TAKE_OWNERSHIP;
    ceres::Problem problem(problem_options);
    problem.AddParameterBlock(pose.data(), kPoseSize, new PoseManifold);
    const bool robust = round < options.robust_rounds;
    int residual_blocks = 0;
    for (size_t i = 0; i < points.size(); ++i) {
      if (!result.point_inlier[i]) continue;
      const PointObservation& obs = points[i];
      ceres::CostFunction* cost =
          obs.stereo ? static_cast<ceres::CostFunction*>(
                           new StereoPointCost(rig, obs.observed, obs.sigma_px))
                     : new PointCost(rig.camera, obs.observed.head<2>(), obs.sigma_px);
      ceres::LossFunction* loss =
          robust ? new ceres::HuberLoss(std::sqrt(obs.stereo ? options.chi2_stereo
                                                             : options.chi2_mono))
                 : nullptr;
      problem.AddResidualBlock(cost, loss, pose.data(), point_params[i].data());
      problem.SetParameterBlockConstant(point_params[i].data());
      ++residual_blocks;
    }
    for (size_t i = 0; i < lines.size(); ++i) {
      if (!result.line_inlier[i] || line_scale == 0.0) continue;
      const LineObservation& obs = lines[i];
      ceres::CostFunction* cost = new LineCost(rig.camera, obs.start_px, obs.end_px,
                                               options.line_angle_weight, obs.sigma_px);
      ceres::LossFunction* loss = robust ? new ceres::HuberLoss(std::sqrt(options.chi2_line))
                                         : nullptr;
      if (line_scale != 1.0) {
        loss = new ceres::ScaledLoss(loss, options.line_weight, ceres::TAKE_OWNERSHIP);
      }
      problem.AddResidualBlock(cost, loss, pose.data(), line_params[i].data());
      problem.SetParameterBlockConstant(line_params[i].data());
      problem.SetManifold(line_params[i].data(), new LineManifold);
      ++residual_blocks;
    }
    // Three points (or an equivalent set of lines) determine a pose; fewer is not a pose.
    if (residual_blocks < 3) {
      if (round == 0) return result;  // success stays false, pose stays the initial guess
      break;
    }

    ceres::Solver::Options solver_options;
    solver_options.linear_solver_type = ceres::DENSE_QR;
    solver_options.max_num_iterations = options.iterations_per_round;
    solver_options.num_threads = 1;
    solver_options.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options, &problem, &summary);

    Rigid3d solved;
    ParametersToPose(pose.data(), &solved);
    // Reclassify every observation, outliers included (an outlier may come back).
    for (size_t i = 0; i < points.size(); ++i) {
      const double bound = points[i].stereo ? options.chi2_stereo : options.chi2_mono;
      result.point_inlier[i] = PointChi2(rig, solved, points[i]) <= bound;
    }
    for (size_t i = 0; i < lines.size(); ++i) {
      result.line_inlier[i] = LineChi2(rig, solved, lines[i]) <= options.chi2_line;
    }
  }

  ParametersToPose(pose.data(), &result.cam_from_world);
  result.point_inliers = static_cast<int>(
      std::count(result.point_inlier.begin(), result.point_inlier.end(), true));
  result.line_inliers = static_cast<int>(
      std::count(result.line_inlier.begin(), result.line_inlier.end(), true));
  result.success = result.point_inliers + result.line_inliers >= 3;
  return result;
}

}  // namespace slslam
