#include "slslam/features/lsd.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <opencv2/imgproc.hpp>

#include "slslam/core/check.h"
#include "slslam/core/cpu_dispatch.h"
#include "slslam/features/gaussian_blur.h"

namespace slslam {

namespace {

constexpr std::uint8_t kNoDirection = 0, kFree = 1, kTaken = 2;

// The gradient grid of the resized image, padded by one pixel of kNoDirection on every side so
// that a region's neighbours need no bounds test. Pixel (x, y) has index (y + 1) * stride + x + 1.
struct GradientGrid {
  int stride = 0;
  std::vector<float> norm;    // LSD's gradient norm, sqrt((gx^2 + gy^2) / 4)
  std::vector<float> ux, uy;  // unit level-line direction, (-gy, gx) / |g|
  std::vector<std::uint8_t> state;
  std::vector<int> seeds;  // pixels with a direction, largest norm first (pseudo-ordered)
  int Index(int x, int y) const { return (y + 1) * stride + x + 1; }
};

struct Pixel {
  int x, y, index;
};

struct Rectangle {
  double x1, y1, x2, y2, width;
};

// One row of LSD's 2 x 2 gradient: at (x, y) from the pixels (x..x+1, y..y+1). Returns the row's
// largest norm.
SLSLAM_AVX2_CLONES
float GradientRow(const std::uint8_t* row, const std::uint8_t* below, int n, float threshold,
                  float* norm, float* ux, float* uy, std::uint8_t* state) {
  float max_norm = 0.0f;
  for (int x = 0; x < n; ++x) {
    const int diagonal = below[x + 1] - row[x];  // LSD's com1
    const int anti = row[x + 1] - below[x];      // com2
    const int gx = diagonal + anti, gy = diagonal - anti;
    const float squared = static_cast<float>(gx * gx + gy * gy);
    const float g = std::sqrt(squared);
    const float nrm = 0.5f * g;
    const bool defined = nrm > threshold;
    const float inverse = defined ? 1.0f / g : 0.0f;
    norm[x] = nrm;
    ux[x] = static_cast<float>(-gy) * inverse;
    uy[x] = static_cast<float>(gx) * inverse;
    state[x] = defined ? kFree : kNoDirection;
    max_norm = std::max(max_norm, nrm);
  }
  return max_norm;
}

void ComputeGradient(const cv::Mat& image, double threshold, int n_bins, GradientGrid* grid) {
  // The last row and column have no 2 x 2 window: they stay without a direction, as in LSD.
  const int w = image.cols, h = image.rows;
  grid->stride = w + 2;
  const std::size_t size = static_cast<std::size_t>(grid->stride) * (h + 2);
  grid->norm.assign(size, 0.0f);
  grid->ux.assign(size, 0.0f);
  grid->uy.assign(size, 0.0f);
  grid->state.assign(size, kNoDirection);
  float max_norm = 0.0f;
  for (int y = 0; y + 1 < h; ++y) {
    const int i = grid->Index(0, y);
    max_norm =
        std::max(max_norm, GradientRow(image.ptr<std::uint8_t>(y), image.ptr<std::uint8_t>(y + 1),
                                       w - 1, static_cast<float>(threshold), &grid->norm[i],
                                       &grid->ux[i], &grid->uy[i], &grid->state[i]));
  }
  // LSD's pseudo-ordering as the paper's reference code (lsd.c) does it: seeds by 1024 bins of
  // norm * n_bins / max (clamped), the highest bin first, row by row within a bin (a counting
  // sort; OpenCV sorts by norm * (n_bins - 1) / max).
  grid->seeds.clear();
  if (max_norm <= 0.0f) return;
  const double bin_per_norm = static_cast<double>(n_bins) / max_norm;
  std::vector<int> bin_of(size, -1), start(n_bins + 1, 0);
  for (int y = 0; y + 1 < h; ++y) {
    for (int i = grid->Index(0, y), end = i + w - 1; i < end; ++i) {
      if (grid->state[i] != kFree) continue;
      const int bin = std::min(n_bins - 1, static_cast<int>(grid->norm[i] * bin_per_norm));
      bin_of[i] = n_bins - 1 - bin;  // highest norm first
      ++start[bin_of[i] + 1];
    }
  }
  for (int b = 0; b < n_bins; ++b) start[b + 1] += start[b];
  grid->seeds.resize(start[n_bins]);
  for (std::size_t i = 0; i < size; ++i) {
    if (bin_of[i] >= 0) grid->seeds[start[bin_of[i]]++] = static_cast<int>(i);
  }
}

Pixel PixelAt(const GradientGrid& grid, int index) {
  return {index % grid.stride - 1, index / grid.stride - 1, index};
}

// Grows a region from the seed: 8-neighbours still free whose direction is within the tolerance
// (cos_tolerance) of the region's mean direction, updated after every pixel taken. The sum of the
// region's unit directions is returned in (sum_x, sum_y).
void GrowRegion(GradientGrid* grid, int seed, double cos_tolerance, std::vector<Pixel>* region,
                double* sum_x, double* sum_y) {
  const int s = grid->stride;
  // The neighbour order of the paper's reference code (lsd.c): column by column, top to bottom
  // (OpenCV's goes row by row; the order decides which pixel a growing region meets first).
  struct Step {
    int dx, dy, offset;
  };
  const Step steps[8] = {{-1, -1, -s - 1}, {-1, 0, -1},     {-1, 1, s - 1}, {0, -1, -s},
                         {0, 1, s},        {1, -1, -s + 1}, {1, 0, 1},      {1, 1, s + 1}};
  region->clear();
  region->push_back(PixelAt(*grid, seed));
  grid->state[seed] = kTaken;
  double sx = grid->ux[seed], sy = grid->uy[seed];
  double bound = cos_tolerance * std::sqrt(sx * sx + sy * sy);
  for (std::size_t k = 0; k < region->size(); ++k) {
    const Pixel centre = (*region)[k];
    for (const Step& step : steps) {
      const int n = centre.index + step.offset;
      if (grid->state[n] != kFree) continue;
      if (grid->ux[n] * sx + grid->uy[n] * sy < bound) continue;
      grid->state[n] = kTaken;
      region->push_back({centre.x + step.dx, centre.y + step.dy, n});
      sx += grid->ux[n];
      sy += grid->uy[n];
      bound = cos_tolerance * std::sqrt(sx * sx + sy * sy);
    }
  }
  *sum_x = sx;
  *sum_y = sy;
}

// LSD's rectangle of a region: centre of the gradient-weighted pixels, direction of the inertia's
// main axis (pointing along the region's mean direction), extent along and across it.
Rectangle RegionRectangle(const GradientGrid& grid, const std::vector<Pixel>& region, double sum_x,
                          double sum_y, double cos_tolerance) {
  double weight = 0.0, cx = 0.0, cy = 0.0;
  for (const Pixel& p : region) {
    const double w = grid.norm[p.index];
    cx += w * p.x;
    cy += w * p.y;
    weight += w;
  }
  cx /= weight;
  cy /= weight;
  double ixx = 0.0, iyy = 0.0, ixy = 0.0;
  for (const Pixel& p : region) {
    const double w = grid.norm[p.index], dx = p.x - cx, dy = p.y - cy;
    ixx += w * dy * dy;
    iyy += w * dx * dx;
    ixy -= w * dx * dy;
  }
  const double lambda = 0.5 * (ixx + iyy - std::sqrt((ixx - iyy) * (ixx - iyy) + 4.0 * ixy * ixy));
  const double theta = std::fabs(ixx) > std::fabs(iyy) ? std::atan2(lambda - ixx, ixy)
                                                       : std::atan2(ixy, lambda - iyy);
  double dir_x = std::cos(theta), dir_y = std::sin(theta);
  if (dir_x * sum_x + dir_y * sum_y < cos_tolerance * std::sqrt(sum_x * sum_x + sum_y * sum_y)) {
    dir_x = -dir_x;
    dir_y = -dir_y;
  }
  double l_min = 0.0, l_max = 0.0, w_min = 0.0, w_max = 0.0;
  for (const Pixel& p : region) {
    const double dx = p.x - cx, dy = p.y - cy;
    const double l = dx * dir_x + dy * dir_y, across = -dx * dir_y + dy * dir_x;
    l_min = std::min(l_min, l);
    l_max = std::max(l_max, l);
    w_min = std::min(w_min, across);
    w_max = std::max(w_max, across);
  }
  return {cx + l_min * dir_x, cy + l_min * dir_y, cx + l_max * dir_x, cy + l_max * dir_y,
          std::max(1.0, w_max - w_min)};
}

double Density(const std::vector<Pixel>& region, const Rectangle& r) {
  return static_cast<double>(region.size()) / (std::hypot(r.x2 - r.x1, r.y2 - r.y1) * r.width);
}

double SquaredDistance(const Pixel& p, double x, double y) {
  return (p.x - x) * (p.x - x) + (p.y - y) * (p.y - y);
}

// Cuts the region to pixels ever nearer its seed until it fills its rectangle densely enough;
// pixels cut off are free again. False when fewer than two remain.
bool ReduceRadius(GradientGrid* grid, std::vector<Pixel>* region, double sum_x, double sum_y,
                  double cos_tolerance, double density_threshold, Rectangle* rect) {
  const Pixel seed = region->front();
  double radius = std::sqrt(std::max(SquaredDistance(seed, rect->x1, rect->y1),
                                     SquaredDistance(seed, rect->x2, rect->y2)));
  while (Density(*region, *rect) < density_threshold) {
    radius *= 0.75;
    const double radius_sq = radius * radius;
    std::size_t kept = 0;  // in order, the seed first
    for (const Pixel& p : *region) {
      if (SquaredDistance(p, seed.x, seed.y) <= radius_sq) {
        (*region)[kept++] = p;
      } else {
        grid->state[p.index] = kFree;
      }
    }
    region->resize(kept);
    if (region->size() < 2) return false;
    *rect = RegionRectangle(*grid, *region, sum_x, sum_y, cos_tolerance);
  }
  return true;
}

// LSD's standard refinement of a region that fills too little of its rectangle: re-grown from
// its seed with a tolerance of twice the spread of directions near the seed, then cut.
bool Refine(GradientGrid* grid, std::vector<Pixel>* region, double* sum_x, double* sum_y,
            double cos_tolerance, double density_threshold, Rectangle* rect) {
  if (Density(*region, *rect) >= density_threshold) return true;
  const Pixel seed = region->front();
  const double seed_x = grid->ux[seed.index], seed_y = grid->uy[seed.index];
  double sum = 0.0, sum_sq = 0.0;
  int n = 0;
  const double width_sq = rect->width * rect->width;
  for (const Pixel& p : *region) {
    grid->state[p.index] = kFree;
    if (SquaredDistance(p, seed.x, seed.y) < width_sq) {
      const double ux = grid->ux[p.index], uy = grid->uy[p.index];
      // Signed angle from the seed's direction, in (-pi, pi].
      const double d = std::atan2(seed_x * uy - seed_y * ux, seed_x * ux + seed_y * uy);
      sum += d;
      sum_sq += d * d;
      ++n;
    }
  }
  const double mean = sum / n;
  const double tau = 2.0 * std::sqrt(std::max(0.0, (sum_sq - 2.0 * mean * sum) / n + mean * mean));
  GrowRegion(grid, seed.index, std::cos(std::min(tau, CV_PI)), region, sum_x, sum_y);
  if (region->size() < 2) return false;
  *rect = RegionRectangle(*grid, *region, *sum_x, *sum_y, cos_tolerance);
  return ReduceRadius(grid, region, *sum_x, *sum_y, cos_tolerance, density_threshold, rect);
}

}  // namespace

void LsdOptions::Check() const {
  CheckAboveInRange("lsd.scale", scale, 0.0, 1.0);
  SLSLAM_CHECK(sigma_scale > 0.0, "lsd.sigma_scale must be > 0, got ", sigma_scale);
  SLSLAM_CHECK(quant > 0.0, "lsd.quant must be > 0, got ", quant);
  SLSLAM_CHECK(angle_tolerance_deg > 0.0 && angle_tolerance_deg < 90.0,
               "lsd.angle_tolerance_deg must be in (0, 90), got ", angle_tolerance_deg);
  CheckAboveInRange("lsd.density_threshold", density_threshold, 0.0, 1.0);
  SLSLAM_CHECK(n_bins >= 1, "lsd.n_bins must be >= 1, got ", n_bins);
}

std::vector<cv::Vec4f> DetectLsdSegments(const cv::Mat& gray, const LsdOptions& options) {
  options.Check();
  Require(!gray.empty() && gray.type() == CV_8UC1, "LSD needs a non-empty 8-bit gray image");
  std::vector<cv::Vec4f> segments;
  cv::Mat image = gray;
  if (options.scale != 1.0) {
    // cv::resize's size for a scale factor; an image that would shrink below 2 x 2 has no
    // gradient (and cv::resize refuses a size of 0).
    if (cvRound(gray.cols * options.scale) < 2 || cvRound(gray.rows * options.scale) < 2) {
      return segments;
    }
    // LSD's Gaussian sub-sampling, as OpenCV's: the kernel's half-width where the Gaussian falls
    // to 10^-3 of its peak (about 3.7 sigma).
    const double sigma = options.sigma_scale / options.scale;
    const int half = static_cast<int>(std::ceil(sigma * std::sqrt(2.0 * 3.0 * std::log(10.0))));
    // (cv::GaussianBlur's pixels, on one thread at a fraction of its CPU: features/gaussian_blur.h)
    const cv::Mat blurred = GaussianBlurAsOpenCv(gray, sigma, half);
    cv::resize(blurred, image, cv::Size(), options.scale, options.scale, cv::INTER_LINEAR_EXACT);
  }
  if (image.cols < 2 || image.rows < 2) return segments;
  const double tolerance = options.angle_tolerance_deg * CV_PI / 180.0;
  const double cos_tolerance = std::cos(tolerance);
  GradientGrid grid;
  ComputeGradient(image, options.quant / std::sin(tolerance), options.n_bins, &grid);
  // LSD's smallest region worth a segment: the size at which a region of aligned pixels becomes
  // meaningful (NFA 1) among the image's ~(W H)^(5/2) x 11 candidate rectangles.
  const double log_tests =
      2.5 * (std::log10(image.cols) + std::log10(image.rows)) + std::log10(11.0);
  const double p = options.angle_tolerance_deg / 180.0;
  const std::size_t min_region = static_cast<std::size_t>(-log_tests / std::log10(p));
  // The gradient of (x, y) sits at the centre of its 2 x 2 window; back to the input's pixels.
  const double to_input = 1.0 / options.scale;
  std::vector<Pixel> region;
  region.reserve(1024);
  for (const int seed : grid.seeds) {
    if (grid.state[seed] != kFree) continue;
    double sum_x = 0.0, sum_y = 0.0;
    GrowRegion(&grid, seed, cos_tolerance, &region, &sum_x, &sum_y);
    if (region.size() < min_region) continue;  // its pixels stay taken, as in LSD
    Rectangle rect = RegionRectangle(grid, region, sum_x, sum_y, cos_tolerance);
    if (!Refine(&grid, &region, &sum_x, &sum_y, cos_tolerance, options.density_threshold, &rect)) {
      continue;
    }
    segments.emplace_back(static_cast<float>((rect.x1 + 0.5) * to_input),
                          static_cast<float>((rect.y1 + 0.5) * to_input),
                          static_cast<float>((rect.x2 + 0.5) * to_input),
                          static_cast<float>((rect.y2 + 0.5) * to_input));
  }
  return segments;
}

}  // namespace slslam
