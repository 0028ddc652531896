// Encoding and decoding of the map file's records (layout in map_io.h). Decoding checks only
// what it needs to stay within the buffer and allocate sensibly; the meaning of the values is
// checked by CheckMapContent (map_io_checks.cpp) on the decoded entries.
#include <cmath>
#include <cstring>
#include <limits>

#include "slslam/core/time.h"
#include "slslam/map/map_io_records.h"

namespace slslam::map_io_detail {

namespace {

static_assert(sizeof(int) == 4, "the map file stores int as int32");
static_assert(std::numeric_limits<double>::is_iec559 && std::numeric_limits<float>::is_iec559,
              "the map file stores IEEE-754 floats");

void WriteMatrix3(const Eigen::Matrix3d& m, ByteWriter* out) {
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out->F64(m(r, c));
  }
}

void WriteVector3(const Eigen::Vector3d& v, ByteWriter* out) {
  for (int i = 0; i < 3; ++i) out->F64(v[i]);
}

Eigen::Matrix3d ReadMatrix3(ByteReader* in, const char* what) {
  Eigen::Matrix3d m;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m(r, c) = in->F64(what);
  }
  return m;
}

Eigen::Vector3d ReadVector3(ByteReader* in, const char* what) {
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) v[i] = in->F64(what);
  return v;
}

void WriteMat(const cv::Mat& mat, ByteWriter* out) {
  Require(mat.dims <= 2, "map file: matrices must be two-dimensional");
  out->I32(mat.type());
  out->I32(mat.rows);
  out->I32(mat.cols);
  const size_t per_row = static_cast<size_t>(mat.cols) * mat.channels();
  for (int r = 0; r < mat.rows; ++r) out->Elements(mat.ptr(r), per_row, mat.elemSize1());
}

cv::Mat ReadMat(ByteReader* in, const char* what) {
  const int type = in->I32(what);
  const int rows = in->I32(what);
  const int cols = in->I32(what);
  const int depth = CV_MAT_DEPTH(type);
  const int channels = CV_MAT_CN(type);
  if (type < 0 || type != CV_MAKETYPE(depth, channels) || depth > kMaxMatDepth ||
      channels > kMaxMatChannels) {
    in->Fail(Message(what, ": unsupported matrix type ", type));
  }
  if (rows < 0 || cols < 0) in->Fail(Message(what, ": negative size ", rows, " x ", cols));
  // Checked against the bytes left before the matrix is allocated.
  const size_t element_bytes = CV_ELEM_SIZE1(type);
  const uint64_t elements = static_cast<uint64_t>(rows) * static_cast<uint64_t>(cols);
  if (elements > in->remaining() / (element_bytes * channels)) {
    in->Fail(Message("truncated: ", what, " of ", rows, " x ", cols, " x ", channels, " x ",
                     element_bytes, " bytes, ", in->remaining(), " left"));
  }
  cv::Mat mat(rows, cols, type);
  const size_t per_row = static_cast<size_t>(cols) * channels;
  for (int r = 0; r < rows; ++r) in->Elements(mat.ptr(r), per_row, element_bytes, what);
  return mat;
}

// Fails unless keys arrive in strictly ascending order, as a std::map writes them: a repeated
// key would otherwise be merged silently.
template <typename Key>
void CheckAscending(ByteReader* in, bool first, Key previous, Key key, const char* what) {
  if (!first && !(key > previous)) {
    in->Fail(Message(what, ": key ", key, " follows ", previous, " (keys must ascend)"));
  }
}

template <typename T>
void WriteCount(const T& container, ByteWriter* out) {
  out->U32(static_cast<uint32_t>(container.size()));
}

void WriteObservations(const std::map<int, int>& observations, ByteWriter* out) {
  WriteCount(observations, out);
  for (const auto& [keyframe, index] : observations) {
    out->I32(keyframe);
    out->I32(index);
  }
}

std::map<int, int> ReadIntPairs(ByteReader* in, const char* what) {
  const uint32_t n = in->Count(8, what);
  std::map<int, int> pairs;
  int previous = 0;
  for (uint32_t i = 0; i < n; ++i) {
    const int key = in->I32(what);
    CheckAscending(in, i == 0, previous, key, what);
    pairs.emplace_hint(pairs.end(), key, in->I32(what));
    previous = key;
  }
  return pairs;
}

void WriteInts(const std::vector<int>& values, ByteWriter* out) {
  WriteCount(values, out);
  out->Elements(values.data(), values.size(), 4);
}

std::vector<int> ReadInts(ByteReader* in, const char* what) {
  std::vector<int> values(in->Count(4, what));
  in->Elements(values.data(), values.size(), 4, what);
  return values;
}

void WriteDoubles(const std::vector<double>& values, ByteWriter* out) {
  WriteCount(values, out);
  out->Elements(values.data(), values.size(), 8);
}

