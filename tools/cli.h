// dps tools — a small command-line parser shared by the tools (no third-party library).
//
// Options are `--name value` or `--name=value`; flags are `--name`; everything else is
// positional. Unknown options are errors. Tools print `Usage()` for --help.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/core/utils/logger.hpp>

#include "dps/util/error.h"

namespace dps_cli {

class Args {
 public:
  // `with_value`: options that take a value; `flags`: options that do not.
  Args(int argc, char** argv, const std::set<std::string>& with_value,
       const std::set<std::string>& flags) {
    for (int i = 1; i < argc; ++i) {
      std::string a = argv[i];
      if (a.rfind("--", 0) != 0 || a == "--") {
        positional_.push_back(a);
        continue;
      }
      std::string name = a.substr(2), value;
      const size_t eq = name.find('=');
      const bool inline_value = eq != std::string::npos;
      if (inline_value) {
        value = name.substr(eq + 1);
        name = name.substr(0, eq);
      }
      if (name == "help" || name == "h") {
        help_ = true;
      } else if (flags.count(name)) {
        if (inline_value) throw dps::Error("option --" + name + " takes no value");
        values_[name] = "1";
      } else if (with_value.count(name)) {
        if (!inline_value) {
          if (i + 1 >= argc) throw dps::Error("option --" + name + " needs a value");
          value = argv[++i];
        }
        values_[name] = value;
      } else {
        throw dps::Error("unknown option --" + name + " (see --help)");
      }
    }
  }

  bool help() const { return help_; }
  bool Has(const std::string& name) const { return values_.count(name) > 0; }
  // A required option: "missing --name VALUE (see --help)" when it is absent (`value` names its
  // value, e.g. "DIR"; empty: none named).
  void Require(const std::string& name, const std::string& value = "") const {
    if (!Has(name)) throw dps::Error("missing --" + name + (value.empty() ? "" : " " + value) + " (see --help)");
  }
  std::string Get(const std::string& name, const std::string& fallback = "") const {
    const auto it = values_.find(name);
    return it == values_.end() ? fallback : it->second;
  }
  double Number(const std::string& name, double fallback) const {
    if (!Has(name)) return fallback;
    char* end = nullptr;
    const std::string v = Get(name);
    const double d = std::strtod(v.c_str(), &end);
    if (v.empty() || *end != '\0') throw dps::Error("option --" + name + ": expected a number, got '" + v + "'");
    return d;
  }
  int Integer(const std::string& name, int fallback) const {
    const double d = Number(name, fallback);
    if (d != static_cast<int>(d)) throw dps::Error("option --" + name + ": expected an integer");
    return static_cast<int>(d);
  }
  const std::vector<std::string>& positional() const { return positional_; }
  // An image size "WxH" (each at least min_px), or the fallback when the option is absent.
  cv::Size Size(const std::string& name, cv::Size fallback, int min_px = 1) const {
    if (!Has(name)) return fallback;
    const std::string v = Get(name);
    int w = 0, h = 0;
    char x = 0, extra = 0;
    if (std::sscanf(v.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || x != 'x' || w < min_px || h < min_px ||
        w > 65536 || h > 65536) {
      throw dps::Error("option --" + name + ": expected WxH, e.g. 640x480, got '" + v + "'");
    }
    return {w, h};
  }
  // "left=a.png,right=b.png" -> {(left, a.png), (right, b.png)}; `what` names the value in the
  // error ("IMAGE"). Empty when the option is absent.
  std::vector<std::pair<std::string, std::string>> Pairs(const std::string& name, const std::string& what) const {
    std::vector<std::pair<std::string, std::string>> out;
    if (!Has(name)) return out;
    std::stringstream ss(Get(name));
    for (std::string item; std::getline(ss, item, ',');) {
      const size_t eq = item.find('=');
      if (eq == std::string::npos || eq == 0 || eq + 1 == item.size()) {
        throw dps::Error("option --" + name + ": expected CAMERA=" + what + ", got '" + item + "'");
      }
      out.emplace_back(item.substr(0, eq), item.substr(eq + 1));
    }
    if (out.empty()) throw dps::Error("option --" + name + ": nothing given");
    return out;
  }

 private:
  bool help_ = false;
  std::map<std::string, std::string> values_;
  std::vector<std::string> positional_;
};

// Runs a tool's body, printing any error as one line "tool: error: message" and returning 1.
template <typename Body>
int Run(const char* tool, Body&& body) {
  // The tools report what went wrong themselves, in one line; OpenCV's own messages (imread's
  // warning on a missing file, a video backend's error while probing a file that is no video)
  // would add lines before it.
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
  try {
    return body();
  } catch (const std::exception& e) {
    std::cerr << tool << ": error: " << e.what() << std::endl;
    return 1;
  }
}

}  // namespace dps_cli
