// The tracker's keypoint refinement: a map point's patch aligned to a later image (shifted,
// scaled, brighter), and refused on flat images and on a patch of something else; the coarse
// search that starts projected points (TrackerOptions::projected_max_frames).
#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "slslam/tracking/tracker_internal.h"

namespace slslam {
namespace {

using tracker_detail::AlignPatch;
using tracker_detail::SamplePatch;

// A smooth random texture, 8 bits, stretched over [20, 235] gray levels.
cv::Mat Texture(int seed, int rows = 200, int cols = 240) {
  cv::Mat noise(rows, cols, CV_32F);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::UNIFORM, 0.0, 255.0);
  cv::Mat smooth, out;
  cv::GaussianBlur(noise, smooth, cv::Size(0, 0), 1.5);
  cv::normalize(smooth, smooth, 20.0, 235.0, cv::NORM_MINMAX);
  smooth.convertTo(out, CV_8U);
  return out;
}

TEST(PatchAlignment, RecoversTheShiftFromTheDetectedPosition) {
  const cv::Mat image = Texture(1);
  const cv::Mat patch = SamplePatch(image, 100.3, 90.7, 5);
  ASSERT_EQ(patch.rows, 11);
  ASSERT_EQ(patch.cols, 11);
  // A detector placed the keypoint about 2 px away.
  double u = 101.8, v = 89.5;
  ASSERT_TRUE(AlignPatch(image, patch, 1.0, 0.8, &u, &v));
  EXPECT_NEAR(u, 100.3, 0.05);
  EXPECT_NEAR(v, 90.7, 0.05);
}

TEST(PatchAlignment, FollowsAChangeOfScaleAndOfBrightness) {
  const cv::Mat image = Texture(2);
  const cv::Mat patch = SamplePatch(image, 110.0, 95.0, 5);
  // The point came closer: the image is 1.25x larger, and the headlamp made it brighter.
  cv::Mat larger;
  cv::resize(image, larger, cv::Size(), 1.25, 1.25, cv::INTER_CUBIC);
  larger.convertTo(larger, CV_8U, 1.0, 15.0);
  const double u_true = (110.0 + 0.5) * 1.25 - 0.5, v_true = (95.0 + 0.5) * 1.25 - 0.5;
  double u = u_true - 1.5, v = v_true + 1.2;
  ASSERT_TRUE(AlignPatch(larger, patch, 1.25, 0.8, &u, &v));
  EXPECT_NEAR(u, u_true, 0.15);
  EXPECT_NEAR(v, v_true, 0.15);
}

TEST(PatchAlignment, RefusesFlatImagesAndOtherPatches) {
  const cv::Mat flat(200, 240, CV_8U, cv::Scalar(90));
  const cv::Mat flat_patch = SamplePatch(flat, 100.0, 100.0, 5);
  double u = 100.0, v = 100.0;
  EXPECT_FALSE(AlignPatch(flat, flat_patch, 1.0, 0.8, &u, &v));
  EXPECT_EQ(u, 100.0);  // untouched on failure
  // A textured patch of another scene does not correlate with this one anywhere near.
  const cv::Mat other = SamplePatch(Texture(3), 100.0, 100.0, 5);
  const cv::Mat image = Texture(4);
  u = 100.0;
  v = 100.0;
  EXPECT_FALSE(AlignPatch(image, other, 1.0, 0.8, &u, &v));
  // Near the border there is no patch to take.
  EXPECT_TRUE(SamplePatch(image, 3.0, 100.0, 5).empty());
}

TEST(PatchSampling, GivesEachSampleAsAPlainBilinearInterpolation) {
  // The grid reuses an image row's horizontal interpolation between grid rows: at every scale
  // (grid rows on the same, adjacent or farther image rows), at the last image row (the lower
  // row clamped to it), near the buffer's end and on a view into a larger image, each sample is
  // the plain interpolation's float, and the sum theirs.
  const cv::Mat full = Texture(7, 70, 100);
  for (const cv::Mat& image :
       {full.rowRange(0, 60).colRange(0, 80).clone(), full(cv::Rect(10, 5, 80, 60))}) {
    const int w = 5, size = 2 * w + 1;
    std::vector<float> out(size * size);
    for (double scale : {0.5, 0.73, 1.0, 1.02, 1.5, 2.0}) {
      const double bottom = 59.0 - w * scale;
      for (const cv::Point2d& centre :
           {cv::Point2d(40.3, 30.7), cv::Point2d(40.0, 30.0), cv::Point2d(60.9, bottom),
            cv::Point2d(25.5, bottom + 0.4), cv::Point2d(77.5 - w * scale, bottom)}) {
        if (centre.y + w * scale > image.rows - 1.0 || centre.x + w * scale > image.cols - 1.0) {
          continue;
        }
        const double sum =
            tracker_detail::SampleGrid(image, centre.x, centre.y, w, scale, out.data());
        double expected_sum = 0.0;
        for (int r = -w, k = 0; r <= w; ++r) {
          const double sy = centre.y + r * scale;
          const int y0 = static_cast<int>(sy), y1 = std::min(y0 + 1, image.rows - 1);
          const float ay = static_cast<float>(sy - y0);
          for (int c = -w; c <= w; ++c, ++k) {
            const double sx = centre.x + c * scale;
            const int x0 = static_cast<int>(sx), x1 = std::min(x0 + 1, image.cols - 1);
            const float ax = static_cast<float>(sx - x0);
            const float top = (1.0f - ax) * image.at<uchar>(y0, x0) + ax * image.at<uchar>(y0, x1);
            const float low = (1.0f - ax) * image.at<uchar>(y1, x0) + ax * image.at<uchar>(y1, x1);
            const float expected = (1.0f - ay) * top + ay * low;
            ASSERT_EQ(out[k], expected) << "scale " << scale << ", sample " << k;
            expected_sum += expected;
          }
        }
        EXPECT_EQ(sum, expected_sum);
      }
    }
  }
}

TEST(PatchSearch, FindsAShiftBeyondTheAlignmentsReachThenAlignsIt) {
  // A projected point predicted 7 px right and 5 px up of where the image shows it (a rotation
  // the motion model missed): the coarse search lands within reach, the alignment finishes.
  const cv::Mat image = Texture(5);
  const cv::Mat patch = SamplePatch(image, 120.4, 100.6, 5);
  double u = 127.4, v = 95.6;
  const double ncc = tracker_detail::SearchPatch(image, patch, 1.0, 8, &u, &v);
  EXPECT_GT(ncc, 0.7);
  EXPECT_LE(std::abs(u - 120.4), 1.5);
  EXPECT_LE(std::abs(v - 100.6), 1.5);
  ASSERT_TRUE(AlignPatch(image, patch, 1.0, 0.8, &u, &v));
  EXPECT_NEAR(u, 120.4, 0.05);
  EXPECT_NEAR(v, 100.6, 0.05);
}

TEST(PatchSearch, SaysWhenNothingFits) {
  const cv::Mat image = Texture(6);
  const cv::Mat patch = SamplePatch(image, 100.0, 100.0, 5);
  // The search window lies outside the image: nothing is tried, (u, v) stays.
  double u = 2.0, v = 2.0;
  EXPECT_EQ(tracker_detail::SearchPatch(image, patch, 1.0, 0, &u, &v), -1.0);
  EXPECT_EQ(u, 2.0);
  // A flat patch has no correlation to offer.
  const cv::Mat flat = SamplePatch(cv::Mat(200, 240, CV_8U, cv::Scalar(90)), 100.0, 100.0, 5);
  u = v = 100.0;
  EXPECT_EQ(tracker_detail::SearchPatch(image, flat, 1.0, 4, &u, &v), -1.0);
}

}  // namespace
}  // namespace slslam
