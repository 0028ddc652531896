// slslam._core tracking: the stereo point-line tracker with local mapping. Python hands over the
// images and the point features (SuperPoint runs in Python through onnxruntime, ORB in C++);
// line extraction, stereo matching, tracking and mapping run here with the GIL released.
#include <memory>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "bindings/image_conversion.h"
#include "slslam/core/check.h"
#include "slslam/features/line_extractor.h"
#include "slslam/features/orb_extractor.h"
#include "slslam/pipeline/tracker_session.h"
#include "slslam/tracking/stereo_frontend.h"
#include "slslam/tracking/tracker.h"

namespace py = pybind11;

namespace slslam::bindings {
namespace {

using PixelArray = Eigen::Matrix<float, Eigen::Dynamic, 2, Eigen::RowMajor>;

Keypoints MakeKeypoints(const PixelArray& uv, const py::array& descriptors, const char* side) {
  Keypoints k;
  k.uv = uv;
  const cv::Mat d = WrapDescriptors(descriptors);
  SLSLAM_CHECK(d.rows == uv.rows(), side, " keypoints: ", uv.rows(), " positions but ", d.rows,
               " descriptor rows");
  k.descriptors = d.clone();  // the frame outlives the numpy array
  k.score = Eigen::VectorXf::Ones(uv.rows());
  k.octave = Eigen::VectorXi::Zero(uv.rows());
  return k;
}

// The map and the counters as the dict slslam.Tracker.map reads.
py::dict MapDict(const SessionMap& session) {
  const MapExport& m = session.map;
  const LocalMappingStats& s = session.mapping;
  const TrackingStats& t = session.tracking;
  const Tracker::InertialReport& imu = session.imu;
  const LoopClosingStats& loops = session.loops;
  py::dict out;
  out["points"] = m.points;
  out["lines"] = m.lines;
  out["point_map"] = m.point_map;
  out["line_map"] = m.line_map;
  out["keyframes"] = m.keyframes;
  out["maps"] = session.maps;
  out["keyframes_processed"] = s.keyframes_processed;
  out["keyframes_culled"] = s.keyframes_culled;
  out["points_culled"] = s.points_culled;
  out["lines_culled"] = s.lines_culled;
  out["points_triangulated"] = s.points_triangulated;
  out["lines_triangulated"] = s.lines_triangulated;
  out["local_mapping_ms"] = s.total_ba_ms;
  out["local_ba_interrupted"] = s.ba_interrupted;
  out["local_ba_solve_ms"] = s.ba_solve_ms;
  out["local_ba_iterations"] = s.ba_iterations;
  out["local_ba_rejected_steps"] = s.ba_rejected_steps;
  out["local_ba_inertial_factors"] = s.ba_inertial_factors;
  out["inertial_frames"] = t.inertial_frames;
  out["inertial_weak_updates"] = t.inertial_weak_updates;
  out["inertial_keyframes"] = t.inertial_keyframes;
  py::dict imu_out;
  imu_out["has_imu"] = imu.has_imu;
  imu_out["initialised"] = imu.initialised;
  imu_out["first_pose_t_ns"] = imu.first_pose_t_ns;  // (None: never)
  imu_out["first_init_t_ns"] = imu.first_init_t_ns;
  imu_out["initialisations"] = imu.initialisations;
  imu_out["refinements"] = imu.refinements;
  imu_out["rejected_refinements"] = imu.rejected_refinements;
  imu_out["nonholonomic_updates"] = imu.nonholonomic_updates;
  imu_out["zero_velocity_updates"] = imu.zero_velocity_updates;
  imu_out["flow_updates"] = imu.flow_updates;
  imu_out["travel_side_ratio"] = imu.travel_side_ratio;  // (-1: not measured)
  imu_out["last_failure"] = imu.last_failure;
  imu_out["gyro_bias_radps"] = imu.gyro_bias;
  imu_out["acc_bias_mps2"] = imu.acc_bias;
  imu_out["g_world_mps2"] = imu.g_world;
  out["imu"] = imu_out;
  out["relocalisations"] = t.relocalisations;
  out["relocalisation_attempts"] = t.relocalisation_attempts;
  out["maps_started"] = t.maps_started;
  out["maps_resumed"] = t.maps_resumed;
  out["line_frames"] = t.line_frames;
  out["loop_keyframes_checked"] = loops.keyframes_checked;
  out["loop_candidates_verified"] = loops.candidates_verified;
  out["loops_detected"] = loops.loops_detected;
  out["loops_rejected"] = loops.loops_rejected;
  out["loops_accepted"] = loops.loops_accepted;
  out["merges"] = loops.merges;
  out["merges_in_yaw_and_position"] = loops.merges_in_yaw_and_position;
  out["global_ba_runs"] = loops.global_ba_runs;
  out["loop_closing_ms"] = loops.loop_ms;
  out["global_ba_ms"] = loops.global_ba_ms;
  out["global_ba_lock_ms"] = loops.global_ba_lock_ms;
  out["global_ba_cancelled"] = loops.global_ba_cancelled;
  out["welding_ba_runs"] = loops.welding_ba_runs;
  out["welding_ba_ms"] = loops.welding_ba_ms;
  py::list loop_events;
  for (const LoopEvent& e : session.loop_events) {
    py::dict d;
    d["frame_index"] = e.frame_index;
    d["candidate_frame_index"] = e.candidate_frame_index;
    d["merge"] = e.merge;
    d["correction_m"] = e.correction_m;
    loop_events.append(d);
  }
  out["loop_events"] = loop_events;
  return out;
}

// The trajectory as arrays (index, t_ns, map_index, cam_from_world rotation, translation).
py::dict TrajectoryDict(const std::vector<FramePose>& poses) {
  const auto n = static_cast<py::ssize_t>(poses.size());
  py::array_t<int> index(n), map_index(n);
  py::array_t<int64_t> t_ns(n);
  py::array_t<double> R_cw({n, py::ssize_t{3}, py::ssize_t{3}});
  py::array_t<double> t_cw({n, py::ssize_t{3}});
  auto idx = index.mutable_unchecked<1>();
  auto mi = map_index.mutable_unchecked<1>();
  auto ts = t_ns.mutable_unchecked<1>();
  auto R = R_cw.mutable_unchecked<3>();
  auto t = t_cw.mutable_unchecked<2>();
  for (py::ssize_t i = 0; i < n; ++i) {
    const FramePose& f = poses[i];
    idx(i) = f.index;
    mi(i) = f.map_index;
    ts(i) = f.t_ns;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) R(i, r, c) = f.cam_from_world.rotation(r, c);
      t(i, r) = f.cam_from_world.translation(r);
    }
  }
  py::dict out;
  out["index"] = index;
  out["t_ns"] = t_ns;
  out["map_index"] = map_index;
  out["cam_from_world_rotation"] = R_cw;
  out["cam_from_world_translation"] = t_cw;
  return out;
}

