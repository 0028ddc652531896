#include "slslam/mapping/map_bundle_adjustment.h"

#include <algorithm>
#include <set>
#include <unordered_set>

#include "slslam/core/check.h"
#include "slslam/core/rigid3.h"
#include "slslam/core/time.h"

namespace slslam {

void MapBundleAdjustment::AddWindowLandmarks(const Map& map, const std::vector<int>& window,
                                             std::unordered_map<int, int>* pose_index,
                                             int max_fixed, double point_sigma_px,
                                             double line_sigma_px) {
  std::set<int> points, lines;
  for (int id : window) {
    auto kf = map.keyframe(id);
    for (int pid : kf->point_ids) {
      if (pid >= 0) points.insert(pid);
    }
    for (int lid : kf->line_ids) {
      if (lid >= 0) lines.insert(lid);
    }
  }
  int fixed_added = 0;
  auto pose_of = [&](int kf_id) -> int {
    auto it = pose_index->find(kf_id);
    if (it != pose_index->end()) return it->second;
    if (fixed_added >= max_fixed) return -1;
    map.mutex().AssertHeld();  // held by this function's caller (a lambda is not followed)
    auto kf = map.keyframe(kf_id);
    if (!kf) return -1;
    ++fixed_added;
    return (*pose_index)[kf_id] = AddPose(*kf, /*fixed=*/true);
  };
  for (int pid : points) {
    auto p = map.point(pid);
    if (p && !p->bad) AddPoint(map, *p, point_sigma_px, pose_of);
  }
  // A line a keyframe with the IMU's pose observes is held: in a stretch without points the camera
  // drives along such lines (a lining's wall-floor edges), which leaves their depth to stereo alone
  // (the left-image distances this problem has do not fix it), and the keyframes around them are
  // held too.
  const auto seen_from_imu_pose = [&](const MapLine& l) {
    map.mutex().AssertHeld();  // held by this function's caller (a lambda is not followed)
    for (const auto& [kf_id, segment] : l.observations) {
      (void)segment;
      auto kf = map.keyframe(kf_id);
      if (kf && kf->pose_from_imu) return true;
    }
    return false;
  };
  for (int lid : lines) {
    auto l = map.line(lid);
    if (l && !l->bad && !seen_from_imu_pose(*l)) AddLine(map, *l, line_sigma_px, pose_of);
  }
}

int MapBundleAdjustment::AddInertialFactors(const Map& map, const std::vector<int>& window,
                                            std::unordered_map<int, int>* pose_index) {
  if (!map.inertial()) return 0;
  const MapInertial& imu = *map.inertial();
  BaInertial& inertial = problem_.inertial;
  inertial.body_from_cam = imu.body_from_cam;
  inertial.g_world = imu.g_world;
  inertial.gravity_sigma_rad = imu.gravity_sigma_rad;
  const std::unordered_set<int> free(window.begin(), window.end());
  std::unordered_map<int, int> state_index;  // keyframe id -> speed-bias index
  const auto state_of = [&](const KeyFrame& kf) {
    auto [it, added] = state_index.try_emplace(kf.id, static_cast<int>(inertial.states.size()));
    if (added) {
      inertial.states.push_back({kf.inertial->v_world_body, kf.inertial->bias, !free.count(kf.id)});
      state_kf_.push_back(kf.id);
    }
    return it->second;
  };
  std::vector<int> ordered(window.begin(), window.end());
  std::sort(ordered.begin(), ordered.end());
  int added = 0;
  for (int id : ordered) {
    auto kf = map.keyframe(id);
    if (!kf || !kf->inertial || kf->inertial->previous < 0) continue;
    auto previous = map.keyframe(kf->inertial->previous);
    if (!previous || !previous->inertial) continue;
    const KeyFrameInertial& from = *previous->inertial;
    const KeyFrameInertial& to = *kf->inertial;
    if (!(SecondsBetween(from.t_ns, to.t_ns) <= imu.max_interval_s)) continue;
    BaInertialFactor factor;
    factor.pre = ImuPreintegration(from.bias, imu.noise);
    const int64_t offset_ns = NsFromSeconds(imu.time_offset_s);
    if (!to.samples_from_previous.Preintegrate(from.t_ns - offset_ns, to.t_ns - offset_ns,
                                               imu.max_sample_gap_s, &factor.pre)) {
      continue;
    }
    auto it = pose_index->find(previous->id);
    if (it == pose_index->end()) {
      it = pose_index->emplace(previous->id, AddPose(*previous, /*fixed=*/true)).first;
    }
    factor.pose_i = it->second;
    const auto window_pose = pose_index->find(id);
    Require(window_pose != pose_index->end(), "AddInertialFactors: a window keyframe has no pose");
    factor.pose_j = window_pose->second;
    factor.state_i = state_of(*previous);
    factor.state_j = state_of(*kf);
    inertial.factors.push_back(std::move(factor));
    ++added;
  }
  return added;
}

void MapBundleAdjustment::ApplyInertial(Map* map) const {
  if (!problem_.inertial.factors.empty() && map->inertial()) {
    MapInertial imu = *map->inertial();
    imu.g_world = problem_.inertial.g_world;
    map->set_inertial(imu);
    map->set_gravity_direction(imu.g_world);  // (what loop correction and merges align to)
  }
  for (size_t i = 0; i < state_kf_.size(); ++i) {
    const BaSpeedBias& state = problem_.inertial.states[i];
    auto kf = map->keyframe(state_kf_[i]);
    if (state.fixed || !kf || !kf->inertial) continue;
    kf->inertial->v_world_body = state.v_world_body;
    kf->inertial->bias = state.bias;
    ++kf->inertial->refined;
  }
}

void MapBundleAdjustment::DropOutliers(Map* map, const BundleAdjustmentReport& report) const {
  for (size_t i = 0; i < point_obs_ref_.size(); ++i) {
    if (!report.point_outlier[i]) continue;
    const auto [pid, kf_id] = point_obs_ref_[i];
    auto p = map->point(pid);
    auto kf = map->keyframe(kf_id);
    if (!p || !kf) continue;
    auto it = p->observations.find(kf_id);
    if (it == p->observations.end()) continue;
    kf->point_ids[it->second] = -1;
    p->observations.erase(it);
  }
  for (size_t i = 0; i < line_obs_ref_.size(); ++i) {
    if (!report.line_outlier[i]) continue;
    const auto [lid, kf_id] = line_obs_ref_[i];
    auto l = map->line(lid);
    auto kf = map->keyframe(kf_id);
    if (!l || !kf) continue;
    auto it = l->observations.find(kf_id);
    if (it == l->observations.end()) continue;
    kf->line_ids[it->second] = -1;
    l->observations.erase(it);
  }
}

int MapBundleAdjustment::AddPose(const KeyFrame& kf, bool fixed) {
  const int index = static_cast<int>(problem_.poses.size());
  problem_.poses.push_back({kf.cam_from_world, fixed});
  pose_kf_.push_back(kf.id);
  return index;
}

int MapBundleAdjustment::Apply(Map* map, const BundleAdjustmentReport& report,
                               bool carry_new) const {
  // Per keyframe of the problem: how its world moved, after_from_before (x_after =
  // after_from_before * x_before; before = its pose now, which local mapping may have changed
  // since the problem was built; after = the solution).
  std::unordered_map<int, Rigid3d> moved;
  for (size_t i = 0; i < problem_.poses.size(); ++i) {
    auto kf = map->keyframe(pose_kf_[i]);
    if (!kf) continue;
    if (problem_.poses[i].fixed) {
      if (carry_new) moved[kf->id] = Rigid3d();
      continue;
    }
    const Rigid3d& after = problem_.poses[i].cam_from_world;
    if (carry_new) {
      Rigid3d after_from_before;
      after_from_before.rotation = after.rotation.transpose() * kf->cam_from_world.rotation;
      after_from_before.translation =
          after.rotation.transpose() * (kf->cam_from_world.translation - after.translation);
      moved[kf->id] = after_from_before;
    }
    kf->cam_from_world = after;
  }
  ApplyInertial(map);
  for (size_t i = 0; i < point_id_.size(); ++i) {
    if (auto p = map->point(point_id_[i])) p->position = problem_.points[i];
  }
  for (size_t i = 0; i < line_id_.size(); ++i) {
    if (auto l = map->line(line_id_[i])) {
      l->line = problem_.lines[i];
      l->start = l->line.ClosestPointTo(l->start);
      l->end = l->line.ClosestPointTo(l->end);
    }
  }
  DropOutliers(map, report);
  if (!carry_new) return 0;

  // Keyframes made while the solve ran follow their first ancestor in the problem.
  int carried = 0;
  std::vector<std::shared_ptr<KeyFrame>> fresh;
  for (const auto& [id, kf] : map->keyframes()) {
    if (!moved.count(id)) fresh.push_back(kf);
  }
  for (const auto& kf : fresh) {
    const Rigid3d* w = nullptr;  // after_from_before of the ancestor
    int ancestor = kf->parent;
    for (size_t hops = 0; ancestor >= 0 && hops <= map->keyframes().size(); ++hops) {
      if (auto it = moved.find(ancestor); it != moved.end()) {
        w = &it->second;
        break;
      }
      auto a = map->keyframe(ancestor);
      ancestor = a ? a->parent : -1;
    }
    if (!w) continue;
    const Rigid3d correction = *w;
    // y = R_cw x + t_cw for x = R^T (x' - t) (R, t: the correction): R_cw' = R_cw R^T,
    // t_cw' = t_cw - R_cw' t.
    Rigid3d& pose = kf->cam_from_world;
    pose.rotation = pose.rotation * correction.rotation.transpose();
    pose.translation = pose.translation - pose.rotation * correction.translation;
    if (kf->inertial) kf->inertial->v_world_body = correction.rotation * kf->inertial->v_world_body;
    moved[kf->id] = correction;
    ++carried;
  }
  // Landmarks outside the problem follow their oldest observer that moved.
  const std::unordered_set<int> solved_points(point_id_.begin(), point_id_.end());
  const std::unordered_set<int> solved_lines(line_id_.begin(), line_id_.end());
  auto reference = [&](const std::map<int, int>& observations) -> const Rigid3d* {
    for (const auto& [kf_id, idx] : observations) {
      (void)idx;
      if (auto it = moved.find(kf_id); it != moved.end()) return &it->second;
    }
    return nullptr;
  };
  for (auto& [id, p] : map->points()) {
    if (solved_points.count(id)) continue;
    if (const Rigid3d* w = reference(p->observations)) p->position = *w * p->position;
  }
  for (auto& [id, l] : map->lines()) {
    if (solved_lines.count(id)) continue;
    if (const Rigid3d* w = reference(l->observations)) {
      l->line = l->line.Transformed(*w);
      l->start = *w * l->start;
      l->end = *w * l->end;
    }
  }
  return carried;
}

}  // namespace slslam
