// Map files: a small but complete atlas (keyframes with their frames, culled keyframes, points,
// lines, covisibility, spanning tree, bags of words) written and read back identical, and every
// kind of damaged or foreign file refused with a message naming it, never a crash.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "slslam/core/byte_io.h"
#include "slslam/core/check.h"
#include "slslam/core/time.h"
#include "slslam/map/map_io.h"

namespace slslam {
namespace {

constexpr size_t kPreambleBytes = 28;  // magic, version, payload size, checksum
constexpr size_t kChecksumOffset = 20;

MapFileHeader Header() {
  MapFileHeader h;
  h.slslam_version = "0.1.0";
  h.descriptor_type = CV_8U;
  h.descriptor_cols = 32;
  h.vocabulary = "orb_vocabulary.slvoc";
  h.rig.camera = {458.0, 457.5, 367.2, 248.4, 752, 480};
  h.rig.baseline_m = 0.11;
  return h;
}

cv::Mat RandomBytes(std::mt19937& rng, int rows, int cols) {
  cv::Mat m(rows, cols, CV_8U);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) m.at<uint8_t>(r, c) = static_cast<uint8_t>(rng());
  }
  return m;
}

// A frame with every field set: n keypoints (some without a stereo match), m segments (some
// without stereo depth).
std::shared_ptr<StereoFrame> MakeFrame(std::mt19937& rng, int index, int n, int m) {
  std::uniform_real_distribution<float> pixel(0.0f, 700.0f);
  std::uniform_real_distribution<double> depth(0.5, 30.0);
  auto f = std::make_shared<StereoFrame>();
  f->index = index;
  f->t_ns = 1'403'715'273'000'000'000 + 250'000'000 * int64_t{index};  // (exact in f64 seconds)
  f->keypoints.uv.resize(n, 2);
  f->keypoints.score.resize(n);
  f->keypoints.octave.resize(n);
  for (int i = 0; i < n; ++i) {
    f->keypoints.uv(i, 0) = pixel(rng);
    f->keypoints.uv(i, 1) = pixel(rng) * 0.6f;
    f->keypoints.score[i] = pixel(rng) / 7.0f;
    f->keypoints.octave[i] = static_cast<int>(rng() % 8);
    const bool stereo = i % 3 != 0;
    f->u_right.push_back(stereo ? f->keypoints.uv(i, 0) - 12.5 : -1.0);
    f->depth.push_back(stereo ? depth(rng) : -1.0);
  }
  f->keypoints.descriptors = RandomBytes(rng, n, 32);
  for (int j = 0; j < m; ++j) {
    LineSegment s;
    s.start = {pixel(rng), pixel(rng) * 0.6f};
    s.end = {pixel(rng), pixel(rng) * 0.6f};
    f->lines.push_back(s);
    f->line_endpoints.push_back({Eigen::Vector3d(0.1 * j, -1.6, depth(rng)),
                                 Eigen::Vector3d(0.1 * j + 1.0, -1.6, depth(rng))});
    f->line_has_depth.push_back(j % 2 == 0);
  }
  f->line_descriptors = RandomBytes(rng, m, 32);
  return f;
}

Eigen::Matrix3d Rotation(double yaw, double pitch) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

// Fills `map` through its public API as tracking and local mapping do: `keyframes` keyframes
// along a corridor, points and lines observed by several of them, covisibility and spanning tree
// from UpdateConnections, bags of words, then a point, a line and a keyframe erased (ids with
// gaps, a culled-keyframe record).
void FillMap(Map* map, unsigned seed, int keyframes) {
  std::mt19937 rng(seed);
  MutexLock lock(map->mutex());
  const int n = 12;
  const int m = 5;
  std::vector<int> kf_ids;
  for (int k = 0; k < keyframes; ++k) {
    auto kf = map->AddKeyFrame(
        Rigid3d(Rotation(0.05 * k, -0.01 * k), Eigen::Vector3d(0.02 * k, 0.0, -0.4 * k)),
        MakeFrame(rng, 10 * k + 3, n, m));
    kf_ids.push_back(kf->id);
    for (int w = 0; w < 4; ++w) kf->bow[static_cast<WordId>(rng() % 1000)] = 0.25;
    kf->bow_features[7] = {0, 3, 5};
    kf->bow_features[12] = {1, 11};
  }
  for (int i = 0; i < 8; ++i) {
    const int first = kf_ids[i % keyframes];
    auto p = map->AddPoint(Eigen::Vector3d(0.3 * i, -1.1, 4.0 + i), RandomBytes(rng, 1, 32), first);
    p->visible = 10 + i;
    p->found = 4 + i;
    for (int k = 0; k < keyframes; ++k) map->AddPointObservation(p->id, kf_ids[k], (i + k) % n);
  }
  for (int j = 0; j < 3; ++j) {
    const Eigen::Vector3d a(-2.2, -1.6 + j, 3.0), b(-2.2, -1.6 + j, 9.0);
    auto l = map->AddLine(PluckerLine::FromPoints(a, b), a, b, RandomBytes(rng, 1, 32), kf_ids[0]);
    l->visible = 6;
    l->found = 5 - j;
    for (int k = 0; k < keyframes; k += 2) map->AddLineObservation(l->id, kf_ids[k], (j + k) % m);
  }
  for (int id : kf_ids) map->UpdateConnections(id);
  map->point(map->points().rbegin()->first)->bad = true;
  map->ErasePoint(map->points().begin()->first + 2);
  map->EraseLine(map->lines().begin()->first + 1);
  if (keyframes > 2) map->EraseKeyFrame(kf_ids[1]);
}