// TrackerSession::Prepare from numpy arrays: converted under the GIL, built without it.
std::shared_ptr<PreparedFrame> PrepareFromArrays(
    const TrackerSession& session, int index, int64_t t_ns, const py::array& left_image,
    const py::array& right_image, const PixelArray& left_uv, const py::array& left_descriptors,
    const PixelArray& right_uv, const py::array& right_descriptors,
    const std::shared_ptr<LeftLines>& left_lines, bool keypoints_pending, bool noisy,
    bool denoised) {
  const cv::Mat left = WrapGray(left_image, "left image");
  const cv::Mat right = WrapGray(right_image, "right image");
  const Keypoints kl = MakeKeypoints(left_uv, left_descriptors, "left");
  const Keypoints kr = MakeKeypoints(right_uv, right_descriptors, "right");
  py::gil_scoped_release release;
  return session.Prepare(index, t_ns, left, right, kl, kr, left_lines, keypoints_pending, noisy,
                         denoised);
}

// The rectified stereo rig.
void BindRig(py::module_& m) {
  py::class_<StereoRig>(m, "StereoRig", "Rectified stereo pair: left intrinsics and baseline.")
      .def(py::init<>())
      .def(py::init([](const PinholeCamera& camera, double baseline_m) {
             StereoRig rig{camera, baseline_m};
             rig.Check();
             return rig;
           }),
           py::arg("camera"), py::arg("baseline_m"))
      .def_readwrite("camera", &StereoRig::camera)
      .def_readwrite("baseline_m", &StereoRig::baseline_m)
      .def("check", &StereoRig::Check);
}

