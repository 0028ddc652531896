// The per-frame front-end steps between the point features (ORB in C++, learned ones run by
// onnxruntime in Python) and the tracker: line segments on both images (two threads: LSD is
// single-threaded), stereo matching of keypoints and lines, subpixel disparity refinement.
// C++ callers and the Python bindings share it.
#pragma once

#include <cstdint>
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
  /// Lines of the right image only for frames that become keyframes or start a map (the only
  /// ones whose stereo lines are used): Build extracts the left image's and marks the frame
  /// (stereo_lines_pending); CompleteStereoLines adds the right image's when the tracker asks.
  bool right_lines_on_keyframes = true;
  /// The left image's lines only when the tracker asks for them (TrackerOptions::
  /// lines_on_demand): Build extracts none and marks the frame (left_lines_pending);
  /// CompleteLeftLines adds them. Needs use_lines and right_lines_on_keyframes.
  bool left_lines_on_demand = false;
  /// Dark frames are noisy: an image noisier than this (Immerkaer's estimate) is smoothed,
  /// sigma = noise / 7 px, before line detection, line descriptors, the row search and the
  /// subpixel refinement, as ORB smooths its detection image. Measured on the dark dusty loop
  /// (ORB + lines, 600 frames): 0.13 m ATE smoothed against 0.27 m raw. 0: never
  /// [gray levels]
  double denoise_above_noise = 6.0;

  void Check() const;
};

struct StereoFrontendTiming {
  double line_extraction_ms = 0.0;  ///< both images (left only: right_lines_on_keyframes), wall
  double stereo_matching_ms = 0.0;  ///< keypoints and lines, subpixel refinement included
};

class StereoFrontend {
 public:
  explicit StereoFrontend(const StereoFrontendOptions& options);

  // The frame for rectified 8-bit images of the rig's size and their keypoints (same descriptor
  // type on both sides). Throws std::invalid_argument on images of another size.
  // `left_lines`, when given, are the left image's lines from ExtractLeftLines on this image
  // (extracted beside the point front end on another thread); else Build extracts them.
  // `left_used`, when given, receives the left image stereo matching used (smoothed when noisy;
  // else `left` itself, sharing its pixels), for Tracker::Track's keypoint refinement;
  // `right_used` the same for the right image (the stereo columns of projected keypoints).
  // `denoised`: both images come from SmoothIfNoisy at options().denoise_above_noise already
  // (slslam.Tracker smooths each image once for all its steps), so they are used as they are,
  // without the noise estimate (0.1 ms an image). The same frame as without it whenever one blur
  // leaves an image quiet (every frame of the simulated sequences; a pattern whose estimate
  // stays above the threshold after one blur would have been blurred a second time).
  std::shared_ptr<StereoFrame> Build(int index, int64_t t_ns, const cv::Mat& left,
                                     const cv::Mat& right, const Keypoints& left_keypoints,
                                     const Keypoints& right_keypoints,
                                     StereoFrontendTiming* timing = nullptr,
                                     const LineFeatures* left_lines = nullptr,
                                     cv::Mat* left_used = nullptr, cv::Mat* right_used = nullptr,
                                     bool denoised = false) const;

  // The left image's lines exactly as Build extracts them from the same image (smoothed when
  // noisy), for a caller that runs them beside the point front end (slslam.Tracker hands both
  // the copy it already smoothed, with `denoised`). Requires
  // right_lines_on_keyframes (with it off, Build extracts both images' lines side by side) and
  // use_lines. Thread-safe (const). `denoised`: as Build's.
  LineFeatures ExtractLeftLines(const cv::Mat& left, bool denoised = false) const;

  // The stereo lines of a frame Build left pending: the right image's segments, matched and
  // triangulated (for Tracker::Track's completer). Does nothing when none are pending.
  // `denoised`: as Build's.
  void CompleteStereoLines(const cv::Mat& right, StereoFrame* frame, bool denoised = false) const;

  // The left lines of a frame Build left pending (left_lines_on_demand), for Tracker::Track's
  // completer: `extracted` when given (ExtractLeftLines of this image, run ahead on another
  // thread in case the tracker would ask), else ExtractLeftLines on `left`, the image given to
  // Build. The frame's stereo lines stay pending. Does nothing when none are pending.
  // `denoised`: as Build's.
  void CompleteLeftLines(const cv::Mat& left, StereoFrame* frame,
                         const LineFeatures* extracted = nullptr, bool denoised = false) const;

  const StereoFrontendOptions& options() const { return options_; }

 private:
  // The image as the front end's steps see it: smoothed when noisy (denoise_above_noise), or as
  // it is when the caller smoothed it already (`denoised`).
  cv::Mat Smoothed(const cv::Mat& image, bool denoised) const;

  StereoFrontendOptions options_;
};

}  // namespace slslam
