// Line matching: between frames driven by point matches (as in the SL-SLAM paper), and across a
// rectified stereo pair with triangulation of 3-D segments.
#pragma once

#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "slslam/core/pinhole_camera.h"
#include "slslam/features/line_segment.h"

namespace slslam {

using IndexPairs = Eigen::Matrix<int, Eigen::Dynamic, 2, Eigen::RowMajor>;

struct LineMatchOptions {
  int min_votes = 1;               ///< shared matched keypoints a candidate pair needs [-]
  float max_lbd_distance = 80.0f;  ///< largest LBD Hamming distance [bits] (of 256)
  float max_angle_rad = 0.2f;      ///< largest direction change between the two lines [rad]

  void Check() const;
};

// Frame-to-frame line matching through the point matches: candidate partners of line a are the
// lines of B associated with the partners of a's keypoints, ranked by votes (shared matched
// keypoints) then LBD distance; a pair is kept when the LBD distance and angle change are within
// bounds and neither line has a better partner. Returns (line in A, line in B) pairs.
IndexPairs MatchLinesByPoints(const Segments& lines_a,
                              const std::vector<std::vector<int>>& points_a, const cv::Mat& lbd_a,
                              const Segments& lines_b,
                              const std::vector<std::vector<int>>& points_b, const cv::Mat& lbd_b,
                              const IndexPairs& point_matches,
                              const LineMatchOptions& options = {});

struct StereoLineOptions {
  float min_row_overlap = 0.6f;                ///< shared row range / the shorter row range [-]
  float max_lbd_distance = 80.0f;              ///< [bits]
  float max_angle_rad = 0.1f;                  ///< [rad]
  float min_angle_from_horizontal_rad = 0.2f;  ///< flatter lines cannot be triangulated [rad]
  float min_disparity_px = 1.0f;               ///< [px]

  void Check() const;
};

// Stereo matching on rectified images: a right line is a candidate when its row range overlaps
// the left line's, the angles agree and the disparity is positive; the best LBD distance wins
// (mutually). Returns (left, right) pairs.
IndexPairs MatchStereoLines(const Segments& left, const cv::Mat& lbd_left, const Segments& right,
                            const cv::Mat& lbd_right, const StereoLineOptions& options = {});

// 3-D endpoints (left rectified camera frame [m]) of a stereo line pair: each left endpoint meets
// the right line on its own row, giving its disparity. Returns false (and leaves the output alone)
// when the line is too flat or a disparity is not positive.
bool TriangulateStereoLine(const LineSegment& left, const LineSegment& right,
                           const PinholeCamera& camera, double baseline_m,
                           Eigen::Vector3d* start_in_cam, Eigen::Vector3d* end_in_cam,
                           float min_disparity_px = 1.0f);

}  // namespace slslam
