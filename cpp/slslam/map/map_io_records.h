// Internal to map_io.cpp: the records of a map file (layout in map_io.h) and the checks every
// map passes before it is written or built. Not part of the public API.
#pragma once

#include <map>
#include <memory>
#include <string>

#include "slslam/core/byte_io.h"
#include "slslam/map/map.h"
#include "slslam/map/map_io.h"

namespace slslam::map_io_detail {

// The entries of one map, detached from any Map (a normalised copy when saving, the parsed file
// when loading), so one set of checks serves both.
struct MapContent {
  std::map<int, std::shared_ptr<KeyFrame>> keyframes;
  std::map<int, RetiredKeyFrame> retired;
  std::map<int, std::shared_ptr<MapPoint>> points;
  std::map<int, std::shared_ptr<MapLine>> lines;
};

// Where a check runs: the file, whether it is being saved, and the map. Builds the message
// "<path>: [not saved: ][map i, ]<parts>" only when a check fails.
class Where {
 public:
  Where(const std::string& path, bool saving) : path_(&path), saving_(saving) {}
  Where InMap(int map) const {
    Where w = *this;
    w.map_ = map;
    return w;
  }
  const std::string& path() const { return *path_; }

  template <typename... Parts>
  [[noreturn]] void Fail(const Parts&... parts) const {
    const char* action = saving_ ? "not saved: " : "";
    if (map_ >= 0)
      ThrowInvalidArgument(Message(*path_, ": ", action, "map ", map_, ", ", parts...));
    ThrowInvalidArgument(Message(*path_, ": ", action, parts...));
  }

 private:
  const std::string* path_;
  bool saving_;
  int map_ = -1;
};

constexpr size_t kMaxVersionBytes = 256;  // header string limits [bytes]
constexpr size_t kMaxVocabularyBytes = 4096;
// Plausibility bounds of a map's records (a damaged or crafted file goes beyond them):
// keyframe times of format version 2 files within int64 nanoseconds [s], positions within 10,000 km
// of the origin [m].
constexpr double kMaxTimestampS = 9.2e9;
constexpr double kMaxCoordinateM = 1e7;
// Keypoint positions within this many pixels of the image origin [px].
constexpr double kMaxImageCoordinatePx = 1e6;
// Id counters leave this many new ids to the run that loads the file, so ids never overflow.
constexpr int kIdHeadroom = 1 << 24;

// OpenCV matrices a map file may hold: two-dimensional, depths CV_8U..CV_16F, 1 to 4 channels.
constexpr int kMaxMatDepth = CV_16F;
constexpr int kMaxMatChannels = 4;

// Smallest encoded size of each record (every list empty, every matrix empty) [bytes]: a count
// read from the file is checked against these before anything is allocated for it.
constexpr size_t kMatMinBytes = 12;
constexpr size_t kFrameMinBytes = 4 + 8 + 3 * 4 + kMatMinBytes + 3 * 4 + kMatMinBytes + 2 * 4;
constexpr size_t kKeyFrameMinBytes = 4 + 9 * 8 + 3 * 8 + 4 + 1 + 5 * 4 + kFrameMinBytes;
constexpr size_t kRetiredBytes = 4 + 4 + 9 * 8 + 3 * 8;
constexpr size_t kPointMinBytes = 4 + 3 * 8 + kMatMinBytes + 4 + 3 * 4 + 1;
constexpr size_t kLineMinBytes = 4 + 12 * 8 + kMatMinBytes + 4 + 3 * 4 + 1;

void WriteKeyFrame(const KeyFrame& keyframe, ByteWriter* out);
void WriteRetired(int id, const RetiredKeyFrame& retired, ByteWriter* out);
void WritePoint(const MapPoint& point, ByteWriter* out);
void WriteLine(const MapLine& line, ByteWriter* out);

// `version`: the file's format version (its frame times: f64 seconds before 3, i64 ns since).
std::shared_ptr<KeyFrame> ReadKeyFrame(ByteReader* in, uint32_t version, const Where& where);
std::pair<int, RetiredKeyFrame> ReadRetired(ByteReader* in);
std::shared_ptr<MapPoint> ReadPoint(ByteReader* in);
std::shared_ptr<MapLine> ReadLine(ByteReader* in);

// Header fields in range: a valid rig, a known descriptor type, strings within their limits.
void CheckHeader(const MapFileHeader& header, const Where& where);

// Every entry of one map on its own (finite values, lengths matching the frame) and against the
// others (references to entries of this map, indices within the referenced frame, ids below the
// counters). Ids unique across maps are checked by the caller.
void CheckMapContent(const MapContent& content, const MapFileHeader& header, const MapIds& ids,
                     const Where& where);

}  // namespace slslam::map_io_detail
