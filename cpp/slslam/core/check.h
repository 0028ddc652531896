// Argument and state checks that throw instead of aborting: a library never exits the process.
#pragma once

#include <sstream>
#include <stdexcept>
#include <string>

namespace slslam {

// Throws std::invalid_argument with `message` when `condition` is false. Bound to Python's
// ValueError by pybind11, so a bad input reaches the user as one readable line.
inline void Require(bool condition, const std::string& message) {
  if (!condition) throw std::invalid_argument(message);
}

// Builds a message from streamable parts: Require(ok, Message("width ", w, " != ", expected)).
template <typename... Parts>
std::string Message(const Parts&... parts) {
  std::ostringstream out;
  (out << ... << parts);
  return out.str();
}

}  // namespace slslam
