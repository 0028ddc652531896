// A bundle adjustment over part or all of a map, in three steps so that the solve runs without the
// map's lock (tracking goes on meanwhile): built under the lock, solved on the copy, written back
// under the lock. Local mapping (a window of keyframes) and loop closing (global BA) share it.
#pragma once

#include <unordered_map>
#include <utility>
#include <vector>

#include "slslam/map/map.h"
#include "slslam/optimization/bundle_adjustment.h"

namespace slslam {

class MapBundleAdjustment {
 public:
  // The map's correction epoch when the problem was built (`Map::correction_epoch`).
  explicit MapBundleAdjustment(int correction_epoch = 0) : correction_epoch_(correction_epoch) {}

  // Adds a keyframe's pose; returns its pose index. Caller holds the map's lock.
  int AddPose(const KeyFrame& kf, bool fixed);
  // Adds a point and its observations by the keyframes `pose_of(keyframe id)` gives a pose index
  // for (-1: the observation is left out). Caller holds the map's lock.
  template <class PoseOf>
  void AddPoint(const Map& map, const MapPoint& p, double sigma_px, PoseOf&& pose_of)
      SLSLAM_REQUIRES(map.mutex());
  template <class PoseOf>
  void AddLine(const Map& map, const MapLine& l, double sigma_px, PoseOf&& pose_of)
      SLSLAM_REQUIRES(map.mutex());
  // A window's landmarks: every point and line the keyframes of `window` observe (each once, in
  // id order, bad ones skipped) with their observations. `pose_index` (keyframe id -> pose index)
  // holds the window's poses; another observer joins as a fixed pose while fewer than
  // `max_fixed` have, else its observation is left out. Caller holds the map's lock.
  void AddWindowLandmarks(const Map& map, const std::vector<int>& window,
                          std::unordered_map<int, int>* pose_index, int max_fixed,
                          double point_sigma_px, double line_sigma_px) SLSLAM_REQUIRES(map.mutex());

  // The IMU between consecutive keyframes of the map's IMU chain (KeyFrame::inertial): for every
  // keyframe of `window` with a predecessor, the factor from it, the predecessor joining as a
  // fixed pose (with fixed velocity and biases) when it is not in the problem yet. The window's
  // velocities and biases are estimated. Nothing when the map has no MapInertial. Caller holds
  // the map's lock. Returns the number of factors.
  int AddInertialFactors(const Map& map, const std::vector<int>& window,
                         std::unordered_map<int, int>* pose_index) SLSLAM_REQUIRES(map.mutex());

  BaProblem& problem() { return problem_; }
  const BaProblem& problem() const { return problem_; }
  int correction_epoch() const { return correction_epoch_; }
  bool empty() const { return problem_.poses.empty(); }

  // Writes the solution back (caller holds the map's lock): poses of the keyframes that were not
  // fixed, points and lines, and drops the observations the solve found to be outliers. Entries
  // that left the map since the problem was built are skipped.
  //
  // With `carry_new`, what joined the map since (keyframes, points and lines local mapping made
  // while the solve ran) moves with the correction of the nearest keyframe of the problem (for a
  // keyframe: its first spanning-tree ancestor in the problem; for a landmark: its oldest observer
  // with a correction), as ORB-SLAM does after a global BA. Returns the number of keyframes so
  // carried.
  int Apply(Map* map, const BundleAdjustmentReport& report, bool carry_new = false) const
      SLSLAM_REQUIRES(map->mutex());

 private:
  // Apply's parts: the velocities, biases and gravity; the outlier observations leave the map.
  void ApplyInertial(Map* map) const SLSLAM_REQUIRES(map->mutex());
  void DropOutliers(Map* map, const BundleAdjustmentReport& report) const
      SLSLAM_REQUIRES(map->mutex());

  BaProblem problem_;
  std::vector<int> pose_kf_;   // pose index -> keyframe id
  std::vector<int> point_id_;  // point index -> map point id
  std::vector<int> line_id_;
  std::vector<int> state_kf_;                       // speed-bias index -> keyframe id
  std::vector<std::pair<int, int>> point_obs_ref_;  // (map point id, keyframe id) per observation
  std::vector<std::pair<int, int>> line_obs_ref_;
  int correction_epoch_ = 0;
};

template <class PoseOf>
void MapBundleAdjustment::AddPoint(const Map& map, const MapPoint& p, double sigma_px,
                                   PoseOf&& pose_of) {
  const int index = static_cast<int>(problem_.points.size());
  problem_.points.push_back(p.position);
  point_id_.push_back(p.id);
  for (const auto& [kf_id, kp] : p.observations) {
    const int pose = pose_of(kf_id);
    if (pose < 0) continue;
    const StereoFrame& f = *map.keyframe(kf_id)->frame;
    BaPointObservation o;
    o.pose = pose;
    o.point = index;
    o.stereo = f.u_right[kp] >= 0.0;
    o.observed << f.keypoints.uv(kp, 0), f.keypoints.uv(kp, 1), f.u_right[kp];
    o.sigma_px = sigma_px;
    problem_.point_observations.push_back(o);
    point_obs_ref_.emplace_back(p.id, kf_id);
  }
}

template <class PoseOf>
void MapBundleAdjustment::AddLine(const Map& map, const MapLine& l, double sigma_px,
                                  PoseOf&& pose_of) {
  const int index = static_cast<int>(problem_.lines.size());
  problem_.lines.push_back(l.line);
  line_id_.push_back(l.id);
  for (const auto& [kf_id, seg] : l.observations) {
    const int pose = pose_of(kf_id);
    if (pose < 0) continue;
    const StereoFrame& f = *map.keyframe(kf_id)->frame;
    BaLineObservation o;
    o.pose = pose;
    o.line = index;
    o.start_px = f.lines[seg].start.template cast<double>();
    o.end_px = f.lines[seg].end.template cast<double>();
    o.sigma_px = sigma_px;
    problem_.line_observations.push_back(o);
    line_obs_ref_.emplace_back(l.id, kf_id);
  }
}

}  // namespace slslam
