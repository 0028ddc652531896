// Stereo point-line tracking (the SL-SLAM paper's tracking, after ORB-SLAM3's Tracking):
// constant-velocity prediction, guided matching of the local map's points and lines into the
// frame, motion-only bundle adjustment on the unified point-line cost, keyframe decision and
// insertion, hand-off to local mapping.
//
// Tracking loss is a state, not an error. A frame that cannot be tracked enters RECENTLY_LOST:
// for a few frames the tracker retries with a wider window around a prediction whose velocity
// decays frame by frame, and tries to relocalise (bag of words against the keyframe database,
// PnP RANSAC, then the local map) into the active map. After that the pose is frozen (LOST) and
// every frame tries relocalisation into every map; a frame with enough stereo points and lines
// starts a new map of the atlas (NEW_MAP) anchored at the frozen pose. Point and line inliers
// both count (a line inlier weighs `line_inlier_weight` points) in the decisions to go lost, to
// make a keyframe and to start a map, so lines carry the low-texture stretches.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <initializer_list>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "slslam/core/rigid3.h"
#include "slslam/features/descriptor_matcher.h"
#include "slslam/features/dynamic_cell_filter.h"
#include "slslam/features/lbd.h"
#include "slslam/map/map.h"
#include "slslam/mapping/atlas.h"
#include "slslam/mapping/local_mapper.h"
#include "slslam/mapping/loop_closer.h"
#include "slslam/optimization/pose_optimizer.h"
#include "slslam/place/keyframe_database.h"
#include "slslam/place/vocabulary.h"
#include "slslam/tracking/inertial_estimator.h"
#include "slslam/tracking/stereo_matching.h"

namespace slslam {

// OK, NEW_MAP and RELOCALISED frames carry a pose the camera estimated (with the IMU's prior once
// it is initialised), INERTIAL frames one the IMU carried on where the camera contributed too
// little (inertial_estimator.h);
// RECENTLY_LOST frames a prediction (decaying velocity), LOST frames the frozen last prediction.
enum class TrackingState {
  kNotInitialized = 0,
  kOk = 1,
  kLost = 2,
  kNewMap = 3,
  kRecentlyLost = 4,
  kRelocalised = 5,
  kInertial = 6,
};

// Relocalisation (ORB-SLAM's): keyframe candidates by bag of words, frame keypoints matched to
// each candidate's map points within the vocabulary nodes they share, PnP RANSAC, then the local
// map around the candidate tracked from that pose as in normal tracking.
struct RelocalisationOptions {
  int candidates = 5;            ///< best keyframes by BoW score tried per frame [-]
  int min_matches = 15;          ///< descriptor matches a candidate needs for PnP [-]
  float match_ratio = 0.75f;     ///< best / second best within a vocabulary node [-]
  double ransac_error_px = 3.0;  ///< PnP RANSAC inlier bound [px]
  int ransac_iterations = 300;   ///< [-]
  int min_pnp_inliers = 12;      ///< [-]
  double min_inliers = 40.0;     ///< weighted inliers after tracking the local map [-]
  int vocabulary_levels_up = 2;  ///< direct-index level for matching (levels above the leaves)

