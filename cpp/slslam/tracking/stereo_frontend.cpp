#include "slslam/tracking/stereo_frontend.h"

#include <chrono>
#include <future>

#include "slslam/core/check.h"
#include "slslam/features/orb_extractor.h"

namespace slslam {

namespace {

double Ms(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - since)
      .count();
}

}  // namespace

void StereoFrontendOptions::Check() const {
  CheckInRange("tracking.denoise_above_noise", denoise_above_noise, 0.0, 255.0);
  rig.Check();
  stereo.Check();
  lines.Check();
  Require(!left_lines_on_demand || (use_lines && right_lines_on_keyframes),
          "tracking.lines_on_demand needs tracking.use_lines and "
          "tracking.right_lines_on_keyframes");
}

StereoFrontend::StereoFrontend(const StereoFrontendOptions& options) : options_(options) {
  options_.Check();
}

std::shared_ptr<StereoFrame> StereoFrontend::Build(
    int index, int64_t t_ns, const cv::Mat& left_image, const cv::Mat& right_image,
    const Keypoints& left_keypoints, const Keypoints& right_keypoints, StereoFrontendTiming* timing,
    const LineFeatures* given_left_lines, cv::Mat* left_used, cv::Mat* right_used,
    bool denoised) const {
  const PinholeCamera& cam = options_.rig.camera;
  SLSLAM_CHECK(left_image.cols == cam.width && left_image.rows == cam.height, "left image is ",
               left_image.cols, "x", left_image.rows, ", calibration says ", cam.width, "x",
               cam.height);
  Require(right_image.size() == left_image.size(), "left and right images differ in size");
  auto start = std::chrono::steady_clock::now();
  const cv::Mat left = Smoothed(left_image, denoised);
  const cv::Mat right = Smoothed(right_image, denoised);
  LineFeatures left_lines, right_lines;
  const bool right_now = options_.use_lines && !options_.right_lines_on_keyframes;
  Require(given_left_lines == nullptr || (options_.use_lines && !right_now),
          "left-image lines are handed to Build only with use_lines and right_lines_on_keyframes");
  if (given_left_lines != nullptr) {
    left_lines = *given_left_lines;
  } else if (right_now) {
    // LSD is single-threaded: the two images on two threads.
    auto right_future =
        std::async(std::launch::async, [&] { return ExtractLines(right, options_.lines); });
    left_lines = ExtractLines(left, options_.lines);
    right_lines = right_future.get();
  } else if (options_.use_lines && !options_.left_lines_on_demand) {
    left_lines = ExtractLines(left, options_.lines);
  }
  const double line_ms = Ms(start);
  start = std::chrono::steady_clock::now();
  auto frame = std::make_shared<StereoFrame>(MakeStereoFrame(
      index, t_ns, left_keypoints, right_keypoints, options_.use_lines ? &left_lines : nullptr,
      right_now ? &right_lines : nullptr, options_.rig, options_.stereo));
  frame->stereo_lines_pending = options_.use_lines && !right_now;
  frame->left_lines_pending = options_.left_lines_on_demand && given_left_lines == nullptr;
  SearchAndRefineStereoPoints(left, right, options_.rig, options_.stereo, frame.get());
  if (timing != nullptr) {
    timing->line_extraction_ms = line_ms;
    timing->stereo_matching_ms = Ms(start);
  }
  if (left_used != nullptr) *left_used = left;
  if (right_used != nullptr) *right_used = right;
  return frame;
}

cv::Mat StereoFrontend::Smoothed(const cv::Mat& image, bool denoised) const {
  return denoised ? image : SmoothIfNoisy(image, options_.denoise_above_noise);
}

LineFeatures StereoFrontend::ExtractLeftLines(const cv::Mat& left_image, bool denoised) const {
  const PinholeCamera& cam = options_.rig.camera;
  SLSLAM_CHECK(left_image.cols == cam.width && left_image.rows == cam.height, "left image is ",
               left_image.cols, "x", left_image.rows, ", calibration says ", cam.width, "x",
               cam.height);
  Require(options_.use_lines && options_.right_lines_on_keyframes,
          "ExtractLeftLines needs use_lines and right_lines_on_keyframes");
  return ExtractLines(Smoothed(left_image, denoised), options_.lines);
}

void StereoFrontend::CompleteLeftLines(const cv::Mat& left, StereoFrame* frame,
                                       const LineFeatures* extracted, bool denoised) const {
  Require(frame != nullptr, "CompleteLeftLines needs a frame");
  if (!frame->left_lines_pending) return;
  SetLeftLines(extracted != nullptr ? *extracted : ExtractLeftLines(left, denoised), frame);
  frame->left_lines_pending = false;
}

void StereoFrontend::CompleteStereoLines(const cv::Mat& right, StereoFrame* frame,
                                         bool denoised) const {
  Require(frame != nullptr, "CompleteStereoLines needs a frame");
  if (!frame->stereo_lines_pending) return;
  const PinholeCamera& cam = options_.rig.camera;
  SLSLAM_CHECK(right.cols == cam.width && right.rows == cam.height, "right image is ", right.cols,
               "x", right.rows, ", calibration says ", cam.width, "x", cam.height);
  const cv::Mat smoothed = Smoothed(right, denoised);  // as in Build
  MatchStereoLinesInto(ExtractLines(smoothed, options_.lines), options_.rig, options_.stereo,
                       frame);
  frame->stereo_lines_pending = false;
}

}  // namespace slslam
