// Nearest-neighbour queries of the registration steps (registration_internal.h).
#include <algorithm>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include <omp.h>

#include "slslam/lidar/registration_internal.h"

namespace slslam::lidar::registration_detail {

int Threads(const RegistrationOptions& options) {
  return options.num_threads > 0 ? options.num_threads : std::max(1, omp_get_num_procs());
}

std::shared_ptr<Tree> MakeTree(const CloudN::Ptr& cloud) {
  auto tree = std::make_shared<Tree>();
  tree->setInputCloud(cloud);
  return tree;
}

void Neighbours(const Tree& tree, const CloudN& cloud, const pcl::Indices& queries, int k,
                double radius_m, int threads, std::vector<pcl::Indices>* indices,
                std::vector<std::vector<float>>* dist2) {
  const int n = static_cast<int>(queries.empty() ? cloud.size() : queries.size());
  k = std::min<int>(k, static_cast<int>(tree.getInputCloud()->size()));
  indices->resize(n);
  dist2->resize(n);
  const int blocks = std::max(1, std::min(threads, n / 512));
#pragma omp parallel for num_threads(blocks) schedule(static, 1)
  for (int b = 0; b < blocks; ++b) {
    const int begin = int(std::int64_t(n) * b / blocks);
    const int end = int(std::int64_t(n) * (b + 1) / blocks);
    // The block as a cloud of its own: PCL 1.13's batch radius search mis-sizes its query matrix
    // when given indices.
    CloudN block;
    const CloudN* points = &cloud;
    if (!queries.empty() || blocks > 1) {
      block.resize(end - begin);
      for (int i = begin; i < end; ++i) block[i - begin] = cloud[queries.empty() ? i : queries[i]];
      points = &block;
    }
    std::vector<pcl::Indices> idx;
    std::vector<std::vector<float>> d2;
    if (k > 0) {
      tree.nearestKSearch(*points, pcl::Indices(), k, idx, d2);
    } else {
      tree.radiusSearch(*points, pcl::Indices(), radius_m, idx, d2);
    }
    std::move(idx.begin(), idx.end(), indices->begin() + begin);
    std::move(d2.begin(), d2.end(), dist2->begin() + begin);
  }
}

void NearestK(const Tree& tree, const CloudN& queries, int k, int threads,
              std::vector<pcl::Indices>* indices, std::vector<std::vector<float>>* dist2) {
  Neighbours(tree, queries, {}, k, 0.0, threads, indices, dist2);
}

pcl::IndicesPtr Thinned(std::size_t n, int max_count) {
  const std::size_t stride =
      max_count > 0 ? std::max<std::size_t>(1, (n + max_count - 1) / max_count) : 1;
  auto indices = std::make_shared<pcl::Indices>();
  for (std::size_t i = 0; i < n; i += stride) indices->push_back(static_cast<pcl::index_t>(i));
  return indices;
}

}  // namespace slslam::lidar::registration_detail
