// Every option struct's Check() against a table of its fields: per field, generated bad values
// (NaN, infinities, each side of its range, the extremes of int) must throw std::invalid_argument
// naming the field, never crash, and values on the range's edges must pass. The count of bad
// values is printed, as the Python robustness suite prints its own.
#include <cmath>
#include <functional>
#include <iostream>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include <gtest/gtest.h>

#include "slslam/core/check.h"
#include "slslam/features/descriptor_matcher.h"
#include "slslam/features/dynamic_cell_filter.h"
#include "slslam/features/grid_limit.h"
#include "slslam/features/line_extractor.h"
#include "slslam/features/line_matcher.h"
#include "slslam/features/orb_extractor.h"
#include "slslam/features/point_line_association.h"
#include "slslam/mapping/local_mapper.h"
#include "slslam/optimization/bundle_adjustment.h"
#include "slslam/optimization/pose_optimizer.h"
#include "slslam/place/vocabulary.h"
#include "slslam/tracking/tracker.h"

namespace slslam {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kIntMin = std::numeric_limits<int>::min();
constexpr double kIntMax = std::numeric_limits<int>::max();
const double kPi = static_cast<double>(limits::kPi);

// One field: the name its message must carry, its allowed range and how to write a value.
template <typename Options>
struct Field {
  std::string name;
  double low, high;
  bool low_open, high_open, integer;
  std::function<void(Options&, double)> set;
};

// FIELD(member, "name", low, high, "[]" | "(]" | "()" | "[)")
#define FIELD(member, name, low, high, brackets)                                               \
  Field<Opts> {                                                                                \
    name, low, high, (brackets)[0] == '(', (brackets)[1] == ')',                               \
        std::is_integral_v<std::decay_t<decltype(Opts{}.member)>>,                             \
        [](Opts& o, double v) { o.member = static_cast<std::decay_t<decltype(o.member)>>(v); } \
  }

int bad_values_rejected = 0;
int good_values_accepted = 0;
int structs_checked = 0;

// Bad values for a field: non-finite, each side just outside its range, far outside.
std::vector<double> BadValues(double low, double high, bool low_open, bool high_open,
                              bool integer) {
  std::vector<double> bad;
  if (integer) {
    if (low > kIntMin) bad.insert(bad.end(), {low - 1, kIntMin, std::max(kIntMin, low - 1000)});
    if (high < kIntMax) bad.insert(bad.end(), {high + 1, kIntMax, std::min(kIntMax, high + 1000)});
    return bad;
  }
  bad.push_back(kNaN);
  const double step_low = std::max(1e-3, 1e-3 * std::abs(low));
  const double step_high = std::max(1e-3, 1e-3 * std::abs(high));
  if (std::isfinite(low)) {
    bad.insert(bad.end(), {-kInf, -1e30, low_open ? low : low - step_low});
    if (low_open && low != 0.0) bad.push_back(low - step_low);
  }
  if (std::isfinite(high)) {
    bad.insert(bad.end(), {kInf, 1e30, high_open ? high : high + step_high});
  }
  if (!std::isfinite(low) && low_open) bad.push_back(-kInf);  // "finite" options
  if (!std::isfinite(high) && high_open) bad.push_back(kInf);
  return bad;
}

std::vector<double> GoodValues(double low, double high, bool low_open, bool high_open,
                               bool integer) {
  const double lo = std::isfinite(low) ? low : -1e6;
  const double hi = std::isfinite(high) ? high : 1e6;
  const double step = integer ? 1.0 : std::max(1e-3, 1e-6 * (hi - lo));
  std::vector<double> good = {low_open ? lo + step : lo, high_open ? hi - step : hi};
  good.push_back(integer ? std::round(0.5 * (lo + hi)) : 0.5 * (lo + hi));
  return good;
}

// `enter` is where the options come in (Check() or a constructor); `base` the valid options
// each case starts from.
template <typename Opts>
void RunTable(const char* family, const std::vector<Field<Opts>>& fields,
              const std::function<void(const Opts&)>& enter, const Opts& base = Opts{}) {
  ++structs_checked;
  ASSERT_NO_THROW(enter(base)) << family << ": the defaults must pass";
  for (const Field<Opts>& f : fields) {
    for (double v : BadValues(f.low, f.high, f.low_open, f.high_open, f.integer)) {
      Opts o = base;
      f.set(o, v);
      try {
        enter(o);
        ADD_FAILURE() << family << ": " << f.name << " = " << v << " accepted";
      } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find(f.name), std::string::npos)
            << family << ": the message for " << f.name << " = " << v << " is: " << e.what();
        ++bad_values_rejected;
      }
    }
    for (double v : GoodValues(f.low, f.high, f.low_open, f.high_open, f.integer)) {
      Opts o = base;
      f.set(o, v);
      EXPECT_NO_THROW(enter(o)) << family << ": " << f.name << " = " << v << " refused";
      ++good_values_accepted;
    }
  }
}

