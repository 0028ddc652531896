#include "slslam/place/keyframe_database.h"

#include <atomic>
#include <chrono>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <thread>

#include <gtest/gtest.h>

#include "synthetic_descriptors.h"

namespace slslam {
namespace {

using test::ClusteredDescriptors;

// A random L1-normalised BoW vector of `words` distinct words out of `vocabulary_size`.
BowVector RandomBow(std::mt19937* rng, int words, int vocabulary_size) {
  BowVector bow;
  while (static_cast<int>(bow.size()) < words) {
    bow[static_cast<WordId>((*rng)() % vocabulary_size)] = 1.0 + ((*rng)() % 100) / 100.0;
  }
  double sum = 0.0;
  for (const auto& entry : bow) sum += entry.second;
  for (auto& entry : bow) entry.second /= sum;
  return bow;
}

// `bow` with a fraction of its words replaced by random ones, renormalised.
BowVector Perturb(const BowVector& bow, double keep, std::mt19937* rng, int vocabulary_size) {
  BowVector out;
  for (const auto& entry : bow) {
    if (((*rng)() % 1000) / 1000.0 < keep) {
      out[entry.first] = entry.second;
    } else {
      out[static_cast<WordId>((*rng)() % vocabulary_size)] = entry.second;
    }
  }
  double sum = 0.0;
  for (const auto& entry : out) sum += entry.second;
  for (auto& entry : out) entry.second /= sum;
  return out;
}

class KeyframeDatabaseTest : public ::testing::Test {
 protected:
  static constexpr int kKeyframes = 60;
  static constexpr int kWords = 2000;
  void SetUp() override {
    for (int id = 0; id < kKeyframes; ++id) {
      bows_.push_back(RandomBow(&rng_, 200, kWords));
      database_.Add(100 + id, bows_.back());
    }
  }
  std::mt19937 rng_{3};
  std::vector<BowVector> bows_;
  KeyframeDatabase database_;
};

TEST_F(KeyframeDatabaseTest, QueryReturnsTheRevisitedKeyframeFirst) {
  EXPECT_EQ(database_.size(), kKeyframes);
  for (const int target : {0, 17, 59}) {
    const BowVector query = Perturb(bows_[target], 0.6, &rng_, kWords);
    const auto candidates = database_.Query(query, 5, 0.0, 0.0);
    ASSERT_FALSE(candidates.empty());
    EXPECT_EQ(candidates[0].keyframe_id, 100 + target);
    EXPECT_NEAR(candidates[0].score, Vocabulary::Score(query, bows_[target]), 1e-12);
    EXPECT_LE(candidates.size(), 5u);
    for (size_t i = 1; i < candidates.size(); ++i) {
      EXPECT_GE(candidates[i - 1].score, candidates[i].score);
    }
    EXPECT_GT(candidates[0].shared_words, 100);
  }
}

TEST_F(KeyframeDatabaseTest, MinScoreAndSharedRatioPrefilter) {
  const BowVector query = Perturb(bows_[5], 0.7, &rng_, kWords);
  // With the ORB-SLAM pre-filter (80 % of the best shared count) only the revisited keyframe,
  // which shares far more words than any distractor, is scored.
  const auto filtered = database_.Query(query, 0, 0.0, 0.8);
  ASSERT_EQ(filtered.size(), 1u);
  EXPECT_EQ(filtered[0].keyframe_id, 105);
  const auto all = database_.Query(query, 0, 0.0, 0.0);
  EXPECT_GT(all.size(), 10u);
  const auto confident = database_.Query(query, 0, 0.3, 0.0);
  ASSERT_EQ(confident.size(), 1u);
  EXPECT_EQ(confident[0].keyframe_id, 105);
  EXPECT_THROW(database_.Query(query, 0, 0.0, 1.5), std::invalid_argument);
}

TEST_F(KeyframeDatabaseTest, RemoveAndReplace) {
  const BowVector query = Perturb(bows_[17], 0.6, &rng_, kWords);
  database_.Remove(117);
  EXPECT_EQ(database_.size(), kKeyframes - 1);
  EXPECT_FALSE(database_.Contains(117));
  for (const auto& c : database_.Query(query, 0, 0.0, 0.0)) EXPECT_NE(c.keyframe_id, 117);
  database_.Remove(117);  // unknown ids are ignored
  database_.Remove(-5);
  EXPECT_EQ(database_.size(), kKeyframes - 1);

  // Add under an existing id replaces its words: 118 now holds 17's vector.
  database_.Add(118, bows_[17]);
  EXPECT_EQ(database_.size(), kKeyframes - 1);
  const auto candidates = database_.Query(query, 1, 0.0, 0.0);
  ASSERT_EQ(candidates.size(), 1u);
  EXPECT_EQ(candidates[0].keyframe_id, 118);
  for (const auto& c : database_.Query(bows_[18], 0, 0.0, 0.0)) {
    EXPECT_LT(c.score, 0.5) << "118's old words still indexed";
  }
  database_.Clear();
  EXPECT_EQ(database_.size(), 0);
  EXPECT_TRUE(database_.Query(query, 0, 0.0, 0.0).empty());
}

TEST_F(KeyframeDatabaseTest, AcceptFiltersBeforeTheSharedWordThreshold) {
  const BowVector query = Perturb(bows_[30], 0.7, &rng_, kWords);
  // Without 130 the best remaining keyframes share few words; they must still come back with the
  // 0.8 ratio, computed among the accepted keyframes only.
  const auto candidates =
      database_.Query(query, 0, 0.0, 0.8, [](int id) { return id != 130 && id != 131; });
  ASSERT_FALSE(candidates.empty());
  for (const auto& c : candidates) {
    EXPECT_NE(c.keyframe_id, 130);
    EXPECT_NE(c.keyframe_id, 131);
  }
  const auto only_even = database_.Query(query, 0, 0.0, 0.0, [](int id) { return id % 2 == 0; });
  for (const auto& c : only_even) EXPECT_EQ(c.keyframe_id % 2, 0);
  // The filter may call back into the database (it runs without the lock).
  const auto reentrant =
      database_.Query(query, 0, 0.0, 0.0, [this](int id) { return database_.Contains(id); });
  EXPECT_FALSE(reentrant.empty());
}

TEST(KeyframeDatabase, FindsTheRevisitedPlaceThroughAVocabulary) {
  ClusteredDescriptors data(64, CV_8U, 32);
  std::vector<cv::Mat> images;
  std::mt19937 rng(11);
  std::vector<std::vector<int>> clusters_of_image;
  for (int i = 0; i < 40; ++i) {
    std::vector<int> clusters;
    for (int j = 0; j < 12; ++j) clusters.push_back(static_cast<int>(rng() % 64));
    clusters_of_image.push_back(clusters);
    images.push_back(data.Image(clusters, 5));
  }
  VocabularyOptions options;
  options.branching = 8;
  options.levels = 2;
  const Vocabulary vocabulary = Vocabulary::Train(images, options);
  KeyframeDatabase database;
  for (int i = 0; i < 40; ++i) {
    BowVector bow;
    vocabulary.Transform(images[i], &bow);
    database.Add(i, bow);
  }
  for (const int revisit : {4, 23}) {
    BowVector bow;
    vocabulary.Transform(data.Image(clusters_of_image[revisit], 5), &bow);  // new noise
    const auto candidates = database.Query(bow, 3);
    ASSERT_FALSE(candidates.empty());
    EXPECT_EQ(candidates[0].keyframe_id, revisit);
    EXPECT_GT(candidates[0].score, 0.5);
  }
}

TEST(KeyframeDatabase, ConcurrentQueriesAndRemovals) {
  std::mt19937 rng(5);
  KeyframeDatabase database;
  std::vector<BowVector> bows;
  for (int id = 0; id < 300; ++id) {
    bows.push_back(RandomBow(&rng, 150, 5000));
    database.Add(id, bows.back());
  }
  std::atomic<bool> stop{false};
  std::thread mapper([&] {
    for (int id = 0; id < 300; id += 2) database.Remove(id);
    for (int id = 0; id < 300; id += 2) database.Add(id, bows[id]);
    stop = true;
  });
  int queries = 0;
  while (!stop || queries < 10) {
    const auto candidates = database.Query(bows[queries % 300], 3, 0.0, 0.5);
    for (const auto& c : candidates) EXPECT_GE(c.score, 0.0);
    ++queries;
  }
  mapper.join();
  EXPECT_EQ(database.size(), 300);
}

// Query cost with a database of ORB-SLAM size (prints the numbers).
TEST(KeyframeDatabase, QueryTimeWithAThousandKeyframes) {
  std::mt19937 rng(9);
  KeyframeDatabase database;
  std::vector<BowVector> bows;
  for (int id = 0; id < 1000; ++id) {
    bows.push_back(RandomBow(&rng, 400, 10000));
    database.Add(id, bows.back());
  }
  const auto t0 = std::chrono::steady_clock::now();
  constexpr int kQueries = 50;
  for (int q = 0; q < kQueries; ++q) {
    const auto candidates = database.Query(bows[q * 7], 10);
    ASSERT_FALSE(candidates.empty());
    EXPECT_EQ(candidates[0].keyframe_id, q * 7);
  }
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() /
      kQueries;
  std::printf("[ perf     ] query, 1000 keyframes x 400 words of 10k: %.3f ms\n", ms);
  EXPECT_LT(ms, 100.0);
}

}  // namespace
}  // namespace slslam