std::vector<double> ReadDoubles(ByteReader* in, const char* what) {
  std::vector<double> values(in->Count(8, what));
  in->Elements(values.data(), values.size(), 8, what);
  return values;
}

void WriteKeypoints(const Keypoints& k, ByteWriter* out) {
  out->U32(static_cast<uint32_t>(k.uv.rows()));
  out->Elements(k.uv.data(), static_cast<size_t>(k.uv.size()), 4);
  out->U32(static_cast<uint32_t>(k.score.size()));
  out->Elements(k.score.data(), static_cast<size_t>(k.score.size()), 4);
  out->U32(static_cast<uint32_t>(k.octave.size()));
  out->Elements(k.octave.data(), static_cast<size_t>(k.octave.size()), 4);
  WriteMat(k.descriptors, out);
}

Keypoints ReadKeypoints(ByteReader* in) {
  Keypoints k;
  k.uv.resize(in->Count(8, "keypoint positions"), 2);
  in->Elements(k.uv.data(), static_cast<size_t>(k.uv.size()), 4, "keypoint positions");
  k.score.resize(in->Count(4, "keypoint scores"));
  in->Elements(k.score.data(), static_cast<size_t>(k.score.size()), 4, "keypoint scores");
  k.octave.resize(in->Count(4, "keypoint octaves"));
  in->Elements(k.octave.data(), static_cast<size_t>(k.octave.size()), 4, "keypoint octaves");
  k.descriptors = ReadMat(in, "keypoint descriptors");
  return k;
}

void WriteFrame(const StereoFrame& f, ByteWriter* out) {
  out->I32(f.index);
  out->I64(f.t_ns);
  WriteKeypoints(f.keypoints, out);
  WriteDoubles(f.u_right, out);
  WriteDoubles(f.depth, out);
  WriteCount(f.lines, out);
  for (const LineSegment& s : f.lines) {
    out->F32(s.start.x());
    out->F32(s.start.y());
    out->F32(s.end.x());
    out->F32(s.end.y());
  }
  WriteMat(f.line_descriptors, out);
  WriteCount(f.line_endpoints, out);
  for (const auto& ends : f.line_endpoints) {
    WriteVector3(ends[0], out);
    WriteVector3(ends[1], out);
  }
  WriteCount(f.line_has_depth, out);
  for (const bool has : f.line_has_depth) out->U8(has ? 1 : 0);
}

std::shared_ptr<StereoFrame> ReadFrame(ByteReader* in, uint32_t version, const Where& where,
                                       int keyframe) {
  auto f = std::make_shared<StereoFrame>();
  f->index = in->I32("frame index");
  if (version >= 3) {
    f->t_ns = in->I64("frame time");
  } else {  // float seconds, rounded to the nanosecond
    const double t_s = in->F64("frame timestamp");
    if (!(std::abs(t_s) <= kMaxTimestampS)) {
      where.Fail("keyframe ", keyframe, ": frame timestamp ", t_s, " s is not finite or beyond ",
                 kMaxTimestampS, " s (int64 nanoseconds)");
    }
    f->t_ns = NsFromSeconds(t_s);
  }
  f->keypoints = ReadKeypoints(in);
  f->u_right = ReadDoubles(in, "right columns");
  f->depth = ReadDoubles(in, "depths");
  f->lines.resize(in->Count(16, "segments"));
  for (LineSegment& s : f->lines) {
    s.start.x() = in->F32("segment");
    s.start.y() = in->F32("segment");
    s.end.x() = in->F32("segment");
    s.end.y() = in->F32("segment");
  }
  f->line_descriptors = ReadMat(in, "line descriptors");
  f->line_endpoints.resize(in->Count(48, "line endpoints"));
  for (auto& ends : f->line_endpoints) {
    ends[0] = ReadVector3(in, "line endpoint");
    ends[1] = ReadVector3(in, "line endpoint");
  }
  f->line_has_depth.resize(in->Count(1, "line depth flags"));
  for (size_t i = 0; i < f->line_has_depth.size(); ++i) {
    f->line_has_depth[i] = in->U8("line depth flag") != 0;
  }
  return f;
}

}  // namespace

void WriteKeyFrame(const KeyFrame& kf, ByteWriter* out) {
  out->I32(kf.id);
  WriteMatrix3(kf.cam_from_world.rotation, out);
  WriteVector3(kf.cam_from_world.translation, out);
  out->I32(kf.parent);
  out->U8(kf.bad ? 1 : 0);
  WriteObservations(kf.covisibility, out);
  WriteInts(kf.point_ids, out);
  WriteInts(kf.line_ids, out);
  WriteCount(kf.bow, out);
  for (const auto& [word, weight] : kf.bow) {
    out->U32(word);
    out->F64(weight);
  }
  WriteCount(kf.bow_features, out);
  for (const auto& [node, keypoints] : kf.bow_features) {
    out->U32(node);
    WriteInts(keypoints, out);
  }
  Require(kf.frame != nullptr, "map file: a keyframe without its frame");
  WriteFrame(*kf.frame, out);
}

