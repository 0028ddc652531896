// SAC-IA coarse alignment on descriptor matches (registration_internal.h).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <random>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "slslam/lidar/registration_internal.h"

namespace slslam::lidar::registration_detail {

// SAC-IA (Rusu et al. 2009) on the coarse level: sample correspondences among similar descriptors,
// fit a rigid transform, keep the hypothesis with the lowest truncated error over the source
// keypoints. Beyond PCL's class: a hypothesis whose sampled edges differ in length between the two
// scans is not scored (prerejection, Buch et al. 2013), scoring stops as soon as the partial error
// exceeds the best one, and the iterations end when the best hypothesis' correspondence inlier
// ratio says a better one would have been drawn with sac_ia_confidence (adaptive RANSAC bound).
template <typename Feature>
Eigen::Matrix4f CoarseAlign(const Prepared& source, const pcl::Indices& keypoints,
                            const Prepared& target, const pcl::PointCloud<Feature>& source_features,
                            const pcl::PointCloud<Feature>& target_features,
                            const RegistrationOptions& options) {
  const std::vector<std::vector<int>> similar = SimilarFeatures(
      source_features, target_features, options.sac_ia_randomness, Threads(options));
  std::vector<int> usable;  // keypoints with at least one similar target descriptor
  for (std::size_t i = 0; i < keypoints.size(); ++i) {
    if (!similar[i].empty()) usable.push_back(static_cast<int>(i));
  }
  const CloudN& src = *source.coarse;
  const CloudN& tgt = *target.coarse;
  const auto point = [](const PointN& p) { return Eigen::Vector3f(p.x, p.y, p.z); };

  std::mt19937 rng(5489u);
  // Keypoints scored in a random order, so that a partial error is representative.
  CloudN scored(src, keypoints);
  std::shuffle(scored.begin(), scored.end(), rng);
  const float tau2 = static_cast<float>(options.sac_ia_max_corr_m * options.sac_ia_max_corr_m);
  constexpr int kBlock = 64;
  const auto error_of = [&](const Eigen::Matrix4f& transform, double bound) {
    double error = 0.0;
    CloudN moved;
    std::vector<pcl::Indices> index;
    std::vector<std::vector<float>> dist2;
    for (std::size_t begin = 0; begin < scored.size() && error <= bound; begin += kBlock) {
      const std::size_t end = std::min(scored.size(), begin + kBlock);
      moved.resize(end - begin);
      for (std::size_t i = begin; i < end; ++i) {
        moved[i - begin].getVector3fMap() =
            transform.topLeftCorner<3, 3>() * scored[i].getVector3fMap() +
            transform.topRightCorner<3, 1>();
      }
      target.coarse_tree->nearestKSearch(moved, pcl::Indices(), 1, index, dist2);
      for (const auto& d : dist2) error += std::min(d[0], tau2) / tau2;
    }
    return error;
  };
  // Fraction of (keypoint, similar descriptor) pairs that `transform` maps within the inlier
  // distance: the chance that one sampled correspondence is right.
  const auto inlier_ratio = [&](const Eigen::Matrix4f& transform) {
    std::size_t inliers = 0, total = 0;
    for (int i : usable) {
      const Eigen::Vector3f p = transform.topLeftCorner<3, 3>() * point(src[keypoints[i]]) +
                                transform.topRightCorner<3, 1>();
      for (int j : similar[i]) inliers += (point(tgt[j]) - p).squaredNorm() <= tau2;
      total += similar[i].size();
    }
    return total == 0 ? 0.0 : double(inliers) / double(total);
  };
  const int samples = options.sac_ia_samples;
  const auto needed_iterations = [&](double ratio) {
    const double all_right = std::pow(ratio, samples);
    if (options.sac_ia_confidence >= 1.0 || all_right <= 0.0) {
      return std::numeric_limits<double>::infinity();
    }
    if (all_right >= 1.0) return 0.0;
    return std::log(1.0 - options.sac_ia_confidence) / std::log(1.0 - all_right);
  };

  Eigen::Matrix4f best = Eigen::Matrix4f::Identity();
  double best_error = std::numeric_limits<double>::infinity();
  double stop_after = std::numeric_limits<double>::infinity();
  if (options.sac_ia_try_identity) {
    best_error = error_of(best, best_error);
    stop_after = needed_iterations(inlier_ratio(best));
  }
  if (static_cast<int>(usable.size()) < samples) return best;

  const float min_sample2 =
      static_cast<float>(options.sac_ia_min_sample_m * options.sac_ia_min_sample_m);
  const float tolerance = static_cast<float>(1.0 - options.sac_ia_edge_similarity);
  std::uniform_int_distribution<int> pick(0, static_cast<int>(usable.size()) - 1);
  Eigen::Matrix3Xf from(3, samples), to(3, samples);
  std::vector<int> chosen;
  for (int iteration = 0; iteration < options.sac_ia_iterations && iteration < stop_after;
       ++iteration) {
    // Keypoints at least sac_ia_min_sample_m apart (a bounded number of draws, as PCL).
    chosen.clear();
    for (int draw = 0; draw < 100 * samples && static_cast<int>(chosen.size()) < samples; ++draw) {
      const int candidate = usable[pick(rng)];
      const Eigen::Vector3f p = point(src[keypoints[candidate]]);
      bool far = true;
      for (int c : chosen) far = far && (point(src[keypoints[c]]) - p).squaredNorm() >= min_sample2;
      if (far) chosen.push_back(candidate);
    }
    if (static_cast<int>(chosen.size()) < samples) continue;
    for (int j = 0; j < samples; ++j) {
      const std::vector<int>& matches = similar[chosen[j]];
      const int match =
          matches[std::uniform_int_distribution<int>(0, static_cast<int>(matches.size()) - 1)(rng)];
      from.col(j) = point(src[keypoints[chosen[j]]]);
      to.col(j) = point(tgt[match]);
    }
    bool similar_edges = true;
    for (int a = 0; a < samples && similar_edges; ++a) {
      for (int b = a + 1; b < samples && similar_edges; ++b) {
        const float ds = (from.col(a) - from.col(b)).norm();
        const float dt = (to.col(a) - to.col(b)).norm();
        similar_edges = std::abs(ds - dt) <= tolerance * std::max(ds, dt);
      }
    }
    if (!similar_edges) continue;
    const Eigen::Matrix4f hypothesis = Eigen::umeyama(from, to, false);
    if (!hypothesis.allFinite()) continue;
    const double error = error_of(hypothesis, best_error);
    if (error < best_error) {
      best_error = error;
      best = hypothesis;
      stop_after = std::min(stop_after, iteration + 1 + needed_iterations(inlier_ratio(best)));
    }
  }
  return best;
}

template Eigen::Matrix4f CoarseAlign(const Prepared& source, const pcl::Indices& keypoints,
                                     const Prepared& target,
                                     const pcl::PointCloud<pcl::FPFHSignature33>& source_features,
                                     const pcl::PointCloud<pcl::FPFHSignature33>& target_features,
                                     const RegistrationOptions& options);
template Eigen::Matrix4f CoarseAlign(const Prepared& source, const pcl::Indices& keypoints,
                                     const Prepared& target,
                                     const pcl::PointCloud<pcl::PFHSignature125>& source_features,
                                     const pcl::PointCloud<pcl::PFHSignature125>& target_features,
                                     const RegistrationOptions& options);

}  // namespace slslam::lidar::registration_detail
