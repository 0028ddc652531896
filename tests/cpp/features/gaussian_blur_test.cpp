#include "slslam/features/gaussian_blur.h"

#include <cmath>
#include <numeric>
#include <stdexcept>
#include <utility>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace slslam {
namespace {

// Random texture with flat regions at both ends of the gray range (sums at their 16-bit limits)
// and a smooth ramp (the rounding's ties).
cv::Mat Texture(int width, int height, uint64_t seed) {
  cv::Mat image(height, width, CV_8U);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0, 256);
  cv::rectangle(image, cv::Rect(0, 0, width / 3 + 1, height / 2 + 1), cv::Scalar(255), cv::FILLED);
  cv::rectangle(image, cv::Rect(width / 2, height / 2, width / 2, height / 2), cv::Scalar(0),
                cv::FILLED);
  for (int y = height / 2; y < height; ++y) {
    for (int x = 0; x < width / 2; ++x) image.at<uint8_t>(y, x) = static_cast<uint8_t>(x + y);
  }
  return image;
}

int CountDifferent(const cv::Mat& a, const cv::Mat& b) { return cv::countNonZero(a != b); }

TEST(GaussianBlurTest, GivesOpenCvsPixelsForEverySigmaAndSize) {
  const cv::Size sizes[] = {{752, 480}, {33, 17}, {9, 9},  {5, 200},
                            {200, 5},   {1, 1},   {1, 30}, {3, 2}};
  // The tracker's range (noise / 7, clamped to [0.5, 2.5]) finely, and beyond it.
  std::vector<double> sigmas = {0.1, 0.3, 0.42, 3.0, 4.0, 7.5};
  for (double sigma = 0.5; sigma <= 2.5; sigma += 0.0625) sigmas.push_back(sigma);
  for (const cv::Size& size : sizes) {
    const cv::Mat image = Texture(size.width, size.height, 7 + size.width);
    for (double sigma : sigmas) {
      cv::Mat expected;
      cv::GaussianBlur(image, expected, cv::Size(), sigma, sigma, cv::BORDER_REFLECT_101);
      const cv::Mat blurred = GaussianBlur8u(image, sigma);
      ASSERT_EQ(blurred.size(), image.size());
      ASSERT_EQ(blurred.type(), CV_8UC1);
      EXPECT_EQ(CountDifferent(blurred, expected), 0) << size << " sigma " << sigma;
    }
  }
}

TEST(GaussianBlurTest, GivesOpenCvsPixelsForAKernelSizeOfItsOwn) {
  const cv::Mat image = Texture(376, 240, 11);
  // (LBD's 5 x 5 at sigma 1; LSD's 11 x 11 at sigma 1.2 before the tracker's half-size image,
  // line_detection_scale 0.5, and its 7 x 7 at 0.75 for its own default scale 0.8)
  for (const auto& [sigma, radius] :
       {std::pair{1.0, 2}, {1.2, 5}, {0.75, 3}, {0.75, 1}, {2.0, 3}, {0.5, 6}}) {
    cv::Mat expected;
    cv::GaussianBlur(image, expected, cv::Size(2 * radius + 1, 2 * radius + 1), sigma);
    EXPECT_EQ(CountDifferent(GaussianBlur8u(image, sigma, radius), expected), 0)
        << "sigma " << sigma << " radius " << radius;
    EXPECT_EQ(static_cast<int>(GaussianTaps8u(sigma, radius).size()), radius + 1);
  }
  EXPECT_THROW(GaussianTaps8u(1.0, -2), std::invalid_argument);
}

