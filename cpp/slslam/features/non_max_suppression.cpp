#include "slslam/features/non_max_suppression.h"

#include <algorithm>
#include <numeric>

#include "slslam/core/check.h"

namespace slslam {

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
