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
