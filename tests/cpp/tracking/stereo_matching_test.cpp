// Stereo keypoint matching and its subpixel refinement on a textured pair with a known disparity.
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include "slslam/features/orb_extractor.h"
#include "slslam/tracking/stereo_frontend.h"
#include "slslam/tracking/stereo_matching.h"

namespace slslam {
namespace {

StereoRig Rig() {
  PinholeCamera camera;
  camera.fx = camera.fy = 400.0;
  camera.cx = 159.5;
  camera.cy = 119.5;
  camera.width = 320;
  camera.height = 240;
  return {camera, 0.1};
}

// A smooth random texture and its copy shifted left by `disparity` pixels (a fronto-parallel wall).
std::pair<cv::Mat, cv::Mat> ShiftedPair(double disparity) {
  cv::Mat noise(240, 320, CV_32F);
  cv::RNG rng(5);
  rng.fill(noise, cv::RNG::UNIFORM, 0.0, 255.0);
  cv::Mat texture;
  cv::GaussianBlur(noise, texture, cv::Size(0, 0), 1.5);
  cv::normalize(texture, texture, 0, 255, cv::NORM_MINMAX);
  cv::Mat left, right;
  texture.convertTo(left, CV_8U);
  const cv::Mat shift = (cv::Mat_<double>(2, 3) << 1, 0, -disparity, 0, 1, 0);
  cv::warpAffine(texture, right, shift, texture.size(), cv::INTER_CUBIC, cv::BORDER_REFLECT);
  right.convertTo(right, CV_8U);
  return {left, right};
}

// Frame with keypoints at (u, v) for u in [u0, u1) by du and v in [v0, v1) by dv, row by row,
// none matched yet (u_right and depth -1).
StereoFrame KeypointGridFrame(int u0, int u1, int du, int v0, int v1, int dv) {
  std::vector<Eigen::Vector2f> uv;
  for (int v = v0; v < v1; v += dv) {
    for (int u = u0; u < u1; u += du) uv.emplace_back(static_cast<float>(u), static_cast<float>(v));
  }
  StereoFrame frame;
  frame.keypoints.uv.resize(static_cast<Eigen::Index>(uv.size()), 2);
  for (size_t i = 0; i < uv.size(); ++i) {
    frame.keypoints.uv.row(static_cast<Eigen::Index>(i)) = uv[i].transpose();
  }
  frame.u_right.assign(uv.size(), -1.0);
  frame.depth.assign(uv.size(), -1.0);
  return frame;
}

// The grid of left keypoints of most tests here, with no right match yet (no right-image
// keypoints).
StereoFrame UnmatchedGridFrame() { return KeypointGridFrame(60, 300, 20, 30, 210, 20); }

// The same grid, each keypoint matched (by "descriptors") to the integer column.
StereoFrame GridFrame(double disparity) {
  StereoFrame frame = UnmatchedGridFrame();
  for (int i = 0; i < frame.NumKeypoints(); ++i) {
    frame.u_right[i] = frame.keypoints.uv(i, 0) - std::round(disparity);
    frame.depth[i] = 1.0;
  }
  return frame;
}

TEST(StereoFrameTest, SubpixelRefinementRecoversAFractionalDisparity) {
  const StereoRig rig = Rig();
  for (double disparity : {7.3, 12.5, 20.8}) {
    const auto [left, right] = ShiftedPair(disparity);
    StereoFrame frame = GridFrame(disparity);
    RefineStereoSubpixel(left, right, rig, StereoMatchOptions{}, &frame);
    int refined = 0;
    double worst = 0.0;
    for (int i = 0; i < frame.NumKeypoints(); ++i) {
      if (frame.u_right[i] < 0.0) continue;
      ++refined;
      const double d = frame.keypoints.uv(i, 0) - frame.u_right[i];
      worst = std::max(worst, std::abs(d - disparity));
      EXPECT_NEAR(frame.depth[i], rig.camera.fx * rig.baseline_m / d, 1e-9);
    }
    EXPECT_GT(refined, 0.9 * frame.NumKeypoints()) << disparity;
    // Integer matching alone is off by up to 0.5 px; the refinement by at most 0.08 px (measured).
    EXPECT_LT(worst, 0.1) << disparity;
  }
}

// The refinement as first written: each column's patch mean and SAD summed on their own, in the
// patch's row-major order. The shipped one sums all columns at once (vectorised); each column's
// sum keeps this order, so every float must come out the same.
void RefineColumnByColumn(const cv::Mat& left, const cv::Mat& right, const StereoRig& rig,
                          const StereoMatchOptions& options, StereoFrame* frame) {
  const int w = options.subpixel_window, L = options.subpixel_search;
  const float area = static_cast<float>((2 * w + 1) * (2 * w + 1));
  for (int i = 0; i < frame->NumKeypoints(); ++i) {
    if (frame->u_right[i] < 0.0) continue;
    const int ul = static_cast<int>(std::lround(frame->keypoints.uv(i, 0)));
    const int v = static_cast<int>(std::lround(frame->keypoints.uv(i, 1)));
    const int ur0 = static_cast<int>(std::lround(frame->u_right[i]));
    if (v - w < 0 || v + w >= left.rows || ul - w < 0 || ul + w >= left.cols || ur0 - L - w < 0 ||
        ur0 + L + w >= right.cols) {
      continue;
    }
    auto mean = [&](const cv::Mat& image, int u) {
      int sum = 0;
      for (int dy = -w; dy <= w; ++dy) {
        for (int dx = -w; dx <= w; ++dx) sum += image.at<uchar>(v + dy, u + dx);
      }
      return static_cast<float>(sum) / area;
    };
    const float mean_left = mean(left, ul);
    std::vector<float> sad;
    for (int k = -L; k <= L; ++k) {
      const float mean_right = mean(right, ur0 + k);
      float sum = 0.0f;
      for (int dy = -w; dy <= w; ++dy) {
        for (int dx = -w; dx <= w; ++dx) {
          sum += std::abs((left.at<uchar>(v + dy, ul + dx) - mean_left) -
                          (right.at<uchar>(v + dy, ur0 + k + dx) - mean_right));
        }
      }
      sad.push_back(sum);
    }
    const int best = static_cast<int>(std::min_element(sad.begin(), sad.end()) - sad.begin());
    frame->u_right[i] = frame->depth[i] = -1.0;
    if (best <= 0 || best >= 2 * L) continue;
    const float d1 = sad[best - 1], d2 = sad[best], d3 = sad[best + 1];
    const float slope = std::max(d1, d3) - d2;
    const float delta = slope > 0.0f ? 0.5f * (d1 - d3) / slope : 0.0f;
    if (delta < -1.0f || delta > 1.0f) continue;
    const double disparity = ul - (ur0 + (best - L) + delta);
    const double z = disparity > 0.0 ? rig.camera.fx * rig.baseline_m / disparity : -1.0;
    if (!(disparity >= options.min_disparity_px &&
          z < options.max_depth_baselines * rig.baseline_m)) {
      continue;
    }
    frame->u_right[i] = frame->keypoints.uv(i, 0) - disparity;
    frame->depth[i] = z;
  }
}

TEST(StereoFrameTest, SubpixelRefinementEqualsTheColumnByColumnSums) {
  const StereoRig rig = Rig();
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> jitter(-0.5f, 0.5f);
  for (double disparity : {7.3, 12.5}) {
    const auto [left, right] = ShiftedPair(disparity);
    for (const int window : {3, 5, 7}) {
      StereoMatchOptions options;
      options.subpixel_window = window;
      StereoFrame frame = GridFrame(disparity);
      for (int i = 0; i < frame.NumKeypoints(); ++i) {  // subpixel keypoints, off-grid matches
        frame.keypoints.uv(i, 0) += jitter(rng);
        frame.keypoints.uv(i, 1) += jitter(rng);
        frame.u_right[i] += (i % 7) - 3;
      }
      StereoFrame expected = frame;
      RefineStereoSubpixel(left, right, rig, options, &frame);
      RefineColumnByColumn(left, right, rig, options, &expected);
      int refined = 0;
      for (int i = 0; i < frame.NumKeypoints(); ++i) {
        EXPECT_EQ(frame.u_right[i], expected.u_right[i]) << i;  // bit for bit
        EXPECT_EQ(frame.depth[i], expected.depth[i]) << i;
        refined += frame.depth[i] > 0.0;
      }
      EXPECT_GT(refined, frame.NumKeypoints() / 2) << window;
    }
  }
}

TEST(StereoFrameTest, AWrongDescriptorMatchLosesItsDepth) {
  const StereoRig rig = Rig();
  const auto [left, right] = ShiftedPair(10.0);
  StereoFrame frame = GridFrame(10.0);
  for (double& u : frame.u_right) u += 9.0;  // 9 px off: the SAD minimum lies outside +-5 px
  RefineStereoSubpixel(left, right, rig, StereoMatchOptions{}, &frame);
  int kept = 0;
  for (double d : frame.depth) kept += d > 0.0;
  EXPECT_LT(kept, 0.1 * frame.NumKeypoints());
}

TEST(StereoFrameTest, RowSearchFindsTheDisparityWithoutRightKeypoints) {
  const StereoRig rig = Rig();
  StereoMatchOptions options;
  options.row_search = true;
  for (double disparity : {7.3, 12.5, 40.8}) {
    const auto [left, right] = ShiftedPair(disparity);
    StereoFrame frame = UnmatchedGridFrame();
    MatchStereoByRowSearch(left, right, rig, options, &frame);
    int matched = 0;
    double worst_integer = 0.0;
    for (int i = 0; i < frame.NumKeypoints(); ++i) {
      if (frame.u_right[i] < 0.0) continue;
      ++matched;
      worst_integer = std::max(worst_integer,
                               std::abs(frame.keypoints.uv(i, 0) - frame.u_right[i] - disparity));
    }
    // Keypoints whose disparity range leaves the image (u < disparity + window) find nothing.
    EXPECT_GT(matched, 0.8 * frame.NumKeypoints()) << disparity;
    EXPECT_LE(worst_integer, 0.5 + 1e-9) << disparity;  // the nearest whole column
    RefineStereoSubpixel(left, right, rig, options, &frame);
    double worst = 0.0;
    for (int i = 0; i < frame.NumKeypoints(); ++i) {
      if (frame.u_right[i] < 0.0) continue;
      const double d = frame.keypoints.uv(i, 0) - frame.u_right[i];
      worst = std::max(worst, std::abs(d - disparity));
      EXPECT_NEAR(frame.depth[i], rig.camera.fx * rig.baseline_m / d, 1e-9);
    }
    EXPECT_LT(worst, 0.1) << disparity;
  }
}

TEST(StereoFrameTest, RowSearchAndRefinementGiveTheSameColumnsOnOneThreadAsOnSeveral) {
  // Both split their keypoints over OpenCV's threads; each keypoint's result is its own.
  const StereoRig rig = Rig();
  StereoMatchOptions options;
  options.row_search = true;
  const auto [left, right] = ShiftedPair(23.4);
  const int threads = cv::getNumThreads();
  cv::setNumThreads(1);
  StereoFrame serial = UnmatchedGridFrame();
  MatchStereoByRowSearch(left, right, rig, options, &serial);
  RefineStereoSubpixel(left, right, rig, options, &serial);
  cv::setNumThreads(std::max(threads, 4));  // more stripes than cores still splits the work
  StereoFrame parallel = UnmatchedGridFrame();
  MatchStereoByRowSearch(left, right, rig, options, &parallel);
  RefineStereoSubpixel(left, right, rig, options, &parallel);
  cv::setNumThreads(threads);
  ASSERT_EQ(serial.u_right.size(), parallel.u_right.size());
  int matched = 0;
  for (size_t i = 0; i < serial.u_right.size(); ++i) {
    EXPECT_EQ(serial.u_right[i], parallel.u_right[i]) << i;
    EXPECT_EQ(serial.depth[i], parallel.depth[i]) << i;
    matched += serial.u_right[i] >= 0.0;
  }
  EXPECT_GT(matched, 0);
}

// ShiftedPair(17.6) whose lower half (rows 120-239) holds the same vertical stripes, 12 px a
// period, in both images: texture above, repeated structure below.
std::pair<cv::Mat, cv::Mat> PairWithRepeatedPattern() {
  auto [left, right] = ShiftedPair(17.6);
  for (int v = 120; v < 240; ++v) {
    for (int u = 0; u < 320; ++u) {
      left.at<uchar>(v, u) = right.at<uchar>(v, u) = static_cast<uchar>(60 + 50 * ((u / 6) % 2));
    }
  }
  return {left, right};
}

// The row search as its header describes it, one column at a time in double: the integer right
// column of keypoint (u, v), or -1.
double PlainRowSearch(const cv::Mat& left, const cv::Mat& right, const StereoMatchOptions& options,
                      int u, int v) {
  const int w = options.row_search_window, side = 2 * w + 1;
  if (v - w < 0 || v + w >= left.rows || u - w < 0 || u + w >= left.cols) return -1.0;
  const int lo = std::max(w, u - static_cast<int>(std::floor(options.max_disparity_px)) - 1);
  const int hi =
      std::min(right.cols - 1 - w, u - static_cast<int>(std::ceil(options.min_disparity_px)) + 1);
  if (hi - lo + 1 < 3) return -1.0;
  const auto patch_mean = [&](const cv::Mat& image, int x) {
    double sum = 0.0;
    for (int dy = -w; dy <= w; ++dy) {
      for (int dx = -w; dx <= w; ++dx) sum += image.at<uchar>(v + dy, x + dx);
    }
    return sum / (side * side);
  };
  const double mean_left = patch_mean(left, u);
  double deviation = 0.0;
  for (int dy = -w; dy <= w; ++dy) {
    for (int dx = -w; dx <= w; ++dx) {
      deviation += std::abs(left.at<uchar>(v + dy, u + dx) - mean_left);
    }
  }
  if (deviation < options.row_search_min_texture * side * side) return -1.0;
  std::vector<double> cost;
  for (int x = lo; x <= hi; ++x) {
    const double mean_right = patch_mean(right, x);
    double c = 0.0;
    for (int dy = -w; dy <= w; ++dy) {
      for (int dx = -w; dx <= w; ++dx) {
        c += std::abs((left.at<uchar>(v + dy, u + dx) - mean_left) -
                      (right.at<uchar>(v + dy, x + dx) - mean_right));
      }
    }
    cost.push_back(c);
  }
  const int count = static_cast<int>(cost.size());
  const int best = static_cast<int>(std::min_element(cost.begin(), cost.end()) - cost.begin());
  if (best == 0 || best == count - 1 || cost[best] > options.row_search_max_cost * deviation) {
    return -1.0;
  }
  double second = std::numeric_limits<double>::max();
  for (int k = 1; k + 1 < count; ++k) {
    if (std::abs(k - best) > 1 && cost[k] <= cost[k - 1] && cost[k] <= cost[k + 1]) {
      second = std::min(second, cost[k]);
    }
  }
  if (best > 1 && cost[0] < cost[1]) second = std::min(second, cost[0]);
  if (best < count - 2 && cost[count - 1] < cost[count - 2]) {
    second = std::min(second, cost[count - 1]);
  }
  if (second < std::numeric_limits<double>::max() &&
      cost[best] >= options.row_search_ratio * second) {
    return -1.0;
  }
  return lo + best;
}

TEST(StereoFrameTest, RowSearchGivesTheColumnsOfAPlainSearch) {
  // Keypoints from the left edge on, so that the columns searched run from a few (fewer than
  // one register block of the cost loop) to the whole disparity range (several blocks, the last
  // one overlapping), on a pair with a repeated pattern beside the texture.
  const StereoRig rig = Rig();
  StereoMatchOptions options;
  options.row_search = true;
  options.max_disparity_px = 70.0f;
  const auto [left, right] = PairWithRepeatedPattern();
  StereoFrame frame = KeypointGridFrame(9, 312, 7, 8, 232, 13);
  MatchStereoByRowSearch(left, right, rig, options, &frame);
  int matched = 0, refused = 0;
  for (int i = 0; i < frame.NumKeypoints(); ++i) {
    const int u = static_cast<int>(frame.keypoints.uv(i, 0));
    const int v = static_cast<int>(frame.keypoints.uv(i, 1));
    const double expected = PlainRowSearch(left, right, options, u, v);
    EXPECT_EQ(frame.u_right[i], expected) << u << " " << v;
    matched += expected >= 0.0;
    refused += expected < 0.0 && v >= 120;
  }
  EXPECT_GT(matched, 100);
  EXPECT_GT(refused, 100);  // (the repeated pattern)
}

TEST(StereoFrameTest, RowSearchGivesThePlainSearchsColumnsForEveryPatchSize) {
  // Patch sizes other than the default 15 x 15 (5 to 47 px), keypoints from the left edge on (as
  // the test above), on the pair with the repeated pattern.
  const StereoRig rig = Rig();
  const auto [left, right] = PairWithRepeatedPattern();
  for (int w : {2, 3, 5, 7, 10, 11, 23}) {
    StereoMatchOptions options;
    options.row_search = true;
    options.row_search_window = w;
    options.max_disparity_px = 70.0f;
    StereoFrame frame = KeypointGridFrame(9, 312, 11, 8, 232, 17);
    MatchStereoByRowSearch(left, right, rig, options, &frame);
    int matched = 0;
    for (int i = 0; i < frame.NumKeypoints(); ++i) {
      const int u = static_cast<int>(frame.keypoints.uv(i, 0));
      const int v = static_cast<int>(frame.keypoints.uv(i, 1));
      EXPECT_EQ(frame.u_right[i], PlainRowSearch(left, right, options, u, v))
          << "window " << w << " at " << u << " " << v;
      matched += frame.u_right[i] >= 0.0;
    }
    EXPECT_GT(matched, 20) << "window " << w;
  }
}

TEST(StereoFrameTest, RowSearchRefusesFlatAndRepeatedPatchesAndKeepsMatches) {
  const StereoRig rig = Rig();
  StereoMatchOptions options;
  options.row_search = true;
  // Flat images: no texture, no match.
  const cv::Mat flat(240, 320, CV_8U, cv::Scalar(90));
  StereoFrame frame = UnmatchedGridFrame();
  MatchStereoByRowSearch(flat, flat, rig, options, &frame);
  for (double d : frame.depth) EXPECT_LT(d, 0.0);
  // Vertical stripes with a 9 px period: every 9th column fits as well as the true one.
  cv::Mat stripes(240, 320, CV_8U);
  for (int v = 0; v < stripes.rows; ++v) {
    for (int u = 0; u < stripes.cols; ++u) stripes.at<uchar>(v, u) = (u % 9) < 4 ? 40 : 200;
  }
  frame = UnmatchedGridFrame();
  MatchStereoByRowSearch(stripes, stripes, rig, options, &frame);
  for (double d : frame.depth) EXPECT_LT(d, 0.0);
  // A match already made (by descriptors) is kept as it is.
  const auto [left, right] = ShiftedPair(12.0);
  frame = UnmatchedGridFrame();
  frame.u_right[0] = 3.0;
  frame.depth[0] = 7.0;
  MatchStereoByRowSearch(left, right, rig, options, &frame);
  EXPECT_EQ(frame.u_right[0], 3.0);
  EXPECT_EQ(frame.depth[0], 7.0);
}

TEST(StereoFrameTest, RowSearchMatchesANoisyPairSmoothedAndLeavesTheImagesAsTheyWere) {
  // (the pair smoothed as StereoFrontend::Build smooths it, tracking.denoise_above_noise)
  const StereoRig rig = Rig();
  StereoMatchOptions options;
  options.row_search = true;
  auto [left, right] = ShiftedPair(12.0);
  // Dim and noisy, as the simulator's light-0.15 frames (sigma 9 gray levels).
  cv::RNG rng(7);
  for (cv::Mat* image : {&left, &right}) {
    cv::Mat noise(image->size(), CV_32F), out;
    rng.fill(noise, cv::RNG::NORMAL, 0.0, 9.0);
    image->convertTo(out, CV_32F, 0.25, 20.0);
    out += noise;
    out.convertTo(*image, CV_8U);
  }
  const cv::Mat left_before = left.clone(), right_before = right.clone();
  StereoFrame smoothed = UnmatchedGridFrame();
  const double above_noise = StereoFrontendOptions{}.denoise_above_noise;
  MatchStereoByRowSearch(SmoothIfNoisy(left, above_noise), SmoothIfNoisy(right, above_noise), rig,
                         options, &smoothed);
  EXPECT_EQ(cv::norm(left, left_before, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(right, right_before, cv::NORM_INF), 0.0);
  StereoFrame raw = UnmatchedGridFrame();
  MatchStereoByRowSearch(left, right, rig, options, &raw);
  int with = 0, without = 0, wrong = 0;
  for (int i = 0; i < smoothed.NumKeypoints(); ++i) {
    with += smoothed.u_right[i] >= 0.0;
    without += raw.u_right[i] >= 0.0;
    if (smoothed.u_right[i] >= 0.0) {
      wrong += std::abs(smoothed.keypoints.uv(i, 0) - smoothed.u_right[i] - 12.0) > 1.0;
    }
  }
  EXPECT_GT(with, without) << "smoothed " << with << ", raw " << without;
  // measured: 51 of 108 smoothed (4 more than 1 px off), raw fewer
  EXPECT_GT(with, smoothed.NumKeypoints() / 3);
  EXPECT_LT(wrong, 0.15 * with);
}

}  // namespace
}  // namespace slslam
