// LSD, the line segment detector of R. Grompone von Gioi, J. Jakubowicz, J.-M. Morel and G.
// Randall (IPOL 2012), written for speed: the SL-SLAM paper's line detector, as OpenCV's
// LineSegmentDetector runs it with its standard refinement (LSD_REFINE_STD: no NFA test; regions
// of low density re-grown with a tighter angle, then cut to a smaller radius). The seeds' order
// and a region's neighbour order are the paper's reference code's, which differ from OpenCV's in
// how ties fall; the segments agree with OpenCV's to 97-98 % of their length (lsd_test.cpp).
//
// Why not OpenCV's: on the half-size images the tracker feeds it, OpenCV's LSD was the largest
// stage of ORB + lines after ORB. It works in double precision on angles, with a sine and a
// cosine for every pixel a region takes; this one keeps each pixel's level-line direction as a
// unit vector and tests alignment by a dot product, so growing a region needs no trigonometry
// (benchmarks/log/realtime.md has the times and how its segments compare with OpenCV's).
#pragma once

#include <vector>

#include <opencv2/core.hpp>

namespace slslam {

struct LsdOptions {
  /// Below 1, the image is blurred by a Gaussian of sigma sigma_scale / scale and resized by this
  /// factor before the gradient (LSD's and OpenCV's default) [-], (0, 1]
  double scale = 0.8;
  double sigma_scale = 0.6;  ///< see scale [-], > 0
  /// Bound on the gradient's quantisation error: gradients below quant / sin(angle tolerance)
  /// are ignored [grey levels], > 0
  double quant = 2.0;
  /// A pixel joins a region when its level-line direction is within this of the region's [deg],
  /// (0, 90)
  double angle_tolerance_deg = 22.5;
  /// Regions filling less of their rectangle than this are refined (re-grown, then cut) [-], (0, 1]
  double density_threshold = 0.7;
  int n_bins = 1024;  ///< bins of the gradient norm for the pseudo-ordering of seeds [-], >= 1

  void Check() const;
};

/// Line segments (x1, y1, x2, y2) of an 8-bit gray image, in pixels with the pixel centres at
/// whole numbers (as OpenCV's LSD returns them). A flat image gives none.
std::vector<cv::Vec4f> DetectLsdSegments(const cv::Mat& gray, const LsdOptions& options = {});

}  // namespace slslam
