// AdaptToRig: the options counted in frames follow the camera's rate, the pixel windows its
// focal length; the reference rig changes nothing.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "slslam/tracking/tracker.h"

namespace slslam {
namespace {

TrackerOptions Options(double fx, double rate_hz) {
  TrackerOptions o;
  o.rig = StereoRig{PinholeCamera{fx, fx, 600.0, 180.0, 1200, 360}, 0.5};
  o.frame_rate_hz = rate_hz;
  o.keyframe_min_frames = 6;
  o.keyframe_min_frames_noisy = 5;
  o.projected_max_frames = 2;
  o.projection_cell_px = 16;
  o.reference_focal_px = 458.654;
  return o;
}

// Every adapted option of a and b equal (the fields AdaptToRig writes).
void ExpectSameAdapted(const TrackerOptions& a, const TrackerOptions& b) {
  EXPECT_EQ(a.keyframe_max_frames, b.keyframe_max_frames);
  EXPECT_EQ(a.keyframe_min_frames, b.keyframe_min_frames);
  EXPECT_EQ(a.keyframe_min_frames_noisy, b.keyframe_min_frames_noisy);
  EXPECT_EQ(a.weak_keyframe_frames, b.weak_keyframe_frames);
  EXPECT_EQ(a.projected_max_frames, b.projected_max_frames);
  EXPECT_EQ(a.recently_lost_frames, b.recently_lost_frames);
  EXPECT_EQ(a.lost_motion_frames, b.lost_motion_frames);
  EXPECT_EQ(a.new_map_after_lost_frames, b.new_map_after_lost_frames);
  EXPECT_EQ(a.lost_velocity_decay, b.lost_velocity_decay);
  EXPECT_EQ(a.unaligned_max_turn_deg_per_frame, b.unaligned_max_turn_deg_per_frame);
  EXPECT_EQ(a.search_radius_px, b.search_radius_px);
  EXPECT_EQ(a.line_search_px, b.line_search_px);
  EXPECT_EQ(a.projection_search_px, b.projection_search_px);
  EXPECT_EQ(a.projection_cell_px, b.projection_cell_px);
}

TEST(AdaptToRig, ReferenceRigAndJitteredRateChangeNothing) {
  const TrackerOptions given = Options(458.654, 20.0);
  ExpectSameAdapted(AdaptToRig(given), given);
  // a rate from jittered timestamps (0.05 % off) and a focal length 0.05 % off
  TrackerOptions jittered = Options(458.654 * 1.0005, 20.0 * 0.9995);
  ExpectSameAdapted(AdaptToRig(jittered), jittered);
  // unknown rate, references off
  TrackerOptions unknown = Options(900.0, 0.0);
  unknown.reference_focal_px = 0.0;
  ExpectSameAdapted(AdaptToRig(unknown), unknown);
}

TEST(AdaptToRig, HalfTheRateHalvesTheCountsAndKeepsTheTimes) {
  const TrackerOptions given = Options(458.654, 10.0);
  const TrackerOptions o = AdaptToRig(given);
  EXPECT_EQ(o.keyframe_max_frames, 10);       // 20 -> 1 s
  EXPECT_EQ(o.keyframe_min_frames, 3);        // 6 -> 0.3 s
  EXPECT_EQ(o.keyframe_min_frames_noisy, 3);  // 5 -> 2.5, rounded half away from zero
  EXPECT_EQ(o.weak_keyframe_frames, 2);       // 3 -> 1.5
  EXPECT_EQ(o.projected_max_frames, 1);       // 2 -> 1
  EXPECT_EQ(o.recently_lost_frames, 5);       // 10 -> 0.5 s
  EXPECT_EQ(o.lost_motion_frames, 3);         // 5 -> 2.5
  EXPECT_EQ(o.new_map_after_lost_frames, 3);  // 5 -> 2.5
  // the speed left after one second is the same: decay^20 at 20 Hz, decay'^10 at 10 Hz
  EXPECT_NEAR(std::pow(o.lost_velocity_decay, 10), std::pow(given.lost_velocity_decay, 20), 1e-12);
  EXPECT_DOUBLE_EQ(o.unaligned_max_turn_deg_per_frame,
                   2.0 * given.unaligned_max_turn_deg_per_frame);
  EXPECT_DOUBLE_EQ(o.reference_rate_hz, 10.0);
}

TEST(AdaptToRig, CountsStayPositiveAndOffStaysOff) {
  TrackerOptions given = Options(458.654, 1.0);  // 1 Hz: every count below 20 rounds to 0 or 1
  given.keyframe_min_frames = 0;                 // no gap
  given.keyframe_min_frames_noisy = -1;          // "the same as keyframe_min_frames"
  given.projected_max_frames = 0;                // off
  const TrackerOptions o = AdaptToRig(given);
  EXPECT_EQ(o.keyframe_min_frames, 0);
  EXPECT_EQ(o.keyframe_min_frames_noisy, -1);
  EXPECT_EQ(o.projected_max_frames, 0);
  EXPECT_EQ(o.keyframe_max_frames, 1);
  EXPECT_EQ(o.weak_keyframe_frames, 1);
  EXPECT_EQ(o.lost_motion_frames, 1);
  EXPECT_LE(o.unaligned_max_turn_deg_per_frame, 180.0);
  o.Check();
  // a rate far above the reference: counts grow, min never above max
  TrackerOptions fast = Options(458.654, 200.0);
  const TrackerOptions f = AdaptToRig(fast);
  EXPECT_EQ(f.keyframe_max_frames, 200);
  EXPECT_EQ(f.keyframe_min_frames, 60);
  EXPECT_LE(f.keyframe_min_frames, f.keyframe_max_frames);
  f.Check();
}

TEST(AdaptToRig, PixelWindowsFollowTheFocalLength) {
  const TrackerOptions given = Options(2.0 * 458.654, 20.0);
  const TrackerOptions o = AdaptToRig(given);
  EXPECT_FLOAT_EQ(o.search_radius_px, 2.0f * given.search_radius_px);
  EXPECT_FLOAT_EQ(o.line_search_px, 2.0f * given.line_search_px);
  EXPECT_EQ(o.projection_search_px, 2 * given.projection_search_px);
  EXPECT_EQ(o.projection_cell_px, 32);
  EXPECT_DOUBLE_EQ(o.reference_focal_px, 2.0 * 458.654);
  // the counts in frames are the rate's business only
  EXPECT_EQ(o.keyframe_min_frames, given.keyframe_min_frames);
}

TEST(AdaptToRig, AdaptingTwiceChangesNothing) {
  const TrackerOptions once = AdaptToRig(Options(721.5, 10.0));
  ExpectSameAdapted(AdaptToRig(once), once);
}

TEST(AdaptToRig, TheTrackerRunsWithTheAdaptedOptions) {
  // The constructor checks the given options by their YAML keys before adapting them.
  TrackerOptions bad = Options(458.654, -1.0);
  try {
    Tracker tracker(bad);
    FAIL() << "a negative frame rate was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("tracking.frame_rate_hz"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace slslam
