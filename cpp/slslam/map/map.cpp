#include "slslam/map/map.h"

#include <algorithm>

#include "slslam/core/check.h"

namespace slslam {

std::shared_ptr<KeyFrame> Map::AddKeyFrame(const Rigid3d& cam_from_world,
                                           std::shared_ptr<const StereoFrame> frame) {
  Require(frame != nullptr, "a keyframe needs its frame");
  auto kf = std::make_shared<KeyFrame>();
  kf->id = ids_->next_keyframe++;
  kf->cam_from_world = cam_from_world;
  kf->point_ids.assign(frame->NumKeypoints(), -1);
  kf->line_ids.assign(frame->NumLines(), -1);
  kf->frame = std::move(frame);
  keyframes_[kf->id] = kf;
  return kf;
}

std::shared_ptr<MapPoint> Map::AddPoint(const Eigen::Vector3d& position, const cv::Mat& descriptor,
                                        int keyframe_id) {
  auto p = std::make_shared<MapPoint>();
  p->id = ids_->next_point++;
  p->position = position;
  p->descriptor = descriptor.clone();
  p->first_keyframe = keyframe_id;
  points_[p->id] = p;
  return p;
}

std::shared_ptr<MapLine> Map::AddLine(const PluckerLine& line, const Eigen::Vector3d& start,
                                      const Eigen::Vector3d& end, const cv::Mat& descriptor,
                                      int keyframe_id) {
  auto l = std::make_shared<MapLine>();
  l->id = ids_->next_line++;
  l->line = line;
  l->start = start;
  l->end = end;
  l->descriptor = descriptor.clone();
  l->first_keyframe = keyframe_id;
  lines_[l->id] = l;
  return l;
}

void Map::AddPointObservation(int point_id, int keyframe_id, int keypoint) {
  auto p = point(point_id);
  auto kf = keyframe(keyframe_id);
  if (!p || !kf) return;
  p->observations[keyframe_id] = keypoint;
  kf->point_ids[keypoint] = point_id;
}

void Map::AddLineObservation(int line_id, int keyframe_id, int segment) {
  auto l = line(line_id);
  auto kf = keyframe(keyframe_id);
  if (!l || !kf) return;
  l->observations[keyframe_id] = segment;
  kf->line_ids[segment] = line_id;
}

void Map::UpdateConnections(int keyframe_id) {
  auto kf = keyframe(keyframe_id);
  if (!kf) return;
  std::map<int, int> counts;
  for (int pid : kf->point_ids) {
    if (pid < 0) continue;
    auto p = point(pid);
    if (!p || p->bad) continue;
    for (const auto& [other, idx] : p->observations) {
      (void)idx;
      if (other != keyframe_id) ++counts[other];
    }
  }
  if (counts.empty()) {
    // A keyframe sharing no point (a stretch where the points are noise): its shared lines.
    for (int lid : kf->line_ids) {
      auto l = lid >= 0 ? line(lid) : nullptr;
      if (!l || l->bad) continue;
      for (const auto& [other, idx] : l->observations) {
        (void)idx;
        if (other != keyframe_id) ++counts[other];
      }
    }
  }
  // ORB-SLAM keeps edges with at least 15 shared points, or the single best one.
  constexpr int kMinShared = 15;
  int best = -1;
  int best_count = 0;
  kf->covisibility.clear();
  for (const auto& [other, count] : counts) {
    if (count > best_count) {
      best = other;
      best_count = count;
    }
    if (count >= kMinShared) kf->covisibility[other] = count;
  }
  if (kf->covisibility.empty() && best >= 0) kf->covisibility[best] = best_count;
  for (const auto& [other, count] : kf->covisibility) {
    if (auto o = keyframe(other)) o->covisibility[keyframe_id] = count;
  }
  if (kf->parent < 0 && best >= 0 && best < keyframe_id) kf->parent = best;
}

void Map::ErasePoint(int point_id) {
  auto p = point(point_id);
  if (!p) return;
  for (const auto& [kf_id, idx] : p->observations) {
    if (auto kf = keyframe(kf_id); kf && idx < static_cast<int>(kf->point_ids.size())) {
      if (kf->point_ids[idx] == point_id) kf->point_ids[idx] = -1;
    }
  }
  points_.erase(point_id);
}

void Map::EraseLine(int line_id) {
  auto l = line(line_id);
  if (!l) return;
  for (const auto& [kf_id, idx] : l->observations) {
    if (auto kf = keyframe(kf_id); kf && idx < static_cast<int>(kf->line_ids.size())) {
      if (kf->line_ids[idx] == line_id) kf->line_ids[idx] = -1;
    }
  }
  lines_.erase(line_id);
}

void Map::EraseKeyFrame(int keyframe_id) {
  auto kf = keyframe(keyframe_id);
  if (!kf) return;
  kf->bad = true;
  // Frames tracked against kf keep a pose: kf relative to its parent at this moment.
  RetiredKeyFrame retired;
  retired.parent = kf->parent;
  if (auto parent = keyframe(kf->parent)) {
    // R_kf R_parent^T, t_kf - R_kf_parent t_parent (not kf * parent.Inverse(), which rounds
    // differently).
    Rigid3d& kf_from_parent = retired.kf_from_parent;
    const Rigid3d& kf_from_world = kf->cam_from_world;
    const Rigid3d& parent_from_world = parent->cam_from_world;
    kf_from_parent.rotation = kf_from_world.rotation * parent_from_world.rotation.transpose();
    kf_from_parent.translation =
        kf_from_world.translation - kf_from_parent.rotation * parent_from_world.translation;
  }
  retired_[keyframe_id] = retired;
  for (int pid : kf->point_ids) {
    if (auto p = point(pid)) p->observations.erase(keyframe_id);
  }
  for (int lid : kf->line_ids) {
    if (auto l = line(lid)) l->observations.erase(keyframe_id);
  }
  // Every keyframe, not only kf's own neighbours: UpdateConnections rebuilds one side of an edge,
  // so another keyframe may still hold a link to kf that kf no longer lists.
  for (auto& [id, other] : keyframes_) {
    (void)id;
    other->covisibility.erase(keyframe_id);
    if (other->parent == keyframe_id) other->parent = kf->parent;
    // The IMU chain skips kf: its successor's interval starts where kf's did.
    if (other->inertial && other->inertial->previous == keyframe_id) {
      if (kf->inertial) {
        ImuBuffer joined = kf->inertial->samples_from_previous;
        joined.Append(other->inertial->samples_from_previous);
        other->inertial->samples_from_previous = std::move(joined);
        other->inertial->previous = kf->inertial->previous;
      } else {
        other->inertial->previous = -1;
      }
    }
  }
  keyframes_.erase(keyframe_id);
}

std::shared_ptr<KeyFrame> Map::keyframe(int id) const {
  auto it = keyframes_.find(id);
  return it == keyframes_.end() ? nullptr : it->second;
}

std::shared_ptr<MapPoint> Map::point(int id) const {
  auto it = points_.find(id);
  return it == points_.end() ? nullptr : it->second;
}

std::vector<MapPoint*> Map::PointsOf(const std::vector<int>& ascending_ids) const {
  std::vector<MapPoint*> out(ascending_ids.size(), nullptr);
  auto it = points_.begin();
  constexpr int kSteps = 8;  // steps along the container before a search from the root
  for (size_t i = 0; i < ascending_ids.size(); ++i) {
    const int id = ascending_ids[i];
    Require(i == 0 || ascending_ids[i - 1] <= id, "PointsOf needs ascending ids");
    int steps = 0;
    while (it != points_.end() && it->first < id && steps < kSteps) {
      ++it;
      ++steps;
    }
    if (it != points_.end() && it->first < id) it = points_.lower_bound(id);
    if (it != points_.end() && it->first == id) out[i] = it->second.get();
  }
  return out;
}

std::shared_ptr<MapLine> Map::line(int id) const {
  auto it = lines_.find(id);
  return it == lines_.end() ? nullptr : it->second;
}

std::vector<int> Map::BestCovisible(int id, int n) const {
  auto kf = keyframe(id);
  if (!kf) return {};
  std::vector<std::pair<int, int>> ranked;
  for (const auto& [other, count] : kf->covisibility) ranked.emplace_back(count, other);
  std::sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) {
    return a.first > b.first || (a.first == b.first && a.second < b.second);
  });
  std::vector<int> out;
  for (const auto& [count, other] : ranked) {
    (void)count;
    if (static_cast<int>(out.size()) >= n) break;
    out.push_back(other);
  }
  return out;
}