std::shared_ptr<KeyFrame> ReadKeyFrame(ByteReader* in, uint32_t version, const Where& where) {
  auto kf = std::make_shared<KeyFrame>();
  kf->id = in->I32("keyframe id");
  kf->cam_from_world.rotation = ReadMatrix3(in, "keyframe rotation");
  kf->cam_from_world.translation = ReadVector3(in, "keyframe translation");
  kf->parent = in->I32("keyframe parent");
  kf->bad = in->U8("keyframe flag") != 0;
  kf->covisibility = ReadIntPairs(in, "covisibility");
  kf->point_ids = ReadInts(in, "keyframe point ids");
  kf->line_ids = ReadInts(in, "keyframe line ids");
  const uint32_t words = in->Count(12, "bag-of-words entries");
  for (uint32_t i = 0; i < words; ++i) {
    const WordId word = in->U32("bag-of-words entry");
    CheckAscending(in, i == 0, kf->bow.empty() ? 0u : kf->bow.rbegin()->first, word,
                   "bag of words");
    kf->bow.emplace_hint(kf->bow.end(), word, in->F64("bag-of-words entry"));
  }
  const uint32_t nodes = in->Count(8, "direct-index nodes");
  for (uint32_t i = 0; i < nodes; ++i) {
    const NodeId node = in->U32("direct-index node");
    CheckAscending(in, i == 0, kf->bow_features.empty() ? 0u : kf->bow_features.rbegin()->first,
                   node, "direct index");
    kf->bow_features.emplace_hint(kf->bow_features.end(), node,
                                  ReadInts(in, "direct-index keypoints"));
  }
  kf->frame = ReadFrame(in, version, where, kf->id);
  return kf;
}

void WriteRetired(int id, const RetiredKeyFrame& retired, ByteWriter* out) {
  out->I32(id);
  out->I32(retired.parent);
  WriteMatrix3(retired.kf_from_parent.rotation, out);
  WriteVector3(retired.kf_from_parent.translation, out);
}

std::pair<int, RetiredKeyFrame> ReadRetired(ByteReader* in) {
  const int id = in->I32("culled keyframe id");
  RetiredKeyFrame retired;
  retired.parent = in->I32("culled keyframe parent");
  retired.kf_from_parent.rotation = ReadMatrix3(in, "culled keyframe rotation");
  retired.kf_from_parent.translation = ReadVector3(in, "culled keyframe translation");
  return {id, retired};
}

void WritePoint(const MapPoint& p, ByteWriter* out) {
  out->I32(p.id);
  WriteVector3(p.position, out);
  WriteMat(p.descriptor, out);
  WriteObservations(p.observations, out);
  out->I32(p.visible);
  out->I32(p.found);
  out->I32(p.first_keyframe);
  out->U8(p.bad ? 1 : 0);
}

std::shared_ptr<MapPoint> ReadPoint(ByteReader* in) {
  auto p = std::make_shared<MapPoint>();
  p->id = in->I32("point id");
  p->position = ReadVector3(in, "point position");
  p->descriptor = ReadMat(in, "point descriptor");
  p->observations = ReadIntPairs(in, "point observations");
  p->visible = in->I32("point counters");
  p->found = in->I32("point counters");
  p->first_keyframe = in->I32("point first keyframe");
  p->bad = in->U8("point flag") != 0;
  return p;
}

void WriteLine(const MapLine& l, ByteWriter* out) {
  out->I32(l.id);
  WriteVector3(l.line.n, out);
  WriteVector3(l.line.v, out);
  WriteVector3(l.start, out);
  WriteVector3(l.end, out);
  WriteMat(l.descriptor, out);
  WriteObservations(l.observations, out);
  out->I32(l.visible);
  out->I32(l.found);
  out->I32(l.first_keyframe);
  out->U8(l.bad ? 1 : 0);
}

std::shared_ptr<MapLine> ReadLine(ByteReader* in) {
  auto l = std::make_shared<MapLine>();
  l->id = in->I32("line id");
  l->line.n = ReadVector3(in, "line moment");
  l->line.v = ReadVector3(in, "line direction");
  l->start = ReadVector3(in, "line endpoints");
  l->end = ReadVector3(in, "line endpoints");
  l->descriptor = ReadMat(in, "line descriptor");
  l->observations = ReadIntPairs(in, "line observations");
  l->visible = in->I32("line counters");
  l->found = in->I32("line counters");
  l->first_keyframe = in->I32("line first keyframe");
  l->bad = in->U8("line flag") != 0;
  return l;
}

}  // namespace slslam::map_io_detail