TEST(GaussianBlurTest, TapsAreOpenCvsSizeAndSumTo256) {
  for (double sigma : {0.1, 0.5, 1.0, 1.3, 2.5, 7.5}) {
    const std::vector<int> taps = GaussianTaps8u(sigma);
    EXPECT_EQ(2 * static_cast<int>(taps.size()) - 1, cvRound(sigma * 6.0 + 1.0) | 1) << sigma;
    EXPECT_EQ(2 * std::accumulate(taps.begin(), taps.end(), 0) - taps[0], 256) << sigma;
    for (int tap : taps) EXPECT_GE(tap, 0) << sigma;
    EXPECT_GT(taps[0], taps.back()) << sigma;
  }
}

TEST(GaussianBlurTest, KeepsAFlatImageAndLeavesItsInputAlone) {
  for (int value : {0, 1, 128, 254, 255}) {
    const cv::Mat flat(40, 60, CV_8U, cv::Scalar(value));
    const cv::Mat copy = flat.clone();
    const cv::Mat blurred = GaussianBlur8u(flat, 1.3);
    EXPECT_EQ(cv::countNonZero(blurred != value), 0) << value;
    EXPECT_EQ(CountDifferent(flat, copy), 0);
    EXPECT_NE(blurred.data, flat.data);
  }
}

TEST(GaussianBlurTest, BlursAViewAsAnImageOfItsOwn) {
  const cv::Mat image = Texture(300, 200, 3);
  const cv::Mat view = image(cv::Rect(17, 11, 150, 90));
  cv::Mat expected;
  cv::GaussianBlur(view.clone(), expected, cv::Size(), 1.4, 1.4, cv::BORDER_REFLECT_101);
  EXPECT_EQ(CountDifferent(GaussianBlur8u(view, 1.4), expected), 0);
}

TEST(GaussianBlurTest, AsOpenCvGivesOpenCvsPixelsForAViewAndBeyondTheLimits) {
  const cv::Mat image = Texture(300, 200, 5);
  const cv::Mat view = image(cv::Rect(17, 11, 150, 90));
  struct Case {
    cv::Mat image;
    double sigma;
    int radius;
  };
  // (a view: OpenCV reads the pixels around it; sigma and radius beyond GaussianBlur8u's)
  for (const Case& c : {Case{view, 1.4, -1}, Case{view, 1.0, 2}, Case{image, 1.3, -1},
                        Case{image, 1.2, 5}, Case{image, 120.0, 3}, Case{image, 1.0, 1200}}) {
    cv::Mat expected;
    const cv::Size size = c.radius < 0 ? cv::Size() : cv::Size(2 * c.radius + 1, 2 * c.radius + 1);
    cv::GaussianBlur(c.image, expected, size, c.sigma, c.sigma, cv::BORDER_REFLECT_101);
    const cv::Mat blurred = GaussianBlurAsOpenCv(c.image, c.sigma, c.radius);
    EXPECT_EQ(CountDifferent(blurred, expected), 0) << "sigma " << c.sigma << " r " << c.radius;
    EXPECT_NE(blurred.data, c.image.data);
  }
  // the view's pixels differ from the isolated blur's at its edges: OpenCV's path was taken
  EXPECT_GT(CountDifferent(GaussianBlurAsOpenCv(view, 1.4), GaussianBlur8u(view, 1.4)), 0);
}

TEST(GaussianBlurTest, RefusesBadInput) {
  EXPECT_THROW(GaussianBlur8u(cv::Mat(), 1.0), std::invalid_argument);
  EXPECT_THROW(GaussianBlur8u(cv::Mat(10, 10, CV_32F, cv::Scalar(0)), 1.0), std::invalid_argument);
  EXPECT_THROW(GaussianBlur8u(cv::Mat(10, 10, CV_8UC3, cv::Scalar(0)), 1.0), std::invalid_argument);
  EXPECT_THROW(GaussianBlur8u(cv::Mat(10, 10, CV_8U, cv::Scalar(0)), 0.0), std::invalid_argument);
  EXPECT_THROW(GaussianBlur8u(cv::Mat(10, 10, CV_8U, cv::Scalar(0)), std::nan("")),
               std::invalid_argument);
}

}  // namespace
}  // namespace slslam