void ExpectSameMat(const cv::Mat& a, const cv::Mat& b, const std::string& what) {
  ASSERT_EQ(a.type(), b.type()) << what;
  ASSERT_EQ(a.rows, b.rows) << what;
  ASSERT_EQ(a.cols, b.cols) << what;
  for (int r = 0; r < a.rows; ++r) {
    EXPECT_EQ(0, std::memcmp(a.ptr(r), b.ptr(r), a.cols * a.elemSize())) << what << " row " << r;
  }
}

void ExpectSameFrame(const StereoFrame& a, const StereoFrame& b) {
  EXPECT_EQ(a.index, b.index);
  EXPECT_EQ(a.t_ns, b.t_ns);
  EXPECT_EQ(a.keypoints.uv, b.keypoints.uv);
  EXPECT_EQ(a.keypoints.score, b.keypoints.score);
  EXPECT_EQ(a.keypoints.octave, b.keypoints.octave);
  ExpectSameMat(a.keypoints.descriptors, b.keypoints.descriptors, "keypoint descriptors");
  EXPECT_EQ(a.u_right, b.u_right);
  EXPECT_EQ(a.depth, b.depth);
  ASSERT_EQ(a.lines.size(), b.lines.size());
  for (size_t j = 0; j < a.lines.size(); ++j) {
    EXPECT_EQ(a.lines[j].start, b.lines[j].start);
    EXPECT_EQ(a.lines[j].end, b.lines[j].end);
  }
  ExpectSameMat(a.line_descriptors, b.line_descriptors, "line descriptors");
  EXPECT_EQ(a.line_endpoints, b.line_endpoints);
  EXPECT_EQ(a.line_has_depth, b.line_has_depth);
}

// Every field of every entry, compared exactly (doubles bit for bit through ==).
void ExpectSameMap(const Map& a, const Map& b) {
  ASSERT_EQ(a.keyframes().size(), b.keyframes().size());
  for (const auto& [id, ka] : a.keyframes()) {
    SCOPED_TRACE("keyframe " + std::to_string(id));
    const auto kb = b.keyframe(id);
    ASSERT_NE(kb, nullptr);
    EXPECT_EQ(ka->id, kb->id);
    EXPECT_EQ(ka->cam_from_world.rotation, kb->cam_from_world.rotation);
    EXPECT_EQ(ka->cam_from_world.translation, kb->cam_from_world.translation);
    EXPECT_EQ(ka->point_ids, kb->point_ids);
    EXPECT_EQ(ka->line_ids, kb->line_ids);
    EXPECT_EQ(ka->covisibility, kb->covisibility);
    EXPECT_EQ(ka->parent, kb->parent);
    EXPECT_EQ(ka->bow, kb->bow);
    EXPECT_EQ(ka->bow_features, kb->bow_features);
    EXPECT_EQ(ka->bad, kb->bad);
    ExpectSameFrame(*ka->frame, *kb->frame);
  }
  ASSERT_EQ(a.retired().size(), b.retired().size());
  for (const auto& [id, ra] : a.retired()) {
    ASSERT_TRUE(b.retired().count(id)) << "culled keyframe " << id;
    const RetiredKeyFrame& rb = b.retired().at(id);
    EXPECT_EQ(ra.parent, rb.parent);
    EXPECT_EQ(ra.kf_from_parent.rotation, rb.kf_from_parent.rotation);
    EXPECT_EQ(ra.kf_from_parent.translation, rb.kf_from_parent.translation);
  }
  ASSERT_EQ(a.points().size(), b.points().size());
  for (const auto& [id, pa] : a.points()) {
    SCOPED_TRACE("point " + std::to_string(id));
    const auto pb = b.point(id);
    ASSERT_NE(pb, nullptr);
    EXPECT_EQ(pa->id, pb->id);
    EXPECT_EQ(pa->position, pb->position);
    ExpectSameMat(pa->descriptor, pb->descriptor, "point descriptor");
    EXPECT_EQ(pa->observations, pb->observations);
    EXPECT_EQ(pa->visible, pb->visible);
    EXPECT_EQ(pa->found, pb->found);
    EXPECT_EQ(pa->first_keyframe, pb->first_keyframe);
    EXPECT_EQ(pa->bad, pb->bad);
  }
  ASSERT_EQ(a.lines().size(), b.lines().size());
  for (const auto& [id, la] : a.lines()) {
    SCOPED_TRACE("line " + std::to_string(id));
    const auto lb = b.line(id);
    ASSERT_NE(lb, nullptr);
    EXPECT_EQ(la->id, lb->id);
    EXPECT_EQ(la->line.n, lb->line.n);
    EXPECT_EQ(la->line.v, lb->line.v);
    EXPECT_EQ(la->start, lb->start);
    EXPECT_EQ(la->end, lb->end);
    ExpectSameMat(la->descriptor, lb->descriptor, "line descriptor");
    EXPECT_EQ(la->observations, lb->observations);
    EXPECT_EQ(la->visible, lb->visible);
    EXPECT_EQ(la->found, lb->found);
    EXPECT_EQ(la->first_keyframe, lb->first_keyframe);
    EXPECT_EQ(la->bad, lb->bad);
  }
  EXPECT_EQ(a.ids().next_keyframe, b.ids().next_keyframe);
  EXPECT_EQ(a.ids().next_point, b.ids().next_point);
  EXPECT_EQ(a.ids().next_line, b.ids().next_line);
}

