#include "slslam/mapping/loop_closer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <set>
#include <tuple>
#include <unordered_map>
#include <utility>

#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>

#include "slslam/core/check.h"
#include "slslam/features/descriptor_matcher.h"
#include "slslam/mapping/map_bundle_adjustment.h"

namespace slslam {

namespace {

using Clock = std::chrono::steady_clock;

double Ms(Clock::time_point since) {
  return std::chrono::duration<double, std::milli>(Clock::now() - since).count();
}

double RotationAngle(const Eigen::Matrix3d& R) { return Eigen::AngleAxisd(R).angle(); }

}  // namespace

void LoopClosingOptions::Check() const {
  SLSLAM_CHECK(min_keyframes >= 2, "tracking.loop_closing.min_keyframes must be >= 2, got ",
               min_keyframes);
  SLSLAM_CHECK(candidates >= 1, "tracking.loop_closing.candidates must be >= 1, got ", candidates);
  SLSLAM_CHECK(min_matches >= 6, "tracking.loop_closing.min_matches must be >= 6, got ",
               min_matches);
  SLSLAM_CHECK(match_ratio > 0.0f && match_ratio <= 1.0f,
               "tracking.loop_closing.match_ratio must be in (0, 1], got ", match_ratio);
  SLSLAM_CHECK(std::isfinite(ransac_error_px) && ransac_error_px > 0.0,
               "tracking.loop_closing.ransac_error_px must be > 0, got ", ransac_error_px);
  SLSLAM_CHECK(ransac_iterations >= 1, "tracking.loop_closing.ransac_iterations must be >= 1");
  SLSLAM_CHECK(min_pnp_inliers >= 4, "tracking.loop_closing.min_pnp_inliers must be >= 4");
  CheckAboveInRange("tracking.loop_closing.min_inliers", min_inliers, 0.0, 100000.0);
  CheckInRange("tracking.loop_closing.consistency", consistency, 1, 100);
  SLSLAM_CHECK(std::isfinite(agree_m) && agree_m > 0.0,
               "tracking.loop_closing.agree_m must be > 0");
  SLSLAM_CHECK(std::isfinite(agree_rad) && agree_rad > 0.0,
               "tracking.loop_closing.agree_rad must be > 0");
  CheckInRange("tracking.loop_closing.max_correction_ratio", max_correction_ratio, 0.0, 1.0);
  CheckInRange("tracking.loop_closing.max_correction_floor_m", max_correction_floor_m, 0.0, 1000.0);
  SLSLAM_CHECK(std::isfinite(max_correction_rad) && max_correction_rad > 0.0,
               "tracking.loop_closing.max_correction_rad must be > 0");
  SLSLAM_CHECK(strong_covisibility >= 1, "tracking.loop_closing.strong_covisibility must be >= 1");
  SLSLAM_CHECK(welding_keyframes >= 0 && welding_keyframes <= 1000,
               "tracking.loop_closing.welding_keyframes must be in [0, 1000], got ",
               welding_keyframes);
  SLSLAM_CHECK(vocabulary_levels_up >= 0,
               "tracking.loop_closing.vocabulary_levels_up must be >= 0");
  SLSLAM_CHECK(std::isfinite(point_sigma_px) && point_sigma_px > 0.0 &&
                   std::isfinite(line_sigma_px) && line_sigma_px > 0.0,
               "tracking.loop_closing sigmas must be > 0");
  pose_graph.Check();
}

std::vector<std::pair<int, int>> MatchByWords(const cv::Mat& descriptors,
                                              const FeatureVector& features, const KeyFrame& kf,
                                              const Map& map, float max_distance, float ratio) {
  // Map point ids are sparse, so the one-to-one table is a map (a point keeps the keypoint with
  // the smaller distance).
  std::map<int, std::pair<float, int>> owner;  // map point -> (distance, keypoint)
  for (const auto& [node, frame_ids] : features) {
    auto it = kf.bow_features.find(node);
    if (it == kf.bow_features.end()) continue;
    for (int i : frame_ids) {
      BestTwo best;  // index: the map point id
      for (int j : it->second) {
        const int pid = j < static_cast<int>(kf.point_ids.size()) ? kf.point_ids[j] : -1;
        if (pid < 0) continue;
        auto p = map.point(pid);
        if (!p || p->bad) continue;
        best.Add(DescriptorDistance(descriptors, i, p->descriptor, 0), pid);
      }
      if (best.index < 0 || best.best > max_distance) continue;
      if (best.second < std::numeric_limits<float>::max() && best.best >= ratio * best.second) {
        continue;
      }
      auto [pos, inserted] = owner.emplace(best.index, std::make_pair(best.best, i));
      if (!inserted && best.best < pos->second.first) pos->second = {best.best, i};
    }
  }
  std::vector<std::pair<int, int>> out;
  out.reserve(owner.size());
  for (const auto& [pid, match] : owner) out.emplace_back(match.second, pid);
  return out;
}

bool PoseFromMatches(const StereoFrame& frame, const Map& map,
                     const std::vector<std::pair<int, int>>& matches, const PinholeCamera& camera,
                     int iterations, double error_px, int min_inliers, Rigid3d* cam_from_world) {
  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> image;
  for (const auto& [keypoint, pid] : matches) {
    const Eigen::Vector3d& x = map.point(pid)->position;
    object.emplace_back(x.x(), x.y(), x.z());
    image.emplace_back(frame.keypoints.uv(keypoint, 0), frame.keypoints.uv(keypoint, 1));
  }
  const cv::Mat K = (cv::Mat_<double>(3, 3) << camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy,
                     0.0, 0.0, 1.0);
  cv::Mat rvec, tvec;
  std::vector<int> inliers;
  const bool solved =
      cv::solvePnPRansac(object, image, K, cv::noArray(), rvec, tvec, false, iterations,
                         static_cast<float>(error_px), 0.99, inliers, cv::SOLVEPNP_EPNP);
  if (!solved || static_cast<int>(inliers.size()) < min_inliers) return false;
  cv::Mat R_cv;
  cv::Rodrigues(rvec, R_cv);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) cam_from_world->rotation(r, c) = R_cv.at<double>(r, c);
    cam_from_world->translation(r) = tvec.at<double>(r);
  }
  return cam_from_world->rotation.allFinite() && cam_from_world->translation.allFinite();
}

