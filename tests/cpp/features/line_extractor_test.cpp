#include "slslam/features/line_extractor.h"

#include <cmath>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

namespace slslam {
namespace {

// Distance from point p to the infinite line through segment s [px].
float DistanceToLine(const LineSegment& s, const Eigen::Vector2f& p) {
  const Eigen::Vector2f d = (s.end - s.start).normalized();
  const Eigen::Vector2f n(-d.y(), d.x());
  return std::abs(n.dot(p - s.start));
}

// Dark rectangles with straight edges (arches, pipes) on a mid-gray wall, slightly blurred.
cv::Mat Rectangles() {
  cv::Mat image(480, 752, CV_8U, cv::Scalar(120));
  cv::rectangle(image, cv::Rect(100, 60, 200, 300), cv::Scalar(40), cv::FILLED);
  cv::rectangle(image, cv::Rect(420, 120, 250, 80), cv::Scalar(200), cv::FILLED);
  cv::line(image, cv::Point(380, 300), cv::Point(700, 440), cv::Scalar(30), 5);
  cv::GaussianBlur(image, image, cv::Size(), 1.0);
  return image;
}

// Every segment of b lies on a segment of a: both endpoints within tolerance_px of the same
// line, at an angle below 1 degree.
void ExpectOnTheSameLines(const Segments& a, const Segments& b, float tolerance_px) {
  for (const LineSegment& s : b) {
    float best = 1e9f;
    for (const LineSegment& t : a) {
      if (AngleDifference(s.Angle(), t.Angle()) > 1.0f * static_cast<float>(M_PI) / 180.0f)
        continue;
      best = std::min(best, std::max(DistanceToLine(t, s.start), DistanceToLine(t, s.end)));
    }
    EXPECT_LT(best, tolerance_px) << "segment (" << s.start.transpose() << ") - ("
                                  << s.end.transpose() << ")";
  }
}

TEST(LineExtractor, HalfResolutionDetectionFindsTheSameLinesAtFullResolution) {
  const cv::Mat image = Rectangles();
  LineExtractorOptions full, half;
  full.detection_scale = 1.0f;
  half.detection_scale = 0.5f;
  const LineFeatures a = ExtractLines(image, full), b = ExtractLines(image, half);
  ASSERT_GE(a.segments.size(), 6u);
  ASSERT_GE(b.segments.size(), 6u);
  EXPECT_EQ(b.descriptors.rows, static_cast<int>(b.segments.size()));
  ExpectOnTheSameLines(a.segments, b.segments, 1.0f);
  LineExtractorOptions bad;
  bad.detection_scale = 0.0f;
  EXPECT_THROW(bad.Check(), std::invalid_argument);
}

TEST(LineExtractor, MaxLinesKeepsTheLongestSegments) {
  const cv::Mat image = Rectangles();
  LineExtractorOptions all, capped;
  all.max_lines = 0;
  const LineFeatures a = ExtractLines(image, all);
  ASSERT_GE(a.segments.size(), 6u);
  capped.max_lines = 3;
  const LineFeatures b = ExtractLines(image, capped);
  ASSERT_EQ(b.segments.size(), 3u);
  EXPECT_EQ(b.descriptors.rows, 3);
  for (int i = 0; i < 3; ++i) {  // the three longest, with the same descriptors
    EXPECT_EQ((a.segments[i].start - b.segments[i].start).norm(), 0.0f);
    EXPECT_EQ(cv::norm(a.descriptors.row(i), b.descriptors.row(i), cv::NORM_HAMMING), 0.0);
  }
  EXPECT_GE(b.segments[2].Length(), a.segments[3].Length());
  LineExtractorOptions bad;
  bad.max_lines = -1;
  EXPECT_THROW(bad.Check(), std::invalid_argument);
}

TEST(LineExtractor, FastLineDetectorFindsTheLinesLsdFinds) {
  const cv::Mat image = Rectangles();
  LineExtractorOptions lsd, fld;  // the detectors at full resolution
  lsd.detection_scale = fld.detection_scale = 1.0f;
  fld.detector = LineDetector::kFld;
  const LineFeatures a = ExtractLines(image, lsd), b = ExtractLines(image, fld);
  ASSERT_GE(b.segments.size(), 6u);
  EXPECT_EQ(b.descriptors.rows, static_cast<int>(b.segments.size()));
  ExpectOnTheSameLines(a.segments, b.segments, 1.0f);  // no FLD segment off LSD's lines
  ExpectOnTheSameLines(b.segments, a.segments, 1.0f);  // and none of LSD's missed
  EXPECT_TRUE(ExtractLines(cv::Mat(480, 752, CV_8U, cv::Scalar(0)), fld).segments.empty());
  EXPECT_EQ(ParseLineDetector("fld"), LineDetector::kFld);
  EXPECT_EQ(ParseLineDetector("lsd"), LineDetector::kLsd);
  EXPECT_EQ(ParseLineDetector("lsd_opencv"), LineDetector::kOpenCvLsd);
  for (const LineDetector d : {LineDetector::kLsd, LineDetector::kOpenCvLsd, LineDetector::kFld}) {
    EXPECT_EQ(ParseLineDetector(LineDetectorName(d)), d);
  }
  EXPECT_THROW(ParseLineDetector("hough"), std::invalid_argument);
}

TEST(LineExtractor, OurLbdDescribesEverySegmentOnTheDetectionImage) {
  const cv::Mat image = Rectangles();
  LineExtractorOptions opencv, ours;
  ours.descriptor = LineDescriptor::kLbd;
  const LineFeatures a = ExtractLines(image, opencv), b = ExtractLines(image, ours);
  ASSERT_GE(b.segments.size(), 6u);
  ASSERT_EQ(a.segments.size(), b.segments.size());  // the descriptor changes no segment
  ASSERT_EQ(b.descriptors.rows, static_cast<int>(b.segments.size()));
  ASSERT_EQ(b.descriptors.type(), CV_8U);
  // The same as describing the segments, mapped to half size, on the half-size image.
  cv::Mat half;
  cv::resize(image, half, cv::Size(376, 240), 0, 0, cv::INTER_AREA);
  Segments on_half;
  for (const LineSegment& s : b.segments) {
    on_half.push_back(
        {(s.start.array() + 0.5f) * 0.5f - 0.5f, (s.end.array() + 0.5f) * 0.5f - 0.5f});
  }
  EXPECT_EQ(cv::norm(b.descriptors, ComputeBandDescriptors(half, on_half), cv::NORM_HAMMING), 0.0);
  EXPECT_GT(cv::norm(a.descriptors, b.descriptors, cv::NORM_HAMMING), 0.0);  // another descriptor
}

}  // namespace
}  // namespace slslam
