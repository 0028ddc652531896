#include "slslam/tracking/tracker.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>
#include <tuple>

#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>

#include "slslam/core/check.h"
#include "slslam/features/line_segment.h"
#include "slslam/map/map_io.h"

namespace slslam {

namespace {

using Clock = std::chrono::steady_clock;

double Ms(Clock::time_point since) {
  return std::chrono::duration<double, std::milli>(Clock::now() - since).count();
}

// One descriptor row of the same type and width as the rows of `rows`.
bool SameKind(const cv::Mat& descriptor, const cv::Mat& rows) {
  return descriptor.rows == 1 && descriptor.cols == rows.cols && descriptor.type() == rows.type();
}

bool InImage(const PinholeCamera& camera, const Eigen::Vector2d& uv, double margin = 0.0) {
  return uv.x() >= -margin && uv.y() >= -margin && uv.x() <= camera.width - 1 + margin &&
         uv.y() <= camera.height - 1 + margin;
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
  }
  return "UNKNOWN";
}

Tracker::Tracker(const TrackerOptions& options) : options_(options) {
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
  if (!options_.use_lines) mapping.ba.line_weight = 0.0;
  mapping.triangulation.Check();
  mapper_ = std::make_unique<LocalMapper>(options_.rig, mapping, options_.sequential);
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

void Tracker::SaveMap(const std::string& path, const std::string& version) {
  Flush();
  MapFileHeader header;
  header.slslam_version = version;
  header.rig = options_.rig;
  // The file name, not the path: the same vocabulary sits elsewhere on another machine.
  header.vocabulary = std::filesystem::path(options_.vocabulary_path).filename().string();
  std::vector<const Map*> maps;
  std::vector<std::unique_lock<Mutex>> locks;
  for (int m = 0; m < atlas_.size(); ++m) {
    if (atlas_.merged(m)) continue;
    const Map& map = atlas_.map(m);
    locks.emplace_back(map.mutex());
    map.mutex().AssertHeld();  // held by locks.back() until the maps are written
    if (map.keyframes().empty()) {
      locks.pop_back();
      continue;
    }
    maps.push_back(&map);
    for (const auto& [id, kf] : map.keyframes()) {
      (void)id;
      if (header.descriptor_type >= 0) break;
      const cv::Mat& d = kf->frame->keypoints.descriptors;
      if (d.rows == 0) continue;  // a keyframe without keypoints says nothing of the front end
      header.descriptor_type = d.type();
      header.descriptor_cols = d.cols;
    }
  }
  SLSLAM_CHECK(!maps.empty(), path, ": nothing to save, the atlas has no map with keyframes");
  SaveMaps(path, maps, header);
}

void Tracker::LoadMap(const std::string& path) {
  SLSLAM_CHECK(atlas_.size() == 0, path, ": a map file loads only before the first frame");
  SLSLAM_CHECK(vocabulary_ != nullptr, path,
               ": tracking in a loaded map relocalises in it and needs the bag-of-words "
               "vocabulary (tracking.vocabulary_path / relocalisation)");
  LoadedMaps loaded = LoadMaps(path, atlas_.ids());
  const PinholeCamera& a = loaded.header.rig.camera;
  const PinholeCamera& b = options_.rig.camera;
  auto close = [](double x, double y) {
    return std::abs(x - y) <= 1e-6 * std::max(1.0, std::abs(y));
  };
  SLSLAM_CHECK(a.width == b.width && a.height == b.height && close(a.fx, b.fx) &&
                   close(a.fy, b.fy) && close(a.cx, b.cx) && close(a.cy, b.cy) &&
                   close(loaded.header.rig.baseline_m, options_.rig.baseline_m),
               path, ": the map was made with another camera (", a.width, "x", a.height, ", fx ",
               a.fx, ", baseline ", loaded.header.rig.baseline_m, " m; this run: ", b.width, "x",
               b.height, ", fx ", b.fx, ", baseline ", options_.rig.baseline_m, " m)");
  SLSLAM_CHECK(!loaded.maps.empty(), path, ": the file holds no map");
  for (auto& map : loaded.maps) {
    const int index = atlas_.AdoptMap(std::move(map));
    Map& m = atlas_.map(index);
    MutexLock lock(m.mutex());
    for (auto& [id, kf] : m.keyframes()) {
      if (kf->bow.empty() && kf->frame && kf->frame->NumKeypoints() > 0) {
        vocabulary_->Transform(kf->frame->keypoints.descriptors, &kf->bow, &kf->bow_features,
                               options_.relocalisation.vocabulary_levels_up);
      }
      if (!kf->bow.empty()) atlas_.database(index).Add(id, kf->bow);
    }
  }
  loaded_descriptor_type_ = loaded.header.descriptor_type;
  loaded_descriptor_cols_ = loaded.header.descriptor_cols;
  loaded_path_ = path;
  active_ = 0;
  mode_ = Mode::kLost;
  lost_count_ = options_.recently_lost_frames + 1;
  have_pose_ = false;
}

std::vector<LoopEvent> Tracker::loop_events() const {
  return loop_closer_ ? loop_closer_->events() : std::vector<LoopEvent>{};
}

int Tracker::live_maps() const {
  int live = 0;
  for (int m = 0; m < atlas_.size(); ++m) live += !atlas_.merged(m);
  return live;
}

void Tracker::FollowCorrections() {
  if (active_ < 0) return;
  const int resolved = atlas_.Resolve(active_);
  Map& map = atlas_.map(resolved);
  MutexLock lock(map.mutex());
  if (resolved == active_ && map.correction_epoch() == seen_epoch_) return;
  active_ = resolved;
  seen_epoch_ = map.correction_epoch();
  // The last pose relative to the reference keyframe, as recorded, on the keyframe's new pose.
  if (records_.empty() || !have_pose_) return;
  const FrameRecord& r = records_.back();
  Rigid3d ref_from_world;
  if (r.reference_kf < 0 || !map.KeyFramePose(r.reference_kf, &ref_from_world)) return;
  last_cam_from_world_ = r.frame_from_ref * ref_from_world;
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

void Tracker::RecordFrame(const StereoFrame& frame, bool keyframe) {
  FrameRecord r;
  r.index = frame.index;
  r.timestamp = frame.timestamp;
  r.map_index = active_;
  r.reference_kf = last_keyframe_;
  r.cam_from_world = last_cam_from_world_;
  if (keyframe) {
    // The frame is its own reference keyframe. Its pose is not read back: in sequential mode
    // loop closing has already run on the keyframe and may have moved it, or merged its map
    // into another map's world; FollowCorrections then moves the last pose with it (the epoch
    // seen stays the one from before the keyframe).
    records_.push_back(r);
    return;
  }
  const std::unique_lock<Mutex> lock = LockActiveMap();
  Map& map = atlas_.map(active_);
  map.mutex().AssertHeld();  // locked by LockActiveMap
  r.map_index = active_;
  if (FollowAnchor(map, {&last_cam_from_world_})) r.cam_from_world = last_cam_from_world_;
  Rigid3d ref_from_world;
  if (r.reference_kf >= 0 && map.KeyFramePose(r.reference_kf, &ref_from_world)) {
    // R_fr = R_cw R_rw^T, t_fr = t_cw - R_fr t_rw (as written, not T_cw * T_rw^-1: the rounding
    // differs).
    r.frame_from_ref.rotation = last_cam_from_world_.rotation * ref_from_world.rotation.transpose();
    r.frame_from_ref.translation =
        last_cam_from_world_.translation - r.frame_from_ref.rotation * ref_from_world.translation;
  } else {
    r.reference_kf = -1;
  }
  seen_epoch_ = map.correction_epoch();
  records_.push_back(r);
}

void Tracker::SetAnchor(const Map& map, int keyframe) {
  anchor_ = Anchor{};
  if (keyframe < 0 || !map.KeyFramePose(keyframe, &anchor_.ref_from_world)) return;
  anchor_.keyframe = keyframe;
  anchor_.map = &map;
  anchor_.epoch = map.correction_epoch();
}

bool Tracker::FollowAnchor(const Map& map, std::initializer_list<Rigid3d*> cams_from_world) {
  if (anchor_.keyframe < 0 || (&map == anchor_.map && map.correction_epoch() == anchor_.epoch)) {
    return false;
  }
  Rigid3d ref_from_world;
  if (!map.KeyFramePose(anchor_.keyframe, &ref_from_world)) return false;
  // T_cw' = T_cw T_rw_old^-1 T_rw_new: the same pose relative to the reference keyframe.
  const Rigid3d& old_ref_from_world = anchor_.ref_from_world;
  const Rigid3d old_world_from_new_world(
      old_ref_from_world.rotation.transpose() * ref_from_world.rotation,
      old_ref_from_world.rotation.transpose() *
          (ref_from_world.translation - old_ref_from_world.translation));
  for (Rigid3d* cam_from_world : cams_from_world) {
    *cam_from_world = *cam_from_world * old_world_from_new_world;
  }
  anchor_.map = &map;
  anchor_.epoch = map.correction_epoch();
  anchor_.ref_from_world = ref_from_world;
  return true;
}

std::vector<FramePose> Tracker::Trajectory() const {
  std::vector<FramePose> out;
  out.reserve(records_.size());
  for (const FrameRecord& r : records_) {
    FramePose f;
    f.index = r.index;
    f.timestamp = r.timestamp;
    f.map_index = atlas_.Resolve(r.map_index);
    f.cam_from_world = r.cam_from_world;
    Map& map = atlas_.map(f.map_index);
    MutexLock lock(map.mutex());
    Rigid3d ref_from_world;
    if (r.reference_kf >= 0 && map.KeyFramePose(r.reference_kf, &ref_from_world)) {
      f.cam_from_world = r.frame_from_ref * ref_from_world;
    }
    out.push_back(f);
  }
  return out;
}

Tracker::~Tracker() {
  mapper_.reset();       // drains and joins the mapping thread before the maps go,
  loop_closer_.reset();  // then a global BA still running in the background
}

void Tracker::Flush() {
  mapper_->Flush();
  if (loop_closer_) loop_closer_->WaitForGlobalBa();
}

void Tracker::Predict(Rigid3d* pred_cam_from_world) const {
  *pred_cam_from_world = last_cam_from_world_;
  if (have_pose_) *pred_cam_from_world = velocity_ * last_cam_from_world_;
}

void Tracker::SetPose(const Rigid3d& cam_from_world, bool update_velocity) {
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

bool Tracker::StartMap(const std::shared_ptr<const StereoFrame>& frame,
                       const Rigid3d& cam_from_world) {
  int stereo_points = 0, stereo_lines = 0;
  for (double d : frame->depth) stereo_points += d > 0.0;
  if (options_.use_lines) {
    for (bool has : frame->line_has_depth) stereo_lines += has;
  }
  // A map needs some points: lines alone leave the first keyframe's pose weakly constrained.
  if (stereo_points < std::min(options_.min_init_points, 15) ||
      Weighted(stereo_points, stereo_lines) < options_.min_init_points) {
    return false;
  }
  active_ = atlas_.AddMap();
  ++stats_.maps_started;
  InsertKeyFrame(frame, cam_from_world, std::vector<int>(frame->NumKeypoints(), -1),
                 std::vector<int>(frame->NumLines(), -1));
  return true;
}

void Tracker::InsertKeyFrame(const std::shared_ptr<const StereoFrame>& frame,
                             Rigid3d cam_from_world, const std::vector<int>& point_matches,
                             const std::vector<int>& line_matches,
                             const std::vector<bool>& valid_keypoints) {
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
    if (FollowAnchor(map, {&cam_from_world, &last_cam_from_world_})) {
      seen_epoch_ = map.correction_epoch();
    }
    auto kf = map.AddKeyFrame(cam_from_world, frame);
    kf_id = kf->id;
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
      }
    }
    if (options_.use_lines) {
      for (int j = 0; j < frame->NumLines(); ++j) {
        if (line_matches[j] >= 0 && map.line(line_matches[j])) {
          map.AddLineObservation(line_matches[j], kf_id, j);
        } else if (frame->line_has_depth[j]) {
          const Eigen::Vector3d s = world_from_cam * frame->line_endpoints[j][0];
          const Eigen::Vector3d e = world_from_cam * frame->line_endpoints[j][1];
          if ((e - s).norm() < 1e-3) continue;
          auto l = map.AddLine(PluckerLine::FromPoints(s, e), s, e, frame->line_descriptors.row(j),
                               kf_id);
          map.AddLineObservation(l->id, kf_id, j);
        }
      }
    }
    map.UpdateConnections(kf_id);
  }
  if (!bow.empty()) atlas_.database(active_).Add(kf_id, bow);
  last_keyframe_ = kf_id;
  last_keyframe_frame_ = frame->index;
  last_keyframe_time_s_ = frame->timestamp;
  first_tracked_ = 0;
  mapper_->Insert(live, kf_id);
}

Tracker::LocalMapSnapshot Tracker::SnapshotLocalMap(const StereoFrame& frame, Map& map,
                                                    int reference_kf,
                                                    const Rigid3d& pred_cam_from_world) const {
  const PinholeCamera& camera = options_.rig.camera;
  const auto start = Clock::now();
  LocalMapSnapshot snap;
  // Local map: the reference keyframe and its covisible keyframes.
  std::vector<int> local = {reference_kf};
  if (!map.keyframe(reference_kf)) local.clear();
  for (int id : map.BestCovisible(reference_kf, options_.mapping.local_keyframes)) {
    local.push_back(id);
  }
  if (local.empty() && !map.keyframes().empty()) local.push_back(map.keyframes().rbegin()->first);
  std::set<int> point_ids, line_ids;
  for (int id : local) {
    auto kf = map.keyframe(id);
    if (!kf) continue;
    for (int pid : kf->point_ids) {
      if (pid >= 0) point_ids.insert(pid);
    }
    for (int lid : kf->line_ids) {
      if (lid >= 0) line_ids.insert(lid);
    }
  }

  // Points in front of the predicted camera and inside the image.
  std::vector<std::shared_ptr<MapPoint>> points;
  std::vector<Eigen::Vector2f> predicted;
  for (int pid : point_ids) {
    auto p = map.point(pid);
    if (!p || p->bad) continue;
    const Eigen::Vector3d x_c = pred_cam_from_world * p->position;
    if (x_c.z() <= 0.05) continue;
    const Eigen::Vector2d uv = camera.Project(x_c);
    if (!InImage(camera, uv)) continue;
    // A descriptor of another kind (a loaded map of another front end) cannot be matched.
    if (frame.NumKeypoints() > 0 && !SameKind(p->descriptor, frame.keypoints.descriptors)) {
      continue;
    }
    points.push_back(p);
    predicted.push_back(uv.cast<float>());
    p->visible += 1;
  }
  const cv::Mat& frame_desc = frame.keypoints.descriptors;
  if (!points.empty() && frame.NumKeypoints() > 0) {
    snap.point_uv.resize(static_cast<Eigen::Index>(points.size()), 2);
    snap.point_descriptors =
        cv::Mat(static_cast<int>(points.size()), frame_desc.cols, frame_desc.type());
    for (size_t i = 0; i < points.size(); ++i) {
      snap.point_ids.push_back(points[i]->id);
      snap.point_w.push_back(points[i]->position);
      snap.point_uv.row(static_cast<Eigen::Index>(i)) = predicted[i].transpose();
      points[i]->descriptor.copyTo(snap.point_descriptors.row(static_cast<int>(i)));
    }
  }

  // Lines whose predicted segment is in front of the camera, long enough and centred inside.
  if (options_.use_lines && frame.NumLines() > 0) {
    std::vector<std::shared_ptr<MapLine>> lines;
    for (int lid : line_ids) {
      auto l = map.line(lid);
      if (!l || l->bad) continue;
      const Eigen::Vector3d s_c = pred_cam_from_world * l->start;
      const Eigen::Vector3d e_c = pred_cam_from_world * l->end;
      if (s_c.z() <= 0.05 || e_c.z() <= 0.05) continue;
      LineSegment proj;
      proj.start = camera.Project(s_c).cast<float>();
      proj.end = camera.Project(e_c).cast<float>();
      const Eigen::Vector2f mid = 0.5f * (proj.start + proj.end);
      if (!InImage(camera, mid.cast<double>()) || proj.Length() < 5.0f) continue;
      if (!SameKind(l->descriptor, frame.line_descriptors)) continue;
      l->visible += 1;
      lines.push_back(l);
      snap.line_px.push_back(proj);
    }
    if (!lines.empty()) {
      const cv::Mat& kind = frame.line_descriptors;
      snap.line_descriptors = cv::Mat(static_cast<int>(lines.size()), kind.cols, kind.type());
      for (size_t i = 0; i < lines.size(); ++i) {
        snap.line_ids.push_back(lines[i]->id);
        snap.lines_w.push_back(lines[i]->line);
        lines[i]->descriptor.copyTo(snap.line_descriptors.row(static_cast<int>(i)));
      }
    }
  }
  snap.ms = Ms(start);
  return snap;
}

Tracker::LocalTracking Tracker::TrackSnapshot(const StereoFrame& frame,
                                              const LocalMapSnapshot& local,
                                              const Rigid3d& pred_cam_from_world,
                                              float radius_scale,
                                              const std::vector<bool>* valid_keypoints) const {
  LocalTracking out;
  const auto match_start = Clock::now();
  // Points: matched in a window around the predicted position.
  const cv::Mat& frame_desc = frame.keypoints.descriptors;
  if (!local.point_ids.empty() && frame.NumKeypoints() > 0) {
    GuidedMatchOptions guided = GuidedOptions(frame_desc.type(), radius_scale);
    Eigen::VectorXi m = GuidedMatch(local.point_uv, local.point_descriptors, frame.keypoints.uv,
                                    frame_desc, guided);
    if ((m.array() >= 0).count() < 30) {  // fast motion: widen the window once
      guided.radius_px *= 2.0f;
      m = GuidedMatch(local.point_uv, local.point_descriptors, frame.keypoints.uv, frame_desc,
                      guided);
    }
    for (size_t i = 0; i < local.point_ids.size(); ++i) {
      if (m(i) < 0) continue;
      const bool masked = valid_keypoints && !valid_keypoints->empty() && !(*valid_keypoints)[m(i)];
      (masked ? out.masked_point_ids : out.point_ids).push_back(static_cast<int>(i));
      (masked ? out.masked_keypoints : out.keypoints).push_back(m(i));
    }
  }

  // Lines: predicted segments against frame segments (angle, distance, LBD).
  std::vector<int> line_rows;  // snapshot rows of the matched lines
  if (options_.use_lines && frame.NumLines() > 0) {
    const float line_search = options_.line_search_px * radius_scale;
    std::vector<std::tuple<float, int, int>> pairs;  // (LBD distance, snapshot row, segment)
    for (size_t r = 0; r < local.line_ids.size(); ++r) {
      const LineSegment& proj = local.line_px[r];
      const Eigen::Vector2f mid = 0.5f * (proj.start + proj.end);
      for (int j = 0; j < frame.NumLines(); ++j) {
        const LineSegment& seg = frame.lines[j];
        if (AngleDifference(seg.Angle(), proj.Angle()) > options_.line_max_angle_rad) continue;
        const Eigen::Vector2f seg_mid = 0.5f * (seg.start + seg.end);
        if (proj.DistanceToLine(seg_mid) > line_search) continue;
        if ((seg_mid - mid).norm() > 0.5f * (proj.Length() + seg.Length()) + line_search) {
          continue;
        }
        const int row = static_cast<int>(r);
        const float d = DescriptorDistance(local.line_descriptors, row, frame.line_descriptors, j);
        if (d <= options_.line_max_lbd) pairs.emplace_back(d, row, j);
      }
    }
    // Rows are in id order, so (distance, row, segment) sorts as (distance, id, segment).
    std::sort(pairs.begin(), pairs.end());
    std::set<int> used_rows, used_segments;
    for (const auto& [d, r, j] : pairs) {
      (void)d;
      if (used_rows.count(r) || used_segments.count(j)) continue;
      used_rows.insert(r);
      used_segments.insert(j);
      line_rows.push_back(r);
      out.segments.push_back(j);
    }
  }
  out.matching_ms = local.ms + Ms(match_start);

  // Motion-only BA.
  const auto opt_start = Clock::now();
  std::vector<PointObservation> points(out.point_ids.size());
  for (size_t i = 0; i < out.point_ids.size(); ++i) {
    const int k = out.keypoints[i];
    points[i].point_w = local.point_w[out.point_ids[i]];
    points[i].stereo = frame.u_right[k] >= 0.0;
    points[i].observed << frame.keypoints.uv(k, 0), frame.keypoints.uv(k, 1), frame.u_right[k];
    points[i].sigma_px = options_.point_sigma_px;
  }
  std::vector<LineObservation> lines(line_rows.size());
  for (size_t i = 0; i < line_rows.size(); ++i) {
    lines[i].line_w = local.lines_w[line_rows[i]];
    lines[i].start_px = frame.lines[out.segments[i]].start.cast<double>();
    lines[i].end_px = frame.lines[out.segments[i]].end.cast<double>();
    lines[i].sigma_px = options_.line_sigma_px;
  }
  out.pose = OptimizePose(options_.rig, pred_cam_from_world, points, lines, options_.pose);
  out.optimisation_ms = Ms(opt_start);
  out.weighted_inliers =
      out.pose.success ? Weighted(out.pose.point_inliers, out.pose.line_inliers) : 0.0;
  // Snapshot rows to map ids.
  for (int& row : out.point_ids) row = local.point_ids[row];
  for (int& row : out.masked_point_ids) row = local.point_ids[row];
  for (int row : line_rows) out.line_ids.push_back(local.line_ids[row]);
  return out;
}

Tracker::LocalTracking Tracker::TrackLocalMap(const StereoFrame& frame, Map& map, int reference_kf,
                                              const Rigid3d& pred_cam_from_world,
                                              float radius_scale,
                                              const std::vector<bool>* valid_keypoints) const {
  return TrackSnapshot(frame, SnapshotLocalMap(frame, map, reference_kf, pred_cam_from_world),
                       pred_cam_from_world, radius_scale, valid_keypoints);
}

GuidedMatchOptions Tracker::GuidedOptions(int descriptor_type, float radius_scale) const {
  GuidedMatchOptions guided;
  guided.radius_px = options_.search_radius_px * radius_scale;
  guided.max_distance =
      descriptor_type == CV_8U ? options_.max_distance_binary : options_.max_distance_float;
  guided.ratio = options_.match_ratio;
  return guided;
}

void Tracker::UpdateDynamicCells(const StereoFrame& frame, const Rigid3d& cam_from_world) {
  // Frame-to-frame evidence, as the paper's filter: the previous frame's stereo keypoints are
  // carried into this frame by the camera motion between the two estimated poses and matched
  // around their predicted pixels; a cell whose matches land far from the prediction moved on
  // its own. Unlike matches to the map, these exist for a mover too (it makes no map points once
  // its cells are invalid), so its cells stay invalid while it moves.
  // The caller replaces previous_frame_ with this frame afterwards.
  const StereoFrame* previous = previous_frame_.get();
  if (!previous || previous->NumKeypoints() == 0 || frame.NumKeypoints() == 0 ||
      previous->keypoints.descriptors.type() != frame.keypoints.descriptors.type()) {
    return;
  }
  const PinholeCamera& camera = options_.rig.camera;
  // x_cur = R_cp x_prev + t_cp: R_cp = R_cw R_pw^T, t_cp = t_cw - R_cp t_pw.
  Rigid3d cam_from_prev;
  cam_from_prev.rotation = cam_from_world.rotation * previous_cam_from_world_.rotation.transpose();
  cam_from_prev.translation =
      cam_from_world.translation - cam_from_prev.rotation * previous_cam_from_world_.translation;
  std::vector<int> rows;
  PixelArray predicted(previous->NumKeypoints(), 2);
  for (int i = 0; i < previous->NumKeypoints(); ++i) {
    if (!(previous->depth[i] > 0.0)) continue;
    const Eigen::Vector3d x_c = cam_from_prev * previous->Backproject(camera, i);
    if (x_c.z() <= 0.05) continue;
    const Eigen::Vector2d uv = camera.Project(x_c);
    if (!InImage(camera, uv)) continue;
    predicted.row(static_cast<Eigen::Index>(rows.size())) = uv.cast<float>().transpose();
    rows.push_back(i);
  }
  const cv::Mat& desc = frame.keypoints.descriptors;
  cv::Mat query(static_cast<int>(rows.size()), desc.cols, desc.type());
  for (size_t r = 0; r < rows.size(); ++r) {
    previous->keypoints.descriptors.row(rows[r]).copyTo(query.row(static_cast<int>(r)));
  }
  const GuidedMatchOptions guided = GuidedOptions(desc.type(), 1.0f);
  const PixelArray pred = predicted.topRows(static_cast<Eigen::Index>(rows.size()));
  const Eigen::VectorXi m = GuidedMatch(pred, query, frame.keypoints.uv, desc, guided);
  PixelArray observed(m.size(), 2), expected(m.size(), 2);
  Eigen::Index n = 0;
  for (Eigen::Index r = 0; r < m.size(); ++r) {
    if (m(r) < 0) continue;
    observed.row(n) = frame.keypoints.uv.row(m(r));
    expected.row(n) = pred.row(r);
    ++n;
  }
  dynamic_->Update(observed.topRows(n), expected.topRows(n));
}

bool Tracker::AcceptTracking(const StereoFrame& frame, Map& map, const LocalTracking& tracking,
                             std::vector<int>* point_match, std::vector<int>* line_match) {
  const PoseOptimizerResult& pose = tracking.pose;
  // The map lock was released after matching: local mapping (threaded) may have culled a
  // landmark since, so each is looked up again.
  for (size_t i = 0; i < tracking.point_ids.size(); ++i) {
    if (!pose.point_inlier[i]) continue;
    auto p = map.point(tracking.point_ids[i]);
    if (!p || p->bad) continue;
    p->found += 1;
    (*point_match)[tracking.keypoints[i]] = tracking.point_ids[i];
  }
  for (size_t i = 0; i < tracking.line_ids.size(); ++i) {
    if (!pose.line_inlier[i]) continue;
    auto l = map.line(tracking.line_ids[i]);
    if (!l || l->bad) continue;
    l->found += 1;
    (*line_match)[tracking.segments[i]] = tracking.line_ids[i];
  }
  // Keyframe decision (ORB-SLAM3's NeedNewKeyFrame for stereo, with local mapping idle: it is
  // in sequential mode, and in threaded mode the queue absorbs the keyframe). Reference: the
  // reference keyframe's map points seen by at least min_obs keyframes.
  const int frames_since = frame.index - last_keyframe_frame_;
  int reference = 0;
  if (auto kf = map.keyframe(last_keyframe_)) {
    const int min_obs = map.keyframes().size() <= 2 ? 2 : 3;
    for (int pid : kf->point_ids) {
      auto p = pid >= 0 ? map.point(pid) : nullptr;
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
  const bool need_close = close_tracked < options_.keyframe_min_inliers && close_untracked > 70;
  const int tracked = pose.point_inliers;
  // A young map has few points seen by three keyframes; the inliers of the first frame tracked
  // after the keyframe stand in for the reference then (how many of its points can be tracked).
  if (first_tracked_ == 0 && frames_since >= 1) first_tracked_ = tracked;
  reference = std::max(reference, first_tracked_);
  // The minimum gap after the last keyframe, in frames and in time.
  const bool past_gap =
      frames_since >= options_.keyframe_min_frames &&
      frame.timestamp - last_keyframe_time_s_ >= options_.keyframe_min_interval_s;
  const bool c1 = frames_since >= options_.keyframe_max_frames || past_gap ||
                  tracked < 0.25 * reference || need_close;
  const bool c2 = (tracked < options_.keyframe_track_ratio * reference || need_close) &&
                  tracking.weighted_inliers > options_.min_inliers;
  // Thin tracking (low texture, few lines): keyframes often, so the map keeps up with the view.
  const bool weak = tracking.weighted_inliers < options_.weak_keyframe_inliers &&
                    frames_since >= options_.weak_keyframe_frames;
  // The minimum gap is a hard one while tracking is strong (sequential local mapping is always
  // idle, so ORB-SLAM3's "mapping busy" brake never acts here).
  const bool gap = frames_since >= 1 && past_gap;
  return frames_since >= 1 &&
         ((gap && c1 && c2) || weak || frames_since >= options_.keyframe_max_frames);
}

bool Tracker::RelocaliseInMap(const StereoFrame& frame, const BowVector& bow,
                              const FeatureVector& features, int map_index, LocalTracking* tracking,
                              int* keyframe_id) {
  const RelocalisationOptions& ro = options_.relocalisation;
  const cv::Mat& desc = frame.keypoints.descriptors;
  Map& map = atlas_.map(map_index);
  MutexLock lock(map.mutex());
  const auto candidates =
      atlas_.database(map_index).Query(bow, ro.candidates, 0.0, 0.8, [&](int id) {
        map.mutex().AssertHeld();  // the lock above (a lambda is not followed)
        auto kf = map.keyframe(id);
        return kf && !kf->bad;
      });
  const float max_distance =
      desc.type() == CV_8U ? options_.max_distance_binary : options_.max_distance_float;
  for (const auto& candidate : candidates) {
    auto kf = map.keyframe(candidate.keyframe_id);
    if (!kf) continue;
    const auto matches = MatchByWords(desc, features, *kf, map, max_distance, ro.match_ratio);
    if (static_cast<int>(matches.size()) < ro.min_matches) continue;
    Rigid3d cam_from_world;
    if (!PoseFromMatches(frame, map, matches, options_.rig.camera, ro.ransac_iterations,
                         ro.ransac_error_px, ro.min_pnp_inliers, &cam_from_world)) {
      continue;
    }
    LocalTracking local = TrackLocalMap(frame, map, kf->id, cam_from_world, 1.0f);

    if (!local.pose.success || local.weighted_inliers < ro.min_inliers) continue;
    *tracking = std::move(local);
    *keyframe_id = kf->id;
    // The pose is in the map's world as of now (not as of an earlier, failed local tracking).
    SetAnchor(map, kf->id);
    return true;
  }
  return false;
}

bool Tracker::Relocalise(const StereoFrame& frame, const std::vector<int>& order,
                         TrackResult* result, LocalTracking* tracking) {
  if (!vocabulary_) return false;
  const auto start = Clock::now();
  ++stats_.relocalisation_attempts;
  const cv::Mat& desc = frame.keypoints.descriptors;
  if (frame.NumKeypoints() < options_.relocalisation.min_matches ||
      desc.type() != vocabulary_->descriptor_type() ||
      desc.cols != vocabulary_->descriptor_cols()) {
    result->relocalisation_ms = Ms(start);
    return false;
  }
  // The frame's words, once for every map tried.
  BowVector bow;
  FeatureVector features;
  vocabulary_->Transform(desc, &bow, &features, options_.relocalisation.vocabulary_levels_up);
  for (int m : order) {
    int keyframe_id = -1;
    if (!RelocaliseInMap(frame, bow, features, m, tracking, &keyframe_id)) continue;
    active_ = m;
    last_keyframe_ = keyframe_id;
    last_keyframe_frame_ = frame.index;
    last_keyframe_time_s_ = frame.timestamp;
    first_tracked_ = 0;
    ++stats_.relocalisations;
    result->relocalisation_ms = Ms(start);
    return true;
  }
  result->relocalisation_ms = Ms(start);
  return false;
}

Tracker::LocalTracking Tracker::TrackAlongLossMotion(const StereoFrame& frame,
                                                     const Rigid3d& frozen_cam_from_world) {
  // The robot most likely kept moving through the dark as before the loss: the local map is
  // tried from poses along the pre-loss motion (a fraction of the frames since the last
  // estimate) and from the frozen pose, with a wide window; the best-supported attempt wins.
  const int since = lost_count_ + 1;  // frames since the last estimated pose
  std::vector<Rigid3d> hypotheses = {frozen_cam_from_world};  // cam_from_world each
  // With the full pre-loss motion, and with its translation only: one frame's rotation may be
  // mostly vibration (roll, pitch), and twenty frames of it extrapolated tilt the camera by
  // degrees.
  const Rigid3d& loss = loss_cam_from_world_;
  const Eigen::Vector3d center = loss.Center();
  const Eigen::Matrix3d R_prev = loss_velocity_.rotation.transpose() * loss.rotation;
  const Eigen::Vector3d t_prev =
      loss_velocity_.rotation.transpose() * (loss.translation - loss_velocity_.translation);
  const Eigen::Vector3d step = center - (-R_prev.transpose() * t_prev);  // world, per frame
  for (const double fraction : {0.5, 0.75, 1.0, 1.25}) {
    const double steps = std::round(fraction * since);
    if (steps <= 0.0) continue;
    hypotheses.emplace_back(loss.rotation, -loss.rotation * (center + steps * step));
    Rigid3d moved = loss;
    for (int k = 0; k < static_cast<int>(steps); ++k) moved = loss_velocity_ * moved;
    hypotheses.push_back(moved);
  }
  LocalTracking best;
  for (const Rigid3d& hypothesis : hypotheses) {
    const std::unique_lock<Mutex> lock = LockActiveMap();
    Map& map = atlas_.map(active_);
    map.mutex().AssertHeld();  // locked by LockActiveMap
    LocalTracking attempt =
        TrackLocalMap(frame, map, last_keyframe_, hypothesis, options_.lost_search_scale);
    if (attempt.pose.success && attempt.weighted_inliers > best.weighted_inliers) {
      best = std::move(attempt);
    }
  }
  return best;
}

TrackResult Tracker::Track(std::shared_ptr<const StereoFrame> frame) {
  Require(frame != nullptr, "Track needs a frame");
  TrackResult result;
  if (loaded_descriptor_type_ >= 0 && frame->NumKeypoints() > 0) {
    const cv::Mat& d = frame->keypoints.descriptors;
    SLSLAM_CHECK(d.type() == loaded_descriptor_type_ && d.cols == loaded_descriptor_cols_,
                 loaded_path_, ": the map was made with another point front end (descriptors of ",
                 loaded_descriptor_cols_, " ",
                 loaded_descriptor_type_ == CV_8U ? "bytes" : "floats", "; this run's have ",
                 d.cols, ")");
    loaded_descriptor_type_ = -1;  // checked once
  }
  // A loop correction or a merge may have moved the last pose (a merge into another map's
  // world): the prediction starts from where it is now.
  FollowCorrections();
  anchor_ = Anchor{};
  Rigid3d predicted;  // cam_from_world
  Predict(&predicted);
  if (atlas_.size() == 0) {  // not initialised yet
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
    } else {
      result.state = TrackingState::kNotInitialized;
    }
    result.cam_from_world = predicted;
    result.map_index = active_;
    result.mapping_ms = Ms(start);
    return result;
  }

  LocalTracking tracking;
  bool tracked = false, relocalised = false;
  // Keypoints in cells the dynamic-cell filter invalidated up to the last frame.
  std::vector<bool> valid;
  if (dynamic_ && mode_ == Mode::kTracking && dynamic_masks_) {
    valid = dynamic_->KeypointMask(frame->keypoints.uv);
    result.masked_keypoints = static_cast<int>(std::count(valid.begin(), valid.end(), false));
  }
  auto track_local_map = [&](float scale) {
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
        Predict(&predicted);
        continue;
      }
      local = SnapshotLocalMap(*frame, map, last_keyframe_, predicted);
      SetAnchor(map, last_keyframe_);
      break;
    }
    tracking = TrackSnapshot(*frame, local, predicted, scale, &valid);
  };
  if (mode_ != Mode::kLost) {
    track_local_map(mode_ == Mode::kRecentlyLost ? options_.lost_search_scale : 1.0f);
    tracked = tracking.pose.success && tracking.weighted_inliers >= options_.min_inliers;
  }
  if (!tracked && mode_ != Mode::kTracking) {
    // Recently lost: the active map only; lost: every map, the active one first, then the newest.
    std::vector<int> order = {active_};
    if (mode_ == Mode::kLost) {
      for (int m = atlas_.size() - 1; m >= 0; --m) {
        if (m != active_ && !atlas_.merged(m)) order.push_back(m);
      }
    }
    relocalised = Relocalise(*frame, order, &result, &tracking);
  }
  if (!tracked && !relocalised && mode_ == Mode::kLost && have_pose_) {
    tracking = TrackAlongLossMotion(*frame, predicted);  // lost: `tracking` was empty
    tracked = tracking.pose.success && tracking.weighted_inliers >= 2.0 * options_.min_inliers;
  }
  result.matched_points = static_cast<int>(tracking.point_ids.size());
  result.matched_lines = static_cast<int>(tracking.line_ids.size());
  result.inlier_points = tracking.pose.point_inliers;
  result.inlier_lines = tracking.pose.line_inliers;
  result.weighted_inliers = tracking.weighted_inliers;
  result.matching_ms = tracking.matching_ms;
  result.optimisation_ms = tracking.optimisation_ms;