LoopCloser::LoopCloser(const StereoRig& rig, const LoopClosingOptions& options,
                       const Vocabulary* vocabulary, float max_descriptor_distance_binary,
                       float max_descriptor_distance_float, LocalMapVerifier verifier,
                       bool background_global_ba)
    : rig_(rig),
      options_(options),
      vocabulary_(vocabulary),
      max_distance_binary_(max_descriptor_distance_binary),
      max_distance_float_(max_descriptor_distance_float),
      verifier_(std::move(verifier)),
      background_global_ba_(background_global_ba) {
  options_.Check();
  Require(static_cast<bool>(verifier_), "the loop closer needs a local-map verifier");
}

LoopCloser::~LoopCloser() { CancelGlobalBa(); }

void LoopCloser::CancelGlobalBa() {
  if (!global_ba_thread_.joinable()) return;
  global_ba_abort_ = true;
  global_ba_thread_.join();
}

void LoopCloser::WaitForGlobalBa() {
  if (global_ba_thread_.joinable()) global_ba_thread_.join();
  if (global_ba_error_) std::rethrow_exception(std::exchange(global_ba_error_, nullptr));
}

LoopClosingStats LoopCloser::stats() const {
  std::lock_guard<std::mutex> lock(stats_mutex_);
  return stats_;
}

std::vector<LoopEvent> LoopCloser::events() const {
  std::lock_guard<std::mutex> lock(stats_mutex_);
  return events_;
}

double LoopCloser::PathLength(const Map& map, int from_id, int to_id) {
  if (from_id > to_id) std::swap(from_id, to_id);
  double length = 0.0;
  bool have = false;
  Eigen::Vector3d last = Eigen::Vector3d::Zero();
  for (auto it = map.keyframes().lower_bound(from_id);
       it != map.keyframes().end() && it->first <= to_id; ++it) {
    const Eigen::Vector3d c = it->second->Center();
    if (have) length += (c - last).norm();
    last = c;
    have = true;
  }
  return length;
}

