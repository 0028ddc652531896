#include "slslam/features/descriptor_matcher.h"

#include <stdexcept>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "slslam/features/orb_extractor.h"

namespace slslam {
namespace {

TEST(DescriptorMatcher, FindsTheHandBuiltPairsOnly) {
  // Rows 0..2 of train are copies of query rows 2, 0, 1; row 3 is far from everything.
  cv::Mat query = (cv::Mat_<float>(3, 2) << 0, 0, 10, 0, 0, 10);
  cv::Mat train = (cv::Mat_<float>(4, 2) << 0, 10.1, 0.1, 0, 10, 0.2, 50, 50);
  MatchOptions options;
  options.max_distance = 1.0f;
  const auto pairs = MatchDescriptors(query, train, options);
  ASSERT_EQ(pairs.rows(), 3);
  EXPECT_EQ(pairs(0, 0), 0);
  EXPECT_EQ(pairs(0, 1), 1);
  EXPECT_EQ(pairs(1, 1), 2);
  EXPECT_EQ(pairs(2, 1), 0);
}

TEST(DescriptorMatcher, RatioTestDropsAmbiguousMatches) {
  cv::Mat query = (cv::Mat_<float>(1, 2) << 0, 0);
  cv::Mat train = (cv::Mat_<float>(2, 2) << 1, 0, -1.05f, 0);
  MatchOptions options;
  options.max_distance = 5.0f;
  options.ratio = 0.8f;
  EXPECT_EQ(MatchDescriptors(query, train, options).rows(), 0);
  options.ratio = 1.0f;
  EXPECT_EQ(MatchDescriptors(query, train, options).rows(), 1);
}

TEST(DescriptorMatcher, RejectsMismatchedDescriptors) {
  EXPECT_THROW(MatchDescriptors(cv::Mat(2, 32, CV_8U), cv::Mat(2, 2, CV_32F)),
               std::invalid_argument);
  EXPECT_THROW(MatchDescriptors(cv::Mat::zeros(2, 3, CV_32F), cv::Mat::zeros(2, 4, CV_32F)),
               std::invalid_argument);
}

TEST(DescriptorDistance, CountsTheBitsAsOpenCvDoes) {
  // Word-wise popcount against cv::norm(NORM_HAMMING), at ORB's 32 bytes and at lengths that
  // leave a tail of bytes after the 8-byte words.
  cv::RNG rng(7);
  for (int cols : {32, 33, 61, 5}) {
    cv::Mat a(20, cols, CV_8U), b(20, cols, CV_8U);
    rng.fill(a, cv::RNG::UNIFORM, 0, 256);
    rng.fill(b, cv::RNG::UNIFORM, 0, 256);
    for (int i = 0; i < a.rows; ++i) {
      for (int j = 0; j < b.rows; ++j) {
        EXPECT_EQ(DescriptorDistance(a, i, b, j), cv::norm(a.row(i), b.row(j), cv::NORM_HAMMING))
            << cols << " bytes, rows " << i << " / " << j;
      }
      EXPECT_EQ(DescriptorDistance(a, i, a, i), 0.0f);
    }
  }
  const cv::Mat ones(1, 32, CV_8U, cv::Scalar(255)), zeros(1, 32, CV_8U, cv::Scalar(0));
  EXPECT_EQ(DescriptorDistance(ones, 0, zeros, 0), 256.0f);
  EXPECT_THROW(DescriptorDistance(ones, 0, cv::Mat(1, 31, CV_8U, cv::Scalar(0)), 0),
               std::invalid_argument);
  EXPECT_THROW(DescriptorDistance(ones, 1, zeros, 0), std::invalid_argument);  // no row 1
  EXPECT_THROW(DescriptorDistance(ones, 0, zeros, -1), std::invalid_argument);
  cv::Mat f(1, 4, CV_32F, cv::Scalar(0.0f)), g(1, 4, CV_32F, cv::Scalar(0.5f));
  EXPECT_FLOAT_EQ(DescriptorDistance(f, 0, g, 0), 1.0f);  // L2 for float descriptors
}

TEST(OrbExtractor, ShiftedImageMatchesWithTheSameShift) {
  cv::Mat image(240, 320, CV_8UC1);
  cv::RNG rng(7);
  rng.fill(image, cv::RNG::UNIFORM, 0, 255);
  cv::GaussianBlur(image, image, cv::Size(5, 5), 1.5);
  const cv::Mat shifted = image(cv::Rect(6, 0, 300, 240)).clone();
  const Keypoints a = ExtractOrb(image), b = ExtractOrb(shifted);
  ASSERT_GT(a.size(), 100);
  const auto pairs = MatchDescriptors(a.descriptors, b.descriptors);
  ASSERT_GT(pairs.rows(), 50);
  int consistent = 0;
  for (int i = 0; i < pairs.rows(); ++i) {
    const float du = a.uv(pairs(i, 0), 0) - b.uv(pairs(i, 1), 0);
    const float dv = a.uv(pairs(i, 0), 1) - b.uv(pairs(i, 1), 1);
    if (std::abs(du - 6.0f) < 1.5f && std::abs(dv) < 1.5f) ++consistent;
  }
  EXPECT_GT(consistent, 0.9 * pairs.rows());
}

TEST(OrbExtractor, BlackImageGivesNoKeypoints) {
  const Keypoints kp = ExtractOrb(cv::Mat::zeros(100, 100, CV_8UC1));
  EXPECT_EQ(kp.size(), 0);
  EXPECT_EQ(kp.descriptors.rows, 0);
}

}  // namespace
}  // namespace slslam

