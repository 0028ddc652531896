// Invalid-cell filter for moving objects (SL-SLAM paper): cells whose matched keypoints disagree
// with the camera motion are dropped, together with their 8 neighbours.
//
// Per cell g at frame t, over its m matched keypoints: d = median ||p_i - p'_i|| (the paper: the
// mean; the median ignores a few mismatches in repetitive texture), where p_i is
// the keypoint and p'_i its position predicted by the camera motion; w~ = exp(-d^2 / (2 sigma^2));
// sigma = max(sigma_px, sigma_median_ratio * the median of every match's distance in the frame);
// w_t = alpha * w~ + (1 - alpha) * w_{t-1}; a cell with w_t < threshold is invalid and so are its
// 8 neighbours. A cell without matches (fewer than min_matches) counts as agreeing (w~ = 1), so it
// recovers once the mover has left it (the paper leaves this case open). Every cell starts at w
// = 1.
//
// The paper predicts p'_i with the constant-velocity model, so any motion-model error flags every
// cell. Here p'_i comes from the caller; PredictWithRobustPose() provides the better choice: the
// projections under a RANSAC PnP pose, so only cells that disagree with the consensus are flagged.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "slslam/core/pinhole_camera.h"
#include "slslam/features/grid_limit.h"

namespace slslam {

struct DynamicCellOptions {
  int cell_size_px = 32;   ///< cell side [px]; use the grid limit's P
  double sigma_px = 3.0;   ///< Gaussian width of G(d) [px]
  double alpha = 0.7;      ///< weight of the current frame in the temporal smoothing [-], (0, 1]
  double threshold = 0.5;  ///< l: a cell with smoothed weight below this is invalid [-]
  /// matches a cell needs in a frame to count as evidence; fewer count as none (G = 1): one
  /// keypoint's localisation noise (2-4 px at coarse ORB octaves) must not drop 9 cells [-]
  int min_matches = 2;
  /// G's width is at least this many times the median residual of all the frame's matches, so
  /// a front end that repeats less precisely (XFeat: 3, configs/xfeat.yaml) does not flag static
  /// cells; 0: sigma_px alone, the paper's (ORB's dark sequences tracked better with it) [-]
  double sigma_median_ratio = 0.0;

  void Check() const;
};

class DynamicCellFilter {
 public:
  DynamicCellFilter(int width, int height, const DynamicCellOptions& options = {});

  // Updates the cell weights from one frame's matches: `observed` (M x 2) keypoint positions and
  // `predicted` (M x 2) positions under the camera motion. Returns the new validity of every cell
  // (row-major, cells_x * cells_y; true = valid).
  const std::vector<bool>& Update(const PixelArray& observed, const PixelArray& predicted);

  // True for keypoints in valid cells (false outside the image).
  std::vector<bool> KeypointMask(const PixelArray& uv) const;

  const std::vector<double>& weights() const { return weights_; }
  const std::vector<bool>& valid() const { return valid_; }
  int cells_x() const { return cells_x_; }
  int cells_y() const { return cells_y_; }
  void Reset();

 private:
  int CellOf(float u, float v) const;

  DynamicCellOptions options_;
  int width_, height_, cells_x_, cells_y_;
  std::vector<double> weights_;
  std::vector<bool> valid_;
};

struct RobustPrediction {
  PixelArray predicted;        ///< projections of the points under the robust pose [px]
  Eigen::Matrix4d T_cur_prev;  ///< the robust pose: previous camera frame -> current frame
  std::vector<bool> inliers;   ///< RANSAC inliers
  bool ok = false;             ///< false when RANSAC found no pose (then predicted is empty)
};

// Robust first pose estimate (RANSAC PnP, OpenCV) from 3-D points in the previous camera frame
// and their matched pixels in the current image; returns the points' predicted pixels under it.
RobustPrediction PredictWithRobustPose(
    const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>& points_prev,
    const PixelArray& observed, const PinholeCamera& camera,
    double reprojection_threshold_px = 2.0);

}  // namespace slslam
