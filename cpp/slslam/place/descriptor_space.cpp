// The Hamming kernels of descriptor_space.h, compiled with and without the POPCNT instruction
// (core/cpu_dispatch.h). 1,000 ORB look-ups take about half the time with it.
#include "slslam/place/descriptor_space.h"

#include <limits>

#include "slslam/core/cpu_dispatch.h"

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
