#include "slslam/core/image_io.h"

#include <filesystem>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>

#include "slslam/core/check.h"

namespace slslam {

cv::Mat ReadGrayImage(const std::string& path) {
  SLSLAM_CHECK(std::filesystem::is_regular_file(path), "image file not found: ", path);
  cv::Mat image = cv::imread(path, cv::IMREAD_GRAYSCALE);
  SLSLAM_CHECK(!image.empty(), "image file is unreadable or not an image: ", path);
  return image;
}

void WriteImage(const std::string& path, const cv::Mat& image) {
  SLSLAM_CHECK(!image.empty(), "refusing to write an empty image to ", path);
  if (!cv::imwrite(path, image)) {
    throw std::runtime_error(Message("could not write image ", path));
  }
}

}  // namespace slslam
