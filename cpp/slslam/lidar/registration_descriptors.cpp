// Local shape descriptors of the coarse keypoints and their nearest descriptors in the other scan
// (registration_internal.h).
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

#include <pcl/features/fpfh.h>
#include <pcl/features/pfh.h>
#include <Eigen/Core>

#include "slslam/lidar/registration_internal.h"

namespace slslam::lidar::registration_detail {
namespace {

// Descriptors as matrix rows; a descriptor with a non-finite bin (too few neighbours) gets an
// infinite squared norm so that it never matches.
template <typename Feature>
void DescriptorMatrix(const pcl::PointCloud<Feature>& features, Eigen::MatrixXf* rows,
                      Eigen::VectorXf* squared_norms) {
  constexpr int kDim = sizeof(Feature::histogram) / sizeof(float);
  rows->resize(features.size(), kDim);
  squared_norms->resize(features.size());
  for (std::size_t i = 0; i < features.size(); ++i) {
    const Eigen::Map<const Eigen::Matrix<float, 1, kDim>> h(features[i].histogram);
    if (h.allFinite()) {
      rows->row(i) = h;
      (*squared_norms)(i) = h.squaredNorm();
    } else {
      rows->row(i).setZero();
      (*squared_norms)(i) = std::numeric_limits<float>::infinity();
    }
  }
}

}  // namespace

// FPFH (Rusu et al. 2009) of the coarse points `keypoints`, with the whole coarse level as
// support: PCL's SPFH and weighting steps, with the radius neighbourhoods found by batch queries
// and shared by both steps (pcl::FPFHEstimationOMP searches twice per point, a query at a time).
pcl::PointCloud<pcl::FPFHSignature33>::Ptr Fpfh(const Prepared& scan, const pcl::Indices& keypoints,
                                                const RegistrationOptions& options, int threads) {
  using Estimator = pcl::FPFHEstimation<PointN, PointN, pcl::FPFHSignature33>;
  const CloudN& cloud = *scan.coarse;
  const int n = static_cast<int>(cloud.size());
  std::vector<pcl::Indices> neighbours(n);
  std::vector<std::vector<float>> dist2(n);
  // Neighbourhoods of the keypoints, then of the rest of their neighbours: the SPFH support.
  std::vector<char> searched(n, 0);
  std::vector<pcl::Indices> found;
  std::vector<std::vector<float>> found2;
  const auto search = [&](const pcl::Indices& queries) {
    Neighbours(*scan.coarse_tree, cloud, queries, 0, options.feature_radius_m, threads, &found,
               &found2);
    for (std::size_t i = 0; i < queries.size(); ++i) {
      searched[queries[i]] = 1;
      neighbours[queries[i]] = std::move(found[i]);
      dist2[queries[i]] = std::move(found2[i]);
    }
  };
  search(keypoints);
  pcl::Indices support;
  std::vector<char> queued(searched);
  for (pcl::index_t key : keypoints) {
    for (pcl::index_t j : neighbours[key]) {
      if (!queued[j]) {
        queued[j] = 1;
        support.push_back(j);
      }
    }
  }
  search(support);
  const int bins = 11;  // PCL's default subdivisions per angle feature (33 bins in all)
  Eigen::MatrixXf f1 = Eigen::MatrixXf::Zero(n, bins), f2 = f1, f3 = f1;
  auto features = std::make_shared<pcl::PointCloud<pcl::FPFHSignature33>>();
  features->resize(keypoints.size());
#pragma omp parallel num_threads(threads)
  {
    Estimator estimator;
#pragma omp for schedule(dynamic, 64)
    for (int i = 0; i < n; ++i) {
      if (searched[i]) {
        estimator.computePointSPFHSignature(cloud, cloud, i, i, neighbours[i], f1, f2, f3);
      }
    }
    Eigen::VectorXf histogram(3 * bins);
#pragma omp for schedule(dynamic, 64)
    for (int i = 0; i < static_cast<int>(keypoints.size()); ++i) {
      const pcl::index_t key = keypoints[i];
      float* out = (*features)[i].histogram;
      if (neighbours[key].size() < 2) {
        std::fill(out, out + 3 * bins, std::numeric_limits<float>::quiet_NaN());
        continue;
      }
      histogram.setZero();
      estimator.weightPointSPFHSignature(f1, f2, f3, neighbours[key], dist2[key], histogram);
      std::copy(histogram.data(), histogram.data() + 3 * bins, out);
    }
  }
  return features;
}

pcl::PointCloud<pcl::PFHSignature125>::Ptr Pfh(const Prepared& scan, const pcl::IndicesPtr& indices,
                                               const RegistrationOptions& options) {
  auto features = std::make_shared<pcl::PointCloud<pcl::PFHSignature125>>();
  pcl::PFHEstimation<PointN, PointN, pcl::PFHSignature125> estimator;
  estimator.setIndices(indices);
  estimator.setInputCloud(scan.coarse);
  estimator.setInputNormals(scan.coarse);
  estimator.setSearchMethod(scan.coarse_tree);
  estimator.setRadiusSearch(options.feature_radius_m);
  estimator.compute(*features);
  return features;
}

// For each source descriptor, the `k` nearest target descriptors: exhaustive, as matrix-vector
// products (|s - t|^2 = |s|^2 + |t|^2 - 2 s.t).
template <typename Feature>
std::vector<std::vector<int>> SimilarFeatures(const pcl::PointCloud<Feature>& source,
                                              const pcl::PointCloud<Feature>& target, int k,
                                              int threads) {
  Eigen::MatrixXf s, t;
  Eigen::VectorXf s2, t2;
  DescriptorMatrix(source, &s, &s2);
  DescriptorMatrix(target, &t, &t2);
  k = std::min<int>(k, static_cast<int>(target.size()));
  std::vector<std::vector<int>> similar(source.size());
#pragma omp parallel num_threads(threads)
  {
    Eigen::VectorXf distance(target.size());
    std::vector<std::pair<float, int>> nearest;
#pragma omp for schedule(static)
    for (int i = 0; i < static_cast<int>(source.size()); ++i) {
      if (!std::isfinite(s2(i))) continue;
      distance.noalias() = t * s.row(i).transpose();
      distance = t2 - 2.0f * distance;  // + s2(i), the same for every target
      nearest.assign(k, {std::numeric_limits<float>::infinity(), -1});
      for (int j = 0; j < distance.size(); ++j) {
        if (distance(j) >= nearest.back().first) continue;
        int slot = k - 1;
        for (; slot > 0 && nearest[slot - 1].first > distance(j); --slot) {
          nearest[slot] = nearest[slot - 1];
        }
        nearest[slot] = {distance(j), j};
      }
      for (const auto& [d, j] : nearest) {
        if (j >= 0) similar[i].push_back(j);
      }
    }
  }
  return similar;
}

template std::vector<std::vector<int>> SimilarFeatures(
    const pcl::PointCloud<pcl::FPFHSignature33>& source,
    const pcl::PointCloud<pcl::FPFHSignature33>& target, int k, int threads);
template std::vector<std::vector<int>> SimilarFeatures(
    const pcl::PointCloud<pcl::PFHSignature125>& source,
    const pcl::PointCloud<pcl::PFHSignature125>& target, int k, int threads);

}  // namespace slslam::lidar::registration_detail