// Options of pose optimisation, bundle adjustment, triangulation, local mapping, stereo.
void BindSolverOptions(py::module_& m) {
  py::class_<PoseOptimizerOptions>(m, "PoseOptimizerOptions", "Motion-only bundle adjustment.")
      .def(py::init<>())
      .def_readwrite("rounds", &PoseOptimizerOptions::rounds)
      .def_readwrite("iterations_per_round", &PoseOptimizerOptions::iterations_per_round)
      .def_readwrite("line_angle_weight", &PoseOptimizerOptions::line_angle_weight)
      .def_readwrite("line_weight", &PoseOptimizerOptions::line_weight)
      .def_readwrite("own_solver", &PoseOptimizerOptions::own_solver)
      .def("check", &PoseOptimizerOptions::Check);
  py::class_<BundleAdjustmentOptions>(m, "BundleAdjustmentOptions", "Local bundle adjustment.")
      .def(py::init<>())
      .def_readwrite("robust_iterations", &BundleAdjustmentOptions::robust_iterations)
      .def_readwrite("refine_iterations", &BundleAdjustmentOptions::refine_iterations)
      .def_readwrite("line_angle_weight", &BundleAdjustmentOptions::line_angle_weight)
      .def_readwrite("line_weight", &BundleAdjustmentOptions::line_weight)
      .def_readwrite("line_prior_weight", &BundleAdjustmentOptions::line_prior_weight)
      .def_readwrite("dogleg_with_lines", &BundleAdjustmentOptions::dogleg_with_lines)
      .def_readwrite("line_min_information_per_rad2",
                     &BundleAdjustmentOptions::line_min_information_per_rad2)
      .def_readwrite("own_solver", &BundleAdjustmentOptions::own_solver)
      .def("check", &BundleAdjustmentOptions::Check);
  py::class_<TriangulationOptions>(m, "TriangulationOptions",
                                   "New landmarks from pairs of keyframes (local mapping).")
      .def(py::init<>())
      .def_readwrite("neighbours", &TriangulationOptions::neighbours)
      .def_readwrite("points", &TriangulationOptions::points)
      .def_readwrite("min_parallax_deg", &TriangulationOptions::min_parallax_deg)
      .def_readwrite("lines", &TriangulationOptions::lines)
      .def("check", &TriangulationOptions::Check);
  py::class_<LocalMapperOptions>(m, "LocalMapperOptions", "Local mapping.")
      .def(py::init<>())
      .def_readwrite("local_keyframes", &LocalMapperOptions::local_keyframes)
      .def_readwrite("max_fixed_keyframes", &LocalMapperOptions::max_fixed_keyframes)
      .def_readwrite("cull_keyframes", &LocalMapperOptions::cull_keyframes)
      .def_readwrite("redundant_ratio", &LocalMapperOptions::redundant_ratio)
      .def_readwrite("triangulate", &LocalMapperOptions::triangulate)
      .def_readwrite("triangulation", &LocalMapperOptions::triangulation)
      .def_readwrite("ba", &LocalMapperOptions::ba)
      .def("check", &LocalMapperOptions::Check);
  py::class_<StereoMatchOptions>(m, "StereoMatchOptions", "Stereo keypoint matching.")
      .def(py::init<>())
      .def_readwrite("max_row_offset_px", &StereoMatchOptions::max_row_offset_px)
      .def_readwrite("max_disparity_px", &StereoMatchOptions::max_disparity_px)
      .def_readwrite("max_distance_binary", &StereoMatchOptions::max_distance_binary)
      .def_readwrite("max_distance_float", &StereoMatchOptions::max_distance_float)
      .def_readwrite("ratio", &StereoMatchOptions::ratio)
      .def_readwrite("max_depth_baselines", &StereoMatchOptions::max_depth_baselines)
      .def_readwrite("subpixel_window", &StereoMatchOptions::subpixel_window)
      .def_readwrite("subpixel_search", &StereoMatchOptions::subpixel_search)
      .def_readwrite("row_search", &StereoMatchOptions::row_search)
      .def_readwrite("row_search_window", &StereoMatchOptions::row_search_window)
      .def_readwrite("row_search_ratio", &StereoMatchOptions::row_search_ratio)
      .def_readwrite("row_search_max_cost", &StereoMatchOptions::row_search_max_cost)
      .def_readwrite("row_search_min_texture", &StereoMatchOptions::row_search_min_texture)
      .def("check", &StereoMatchOptions::Check);
}

