// Point-line association on the keypoint grid (the SL-SLAM paper's): each line keeps the ids of
// the keypoints that lie on it, so lines can later be matched through the point matches.
#pragma once

#include <vector>

#include "slslam/features/grid_limit.h"
#include "slslam/features/line_segment.h"

namespace slslam {

struct AssociationOptions {
  int cell_size_px = 32;         ///< grid cell side P [px]; the grid limit's P
  int layers = 1;                ///< n: a cell's extended region is (2n + 1) x (2n + 1) cells
  float max_distance_px = 2.0f;  ///< largest point-to-line distance D_ij [px]

  void Check() const;
};

// For every line, the indices (ascending) of the keypoints associated with it: keypoint p in cell
// g is associated with line l when l passes through g's extended region, the distance of p to l's
// line is below max_distance_px, and p's u lies within the segment's u-range or its v within the
// v-range. `valid_cells` (row-major, optional: empty = all valid) excludes the keypoints of invalid
// cells (dynamic-cell filter).
std::vector<std::vector<int>> AssociatePointsToLines(const PixelArray& keypoints,
                                                     const Segments& lines, int width, int height,
                                                     const AssociationOptions& options = {},
                                                     const std::vector<bool>& valid_cells = {});

}  // namespace slslam
