// Line features: LSD segments (ours or OpenCV's), the SL-SLAM paper's preprocessing and LBD
// descriptors (ours, features/lbd.h, or OpenCV contrib line_descriptor's).
#pragma once

#include <string>

#include <opencv2/core.hpp>

#include "slslam/features/lbd.h"
#include "slslam/features/line_preprocess.h"
#include "slslam/features/line_segment.h"

namespace slslam {

struct LineFeatures {
  Segments segments;    ///< preprocessed segments, longest first
  cv::Mat descriptors;  ///< LBD (options.descriptor), one 32-byte row (CV_8U) per segment
  int raw_count = 0;    ///< LSD segments before preprocessing
};

/// The segment detector. LSD is the paper's: ours (features/lsd.h) or OpenCV's
/// LineSegmentDetector (LSD_REFINE_STD), the same algorithm; FLD (OpenCV contrib ximgproc's
/// FastLineDetector: Canny edges fitted by lines, no merging) took about half OpenCV's LSD's time
/// on simulated mine frames (benchmarks/log/realtime.md).
enum class LineDetector { kLsd, kOpenCvLsd, kFld };

/// "lsd", "lsd_opencv" or "fld"; anything else throws std::invalid_argument naming the choices.
LineDetector ParseLineDetector(const std::string& name);
/// The name ParseLineDetector reads.
std::string LineDetectorName(LineDetector detector);

struct LineExtractorOptions {
  LinePreprocessOptions preprocess;
  bool run_preprocess = true;  ///< false: LSD segments as they come (for comparisons)
  /// LSD runs on the image resized by this factor (area averaging), segments are mapped back to
  /// full resolution; LBD and everything after work at full resolution. 0.5 cuts LSD's time about
  /// 4x and keeps the long segments preprocessing keeps anyway; with max_lines 150 and
  /// keyframe_min_frames 2 it gave equal or lower ATE on the four hard simulated sequences of
  /// benchmarks/tracking_recovery.py (benchmarks/log/tracking_recovery.md) [-], (0, 1]
  float detection_scale = 0.5f;
  LineDetector detector = LineDetector::kLsd;
  /// Keep at most this many segments after preprocessing, the longest (0: all). The LBD costs
  /// about 20 us per segment with AVX2, 65 us without (a 752 x 480 mine frame gives 250 after
  /// preprocessing) [-], >= 0
  int max_lines = 150;
  /// Descriptor of the segments: OpenCV's BinaryDescriptor's bytes at full resolution
  /// (computed by features/opencv_lbd.h, the same bytes three times faster), or our LBD
  /// (features/lbd.h) on the image LSD ran on (the detection scale): cheaper, but it tracked less
  /// accurately on the simulated sequences (benchmarks/log/realtime.md).
  LineDescriptor descriptor = LineDescriptor::kOpenCvLbd;
  LbdOptions lbd;  ///< our LBD's settings (in pixels of the detection image)

  void Check() const;
};

// Segments (LSD or FLD, options.detector) on an 8-bit gray image, then preprocessing and LBD
// descriptors. A textureless image yields no segments, not an error.
LineFeatures ExtractLines(const cv::Mat& image, const LineExtractorOptions& options = {});

// Descriptors (32 bytes each) of given segments on an image: ours (ComputeBandDescriptors) or
// OpenCV's BinaryDescriptor's (ComputeOpenCvCompatibleLbd).
cv::Mat ComputeLineDescriptors(const cv::Mat& image, const Segments& segments,
                               LineDescriptor descriptor, const LbdOptions& lbd = {});

}  // namespace slslam
