#include "slslam/features/dense_sampling.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "slslam/core/check.h"
#include "slslam/core/cpu_dispatch.h"

namespace slslam {
namespace {

constexpr double kCubicA = -0.75;  // PyTorch's bicubic kernel

// Weights of the taps at floor(x) + offset, offset in [first, first + count).
int Taps(double t, bool cubic, double* w) {
  if (!cubic) {
    w[0] = 1.0 - t;
    w[1] = t;
    return 0;
  }
  const auto near = [](double x) { return ((kCubicA + 2.0) * x - (kCubicA + 3.0)) * x * x + 1.0; };
  const auto far = [](double x) {
    return ((kCubicA * x - 5.0 * kCubicA) * x + 8.0 * kCubicA) * x - 4.0 * kCubicA;
  };
  w[0] = far(t + 1.0);
  w[1] = near(t);
  w[2] = near(1.0 - t);
  w[3] = far(2.0 - t);
  return -1;
}

// The keypoints' accumulation, one channel vector per tap: acc[c] += w * tap[c] over the taps
// in the same order as a per-channel loop would, so each channel's sum is the same double.
// Compiled for AVX2 too (core/cpu_dispatch.h; no FMA: the products are rounded as in the plain
// build), the channel loop in four-wide double lanes.
SLSLAM_AVX2_CLONES void AccumulateTaps(const float* __restrict pixels, int channels, int map_height,
                                       int map_width, int taps, int x_first, int y_first,
                                       const double* wx, const double* wy, double* __restrict acc) {
  for (int c = 0; c < channels; ++c) acc[c] = 0.0;
  for (int b = 0; b < taps; ++b) {
    const int yi = y_first + b;
    if (yi < 0 || yi >= map_height) continue;
    for (int a = 0; a < taps; ++a) {
      const int xi = x_first + a;
      if (xi < 0 || xi >= map_width) continue;
      const double w = wy[b] * wx[a];
      const float* tap = pixels + (static_cast<size_t>(yi) * map_width + xi) * channels;
      for (int c = 0; c < channels; ++c) acc[c] += w * tap[c];
    }
  }
}

}  // namespace

DenseSamples SampleDenseMap(const Eigen::Ref<const DenseSamples>& map, int map_height,
                            int map_width, const PixelArray& uv, int input_height, int input_width,
                            bool cubic) {
  SLSLAM_CHECK(map_height > 0 && map_width > 0 &&
                   map.cols() == static_cast<Eigen::Index>(map_height) * map_width,
               "a map of ", map.cols(), " values per channel is not ", map_height, " x ",
               map_width);
  SLSLAM_CHECK(input_height > 1 && input_width > 1, "input size must exceed 1 x 1, got ",
               input_height, " x ", input_width);
  const int channels = static_cast<int>(map.rows());
  const int taps = cubic ? 4 : 2;
  DenseSamples out(uv.rows(), channels);
  if (uv.rows() == 0 || channels == 0) return out;
  // The map pixel-major (each pixel's channels side by side), made once: a tap then reads its
  // channels from consecutive memory instead of one value per channel plane (64 cache lines a
  // tap for XFeat's descriptors). 2.4 % of XFeat + lines' CPU before (perf).
  const Eigen::Index pixels = map.cols();
  std::vector<float> by_pixel(static_cast<size_t>(pixels) * channels);
  // (in blocks of 16 pixels: each plane's 16 values are one cache line, and the block's
  // channels stay in L1 while they are written)
  constexpr Eigen::Index kBlock = 16;
  for (Eigen::Index begin = 0; begin < pixels; begin += kBlock) {
    const Eigen::Index end = std::min(pixels, begin + kBlock);
    for (int c = 0; c < channels; ++c) {
      for (Eigen::Index at = begin; at < end; ++at) {
        by_pixel[static_cast<size_t>(at) * channels + c] = map(c, at);
      }
    }
  }
  std::vector<double> acc(channels);
  for (Eigen::Index i = 0; i < uv.rows(); ++i) {
    const double x = static_cast<double>(uv(i, 0)) * map_width / (input_width - 1) - 0.5;
    const double y = static_cast<double>(uv(i, 1)) * map_height / (input_height - 1) - 0.5;
    const double x0 = std::floor(x), y0 = std::floor(y);
    double wx[4], wy[4];
    const int first = Taps(x - x0, cubic, wx);
    Taps(y - y0, cubic, wy);
    AccumulateTaps(by_pixel.data(), channels, map_height, map_width, taps,
                   static_cast<int>(x0) + first, static_cast<int>(y0) + first, wx, wy, acc.data());
    for (int c = 0; c < channels; ++c) out(i, c) = static_cast<float>(acc[c]);
  }
  return out;
}

}  // namespace slslam
