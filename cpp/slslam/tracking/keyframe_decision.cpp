#include "slslam/tracking/keyframe_decision.h"

namespace slslam {

KeyframeDecision DecideKeyframe(const KeyframeEvidence& e, const KeyframeRules& r) {
  const bool need_close =
      e.close_tracked < r.min_close_tracked && e.close_untracked > kCloseUntrackedForKeyframe;
  // The minimum gap after the last keyframe, in frames and in time.
  const int min_frames = e.noisy && r.min_frames_noisy >= 0 ? r.min_frames_noisy : r.min_frames;
  const bool past_gap = e.frames_since >= min_frames && e.seconds_since >= r.min_interval_s;
  const bool at_most = e.frames_since >= r.max_frames;
  // c1 of ORB-SLAM3 without the gap (c1a and c1c), then with it (c1b).
  const bool c1_without_gap =
      at_most || e.tracked < kLeavingTrackedFraction * e.reference || need_close;
  const bool c1 = c1_without_gap || past_gap;
  const bool c2 =
      (e.tracked < r.track_ratio * e.reference || need_close) && e.weighted_inliers > r.min_inliers;
  // Thin tracking (low texture, few lines): keyframes often, so the map keeps up with the view.
  const bool weak = e.weighted_inliers < r.weak_inliers && e.frames_since >= r.weak_frames;
  // The minimum gap is a hard one while tracking is strong.
  const bool gap = e.frames_since >= 1 && past_gap;
  KeyframeDecision d;
  d.insert = e.frames_since >= 1 && ((gap && c1 && c2) || weak || at_most);
  d.due = d.insert && ((c1_without_gap && c2 && gap) || weak || at_most);
  return d;
}

}  // namespace slslam
