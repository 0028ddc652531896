// Line features: OpenCV's LSD segments, preprocessing (SPEC A3) and LBD descriptors (OpenCV
// contrib line_descriptor).
#pragma once

#include <opencv2/core.hpp>

#include "slslam/features/line_preprocess.h"
#include "slslam/features/line_segment.h"

namespace slslam {

struct LineFeatures {
  Segments segments;    ///< preprocessed segments, longest first
  cv::Mat descriptors;  ///< LBD, one 32-byte row (CV_8U) per segment
  int raw_count = 0;    ///< LSD segments before preprocessing
};

struct LineExtractorOptions {
  LinePreprocessOptions preprocess;
  bool run_preprocess = true;  ///< false: LSD segments as they come (for comparisons)

  void Check() const { preprocess.Check(); }
};

// LSD (cv::createLineSegmentDetector, LSD_REFINE_STD) on an 8-bit gray image, then preprocessing
// and LBD descriptors. A textureless image yields no segments, not an error.
LineFeatures ExtractLines(const cv::Mat& image, const LineExtractorOptions& options = {});

// LBD descriptors (32 bytes each) of given segments on an image.
cv::Mat ComputeLbd(const cv::Mat& image, const Segments& segments);

}  // namespace slslam
