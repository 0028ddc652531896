#include "slslam/lidar/registration.h"

#include <chrono>
#include <exception>
#include <future>
#include <stdexcept>
#include <string>
#include <utility>

#include <Eigen/Core>

#include "slslam/core/check.h"
#include "slslam/lidar/registration_internal.h"

// The steps live in registration_*.cpp (registration_internal.h); this file runs them in order.
namespace slslam::lidar {
namespace {

using registration_detail::CoarseAlign;
using registration_detail::FineAlign;
using registration_detail::Fpfh;
using registration_detail::NdtAlign;
using registration_detail::Pfh;
using registration_detail::Preprocess;
using registration_detail::Score;
using registration_detail::Thinned;
using registration_detail::Threads;
using Clock = std::chrono::steady_clock;

double MsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// Runs first() and second(), on two threads when `concurrent`; rethrows what either threw.
template <typename First, typename Second>
auto Both(bool concurrent, First first, Second second) {
  using A = decltype(first());
  using B = decltype(second());
  if (!concurrent) {
    A a = first();
    return std::pair<A, B>(std::move(a), second());
  }
  std::future<A> a = std::async(std::launch::async, first);
  std::exception_ptr error;
  B b{};
  try {
    b = second();
  } catch (...) {
    error = std::current_exception();
  }
  A a_value = a.get();  // rethrows the first job's error
  if (error) std::rethrow_exception(error);
  return std::pair<A, B>(std::move(a_value), std::move(b));
}

}  // namespace

std::string MethodName(Method method) {
  switch (method) {
    case Method::kFpfhSacIaIcp:
      return "fpfh_sac_ia_icp";
    case Method::kNdt:
      return "ndt";
    case Method::kPfhSacIaIcp:
      return "pfh_sac_ia_icp";
    case Method::kIcp:
      return "icp";
  }
  throw std::invalid_argument(Message("unknown registration method ", static_cast<int>(method)));
}

Method MethodFromName(const std::string& name) {
  for (Method m : {Method::kFpfhSacIaIcp, Method::kNdt, Method::kPfhSacIaIcp, Method::kIcp}) {
    if (MethodName(m) == name) return m;
  }
  throw std::invalid_argument(Message("unknown registration method '", name,
                                      "' (expected fpfh_sac_ia_icp, ndt, pfh_sac_ia_icp or icp)"));
}

void RegistrationOptions::Check() const {
  SLSLAM_CHECK(min_range_m >= 0, "min_range_m must be >= 0, got ", min_range_m);
  SLSLAM_CHECK(max_range_m <= 0 || max_range_m > min_range_m,
               "max_range_m must be <= 0 (no limit) or > min_range_m, got ", max_range_m);
  SLSLAM_CHECK(fine_voxel_m > 0, "fine_voxel_m must be > 0, got ", fine_voxel_m);
  SLSLAM_CHECK(coarse_voxel_m >= fine_voxel_m, "coarse_voxel_m must be >= fine_voxel_m, got ",
               coarse_voxel_m);
  SLSLAM_CHECK(outlier_k >= 0, "outlier_k must be >= 0, got ", outlier_k);
  SLSLAM_CHECK(outlier_std_mul > 0, "outlier_std_mul must be > 0, got ", outlier_std_mul);
  SLSLAM_CHECK(normal_k >= 3, "normal_k must be >= 3, got ", normal_k);
  SLSLAM_CHECK(feature_radius_m > coarse_voxel_m, "feature_radius_m must be > coarse_voxel_m, got ",
               feature_radius_m);
  SLSLAM_CHECK(sac_ia_iterations >= 1, "sac_ia_iterations must be >= 1, got ", sac_ia_iterations);
  SLSLAM_CHECK(sac_ia_samples >= 3, "sac_ia_samples must be >= 3, got ", sac_ia_samples);
  SLSLAM_CHECK(sac_ia_source_keypoints >= 0, "sac_ia_source_keypoints must be >= 0, got ",
               sac_ia_source_keypoints);
  SLSLAM_CHECK(sac_ia_randomness >= 1, "sac_ia_randomness must be >= 1, got ", sac_ia_randomness);
  SLSLAM_CHECK(sac_ia_min_sample_m >= 0, "sac_ia_min_sample_m must be >= 0, got ",
               sac_ia_min_sample_m);
  SLSLAM_CHECK(sac_ia_max_corr_m > 0, "sac_ia_max_corr_m must be > 0, got ", sac_ia_max_corr_m);
  SLSLAM_CHECK(sac_ia_edge_similarity >= 0 && sac_ia_edge_similarity < 1,
               "sac_ia_edge_similarity must be in [0, 1), got ", sac_ia_edge_similarity);
  SLSLAM_CHECK(sac_ia_confidence > 0 && sac_ia_confidence <= 1,
               "sac_ia_confidence must be in (0, 1], got ", sac_ia_confidence);
  SLSLAM_CHECK(icp_source_points_coarse >= 0, "icp_source_points_coarse must be >= 0, got ",
               icp_source_points_coarse);
  SLSLAM_CHECK(icp_source_points_fine >= 0, "icp_source_points_fine must be >= 0, got ",
               icp_source_points_fine);
  SLSLAM_CHECK(icp_iterations_coarse >= 0, "icp_iterations_coarse must be >= 0, got ",
               icp_iterations_coarse);
  SLSLAM_CHECK(icp_iterations_fine >= 1, "icp_iterations_fine must be >= 1, got ",
               icp_iterations_fine);
  SLSLAM_CHECK(icp_max_corr_coarse_m > 0, "icp_max_corr_coarse_m must be > 0, got ",
               icp_max_corr_coarse_m);
  SLSLAM_CHECK(icp_max_corr_fine_m > 0, "icp_max_corr_fine_m must be > 0, got ",
               icp_max_corr_fine_m);
  SLSLAM_CHECK(icp_transformation_epsilon >= 0, "icp_transformation_epsilon must be >= 0, got ",
               icp_transformation_epsilon);
  SLSLAM_CHECK(icp_fitness_epsilon >= 0, "icp_fitness_epsilon must be >= 0, got ",
               icp_fitness_epsilon);
  SLSLAM_CHECK(ndt_resolution_m > 0, "ndt_resolution_m must be > 0, got ", ndt_resolution_m);
  SLSLAM_CHECK(ndt_step_m > 0, "ndt_step_m must be > 0, got ", ndt_step_m);
  SLSLAM_CHECK(ndt_iterations >= 1, "ndt_iterations must be >= 1, got ", ndt_iterations);
  SLSLAM_CHECK(num_threads >= 0, "num_threads must be >= 0, got ", num_threads);
  // Every real-valued option finite: an infinite voxel or radius leaves one point, or makes every
  // point a neighbour of every other. Counts bounded where they size work or memory.
  const std::pair<const char*, double> reals[] = {
      {"min_range_m", min_range_m},
      {"max_range_m", max_range_m},
      {"fine_voxel_m", fine_voxel_m},
      {"coarse_voxel_m", coarse_voxel_m},
      {"outlier_std_mul", outlier_std_mul},
      {"feature_radius_m", feature_radius_m},
      {"sac_ia_min_sample_m", sac_ia_min_sample_m},
      {"sac_ia_max_corr_m", sac_ia_max_corr_m},
      {"icp_max_corr_coarse_m", icp_max_corr_coarse_m},
      {"icp_max_corr_fine_m", icp_max_corr_fine_m},
      {"icp_transformation_epsilon", icp_transformation_epsilon},
      {"icp_fitness_epsilon", icp_fitness_epsilon},
      {"ndt_resolution_m", ndt_resolution_m},
      {"ndt_step_m", ndt_step_m}};
  for (const auto& [option, value] : reals) CheckFinite(option, value);
  CheckInRange("outlier_k", outlier_k, 0, 10000);
  CheckInRange("normal_k", normal_k, 3, 10000);
  CheckInRange("sac_ia_samples", sac_ia_samples, 3, 10000);
  CheckInRange("sac_ia_randomness", sac_ia_randomness, 1, 10000);
  CheckInRange("num_threads", num_threads, 0, 4096);
}

void CheckPoints(const PointMatrix& points, const std::string& name, int min_points) {
  SLSLAM_CHECK(points.cols() == 3 || points.cols() == 4, name,
               ": expected an N x 3 or N x 4 matrix (x, y, z[, intensity]), got ", points.rows(),
               " x ", points.cols());
  SLSLAM_CHECK(points.rows() >= min_points, name, ": ", points.rows(), " points, need at least ",
               min_points);
  SLSLAM_CHECK(points.allFinite(), name, ": contains NaN or infinite values");
}

RegistrationResult RegisterClouds(const PointMatrix& source, const PointMatrix& target,
                                  const RegistrationOptions& options, Method method) {
  const Clock::time_point start = Clock::now();
  options.Check();
  CheckPoints(source, "source");
  CheckPoints(target, "target");
  RegistrationResult result;

  Clock::time_point stage = Clock::now();
  const int threads = Threads(options);
  const bool concurrent = threads >= 2;  // one thread per scan
  auto [src, tgt] = Both(
      concurrent, [&] { return Preprocess(source, options, false, 1, "source"); },
      [&] { return Preprocess(target, options, true, 1, "target"); });
  result.preprocess_ms = MsSince(stage);
  result.source_points = static_cast<int>(src.fine->size());
  result.source_keypoints = static_cast<int>(src.coarse->size());
  result.target_points = static_cast<int>(tgt.fine->size());
  result.target_keypoints = static_cast<int>(tgt.coarse->size());

  Eigen::Matrix4f guess = Eigen::Matrix4f::Identity();
  if (method == Method::kFpfhSacIaIcp || method == Method::kPfhSacIaIcp) {
    stage = Clock::now();
    const pcl::IndicesPtr keys = Thinned(src.coarse->size(), options.sac_ia_source_keypoints);
    const pcl::IndicesPtr all = Thinned(tgt.coarse->size(), 0);
    const int per_scan = concurrent ? 1 : threads;
    if (method == Method::kFpfhSacIaIcp) {
      const auto [fs, ft] = Both(
          concurrent, [&] { return Fpfh(src, *keys, options, per_scan); },
          [&] { return Fpfh(tgt, *all, options, per_scan); });
      result.features_ms = MsSince(stage);
      stage = Clock::now();
      guess = CoarseAlign(src, *keys, tgt, *fs, *ft, options);
    } else {
      const auto [fs, ft] = Both(
          concurrent, [&] { return Pfh(src, keys, options); },
          [&] { return Pfh(tgt, all, options); });
      result.features_ms = MsSince(stage);
      stage = Clock::now();
      guess = CoarseAlign(src, *keys, tgt, *fs, *ft, options);
    }
    result.coarse_ms = MsSince(stage);
  }

  stage = Clock::now();
  const Eigen::Matrix4f transform = method == Method::kNdt
                                        ? NdtAlign(src, tgt, options, &result)
                                        : FineAlign(src, &tgt, guess, options, &result);
  result.fine_ms = MsSince(stage);

  Score(src, tgt, transform, options.icp_max_corr_fine_m, options, &result);
  result.target_from_source = Rigid3d::FromMatrix4(transform.cast<double>());
  result.total_ms = MsSince(start);
  return result;
}

}  // namespace slslam::lidar