bool LoopCloser::Verify(Atlas* atlas, int source_map, const KeyFrame& kf, int target_map,
                        int candidate, Verified* out) {
  Map& target = atlas->map(target_map);
  MutexLock lock(target.mutex());
  auto c = target.keyframe(candidate);
  if (!c || c->bad) return false;
  const StereoFrame& frame = *kf.frame;
  const cv::Mat& desc = frame.keypoints.descriptors;
  const float max_distance = desc.type() == CV_8U ? max_distance_binary_ : max_distance_float_;
  const auto matches =
      MatchByWords(desc, kf.bow_features, *c, target, max_distance, options_.match_ratio);
  if (static_cast<int>(matches.size()) < options_.min_matches) return false;
  Rigid3d cam_from_world;
  if (!PoseFromMatches(frame, target, matches, rig_.camera, options_.ransac_iterations,
                       options_.ransac_error_px, options_.min_pnp_inliers, &cam_from_world)) {
    return false;
  }
  LocalMapMatch match = verifier_(frame, target, candidate, cam_from_world);
  if (!match.success || match.weighted_inliers < options_.min_inliers) return false;
  {
    std::lock_guard<std::mutex> stats_lock(stats_mutex_);
    ++stats_.candidates_verified;
  }
  out->target_map = target_map;
  out->candidate = candidate;
  // target_from_source = target_from_K * K_from_source (the keyframe's pose in its own map: kf).
  const Rigid3d& target_cam = match.cam_from_world;  // K in the target map
  Rigid3d& target_from_source = out->target_from_source;
  target_from_source.rotation = target_cam.rotation.transpose() * kf.cam_from_world.rotation;
  target_from_source.translation =
      target_cam.rotation.transpose() * (kf.cam_from_world.translation - target_cam.translation);
  out->match = std::move(match);
  if (target_map != source_map) return true;
  // Same map: the correction must be explainable by drift since the candidate.
  const Eigen::Vector3d center_old = kf.Center();
  const Eigen::Vector3d center_new = out->match.cam_from_world.Center();
  const double moved = (center_new - center_old).norm();
  const double turned =
      RotationAngle(out->match.cam_from_world.rotation * kf.cam_from_world.rotation.transpose());
  const double allowed = options_.max_correction_floor_m +
                         options_.max_correction_ratio * PathLength(target, candidate, kf.id);
  return moved <= allowed && turned <= options_.max_correction_rad;
}

bool LoopCloser::Process(Atlas* atlas, int map_index, int keyframe_id) {
  if (!vocabulary_ || (!options_.enabled && !options_.merge_maps)) return false;
  const auto start = Clock::now();
  const int source = atlas->Resolve(map_index);
  Map& source_map = atlas->map(source);
  // Threaded mode: a keyframe the tracker made before the last correction of its map was
  // queued in the world that correction has since fixed, and sees the place just closed again.
  // (Inline, every later keyframe is newer than the correction: nothing is skipped.)
  if (auto it = corrected_before_.find(source);
      it != corrected_before_.end() && keyframe_id < it->second) {
    std::lock_guard<std::mutex> stats_lock(stats_mutex_);
    ++stats_.keyframes_checked;
    return false;
  }
  std::shared_ptr<KeyFrame> kf;
  std::set<int> exclude = {keyframe_id};
  std::vector<BowVector> neighbour_bows;
  int map_keyframes = 0;
  {
    MutexLock lock(source_map.mutex());
    kf = source_map.keyframe(keyframe_id);
    if (!kf || kf->bad || kf->bow.empty() || !kf->frame) return false;
    for (const auto& [id, weight] : kf->covisibility) {
      (void)weight;
      exclude.insert(id);
      if (auto n = source_map.keyframe(id); n && !n->bow.empty()) neighbour_bows.push_back(n->bow);
    }
    map_keyframes = static_cast<int>(source_map.keyframes().size());
  }
  // A candidate must look at least as similar as the keyframe's weakest covisible neighbour.
  double min_score = 1.0;
  for (const BowVector& bow : neighbour_bows) {
    min_score = std::min(min_score, vocabulary_->Score(kf->bow, bow));
  }
  if (neighbour_bows.empty()) min_score = 0.0;

  const std::vector<std::tuple<double, int, int>> candidates =
      Candidates(atlas, source, *kf, exclude, min_score, map_keyframes);
  Verified verified;
  const bool found = VerifyFirst(atlas, source, *kf, candidates, &verified);
  const bool accept = Consistent(source, found, verified);
  const int corrected_map = accept ? Apply(atlas, source, keyframe_id, *kf, verified) : -1;
  {
    std::lock_guard<std::mutex> stats_lock(stats_mutex_);
    ++stats_.keyframes_checked;
    stats_.loop_ms += Ms(start);
  }
  if (corrected_map >= 0 && options_.global_ba) GlobalBundleAdjustment(atlas, corrected_map);
  return corrected_map >= 0;
}