class MapIo : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = std::filesystem::temp_directory_path() /
           (std::string("slslam_map_io_") + info->name() + "_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
    path_ = (dir_ / "atlas.slmap").string();
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  // Two maps of one atlas (shared ids), saved to path_; returns the file's bytes.
  std::vector<uint8_t> SaveAtlas() {
    ids_ = std::make_shared<MapIds>();
    first_ = std::make_unique<Map>(ids_);
    second_ = std::make_unique<Map>(ids_);
    FillMap(first_.get(), 1, 5);
    FillMap(second_.get(), 2, 3);
    SaveMaps(path_, {first_.get(), second_.get()}, Header());
    return ReadBytes(path_);
  }

  static std::vector<uint8_t> ReadBytes(const std::string& path) {
    std::ifstream file(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
  }
  std::string Write(const std::vector<uint8_t>& bytes, const std::string& name) const {
    const std::string path = (dir_ / name).string();
    std::ofstream file(path, std::ios::binary | std::ios::trunc);
    file.write(reinterpret_cast<const char*>(bytes.data()),
               static_cast<std::streamsize>(bytes.size()));
    return path;
  }

  std::filesystem::path dir_;
  std::string path_;
  std::shared_ptr<MapIds> ids_;
  std::unique_ptr<Map> first_, second_;
};

// Loading `path` throws std::invalid_argument naming the file and containing `expected`; so does
// reading its summary when `summary_too` (damage past the map table is invisible to it only when
// the checksum still matches).
void ExpectRefused(const std::string& path, const std::string& expected, bool summary_too = true) {
  try {
    LoadMaps(path);
    ADD_FAILURE() << "loaded " << path << " (expected: " << expected << ")";
  } catch (const std::invalid_argument& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind(path + ": ", 0), 0u) << message;
    EXPECT_NE(message.find(expected), std::string::npos) << message;
  }
  if (summary_too) {
    EXPECT_THROW(ReadMapFileSummary(path), std::invalid_argument) << path;
  }
}

// Recomputes the checksum after a deliberate edit, so the structural checks behind it are reached.
void Rechecksum(std::vector<uint8_t>* bytes) {
  const uint64_t sum = Fnv1a64(bytes->data() + kPreambleBytes, bytes->size() - kPreambleBytes);
  for (int i = 0; i < 8; ++i) (*bytes)[kChecksumOffset + i] = static_cast<uint8_t>(sum >> (8 * i));
}

void PutU32(std::vector<uint8_t>* bytes, size_t offset, uint32_t v) {
  for (int i = 0; i < 4; ++i) (*bytes)[offset + i] = static_cast<uint8_t>(v >> (8 * i));
}

void PutF64(std::vector<uint8_t>* bytes, size_t offset, double v) {
  uint64_t bits;
  std::memcpy(&bits, &v, 8);
  for (int i = 0; i < 8; ++i) bytes->at(offset + i) = static_cast<uint8_t>(bits >> (8 * i));
}

// Offsets of the fields the crafted-file tests edit, derived from Header() and the layout in
// map_io.h.
size_t MapCountOffset() {
  const MapFileHeader h = Header();
  return kPreambleBytes + 4 + h.slslam_version.size() + 4 + 4 + 4 + h.vocabulary.size() + 4 +
         LineDescriptorName(h.line_descriptor).size() + 4 * 8 + 2 * 4 + 8 + 3 * 4;
}
size_t FirstSectionOffset(int maps) { return MapCountOffset() + 4 + maps * 24; }