// Options of relocalisation, the IMU, the pose graph and loop closing.
void BindRecoveryOptions(py::module_& m) {
  py::class_<RelocalisationOptions>(m, "RelocalisationOptions",
                                    "Relocalisation by bag of words, PnP RANSAC and the local map.")
      .def(py::init<>())
      .def_readwrite("candidates", &RelocalisationOptions::candidates)
      .def_readwrite("min_matches", &RelocalisationOptions::min_matches)
      .def_readwrite("match_ratio", &RelocalisationOptions::match_ratio)
      .def_readwrite("ransac_error_px", &RelocalisationOptions::ransac_error_px)
      .def_readwrite("ransac_iterations", &RelocalisationOptions::ransac_iterations)
      .def_readwrite("min_pnp_inliers", &RelocalisationOptions::min_pnp_inliers)
      .def_readwrite("min_inliers", &RelocalisationOptions::min_inliers)
      .def_readwrite("vocabulary_levels_up", &RelocalisationOptions::vocabulary_levels_up)
      .def("check", &RelocalisationOptions::Check);

  py::class_<InertialOptions>(
      m, "InertialOptions",
      "The IMU tightly coupled in tracking: initialisation, prediction, the pose prior, the "
      "propagated pose while the camera cannot track.")
      .def(py::init<>())
      .def_readwrite("time_offset_s", &InertialOptions::time_offset_s)
      .def_readwrite("gyro_noise_density", &InertialOptions::gyro_noise_density)
      .def_readwrite("acc_noise_density", &InertialOptions::acc_noise_density)
      .def_readwrite("gyro_random_walk", &InertialOptions::gyro_random_walk)
      .def_readwrite("acc_random_walk", &InertialOptions::acc_random_walk)
      .def_readwrite("gravity_mps2", &InertialOptions::gravity_mps2)
      .def_readwrite("gravity_tolerance_mps2", &InertialOptions::gravity_tolerance_mps2)
      .def_readwrite("acc_bias_prior_mps2", &InertialOptions::acc_bias_prior_mps2)
      .def_readwrite("gyro_bias_sigma_radps", &InertialOptions::gyro_bias_sigma_radps)
      .def_readwrite("window_s", &InertialOptions::window_s)
      .def_readwrite("min_window_s", &InertialOptions::min_window_s)
      .def_readwrite("refine_after_s", &InertialOptions::refine_after_s)
      .def_readwrite("refine_min_path_m", &InertialOptions::refine_min_path_m)
      .def_readwrite("max_sample_gap_s", &InertialOptions::max_sample_gap_s)
      .def_readwrite("lost_sigma_fraction", &InertialOptions::lost_sigma_fraction)
      .def_readwrite("lost_sigma_min_m", &InertialOptions::lost_sigma_min_m)
      .def_readwrite("max_gap_s", &InertialOptions::max_gap_s)
      .def_readwrite("nonholonomic_max_side_ratio", &InertialOptions::nonholonomic_max_side_ratio)
      .def_readwrite("nonholonomic_sigma_mps", &InertialOptions::nonholonomic_sigma_mps)
      .def_readwrite("zero_velocity_max_statistic", &InertialOptions::zero_velocity_max_statistic)
      .def_readwrite("zero_velocity_sigma_mps", &InertialOptions::zero_velocity_sigma_mps)
      .def_readwrite("flow_min_inliers", &InertialOptions::flow_min_inliers)
      .def_readwrite("flow_sigma_mps", &InertialOptions::flow_sigma_mps)
      .def_readwrite("weak_update_min_inliers", &InertialOptions::weak_update_min_inliers)
      .def_readwrite("weak_update_min_lines", &InertialOptions::weak_update_min_lines)
      .def_readwrite("keyframe_min_stereo_lines", &InertialOptions::keyframe_min_stereo_lines)
      .def_readwrite("keyframe_interval_s", &InertialOptions::keyframe_interval_s)
      .def_readwrite("resume_map_after_lost", &InertialOptions::resume_map_after_lost)
      .def_readwrite("visual_information_scale", &InertialOptions::visual_information_scale)
      .def_readwrite("local_ba_keyframes", &InertialOptions::local_ba_keyframes)
      .def_property(
          "T_body_cam", [](const InertialOptions& o) { return o.body_from_cam.ToMatrix4(); },
          [](InertialOptions& o, const Eigen::Matrix4d& T) {
            o.body_from_cam = Rigid3d::FromMatrix4(T);
          },
          "4x4 pose of the rectified left camera in the IMU (body) frame.")
      .def("check", &InertialOptions::Check);

  py::class_<PoseGraphOptions>(m, "PoseGraphOptions", "Essential-graph optimisation.")
      .def(py::init<>())
      .def_readwrite("max_iterations", &PoseGraphOptions::max_iterations)
      .def_readwrite("rotation_sigma_rad", &PoseGraphOptions::rotation_sigma_rad)
      .def_readwrite("translation_sigma_m", &PoseGraphOptions::translation_sigma_m)
      .def("check", &PoseGraphOptions::Check);

  py::class_<LoopClosingOptions>(m, "LoopClosingOptions",
                                 "Loop closing and map merging (bag of words, points and lines).")
      .def(py::init<>())
      .def_readwrite("enabled", &LoopClosingOptions::enabled)
      .def_readwrite("merge_maps", &LoopClosingOptions::merge_maps)
      .def_readwrite("min_keyframes", &LoopClosingOptions::min_keyframes)
      .def_readwrite("candidates", &LoopClosingOptions::candidates)
      .def_readwrite("min_matches", &LoopClosingOptions::min_matches)
      .def_readwrite("match_ratio", &LoopClosingOptions::match_ratio)
      .def_readwrite("ransac_error_px", &LoopClosingOptions::ransac_error_px)
      .def_readwrite("ransac_iterations", &LoopClosingOptions::ransac_iterations)
      .def_readwrite("min_pnp_inliers", &LoopClosingOptions::min_pnp_inliers)
      .def_readwrite("min_inliers", &LoopClosingOptions::min_inliers)
      .def_readwrite("consistency", &LoopClosingOptions::consistency)
      .def_readwrite("agree_m", &LoopClosingOptions::agree_m)
      .def_readwrite("agree_rad", &LoopClosingOptions::agree_rad)
      .def_readwrite("max_correction_ratio", &LoopClosingOptions::max_correction_ratio)
      .def_readwrite("max_correction_floor_m", &LoopClosingOptions::max_correction_floor_m)
      .def_readwrite("max_correction_rad", &LoopClosingOptions::max_correction_rad)
      .def_readwrite("strong_covisibility", &LoopClosingOptions::strong_covisibility)
      .def_readwrite("global_ba", &LoopClosingOptions::global_ba)
      .def_readwrite("yaw_and_position_with_gravity",
                     &LoopClosingOptions::yaw_and_position_with_gravity)
      .def_readwrite("welding_keyframes", &LoopClosingOptions::welding_keyframes)
      .def_readwrite("pose_graph", &LoopClosingOptions::pose_graph)
      .def("check", &LoopClosingOptions::Check);
}

