// The per-frame front-end steps between the point features (ORB in C++, learned ones run by
// onnxruntime in Python) and the tracker: line segments on both images (two threads: LSD is
// single-threaded), stereo matching of keypoints and lines, subpixel disparity refinement.
// C++ callers and the Python bindings share it.
#pragma once

#include <memory>

#include <opencv2/core.hpp>

#include "slslam/core/stereo_rig.h"
#include "slslam/features/keypoints.h"
#include "slslam/features/line_extractor.h"
#include "slslam/features/stereo_frame.h"
#include "slslam/tracking/stereo_matching.h"

namespace slslam {

struct StereoFrontendOptions {
  StereoRig rig;
  StereoMatchOptions stereo;
  LineExtractorOptions lines;
  bool use_lines = true;  ///< false: point features only (no line extraction)

  void Check() const;
};

struct StereoFrontendTiming {
  double line_extraction_ms = 0.0;  ///< both images, wall time
  double stereo_matching_ms = 0.0;  ///< keypoints and lines, subpixel refinement included
};

class StereoFrontend {
 public:
  explicit StereoFrontend(const StereoFrontendOptions& options);

  // The frame for rectified 8-bit images of the rig's size and their keypoints (same descriptor
  // type on both sides). Throws std::invalid_argument on images of another size.
  std::shared_ptr<StereoFrame> Build(int index, double timestamp, const cv::Mat& left,
                                     const cv::Mat& right, const Keypoints& left_keypoints,
                                     const Keypoints& right_keypoints,
                                     StereoFrontendTiming* timing = nullptr) const;

  const StereoFrontendOptions& options() const { return options_; }

 private:
  StereoFrontendOptions options_;
};

}  // namespace slslam
