// ORB keypoints and descriptors (OpenCV): the baseline point front end of every comparison.
#pragma once

#include <opencv2/core.hpp>

#include "slslam/features/keypoints.h"

namespace slslam {

struct OrbOptions {
  int max_features = 1000;    ///< keypoints kept per image [-]
  float scale_factor = 1.2f;  ///< pyramid scale between levels [-], > 1
  int num_levels = 8;         ///< pyramid levels [-]
  int fast_threshold = 20;    ///< FAST intensity threshold [gray levels]
  int edge_threshold = 19;    ///< border without keypoints [px]

  void Check() const;
};

// Detects ORB keypoints on an 8-bit gray image. Descriptors are 32-byte rows (CV_8U).
// An image without texture yields zero keypoints, not an error.
Keypoints ExtractOrb(const cv::Mat& image, const OrbOptions& options = {});

}  // namespace slslam
