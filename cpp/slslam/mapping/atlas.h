// The atlas (ORB-SLAM3's, on which the SL-SLAM paper builds): the maps of one run, each with its
// keyframe database, and which map each was merged into. Maps share one id source, so keyframe,
// point and line ids are unique across the atlas and a merge moves entries without renumbering.
//
// Thread safety: the list of maps has its own mutex; entries are never removed, so references
// returned stay valid for the atlas's lifetime. Each Map guards its content with its own mutex
// and each KeyframeDatabase is thread-safe.
#pragma once

#include <memory>
#include <vector>

#include "slslam/map/map.h"
#include "slslam/place/keyframe_database.h"

namespace slslam {

class Atlas {
 public:
  Atlas() : ids_(std::make_shared<MapIds>()) {}

  // Appends an empty map and returns its index.
  int AddMap();
  // Appends a map built on this atlas's id counters (`ids()`, e.g. one loaded from a file).
  int AdoptMap(std::unique_ptr<Map> map);
  const std::shared_ptr<MapIds>& ids() const { return ids_; }
  int size() const;
  Map& map(int index) const;
  KeyframeDatabase& database(int index) const;
  // The map `index` lives on in after merges (itself when never merged).
  int Resolve(int index) const;
  bool merged(int index) const { return Resolve(index) != index; }
  void MarkMerged(int from, int into);

 private:
  struct Entry {
    std::unique_ptr<Map> map;
    std::unique_ptr<KeyframeDatabase> database;
    int merged_into = -1;
  };
  const Entry& entry(int index) const SLSLAM_EXCLUDES(mutex_);  // takes the lock

  mutable Mutex mutex_;
  std::shared_ptr<MapIds> ids_;
  std::vector<std::unique_ptr<Entry>> entries_ SLSLAM_GUARDED_BY(mutex_);
};

}  // namespace slslam