TEST_F(MapIo, RoundTripGivesIdenticalMaps) {
  SaveAtlas();
  const LoadedMaps loaded = LoadMaps(path_);
  EXPECT_EQ(loaded.header.slslam_version, "0.1.0");
  EXPECT_EQ(loaded.header.descriptor_type, CV_8U);
  EXPECT_EQ(loaded.header.descriptor_cols, 32);
  EXPECT_EQ(loaded.header.vocabulary, "orb_vocabulary.slvoc");
  EXPECT_EQ(loaded.header.line_descriptor, LineDescriptor::kOpenCvLbd);
  EXPECT_EQ(loaded.header.rig.camera.fx, 458.0);
  EXPECT_EQ(loaded.header.rig.camera.fy, 457.5);
  EXPECT_EQ(loaded.header.rig.camera.cx, 367.2);
  EXPECT_EQ(loaded.header.rig.camera.cy, 248.4);
  EXPECT_EQ(loaded.header.rig.camera.width, 752);
  EXPECT_EQ(loaded.header.rig.camera.height, 480);
  EXPECT_EQ(loaded.header.rig.baseline_m, 0.11);
  ASSERT_EQ(loaded.maps.size(), 2u);
  // The fixture is what it claims: gaps in the ids, a culled keyframe, links, a tree, a bad point.
  ASSERT_EQ(first_->keyframes().size(), 4u);
  ASSERT_EQ(first_->retired().size(), 1u);
  ASSERT_EQ(first_->points().size(), 7u);
  ASSERT_EQ(first_->lines().size(), 2u);
  EXPECT_FALSE(first_->keyframes().rbegin()->second->covisibility.empty());
  EXPECT_NE(first_->keyframes().rbegin()->second->parent, -1);
  EXPECT_EQ(second_->keyframes().begin()->first, 5);  // ids shared across the atlas
  ExpectSameMap(*first_, *loaded.maps[0]);
  ExpectSameMap(*second_, *loaded.maps[1]);
  // Both loaded maps count on one id source, past every id in the file.
  EXPECT_EQ(&loaded.maps[0]->ids(), &loaded.maps[1]->ids());
  MutexLock lock(loaded.maps[1]->mutex());
  const auto kf = loaded.maps[1]->AddKeyFrame(Rigid3d(), std::make_shared<StereoFrame>());
  EXPECT_EQ(kf->id, ids_->next_keyframe);
}

TEST_F(MapIo, SavedFileSavesAgainByteForByte) {
  const std::vector<uint8_t> bytes = SaveAtlas();
  LoadedMaps loaded = LoadMaps(path_);
  const std::string again = (dir_ / "again.slmap").string();
  SaveMaps(again, {loaded.maps[0].get(), loaded.maps[1].get()}, loaded.header);
  EXPECT_EQ(ReadBytes(again), bytes);
  EXPECT_FALSE(std::filesystem::exists(again + ".partial"));
}

TEST_F(MapIo, SummaryDescribesTheFile) {
  SaveAtlas();
  const MapFileSummary s = ReadMapFileSummary(path_);
  EXPECT_EQ(s.format_version, kMapFileFormatVersion);
  EXPECT_EQ(s.header.vocabulary, "orb_vocabulary.slvoc");
  EXPECT_EQ(s.next_ids.next_keyframe, 8);
  ASSERT_EQ(s.maps.size(), 2u);
  EXPECT_EQ(s.maps[0].keyframes, 4);
  EXPECT_EQ(s.maps[0].retired, 1);
  EXPECT_EQ(s.maps[0].points, 7);
  EXPECT_EQ(s.maps[0].lines, 2);
  EXPECT_EQ(s.maps[1].keyframes, 2);
}

TEST_F(MapIo, EmptyAtlasAndEmptyMapRoundTrip) {
  SaveMaps(path_, {}, Header());
  EXPECT_TRUE(LoadMaps(path_).maps.empty());
  Map empty;
  SaveMaps(path_, {&empty}, Header());
  const LoadedMaps loaded = LoadMaps(path_);
  ASSERT_EQ(loaded.maps.size(), 1u);
  ExpectSameMap(empty, *loaded.maps[0]);
}

TEST_F(MapIo, ReferencesToErasedEntriesAreWrittenAsNone) {
  Map map;
  FillMap(&map, 3, 4);
  {
    MutexLock lock(map.mutex());
    const auto kf = map.keyframes().begin()->second;
    const int erased_point = map.points().begin()->first + 2;  // erased by FillMap
    ASSERT_EQ(map.point(erased_point), nullptr);
    kf->point_ids[0] = erased_point;
    map.points().begin()->second->observations[1] = 0;  // keyframe 1 was culled
  }
  SaveMaps(path_, {&map}, Header());
  const LoadedMaps loaded = LoadMaps(path_);
  const Map& back = *loaded.maps[0];
  EXPECT_EQ(back.keyframes().begin()->second->point_ids[0], -1);
  EXPECT_EQ(back.points().begin()->second->observations.count(1), 0u);
}

