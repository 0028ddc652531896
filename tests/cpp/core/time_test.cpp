#include "slslam/core/time.h"

#include <cmath>
#include <cstdint>

#include <gtest/gtest.h>

namespace slslam {
namespace {

constexpr int64_t kUnixNs = 1'403'715'273'262'142'000;  // a EuRoC stamp

TEST(Time, DifferencesAreExactAtAUnixClock) {
  EXPECT_EQ(SecondsBetween(kUnixNs, kUnixNs + 500'000'000), 0.5);
  EXPECT_EQ(SecondsBetween(kUnixNs, kUnixNs + 50'000'000), 0.05);
  EXPECT_EQ(SecondsBetween(kUnixNs + 1, kUnixNs), -1e-9);
  // The same difference from float seconds: off by the stamps' rounding (hundreds of ns).
  const double t0 = static_cast<double>(kUnixNs) * 1e-9;
  const double t1 = static_cast<double>(kUnixNs + 50'000'000) * 1e-9;
  EXPECT_GT(std::abs((t1 - t0) - 0.05), 1e-8);
}

TEST(Time, SecondsConvertToTheNearestNanosecond) {
  EXPECT_EQ(NsFromSeconds(0.05), 50'000'000);
  EXPECT_EQ(NsFromSeconds(-0.0025), -2'500'000);
  EXPECT_EQ(NsFromSeconds(1403715273.25), 1'403'715'273'250'000'000);
  // A Unix time in float seconds holds it to 238 ns; the conversion adds no error of its own.
  const double s = Seconds(kUnixNs);
  EXPECT_LE(std::abs(NsFromSeconds(s) - kUnixNs), 119);
  EXPECT_EQ(Seconds(1'403'715'273'250'000'000), 1403715273.25);
  EXPECT_EQ(Seconds(-1'500'000'000), -1.5);
  for (int64_t t : {int64_t{0}, int64_t{1}, int64_t{999'999'999}, kUnixNs, -kUnixNs}) {
    EXPECT_LE(std::abs(NsFromSeconds(Seconds(t)) - t), 119) << t;
  }
}

}  // namespace
}  // namespace slslam
