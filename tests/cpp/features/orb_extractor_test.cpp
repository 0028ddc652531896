#include "slslam/features/orb_extractor.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core/utility.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "slslam/features/descriptor_matcher.h"

namespace slslam {
namespace {

// Random blobs: strong texture with `contrast` gray levels of amplitude around `mean`.
cv::Mat Texture(int width, int height, double mean, double contrast, uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat noise(height / 4, width / 4, CV_32F);
  rng.fill(noise, cv::RNG::UNIFORM, -1.0, 1.0);
  cv::Mat big;
  cv::resize(noise, big, cv::Size(width, height), 0, 0, cv::INTER_CUBIC);
  cv::Mat out;
  big.convertTo(out, CV_8U, contrast, mean);
  return out;
}

int CountIn(const Keypoints& k, const cv::Rect& region) {
  int n = 0;
  for (int i = 0; i < k.size(); ++i) n += region.contains(cv::Point(k.uv(i, 0), k.uv(i, 1)));
  return n;
}

TEST(OrbExtractor, LowContrastHalfStillGetsKeypoints) {
  // Left half textured (contrast 120), right half nearly flat (contrast 12: few FAST corners at
  // threshold 20, many at 7), as a lit wall next to a dark, smooth one.
  cv::Mat image = Texture(752, 480, 128, 120, 1);
  Texture(376, 480, 40, 12, 2).copyTo(image(cv::Rect(376, 0, 376, 480)));
  const cv::Rect dark(376 + 32, 0, 376 - 32, 480);
  OrbOptions plain;
  plain.adaptive = false;
  const Keypoints before = ExtractOrb(image, plain);
  const Keypoints after = ExtractOrb(image, OrbOptions{});
  EXPECT_LE(after.size(), OrbOptions{}.max_features);
  EXPECT_EQ(after.descriptors.rows, after.size());
  EXPECT_EQ(after.descriptors.type(), CV_8U);
  const int dark_before = CountIn(before, dark), dark_after = CountIn(after, dark);
  EXPECT_LT(dark_before, 60) << "the dark half is meant to starve plain ORB";
  EXPECT_GT(dark_after, 4 * std::max(dark_before, 25));
  // The bright half keeps a fair share too.
  EXPECT_GT(CountIn(after, cv::Rect(0, 0, 376, 480)), 250);
}

TEST(OrbExtractor, OneThreadGivesTheKeypointsAndDescriptorsOfSeveral) {
  // The pyramid levels are extracted in parallel and joined in level order.
  cv::Mat image = Texture(752, 480, 100, 90, 3);
  Texture(376, 480, 40, 12, 4).copyTo(image(cv::Rect(376, 0, 376, 480)));
  const int threads = cv::getNumThreads();
  cv::setNumThreads(1);
  const Keypoints serial = ExtractOrb(image);
  cv::setNumThreads(std::max(threads, 4));
  const Keypoints parallel = ExtractOrb(image);
  cv::setNumThreads(threads);
  ASSERT_GT(serial.size(), 500);
  ASSERT_EQ(serial.size(), parallel.size());
  EXPECT_TRUE(serial.uv == parallel.uv);
  EXPECT_TRUE(serial.octave == parallel.octave);
  EXPECT_EQ(cv::norm(serial.descriptors, parallel.descriptors, cv::NORM_HAMMING), 0.0);
  int coarse = 0;  // keypoints from every part of the pyramid
  for (int i = 0; i < serial.size(); ++i) coarse += serial.octave(i) >= 4;
  EXPECT_GT(coarse, 0);
}

TEST(OrbExtractor, FlatImageGivesNoKeypoints) {
  const cv::Mat flat(480, 752, CV_8U, cv::Scalar(90));
  const Keypoints k = ExtractOrb(flat);
  EXPECT_EQ(k.size(), 0);
  EXPECT_EQ(k.descriptors.cols, 32);
}

TEST(OrbExtractor, MatchesAcrossAShiftAreConsistent) {
  const cv::Mat image = Texture(800, 520, 100, 60, 7);
  const cv::Mat a = image(cv::Rect(0, 0, 752, 480)).clone();
  const cv::Mat b = image(cv::Rect(9, 5, 752, 480)).clone();  // b(u, v) = a(u + 9, v + 5)
  const Keypoints ka = ExtractOrb(a), kb = ExtractOrb(b);
  ASSERT_GT(ka.size(), 500);
  MatchOptions options;
  options.max_distance = 50.0f;
  const auto pairs = MatchDescriptors(ka.descriptors, kb.descriptors, options);
  int matches = 0, consistent = 0;
  for (Eigen::Index r = 0; r < pairs.rows(); ++r) {
    const int i = pairs(r, 0), j = pairs(r, 1);
    ++matches;
    const float du = ka.uv(i, 0) - 9.0f - kb.uv(j, 0);
    const float dv = ka.uv(i, 1) - 5.0f - kb.uv(j, 1);
    consistent += std::hypot(du, dv) < 3.0f;
  }
  ASSERT_GT(matches, 200);
  EXPECT_GT(consistent, 0.9 * matches);
}

TEST(OrbExtractor, AnglesAgreeWithOpenCv) {
  const cv::Mat image = Texture(752, 480, 120, 100, 11);
  auto orb = cv::ORB::create(500, 1.2f, 1, 31, 0, 2, cv::ORB::HARRIS_SCORE, 31, 20);
  std::vector<cv::KeyPoint> keypoints;
  orb->detect(image, keypoints);
  ASSERT_GT(keypoints.size(), 100u);
  std::vector<cv::Point2f> points;
  for (const auto& kp : keypoints) points.push_back(kp.pt);
  const std::vector<float> angles = IntensityCentroidAngles(image, points, 15);
  // The disc's rim pixels differ slightly from OpenCV's, and where the centroid is near the
  // centre (smooth blobs) that moves the angle: compare the bulk, not every keypoint.
  std::vector<float> diff;
  for (size_t i = 0; i < keypoints.size(); ++i) {
    const float d = std::fabs(angles[i] - keypoints[i].angle);
    diff.push_back(std::min(d, 360.0f - d));
  }
  std::sort(diff.begin(), diff.end());
  EXPECT_LT(diff[diff.size() / 2], 5.0f);
  EXPECT_LT(diff[diff.size() * 8 / 10], 20.0f);
}

TEST(OrbExtractor, NoiseEstimateMatchesTheAddedNoise) {
  cv::Mat flat(480, 752, CV_8U, cv::Scalar(100)), noisy;
  cv::Mat noise(480, 752, CV_32F);
  cv::RNG rng(5);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 8.0);
  flat.convertTo(noisy, CV_32F);
  noisy += noise;
  noisy.convertTo(noisy, CV_8U);
  EXPECT_NEAR(EstimateNoiseSigma(noisy), 8.0, 0.8);
  EXPECT_LT(EstimateNoiseSigma(flat), 0.01);
}

// The estimate sums the mask's response in two integer passes; it must be the exact value of the
// 3 x 3 mask filtered by OpenCV and its L1 norm (the definition), edges and odd sizes included.
TEST(OrbExtractor, NoiseEstimateEqualsTheFilteredMasksNorm) {
  cv::RNG rng(11);
  for (const cv::Size size :
       {cv::Size(3, 3), cv::Size(4, 7), cv::Size(752, 480), cv::Size(257, 33)}) {
    cv::Mat image(size, CV_8U);
    rng.fill(image, cv::RNG::UNIFORM, 0, 256);
    const cv::Mat mask = (cv::Mat_<float>(3, 3) << 1, -2, 1, -2, 4, -2, 1, -2, 1);
    cv::Mat response;
    cv::filter2D(image, response, CV_32F, mask, cv::Point(-1, -1), 0.0, cv::BORDER_REFLECT_101);
    const cv::Mat inner = response(cv::Rect(1, 1, size.width - 2, size.height - 2));
    const double expected =
        std::sqrt(CV_PI / 2.0) * cv::norm(inner, cv::NORM_L1) / (6.0 * inner.total());
    EXPECT_DOUBLE_EQ(EstimateNoiseSigma(image), expected) << size;
  }
}

// Fraction of keypoints of `a` with a keypoint of `b` within 2 px.
double Repeatability(const Keypoints& a, const Keypoints& b) {
  int repeated = 0;
  for (int i = 0; i < a.size(); ++i) {
    for (int j = 0; j < b.size(); ++j) {
      if (std::hypot(a.uv(i, 0) - b.uv(j, 0), a.uv(i, 1) - b.uv(j, 1)) < 2.0f) {
        ++repeated;
        break;
      }
    }
  }
  return a.size() > 0 ? static_cast<double>(repeated) / a.size() : 0.0;
}

TEST(OrbExtractor, SmoothingNoisyDarkFramesMakesKeypointsRepeatable) {
  // A dim, weakly textured scene seen twice with independent sensor noise (sigma 9 gray levels,
  // as the simulator's light-0.15 frames): keypoints on noise do not repeat, on structure they do.
  const cv::Mat scene = Texture(752, 480, 40, 25, 3);
  auto observe = [&](uint64_t seed) {
    cv::Mat noise(480, 752, CV_32F), out;
    cv::RNG rng(seed);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, 9.0);
    scene.convertTo(out, CV_32F);
    out += noise;
    out.convertTo(out, CV_8U);
    return out;
  };
  const cv::Mat a = observe(1), b = observe(2);
  OrbOptions raw;
  raw.denoise_above_noise = 0.0;
  const double without = Repeatability(ExtractOrb(a, raw), ExtractOrb(b, raw));
  const double with = Repeatability(ExtractOrb(a), ExtractOrb(b));
  EXPECT_GT(with, without + 0.15) << "without smoothing " << without << ", with " << with;
}

TEST(OrbExtractor, SmoothingLeavesTheCallersImageAsItWas) {
  // The smoothed detection image is a buffer of its own: the frame's image goes on to lines and
  // stereo matching unchanged (it was once blurred in place).
  const cv::Mat scene = Texture(752, 480, 40, 25, 3);
  cv::Mat noise(480, 752, CV_32F), noisy;
  cv::RNG rng(3);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 9.0);
  scene.convertTo(noisy, CV_32F);
  noisy += noise;
  noisy.convertTo(noisy, CV_8U);
  ASSERT_GT(EstimateNoiseSigma(noisy), OrbOptions{}.denoise_above_noise);
  const cv::Mat before = noisy.clone();
  EXPECT_GT(ExtractOrb(noisy).size(), 0);
  EXPECT_EQ(cv::norm(noisy, before, cv::NORM_INF), 0.0);
}

TEST(OrbExtractor, BadOptionsThrow) {
  OrbOptions options;
  options.min_fast_threshold = 30;  // above fast_threshold
  EXPECT_THROW(options.Check(), std::invalid_argument);
  options = OrbOptions{};
  options.cell_size_px = 2;
  EXPECT_THROW(options.Check(), std::invalid_argument);
}

}  // namespace
}  // namespace slslam
