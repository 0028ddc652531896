#include "slslam/features/line_matcher.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "slslam/features/line_extractor.h"

namespace slslam {
namespace {

const PinholeCamera kCamera{458.0, 458.0, 375.5, 239.5, 752, 480};
constexpr double kBaseline = 0.11;

LineSegment ProjectSegment(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double shift_x) {
  const Eigen::Vector3d offset(shift_x, 0, 0);
  return {kCamera.Project(a - offset).cast<float>(), kCamera.Project(b - offset).cast<float>()};
}

TEST(TriangulateStereoLine, RecoversAKnown3DSegment) {
  // A roof bolt / arch edge 4 m ahead, slanted in depth.
  const Eigen::Vector3d a(-0.4, -0.6, 3.5), b(0.2, 0.5, 4.5);
  const LineSegment left = ProjectSegment(a, b, 0.0);
  // The right camera sits at +baseline along x; its right line is sampled at other points of the
  // same 3-D line, so the endpoints differ from the left ones (as LSD's would).
  const LineSegment right = ProjectSegment(a + 0.1 * (b - a), b + 0.05 * (b - a), kBaseline);
  Eigen::Vector3d s, e;
  ASSERT_TRUE(TriangulateStereoLine(left, right, kCamera, kBaseline, &s, &e));
  EXPECT_LT((s - a).norm(), 1e-3);
  EXPECT_LT((e - b).norm(), 1e-3);
  // A horizontal line gives no depth along the rows.
  const LineSegment flat{{100, 200}, {300, 200}};
  EXPECT_FALSE(TriangulateStereoLine(flat, flat, kCamera, kBaseline, &s, &e));
}

cv::Mat RandomDescriptors(int n, cv::RNG& rng) {
  cv::Mat d(n, 32, CV_8U);
  rng.fill(d, cv::RNG::UNIFORM, 0, 256);
  return d;
}

cv::Mat FlipBits(const cv::Mat& d, cv::RNG& rng, int bits) {
  cv::Mat out = d.clone();
  for (int r = 0; r < out.rows; ++r) {
    for (int k = 0; k < bits; ++k) out.at<uint8_t>(r, rng.uniform(0, 32)) ^= 1 << rng.uniform(0, 8);
  }
  return out;
}

TEST(MatchStereoLines, PairsTheShiftedCopies) {
  cv::RNG rng(5);
  Segments left, right;
  for (int i = 0; i < 6; ++i) {
    const float u = 80.0f + 100.0f * i;
    left.push_back({{u, 50.0f + 10 * i}, {u + 30.0f, 300.0f}});
    right.push_back({{u - 12.0f, 50.0f + 10 * i}, {u + 18.0f, 300.0f}});  // 12 px disparity
  }
  const cv::Mat lbd_left = RandomDescriptors(6, rng);
  const cv::Mat lbd_right = FlipBits(lbd_left, rng, 10);
  const IndexPairs pairs = MatchStereoLines(left, lbd_left, right, lbd_right);
  ASSERT_EQ(pairs.rows(), 6);
  for (int k = 0; k < 6; ++k) EXPECT_EQ(pairs(k, 0), pairs(k, 1));
}

TEST(MatchLinesByPoints, FollowsThePointMatchesAndChecksDescriptors) {
  cv::RNG rng(9);
  const Segments a = {{{0, 0}, {100, 5}}, {{0, 50}, {100, 150}}, {{200, 0}, {200, 90}}};
  const Segments b = {{{200, 3}, {200, 95}}, {{2, 1}, {102, 6}}, {{3, 52}, {103, 152}}};
  const std::vector<std::vector<int>> points_a = {{0, 1}, {2}, {3}};
  const std::vector<std::vector<int>> points_b = {{13}, {10, 11}, {12}};
  IndexPairs point_matches(4, 2);
  point_matches << 0, 10, 1, 11, 2, 12, 3, 13;
  const cv::Mat lbd_a = RandomDescriptors(3, rng);
  cv::Mat lbd_b(3, 32, CV_8U);
  FlipBits(lbd_a.row(2), rng, 5).copyTo(lbd_b.row(0));
  FlipBits(lbd_a.row(0), rng, 5).copyTo(lbd_b.row(1));
  RandomDescriptors(1, rng).copyTo(lbd_b.row(2));  // line 1 <-> 2 disagree in appearance
  const IndexPairs pairs =
      MatchLinesByPoints(a, points_a, lbd_a, b, points_b, lbd_b, point_matches);
  ASSERT_EQ(pairs.rows(), 2);
  EXPECT_EQ(pairs(0, 0), 0);
  EXPECT_EQ(pairs(0, 1), 1);
  EXPECT_EQ(pairs(1, 0), 2);
  EXPECT_EQ(pairs(1, 1), 0);
}

TEST(ExtractLines, FindsTheEdgesOfADrawnRectangleAndNothingOnBlack) {
  cv::Mat image(240, 320, CV_8UC1, cv::Scalar(30));
  cv::rectangle(image, cv::Rect(60, 50, 180, 120), cv::Scalar(200), cv::FILLED);
  const LineFeatures f = ExtractLines(image);
  EXPECT_GE(f.segments.size(), 4u);
  EXPECT_EQ(f.descriptors.rows, static_cast<int>(f.segments.size()));
  EXPECT_EQ(f.descriptors.cols, 32);
  for (const LineSegment& s : f.segments) EXPECT_GT(s.Length(), 240 * 0.05f);
  const LineFeatures none = ExtractLines(cv::Mat::zeros(240, 320, CV_8UC1));
  EXPECT_EQ(none.segments.size(), 0u);
  EXPECT_EQ(none.descriptors.rows, 0);
}

}  // namespace
}  // namespace slslam
