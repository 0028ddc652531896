#include "slslam/tracking/stereo_matching.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include "slslam/core/check.h"
#include "slslam/core/cpu_dispatch.h"
#include "slslam/features/descriptor_matcher.h"

namespace slslam {

namespace {

void CheckKeypoints(const Keypoints& k, const char* side) {
  SLSLAM_CHECK(k.uv.rows() == k.descriptors.rows || k.uv.rows() == 0, side,
               " keypoints: ", k.uv.rows(), " positions but ", k.descriptors.rows,
               " descriptor rows");
  SLSLAM_CHECK(k.uv.allFinite(), side, " keypoint positions must be finite");
}

}  // namespace

StereoFrame MakeStereoFrame(int index, int64_t t_ns, const Keypoints& left, const Keypoints& right,
                            const LineFeatures* left_lines, const LineFeatures* right_lines,
                            const StereoRig& rig, const StereoMatchOptions& options) {
  rig.Check();
  options.Check();
  CheckKeypoints(left, "left");
  CheckKeypoints(right, "right");
  const bool have_right = right.size() > 0 && left.size() > 0;
  if (have_right) {
    Require(left.descriptors.type() == right.descriptors.type() &&
                left.descriptors.cols == right.descriptors.cols,
            "left and right descriptors differ in type or length");
  }

  StereoFrame frame;
  frame.index = index;
  frame.t_ns = t_ns;
  frame.keypoints = left;
  const int n = left.size();
  frame.u_right.assign(n, -1.0);
  frame.depth.assign(n, -1.0);

  if (have_right) {
    // Right keypoints bucketed by integer row, so a left keypoint visits its row band only.
    const int rows = rig.camera.height + 1;
    std::vector<std::vector<int>> by_row(rows);
    for (int j = 0; j < right.size(); ++j) {
      const int r = static_cast<int>(std::lround(right.uv(j, 1)));
      if (r >= 0 && r < rows) by_row[r].push_back(j);
    }
    const bool binary = left.descriptors.type() == CV_8U;
    const float max_distance = binary ? options.max_distance_binary : options.max_distance_float;
    const int band = static_cast<int>(std::ceil(options.max_row_offset_px));
    const double max_depth = options.max_depth_baselines * rig.baseline_m;
    // Best left keypoint per right keypoint, to keep matches one-to-one.
    OneToOne one_to_one(right.size());
    std::vector<int> match(n, -1);
    for (int i = 0; i < n; ++i) {
      const float ul = left.uv(i, 0);
      const float vl = left.uv(i, 1);
      const int r0 = static_cast<int>(std::lround(vl));
      BestTwo best;
      for (int r = std::max(0, r0 - band); r <= std::min(rows - 1, r0 + band); ++r) {
        for (int j : by_row[r]) {
          if (std::abs(right.uv(j, 1) - vl) > options.max_row_offset_px) continue;
          const float disparity = ul - right.uv(j, 0);
          if (disparity < options.min_disparity_px || disparity > options.max_disparity_px) {
            continue;
          }
          best.Add(DescriptorDistance(left.descriptors, i, right.descriptors, j), j);
        }
      }
      if (best.index < 0 || best.best > max_distance || best.best > options.ratio * best.second) {
        continue;
      }
      one_to_one.Offer(i, best.index, best.best, &match);
    }
    for (int i = 0; i < n; ++i) {
      if (match[i] < 0) continue;
      const double u_r = right.uv(match[i], 0);
      const double disparity = left.uv(i, 0) - u_r;
      const double z = rig.camera.fx * rig.baseline_m / disparity;
      if (z > max_depth) continue;
      frame.u_right[i] = u_r;
      frame.depth[i] = z;
    }
  }

  if (left_lines) {
    SetLeftLines(*left_lines, &frame);
    if (right_lines) MatchStereoLinesInto(*right_lines, rig, options, &frame);
  }
  return frame;
}

void SetLeftLines(const LineFeatures& left_lines, StereoFrame* frame) {
  Require(frame != nullptr, "setting left lines needs a frame");
  Require(left_lines.descriptors.rows == static_cast<int>(left_lines.segments.size()),
          "left line descriptors do not match the segments");
  frame->lines = left_lines.segments;
  frame->line_descriptors = left_lines.descriptors;
  const int m = frame->NumLines();
  frame->line_endpoints.assign(m, {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()});
  frame->line_has_depth.assign(m, false);
}

void MatchStereoLinesInto(const LineFeatures& right_lines, const StereoRig& rig,
                          const StereoMatchOptions& options, StereoFrame* frame) {
  Require(frame != nullptr, "stereo line matching needs a frame");
  Require(right_lines.descriptors.rows == static_cast<int>(right_lines.segments.size()),
          "right line descriptors do not match the segments");
  const int m = frame->NumLines();
  frame->line_endpoints.assign(m, {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()});
  frame->line_has_depth.assign(m, false);
  if (m == 0 || right_lines.segments.empty()) return;
  const IndexPairs pairs =
      MatchStereoLines(frame->lines, frame->line_descriptors, right_lines.segments,
                       right_lines.descriptors, options.lines);
  const double max_depth = options.max_depth_baselines * rig.baseline_m;
  for (Eigen::Index k = 0; k < pairs.rows(); ++k) {
    const int a = pairs(k, 0);
    Eigen::Vector3d s, e;
    if (!TriangulateStereoLine(frame->lines[a], right_lines.segments[pairs(k, 1)], rig.camera,
                               rig.baseline_m, &s, &e, options.lines.min_disparity_px)) {
      continue;
    }
    if (s.z() > max_depth || e.z() > max_depth) continue;
    frame->line_endpoints[a] = {s, e};
    frame->line_has_depth[a] = true;
  }
}

namespace {

// cost[k] = sum over the patch of |(L - mean_L) - (R - mean_R[k])|, the row search's inner loop
// (side^2 x count per keypoint: with the 15 x 15 patch the largest part of stereo matching).
// Blocks of kRowSearchBlock columns are summed over the whole patch in registers (GCC's vector
// extensions: two 16-float vectors, four AVX2 or eight SSE registers in the other clones), each
// block stored once: summing into `cost` tap by tap loaded and stored every column for every
// tap, and that traffic, not the arithmetic, bounded the loop (perf annotate: the load, add and
// store of cost[k] were 40 % of its samples). The last block overlaps the one before it when
// `count` is not a multiple (columns computed twice give the same floats); fewer columns than a
// block are summed one tap at a time. Compiled three times, and the loader picks the AVX-512 or
// AVX2 version where the CPU has it (slslam is built without -march so wheels run anywhere).
// Each cost[k] is summed in the patch's row-major order in every path and every version (no
// multiplication, so no contraction into FMA), so they give the same floats.
constexpr int kRowSearchBlock = 32;
typedef float RowSearchVector __attribute__((vector_size(64), aligned(4), may_alias));
typedef int32_t RowSearchMask __attribute__((vector_size(64)));

SLSLAM_AVX512_CLONES void AccumulateRowSearchCosts(const float* patch, int side, const float* strip,
                                                   int width, const float* mean_right, int count,
                                                   float* cost) {
  if (count < kRowSearchBlock) {
    for (int k = 0; k < count; ++k) cost[k] = 0.0f;
    for (int dy = 0; dy < side; ++dy) {
      const float* row = strip + static_cast<size_t>(dy) * width;
      for (int dx = 0; dx < side; ++dx) {
        const float a = patch[dy * side + dx];
        const float* r = row + dx;
        for (int k = 0; k < count; ++k) cost[k] += std::abs(a + mean_right[k] - r[k]);
      }
    }
    return;
  }
  const RowSearchMask abs_mask = RowSearchMask{} + 0x7fffffff;
  for (int start = 0; start < count; start += kRowSearchBlock) {
    const int k0 = std::min(start, count - kRowSearchBlock);
    const RowSearchVector mean0 = *reinterpret_cast<const RowSearchVector*>(mean_right + k0);
    const RowSearchVector mean1 = *reinterpret_cast<const RowSearchVector*>(mean_right + k0 + 16);
    RowSearchVector sum0 = RowSearchVector{}, sum1 = RowSearchVector{};
    for (int dy = 0; dy < side; ++dy) {
      const float* row = strip + static_cast<size_t>(dy) * width + k0;
      for (int dx = 0; dx < side; ++dx) {
        const float a = patch[dy * side + dx];
        const RowSearchVector r0 = *reinterpret_cast<const RowSearchVector*>(row + dx);
        const RowSearchVector r1 = *reinterpret_cast<const RowSearchVector*>(row + dx + 16);
        const RowSearchVector d0 = (a + mean0) - r0;
        const RowSearchVector d1 = (a + mean1) - r1;
        sum0 += reinterpret_cast<RowSearchVector>(reinterpret_cast<RowSearchMask>(d0) & abs_mask);
        sum1 += reinterpret_cast<RowSearchVector>(reinterpret_cast<RowSearchMask>(d1) & abs_mask);
      }
    }
    *reinterpret_cast<RowSearchVector*>(cost + k0) = sum0;
    *reinterpret_cast<RowSearchVector*>(cost + k0 + 16) = sum1;
  }
}

// sad[k] += sum over the patch of |a - (r[k] - mean_right[k])|, the subpixel refinement's costs
// for all its columns at once (a: the left patch minus its mean). Each sad[k] is summed in the
// patch's row-major order, as one column at a time summed it, so the floats are the same.
SLSLAM_AVX2_CLONES void AccumulateSubpixelCosts(const float* patch, int side, const float* strip,
                                                int width, const float* mean_right, int count,
                                                float* sad) {
  for (int dy = 0; dy < side; ++dy) {
    const float* row = strip + static_cast<size_t>(dy) * width;
    for (int dx = 0; dx < side; ++dx) {
      const float a = patch[dy * side + dx];
      const float* r = row + dx;
      for (int k = 0; k < count; ++k) sad[k] += std::abs(a - (r[k] - mean_right[k]));
    }
  }
}

// The 2w+1 right rows around row v over columns [x0, x0 + count + 2w) as float (`strip`, row-major,
// width count + 2w), and the mean of each of the `count` (2w+1)^2 patches centred on columns
// x0 + w + k. The means come from column sums and their prefix sums: O(width) per row, not
// O(side * count), and integer sums, so they are the same floats as summing every pixel. The row
// search and the subpixel refinement both take their right patches from here.
void RightStrip(const cv::Mat& right, int v, int w, int x0, int count, std::vector<float>* strip,
                std::vector<int>* column_sum, std::vector<float>* mean_right) {
  const int side = 2 * w + 1;
  const int width = count + 2 * w;
  const float area = static_cast<float>(side * side);
  strip->resize(static_cast<size_t>(side) * width);
  column_sum->assign(width, 0);
  for (int dy = 0; dy < side; ++dy) {
    const uchar* row = right.ptr<uchar>(v - w + dy) + x0;
    float* out = strip->data() + static_cast<size_t>(dy) * width;
    for (int x = 0; x < width; ++x) {
      out[x] = row[x];
      (*column_sum)[x] += row[x];
    }
  }
  // Prefix sums of the column sums, then each window's sum as a difference of two: the divisions
  // are independent (vectorised), where a sliding window chained each to the one before.
  std::vector<int>& prefix = *column_sum;
  int running = 0;
  for (int x = 0; x < width; ++x) {
    const int column = prefix[x];
    prefix[x] = running;  // sum of columns [0, x)
    running += column;
  }
  prefix.push_back(running);
  mean_right->resize(count);
  for (int k = 0; k < count; ++k) {
    (*mean_right)[k] = static_cast<float>(prefix[k + side] - prefix[k]) / area;
  }
}

// The (2w+1)^2 left patch around (ul, v) minus its mean, row-major into `patch`, the mean from
// an integer sum as RightStrip's (so the same floats in the row search and the refinement).
// Returns the patch's integer sum; `scaled_deviation`, when given, receives the sum of
// |area x - sum| over the patch (area times its absolute deviation from its mean, in integers).
// The pixels are gathered into `values` (side^2 ints) first, so the sums run over one flat array
// the compiler vectorises instead of rows of 2w+1 (an integer sum, not a float one: a float sum
// is one chain of dependent additions the compiler may not reorder).
int CenteredLeftPatch(const cv::Mat& left, int ul, int v, int w, float* patch,
                      std::vector<int>* values, int* scaled_deviation = nullptr) {
  const int side = 2 * w + 1;
  const int area = side * side;
  values->resize(area);
  int* x = values->data();
  for (int dy = 0; dy < side; ++dy) {
    const uchar* row = left.ptr<uchar>(v - w + dy) + (ul - w);
    for (int dx = 0; dx < side; ++dx) x[dy * side + dx] = row[dx];
  }
  int left_sum = 0;
  for (int i = 0; i < area; ++i) left_sum += x[i];
  const float mean_left = static_cast<float>(left_sum) / static_cast<float>(area);
  for (int i = 0; i < area; ++i) patch[i] = static_cast<float>(x[i]) - mean_left;
  if (scaled_deviation != nullptr) {
    int deviation = 0;
    for (int i = 0; i < area; ++i) deviation += std::abs(area * x[i] - left_sum);
    *scaled_deviation = deviation;
  }
  return left_sum;
}

}  // namespace

void MatchStereoByRowSearch(const cv::Mat& left, const cv::Mat& right, const StereoRig& rig,
                            const StereoMatchOptions& options, StereoFrame* frame) {
  Require(frame != nullptr, "row search needs a frame");
  Require(left.type() == CV_8UC1 && right.type() == CV_8UC1 && left.size() == right.size(),
          "row search needs two 8-bit gray images of one size");
  const int w = options.row_search_window;
  const int side = 2 * w + 1;
  const float area = static_cast<float>(side * side);
  const int d_min = static_cast<int>(std::ceil(options.min_disparity_px));
  const int d_max = static_cast<int>(std::floor(options.max_disparity_px));
  const double max_depth = options.max_depth_baselines * rig.baseline_m;
  const int n = frame->NumKeypoints();
  frame->u_right.resize(n, -1.0);
  frame->depth.resize(n, -1.0);
  // Keypoints in parallel stripes, for the stereo stage's time on several cores
  // (benchmarks/log/realtime.md); each keypoint writes only its own entries and the buffers are
  // per stripe, so the matches are the same on any thread count.
  const auto search = [&](const cv::Range& range) {
    std::vector<float> patch(side * side);  // left patch minus its mean, row-major
    std::vector<float> strip;               // right rows of the search range, as float
    std::vector<float> mean_right, cost;
    std::vector<int> column_sum, values;
    for (int i = range.start; i < range.end; ++i) {
      if (frame->u_right[i] >= 0.0) continue;
      const int ul = static_cast<int>(std::lround(frame->keypoints.uv(i, 0)));
      const int v = static_cast<int>(std::lround(frame->keypoints.uv(i, 1)));
      if (v - w < 0 || v + w >= left.rows || ul - w < 0 || ul + w >= left.cols) continue;
      // Right columns searched: disparities [d_min, d_max], patches inside the image; one column
      // more on each side where possible, so an interior minimum has two neighbours.
      const int lo = std::max(w, ul - d_max - 1);
      const int hi = std::min(right.cols - 1 - w, ul - d_min + 1);
      const int count = hi - lo + 1;
      if (count < 3) continue;
      // The patch's absolute deviation from its mean, in integers too: the sum of
      // |area x - sum| is area times it.
      int scaled_deviation = 0;
      CenteredLeftPatch(left, ul, v, w, patch.data(), &values, &scaled_deviation);
      const float deviation = static_cast<float>(scaled_deviation) / area;
      if (deviation < options.row_search_min_texture * area) continue;  // flat: no reliable match
      // The strip: 2w+1 right rows over columns [lo - w, hi + w].
      const int width = count + 2 * w;
      RightStrip(right, v, w, lo - w, count, &strip, &column_sum, &mean_right);
      cost.resize(count);  // (set by AccumulateRowSearchCosts)
      AccumulateRowSearchCosts(patch.data(), side, strip.data(), width, mean_right.data(), count,
                               cost.data());
      int best = 0;
      for (int k = 1; k < count; ++k) {
        if (cost[k] < cost[best]) best = k;
      }
      if (best == 0 || best == count - 1) continue;  // on the edge of the range: unreliable
      float second = std::numeric_limits<float>::max();
      for (int k = 1; k + 1 < count; ++k) {
        if (std::abs(k - best) <= 1) continue;
        if (cost[k] <= cost[k - 1] && cost[k] <= cost[k + 1]) second = std::min(second, cost[k]);
      }
      // the range's ends count as minima when the cost falls towards them
      if (best > 1 && cost[0] < cost[1]) second = std::min(second, cost[0]);
      if (best < count - 2 && cost[count - 1] < cost[count - 2]) {
        second = std::min(second, cost[count - 1]);
      }
      if (cost[best] > options.row_search_max_cost * deviation) continue;
      if (second < std::numeric_limits<float>::max() &&
          cost[best] >= options.row_search_ratio * second) {
        continue;  // another column fits almost as well: repeated structure
      }
      const int ur = lo + best;
      const double disparity = frame->keypoints.uv(i, 0) - ur;
      if (disparity < options.min_disparity_px || disparity > options.max_disparity_px) continue;
      const double z = rig.camera.fx * rig.baseline_m / disparity;
      if (z > max_depth) continue;
      frame->u_right[i] = ur;
      frame->depth[i] = z;
    }
  };
  cv::parallel_for_(cv::Range(0, n), search, 8);
}

void SearchAndRefineStereoPoints(const cv::Mat& left, const cv::Mat& right, const StereoRig& rig,
                                 const StereoMatchOptions& options, StereoFrame* frame) {
  if (options.row_search) MatchStereoByRowSearch(left, right, rig, options, frame);
  RefineStereoSubpixel(left, right, rig, options, frame);
}

bool SubpixelWindowFits(const cv::Mat& left, const cv::Mat& right,
                        const StereoMatchOptions& options, int ul, int v, int ur) {
  const int w = options.subpixel_window, L = options.subpixel_search;
  return v - w >= 0 && v + w < left.rows && ul - w >= 0 && ul + w < left.cols && ur - L - w >= 0 &&
         ur + L + w < right.cols;
}

void RefineStereoSubpixel(const cv::Mat& left, const cv::Mat& right, const StereoRig& rig,
                          const StereoMatchOptions& options, StereoFrame* frame) {
  Require(frame != nullptr, "subpixel refinement needs a frame");
  Require(left.type() == CV_8UC1 && right.type() == CV_8UC1 && left.size() == right.size(),
          "subpixel refinement needs two 8-bit gray images of one size");
  const int w = options.subpixel_window;
  const int L = options.subpixel_search;
  if (w <= 0) return;
  const double max_depth = options.max_depth_baselines * rig.baseline_m;
  const int n = frame->NumKeypoints();
  const int side = 2 * w + 1;
  const int count = 2 * L + 1;      // columns tried
  const int width = count + 2 * w;  // right columns their patches cover
  // Keypoints in parallel stripes, as MatchStereoByRowSearch.
  const auto refine = [&](const cv::Range& range) {
    std::vector<float> sad(count), patch(side * side), strip, mean_right;
    std::vector<int> column_sum, values;
    for (int i = range.start; i < range.end; ++i) {
      if (frame->u_right[i] < 0.0) continue;
      const int ul = static_cast<int>(std::lround(frame->keypoints.uv(i, 0)));
      const int v = static_cast<int>(std::lround(frame->keypoints.uv(i, 1)));
      const int ur0 = static_cast<int>(std::lround(frame->u_right[i]));
      if (!SubpixelWindowFits(left, right, options, ul, v, ur0)) {
        continue;  // too close to the border to refine: keep the descriptor match
      }
      CenteredLeftPatch(left, ul, v, w, patch.data(), &values);
      RightStrip(right, v, w, ur0 - L - w, count, &strip, &column_sum, &mean_right);
      std::fill(sad.begin(), sad.end(), 0.0f);
      AccumulateSubpixelCosts(patch.data(), side, strip.data(), width, mean_right.data(), count,
                              sad.data());
      int best = -1;
      float best_sad = std::numeric_limits<float>::max();
      for (int k = 0; k < count; ++k) {
        if (sad[k] < best_sad) {
          best_sad = sad[k];
          best = k;
        }
      }
      if (best <= 0 || best >= 2 * L) {  // minimum on the edge: unreliable
        frame->u_right[i] = -1.0;
        frame->depth[i] = -1.0;
        continue;
      }
      // Equiangular (V-shaped) fit: the SAD cost is V-shaped near its minimum, where a parabola
      // pulls the estimate towards the integer column.
      const float d1 = sad[best - 1], d2 = sad[best], d3 = sad[best + 1];
      const float slope = std::max(d1, d3) - d2;
      const float delta = slope > 0.0f ? 0.5f * (d1 - d3) / slope : 0.0f;
      if (delta < -1.0f || delta > 1.0f) {
        frame->u_right[i] = -1.0;
        frame->depth[i] = -1.0;
        continue;
      }
      const double u_r = ur0 + (best - L) + delta;
      const double disparity = ul - u_r;
      const double z = disparity > 0.0 ? rig.camera.fx * rig.baseline_m / disparity : -1.0;
      if (!(disparity >= options.min_disparity_px && z < max_depth)) {
        frame->u_right[i] = -1.0;
        frame->depth[i] = -1.0;
        continue;
      }
      // The disparity was measured at the pixel centre ul; the keypoint keeps its own column.
      frame->u_right[i] = frame->keypoints.uv(i, 0) - disparity;
      frame->depth[i] = z;
    }
  };
  cv::parallel_for_(cv::Range(0, n), refine, 4);
}

}  // namespace slslam