std::vector<std::tuple<double, int, int>> LoopCloser::Candidates(Atlas* atlas, int source,
                                                                 const KeyFrame& kf,
                                                                 const std::set<int>& exclude,
                                                                 double min_score,
                                                                 int map_keyframes) const {
  const int keyframe_id = kf.id;
  std::vector<std::tuple<double, int, int>> candidates;  // (-score, map, keyframe)
  for (int m = 0; m < atlas->size(); ++m) {
    if (atlas->merged(m)) continue;
    const bool same = m == source;
    if (same && (!options_.enabled || map_keyframes < options_.min_keyframes)) continue;
    if (!same && !options_.merge_maps) continue;
    Map& target = atlas->map(m);
    const auto found =
        atlas->database(m).Query(kf.bow, options_.candidates, min_score, 0.8, [&](int id) {
          if (same && (exclude.count(id) || id >= keyframe_id)) return false;
          MutexLock lock(target.mutex());
          auto c = target.keyframe(id);
          if (!c || c->bad) return false;
          if (!same) return true;
          // Not a neighbour of a neighbour either: the keyframes just behind on this pass.
          for (const auto& [n, w] : c->covisibility) {
            (void)w;
            if (exclude.count(n)) return false;
          }
          return true;
        });
    for (const auto& c : found) candidates.emplace_back(-c.score, m, c.keyframe_id);
  }
  std::sort(candidates.begin(), candidates.end());
  if (static_cast<int>(candidates.size()) > options_.candidates) {
    candidates.resize(options_.candidates);
  }
  return candidates;
}

bool LoopCloser::VerifyFirst(Atlas* atlas, int source, const KeyFrame& kf,
                             const std::vector<std::tuple<double, int, int>>& candidates,
                             Verified* out) {
  for (const auto& [score, m, id] : candidates) {
    (void)score;
    Verified attempt;
    if (Verify(atlas, source, kf, m, id, &attempt)) {
      *out = std::move(attempt);
      return true;
    }
    if (attempt.target_map >= 0) {  // verified geometrically but implausible
      std::lock_guard<std::mutex> stats_lock(stats_mutex_);
      ++stats_.loops_rejected;
    }
  }
  return false;
}

bool LoopCloser::Consistent(int source, bool found, const Verified& verified) {
  Pending& pending = pending_[source];
  bool accept = false;
  if (found) {
    {
      std::lock_guard<std::mutex> stats_lock(stats_mutex_);
      ++stats_.loops_detected;
    }
    const Rigid3d& before = pending.target_from_source;
    const Rigid3d& now = verified.target_from_source;
    const bool agrees =
        pending.count > 0 && pending.target_map == verified.target_map &&
        (before.translation - now.translation).norm() <= options_.agree_m &&
        RotationAngle(before.rotation.transpose() * now.rotation) <= options_.agree_rad;
    if (agrees) {
      ++pending.count;
    } else {
      if (pending.count > 0) {
        std::lock_guard<std::mutex> stats_lock(stats_mutex_);
        ++stats_.loops_rejected;
      }
      pending = Pending{verified.target_map, 1, 0, verified.target_from_source};
    }
    pending.misses = 0;
    pending.target_from_source = verified.target_from_source;
    accept = pending.count >= options_.consistency;
  } else if (pending.count > 0 && ++pending.misses > 1) {
    std::lock_guard<std::mutex> stats_lock(stats_mutex_);
    ++stats_.loops_rejected;
    pending = Pending{};
  }
  return accept;
}

