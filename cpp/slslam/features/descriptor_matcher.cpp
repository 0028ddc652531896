#include "slslam/features/descriptor_matcher.h"

#include <vector>

#include <opencv2/features2d.hpp>

#include "slslam/core/check.h"

namespace slslam {

void MatchOptions::Check() const {
  Require(max_distance > 0.0f, Message("match.max_distance must be > 0, got ", max_distance));
  Require(ratio > 0.0f && ratio <= 1.0f, Message("match.ratio must be in (0, 1], got ", ratio));
}

Eigen::Matrix<int, Eigen::Dynamic, 2, Eigen::RowMajor> MatchDescriptors(
    const cv::Mat& query, const cv::Mat& train, const MatchOptions& options) {
  options.Check();
  Require(query.type() == train.type(), "query and train descriptors differ in type");
  Require(query.type() == CV_8U || query.type() == CV_32F,
          "descriptors must be CV_8U (binary) or CV_32F (float)");
  Require(query.empty() || train.empty() || query.cols == train.cols,
          Message("descriptor lengths differ: ", query.cols, " vs ", train.cols));
  Eigen::Matrix<int, Eigen::Dynamic, 2, Eigen::RowMajor> pairs(0, 2);
  if (query.rows == 0 || train.rows == 0) return pairs;

  const int norm = query.type() == CV_8U ? cv::NORM_HAMMING : cv::NORM_L2;
  cv::BFMatcher matcher(norm, /*crossCheck=*/false);
  std::vector<std::vector<cv::DMatch>> forward;
  matcher.knnMatch(query, train, forward, 2);
  std::vector<int> best_query_for_train;
  if (options.mutual) {
    std::vector<cv::DMatch> backward;
    matcher.match(train, query, backward);
    best_query_for_train.assign(train.rows, -1);
    for (const auto& m : backward) best_query_for_train[m.queryIdx] = m.trainIdx;
  }

  std::vector<std::pair<int, int>> kept;
  for (const auto& candidates : forward) {
    if (candidates.empty()) continue;
    const cv::DMatch& best = candidates[0];
    if (best.distance > options.max_distance) continue;
    if (candidates.size() > 1 && best.distance >= options.ratio * candidates[1].distance) continue;
    if (options.mutual && best_query_for_train[best.trainIdx] != best.queryIdx) continue;
    kept.emplace_back(best.queryIdx, best.trainIdx);
  }
  pairs.resize(static_cast<Eigen::Index>(kept.size()), 2);
  for (size_t i = 0; i < kept.size(); ++i) {
    pairs(static_cast<Eigen::Index>(i), 0) = kept[i].first;
    pairs(static_cast<Eigen::Index>(i), 1) = kept[i].second;
  }
  return pairs;
}

}  // namespace slslam
