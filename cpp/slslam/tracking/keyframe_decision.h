// The keyframe decision of a tracked frame: ORB-SLAM3's NeedNewKeyFrame for stereo (conditions
// c1a-c1c and c2, the close-point rule), slslam's minimum gap in frames and in time, and keyframes
// by the gap alone while tracking is thin. A pure function of the frame's evidence and the rules.
#pragma once

namespace slslam {

/// Untracked close stereo points above this, with too few tracked ones: the view holds close
/// structure the map lacks, and the frame is a keyframe (ORB-SLAM3's stereo rule) [points].
inline constexpr int kCloseUntrackedForKeyframe = 70;
/// Tracked points below this fraction of the reference: a keyframe whatever the gap (ORB-SLAM3's
/// c1c, for a view that is leaving the map quickly) [-].
inline constexpr double kLeavingTrackedFraction = 0.25;

/// What one tracked frame shows about the map (Tracker::AcceptTracking gathers it).
struct KeyframeEvidence {
  int frames_since = 0;           ///< frames since the last keyframe [frames]
  double seconds_since = 0.0;     ///< time since the last keyframe [s]
  bool noisy = false;             ///< the frame was smoothed as dark (StereoFrame::noisy)
  int tracked = 0;                ///< point inliers of the frame's pose [points]
  int reference = 0;              ///< the reference keyframe's well-observed points [points]
  int close_tracked = 0;          ///< tracked stereo points closer than the close depth [points]
  int close_untracked = 0;        ///< untracked stereo points closer than it [points]
  double weighted_inliers = 0.0;  ///< point inliers plus weighted line inliers [-]
};

/// The rules, from TrackerOptions' keyframe_* keys (the same names and units).
struct KeyframeRules {
  int max_frames = 20;          ///< a keyframe at least this often [frames]
  int min_frames = 2;           ///< no keyframe sooner while tracking is strong [frames]
  int min_frames_noisy = -1;    ///< ... in a noisy frame; -1: min_frames [frames]
  double min_interval_s = 0.0;  ///< ... nor sooner than this [s]
  double track_ratio = 0.75;    ///< tracked / reference below this: c2 [-]
  int min_close_tracked = 100;  ///< keyframe_min_inliers: the close-point rule's bound
  double min_inliers = 15.0;    ///< c2 needs more weighted inliers than this [-]
  double weak_inliers = 60.0;   ///< weighted inliers below this: thin tracking [-]
  int weak_frames = 3;          ///< thin tracking: a keyframe this often [frames]
};

/// The outcome: ``insert`` with local mapping idle; ``due`` is the subset that ORB-SLAM3's brake
/// (TrackerOptions::mapping_brake, mapping busy) still lets through.
struct KeyframeDecision {
  bool insert = false;
  bool due = false;
  bool operator==(const KeyframeDecision& o) const { return insert == o.insert && due == o.due; }
};

KeyframeDecision DecideKeyframe(const KeyframeEvidence& evidence, const KeyframeRules& rules);

}  // namespace slslam