  if (tracked || relocalised) {
    std::vector<int> point_match(frame->NumKeypoints(), -1);
    std::vector<int> line_match(frame->NumLines(), -1);
    bool make_keyframe = false;
    bool velocity_known = mode_ == Mode::kTracking;
    {
      // (the live map: merged into another meanwhile in threaded mode, see LockActiveMap)
      const std::unique_lock<Mutex> lock = LockActiveMap();
      Map& map = atlas_.map(active_);
      map.mutex().AssertHeld();  // locked by LockActiveMap
      // The last pose moves too when it was in the world the estimate was made in; otherwise
      // (a merge meanwhile) the motion between the two is unknown.
      const bool move_last = anchor_.map == &map && anchor_.epoch == seen_epoch_;
      Rigid3d* estimate = &tracking.pose.cam_from_world;
      if (move_last ? FollowAnchor(map, {estimate, &last_cam_from_world_})
                    : FollowAnchor(map, {estimate})) {
        if (move_last) seen_epoch_ = map.correction_epoch();
        velocity_known = velocity_known && move_last;
      }
      make_keyframe = AcceptTracking(*frame, map, tracking, &point_match, &line_match);
    }
    if (dynamic_) {
      // Thin tracking (low texture, dark, dust) masks nothing: its sparse frame-to-frame
      // evidence is noise-dominated, and every keypoint counts there (measured on the junction
      // with flicker, dust and a blackout: masking there lost 33 frames and split the map). The
      // weights still follow the evidence, so a mover seen while tracking is thin is masked as
      // soon as tracking is strong again.
      dynamic_masks_ = tracked && tracking.weighted_inliers >= options_.weak_keyframe_inliers;
      if (tracked) UpdateDynamicCells(*frame, tracking.pose.cam_from_world);
      if (!tracked) dynamic_->Reset();  // relocalised: the cells start afresh from here
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
    mode_ = Mode::kTracking;
    lost_count_ = 0;
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
      InsertKeyFrame(frame, tracking.pose.cam_from_world, point_match, line_match, valid);
      result.keyframe = true;
      result.mapping_ms = Ms(start);
    }
    RecordFrame(*frame, result.keyframe);
    return result;
  }