  void Check() const;
};

// Counts of the loss / recovery machinery since the tracker started.
struct TrackingStats {
  int inertial_frames = 0;        ///< frames whose pose the IMU carried (state INERTIAL)
  int inertial_weak_updates = 0;  ///< ... of them corrected by a weak visual pose
  int inertial_keyframes =
      0;  ///< ... of them made keyframes (InertialOptions::keyframe_interval_s)
  int relocalisations = 0;
  int relocalisation_attempts = 0;
  int maps_started = 0;
  /// Maps resumed at the IMU's pose after a loss instead of a new one started
  /// (InertialOptions::resume_map_after_lost)
  int maps_resumed = 0;
  int line_frames = 0;  ///< frames whose left lines were extracted (all with use_lines, unless
                        ///< lines_on_demand)
};

const char* TrackingStateName(TrackingState state);

struct TrackerOptions {
  StereoRig rig;
  StereoMatchOptions stereo;
  PoseOptimizerOptions pose;
  LocalMapperOptions mapping;
  bool use_lines = true;  ///< lines in tracking and mapping
  /// the right image's lines only for frames that become keyframes or start a map
  /// (StereoFrontendOptions::right_lines_on_keyframes; the tracker completes those frames):
  /// the same poses and map, about half the line work on the frames between keyframes
  bool right_lines_on_keyframes = true;
  /// The left image's lines only for the frames that use them (StereoFrontendOptions::
  /// left_lines_on_demand; the tracker completes those frames through Track's
  /// `complete_left_lines`): a frame after one tracked with fewer than lines_on_demand_inliers
  /// point inliers, a frame its points alone do not track (tracked again with its lines), a
  /// keyframe (its lines matched to the local map from the pose its points gave, and the pose
  /// optimised again with them), a frame that starts a map, and every frame while the tracker is
  /// lost. The frames between keyframes of a well-textured stretch are tracked on their points:
  /// no line detection and no LBD there (the largest part of a frame's front end with ORB).
  /// Applies with right_lines_on_keyframes (without it both images' lines are extracted every
  /// frame). Over five simulator seeds of the four 600-frame sequences with the IMU the two dark
  /// sequences drifted less with it and the bright loop and the spin a little more; about half
  /// the bright loop's frames skip their lines (benchmarks/log/realtime.md). Off: every frame's
  /// lines
  bool lines_on_demand = true;
  /// With lines_on_demand: a frame after one tracked with fewer point inliers than this is
  /// tracked with its lines from the start [-]
  int lines_on_demand_inliers = 150;
  /// images noisier than this (Immerkaer's estimate, as orb.denoise_above_noise) reach line
  /// detection, line descriptors and stereo matching Gaussian-smoothed, sigma = noise / 7 px
  /// (StereoFrontendOptions::denoise_above_noise); 0: never [gray levels]
  double denoise_above_noise = 6.0;
  bool sequential = true;  ///< local mapping inline (reproducible) or on its own thread
  /// Threaded mode only: ORB-SLAM3's brake on keyframes. While local mapping is busy the minimum
  /// gap alone asks for no keyframe, and a keyframe that is due interrupts the running local BA
  /// (it keeps its estimate) and queues unless 3 wait. More frames/s, but worse ATE on the hard
  /// dark sequences (benchmarks/log/realtime.md), so off.
  bool mapping_brake = false;
  /// Sequential mode only: each keyframe's local BA solves on a thread of its own, on the window's
  /// copy of the map, while tracking goes on; its solution is applied (and the landmarks and
  /// keyframes culled) when the next keyframe is inserted, or at Flush. Still exactly
  /// reproducible: the point where a solution lands is fixed by the frames, not by timing, as
  /// long as nothing asks for the settled map mid-run: Flush, a saved map, the final trajectory
  /// and Python's `Tracker.map()` (but not `map(settle=False)`) apply a pending solution there
  /// and then, so a run that calls them mid-way differs from one that does not. The
  /// frames between two keyframes are tracked against the map as it was before the first one's BA
  /// (ORB-SLAM3's tracking sees the same while its mapping thread is busy). Off: on two cores the
  /// solve competes with the frames' own work, so the 95th percentile of the per-frame latency
  /// falls but its median rises (ORB points, bright loop), frames/s gain only in the dark, and
  /// XFeat + lines drifted more on the dark 150-frame loop (benchmarks/log/realtime.md).
  bool mapping_overlap = false;
  int min_init_points = 50;           ///< stereo points a frame needs to start a map [-]
  int min_inliers = 15;               ///< fewer inliers after motion-only BA: LOST [-]
  float search_radius_px = 15.0f;     ///< guided matching window [px]; doubled on a retry
  float max_distance_binary = 80.0f;  ///< guided matching, ORB (Hamming) [bits]; dark, noisy
                                      ///< frames need more than 50 (ORB-SLAM uses 100)
  float max_distance_float = 0.8f;    ///< guided matching, SuperPoint (L2) [-]
  float match_ratio = 0.9f;           ///< ratio test inside the window [-]
  float line_search_px = 20.0f;       ///< frame segment midpoint to predicted line [px]
  float line_max_angle_rad = 0.2f;    ///< [rad]
  float line_max_lbd = 80.0f;         ///< [bits]
  /// The kind of line descriptors the frames carry (the line front end's, LineExtractorOptions::
  /// descriptor): written into map files, and a map file of another kind is refused.
  LineDescriptor line_descriptor = LineDescriptor::kOpenCvLbd;
  int keyframe_max_frames = 20;  ///< a keyframe at least this often [frames]
  int keyframe_min_frames = 2;   ///< no keyframe sooner than this after the last [frames]
  /// ... in a noisy frame (StereoFrame::noisy: smoothed as dark) instead: keypoints repeat less
  /// well there and fewer are tracked, so the map needs its keyframes sooner: over five seeds of
  /// the dark 150-frame simulated loop XFeat + lines drifted less with a gap of 5 or 4 frames in
  /// noisy frames than with its preset's usual 6 (the preset sets 5 here;
  /// benchmarks/log/realtime.md). -1: the same as keyframe_min_frames [frames]
  int keyframe_min_frames_noisy = -1;
  /// ... nor sooner than this after it, while tracking is strong: a gap in time, the same at any
  /// camera rate. Off by default: 0.075 s (2 frames at 20 Hz, 1 at 10 Hz) with no frame gap was
  /// better on the dark 10 Hz loop and much worse on the bright one
  /// (benchmarks/log/loop_closing.md) [s]
  double keyframe_min_interval_s = 0.0;
  double keyframe_track_ratio = 0.75;   ///< tracked / reference-keyframe points (those seen by
                                        ///< >= 3 keyframes) below this: keyframe [-]
  int keyframe_min_inliers = 100;       ///< fewer tracked close points (and > 70 untracked
                                        ///< ones): keyframe, as ORB-SLAM3's stereo rule [-]
  double close_depth_baselines = 40.0;  ///< "close" stereo points for the rule above [-]
  double point_sigma_px = 1.0;          ///< [px]
  /// Half size of the patch that refines a tracked keypoint's position [px]: a map point made
  /// from a keyframe's keypoint keeps the (2w+1)^2 patch of the left image around it (as stereo
  /// matching saw it), and a later match is aligned to that patch (inverse compositional
  /// Gauss-Newton, zero-mean, the patch scaled by the point's change of depth, the detected
  /// position as the start; textured patches only, accepted at NCC >= 0.8). The motion-only BA
  /// and a keyframe take the aligned position, the stereo column shifted with it. Detected
  /// keypoints repeat to 1-2 px against the ground truth (median on the simulated loop); aligned
  /// ones follow the point the map was made from. With it XFeat + lines drifted much less on the
  /// 600-frame bright loop and ORB + lines on the hard junction (benchmarks/log/realtime.md).
  /// Points that local mapping triangulates (unless triangulated_point_patches) and points loaded
  /// from a map file have no patch. 0: off
  int track_refine_window_px = 5;
  /// Points that local mapping triangulates from keyframe pairs keep a patch too, of the new
  /// keyframe's left image (TriangulationOptions::patch_window_px, the keyframe holding its image
  /// until then): their later matches are aligned as the stereo points' are, instead of taken at
  /// the detected position, which follows a small image motion only in part (XFeat's keypoints
  /// follow most, not all, of a small scale change; benchmarks/log/realtime.md). Needs
  /// track_refine_window_px > 0. false: triangulated points have no patch, only the points the
  /// tracker makes from stereo in its keyframes have one [-]
  bool triangulated_point_patches = false;
  float track_refine_max_px = 3.0f;  ///< an alignment moving the keypoint further is not taken [px]
  /// In a noisy frame (StereoFrame::noisy: smoothed as dark) with at least
  /// unaligned_min_aligned matches aligned to their map points' patches (track_refine_window_px),
  /// the matches that could not be aligned enter the motion-only BA with their sigma times this.
  /// Detected keypoints follow a small image motion only in part (XFeat's follow most, not all,
  /// of a 0.5-1 % scale change; benchmarks/log/realtime.md), so in a dark stretch where the image
  /// scales by about 1 % a frame the unaligned matches pull the pose short; the aligned ones
  /// follow the map. The count gate keeps the weights where few matches align (a turn on the
  /// spot: the alignment models no rotation; frames tracked on projected keypoints, which are
  /// aligned already). Off by default: for XFeat + lines, 3 (the other gates as below) drifted
  /// less on the 600-frame dusty dark loop and hard junction over three seeds and left the
  /// bright loop's poses unchanged, but drifted more on the spin and on realtime.py's 150-frame
  /// dark loop (benchmarks/log/realtime.md). 1: every match with point_sigma_px [-]
  double unaligned_sigma_factor = 1.0;
  int unaligned_min_aligned = 30;  ///< see unaligned_sigma_factor [-]
  /// ... and while the camera turned by at most this between the last two frames (the motion
  /// model's rotation) [deg per frame]
  double unaligned_max_turn_deg_per_frame = 1.5;
  /// Frames tracked on projected keypoints instead of detected ones, at most this many in a row
  /// [frames]. A frame given without keypoints (StereoFrame::keypoints_pending; which frames is
  /// the caller's choice, Python's Tracker._detect_ahead) is tracked this way while tracking is
  /// strong (the frame before held projection_min_inliers point inliers); a frame given with its
  /// keypoints is tracked on them. The local map's points that have a patch are projected with
  /// the predicted pose and aligned to their patches in the image (track_refine_window_px; a
  /// global shift found on a few of them first absorbs the prediction's rotation error), their
  /// stereo column searched around the one their depth predicts; the frame is tracked on these,
  /// as semi-direct odometry (SVO) does between keyframes. A frame that would become a keyframe,
  /// that tracks on fewer than projection_min_inliers of them, that comes after this many
  /// projected frames, or that comes right after a keyframe (its inliers are the keyframe rule's
  /// reference: measured on a projected frame they understated it, and keyframes came late) is
  /// handed back for detected keypoints (TrackResult::needs_keypoints; nothing changed), so
  /// keyframes always have detected keypoints. The point front end then runs on a fraction of
  /// the frames. Off by default: ORB + lines makes a keyframe every 2-3 frames in the light
  /// (mostly for new close points, which a projected frame cannot see), so little is left to
  /// project, and in the trial benchmarks/log/realtime.md records, 3 gained frames/s but drifted
  /// more on the 600-frame bright loop. XFeat's preset (python/slslam/presets/xfeat.yaml) sets 2
  /// with projection_cell_px 16: more frames/s for XFeat + lines in the light and in the dark, at
  /// about the same ATE on the 600-frame sequences (benchmarks/log/realtime.md). 0: every frame's
  /// keypoints are detected
  int projected_max_frames = 0;
  int projection_min_inliers = 150;  ///< see projected_max_frames [-]
  int projection_search_px = 8;      ///< the global shift's search radius [px]
  int projection_cell_px = 24;       ///< at most one projected point per cell of this size [px]
  double line_sigma_px = 3.0;        ///< line endpoint distance sigma [px]: the two
                                     ///< distances of one segment share the map line's error
                                     ///< (benchmarks/log/tracking_ablation.md:
                                     ///< 1.5 px over-weighted lines)
  double line_inlier_weight = 1.0;   ///< a line inlier counts as this many point inliers when
                                     ///< deciding LOST, keyframes and a new map [-]
  int recently_lost_frames = 10;     ///< frames of RECENTLY_LOST before LOST [frames]
  double lost_velocity_decay = 0.6;  ///< per-frame factor on the predicted motion while
                                     ///< recently lost (rotation angle and translation) [-]
  float lost_search_scale = 2.0f;    ///< guided-matching window factor while recently lost [-]
  /// Lost: the motion before the loss, along which the local map is tried (TrackAlongLossMotion),
  /// is the mean per-frame motion over this many frames before it, not the last frame's alone:
  /// twenty black frames extrapolate one frame's jitter twentyfold. On the camera-only blackouts
  /// of the simulated junction (many seeds, in the light and in the dusty dark) 5 brought every
  /// run back at the right pose with either local BA solver, where with 1 a bright run with the
  /// own solver re-entered the repeated roadway far off the truth (benchmarks/log/realtime.md).
  /// 1: the last frame's [frames]
  int lost_motion_frames = 5;
  /// Lost, the local map tracked from a pose along the motion before the loss is taken only where
  /// at least this share of its point matches are inliers [-]. Lines do not count here: a line
  /// constrains a pose little along itself, and on the camera-only blackout of the simulated
  /// junction at light 0.5 the wrong re-entries kept well under a quarter of their point matches
  /// and made up the rest with line inliers, the right ones well over a quarter
  /// (benchmarks/log/realtime.md). 0: any share above none (a pose held by lines alone is never
  /// taken)
  double lost_reentry_min_point_ratio = 0.25;
  /// Lost: the re-entry along the loss motion whose pose holds fewer than twice min_inliers is
  /// taken when it holds min_inliers and the previous frame's (also short of the bar, with
  /// min_inliers) lies, moved one step along that motion, within this distance and 5 degrees of
  /// it: two frames agreeing where one alone would not do. Attempts started from the frozen pose
  /// take no part (two frames of it agree by construction). On the dark camera-only blackout of
  /// the simulated junction the attempts along the motion reached the right pose (within
  /// centimetres) frame after frame, but with fewer than twice min_inliers weighted inliers, until
  /// the frozen pose, a metre behind, got past the bar on its lines (benchmarks/log/realtime.md).
  /// 0: off [m]
  double lost_reentry_confirm_m = 0.15;
  /// Lost: lit frames (at least min(min_init_points, 15) stereo points, StartMap's first check;
  /// a black frame has none) that must fail relocalisation and the re-entry along the loss
  /// motion before one starts a new map [frames]. The first lit frame after a blackout often
  /// fails both where the next ones do not; a new map is merged back only when place recognition
  /// links it. 0: the first lit frame starts one (where StartMap's other checks pass)
  int new_map_after_lost_frames = 5;
  int weak_keyframe_inliers = 60;  ///< weighted inliers below this: a keyframe every
                                   ///< `weak_keyframe_frames`, to keep a thin map alive [-]
  int weak_keyframe_frames = 3;    ///< [frames]
  /// The camera's frame rate [Hz]: the options counted in frames follow it (AdaptToRig, with
  /// reference_rate_hz). slslam's readers take it from the sequence (EuRoC's sensor.yaml or its
  /// timestamps, KITTI's times.txt, a bag's stamps, the simulator's rate). 0: unknown, the counts
  /// are used as given
  double frame_rate_hz = 0.0;
  /// The frame rate the options counted in frames (keyframe gaps, RECENTLY_LOST, lost motion, a
  /// new map after loss, projected frames) and per frame (lost_velocity_decay,
  /// unaligned_max_turn_deg_per_frame) are given at [Hz]: the simulated rig's, on which they were
  /// tuned. At frame_rate_hz each count becomes round(count * frame_rate_hz / reference_rate_hz),
  /// so it spans the same time at any camera rate: XFeat's keyframe gap of 6 frames is 0.3 s at
  /// 20 Hz, and 6 frames of KITTI's 10 Hz (0.6 s, 6 m at its speed) cost it most of the path
  /// (benchmarks/log/kitti_low_light.md). 0: the counts as given at every rate
  double reference_rate_hz = 20.0;
  /// The focal length the image-motion windows in pixels (search_radius_px, line_search_px,
  /// projection_search_px, projection_cell_px) are given at [px]: the simulated rig's, on which
  /// they were tuned. At the rig's fx each is scaled by fx / reference_focal_px, the same angle at
  /// any resolution: on KITTI (fx 721 px, 10 Hz) with the frame rate above, ORB + lines and XFeat
  /// + lines both came closer to ORB-SLAM3's path than with the rate alone
  /// (benchmarks/log/kitti_low_light.md). 0: the windows as given
  double reference_focal_px = 458.0;
  std::string vocabulary_path;  ///< bag-of-words vocabulary for relocalisation; empty:
                                ///< no relocalisation
  RelocalisationOptions relocalisation;
  LoopClosingOptions loop_closing;  ///< loop closing and map merging (need the vocabulary)
  bool localise_only = false;       ///< track in the loaded maps without changing them: no
                                    ///< keyframes, no mapping, no new maps
  /// Invalid-cell filter for moving objects (the SL-SLAM paper's): a cell whose matched keypoints
  /// disagree with the pose of the frame (motion-only BA over the other cells, i.e. the consensus
  /// motion) is dropped with its 8 neighbours: its keypoints take no part in the next frames'
  /// pose and make no map points, but are still matched so that the cell can recover. The mask
  /// applies only after a frame tracked with at least `weak_keyframe_inliers` weighted inliers.
  bool dynamic_cells = true;
  DynamicCellOptions dynamic;
  /// The IMU tightly coupled once samples are given (Tracker::AddImu) and it initialised: its
  /// prediction and prior in every frame's pose, its propagated pose where the camera cannot
  /// track (state INERTIAL); without samples the tracker is camera-only whatever this says.
  bool use_imu = true;
  InertialOptions imu;

