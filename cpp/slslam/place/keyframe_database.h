// Keyframe database for relocalisation and loop closing: an inverted index (word -> keyframes
// holding it) over the keyframes' BoW vectors, queried by shared words and scored with
// Vocabulary::Score (after DBoW2's database and ORB-SLAM's candidate pre-filter).
//
// Thread-safe: every method takes an internal mutex, so the tracker may query while local mapping
// adds and removes keyframes. Keyframes are plain integer ids; the map is not known here.
#pragma once

#include <functional>
#include <unordered_map>
#include <vector>

#include "slslam/core/thread_annotations.h"
#include "slslam/place/vocabulary.h"

namespace slslam {

class KeyframeDatabase {
 public:
  struct Candidate {
    int keyframe_id = -1;
    double score = 0.0;    ///< Vocabulary::Score against the query, in [0, 1]
    int shared_words = 0;  ///< words the keyframe shares with the query
  };

  // Adds a keyframe's BoW vector; replaces an existing entry with that id.
  void Add(int keyframe_id, const BowVector& bow);
  // Removes a keyframe; unknown ids are ignored.
  void Remove(int keyframe_id);
  void Clear();
  int size() const;
  bool Contains(int keyframe_id) const;

  // Keyframes sharing words with `bow`, best score first (ties: more shared words, then lower id),
  // at most `max_results` (<= 0: all) with score >= min_score.
  //
  // `accept` (may be empty) filters ids first, e.g. to drop keyframes covisible with the query.
  // Among the accepted, only keyframes sharing at least min_shared_ratio * (the most words any of
  // them shares) are scored. `accept` runs without the database lock held, so it may take other
  // locks (the map's) or call back into the database; a keyframe removed meanwhile is skipped.
  std::vector<Candidate> Query(const BowVector& bow, int max_results, double min_score = 0.0,
                               double min_shared_ratio = 0.8,
                               const std::function<bool(int)>& accept = {}) const;

 private:
  void RemoveLocked(int keyframe_id) SLSLAM_REQUIRES(mutex_);

  mutable Mutex mutex_;
  std::unordered_map<int, BowVector> bow_of_keyframe_ SLSLAM_GUARDED_BY(mutex_);
  // inverted index
  std::unordered_map<WordId, std::vector<int>> keyframes_of_word_ SLSLAM_GUARDED_BY(mutex_);
};

}  // namespace slslam
