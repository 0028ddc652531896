// Tracker: map files (SaveMap, LoadMap), the per-frame records and anchors from which every frame's
// pose is read in the final map (Trajectory), and the map export.
#include "slslam/tracking/tracker.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "slslam/core/check.h"
#include "slslam/map/map_io.h"

namespace slslam {

namespace {

// The map header's vocabulary: "<file name>@<checksum, 16 hex digits>". The file name, not the
// path: the same vocabulary sits elsewhere on another machine; the checksum tells whether it is
// the same vocabulary (Vocabulary::Checksum).
std::string VocabularyIdentity(const std::string& path, const Vocabulary* vocabulary) {
  std::string name = std::filesystem::path(path).filename().string();
  if (vocabulary == nullptr || vocabulary->empty()) return name;
  char hex[17];
  std::snprintf(hex, sizeof(hex), "%016llx",
                static_cast<unsigned long long>(vocabulary->Checksum()));
  return name + "@" + hex;
}

// The checksum part of a header's vocabulary identity; empty when the file holds none (a file
// written before identities held checksums, or by a run without a vocabulary).
std::string ChecksumOf(const std::string& identity) {
  const size_t at = identity.rfind('@');
  return at == std::string::npos ? std::string() : identity.substr(at + 1);
}

}  // namespace

void Tracker::SaveMap(const std::string& path, const std::string& version) {
  Flush();
  MapFileHeader header;
  header.slslam_version = version;
  header.rig = options_.rig;
  header.vocabulary = VocabularyIdentity(options_.vocabulary_path, vocabulary_.get());
  header.line_descriptor = options_.line_descriptor;
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
  // Keyframes' bag-of-words vectors and relocalisation compare words of one vocabulary only.
  const std::string saved = ChecksumOf(loaded.header.vocabulary);
  const std::string current =
      ChecksumOf(VocabularyIdentity(options_.vocabulary_path, vocabulary_.get()));
  SLSLAM_CHECK(saved.empty() || saved == current, path, ": the map was made with the vocabulary ",
               loaded.header.vocabulary, " and this run loads another (",
               VocabularyIdentity(options_.vocabulary_path, vocabulary_.get()),
               "); its keyframes' words would not compare: give the run the map's vocabulary "
               "(tracking.vocabulary_path)");
  SLSLAM_CHECK(loaded.header.line_descriptor == options_.line_descriptor, path,
               ": the map's lines carry ", LineDescriptorName(loaded.header.line_descriptor),
               " descriptors and this run computes ", LineDescriptorName(options_.line_descriptor),
               " (tracking.line_descriptor); their bits do not compare");
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

void Tracker::RecordFrame(const StereoFrame& frame, bool keyframe) {
  FrameRecord r;
  r.index = frame.index;
  r.t_ns = frame.t_ns;
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
    f.t_ns = r.t_ns;
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