  void Check() const;
};

// `options` with the options counted in frames and the image-motion windows in pixels turned to
// the rig (frame_rate_hz against reference_rate_hz, the camera's fx against reference_focal_px;
// a ratio within 1 % of 1 counts as 1, so a rate read from jittered timestamps changes
// nothing). The result's references are the rig's own, so adapting it again changes nothing.
// The Tracker adapts its options on construction; a count that was positive stays at least 1.
TrackerOptions AdaptToRig(const TrackerOptions& options);

// A frame's pose expressed in the final map: relative to its reference keyframe, so loop
// correction, merging and bundle adjustment that move the keyframe move the frame too.
struct FramePose {
  int index = 0;           ///< input frame number
  int64_t t_ns = 0;        ///< capture time [ns]
  int map_index = -1;      ///< map of the atlas the pose is in (after merges)
  Rigid3d cam_from_world;  ///< world -> camera
};

struct TrackResult {
  TrackingState state = TrackingState::kNotInitialized;
  Rigid3d cam_from_world;  ///< world -> camera
  int map_index = -1;      ///< which map of the atlas the pose belongs to
  int matched_points = 0;  ///< guided matches before optimisation
  int inlier_points = 0;
  int matched_lines = 0;
  int inlier_lines = 0;
  bool keyframe = false;           ///< a keyframe was made from this frame
  int masked_keypoints = 0;        ///< keypoints in cells the dynamic-cell filter invalidated
  double weighted_inliers = 0.0;   ///< point inliers + line_inlier_weight * line inliers [-]
  double relocalisation_ms = 0.0;  ///< BoW query, PnP and local-map tracking when lost [ms]
  double matching_ms = 0.0;        ///< local map projection and guided matching [ms]
  double optimisation_ms = 0.0;    ///< motion-only BA [ms]
  double mapping_ms = 0.0;         ///< keyframe insertion (+ local mapping in sequential mode) [ms]
  int frame_lines = 0;             ///< the frame's left-image segments (use_lines; with
                                   ///< lines_on_demand 0 unless it needed them)
  double left_lines_ms = 0.0;      ///< its left lines extracted during Track (lines_on_demand) [ms]
  /// the frame came without keypoints (StereoFrame::keypoints_pending) and the tracker could not
  /// place the map's points in it: nothing changed, track it again with detected keypoints
  bool needs_keypoints = false;
  int projected_keypoints = 0;    ///< tracked on this many projected keypoints (0: detected ones)
  bool imu_initialised = false;   ///< the inertial state existed after this frame
  double position_sigma_m = 0.0;  ///< its position standard deviation then (0: no IMU) [m]
  /// The inertial state after this frame (zero without it): the body's velocity in the world
  /// [m/s] and the IMU biases (body frame; gyroscope [rad/s], accelerometer [m/s^2])
  Eigen::Vector3d v_world_body = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();
  Eigen::Vector3d acc_bias = Eigen::Vector3d::Zero();
};

struct MapExport {
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> points;  ///< world [m]
  Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor> lines;   ///< start, end world [m]
  Eigen::VectorXi point_map;                                         ///< map index per point
  Eigen::VectorXi line_map;
  int keyframes = 0;
};

class Tracker {
 public:
  explicit Tracker(const TrackerOptions& options);
  ~Tracker();
  Tracker(const Tracker&) = delete;
  Tracker& operator=(const Tracker&) = delete;

