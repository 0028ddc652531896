// The checks every map passes before it is written or built (list in map_io.h). Each names the
// map, the entry and the value; messages are built only when a check fails.
#include <cmath>
#include <stdexcept>
#include <type_traits>

#include "slslam/map/map_io_records.h"

namespace slslam::map_io_detail {

namespace {

constexpr int kMaxDescriptorCols = 1 << 16;  // far beyond any descriptor
constexpr int kMaxOctave = 64;               // pyramid levels [-]
// |R^T R - I| (largest entry) a stored rotation may show: poses come from Eigen rotations and
// products of them, orthonormal to ~1e-15; anything near this bound is a damaged file.
constexpr double kRotationTolerance = 1e-6;

bool Finite(const Eigen::Vector3d& v) { return v.allFinite(); }
// Finite and within kMaxCoordinateM of the origin in every coordinate.
bool Plausible(const Eigen::Vector3d& v) {
  return v.allFinite() && v.cwiseAbs().maxCoeff() <= kMaxCoordinateM;
}

bool IsRotation(const Eigen::Matrix3d& R) {
  if (!R.allFinite()) return false;
  const double error = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  return error <= kRotationTolerance && R.determinant() > 0.0;
}

template <typename Container>
bool AllFinite(const Container& values) {
  for (const auto v : values) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}

// A matrix the file can hold (see ReadMat).
void CheckMatrix(const cv::Mat& d, const Where& where, const char* entry, int id) {
  if (d.dims > 2 || d.depth() > kMaxMatDepth || d.channels() > kMaxMatChannels) {
    where.Fail(entry, " ", id, ": descriptor matrix of type ", d.type(), " with ", d.dims,
               " dimensions (at most 2, depth CV_8U..CV_16F, 4 channels)");
  }
}

// Keypoint descriptors (or a map point's) of the header's type; any type when it names none.
void CheckDescriptorType(const cv::Mat& d, const MapFileHeader& header, const Where& where,
                         const char* entry, int id) {
  CheckMatrix(d, where, entry, id);
  if (header.descriptor_type < 0 || d.empty()) return;
  if (d.type() != header.descriptor_type || d.cols != header.descriptor_cols) {
    where.Fail(entry, " ", id, ": descriptor of type ", d.type(), " with ", d.cols,
               " columns, the file's header says type ", header.descriptor_type, " with ",
               header.descriptor_cols);
  }
}

void CheckFrame(const StereoFrame& f, const MapFileHeader& header, const Where& where, int kf) {
  const int n = f.NumKeypoints();
  const Keypoints& k = f.keypoints;
  if (f.index < 0) where.Fail("keyframe ", kf, ": frame index ", f.index, " is negative");
  if (!k.uv.allFinite() ||
      (k.uv.size() > 0 && k.uv.cwiseAbs().maxCoeff() > kMaxImageCoordinatePx)) {
    where.Fail("keyframe ", kf, ": a keypoint position is not finite or beyond ",
               kMaxImageCoordinatePx, " px");
  }
  if ((k.score.size() != n && k.score.size() != 0) || !k.score.allFinite()) {
    where.Fail("keyframe ", kf, ": ", k.score.size(), " keypoint scores (finite) for ", n,
               " keypoints");
  }
  if (k.octave.size() != n && k.octave.size() != 0) {
    where.Fail("keyframe ", kf, ": ", k.octave.size(), " keypoint octaves for ", n, " keypoints");
  }
  for (int i = 0; i < k.octave.size(); ++i) {
    if (k.octave[i] < 0 || k.octave[i] >= kMaxOctave) {
      where.Fail("keyframe ", kf, ": keypoint ", i, " has octave ", k.octave[i]);
    }
  }
  if (n > 0 && k.descriptors.rows != n) {
    where.Fail("keyframe ", kf, ": ", k.descriptors.rows, " descriptor rows for ", n, " keypoints");
  }
  CheckDescriptorType(k.descriptors, header, where, "keyframe", kf);
  if (static_cast<int>(f.u_right.size()) != n || static_cast<int>(f.depth.size()) != n) {
    where.Fail("keyframe ", kf, ": ", f.u_right.size(), " right columns and ", f.depth.size(),
               " depths for ", n, " keypoints");
  }
  if (!AllFinite(f.u_right) || !AllFinite(f.depth)) {
    where.Fail("keyframe ", kf, ": a right column or depth is not finite");
  }
  for (const double d : f.depth) {
    // a stereo depth [m], or -1 for a keypoint without one
    if (!(d == -1.0 || (d > 0.0 && d <= kMaxCoordinateM))) {
      where.Fail("keyframe ", kf, ": depth ", d, " m is neither -1 (none) nor in (0, ",
                 kMaxCoordinateM, "]");
    }
  }
  const size_t m = f.lines.size();
  for (const LineSegment& s : f.lines) {
    if (!s.start.allFinite() || !s.end.allFinite()) {
      where.Fail("keyframe ", kf, ": a segment endpoint is not finite");
    }
  }
  CheckMatrix(f.line_descriptors, where, "keyframe", kf);
  if (static_cast<size_t>(f.line_descriptors.rows) != m || f.line_endpoints.size() != m ||
      f.line_has_depth.size() != m) {
    where.Fail("keyframe ", kf, ": ", f.line_descriptors.rows, " line descriptors, ",
               f.line_endpoints.size(), " endpoint pairs and ", f.line_has_depth.size(),
               " depth flags for ", m, " segments");
  }
  for (const auto& ends : f.line_endpoints) {
    if (!Plausible(ends[0]) || !Plausible(ends[1])) {
      where.Fail("keyframe ", kf, ": a stereo line endpoint is not finite or beyond ",
                 kMaxCoordinateM, " m");
    }
  }
}

void CheckKeyFrame(const KeyFrame& kf, const MapContent& c, const MapFileHeader& header,
                   const Where& where) {
  const int id = kf.id;
  if (!IsRotation(kf.cam_from_world.rotation) || !Plausible(kf.cam_from_world.translation)) {
    where.Fail("keyframe ", id, ": pose is not finite, beyond ", kMaxCoordinateM,
               " m, or its rotation is not orthonormal");
  }
  if (kf.frame == nullptr) where.Fail("keyframe ", id, ": no frame");
  CheckFrame(*kf.frame, header, where, id);
  if (kf.parent != -1 &&
      (kf.parent == id || (!c.keyframes.count(kf.parent) && !c.retired.count(kf.parent)))) {
    where.Fail("keyframe ", id, ": parent ", kf.parent, " is not another keyframe of the map");
  }
  for (const auto& [other, shared] : kf.covisibility) {
    if (other == id || !c.keyframes.count(other) || shared < 0) {
      where.Fail("keyframe ", id, ": covisibility link to ", other, " (", shared,
                 " shared points) is not to another keyframe of the map");
    }
  }
  const int n = kf.frame->NumKeypoints();
  const int m = kf.frame->NumLines();
  if (static_cast<int>(kf.point_ids.size()) != n || static_cast<int>(kf.line_ids.size()) != m) {
    where.Fail("keyframe ", id, ": ", kf.point_ids.size(), " point ids and ", kf.line_ids.size(),
               " line ids for ", n, " keypoints and ", m, " segments");
  }
  for (const int p : kf.point_ids) {
    if (p != -1 && !c.points.count(p)) where.Fail("keyframe ", id, ": unknown point id ", p);
  }
  for (const int l : kf.line_ids) {
    if (l != -1 && !c.lines.count(l)) where.Fail("keyframe ", id, ": unknown line id ", l);
  }
  for (const auto& [word, weight] : kf.bow) {
    // an L1-normalised bag of words: each weight in [0, 1]
    if (!(weight >= 0.0 && weight <= 1.0 + 1e-9)) {
      where.Fail("keyframe ", id, ": word ", word, " has weight ", weight,
                 " (an L1-normalised bag of words holds weights in [0, 1])");
    }
  }
  for (const auto& [node, keypoints] : kf.bow_features) {
    for (const int i : keypoints) {
      if (i < 0 || i >= n) {
        where.Fail("keyframe ", id, ": direct index node ", node, " holds keypoint ", i, " of ", n);
      }
    }
  }
}

void CheckRetired(int id, const RetiredKeyFrame& r, const MapContent& c, const Where& where) {
  if (c.keyframes.count(id)) where.Fail("culled keyframe id ", id, " is also a live keyframe");
  if (r.parent != -1 &&
      (r.parent == id || (!c.keyframes.count(r.parent) && !c.retired.count(r.parent)))) {
    where.Fail("culled keyframe ", id, ": parent ", r.parent, " is not a keyframe of the map");
  }
  if (!IsRotation(r.kf_from_parent.rotation) || !Plausible(r.kf_from_parent.translation)) {
    where.Fail("culled keyframe ", id, ": relative pose is not finite or not a rotation");
  }
}

// Observations, counters and first keyframe, shared by points and lines. `count` gives the
// number of keypoints (points) or segments (lines) of a keyframe's frame.
template <typename Landmark, typename Count>
void CheckLandmarkCommon(const Landmark& l, const MapContent& c, const MapIds& ids,
                         const Where& where, const char* entry, Count count) {
  for (const auto& [kf, index] : l.observations) {
    const auto it = c.keyframes.find(kf);
    if (it == c.keyframes.end()) {
      where.Fail(entry, " ", l.id, ": observed in ", kf, ", not a keyframe of the map");
    }
    if (index < 0 || index >= count(*it->second->frame)) {
      where.Fail(entry, " ", l.id, ": observed as feature ", index, " of keyframe ", kf,
                 ", which has ", count(*it->second->frame));
    }
  }
  if (l.visible < 0 || l.found < 0) {
    where.Fail(entry, " ", l.id, ": negative counters (visible ", l.visible, ", found ", l.found,
               ")");
  }
  if (l.first_keyframe < -1 || l.first_keyframe >= ids.next_keyframe) {
    where.Fail(entry, " ", l.id, ": first keyframe ", l.first_keyframe, " is outside [-1, ",
               ids.next_keyframe, ")");
  }
  if (l.descriptor.rows > 1) {
    where.Fail(entry, " ", l.id, ": descriptor has ", l.descriptor.rows, " rows (at most 1)");
  }
}

void CheckPoint(const MapPoint& p, const MapContent& c, const MapFileHeader& header,
                const MapIds& ids, const Where& where) {
  if (!Plausible(p.position)) {
    where.Fail("point ", p.id, ": position is not finite or beyond ", kMaxCoordinateM, " m");
  }
  CheckDescriptorType(p.descriptor, header, where, "point", p.id);
  CheckLandmarkCommon(p, c, ids, where, "point",
                      [](const StereoFrame& f) { return f.NumKeypoints(); });
}

void CheckLine(const MapLine& l, const MapContent& c, const MapIds& ids, const Where& where) {
  if (!Finite(l.line.n) || !Finite(l.line.v) || l.line.v.norm() == 0.0 || !Plausible(l.start) ||
      !Plausible(l.end)) {
    where.Fail("line ", l.id, ": not finite, endpoints beyond ", kMaxCoordinateM,
               " m, or no direction");
  }
  CheckMatrix(l.descriptor, where, "line", l.id);
  CheckLandmarkCommon(l, c, ids, where, "line", [](const StereoFrame& f) { return f.NumLines(); });
}

}  // namespace

void CheckHeader(const MapFileHeader& header, const Where& where) {
  try {
    header.rig.Check();
  } catch (const std::invalid_argument& e) {
    where.Fail("stereo rig: ", e.what());
  }
  if (header.descriptor_type != -1 && header.descriptor_type != CV_8U &&
      header.descriptor_type != CV_32F) {
    where.Fail("descriptor type ", header.descriptor_type, " (CV_8U ", CV_8U, ", CV_32F ", CV_32F,
               " or -1 for none)");
  }
  if (header.descriptor_type != -1 &&
      (header.descriptor_cols <= 0 || header.descriptor_cols > kMaxDescriptorCols)) {
    where.Fail("descriptor width ", header.descriptor_cols, " is outside [1, ", kMaxDescriptorCols,
               "]");
  }
  if (header.slslam_version.size() > kMaxVersionBytes ||
      header.vocabulary.size() > kMaxVocabularyBytes) {
    where.Fail("version string or vocabulary name too long (", kMaxVersionBytes, " / ",
               kMaxVocabularyBytes, " bytes at most)");
  }
}

void CheckMapContent(const MapContent& c, const MapFileHeader& header, const MapIds& ids,
                     const Where& where) {
  // Ids first: the entries' own ids below the counters, and each entry filed under its id.
  auto check_ids = [&where](const auto& entries, int next, const char* what) {
    for (const auto& [id, entry] : entries) {
      if (id < 0 || id >= next) where.Fail(what, " id ", id, " is outside [0, ", next, ")");
      if constexpr (!std::is_same_v<std::decay_t<decltype(entry)>, RetiredKeyFrame>) {
        if (entry == nullptr || entry->id != id) where.Fail(what, " ", id, ": holds another id");
      }
    }
  };
  check_ids(c.keyframes, ids.next_keyframe, "keyframe");
  check_ids(c.retired, ids.next_keyframe, "culled keyframe");
  check_ids(c.points, ids.next_point, "point");
  check_ids(c.lines, ids.next_line, "line");
  for (const auto& [id, kf] : c.keyframes) CheckKeyFrame(*kf, c, header, where);
  for (const auto& [id, retired] : c.retired) CheckRetired(id, retired, c, where);
  for (const auto& [id, p] : c.points) CheckPoint(*p, c, header, ids, where);
  for (const auto& [id, l] : c.lines) CheckLine(*l, c, ids, where);
}

}  // namespace slslam::map_io_detail