// TrackerOptions, which holds the option structs above.
void BindTrackerOptions(py::module_& m) {
  py::class_<TrackerOptions>(m, "TrackerOptions", "Tracking, mapping and front-end thresholds.")
      .def(py::init<>())
      .def_readwrite("rig", &TrackerOptions::rig)
      .def_readwrite("stereo", &TrackerOptions::stereo)
      .def_readwrite("pose", &TrackerOptions::pose)
      .def_readwrite("mapping", &TrackerOptions::mapping)
      .def_readwrite("use_lines", &TrackerOptions::use_lines)
      .def_readwrite("right_lines_on_keyframes", &TrackerOptions::right_lines_on_keyframes)
      .def_readwrite("lines_on_demand", &TrackerOptions::lines_on_demand)
      .def_readwrite("lines_on_demand_inliers", &TrackerOptions::lines_on_demand_inliers)
      .def_readwrite("denoise_above_noise", &TrackerOptions::denoise_above_noise)
      .def_readwrite("sequential", &TrackerOptions::sequential)
      .def_readwrite("mapping_brake", &TrackerOptions::mapping_brake)
      .def_readwrite("mapping_overlap", &TrackerOptions::mapping_overlap)
      .def_readwrite("min_init_points", &TrackerOptions::min_init_points)
      .def_readwrite("min_inliers", &TrackerOptions::min_inliers)
      .def_readwrite("search_radius_px", &TrackerOptions::search_radius_px)
      .def_readwrite("max_distance_binary", &TrackerOptions::max_distance_binary)
      .def_readwrite("max_distance_float", &TrackerOptions::max_distance_float)
      .def_readwrite("match_ratio", &TrackerOptions::match_ratio)
      .def_readwrite("line_search_px", &TrackerOptions::line_search_px)
      .def_readwrite("line_max_angle_rad", &TrackerOptions::line_max_angle_rad)
      .def_readwrite("line_max_lbd", &TrackerOptions::line_max_lbd)
      .def_readwrite("keyframe_max_frames", &TrackerOptions::keyframe_max_frames)
      .def_readwrite("keyframe_min_frames", &TrackerOptions::keyframe_min_frames)
      .def_readwrite("keyframe_min_frames_noisy", &TrackerOptions::keyframe_min_frames_noisy)
      .def_readwrite("keyframe_min_interval_s", &TrackerOptions::keyframe_min_interval_s)
      .def_readwrite("keyframe_track_ratio", &TrackerOptions::keyframe_track_ratio)
      .def_readwrite("close_depth_baselines", &TrackerOptions::close_depth_baselines)
      .def_readwrite("keyframe_min_inliers", &TrackerOptions::keyframe_min_inliers)
      .def_readwrite("point_sigma_px", &TrackerOptions::point_sigma_px)
      .def_readwrite("track_refine_window_px", &TrackerOptions::track_refine_window_px)
      .def_readwrite("triangulated_point_patches", &TrackerOptions::triangulated_point_patches)
      .def_readwrite("track_refine_max_px", &TrackerOptions::track_refine_max_px)
      .def_readwrite("projected_max_frames", &TrackerOptions::projected_max_frames)
      .def_readwrite("projection_min_inliers", &TrackerOptions::projection_min_inliers)
      .def_readwrite("projection_search_px", &TrackerOptions::projection_search_px)
      .def_readwrite("projection_cell_px", &TrackerOptions::projection_cell_px)
      .def_readwrite("unaligned_sigma_factor", &TrackerOptions::unaligned_sigma_factor)
      .def_readwrite("unaligned_min_aligned", &TrackerOptions::unaligned_min_aligned)
      .def_readwrite("unaligned_max_turn_deg_per_frame",
                     &TrackerOptions::unaligned_max_turn_deg_per_frame)
      .def_readwrite("line_sigma_px", &TrackerOptions::line_sigma_px)
      .def_readwrite("line_inlier_weight", &TrackerOptions::line_inlier_weight)
      .def_readwrite("recently_lost_frames", &TrackerOptions::recently_lost_frames)
      .def_readwrite("lost_reentry_min_point_ratio", &TrackerOptions::lost_reentry_min_point_ratio)
      .def_readwrite("lost_reentry_confirm_m", &TrackerOptions::lost_reentry_confirm_m)
      .def_readwrite("new_map_after_lost_frames", &TrackerOptions::new_map_after_lost_frames)
      .def_readwrite("lost_velocity_decay", &TrackerOptions::lost_velocity_decay)
      .def_readwrite("lost_motion_frames", &TrackerOptions::lost_motion_frames)
      .def_readwrite("lost_search_scale", &TrackerOptions::lost_search_scale)
      .def_readwrite("weak_keyframe_inliers", &TrackerOptions::weak_keyframe_inliers)
      .def_readwrite("weak_keyframe_frames", &TrackerOptions::weak_keyframe_frames)
      .def_readwrite("frame_rate_hz", &TrackerOptions::frame_rate_hz)
      .def_readwrite("reference_rate_hz", &TrackerOptions::reference_rate_hz)
      .def_readwrite("reference_focal_px", &TrackerOptions::reference_focal_px)
      .def_readwrite("vocabulary_path", &TrackerOptions::vocabulary_path)
      .def_readwrite("relocalisation", &TrackerOptions::relocalisation)
      .def_readwrite("loop_closing", &TrackerOptions::loop_closing)
      .def_readwrite("localise_only", &TrackerOptions::localise_only)
      .def_readwrite("dynamic_cells", &TrackerOptions::dynamic_cells)
      .def_readwrite("dynamic", &TrackerOptions::dynamic)
      .def_readwrite("use_imu", &TrackerOptions::use_imu)
      .def_readwrite("imu", &TrackerOptions::imu)
      .def("check", &TrackerOptions::Check);
}

