#include "slslam/features/point_line_association.h"

#include <algorithm>
#include <set>

#include "slslam/core/check.h"

namespace slslam {

void AssociationOptions::Check() const {
  CheckInRange("association.cell_size_px", cell_size_px, 4, limits::kMaxCellSizePx);
  CheckInRange("association.layers", layers, 0, 1000);
  CheckAboveInRange("association.max_distance_px", max_distance_px, 0.0f,
                    limits::kMaxImageDistancePx);
}

std::vector<std::vector<int>> AssociatePointsToLines(const PixelArray& keypoints,
                                                     const Segments& lines, int width, int height,
                                                     const AssociationOptions& options,
                                                     const std::vector<bool>& valid_cells) {
  options.Check();
  SLSLAM_CHECK(width > 0 && height > 0, "image size must be positive, got ", width, "x", height);
  const int P = options.cell_size_px;
  const int cells_x = (width + P - 1) / P, cells_y = (height + P - 1) / P;
  SLSLAM_CHECK(valid_cells.empty() || valid_cells.size() == static_cast<size_t>(cells_x) * cells_y,
               "valid_cells has ", valid_cells.size(), " entries for ", cells_x * cells_y,
               " cells");
  // Keypoints bucketed by cell.
  std::vector<std::vector<int>> in_cell(static_cast<size_t>(cells_x) * cells_y);
  for (Eigen::Index i = 0; i < keypoints.rows(); ++i) {
    const float u = keypoints(i, 0), v = keypoints(i, 1);
    if (!(u >= 0.0f && v >= 0.0f && u < width && v < height)) continue;
    const int c = static_cast<int>(v) / P * cells_x + static_cast<int>(u) / P;
    if (valid_cells.empty() || valid_cells[c]) in_cell[c].push_back(static_cast<int>(i));
  }
  std::vector<std::vector<int>> associated(lines.size());
  for (size_t j = 0; j < lines.size(); ++j) {
    const LineSegment& line = lines[j];
    // Cells the segment passes through (sampled at a quarter cell), grown by n layers: these are
    // exactly the cells whose extended region the segment crosses.
    std::set<int> cells;
    const int steps = std::max(1, static_cast<int>(std::ceil(line.Length() / (0.25f * P))));
    for (int s = 0; s <= steps; ++s) {
      const Eigen::Vector2f p = line.start + (line.end - line.start) * (float(s) / steps);
      const int cx = static_cast<int>(std::floor(p.x() / P));
      const int cy = static_cast<int>(std::floor(p.y() / P));
      for (int dy = -options.layers; dy <= options.layers; ++dy) {
        for (int dx = -options.layers; dx <= options.layers; ++dx) {
          const int x = cx + dx, y = cy + dy;
          if (x >= 0 && y >= 0 && x < cells_x && y < cells_y) cells.insert(y * cells_x + x);
        }
      }
    }
    const float u_lo = std::min(line.start.x(), line.end.x());
    const float u_hi = std::max(line.start.x(), line.end.x());
    const float v_lo = std::min(line.start.y(), line.end.y());
    const float v_hi = std::max(line.start.y(), line.end.y());
    for (int c : cells) {
      for (int i : in_cell[c]) {
        const Eigen::Vector2f p(keypoints(i, 0), keypoints(i, 1));
        if (line.DistanceToLine(p) >= options.max_distance_px) continue;
        const bool within_u = p.x() >= u_lo && p.x() <= u_hi;
        const bool within_v = p.y() >= v_lo && p.y() <= v_hi;
        if (within_u || within_v) associated[j].push_back(i);
      }
    }
    std::sort(associated[j].begin(), associated[j].end());
  }
  return associated;
}

}  // namespace slslam
