// AdaptToRig: the tracker's options counted in frames and its pixel windows turned to the
// camera's frame rate and focal length.
#include <algorithm>
#include <cmath>

#include "slslam/core/check.h"
#include "slslam/tracking/tracker.h"

namespace slslam {
namespace {

// Ratios within 1 % of 1 leave the options as they are (a rate from jittered timestamps, a
// focal length calibrated a little differently).
constexpr double kSameRatio = 0.01;

// `ratio` when both are known and differ by more than kSameRatio, else 1.
double RatioOrOne(double value, double reference) {
  if (!(value > 0.0) || !(reference > 0.0)) return 1.0;
  const double ratio = value / reference;
  return std::abs(ratio - 1.0) <= kSameRatio ? 1.0 : ratio;
}

// round(count * ratio); a positive count stays at least 1, 0 and negative (off, "the same as
// another option") stay as they are.
int ScaledCount(int count, double ratio) {
  if (count <= 0 || ratio == 1.0) return count;
  const double scaled = std::round(static_cast<double>(count) * ratio);
  return static_cast<int>(std::clamp(scaled, 1.0, 1e9));
}

}  // namespace

TrackerOptions AdaptToRig(const TrackerOptions& options) {
  TrackerOptions o = options;
  const double rate = RatioOrOne(options.frame_rate_hz, options.reference_rate_hz);
  if (rate != 1.0) {
    o.keyframe_max_frames = ScaledCount(options.keyframe_max_frames, rate);
    o.keyframe_min_frames = ScaledCount(options.keyframe_min_frames, rate);
    o.keyframe_min_frames_noisy = ScaledCount(options.keyframe_min_frames_noisy, rate);
    o.weak_keyframe_frames = ScaledCount(options.weak_keyframe_frames, rate);
    o.projected_max_frames = ScaledCount(options.projected_max_frames, rate);
    o.recently_lost_frames = ScaledCount(options.recently_lost_frames, rate);
    o.lost_motion_frames = std::min(1000, ScaledCount(options.lost_motion_frames, rate));
    o.new_map_after_lost_frames = ScaledCount(options.new_map_after_lost_frames, rate);
    // per-frame quantities: the same per second
    o.lost_velocity_decay = std::pow(options.lost_velocity_decay, 1.0 / rate);
    o.unaligned_max_turn_deg_per_frame =
        std::min(180.0, options.unaligned_max_turn_deg_per_frame / rate);
    if (o.keyframe_min_frames > o.keyframe_max_frames)
      o.keyframe_min_frames = o.keyframe_max_frames;
  }
  if (options.frame_rate_hz > 0.0 && options.reference_rate_hz > 0.0) {
    o.reference_rate_hz = options.frame_rate_hz;
  }
  const double focal = RatioOrOne(options.rig.camera.fx, options.reference_focal_px);
  if (focal != 1.0) {
    const auto window = [focal](float px) {
      return std::min(limits::kMaxImageDistancePx, static_cast<float>(px * focal));
    };
    o.search_radius_px = window(options.search_radius_px);
    o.line_search_px = window(options.line_search_px);
    o.projection_search_px = std::min(64, ScaledCount(options.projection_search_px, focal));
    o.projection_cell_px = std::min(1000, ScaledCount(options.projection_cell_px, focal));
  }
  if (options.reference_focal_px > 0.0) o.reference_focal_px = options.rig.camera.fx;
  return o;
}

}  // namespace slslam