template <typename Opts>
void CheckOnly(const Opts& o) {
  o.Check();
}

TEST(OptionsCheck, FeatureOptions) {
  {
    using Opts = OrbOptions;
    RunTable<Opts>("OrbOptions",
                   {FIELD(max_features, "orb.max_features", 1, 1e6, "[]"),
                    FIELD(scale_factor, "orb.scale_factor", 1, 4, "(]"),
                    FIELD(num_levels, "orb.num_levels", 1, 32, "[]"),
                    FIELD(fast_threshold, "fast_threshold", 7, 255, "[]"),
                    FIELD(edge_threshold, "orb.edge_threshold", 0, 1000, "[]"),
                    FIELD(min_fast_threshold, "orb.min_fast_threshold", 1, 20, "[]"),
                    FIELD(cell_size_px, "orb.cell_size_px", 8, 1 << 16, "[]"),
                    FIELD(denoise_above_noise, "orb.denoise_above_noise", -kInf, kInf, "()")},
                   CheckOnly<Opts>);
  }
  {
    using Opts = MatchOptions;
    RunTable<Opts>("MatchOptions",
                   {FIELD(max_distance, "match.max_distance", 0, 1e6, "(]"),
                    FIELD(ratio, "match.ratio", 0, 1, "(]")},
                   CheckOnly<Opts>);
  }
  {
    using Opts = GuidedMatchOptions;
    RunTable<Opts>("GuidedMatchOptions",
                   {FIELD(radius_px, "guided.radius_px", 0, 1e5, "(]"),
                    FIELD(max_distance, "guided.max_distance", 0, 1e6, "(]"),
                    FIELD(ratio, "guided.ratio", 0, 1, "(]")},
                   CheckOnly<Opts>);
  }
  {
    using Opts = DynamicCellOptions;
    RunTable<Opts>("DynamicCellOptions",
                   {FIELD(cell_size_px, "dynamic.cell_size_px", 4, 1 << 16, "[]"),
                    FIELD(sigma_px, "dynamic.sigma_px", 0, 1e6, "(]"),
                    FIELD(alpha, "dynamic.alpha", 0, 1, "(]"),
                    FIELD(threshold, "dynamic.threshold", 0, 1, "[]")},
                   CheckOnly<Opts>);
  }
  {
    using Opts = GridLimitOptions;
    RunTable<Opts>("GridLimitOptions",
                   {FIELD(cell_size_px, "grid.cell_size_px", 4, 1 << 16, "[]"),
                    FIELD(max_per_cell, "grid.max_per_cell", 1, 1e6, "[]"),
                    FIELD(strong_score, "grid.strong_score", -kInf, kInf, "[]")},
                   CheckOnly<Opts>);
  }
  {
    using Opts = LinePreprocessOptions;
    RunTable<Opts>("LinePreprocessOptions",
                   {FIELD(length_ratio, "lines.length_ratio", 0, 1, "()"),
                    FIELD(theta_min_rad, "lines.theta_min_rad", 0, kPi, "(]"),
                    FIELD(xi_d_px, "lines.xi_d_px", 0, 1e5, "(]"),
                    FIELD(max_gap_px, "lines.max_gap_px", 0, kInf, "[]")},
                   CheckOnly<Opts>);
  }
  {
    using Opts = LineExtractorOptions;
    RunTable<Opts>("LineExtractorOptions",
                   {FIELD(detection_scale, "lines.detection_scale", 0, 1, "(]"),
                    FIELD(preprocess.xi_d_px, "lines.xi_d_px", 0, 1e5, "(]")},
                   CheckOnly<Opts>);
  }
  {
    using Opts = LineMatchOptions;
    RunTable<Opts>("LineMatchOptions",
                   {FIELD(min_votes, "line_match.min_votes", 1, 1e6, "[]"),
                    FIELD(max_lbd_distance, "line_match.max_lbd_distance", 0, 256, "(]"),
                    FIELD(max_angle_rad, "line_match.max_angle_rad", 0, kPi, "(]")},
                   CheckOnly<Opts>);
  }
  {
    using Opts = StereoLineOptions;
    RunTable<Opts>("StereoLineOptions",
                   {FIELD(min_row_overlap, "stereo_lines.min_row_overlap", 0, 1, "(]"),
                    FIELD(max_lbd_distance, "stereo_lines.max_lbd_distance", 0, 256, "(]"),
                    FIELD(max_angle_rad, "stereo_lines.max_angle_rad", 0, kPi, "(]"),
                    FIELD(min_angle_from_horizontal_rad,
                          "stereo_lines.min_angle_from_horizontal_rad", 0, kPi / 2, "[]"),
                    FIELD(min_disparity_px, "stereo_lines.min_disparity_px", 0, 1e5, "[]")},
                   CheckOnly<Opts>);
  }
  {
    using Opts = AssociationOptions;
    RunTable<Opts>("AssociationOptions",
                   {FIELD(cell_size_px, "association.cell_size_px", 4, 1 << 16, "[]"),
                    FIELD(layers, "association.layers", 0, 1000, "[]"),
                    FIELD(max_distance_px, "association.max_distance_px", 0, 1e5, "(]")},
                   CheckOnly<Opts>);
  }
  {
    using Opts = VocabularyOptions;
    RunTable<Opts>(
        "VocabularyOptions",
        {FIELD(branching, "VocabularyOptions.branching", 2, 100, "[]"),
         FIELD(levels, "levels", 1, 8, "[]"),
         FIELD(kmeans_iterations, "VocabularyOptions.kmeans_iterations", 1, 10000, "[]")},
        CheckOnly<Opts>);
  }
}