namespace slslam {
namespace {

TEST(GuidedMatch, FindsTheNearbyKeypointAndIgnoresFarTwins) {
  // Keypoint 0 sits near the prediction; keypoint 1 has the same descriptor but is far away.
  Eigen::Matrix<float, Eigen::Dynamic, 2, Eigen::RowMajor> predicted(2, 2), keypoints(3, 2);
  predicted << 100, 100, 300, 50;
  keypoints << 104, 97, 400, 400, 303, 52;
  cv::Mat query = (cv::Mat_<float>(2, 2) << 1, 0, 0, 1);
  cv::Mat train = (cv::Mat_<float>(3, 2) << 0.98f, 0.05f, 1, 0, 0.1f, 0.99f);
  const Eigen::VectorXi match = GuidedMatch(predicted, query, keypoints, train);
  EXPECT_EQ(match(0), 0);
  EXPECT_EQ(match(1), 2);
  GuidedMatchOptions tight;
  tight.radius_px = 3.0f;  // keypoint 0 is 5 px away
  EXPECT_EQ(GuidedMatch(predicted, query, keypoints, train, tight)(0), -1);
}

TEST(GuidedMatch, KeypointsFarOutsideTheImageChangeNoMatch) {
  // Random binary descriptors, queries predicted near keypoints: the buckets form one dense grid.
  // Keypoints a million pixels away (and at negative coordinates) make the grid sparse; the
  // matches of the others must stay as they were, ties (equal distances) included.
  cv::RNG rng(7);
  const int n = 400;
  Eigen::Matrix<float, Eigen::Dynamic, 2, Eigen::RowMajor> keypoints(n, 2), predicted(n, 2);
  cv::Mat train(n, 32, CV_8U), query(n, 32, CV_8U);
  rng.fill(train, cv::RNG::UNIFORM, 0, 256);
  for (int i = 0; i < n; ++i) {
    keypoints(i, 0) = rng.uniform(0.0f, 752.0f);
    keypoints(i, 1) = rng.uniform(0.0f, 480.0f);
    predicted(i, 0) = keypoints(i, 0) + rng.uniform(-6.0f, 6.0f);
    predicted(i, 1) = keypoints(i, 1) + rng.uniform(-6.0f, 6.0f);
    train.row(i).copyTo(query.row(i));
    for (int b = 0; b < 3; ++b) query.at<uint8_t>(i, rng.uniform(0, 32)) ^= 1;  // a few bits off
  }
  train.row(5).copyTo(train.row(6));  // twins: a tie for the queries near both
  keypoints.row(6) = keypoints.row(5).array() + 2.0f;
  GuidedMatchOptions options;
  options.max_distance = 64.0f;  // bits (binary descriptors)
  const Eigen::VectorXi dense = GuidedMatch(predicted, query, keypoints, train, options);
  Eigen::Matrix<float, Eigen::Dynamic, 2, Eigen::RowMajor> more(n + 2, 2);
  more.topRows(n) = keypoints;
  more.row(n) << 1.0e6f, 2.0e6f;
  more.row(n + 1) << -3.0e6f, -1.0e6f;
  cv::Mat more_train;
  cv::vconcat(train, train.rowRange(0, 2), more_train);
  const Eigen::VectorXi sparse = GuidedMatch(predicted, query, more, more_train, options);
  EXPECT_TRUE(dense == sparse);
  EXPECT_GT((dense.array() >= 0).count(), n / 2);
}

TEST(GuidedMatch, AKeypointGoesToTheBetterQueryOnly) {
  Eigen::Matrix<float, Eigen::Dynamic, 2, Eigen::RowMajor> predicted(2, 2), keypoints(1, 2);
  predicted << 10, 10, 12, 10;
  keypoints << 11, 10;
  cv::Mat query = (cv::Mat_<float>(2, 2) << 1, 0, 0.9f, 0.3f);
  cv::Mat train = (cv::Mat_<float>(1, 2) << 1, 0);
  const Eigen::VectorXi match = GuidedMatch(predicted, query, keypoints, train);
  EXPECT_EQ(match(0), 0);
  EXPECT_EQ(match(1), -1);
}

}  // namespace
}  // namespace slslam
