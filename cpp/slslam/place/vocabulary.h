// Bag-of-words vocabulary for place recognition: a hierarchical k-means tree over binary (ORB,
// Hamming) or float (SuperPoint, L2) descriptors whose leaves are the words, with TF-IDF weights
// (after Galvez-Lopez and Tardos, "Bags of Binary Words", T-RO 2012; written for slslam).
//
// Layer: place/ depends on OpenCV matrices only; it never includes map/ or tracking/.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace slslam {

using WordId = uint32_t;
using NodeId = uint32_t;
// Word -> weight, L1-normalised TF-IDF (weights sum to 1; empty when nothing was weighted).
using BowVector = std::map<WordId, double>;
// Node `levels_up` above the leaves -> indices (rows) of the features below it. The direct index:
// features of two images need only be compared when they share a node.
using FeatureVector = std::map<NodeId, std::vector<int>>;

struct VocabularyOptions {
  int branching = 10;          ///< k of the hierarchical k-means [-]
  int levels = 4;              ///< depth L of the tree (root excluded) [-]
  int kmeans_iterations = 15;  ///< Lloyd iterations per node (stops earlier when stable) [-]
  uint64_t seed = 0;           ///< k-means++ seeding; same seed and data, same tree [-]

  // Throws std::invalid_argument naming the first field out of range.
  void Check() const;
};

// An immutable tree after Train/Load; const methods may run concurrently from many threads.
class Vocabulary {
 public:
  Vocabulary() = default;  // empty; Transform refuses it

  // descriptors_per_image: one matrix per training image, one descriptor per row; all CV_8UC1
  // (binary, Hamming, cols = bytes) or all CV_32FC1 (L2, cols = dimensions). Matrices with no rows
  // are skipped. IDF weight of a word: log(N / n), N the images with descriptors, n those with at
  // least one descriptor looked up to the word (log N for a word no image reaches).
  static Vocabulary Train(const std::vector<cv::Mat>& descriptors_per_image,
                          const VocabularyOptions& options = {});

  // Reads a file written by Save. Every defect (missing file, wrong magic, newer format version,
  // size that does not fit the header, checksum, broken tree) throws std::invalid_argument
  // "<path>: <what is wrong>".
  static Vocabulary Load(const std::string& path);
  // Writes path + ".partial" then renames it to path, so readers never see half a file.
  // Throws std::invalid_argument naming the path when it cannot be written.
  void Save(const std::string& path) const;
  // The checksum its file holds (FNV-1a 64 of the file's bytes before it), the same for the
  // vocabulary loaded and for the one trained and saved; 0 for an empty vocabulary. Map files
  // store it, and a map loads only with the vocabulary it was made with.
  uint64_t Checksum() const;

  bool empty() const { return num_nodes() == 0; }
  int num_words() const { return static_cast<int>(node_of_word_.size()); }
  int num_nodes() const { return static_cast<int>(parent_.size()); }
  int descriptor_type() const { return descriptor_type_; }  // CV_8U or CV_32F (-1 when empty)
  int descriptor_cols() const { return cols_; }             // bytes (binary) or floats
  int branching() const { return branching_; }
  int levels() const { return levels_; }
  double word_weight(WordId word) const;  // IDF weight; throws std::out_of_range
  // Depth of a node: 0 for the root.
  int node_depth(NodeId node) const;

  // Word of one descriptor (row `row` of `descriptors`), descending the tree from the root:
  // at most branching * levels distance computations. `node_at_depth` (may be null) receives the
  // node on the path at depth `depth` (the leaf when the path is shorter).
  WordId Lookup(const cv::Mat& descriptors, int row, int depth = 0,
                NodeId* node_at_depth = nullptr) const;

  // BoW vector (TF-IDF, L1-normalised) of an image's descriptors, and optionally its direct index
  // at `levels_up` levels above the leaves (every feature appears in exactly one node, including
  // features whose word has weight 0). A type or width different from the vocabulary's throws
  // std::invalid_argument naming both; an empty matrix gives empty outputs.
  void Transform(const cv::Mat& descriptors, BowVector* bow, FeatureVector* features = nullptr,
                 int levels_up = 2) const;

  // DBoW2's L1 score of two L1-normalised vectors: 1 - 0.5 * |a - b|_1, in [0, 1]; 1 for identical
  // vectors, 0 when no word is shared (and when either is empty).
  static double Score(const BowVector& a, const BowVector& b);

 private:
  friend class VocabularyBuilder;
  friend class VocabularyFile;

  // Rebuilds children_ / child_begin_ / node_of_word_ from parent_ and word_of_node_.
  void BuildIndex();
  void CheckDescriptors(const cv::Mat& descriptors) const;
  // Row `row` in the layout of the node descriptors: packed 64-bit words in `scratch` (binary) or
  // the row itself (float).
  const void* PrepareQuery(const cv::Mat& descriptors, int row,
                           std::vector<uint64_t>* scratch) const;
  // Leaf reached from the root by a prepared query; `node_at_depth` as in Lookup.
  NodeId Descend(const void* query, int depth, NodeId* node_at_depth) const;

  int descriptor_type_ = -1;
  int cols_ = 0;
  int branching_ = 0;
  int levels_ = 0;
  int words_per_descriptor_ = 0;  // binary: 64-bit words per (zero-padded) descriptor

  std::vector<int32_t> parent_;        // per node; -1 for the root (node 0)
  std::vector<int32_t> word_of_node_;  // per node; -1 for inner nodes
  std::vector<double> weight_;         // per node; IDF weight of a leaf, 0 for inner nodes
  std::vector<uint64_t> binary_;       // per node, words_per_descriptor_ words (root: zeros)
  std::vector<float> float_;           // per node, cols_ floats (root: zeros)
  std::vector<uint32_t> child_begin_;  // CSR: children of n are children_[begin[n], begin[n+1])
  std::vector<NodeId> children_;
  std::vector<NodeId> node_of_word_;
};

}  // namespace slslam
