// OpenCV's YAML parser (4.6) loops forever on some malformed files; a batch must not stall on one.
// The file is parsed on a thread of its own that is given a time limit. (A child process would
// isolate the loop better, but fork() in a process whose other threads hold locks - the batch's
// workers, OpenCV's pool, the sanitizers' allocator - can leave the child deadlocked on a good
// file.)
#include <chrono>
#include <condition_variable>
#include <exception>
#include <memory>
#include <mutex>
#include <thread>

#include "dps/util/error.h"
#include "util/yaml_fields.h"

namespace dps::internal {

cv::FileStorage OpenWithin(const std::string& path, double seconds) {
  struct Outcome {
    std::mutex mutex;
    std::condition_variable finished;
    bool done = false;
    cv::FileStorage fs;
    std::exception_ptr error;
  };
  auto outcome = std::make_shared<Outcome>();
  std::thread([outcome, path] {
    cv::FileStorage fs;
    std::exception_ptr error;
    try {
      fs.open(path, cv::FileStorage::READ);
    } catch (...) {
      error = std::current_exception();
    }
    std::lock_guard<std::mutex> lock(outcome->mutex);
    outcome->fs = std::move(fs);
    outcome->error = error;
    outcome->done = true;
    outcome->finished.notify_all();
  }).detach();
  std::unique_lock<std::mutex> lock(outcome->mutex);
  if (!outcome->finished.wait_for(lock, std::chrono::duration<double>(seconds), [&] { return outcome->done; })) {
    // The parser thread cannot be stopped; it is left looping (one core) until the process ends.
    throw Error(Str(path, ": the YAML parser did not finish within ", seconds, " s; the file is malformed"));
  }
  if (outcome->error) std::rethrow_exception(outcome->error);
  return std::move(outcome->fs);
}

}  // namespace dps::internal
