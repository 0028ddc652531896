#include "slslam/features/orb_extractor.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <vector>

#include <opencv2/core/utility.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "slslam/core/check.h"
#include "slslam/core/cpu_dispatch.h"
#include "slslam/features/gaussian_blur.h"

namespace slslam {

namespace {

constexpr int kPatchSize = 31;  // rotated BRIEF patch at level 0 [px], OpenCV's and ORB-SLAM's
constexpr int kHalfPatch = kPatchSize / 2;

Keypoints ToKeypoints(const std::vector<cv::KeyPoint>& cv_keypoints, cv::Mat descriptors) {
  Keypoints out;
  const int n = static_cast<int>(cv_keypoints.size());
  out.uv.resize(n, 2);
  out.score.resize(n);
  out.octave.resize(n);
  for (int i = 0; i < n; ++i) {
    out.uv(i, 0) = cv_keypoints[i].pt.x;
    out.uv(i, 1) = cv_keypoints[i].pt.y;
    out.score(i) = cv_keypoints[i].response;
    out.octave(i) = cv_keypoints[i].octave;
  }
  out.descriptors = n == 0 ? cv::Mat(0, 32, CV_8U) : descriptors;
  return out;
}

cv::Ptr<cv::ORB> MakeOrb(const OrbOptions& options) {
  return cv::ORB::create(options.max_features, options.scale_factor, options.num_levels,
                         options.edge_threshold, 0, 2, cv::ORB::HARRIS_SCORE, kPatchSize,
                         options.fast_threshold);
}

// Keypoints per level: a geometric series over the levels, as ORB-SLAM (area shrinks by scale^2
// per level, the series uses 1 / scale so coarse levels keep a useful share).
std::vector<int> LevelBudgets(const OrbOptions& options) {
  const double factor = 1.0 / options.scale_factor;
  const int levels = options.num_levels;
  std::vector<int> budget(levels, 0);
  double per_level =
      options.max_features * (1.0 - factor) / (1.0 - std::pow(factor, static_cast<double>(levels)));
  int total = 0;
  for (int l = 0; l + 1 < levels; ++l) {
    budget[l] = static_cast<int>(std::lround(per_level));
    total += budget[l];
    per_level *= factor;
  }
  budget[levels - 1] = std::max(options.max_features - total, 0);
  return budget;
}

// FAST corners of one level with the per-cell threshold fallback, spread round-robin over the
// cells. Positions are in the level's pixels.
//
// FAST runs at the normal threshold on the whole level, then at the fallback threshold only on the
// cells where it found nothing (as ORB-SLAM): at the fallback threshold FAST fires about five times
// as often (43,000 against 9,400 corners over the 8 levels of a bright simulated frame), mostly in
// cells that keep only their strong corners. The corners are those of one fallback-threshold pass
// kept per cell: a corner's FAST score does not depend on the threshold, non-maximum suppression
// between corners at or above the normal threshold never involves weaker ones, and a cell's crop
// reaches kSuppressionMargin beyond the cell, so the suppression sees the same neighbours.
constexpr int kSuppressionMargin = 4;  // FAST's 3 px circle + the 1 px suppression neighbourhood

std::vector<cv::KeyPoint> DetectLevel(const cv::Mat& level, int border, int budget,
                                      const OrbOptions& options) {
  std::vector<cv::KeyPoint> out;
  if (budget <= 0 || level.cols <= 2 * border || level.rows <= 2 * border) return out;
  const cv::Rect inner(border, border, level.cols - 2 * border, level.rows - 2 * border);
  const cv::Mat roi = level(inner);
  const int cell = options.cell_size_px;
  const int cells_x = (inner.width + cell - 1) / cell;
  const int cells_y = (inner.height + cell - 1) / cell;
  const auto cell_of = [&](const cv::KeyPoint& k) {
    const int cx = std::min(static_cast<int>(k.pt.x) / cell, cells_x - 1);
    const int cy = std::min(static_cast<int>(k.pt.y) / cell, cells_y - 1);
    return static_cast<size_t>(cy) * cells_x + cx;
  };
  std::vector<cv::KeyPoint> corners;
  cv::FAST(roi, corners, options.fast_threshold, /*nonmaxSuppression=*/true);
  std::vector<std::vector<int>> per_cell(static_cast<size_t>(cells_x) * cells_y);
  for (int i = 0; i < static_cast<int>(corners.size()); ++i) {
    per_cell[cell_of(corners[i])].push_back(i);
  }
  if (options.min_fast_threshold < options.fast_threshold) {
    std::vector<size_t> empty;
    for (size_t c = 0; c < per_cell.size(); ++c) {
      if (per_cell[c].empty()) empty.push_back(c);
    }
    std::vector<cv::KeyPoint> weak;
    const auto keep_weak = [&](const cv::KeyPoint& k, size_t c) {
      per_cell[c].push_back(static_cast<int>(corners.size()));
      corners.push_back(k);
    };
    if (2 * empty.size() > per_cell.size()) {
      // Mostly weak cells (a dark, smoothed frame): one pass over the level is cheaper than
      // one per cell; its corners are kept in the cells that were empty.
      std::vector<char> was_empty(per_cell.size(), 0);
      for (size_t c : empty) was_empty[c] = 1;
      cv::FAST(roi, weak, options.min_fast_threshold, /*nonmaxSuppression=*/true);
      for (const cv::KeyPoint& k : weak) {
        const size_t c = cell_of(k);
        if (was_empty[c]) keep_weak(k, c);
      }
    } else {
      for (size_t c : empty) {
        const int cx = static_cast<int>(c % cells_x), cy = static_cast<int>(c / cells_x);
        const cv::Rect crop =
            cv::Rect(cx * cell - kSuppressionMargin, cy * cell - kSuppressionMargin,
                     cell + 2 * kSuppressionMargin, cell + 2 * kSuppressionMargin) &
            cv::Rect(0, 0, roi.cols, roi.rows);
        cv::FAST(roi(crop), weak, options.min_fast_threshold, /*nonmaxSuppression=*/true);
        for (cv::KeyPoint& k : weak) {
          k.pt.x += crop.x;
          k.pt.y += crop.y;
          if (cell_of(k) == c) keep_weak(k, c);
        }
      }
    }
  }
  if (corners.empty()) return out;
  // Ties in raster order (the order of one FAST pass over the level).
  const auto stronger = [&](int a, int b) {
    if (corners[a].response != corners[b].response)
      return corners[a].response > corners[b].response;
    if (corners[a].pt.y != corners[b].pt.y) return corners[a].pt.y < corners[b].pt.y;
    return corners[a].pt.x < corners[b].pt.x;
  };
  for (auto& ids : per_cell) std::sort(ids.begin(), ids.end(), stronger);
  // Round-robin: every cell's best, then every cell's second best, ... (within a round the
  // stronger corners first, so a budget that ends mid-round keeps the strongest).
  std::vector<int> round;
  for (size_t rank = 0; static_cast<int>(out.size()) < budget; ++rank) {
    round.clear();
    for (const auto& ids : per_cell) {
      if (rank < ids.size()) round.push_back(ids[rank]);
    }
    if (round.empty()) break;
    std::sort(round.begin(), round.end(), stronger);
    for (int i : round) {
      if (static_cast<int>(out.size()) >= budget) break;
      cv::KeyPoint kp = corners[i];
      kp.pt.x += border;
      kp.pt.y += border;
      out.push_back(kp);
    }
  }
  return out;
}

Keypoints ExtractPlain(const cv::Mat& image, const OrbOptions& options) {
  std::vector<cv::KeyPoint> cv_keypoints;
  cv::Mat descriptors;
  MakeOrb(options)->detectAndCompute(image, cv::noArray(), cv_keypoints, descriptors);
  return ToKeypoints(cv_keypoints, descriptors);
}

}  // namespace

void OrbOptions::Check() const {
  CheckInRange("orb.max_features", max_features, 1, limits::kMaxKeypoints);
  CheckAboveInRange("orb.scale_factor", scale_factor, 1.0f, 4.0f);
  CheckInRange("orb.num_levels", num_levels, 1, 32);
  CheckInRange("orb.fast_threshold", fast_threshold, 1, 255);
  CheckInRange("orb.edge_threshold", edge_threshold, 0, 1000);
  SLSLAM_CHECK(min_fast_threshold > 0 && min_fast_threshold <= fast_threshold,
               "orb.min_fast_threshold must be in [1, fast_threshold], got ", min_fast_threshold);
  CheckInRange("orb.cell_size_px", cell_size_px, 8, limits::kMaxCellSizePx);
  CheckFinite("orb.denoise_above_noise", denoise_above_noise);
}

SLSLAM_AVX2_CLONES double EstimateNoiseSigma(const cv::Mat& image) {
  Require(!image.empty() && image.type() == CV_8UC1, "noise estimation needs an 8-bit gray image");
  if (image.rows < 3 || image.cols < 3) return 0.0;
  // The mask [1 -2 1]^T [1 -2 1] applied as two passes of second differences in integers: the row
  // pass per pixel (|.| <= 510 fits 16 bits), then the column pass over three rows of it, summed
  // as |.| (the same integer as cv::filter2D with the 3 x 3 mask and an L1 norm, which this
  // replaced: one pass over the frame instead of a filtered copy and a second pass, 0.34 -> 0.10 ms
  // a 752 x 480 image; it runs several times on every image: the tracker's smoothing, ORB, the
  // stereo front end, the lines). Compiled for AVX2 too (core/cpu_dispatch.h), the column pass in
  // 16-bit lanes: 2.3 -> 0.7 million instructions an image (callgrind).
  const int width = image.cols - 2;
  std::vector<int16_t> rows_buffer(3 * static_cast<size_t>(width));
  const auto second_difference = [&](int y, int16_t* out) {
    const uchar* row = image.ptr<uchar>(y);
    for (int x = 0; x < width; ++x) {
      out[x] = static_cast<int16_t>(row[x] - 2 * row[x + 1] + row[x + 2]);
    }
  };
  int16_t* above = rows_buffer.data();
  int16_t* middle = above + width;
  int16_t* below = middle + width;
  second_difference(0, above);
  second_difference(1, middle);
  int64_t sum_abs = 0;
  for (int y = 1; y + 1 < image.rows; ++y) {
    second_difference(y + 1, below);
    // |value| <= 2040 fits 16 bits; 32-bit sums over chunks of 65,536 columns cannot overflow.
    for (int x0 = 0; x0 < width; x0 += 65536) {
      const int x1 = std::min(width, x0 + 65536);
      int32_t chunk_sum = 0;
      for (int x = x0; x < x1; ++x) {
        const int16_t value = static_cast<int16_t>(above[x] - 2 * middle[x] + below[x]);
        chunk_sum += static_cast<uint16_t>(value < 0 ? -value : value);
      }
      sum_abs += chunk_sum;
    }
    std::swap(above, middle);
    std::swap(middle, below);
  }
  const double inner = static_cast<double>(width) * (image.rows - 2);
  return std::sqrt(CV_PI / 2.0) * static_cast<double>(sum_abs) / (6.0 * inner);
}

// Compiled for AVX2 too (core/cpu_dispatch.h): 6.0 -> 4.9 million instructions for an image's 1,000
// keypoints (callgrind), the same angles.
SLSLAM_AVX2_CLONES std::vector<float> IntensityCentroidAngles(
    const cv::Mat& image, const std::vector<cv::Point2f>& points, int radius_px) {
  Require(!image.empty() && image.type() == CV_8UC1, "angles need an 8-bit gray image");
  Require(radius_px >= 1 && radius_px <= 1000, "angle radius must be in [1, 1000] px");
  // The reflected copy only when a disc reaches past the edge (the extractor's keypoints never
  // do: they keep edge_threshold >= radius from it).
  const int pad = radius_px + 1;
  bool inside = true;
  for (const cv::Point2f& p : points) {
    const long u = std::lround(p.x), v = std::lround(p.y);
    inside = inside && u >= pad && v >= pad && u < image.cols - pad && v < image.rows - pad;
  }
  cv::Mat padded;
  int offset = 0;  // padded pixel of image pixel (0, 0)
  if (inside) {
    padded = image;
  } else {
    cv::copyMakeBorder(image, padded, pad, pad, pad, pad, cv::BORDER_REFLECT_101);
    offset = pad;
  }
  // Half-widths of the disc per row offset.
  std::vector<int> half_width(radius_px + 1);
  for (int v = 0; v <= radius_px; ++v) {
    half_width[v] = static_cast<int>(std::floor(std::sqrt(radius_px * radius_px - v * v + 0.5)));
  }
  std::vector<float> angles(points.size(), 0.0f);
  for (size_t k = 0; k < points.size(); ++k) {
    const int u0 = static_cast<int>(std::lround(points[k].x)) + offset;
    const int v0 = static_cast<int>(std::lround(points[k].y)) + offset;
    if (u0 < radius_px || v0 < radius_px || u0 >= padded.cols - radius_px ||
        v0 >= padded.rows - radius_px) {
      continue;
    }
    // 64-bit moments; each row's sums in 32 bits, which the compiler vectorises (a row's
    // |u * value| sum is below 2^31 for radii up to about 2,900 px; the Require above caps 1000).
    long m01 = 0, m10 = 0;
    for (int v = -radius_px; v <= radius_px; ++v) {
      const uchar* row = padded.ptr<uchar>(v0 + v) + u0;
      const int w = half_width[std::abs(v)];
      int32_t row_m10 = 0, row_sum = 0;
      for (int u = -w; u <= w; ++u) {
        const int32_t value = row[u];
        row_m10 += u * value;
        row_sum += value;
      }
      m10 += row_m10;
      m01 += static_cast<long>(v) * row_sum;
    }
    float angle = static_cast<float>(
        std::atan2(static_cast<double>(m01), static_cast<double>(m10)) * 180.0 / CV_PI);
    if (angle < 0.0f) angle += 360.0f;
    angles[k] = angle;
  }
  return angles;
}

cv::Mat SmoothIfNoisy(const cv::Mat& image, double above_noise) {
  if (above_noise <= 0.0) return image;
  const double noise = EstimateNoiseSigma(image);
  if (noise <= above_noise) return image;
  // (cv::GaussianBlur's pixels, on one thread at a fraction of its CPU: features/gaussian_blur.h)
  return GaussianBlurAsOpenCv(image, std::clamp(noise / 7.0, 0.5, 2.5));
}

Keypoints ExtractOrb(const cv::Mat& image, const OrbOptions& options) {
  options.Check();
  Require(!image.empty() && image.type() == CV_8UC1, "ORB needs a non-empty 8-bit gray image");
  if (!options.adaptive) return ExtractPlain(image, options);

  const std::vector<int> budget = LevelBudgets(options);
  // Detection image: smoothed when the frame is noisy (dark, high gain).
  const cv::Mat detect_image = SmoothIfNoisy(image, options.denoise_above_noise);
  // The descriptors' image: the detection image, or the image as given (describe_smoothed false
  // on a frame that was smoothed), with a pyramid of its own.
  const cv::Mat& describe_image = options.describe_smoothed ? detect_image : image;
  const bool own_describe_pyramid = describe_image.data != detect_image.data;
  // FAST needs 3 px around a corner; the descriptor patch is handled by OpenCV's padded levels.
  const int border = std::max(options.edge_threshold, 3);
  // Level sizes first (a level too small for the border ends the pyramid), then the levels in
  // parallel: each resizes from the full image, so they share nothing. One task per level, taken
  // by OpenCV's pool as its threads come free (level 0 holds a third of the pixels: on two
  // threads one takes it while the other works through levels 1, 2, ...); the levels' keypoints
  // and descriptors are joined in level order, so the result is the same on any thread count
  // (benchmarks/log/realtime.md has the times).
  std::vector<double> scales;
  std::vector<cv::Size> sizes;
  double scale = 1.0;  // level-0 pixels per level pixel
  for (int l = 0; l < options.num_levels; ++l) {
    if (l > 0) scale *= options.scale_factor;
    const cv::Size size = l == 0 ? image.size()
                                 : cv::Size(static_cast<int>(std::lround(image.cols / scale)),
                                            static_cast<int>(std::lround(image.rows / scale)));
    if (l > 0 && (size.width <= 2 * border || size.height <= 2 * border)) break;
    scales.push_back(scale);
    sizes.push_back(size);
  }
  const int levels = static_cast<int>(scales.size());
  std::vector<std::vector<cv::KeyPoint>> level_keypoints(levels);
  std::vector<cv::Mat> level_descriptors(levels);
  const auto extract_level = [&](int l) {
    cv::Mat level = detect_image, describe_level = describe_image;
    if (l > 0) {
      cv::resize(detect_image, level, sizes[l], 0, 0, cv::INTER_LINEAR);
      if (own_describe_pyramid) {
        cv::resize(describe_image, describe_level, sizes[l], 0, 0, cv::INTER_LINEAR);
      } else {
        describe_level = level;
      }
    }
    std::vector<cv::KeyPoint> found = DetectLevel(level, border, budget[l], options);
    if (found.empty()) return;
    std::vector<cv::Point2f> at(found.size());
    for (size_t i = 0; i < found.size(); ++i) at[i] = found[i].pt;
    const std::vector<float> angles = IntensityCentroidAngles(level, at, kHalfPatch);
    for (size_t i = 0; i < found.size(); ++i) {
      found[i].octave = 0;
      found[i].size = static_cast<float>(kPatchSize);
      found[i].angle = angles[i];
    }
    // Rotated BRIEF on this level's own image, each level a call of its own: OpenCV's ORB given
    // the full image would build its own pyramid of it again (about a sixth of the extractor's
    // instructions). A keypoint of octave 0 on a level image is described as OpenCV describes
    // one of that octave on a pyramid whose level is this image (padded by reflection and
    // blurred the same way); OpenCV resizes level by level from the previous one, this pyramid
    // resizes each level from the full image, the one FAST saw. OpenCV may drop keypoints too
    // close to the border, so the returned list is used. (An ORB object per level: no state is
    // shared between the threads.)
    cv::Mat descriptors;
    MakeOrb(options)->detectAndCompute(describe_level, cv::noArray(), found, descriptors,
                                       /*useProvidedKeypoints=*/true);
    for (cv::KeyPoint& kp : found) {
      kp.pt.x = static_cast<float>(kp.pt.x * scales[l]);
      kp.pt.y = static_cast<float>(kp.pt.y * scales[l]);
      kp.octave = l;
      kp.size = static_cast<float>(kPatchSize * scales[l]);
    }
    level_keypoints[l] = std::move(found);
    level_descriptors[l] = descriptors;
  };
  cv::parallel_for_(
      cv::Range(0, levels),
      [&](const cv::Range& range) {
        for (int l = range.start; l < range.end; ++l) extract_level(l);
      },
      levels);
  std::vector<cv::KeyPoint> all;
  std::vector<cv::Mat> nonempty;
  for (int l = 0; l < levels; ++l) {
    if (level_keypoints[l].empty()) continue;
    all.insert(all.end(), level_keypoints[l].begin(), level_keypoints[l].end());
    nonempty.push_back(level_descriptors[l]);
  }
  cv::Mat descriptors;
  if (!nonempty.empty()) cv::vconcat(nonempty, descriptors);
  return ToKeypoints(all, descriptors);
}

}  // namespace slslam
