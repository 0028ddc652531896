#include "slslam/mapping/atlas.h"

#include "slslam/core/check.h"

namespace slslam {

int Atlas::AddMap() {
  MutexLock lock(mutex_);
  auto e = std::make_unique<Entry>();
  e->map = std::make_unique<Map>(ids_);
  e->database = std::make_unique<KeyframeDatabase>();
  entries_.push_back(std::move(e));
  return static_cast<int>(entries_.size()) - 1;
}

int Atlas::AdoptMap(std::unique_ptr<Map> map) {
  Require(map != nullptr, "the atlas cannot adopt a null map");
  Require(map->shared_ids() == ids_, "an adopted map must count on the atlas's ids");
  MutexLock lock(mutex_);
  auto e = std::make_unique<Entry>();
  e->map = std::move(map);
  e->database = std::make_unique<KeyframeDatabase>();
  entries_.push_back(std::move(e));
  return static_cast<int>(entries_.size()) - 1;
}

int Atlas::size() const {
  MutexLock lock(mutex_);
  return static_cast<int>(entries_.size());
}

const Atlas::Entry& Atlas::entry(int index) const {
  MutexLock lock(mutex_);
  SLSLAM_CHECK(index >= 0 && index < static_cast<int>(entries_.size()), "atlas has no map ", index,
               " (", entries_.size(), " maps)");
  return *entries_[index];
}

Map& Atlas::map(int index) const { return *entry(index).map; }
KeyframeDatabase& Atlas::database(int index) const { return *entry(index).database; }

int Atlas::Resolve(int index) const {
  MutexLock lock(mutex_);
  SLSLAM_CHECK(index >= 0 && index < static_cast<int>(entries_.size()), "atlas has no map ", index);
  for (size_t hops = 0; hops < entries_.size() && entries_[index]->merged_into >= 0; ++hops) {
    index = entries_[index]->merged_into;
  }
  return index;
}

void Atlas::MarkMerged(int from, int into) {
  MutexLock lock(mutex_);
  SLSLAM_CHECK(from >= 0 && into >= 0 && from != into && from < static_cast<int>(entries_.size()) &&
                   into < static_cast<int>(entries_.size()),
               "cannot merge map ", from, " into map ", into);
  entries_[from]->merged_into = into;
}

}  // namespace slslam
