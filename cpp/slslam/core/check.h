// Argument and state checks that throw instead of aborting: a library never exits the process.
//
// Checks run in hot paths (every residual evaluation, every matched keypoint), so a passing check
// must cost a comparison and nothing else: SLSLAM_CHECK builds its message only when the
// condition fails, and Require with a string literal allocates nothing.
#pragma once

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

}  // namespace slslam

// SLSLAM_CHECK(condition, parts...): throws std::invalid_argument(Message(parts...)) when the
// condition is false; the parts are not evaluated when it holds.
#define SLSLAM_CHECK(condition, ...)                                                  \
  do {                                                                                \
    if (!(condition)) ::slslam::ThrowInvalidArgument(::slslam::Message(__VA_ARGS__)); \
  } while (false)
