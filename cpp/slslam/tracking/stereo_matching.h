// Stereo matching that builds a StereoFrame (features/stereo_frame.h): row-band matching of the
// keypoints with subpixel refinement, stereo matching and triangulation of the line segments.
#pragma once

#include <cstdint>

#include <opencv2/core.hpp>

#include "slslam/core/stereo_rig.h"
#include "slslam/features/keypoints.h"
#include "slslam/features/line_extractor.h"
#include "slslam/features/line_matcher.h"
#include "slslam/features/stereo_frame.h"

namespace slslam {

struct StereoMatchOptions {
  float max_row_offset_px = 2.0f;     ///< |v_left - v_right| bound on rectified images [px]
  float min_disparity_px = 0.5f;      ///< [px]
  float max_disparity_px = 120.0f;    ///< [px]
  float max_distance_binary = 60.0f;  ///< largest Hamming distance (ORB, 256 bits) [bits]
  float max_distance_float = 0.9f;    ///< largest L2 distance (unit float descriptors) [-]
  float ratio = 0.9f;                 ///< best / second best along the row band [-]
  float max_depth_baselines = 60.0f;  ///< depths beyond this many baselines count as unknown [-]
  int subpixel_window = 5;  ///< half size of the SAD patch for subpixel disparity [px]; 0: off
  int subpixel_search = 5;  ///< columns searched on each side of the descriptor match [px]
  /// Points: no right-image keypoints; each left keypoint's patch is searched along its row of
  /// the right image over the disparity range (MatchStereoByRowSearch). Lets a learned front end
  /// run its network on the left image only.
  bool row_search = false;
  /// half size of the SAD patch of the row search [px]. 7 (15 x 15): on dark frames a smaller
  /// patch of a noisy pair refused or biased matches, the map's scale came out short and XFeat +
  /// lines drifted more on the simulated loop; in bright frames the size made no clear difference
  /// (benchmarks/log/realtime.md). Keypoints within w px of the image's edge are not searched
  int row_search_window = 7;
  /// best cost / lowest other local minimum of the cost along the row must be below this [-]
  float row_search_ratio = 0.8f;
  /// best cost / the left patch's own absolute deviation from its mean must be below this [-]
  float row_search_max_cost = 0.5f;
  /// patches whose mean absolute deviation is below this are not searched [gray levels]
  float row_search_min_texture = 2.0f;
  StereoLineOptions lines;

  void Check() const;
};

// Builds the frame captured at t_ns [ns]: row-band stereo matching of the keypoints (same
// descriptor type on both sides), and stereo matching + triangulation of the lines when line
// features are given (may be null).
StereoFrame MakeStereoFrame(int index, int64_t t_ns, const Keypoints& left, const Keypoints& right,
                            const LineFeatures* left_lines, const LineFeatures* right_lines,
                            const StereoRig& rig, const StereoMatchOptions& options = {});

// The frame's left-image line segments and descriptors, none with stereo depth yet
// (MakeStereoFrame's first line step, also run on its own when the left image's lines are
// extracted later, lines_on_demand).
void SetLeftLines(const LineFeatures& left_lines, StereoFrame* frame);

// Stereo matching and triangulation of the frame's (left) line segments with the right image's:
// fills line_endpoints and line_has_depth (MakeStereoFrame's line step, also run on its own when
// the right image's lines are extracted later, for keyframes only).
void MatchStereoLinesInto(const LineFeatures& right_lines, const StereoRig& rig,
                          const StereoMatchOptions& options, StereoFrame* frame);

// Stereo matching of the left keypoints without right-image keypoints (options.row_search): for
// each keypoint the (2w+1)^2 patch around it (w = row_search_window), minus its mean, is compared
// by the sum of absolute differences with every right patch of its row whose disparity lies in
// [min_disparity_px, max_disparity_px], each minus its own mean (as RefineStereoSubpixel). A
// match needs texture in the left patch, a best cost small against the patch's own deviation
// (row_search_max_cost), a clear lowest minimum (row_search_ratio against the lowest other local
// minimum: repeated structure along the row is refused) and a minimum inside the range. Give it
// a noisy (dark) pair smoothed (SmoothIfNoisy, as StereoFrontend does): on raw light-0.15 frames
// the patches' own noise decides (with the 7 x 7 patch: 16 of 2,500 keypoints matched, about 550
// smoothed, with fewer wrong than the descriptors' matches). The integer column is stored;
// RefineStereoSubpixel refines it as a descriptor match. Keypoints with a match already keep it.
// About (2w+1)^2 x (disparity range) absolute differences per keypoint (225 x for the default),
// vectorised over 32 columns at a time whose sums stay in registers (AVX-512 or AVX2 versions
// where the CPU has them); keypoints in parallel stripes on OpenCV's threads.
void MatchStereoByRowSearch(const cv::Mat& left, const cv::Mat& right, const StereoRig& rig,
                            const StereoMatchOptions& options, StereoFrame* frame);

// The point steps after MakeStereoFrame's descriptor matching, on the pair the frame's lines saw:
// the row search (options.row_search), then the subpixel refinement (StereoFrontend::Build and
// the bindings' match_stereo_points share them).
void SearchAndRefineStereoPoints(const cv::Mat& left, const cv::Mat& right, const StereoRig& rig,
                                 const StereoMatchOptions& options, StereoFrame* frame);

// Refines the right-image column of every stereo-matched keypoint to subpixel precision (as
// ORB-SLAM's ComputeStereoMatches): the (2w+1)^2 patch around the left keypoint is slid along the
// right row within +-search columns of the descriptor match, each patch minus its mean (robust
// to an offset between the cameras); the best sum of absolute differences and a V-shaped
// (equiangular) fit through it and its neighbours give the column. A minimum on the edge of the
// search is no reliable match: the keypoint loses its depth. Depths are recomputed. Images: the
// rectified 8-bit pair.
void RefineStereoSubpixel(const cv::Mat& left, const cv::Mat& right, const StereoRig& rig,
                          const StereoMatchOptions& options, StereoFrame* frame);

// Whether RefineStereoSubpixel can refine a match at left column `ul`, row `v` and right column
// `ur` (integers): its patch and search fit inside both images. Elsewhere it keeps the column
// it was given.
bool SubpixelWindowFits(const cv::Mat& left, const cv::Mat& right,
                        const StereoMatchOptions& options, int ul, int v, int ur);

}  // namespace slslam
