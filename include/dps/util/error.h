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

// The check of an options struct's fields, for its Check(): `const OptionCheck Require("tracker");`
// then Require(ok, "field", value, "constraint") throws Error("tracker option field = value:
// violated constraint constraint") unless ok.
class OptionCheck {
 public:
  explicit OptionCheck(const char* what) : what_(what) {}
  void operator()(bool ok, const char* field, double value, const char* constraint) const {
    if (!ok) throw Error(Str(what_, " option ", field, " = ", value, ": violated constraint ", constraint));
  }

 private:
  const char* what_;
};

}  // namespace dps
