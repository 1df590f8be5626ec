// dps — errors.
//
// Bad user input (files, flags, options) is reported by throwing dps::Error with a one-line
// message that names the file, the field and what was expected. Tools print what() and exit
// non-zero. Per-pixel failures never throw; they use validity flags (see camera_model.h).
#pragma once

#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

namespace dps {

// An error in user input: a file, a field in it, a flag or an option value.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

// Concatenates its arguments with operator<< into a string.
template <typename... Args>
std::string Str(Args&&... args) {
  std::ostringstream out;
  out.precision(10);
  (out << ... << std::forward<Args>(args));
  return out.str();
}

}  // namespace dps
