#include "slslam/features/descriptor_matcher.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include <opencv2/features2d.hpp>

#include "slslam/core/check.h"
#include "slslam/core/cpu_dispatch.h"

namespace slslam {

void MatchOptions::Check() const {
  CheckAboveInRange("match.max_distance", max_distance, 0.0f, limits::kMaxDescriptorDistance);
  CheckAboveInRange("match.ratio", ratio, 0.0f, 1.0f);
}

Eigen::Matrix<int, Eigen::Dynamic, 2, Eigen::RowMajor> MatchDescriptors(
    const cv::Mat& query, const cv::Mat& train, const MatchOptions& options) {
  options.Check();
  Require(query.type() == train.type(), "query and train descriptors differ in type");
  Require(query.type() == CV_8U || query.type() == CV_32F,
          "descriptors must be CV_8U (binary) or CV_32F (float)");
  SLSLAM_CHECK(query.empty() || train.empty() || query.cols == train.cols,
               "descriptor lengths differ: ", query.cols, " vs ", train.cols);
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

void GuidedMatchOptions::Check() const {
  CheckAboveInRange("guided.radius_px", radius_px, 0.0f, limits::kMaxImageDistancePx);
  CheckAboveInRange("guided.max_distance", max_distance, 0.0f, limits::kMaxDescriptorDistance);
  CheckAboveInRange("guided.ratio", ratio, 0.0f, 1.0f);
}

namespace {

// Hamming bits of two byte strings, 8 bytes a word, with the POPCNT instruction where the CPU has
// it (core/cpu_dispatch.h): the same count as cv::norm(NORM_HAMMING).
SLSLAM_POPCNT_CLONES int HammingBytes(const uint8_t* x, const uint8_t* y, int bytes) {
  int bits = 0;
  int k = 0;
  for (; k + 8 <= bytes; k += 8) {
    uint64_t u, v;
    std::memcpy(&u, x + k, 8);
    std::memcpy(&v, y + k, 8);
    bits += __builtin_popcountll(u ^ v);
  }
  for (; k < bytes; ++k) bits += __builtin_popcount(static_cast<unsigned>(x[k] ^ y[k]));
  return bits;
}

}  // namespace

float DescriptorDistance(const cv::Mat& a, int i, const cv::Mat& b, int j) {
  SLSLAM_CHECK(a.cols == b.cols && a.type() == b.type(),
               "descriptors differ in length or type: ", a.cols, " vs ", b.cols, " columns");
  SLSLAM_CHECK(i >= 0 && i < a.rows && j >= 0 && j < b.rows, "descriptor rows ", i, " / ", j,
               " outside ", a.rows, " / ", b.rows);
  if (a.type() == CV_8U) {
    // (not cv::norm: its two row headers and dispatch per call cost more than the count, and
    // this runs for every candidate of every guided, stereo, line and triangulation match;
    // benchmarks/log/realtime.md)
    return static_cast<float>(HammingBytes(a.ptr<uint8_t>(i), b.ptr<uint8_t>(j), a.cols));
  }
  const float* x = a.ptr<float>(i);
  const float* y = b.ptr<float>(j);
  float sum = 0.0f;
  for (int k = 0; k < a.cols; ++k) sum += (x[k] - y[k]) * (x[k] - y[k]);
  return std::sqrt(sum);
}

Eigen::VectorXi GuidedMatch(
    const Eigen::Matrix<float, Eigen::Dynamic, 2, Eigen::RowMajor>& predicted,
    const cv::Mat& query_descriptors,
    const Eigen::Matrix<float, Eigen::Dynamic, 2, Eigen::RowMajor>& keypoints,
    const cv::Mat& keypoint_descriptors, const GuidedMatchOptions& options) {
  options.Check();
  SLSLAM_CHECK(predicted.rows() == query_descriptors.rows, predicted.rows(), " predictions but ",
               query_descriptors.rows, " descriptors");
  SLSLAM_CHECK(keypoints.rows() == keypoint_descriptors.rows, keypoints.rows(), " keypoints but ",
               keypoint_descriptors.rows, " descriptors");
  Eigen::VectorXi match = Eigen::VectorXi::Constant(predicted.rows(), -1);
  if (predicted.rows() == 0 || keypoints.rows() == 0) return match;
  Require(query_descriptors.type() == keypoint_descriptors.type() &&
              query_descriptors.cols == keypoint_descriptors.cols,
          "query and keypoint descriptors differ in type or length");
  Require(query_descriptors.type() == CV_8U || query_descriptors.type() == CV_32F,
          "descriptors must be CV_8U (binary) or CV_32F (float)");

  // Bucket the keypoints; a window of radius r around a point lies in the 3 x 3 buckets around it.
  // The buckets are one flat grid over the keypoints' cells (counted, then filled: the keypoints
  // of a bucket in index order, as pushing them one by one gave), not a hash map of vectors: its
  // allocations were most of this function's time (benchmarks/log/realtime.md).
  const float cell = options.radius_px;
  const Eigen::Index n_keypoints = keypoints.rows();
  std::vector<int64_t> cell_x(n_keypoints), cell_y(n_keypoints);
  int64_t min_cx = std::numeric_limits<int64_t>::max();
  int64_t max_cx = std::numeric_limits<int64_t>::min();
  int64_t min_cy = min_cx, max_cy = max_cx;
  for (Eigen::Index j = 0; j < n_keypoints; ++j) {
    cell_x[j] = static_cast<int64_t>(std::floor(keypoints(j, 0) / cell));
    cell_y[j] = static_cast<int64_t>(std::floor(keypoints(j, 1) / cell));
    min_cx = std::min(min_cx, cell_x[j]);
    max_cx = std::max(max_cx, cell_x[j]);
    min_cy = std::min(min_cy, cell_y[j]);
    max_cy = std::max(max_cy, cell_y[j]);
  }
  const int64_t grid_w = max_cx - min_cx + 1, grid_h = max_cy - min_cy + 1;
  // (keypoints far outside the image could make a grid larger than the keypoints: a sparse map
  // of the occupied cells then, sorted, as the hash map was)
  const int64_t dense_cells = 4 * static_cast<int64_t>(n_keypoints) + 4096;
  const bool dense = grid_w > 0 && grid_h > 0 && grid_w <= dense_cells && grid_h <= dense_cells &&
                     grid_w * grid_h <= dense_cells;
  std::vector<int> start, members(n_keypoints);
  std::vector<int64_t> occupied;  // sparse: the occupied cells' keys, sorted
  const auto dense_key = [&](int64_t cx, int64_t cy) {
    return (cy - min_cy) * grid_w + (cx - min_cx);
  };
  const auto sparse_key = [](int64_t cx, int64_t cy) {
    return static_cast<int64_t>(static_cast<uint64_t>(cx) << 32) ^ (cy & 0xffffffff);
  };
  std::vector<int64_t> key_of(n_keypoints);
  if (dense) {
    for (Eigen::Index j = 0; j < n_keypoints; ++j) key_of[j] = dense_key(cell_x[j], cell_y[j]);
    start.assign(static_cast<size_t>(grid_w * grid_h) + 1, 0);
  } else {
    for (Eigen::Index j = 0; j < n_keypoints; ++j) key_of[j] = sparse_key(cell_x[j], cell_y[j]);
    occupied = key_of;
    std::sort(occupied.begin(), occupied.end());
    occupied.erase(std::unique(occupied.begin(), occupied.end()), occupied.end());
    for (int64_t& k : key_of) {
      k = std::lower_bound(occupied.begin(), occupied.end(), k) - occupied.begin();
    }
    start.assign(occupied.size() + 1, 0);
  }
  for (Eigen::Index j = 0; j < n_keypoints; ++j) ++start[static_cast<size_t>(key_of[j]) + 1];
  for (size_t b = 1; b < start.size(); ++b) start[b] += start[b - 1];
  {
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (Eigen::Index j = 0; j < n_keypoints; ++j) {
      members[fill[static_cast<size_t>(key_of[j])]++] = static_cast<int>(j);
    }
  }
  // The bucket of cell (cx, cy): its slot, or -1 when no keypoint lies in it.
  const auto bucket = [&](int64_t cx, int64_t cy) -> int64_t {
    if (cx < min_cx || cx > max_cx || cy < min_cy || cy > max_cy) return -1;
    if (dense) return dense_key(cx, cy);
    const int64_t key = sparse_key(cx, cy);
    const auto it = std::lower_bound(occupied.begin(), occupied.end(), key);
    return it != occupied.end() && *it == key ? it - occupied.begin() : -1;
  };
  OneToOne one_to_one(static_cast<int>(keypoints.rows()));
  const float r2 = options.radius_px * options.radius_px;
  for (Eigen::Index i = 0; i < predicted.rows(); ++i) {
    const float u = predicted(i, 0), v = predicted(i, 1);
    if (!std::isfinite(u) || !std::isfinite(v)) continue;
    const int64_t cx = static_cast<int64_t>(std::floor(u / cell));
    const int64_t cy = static_cast<int64_t>(std::floor(v / cell));
    BestTwo best(std::numeric_limits<float>::infinity());
    for (int64_t dy = -1; dy <= 1; ++dy) {
      for (int64_t dx = -1; dx <= 1; ++dx) {
        const int64_t b = bucket(cx + dx, cy + dy);
        if (b < 0) continue;
        for (int m = start[static_cast<size_t>(b)]; m < start[static_cast<size_t>(b) + 1]; ++m) {
          const int j = members[static_cast<size_t>(m)];
          const float du = keypoints(j, 0) - u, dv = keypoints(j, 1) - v;
          if (du * du + dv * dv > r2) continue;
          best.Add(
              DescriptorDistance(query_descriptors, static_cast<int>(i), keypoint_descriptors, j),
              j);
        }
      }
    }
    if (best.index < 0 || best.best > options.max_distance) continue;
    if (std::isfinite(best.second) && best.best >= options.ratio * best.second) continue;
    // A keypoint already held by a query with a smaller distance stays with it.
    one_to_one.Offer(static_cast<int>(i), best.index, best.best, &match);
  }
  return match;
}

}  // namespace slslam
