// Vocabulary look-up, BoW vectors and scoring. Training is in vocabulary_train.cpp, the file format
// in vocabulary_io.cpp.
#include "slslam/place/vocabulary.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "slslam/core/check.h"
#include "slslam/place/descriptor_space.h"

namespace slslam {

using place_detail::NearestBinaryNode;
using place_detail::PackBinaryRow;
using place_detail::SquaredL2;
using place_detail::TypeName;

void VocabularyOptions::Check() const {
  SLSLAM_CHECK(branching >= 2, "VocabularyOptions.branching must be >= 2, got ", branching);
  SLSLAM_CHECK(levels >= 1, "VocabularyOptions.levels must be >= 1, got ", levels);
  // k^L words must stay addressable by 32-bit ids (and fit in memory long before that).
  SLSLAM_CHECK(std::pow(static_cast<double>(branching), levels) <= 1e8,
               "VocabularyOptions.branching^levels must be <= 1e8 words, got ", branching, "^",
               levels);
  CheckInRange("VocabularyOptions.kmeans_iterations", kmeans_iterations, 1, 10000);
}

void Vocabulary::BuildIndex() {
  const size_t n = parent_.size();
  child_begin_.assign(n + 1, 0);
  for (size_t i = 1; i < n; ++i) ++child_begin_[parent_[i] + 1];
  for (size_t i = 0; i < n; ++i) child_begin_[i + 1] += child_begin_[i];
  children_.assign(n > 0 ? n - 1 : 0, 0);
  std::vector<uint32_t> fill(child_begin_.begin(), child_begin_.end() - (n > 0 ? 1 : 0));
  for (size_t i = 1; i < n; ++i) children_[fill[parent_[i]]++] = static_cast<NodeId>(i);

  int num_words = 0;
  for (const int32_t w : word_of_node_) num_words += w >= 0 ? 1 : 0;
  node_of_word_.assign(num_words, 0);
  for (size_t i = 0; i < n; ++i) {
    if (word_of_node_[i] >= 0) node_of_word_[word_of_node_[i]] = static_cast<NodeId>(i);
  }
}

double Vocabulary::word_weight(WordId word) const {
  if (word >= node_of_word_.size()) {
    throw std::out_of_range(Message("word ", word, " >= ", node_of_word_.size(), " words"));
  }
  return weight_[node_of_word_[word]];
}

int Vocabulary::node_depth(NodeId node) const {
  if (node >= parent_.size()) {
    throw std::out_of_range(Message("node ", node, " >= ", parent_.size(), " nodes"));
  }
  int depth = 0;
  for (int32_t n = static_cast<int32_t>(node); parent_[n] >= 0; n = parent_[n]) ++depth;
  return depth;
}

void Vocabulary::CheckDescriptors(const cv::Mat& descriptors) const {
  Require(!empty(), "the vocabulary is empty (train or load one first)");
  if (descriptors.type() != descriptor_type_ || descriptors.cols != cols_) {
    throw std::invalid_argument(Message("descriptors are ", TypeName(descriptors.depth()),
                                        descriptors.channels() > 1 ? " multi-channel" : "", " x ",
                                        descriptors.cols, " but the vocabulary is for ",
                                        TypeName(descriptor_type_), " x ", cols_));
  }
}

const void* Vocabulary::PrepareQuery(const cv::Mat& descriptors, int row,
                                     std::vector<uint64_t>* scratch) const {
  if (descriptor_type_ == CV_8U) {
    scratch->resize(words_per_descriptor_);
    PackBinaryRow(descriptors, row, words_per_descriptor_, scratch->data());
    return scratch->data();
  }
  return descriptors.ptr<float>(row);
}

NodeId Vocabulary::Descend(const void* query, int depth, NodeId* node_at_depth) const {
  NodeId node = 0;
  int level = 0;
  if (node_at_depth != nullptr && depth <= 0) *node_at_depth = 0;
  while (child_begin_[node + 1] > child_begin_[node]) {
    const NodeId* first = children_.data() + child_begin_[node];
    const NodeId* last = children_.data() + child_begin_[node + 1];
    NodeId best = *first;
    if (descriptor_type_ == CV_8U) {
      best = NearestBinaryNode(static_cast<const uint64_t*>(query), binary_.data(),
                               words_per_descriptor_, first, last);
    } else {
      const auto* q = static_cast<const float*>(query);
      float best_distance = std::numeric_limits<float>::infinity();
      for (const NodeId* c = first; c != last; ++c) {
        const float d = SquaredL2(q, float_.data() + static_cast<size_t>(*c) * cols_, cols_);
        if (d < best_distance) best_distance = d, best = *c;
      }
    }
    node = best;
    ++level;
    if (node_at_depth != nullptr && level <= depth) *node_at_depth = node;
  }
  return node;
}

WordId Vocabulary::Lookup(const cv::Mat& descriptors, int row, int depth,
                          NodeId* node_at_depth) const {
  CheckDescriptors(descriptors);
  SLSLAM_CHECK(row >= 0 && row < descriptors.rows, "descriptor row ", row, " out of range [0, ",
               descriptors.rows, ")");
  std::vector<uint64_t> scratch;
  const NodeId leaf = Descend(PrepareQuery(descriptors, row, &scratch), depth, node_at_depth);
  return static_cast<WordId>(word_of_node_[leaf]);
}

void Vocabulary::Transform(const cv::Mat& descriptors, BowVector* bow, FeatureVector* features,
                           int levels_up) const {
  Require(bow != nullptr, "Vocabulary::Transform: bow must not be null");
  SLSLAM_CHECK(levels_up >= 0, "Vocabulary::Transform: levels_up must be >= 0, got ", levels_up);
  bow->clear();
  if (features != nullptr) features->clear();
  if (descriptors.empty()) return;
  CheckDescriptors(descriptors);

  // The direct-index node sits at depth L - levels_up on the path (the leaf on shorter paths).
  const int depth = std::max(0, levels_ - levels_up);
  std::vector<uint64_t> scratch;
  for (int row = 0; row < descriptors.rows; ++row) {
    NodeId indexed = 0;
    const NodeId leaf = Descend(PrepareQuery(descriptors, row, &scratch), depth, &indexed);
    const double weight = weight_[leaf];
    // Words every training image had (weight 0) say nothing about the place.
    if (weight > 0.0) (*bow)[static_cast<WordId>(word_of_node_[leaf])] += weight;
    if (features != nullptr) (*features)[indexed].push_back(row);
  }
  double sum = 0.0;
  for (const auto& [word, value] : *bow) sum += value;
  if (sum > 0.0) {
    for (auto& [word, value] : *bow) value /= sum;
  }
}

double Vocabulary::Score(const BowVector& a, const BowVector& b) {
  // For non-negative L1-normalised vectors 1 - 0.5 |a - b|_1 = sum over shared words of min(a, b):
  // one merge over the two sorted maps.
  double score = 0.0;
  auto ia = a.begin(), ib = b.begin();
  while (ia != a.end() && ib != b.end()) {
    if (ia->first < ib->first) {
      ia = a.lower_bound(ib->first);
    } else if (ib->first < ia->first) {
      ib = b.lower_bound(ia->first);
    } else {
      score += std::min(ia->second, ib->second);
      ++ia, ++ib;
    }
  }
  return std::clamp(score, 0.0, 1.0);
}

}  // namespace slslam
