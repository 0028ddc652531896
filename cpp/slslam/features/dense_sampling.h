// Sampling a network's dense coarse maps (descriptors, reliability) at keypoints, as PyTorch's
// grid_sample with align_corners=False and zero padding does for XFeat's reference.
#pragma once

#include <Eigen/Core>

#include "slslam/features/grid_limit.h"  // PixelArray

namespace slslam {

using DenseSamples = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// `map` holds C channels of a Hc x Wc map, channel-major (C x (Hc Wc), the network's layout).
// A pixel (u, v) of the H x W network input maps to x = u Wc / (W - 1) - 0.5,
// y = v Hc / (H - 1) - 0.5 on the map; taps outside the map count as zero. Bilinear, or bicubic
// with Keys' kernel (A = -0.75, PyTorch's). Returns N x C samples (sums in double).
DenseSamples SampleDenseMap(const Eigen::Ref<const DenseSamples>& map, int map_height,
                            int map_width, const PixelArray& uv, int input_height, int input_width,
                            bool cubic);

}  // namespace slslam