StereoRig TestRig() { return StereoRig{PinholeCamera{400.0, 400.0, 320.0, 240.0, 640, 480}, 0.1}; }

TEST(OptionsCheck, OptimisationAndMappingOptions) {
  const StereoRig rig = TestRig();
  {
    using Opts = PoseOptimizerOptions;
    // Through the optimiser itself: its options are checked before any work.
    RunTable<Opts>("PoseOptimizerOptions",
                   {FIELD(rounds, "rounds", 3, 100, "[]"),
                    FIELD(iterations_per_round, "pose.iterations_per_round", 1, 10000, "[]"),
                    FIELD(robust_rounds, "pose.robust_rounds", 0, 4, "[]"),
                    FIELD(chi2_mono, "pose.chi2_mono", 0, 1e6, "(]"),
                    FIELD(chi2_stereo, "pose.chi2_stereo", 0, 1e6, "(]"),
                    FIELD(chi2_line, "pose.chi2_line", 0, 1e6, "(]"),
                    FIELD(line_angle_weight, "pose.line_angle_weight", 0, 1e6, "[]"),
                    FIELD(line_weight, "pose.line_weight", 0, 1e6, "[]")},
                   CheckOnly<Opts>);
    PoseOptimizerOptions bad;
    bad.line_weight = kNaN;
    EXPECT_THROW(OptimizePose(rig, Rigid3d(), {}, {}, bad), std::invalid_argument);
  }
  {
    using Opts = BundleAdjustmentOptions;
    RunTable<Opts>(
        "BundleAdjustmentOptions",
        {FIELD(robust_iterations, "ba.robust_iterations", 0, 10000, "[]"),
         FIELD(refine_iterations, "ba.refine_iterations", 0, 10000, "[]"),
         FIELD(chi2_mono, "ba.chi2_mono", 0, 1e6, "(]"),
         FIELD(chi2_stereo, "ba.chi2_stereo", 0, 1e6, "(]"),
         FIELD(chi2_line, "ba.chi2_line", 0, 1e6, "(]"),
         FIELD(line_angle_weight, "ba.line_angle_weight", 0, 1e6, "[]"),
         FIELD(line_weight, "ba.line_weight", 0, 1e6, "[]"),
         FIELD(line_prior_weight, "ba.line_prior_weight", 0, 1e6, "[]"),
         FIELD(line_min_information_per_rad2, "ba.line_min_information_per_rad2", 0, 1e12, "[]")},
        CheckOnly<Opts>);
    BundleAdjustmentOptions bad;
    bad.line_weight = kInf;
    BaProblem problem;
    EXPECT_THROW(SolveBundleAdjustment(rig, &problem, bad), std::invalid_argument);
  }
  {
    using Opts = LocalMapperOptions;
    // Through the local mapper's constructor, where the options enter.
    RunTable<Opts>(
        "LocalMapperOptions",
        {FIELD(local_keyframes, "mapping.local_keyframes", 1, 10000, "[]"),
         FIELD(max_fixed_keyframes, "mapping.max_fixed_keyframes", 0, 10000, "[]"),
         FIELD(redundant_ratio, "mapping.redundant_ratio", 0, 1, "(]"),
         FIELD(redundant_observers, "mapping.redundant_observers", 1, 1000, "[]"),
         FIELD(min_found_ratio, "mapping.min_found_ratio", 0, 1, "[]"),
         FIELD(point_sigma_px, "mapping.point_sigma_px", 0, 1e4, "(]"),
         FIELD(line_sigma_px, "mapping.line_sigma_px", 0, 1e4, "(]"),
         FIELD(ba.line_weight, "ba.line_weight", 0, 1e6, "[]"),
         FIELD(triangulation.neighbours, "triangulation.neighbours", 0, 10000, "[]"),
         FIELD(triangulation.epipolar_px, "triangulation.epipolar_px", 0, 1e5, "(]"),
         FIELD(triangulation.max_distance_binary, "triangulation.max_distance_binary", 0, 256,
               "(]"),
         FIELD(triangulation.max_distance_float, "triangulation.max_distance_float", 0, 1e6, "(]"),
         FIELD(triangulation.ratio, "triangulation.ratio", 0, 1, "(]"),
         FIELD(triangulation.min_parallax_deg, "triangulation.min_parallax_deg", 0, 180, "[]"),
         FIELD(triangulation.max_depth_baselines, "triangulation.max_depth_baselines", 0, 1e6,
               "(]"),
         FIELD(triangulation.chi2, "triangulation.chi2", 0, 1e6, "(]"),
         FIELD(triangulation.sigma_px, "triangulation.sigma_px", 0, 1e4, "(]"),
         FIELD(triangulation.line_sigma_px, "triangulation.line_sigma_px", 0, 1e4, "(]"),
         FIELD(triangulation.line_max_lbd, "triangulation.line_max_lbd", 0, 256, "(]"),
         FIELD(triangulation.line_ratio, "triangulation.line_ratio", 0, 1, "(]"),
         FIELD(triangulation.min_plane_angle_deg, "triangulation.min_plane_angle_deg", 0, 90,
               "[]")},
        [&rig](const Opts& o) { LocalMapper mapper(rig, o, true); });
  }
}