// One frame's result and the free functions of the tracking front end.
void BindFrameOutputAndHelpers(py::module_& m) {
  py::class_<FrameOutput>(m, "FrameOutput",
                          "One frame's result from TrackerCore.track (slslam.Tracker wraps it "
                          "into a TrackResult).")
      .def_property_readonly(
          "state", [](const FrameOutput& o) { return std::string(TrackingStateName(o.state)); })
      .def_property_readonly(
          "cam_from_world", [](const FrameOutput& o) { return o.cam_from_world.ToMatrix4(); },
          "4x4 pose: x_cam = T x_world.")
      .def_readonly("map_index", &FrameOutput::map_index)
      .def_readonly("matched_points", &FrameOutput::matched_points)
      .def_readonly("inlier_points", &FrameOutput::inlier_points)
      .def_readonly("matched_lines", &FrameOutput::matched_lines)
      .def_readonly("inlier_lines", &FrameOutput::inlier_lines)
      .def_readonly("lines", &FrameOutput::lines, "left-image line segments")
      .def_readonly("keyframe", &FrameOutput::keyframe)
      .def_readonly("masked_keypoints", &FrameOutput::masked_keypoints)
      .def_readonly("weighted_inliers", &FrameOutput::weighted_inliers)
      .def_readonly("relocalisation_ms", &FrameOutput::relocalisation_ms)
      .def_readonly("line_extraction_ms", &FrameOutput::line_extraction_ms)
      .def_readonly("stereo_matching_ms", &FrameOutput::stereo_matching_ms)
      .def_readonly("matching_ms", &FrameOutput::matching_ms)
      .def_readonly("optimisation_ms", &FrameOutput::optimisation_ms)
      .def_readonly("mapping_ms", &FrameOutput::mapping_ms)
      .def_readonly("needs_keypoints", &FrameOutput::needs_keypoints,
                    "the frame came without keypoints and the tracker could not place the map's "
                    "points in it: nothing changed, prepare it again with detected keypoints")
      .def_readonly("imu_initialised", &FrameOutput::imu_initialised,
                    "the inertial state existed after this frame")
      .def_readonly("position_sigma_m", &FrameOutput::position_sigma_m,
                    "its position standard deviation then [m] (0: no IMU)")
      .def_readonly("v_world_body", &FrameOutput::v_world_body,
                    "the body's velocity in the world after this frame [m/s] (0: no IMU)")
      .def_readonly("gyro_bias", &FrameOutput::gyro_bias,
                    "the gyroscope bias estimated then, body frame [rad/s] (0: no IMU)")
      .def_readonly("acc_bias", &FrameOutput::acc_bias,
                    "the accelerometer bias estimated then, body frame [m/s^2] (0: no IMU)")
      .def_readonly("projected_keypoints", &FrameOutput::projected_keypoints,
                    "tracked on this many projected keypoints (0: on detected ones)");

  m.def("adapt_to_rig", &AdaptToRig, py::arg("options"),
        "The options the tracker runs with: counts in frames turned to frame_rate_hz against "
        "reference_rate_hz, pixel windows to the rig's fx against reference_focal_px.");
  m.def(
      "match_stereo_points",
      [](const py::array& left_image, const py::array& right_image, const PixelArray& left_uv,
         const py::array& left_descriptors, const PixelArray& right_uv,
         const py::array& right_descriptors, const StereoRig& rig,
         const StereoMatchOptions& options, double denoise_above_noise) {
        const cv::Mat left_image_mat = WrapGray(left_image, "left image");
        const cv::Mat right_image_mat = WrapGray(right_image, "right image");
        const Keypoints kl = MakeKeypoints(left_uv, left_descriptors, "left");
        const Keypoints kr = MakeKeypoints(right_uv, right_descriptors, "right");
        StereoFrame frame;
        {
          py::gil_scoped_release release;
          // the pair as StereoFrontend::Build matches it (tracking.denoise_above_noise)
          const cv::Mat left = SmoothIfNoisy(left_image_mat, denoise_above_noise);
          const cv::Mat right = SmoothIfNoisy(right_image_mat, denoise_above_noise);
          frame = MakeStereoFrame(0, 0, kl, kr, nullptr, nullptr, rig, options);
          SearchAndRefineStereoPoints(left, right, rig, options, &frame);
        }
        // Copies: a Map would hand Python a view of `frame`, which dies on return.
        const Eigen::VectorXd u_right =
            Eigen::VectorXd::Map(frame.u_right.data(), frame.u_right.size());
        const Eigen::VectorXd depth = Eigen::VectorXd::Map(frame.depth.data(), frame.depth.size());
        return py::make_tuple(u_right, depth);
      },
      py::arg("left_image"), py::arg("right_image"), py::arg("left_uv"),
      py::arg("left_descriptors"), py::arg("right_uv"), py::arg("right_descriptors"),
      py::arg("rig"), py::arg("options") = StereoMatchOptions{},
      py::arg("denoise_above_noise") = TrackerOptions{}.denoise_above_noise,
      "The tracker's stereo matching of keypoints on the pair smoothed as the tracker smooths it "
      "(noisier than denoise_above_noise; 0: never): descriptors along the row band, then the row "
      "search with options.row_search, then subpixel refinement. (u_right, depth) per left "
      "keypoint, -1 where unmatched.");
}

