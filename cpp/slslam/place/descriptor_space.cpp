// The Hamming kernels of descriptor_space.h. Baseline x86-64 has no POPCNT instruction (slslam is
// built without -march so wheels run anywhere), and without it a popcount is a library call; so
// these loops are compiled twice and the loader picks the POPCNT version where the CPU has it
// (GCC / Clang function multiversioning). 1,000 ORB look-ups take about half the time.
#include "slslam/place/descriptor_space.h"

#include <limits>

// Not under a sanitizer: the loader runs the clones' resolver before the sanitizer's runtime is
// up, and an instrumented resolver crashes the program at start (SLSLAM_SANITIZED, CMakeLists).
#if defined(__x86_64__) && defined(__linux__) && (defined(__GNUC__) || defined(__clang__)) && \
    !defined(SLSLAM_SANITIZED)
#define SLSLAM_POPCNT_CLONES __attribute__((target_clones("popcnt", "default")))
#else
#define SLSLAM_POPCNT_CLONES
#endif

namespace slslam::place_detail {

namespace {

inline int HammingInline(const uint64_t* a, const uint64_t* b, int words) {
  int distance = 0;
  for (int w = 0; w < words; ++w) distance += __builtin_popcountll(a[w] ^ b[w]);
  return distance;
}

}  // namespace

SLSLAM_POPCNT_CLONES int Hamming(const uint64_t* a, const uint64_t* b, int words) {
  return HammingInline(a, b, words);
}

SLSLAM_POPCNT_CLONES int NearestBinaryCentre(const uint64_t* query, const uint64_t* centres,
                                             int count, int words) {
  int best = 0;
  int best_distance = std::numeric_limits<int>::max();
  for (int c = 0; c < count; ++c) {
    const int d = HammingInline(query, centres + static_cast<size_t>(c) * words, words);
    if (d < best_distance) best_distance = d, best = c;
  }
  return best;
}

SLSLAM_POPCNT_CLONES uint32_t NearestBinaryNode(const uint64_t* query, const uint64_t* centres,
                                                int words, const uint32_t* first,
                                                const uint32_t* last) {
  uint32_t best = *first;
  int best_distance = std::numeric_limits<int>::max();
  for (const uint32_t* c = first; c != last; ++c) {
    const int d = HammingInline(query, centres + static_cast<size_t>(*c) * words, words);
    if (d < best_distance) best_distance = d, best = *c;
  }
  return best;
}

}  // namespace slslam::place_detail
