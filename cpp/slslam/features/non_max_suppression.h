// Greedy non-maximum suppression of scored pixel candidates (SuperPoint's reference NMS).
#pragma once

#include <vector>

#include <Eigen/Core>

namespace slslam {

using PixelIndexArray = Eigen::Matrix<int, Eigen::Dynamic, 2, Eigen::RowMajor>;

// Visits candidates (integer u, v) from the highest score down; a candidate is kept unless an
// already kept one lies within `radius_px` in both u and v (a (2r+1) x (2r+1) square), and every
// kept candidate suppresses its square. This is the reference implementation's NMS: unlike a
// max-filter it keeps a point whose stronger neighbour was itself suppressed. Ties are broken by
// the lower index. Returns the kept indices, strongest first. Candidates outside the
// width x height image are ignored.
std::vector<int> SuppressNonMaxima(const PixelIndexArray& uv, const Eigen::VectorXf& score,
                                   int width, int height, int radius_px);

using HeatMap = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// Max-filter NMS of a dense heatmap (XFeat's reference: a (2r+1) x (2r+1) max-pool): the
// pixels above `threshold` that are >= every pixel of the window around them (ties all kept;
// outside the map counts as 0, never above a value that passed the threshold), at least
// `border_px` inside the map. Returns (u, v) in row-major order (v, then u), as numpy's nonzero.
PixelIndexArray LocalMaxima(const Eigen::Ref<const HeatMap>& heat, float threshold, int radius_px,
                            int border_px);

}  // namespace slslam
