#include "slslam/tracking/stereo_frontend.h"

#include <chrono>
#include <future>

#include "slslam/core/check.h"

namespace slslam {

namespace {

double Ms(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - since)
      .count();
}

}  // namespace

void StereoFrontendOptions::Check() const {
  rig.Check();
  stereo.Check();
  lines.Check();
}

StereoFrontend::StereoFrontend(const StereoFrontendOptions& options) : options_(options) {
  options_.Check();
}

std::shared_ptr<StereoFrame> StereoFrontend::Build(int index, double timestamp, const cv::Mat& left,
                                                   const cv::Mat& right,
                                                   const Keypoints& left_keypoints,
                                                   const Keypoints& right_keypoints,
                                                   StereoFrontendTiming* timing) const {
  const PinholeCamera& cam = options_.rig.camera;
  SLSLAM_CHECK(left.cols == cam.width && left.rows == cam.height, "left image is ", left.cols, "x",
               left.rows, ", calibration says ", cam.width, "x", cam.height);
  Require(right.size() == left.size(), "left and right images differ in size");
  auto start = std::chrono::steady_clock::now();
  LineFeatures left_lines, right_lines;
  if (options_.use_lines) {
    // LSD is single-threaded: the two images on two threads.
    auto right_future =
        std::async(std::launch::async, [&] { return ExtractLines(right, options_.lines); });
    left_lines = ExtractLines(left, options_.lines);
    right_lines = right_future.get();
  }
  const double line_ms = Ms(start);
  start = std::chrono::steady_clock::now();
  auto frame = std::make_shared<StereoFrame>(MakeStereoFrame(
      index, timestamp, left_keypoints, right_keypoints, options_.use_lines ? &left_lines : nullptr,
      options_.use_lines ? &right_lines : nullptr, options_.rig, options_.stereo));
  RefineStereoSubpixel(left, right, options_.rig, options_.stereo, frame.get());
  if (timing != nullptr) {
    timing->line_extraction_ms = line_ms;
    timing->stereo_matching_ms = Ms(start);
  }
  return frame;
}

}  // namespace slslam
