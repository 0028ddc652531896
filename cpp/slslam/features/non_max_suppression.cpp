#include "slslam/features/non_max_suppression.h"

#include <algorithm>
#include <numeric>

#include "slslam/core/check.h"

namespace slslam {

PixelIndexArray LocalMaxima(const Eigen::Ref<const HeatMap>& heat, float threshold, int radius_px,
                            int border_px) {
  SLSLAM_CHECK(radius_px >= 0 && border_px >= 0, "NMS radius and border must be >= 0, got ",
               radius_px, " and ", border_px);
  const int h = static_cast<int>(heat.rows()), w = static_cast<int>(heat.cols());
  std::vector<int> kept;  // u, v pairs
  for (int v = border_px; v < h - border_px; ++v) {
    const float* row = heat.data() + v * heat.outerStride();
    for (int u = border_px; u < w - border_px; ++u) {
      const float value = row[u];
      if (!(value > threshold)) continue;
      bool peak = true;
      for (int y = std::max(0, v - radius_px); peak && y <= std::min(h - 1, v + radius_px); ++y) {
        const float* r = heat.data() + y * heat.outerStride();
        for (int x = std::max(0, u - radius_px); x <= std::min(w - 1, u + radius_px); ++x) {
          if (!(r[x] <= value)) {  // as numpy: a NaN neighbour is no peak either
            peak = false;
            break;
          }
        }
      }
      if (peak) {
        kept.push_back(u);
        kept.push_back(v);
      }
    }
  }
  PixelIndexArray uv(static_cast<Eigen::Index>(kept.size() / 2), 2);
  std::copy(kept.begin(), kept.end(), uv.data());
  return uv;
}

std::vector<int> SuppressNonMaxima(const PixelIndexArray& uv, const Eigen::VectorXf& score,
                                   int width, int height, int radius_px) {
  SLSLAM_CHECK(width > 0 && height > 0, "image size must be positive, got ", width, "x", height);
  SLSLAM_CHECK(radius_px >= 0, "NMS radius must be >= 0, got ", radius_px);
  SLSLAM_CHECK(score.size() == uv.rows(), uv.rows(), " candidates but ", score.size(), " scores");
  std::vector<int> order(uv.rows());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return score(a) > score(b); });
  std::vector<uint8_t> suppressed(static_cast<size_t>(width) * height, 0);
  std::vector<int> kept;
  for (int i : order) {
    const int u = uv(i, 0), v = uv(i, 1);
    if (u < 0 || v < 0 || u >= width || v >= height) continue;
    if (suppressed[static_cast<size_t>(v) * width + u]) continue;
    kept.push_back(i);
    for (int y = std::max(0, v - radius_px); y <= std::min(height - 1, v + radius_px); ++y) {
      std::fill_n(suppressed.begin() + static_cast<size_t>(y) * width + std::max(0, u - radius_px),
                  std::min(width - 1, u + radius_px) - std::max(0, u - radius_px) + 1, 1);
    }
  }
  return kept;
}

}  // namespace slslam
