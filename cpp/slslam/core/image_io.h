// Image file reading with errors that name the file.
#pragma once

#include <string>

#include <opencv2/core.hpp>

namespace slslam {

// Reads an image as 8-bit single channel (colour images are converted to gray). Throws
// std::invalid_argument naming `path` when the file is missing, unreadable or empty.
cv::Mat ReadGrayImage(const std::string& path);

// Writes an 8-bit image (PNG, JPEG, ... by extension). Throws std::runtime_error on failure.
void WriteImage(const std::string& path, const cv::Mat& image);

}  // namespace slslam
