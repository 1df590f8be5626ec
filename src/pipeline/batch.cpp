#include "dps/pipeline/batch.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
#include <mutex>
#include <thread>

#include "dps/util/atomic_file.h"
#include "dps/util/error.h"

namespace dps {
namespace {

using Clock = std::chrono::steady_clock;
double SecondsSince(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// The state the workers share: the next drive to take, the counts, and each drive's fraction
// done (for the batch's ETA), all reported under one lock.
class Batch {
 public:
  // shared: the drives (by index) whose output folder another drive of the whole list has, with
  // that drive.
  Batch(const std::vector<std::string>& drives, const BatchOptions& options, const BatchEvents& events,
        std::map<size_t, std::string> shared)
      : drives_(drives), options_(options), events_(events), fraction_(drives.size(), 0.0), shared_(std::move(shared)) {}

  void Work() {
    for (size_t i = next_++; i < drives_.size(); i = next_++) Process(i);
  }

  BatchResult result() const { return {processed_.load(), skipped_.load(), failed_.load()}; }

 private:
  void Process(size_t i) {
    const std::string& drive = drives_[i];
    const std::string out_dir = DriveOutputDir(drive, options_.out_root);
    const auto shared = shared_.find(i);
    if (shared != shared_.end()) {
      ++failed_;
      std::lock_guard<std::mutex> lock(mutex_);
      fraction_[i] = 1.0;
      if (events_.failed) {
        events_.failed(drive, Str(drive, ": its output ", out_dir, " would also be that of ", shared->second,
                                  " (two drives of one folder name); neither is processed"));
      }
      return;
    }
    if (!options_.force && DriveOutputComplete(out_dir)) {
      ++skipped_;
      std::lock_guard<std::mutex> lock(mutex_);
      fraction_[i] = 1.0;
      if (events_.skipped) events_.skipped(out_dir);
      return;
    }
    const auto start = Clock::now();
    const auto progress = [&](int f, int total) { Progress(i, start, f, total); };
    try {
      const DriveSummary s = ProcessDrive(drive, options_.out_root, options_.drive, progress);
      ++processed_;
      std::lock_guard<std::mutex> lock(mutex_);
      fraction_[i] = 1.0;
      if (events_.finished) events_.finished(s);
    } catch (const std::exception& e) {
      ++failed_;
      std::lock_guard<std::mutex> lock(mutex_);
      fraction_[i] = 1.0;
      if (events_.failed) events_.failed(drive, e.what());
    }
  }

  void Progress(size_t i, Clock::time_point start, int f, int total) {
    BatchProgress p;
    p.index = i + 1;
    p.count = drives_.size();
    p.drive = drives_[i];
    p.frame = f;
    p.frames = total;
    p.frames_per_second = f / std::max(SecondsSince(start), 1e-9);
    p.drive_eta_s = (total - f) / std::max(p.frames_per_second, 1e-9);
    std::lock_guard<std::mutex> lock(mutex_);
    fraction_[i] = total > 0 ? static_cast<double>(f) / total : 1.0;
    double sum = 0;
    for (const double x : fraction_) sum += x;
    const double share = sum / std::max<size_t>(1, fraction_.size());
    p.batch_eta_s = share > 0 ? SecondsSince(batch_start_) * (1 - share) / share : 0.0;
    if (events_.progress) events_.progress(p);
  }

  const std::vector<std::string>& drives_;
  const BatchOptions& options_;
  const BatchEvents& events_;
  const Clock::time_point batch_start_ = Clock::now();
  std::atomic<size_t> next_{0};
  std::atomic<int> processed_{0}, skipped_{0}, failed_{0};
  std::mutex mutex_;
  std::vector<double> fraction_;
  const std::map<size_t, std::string> shared_;
};

}  // namespace

void BatchOptions::Check() const {
  if (out_root.empty()) throw Error("batch option out_root: empty");
  const OptionCheck Require("batch");
  Require(shards >= 1, "shards", shards, ">= 1");
  Require(shard >= 0 && shard < shards, "shard", shard, "in [0, shards)");
  Require(jobs >= 1, "jobs", jobs, ">= 1");
}

std::vector<std::string> ReadDriveList(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(path + ": cannot open");
  std::vector<std::string> drives;
  for (std::string line; std::getline(in, line);) {
    if (!line.empty() && line[0] != '#') drives.push_back(line);
  }
  return drives;
}

void ParseShard(const std::string& text, int* shard, int* shards) {
  int i = 0, n = 0;
  char end = 0;
  if (std::sscanf(text.c_str(), "%d/%d%c", &i, &n, &end) != 2 || n < 1 || i < 0 || i >= n) {
    throw Error("option --shard: expected I/N with 0 <= I < N, got '" + text + "'");
  }
  *shard = i;
  *shards = n;
}

std::vector<std::string> ShardOf(const std::vector<std::string>& drives, int shard, int shards) {
  std::vector<std::string> mine;
  for (size_t i = 0; i < drives.size(); ++i) {
    if (static_cast<int>(i % shards) == shard) mine.push_back(drives[i]);
  }
  return mine;
}

BatchResult RunBatch(const std::vector<std::string>& drives, const BatchOptions& options, const BatchEvents& events) {
  options.Check();
  // Drives of one folder name would share an output folder: over the whole list (every shard sees
  // it), each such drive is failed with the other named.
  std::map<std::string, std::vector<size_t>> by_output;
  for (size_t i = 0; i < drives.size(); ++i) by_output[AbsolutePath(DriveOutputDir(drives[i], options.out_root))].push_back(i);
  std::map<size_t, std::string> shared_all;
  for (const auto& [out, indices] : by_output) {
    if (indices.size() < 2) continue;
    for (size_t i : indices) shared_all[i] = drives[indices[i == indices[0] ? 1 : 0]];
  }
  std::vector<std::string> mine;
  std::map<size_t, std::string> shared;
  for (size_t i = 0; i < drives.size(); ++i) {
    if (static_cast<int>(i % options.shards) != options.shard) continue;
    const auto it = shared_all.find(i);
    if (it != shared_all.end()) shared[mine.size()] = it->second;
    mine.push_back(drives[i]);
  }
  Batch batch(mine, options, events, std::move(shared));
  std::vector<std::thread> threads;
  for (int j = 1; j < options.jobs; ++j) threads.emplace_back([&] { batch.Work(); });
  batch.Work();
  for (std::thread& t : threads) t.join();
  return batch.result();
}

}  // namespace dps
