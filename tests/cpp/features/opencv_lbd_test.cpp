#include "slslam/features/opencv_lbd.h"

#include <cstring>
#include <random>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "slslam/features/line_extractor.h"

namespace slslam {
namespace {

// A wall with arches, pipes and cables over blurred noise (rock texture); `gain` < 1 darkens it
// as the mine's dark stretches do, with sensor noise on top.
cv::Mat Wall(float gain, unsigned seed) {
  cv::Mat texture(480, 752, CV_32F);
  cv::RNG rng(seed);
  rng.fill(texture, cv::RNG::NORMAL, 0.0, 30.0);
  cv::GaussianBlur(texture, texture, cv::Size(), 2.0);
  cv::Mat image(480, 752, CV_32F, cv::Scalar(110));
  image += texture;
  cv::rectangle(image, cv::Rect(100, 60, 200, 300), cv::Scalar(40), cv::FILLED);
  cv::rectangle(image, cv::Rect(420, 120, 250, 80), cv::Scalar(200), cv::FILLED);
  cv::ellipse(image, cv::Point(376, 480), cv::Size(300, 380), 0, 180, 360, cv::Scalar(60), 6);
  cv::line(image, cv::Point(380, 300), cv::Point(700, 440), cv::Scalar(30), 5);
  cv::line(image, cv::Point(0, 20), cv::Point(751, 35), cv::Scalar(220), 3);
  image *= gain;
  cv::Mat noise(image.size(), CV_32F);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 2.0);
  image += noise;
  cv::Mat out;
  image.convertTo(out, CV_8U);
  return out;
}

// Segments of every direction and length, some along the image border, inside the image.
Segments RandomSegments(int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> x(0.0f, 751.0f), y(0.0f, 479.0f), len(1.5f, 300.0f),
      angle(-3.14159f, 3.14159f);
  Segments out;
  while (static_cast<int>(out.size()) < count) {
    const Eigen::Vector2f start(x(rng), y(rng));
    const float a = angle(rng), l = len(rng);
    Eigen::Vector2f end = start + l * Eigen::Vector2f(std::cos(a), std::sin(a));
    end.x() = std::clamp(end.x(), 0.0f, 751.0f);
    end.y() = std::clamp(end.y(), 0.0f, 479.0f);
    if ((end - start).norm() > 1.0f) out.push_back({start, end});
  }
  out.push_back({{0.0f, 0.0f}, {751.0f, 0.0f}});      // the top row
  out.push_back({{751.0f, 479.0f}, {751.0f, 0.0f}});  // the right column, upwards
  out.push_back({{10.25f, 5.5f}, {12.75f, 5.5f}});    // a short one on half pixels
  out.push_back({{0.0f, 479.0f}, {751.0f, 0.0f}});    // the longest: the image's diagonal
  return out;
}

void ExpectSameBytes(const cv::Mat& ours, const cv::Mat& opencv, const std::string& what) {
  ASSERT_EQ(ours.rows, opencv.rows) << what;
  ASSERT_EQ(ours.cols, 32) << what;
  ASSERT_EQ(opencv.cols, 32) << what;
  int differing_rows = 0;
  for (int r = 0; r < ours.rows; ++r) {
    differing_rows += cv::norm(ours.row(r), opencv.row(r), cv::NORM_HAMMING) > 0 ? 1 : 0;
  }
  EXPECT_EQ(differing_rows, 0) << what << ": of " << ours.rows << " segments";
}

TEST(OpenCvLbd, GivesOpenCvsBytesOnDetectedAndRandomSegments) {
  for (const float gain : {1.0f, 0.15f}) {
    for (const unsigned seed : {1u, 2u}) {
      const cv::Mat image = Wall(gain, seed);
      LineExtractorOptions options;
      options.max_lines = 0;
      const Segments detected = ExtractLines(image, options).segments;
      ASSERT_GE(detected.size(), 10u);
      const Segments random = RandomSegments(300, seed);
      for (const Segments* segments : {&detected, &random}) {
        const cv::Mat reference = ComputeOpenCvLbdReference(image, *segments);
        const std::string what = "gain " + std::to_string(gain) + ", seed " + std::to_string(seed) +
                                 (segments == &detected ? ", detected" : ", random");
        ExpectSameBytes(ComputeOpenCvCompatibleLbd(image, *segments), reference, what);
        ExpectSameBytes(ComputeOpenCvCompatibleLbd(image, *segments, /*simd=*/false), reference,
                        what + ", scalar");
        // The floats behind the bytes, to the bit (a byte flips only where two are close).
        const cv::Mat reference_floats = ComputeOpenCvLbdReference(image, *segments, true);
        for (const bool simd : {true, false}) {
          const cv::Mat floats = ComputeOpenCvCompatibleLbdFloat(image, *segments, simd);
          ASSERT_EQ(floats.size(), reference_floats.size()) << what;
          EXPECT_EQ(
              std::memcmp(floats.data, reference_floats.data, floats.total() * floats.elemSize()),
              0)
              << what << (simd ? "" : ", scalar") << ": floats differ, by up to "
              << cv::norm(floats, reference_floats, cv::NORM_INF) << ", "
              << cv::countNonZero(floats != reference_floats) << " of " << floats.total();
        }
      }
    }
  }
}

TEST(OpenCvLbd, EmptyInputAndBadInput) {
  const cv::Mat image = Wall(1.0f, 3);
  EXPECT_EQ(ComputeOpenCvCompatibleLbd(image, {}).rows, 0);
  EXPECT_THROW(ComputeOpenCvCompatibleLbd(cv::Mat(), {}), std::invalid_argument);
  const Segments outside = {{{-5.0f, 10.0f}, {40.0f, 10.0f}}};
  EXPECT_THROW(ComputeOpenCvCompatibleLbd(image, outside), std::invalid_argument);
}

TEST(OpenCvLbd, InterleavedSobelGivesOpenCvsSobelAtEverySize) {
  cv::RNG rng(7);
  std::vector<cv::Size> sizes = {
      cv::Size(1, 1), cv::Size(5, 1), cv::Size(1, 5),  cv::Size(2, 2),  cv::Size(2, 9),
      cv::Size(9, 2), cv::Size(3, 3), cv::Size(13, 7), cv::Size(7, 13), cv::Size(752, 480)};
  for (int w = 4; w <= 40; ++w) sizes.emplace_back(w, 3);  // the vector loop's tails
  for (const cv::Size size : sizes) {
    cv::Mat image(size, CV_8U);
    rng.fill(image, cv::RNG::UNIFORM, 0, 256);
    // 0 / 255 stripes two pixels wide, across x (13 x 7) or y (7 x 13): derivatives of +-1020.
    for (int y = 0; y < size.height && (size.width == 13 || size.height == 13); ++y) {
      for (int x = 0; x < size.width; ++x) {
        image.at<uchar>(y, x) = (((size.width == 13 ? x : y) / 2) % 2) ? 255 : 0;
      }
    }
    cv::Mat dx, dy, expected, ours;
    cv::Sobel(image, dx, CV_16S, 1, 0, 3);
    cv::Sobel(image, dy, CV_16S, 0, 1, 3);
    cv::merge(std::vector<cv::Mat>{dx, dy}, expected);
    opencv_lbd_detail::InterleavedSobel(image, &ours);
    ASSERT_EQ(ours.type(), CV_16SC2);
    ASSERT_EQ(ours.size(), size);
    EXPECT_EQ(cv::norm(ours, expected, cv::NORM_INF), 0.0) << size;
    if (size.width == 13 || size.height == 13) {
      double lowest = 0.0, highest = 0.0;
      cv::minMaxLoc(ours.reshape(1), &lowest, &highest);
      EXPECT_EQ(lowest, -1020.0) << size;
      EXPECT_EQ(highest, 1020.0) << size;
    }
  }
  cv::Mat out;
  EXPECT_THROW(opencv_lbd_detail::InterleavedSobel(cv::Mat(), &out), std::invalid_argument);
}

}  // namespace
}  // namespace slslam
