// dps-process: recorded drives -> detections.csv, surround-map video, summary.json.
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <mutex>
#include <thread>

#include "cli.h"
#include "dps/pipeline/drive_processing.h"

namespace {

const char* kUsage = R"(usage: dps-process DRIVE_DIR... --out OUT_DIR [options]

Processes recorded drives (DESIGN.md §3.2: rig.yaml, left/ and right/ images or left.<ext> and
right.<ext> videos, can.csv, optional frames.csv) into OUT_DIR/<drive folder name>/:
detections.csv, tracks.csv, map.mp4 (the surround map video, H.264 or MPEG-4; map.avi with MJPG,
or map/ PNGs, when OpenCV has no such encoder) and summary.json.
Outputs appear only when complete; drives already complete are skipped (--force redoes them).
One bad drive is reported and the others still run; the exit status is the number that failed.

  --out DIR             output root
  --list FILE           more drives, one folder per line
  --shard I/N           process every N-th drive starting at I (0-based), for job arrays
  --jobs N              process N drives at once (default 1)
  --force               redo drives whose outputs are complete
  --map-png             also write map/NNNNNN.png
  --diagnostics         also write diagnostics.avi: six panels per source (views, composite,
                        disparity, column histogram, obstacles) and diagnostics_middle.png
  --no-video            no map video
  --truncate            left and right differ in length: use the shorter
  --image-fps F         frame rate of image folders without frames.csv (default 30)
  --speed-column NAME   CAN column with the speed (default speed)
  --speed-scale S       to m/s, e.g. 0.2777778 for km/h (default 1)
  --yaw-column NAME     column with the yaw rate (default yaw_rate; absent = 0)
  --yaw-scale S         to rad/s, positive left, e.g. 0.01745329 for deg/s (default 1)
  --time-column NAME    CAN time column (default t)
  --yaw-file FILE       take the yaw rate from another CSV (a gyro log), same column options
  --quiet               no progress on stderr
  --help                this text
)";

}  // namespace

