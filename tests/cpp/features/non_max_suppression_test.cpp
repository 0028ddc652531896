#include "slslam/features/non_max_suppression.h"

#include <algorithm>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

namespace slslam {
namespace {

TEST(LocalMaxima, EqualsABruteForceMaxFilterWithTiesAndBorder) {
  // Random values on a coarse set of levels (many ties), compared with the definition.
  HeatMap heat(37, 53);
  unsigned state = 7;
  for (Eigen::Index i = 0; i < heat.size(); ++i) {
    state = state * 1103515245u + 12345u;
    heat.data()[i] = static_cast<float>((state >> 16) % 8) / 8.0f;
  }
  for (int radius : {0, 1, 2, 4}) {
    for (int border : {0, 3}) {
      const PixelIndexArray got = LocalMaxima(heat, 0.3f, radius, border);
      std::vector<int> want;
      for (int v = border; v < heat.rows() - border; ++v) {
        for (int u = border; u < heat.cols() - border; ++u) {
          if (!(heat(v, u) > 0.3f)) continue;
          bool peak = true;
          for (int y = v - radius; y <= v + radius; ++y) {
            for (int x = u - radius; x <= u + radius; ++x) {
              const bool inside = y >= 0 && x >= 0 && y < heat.rows() && x < heat.cols();
              if (inside && heat(y, x) > heat(v, u)) peak = false;
            }
          }
          if (peak) want.insert(want.end(), {u, v});
        }
      }
      ASSERT_EQ(got.rows() * 2, static_cast<Eigen::Index>(want.size()));
      EXPECT_TRUE(std::equal(want.begin(), want.end(), got.data())) << radius << " " << border;
      if (radius == 0 && border == 0) EXPECT_GT(got.rows(), heat.size() / 2);
    }
  }
  EXPECT_EQ(LocalMaxima(heat, 1.0f, 2, 0).rows(), 0);  // nothing above the threshold
  EXPECT_THROW(LocalMaxima(heat, 0.3f, -1, 0), std::invalid_argument);
}

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
