// The binary line band descriptor of OpenCV contrib's line_descriptor::BinaryDescriptor (its
// default parameters: one octave, 9 bands of 7 rows, 256 bits), computed here for segments on the
// image they were found in, with the same bytes.
//
// Why: OpenCV's `compute` took about 60 us a segment (9-10 ms for the 150 segments of a 752 x 480
// frame, half the line front end), most of it a per-pixel loop with a rounding call per sample,
// per-line containers and a map. This version samples eight rows of a segment's support region at
// once (AVX2 gathers where the CPU has them) and keeps every floating-point operation of each row
// in OpenCV's order, so each row's sums and therefore the descriptor are the same bit for bit
// (tests/cpp/features/opencv_lbd_test.cpp compares it with OpenCV's on many segments).
//
// What it computes, per segment (start s, end e, length L rounded down to n pixels):
//   - the image smoothed by a 5 x 5 Gaussian (sigma 1) and its 3 x 3 Sobel derivatives (int16);
//   - a support region of 63 rows (9 bands x 7) and n columns, centred on the segment, its rows
//     along the segment direction d = (cos a, sin a), a = atan2(e - s), its columns along
//     (-sin a, cos a); each sample takes the derivatives at the nearest pixel (clamped to the
//     image) and splits their projections on d and on the normal into positive and negative sums
//     per row;
//   - rows weighted by a Gaussian across the region (sigma 31 rows) and each band by a Gaussian
//     over itself and its two neighbours (sigma 7); per band the weighted mean and deviation of
//     the four row sums (72 floats), normalised, clipped at 0.4, normalised again;
//   - 32 bytes, each comparing the 8 numbers of two bands (a fixed list of 32 band pairs).
#pragma once

#include <opencv2/core.hpp>

#include "slslam/features/line_segment.h"

namespace slslam {

/// One 32-byte row (CV_8U) per segment on an 8-bit gray image: the bytes OpenCV's
/// BinaryDescriptor::compute gives for these segments as keylines of octave 0 (angle the float
/// atan2 of end - start, numOfPixels the length rounded down). Segments must lie inside the image
/// (the line front end clamps them). `simd` false takes the scalar loop even where AVX2 is there
/// (the same bytes; for tests).
cv::Mat ComputeOpenCvCompatibleLbd(const cv::Mat& image, const Segments& segments,
                                   bool simd = true);

/// The 72 floats (CV_32F rows) the bytes compare: OpenCV's float descriptor (its compute with
/// returnFloatDescr), for tests and diagnostics.
cv::Mat ComputeOpenCvCompatibleLbdFloat(const cv::Mat& image, const Segments& segments,
                                        bool simd = true);

/// OpenCV's own BinaryDescriptor::compute on the same keylines (the reference; slower): its bytes,
/// or with `floats` its 72 floats.
cv::Mat ComputeOpenCvLbdReference(const cv::Mat& image, const Segments& segments,
                                  bool floats = false);

namespace opencv_lbd_detail {

/// The 3 x 3 Sobel derivatives (dx, dy) of an 8-bit image as CV_16SC2, the values of cv::Sobel
/// (ksize 3, BORDER_REFLECT_101) for each, interleaved: one pass instead of two Sobel calls and a
/// cv::merge (exposed for the test that compares them). The image is reflected at its own edges,
/// as with BORDER_ISOLATED: for a region of a larger image cv::Sobel would read the pixels around
/// it (the LBD passes a whole image).
void InterleavedSobel(const cv::Mat& image, cv::Mat* gradients);

}  // namespace opencv_lbd_detail

}  // namespace slslam
