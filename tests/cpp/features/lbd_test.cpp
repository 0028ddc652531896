#include "slslam/features/lbd.h"

#include "slslam/features/line_extractor.h"

#include <random>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace slslam {
namespace {

double Hamming(const cv::Mat& a, int i, const cv::Mat& b, int j) {
  return cv::norm(a.row(i), b.row(j), cv::NORM_HAMMING);
}

// A wall of random blocks (shotcrete-like patches) with straight edges, slightly blurred.
cv::Mat Blocks(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> gray(20, 230), x(0, 700), y(0, 430), side(20, 120);
  cv::Mat image(480, 752, CV_8U, cv::Scalar(110));
  for (int i = 0; i < 60; ++i) {
    cv::rectangle(image, cv::Rect(x(rng), y(rng), side(rng), side(rng)), cv::Scalar(gray(rng)),
                  cv::FILLED);
  }
  cv::GaussianBlur(image, image, cv::Size(), 1.0);
  return image;
}

// The wall's LSD segments (on real edges, as the line front end gives them).
Segments SegmentsOf(const cv::Mat& image) {
  LineExtractorOptions options;
  options.max_lines = 60;
  return ExtractLines(image, options).segments;
}

TEST(Lbd, SegmentAndItsReversalGetTheSameDescriptor) {
  const cv::Mat image = Blocks(1);
  const Segments segments = SegmentsOf(image);
  ASSERT_GE(segments.size(), 40u);
  Segments reversed;
  for (const LineSegment& s : segments) reversed.push_back({s.end, s.start});
  const cv::Mat a = ComputeBandDescriptors(image, segments);
  const cv::Mat b = ComputeBandDescriptors(image, reversed);
  ASSERT_EQ(a.rows, static_cast<int>(segments.size()));
  ASSERT_EQ(a.cols, 32);
  ASSERT_EQ(a.type(), CV_8U);
  // The same pixels in another summation order: at most a bit on a near tie.
  for (int i = 0; i < a.rows; ++i) EXPECT_LE(Hamming(a, i, b, i), 2.0) << "segment " << i;
}

TEST(Lbd, ShiftingTheImageAndTheSegmentsTogetherChangesNothing) {
  const cv::Mat image = Blocks(2);
  cv::Mat shifted(image.size(), image.type(), cv::Scalar(0));
  image(cv::Rect(0, 0, image.cols - 13, image.rows - 7))
      .copyTo(shifted(cv::Rect(13, 7, image.cols - 13, image.rows - 7)));
  Segments segments;  // away from the borders the shift moves in or out
  for (const LineSegment& s : SegmentsOf(image)) {
    if (std::min(s.start.minCoeff(), s.end.minCoeff()) > 40.0f &&
        std::max(s.start.x(), s.end.x()) < 680.0f && std::max(s.start.y(), s.end.y()) < 410.0f)
      segments.push_back(s);
  }
  ASSERT_GE(segments.size(), 20u);
  Segments moved;
  for (const LineSegment& s : segments) {
    moved.push_back({s.start + Eigen::Vector2f(13, 7), s.end + Eigen::Vector2f(13, 7)});
  }
  const cv::Mat a = ComputeBandDescriptorsFloat(image, segments);
  const cv::Mat b = ComputeBandDescriptorsFloat(shifted, moved);
  ASSERT_EQ(a.cols, 72);
  // The same pixels up to float rounding of the sample positions (a rare neighbour pixel).
  EXPECT_LT(cv::norm(a, b, cv::NORM_INF), 0.02);
  for (int i = 0; i < a.rows; ++i) EXPECT_NEAR(cv::norm(a.row(i)), 1.0, 1e-4);
}

TEST(Lbd, SameSegmentsMatchUnderGainAndNoiseOtherSegmentsDoNot) {
  const cv::Mat image = Blocks(3);
  // The same wall darker (gain 0.4, offset 10) with sensor noise (sigma 3 gray levels).
  cv::Mat dark;
  image.convertTo(dark, CV_32F, 0.4, 10.0);
  cv::Mat noise(image.size(), CV_32F);
  cv::RNG rng;  // its own generator: the same noise whichever tests ran before in this process
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 3.0);
  dark += noise;
  dark.convertTo(dark, CV_8U);
  const Segments segments = SegmentsOf(image);
  ASSERT_GE(segments.size(), 40u);
  LbdOptions full_resolution;  // the paper's w on a full-resolution image
  full_resolution.band_width_px = 7;
  const cv::Mat a = ComputeBandDescriptors(image, segments, full_resolution);
  const cv::Mat b = ComputeBandDescriptors(dark, segments, full_resolution);
  int nearest_is_itself = 0;
  double same = 0.0, other = 0.0;
  for (int i = 0; i < a.rows; ++i) {
    int best = -1;
    double best_d = 1e9;
    for (int j = 0; j < b.rows; ++j) {
      const double d = Hamming(a, i, b, j);
      if (d < best_d) best_d = d, best = j;
      (i == j ? same : other) += d;
    }
    nearest_is_itself += best == i;
  }
  same /= a.rows;
  other /= a.rows * (a.rows - 1.0);
  // A hard case (contrast down 2.5x and noise; every edge a blurred step, alike after
  // normalisation): OpenCV's BinaryDescriptor found 28 of 60 segments, its distances 52 bits to
  // the same segment and 94 to others; this descriptor 31 of 60, 50 and 86.
  EXPECT_GE(nearest_is_itself, a.rows / 2);
  EXPECT_LT(same, 52.0);  // of 256 bits
  EXPECT_GT(other, 1.6 * same) << "nearest " << nearest_is_itself << " same " << same;
}

TEST(Lbd, EmptyInputAndFlatImagesAndBadOptions) {
  const cv::Mat flat(100, 100, CV_8U, cv::Scalar(90));
  EXPECT_EQ(ComputeBandDescriptors(flat, {}).rows, 0);
  EXPECT_EQ(ComputeBandDescriptors(flat, {}).cols, 32);
  const cv::Mat d = ComputeBandDescriptors(flat, {{{10, 10}, {80, 60}}});
  EXPECT_EQ(cv::countNonZero(d), 0);  // no gradient: all-zero row
  // A segment far outside the image: every sample skipped, no crash.
  EXPECT_EQ(ComputeBandDescriptors(flat, {{{-500, -500}, {-400, -450}}}).rows, 1);
  LbdOptions bad;
  bad.band_width_px = 0;
  EXPECT_THROW(bad.Check(), std::invalid_argument);
  EXPECT_THROW(ComputeBandDescriptors(cv::Mat(), {}), std::invalid_argument);
  EXPECT_EQ(ParseLineDescriptor("lbd"), LineDescriptor::kLbd);
  EXPECT_EQ(ParseLineDescriptor("opencv_lbd"), LineDescriptor::kOpenCvLbd);
  EXPECT_THROW(ParseLineDescriptor("sift"), std::invalid_argument);
  EXPECT_EQ(LineDescriptorName(LineDescriptor::kOpenCvLbd), "opencv_lbd");
}

}  // namespace
}  // namespace slslam
