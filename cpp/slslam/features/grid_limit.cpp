#include "slslam/features/grid_limit.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "slslam/core/check.h"

namespace slslam {

void GridLimitOptions::Check() const {
  CheckInRange("grid.cell_size_px", cell_size_px, 4, limits::kMaxCellSizePx);
  CheckInRange("grid.max_per_cell", max_per_cell, 1, limits::kMaxKeypoints);
  Require(!std::isnan(strong_score), "grid.strong_score must not be NaN");
}

std::vector<int> GridLimit(const PixelArray& uv, const Eigen::VectorXf& score, int width,
                           int height, const GridLimitOptions& options) {
  options.Check();
  SLSLAM_CHECK(width > 0 && height > 0, "image size must be positive, got ", width, "x", height);
  SLSLAM_CHECK(score.size() == uv.rows(), uv.rows(), " keypoints but ", score.size(), " scores");
  const int cells_x = (width + options.cell_size_px - 1) / options.cell_size_px;
  std::vector<int> cell(uv.rows(), -1);
  std::vector<int> order;
  order.reserve(uv.rows());
  for (Eigen::Index i = 0; i < uv.rows(); ++i) {
    const float u = uv(i, 0), v = uv(i, 1);
    if (!(u >= 0.0f && v >= 0.0f && u < width && v < height) || !std::isfinite(score(i))) continue;
    cell[i] = static_cast<int>(v) / options.cell_size_px * cells_x +
              static_cast<int>(u) / options.cell_size_px;
    order.push_back(static_cast<int>(i));
  }
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    if (cell[a] != cell[b]) return cell[a] < cell[b];
    if (score(a) != score(b)) return score(a) > score(b);
    return a < b;
  });
  // Sorted by cell, then score: a cell's first keypoint tells whether it has a strong one.
  std::vector<int> kept;
  int current_cell = -1, taken = 0;
  bool cell_has_strong = false;
  for (int i : order) {
    if (cell[i] != current_cell) {
      current_cell = cell[i];
      taken = 0;
      cell_has_strong = score(i) >= options.strong_score;
    }
    if (cell_has_strong && score(i) < options.strong_score) continue;
    if (taken++ < options.max_per_cell) kept.push_back(i);
  }
  std::sort(kept.begin(), kept.end());
  return kept;
}

}  // namespace slslam