  // Not tracked. Recently lost: follow the prediction with a decaying velocity. Lost: freeze.
  anchor_ = Anchor{};
  if (dynamic_) {
    dynamic_->Reset();
    previous_frame_ = nullptr;
    dynamic_masks_ = false;
  }
  if (mode_ == Mode::kTracking) {  // the last estimate and the motion before the loss
    loss_cam_from_world_ = last_cam_from_world_;
    loss_velocity_ = velocity_;
  }
  ++lost_count_;
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
  if (!options_.localise_only && StartMap(frame, last_cam_from_world_)) {
    result.state = TrackingState::kNewMap;
    result.keyframe = true;
    mode_ = Mode::kTracking;
    lost_count_ = 0;
    RecordFrame(*frame, /*keyframe=*/true);
  } else {
    result.state = TrackingState::kLost;
  }
  result.mapping_ms = Ms(start);
  result.map_index = active_;
  return result;
}

MapExport Tracker::ExportMap() const {
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Matrix<double, 6, 1>> lines;
  std::vector<int> point_map, line_map;
  MapExport out;
  for (int m = 0; m < atlas_.size(); ++m) {
    const Map& map = atlas_.map(m);
    MutexLock lock(map.mutex());
    for (const auto& [id, p] : map.points()) {
      (void)id;
      if (p->bad || p->observations.empty()) continue;
      points.push_back(p->position);
      point_map.push_back(static_cast<int>(m));
    }
    for (const auto& [id, l] : map.lines()) {
      (void)id;
      if (l->bad || l->observations.empty()) continue;
      Eigen::Matrix<double, 6, 1> row;
      row << l->start, l->end;
      lines.push_back(row);
      line_map.push_back(static_cast<int>(m));
    }
    out.keyframes += static_cast<int>(map.keyframes().size());
  }
  out.points.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (size_t i = 0; i < points.size(); ++i) out.points.row(i) = points[i].transpose();
  out.lines.resize(static_cast<Eigen::Index>(lines.size()), 6);
  for (size_t i = 0; i < lines.size(); ++i) out.lines.row(i) = lines[i].transpose();
  out.point_map = Eigen::Map<Eigen::VectorXi>(point_map.data(), point_map.size());
  out.line_map = Eigen::Map<Eigen::VectorXi>(line_map.data(), line_map.size());
  return out;
}

}  // namespace slslam
