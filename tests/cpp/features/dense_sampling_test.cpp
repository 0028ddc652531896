#include "slslam/features/dense_sampling.h"

#include <stdexcept>

#include <gtest/gtest.h>

namespace slslam {
namespace {

TEST(SampleDenseMap, BilinearIsExactOnAPlaneAndPadsWithZeros) {
  const int hc = 6, wc = 9, h = 48, w = 72;
  DenseSamples map(2, hc * wc);
  for (int y = 0; y < hc; ++y) {
    for (int x = 0; x < wc; ++x) {
      map(0, y * wc + x) = 2.0f * x + 3.0f * y;
      map(1, y * wc + x) = 1.0f;
    }
  }
  PixelArray uv(2, 2);
  uv << 33.0f, 25.0f, 0.0f, 0.0f;
  const DenseSamples s = SampleDenseMap(map, hc, wc, uv, h, w, /*cubic=*/false);
  const double x = 33.0 * wc / (w - 1) - 0.5, y = 25.0 * hc / (h - 1) - 0.5;
  EXPECT_NEAR(s(0, 0), 2.0 * x + 3.0 * y, 1e-5);
  EXPECT_NEAR(s(0, 1), 1.0, 1e-6);
  EXPECT_NEAR(s(1, 1), 0.25, 1e-6);  // the corner: three of four taps are outside (zeros)
  const DenseSamples c = SampleDenseMap(map, hc, wc, uv.topRows(1), h, w, /*cubic=*/true);
  EXPECT_NEAR(c(0, 1), 1.0, 1e-6);  // the cubic weights sum to one
}

TEST(SampleDenseMap, ChecksItsSizes) {
  const DenseSamples map(3, 20);
  const PixelArray uv(1, 2);
  EXPECT_THROW(SampleDenseMap(map, 4, 4, uv, 32, 32, false), std::invalid_argument);
  EXPECT_THROW(SampleDenseMap(map, 4, 5, uv, 1, 32, false), std::invalid_argument);
}

}  // namespace
}  // namespace slslam
