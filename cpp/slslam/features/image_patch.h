// Bilinear patches of an 8-bit image: the map points' reference patches (sampled where a point
// is made: the tracker's keyframes, local mapping's triangulation) and the samples the tracker
// aligns to them (tracking/tracker_internal.h, AlignPatch).
#pragma once

#include <opencv2/core.hpp>

namespace slslam {

// Bilinear samples of an 8-bit image on the (2w+1) x (2w+1) grid centred on (x, y), `scale`
// image pixels apart, row-major into `out`; the grid must lie inside [0, cols - 1] x
// [0, rows - 1]. Returns the samples' sum.
double SampleGrid(const cv::Mat& image, double x, double y, int w, double scale, float* out);

// The (2w+1) x (2w+1) float patch of an 8-bit image centred on (u, v), bilinear; empty when it
// (with one pixel more around it) does not fit inside the image.
cv::Mat SamplePatch(const cv::Mat& image, double u, double v, int w);

}  // namespace slslam
