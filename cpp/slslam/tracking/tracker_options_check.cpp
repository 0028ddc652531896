// Range checks of the tracking options (stereo matching, relocalisation, the tracker), kept apart
// from the algorithms so that a new option and its bound are read together. Names follow the
// YAML keys (configs/default.yaml) where an option has one.
#include <limits>

#include "slslam/core/check.h"
#include "slslam/tracking/stereo_matching.h"
#include "slslam/tracking/tracker.h"

namespace slslam {
namespace {
constexpr int kMaxCount = 1'000'000'000;  ///< frames, inliers: any sensible int [-]
}  // namespace

void StereoMatchOptions::Check() const {
  CheckInRange("stereo.max_row_offset_px", max_row_offset_px, 0.0f, limits::kMaxImageDistancePx);
  CheckAboveInRange("stereo.min_disparity_px", min_disparity_px, 0.0f, limits::kMaxImageDistancePx);
  SLSLAM_CHECK(
      max_disparity_px > min_disparity_px && max_disparity_px <= limits::kMaxImageDistancePx,
      "stereo.max_disparity_px must be in (min_disparity_px, ", limits::kMaxImageDistancePx,
      "], got ", max_disparity_px);
  CheckAboveInRange("stereo.max_distance_binary", max_distance_binary, 0.0f, 256.0f);
  CheckAboveInRange("stereo.max_distance_float", max_distance_float, 0.0f,
                    limits::kMaxDescriptorDistance);
  CheckAboveInRange("stereo.ratio", ratio, 0.0f, 1.0f);
  CheckAboveInRange("tracking.max_depth_baselines", max_depth_baselines, 0.0f, 1e6f);
  CheckInRange("stereo.subpixel_window", subpixel_window, 0, 100);
  CheckInRange("stereo.subpixel_search", subpixel_search, 1, 1000);
  CheckInRange("stereo.row_search_window", row_search_window, 1, 50);
  CheckAboveInRange("stereo.row_search_ratio", row_search_ratio, 0.0f, 1.0f);
  CheckAboveInRange("stereo.row_search_max_cost", row_search_max_cost, 0.0f, 100.0f);
  CheckInRange("stereo.row_search_min_texture", row_search_min_texture, 0.0f, 255.0f);
  lines.Check();
}

void RelocalisationOptions::Check() const {
  CheckInRange("tracking.relocalisation.candidates", candidates, 1, 1000);
  CheckInRange("tracking.relocalisation.min_matches", min_matches, 6, limits::kMaxKeypoints);
  CheckAboveInRange("tracking.relocalisation.match_ratio", match_ratio, 0.0f, 1.0f);
  CheckAboveInRange("tracking.relocalisation.ransac_error_px", ransac_error_px, 0.0,
                    limits::kMaxImageDistancePx);
  CheckInRange("tracking.relocalisation.ransac_iterations", ransac_iterations, 1, 1'000'000);
  CheckInRange("tracking.relocalisation.min_pnp_inliers", min_pnp_inliers, 4,
               limits::kMaxKeypoints);
  CheckAboveInRange("tracking.relocalisation.min_inliers", min_inliers, 0.0, 1e9);
  CheckInRange("tracking.relocalisation.vocabulary_levels_up", vocabulary_levels_up, 0, 32);
}

void TrackerOptions::Check() const {
  rig.Check();
  stereo.Check();
  pose.Check();
  mapping.Check();
  relocalisation.Check();
  if (dynamic_cells) dynamic.Check();
  loop_closing.Check();
  if (use_imu) imu.Check();
  CheckInRange("tracking.min_init_points", min_init_points, 3, limits::kMaxKeypoints);
  CheckInRange("tracking.denoise_above_noise", denoise_above_noise, 0.0, 255.0);
  CheckInRange("tracking.min_inliers", min_inliers, 3, limits::kMaxKeypoints);
  // doubled on a retry and scaled by lost_search_scale: still far inside int
  CheckAboveInRange("tracking.search_radius_px", search_radius_px, 0.0f,
                    limits::kMaxImageDistancePx);
  CheckInRange("tracking.track_refine_window_px", track_refine_window_px, 0, 50);
  CheckAboveInRange("tracking.track_refine_max_px", track_refine_max_px, 0.0f,
                    limits::kMaxImageDistancePx);
  CheckInRange("tracking.unaligned_sigma_factor", unaligned_sigma_factor, 1.0, 1000.0);
  CheckInRange("tracking.unaligned_min_aligned", unaligned_min_aligned, 0, kMaxCount);
  CheckInRange("tracking.unaligned_max_turn_deg_per_frame", unaligned_max_turn_deg_per_frame, 0.0,
               180.0);
  CheckInRange("tracking.projected_max_frames", projected_max_frames, 0, kMaxCount);
  CheckInRange("tracking.projection_min_inliers", projection_min_inliers, 0, kMaxCount);
  CheckInRange("tracking.projection_search_px", projection_search_px, 0, 64);
  CheckInRange("tracking.projection_cell_px", projection_cell_px, 1, 1000);
  Require(projected_max_frames == 0 || track_refine_window_px >= 2,
          "tracking.projected_max_frames needs tracking.track_refine_window_px >= 2 (the patches "
          "it aligns)");
  CheckAboveInRange("tracking.max_distance_binary", max_distance_binary, 0.0f, 256.0f);
  CheckAboveInRange("tracking.max_distance_float", max_distance_float, 0.0f,
                    limits::kMaxDescriptorDistance);
  CheckAboveInRange("tracking.match_ratio", match_ratio, 0.0f, 1.0f);
  CheckAboveInRange("tracking.line_search_px", line_search_px, 0.0f, limits::kMaxImageDistancePx);
  CheckAboveInRange("tracking.line_max_angle_rad", line_max_angle_rad, 0.0f, limits::kPi);
  CheckAboveInRange("tracking.line_max_lbd", line_max_lbd, 0.0f, limits::kLbdBits);
  CheckInRange("tracking.keyframe_max_frames", keyframe_max_frames, 1, kMaxCount);
  CheckInRange("tracking.keyframe_min_frames", keyframe_min_frames, 0, kMaxCount);
  CheckInRange("tracking.keyframe_min_frames_noisy", keyframe_min_frames_noisy, -1, kMaxCount);
  CheckInRange("tracking.keyframe_min_interval_s", keyframe_min_interval_s, 0.0, 1e6);
  CheckAboveInRange("tracking.keyframe_track_ratio", keyframe_track_ratio, 0.0, 1.0);
  CheckInRange("tracking.keyframe_min_inliers", keyframe_min_inliers, 0, kMaxCount);
  CheckAboveInRange("tracking.close_depth_baselines", close_depth_baselines, 0.0, 1e6);
  CheckAboveInRange("tracking.point_sigma_px", point_sigma_px, 0.0, 1e4);
  CheckAboveInRange("tracking.line_sigma_px", line_sigma_px, 0.0, 1e4);
  CheckInRange("tracking.line_inlier_weight", line_inlier_weight, 0.0, 1e6);
  CheckInRange("tracking.recently_lost_frames", recently_lost_frames, 0, kMaxCount);
  CheckInRange("tracking.lost_velocity_decay", lost_velocity_decay, 0.0, 1.0);
  CheckInRange("tracking.lost_motion_frames", lost_motion_frames, 1, 1000);
  CheckInRange("tracking.lost_search_scale", lost_search_scale, 1.0f, 1000.0f);
  CheckInRange("tracking.lost_reentry_min_point_ratio", lost_reentry_min_point_ratio, 0.0, 1.0);
  CheckInRange("tracking.lost_reentry_confirm_m", lost_reentry_confirm_m, 0.0, 100.0);
  CheckInRange("tracking.new_map_after_lost_frames", new_map_after_lost_frames, 0, kMaxCount);
  CheckInRange("tracking.weak_keyframe_inliers", weak_keyframe_inliers, 0, kMaxCount);
  CheckInRange("tracking.weak_keyframe_frames", weak_keyframe_frames, 1, kMaxCount);
  CheckInRange("tracking.lines_on_demand_inliers", lines_on_demand_inliers, 0, kMaxCount);
  CheckInRange("tracking.frame_rate_hz", frame_rate_hz, 0.0, 1e5);
  CheckInRange("tracking.reference_rate_hz", reference_rate_hz, 0.0, 1e5);
  CheckInRange("tracking.reference_focal_px", reference_focal_px, 0.0, 1e7);
}

}  // namespace slslam
