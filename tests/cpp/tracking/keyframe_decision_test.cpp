#include "slslam/tracking/keyframe_decision.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace slslam {
namespace {

// A frame tracked strongly 3 frames (0.15 s) after the last keyframe: 300 of the reference's 400
// points, exactly track_ratio (0.75) of them, so c2 does not hold; the close rule does not hold.
KeyframeEvidence Strong() {
  KeyframeEvidence e;
  e.frames_since = 3;
  e.seconds_since = 0.15;
  e.tracked = 300;
  e.reference = 400;
  e.close_tracked = 150;
  e.close_untracked = 20;
  e.weighted_inliers = 320.0;
  return e;
}

struct Case {
  std::string name;
  KeyframeEvidence evidence;
  KeyframeRules rules;
  KeyframeDecision expected;
};

template <typename F>
KeyframeEvidence With(F change) {
  KeyframeEvidence e = Strong();
  change(e);
  return e;
}

template <typename F>
KeyframeRules Rules(F change) {
  KeyframeRules r;
  change(r);
  return r;
}

const KeyframeRules kDefault;

TEST(KeyframeDecisionTest, Table) {
  const std::vector<Case> cases = {
      {"strong tracking keeps the map", Strong(), kDefault, {false, false}},
      {"c2: tracked below track_ratio of the reference, past the gap",
       With([](auto& e) { e.tracked = 299; }),
       kDefault,
       {true, false}},
      {"... but never on the keyframe's own frame",
       With([](auto& e) {
         e.tracked = 299;
         e.frames_since = 0;
       }),
       kDefault,
       {false, false}},
      {"... nor inside the minimum gap",
       With([](auto& e) {
         e.tracked = 299;
         e.frames_since = 1;
       }),
       kDefault,
       {false, false}},
      {"... nor sooner than min_interval_s",
       With([](auto& e) { e.tracked = 299; }),
       Rules([](auto& r) { r.min_interval_s = 0.2; }),
       {false, false}},
      {"... nor with too few weighted inliers (c2's bound)",
       With([](auto& e) {
         e.tracked = 299;
         e.weighted_inliers = 15.0;
       }),
       Rules([](auto& r) { r.weak_inliers = 0.0; }),
       {false, false}},
      {"c1c: below a quarter of the reference, the keyframe is due",
       With([](auto& e) { e.tracked = 99; }),
       kDefault,
       {true, true}},
      {"a quarter exactly is not c1c",
       With([](auto& e) { e.tracked = 100; }),
       kDefault,
       {true, false}},
      {"close rule: few close points tracked, more than 70 untracked",
       With([](auto& e) {
         e.close_tracked = 99;
         e.close_untracked = kCloseUntrackedForKeyframe + 1;
       }),
       kDefault,
       {true, true}},
      {"close rule: 70 untracked are not enough",
       With([](auto& e) {
         e.close_tracked = 99;
         e.close_untracked = kCloseUntrackedForKeyframe;
       }),
       kDefault,
       {false, false}},
      {"close rule: enough close points tracked",
       With([](auto& e) {
         e.close_tracked = 100;
         e.close_untracked = 500;
       }),
       kDefault,
       {false, false}},
      {"max_frames: a keyframe however strong the tracking",
       With([](auto& e) { e.frames_since = 20; }),
       kDefault,
       {true, true}},
      {"thin tracking: a keyframe every weak_frames, inside the gap",
       With([](auto& e) { e.weighted_inliers = 59.0; }),
       Rules([](auto& r) { r.min_frames = 6; }),
       {true, true}},
      {"thin tracking: not sooner than weak_frames",
       With([](auto& e) {
         e.weighted_inliers = 59.0;
         e.frames_since = 2;
       }),
       Rules([](auto& r) { r.min_frames = 6; }),
       {false, false}},
      {"a noisy frame takes min_frames_noisy",
       With([](auto& e) {
         e.tracked = 299;
         e.frames_since = 5;
         e.noisy = true;
       }),
       Rules([](auto& r) {
         r.min_frames = 6;
         r.min_frames_noisy = 5;
       }),
       {true, false}},
      {"a clean frame keeps min_frames",
       With([](auto& e) {
         e.tracked = 299;
         e.frames_since = 5;
       }),
       Rules([](auto& r) {
         r.min_frames = 6;
         r.min_frames_noisy = 5;
       }),
       {false, false}},
      {"min_frames_noisy -1 follows min_frames",
       With([](auto& e) {
         e.tracked = 299;
         e.frames_since = 5;
         e.noisy = true;
       }),
       Rules([](auto& r) { r.min_frames = 6; }),
       {false, false}},
  };
  for (const Case& c : cases) {
    const KeyframeDecision got = DecideKeyframe(c.evidence, c.rules);
    EXPECT_EQ(got.insert, c.expected.insert) << c.name;
    EXPECT_EQ(got.due, c.expected.due) << c.name;
  }
}

TEST(KeyframeDecisionTest, DueImpliesInsert) {
  for (int frames = 0; frames <= 25; ++frames) {
    for (int tracked : {0, 50, 99, 100, 299, 300, 500}) {
      for (double weighted : {0.0, 15.0, 59.0, 60.0, 400.0}) {
        KeyframeEvidence e = Strong();
        e.frames_since = frames;
        e.tracked = tracked;
        e.weighted_inliers = weighted;
        const KeyframeDecision d = DecideKeyframe(e, kDefault);
        EXPECT_TRUE(!d.due || d.insert) << frames << " " << tracked << " " << weighted;
        if (frames == 0) EXPECT_FALSE(d.insert);
      }
    }
  }
}

}  // namespace
}  // namespace slslam