TEST(OptionsCheck, TrackingOptions) {
  TrackerOptions base;
  base.rig = TestRig();
  using Opts = TrackerOptions;
  const std::function<void(const Opts&)> construct = [](const Opts& o) { Tracker tracker(o); };
  RunTable<Opts>(
      "TrackerOptions",
      {FIELD(min_init_points, "tracking.min_init_points", 3, 1e6, "[]"),
       FIELD(min_inliers, "tracking.min_inliers", 3, 1e6, "[]"),
       FIELD(search_radius_px, "tracking.search_radius_px", 0, 1e5, "(]"),
       FIELD(track_refine_window_px, "tracking.track_refine_window_px", 0, 50, "[]"),
       FIELD(track_refine_max_px, "tracking.track_refine_max_px", 0, 1e5, "(]"),
       FIELD(unaligned_sigma_factor, "tracking.unaligned_sigma_factor", 1, 1000, "[]"),
       FIELD(unaligned_min_aligned, "tracking.unaligned_min_aligned", 0, 1e9, "[]"),
       FIELD(unaligned_max_turn_deg_per_frame, "tracking.unaligned_max_turn_deg_per_frame", 0, 180,
             "[]"),
       FIELD(projected_max_frames, "tracking.projected_max_frames", 0, 1e9, "[]"),
       FIELD(projection_min_inliers, "tracking.projection_min_inliers", 0, 1e9, "[]"),
       FIELD(projection_search_px, "tracking.projection_search_px", 0, 64, "[]"),
       FIELD(projection_cell_px, "tracking.projection_cell_px", 1, 1000, "[]"),
       FIELD(max_distance_binary, "tracking.max_distance_binary", 0, 256, "(]"),
       FIELD(max_distance_float, "tracking.max_distance_float", 0, 1e6, "(]"),
       FIELD(match_ratio, "tracking.match_ratio", 0, 1, "(]"),
       FIELD(line_search_px, "tracking.line_search_px", 0, 1e5, "(]"),
       FIELD(line_max_angle_rad, "tracking.line_max_angle_rad", 0, kPi, "(]"),
       FIELD(line_max_lbd, "tracking.line_max_lbd", 0, 256, "(]"),
       FIELD(keyframe_max_frames, "tracking.keyframe_max_frames", 1, 1e9, "[]"),
       FIELD(keyframe_min_frames, "tracking.keyframe_min_frames", 0, 1e9, "[]"),
       FIELD(keyframe_min_frames_noisy, "tracking.keyframe_min_frames_noisy", -1, 1e9, "[]"),
       FIELD(keyframe_min_interval_s, "tracking.keyframe_min_interval_s", 0, 1e6, "[]"),
       FIELD(keyframe_track_ratio, "tracking.keyframe_track_ratio", 0, 1, "(]"),
       FIELD(keyframe_min_inliers, "tracking.keyframe_min_inliers", 0, 1e9, "[]"),
       FIELD(close_depth_baselines, "tracking.close_depth_baselines", 0, 1e6, "(]"),
       FIELD(point_sigma_px, "tracking.point_sigma_px", 0, 1e4, "(]"),
       FIELD(line_sigma_px, "tracking.line_sigma_px", 0, 1e4, "(]"),
       FIELD(line_inlier_weight, "tracking.line_inlier_weight", 0, 1e6, "[]"),
       FIELD(recently_lost_frames, "tracking.recently_lost_frames", 0, 1e9, "[]"),
       FIELD(lost_velocity_decay, "tracking.lost_velocity_decay", 0, 1, "[]"),
       FIELD(lost_search_scale, "tracking.lost_search_scale", 1, 1000, "[]"),
       FIELD(lost_motion_frames, "tracking.lost_motion_frames", 1, 1000, "[]"),
       FIELD(lost_reentry_min_point_ratio, "tracking.lost_reentry_min_point_ratio", 0, 1, "[]"),
       FIELD(lost_reentry_confirm_m, "tracking.lost_reentry_confirm_m", 0, 100, "[]"),
       FIELD(new_map_after_lost_frames, "tracking.new_map_after_lost_frames", 0, 1e9, "[]"),
       FIELD(weak_keyframe_inliers, "tracking.weak_keyframe_inliers", 0, 1e9, "[]"),
       FIELD(weak_keyframe_frames, "tracking.weak_keyframe_frames", 1, 1e9, "[]"),
       FIELD(lines_on_demand_inliers, "tracking.lines_on_demand_inliers", 0, 1e9, "[]"),
       FIELD(frame_rate_hz, "tracking.frame_rate_hz", 0, 1e5, "[]"),
       FIELD(reference_rate_hz, "tracking.reference_rate_hz", 0, 1e5, "[]"),
       FIELD(reference_focal_px, "tracking.reference_focal_px", 0, 1e7, "[]"),
       // nested structs, reached through the tracker's constructor
       FIELD(rig.baseline_m, "stereo baseline", 0, 1000, "(]"),
       FIELD(rig.camera.fx, "camera fx", 0, 1e7, "(]"),
       FIELD(rig.camera.width, "camera image size", 1, 1 << 15, "[]"),
       FIELD(pose.line_weight, "pose.line_weight", 0, 1e6, "[]"),
       FIELD(pose.line_angle_weight, "pose.line_angle_weight", 0, 1e6, "[]"),
       FIELD(mapping.local_keyframes, "mapping.local_keyframes", 1, 10000, "[]"),
       FIELD(mapping.ba.line_weight, "ba.line_weight", 0, 1e6, "[]"),
       FIELD(stereo.max_row_offset_px, "stereo.max_row_offset_px", 0, 1e5, "[]"),
       FIELD(stereo.min_disparity_px, "disparity_px", 0, 120, "()"),
       FIELD(stereo.max_distance_binary, "stereo.max_distance_binary", 0, 256, "(]"),
       FIELD(stereo.max_distance_float, "stereo.max_distance_float", 0, 1e6, "(]"),
       FIELD(stereo.ratio, "stereo.ratio", 0, 1, "(]"),
       FIELD(stereo.max_depth_baselines, "tracking.max_depth_baselines", 0, 1e6, "(]"),
       FIELD(stereo.subpixel_window, "stereo.subpixel_window", 0, 100, "[]"),
       FIELD(stereo.subpixel_search, "stereo.subpixel_search", 1, 1000, "[]"),
       FIELD(stereo.row_search_window, "stereo.row_search_window", 1, 50, "[]"),
       FIELD(stereo.row_search_ratio, "stereo.row_search_ratio", 0, 1, "(]"),
       FIELD(stereo.row_search_max_cost, "stereo.row_search_max_cost", 0, 100, "(]"),
       FIELD(stereo.row_search_min_texture, "stereo.row_search_min_texture", 0, 255, "[]"),
       FIELD(denoise_above_noise, "tracking.denoise_above_noise", 0, 255, "[]"),
       FIELD(stereo.lines.min_row_overlap, "stereo_lines.min_row_overlap", 0, 1, "(]"),
       FIELD(relocalisation.candidates, "tracking.relocalisation.candidates", 1, 1000, "[]"),
       FIELD(relocalisation.min_matches, "tracking.relocalisation.min_matches", 6, 1e6, "[]"),
       FIELD(relocalisation.match_ratio, "tracking.relocalisation.match_ratio", 0, 1, "(]"),
       FIELD(relocalisation.ransac_error_px, "tracking.relocalisation.ransac_error_px", 0, 1e5,
             "(]"),
       FIELD(relocalisation.ransac_iterations, "tracking.relocalisation.ransac_iterations", 1, 1e6,
             "[]"),
       FIELD(relocalisation.min_pnp_inliers, "tracking.relocalisation.min_pnp_inliers", 4, 1e6,
             "[]"),
       FIELD(relocalisation.min_inliers, "tracking.relocalisation.min_inliers", 0, 1e9, "(]"),
       FIELD(relocalisation.vocabulary_levels_up, "tracking.relocalisation.vocabulary_levels_up", 0,
             32, "[]"),
       FIELD(imu.time_offset_s, "tracking.imu.time_offset_s", -10, 10, "[]"),
       FIELD(imu.gyro_noise_density, "tracking.imu.gyro_noise_density", 0, 1, "[]"),
       FIELD(imu.acc_noise_density, "tracking.imu.acc_noise_density", 0, 1, "[]"),
       FIELD(imu.gyro_random_walk, "tracking.imu.gyro_random_walk", 0, 1, "[]"),
       FIELD(imu.acc_random_walk, "tracking.imu.acc_random_walk", 0, 1, "[]"),
       FIELD(imu.gravity_mps2, "tracking.imu.gravity_mps2", 0, 20, "()"),
       FIELD(imu.gravity_tolerance_mps2, "tracking.imu.gravity_tolerance_mps2", 0, 100, "(]"),
       FIELD(imu.acc_bias_prior_mps2, "tracking.imu.acc_bias_prior_mps2", 0, 100, "(]"),
       FIELD(imu.gyro_bias_sigma_radps, "tracking.imu.gyro_bias_sigma_radps", 0, 1, "(]"),
       FIELD(imu.window_s, "tracking.imu.window_s", 1, 1000, "[]"),          // >= min_window_s
       FIELD(imu.min_window_s, "tracking.imu.min_window_s", 0.05, 3, "[]"),  // <= window_s
       FIELD(imu.refine_after_s, "tracking.imu.refine_after_s", 0, 1e6, "[]"),
       FIELD(imu.refine_min_path_m, "tracking.imu.refine_min_path_m", 0, 1e6, "[]"),
       FIELD(imu.max_sample_gap_s, "tracking.imu.max_sample_gap_s", 0, 10, "(]"),
       FIELD(imu.lost_sigma_fraction, "tracking.imu.lost_sigma_fraction", 0, 10, "[]"),
       FIELD(imu.lost_sigma_min_m, "tracking.imu.lost_sigma_min_m", 0, 1e6, "[]"),
       FIELD(imu.max_gap_s, "tracking.imu.max_gap_s", 0, 1e6, "[]"),
       FIELD(imu.nonholonomic_max_side_ratio, "tracking.imu.nonholonomic_max_side_ratio", 0, 1,
             "[]"),
       FIELD(imu.nonholonomic_sigma_mps, "tracking.imu.nonholonomic_sigma_mps", 0, 100, "(]"),
       FIELD(imu.zero_velocity_max_statistic, "tracking.imu.zero_velocity_max_statistic", 0, 1e6,
             "[]"),
       FIELD(imu.zero_velocity_sigma_mps, "tracking.imu.zero_velocity_sigma_mps", 0, 100, "(]"),
       FIELD(imu.flow_min_inliers, "tracking.imu.flow_min_inliers", 0, 100000, "[]"),
       FIELD(imu.flow_sigma_mps, "tracking.imu.flow_sigma_mps", 0, 100, "(]"),
       FIELD(imu.weak_update_min_inliers, "tracking.imu.weak_update_min_inliers", 0, 100000, "[]"),
       FIELD(imu.weak_update_min_lines, "tracking.imu.weak_update_min_lines", 0, 100000, "[]"),
       FIELD(imu.keyframe_min_stereo_lines, "tracking.imu.keyframe_min_stereo_lines", 0, 100000,
             "[]"),
       FIELD(imu.keyframe_interval_s, "tracking.imu.keyframe_interval_s", 0, 1e6, "[]"),
       FIELD(imu.local_ba_keyframes, "tracking.imu.local_ba_keyframes", 0, 1000, "[]"),
       FIELD(imu.visual_information_scale, "tracking.imu.visual_information_scale", 1e-6, 1e6,
             "[]")},
      construct, base);
}