int main(int argc, char** argv) {
  return dps_cli::Run("dps-process", [&] {
    const dps_cli::Args args(argc, argv,
                             {"out", "list", "shard", "jobs", "image-fps", "speed-column", "speed-scale", "yaw-column",
                              "yaw-scale", "time-column", "yaw-file"},
                             {"force", "map-png", "no-video", "truncate", "quiet", "diagnostics"});
    if (args.help()) {
      std::cout << kUsage;
      return 0;
    }
    if (!args.Has("out")) throw dps::Error("missing --out OUT_DIR (see --help)");
    std::vector<std::string> drives = args.positional();
    if (args.Has("list")) {
      std::ifstream in(args.Get("list"));
      if (!in) throw dps::Error(args.Get("list") + ": cannot open");
      for (std::string line; std::getline(in, line);) {
        if (!line.empty() && line[0] != '#') drives.push_back(line);
      }
    }
    if (drives.empty()) throw dps::Error("no drives given (see --help)");
    int shard = 0, shards = 1;
    if (args.Has("shard") && (std::sscanf(args.Get("shard").c_str(), "%d/%d", &shard, &shards) != 2 || shards < 1 ||
                              shard < 0 || shard >= shards)) {
      throw dps::Error("option --shard: expected I/N with 0 <= I < N, got '" + args.Get("shard") + "'");
    }
    dps::DriveOptions options;
    options.map_video = !args.Has("no-video");
    options.map_png = args.Has("map-png");
    options.diagnostics = args.Has("diagnostics");
    options.truncate = args.Has("truncate");
    options.image_fps = args.Number("image-fps", 30.0);
    if (!(options.image_fps > 0)) throw dps::Error("option --image-fps: expected > 0");
    options.can.time_column = args.Get("time-column", "t");
    options.can.speed_column = args.Get("speed-column", "speed");
    options.can.speed_scale = args.Number("speed-scale", 1.0);
    options.can.yaw_rate_column = args.Get("yaw-column", "yaw_rate");
    options.can.yaw_rate_scale = args.Number("yaw-scale", 1.0);
    options.can.yaw_rate_file = args.Get("yaw-file");
    options.can.yaw_rate_time_column = options.can.time_column;
    const bool quiet = args.Has("quiet"), tty = isatty(STDERR_FILENO);
    const int jobs = args.Integer("jobs", 1);
    if (jobs < 1) throw dps::Error("option --jobs: expected >= 1");
    std::vector<std::string> mine;
    for (size_t i = 0; i < drives.size(); ++i) {
      if (static_cast<int>(i % shards) == shard) mine.push_back(drives[i]);
    }
    std::atomic<int> failed{0}, done{0}, skipped{0};
    std::atomic<size_t> next{0};
    std::mutex print;
    // The whole batch's progress for its ETA: each drive's done fraction (under `print`).
    const auto batch_start = std::chrono::steady_clock::now();
    std::vector<double> fraction(mine.size(), 0.0);
    const auto batch_eta = [&] {
      double sum = 0;
      for (const double f : fraction) sum += f;
      const double share = sum / std::max<size_t>(1, mine.size());
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - batch_start).count();
      return share > 0 ? s * (1 - share) / share : 0.0;
    };
    auto worker = [&] {
      for (size_t i = next++; i < mine.size(); i = next++) {
        const std::string& drive = mine[i];
        const std::string out_dir = dps::DriveOutputDir(drive, args.Get("out"));
        if (!args.Has("force") && dps::DriveOutputComplete(out_dir)) {
          ++skipped;
          std::lock_guard<std::mutex> lock(print);
          fraction[i] = 1.0;
          if (!quiet) std::cerr << "dps-process: " << out_dir << " is complete; skipped (--force redoes it)\n";
          continue;
        }
        const auto start = std::chrono::steady_clock::now();
        // A live line on a terminal when one drive runs at a time; plain lines otherwise.
        const bool live = tty && jobs == 1;
        auto progress = [&](int f, int total) {
          if (quiet) return;
          const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
          const double fps = f / std::max(s, 1e-9);
          std::lock_guard<std::mutex> lock(print);
          fraction[i] = total > 0 ? static_cast<double>(f) / total : 1.0;
          const double drive_eta = (total - f) / std::max(fps, 1e-9), all_eta = batch_eta();
          if (live) {
            std::fprintf(stderr, "\rdps-process: drive %zu/%zu %s  frame %d/%d  %.1f frames/s  ETA %.0f s, all %.0f s   ",
                         i + 1, mine.size(), drive.c_str(), f, total, fps, drive_eta, all_eta);
            if (f == total) std::fprintf(stderr, "\n");
          } else if (f == total || f % 25 == 0) {
            std::fprintf(stderr, "dps-process: drive %zu/%zu %s frame %d/%d (%.1f frames/s, ETA %.0f s, all %.0f s)\n",
                         i + 1, mine.size(), drive.c_str(), f, total, fps, drive_eta, all_eta);
          }
        };
        try {
          const dps::DriveSummary s = dps::ProcessDrive(drive, args.Get("out"), options, progress);
          ++done;
          std::lock_guard<std::mutex> lock(print);
          if (!quiet) {
            std::cerr << "dps-process: " << s.output_dir << ": " << s.frames << " frames, " << s.detections
                      << " detections, " << s.frames_per_second << " frames/s";
            if (!s.warnings.empty()) std::cerr << ", " << s.warnings.size() << " warning(s) in summary.json";
            std::cerr << "\n";
          }
        } catch (const std::exception& e) {
          ++failed;
          std::lock_guard<std::mutex> lock(print);
          fraction[i] = 1.0;
          std::cerr << "dps-process: error: " << e.what() << std::endl;
        }
      }
    };
    std::vector<std::thread> threads;
    for (int j = 1; j < jobs; ++j) threads.emplace_back(worker);
    worker();
    for (std::thread& t : threads) t.join();
    if (!quiet) {
      std::cerr << "dps-process: " << done << " processed, " << skipped << " skipped, " << failed << " failed\n";
    }
    return std::min(failed.load(), 125);
  });
}
