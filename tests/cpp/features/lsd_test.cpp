#include "slslam/features/lsd.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

namespace slslam {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Edges in every direction and of both polarities (a rotated square, a lighter bar, a disc for
// curves LSD cuts into pieces) on a noisy wall, the size the tracker hands LSD (half of 752 x 480).
cv::Mat Shapes(double noise_sigma) {
  cv::Mat image(240, 376, CV_8U, cv::Scalar(110));
  const cv::Point2d c(120, 120);
  std::vector<cv::Point> square;
  for (int k = 0; k < 4; ++k) {
    const double a = 17.0 * kPi / 180.0 + k * kPi / 2.0;
    square.emplace_back(cv::Point(static_cast<int>(std::lround((c.x + 70 * std::cos(a)) * 16)),
                                  static_cast<int>(std::lround((c.y + 70 * std::sin(a)) * 16))));
  }
  cv::fillConvexPoly(image, square, cv::Scalar(40), cv::LINE_AA, 4);
  cv::rectangle(image, cv::Rect(230, 30, 120, 40), cv::Scalar(190), cv::FILLED);
  cv::line(image, cv::Point(220, 220), cv::Point(360, 110), cv::Scalar(20), 4, cv::LINE_AA);
  cv::circle(image, cv::Point(300, 170), 30, cv::Scalar(170), cv::FILLED, cv::LINE_AA);
  cv::GaussianBlur(image, image, cv::Size(), 0.8);
  cv::Mat noise(image.size(), CV_16S);
  cv::RNG rng(42);  // its own generator: the same image whatever ran before
  rng.fill(noise, cv::RNG::NORMAL, 0.0, noise_sigma);
  cv::Mat out;
  cv::add(image, noise, out, cv::noArray(), CV_8U);
  return out;
}

double Length(const cv::Vec4f& s) { return std::hypot(s[2] - s[0], s[3] - s[1]); }

// Fraction of the length of a's segments (10 px and longer) within 1 px of a segment of b running
// the same way (within 5 degrees, the same direction: LSD's orientation keeps the dark side on one
// hand).
double CoveredLength(const std::vector<cv::Vec4f>& a, const std::vector<cv::Vec4f>& b) {
  double total = 0.0, covered = 0.0;
  for (const cv::Vec4f& s : a) {
    const double length = Length(s);
    if (length < 10.0) continue;
    const double ux = (s[2] - s[0]) / length, uy = (s[3] - s[1]) / length;
    const int n = static_cast<int>(length);
    for (int i = 0; i <= n; ++i) {
      const double px = s[0] + ux * length * i / n, py = s[1] + uy * length * i / n;
      bool near = false;
      for (const cv::Vec4f& t : b) {
        const double lt = Length(t);
        if (lt < 1e-6) continue;
        const double vx = (t[2] - t[0]) / lt, vy = (t[3] - t[1]) / lt;
        if (ux * vx + uy * vy < std::cos(5.0 * kPi / 180.0)) continue;
        const double along = std::clamp((px - t[0]) * vx + (py - t[1]) * vy, 0.0, lt);
        if (std::hypot(px - t[0] - along * vx, py - t[1] - along * vy) <= 1.0) {
          near = true;
          break;
        }
      }
      covered += near ? 1.0 : 0.0;
      total += 1.0;
    }
  }
  return total > 0.0 ? covered / total : 0.0;
}

std::vector<cv::Vec4f> OpenCvLsd(const cv::Mat& image) {
  std::vector<cv::Vec4f> out;
  cv::createLineSegmentDetector(cv::LSD_REFINE_STD)->detect(image, out);
  return out;
}

TEST(Lsd, FindsTheSegmentsOfOpenCvsLsdRunningTheSameWay) {
  for (const double noise : {0.0, 3.0, 8.0}) {
    const cv::Mat image = Shapes(noise);
    const std::vector<cv::Vec4f> ours = DetectLsdSegments(image), theirs = OpenCvLsd(image);
    ASSERT_GE(theirs.size(), 8u) << "noise " << noise;
    // The same algorithm; OpenCV's angles come from an approximate arctangent, so regions at a
    // tolerance's edge can differ by a pixel.
    EXPECT_GT(CoveredLength(theirs, ours), 0.9) << "noise " << noise;
    EXPECT_GT(CoveredLength(ours, theirs), 0.9) << "noise " << noise;
    EXPECT_NEAR(static_cast<double>(ours.size()), static_cast<double>(theirs.size()),
                0.2 * theirs.size())
        << "noise " << noise;
  }
}

TEST(Lsd, GivesTheFourEdgesOfARotatedSquareAtTheirPlace) {
  const cv::Mat image = Shapes(0.0);
  const std::vector<cv::Vec4f> segments = DetectLsdSegments(image);
  // Each edge: one long segment along it, within a pixel (LSD's 2 x 2 gradient and its 0.8
  // resampling put it a fraction of a pixel off the drawn edge; OpenCV's LSD gives the same).
  for (int k = 0; k < 4; ++k) {
    const double a0 = 17.0 * kPi / 180.0 + k * kPi / 2.0, a1 = a0 + kPi / 2.0;
    const cv::Point2d p0(120 + 70 * std::cos(a0), 120 + 70 * std::sin(a0));
    const cv::Point2d p1(120 + 70 * std::cos(a1), 120 + 70 * std::sin(a1));
    const double edge = std::hypot(p1.x - p0.x, p1.y - p0.y);
    const cv::Point2d n((p0.y - p1.y) / edge, (p1.x - p0.x) / edge);
    double longest = 0.0;
    for (const cv::Vec4f& s : segments) {
      const double d0 = std::abs((s[0] - p0.x) * n.x + (s[1] - p0.y) * n.y);
      const double d1 = std::abs((s[2] - p0.x) * n.x + (s[3] - p0.y) * n.y);
      if (d0 < 1.0 && d1 < 1.0) longest = std::max(longest, Length(s));
    }
    EXPECT_GT(longest, 0.8 * edge) << "edge " << k;
  }
}

TEST(Lsd, FlatOrTinyImagesGiveNoSegmentsAndBadInputThrows) {
  EXPECT_TRUE(DetectLsdSegments(cv::Mat(240, 376, CV_8U, cv::Scalar(90))).empty());
  EXPECT_TRUE(DetectLsdSegments(cv::Mat(1, 1, CV_8U, cv::Scalar(90))).empty());
  LsdOptions full;
  full.scale = 1.0;  // no resizing
  EXPECT_TRUE(DetectLsdSegments(cv::Mat(2, 2, CV_8U, cv::Scalar(90)), full).empty());
  // Tiny images with step edges (the padded grid's borders): segments, if any, inside the image.
  for (const cv::Size size : {cv::Size(2, 2), cv::Size(3, 3), cv::Size(40, 2), cv::Size(2, 40)}) {
    cv::Mat step(size, CV_8U, cv::Scalar(20));
    step.colRange(size.width / 2, size.width).setTo(200);
    step.rowRange(size.height / 2, size.height).setTo(120);
    for (const LsdOptions& options : {full, LsdOptions()}) {
      for (const cv::Vec4f& s : DetectLsdSegments(step, options)) {
        for (int k = 0; k < 4; k += 2) {
          EXPECT_TRUE(s[k] >= -0.5f && s[k] <= size.width) << size << " " << s;
          EXPECT_TRUE(s[k + 1] >= -0.5f && s[k + 1] <= size.height) << size << " " << s;
        }
      }
    }
  }
  cv::Mat wide_step(8, 200, CV_8U, cv::Scalar(20));  // a 200 px edge in an 8-row image
  wide_step.rowRange(4, 8).setTo(200);
  const std::vector<cv::Vec4f> found = DetectLsdSegments(wide_step, full);
  ASSERT_FALSE(found.empty());
  EXPECT_GT(Length(found.front()), 150.0);
  EXPECT_NEAR(found.front()[1], 3.5, 0.5);  // between rows 3 and 4
  EXPECT_TRUE(DetectLsdSegments(cv::Mat(1, 1, CV_8U, cv::Scalar(90)), LsdOptions{0.4}).empty());
  EXPECT_THROW(DetectLsdSegments(cv::Mat(), full), std::invalid_argument);
  EXPECT_THROW(DetectLsdSegments(cv::Mat(10, 10, CV_8UC3), full), std::invalid_argument);
  LsdOptions bad;
  bad.angle_tolerance_deg = 95.0;
  try {
    bad.Check();
    FAIL() << "an angle tolerance of 95 degrees passed";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("lsd.angle_tolerance_deg"), std::string::npos);
  }
  bad = LsdOptions();
  bad.scale = 0.0;
  EXPECT_THROW(bad.Check(), std::invalid_argument);
}

}  // namespace
}  // namespace slslam