// The per-frame session (pipeline/tracker_session.h) and what it prepares ahead.
void BindSession(py::module_& m) {
  py::class_<PreparedFrame, std::shared_ptr<PreparedFrame>>(
      m, "PreparedFrame", "A frame whose stereo matching ran ahead (TrackerCore.prepare).")
      .def_property_readonly("stereo_matching_ms",
                             [](const PreparedFrame& p) { return p.timing.stereo_matching_ms; });
  py::class_<LeftLines, std::shared_ptr<LeftLines>>(
      m, "LeftLines", "A left image's lines extracted ahead (TrackerCore.extract_left_lines).")
      .def_property_readonly("count", [](const LeftLines& l) { return l.features.segments.size(); })
      .def_readonly("extraction_ms", &LeftLines::extraction_ms);

  py::class_<TrackerSession>(m, "TrackerCore",
                             "Stereo point-line tracker with local mapping (use slslam.Tracker).")
      .def(py::init([](const TrackerOptions& options, const LineExtractorOptions& lines) {
             return std::make_unique<TrackerSession>(options, lines);
           }),
           py::arg("options"), py::arg("lines") = LineExtractorOptions{})
      .def(
          "track",
          [](TrackerSession& session, int index, int64_t t_ns, const py::array& left_image,
             const py::array& right_image, const PixelArray& left_uv,
             const py::array& left_descriptors, const PixelArray& right_uv,
             const py::array& right_descriptors, const std::shared_ptr<LeftLines>& left_lines,
             bool noisy, bool denoised) {
            const std::shared_ptr<PreparedFrame> p =
                PrepareFromArrays(session, index, t_ns, left_image, right_image, left_uv,
                                  left_descriptors, right_uv, right_descriptors, left_lines,
                                  /*keypoints_pending=*/false, noisy, denoised);
            py::gil_scoped_release release;
            return session.TrackPrepared(*p);
          },
          py::arg("index"), py::arg("t_ns"), py::arg("left_image"), py::arg("right_image"),
          py::arg("left_uv"), py::arg("left_descriptors"), py::arg("right_uv"),
          py::arg("right_descriptors"), py::arg("left_lines") = nullptr, py::arg("noisy") = false,
          py::arg("denoised") = false,
          "Tracks one rectified stereo frame captured at t_ns [ns]; returns its FrameOutput. "
          "left_lines: the left "
          "image's lines from extract_left_lines on this left image (None: extracted here). "
          "noisy: the images were smoothed as noisy before (tracking.unaligned_sigma_factor). "
          "denoised: both images come from smooth_if_noisy at the options' "
          "denoise_above_noise (slslam.Tracker's own), so they are not checked again.")
      .def("prepare", &PrepareFromArrays, py::arg("index"), py::arg("t_ns"), py::arg("left_image"),
           py::arg("right_image"), py::arg("left_uv"), py::arg("left_descriptors"),
           py::arg("right_uv"), py::arg("right_descriptors"), py::arg("left_lines") = nullptr,
           py::arg("keypoints_pending") = false, py::arg("noisy") = false,
           py::arg("denoised") = false,
           "track's first part without the session's lock: the frame's stereo matching (and "
           "its lines unless left_lines or lines on demand), for a thread ahead of the core. "
           "track(...) equals track_prepared(prepare(...)). keypoints_pending (no keypoints "
           "given; tracking.projected_max_frames): the tracker places the map's points in the "
           "frame, or returns needs_keypoints. noisy, denoised: as track's.")
      .def("track_prepared", &TrackerSession::TrackPrepared, py::arg("frame"),
           py::call_guard<py::gil_scoped_release>(),
           "track's second part on a frame from prepare (once, in frame order): the tracker and "
           "local mapping; returns its FrameOutput.")
      .def(
          "extract_left_lines",
          [](const TrackerSession& session, const py::array& left_image, bool denoised) {
            const cv::Mat left = WrapGray(left_image, "left image");
            py::gil_scoped_release release;
            return session.ExtractLeftLines(left, denoised);
          },
          py::arg("left_image"), py::arg("denoised") = false,
          "The left image's lines as track extracts them (smoothed when noisy), without the "
          "session's lock: for a thread beside the point front end. Needs use_lines and "
          "right_lines_on_keyframes. denoised: as track's.")
      .def("add_imu", &TrackerSession::AddImu, py::arg("t_ns"), py::arg("gyro"), py::arg("acc"),
           py::call_guard<py::gil_scoped_release>(),
           "IMU samples (times [ns] int64, body frame, on the IMU's clock) for the "
           "visual-inertial tracking, before the frames they precede.")
      .def(
          "map",
          [](TrackerSession& session, bool settle) {
            SessionMap map;
            {
              py::gil_scoped_release release;
              map = session.Map(settle);
            }
            return MapDict(map);
          },
          py::arg("settle") = true,
          "Points and lines; settle: first waits for local mapping (and applies an overlapped "
          "local BA), else the map as it stands.")
      .def("save_map", &TrackerSession::SaveMap, py::arg("path"), py::arg("version"),
           py::call_guard<py::gil_scoped_release>(),
           "Writes every live map (versioned binary, checksummed); waits for mapping.")
      .def("load_map", &TrackerSession::LoadMap, py::arg("path"),
           py::call_guard<py::gil_scoped_release>(),
           "Loads a saved atlas before the first frame; tracking starts by relocalising in it.")
      .def(
          "trajectory",
          [](TrackerSession& session) {
            std::vector<FramePose> poses;
            {
              py::gil_scoped_release release;
              poses = session.Trajectory();
            }
            return TrajectoryDict(poses);
          },
          "Every estimated frame pose (index, t_ns, map_index, cam_from_world_rotation and "
          "_translation arrays) in the "
          "final map: after loop correction, merges and bundle adjustment.")
      .def("flush", &TrackerSession::Flush, py::call_guard<py::gil_scoped_release>());
}

}  // namespace

void BindTracking(py::module_& m) {
  BindRig(m);
  BindSolverOptions(m);
  BindRecoveryOptions(m);
  BindTrackerOptions(m);
  BindFrameOutputAndHelpers(m);
  BindSession(m);
}

}  // namespace slslam::bindings