TEST_F(MapIo, SaveRefusesWhatCouldNotBeLoaded) {
  Map map;
  FillMap(&map, 4, 3);
  const auto kf = map.keyframes().begin()->second;
  kf->cam_from_world.rotation(0, 0) = std::numeric_limits<double>::quiet_NaN();
  try {
    SaveMaps(path_, {&map}, Header());
    ADD_FAILURE() << "saved a keyframe with a NaN pose";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(path_ + ": not saved: map 0, keyframe 0: pose"),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(path_));
  kf->cam_from_world.rotation = Eigen::Matrix3d::Identity();
  MapFileHeader float_header = Header();
  float_header.descriptor_type = CV_32F;
  EXPECT_THROW(SaveMaps(path_, {&map}, float_header), std::invalid_argument);
  MapFileHeader no_rig = Header();
  no_rig.rig.baseline_m = 0.0;
  EXPECT_THROW(SaveMaps(path_, {&map}, no_rig), std::invalid_argument);
  Map other;  // its own counters: ids 0, 1, ... again, so the two maps share ids
  FillMap(&other, 5, 3);
  EXPECT_THROW(SaveMaps(path_, {&map, &other}, Header()), std::invalid_argument);
  EXPECT_THROW(SaveMaps(path_, {&map, nullptr}, Header()), std::invalid_argument);
  EXPECT_FALSE(std::filesystem::exists(path_));
  const std::string unwritable = (dir_ / "no_such_folder" / "atlas.slmap").string();
  try {
    SaveMaps(unwritable, {&map}, Header());
    ADD_FAILURE() << "saved into a missing folder";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()).rfind(unwritable + ": cannot open", 0), 0u) << e.what();
  }
}

TEST_F(MapIo, MissingForeignAndFolderPathsAreRefused) {
  ExpectRefused((dir_ / "missing.slmap").string(), "cannot open");
  ExpectRefused(dir_.string(), "is a folder");
  ExpectRefused(Write({}, "empty.slmap"), "not an slslam map file");
  const std::string ply = "ply\nformat binary_little_endian 1.0\nelement vertex 3\n";
  ExpectRefused(Write({ply.begin(), ply.end()}, "cloud.ply"), "not an slslam map file");
  ExpectRefused(Write({'S', 'L', 'S', 'V', 'O', 'C', 'A', 'B', 1, 0, 0, 0}, "vocab.slvoc"),
                "not an slslam map file");
}

TEST_F(MapIo, NewerAndZeroVersionsAreRefused) {
  std::vector<uint8_t> bytes = SaveAtlas();
  PutU32(&bytes, 8, kMapFileFormatVersion + 1);
  ExpectRefused(Write(bytes, "newer.slmap"), "is newer than this slslam reads");
  PutU32(&bytes, 8, 0);
  ExpectRefused(Write(bytes, "zero.slmap"), "format version 0");
}

// Defined with the layout helpers below.
void FrameTimesAsSeconds(const std::vector<const Map*>& maps, size_t map_count_offset,
                         std::vector<uint8_t>* bytes);

TEST_F(MapIo, VersionOneFilesReadAsOpenCvLineDescriptors) {
  // A version-3 file with f64 frame times and less its line descriptor name is the version-1
  // layout of the same maps; version 1 predates the name, and its lines carry OpenCV's LBD
  // whatever the name said.
  SaveAtlas();
  MapFileHeader h = Header();
  h.line_descriptor = LineDescriptor::kLbd;
  SaveMaps(path_, {first_.get(), second_.get()}, h);
  std::vector<uint8_t> bytes = ReadBytes(path_);
  EXPECT_EQ(LoadMaps(path_).header.line_descriptor, LineDescriptor::kLbd);
  FrameTimesAsSeconds({first_.get(), second_.get()},
                      MapCountOffset() - LineDescriptorName(LineDescriptor::kOpenCvLbd).size() +
                          LineDescriptorName(LineDescriptor::kLbd).size(),
                      &bytes);
  const size_t name =
      kPreambleBytes + 4 + h.slslam_version.size() + 4 + 4 + 4 + h.vocabulary.size();
  ASSERT_EQ(std::string(bytes.begin() + name + 4, bytes.begin() + name + 4 + 3), "lbd");
  bytes.erase(bytes.begin() + name, bytes.begin() + name + 4 + 3);
  PutU32(&bytes, 8, 1);
  const uint64_t payload = bytes.size() - kPreambleBytes;
  for (int i = 0; i < 8; ++i) bytes[12 + i] = static_cast<uint8_t>(payload >> (8 * i));
  Rechecksum(&bytes);
  const LoadedMaps loaded = LoadMaps(Write(bytes, "v1.slmap"));
  EXPECT_EQ(loaded.header.line_descriptor, LineDescriptor::kOpenCvLbd);
  ASSERT_EQ(loaded.maps.size(), 2u);
  ExpectSameMap(*first_, *loaded.maps[0]);
  EXPECT_EQ(ReadMapFileSummary(Write(bytes, "v1.slmap")).format_version, 1u);
}

