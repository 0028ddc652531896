// Vocabulary training: hierarchical k-means (k-means++ seeding, Lloyd iterations) level by level,
// then IDF weights from looking the training images up in the finished tree.
//
// Determinism: every node draws from its own generator seeded by (seed, node id), node ids follow
// breadth-first order, and centres are accumulated per cluster in member order, so the tree does
// not depend on the number of threads.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <unordered_set>
#include <vector>

#include "slslam/core/check.h"
#include "slslam/place/descriptor_space.h"
#include "slslam/place/vocabulary.h"

namespace slslam {

using place_detail::BinarySpace;
using place_detail::FloatSpace;

namespace {

// Below this many descriptors a node's assignment step runs on one thread (thread start-up costs
// more than the distances).
constexpr size_t kParallelAssignMin = 4096;

uint64_t MixSeed(uint64_t seed, uint64_t node) {
  // SplitMix64 finaliser: nearby (seed, node) pairs give unrelated generator states.
  uint64_t z = seed + 0x9E3779B97F4A7C15ull * (node + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// Uniform double in [0, 1) from 53 random bits: the same on every standard library (unlike
// std::uniform_real_distribution).
double Uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

// Clusters of one node: members (indices into the training set) per non-empty cluster, and their
// centres (stride elements each).
template <class Space>
struct NodeClusters {
  std::vector<std::vector<int>> members;
  std::vector<typename Space::Element> centres;
};

template <class Space>
class HierarchicalKMeans {
 public:
  using T = typename Space::Element;

  HierarchicalKMeans(const Space& space, const std::vector<T>& data,
                     const VocabularyOptions& options)
      : space_(space), data_(data), options_(options) {}

  const T* At(int i) const { return data_.data() + static_cast<size_t>(i) * space_.stride; }

  // Splits `members` into at most `branching` clusters; fewer when there are fewer distinct
  // descriptors. Empty clusters are dropped.
  NodeClusters<Space> Cluster(const std::vector<int>& members, uint64_t node_id) const {
    const int k = options_.branching;
    const int stride = space_.stride;
    std::mt19937_64 rng(MixSeed(options_.seed, node_id));
    std::vector<T> centres = SeedCentres(members, k, rng);
    const int num_centres = static_cast<int>(centres.size() / stride);

    std::vector<int> assignment(members.size(), -1);
    std::vector<std::vector<int>> clusters(num_centres);
    for (int iteration = 0; iteration < options_.kmeans_iterations; ++iteration) {
      bool changed = false;
      const long n = static_cast<long>(members.size());
#pragma omp parallel for schedule(static) reduction(|| : changed) if (n >= kParallelAssignMin)
      for (long i = 0; i < n; ++i) {
        const int nearest = Nearest(At(members[i]), centres, num_centres);
        if (nearest != assignment[i]) changed = true;
        assignment[i] = nearest;
      }
      if (!changed) break;
      for (auto& c : clusters) c.clear();
      for (size_t i = 0; i < members.size(); ++i) clusters[assignment[i]].push_back(members[i]);
      for (int c = 0; c < num_centres; ++c) {
        // An empty cluster keeps its centre and may win members back next iteration.
        if (!clusters[c].empty()) space_.Centre(clusters[c], data_.data(), &centres[c * stride]);
      }
    }
    for (auto& c : clusters) c.clear();
    for (size_t i = 0; i < members.size(); ++i) clusters[assignment[i]].push_back(members[i]);

    NodeClusters<Space> out;
    for (int c = 0; c < num_centres; ++c) {
      if (clusters[c].empty()) continue;
      out.members.push_back(std::move(clusters[c]));
      out.centres.insert(out.centres.end(), centres.begin() + c * stride,
                         centres.begin() + (c + 1) * stride);
    }
    return out;
  }

 private:
  int Nearest(const T* d, const std::vector<T>& centres, int num_centres) const {
    return space_.Nearest(d, centres.data(), num_centres);
  }

  // k-means++: the first centre uniformly, each next one with probability proportional to
  // SeedWeight(distance to the nearest centre chosen so far). Stops early when every member
  // coincides with a centre.
  std::vector<T> SeedCentres(const std::vector<int>& members, int k, std::mt19937_64& rng) const {
    const int stride = space_.stride;
    const size_t n = members.size();
    std::vector<T> centres;
    std::vector<double> weight(n, std::numeric_limits<double>::infinity());
    int chosen = static_cast<int>(rng() % n);
    for (int c = 0; c < k; ++c) {
      const T* centre = At(members[chosen]);
      centres.insert(centres.end(), centre, centre + stride);
      double total = 0.0;
      for (size_t i = 0; i < n; ++i) {
        weight[i] = std::min(weight[i], Space::SeedWeight(space_.Distance(At(members[i]), centre)));
        total += weight[i];
      }
      if (c + 1 == k || total <= 0.0) break;
      double target = Uniform01(rng) * total;
      chosen = -1;
      for (size_t i = 0; i < n; ++i) {
        if (weight[i] <= 0.0) continue;
        chosen = static_cast<int>(i);  // the last positive one absorbs rounding at the end
        target -= weight[i];
        if (target < 0.0) break;
      }
    }
    return centres;
  }

  const Space& space_;
  const std::vector<T>& data_;
  const VocabularyOptions& options_;
};

}  // namespace

// Builds the tree for one descriptor space and fills the vocabulary's node arrays.
class VocabularyBuilder {
 public:
  template <class Space>
  static void BuildTree(const Space& space, const std::vector<typename Space::Element>& data,
                        int num_descriptors, const VocabularyOptions& options,
                        std::vector<typename Space::Element>* node_descriptors,
                        Vocabulary* vocabulary) {
    using T = typename Space::Element;
    const int stride = space.stride;
    HierarchicalKMeans<Space> kmeans(space, data, options);

    auto& parent = vocabulary->parent_;
    parent.assign(1, -1);
    node_descriptors->assign(stride, T{});  // the root has no descriptor
    // Nodes of the current level still to split, with their members.
    std::vector<NodeId> level_nodes{0};
    std::vector<std::vector<int>> level_members(1);
    level_members[0].resize(num_descriptors);
    for (int i = 0; i < num_descriptors; ++i) level_members[0][i] = i;

    for (int level = 0; level < options.levels && !level_nodes.empty(); ++level) {
      const long count = static_cast<long>(level_nodes.size());
      std::vector<NodeClusters<Space>> split(count);
      // Nested regions run on one thread: one big node uses the threads inside its own k-means.
#pragma omp parallel for schedule(dynamic) if (count > 1)
      for (long i = 0; i < count; ++i) {
        // Nodes with fewer descriptors than k stay leaves, as do nodes of identical descriptors.
        if (level_members[i].size() < static_cast<size_t>(options.branching)) continue;
        split[i] = kmeans.Cluster(level_members[i], level_nodes[i]);
        if (split[i].members.size() < 2) split[i] = {};
      }
      std::vector<NodeId> next_nodes;
      std::vector<std::vector<int>> next_members;
      for (long i = 0; i < count; ++i) {
        for (size_t c = 0; c < split[i].members.size(); ++c) {
          const NodeId child = static_cast<NodeId>(parent.size());
          parent.push_back(static_cast<int32_t>(level_nodes[i]));
          node_descriptors->insert(node_descriptors->end(), split[i].centres.begin() + c * stride,
                                   split[i].centres.begin() + (c + 1) * stride);
          next_nodes.push_back(child);
          next_members.push_back(std::move(split[i].members[c]));
        }
      }
      level_nodes = std::move(next_nodes);
      level_members = std::move(next_members);
    }

    // Leaves become words in node (breadth-first) order.
    std::vector<bool> has_child(parent.size(), false);
    for (size_t i = 1; i < parent.size(); ++i) has_child[parent[i]] = true;
    vocabulary->word_of_node_.assign(parent.size(), -1);
    int32_t words = 0;
    for (size_t i = 0; i < parent.size(); ++i) {
      if (!has_child[i]) vocabulary->word_of_node_[i] = words++;
    }
    vocabulary->weight_.assign(parent.size(), 0.0);
    vocabulary->BuildIndex();
  }

  // IDF weight of every word: log(N / n_w) over the N training images.
  static void SetIdfWeights(const std::vector<cv::Mat>& images, Vocabulary* vocabulary) {
    std::vector<const cv::Mat*> used;
    for (const cv::Mat& image : images) {
      if (image.rows > 0) used.push_back(&image);
    }
    const long n = static_cast<long>(used.size());
    std::vector<std::vector<WordId>> words_of_image(n);
#pragma omp parallel for schedule(dynamic)
    for (long i = 0; i < n; ++i) {
      std::vector<uint64_t> scratch;
      std::unordered_set<WordId> seen;
      for (int row = 0; row < used[i]->rows; ++row) {
        const NodeId leaf =
            vocabulary->Descend(vocabulary->PrepareQuery(*used[i], row, &scratch), 0, nullptr);
        seen.insert(static_cast<WordId>(vocabulary->word_of_node_[leaf]));
      }
      words_of_image[i].assign(seen.begin(), seen.end());
    }
    std::vector<int> images_with_word(vocabulary->num_words(), 0);
    for (const auto& words : words_of_image) {
      for (const WordId w : words) ++images_with_word[w];
    }
    for (int w = 0; w < vocabulary->num_words(); ++w) {
      // A word no training image reaches is as rare as can be: log N.
      const double containing = std::max(1, images_with_word[w]);
      vocabulary->weight_[vocabulary->node_of_word_[w]] = std::log(n / containing);
    }
  }
};

Vocabulary Vocabulary::Train(const std::vector<cv::Mat>& descriptors_per_image,
                             const VocabularyOptions& options) {
  options.Check();
  int type = -1, cols = 0;
  size_t total = 0;
  for (size_t i = 0; i < descriptors_per_image.size(); ++i) {
    const cv::Mat& d = descriptors_per_image[i];
    if (d.rows == 0) continue;
    SLSLAM_CHECK(d.type() == CV_8UC1 || d.type() == CV_32FC1,
                 "Vocabulary::Train: descriptors_per_image[", i,
                 "] must be single-channel CV_8U (binary, uint8) or CV_32F (float32), got ",
                 place_detail::TypeName(d.depth()), " with ", d.channels(), " channels");
    if (type < 0) type = d.type(), cols = d.cols;
    SLSLAM_CHECK(d.type() == type && d.cols == cols, "Vocabulary::Train: descriptors_per_image[", i,
                 "] are ", place_detail::TypeName(d.type()), " x ", d.cols,
                 " but earlier images have ", place_detail::TypeName(type), " x ", cols,
                 " (uint8 binary and float32 descriptors do not mix)");
    total += d.rows;
  }
  Require(total > 0, "Vocabulary::Train: no descriptors to train on");
  Require(cols > 0, "Vocabulary::Train: descriptors have no columns");
  Require(total <= static_cast<size_t>(std::numeric_limits<int>::max()),
          "Vocabulary::Train: more than 2^31 descriptors");

  Vocabulary vocabulary;
  vocabulary.descriptor_type_ = type;
  vocabulary.cols_ = cols;
  vocabulary.branching_ = options.branching;
  vocabulary.levels_ = options.levels;
  const int n = static_cast<int>(total);
  if (type == CV_8U) {
    BinarySpace space{place_detail::WordsForBytes(cols)};
    vocabulary.words_per_descriptor_ = space.stride;
    std::vector<uint64_t> data(static_cast<size_t>(n) * space.stride);
    size_t next = 0;
    for (const cv::Mat& d : descriptors_per_image) {
      for (int row = 0; row < d.rows; ++row, ++next) {
        place_detail::PackBinaryRow(d, row, space.stride, data.data() + next * space.stride);
      }
    }
    VocabularyBuilder::BuildTree(space, data, n, options, &vocabulary.binary_, &vocabulary);
  } else {
    FloatSpace space{cols};
    std::vector<float> data(static_cast<size_t>(n) * cols);
    size_t next = 0;
    for (const cv::Mat& d : descriptors_per_image) {
      for (int row = 0; row < d.rows; ++row, ++next) {
        std::copy(d.ptr<float>(row), d.ptr<float>(row) + cols, data.data() + next * cols);
      }
    }
    VocabularyBuilder::BuildTree(space, data, n, options, &vocabulary.float_, &vocabulary);
  }
  VocabularyBuilder::SetIdfWeights(descriptors_per_image, &vocabulary);
  return vocabulary;
}

}  // namespace slslam