int LoopCloser::Apply(Atlas* atlas, int source, int keyframe_id, const KeyFrame& kf,
                      const Verified& verified) {
  Map& source_map = atlas->map(source);
  int corrected_map = -1;
  // A global BA in flight works on the world this correction is about to change.
  CancelGlobalBa();
  pending_.erase(source);
  const int target = verified.target_map;
  Map& target_map = atlas->map(target);
  LoopEvent event;
  event.keyframe_id = keyframe_id;
  event.candidate_id = verified.candidate;
  event.merge = target != source;
  event.frame_index = kf.frame->index;
  {
    MutexLock lock(target_map.mutex());
    if (auto c = target_map.keyframe(verified.candidate); c && c->frame) {
      event.candidate_frame_index = c->frame->index;
    }
  }
  event.correction_m = (kf.Center() - verified.match.cam_from_world.Center()).norm();
  if (event.merge) event.correction_m = 0.0;  // different worlds: no distance to compare
  {
    std::lock_guard<std::mutex> stats_lock(stats_mutex_);
    events_.push_back(event);
  }
  if (target == source) {
    MutexLock lock(source_map.mutex());
    if (source_map.keyframe(keyframe_id)) {
      Correct(&source_map, keyframe_id, verified);
      std::lock_guard<std::mutex> stats_lock(stats_mutex_);
      ++stats_.loops_accepted;
      corrected_map = source;
      corrected_before_[source] = source_map.ids().next_keyframe;
    }
  } else {
    std::scoped_lock lock(source_map.mutex(), target_map.mutex());  // in a fixed order
    source_map.mutex().AssertHeld();  // (the analysis does not follow std::scoped_lock)
    target_map.mutex().AssertHeld();
    if (auto kf = source_map.keyframe(keyframe_id)) {
      // With gravity in both maps, the merged one turns about it only; the keyframe's verified
      // pose becomes the one that alignment gives it (the correction below moves it there).
      Verified aligned = verified;
      const bool yaw_only = options_.yaw_and_position_with_gravity &&
                            source_map.gravity_direction() && target_map.gravity_direction();
      if (yaw_only) {
        aligned.target_from_source =
            YawAndPositionAlignment(verified.target_from_source, *source_map.gravity_direction(),
                                    *target_map.gravity_direction(), kf->Center());
        std::lock_guard<std::mutex> stats_lock(stats_mutex_);
        ++stats_.merges_in_yaw_and_position;
      }
      TransformMap(&source_map, aligned.target_from_source);
      if (yaw_only) aligned.match.cam_from_world = kf->cam_from_world;
      std::vector<std::pair<int, BowVector>> moved;
      for (const auto& [id, k] : source_map.keyframes()) moved.emplace_back(id, k->bow);
      target_map.Absorb(&source_map);
      atlas->database(source).Clear();
      for (const auto& [id, bow] : moved) {
        if (!bow.empty()) atlas->database(target).Add(id, bow);
      }
      atlas->MarkMerged(source, target);
      auto& edges = loop_edges_[target];
      for (const LoopEdge& e : loop_edges_[source]) edges.push_back(e);
      loop_edges_.erase(source);
      Correct(&target_map, keyframe_id, aligned);
      // Inline, a global BA over the whole map follows at once and subsumes it.
      if (!options_.global_ba || background_global_ba_) {
        std::set<int> merged_side;
        for (const auto& [id, bow] : moved) merged_side.insert(id);
        WeldingBundleAdjustment(&target_map, keyframe_id, verified.candidate, merged_side);
      }
      std::lock_guard<std::mutex> stats_lock(stats_mutex_);
      ++stats_.merges;
      corrected_map = target;
      corrected_before_[target] = target_map.ids().next_keyframe;
    }
  }
  return corrected_map;
}

Rigid3d YawAndPositionAlignment(const Rigid3d& target_from_source, const Eigen::Vector3d& g_source,
                                const Eigen::Vector3d& g_target,
                                const Eigen::Vector3d& pivot_source) {
  const Eigen::Vector3d mapped = (target_from_source.rotation * g_source).normalized();
  const Eigen::Matrix3d tilt =
      Eigen::Quaterniond::FromTwoVectors(mapped, g_target.normalized()).toRotationMatrix();
  Rigid3d aligned;
  aligned.rotation = tilt * target_from_source.rotation;
  aligned.translation = target_from_source * pivot_source - aligned.rotation * pivot_source;
  return aligned;
}

void LoopCloser::TransformMap(Map* map, const Rigid3d& target_from_source) {
  // x_t = target_from_source * x_s; a pose cam_from_source becomes
  // cam_from_target = cam_from_source * source_from_target.
  const Rigid3d source_from_target = target_from_source.Inverse();
  for (auto& [id, kf] : map->keyframes()) {
    (void)id;
    MoveKeyFrame(kf.get(), kf->cam_from_world * source_from_target);
  }
  for (auto& [id, p] : map->points()) {
    (void)id;
    p->position = target_from_source * p->position;
  }
  for (auto& [id, l] : map->lines()) {
    (void)id;
    l->line = l->line.Transformed(target_from_source);
    l->start = target_from_source * l->start;
    l->end = target_from_source * l->end;
  }
  map->BumpCorrectionEpoch();
}

