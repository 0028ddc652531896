#include "slslam/features/non_max_suppression.h"

#include <stdexcept>

#include <gtest/gtest.h>

namespace slslam {
namespace {

TEST(SuppressNonMaxima, KeepsThePeakOfAClusterAndSeparatePeaks) {
  PixelIndexArray uv(5, 2);
  uv << 10, 10, 11, 10, 12, 12, 20, 10, 14, 10;
  Eigen::VectorXf score(5);
  score << 0.5f, 0.9f, 0.3f, 0.8f, 0.2f;
  // 11,10 wins; 10,10 and 12,12 lie within 4 px of it; 20,10 is 9 px away; 14,10 is 3 px from
  // the winner: suppressed.
  EXPECT_EQ(SuppressNonMaxima(uv, score, 32, 32, 4), (std::vector<int>{1, 3}));
}

TEST(SuppressNonMaxima, GreedyChainsKeepThePointBehindASuppressedNeighbour) {
  // a (0.9) suppresses b (0.8) at 3 px; c (0.7) is 3 px beyond b, 6 px from a: kept, although
  // its stronger neighbour b is within its window. A max-filter NMS would drop c.
  PixelIndexArray uv(3, 2);
  uv << 5, 5, 8, 5, 11, 5;
  Eigen::VectorXf score(3);
  score << 0.9f, 0.8f, 0.7f;
  EXPECT_EQ(SuppressNonMaxima(uv, score, 32, 32, 4), (std::vector<int>{0, 2}));
  EXPECT_EQ(SuppressNonMaxima(uv, score, 32, 32, 0), (std::vector<int>{0, 1, 2}));
}

TEST(SuppressNonMaxima, RejectsBadInput) {
  PixelIndexArray uv(1, 2);
  uv << 0, 0;
  EXPECT_THROW(SuppressNonMaxima(uv, Eigen::VectorXf(2), 8, 8, 4), std::invalid_argument);
  EXPECT_THROW(SuppressNonMaxima(uv, Eigen::VectorXf(1), 8, 8, -1), std::invalid_argument);
}

}  // namespace
}  // namespace slslam
