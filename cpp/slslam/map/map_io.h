// Saving and loading the atlas's maps: one versioned, checksummed binary file holding every
// keyframe (with the stereo frame it was made from), culled-keyframe record, map point and map
// line, with their ids, so a map kept from one shift can be tracked in on the next (issue 14).
//
// File layout (format version 3; version 2 has f64 frame timestamps [s] where 3 has i64 t_ns,
// version 1 also lacks line_descriptor, its lines carry OpenCV's LBD).
// Integers are little-endian two's complement, floats IEEE-754
// little-endian; "str" is a u32 byte count and the bytes; "[T]" is a u32 count and that many T;
// ids and counts are i32/u32 and every id fits an int.
//
//   offset  size  field
//   0       8     magic "SLSLAMAP"
//   8       4     format version (u32)
//   12      8     payload size (u64): bytes from offset 28 to the end of the file
//   20      8     FNV-1a 64 of the payload
//   28      ...   payload:
//     header    str slslam_version (<= 256 bytes); i32 descriptor_type (OpenCV type of the
//               keypoint descriptors: 0 CV_8U binary, 5 CV_32F float, -1 none); i32
//               descriptor_cols; str vocabulary (<= 4096 bytes); str line_descriptor ("lbd" or
//               "opencv_lbd", <= 256 bytes); f64 fx, fy, cx, cy [px]; i32 width, height [px];
//               f64 baseline_m [m]
//     ids       i32 next_keyframe, next_point, next_line: the id counters the maps share
//     table     u32 map count M; M x (u32 keyframes, retired, points, lines; u64 section bytes)
//     M map sections, each exactly its table's byte count, entries in ascending id:
//       keyframe  i32 id; f64 R_cw[9] (row-major, world -> camera); f64 t_cw[3] [m]; i32 parent;
//                 u8 bad; [i32 keyframe, i32 shared points] covisibility; [i32] point_ids;
//                 [i32] line_ids; [u32 word, f64 weight] bow; [u32 node, [i32 keypoint]]
//                 bow_features; then its frame:
//                   i32 index; i64 t_ns [ns]; [f32 u, v] keypoints.uv [px];
//                   [f32] keypoints.score; [i32] keypoints.octave; mat keypoints.descriptors;
//                   [f64] u_right [px]; [f64] depth [m]; [f32 u0, v0, u1, v1] lines [px];
//                   mat line_descriptors; [f64 start xyz, end xyz] line_endpoints (left camera
//                   frame) [m]; [u8] line_has_depth
//       retired   i32 id; i32 parent; f64 R_kf_parent[9] (row-major); f64 t_kf_parent[3] [m]
//       point     i32 id; f64 position[3] (world) [m]; mat descriptor; [i32 keyframe,
//                 i32 keypoint] observations; i32 visible, found, first_keyframe; u8 bad
//       line      i32 id; f64 n[3], v[3] (Pluecker, world); f64 start[3], end[3] (world) [m];
//                 mat descriptor; [i32 keyframe, i32 segment] observations; i32 visible, found,
//                 first_keyframe; u8 bad
//     mat         i32 OpenCV type (depth 8U..64F, 1-4 channels); i32 rows, cols; the elements
//                 row by row
//
// Loading checks everything before it builds a map: magic, version, size and checksum; every
// count against the bytes left before it allocates; ids unique across the file and below the
// counters; references (parent, covisibility, point_ids, line_ids, observations) to entries of
// the same map and indices within the keyframe's frame; finite poses with orthonormal rotations,
// finite positions, lines and frame values; array lengths matching the keypoint and segment
// counts; descriptors of the header's type. Saving runs the same checks first, so a file that
// was written always loads. Every failure throws std::invalid_argument
// "<path>: [not saved: ][map i, ]<entry>: <what is wrong>".
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "slslam/features/lbd.h"
#include "slslam/geometry/reprojection.h"
#include "slslam/map/map.h"

namespace slslam {

constexpr uint32_t kMapFileFormatVersion = 3;

// What the maps were made with: a tracker refuses a map made with another front end or rig.
struct MapFileHeader {
  std::string slslam_version;  ///< version of the slslam that wrote the file
  int descriptor_type = -1;    ///< keypoint descriptors: CV_8U (binary) or CV_32F; -1: none
  int descriptor_cols = 0;     ///< bytes (binary) or floats per descriptor
  std::string vocabulary;      ///< name or checksum of the bag-of-words vocabulary; empty: none
  /// Descriptor of the keyframes' line segments and the map lines (features/lbd.h); files of
  /// format version 1 read as OpenCV's.
  LineDescriptor line_descriptor = LineDescriptor::kOpenCvLbd;
  StereoRig rig;  ///< the rectified stereo rig of the frames
};

struct LoadedMaps {
  MapFileHeader header;
  std::vector<std::unique_ptr<Map>> maps;  ///< in file order, all on one shared MapIds
};

struct MapFileSummary {
  struct Counts {
    int keyframes = 0;
    int retired = 0;  ///< culled keyframes kept as a pose relative to their parent
    int points = 0;
    int lines = 0;
  };
  uint32_t format_version = 0;
  MapFileHeader header;
  MapIds next_ids;
  std::vector<Counts> maps;
};

// Writes `maps` (the caller holds each map's mutex) to path + ".partial", then renames it to
// path, so a reader never sees half a file. References to entries no longer in a map (a point id
// left in a keyframe after the point was erased, an observation of an erased keyframe) are
// written as none (-1, or left out), which is what the map makes of them when it looks them up.
// The id counters written are the largest of the maps'.
void SaveMaps(const std::string& path, const std::vector<const Map*>& maps,
              const MapFileHeader& header);

// Reads and checks a file written by SaveMaps. The maps are created on `ids` (the shared counters
// of the atlas they join; null: new ones), whose counters move past the file's. The file's ids
// are not checked against entries already counted on `ids`: load into an empty atlas.
LoadedMaps LoadMaps(const std::string& path, std::shared_ptr<MapIds> ids = nullptr);

// Header, counters and per-map counts, for describing a file; checks the magic, version, size,
// checksum and header but builds no map.
MapFileSummary ReadMapFileSummary(const std::string& path);

}  // namespace slslam