bool Map::KeyFramePose(int id, Rigid3d* cam_from_world) const {
  // T_id_w = T_id_p1 * T_p1_p2 * ... * T_pn_w along retired parents until a live keyframe.
  Rigid3d cam_from_kf;  // the culled keyframe `id` from the keyframe reached so far
  for (size_t hops = 0; hops <= retired_.size(); ++hops) {
    if (auto kf = keyframe(id)) {
      *cam_from_world = cam_from_kf * kf->cam_from_world;
      return true;
    }
    auto it = retired_.find(id);
    if (it == retired_.end()) return false;
    cam_from_kf = cam_from_kf * it->second.kf_from_parent;
    id = it->second.parent;
  }
  return false;  // a cycle: cannot happen with parents older than children
}

void Map::RestoreKeyFrame(std::shared_ptr<KeyFrame> keyframe) {
  Require(keyframe != nullptr && keyframe->id >= 0, "a restored keyframe needs an id");
  SLSLAM_CHECK(!keyframes_.count(keyframe->id), "keyframe id ", keyframe->id, " is in use");
  ids_->next_keyframe = std::max(ids_->next_keyframe, keyframe->id + 1);
  keyframes_[keyframe->id] = std::move(keyframe);
}

void Map::RestorePoint(std::shared_ptr<MapPoint> point) {
  Require(point != nullptr && point->id >= 0, "a restored map point needs an id");
  SLSLAM_CHECK(!points_.count(point->id), "map point id ", point->id, " is in use");
  ids_->next_point = std::max(ids_->next_point, point->id + 1);
  points_[point->id] = std::move(point);
}

void Map::RestoreLine(std::shared_ptr<MapLine> line) {
  Require(line != nullptr && line->id >= 0, "a restored map line needs an id");
  SLSLAM_CHECK(!lines_.count(line->id), "map line id ", line->id, " is in use");
  ids_->next_line = std::max(ids_->next_line, line->id + 1);
  lines_[line->id] = std::move(line);
}

void Map::RestoreRetired(int id, const RetiredKeyFrame& retired) {
  ids_->next_keyframe = std::max(ids_->next_keyframe, id + 1);
  retired_[id] = retired;
}

void Map::Absorb(Map* other) {
  Require(other != nullptr && other != this, "a map cannot absorb itself");
  for (auto& [id, kf] : other->keyframes_) RestoreKeyFrame(kf);
  for (auto& [id, p] : other->points_) RestorePoint(p);
  for (auto& [id, l] : other->lines_) RestoreLine(l);
  for (auto& [id, r] : other->retired_) RestoreRetired(id, r);
  other->keyframes_.clear();
  other->points_.clear();
  other->lines_.clear();
  other->retired_.clear();
  ++correction_epoch_;
  ++other->correction_epoch_;
}

}  // namespace slslam
