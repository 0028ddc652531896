// A Gaussian blur of 8-bit gray images for the per-frame smoothing of noisy (dark) frames.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

namespace slslam {

// The Gaussian of `sigma_px` (> 0) applied to an 8-bit gray image: the same pixels as
// cv::GaussianBlur(image, out, cv::Size(n, n), sigma_px, sigma_px, cv::BORDER_REFLECT_101) gives
// an image it owns (tested over sizes and sigmas), into a new image; n = 2 radius_px + 1, or with
// radius_px -1 OpenCV's size for 8-bit images (cvRound(6 sigma + 1) | 1, cv::Size() above). A
// view is reflected at its own edges (where OpenCV would read the pixels around it).
//
// Why not cv::GaussianBlur itself: this runs on both images of every dark frame, and OpenCV 4.6's
// 8-bit path spreads an image over its thread pool, taking CPU the frame's other threads are
// waiting for. This is the same integer arithmetic (8-bit taps, exact sums, one rounding) on one
// thread, in 16-bit lanes the compiler vectorises (AVX2 clone, core/cpu_dispatch.h):
// benchmarks/log/realtime.md has the times.
cv::Mat GaussianBlur8u(const cv::Mat& image, double sigma_px, int radius_px = -1);

// The kernel GaussianBlur8u uses, from the centre out: tap k in 1/256, the centre and twice the
// others summing to 256, radius_px + 1 taps (-1: OpenCV's size for 8-bit images) with OpenCV's
// rounding (the sampled Gaussian, each tap's rounding error carried inward).
std::vector<int> GaussianTaps8u(double sigma_px, int radius_px = -1);

// cv::GaussianBlur(image, out, cv::Size(n, n), sigma_px, sigma_px, cv::BORDER_REFLECT_101) for
// any 8-bit gray image, n as GaussianBlur8u's: GaussianBlur8u where it gives those pixels (an
// image that owns its pixels, sigma up to 100 px, radius up to 1000), OpenCV itself otherwise
// (a view, whose surrounding pixels OpenCV reads), into a new image. The one entry point of the
// library's blurs of 8-bit images (the dark frames' smoothing, LSD, LBD).
cv::Mat GaussianBlurAsOpenCv(const cv::Mat& image, double sigma_px, int radius_px = -1);

}  // namespace slslam
