// Per-cell keypoint limit (the SL-SLAM paper's "grid limitation"): the image is divided into cells
// of P x P pixels and each cell keeps only its highest-scoring keypoints. Replaces ORB-SLAM's
// quadtree distribution: it spreads keypoints evenly at a cost linear in their number.
#pragma once

#include <limits>
#include <vector>

#include <Eigen/Core>

namespace slslam {

using PixelArray = Eigen::Matrix<float, Eigen::Dynamic, 2, Eigen::RowMajor>;

struct GridLimitOptions {
  int cell_size_px = 32;  ///< P: side of a square cell [px]; the paper leaves P open
  int max_per_cell = 8;   ///< keypoints kept per cell [-] (the paper's 8)
  /// Low-texture fallback: a cell holding any keypoint scoring >= strong_score keeps only those;
  /// a cell without one keeps its weaker keypoints (a detector run at a lower threshold fills
  /// dark, smooth cells). -infinity: every keypoint counts as strong (off).
  float strong_score = -std::numeric_limits<float>::infinity();

  void Check() const;
};

// Indices (ascending) of the keypoints kept: in every cell the `max_per_cell` with the highest
// score among its strong keypoints, or among all when it has no strong one (ties: the lower index
// wins, so the result is deterministic). Keypoints outside the image (u, v not in [0, width) x [0,
// height)) are dropped.
std::vector<int> GridLimit(const PixelArray& uv, const Eigen::VectorXf& score, int width,
                           int height, const GridLimitOptions& options = {});

}  // namespace slslam
