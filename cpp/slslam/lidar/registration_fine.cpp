// Fine alignment and scoring (registration_internal.h): coarse-to-fine ICP, NDT, fitness.
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include <pcl/common/io.h>
#include <pcl/registration/ndt.h>
#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "slslam/lidar/registration_internal.h"

namespace slslam::lidar::registration_detail {
namespace {

// One Gauss-Newton step of the point-to-plane distance of the inlier pairs (moved source point
// i, target point index[i][0]), from the normal equations summed per thread and then in thread
// order (deterministic); adds their squared error and count. False when fewer than six pairs or
// the step is not finite.
bool PointToPlaneStep(const CloudN& moved, const CloudN& target,
                      const std::vector<pcl::Indices>& index, const std::vector<char>& inlier,
                      int threads, Eigen::Matrix4d* step, double* squared_error, int* count) {
  const int n = static_cast<int>(moved.size());
  using Matrix6 = Eigen::Matrix<double, 6, 6>;
  using Vector6 = Eigen::Matrix<double, 6, 1>;
  const int teams = n > 2048 ? threads : 1;
  std::vector<Matrix6> Hs(teams, Matrix6::Zero());
  std::vector<Vector6> gs(teams, Vector6::Zero());
  std::vector<double> errors(teams, 0.0);
  std::vector<int> counts(teams, 0);
#pragma omp parallel for num_threads(teams) schedule(static, 1)
  for (int team = 0; team < teams; ++team) {
    for (int i = int(std::int64_t(n) * team / teams); i < int(std::int64_t(n) * (team + 1) / teams);
         ++i) {
      if (!inlier[i]) continue;
      const PointN& q = target[index[i][0]];
      const Eigen::Vector3d p = moved[i].getVector3fMap().cast<double>();
      const Eigen::Vector3d normal = q.getNormalVector3fMap().cast<double>();
      const double r = normal.dot(p - q.getVector3fMap().cast<double>());
      Vector6 J;
      J << p.cross(normal), normal;
      Hs[team].selfadjointView<Eigen::Upper>().rankUpdate(J);
      gs[team] += J * r;
      errors[team] += r * r;
      ++counts[team];
    }
  }
  Matrix6 H = Matrix6::Zero();
  Vector6 g = Vector6::Zero();
  for (int team = 0; team < teams; ++team) {
    H += Hs[team];
    g += gs[team];
    *squared_error += errors[team];
    *count += counts[team];
  }
  if (*count < 6) return false;
  H.triangularView<Eigen::Lower>() = H.transpose();
  const Vector6 delta = H.ldlt().solve(-g);
  if (!delta.allFinite()) return false;
  const double angle = delta.head<3>().norm();
  if (angle > 0) {
    step->topLeftCorner<3, 3>() =
        Eigen::AngleAxisd(angle, delta.head<3>() / angle).toRotationMatrix();
  }
  step->topRightCorner<3, 1>() = delta.tail<3>();
  return true;
}

// One ICP level: Gauss-Newton on the point-to-plane distance (or the closed-form point-to-point
// fit) of `source` points to their nearest `target` points within max_corr_m, from `transform`.
void IcpLevel(const CloudN& source, Prepared* target_scan, bool fine, double max_corr_m,
              int iterations, const RegistrationOptions& options, Eigen::Matrix4f* transform,
              RegistrationResult* result) {
  const CloudN& target = fine ? *target_scan->fine : *target_scan->coarse;
  const Tree& tree = fine ? *target_scan->fine_tree : *target_scan->coarse_tree;
  const int threads = Threads(options);
  const float max2 = static_cast<float>(max_corr_m * max_corr_m);
  const int n = static_cast<int>(source.size());
  CloudN moved(source);
  std::vector<pcl::Indices> index;
  std::vector<std::vector<float>> dist2;
  std::vector<int> best_source;
  double previous_mse = std::numeric_limits<double>::infinity();
  Eigen::Matrix4d previous_step = Eigen::Matrix4d::Identity();
  result->converged = false;
  for (int iteration = 0; iteration < iterations; ++iteration) {
    const Eigen::Matrix3f R = transform->topLeftCorner<3, 3>();
    const Eigen::Vector3f t = transform->topRightCorner<3, 1>();
    for (int i = 0; i < n; ++i) {
      moved[i].getVector3fMap() = R * source[i].getVector3fMap() + t;
    }
    NearestK(tree, moved, 1, threads, &index, &dist2);
    std::vector<char> inlier(n);
    for (int i = 0; i < n; ++i) inlier[i] = !dist2[i].empty() && dist2[i][0] <= max2;
    if (options.icp_reject_one_to_one) {  // keep the closest source point per target point
      best_source.assign(target.size(), -1);
      for (int i = 0; i < n; ++i) {
        if (!inlier[i]) continue;
        int& b = best_source[index[i][0]];
        if (b >= 0 && dist2[b][0] <= dist2[i][0]) {
          inlier[i] = 0;
        } else {
          if (b >= 0) inlier[b] = 0;
          b = i;
        }
      }
    }
    if (fine && options.point_to_plane) {
      pcl::Indices paired;
      for (int i = 0; i < n; ++i) {
        if (inlier[i]) paired.push_back(index[i][0]);
      }
      AddFineNormals(paired, options, threads, target_scan);
      for (int i = 0; i < n; ++i) {
        inlier[i] = inlier[i] && target_scan->fine_normal[index[i][0]] == 1;
      }
    }

    Eigen::Matrix4d step = Eigen::Matrix4d::Identity();
    double squared_error = 0.0;
    int count = 0;
    if (options.point_to_plane) {
      if (!PointToPlaneStep(moved, target, index, inlier, threads, &step, &squared_error, &count)) {
        break;
      }
    } else {
      Eigen::Matrix3Xf from(3, n), to(3, n);
      for (int i = 0; i < n; ++i) {
        if (!inlier[i]) continue;
        from.col(count) = moved[i].getVector3fMap();
        to.col(count) = target[index[i][0]].getVector3fMap();
        squared_error += dist2[i][0];
        ++count;
      }
      if (count < 3) break;
      step = Eigen::umeyama(from.leftCols(count), to.leftCols(count), false).cast<double>();
      if (!step.allFinite()) break;
    }
    *transform = (step * transform->cast<double>()).cast<float>();
    ++result->iterations;

    // Converged when a step is small, or when the last two steps cancel out (the iterations
    // alternate between two correspondence sets), or when the error stops changing.
    const auto small = [&](const Eigen::Matrix4d& T) {
      const double rotation = Eigen::AngleAxisd(Eigen::Matrix3d(T.topLeftCorner<3, 3>())).angle();
      const double translation = T.topRightCorner<3, 1>().norm();
      return rotation * rotation <= options.icp_transformation_epsilon &&
             translation * translation <= options.icp_transformation_epsilon;
    };
    const bool cycle = iteration > 0 && small(step * previous_step);
    previous_step = step;
    const double mse = squared_error / count;
    if (small(step) || cycle || std::abs(previous_mse - mse) <= options.icp_fitness_epsilon) {
      result->converged = true;
      break;
    }
    previous_mse = mse;
  }
}

}  // namespace

// Coarse-to-fine ICP from `guess`, each level on an even thinning of the source.
Eigen::Matrix4f FineAlign(const Prepared& source, Prepared* target, Eigen::Matrix4f guess,
                          const RegistrationOptions& options, RegistrationResult* result) {
  if (options.icp_iterations_coarse > 0) {
    const CloudN coarse(*source.coarse,
                        *Thinned(source.coarse->size(), options.icp_source_points_coarse));
    IcpLevel(coarse, target, false, options.icp_max_corr_coarse_m, options.icp_iterations_coarse,
             options, &guess, result);
  }
  const CloudN fine(*source.fine, *Thinned(source.fine->size(), options.icp_source_points_fine));
  IcpLevel(fine, target, true, options.icp_max_corr_fine_m, options.icp_iterations_fine, options,
           &guess, result);
  return guess;
}

Eigen::Matrix4f NdtAlign(const Prepared& source, const Prepared& target,
                         const RegistrationOptions& options, RegistrationResult* result) {
  Eigen::Matrix4f transform = Eigen::Matrix4f::Identity();
  const CloudN::Ptr sources[] = {source.coarse, source.fine};
  const CloudN::Ptr targets[] = {target.coarse, target.fine};
  const double resolutions[] = {options.ndt_resolution_m, 0.5 * options.ndt_resolution_m};
  for (int level = 0; level < 2; ++level) {
    auto src = std::make_shared<CloudXYZ>();
    auto tgt = std::make_shared<CloudXYZ>();
    pcl::copyPointCloud(*sources[level], *src);
    pcl::copyPointCloud(*targets[level], *tgt);
    CheckVoxelCount(*tgt, resolutions[level],
                    level == 0 ? "ndt_resolution_m" : "ndt_resolution_m / 2", "target");
    pcl::NormalDistributionsTransform<pcl::PointXYZ, pcl::PointXYZ> ndt;
    ndt.setResolution(static_cast<float>(resolutions[level]));
    ndt.setStepSize(options.ndt_step_m);
    ndt.setTransformationEpsilon(options.icp_transformation_epsilon);
    ndt.setMaximumIterations(options.ndt_iterations);
    ndt.setInputSource(src);
    ndt.setInputTarget(tgt);
    CloudXYZ aligned;
    ndt.align(aligned, transform);
    transform = ndt.getFinalTransformation();
    result->iterations += ndt.getFinalNumIteration();
    result->converged = ndt.hasConverged();
  }
  return transform;
}

// Fitness and inlier RMSE of the fine source points under `transform`. On the evenly thinned
// subset that fine ICP aligns (icp_source_points_fine), an unbiased estimate at a fraction of
// the nearest-neighbour queries.
void Score(const Prepared& source, const Prepared& target, const Eigen::Matrix4f& transform,
           double inlier_m, const RegistrationOptions& options, RegistrationResult* result) {
  const pcl::IndicesPtr subset = Thinned(source.fine->size(), options.icp_source_points_fine);
  CloudN moved;
  moved.reserve(subset->size());
  for (pcl::index_t i : *subset) {
    PointN p = (*source.fine)[i];
    p.getVector3fMap() =
        transform.topLeftCorner<3, 3>() * p.getVector3fMap() + transform.topRightCorner<3, 1>();
    moved.push_back(p);
  }
  std::vector<pcl::Indices> index;
  std::vector<std::vector<float>> dist2;
  NearestK(*target.fine_tree, moved, 1, Threads(options), &index, &dist2);
  std::size_t inliers = 0;
  double sum2 = 0.0;
  for (const auto& d : dist2) {
    if (!d.empty() && d[0] <= inlier_m * inlier_m) {
      ++inliers;
      sum2 += d[0];
    }
  }
  result->fitness = moved.empty() ? 0.0 : double(inliers) / double(moved.size());
  result->inlier_rmse = inliers == 0 ? 0.0 : std::sqrt(sum2 / double(inliers));
}

}  // namespace slslam::lidar::registration_detail
