// ORB keypoints and descriptors: the baseline point front end of every comparison.
//
// Detection adapts to low texture as ORB-SLAM's extractor does: FAST runs once per pyramid level
// at the low threshold, and each cell of the level keeps its corners that reach the normal
// threshold, or, when it has none, its weaker ones. The level's budget is then spread over the
// cells round-robin (each cell's best first), so a dark or smooth stretch still yields keypoints
// everywhere a corner exists instead of a few hundred in the one bright patch. Orientation is the
// intensity centroid; descriptors are OpenCV's rotated BRIEF (cv::ORB::compute) on our keypoints,
// level by level on the pyramid detection used.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "slslam/features/keypoints.h"

namespace slslam {

struct OrbOptions {
  int max_features = 1000;     ///< keypoints kept per image [-]
  float scale_factor = 1.2f;   ///< pyramid scale between levels [-], > 1
  int num_levels = 8;          ///< pyramid levels [-]
  int fast_threshold = 20;     ///< FAST intensity threshold [gray levels]
  int edge_threshold = 19;     ///< border without keypoints [px]
  bool adaptive = true;        ///< per-cell threshold fallback; false: plain cv::ORB detection
  int min_fast_threshold = 7;  ///< FAST threshold in cells with no corner at fast_threshold
                               ///< (ORB-SLAM's 20 -> 7) [gray levels]
  int cell_size_px = 32;       ///< side of the adaptive cells, in each level's pixels [px]
  /// Dark frames are noisy (gain): above this estimated noise (Immerkaer's estimator) detection
  /// runs on a Gaussian-smoothed image, sigma = noise / 7 px (residual noise about 2 gray
  /// levels), so FAST fires on structure, not on noise (descriptors: describe_smoothed).
  /// <= 0: never [gray levels]
  double denoise_above_noise = 6.0;
  /// The descriptors of a frame smoothed for detection come from the smoothed image too (BRIEF's
  /// own 7 x 7 box blur leaves the noise of a light-0.15 frame in its bits); false: from the
  /// image as given. On the dark dusty loop (ORB + lines) descriptors from the raw image drifted
  /// more (benchmarks/log/realtime.md).
  bool describe_smoothed = true;

  void Check() const;
};

// Detects ORB keypoints on an 8-bit gray image. Descriptors are 32-byte rows (CV_8U); scores are
// FAST scores (adaptive) or Harris responses (plain). An image without texture yields zero
// keypoints, not an error. Adaptive extraction runs the pyramid levels on OpenCV's threads
// (cv::setNumThreads); the result does not depend on their number.
Keypoints ExtractOrb(const cv::Mat& image, const OrbOptions& options = {});

// Standard deviation of white noise in an 8-bit gray image [gray levels], by Immerkaer's
// method ("Fast noise variance estimation", 1996): the image convolved with a mask that cancels
// smooth intensity up to second order; texture makes it an overestimate.
double EstimateNoiseSigma(const cv::Mat& image);

// The image smoothed by a Gaussian of sigma = noise / 7 px (clamped to [0.5, 2.5] px; residual
// noise about 2 gray levels) when its estimated noise exceeds `above_noise` (> 0), into a buffer
// of its own; otherwise the image itself (shared, not copied).
cv::Mat SmoothIfNoisy(const cv::Mat& image, double above_noise);

// Orientation [deg, 0..360) of each keypoint by the intensity centroid of the disc of radius
// `radius_px` around it (Rosin's measure, as ORB). `points` are pixel positions in `image`;
// points closer than `radius_px` to the edge use the reflected image.
std::vector<float> IntensityCentroidAngles(const cv::Mat& image,
                                           const std::vector<cv::Point2f>& points,
                                           int radius_px = 15);

}  // namespace slslam