TEST_F(MapIo, UnknownLineDescriptorIsRefused) {
  // The header field is an enum, so saving cannot write an unknown name; a file can hold one.
  std::vector<uint8_t> bytes = SaveAtlas();
  const MapFileHeader h = Header();
  const size_t name =
      kPreambleBytes + 4 + h.slslam_version.size() + 4 + 4 + 4 + h.vocabulary.size() + 4;
  ASSERT_EQ(std::string(bytes.begin() + name, bytes.begin() + name + 10), "opencv_lbd");
  const std::string sift = "sift______";
  std::copy(sift.begin(), sift.end(), bytes.begin() + name);
  Rechecksum(&bytes);
  ExpectRefused(Write(bytes, "sift.slmap"), "line descriptor 'sift______'");
}

TEST_F(MapIo, TruncatedFilesAreRefusedAtEveryLength) {
  const std::vector<uint8_t> bytes = SaveAtlas();
  std::vector<size_t> lengths = {0, 1, 7, 8, 11, 12, 19, 20, 27, 28, 29, 40, bytes.size() - 1};
  for (size_t n = 64; n < bytes.size(); n += bytes.size() / 97) lengths.push_back(n);
  for (const size_t n : lengths) {
    SCOPED_TRACE("length " + std::to_string(n));
    const std::vector<uint8_t> prefix(bytes.begin(), bytes.begin() + n);
    ExpectRefused(Write(prefix, "truncated.slmap"), n < 8 ? "not an slslam map file" : "");
  }
  std::vector<uint8_t> longer = bytes;
  longer.push_back(0);
  ExpectRefused(Write(longer, "longer.slmap"), "trailing data");
}

TEST_F(MapIo, FlippedBytesFailTheChecksum) {
  const std::vector<uint8_t> bytes = SaveAtlas();
  for (size_t at = kPreambleBytes; at < bytes.size(); at += bytes.size() / 89) {
    SCOPED_TRACE("byte " + std::to_string(at));
    std::vector<uint8_t> damaged = bytes;
    damaged[at] ^= 0x10;
    ExpectRefused(Write(damaged, "flipped.slmap"), "checksum mismatch");
  }
  std::vector<uint8_t> damaged = bytes;
  damaged[kChecksumOffset] ^= 1;
  ExpectRefused(Write(damaged, "flipped_sum.slmap"), "checksum mismatch");
  damaged = bytes;
  damaged[2] ^= 1;
  ExpectRefused(Write(damaged, "flipped_magic.slmap"), "not an slslam map file");
  damaged = bytes;
  damaged[12] ^= 1;
  ExpectRefused(Write(damaged, "flipped_size.slmap"), "its preamble announces");
}

// Random damage behind a valid checksum, as a buggy writer could leave: every load either gives
// maps or throws std::invalid_argument naming the file; nothing else escapes (no bad_alloc, no
// OpenCV or Eigen assertion, no crash; the sanitizer build checks the memory accesses).
TEST_F(MapIo, RandomDamageBehindAValidChecksumNeverCrashes) {
  const std::vector<uint8_t> bytes = SaveAtlas();
  std::mt19937 rng(14);
  std::uniform_int_distribution<size_t> offset(kPreambleBytes, bytes.size() - 1);
  int refused = 0;
  const int trials = 400;
  for (int t = 0; t < trials; ++t) {
    std::vector<uint8_t> damaged = bytes;
    const int edits = 1 + static_cast<int>(rng() % 4);
    for (int e = 0; e < edits; ++e) damaged[offset(rng)] = static_cast<uint8_t>(rng());
    Rechecksum(&damaged);
    const std::string path = Write(damaged, "random.slmap");
    try {
      LoadMaps(path);
    } catch (const std::invalid_argument& e) {
      ++refused;
      EXPECT_EQ(std::string(e.what()).rfind(path + ": ", 0), 0u) << e.what();
    }
  }
  // Most edits land in a field whose value is checked (ids, counts, rotations); some in free
  // values (a score, a descriptor byte) and load.
  EXPECT_GT(refused, trials / 4);
}

// Encoded sizes following the layout documented in map_io.h: a keyframe record up to its frame,
// and the frame.
size_t KeyFrameHeadBytes(const KeyFrame& kf) {
  size_t bytes = 4 + 9 * 8 + 3 * 8 + 4 + 1;
  bytes += 4 + 8 * kf.covisibility.size();
  bytes += 4 + 4 * kf.point_ids.size() + 4 + 4 * kf.line_ids.size();
  bytes += 4 + 12 * kf.bow.size() + 4;
  for (const auto& [node, keypoints] : kf.bow_features) bytes += 4 + 4 + 4 * keypoints.size();
  return bytes;
}

size_t MatBytes(const cv::Mat& d) { return 12 + d.total() * d.elemSize(); }

// Bytes of a frame record before its keypoint descriptors.
size_t FrameBytesBeforeDescriptors(const StereoFrame& f) {
  return 4 + 8 + 4 + 8 * f.NumKeypoints() + 4 + 4 * f.keypoints.score.size() + 4 +
         4 * f.keypoints.octave.size();
}