void LoopCloser::Correct(Map* map, int keyframe_id, const Verified& verified) {
  auto current = map->keyframe(keyframe_id);
  // Poses before the correction, and the initial values of the essential graph: the keyframe and
  // its covisible neighbours move rigidly to the verified pose.
  std::unordered_map<int, Rigid3d> original;  // cam_from_world of each keyframe
  for (const auto& [id, kf] : map->keyframes()) original[id] = kf->cam_from_world;
  const Rigid3d K_old = original[keyframe_id];
  const Rigid3d K_new = verified.match.cam_from_world;
  std::set<int> group = {keyframe_id};
  for (const auto& [id, w] : current->covisibility) {
    (void)w;
    if (map->keyframe(id) && id != verified.candidate) group.insert(id);
  }
  std::vector<int> ids;
  std::unordered_map<int, int> index;
  std::vector<BaPose> poses;
  const int root = map->keyframes().begin()->first;
  for (const auto& [id, kf] : map->keyframes()) {
    BaPose pose;
    const Rigid3d& o = original[id];
    if (group.count(id)) {
      const Eigen::Matrix3d R_iK = o.rotation * K_old.rotation.transpose();
      pose.cam_from_world.rotation = R_iK * K_new.rotation;
      pose.cam_from_world.translation =
          R_iK * (K_new.translation - K_old.translation) + o.translation;
    } else {
      pose.cam_from_world = o;
    }
    pose.fixed = id == root || id == verified.candidate;
    index[id] = static_cast<int>(poses.size());
    ids.push_back(id);
    poses.push_back(pose);
  }
  // Essential graph: spanning tree and strong covisibility from the poses before the correction,
  // loop edges (earlier ones and the keyframe's group to the candidate) from the corrected ones.
  std::vector<PoseGraphEdge> edges;
  auto add_edge = [&](int a, int b, const Rigid3d& pa, const Rigid3d& pb) {
    PoseGraphEdge e;
    e.a = index[a];
    e.b = index[b];
    e.a_from_b = RelativePose(pa, pb);
    edges.push_back(e);
  };
  for (const auto& [id, kf] : map->keyframes()) {
    if (kf->parent >= 0 && index.count(kf->parent)) {
      add_edge(kf->parent, id, original[kf->parent], original[id]);
    }
    for (const auto& [other, weight] : kf->covisibility) {
      if (other > id && weight >= options_.strong_covisibility && index.count(other) &&
          other != kf->parent) {
        add_edge(id, other, original[id], original[other]);
      }
    }
  }
  for (const LoopEdge& e : loop_edges_[verified.target_map]) {
    if (!index.count(e.a) || !index.count(e.b)) continue;
    PoseGraphEdge edge;
    edge.a = index[e.a];
    edge.b = index[e.b];
    edge.a_from_b = e.a_from_b;
    edges.push_back(edge);
  }
  const Rigid3d C = poses[index[verified.candidate]].cam_from_world;
  for (int g : group) {
    const Rigid3d& p = poses[index[g]].cam_from_world;
    add_edge(verified.candidate, g, C, p);
    LoopEdge loop;
    loop.a = verified.candidate;
    loop.b = g;
    loop.a_from_b = RelativePose(C, p);
    loop_edges_[verified.target_map].push_back(loop);
  }
  PoseGraphOptions pose_graph = options_.pose_graph;
  if (options_.yaw_and_position_with_gravity && map->gravity_direction()) {
    pose_graph.yaw_and_position_only = true;
    pose_graph.gravity_in_world = *map->gravity_direction();
  }
  const PoseGraphReport report = OptimizePoseGraph(&poses, edges, pose_graph);
  if (!report.solved) {  // keep the rigid correction of the group at least
    for (size_t i = 0; i < ids.size(); ++i) {
      if (!group.count(ids[i])) poses[i] = {original[ids[i]], false};
    }
  }
  // Poses, then every landmark follows its reference keyframe (its oldest live observer).
  for (size_t i = 0; i < ids.size(); ++i) {
    MoveKeyFrame(map->keyframe(ids[i]).get(), poses[i].cam_from_world);
  }
  auto reference = [&](const std::map<int, int>& observations) -> int {
    for (const auto& [kf_id, idx] : observations) {
      (void)idx;
      if (index.count(kf_id)) return kf_id;
    }
    return -1;
  };
  for (auto& [id, p] : map->points()) {
    (void)id;
    const int ref = reference(p->observations);
    if (ref < 0) continue;
    const Rigid3d& o = original[ref];
    const Rigid3d& n = poses[index[ref]].cam_from_world;
    p->position =
        n.rotation.transpose() * (o.rotation * p->position + o.translation - n.translation);
  }
  for (auto& [id, l] : map->lines()) {
    (void)id;
    const int ref = reference(l->observations);
    if (ref < 0) continue;
    const Rigid3d& o = original[ref];
    const Rigid3d& n = poses[index[ref]].cam_from_world;
    const Rigid3d world_from_n = n.Inverse();
    l->line = l->line.Transformed(o).Transformed(world_from_n);
    l->start = world_from_n * (o * l->start);
    l->end = world_from_n * (o * l->end);
  }
  Fuse(map, keyframe_id, verified.match);
  for (int g : group) map->UpdateConnections(g);
  map->BumpCorrectionEpoch();
}

