// Map files: the preamble (magic, version, size, checksum), the header, the map table and the
// map sections (layout in map_io.h); records in map_io_records.cpp, checks in map_io_checks.cpp.
#include "slslam/map/map_io.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <mutex>
#include <set>

#include "slslam/core/byte_io.h"
#include "slslam/core/check.h"
#include "slslam/map/map_io_records.h"

namespace slslam {

namespace {

using map_io_detail::MapContent;
using map_io_detail::Where;

constexpr char kMagic[8] = {'S', 'L', 'S', 'L', 'A', 'M', 'A', 'P'};
constexpr size_t kVersionOffset = 8;
constexpr size_t kPayloadSizeOffset = 12;
constexpr size_t kChecksumOffset = 20;
constexpr size_t kPreambleBytes = 28;
constexpr size_t kTableEntryBytes = 4 * 4 + 8;

struct TableEntry {
  uint32_t keyframes = 0;
  uint32_t retired = 0;
  uint32_t points = 0;
  uint32_t lines = 0;
  uint64_t bytes = 0;
};

// What precedes the map sections.
struct Front {
  MapFileHeader header;
  MapIds ids;
  std::vector<TableEntry> table;
};

// A copy of a map's entries in which references to entries no longer in the map (a point id left
// in a keyframe after the point was erased, an observation of an erased keyframe) are none.
MapContent NormalisedContent(const Map& map) SLSLAM_REQUIRES(map.mutex()) {
  MapContent c;
  c.retired = map.retired();
  for (const auto& [id, p] : map.points()) c.points[id] = std::make_shared<MapPoint>(*p);
  for (const auto& [id, l] : map.lines()) c.lines[id] = std::make_shared<MapLine>(*l);
  for (const auto& [id, kf] : map.keyframes()) c.keyframes[id] = std::make_shared<KeyFrame>(*kf);
  auto is_keyframe = [&c](int id) { return c.keyframes.count(id) || c.retired.count(id); };
  auto drop_unknown_keyframes = [&c](std::map<int, int>* links) {
    for (auto it = links->begin(); it != links->end();) {
      it = c.keyframes.count(it->first) ? std::next(it) : links->erase(it);
    }
  };
  for (auto& [id, kf] : c.keyframes) {
    if (!is_keyframe(kf->parent)) kf->parent = -1;
    drop_unknown_keyframes(&kf->covisibility);
    for (int& p : kf->point_ids) p = c.points.count(p) ? p : -1;
    for (int& l : kf->line_ids) l = c.lines.count(l) ? l : -1;
  }
  for (auto& [id, r] : c.retired) {
    if (!is_keyframe(r.parent)) r.parent = -1;
  }
  for (auto& [id, p] : c.points) drop_unknown_keyframes(&p->observations);
  for (auto& [id, l] : c.lines) drop_unknown_keyframes(&l->observations);
  return c;
}

// Keyframe (live or culled), point and line ids appear in one map of the file only: ids are
// unique across an atlas.
void CheckUniqueIds(const std::vector<MapContent>& contents, const Where& where) {
  std::set<int> keyframes, points, lines;
  for (size_t m = 0; m < contents.size(); ++m) {
    const MapContent& c = contents[m];
    for (const auto& [id, kf] : c.keyframes) {
      if (!keyframes.insert(id).second) where.Fail("keyframe id ", id, " is in two maps");
    }
    for (const auto& [id, r] : c.retired) {
      if (!keyframes.insert(id).second) where.Fail("keyframe id ", id, " is in two maps");
    }
    for (const auto& [id, p] : c.points) {
      if (!points.insert(id).second) where.Fail("point id ", id, " is in two maps");
    }
    for (const auto& [id, l] : c.lines) {
      if (!lines.insert(id).second) where.Fail("line id ", id, " is in two maps");
    }
  }
}

void WriteFront(const MapFileHeader& h, const MapIds& ids, ByteWriter* out) {
  out->String(h.slslam_version);
  out->I32(h.descriptor_type);
  out->I32(h.descriptor_cols);
  out->String(h.vocabulary);
  out->String(LineDescriptorName(h.line_descriptor));
  const PinholeCamera& camera = h.rig.camera;
  out->F64(camera.fx);
  out->F64(camera.fy);
  out->F64(camera.cx);
  out->F64(camera.cy);
  out->I32(camera.width);
  out->I32(camera.height);
  out->F64(h.rig.baseline_m);
  out->I32(ids.next_keyframe);
  out->I32(ids.next_point);
  out->I32(ids.next_line);
}

// Header, counters and table; checks the header and that the sections fill the payload.
Front ReadFront(ByteReader* in, uint32_t version, const Where& where) {
  Front f;
  MapFileHeader& h = f.header;
  h.slslam_version = in->String(map_io_detail::kMaxVersionBytes, "version string");
  h.descriptor_type = in->I32("header");
  h.descriptor_cols = in->I32("header");
  h.vocabulary = in->String(map_io_detail::kMaxVocabularyBytes, "vocabulary name");
  // Version 1 predates our LBD: its lines carry OpenCV's.
  if (version >= 2) {
    const std::string name = in->String(map_io_detail::kMaxVersionBytes, "line descriptor name");
    try {
      h.line_descriptor = ParseLineDescriptor(name);
    } catch (const std::invalid_argument&) {
      where.Fail("line descriptor '", name, "' (lbd or opencv_lbd)");
    }
  } else {
    h.line_descriptor = LineDescriptor::kOpenCvLbd;
  }
  PinholeCamera& camera = h.rig.camera;
  camera.fx = in->F64("camera");
  camera.fy = in->F64("camera");
  camera.cx = in->F64("camera");
  camera.cy = in->F64("camera");
  camera.width = in->I32("camera");
  camera.height = in->I32("camera");
  h.rig.baseline_m = in->F64("baseline");
  map_io_detail::CheckHeader(h, where);
  f.ids.next_keyframe = in->I32("id counters");
  f.ids.next_point = in->I32("id counters");
  f.ids.next_line = in->I32("id counters");
  if (f.ids.next_keyframe < 0 || f.ids.next_point < 0 || f.ids.next_line < 0) {
    where.Fail("negative id counters (", f.ids.next_keyframe, ", ", f.ids.next_point, ", ",
               f.ids.next_line, ")");
  }
  constexpr int kMaxNextId = std::numeric_limits<int>::max() - map_io_detail::kIdHeadroom;
  if (f.ids.next_keyframe > kMaxNextId || f.ids.next_point > kMaxNextId ||
      f.ids.next_line > kMaxNextId) {
    where.Fail("id counters (", f.ids.next_keyframe, ", ", f.ids.next_point, ", ", f.ids.next_line,
               ") leave fewer than ", map_io_detail::kIdHeadroom,
               " new ids before int32 overflow (at most ", kMaxNextId, ")");
  }
  f.table.resize(in->Count(kTableEntryBytes, "map count"));
  uint64_t total = 0;
  for (size_t m = 0; m < f.table.size(); ++m) {
    TableEntry& e = f.table[m];
    e.keyframes = in->U32("map table");
    e.retired = in->U32("map table");
    e.points = in->U32("map table");
    e.lines = in->U32("map table");
    e.bytes = in->U64("map table");
    using namespace map_io_detail;
    const uint64_t least = uint64_t{e.keyframes} * kKeyFrameMinBytes +
                           uint64_t{e.retired} * kRetiredBytes +
                           uint64_t{e.points} * kPointMinBytes + uint64_t{e.lines} * kLineMinBytes;
    if (least > e.bytes || e.bytes > in->remaining()) {
      where.InMap(static_cast<int>(m))
          .Fail(e.keyframes, " keyframes, ", e.retired, " culled, ", e.points, " points and ",
                e.lines, " lines cannot fit its ", e.bytes, " bytes (", least,
                " at least), or the file lacks them");
    }
    total += e.bytes;
  }
  if (total != in->remaining()) {
    where.Fail("the map sections take ", total, " bytes but ", in->remaining(),
               " follow the table");
  }
  return f;
}

// Decodes one section; entries must come in ascending id, as a map stores them.
MapContent ReadSection(ByteReader* in, uint32_t version, const TableEntry& e, const Where& where) {
  MapContent c;
  auto ascending = [&where](const auto& entries, int id, const char* what) {
    if (!entries.empty() && id <= entries.rbegin()->first) {
      where.Fail(what, " id ", id, " follows ", entries.rbegin()->first, " (ids must ascend)");
    }
  };
  for (uint32_t i = 0; i < e.keyframes; ++i) {
    auto kf = map_io_detail::ReadKeyFrame(in, version, where);
    ascending(c.keyframes, kf->id, "keyframe");
    c.keyframes.emplace_hint(c.keyframes.end(), kf->id, std::move(kf));
  }
  for (uint32_t i = 0; i < e.retired; ++i) {
    auto [id, retired] = map_io_detail::ReadRetired(in);
    ascending(c.retired, id, "culled keyframe");
    c.retired.emplace_hint(c.retired.end(), id, retired);
  }
  for (uint32_t i = 0; i < e.points; ++i) {
    auto p = map_io_detail::ReadPoint(in);
    ascending(c.points, p->id, "point");
    c.points.emplace_hint(c.points.end(), p->id, std::move(p));
  }
  for (uint32_t i = 0; i < e.lines; ++i) {
    auto l = map_io_detail::ReadLine(in);
    ascending(c.lines, l->id, "line");
    c.lines.emplace_hint(c.lines.end(), l->id, std::move(l));
  }
  if (in->remaining() != 0) where.Fail(in->remaining(), " bytes left after its entries");
  return c;
}

// The whole file, after the checks that need no parsing: magic, version, size, checksum.
std::vector<uint8_t> ReadCheckedFile(const std::string& path, uint32_t* version) {
  auto fail = [&path](const std::string& problem) {
    throw std::invalid_argument(Message(path, ": ", problem));
  };
  std::error_code error;
  if (std::filesystem::is_directory(path, error)) fail("is a folder, not a map file");
  std::ifstream file(path, std::ios::binary | std::ios::ate);
  if (!file.is_open()) fail("cannot open the map file (missing or unreadable)");
  const std::streamoff size = file.tellg();
  if (size < 0) fail("cannot tell the file's size");
  std::vector<uint8_t> data(static_cast<size_t>(size));
  file.seekg(0);
  file.read(reinterpret_cast<char*>(data.data()), size);
  if (!file || file.gcount() != size) fail("read error");
  if (data.size() < sizeof(kMagic) || std::memcmp(data.data(), kMagic, sizeof(kMagic)) != 0) {
    fail("not an slslam map file (it does not start with \"SLSLAMAP\")");
  }
  if (data.size() < kPreambleBytes) {
    fail(Message("truncated: ", data.size(), " bytes, shorter than the ", kPreambleBytes,
                 "-byte preamble"));
  }
  ByteReader preamble(data.data() + kVersionOffset, kPreambleBytes - kVersionOffset, path);
  *version = preamble.U32("format version");
  if (*version == 0) fail("format version 0 is not a valid version");
  if (*version > kMapFileFormatVersion) {
    fail(Message("format version ", *version, " is newer than this slslam reads (",
                 kMapFileFormatVersion, "); upgrade slslam"));
  }
  const uint64_t payload = preamble.U64("payload size");
  const uint64_t stored = preamble.U64("checksum");
  if (payload != data.size() - kPreambleBytes) {
    fail(Message("file is ", data.size(), " bytes but its preamble announces ",
                 payload + kPreambleBytes,
                 payload > data.size() - kPreambleBytes ? " (truncated)" : " (trailing data)"));
  }
  const uint64_t computed = Fnv1a64(data.data() + kPreambleBytes, payload);
  if (stored != computed) {
    fail(Message("checksum mismatch (stored ", std::hex, stored, ", computed ", computed,
                 "): the file is corrupt"));
  }
  return data;
}

void WriteFileAtomically(const std::string& path, const std::vector<uint8_t>& bytes) {
  const std::string partial = path + ".partial";
  {
    std::ofstream file(partial, std::ios::binary | std::ios::trunc);
    SLSLAM_CHECK(file.is_open(), path, ": cannot open ", partial, " for writing");
    file.write(reinterpret_cast<const char*>(bytes.data()),
               static_cast<std::streamsize>(bytes.size()));
    file.close();
    if (!file) {
      std::remove(partial.c_str());
      ThrowInvalidArgument(Message(path, ": writing ", partial, " failed (disk full?)"));
    }
  }
  if (std::rename(partial.c_str(), path.c_str()) != 0) {
    std::remove(partial.c_str());
    ThrowInvalidArgument(Message(path, ": cannot rename ", partial, " to it"));
  }
}

}  // namespace

void SaveMaps(const std::string& path, const std::vector<const Map*>& maps,
              const MapFileHeader& header) {
  const Where where(path, /*saving=*/true);
  map_io_detail::CheckHeader(header, where);
  MapIds ids;
  std::vector<MapContent> contents;
  contents.reserve(maps.size());
  for (size_t m = 0; m < maps.size(); ++m) {
    if (maps[m] == nullptr) where.InMap(static_cast<int>(m)).Fail("is null");
    const MapIds& own = maps[m]->ids();
    ids.next_keyframe = std::max(ids.next_keyframe, own.next_keyframe);
    ids.next_point = std::max(ids.next_point, own.next_point);
    ids.next_line = std::max(ids.next_line, own.next_line);
    maps[m]->mutex().AssertHeld();  // the contract: the caller holds every map's lock
    contents.push_back(NormalisedContent(*maps[m]));
  }
  for (size_t m = 0; m < contents.size(); ++m) {
    map_io_detail::CheckMapContent(contents[m], header, ids, where.InMap(static_cast<int>(m)));
  }
  CheckUniqueIds(contents, where);

  ByteWriter out;
  out.Bytes(kMagic, sizeof(kMagic));
  out.U32(kMapFileFormatVersion);
  out.U64(0);  // payload size, patched below
  out.U64(0);  // checksum, patched below
  WriteFront(header, ids, &out);
  out.U32(static_cast<uint32_t>(contents.size()));
  std::vector<size_t> size_offsets;
  for (const MapContent& c : contents) {
    out.U32(static_cast<uint32_t>(c.keyframes.size()));
    out.U32(static_cast<uint32_t>(c.retired.size()));
    out.U32(static_cast<uint32_t>(c.points.size()));
    out.U32(static_cast<uint32_t>(c.lines.size()));
    size_offsets.push_back(out.size());
    out.U64(0);  // section bytes, patched below
  }
  for (size_t m = 0; m < contents.size(); ++m) {
    const size_t begin = out.size();
    for (const auto& [id, kf] : contents[m].keyframes) map_io_detail::WriteKeyFrame(*kf, &out);
    for (const auto& [id, r] : contents[m].retired) map_io_detail::WriteRetired(id, r, &out);
    for (const auto& [id, p] : contents[m].points) map_io_detail::WritePoint(*p, &out);
    for (const auto& [id, l] : contents[m].lines) map_io_detail::WriteLine(*l, &out);
    out.PatchU64(size_offsets[m], out.size() - begin);
  }
  const size_t payload = out.size() - kPreambleBytes;
  out.PatchU64(kPayloadSizeOffset, payload);
  out.PatchU64(kChecksumOffset, Fnv1a64(out.buffer().data() + kPreambleBytes, payload));
  WriteFileAtomically(path, out.buffer());
}

LoadedMaps LoadMaps(const std::string& path, std::shared_ptr<MapIds> ids) {
  const Where where(path, /*saving=*/false);
  uint32_t version = 0;
  const std::vector<uint8_t> data = ReadCheckedFile(path, &version);
  ByteReader in(data.data() + kPreambleBytes, data.size() - kPreambleBytes, path);
  Front front = ReadFront(&in, version, where);
  std::vector<MapContent> contents;
  contents.reserve(front.table.size());
  for (size_t m = 0; m < front.table.size(); ++m) {
    const TableEntry& e = front.table[m];
    ByteReader section(in.Take(e.bytes, "map section"), e.bytes, path);
    const Where in_map = where.InMap(static_cast<int>(m));
    contents.push_back(ReadSection(&section, version, e, in_map));
    map_io_detail::CheckMapContent(contents.back(), front.header, front.ids, in_map);
  }
  CheckUniqueIds(contents, where);

  if (!ids) ids = std::make_shared<MapIds>();
  ids->next_keyframe = std::max(ids->next_keyframe, front.ids.next_keyframe);
  ids->next_point = std::max(ids->next_point, front.ids.next_point);
  ids->next_line = std::max(ids->next_line, front.ids.next_line);
  LoadedMaps loaded;
  loaded.header = front.header;
  for (MapContent& c : contents) {
    auto map = std::make_unique<Map>(ids);
    MutexLock lock(map->mutex());
    for (auto& [id, kf] : c.keyframes) map->RestoreKeyFrame(std::move(kf));
    for (const auto& [id, r] : c.retired) map->RestoreRetired(id, r);
    for (auto& [id, p] : c.points) map->RestorePoint(std::move(p));
    for (auto& [id, l] : c.lines) map->RestoreLine(std::move(l));
    loaded.maps.push_back(std::move(map));
  }
  return loaded;
}

MapFileSummary ReadMapFileSummary(const std::string& path) {
  MapFileSummary summary;
  const std::vector<uint8_t> data = ReadCheckedFile(path, &summary.format_version);
  ByteReader in(data.data() + kPreambleBytes, data.size() - kPreambleBytes, path);
  Front front = ReadFront(&in, summary.format_version, Where(path, /*saving=*/false));
  summary.header = front.header;
  summary.next_ids = front.ids;
  for (const TableEntry& e : front.table) {
    MapFileSummary::Counts counts;
    counts.keyframes = static_cast<int>(e.keyframes);
    counts.retired = static_cast<int>(e.retired);
    counts.points = static_cast<int>(e.points);
    counts.lines = static_cast<int>(e.lines);
    summary.maps.push_back(counts);
  }
  return summary;
}

}  // namespace slslam