size_t KeyFrameRecordBytes(const KeyFrame& kf) {
  const StereoFrame& f = *kf.frame;
  const size_t n = f.NumKeypoints();
  const size_t m = f.NumLines();
  return KeyFrameHeadBytes(kf) + FrameBytesBeforeDescriptors(f) +
         MatBytes(f.keypoints.descriptors) + 2 * (4 + 8 * n) + 4 + 16 * m +
         MatBytes(f.line_descriptors) + 4 + 48 * m + 4 + m;
}

size_t FirstSectionBytes(const std::vector<uint8_t>& bytes) {
  uint64_t size = 0;
  for (int i = 0; i < 8; ++i) size |= uint64_t{bytes[MapCountOffset() + 4 + 16 + i]} << (8 * i);
  return static_cast<size_t>(size);
}

void FrameTimesAsSeconds(const std::vector<const Map*>& maps, size_t map_count_offset,
                         std::vector<uint8_t>* bytes) {
  size_t section = map_count_offset + 4 + 24 * maps.size();
  for (size_t m = 0; m < maps.size(); ++m) {
    size_t at = section;
    for (const auto& [id, kf] : maps[m]->keyframes()) {
      (void)id;
      PutF64(bytes, at + KeyFrameHeadBytes(*kf) + 4, Seconds(kf->frame->t_ns));
      at += KeyFrameRecordBytes(*kf);
    }
    uint64_t size = 0;
    for (int i = 0; i < 8; ++i) {
      size |= uint64_t{bytes->at(map_count_offset + 4 + 24 * m + 16 + i)} << (8 * i);
    }
    section += static_cast<size_t>(size);
  }
}

// A version-2 file (f64 frame times [s]) reads each time as the nanosecond nearest it; a time
// that is not finite or beyond int64 nanoseconds is refused, naming the keyframe.
TEST_F(MapIo, VersionTwoFrameSecondsReadAsNanoseconds) {
  std::vector<uint8_t> bytes = SaveAtlas();
  FrameTimesAsSeconds({first_.get(), second_.get()}, MapCountOffset(), &bytes);
  PutU32(&bytes, 8, 2);
  Rechecksum(&bytes);
  LoadedMaps loaded = LoadMaps(Write(bytes, "v2.slmap"));
  ASSERT_EQ(loaded.maps.size(), 2u);
  ExpectSameMap(*first_, *loaded.maps[0]);  // (the fixture's times are exact in f64 seconds)
  ExpectSameMap(*second_, *loaded.maps[1]);
  const auto kf0 = first_->keyframes().begin()->second;
  const size_t first_time = FirstSectionOffset(2) + KeyFrameHeadBytes(*kf0) + 4;
  PutF64(&bytes, first_time, 1403715273.262142);
  Rechecksum(&bytes);
  loaded = LoadMaps(Write(bytes, "v2.slmap"));
  const int64_t t_ns = loaded.maps[0]->keyframes().begin()->second->frame->t_ns;
  EXPECT_EQ(t_ns, NsFromSeconds(1403715273.262142));
  EXPECT_LE(std::abs(t_ns - 1'403'715'273'262'142'000), 120);  // (f64's spacing there: 238 ns)
  for (const double bad : {double{INFINITY}, std::nan(""), 1e300}) {
    SCOPED_TRACE(bad);
    PutF64(&bytes, first_time, bad);
    Rechecksum(&bytes);
    ExpectRefused(Write(bytes, "v2.slmap"),
                  Message("keyframe ", kf0->id, ": frame timestamp ", bad, " s is not finite"),
                  /*summary_too=*/false);
  }
}

