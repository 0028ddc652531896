// Brute-force descriptor matching with the mutual-nearest-neighbour and ratio tests.
#pragma once

#include <limits>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace slslam {

// The smallest and second-smallest distance among candidates, and the index of the best: the
// accumulator behind every ratio test (the tests themselves differ per caller and stay there).
struct BestTwo {
  explicit BestTwo(float start = std::numeric_limits<float>::max()) : best(start), second(start) {}

  void Add(float distance, int candidate) {
    if (distance < best) {
      second = best;
      best = distance;
      index = candidate;
    } else if (distance < second) {
      second = distance;
    }
  }

  float best;
  float second;
  int index = -1;  ///< -1 until a candidate was added
};

// One-to-one assignment of queries to targets: a target keeps the query with the smaller
// distance, and a query it displaces loses its match. `Match` is any indexable container of
// per-query target indices (-1: none).
class OneToOne {
 public:
  explicit OneToOne(int targets)
      : distance_(targets, std::numeric_limits<float>::infinity()), owner_(targets, -1) {}

  // Offers `target` to `query` at `distance`; returns whether the query got it.
  template <typename Match>
  bool Offer(int query, int target, float distance, Match* match) {
    if (!(distance < distance_[target])) return false;
    if (owner_[target] >= 0) (*match)[owner_[target]] = -1;
    owner_[target] = query;
    distance_[target] = distance;
    (*match)[query] = target;
    return true;
  }

 private:
  std::vector<float> distance_;
  std::vector<int> owner_;
};

struct MatchOptions {
  float max_distance = 64.0f;  ///< largest accepted descriptor distance (Hamming bits or L2)
  float ratio = 0.8f;          ///< best / second-best distance must be below this [-], in (0, 1]
  bool mutual = true;          ///< keep a pair only if each is the other's nearest neighbour

  void Check() const;
};

// Matches rows of `query` against rows of `train`. Binary (CV_8U) descriptors use the Hamming
// distance, float (CV_32F) descriptors the L2 distance. Returns an N x 2 array of
// (query index, train index) pairs ordered by query index.
Eigen::Matrix<int, Eigen::Dynamic, 2, Eigen::RowMajor> MatchDescriptors(
    const cv::Mat& query, const cv::Mat& train, const MatchOptions& options = {});

// Distance between row i of a and row j of b: Hamming bits for CV_8U, L2 for CV_32F.
float DescriptorDistance(const cv::Mat& a, int i, const cv::Mat& b, int j);

struct GuidedMatchOptions {
  float radius_px = 15.0f;    ///< search window around each predicted position [px]
  float max_distance = 0.7f;  ///< largest accepted distance (L2 for unit float, bits for binary)
  float ratio = 0.9f;         ///< best / second-best in the window must be below this, (0, 1]

  void Check() const;
};

// Guided matching, the hot path of tracking: for every query (a map point's predicted pixel
// position and its descriptor) the keypoint within `radius_px` of the prediction with the smallest
// descriptor distance, accepted under `max_distance` and the ratio test against the runner-up in
// the window. A keypoint goes to at most one query (the one with the smaller distance). Keypoints
// are bucketed in a grid of radius-sized cells, so a query costs the keypoints near it, not all.
// Returns, per query, the keypoint index or -1.
Eigen::VectorXi GuidedMatch(
    const Eigen::Matrix<float, Eigen::Dynamic, 2, Eigen::RowMajor>& predicted,
    const cv::Mat& query_descriptors,
    const Eigen::Matrix<float, Eigen::Dynamic, 2, Eigen::RowMajor>& keypoints,
    const cv::Mat& keypoint_descriptors, const GuidedMatchOptions& options = {});

}  // namespace slslam
