#include "slslam/lidar/scan_matcher.h"

#include <cmath>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "slslam/core/check.h"
#include "slslam/geometry/rotation.h"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace slslam::lidar {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

void ScanMatchOptions::Check() const {
  SLSLAM_CHECK(max_iterations >= 1 && max_iterations <= 200,
               "ScanMatchOptions.max_iterations must be in [1, 200], got ", max_iterations);
  SLSLAM_CHECK(max_correspondence_m > 0, "ScanMatchOptions.max_correspondence_m must be > 0 m");
  SLSLAM_CHECK(plane_neighbours >= 3 && plane_neighbours <= 16,
               "ScanMatchOptions.plane_neighbours must be in [3, 16], got ", plane_neighbours);
  SLSLAM_CHECK(plane_max_thickness_m > 0,
               "ScanMatchOptions.plane_max_thickness_m must be > 0 m, got ", plane_max_thickness_m);
  SLSLAM_CHECK(robust_scale_m > 0, "ScanMatchOptions.robust_scale_m must be > 0 m");
  SLSLAM_CHECK(prior_translation_sigma_m >= 0 && prior_rotation_sigma_rad >= 0,
               "ScanMatchOptions prior sigmas must be >= 0");
  SLSLAM_CHECK(inlier_m > 0, "ScanMatchOptions.inlier_m must be > 0 m");
  SLSLAM_CHECK(num_threads >= 0, "ScanMatchOptions.num_threads must be >= 0");
}

namespace {

struct Normal {
  Matrix6d H = Matrix6d::Zero();
  Vector6d b = Vector6d::Zero();
  int pairs = 0, inliers = 0;
  double inlier_sq = 0.0;
  void Add(const Normal& o) {
    H += o.H;
    b += o.b;
    pairs += o.pairs;
    inliers += o.inliers;
    inlier_sq += o.inlier_sq;
  }
};

Normal Linearise(const std::vector<Eigen::Vector3d>& source, const VoxelMap& map,
                 const Rigid3d& world_from_sensor, const ScanMatchOptions& o) {
  const double k2 = o.robust_scale_m * o.robust_scale_m;
  const int n = static_cast<int>(source.size());
  Normal total;
#ifdef _OPENMP
  const int threads = o.num_threads > 0 ? o.num_threads : omp_get_max_threads();
#pragma omp parallel num_threads(threads)
#endif
  {
    Normal local;
#ifdef _OPENMP
#pragma omp for schedule(static) nowait
#endif
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d Rs = world_from_sensor.rotation * source[i];
      const Eigen::Vector3d q = Rs + world_from_sensor.translation;
      if (!o.point_to_plane) {
        Eigen::Vector3d nearest;
        if (!map.Nearest(q, o.max_correspondence_m, &nearest)) continue;
        const Eigen::Vector3d r = q - nearest;
        Eigen::Matrix<double, 3, 6> J;
        J.leftCols<3>().setIdentity();
        J.rightCols<3>() = -Skew(Rs);
        const double r2 = r.squaredNorm();
        const double s = k2 + r2;
        const double w = k2 * k2 / (s * s);
        local.H.noalias() += w * J.transpose() * J;
        local.b.noalias() += w * J.transpose() * r;
        ++local.pairs;
        if (r2 < o.inlier_m * o.inlier_m) {
          ++local.inliers;
          local.inlier_sq += r2;
        }
        continue;
      }
      LocalPlane plane;
      if (!map.FitPlane(q, o.plane_neighbours, o.max_correspondence_m, o.plane_max_thickness_m,
                        &plane)) {
        continue;
      }
      const double r = plane.normal.dot(q - plane.centre);
      if (std::abs(r) > o.max_correspondence_m) continue;
      Vector6d J;
      J.head<3>() = plane.normal;
      J.tail<3>() = Rs.cross(plane.normal);
      // Geman-McClure weight, scaled so that w = 1 at r = 0.
      const double s = k2 + r * r;
      const double w = k2 * k2 / (s * s);
      local.H.noalias() += w * J * J.transpose();
      local.b.noalias() += w * r * J;
      ++local.pairs;
      if (std::abs(r) < o.inlier_m) {
        ++local.inliers;
        local.inlier_sq += r * r;
      }
    }
#ifdef _OPENMP
#pragma omp critical
#endif
    total.Add(local);
  }
  return total;
}

}  // namespace

ScanMatchResult MatchScanToMap(const std::vector<Eigen::Vector3d>& source_sensor,
                               const VoxelMap& map, const Rigid3d& world_from_predicted,
                               const ScanMatchOptions& options) {
  options.Check();
  SLSLAM_CHECK(!source_sensor.empty(), "scan matching needs source points");
  Matrix6d prior = Matrix6d::Zero();
  if (options.prior_translation_sigma_m > 0) {
    prior.topLeftCorner<3, 3>().diagonal().setConstant(
        1.0 / (options.prior_translation_sigma_m * options.prior_translation_sigma_m));
  }
  if (options.prior_rotation_sigma_rad > 0) {
    prior.bottomRightCorner<3, 3>().diagonal().setConstant(
        1.0 / (options.prior_rotation_sigma_rad * options.prior_rotation_sigma_rad));
  }
  // The scan's residuals are in metres with robust scale k: information r^2 / k^2.
  const double scale = 1.0 / (options.robust_scale_m * options.robust_scale_m);
  ScanMatchResult result;
  Rigid3d world_from_sensor = world_from_predicted;
  Normal normal;
  for (int it = 0; it < options.max_iterations; ++it) {
    normal = Linearise(source_sensor, map, world_from_sensor, options);
    result.iterations = it + 1;
    // Prior residual e = (p - p_pred, Log(R R_pred^T)), Jacobian ~ identity.
    Vector6d e;
    e.head<3>() = world_from_sensor.translation - world_from_predicted.translation;
    e.tail<3>() = LogSO3(
        Eigen::Quaterniond(world_from_sensor.rotation * world_from_predicted.rotation.transpose()));
    const Matrix6d H = scale * normal.H + prior;
    const Vector6d b = scale * normal.b + prior * e;
    if (normal.pairs < 6 && prior.isZero()) break;
    const Vector6d step = -(H + 1e-9 * Matrix6d::Identity()).ldlt().solve(b);
    if (!step.allFinite()) break;
    world_from_sensor.translation += step.head<3>();
    world_from_sensor.rotation = (ExpSO3(step.tail<3>()) * world_from_sensor.rotation).eval();
    if (step.head<3>().norm() < options.convergence_translation_m &&
        step.tail<3>().norm() < options.convergence_rotation_rad) {
      break;
    }
  }
  normal = Linearise(source_sensor, map, world_from_sensor, options);
  result.world_from_sensor = world_from_sensor;
  result.information = scale * normal.H;
  result.correspondences = normal.pairs;
  result.fitness = static_cast<double>(normal.inliers) / source_sensor.size();
  result.inlier_rmse_m = normal.inliers ? std::sqrt(normal.inlier_sq / normal.inliers) : 0.0;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(normal.H.topLeftCorner<3, 3>());
  const Eigen::Vector3d lambda = eig.eigenvalues();
  result.degeneracy = lambda(2) > 0 ? lambda(0) / lambda(2) : 0.0;
  return result;
}

}  // namespace slslam::lidar
