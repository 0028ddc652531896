// Stereo matching that builds a StereoFrame (features/stereo_frame.h): row-band matching of the
// keypoints with subpixel refinement, stereo matching and triangulation of the line segments.
#pragma once

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
  StereoLineOptions lines;

  void Check() const;
};

// Builds a frame: row-band stereo matching of the keypoints (same descriptor type on both sides),
// and stereo matching + triangulation of the lines when line features are given (may be null).
StereoFrame MakeStereoFrame(int index, double timestamp, const Keypoints& left,
                            const Keypoints& right, const LineFeatures* left_lines,
                            const LineFeatures* right_lines, const StereoRig& rig,
                            const StereoMatchOptions& options = {});

// Refines the right-image column of every stereo-matched keypoint to subpixel precision (as
// ORB-SLAM's ComputeStereoMatches): the (2w+1)^2 patch around the left keypoint is slid along the
// right row within +-search columns of the descriptor match, each patch minus its mean (robust
// to an offset between the cameras); the best sum of absolute differences and a V-shaped
// (equiangular) fit through it and its neighbours give the column. A minimum on the edge of the
// search is no reliable match: the keypoint loses its depth. Depths are recomputed. Images: the
// rectified 8-bit pair.
void RefineStereoSubpixel(const cv::Mat& left, const cv::Mat& right, const StereoRig& rig,
                          const StereoMatchOptions& options, StereoFrame* frame);

}  // namespace slslam
