// Time in the library: an instant is an int64 count of nanoseconds (`t_ns`, on the sensor's
// clock: a dataset's stamps, Unix time for KITTI raw and bags), exact however large it is; a
// duration that enters arithmetic (an IMU interval, a window length, an option) is double
// seconds (`_s`). These helpers convert between the two in one place.
#pragma once

#include <cmath>
#include <cstdint>

namespace slslam {

inline constexpr double kNanosecondsPerSecond = 1e9;

// t1_ns - t0_ns in seconds: the difference is taken exactly in integers first, then divided
// (correctly rounded: 500'000'000 ns is exactly 0.5 s).
inline double SecondsBetween(int64_t t0_ns, int64_t t1_ns) {
  return static_cast<double>(t1_ns - t0_ns) / kNanosecondsPerSecond;
}

// Seconds (an instant or a duration) as nanoseconds: the nanosecond nearest the double's value.
// The whole seconds and the fraction are converted apart (s * 1e9 itself is off by up to 128 ns
// at a Unix time). For |t_s| below about 9.2e9 s (callers check a range first).
inline int64_t NsFromSeconds(double t_s) {
  const double whole = std::floor(t_s);
  return static_cast<int64_t>(whole) * 1'000'000'000 +
         static_cast<int64_t>(std::llround((t_s - whole) * kNanosecondsPerSecond));
}

// An instant in seconds on the same clock (for logs and float-second formats): whole seconds
// and the remainder apart, so the result is within a rounding of t_ns (a cast of t_ns to double
// first would round a Unix time to 256 ns).
inline double Seconds(int64_t t_ns) {
  const int64_t whole = t_ns / 1'000'000'000;
  const int64_t rest = t_ns % 1'000'000'000;
  return static_cast<double>(whole) + static_cast<double>(rest) / kNanosecondsPerSecond;
}

}  // namespace slslam
