// Brute-force descriptor matching with the mutual-nearest-neighbour and ratio tests.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace slslam {

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

}  // namespace slslam
