#include "slslam/features/image_patch.h"

#include <algorithm>
#include <utility>
#include <vector>

namespace slslam {

// Bilinear samples of an 8-bit image on the (2w+1) x (2w+1) grid centred on (x, y), `scale`
// image pixels apart, row-major into `out` (the grid inside [0, cols - 1] x [0, rows - 1]);
// returns their sum. The column taps are the same on every row, so each image row's horizontal
// interpolation is made once: a grid row's lower image row is usually the next grid row's upper
// one (scale near 1), and that row is reused, the same floats. (AVX2 gathers of the taps were
// no faster on this machine's CPU: measured, not kept.)
double SampleGrid(const cv::Mat& image, double x, double y, int w, double scale, float* out) {
  const int size = 2 * w + 1;
  static thread_local std::vector<float> col_ax, upper, lower;  // (no allocation per call)
  static thread_local std::vector<int> col_x0, col_x1;
  col_ax.resize(size);
  col_x0.resize(size);
  col_x1.resize(size);
  upper.resize(size);
  lower.resize(size);
  for (int c = -w; c <= w; ++c) {
    const double sx = x + c * scale;
    col_x0[c + w] = static_cast<int>(sx);
    col_x1[c + w] = std::min(col_x0[c + w] + 1, image.cols - 1);
    col_ax[c + w] = static_cast<float>(sx - col_x0[c + w]);
  }
  const auto interpolate_row = [&](int y_row, float* row_out) {
    const uchar* row = image.ptr<uchar>(y_row);
    for (int c = 0; c < size; ++c) {
      const float ax = col_ax[c];
      row_out[c] = (1.0f - ax) * row[col_x0[c]] + ax * row[col_x1[c]];
    }
  };
  int upper_row = -1, lower_row = -1;  // the image rows `upper` and `lower` hold
  for (int r = -w, k = 0; r <= w; ++r) {
    const double sy = y + r * scale;
    const int y0 = static_cast<int>(sy), y1 = std::min(y0 + 1, image.rows - 1);
    const float ay = static_cast<float>(sy - y0);
    if (y0 != upper_row) {
      if (y0 == lower_row) {
        std::swap(upper, lower);
        std::swap(upper_row, lower_row);
      } else {
        interpolate_row(y0, upper.data());
        upper_row = y0;
      }
    }
    if (y1 != lower_row) {
      if (y1 == upper_row) {
        lower = upper;  // (the last image row: y1 clamped to y0)
      } else {
        interpolate_row(y1, lower.data());
      }
      lower_row = y1;
    }
    for (int c = 0; c < size; ++c, ++k) out[k] = (1.0f - ay) * upper[c] + ay * lower[c];
  }
  double sum = 0.0;
  for (int k = 0; k < size * size; ++k) sum += out[k];
  return sum;
}

cv::Mat SamplePatch(const cv::Mat& image, double u, double v, int w) {
  if (image.empty() || image.type() != CV_8UC1 || u - w - 1 < 0.0 || v - w - 1 < 0.0 ||
      u + w + 1 > image.cols - 1.0 || v + w + 1 > image.rows - 1.0) {
    return cv::Mat();  // (one pixel more than the patch: its gradients stay inside the image)
  }
  cv::Mat patch(2 * w + 1, 2 * w + 1, CV_32F);
  SampleGrid(image, u, v, w, 1.0, patch.ptr<float>());
  return patch;
}

}  // namespace slslam