  // Fills in the stereo lines of a frame built without them (StereoFrame::stereo_lines_pending);
  // called on a copy of the frame, during Track, when it is about to become a keyframe or to
  // start a map: the only places the right image's lines are used.
  using StereoLineCompleter = std::function<void(StereoFrame*)>;

  // `left_image`: the left image as stereo matching saw it (StereoFrontend::Build's
  // `left_used`), for track_refine_window_px; empty: no refinement for this frame. Read during
  // the call only.
  // `complete_left_lines` fills in the left image's lines of a frame built without them
  // (StereoFrame::left_lines_pending, lines_on_demand), on a copy, when the frame needs them.
  // `right_image`: the right image as stereo matching saw it, for the stereo columns of
  // projected keypoints (projected_max_frames); empty: they are monocular.
  TrackResult Track(std::shared_ptr<const StereoFrame> frame,
                    const StereoLineCompleter& complete_stereo_lines = {},
                    const cv::Mat& left_image = cv::Mat(),
                    const StereoLineCompleter& complete_left_lines = {},
                    const cv::Mat& right_image = cv::Mat());
  // One IMU sample (body frame: gyro [rad/s], specific force [m/s^2]) at t_ns on the IMU's clock
  // (t_cam = t_imu + imu.time_offset_s); samples up to a frame's time must be added before the
  // frame is tracked. Ignored when options.use_imu is off. Throws std::invalid_argument on a
  // non-finite or non-increasing sample.
  void AddImu(int64_t t_ns, const Eigen::Vector3d& gyro_radps, const Eigen::Vector3d& acc_mps2);
  // Waits for local mapping to finish its queue and for a global BA running in the background
  // to be written back (threaded mode).
  void Flush();
  MapExport ExportMap() const;
  LocalMappingStats mapping_stats() const { return mapper_->stats(); }
  LoopClosingStats loop_stats() const;
  std::vector<LoopEvent> loop_events() const;
  TrackingStats stats() const { return stats_; }
  // The IMU's part of the run (metrics.json): whether samples came, when it initialised, the
  // bias and gravity estimates now.
  struct InertialReport {
    bool has_imu = false;
    bool initialised = false;
    std::optional<int64_t> first_pose_t_ns;  ///< camera time of the first pose it was given [ns]
    std::optional<int64_t> first_init_t_ns;  ///< camera time of the first initialisation [ns]
    int initialisations = 0;
    int refinements = 0;
    int rejected_refinements = 0;     ///< refinements not taken (InertialEstimator::Report)
    int nonholonomic_updates = 0;     ///< frames held by the non-holonomic constraint
    int zero_velocity_updates = 0;    ///< frames held at zero velocity (the IMU at rest)
    int flow_updates = 0;             ///< frames given the optical flow's velocity
    double travel_side_ratio = -1.0;  ///< InertialEstimator::Report's (-1: not measured)
    std::string last_failure;
    Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();  ///< [rad/s]
    Eigen::Vector3d acc_bias = Eigen::Vector3d::Zero();   ///< [m/s^2]
    Eigen::Vector3d g_world = Eigen::Vector3d::Zero();    ///< in the active map's world [m/s^2]
  };
  InertialReport inertial_report() const;
  int num_maps() const { return atlas_.size(); }  ///< maps started (merged ones included)
  /// Gravity's direction in map `map_index`'s world (unit) once the IMU gave it, else false.
  bool MapGravityDirection(int map_index, Eigen::Vector3d* g_world) const;
  int live_maps() const;  ///< maps not merged into another
  int active_map() const { return active_; }
  bool has_vocabulary() const { return vocabulary_ != nullptr; }
  // Every estimated frame pose (OK, RELOCALISED, NEW_MAP), expressed in the final map.
  std::vector<FramePose> Trajectory() const;
  // Writes every live map of the atlas (map_io.h's versioned binary file). Waits for mapping.
  void SaveMap(const std::string& path, const std::string& version);
  // Loads the maps of a file into an atlas that has none yet (before the first frame): tracking
  // starts by relocalising in them. Refuses a file made with another rig, or when the tracker
  // has no vocabulary. The descriptor type is checked against the first frame's.
  void LoadMap(const std::string& path);