void LoopCloser::Fuse(Map* map, int keyframe_id, const LocalMapMatch& match) {
  auto kf = map->keyframe(keyframe_id);
  if (!kf) return;
  // Points: the keyframe's keypoint takes the older map point; a duplicate gives its
  // observations to it and goes.
  for (size_t i = 0; i < match.point_ids.size(); ++i) {
    auto keep = map->point(match.point_ids[i]);
    const int k = match.keypoints[i];
    if (!keep || keep->bad || k < 0 || k >= static_cast<int>(kf->point_ids.size())) continue;
    const int old_id = kf->point_ids[k];
    if (old_id == keep->id) continue;
    if (keep->observations.count(keyframe_id)) continue;  // already seen at another keypoint
    auto duplicate = old_id >= 0 ? map->point(old_id) : nullptr;
    if (duplicate) {
      for (const auto& [other_kf, idx] : duplicate->observations) {
        auto o = map->keyframe(other_kf);
        if (!o || keep->observations.count(other_kf)) continue;
        keep->observations[other_kf] = idx;
        o->point_ids[idx] = keep->id;
      }
      keep->visible += duplicate->visible;
      keep->found += duplicate->found;
      map->ErasePoint(old_id);
    }
    map->AddPointObservation(keep->id, keyframe_id, k);
  }
  for (size_t i = 0; i < match.line_ids.size(); ++i) {
    auto keep = map->line(match.line_ids[i]);
    const int s = match.segments[i];
    if (!keep || keep->bad || s < 0 || s >= static_cast<int>(kf->line_ids.size())) continue;
    const int old_id = kf->line_ids[s];
    if (old_id == keep->id) continue;
    if (keep->observations.count(keyframe_id)) continue;
    auto duplicate = old_id >= 0 ? map->line(old_id) : nullptr;
    if (duplicate) {
      for (const auto& [other_kf, idx] : duplicate->observations) {
        auto o = map->keyframe(other_kf);
        if (!o || keep->observations.count(other_kf)) continue;
        keep->observations[other_kf] = idx;
        o->line_ids[idx] = keep->id;
      }
      keep->visible += duplicate->visible;
      keep->found += duplicate->found;
      map->EraseLine(old_id);
    }
    map->AddLineObservation(keep->id, keyframe_id, s);
  }
}

