#include "slslam/core/image_io.h"

#include <filesystem>
#include <fstream>
#include <stdexcept>

#include <gtest/gtest.h>

namespace slslam {
namespace {

namespace fs = std::filesystem;

TEST(ImageIo, WriteThenReadGray) {
  const fs::path path = fs::temp_directory_path() / "slslam_image_io_test.png";
  cv::Mat image(12, 20, CV_8UC1);
  cv::randu(image, 0, 255);
  WriteImage(path.string(), image);
  const cv::Mat back = ReadGrayImage(path.string());
  EXPECT_EQ(cv::norm(image, back, cv::NORM_INF), 0.0);
  fs::remove(path);
}

TEST(ImageIo, MissingFileNamesThePath) {
  try {
    ReadGrayImage("/nonexistent/frame_0001.png");
    FAIL() << "expected an exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/frame_0001.png"), std::string::npos);
  }
}

TEST(ImageIo, CorruptFileIsRejected) {
  const fs::path path = fs::temp_directory_path() / "slslam_corrupt.png";
  std::ofstream(path) << "not a png";
  EXPECT_THROW(ReadGrayImage(path.string()), std::invalid_argument);
  fs::remove(path);
}

}  // namespace
}  // namespace slslam
