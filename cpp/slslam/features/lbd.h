// Line Band Descriptor (LBD, Zhang and Koch, "An efficient and robust line segment matching
// approach based on LBD descriptor and pairwise geometric consistency", JVCIR 2013), written
// here from the paper, binarised to 256 bits.
//
// The support region of a segment is m bands of w rows each, parallel to the segment and centred
// on it. Every pixel of a row contributes its image gradient split along the segment's normal and
// direction into four sums (positive / negative part of each); rows are weighted by a Gaussian
// across the region (sigma (m w - 1) / 2) and, for each band, by a Gaussian around the band's
// centre row (sigma w) over the band and its two neighbours. A band's description is the mean and
// the standard deviation of its weighted row vectors (4 + 4 numbers); the 72 numbers of the 9
// bands are normalised (means and deviations apart), clipped at 0.4 and normalised again. The
// bits compare every component of band i with the same component of band j for 32 of the 36 band
// pairs: all pairs at most 5 bands apart, and (0, 6) and (2, 8) (a set symmetric under reversing
// the bands). m = 9 bands as in the paper; w is an option.
//
// The segment's frame is oriented by its gradient (the normal points up the mean gradient across
// the central band), so a segment and its reversal get the same descriptor. Long segments are
// sampled at `max_samples_along` points along their length, so the cost per segment is bounded.
// Why: OpenCV's BinaryDescriptor was the largest cost of the line front end (the default takes
// its bytes from features/opencv_lbd.h, which computes them faster). The line front end computes
// this one on the half-size image LSD ran on, which makes it cheaper. It is not the default: it
// matched as well in isolation but degraded faster as the views moved apart, and the tracker was
// less accurate with it (benchmarks/log/realtime.md).
#pragma once

#include <string>

#include <opencv2/core.hpp>

#include "slslam/features/line_segment.h"

namespace slslam {

struct LbdOptions {
  int band_width_px = 4;            ///< rows per band (the paper's w: 7 at full resolution) [px]
  int max_samples_along = 64;       ///< points sampled along a segment at most [-], >= 2
  double smoothing_sigma_px = 1.0;  ///< Gaussian on the image before its gradient [px]; 0: none

  void Check() const;
};

/// Which line descriptor the line front end computes: "lbd" (this file's) or "opencv_lbd"
/// (OpenCV contrib's BinaryDescriptor's bytes, computed by features/opencv_lbd.h; the default).
/// Both are 256
/// bits, but their bits differ: descriptors of one kind never match the other's.
enum class LineDescriptor { kLbd, kOpenCvLbd };

/// "lbd" or "opencv_lbd"; anything else throws std::invalid_argument naming the choices.
LineDescriptor ParseLineDescriptor(const std::string& name);
/// The name ParseLineDescriptor reads.
std::string LineDescriptorName(LineDescriptor descriptor);

/// One 32-byte row (CV_8U) per segment on an 8-bit gray image. Samples outside the image are
/// skipped; a segment with no gradient in its region gets an all-zero row.
cv::Mat ComputeBandDescriptors(const cv::Mat& image, const Segments& segments,
                               const LbdOptions& options = {});

/// The 72 normalised floats (CV_32F rows) before binarisation, for tests and diagnostics.
cv::Mat ComputeBandDescriptorsFloat(const cv::Mat& image, const Segments& segments,
                                    const LbdOptions& options = {});

}  // namespace slslam