void LoopCloser::WeldingBundleAdjustment(Map* map, int keyframe_id, int candidate_id,
                                         const std::set<int>& merged_side) {
  if (options_.welding_keyframes <= 0) return;
  const auto start = Clock::now();
  // The window: both sides of the seam, each keyframe with its best covisible ones (after the
  // fusion, covisibility crosses the seam). As in ORB-SLAM3 the older map's side is fixed (it
  // holds the world the merged map was moved into) and the merged map's side moves onto it.
  std::set<int> window;
  for (int side : {keyframe_id, candidate_id}) {
    if (!map->keyframe(side)) continue;
    window.insert(side);
    for (int id : map->BestCovisible(side, options_.welding_keyframes)) {
      if (map->keyframe(id)) window.insert(id);
    }
  }
  int free_poses = 0;
  for (int id : window) free_poses += merged_side.count(id) > 0;
  if (free_poses == 0 || !window.count(candidate_id)) return;
  MapBundleAdjustment ba(map->correction_epoch());
  std::unordered_map<int, int> pose_index;
  for (int id : window) {
    pose_index[id] = ba.AddPose(*map->keyframe(id), /*fixed=*/merged_side.count(id) == 0);
  }
  // Other observers of the window's landmarks anchor it too, fixed (at most as many as the
  // window has).
  ba.AddWindowLandmarks(*map, std::vector<int>(window.begin(), window.end()), &pose_index,
                        static_cast<int>(window.size()), options_.point_sigma_px,
                        options_.line_sigma_px);
  // Solved under the maps' locks, as the merge itself (a window of about 20 keyframes: tens of
  // milliseconds, benchmarks/log/loop_closing.md).
  const BundleAdjustmentReport report =
      SolveBundleAdjustment(rig_, &ba.problem(), options_.global_ba_options);
  if (!report.solved) return;
  ba.Apply(map, report);
  for (int id : window) map->UpdateConnections(id);
  map->BumpCorrectionEpoch();
  std::lock_guard<std::mutex> stats_lock(stats_mutex_);
  ++stats_.welding_ba_runs;
  stats_.welding_ba_ms += Ms(start);
}

void LoopCloser::GlobalBundleAdjustment(Atlas* atlas, int map_index) {
  const auto start = Clock::now();
  Map& map = atlas->map(map_index);
  auto ba = std::make_shared<MapBundleAdjustment>();
  {
    MutexLock lock(map.mutex());
    if (map.keyframes().empty()) return;
    std::unordered_map<int, int> pose_index;
    const int root = map.keyframes().begin()->first;
    for (const auto& [id, kf] : map.keyframes()) pose_index[id] = ba->AddPose(*kf, id == root);
    auto pose_of = [&](int kf_id) {
      auto it = pose_index.find(kf_id);
      return it == pose_index.end() ? -1 : it->second;
    };
    for (const auto& [pid, p] : map.points()) {
      (void)pid;
      if (!p->bad && !p->observations.empty()) {
        ba->AddPoint(map, *p, options_.point_sigma_px, pose_of);
      }
    }
    for (const auto& [lid, l] : map.lines()) {
      (void)lid;
      if (!l->bad && !l->observations.empty()) {
        ba->AddLine(map, *l, options_.line_sigma_px, pose_of);
      }
    }
    // With the IMU in the map (tracking.imu.local_ba_keyframes), the IMU between consecutive
    // keyframes too, every velocity and bias estimated.
    std::vector<int> all;
    all.reserve(map.keyframes().size());
    for (const auto& [id, kf] : map.keyframes()) all.push_back(id);
    ba->AddInertialFactors(map, all, &pose_index);
  }
  const double build_ms = Ms(start);
  auto run = [this, atlas, map_index, ba, start, build_ms] {
    const BundleAdjustmentReport report =
        SolveBundleAdjustment(rig_, &ba->problem(), options_.global_ba_options,
                              background_global_ba_ ? &global_ba_abort_ : nullptr);
    double apply_ms = 0.0;
    bool cancelled = global_ba_abort_;
    if (report.solved && !cancelled) {
      Map& map = atlas->map(map_index);
      MutexLock lock(map.mutex());
      const auto apply_start = Clock::now();
      // Merged into another map meanwhile: that merge cancelled this run (checked again under
      // the lock all the same).
      cancelled = global_ba_abort_ || atlas->merged(map_index);
      if (!cancelled) {
        ba->Apply(&map, report, /*carry_new=*/background_global_ba_);
        map.BumpCorrectionEpoch();
      }
      apply_ms = Ms(apply_start);
    }
    std::lock_guard<std::mutex> stats_lock(stats_mutex_);
    if (cancelled) {
      ++stats_.global_ba_cancelled;
      return;
    }
    ++stats_.global_ba_runs;
    stats_.global_ba_ms += Ms(start);
    stats_.global_ba_lock_ms += build_ms + apply_ms;
  };
  if (!background_global_ba_) {
    run();
    return;
  }
  global_ba_abort_ = false;
  global_ba_thread_ = std::thread([this, run] {
    try {
      run();
    } catch (...) {  // rethrown by WaitForGlobalBa (the end of the run)
      global_ba_error_ = std::current_exception();
    }
  });
}

}  // namespace slslam
