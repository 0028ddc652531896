#include "slslam/features/gaussian_blur.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "slslam/core/check.h"
#include "slslam/core/cpu_dispatch.h"

namespace slslam {

namespace {

// The arithmetic of OpenCV's 8-bit Gaussian (its "bit-exact" path), reproduced: the taps in 8
// fractional bits (they sum to 256); the horizontal pass sums tap x pixel exactly (at most
// 255 x 256, 16 bits); the vertical pass sums tap x row exactly (at most 255 x 2^16) and rounds
// once, (sum + 2^15) >> 16. Here in 16-bit lanes (16 pixels an AVX2 instruction): a mirrored pair
// of pixels enters once with its shared tap (a side tap is below 128, so tap x (a + b) fits 16
// bits), and the vertical sum is split by the rows' high and low bytes into two 16-bit sums.
constexpr int kTapBits = 8;

// Index into [0, n) reflected at the ends without repeating the edge (cv::BORDER_REFLECT_101),
// as often as it takes (a kernel wider than the image).
int Reflect101(int i, int n) {
  if (n == 1) return 0;
  const int period = 2 * (n - 1);
  i %= period;
  if (i < 0) i += period;
  return i < n ? i : period - i;
}

// One row: `padded` holds the row with `radius` reflected pixels on each side; taps[k] is tap k
// from the centre.
SLSLAM_AVX2_CLONES void HorizontalPass(const uint8_t* padded, int width, const uint16_t* taps,
                                       int radius, uint16_t* out) {
  const uint8_t* centre = padded + radius;
  const uint16_t t0 = taps[0];
  for (int x = 0; x < width; ++x) out[x] = static_cast<uint16_t>(t0 * centre[x]);
  for (int k = 1; k <= radius; ++k) {
    const uint16_t t = taps[k];
    const uint8_t* left = centre - k;
    const uint8_t* right = centre + k;
    for (int x = 0; x < width; ++x) {
      out[x] = static_cast<uint16_t>(out[x] + t * static_cast<uint16_t>(left[x] + right[x]));
    }
  }
}

// One output row from the 2 radius + 1 horizontally blurred rows around it (`rows[0]` the
// centre, `rows[2k - 1]` / `rows[2k]` the rows k above / below). `high` and `low` sum tap x
// the rows' high and low bytes (each at most 255 x 256).
SLSLAM_AVX2_CLONES void VerticalPass(const uint16_t* const* rows, int width, const uint16_t* taps,
                                     int radius, uint16_t* high, uint16_t* low, uint8_t* out) {
  const uint16_t t0 = taps[0];
  for (int x = 0; x < width; ++x) {
    high[x] = static_cast<uint16_t>(t0 * (rows[0][x] >> 8));
    low[x] = static_cast<uint16_t>(t0 * (rows[0][x] & 0xff));
  }
  for (int k = 1; k <= radius; ++k) {
    const uint16_t t = taps[k];
    const uint16_t* above = rows[2 * k - 1];
    const uint16_t* below = rows[2 * k];
    for (int x = 0; x < width; ++x) {
      high[x] = static_cast<uint16_t>(high[x] +
                                      t * static_cast<uint16_t>((above[x] >> 8) + (below[x] >> 8)));
      low[x] = static_cast<uint16_t>(
          low[x] + t * static_cast<uint16_t>((above[x] & 0xff) + (below[x] & 0xff)));
    }
  }
  for (int x = 0; x < width; ++x) {
    const uint32_t sum = (static_cast<uint32_t>(high[x]) << 8) + low[x];
    out[x] = static_cast<uint8_t>((sum + (1u << (2 * kTapBits - 1))) >> (2 * kTapBits));
  }
}

}  // namespace

std::vector<int> GaussianTaps8u(double sigma_px, int radius) {
  Require(std::isfinite(sigma_px) && sigma_px > 0.0 && sigma_px <= 100.0,
          "Gaussian blur needs sigma in (0, 100] px");
  Require(radius >= -1 && radius <= 1000, "Gaussian blur needs a radius in [0, 1000] px or -1");
  // OpenCV's size for 8-bit images: cvRound(sigma * 6 + 1) | 1 taps.
  if (radius < 0) radius = (cvRound(sigma_px * 6.0 + 1.0) | 1) / 2;
  // The sampled Gaussian normalised to 1, then in 8 fractional bits from the outermost tap in,
  // each tap's rounding error carried into the next (error diffusion), the centre taking what is
  // left of 256 (as OpenCV's fixed-point kernel).
  std::vector<double> gaussian(radius + 1);
  double total = 1.0;
  for (int k = 1; k <= radius; ++k) {
    gaussian[k] = std::exp(-0.5 * k * k / (sigma_px * sigma_px));
    total += 2.0 * gaussian[k];
  }
  std::vector<int> taps(radius + 1);
  double carried = 0.0;
  int sides = 0;
  for (int k = radius; k >= 1; --k) {
    const double scaled = gaussian[k] / total * (1 << kTapBits) + carried;
    taps[k] = static_cast<int>(std::lrint(scaled));
    carried = scaled - taps[k];
    sides += 2 * taps[k];
  }
  taps[0] = (1 << kTapBits) - sides;
  return taps;
}

cv::Mat GaussianBlur8u(const cv::Mat& image, double sigma_px, int radius_px) {
  Require(!image.empty() && image.type() == CV_8UC1, "Gaussian blur needs an 8-bit gray image");
  const std::vector<int> int_taps = GaussianTaps8u(sigma_px, radius_px);
  const int radius = static_cast<int>(int_taps.size()) - 1;
  cv::Mat out(image.size(), CV_8UC1);
  if (radius == 0) {
    image.copyTo(out);
    return out;
  }
  std::vector<uint16_t> taps(int_taps.begin(), int_taps.end());

  const int width = image.cols, height = image.rows, span = 2 * radius + 1;
  std::vector<uint8_t> padded(width + 2 * radius);
  std::vector<uint16_t> high(width), low(width);
  // The horizontally blurred rows, a ring of the last `span` image rows (row i in slot i % span):
  // every row an output row needs, its reflections included, lies within `radius` of it (or the
  // image has fewer rows than the ring, which then holds them all).
  std::vector<uint16_t> ring(static_cast<size_t>(span) * width);
  const auto slot = [&](int row) { return ring.data() + static_cast<size_t>(row % span) * width; };
  const auto blur_row = [&](int row) {
    const uint8_t* src = image.ptr<uint8_t>(row);
    for (int i = 0; i < radius; ++i) {
      padded[i] = src[Reflect101(i - radius, width)];
      padded[radius + width + i] = src[Reflect101(width + i, width)];
    }
    std::copy(src, src + width, padded.data() + radius);
    HorizontalPass(padded.data(), width, taps.data(), radius, slot(row));
  };
  std::vector<const uint16_t*> rows(span);
  int next = 0;  // the next image row to blur horizontally
  for (int y = 0; y < height; ++y) {
    for (; next <= std::min(y + radius, height - 1); ++next) blur_row(next);
    rows[0] = slot(y);
    for (int k = 1; k <= radius; ++k) {
      rows[2 * k - 1] = slot(Reflect101(y - k, height));
      rows[2 * k] = slot(Reflect101(y + k, height));
    }
    VerticalPass(rows.data(), width, taps.data(), radius, high.data(), low.data(),
                 out.ptr<uint8_t>(y));
  }
  return out;
}

cv::Mat GaussianBlurAsOpenCv(const cv::Mat& image, double sigma_px, int radius_px) {
  if (!image.isSubmatrix() && sigma_px <= 100.0 && radius_px <= 1000) {
    return GaussianBlur8u(image, sigma_px, radius_px);
  }
  const cv::Size size = radius_px < 0 ? cv::Size() : cv::Size(2 * radius_px + 1, 2 * radius_px + 1);
  cv::Mat out;  // (a buffer of its own: into a header copy of `image` OpenCV would write in place)
  cv::GaussianBlur(image, out, size, sigma_px, sigma_px, cv::BORDER_REFLECT_101);
  return out;
}

}  // namespace slslam
