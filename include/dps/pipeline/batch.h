// dps — a batch of drives (what dps-process runs): the share of one job in a job array, a pool
// of workers processing drives at once, drives already complete skipped, one bad drive reported
// while the others finish, and the whole batch's progress with its estimated time left.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "dps/pipeline/drive_processing.h"

namespace dps {

struct BatchOptions {
  std::string out_root;     // the drives' outputs go to <out_root>/<drive folder name>
  int shard = 0;            // this job processes every `shards`-th drive from `shard` (0-based)
  int shards = 1;           // >= 1, shard in [0, shards)
  int jobs = 1;             // drives processed at once, >= 1
  bool force = false;       // redo drives whose outputs are complete
  DriveOptions drive;

  // Throws dps::Error naming the field, its value and the violated constraint.
  void Check() const;
};

// Progress of one drive of the batch: its place in this job's share, its frames so far, its
// frame rate, and the estimated seconds left for it and for the whole share (from the fraction
// of all its drives' frames done in the time so far).
struct BatchProgress {
  size_t index = 0, count = 0;  // the drive's place in the share, 1-based, of count
  std::string drive;
  int frame = 0, frames = 0;
  double frames_per_second = 0.0;
  double drive_eta_s = 0.0, batch_eta_s = 0.0;
};

// What the batch reports as it goes; each is called under one lock (never two at once). Unset
// callbacks are skipped.
struct BatchEvents {
  std::function<void(const BatchProgress&)> progress;           // after each frame
  std::function<void(const std::string& output_dir)> skipped;   // complete already
  std::function<void(const DriveSummary&)> finished;
  std::function<void(const std::string& drive, const std::string& error)> failed;
};

struct BatchResult {
  int processed = 0, skipped = 0, failed = 0;
};

// Drives listed in a file, one folder per line; empty lines and lines starting with '#' are
// skipped. Throws dps::Error when the file cannot be read.
std::vector<std::string> ReadDriveList(const std::string& path);

// "I/N" (a job array's index and size) into shard and shards; throws dps::Error otherwise.
void ParseShard(const std::string& text, int* shard, int* shards);

// The drives of one shard: every `shards`-th from `shard`, in order.
std::vector<std::string> ShardOf(const std::vector<std::string>& drives, int shard, int shards);

// Processes this job's share of `drives` (ProcessDrive each) with `options.jobs` workers. A drive
// that fails is reported through events.failed and counted; the others still run.
BatchResult RunBatch(const std::vector<std::string>& drives, const BatchOptions& options,
                     const BatchEvents& events = {});

}  // namespace dps