 private:
  // Matches of the local map around `reference_kf` in a frame, and the motion-only BA on them.
  struct LocalTracking {
    PoseOptimizerResult pose;
    /// With the IMU's prior, for a frame the points do not track: the pose from the prior and
    /// the matched lines alone (the inertial state's correction where the points are noise)
    PoseOptimizerResult line_pose;
    /// The world direction line_pose leaves unobserved (unit): the one its inlier lines share,
    /// else the camera's viewing direction
    Eigen::Vector3d line_pose_along_world = Eigen::Vector3d::Zero();
    std::vector<int> point_ids, keypoints, line_ids, segments;  ///< matched pairs
    /// matches of keypoints in invalid cells: left out of the pose, kept for the cell filter
    std::vector<int> masked_point_ids, masked_keypoints;
    /// per matched pair: the keypoint's refined position (track_refine_window_px), or NaN
    std::vector<Eigen::Vector2f> refined_uv;
    double weighted_inliers = 0.0;
    double matching_ms = 0.0;
    double optimisation_ms = 0.0;
  };
  // What the local map's pose optimisation of a frame the camera did not track may still give
  // the inertial state.
  struct WeakVision {
    bool with_prior = false;    ///< the optimisations had the IMU's prior
    PoseOptimizerResult all;    ///< with every match
    PoseOptimizerResult lines;  ///< with the matched lines alone (LocalTracking::line_pose)
    Eigen::Vector3d lines_along_world = Eigen::Vector3d::Zero();  ///< line_pose_along_world
    /// per segment: the map line of its inlier match in `lines`, or -1 (empty: `lines` failed)
    std::vector<int> line_match;
  };
  enum class Mode { kTracking, kRecentlyLost, kLost };
  // The weak vision of `tracking` (the local map's optimisation of `frame`) before relocalisation
  // overwrites it.
  static WeakVision WeakVisionOf(const StereoFrame& frame, const LocalTracking& tracking,
                                 bool have_prior);

  // TrackFrame's steps. The frame's inputs checked (complete lines; a loaded map's descriptors).
  void CheckFrameInput(const StereoFrame& frame);
  // A frame the local map did not track: relocalised (recently lost: in the active map; lost: in
  // every map), else, lost, tracked along the motion before the loss.
  void Recover(const StereoFrame& frame, const Rigid3d& predicted, TrackResult* result,
               LocalTracking* tracking, bool* tracked, bool* relocalised);
  // The match and inlier counts of `tracking` into the result.
  static void CountMatches(const LocalTracking& tracking, TrackResult* result);

