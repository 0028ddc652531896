#include "slslam/place/keyframe_database.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "slslam/core/check.h"

namespace slslam {

void KeyframeDatabase::Add(int keyframe_id, const BowVector& bow) {
  MutexLock lock(mutex_);
  RemoveLocked(keyframe_id);
  for (const auto& entry : bow) keyframes_of_word_[entry.first].push_back(keyframe_id);
  bow_of_keyframe_.emplace(keyframe_id, bow);
}

void KeyframeDatabase::Remove(int keyframe_id) {
  MutexLock lock(mutex_);
  RemoveLocked(keyframe_id);
}

void KeyframeDatabase::RemoveLocked(int keyframe_id) {
  const auto found = bow_of_keyframe_.find(keyframe_id);
  if (found == bow_of_keyframe_.end()) return;
  for (const auto& entry : found->second) {
    const auto list = keyframes_of_word_.find(entry.first);
    if (list == keyframes_of_word_.end()) continue;
    auto& ids = list->second;
    ids.erase(std::remove(ids.begin(), ids.end(), keyframe_id), ids.end());
    if (ids.empty()) keyframes_of_word_.erase(list);
  }
  bow_of_keyframe_.erase(found);
}

void KeyframeDatabase::Clear() {
  MutexLock lock(mutex_);
  bow_of_keyframe_.clear();
  keyframes_of_word_.clear();
}

int KeyframeDatabase::size() const {
  MutexLock lock(mutex_);
  return static_cast<int>(bow_of_keyframe_.size());
}

bool KeyframeDatabase::Contains(int keyframe_id) const {
  MutexLock lock(mutex_);
  return bow_of_keyframe_.count(keyframe_id) > 0;
}

std::vector<KeyframeDatabase::Candidate> KeyframeDatabase::Query(
    const BowVector& bow, int max_results, double min_score, double min_shared_ratio,
    const std::function<bool(int)>& accept) const {
  SLSLAM_CHECK(min_shared_ratio >= 0.0 && min_shared_ratio <= 1.0,
               "KeyframeDatabase::Query: min_shared_ratio must be in [0, 1], got ",
               min_shared_ratio);
  SLSLAM_CHECK(std::isfinite(min_score), "KeyframeDatabase::Query: min_score must be finite, got ",
               min_score);

  // 1. Shared words per keyframe from the inverted index.
  std::vector<Candidate> candidates;
  {
    MutexLock lock(mutex_);
    std::unordered_map<int, int> shared;
    for (const auto& entry : bow) {
      const auto list = keyframes_of_word_.find(entry.first);
      if (list == keyframes_of_word_.end()) continue;
      for (const int id : list->second) ++shared[id];
    }
    candidates.reserve(shared.size());
    for (const auto& [id, count] : shared) candidates.push_back({id, 0.0, count});
  }
  // 2. The caller's filter, outside the lock.
  if (accept) {
    candidates.erase(
        std::remove_if(candidates.begin(), candidates.end(),
                       [&accept](const Candidate& c) { return !accept(c.keyframe_id); }),
        candidates.end());
  }
  // 3. Only keyframes sharing nearly as many words as the best one are worth scoring.
  int most_shared = 0;
  for (const Candidate& c : candidates) most_shared = std::max(most_shared, c.shared_words);
  const double min_shared = min_shared_ratio * most_shared;
  candidates.erase(
      std::remove_if(candidates.begin(), candidates.end(),
                     [min_shared](const Candidate& c) { return c.shared_words < min_shared; }),
      candidates.end());
  // 4. Scores; keyframes removed since step 1 drop out.
  {
    MutexLock lock(mutex_);
    auto scored = candidates.begin();
    for (const Candidate& c : candidates) {
      const auto found = bow_of_keyframe_.find(c.keyframe_id);
      if (found == bow_of_keyframe_.end()) continue;
      const double score = Vocabulary::Score(bow, found->second);
      if (score < min_score) continue;
      *scored++ = {c.keyframe_id, score, c.shared_words};
    }
    candidates.erase(scored, candidates.end());
  }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
    if (a.score != b.score) return a.score > b.score;
    if (a.shared_words != b.shared_words) return a.shared_words > b.shared_words;
    return a.keyframe_id < b.keyframe_id;
  });
  if (max_results > 0 && candidates.size() > static_cast<size_t>(max_results)) {
    candidates.resize(max_results);
  }
  return candidates;
}

}  // namespace slslam