// Files with a correct checksum whose content is wrong, as another writer could produce: each
// is refused by the check behind it, before any allocation the file could not back.
TEST_F(MapIo, CraftedFilesWithValidChecksumsAreRefused) {
  const std::vector<uint8_t> bytes = SaveAtlas();
  const size_t map_count = MapCountOffset();
  const size_t section = FirstSectionOffset(2);
  const size_t first_kf_pose = section + 4;
  const size_t first_kf_parent = first_kf_pose + 12 * 8;
  const size_t first_kf_covisibility = first_kf_parent + 4 + 1;
  const auto kf0 = first_->keyframes().begin()->second;
  const size_t first_kf_point_ids = first_kf_covisibility + 4 + 8 * kf0->covisibility.size();
  const size_t first_frame = section + KeyFrameHeadBytes(*kf0);
  const size_t first_descriptors = first_frame + FrameBytesBeforeDescriptors(*kf0->frame);
  const size_t first_depths = first_descriptors + MatBytes(kf0->frame->keypoints.descriptors) + 4 +
                              8 * kf0->frame->NumKeypoints();
  size_t last_kf = section;
  for (const auto& [id, kf] : first_->keyframes()) {
    if (id != first_->keyframes().rbegin()->first) last_kf += KeyFrameRecordBytes(*kf);
  }
  struct Case {
    const char* name;
    size_t offset;
    bool f64;
    double value;
    const char* expected;
  };
  const std::vector<Case> cases = {
      {"huge map count", map_count, false, 0xFFFFFFFFu, "map count is 4294967295"},
      {"huge keyframe count", map_count + 4, false, 0x7FFFFFFFu, "cannot fit"},
      {"huge section size", map_count + 4 + 16, false, 0xFFFFFFF0u, "cannot fit"},
      {"huge covisibility count", first_kf_covisibility, false, 0x7FFFFFFFu, "covisibility is"},
      {"huge point id count", first_kf_point_ids, false, 0x40000000u, "point ids is"},
      {"unknown point id", first_kf_point_ids + 4, false, 123456, "unknown point id 123456"},
      {"NaN pose", first_kf_pose, true, std::nan(""), "keyframe 0: pose"},
      {"skewed rotation", first_kf_pose, true, 1.5, "keyframe 0: pose"},
      {"infinite translation", first_kf_pose + 9 * 8, true, INFINITY, "keyframe 0: pose"},
      {"unknown parent", first_kf_parent, false, 77, "parent 77"},
      {"keyframe id beyond the counter", last_kf, false, 5000, "keyframe id 5000 is outside"},
      {"keyframe ids out of order", section, false, 5000, "keyframe id 2 follows 5000"},
      {"negative keyframe id", section, false, 0xFFFFFFFEu, "keyframe id -2 is outside"},
      {"NaN keypoint", first_frame + 12 + 4, false, 0x7FC00000u, "keypoint position"},
      {"translation of 1e300 m", first_kf_pose + 9 * 8, true, 1e300, "beyond 1e+07 m"},
      {"id counter at int32's end", map_count - 12, false, 0x7FFFFFFFu,
       "leave fewer than 16777216 new ids"},
      {"negative frame index", first_frame, false, 0xFFFFFFFFu, "frame index -1"},
      {"huge descriptor matrix", first_descriptors + 4, false, 0x7FFFFFFFu,
       "truncated: keypoint descriptors of 2147483647 x 32"},
      {"unknown matrix type", first_descriptors, false, 1234, "unsupported matrix type 1234"},
      {"descriptor type unlike the header", first_descriptors, false, CV_8S,
       "the file's header says type 0"},
      {"octave out of range", first_descriptors - 4 * kf0->frame->NumKeypoints(), false, 99,
       "keypoint 0 has octave 99"},
      {"NaN depth", first_depths + 4, true, std::nan(""), "right column or depth"},
      {"zero width camera", map_count - 12 - 8 - 8, false, 0, "stereo rig"},
      {"unknown descriptor type", kPreambleBytes + 4 + 5, false, 3, "descriptor type 3"},
      {"huge version string", kPreambleBytes, false, 0x10000000u, "version string is"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    std::vector<uint8_t> crafted = bytes;
    if (c.f64) {
      PutF64(&crafted, c.offset, c.value);
    } else {
      PutU32(&crafted, c.offset, static_cast<uint32_t>(static_cast<int64_t>(c.value)));
    }
    Rechecksum(&crafted);
    ExpectRefused(Write(crafted, "crafted.slmap"), c.expected, /*summary_too=*/false);
  }
}

TEST_F(MapIo, LayoutMatchesTheDocumentation) {
  const std::vector<uint8_t> bytes = SaveAtlas();
  size_t expected = 0;
  for (const auto& [id, kf] : first_->keyframes()) expected += KeyFrameRecordBytes(*kf);
  expected += first_->retired().size() * (4 + 4 + 12 * 8);
  for (const auto& [id, p] : first_->points()) {
    expected += 4 + 24 + 12 + p->descriptor.total() + 4 + 8 * p->observations.size() + 12 + 1;
  }
  for (const auto& [id, l] : first_->lines()) {
    expected += 4 + 96 + 12 + l->descriptor.total() + 4 + 8 * l->observations.size() + 12 + 1;
  }
  EXPECT_EQ(FirstSectionBytes(bytes), expected);
  EXPECT_EQ(std::string(bytes.begin(), bytes.begin() + 8), "SLSLAMAP");
}

TEST_F(MapIo, IdsMustBeUniqueAcrossTheFile) {
  // The first map's culled keyframe renamed to the second map's first keyframe id: each map
  // alone is consistent, the file is not.
  std::vector<uint8_t> bytes = SaveAtlas();
  size_t retired = FirstSectionOffset(2);
  for (const auto& [id, kf] : first_->keyframes()) retired += KeyFrameRecordBytes(*kf);
  ASSERT_EQ(first_->retired().begin()->first, 1);
  PutU32(&bytes, retired, static_cast<uint32_t>(second_->keyframes().begin()->first));
  Rechecksum(&bytes);
  ExpectRefused(Write(bytes, "duplicate.slmap"), "keyframe id 5 is in two maps",
                /*summary_too=*/false);
}

}  // namespace
}  // namespace slslam
