#include "slslam/tracking/tracker.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <set>
#include <tuple>

#include "slslam/core/check.h"
#include "slslam/features/line_segment.h"

namespace slslam {

namespace {

using Clock = std::chrono::steady_clock;

double Ms(Clock::time_point since) {
  return std::chrono::duration<double, std::milli>(Clock::now() - since).count();
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
  }
  return "UNKNOWN";
}

void TrackerOptions::Check() const {
  rig.Check();
  stereo.Check();
  Require(min_init_points >= 3, "tracker.min_init_points must be >= 3");
  Require(min_inliers >= 3, "tracker.min_inliers must be >= 3");
  Require(search_radius_px > 0.0f, "tracker.search_radius_px must be > 0");
  Require(max_distance_binary > 0.0f && max_distance_float > 0.0f,
          "tracker descriptor distance bounds must be > 0");
  Require(match_ratio > 0.0f && match_ratio <= 1.0f, "tracker.match_ratio must be in (0, 1]");
  Require(keyframe_max_frames >= 1, "tracker.keyframe_max_frames must be >= 1");
  Require(keyframe_min_frames >= 0 && keyframe_min_frames <= keyframe_max_frames,
          "tracker.keyframe_min_frames must be in [0, keyframe_max_frames]");
  Require(keyframe_track_ratio > 0.0 && keyframe_track_ratio <= 1.0,
          "tracker.keyframe_track_ratio must be in (0, 1]");
  Require(close_depth_baselines > 0.0, "tracker.close_depth_baselines must be > 0");
  Require(point_sigma_px > 0.0 && line_sigma_px > 0.0, "measurement sigmas must be > 0");
}

Tracker::Tracker(const TrackerOptions& options) : options_(options) {
  options_.Check();
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
}

Tracker::~Tracker() {
  mapper_.reset();  // drains and joins the mapping thread before the maps go
}

void Tracker::Flush() { mapper_->Flush(); }

bool Tracker::StartMap(const std::shared_ptr<const StereoFrame>& frame, const Eigen::Matrix3d& R_cw,
                       const Eigen::Vector3d& t_cw) {
  int stereo_points = 0;
  for (double d : frame->depth) stereo_points += d > 0.0;
  if (stereo_points < options_.min_init_points) return false;
  maps_.push_back(std::make_unique<Map>());
  InsertKeyFrame(frame, R_cw, t_cw, std::vector<int>(frame->NumKeypoints(), -1),
                 std::vector<int>(frame->NumLines(), -1));
  return true;
}

void Tracker::InsertKeyFrame(const std::shared_ptr<const StereoFrame>& frame,
                             const Eigen::Matrix3d& R_cw, const Eigen::Vector3d& t_cw,
                             const std::vector<int>& point_matches,
                             const std::vector<int>& line_matches) {
  Map& map = *maps_.back();
  int kf_id = -1;
  {
    std::lock_guard<std::mutex> lock(map.mutex());
    auto kf = map.AddKeyFrame(R_cw, t_cw, frame);
    kf_id = kf->id;
    const Eigen::Matrix3d R_wc = R_cw.transpose();
    const Eigen::Vector3d t_wc = -R_wc * t_cw;
    int points = 0;
    for (int i = 0; i < frame->NumKeypoints(); ++i) {
      if (point_matches[i] >= 0 && map.point(point_matches[i])) {
        map.AddPointObservation(point_matches[i], kf_id, i);
        ++points;
      } else if (frame->depth[i] > 0.0) {
        const Eigen::Vector3d p_w = R_wc * frame->Backproject(options_.rig.camera, i) + t_wc;
        auto p = map.AddPoint(p_w, frame->keypoints.descriptors.row(i), kf_id);
        map.AddPointObservation(p->id, kf_id, i);
        ++points;
      }
    }
    if (options_.use_lines) {
      for (int j = 0; j < frame->NumLines(); ++j) {
        if (line_matches[j] >= 0 && map.line(line_matches[j])) {
          map.AddLineObservation(line_matches[j], kf_id, j);
        } else if (frame->line_has_depth[j]) {
          const Eigen::Vector3d s = R_wc * frame->line_endpoints[j][0] + t_wc;
          const Eigen::Vector3d e = R_wc * frame->line_endpoints[j][1] + t_wc;
          if ((e - s).norm() < 1e-3) continue;
          auto l = map.AddLine(PluckerLine::FromPoints(s, e), s, e,
                               frame->line_descriptors.row(j), kf_id);
          map.AddLineObservation(l->id, kf_id, j);
        }
      }
    }
    map.UpdateConnections(kf_id);
  }
  last_keyframe_ = kf_id;
  last_keyframe_frame_ = frame->index;
  first_tracked_ = 0;
  mapper_->Insert(&map, kf_id);
}

TrackResult Tracker::Track(std::shared_ptr<const StereoFrame> frame) {
  Require(frame != nullptr, "Track needs a frame");
  TrackResult result;
  const PinholeCamera& camera = options_.rig.camera;

  // Constant-velocity prediction.
  Eigen::Matrix3d R_pred = last_R_;
  Eigen::Vector3d t_pred = last_t_;
  if (have_pose_) {
    R_pred = velocity_R_ * last_R_;
    t_pred = velocity_R_ * last_t_ + velocity_t_;
  }

  if (lost_ || maps_.empty()) {
    const auto start = Clock::now();
    const bool had_map = !maps_.empty();
    if (StartMap(frame, R_pred, t_pred)) {
      result.state = had_map ? TrackingState::kNewMap : TrackingState::kOk;
      lost_ = false;
      velocity_R_.setIdentity();
      velocity_t_.setZero();
      result.keyframe = true;
    } else {
      result.state = had_map ? TrackingState::kLost : TrackingState::kNotInitialized;
    }
    result.R_cw = R_pred;
    result.t_cw = t_pred;
    result.map_index = static_cast<int>(maps_.size()) - 1;
    result.mapping_ms = Ms(start);
    if (had_map || result.state != TrackingState::kNotInitialized) {
      last_R_ = R_pred;
      last_t_ = t_pred;
      have_pose_ = true;
    }
    return result;
  }

  Map& map = *maps_.back();
  result.map_index = static_cast<int>(maps_.size()) - 1;
  std::vector<int> point_match(frame->NumKeypoints(), -1);
  std::vector<int> line_match(frame->NumLines(), -1);
  PoseOptimizerResult pose;
  std::vector<int> obs_point_ids, obs_keypoints, obs_line_ids, obs_segments;
  bool make_keyframe = false;
  {
    std::lock_guard<std::mutex> lock(map.mutex());
    const auto match_start = Clock::now();
    // Local map: the reference keyframe and its covisible keyframes.
    std::vector<int> local = {last_keyframe_};
    if (!map.keyframe(last_keyframe_)) local.clear();
    for (int id : map.BestCovisible(last_keyframe_, options_.mapping.local_keyframes)) {
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

    // Points: project with the prediction, match in a window around it.
    std::vector<std::shared_ptr<MapPoint>> candidates;
    std::vector<Eigen::Vector2f> predicted;
    for (int pid : point_ids) {
      auto p = map.point(pid);
      if (!p || p->bad) continue;
      const Eigen::Vector3d x_c = R_pred * p->position + t_pred;
      if (x_c.z() <= 0.05) continue;
      const Eigen::Vector2d uv = camera.Project(x_c);
      if (!InImage(camera, uv)) continue;
      candidates.push_back(p);
      predicted.push_back(uv.cast<float>());
      p->visible += 1;
    }
    const cv::Mat& frame_desc = frame->keypoints.descriptors;
    if (!candidates.empty() && frame->NumKeypoints() > 0) {
      Eigen::Matrix<float, Eigen::Dynamic, 2, Eigen::RowMajor> pred(candidates.size(), 2);
      cv::Mat query(static_cast<int>(candidates.size()), frame_desc.cols, frame_desc.type());
      for (size_t i = 0; i < candidates.size(); ++i) {
        pred.row(i) = predicted[i].transpose();
        candidates[i]->descriptor.copyTo(query.row(static_cast<int>(i)));
      }
      GuidedMatchOptions guided;
      guided.radius_px = options_.search_radius_px;
      guided.max_distance = frame_desc.type() == CV_8U ? options_.max_distance_binary
                                                        : options_.max_distance_float;
      guided.ratio = options_.match_ratio;
      Eigen::VectorXi m = GuidedMatch(pred, query, frame->keypoints.uv, frame_desc, guided);
      if ((m.array() >= 0).count() < 30) {  // fast motion: widen the window once
        guided.radius_px *= 2.0f;
        m = GuidedMatch(pred, query, frame->keypoints.uv, frame_desc, guided);
      }
      for (size_t i = 0; i < candidates.size(); ++i) {
        if (m(i) < 0) continue;
        obs_point_ids.push_back(candidates[i]->id);
        obs_keypoints.push_back(m(i));
      }
    }

    // Lines: projected map segments against frame segments (angle, distance, LBD).
    if (options_.use_lines && frame->NumLines() > 0) {
      std::vector<std::tuple<float, int, int>> pairs;  // (LBD distance, map line, segment)
      for (int lid : line_ids) {
        auto l = map.line(lid);
        if (!l || l->bad) continue;
        const Eigen::Vector3d s_c = R_pred * l->start + t_pred;
        const Eigen::Vector3d e_c = R_pred * l->end + t_pred;
        if (s_c.z() <= 0.05 || e_c.z() <= 0.05) continue;
        LineSegment proj;
        proj.start = camera.Project(s_c).cast<float>();
        proj.end = camera.Project(e_c).cast<float>();
        const Eigen::Vector2f mid = 0.5f * (proj.start + proj.end);
        if (!InImage(camera, mid.cast<double>()) || proj.Length() < 5.0f) continue;
        l->visible += 1;
        for (int j = 0; j < frame->NumLines(); ++j) {
          const LineSegment& seg = frame->lines[j];
          if (AngleDifference(seg.Angle(), proj.Angle()) > options_.line_max_angle_rad) continue;
          const Eigen::Vector2f seg_mid = 0.5f * (seg.start + seg.end);
          if (proj.DistanceToLine(seg_mid) > options_.line_search_px) continue;
          if ((seg_mid - mid).norm() > 0.5f * (proj.Length() + seg.Length()) + options_.line_search_px) {
            continue;
          }
          const float d = DescriptorDistance(l->descriptor, 0, frame->line_descriptors, j);
          if (d <= options_.line_max_lbd) pairs.emplace_back(d, lid, j);
        }
      }
      std::sort(pairs.begin(), pairs.end());
      std::set<int> used_lines, used_segments;
      for (const auto& [d, lid, j] : pairs) {
        (void)d;
        if (used_lines.count(lid) || used_segments.count(j)) continue;
        used_lines.insert(lid);
        used_segments.insert(j);
        obs_line_ids.push_back(lid);
        obs_segments.push_back(j);
      }
    }
    result.matched_points = static_cast<int>(obs_point_ids.size());
    result.matched_lines = static_cast<int>(obs_line_ids.size());
    result.matching_ms = Ms(match_start);

    // Motion-only BA.
    const auto opt_start = Clock::now();
    std::vector<PointObservation> points(obs_point_ids.size());
    for (size_t i = 0; i < obs_point_ids.size(); ++i) {
      const int k = obs_keypoints[i];
      points[i].point_w = map.point(obs_point_ids[i])->position;
      points[i].stereo = frame->u_right[k] >= 0.0;
      points[i].observed << frame->keypoints.uv(k, 0), frame->keypoints.uv(k, 1), frame->u_right[k];
      points[i].sigma_px = options_.point_sigma_px;
    }
    std::vector<LineObservation> lines(obs_line_ids.size());
    for (size_t i = 0; i < obs_line_ids.size(); ++i) {
      lines[i].line_w = map.line(obs_line_ids[i])->line;
      lines[i].start_px = frame->lines[obs_segments[i]].start.cast<double>();
      lines[i].end_px = frame->lines[obs_segments[i]].end.cast<double>();
      lines[i].sigma_px = options_.line_sigma_px;
    }
    pose = OptimizePose(options_.rig, R_pred, t_pred, points, lines, options_.pose);
    result.optimisation_ms = Ms(opt_start);
    result.inlier_points = pose.point_inliers;
    result.inlier_lines = pose.line_inliers;

    if (!pose.success || pose.point_inliers + pose.line_inliers < options_.min_inliers) {
      result.state = TrackingState::kLost;
      result.R_cw = R_pred;
      result.t_cw = t_pred;
      lost_ = true;
      last_R_ = R_pred;
      last_t_ = t_pred;
      return result;
    }
    for (size_t i = 0; i < obs_point_ids.size(); ++i) {
      if (!pose.point_inlier[i]) continue;
      map.point(obs_point_ids[i])->found += 1;
      point_match[obs_keypoints[i]] = obs_point_ids[i];
    }
    for (size_t i = 0; i < obs_line_ids.size(); ++i) {
      if (!pose.line_inlier[i]) continue;
      map.line(obs_line_ids[i])->found += 1;
      line_match[obs_segments[i]] = obs_line_ids[i];
    }
    // Keyframe decision (ORB-SLAM3's NeedNewKeyFrame for stereo, with local mapping idle: it is
    // in sequential mode, and in threaded mode the queue absorbs the keyframe). Reference: the
    // reference keyframe's map points seen by at least min_obs keyframes.
    const int frames_since = frame->index - last_keyframe_frame_;
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
    for (int i = 0; i < frame->NumKeypoints(); ++i) {
      if (!(frame->depth[i] > 0.0 && frame->depth[i] < close_depth)) continue;
      if (point_match[i] >= 0) {
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
    const bool c1 = frames_since >= options_.keyframe_max_frames ||
                    frames_since >= options_.keyframe_min_frames ||
                    tracked < 0.25 * reference || need_close;
    const bool c2 = (tracked < options_.keyframe_track_ratio * reference || need_close) &&
                    tracked > options_.min_inliers;
    make_keyframe = frames_since >= 1 &&
                    ((c1 && c2) || frames_since >= options_.keyframe_max_frames);
  }

  result.state = TrackingState::kOk;
  result.R_cw = pose.R_cw;
  result.t_cw = pose.t_cw;
  velocity_R_ = pose.R_cw * last_R_.transpose();
  velocity_t_ = pose.t_cw - velocity_R_ * last_t_;
  last_R_ = pose.R_cw;
  last_t_ = pose.t_cw;
  have_pose_ = true;
  if (make_keyframe) {
    const auto start = Clock::now();
    InsertKeyFrame(frame, pose.R_cw, pose.t_cw, point_match, line_match);
    result.keyframe = true;
    result.mapping_ms = Ms(start);
  }
  return result;
}

MapExport Tracker::ExportMap() const {
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Matrix<double, 6, 1>> lines;
  std::vector<int> point_map, line_map;
  MapExport out;
  for (size_t m = 0; m < maps_.size(); ++m) {
    std::lock_guard<std::mutex> lock(maps_[m]->mutex());
    for (const auto& [id, p] : maps_[m]->points()) {
      (void)id;
      if (p->bad || p->observations.empty()) continue;
      points.push_back(p->position);
      point_map.push_back(static_cast<int>(m));
    }
    for (const auto& [id, l] : maps_[m]->lines()) {
      (void)id;
      if (l->bad || l->observations.empty()) continue;
      Eigen::Matrix<double, 6, 1> row;
      row << l->start, l->end;
      lines.push_back(row);
      line_map.push_back(static_cast<int>(m));
    }
    out.keyframes += static_cast<int>(maps_[m]->keyframes().size());
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
