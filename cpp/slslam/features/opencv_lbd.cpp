#include "slslam/features/opencv_lbd.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include <opencv2/imgproc.hpp>
#include <opencv2/line_descriptor.hpp>

#include "slslam/core/check.h"
#include "slslam/core/cpu_dispatch.h"
#include "slslam/features/gaussian_blur.h"

// (not under a sanitizer, which does not see into the gathers: the scalar loop reads the same
// pixels)
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__)) && !defined(SLSLAM_SANITIZED)
#include <immintrin.h>
#define SLSLAM_LBD_AVX2 1
#endif

namespace slslam {

namespace {

constexpr int kBands = 9;
constexpr int kBandRows = 7;
constexpr int kRows = kBands * kBandRows;  // rows of the support region
constexpr int kHalfRows = (kRows - 1) / 2;
constexpr int kLanes = 8;                                            // rows sampled together
constexpr int kPaddedRows = (kRows + kLanes - 1) / kLanes * kLanes;  // 64: one spare lane
constexpr int kFloats = kBands * 8;

// The band pairs each descriptor byte compares, in OpenCV's order: every pair at most 5 bands
// apart, (0, 6) and (2, 8) excepted and (2, 7), (2, 8), (3, 8) included as it lists them.
constexpr int kBandPairs[32][2] = {{0, 1}, {0, 2}, {0, 3}, {0, 4}, {0, 5}, {0, 6}, {1, 2}, {1, 3},
                                   {1, 4}, {1, 5}, {1, 6}, {2, 3}, {2, 4}, {2, 5}, {2, 6}, {2, 7},
                                   {2, 8}, {3, 4}, {3, 5}, {3, 6}, {3, 7}, {3, 8}, {4, 5}, {4, 6},
                                   {4, 7}, {4, 8}, {5, 6}, {5, 7}, {5, 8}, {6, 7}, {6, 8}, {7, 8}};

// Gaussian weights, computed in double and used as floats as OpenCV does: across the 63 rows
// (centre 31, sigma 31) and over a band and its neighbours (21 rows, centre 10, sigma 7: OpenCV's
// integer (2 w + 1) / 2).
struct Weights {
  std::array<float, kRows> across{};
  std::array<float, 3 * kBandRows> band{};
};

const Weights& GaussianWeights() {
  static const Weights weights = [] {
    Weights w;
    const auto fill = [](float* out, int count, double centre, double sigma) {
      const double inv_two_sigma2 = -1.0 / (2.0 * sigma * sigma);
      for (int i = 0; i < count; ++i) {
        const double d = i - centre;
        out[i] = static_cast<float>(std::exp(d * d * inv_two_sigma2));
      }
    };
    fill(w.across.data(), kRows, kHalfRows, kHalfRows);
    fill(w.band.data(), 3 * kBandRows, (3 * kBandRows - 1) / 2, (2 * kBandRows + 1) / 2);
    return w;
  }();
  return weights;
}

// The four sums of one row of the support region: positive and negative parts of the gradient's
// projections on the segment direction (L) and on its normal (O).
struct RowSums {
  std::array<float, kPaddedRows> pos_l{}, neg_l{}, pos_o{}, neg_o{};
};

// One segment's sampling frame: each row's first sample, the step along the row, the image.
struct Sampling {
  std::array<float, kPaddedRows> x0{}, y0{};
  float dl0 = 0.0f, dl1 = 0.0f;             // direction (cos, sin)
  int length = 0;                           // samples per row
  int width = 0, height = 0;                // image size [px]
  const std::int16_t* gradients = nullptr;  // (dx, dy) int16 pairs, row-major
};

// Nearest pixel, OpenCV's rounding (half away from zero) and clamp to [0, max]; the truncation
// then the fraction's comparison is exact for image coordinates, and negative values clamp to 0
// either way.
inline int RoundClamp(float v, int max) {
  const int t = static_cast<int>(v);
  const int r = t + (v - static_cast<float>(t) >= 0.5f ? 1 : 0);
  return r < 0 ? 0 : (r > max ? max : r);
}

void SampleRowsScalar(const Sampling& s, int first_row, RowSums* sums) {
  const float do0 = -s.dl1, do1 = s.dl0;
  for (int h = first_row; h < first_row + kLanes; ++h) {
    float x = s.x0[h], y = s.y0[h];
    float pl = 0.0f, nl = 0.0f, po = 0.0f, no = 0.0f;
    for (int w = 0; w < s.length; ++w) {
      const std::int16_t* g =
          s.gradients + 2 * (RoundClamp(y, s.height - 1) * s.width + RoundClamp(x, s.width - 1));
      const float dx = static_cast<float>(g[0]);
      const float dy = static_cast<float>(g[1]);
      const float gl = dx * s.dl0 + dy * s.dl1;
      const float go = dx * do0 + dy * do1;
      if (gl > 0.0f) {
        pl += gl;
      } else {
        nl -= gl;
      }
      if (go > 0.0f) {
        po += go;
      } else {
        no -= go;
      }
      x += s.dl0;
      y += s.dl1;
    }
    sums->pos_l[h] = pl;
    sums->neg_l[h] = nl;
    sums->pos_o[h] = po;
    sums->neg_o[h] = no;
  }
}

#ifdef SLSLAM_LBD_AVX2
// RoundClamp on eight lanes.
__attribute__((target("avx2"))) inline __m256i RoundClampAvx2(__m256 v, __m256i max) {
  const __m256i t = _mm256_cvttps_epi32(v);
  const __m256 frac = _mm256_sub_ps(v, _mm256_cvtepi32_ps(t));
  const __m256i up = _mm256_castps_si256(_mm256_cmp_ps(frac, _mm256_set1_ps(0.5f), _CMP_GE_OQ));
  const __m256i r = _mm256_sub_epi32(t, up);  // a true lane is -1
  return _mm256_min_epi32(_mm256_max_epi32(r, _mm256_setzero_si256()), max);
}

// Eight rows at once, each lane the scalar loop's operations in the same order (a multiply then
// an add, never fused; a masked add of 0 leaves a sum unchanged).
__attribute__((target("avx2"))) void SampleRowsAvx2(const Sampling& s, int first_row,
                                                    RowSums* sums) {
  const __m256 dl0 = _mm256_set1_ps(s.dl0), dl1 = _mm256_set1_ps(s.dl1);
  const __m256 do0 = _mm256_set1_ps(-s.dl1), do1 = dl0;
  const __m256 zero = _mm256_setzero_ps();
  const __m256i max_x = _mm256_set1_epi32(s.width - 1), max_y = _mm256_set1_epi32(s.height - 1);
  const __m256i stride = _mm256_set1_epi32(s.width);
  __m256 x = _mm256_loadu_ps(&s.x0[first_row]), y = _mm256_loadu_ps(&s.y0[first_row]);
  __m256 pl = zero, nl = zero, po = zero, no = zero;
  // (one 32-bit lane a pixel: dx in the low half, x86 being little-endian)
  const int* base = reinterpret_cast<const int*>(s.gradients);
  for (int w = 0; w < s.length; ++w) {
    const __m256i index = _mm256_add_epi32(_mm256_mullo_epi32(RoundClampAvx2(y, max_y), stride),
                                           RoundClampAvx2(x, max_x));
    const __m256i v = _mm256_i32gather_epi32(base, index, 4);
    const __m256 dx = _mm256_cvtepi32_ps(_mm256_srai_epi32(_mm256_slli_epi32(v, 16), 16));
    const __m256 dy = _mm256_cvtepi32_ps(_mm256_srai_epi32(v, 16));
    const __m256 gl = _mm256_add_ps(_mm256_mul_ps(dx, dl0), _mm256_mul_ps(dy, dl1));
    const __m256 go = _mm256_add_ps(_mm256_mul_ps(dx, do0), _mm256_mul_ps(dy, do1));
    const __m256 l_pos = _mm256_cmp_ps(gl, zero, _CMP_GT_OQ);
    const __m256 o_pos = _mm256_cmp_ps(go, zero, _CMP_GT_OQ);
    pl = _mm256_add_ps(pl, _mm256_and_ps(l_pos, gl));
    nl = _mm256_sub_ps(nl, _mm256_andnot_ps(l_pos, gl));
    po = _mm256_add_ps(po, _mm256_and_ps(o_pos, go));
    no = _mm256_sub_ps(no, _mm256_andnot_ps(o_pos, go));
    x = _mm256_add_ps(x, dl0);
    y = _mm256_add_ps(y, dl1);
  }
  _mm256_storeu_ps(&sums->pos_l[first_row], pl);
  _mm256_storeu_ps(&sums->neg_l[first_row], nl);
  _mm256_storeu_ps(&sums->pos_o[first_row], po);
  _mm256_storeu_ps(&sums->neg_o[first_row], no);
}

bool HasAvx2() {
  static const bool has = __builtin_cpu_supports("avx2");
  return has;
}
#endif

void SampleRows(const Sampling& s, bool simd, RowSums* sums) {
  for (int first = 0; first < kPaddedRows; first += kLanes) {
#ifdef SLSLAM_LBD_AVX2
    if (simd && HasAvx2()) {
      SampleRowsAvx2(s, first, sums);
      continue;
    }
#else
    (void)simd;
#endif
    SampleRowsScalar(s, first, sums);
  }
}

// The 72 floats of one segment from its row sums, in OpenCV's order of operations.
std::array<float, kFloats> BandVector(const RowSums& rows) {
  const Weights& g = GaussianWeights();
  std::array<float, kBands> pl{}, nl{}, pl2{}, nl2{}, po{}, no{}, po2{}, no2{};
  for (int h = 0; h < kRows; ++h) {
    const float c = g.across[h];
    const float rpl = c * rows.pos_l[h], rnl = c * rows.neg_l[h];
    const float rpo = c * rows.pos_o[h], rno = c * rows.neg_o[h];
    const float rpl2 = rpl * rpl, rnl2 = rnl * rnl, rpo2 = rpo * rpo, rno2 = rno * rno;
    const auto add = [&](int band, float cb) {
      pl[band] += cb * rpl;
      nl[band] += cb * rnl;
      pl2[band] += cb * cb * rpl2;
      nl2[band] += cb * cb * rnl2;
      po[band] += cb * rpo;
      no[band] += cb * rno;
      po2[band] += cb * cb * rpo2;
      no2[band] += cb * cb * rno2;
    };
    const int band = h / kBandRows, in_band = h % kBandRows;
    add(band, g.band[in_band + kBandRows]);                             // its own band
    if (band - 1 >= 0) add(band - 1, g.band[in_band + 2 * kBandRows]);  // the band above
    if (band + 1 < kBands) add(band + 1, g.band[in_band]);              // the band below
  }
  std::array<float, kFloats> d{};
  const float inv_n2 = static_cast<float>(1.0 / (kBandRows * 2.0));  // first and last band
  const float inv_n3 = static_cast<float>(1.0 / (kBandRows * 3.0));
  for (int b = 0; b < kBands; ++b) {
    const float inv_n = (b == 0 || b == kBands - 1) ? inv_n2 : inv_n3;
    const auto mean_dev = [&](float sum, float sum2, int at) {
      const float mean = sum * inv_n;
      d[8 * b + at] = mean;
      d[8 * b + at + 4] = std::sqrt(sum2 * inv_n - mean * mean);
    };
    mean_dev(pl[b], pl2[b], 0);
    mean_dev(nl[b], nl2[b], 1);
    mean_dev(po[b], po2[b], 2);
    mean_dev(no[b], no2[b], 3);
  }
  // Means and deviations normalised apart, clipped at 0.4 (compared in double), normalised
  // together.
  const auto inverse_norm = [](float sum2) { return 1.0f / std::sqrt(sum2); };
  float means2 = 0.0f, devs2 = 0.0f;
  for (int b = 0; b < kBands; ++b) {
    for (int k = 0; k < 4; ++k) means2 += d[8 * b + k] * d[8 * b + k];
    for (int k = 4; k < 8; ++k) devs2 += d[8 * b + k] * d[8 * b + k];
  }
  const float inv_means = inverse_norm(means2), inv_devs = inverse_norm(devs2);
  for (int b = 0; b < kBands; ++b) {
    for (int k = 0; k < 4; ++k) d[8 * b + k] = d[8 * b + k] * inv_means;
    for (int k = 4; k < 8; ++k) d[8 * b + k] = d[8 * b + k] * inv_devs;
  }
  float all2 = 0.0f;
  for (float& v : d) {
    if (static_cast<double>(v) > 0.4) v = 0.4f;
  }
  for (const float v : d) all2 += v * v;
  const float inv_all = inverse_norm(all2);
  for (float& v : d) v = v * inv_all;
  return d;
}

}  // namespace

namespace {

// The 72 floats of each segment (`floats`, CV_32F rows) or its 32 bytes (`bytes`, CV_8U rows).
void Describe(const cv::Mat& image, const Segments& segments, bool simd, cv::Mat* floats,
              cv::Mat* bytes) {
  Require(!image.empty() && image.type() == CV_8UC1, "LBD needs a non-empty 8-bit gray image");
  const int n = static_cast<int>(segments.size());
  if (floats) floats->create(n, kFloats, CV_32F);
  if (bytes) bytes->create(n, 32, CV_8U);
  if (segments.empty()) return;
  // The gradients OpenCV's compute takes: 5 x 5 Gaussian (sigma 1), 3 x 3 Sobel, int16; here
  // interleaved so that one 32-bit load gives a pixel's (dx, dy).
  // (cv::GaussianBlur's pixels, on one thread at a fraction of its CPU: features/gaussian_blur.h)
  const cv::Mat smooth = GaussianBlurAsOpenCv(image, 1.0, 2);
  cv::Mat gradients;
  opencv_lbd_detail::InterleavedSobel(smooth, &gradients);
  Require(gradients.isContinuous(), "LBD gradients must be one block");

  Sampling s;
  s.width = image.cols;
  s.height = image.rows;
  s.gradients = gradients.ptr<std::int16_t>();
  RowSums rows;
  constexpr float kHalfRowsF = static_cast<float>(kHalfRows);
  for (size_t i = 0; i < segments.size(); ++i) {
    const LineSegment& seg = segments[i];
    Require(seg.start.x() >= 0.0f && seg.start.y() >= 0.0f && seg.end.x() >= 0.0f &&
                seg.end.y() >= 0.0f && seg.start.x() <= image.cols - 1.0f &&
                seg.end.x() <= image.cols - 1.0f && seg.start.y() <= image.rows - 1.0f &&
                seg.end.y() <= image.rows - 1.0f,
            "LBD needs segments inside the image");
    const float angle = std::atan2(seg.end.y() - seg.start.y(), seg.end.x() - seg.start.x());
    // cos / sin in float, n = (int) length (the double versions of cos, sin and of the inverse
    // square roots below change the floats in the last bit: the test tells them apart).
    s.dl0 = std::cos(angle);
    s.dl1 = std::sin(angle);
    s.length = static_cast<int>(seg.Length());
    const int half_length = (s.length - 1) / 2;
    const float mid_x = static_cast<float>(0.5 * (seg.start.x() + seg.end.x()));
    const float mid_y = static_cast<float>(0.5 * (seg.start.y() + seg.end.y()));
    const float hw = static_cast<float>(half_length);
    // Each row's first sample, one row further along the normal each time (OpenCV's running
    // sums, in its order).
    float x0 = -s.dl0 * hw + s.dl1 * kHalfRowsF + mid_x;
    float y0 = -s.dl1 * hw - s.dl0 * kHalfRowsF + mid_y;
    for (int h = 0; h < kPaddedRows; ++h) {
      s.x0[h] = x0;
      s.y0[h] = y0;
      x0 -= s.dl1;
      y0 += s.dl0;
    }
    SampleRows(s, simd, &rows);
    const std::array<float, kFloats> d = BandVector(rows);
    if (floats) std::copy(d.begin(), d.end(), floats->ptr<float>(static_cast<int>(i)));
    if (!bytes) continue;
    std::uint8_t* out = bytes->ptr<std::uint8_t>(static_cast<int>(i));
    for (int p = 0; p < 32; ++p) {
      const float* a = &d[8 * kBandPairs[p][0]];
      const float* b = &d[8 * kBandPairs[p][1]];
      std::uint8_t byte = 0;
      for (int k = 0; k < 8; ++k) byte |= static_cast<std::uint8_t>((a[k] > b[k] ? 1 : 0) << k);
      out[p] = byte;
    }
  }
}

}  // namespace

namespace opencv_lbd_detail {

namespace {

// One row of (dx, dy) for the columns [begin, end), given the rows above and below (reflected at
// the image's edge by the caller). GCC vectorises the interleaved stores at -O3 (the build's).
SLSLAM_AVX2_CLONES
void SobelRowInterior(const std::uint8_t* above, const std::uint8_t* row, const std::uint8_t* below,
                      int begin, int end, std::int16_t* out) {
  for (int x = begin; x < end; ++x) {
    const int left = above[x - 1] + 2 * row[x - 1] + below[x - 1];
    const int right = above[x + 1] + 2 * row[x + 1] + below[x + 1];
    const int up = above[x - 1] + 2 * above[x] + above[x + 1];
    const int down = below[x - 1] + 2 * below[x] + below[x + 1];
    out[2 * x] = static_cast<std::int16_t>(right - left);
    out[2 * x + 1] = static_cast<std::int16_t>(down - up);
  }
}

// cv::Sobel's default border: -1 -> 1, n -> n - 2 (0 for a single pixel).
int Reflect101(int i, int n) { return cv::borderInterpolate(i, n, cv::BORDER_REFLECT_101); }

}  // namespace

void InterleavedSobel(const cv::Mat& image, cv::Mat* gradients) {
  Require(!image.empty() && image.type() == CV_8UC1, "Sobel needs a non-empty 8-bit gray image");
  const int w = image.cols, h = image.rows;
  gradients->create(h, w, CV_16SC2);
  for (int y = 0; y < h; ++y) {
    const std::uint8_t* above = image.ptr<std::uint8_t>(Reflect101(y - 1, h));
    const std::uint8_t* row = image.ptr<std::uint8_t>(y);
    const std::uint8_t* below = image.ptr<std::uint8_t>(Reflect101(y + 1, h));
    std::int16_t* out = gradients->ptr<std::int16_t>(y);
    if (w >= 3) SobelRowInterior(above, row, below, 1, w - 1, out);
    for (const int x : {0, w - 1}) {  // the edge columns, reflected
      const int l = Reflect101(x - 1, w), r = Reflect101(x + 1, w);
      const int left = above[l] + 2 * row[l] + below[l];
      const int right = above[r] + 2 * row[r] + below[r];
      const int up = above[l] + 2 * above[x] + above[r];
      const int down = below[l] + 2 * below[x] + below[r];
      out[2 * x] = static_cast<std::int16_t>(right - left);
      out[2 * x + 1] = static_cast<std::int16_t>(down - up);
    }
  }
}

}  // namespace opencv_lbd_detail

cv::Mat ComputeOpenCvCompatibleLbd(const cv::Mat& image, const Segments& segments, bool simd) {
  cv::Mat bytes;
  Describe(image, segments, simd, nullptr, &bytes);
  return bytes;
}

cv::Mat ComputeOpenCvCompatibleLbdFloat(const cv::Mat& image, const Segments& segments, bool simd) {
  cv::Mat floats;
  Describe(image, segments, simd, &floats, nullptr);
  return floats;
}

cv::Mat ComputeOpenCvLbdReference(const cv::Mat& image, const Segments& segments, bool floats) {
  namespace ld = cv::line_descriptor;
  if (segments.empty()) return cv::Mat(0, floats ? kFloats : 32, floats ? CV_32F : CV_8U);
  std::vector<ld::KeyLine> keylines(segments.size());
  const float max_side = static_cast<float>(std::max(image.cols, image.rows));
  for (size_t i = 0; i < segments.size(); ++i) {
    const LineSegment& s = segments[i];
    ld::KeyLine& k = keylines[i];
    k.startPointX = k.sPointInOctaveX = s.start.x();
    k.startPointY = k.sPointInOctaveY = s.start.y();
    k.endPointX = k.ePointInOctaveX = s.end.x();
    k.endPointY = k.ePointInOctaveY = s.end.y();
    k.lineLength = s.Length();
    k.angle = std::atan2(s.end.y() - s.start.y(), s.end.x() - s.start.x());
    k.pt = cv::Point2f(0.5f * (s.start.x() + s.end.x()), 0.5f * (s.start.y() + s.end.y()));
    k.octave = 0;
    k.class_id = static_cast<int>(i);
    k.response = k.lineLength / max_side;
    k.size = k.lineLength;
    k.numOfPixels = static_cast<int>(k.lineLength);
  }
  cv::Mat descriptors;
  ld::BinaryDescriptor::createBinaryDescriptor()->compute(image, keylines, descriptors, floats);
  Require(descriptors.rows == static_cast<int>(segments.size()),
          "LBD dropped segments; give segments inside the image");
  return descriptors;
}

}  // namespace slslam
