// One rectified stereo frame as tracking and the map see it: left keypoints with their
// right-image match (disparity, depth), and left line segments with their stereo-triangulated
// endpoints. Plain data; stereo matching that fills it lives in tracking/stereo_matching.h.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "slslam/core/pinhole_camera.h"
#include "slslam/features/keypoints.h"
#include "slslam/features/line_segment.h"

namespace slslam {

struct StereoFrame {
  int index = 0;                ///< input frame number (0-based)
  int64_t t_ns = 0;             ///< capture time [ns] (core/time.h)
  Keypoints keypoints;          ///< left image
  std::vector<double> u_right;  ///< per keypoint: matched right column [px], or -1
  std::vector<double> depth;    ///< per keypoint: depth from the stereo match [m], or -1
  Segments lines;               ///< left image segments
  cv::Mat line_descriptors;     ///< LBD rows of `lines`
  /// per line: 3-D endpoints in the left camera frame [m] when the stereo pair triangulated it
  std::vector<std::array<Eigen::Vector3d, 2>> line_endpoints;
  std::vector<bool> line_has_depth;
  /// the right image's lines are not matched yet (StereoFrontendOptions::
  /// right_lines_on_keyframes): line_has_depth is all false until the tracker completes the
  /// frame before it becomes a keyframe or starts a map
  bool stereo_lines_pending = false;
  /// the left image's lines are not extracted yet (TrackerOptions::lines_on_demand): `lines` is
  /// empty until the tracker asks for them (a weak frame, a keyframe, a new map, a lost tracker)
  bool left_lines_pending = false;
  /// the keypoints are not detected (TrackerOptions::projected_max_frames): `keypoints` is
  /// empty, and the tracker either places the local map's points in the image itself (aligned
  /// to their patches) or asks for the frame again with detected keypoints
  bool keypoints_pending = false;
  /// the left image was smoothed as noisy before the front end saw it (dark, high gain: slslam's
  /// Python Tracker sets it; TrackerOptions::unaligned_sigma_factor applies only then)
  bool noisy = false;

  int NumKeypoints() const { return keypoints.size(); }
  int NumLines() const { return static_cast<int>(lines.size()); }
  // Camera-frame point of keypoint i (requires depth[i] > 0).
  Eigen::Vector3d Backproject(const PinholeCamera& camera, int i) const;
};

}  // namespace slslam
