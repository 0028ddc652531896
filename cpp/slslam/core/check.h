// Argument and state checks that throw instead of aborting: a library never exits the process.
//
// Checks run in hot paths (every residual evaluation, every matched keypoint), so a passing check
// must cost a comparison and nothing else: SLSLAM_CHECK builds its message only when the
// condition fails, and Require with a string literal allocates nothing.
#pragma once

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace slslam {

// Throws std::invalid_argument with `message` when `condition` is false. Bound to Python's
// ValueError by pybind11, so a bad input reaches the user as one readable line.
inline void Require(bool condition, const char* message) {
  if (!condition) throw std::invalid_argument(message);
}
inline void Require(bool condition, const std::string& message) {
  if (!condition) throw std::invalid_argument(message);
}

// Builds a message from streamable parts: Message("width ", w, " != ", expected).
template <typename... Parts>
std::string Message(const Parts&... parts) {
  std::ostringstream out;
  (out << ... << parts);
  return out.str();
}

[[noreturn]] inline void ThrowInvalidArgument(const std::string& message) {
  throw std::invalid_argument(message);
}

// Practical ceilings shared by the options' Check()s: far above any sensible value, low enough
// that no allocation, cast to int or product of two of them overflows.
namespace limits {
inline constexpr int kMaxKeypoints = 1'000'000;        ///< per image, per cell, per vote [-]
inline constexpr int kMaxCellSizePx = 1 << 16;         ///< grid cells [px]
inline constexpr float kMaxImageDistancePx = 1e5f;     ///< windows and distances in an image [px]
inline constexpr float kMaxDescriptorDistance = 1e6f;  ///< Hamming bits or L2 [-]
inline constexpr float kLbdBits = 256.0f;              ///< length of an LBD descriptor [bits]
inline constexpr float kPi = 3.14159265358979f;
}  // namespace limits

// Option range checks, called by the options' Check(): each names the option ("orb.num_levels
// must be in [1, 32], got 0") and builds its message only on failure. NaN fails every check; an
// infinity fails unless the bound it meets is itself infinite.
template <typename T, typename Low, typename High>
void CheckInRange(const char* name, T value, Low low, High high) {
  if (!(value >= static_cast<T>(low) && value <= static_cast<T>(high))) {
    ThrowInvalidArgument(Message(name, " must be in [", low, ", ", high, "], got ", value));
  }
}

// (low, high]: sizes, sigmas, ratios that must stay above a bound they may not reach.
template <typename T, typename Low, typename High>
void CheckAboveInRange(const char* name, T value, Low low, High high) {
  if (!(value > static_cast<T>(low) && value <= static_cast<T>(high))) {
    ThrowInvalidArgument(Message(name, " must be in (", low, ", ", high, "], got ", value));
  }
}

// Any finite value (an option whose sign carries a meaning, e.g. "<= 0: off").
template <typename T>
void CheckFinite(const char* name, T value) {
  if (!std::isfinite(static_cast<double>(value)))
    ThrowInvalidArgument(Message(name, " must be finite, got ", value));
}

}  // namespace slslam

// SLSLAM_CHECK(condition, parts...): throws std::invalid_argument(Message(parts...)) when the
// condition is false; the parts are not evaluated when it holds.
#define SLSLAM_CHECK(condition, ...)                                                  \
  do {                                                                                \
    if (!(condition)) ::slslam::ThrowInvalidArgument(::slslam::Message(__VA_ARGS__)); \
  } while (false)
