// OpenCV's YAML parser (4.6) loops forever on some malformed files; a batch must not stall on one.
// The file is parsed first in a child process that is given a time limit.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <thread>

#include <opencv2/core.hpp>

#include "dps/util/error.h"
#include "util/yaml_fields.h"

namespace dps::internal {

void RequireParserFinishes(const std::string& path, double seconds) {
  const pid_t child = ::fork();
  if (child < 0) return;  // no process to spare: parse in this one, unguarded
  if (child == 0) {
    int status = 1;
    try {
      cv::FileStorage fs(path, cv::FileStorage::READ);
      status = fs.isOpened() ? 0 : 1;
    } catch (...) {
      status = 2;
    }
    ::_exit(status);
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  int status = 0;
  for (auto wait = std::chrono::microseconds(200);; wait = std::min(wait * 2, std::chrono::microseconds(20000))) {
    const pid_t done = ::waitpid(child, &status, WNOHANG);
    if (done == child || (done < 0 && errno != EINTR)) return;  // finished (the real parse reports errors)
    if (std::chrono::steady_clock::now() > deadline) break;
    std::this_thread::sleep_for(wait);
  }
  ::kill(child, SIGKILL);
  ::waitpid(child, &status, 0);
  throw Error(Str(path, ": the YAML parser did not finish within ", seconds, " s; the file is malformed"));
}

}  // namespace dps::internal
