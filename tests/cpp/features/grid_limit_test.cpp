#include "slslam/features/grid_limit.h"

#include <map>
#include <stdexcept>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

namespace slslam {
namespace {

TEST(GridLimit, NoCellKeepsMoreThanItsLimitAndTheBestSurvive) {
  cv::RNG rng(3);
  const int n = 5000, width = 752, height = 480;
  PixelArray uv(n, 2);
  Eigen::VectorXf score(n);
  for (int i = 0; i < n; ++i) {
    uv(i, 0) = rng.uniform(0.0f, static_cast<float>(width));
    uv(i, 1) = rng.uniform(0.0f, static_cast<float>(height));
    score(i) = rng.uniform(0.0f, 1.0f);
  }
  GridLimitOptions options;
  const std::vector<int> kept = GridLimit(uv, score, width, height, options);
  std::map<int, std::vector<float>> per_cell;
  for (int i : kept) {
    per_cell[static_cast<int>(uv(i, 1)) / 32 * 24 + static_cast<int>(uv(i, 0)) / 32].push_back(
        score(i));
  }
  for (const auto& [cell, scores] : per_cell) EXPECT_LE(scores.size(), 8u) << "cell " << cell;
  // Every cell keeps min(its keypoints, 8).
  std::map<int, int> count;
  for (int i = 0; i < n; ++i) {
    ++count[static_cast<int>(uv(i, 1)) / 32 * 24 + static_cast<int>(uv(i, 0)) / 32];
  }
  size_t expected = 0;
  for (const auto& [cell, c] : count) expected += std::min(c, 8);
  EXPECT_EQ(kept.size(), expected);
  EXPECT_GT(kept.size(), 2500u);
  // The kept ones are each cell's best: no dropped keypoint beats the worst kept in its cell.
  std::map<int, float> worst_kept;
  for (const auto& [cell, scores] : per_cell) {
    worst_kept[cell] = *std::min_element(scores.begin(), scores.end());
  }
  std::vector<bool> is_kept(n, false);
  for (int i : kept) is_kept[i] = true;
  for (int i = 0; i < n; ++i) {
    if (is_kept[i]) continue;
    const int cell = static_cast<int>(uv(i, 1)) / 32 * 24 + static_cast<int>(uv(i, 0)) / 32;
    EXPECT_LE(score(i), worst_kept[cell]);
  }
}

TEST(GridLimit, SmallCaseByHand) {
  PixelArray uv(5, 2);
  uv << 1, 1, 2, 2, 3, 3, 40, 1, -5, 3;  // three in cell 0, one in cell 1, one outside
  Eigen::VectorXf score(5);
  score << 0.1f, 0.9f, 0.5f, 0.2f, 1.0f;
  GridLimitOptions options;
  options.max_per_cell = 2;
  const std::vector<int> kept = GridLimit(uv, score, 64, 32, options);
  EXPECT_EQ(kept, (std::vector<int>{1, 2, 3}));
}

TEST(GridLimit, WeakKeypointsFillOnlyCellsWithoutAStrongOne) {
  PixelArray uv(6, 2);
  // Cell 0: one strong (0.9) and two weak; cell 1: only weak ones (0.2, 0.1, 0.05).
  uv << 1, 1, 2, 2, 3, 3, 40, 1, 41, 2, 42, 3;
  Eigen::VectorXf score(6);
  score << 0.9f, 0.3f, 0.2f, 0.2f, 0.1f, 0.05f;
  GridLimitOptions options;
  options.max_per_cell = 2;
  options.strong_score = 0.5f;
  EXPECT_EQ(GridLimit(uv, score, 64, 32, options), (std::vector<int>{0, 3, 4}));
  options.strong_score = -std::numeric_limits<float>::infinity();  // off: the plain limit
  EXPECT_EQ(GridLimit(uv, score, 64, 32, options), (std::vector<int>{0, 1, 3, 4}));
}

TEST(GridLimit, RejectsBadInput) {
  PixelArray uv(2, 2);
  uv.setZero();
  EXPECT_THROW(GridLimit(uv, Eigen::VectorXf(3), 10, 10), std::invalid_argument);
  GridLimitOptions bad;
  bad.max_per_cell = 0;
  EXPECT_THROW(GridLimit(uv, Eigen::VectorXf::Zero(2), 10, 10, bad), std::invalid_argument);
}

}  // namespace
}  // namespace slslam