  // Whether frames the camera does not track correct the inertial state with lines alone
  // (imu.weak_update_min_lines): INERTIAL keyframes observe the map lines they matched and are
  // held in local BA, and the local map's lines are cut to the part in front and in the image.
  bool LineAided() const { return options_.use_lines && options_.imu.weak_update_min_lines > 0; }
  double Weighted(int points, int lines) const {
    return points + options_.line_inlier_weight * lines;
  }
  // Track's work on one frame; `frame` is replaced by a completed copy when the frame takes its
  // left lines on demand (lines_on_demand).
  TrackResult TrackFrame(std::shared_ptr<const StereoFrame>& frame);
  // TrackFrame's states: the first frame of the run (a map starts or not), a frame tracked by the
  // local map or relocalised (its keyframe decision, the dynamic cells, the inertial state), and
  // a frame the camera did not track (INERTIAL, RECENTLY_LOST, LOST or a new map).
  TrackResult FirstFrame(std::shared_ptr<const StereoFrame>& frame, const Rigid3d& predicted,
                         TrackResult result);
  TrackResult TrackedFrame(std::shared_ptr<const StereoFrame>& frame, TrackResult result,
                           LocalTracking tracking, bool relocalised, bool project,
                           std::vector<bool> valid, const PosePrior* prior);
  // An INERTIAL frame at the IMU's pose `cam_from_world` becomes a keyframe when it has stereo
  // points for a map, or imu.keyframe_min_stereo_lines stereo lines.
  // `line_match`: per segment, the map line it observes, or -1 (empty: none).
  void InertialKeyFrame(std::shared_ptr<const StereoFrame>& frame, const Rigid3d& cam_from_world,
                        const std::vector<int>& line_match, TrackResult* result);
  TrackResult NotTracked(std::shared_ptr<const StereoFrame>& frame, TrackResult result,
                         const WeakVision& weak, const Rigid3d& predicted);
  // lines_on_demand: a keyframe tracked on its points takes its lines, matched to the local map
  // from that pose, and the pose is optimised again with them (TrackedFrame's part).
  void KeyframeWithLines(std::shared_ptr<const StereoFrame>& frame, TrackResult* result,
                         LocalTracking* tracking, std::vector<int>* line_match,
                         const std::vector<bool>& valid, const PosePrior* prior);
  bool StartMap(std::shared_ptr<const StereoFrame> frame, const Rigid3d& cam_from_world);
  static int StereoPoints(const StereoFrame& frame);  ///< keypoints with a stereo depth
  static int StereoLines(const StereoFrame& frame);   ///< segments with a stereo depth
  /// StartMap's first check: at least min(min_init_points, 15) stereo points (a lit frame)
  bool CouldStartMap(const StereoFrame& frame) const;
  // The frame with its stereo lines: itself, or a completed copy when they are pending and Track
  // was given a completer.
  std::shared_ptr<const StereoFrame> WithStereoLines(
      std::shared_ptr<const StereoFrame> frame) const;
  // The frame with its left lines: itself, or a completed copy when they are pending
  // (lines_on_demand) and Track was given a completer. Adds the time taken to `*ms`.
  std::shared_ptr<const StereoFrame> WithLeftLines(std::shared_ptr<const StereoFrame> frame,
                                                   double* ms = nullptr) const;
  // (by value: the pose follows a correction written meanwhile, see FollowAnchor).
  // pose_from_imu: a keyframe at the IMU's pose in the line-aided mode (KeyFrame::pose_from_imu);
  // the map lines it observes are refitted to its stereo lines and extended to its segments.
  void InsertKeyFrame(const std::shared_ptr<const StereoFrame>& frame, Rigid3d cam_from_world,
                      const std::vector<int>& point_matches, const std::vector<int>& line_matches,
                      const std::vector<bool>& valid_keypoints = {}, bool pose_from_imu = false,
                      bool camera_tracked = true);
  // What tracking needs of the local map around a reference keyframe, copied under the map
  // lock: the landmarks in front of the predicted camera, with their positions, descriptors and
  // predicted image positions, in id order. Matching and the motion-only BA run on it without
  // the lock (threaded mode: local mapping and loop closing go on meanwhile).
  struct LocalMapSnapshot {
    std::vector<int> point_ids;
    std::vector<Eigen::Vector3d> point_w;
    Eigen::Matrix<float, Eigen::Dynamic, 2, Eigen::RowMajor> point_uv;  ///< predicted [px]
    cv::Mat point_descriptors;                                          ///< one row per point
    std::vector<cv::Mat> point_patches;       ///< per point: MapPoint::patch (may be empty)
    std::vector<double> point_patch_depth_m;  ///< per point: MapPoint::patch_depth_m
    std::vector<int> line_ids;
    std::vector<PluckerLine> lines_w;
    std::vector<LineSegment> line_px;  ///< predicted segments [px]
    cv::Mat line_descriptors;          ///< one row per line
    double ms = 0.0;                   ///< time taken to copy it
  };
  // Caller holds map.mutex(). Marks the copied landmarks visible (found / visible culling); the
  // points not when `points_visible` is false (a frame tracked again: they were counted).
  // The segment map line `line` projects to from cam_from_world, for matching; false when it is
  // not in view (in front, long enough, inside the image: LineAided cuts it to that part).
  bool ProjectMapLine(const MapLine& line, const Rigid3d& cam_from_world, LineSegment* proj) const;
  LocalMapSnapshot SnapshotLocalMap(const StereoFrame& frame, Map& map, int reference_kf,
                                    const Rigid3d& pred_cam_from_world,
                                    bool points_visible = true) const SLSLAM_REQUIRES(map.mutex());
  // No lock: guided matching of the snapshot in the frame and the motion-only BA. With
  // `refine_image` (the frame's left image, as stereo matching saw it) the matches are aligned
  // to their points' patches first (track_refine_window_px): tracking's own frames only, never
  // a keyframe re-tracked by loop verification on its thread.
  LocalTracking TrackSnapshot(const StereoFrame& frame, const LocalMapSnapshot& local,
                              const Rigid3d& pred_cam_from_world, float radius_scale,
                              const std::vector<bool>* valid_keypoints = nullptr,
                              const cv::Mat* refine_image = nullptr,
                              const PosePrior* prior = nullptr) const;
  // Both in one (caller holds map.mutex()): relocalisation, loop verification.
  LocalTracking TrackLocalMap(const StereoFrame& frame, Map& map, int reference_kf,
                              const Rigid3d& pred_cam_from_world, float radius_scale,
                              const std::vector<bool>* valid_keypoints = nullptr) const
      SLSLAM_REQUIRES(map.mutex());
  // Locks the live map of the active one (where a merge has moved it, threaded mode), makes it
  // the active map and returns its lock.
  std::unique_lock<Mutex> LockActiveMap();
  // Guided matching bounds for descriptors of this type, window scaled by radius_scale.
  GuidedMatchOptions GuidedOptions(int descriptor_type, float radius_scale) const;
  // Updates the dynamic-cell filter from the previous tracked frame's stereo keypoints matched
  // into this frame under the two frames' poses.
  void UpdateDynamicCells(const StereoFrame& frame, const Rigid3d& cam_from_world);
  // Marks inliers found, fills the per-feature matches and decides on a keyframe. Caller holds
  // map.mutex(). `decide_only`: the decision alone, nothing marked or changed (a frame on
  // projected keypoints asks whether it would become a keyframe). `projected`: the frame's
  // keypoints are projected ones (projected_max_frames).
  bool AcceptTracking(const StereoFrame& frame, Map& map, const LocalTracking& tracking,
                      std::vector<int>* point_match, std::vector<int>* line_match,
                      bool decide_only = false, bool projected = false)
      SLSLAM_REQUIRES(map.mutex());
  // The line part of AcceptTracking: marks the inlier lines found and fills their matches.
  void AcceptLines(Map& map, const LocalTracking& tracking, std::vector<int>* line_match)
      SLSLAM_REQUIRES(map.mutex());
  // Tries the maps in `order`; on success switches to that map and fills the pose and tracking.
  bool Relocalise(const StereoFrame& frame, const std::vector<int>& order, TrackResult* result,
                  LocalTracking* tracking);
  // One map: database candidates for the frame's words, matching, PnP, local map.
  bool RelocaliseInMap(const StereoFrame& frame, const BowVector& bow,
                       const FeatureVector& features, int map_index, LocalTracking* tracking,
                       int* keyframe_id);
  // The poses TrackAlongLossMotion starts from (cam_from_world each): the frozen pose, then the
  // pose before the loss moved on by fractions of the frames since, with the full pre-loss motion
  // and with its translation only.
  std::vector<Rigid3d> LossMotionHypotheses(const Rigid3d& frozen_cam_from_world) const;
  // Lost: the local map tracked from poses along the motion before the loss and from the frozen
  // pose, ranked by point inliers with a stereo depth: the best-ranked attempt with
  // lost_reentry_min_point_ratio of its point matches as inliers, else the local map searched
  // again from the best-ranked pose if that one has them, else none (pose.success false). The
  // caller takes it with twice min_inliers, or with min_inliers where `*confirmed`: the previous
  // frame's attempt agrees with it (lost_reentry_confirm_m).
  LocalTracking TrackAlongLossMotion(const StereoFrame& frame, const Rigid3d& frozen_cam_from_world,
                                     bool* confirmed);
  // The pose predicted for the next frame from the current motion model.
  void Predict(Rigid3d* pred_cam_from_world) const;
  void SetPose(const Rigid3d& cam_from_world, bool update_velocity);

