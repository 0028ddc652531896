// Stereo point-line tracking (SPEC A5-A6, ORB-SLAM3's Tracking): constant-velocity prediction,
// guided matching of the local map's points and lines into the frame, motion-only bundle
// adjustment on the unified cost, keyframe decision and insertion, hand-off to local mapping.
//
// Tracking loss is a state, not an error: a lost frame reports LOST with the predicted pose, and
// the next frame with enough stereo points starts a new map (state NEW_MAP) anchored at the last
// known pose, so the trajectory stays continuous. Relocalisation into an old map needs place
// recognition (the loop-closing issue) and is not done yet.
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Core>

#include "slslam/features/descriptor_matcher.h"
#include "slslam/map/map.h"
#include "slslam/mapping/local_mapper.h"
#include "slslam/optimization/pose_optimizer.h"
#include "slslam/tracking/stereo_frame.h"

namespace slslam {

enum class TrackingState { kNotInitialized = 0, kOk = 1, kLost = 2, kNewMap = 3 };

const char* TrackingStateName(TrackingState state);

struct TrackerOptions {
  StereoRig rig;
  StereoMatchOptions stereo;
  PoseOptimizerOptions pose;
  LocalMapperOptions mapping;
  bool use_lines = true;           ///< lines in tracking and mapping
  bool sequential = true;          ///< local mapping inline (reproducible) or on its own thread
  int min_init_points = 50;        ///< stereo points a frame needs to start a map [-]
  int min_inliers = 15;            ///< fewer inliers after motion-only BA: LOST [-]
  float search_radius_px = 15.0f;  ///< guided matching window [px]; doubled on a retry
  float max_distance_binary = 50.0f;  ///< guided matching, ORB (Hamming) [bits]
  float max_distance_float = 0.8f;    ///< guided matching, SuperPoint (L2) [-]
  float match_ratio = 0.9f;           ///< ratio test inside the window [-]
  float line_search_px = 20.0f;       ///< frame segment midpoint to predicted line [px]
  float line_max_angle_rad = 0.2f;    ///< [rad]
  float line_max_lbd = 80.0f;         ///< [bits]
  int keyframe_max_frames = 20;       ///< a keyframe at least this often [frames]
  int keyframe_min_frames = 0;        ///< no keyframe sooner than this after the last [frames]
  double keyframe_track_ratio = 0.75;  ///< tracked / reference-keyframe points (those seen by
                                       ///< >= 3 keyframes) below this: keyframe [-]
  int keyframe_min_inliers = 100;      ///< fewer tracked close points (and > 70 untracked
                                       ///< ones): keyframe, as ORB-SLAM3's stereo rule [-]
  double close_depth_baselines = 40.0;  ///< "close" stereo points for the rule above [-]
  double point_sigma_px = 1.0;         ///< [px]
  double line_sigma_px = 3.0;          ///< line endpoint distance sigma [px]: the two
                                       ///< distances of one segment share the map line's error
                                       ///< (benchmarks/README.md: 1.5 px over-weighted lines)

  void Check() const;
};

struct TrackResult {
  TrackingState state = TrackingState::kNotInitialized;
  Eigen::Matrix3d R_cw = Eigen::Matrix3d::Identity();  ///< world -> camera
  Eigen::Vector3d t_cw = Eigen::Vector3d::Zero();
  int map_index = -1;        ///< which map of the atlas the pose belongs to
  int matched_points = 0;    ///< guided matches before optimisation
  int inlier_points = 0;
  int matched_lines = 0;
  int inlier_lines = 0;
  bool keyframe = false;     ///< a keyframe was made from this frame
  double matching_ms = 0.0;  ///< local map projection and guided matching [ms]
  double optimisation_ms = 0.0;  ///< motion-only BA [ms]
  double mapping_ms = 0.0;   ///< keyframe insertion (+ local mapping in sequential mode) [ms]
};

struct MapExport {
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> points;  ///< world [m]
  Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor> lines;   ///< start, end world [m]
  Eigen::VectorXi point_map;  ///< map index per point
  Eigen::VectorXi line_map;
  int keyframes = 0;
};

class Tracker {
 public:
  explicit Tracker(const TrackerOptions& options);
  ~Tracker();
  Tracker(const Tracker&) = delete;
  Tracker& operator=(const Tracker&) = delete;

  TrackResult Track(std::shared_ptr<const StereoFrame> frame);
  // Waits for local mapping to finish its queue (threaded mode).
  void Flush();
  MapExport ExportMap() const;
  LocalMappingStats mapping_stats() const { return mapper_->stats(); }
  int num_maps() const { return static_cast<int>(maps_.size()); }

 private:
  bool StartMap(const std::shared_ptr<const StereoFrame>& frame, const Eigen::Matrix3d& R_cw,
                const Eigen::Vector3d& t_cw);
  void InsertKeyFrame(const std::shared_ptr<const StereoFrame>& frame, const Eigen::Matrix3d& R_cw,
                      const Eigen::Vector3d& t_cw, const std::vector<int>& point_matches,
                      const std::vector<int>& line_matches);

  TrackerOptions options_;
  std::vector<std::unique_ptr<Map>> maps_;
  std::unique_ptr<LocalMapper> mapper_;
  bool lost_ = true;
  bool have_pose_ = false;
  Eigen::Matrix3d last_R_ = Eigen::Matrix3d::Identity();
  Eigen::Vector3d last_t_ = Eigen::Vector3d::Zero();
  Eigen::Matrix3d velocity_R_ = Eigen::Matrix3d::Identity();  ///< T_last * T_prev^-1
  Eigen::Vector3d velocity_t_ = Eigen::Vector3d::Zero();
  int last_keyframe_ = -1;
  int last_keyframe_frame_ = 0;
  int first_tracked_ = 0;  ///< inliers of the first frame after the last keyframe
};

}  // namespace slslam
