// Distances and cluster centres of the two descriptor kinds the vocabulary handles. Internal to
// place/: binary descriptors are held as zero-padded 64-bit words so Hamming distance is a
// popcount per word; float descriptors as plain floats with squared L2 distance.
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>
#include <vector>

#include <opencv2/core.hpp>

namespace slslam::place_detail {

// "CV_8U (binary)" / "CV_32F (float)" for error messages.
inline const char* TypeName(int depth) {
  switch (depth) {
    case CV_8U:
      return "CV_8U (binary)";
    case CV_32F:
      return "CV_32F (float)";
    default:
      return "an unsupported type";
  }
}

// 64-bit words holding a binary descriptor of `bytes` bytes (the tail is zero-padded).
inline int WordsForBytes(int bytes) { return (bytes + 7) / 8; }

// Copies row `row` of a CV_8U matrix into `words` zero-padded 64-bit words at `out`. Byte j of the
// row goes to bits 8 (j % 8) .. 8 (j % 8) + 7 of word j / 8 on any host; only distances matter.
inline void PackBinaryRow(const cv::Mat& descriptors, int row, int words, uint64_t* out) {
  const uint8_t* src = descriptors.ptr<uint8_t>(row);
  const int bytes = descriptors.cols;
  for (int w = 0; w < words; ++w) {
    uint64_t value = 0;
    const int end = std::min(bytes, 8 * w + 8);
    for (int j = 8 * w; j < end; ++j) value |= static_cast<uint64_t>(src[j]) << (8 * (j - 8 * w));
    out[w] = value;
  }
}

// Inverse of PackBinaryRow: the first `bytes` bytes of the packed words.
inline void UnpackBinary(const uint64_t* words, int bytes, uint8_t* out) {
  for (int j = 0; j < bytes; ++j) out[j] = static_cast<uint8_t>(words[j / 8] >> (8 * (j % 8)));
}

// Hamming distances; defined in descriptor_space.cpp, compiled with and without the POPCNT
// instruction (baseline x86-64 lacks it) and picked at load time.
int Hamming(const uint64_t* a, const uint64_t* b, int words);
// Index in [0, count) of the centre (`words` each, contiguous) nearest to `query`; lowest on ties.
int NearestBinaryCentre(const uint64_t* query, const uint64_t* centres, int count, int words);
// The node among ids [first, last) whose centre (`words` each at centres + id * words) is nearest.
uint32_t NearestBinaryNode(const uint64_t* query, const uint64_t* centres, int words,
                           const uint32_t* first, const uint32_t* last);

inline float SquaredL2(const float* a, const float* b, int dims) {
  // Four partial sums let the compiler use SIMD lanes without -ffast-math.
  float s[4] = {0.f, 0.f, 0.f, 0.f};
  int i = 0;
  for (; i + 4 <= dims; i += 4) {
    for (int l = 0; l < 4; ++l) {
      const float d = a[i + l] - b[i + l];
      s[l] += d * d;
    }
  }
  float sum = (s[0] + s[1]) + (s[2] + s[3]);
  for (; i < dims; ++i) sum += (a[i] - b[i]) * (a[i] - b[i]);
  return sum;
}

// Binary descriptors, Hamming distance; centres by bitwise majority (a bit is set when more than
// half of the members have it).
struct BinarySpace {
  using Element = uint64_t;
  int stride = 0;  // 64-bit words per descriptor

  double Distance(const Element* a, const Element* b) const { return Hamming(a, b, stride); }
  int Nearest(const Element* d, const Element* centres, int count) const {
    return NearestBinaryCentre(d, centres, count, stride);
  }
  // k-means++ draws proportionally to D^2 (Arthur and Vassilvitskii 2007).
  static double SeedWeight(double distance) { return distance * distance; }

  void Centre(const std::vector<int>& members, const Element* data, Element* out) const {
    std::vector<int> ones(static_cast<size_t>(stride) * 64, 0);
    for (const int m : members) {
      const Element* d = data + static_cast<size_t>(m) * stride;
      for (int w = 0; w < stride; ++w) {
        uint64_t bits = d[w];
        while (bits) {  // only the set bits: about half of a random descriptor
          ++ones[64 * w + __builtin_ctzll(bits)];
          bits &= bits - 1;
        }
      }
    }
    const size_t half = members.size();
    for (int w = 0; w < stride; ++w) {
      uint64_t value = 0;
      for (int b = 0; b < 64; ++b) {
        if (2 * static_cast<size_t>(ones[64 * w + b]) > half) value |= uint64_t{1} << b;
      }
      out[w] = value;
    }
  }
};

// Float descriptors, squared L2 distance; centres are means (accumulated in double).
struct FloatSpace {
  using Element = float;
  int stride = 0;  // floats per descriptor

  double Distance(const Element* a, const Element* b) const { return SquaredL2(a, b, stride); }
  int Nearest(const Element* d, const Element* centres, int count) const {
    int best = 0;
    float best_distance = std::numeric_limits<float>::infinity();
    for (int c = 0; c < count; ++c) {
      const float distance = SquaredL2(d, centres + static_cast<size_t>(c) * stride, stride);
      if (distance < best_distance) best_distance = distance, best = c;
    }
    return best;
  }
  static double SeedWeight(double squared_distance) { return squared_distance; }

  void Centre(const std::vector<int>& members, const Element* data, Element* out) const {
    std::vector<double> sum(stride, 0.0);
    for (const int m : members) {
      const Element* d = data + static_cast<size_t>(m) * stride;
      for (int i = 0; i < stride; ++i) sum[i] += d[i];
    }
    const double inv = members.empty() ? 0.0 : 1.0 / static_cast<double>(members.size());
    for (int i = 0; i < stride; ++i) out[i] = static_cast<float>(sum[i] * inv);
  }
};

}  // namespace slslam::place_detail