  TrackerOptions options_;
  Atlas atlas_;
  std::unique_ptr<Vocabulary> vocabulary_;
  std::unique_ptr<LocalMapper> mapper_;
  bool keyframe_images_ = false;  // keyframes keep their left image for local mapping (patches)
  std::unique_ptr<DynamicCellFilter> dynamic_;   ///< null when options_.dynamic_cells is off
  std::unique_ptr<InertialEstimator> inertial_;  ///< from the first IMU sample on (use_imu)
  int inertial_map_ = -1;                        ///< the map whose world the inertial state is in
  int gravity_fits_ = 0;  ///< the estimator's fits (initialisations + refinements) given to a map
  /// The IMU samples since the last keyframe of the IMU chain (imu.local_ba_keyframes > 0).
  ImuBuffer keyframe_imu_;
  int imu_chain_keyframe_ = -1;  ///< the chain's last keyframe (-1: none)
  int imu_chain_map_ = -1;       ///< ... and its map
  int imu_chain_refined_ = 0;    ///< its local BAs the inertial state followed (FollowLocalBa)
  // The inertial state's prior on the frame's pose; false when there is none (no IMU, not
  // initialised, another map's world, samples missing).
  bool InertialPrior(const StereoFrame& frame, PosePrior* prior) const;
  // Gives the inertial estimator the pose the camera estimated for `frame` (in the active map's
  // world), with the pose optimiser's information (zero: none) and whether it had the prior.
  void InertialPose(const StereoFrame& frame, const Rigid3d& cam_from_world,
                    const Matrix6d& information, bool with_prior);
  // A new keyframe (at camera time t_ns) of the active map `map` joins the IMU chain with the
  // inertial state at its time (imu.local_ba_keyframes > 0; the state must be at t_ns, in the
  // map's world), and the map gets the IMU settings; else the chain ends. Caller holds the lock.
  // `same_world`: the inertial state is in the map's world (no correction landed since the frame
  // was tracked).
  void AttachImu(int64_t t_ns, bool camera_tracked, bool same_world, Map* map, KeyFrame* kf)
      SLSLAM_REQUIRES(map->mutex());
  // Local BA estimated the IMU chain's last keyframe again: the inertial state restarts from it
  // (its pose, velocity and biases, propagated to the state's time), as ORB-SLAM3's tracking
  // predicts from the last keyframe once local mapping changed the map; not from a keyframe the
  // camera did not track (INERTIAL), whose points say little.
  void FollowLocalBa();
  // A frame the camera did not track: true (and the frame's pose) when the inertial state
  // carries it, after the weak visual correction `weak` may give; *by_lines when its lines alone
  // gave it.
  bool InertialCarry(const StereoFrame& frame, const WeakVision& weak, Rigid3d* cam_from_world,
                     bool* by_lines);
  // The camera's motion from the frame before by optical flow into the carried state
  // (InertialOptions::flow_min_inliers), and the images it needs kept for the next frame.
  void InertialFlow(const StereoFrame& frame);
  // Past the lost bound (InertialOptions::resume_map_after_lost) a LOST frame propagates the
  // state on; false, and the state forgotten, once it cannot (samples missing, max_gap_s).
  bool InertialDeadReckon(const StereoFrame& frame);
  // A LOST frame that could start a map while the state dead-reckons: instead a keyframe of the
  // active map at the IMU's pose (the last pose; the caller restarts the state's pose uncertainty
  // there); false when the state's speed ran away or the frame makes no keyframe.
  bool ResumeMap(std::shared_ptr<const StereoFrame>& frame, TrackResult* result);
  void KeepFlowImages(const StereoFrame& frame, const cv::Mat& left, const cv::Mat& right);
  void FillInertial(TrackResult* result) const;
  // Aligns matched keypoints to their map points' patches in `image` (track_refine_window_px;
  // null or empty: none): fills tracking->refined_uv (rows of the snapshot: called before they
  // become map ids).
  void RefineTracks(const StereoFrame& frame, const LocalMapSnapshot& local,
                    const Rigid3d& pred_cam_from_world, const cv::Mat* image,
                    LocalTracking* tracking) const;
  // The frame, or a copy whose inlier keypoints sit at their refined positions (a keyframe's
  // observations in the local BA).
  std::shared_ptr<const StereoFrame> WithRefinedKeypoints(std::shared_ptr<const StereoFrame> frame,
                                                          const LocalTracking& tracking) const;
  const cv::Mat* current_left_ = nullptr;     ///< the image handed to Track, during the call
                                              ///< (tracking's thread only)
  const cv::Mat* current_right_ = nullptr;    ///< (as current_left_)
  cv::Mat flow_prev_left_, flow_prev_right_;  ///< the previous frame's images (InertialFlow)
  std::optional<int64_t> flow_prev_t_ns_;     ///< ... and its time; none: not kept
  int projected_run_ = 0;  ///< frames tracked on projected keypoints since the last detected one
  // Whether a frame given without keypoints is tracked on projected ones (projected_max_frames):
  // tracking strong, fewer than projected_max_frames in a row, not the frame after a keyframe.
  bool CanProject(const StereoFrame& frame) const;
  // A copy of the frame whose keypoints are the snapshot's points aligned in current_left_
  // (projected_max_frames), with the snapshot's descriptors and stereo columns searched in
  // current_right_.
  std::shared_ptr<const StereoFrame> WithProjectedKeypoints(
      std::shared_ptr<const StereoFrame> frame, const LocalMapSnapshot& local,
      const Rigid3d& pred_cam_from_world) const;
  std::shared_ptr<const StereoFrame> previous_frame_;  ///< last tracked frame (dynamic cells)
  Rigid3d previous_cam_from_world_;                    ///< of previous_frame_
  int active_ = -1;                                    ///< index of the map being tracked in
  Mode mode_ = Mode::kLost;
  int lost_count_ = 0;           ///< frames since tracking failed
  int lost_map_candidates_ = 0;  ///< lit lost frames since tracking failed (CouldStartMap)
  bool dead_reckoning_ = false;  ///< the state went on past the lost bound (ResumeMap)
  bool dynamic_masks_ = false;   ///< the dynamic-cell mask applies (last frame tracked strongly)
  Rigid3d loss_cam_from_world_;  ///< last estimated pose before a loss
  Rigid3d loss_velocity_;        ///< motion before the loss (as velocity_)
  /// the poses of the last consecutive frames set with a known motion (newest last), at most
  /// lost_motion_frames + 1: the mean motion before a loss
  std::deque<Rigid3d> recent_poses_;
  /// The previous frame's re-entry attempt along the loss motion that fell short of the bar
  /// (TrackAlongLossMotion): its frame, the map and correction epoch its pose is expressed in.
  struct LossCandidate {
    bool valid = false;
    int frame = 0;
    int map = -1;
    int epoch = -1;
    Rigid3d cam_from_world;
  } loss_candidate_;
  bool have_pose_ = false;
  Rigid3d last_cam_from_world_;
  Rigid3d velocity_;  ///< last camera from the camera before: T_last * T_prev^-1
  int last_keyframe_ = -1;
  int last_keyframe_frame_ = 0;
  int64_t last_keyframe_t_ns_ = 0;  ///< capture time of the frame of the last keyframe [ns]
  TrackingState last_state_ = TrackingState::kNotInitialized;  ///< of the last frame tracked
  std::optional<int64_t> last_relocalisation_t_ns_;  ///< the last relocalisation attempt's frame
  int first_tracked_ = 0;  ///< inliers of the first frame after the last keyframe
  // After a loop correction or merge moved the active map: the active map index and the last
  // pose follow (the pose through its reference keyframe).
  void FollowCorrections();
  void RecordFrame(const StereoFrame& frame, bool keyframe);