TEST(OptionsCheck, CameraGeometryThatCannotBeACamera) {
  // RadTanCamera: distortion coefficients beyond any lens (the k1 = 1e6).
  using Opts = RadTanCamera;
  Opts base;
  base.pinhole = PinholeCamera{400.0, 400.0, 320.0, 240.0, 640, 480};
  RunTable<Opts>("RadTanCamera",
                 {FIELD(distortion[0], "camera distortion coefficient", -100, 100, "[]"),
                  FIELD(distortion[3], "camera distortion coefficient", -100, 100, "[]"),
                  FIELD(pinhole.fy, "camera fy", 0, 1e7, "(]"),
                  FIELD(pinhole.height, "camera image size", 1, 1 << 15, "[]")},
                 CheckOnly<Opts>, base);
}

// Last in the file (gtest runs a file's tests in order): the count, as the Python suite prints.
TEST(OptionsCheck, ZzCount) {
  std::cout << "option checks: " << bad_values_rejected << " generated bad values rejected, "
            << good_values_accepted << " edge values accepted, " << structs_checked
            << " option tables\n";
  if (structs_checked < 15) GTEST_SKIP() << "only part of the tables ran";
  EXPECT_GE(bad_values_rejected, 500);
}

#undef FIELD

}  // namespace
}  // namespace slslam
