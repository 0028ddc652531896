#include "slslam/tracking/tracker.h"

#include <algorithm>
#include <map>
#include <stdexcept>

#include <Eigen/Geometry>

#include "slslam/core/check.h"
#include "slslam/core/time.h"
#include "slslam/tracking/keyframe_decision.h"
#include "slslam/tracking/stereo_flow.h"
#include "slslam/tracking/tracker_internal.h"

namespace slslam {

using tracker_detail::Clock;
using tracker_detail::Ms;

namespace {
// Threaded local mapping: keyframes that may wait for it (ORB-SLAM3's stereo limit). Past it
// tracking goes on from the last keyframe until the queue shrinks.
constexpr int kMaxQueuedKeyFrames = 3;
// While the IMU carries the pose (frames INERTIAL), relocalisation in the active map is tried at
// most this often [s]: the carried pose already predicts where the map's points should be (the
// frame's own tracking tries them every frame), and each bag-of-words relocalisation that fails
// on a featureless lining costs about 24 ms of a 32 ms frame (shotcrete_l015_dust).
constexpr double kInertialRelocalisationIntervalS = 0.25;

// The keyframe rules of the tracker's options (the same keys, named for DecideKeyframe).
KeyframeRules KeyframeRulesOf(const TrackerOptions& o) {
  KeyframeRules r;
  r.max_frames = o.keyframe_max_frames;
  r.min_frames = o.keyframe_min_frames;
  r.min_frames_noisy = o.keyframe_min_frames_noisy;
  r.min_interval_s = o.keyframe_min_interval_s;
  r.track_ratio = o.keyframe_track_ratio;
  r.min_close_tracked = o.keyframe_min_inliers;
  r.min_inliers = o.min_inliers;
  r.weak_inliers = o.weak_keyframe_inliers;
  r.weak_frames = o.weak_keyframe_frames;
  return r;
}

// `frame` itself, or a copy completed by `completer` when the flag `pending` marks what it lacks
// (the right image's lines, or the left image's) and a completer was given; the copy's flag
// cleared.
std::shared_ptr<const StereoFrame> Completed(std::shared_ptr<const StereoFrame> frame,
                                             bool StereoFrame::*pending,
                                             const Tracker::StereoLineCompleter* completer) {
  if (!((*frame).*pending) || completer == nullptr || !*completer) return frame;
  auto full = std::make_shared<StereoFrame>(*frame);
  (*completer)(full.get());
  (*full).*pending = false;
  return full;
}
}  // namespace

const char* TrackingStateName(TrackingState state) {
  switch (state) {
    case TrackingState::kNotInitialized:
      return "NOT_INITIALIZED";
    case TrackingState::kOk:
      return "OK";
    case TrackingState::kLost:
      return "LOST";
    case TrackingState::kNewMap:
      return "NEW_MAP";
    case TrackingState::kRecentlyLost:
      return "RECENTLY_LOST";
    case TrackingState::kRelocalised:
      return "RELOCALISED";
    case TrackingState::kInertial:
      return "INERTIAL";
  }
  return "UNKNOWN";
}

Tracker::Tracker(const TrackerOptions& options) : options_(options) {
  options_.Check();
  options_ = AdaptToRig(options_);
  options_.Check();
  if (!options_.vocabulary_path.empty()) {
    vocabulary_ = std::make_unique<Vocabulary>(Vocabulary::Load(options_.vocabulary_path));
  }
  LocalMapperOptions mapping = options_.mapping;
  mapping.point_sigma_px = options_.point_sigma_px;
  mapping.line_sigma_px = options_.line_sigma_px;
  mapping.triangulation.sigma_px = options_.point_sigma_px;
  mapping.triangulation.line_sigma_px = options_.line_sigma_px;
  mapping.triangulation.max_depth_baselines = options_.stereo.max_depth_baselines;
  mapping.triangulation.lines = options_.use_lines;
  mapping.triangulation.patch_window_px =
      options_.triangulated_point_patches ? options_.track_refine_window_px : 0;
  if (!options_.use_lines) mapping.ba.line_weight = 0.0;
  mapping.inertial_keyframes = options_.use_imu ? options_.imu.local_ba_keyframes : 0;
  mapping.triangulation.Check();
  // (a keyframe's image is of use only to local mapping's triangulated points' patches)
  keyframe_images_ = mapping.triangulate && mapping.triangulation.points &&
                     mapping.triangulation.patch_window_px > 0;
  mapper_ = std::make_unique<LocalMapper>(options_.rig, mapping, options_.sequential,
                                          options_.mapping_overlap);
  if (options_.dynamic_cells) {
    dynamic_ = std::make_unique<DynamicCellFilter>(options_.rig.camera.width,
                                                   options_.rig.camera.height, options_.dynamic);
  }
  if (vocabulary_ && !options_.localise_only &&
      (options_.loop_closing.enabled || options_.loop_closing.merge_maps)) {
    LoopClosingOptions loop = options_.loop_closing;
    loop.point_sigma_px = options_.point_sigma_px;
    loop.line_sigma_px = options_.line_sigma_px;
    loop.vocabulary_levels_up = options_.relocalisation.vocabulary_levels_up;
    if (!options_.use_lines) loop.global_ba_options.line_weight = 0.0;
    // Verification tracks the candidate's local map (points and lines) as tracking does.
    auto verifier = [this](const StereoFrame& frame, Map& map, int reference_kf,
                           const Rigid3d& cam_from_world) {
      map.mutex().AssertHeld();  // LocalMapVerifier's contract: the loop closer holds the lock
      LocalTracking t = TrackLocalMap(frame, map, reference_kf, cam_from_world, 1.0f);
      LocalMapMatch match;
      match.success = t.pose.success;
      match.cam_from_world = t.pose.cam_from_world;
      match.weighted_inliers = t.weighted_inliers;
      for (size_t i = 0; i < t.point_ids.size(); ++i) {
        if (!t.pose.point_inlier[i]) continue;
        match.point_ids.push_back(t.point_ids[i]);
        match.keypoints.push_back(t.keypoints[i]);
      }
      for (size_t i = 0; i < t.line_ids.size(); ++i) {
        if (!t.pose.line_inlier[i]) continue;
        match.line_ids.push_back(t.line_ids[i]);
        match.segments.push_back(t.segments[i]);
      }
      return match;
    };
    loop_closer_ = std::make_unique<LoopCloser>(options_.rig, loop, vocabulary_.get(),
                                                options_.max_distance_binary,
                                                options_.max_distance_float, verifier,
                                                /*background_global_ba=*/!options_.sequential);
    mapper_->SetAfterKeyFrame([this](Map* map, int keyframe_id) {
      for (int m = 0; m < atlas_.size(); ++m) {
        if (&atlas_.map(m) == map) {
          loop_closer_->Process(&atlas_, m, keyframe_id);
          return;
        }
      }
    });
  }
}

LoopClosingStats Tracker::loop_stats() const {
  return loop_closer_ ? loop_closer_->stats() : LoopClosingStats{};
}

void Tracker::FollowCorrections() {
  if (active_ < 0) return;
  const int resolved = atlas_.Resolve(active_);
  Map& map = atlas_.map(resolved);
  MutexLock lock(map.mutex());
  if (resolved == active_ && map.correction_epoch() == seen_epoch_) return;
  const int before_active = active_;
  active_ = resolved;
  seen_epoch_ = map.correction_epoch();
  // The last pose relative to the reference keyframe, as recorded, on the keyframe's new pose;
  // the inertial state follows it into the corrected world (or is forgotten when it cannot).
  bool followed = false;
  if (!records_.empty() && have_pose_) {
    const FrameRecord& r = records_.back();
    Rigid3d ref_from_world;
    if (r.reference_kf >= 0 && map.KeyFramePose(r.reference_kf, &ref_from_world)) {
      const Rigid3d before = last_cam_from_world_;
      last_cam_from_world_ = r.frame_from_ref * ref_from_world;
      followed = true;
      if (inertial_ && inertial_map_ == before_active) {
        // world_new_from_world_old = (cam_from_world_new)^-1 * cam_from_world_old
        inertial_->ChangeWorld(last_cam_from_world_.Inverse() * before);
        inertial_map_ = active_;
      }
    }
  }
  if (inertial_ && !followed) inertial_->Reset();
}

std::unique_lock<Mutex> Tracker::LockActiveMap() {
  // A merge marks the source map merged under the locks of both maps, so once the lock of a map
  // that is not merged is held, it stays the live one until the lock is released.
  for (;;) {
    const int live = atlas_.Resolve(active_);
    std::unique_lock<Mutex> lock(atlas_.map(live).mutex());
    if (!atlas_.merged(live)) {
      active_ = live;
      return lock;
    }
  }
}

Tracker::~Tracker() {
  mapper_.reset();       // drains and joins the mapping thread before the maps go,
  loop_closer_.reset();  // then a global BA still running in the background
}

void Tracker::Flush() {
  mapper_->Flush();
  if (loop_closer_) loop_closer_->WaitForGlobalBa();
}

void Tracker::AddImu(int64_t t_ns, const Eigen::Vector3d& gyro_radps,
                     const Eigen::Vector3d& acc_mps2) {
  if (!options_.use_imu) return;
  if (!inertial_) inertial_ = std::make_unique<InertialEstimator>(options_.imu);
  inertial_->AddImu(t_ns, gyro_radps, acc_mps2);
  if (options_.imu.local_ba_keyframes > 0) keyframe_imu_.Add(t_ns, gyro_radps, acc_mps2);
}

bool Tracker::InertialPrior(const StereoFrame& frame, PosePrior* prior) const {
  return inertial_ && inertial_->initialised() && inertial_map_ == active_ &&
         inertial_->PosePriorAt(frame.t_ns, prior);
}

void Tracker::InertialPose(const StereoFrame& frame, const Rigid3d& cam_from_world,
                           const Matrix6d& information, bool with_prior) {
  if (!inertial_) return;
  // (without a chain to extend, the next keyframe's interval starts after this frame)
  if (options_.imu.local_ba_keyframes > 0 && imu_chain_keyframe_ < 0) {
    keyframe_imu_.DropBefore(frame.t_ns - options_.imu.time_offset_ns());
  }
  // A relocalised or re-entered frame after the bound: not from a state whose speed ran away
  // (as ResumeMap).
  if (dead_reckoning_ && inertial_->initialised() && !inertial_->SpeedPlausible()) {
    inertial_->Reset();
  }
  dead_reckoning_ = false;
  if (inertial_map_ != active_) {  // another map's world: the state before does not fit
    inertial_->Reset();
    inertial_map_ = active_;
  }
  inertial_->AddVisualPose(frame.t_ns, cam_from_world, information, with_prior);
  // The map learns gravity's direction from each (re)initialisation (loop correction in 4 DoF).
  const InertialEstimator::Report& report = inertial_->report();
  const int fits = report.initialisations + report.refinements;
  if (inertial_->initialised() && fits != gravity_fits_) {
    gravity_fits_ = fits;
    const std::unique_lock<Mutex> lock = LockActiveMap();
    Map& map = atlas_.map(active_);
    map.mutex().AssertHeld();  // locked by LockActiveMap
    map.set_gravity_direction(inertial_->g_world());
  }
}

bool Tracker::InertialCarry(const StereoFrame& frame, const WeakVision& weak,
                            Rigid3d* cam_from_world, bool* by_lines) {
  *by_lines = false;
  if (!inertial_ || !inertial_->initialised() || inertial_map_ != active_) return false;
  // Too few inliers to count as tracked, enough to correct the state (the optimisation had the
  // prior: its information is the posterior's): all its matches, or its lines alone.
  const PoseOptimizerResult& all = weak.all;
  const int min_inliers = options_.imu.weak_update_min_inliers;
  const int min_lines = options_.imu.weak_update_min_lines;
  const auto usable = [&](const PoseOptimizerResult& pose) {
    return weak.with_prior && pose.success && !pose.information.isZero(0.0);
  };
  if (min_inliers > 0 && all.point_inliers + all.line_inliers >= min_inliers && usable(all)) {
    inertial_->AddVisualPose(frame.t_ns, all.cam_from_world, all.information,
                             /*with_prior=*/true);
    ++stats_.inertial_weak_updates;
  } else if (min_lines > 0 && weak.lines.line_inliers >= min_lines && usable(weak.lines)) {
    inertial_->AddVisualPose(frame.t_ns, weak.lines.cam_from_world, weak.lines.information,
                             /*with_prior=*/true, weak.lines_along_world);
    ++stats_.inertial_weak_updates;
    *by_lines = true;
  } else if (!inertial_->Propagate(frame.t_ns)) {
    inertial_->Reset();
    return false;
  }
  InertialFlow(frame);
  if (!inertial_->Trustworthy()) {
    // (the frame is LOST; the state may still place the map's part after the stretch)
    dead_reckoning_ = options_.imu.resume_map_after_lost && !options_.localise_only &&
                      inertial_->seconds_without_vision() <= options_.imu.max_gap_s;
    if (!dead_reckoning_) inertial_->Reset();
    return false;
  }
  *cam_from_world = inertial_->cam_from_world();
  return true;
}

bool Tracker::InertialDeadReckon(const StereoFrame& frame) {
  if (!dead_reckoning_) return false;
  if (inertial_ && inertial_->initialised() && inertial_map_ == active_) {
    // (the frame the bound was passed on: InertialCarry propagated it, its flow included)
    if (frame.t_ns == inertial_->state_t_ns()) return true;
    if (frame.t_ns > inertial_->state_t_ns() && inertial_->Propagate(frame.t_ns)) {
      InertialFlow(frame);
      if (inertial_->seconds_without_vision() <= options_.imu.max_gap_s) return true;
    }
  }
  dead_reckoning_ = false;
  if (inertial_) inertial_->Reset();
  return false;
}

bool Tracker::ResumeMap(std::shared_ptr<const StereoFrame>& frame, TrackResult* result) {
  if (!inertial_->SpeedPlausible()) return false;  // (a new map starts instead)
  // (the last pose first: InsertKeyFrame moves it with the keyframe's through a correction of
  // the map written meanwhile)
  SetPose(inertial_->cam_from_world(), /*update_velocity=*/false);
  InertialKeyFrame(frame, last_cam_from_world_, /*line_match=*/{}, result);
  if (!result->keyframe) return false;
  ++stats_.maps_resumed;
  ++stats_.inertial_frames;  // (its state is INERTIAL)
  return true;
}

void Tracker::KeepFlowImages(const StereoFrame& frame, const cv::Mat& left, const cv::Mat& right) {
  if (!options_.use_imu || options_.imu.flow_min_inliers <= 0 || left.empty() || right.empty()) {
    flow_prev_t_ns_.reset();
    return;
  }
  // (copies: the caller's buffers may be reused for the next frame)
  left.copyTo(flow_prev_left_);
  right.copyTo(flow_prev_right_);
  flow_prev_t_ns_ = frame.t_ns;
}

void Tracker::InertialFlow(const StereoFrame& frame) {
  // (no previous images: the flow is off, or the frame before had none)
  if (!flow_prev_t_ns_ || current_left_ == nullptr || !(*flow_prev_t_ns_ < frame.t_ns)) {
    return;
  }
  const std::optional<StereoFlowMotion> motion =
      MeasureStereoFlow(flow_prev_left_, flow_prev_right_, *current_left_, options_.rig,
                        options_.imu.flow_min_inliers);
  if (motion) {
    inertial_->AddCameraMotion(*flow_prev_t_ns_, frame.t_ns, motion->cur_from_prev,
                               motion->covariance);
  }
}

void Tracker::AttachImu(int64_t t_ns, bool camera_tracked, bool same_world, Map* map,
                        KeyFrame* kf) {
  if (options_.imu.local_ba_keyframes <= 0) return;
  const bool stateful = same_world && inertial_ && inertial_->initialised() &&
                        inertial_map_ == active_ && inertial_->state_t_ns() == t_ns;
  const int64_t offset_ns = options_.imu.time_offset_ns();
  if (!stateful) {
    imu_chain_keyframe_ = -1;
    keyframe_imu_.DropBefore(t_ns - offset_ns);
    return;
  }
  const int64_t t_imu_ns = t_ns - offset_ns;
  KeyFrameInertial imu;
  imu.t_ns = t_ns;
  imu.v_world_body = inertial_->state().nav.v_world_body;
  imu.bias = inertial_->state().bias;
  imu.camera_tracked = camera_tracked;
  auto previous = imu_chain_map_ == active_ ? map->keyframe(imu_chain_keyframe_) : nullptr;
  if (previous && previous->inertial) {
    imu.previous = previous->id;
    imu.samples_from_previous = keyframe_imu_.Slice(previous->inertial->t_ns - offset_ns, t_imu_ns);
  }
  kf->inertial = std::move(imu);
  keyframe_imu_.DropBefore(t_imu_ns);
  imu_chain_keyframe_ = kf->id;
  imu_chain_map_ = active_;
  imu_chain_refined_ = 0;
  MapInertial settings;
  settings.body_from_cam = options_.imu.body_from_cam;
  settings.g_world = inertial_->g_world();
  settings.noise = options_.imu.Noise();
  settings.time_offset_s = options_.imu.time_offset_s;
  settings.max_sample_gap_s = options_.imu.max_sample_gap_s;
  const Eigen::Matrix3d gravity_covariance =
      inertial_->state().covariance.bottomRightCorner<3, 3>();
  // (per axis across gravity: half the trace of its covariance, the radial part included; a
  // floor of 0.1 mrad, about 0.006 degrees, keeps the prior finite)
  constexpr double kMinGravitySigmaRad = 1e-4;
  settings.gravity_sigma_rad = std::max(
      kMinGravitySigmaRad, std::sqrt(0.5 * gravity_covariance.trace()) / options_.imu.gravity_mps2);
  map->set_inertial(settings);
}

void Tracker::FollowLocalBa() {
  if (options_.imu.local_ba_keyframes <= 0 || imu_chain_keyframe_ < 0 || !inertial_ ||
      !inertial_->initialised() || inertial_map_ != active_ || imu_chain_map_ != active_) {
    return;
  }
  KeyFrameInertial imu;
  Rigid3d cam_from_world;
  Eigen::Vector3d g_world;
  {
    const std::unique_lock<Mutex> lock = LockActiveMap();
    Map& map = atlas_.map(active_);
    map.mutex().AssertHeld();  // locked by LockActiveMap
    auto kf = map.keyframe(imu_chain_keyframe_);
    if (!kf || !kf->inertial || !kf->inertial->camera_tracked ||
        kf->inertial->refined == imu_chain_refined_) {
      return;
    }
    imu_chain_refined_ = kf->inertial->refined;
    imu.t_ns = kf->inertial->t_ns;
    imu.v_world_body = kf->inertial->v_world_body;
    imu.bias = kf->inertial->bias;
    cam_from_world = kf->cam_from_world;
    if (!map.inertial()) return;
    g_world = map.inertial()->g_world;
  }
  inertial_->Rebase(imu.t_ns, cam_from_world, imu.v_world_body, imu.bias, g_world);
}

bool Tracker::MapGravityDirection(int map_index, Eigen::Vector3d* g_world) const {
  if (map_index < 0 || map_index >= atlas_.size()) return false;
  Map& map = atlas_.map(map_index);
  MutexLock lock(map.mutex());
  if (!map.gravity_direction()) return false;
  *g_world = *map.gravity_direction();
  return true;
}

Tracker::WeakVision Tracker::WeakVisionOf(const StereoFrame& frame, const LocalTracking& tracking,
                                          bool have_prior) {
  WeakVision weak;
  weak.with_prior = have_prior;
  weak.all = tracking.pose;
  weak.lines = tracking.line_pose;
  weak.lines_along_world = tracking.line_pose_along_world;
  if (weak.lines.success) {
    // (an INERTIAL keyframe observes these map lines rather than making new ones)
    weak.line_match.assign(frame.NumLines(), -1);
    for (size_t i = 0; i < tracking.segments.size(); ++i) {
      if (weak.lines.line_inlier[i]) weak.line_match[tracking.segments[i]] = tracking.line_ids[i];
    }
  }
  return weak;
}

Tracker::InertialReport Tracker::inertial_report() const {
  InertialReport r;
  if (!inertial_) return r;
  r.has_imu = true;
  r.initialised = inertial_->initialised();
  const InertialEstimator::Report& e = inertial_->report();
  r.first_pose_t_ns = e.first_pose_t_ns;
  r.first_init_t_ns = e.first_init_t_ns;
  r.initialisations = e.initialisations;
  r.refinements = e.refinements;
  r.rejected_refinements = e.rejected_refinements;
  r.nonholonomic_updates = e.nonholonomic_updates;
  r.zero_velocity_updates = e.zero_velocity_updates;
  r.flow_updates = e.flow_updates;
  r.travel_side_ratio = e.travel_side_ratio;
  r.last_failure = e.last_failure;
  r.gyro_bias = inertial_->state().bias.gyro;
  r.acc_bias = inertial_->state().bias.acc;
  r.g_world = inertial_->g_world();
  return r;
}

void Tracker::FillInertial(TrackResult* result) const {
  result->imu_initialised = inertial_ && inertial_->initialised() && inertial_map_ == active_;
  result->position_sigma_m = 0.0;
  result->v_world_body.setZero();
  result->gyro_bias.setZero();
  result->acc_bias.setZero();
  if (!result->imu_initialised) return;
  const InertialState& state = inertial_->state();
  result->position_sigma_m = state.PositionSigma();
  result->v_world_body = state.nav.v_world_body;
  result->gyro_bias = state.bias.gyro;
  result->acc_bias = state.bias.acc;
}

void Tracker::Predict(Rigid3d* pred_cam_from_world) const {
  *pred_cam_from_world = last_cam_from_world_;
  if (have_pose_) *pred_cam_from_world = velocity_ * last_cam_from_world_;
}

void Tracker::SetPose(const Rigid3d& cam_from_world, bool update_velocity) {
  if (!(update_velocity && have_pose_)) recent_poses_.clear();
  recent_poses_.push_back(cam_from_world);
  while (static_cast<int>(recent_poses_.size()) > options_.lost_motion_frames + 1) {
    recent_poses_.pop_front();
  }
  if (update_velocity && have_pose_) {
    // R_v = R_cw R_last^T, t_v = t_cw - R_v t_last (as written, not T_cw * T_last^-1).
    velocity_.rotation = cam_from_world.rotation * last_cam_from_world_.rotation.transpose();
    velocity_.translation =
        cam_from_world.translation - velocity_.rotation * last_cam_from_world_.translation;
  } else if (!update_velocity) {
    velocity_ = Rigid3d();
  }
  last_cam_from_world_ = cam_from_world;
  have_pose_ = true;
}

std::shared_ptr<const StereoFrame> Tracker::WithLeftLines(std::shared_ptr<const StereoFrame> frame,
                                                          double* ms) const {
  const auto start = Clock::now();
  const bool pending = frame->left_lines_pending;
  frame = Completed(std::move(frame), &StereoFrame::left_lines_pending, complete_left_lines_);
  if (pending && ms != nullptr) *ms += Ms(start);
  return frame;
}

std::shared_ptr<const StereoFrame> Tracker::WithStereoLines(
    std::shared_ptr<const StereoFrame> frame) const {
  frame = WithLeftLines(std::move(frame));  // (stereo lines are matched to the left ones)
  return Completed(std::move(frame), &StereoFrame::stereo_lines_pending, complete_stereo_lines_);
}

int Tracker::StereoLines(const StereoFrame& frame) {
  int stereo_lines = 0;
  for (bool has : frame.line_has_depth) stereo_lines += has;
  return stereo_lines;
}

int Tracker::StereoPoints(const StereoFrame& frame) {
  int stereo_points = 0;
  for (double d : frame.depth) stereo_points += d > 0.0;
  return stereo_points;
}

bool Tracker::CouldStartMap(const StereoFrame& frame) const {
  // (too few points already: the right image's lines cannot start a map)
  return StereoPoints(frame) >= std::min(options_.min_init_points, 15);
}

bool Tracker::StartMap(std::shared_ptr<const StereoFrame> frame, const Rigid3d& cam_from_world) {
  if (!CouldStartMap(*frame)) return false;
  const int stereo_points = StereoPoints(*frame);
  int stereo_lines = 0;
  if (options_.use_lines) {
    frame = WithStereoLines(std::move(frame));
    stereo_lines = StereoLines(*frame);
  }
  // A map needs some points: lines alone leave the first keyframe's pose weakly constrained.
  if (Weighted(stereo_points, stereo_lines) < options_.min_init_points) return false;
  active_ = atlas_.AddMap();
  ++stats_.maps_started;
  InsertKeyFrame(frame, cam_from_world, std::vector<int>(frame->NumKeypoints(), -1),
                 std::vector<int>(frame->NumLines(), -1));
  return true;
}

void Tracker::InsertKeyFrame(const std::shared_ptr<const StereoFrame>& frame,
                             Rigid3d cam_from_world, const std::vector<int>& point_matches,
                             const std::vector<int>& line_matches,
                             const std::vector<bool>& valid_keypoints, bool pose_from_imu,
                             bool camera_tracked) {
  BowVector bow;
  FeatureVector bow_features;
  if (vocabulary_ && frame->NumKeypoints() > 0) {
    vocabulary_->Transform(frame->keypoints.descriptors, &bow, &bow_features,
                           options_.relocalisation.vocabulary_levels_up);
  }
  int kf_id = -1;
  Map* live = nullptr;
  {
    // The map the frame was tracked in may have been merged into another since (threaded mode):
    // the keyframe goes into the live one, its pose follows the merge (FollowAnchor).
    const std::unique_lock<Mutex> lock = LockActiveMap();
    Map& map = atlas_.map(active_);
    map.mutex().AssertHeld();  // locked by LockActiveMap
    live = &map;
    // (the frame's pose is the last pose: both move with a correction written meanwhile)
    const bool corrected = FollowAnchor(map, {&cam_from_world, &last_cam_from_world_});
    if (corrected) seen_epoch_ = map.correction_epoch();
    auto kf = map.AddKeyFrame(cam_from_world, frame);
    kf_id = kf->id;
    kf->pose_from_imu = pose_from_imu;
    // (after a correction landed meanwhile the inertial state is in the world before it: the
    // chain ends rather than take its velocity)
    AttachImu(frame->t_ns, camera_tracked && !corrected, !corrected, &map, kf.get());
    if (keyframe_images_ && current_left_ != nullptr) {
      // (for local mapping's triangulated points, which sample their patches from it; a copy:
      // the caller's image is not the tracker's to keep. Released after local mapping.)
      kf->left_image = current_left_->clone();
    }
    kf->bow = bow;
    kf->bow_features = std::move(bow_features);
    const Rigid3d world_from_cam = cam_from_world.Inverse();
    for (int i = 0; i < frame->NumKeypoints(); ++i) {
      if (point_matches[i] >= 0 && map.point(point_matches[i])) {
        map.AddPointObservation(point_matches[i], kf_id, i);
      } else if (frame->depth[i] > 0.0 && (valid_keypoints.empty() || valid_keypoints[i])) {
        // (a keypoint in a cell the dynamic-cell filter invalidated makes no map point)
        const Eigen::Vector3d p_w = world_from_cam * frame->Backproject(options_.rig.camera, i);
        auto p = map.AddPoint(p_w, frame->keypoints.descriptors.row(i), kf_id);
        map.AddPointObservation(p->id, kf_id, i);
        if (options_.track_refine_window_px > 0 && current_left_ != nullptr) {
          // the image around its keypoint: later matches are aligned to it (RefineTracks)
          p->patch = tracker_detail::SamplePatch(*current_left_, frame->keypoints.uv(i, 0),
                                                 frame->keypoints.uv(i, 1),
                                                 options_.track_refine_window_px);
          p->patch_depth_m = frame->depth[i];
        }
      }
    }
    if (options_.use_lines) {
      for (int j = 0; j < frame->NumLines(); ++j) {
        if (line_matches[j] >= 0 && map.line(line_matches[j])) {
          map.AddLineObservation(line_matches[j], kf_id, j);
          if (pose_from_imu) {
            MapLine* line = map.line(line_matches[j]).get();
            // (the stereo endpoints of every such keyframe refit it: the camera drives along it,
            // which leaves its depth to stereo alone, and one stereo pair tilts it)
            if (frame->line_has_depth[j]) {
              if (line->stereo_support.empty()) {
                line->stereo_support = {{line->start, 1.0}, {line->end, 1.0}};
              }
              tracker_detail::AddStereoSupport(world_from_cam, frame->line_endpoints[j], line);
              tracker_detail::RefitToSupport(line);
            }
            tracker_detail::ExtendToSegment(
                options_.rig.camera, cam_from_world, frame->lines[j],
                options_.stereo.max_depth_baselines * options_.rig.baseline_m, line);
          }
        } else if (frame->line_has_depth[j]) {
          const Eigen::Vector3d s = world_from_cam * frame->line_endpoints[j][0];
          const Eigen::Vector3d e = world_from_cam * frame->line_endpoints[j][1];
          if ((e - s).norm() < 1e-3) continue;
          auto l = map.AddLine(PluckerLine::FromPoints(s, e), s, e, frame->line_descriptors.row(j),
                               kf_id);
          map.AddLineObservation(l->id, kf_id, j);
          if (pose_from_imu) {
            tracker_detail::AddStereoSupport(world_from_cam, frame->line_endpoints[j], l.get());
          }
        }
      }
    }
    map.UpdateConnections(kf_id);
  }
  if (!bow.empty()) atlas_.database(active_).Add(kf_id, bow);
  last_keyframe_ = kf_id;
  last_keyframe_frame_ = frame->index;
  last_keyframe_t_ns_ = frame->t_ns;
  first_tracked_ = 0;
  mapper_->Insert(live, kf_id);
}

void Tracker::AcceptLines(Map& map, const LocalTracking& tracking, std::vector<int>* line_match) {
  for (size_t i = 0; i < tracking.line_ids.size(); ++i) {
    if (!tracking.pose.line_inlier[i]) continue;
    auto l = map.line(tracking.line_ids[i]);
    if (!l || l->bad) continue;
    l->found += 1;
    (*line_match)[tracking.segments[i]] = tracking.line_ids[i];
  }
}

bool Tracker::AcceptTracking(const StereoFrame& frame, Map& map, const LocalTracking& tracking,
                             std::vector<int>* point_match, std::vector<int>* line_match,
                             bool decide_only, bool projected) {
  const PoseOptimizerResult& pose = tracking.pose;
  // The map lock was released after matching: local mapping (threaded) may have culled a
  // landmark since, so each is looked up again.
  for (size_t i = 0; i < tracking.point_ids.size(); ++i) {
    if (!pose.point_inlier[i]) continue;
    auto p = map.point(tracking.point_ids[i]);
    if (!p || p->bad) continue;
    if (!decide_only) p->found += 1;
    (*point_match)[tracking.keypoints[i]] = tracking.point_ids[i];
  }
  if (!decide_only) AcceptLines(map, tracking, line_match);
  // Keyframe decision (ORB-SLAM3's NeedNewKeyFrame for stereo, as with local mapping idle: it is
  // in sequential mode, and in threaded mode the queue absorbs the keyframe, unless mapping_brake
  // holds it back, below). Reference: the reference keyframe's map points seen by at least
  // min_obs keyframes.
  const int frames_since = frame.index - last_keyframe_frame_;
  int reference = 0;
  if (auto kf = map.keyframe(last_keyframe_)) {
    const int min_obs = map.keyframes().size() <= 2 ? 2 : 3;
    // (the ids sorted for one walk along the map's ordered points, Map::PointsOf, which gives a
    // repeated id each time: the same count as a search per keypoint)
    std::vector<int> ids;
    ids.reserve(kf->point_ids.size());
    for (int pid : kf->point_ids) {
      if (pid >= 0) ids.push_back(pid);
    }
    std::sort(ids.begin(), ids.end());
    for (const MapPoint* p : map.PointsOf(ids)) {
      if (p && !p->bad && static_cast<int>(p->observations.size()) >= min_obs) ++reference;
    }
  }
  // Close stereo points (depth < close_depth_baselines): tracked vs not yet in the map.
  const double close_depth = options_.close_depth_baselines * options_.rig.baseline_m;
  int close_tracked = 0, close_untracked = 0;
  for (int i = 0; i < frame.NumKeypoints(); ++i) {
    if (!(frame.depth[i] > 0.0 && frame.depth[i] < close_depth)) continue;
    if ((*point_match)[i] >= 0) {
      ++close_tracked;
    } else {
      ++close_untracked;
    }
  }
  const int tracked = pose.point_inliers;
  // A young map has few points seen by three keyframes; the inliers of the first frame tracked
  // after the keyframe stand in for the reference then (how many of its points can be tracked).
  // Detected frames only: projected ones keep one point per cell.
  const int first_tracked = first_tracked_ == 0 && frames_since >= 1 ? tracked : first_tracked_;
  if (!decide_only && !projected) first_tracked_ = first_tracked;
  KeyframeEvidence evidence;
  evidence.frames_since = frames_since;
  evidence.seconds_since = SecondsBetween(last_keyframe_t_ns_, frame.t_ns);
  evidence.noisy = frame.noisy;
  evidence.tracked = tracked;
  evidence.reference = std::max(reference, first_tracked);
  evidence.close_tracked = close_tracked;
  evidence.close_untracked = close_untracked;
  evidence.weighted_inliers = tracking.weighted_inliers;
  const KeyframeDecision decision = DecideKeyframe(evidence, KeyframeRulesOf(options_));
  // ORB-SLAM3's brake (mapping_brake, threaded mode; sequential local mapping is always idle):
  // while local mapping is busy the gap alone is no reason for a keyframe (c1b), and a keyframe
  // that is due stops the running local BA early and queues, unless kMaxQueuedKeyFrames wait.
  if (!options_.mapping_brake || !decision.insert || mapper_->Idle()) return decision.insert;
  if (!decision.due) return false;
  if (!decide_only) mapper_->InterruptBA();
  return mapper_->QueuedKeyFrames() < kMaxQueuedKeyFrames;
}

TrackResult Tracker::Track(std::shared_ptr<const StereoFrame> frame,
                           const StereoLineCompleter& complete_stereo_lines,
                           const cv::Mat& left_image,
                           const StereoLineCompleter& complete_left_lines,
                           const cv::Mat& right_image) {
  Require(frame != nullptr, "Track needs a frame");
  // The completers and the image are valid for this call only.
  struct CallScope {
    Tracker& tracker;
    ~CallScope() {
      tracker.complete_stereo_lines_ = nullptr;
      tracker.complete_left_lines_ = nullptr;
      tracker.current_left_ = nullptr;
      tracker.current_right_ = nullptr;
    }
  } scope{*this};
  complete_stereo_lines_ = &complete_stereo_lines;
  complete_left_lines_ = &complete_left_lines;
  current_left_ = &left_image;
  current_right_ = &right_image;
  TrackResult result = TrackFrame(frame);
  if (result.needs_keypoints) return result;  // (handed back: it comes again, counted then)
  last_state_ = result.state;
  KeepFlowImages(*frame, left_image, right_image);
  FillInertial(&result);
  // (the frame as it ended up: its left lines completed on demand or not)
  if (options_.use_lines && !frame->left_lines_pending) ++stats_.line_frames;
  result.frame_lines = frame->NumLines();
  return result;
}

namespace {
// A frame handed back before anything changed: it comes again with detected keypoints.
TrackResult HandedBack() {
  TrackResult handed_back;
  handed_back.needs_keypoints = true;
  return handed_back;
}
}  // namespace

void Tracker::CheckFrameInput(const StereoFrame& frame) {
  Require(!frame.left_lines_pending || (complete_left_lines_ && *complete_left_lines_),
          "a frame built without its left lines (lines_on_demand) needs Track's "
          "complete_left_lines");
  if (loaded_descriptor_type_ >= 0 && frame.NumKeypoints() > 0) {
    const cv::Mat& d = frame.keypoints.descriptors;
    SLSLAM_CHECK(d.type() == loaded_descriptor_type_ && d.cols == loaded_descriptor_cols_,
                 loaded_path_, ": the map was made with another point front end (descriptors of ",
                 loaded_descriptor_cols_, " ",
                 loaded_descriptor_type_ == CV_8U ? "bytes" : "floats", "; this run's have ",
                 d.cols, ")");
    loaded_descriptor_type_ = -1;  // checked once
  }
}

void Tracker::Recover(const StereoFrame& frame, const Rigid3d& predicted, TrackResult* result,
                      LocalTracking* tracking, bool* tracked, bool* relocalised) {
  const bool throttled =
      last_state_ == TrackingState::kInertial && mode_ != Mode::kLost &&
      last_relocalisation_t_ns_ &&
      SecondsBetween(*last_relocalisation_t_ns_, frame.t_ns) < kInertialRelocalisationIntervalS;
  if (mode_ != Mode::kTracking && !throttled) {
    last_relocalisation_t_ns_ = frame.t_ns;
    // Recently lost: the active map only; lost: every map, the active one first, then the newest.
    std::vector<int> order = {active_};
    if (mode_ == Mode::kLost) {
      for (int m = atlas_.size() - 1; m >= 0; --m) {
        if (m != active_ && !atlas_.merged(m)) order.push_back(m);
      }
    }
    *relocalised = Relocalise(frame, order, result, tracking);
  }
  if (!*relocalised && mode_ == Mode::kLost && have_pose_) {
    bool confirmed = false;
    *tracking = TrackAlongLossMotion(frame, predicted, &confirmed);  // lost: it was empty
    // (a confirmed attempt holds min_inliers: TrackAlongLossMotion's candidate rule)
    *tracked = tracking->pose.success &&
               (confirmed || tracking->weighted_inliers >= 2.0 * options_.min_inliers);
  }
}

void Tracker::CountMatches(const LocalTracking& tracking, TrackResult* result) {
  result->matched_points = static_cast<int>(tracking.point_ids.size());
  result->matched_lines = static_cast<int>(tracking.line_ids.size());
  result->inlier_points = tracking.pose.point_inliers;
  result->inlier_lines = tracking.pose.line_inliers;
  result->weighted_inliers = tracking.weighted_inliers;
}

TrackResult Tracker::TrackFrame(std::shared_ptr<const StereoFrame>& frame) {
  TrackResult result;
  CheckFrameInput(*frame);
  // projected_max_frames: a frame given without its keypoints is tracked on the map's points
  // placed in it, or handed back (before anything changed) to come again with them. A frame
  // given with its keypoints is tracked on them: the caller decides which frames are detected
  // (Python's Tracker._detect_ahead, the same way in a pipeline and one frame at a time).
  const bool project = frame->keypoints_pending && CanProject(*frame);
  if (frame->keypoints_pending && !project) return HandedBack();
  // A loop correction or a merge may have moved the last pose (a merge into another map's
  // world): the prediction starts from where it is now.
  FollowCorrections();
  FollowLocalBa();
  anchor_ = Anchor{};
  Rigid3d predicted;  // cam_from_world
  // With the IMU initialised its propagated state predicts the pose and gives the frame's pose
  // optimisation its prior; otherwise the constant-velocity model predicts.
  PosePrior prior;
  bool have_prior = false;
  const auto predict = [&]() {
    Predict(&predicted);
    have_prior = mode_ != Mode::kLost && InertialPrior(*frame, &prior);
    if (have_prior) predicted = prior.mean;
  };
  predict();
  // lines_on_demand: a frame that starts a map, a frame while lost, and a frame after thin
  // tracking take their lines before anything else (as if extracted up front).
  if (frame->left_lines_pending && (atlas_.size() == 0 || mode_ != Mode::kTracking ||
                                    last_point_inliers_ < options_.lines_on_demand_inliers)) {
    frame = WithLeftLines(std::move(frame), &result.left_lines_ms);
  }
  if (atlas_.size() == 0)
    return FirstFrame(frame, predicted, std::move(result));  // not initialised yet

  LocalTracking tracking;
  bool tracked = false, relocalised = false;
  // Keypoints in cells the dynamic-cell filter invalidated up to the last frame.
  std::vector<bool> valid;
  if (dynamic_ && mode_ == Mode::kTracking && dynamic_masks_) {
    valid = dynamic_->KeypointMask(frame->keypoints.uv);
    result.masked_keypoints = static_cast<int>(std::count(valid.begin(), valid.end(), false));
  }
  auto track_local_map = [&](float scale, bool points_visible) {
    LocalMapSnapshot local;
    for (int attempt = 0;; ++attempt) {
      // The lock covers the copy only; matching and the pose run beside local mapping. The
      // anchor records the world the snapshot was taken in (FollowAnchor moves the estimate
      // with a correction written meanwhile).
      const int predicted_in = active_;
      std::unique_lock<Mutex> lock = LockActiveMap();
      Map& map = atlas_.map(active_);
      map.mutex().AssertHeld();  // locked by LockActiveMap
      if (attempt < 2 && (active_ != predicted_in || map.correction_epoch() != seen_epoch_)) {
        // A merge or correction landed since the prediction (threaded mode): predict again in
        // the new world rather than search the local map from the old one.
        lock.unlock();
        active_ = predicted_in;  // FollowCorrections sees the change and follows it
        FollowCorrections();
        predict();
        continue;
      }
      local = SnapshotLocalMap(*frame, map, last_keyframe_, predicted, points_visible);
      SetAnchor(map, last_keyframe_);
      break;
    }
    // (project: called once, the frame is handed back before a second pass)
    double projection_ms = 0.0;
    if (project) {
      const auto projection_start = Clock::now();
      frame = WithProjectedKeypoints(std::move(frame), local, predicted);
      projection_ms = Ms(projection_start);
      valid.clear();
      if (dynamic_ && dynamic_masks_) valid = dynamic_->KeypointMask(frame->keypoints.uv);
      result.masked_keypoints = static_cast<int>(std::count(valid.begin(), valid.end(), false));
    }
    // (projected keypoints are aligned to their patches already)
    tracking = TrackSnapshot(*frame, local, predicted, scale, &valid,
                             project ? nullptr : current_left_, have_prior ? &prior : nullptr);
    tracking.matching_ms += projection_ms;  // (placing the points is their matching)
  };
  if (mode_ != Mode::kLost) {
    const float scale = mode_ == Mode::kRecentlyLost ? options_.lost_search_scale : 1.0f;
    track_local_map(scale, /*points_visible=*/true);
    tracked = tracking.pose.success && tracking.weighted_inliers >= options_.min_inliers;
    if (project && (!tracked || tracking.pose.point_inliers < options_.projection_min_inliers)) {
      return HandedBack();
    }
    if (!tracked && frame->left_lines_pending) {
      // lines_on_demand: its points alone do not track it; again with its lines (both passes
      // timed).
      frame = WithLeftLines(std::move(frame), &result.left_lines_ms);
      const double first_matching_ms = tracking.matching_ms;
      const double first_optimisation_ms = tracking.optimisation_ms;
      track_local_map(scale, /*points_visible=*/false);
      tracking.matching_ms += first_matching_ms;
      tracking.optimisation_ms += first_optimisation_ms;
      tracked = tracking.pose.success && tracking.weighted_inliers >= options_.min_inliers;
    }
  }
  // The local map's pose optimisation (with the IMU prior), for the inertial state's weak
  // correction when the frame is not tracked; relocalisation below overwrites `tracking`.
  const WeakVision weak = WeakVisionOf(*frame, tracking, have_prior);
  if (!tracked) Recover(*frame, predicted, &result, &tracking, &tracked, &relocalised);
  CountMatches(tracking, &result);
  result.matching_ms = tracking.matching_ms;
  result.optimisation_ms = tracking.optimisation_ms;

  if (tracked || relocalised) {
    return TrackedFrame(frame, std::move(result), std::move(tracking), relocalised, project,
                        std::move(valid), have_prior ? &prior : nullptr);
  }
  return NotTracked(frame, std::move(result), weak, predicted);
}

TrackResult Tracker::FirstFrame(std::shared_ptr<const StereoFrame>& frame, const Rigid3d& predicted,
                                TrackResult result) {
  const auto start = Clock::now();
  if (options_.localise_only) {
    throw std::runtime_error("localise-only mode needs a loaded map (the atlas is empty)");
  }
  if (StartMap(frame, predicted)) {
    result.state = TrackingState::kOk;
    result.keyframe = true;
    mode_ = Mode::kTracking;
    SetPose(predicted, /*update_velocity=*/false);
    RecordFrame(*frame, /*keyframe=*/true);
    InertialPose(*frame, predicted, Matrix6d::Zero(), /*with_prior=*/false);
  } else {
    result.state = TrackingState::kNotInitialized;
  }
  result.cam_from_world = predicted;
  result.map_index = active_;
  result.mapping_ms = Ms(start);
  return result;
}

TrackResult Tracker::TrackedFrame(std::shared_ptr<const StereoFrame>& frame, TrackResult result,
                                  LocalTracking tracking, bool relocalised, bool project,
                                  std::vector<bool> valid, const PosePrior* prior) {
  // (tracked by the local map, or relocalised: exactly one of the two)
  std::vector<int> point_match(frame->NumKeypoints(), -1);
  std::vector<int> line_match(frame->NumLines(), -1);
  bool make_keyframe = false, want_keyframe = false;
  bool velocity_known = mode_ == Mode::kTracking;
  {
    // (the live map: merged into another meanwhile in threaded mode, see LockActiveMap)
    const std::unique_lock<Mutex> lock = LockActiveMap();
    Map& map = atlas_.map(active_);
    map.mutex().AssertHeld();  // locked by LockActiveMap
    // A keyframe takes detected keypoints (new points for the map): a frame on projected ones
    // that would become one is handed back (below), before anything changed.
    want_keyframe = project && !options_.localise_only &&
                    AcceptTracking(*frame, map, tracking, &point_match, &line_match,
                                   /*decide_only=*/true, /*projected=*/true);
    if (!want_keyframe) {
      // The last pose moves too when it was in the world the estimate was made in; otherwise
      // (a merge meanwhile) the motion between the two is unknown.
      const bool move_last = anchor_.map == &map && anchor_.epoch == seen_epoch_;
      Rigid3d* estimate = &tracking.pose.cam_from_world;
      if (move_last ? FollowAnchor(map, {estimate, &last_cam_from_world_})
                    : FollowAnchor(map, {estimate})) {
        if (move_last) seen_epoch_ = map.correction_epoch();
        velocity_known = velocity_known && move_last;
      }
      point_match.assign(frame->NumKeypoints(), -1);
      make_keyframe = AcceptTracking(*frame, map, tracking, &point_match, &line_match,
                                     /*decide_only=*/false, project) &&
                      !project;
    }
  }
  if (want_keyframe) return HandedBack();
  projected_run_ = project ? projected_run_ + 1 : 0;
  result.projected_keypoints = project ? frame->NumKeypoints() : 0;
  if (make_keyframe && !options_.localise_only && frame->left_lines_pending) {
    KeyframeWithLines(frame, &result, &tracking, &line_match, valid, prior);
  }
  last_point_inliers_ = tracking.pose.point_inliers;
  if (dynamic_) {
    // Thin tracking (low texture, dark, dust) masks nothing: its sparse frame-to-frame
    // evidence is noise-dominated, and every keypoint counts there (measured on the junction
    // with flicker, dust and a blackout: masking there lost 33 frames and split the map). The
    // weights still follow the evidence, so a mover seen while tracking is thin is masked as
    // soon as tracking is strong again.
    dynamic_masks_ = !relocalised && tracking.weighted_inliers >= options_.weak_keyframe_inliers;
    if (!relocalised) UpdateDynamicCells(*frame, tracking.pose.cam_from_world);
    if (relocalised) dynamic_->Reset();  // relocalised: the cells start afresh from here
    valid.clear();
    if (dynamic_masks_) valid = dynamic_->KeypointMask(frame->keypoints.uv);
    previous_frame_ = frame;
    previous_cam_from_world_ = tracking.pose.cam_from_world;
  }
  result.state = relocalised ? TrackingState::kRelocalised : TrackingState::kOk;
  result.cam_from_world = tracking.pose.cam_from_world;
  result.map_index = active_;
  // After a loss the velocity is unknown: start again from rest.
  SetPose(tracking.pose.cam_from_world, /*update_velocity=*/velocity_known);
  // (a relocalised pose has no information: the state takes it as it is)
  InertialPose(*frame, tracking.pose.cam_from_world,
               relocalised ? Matrix6d::Zero() : Matrix6d(tracking.pose.information),
               prior != nullptr && !relocalised);
  mode_ = Mode::kTracking;
  lost_count_ = 0;
  lost_map_candidates_ = 0;
  if (options_.localise_only) {
    // No keyframes are made: the reference keyframe (centre of the local map) moves to the
    // keyframe that observes most of this frame's inlier points (ORB-SLAM's local keyframes).
    const std::unique_lock<Mutex> lock = LockActiveMap();
    const Map& map = atlas_.map(active_);
    map.mutex().AssertHeld();  // locked by LockActiveMap
    std::map<int, int> seen;
    for (int pid : point_match) {
      auto p = pid >= 0 ? map.point(pid) : nullptr;
      if (!p) continue;
      for (const auto& [kf_id, idx] : p->observations) {
        (void)idx;
        ++seen[kf_id];
      }
    }
    int best = 0;
    for (const auto& [kf_id, count] : seen) {
      if (count > best) {
        best = count;
        last_keyframe_ = kf_id;
      }
    }
  }
  if (make_keyframe && !options_.localise_only) {
    const auto start = Clock::now();
    frame = WithRefinedKeypoints(std::move(frame), tracking);
    if (options_.use_lines) frame = WithStereoLines(std::move(frame));
    InsertKeyFrame(frame, tracking.pose.cam_from_world, point_match, line_match, valid);
    result.keyframe = true;
    result.mapping_ms = Ms(start);
  }
  RecordFrame(*frame, result.keyframe);
  return result;
}

void Tracker::KeyframeWithLines(std::shared_ptr<const StereoFrame>& frame, TrackResult* result_out,
                                LocalTracking* tracking_out, std::vector<int>* line_match_out,
                                const std::vector<bool>& valid_in, const PosePrior* prior) {
  TrackResult& result = *result_out;
  LocalTracking& tracking = *tracking_out;
  std::vector<int>& line_match = *line_match_out;
  const std::vector<bool>& valid = valid_in;
  // lines_on_demand: a keyframe tracked on its points. Its lines are matched to the local map
  // from the pose its points gave, and the pose is optimised again with them. The keyframe
  // keeps its points' matches from the first tracking (the second, pulled by the lines,
  // keeps fewer: taking its matches drifted more on the dark sequences,
  // benchmarks/log/realtime.md); its keypoints are refined as the second tracking aligned them
  // (below), and it is made either way. The local map is copied again in the world the estimate is
  // in (the anchor's): when a correction or a merge landed since (threaded mode), the
  // keyframe goes in without matched lines rather than mix two worlds.
  frame = WithLeftLines(std::move(frame), &result.left_lines_ms);
  line_match.assign(frame->NumLines(), -1);
  const Rigid3d points_pose = tracking.pose.cam_from_world;
  LocalMapSnapshot local;
  bool same_world = false;
  {
    const std::unique_lock<Mutex> lock = LockActiveMap();
    Map& map = atlas_.map(active_);
    map.mutex().AssertHeld();  // locked by LockActiveMap
    same_world = anchor_.map == &map && anchor_.epoch == map.correction_epoch();
    if (same_world) {
      local = SnapshotLocalMap(*frame, map, last_keyframe_, points_pose,
                               /*points_visible=*/false);
    }
  }
  if (same_world) {
    LocalTracking with_lines =
        TrackSnapshot(*frame, local, points_pose, 1.0f, &valid, current_left_, prior);
    result.matching_ms += with_lines.matching_ms;
    result.optimisation_ms += with_lines.optimisation_ms;
    if (with_lines.pose.success && with_lines.weighted_inliers >= options_.min_inliers) {
      const std::unique_lock<Mutex> lock = LockActiveMap();
      Map& map = atlas_.map(active_);
      map.mutex().AssertHeld();  // locked by LockActiveMap
      AcceptLines(map, with_lines, &line_match);
      tracking = std::move(with_lines);
      CountMatches(tracking, &result);
    }
  }
}

void Tracker::InertialKeyFrame(std::shared_ptr<const StereoFrame>& frame,
                               const Rigid3d& cam_from_world, const std::vector<int>& line_match,
                               TrackResult* result) {
  const auto start = Clock::now();
  const bool points = CouldStartMap(*frame);
  const int min_lines = options_.imu.keyframe_min_stereo_lines;
  if (!points && (!options_.use_lines || min_lines <= 0)) return;
  if (frame->left_lines_pending) frame = WithLeftLines(std::move(frame), &result->left_lines_ms);
  // (a frame with too few left lines needs no right ones)
  if (!points && frame->NumLines() < min_lines) return;
  std::shared_ptr<const StereoFrame> keyframe = frame;
  if (options_.use_lines) keyframe = WithStereoLines(std::move(keyframe));
  if (!points && StereoLines(*keyframe) < min_lines) return;
  std::vector<int> lines = line_match;
  lines.resize(keyframe->NumLines(), -1);
  InsertKeyFrame(keyframe, cam_from_world, std::vector<int>(keyframe->NumKeypoints(), -1), lines,
                 {}, /*pose_from_imu=*/LineAided(), /*camera_tracked=*/false);
  ++stats_.inertial_keyframes;
  result->keyframe = true;
  result->mapping_ms = Ms(start);
}

TrackResult Tracker::NotTracked(std::shared_ptr<const StereoFrame>& frame, TrackResult result,
                                const WeakVision& weak, const Rigid3d& predicted) {
  // Not tracked. Recently lost: follow the prediction with a decaying velocity. Lost: freeze.
  anchor_ = Anchor{};
  last_point_inliers_ = 0;
  if (dynamic_) {
    dynamic_->Reset();
    previous_frame_ = nullptr;
    dynamic_masks_ = false;
  }
  if (mode_ == Mode::kTracking) {  // the last estimate and the motion before the loss
    loss_cam_from_world_ = last_cam_from_world_;
    loss_velocity_ = velocity_;
    if (recent_poses_.size() >= 3) {
      // The mean per-frame motion over the recent frames: T_newest T_oldest^-1 taken to the
      // 1/n (the rotation's angle divided, the translation too: exact for a constant rotation).
      const Rigid3d& oldest = recent_poses_.front();
      const Rigid3d& newest = recent_poses_.back();
      const double n = static_cast<double>(recent_poses_.size() - 1);
      const Eigen::Matrix3d R = newest.rotation * oldest.rotation.transpose();
      const Eigen::AngleAxisd per_frame(R);
      loss_velocity_.rotation =
          Eigen::AngleAxisd(per_frame.angle() / n, per_frame.axis()).toRotationMatrix();
      loss_velocity_.translation = (newest.translation - R * oldest.translation) / n;
    }
    recent_poses_.clear();
  }
  ++lost_count_;
  // The camera contributed too little: while the inertial state's uncertainty allows, its pose
  // is the frame's, and the frame is recorded. Tracking goes on retrying the local map around it
  // (a wider window, as recently lost).
  Rigid3d inertial;
  bool by_lines = false;
  if (mode_ != Mode::kLost && InertialCarry(*frame, weak, &inertial, &by_lines)) {
    if (by_lines) {
      // (the lines it was corrected by were found where expected, as in a tracked frame)
      const std::unique_lock<Mutex> lock = LockActiveMap();
      Map& map = atlas_.map(active_);
      map.mutex().AssertHeld();  // locked by LockActiveMap
      for (int lid : weak.line_match) {
        if (auto l = lid >= 0 ? map.line(lid) : nullptr) l->found += 1;
      }
    }
    mode_ = Mode::kRecentlyLost;
    ++stats_.inertial_frames;
    SetPose(inertial, /*update_velocity=*/true);
    result.state = TrackingState::kInertial;
    result.cam_from_world = inertial;
    result.map_index = active_;
    // The map goes on where the local map does not reach (a stretch driven in the dark, a wall
    // whose features the map never saw): a lit frame becomes a keyframe at the IMU's pose, its
    // stereo points new map points for the frames after it.
    const double interval = options_.imu.keyframe_interval_s;
    if (interval > 0.0 && !options_.localise_only &&
        SecondsBetween(last_keyframe_t_ns_, frame->t_ns) >= interval) {
      InertialKeyFrame(frame, inertial, weak.line_match, &result);
    }
    RecordFrame(*frame, result.keyframe);
    return result;
  }
  if (lost_count_ > options_.recently_lost_frames)
    mode_ = Mode::kLost;
  else
    mode_ = Mode::kRecentlyLost;
  if (mode_ == Mode::kRecentlyLost) {
    result.state = TrackingState::kRecentlyLost;
    last_cam_from_world_ = predicted;
    const double decay = options_.lost_velocity_decay;
    const Eigen::AngleAxisd rotation(velocity_.rotation);
    velocity_.rotation =
        Eigen::AngleAxisd(decay * rotation.angle(), rotation.axis()).toRotationMatrix();
    velocity_.translation *= decay;
    result.cam_from_world = predicted;
    result.map_index = active_;
    return result;
  }
  velocity_ = Rigid3d();
  result.cam_from_world = last_cam_from_world_;
  const auto start = Clock::now();
  const bool reckoning = InertialDeadReckon(*frame);
  // A new map only after new_map_after_lost_frames lit frames failed to come back into the old
  // maps (a black frame does not count, and StartMap refuses it); while the IMU dead-reckons,
  // the map it left resumed instead.
  const bool lit = CouldStartMap(*frame);
  if (lit) ++lost_map_candidates_;
  const bool may_start =
      !options_.localise_only && lit && lost_map_candidates_ > options_.new_map_after_lost_frames;
  const bool resumed = may_start && reckoning && ResumeMap(frame, &result);
  if (resumed || (may_start && StartMap(frame, last_cam_from_world_))) {
    result.state = resumed ? TrackingState::kInertial : TrackingState::kNewMap;
    result.keyframe = true;
    result.cam_from_world = last_cam_from_world_;  // (ResumeMap's: the IMU's)
    mode_ = Mode::kTracking;
    lost_count_ = 0;
    lost_map_candidates_ = 0;
    RecordFrame(*frame, /*keyframe=*/true);
    // A pose without an uncertainty: a new map's initialisation starts from it; a resumed map's
    // state restarts its pose covariance there, its velocity, biases and gravity go on.
    InertialPose(*frame, last_cam_from_world_, Matrix6d::Zero(), /*with_prior=*/false);
  } else {
    result.state = TrackingState::kLost;
  }
  result.mapping_ms = Ms(start);
  result.map_index = active_;
  return result;
}

}  // namespace slslam