  // Threaded mode: the mapping thread may correct the map (a background global BA, a loop, a
  // merge) after this frame's pose was estimated against it and before the frame is recorded or
  // made a keyframe. The anchor is the reference keyframe's pose at estimation time; under each
  // later lock FollowAnchor moves the given poses with that keyframe into the corrected world
  // and returns true when it did. Never fires in sequential mode (nothing runs in between).
  // Caller holds the map's lock for both.
  void SetAnchor(const Map& map, int keyframe) SLSLAM_REQUIRES(map.mutex());
  bool FollowAnchor(const Map& map, std::initializer_list<Rigid3d*> cams_from_world)
      SLSLAM_REQUIRES(map.mutex());
  struct Anchor {
    int keyframe = -1;  ///< -1: none for this frame
    const Map* map = nullptr;
    int epoch = -1;
    Rigid3d ref_from_world;  ///< the keyframe's pose then
  };
  Anchor anchor_;

  struct FrameRecord {
    int index = 0;
    int64_t t_ns = 0;
    int map_index = -1;
    int reference_kf = -1;
    Rigid3d frame_from_ref;  ///< reference keyframe camera -> frame camera
    Rigid3d cam_from_world;  ///< the online estimate (fallback)
  };
  std::vector<FrameRecord> records_;
  int loaded_descriptor_type_ = -1;  ///< of a loaded map file (-1: none loaded)
  int loaded_descriptor_cols_ = 0;
  std::string loaded_path_;
  std::unique_ptr<LoopCloser> loop_closer_;
  int seen_epoch_ = -1;  ///< the active map's correction epoch the last pose is expressed in
  TrackingStats stats_;
  /// the completer given to the Track call in progress (null outside Track, or none given)
  const StereoLineCompleter* complete_stereo_lines_ = nullptr;
  const StereoLineCompleter* complete_left_lines_ = nullptr;  ///< during Track only
  /// point inliers of the last tracked frame (lines_on_demand); 0 after a loss
  int last_point_inliers_ = 0;
};

}  // namespace slslam
