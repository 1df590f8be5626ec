// dps-process: recorded drives -> detections.csv, surround-map video, summary.json.
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <iostream>

#include "cli.h"
#include "dps/pipeline/batch.h"

namespace {

const char* kUsage = R"(usage: dps-process DRIVE_DIR... --out OUT_DIR [options]

Processes recorded drives (DESIGN.md §3.2: rig.yaml, left/ and right/ images or left.<ext> and
right.<ext> videos, can.csv, optional frames.csv) into OUT_DIR/<drive folder name>/:
detections.csv, tracks.csv, map.mp4 (the surround map video, H.264 or MPEG-4; map.avi with MJPG,
or map/ PNGs, when OpenCV has no such encoder), summary.json and masks/<camera>.png (the pixels
each camera was taken to see the world with: from the drive's masks/, rig.yaml's `mask:`, or
estimated from the drive's first seconds) with masks/<camera>_own_car.png (the own car it was
taken to see, from the drive's masks/ or estimated when the car moves in those seconds; no
obstacle is taken from it). Correct one and put it into the drive's masks/.
Each camera's rotation in rig.yaml is corrected from the road's motion over the drive's first
second when the estimate is sure enough (standard error within 0.05 deg): summary.json's
"extrinsic_correction" gives the estimate (pitch, yaw, roll in degrees, about the vehicle's X, Y,
Z axes), whether it was applied (or the rig confirmed within 0.05 deg) and, if not, why.
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
  --grid-every N        every N-th frame, the occupancy grid as grid/NNNNNN.png (16-bit evidence:
                        (value - 32768) * evidence_per_step, summary.json's "grid"; +Z up) with
                        grid/grid.csv (each file's world origin and the vehicle's pose)
  --remember            also report the obstacles the occupancy grid remembers where no view looks
                        this frame (parked cars, poles, walls passed: behind the car and in the
                        wedges between the views) as detections of the side they are on
  --rear                also look behind the mirrors: each camera's rear view against its earlier
                        frames, obstacles where they meet the road (docs/detection.md; experimental:
                        more false detections than found ones on the tuning drives)
  --reach-forward       the side views also cover the road ahead that the front pair does not see
                        (fisheyes looking sideways see ahead only at their fields' edges), by motion
                        stereo up to 76 deg in front of their axes (docs/detection.md; off by
                        default: more found ahead, at lower precision)
  --truncate            left and right differ: process the frame numbers both have
                        (image folders pair by file number; videos by position)
  --allow-gaps          a frame lost in recording - a number missing in an image folder, or
                        consecutive frames in frames.csv more than 1.5 median intervals apart -
                        is processed across with a warning instead of failing the drive: the
                        frame numbers both cameras have, at their own times (never by position)
  --no-mask-estimate    cameras without a mask: the model's field alone, and no own car (no estimate
                        from the images)
  --mask-seconds S      estimate masks from the first S seconds (default 2)
  --no-extrinsic-correction
                        process with rig.yaml's rotations as they are (the estimate is not made)
  --extrinsic-seconds S estimate the rotations from the first S seconds (default 1)
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

// Progress and results on stderr: a live line on a terminal when one drive runs at a time,
// plain lines otherwise (every 25 frames); errors even when quiet.
dps::BatchEvents Reporter(bool quiet, int jobs) {
  dps::BatchEvents events;
  events.failed = [](const std::string&, const std::string& error) {
    std::cerr << "dps-process: error: " << error << std::endl;
  };
  if (quiet) return events;
  const bool live = isatty(STDERR_FILENO) && jobs == 1;
  events.progress = [live](const dps::BatchProgress& p) {
    if (live) {
      std::fprintf(stderr, "\rdps-process: drive %zu/%zu %s  frame %d/%d  %.1f frames/s  ETA %.0f s, all %.0f s   ",
                   p.index, p.count, p.drive.c_str(), p.frame, p.frames, p.frames_per_second, p.drive_eta_s,
                   p.batch_eta_s);
      if (p.frame == p.frames) std::fprintf(stderr, "\n");
    } else if (p.frame == p.frames || p.frame % 25 == 0) {
      std::fprintf(stderr, "dps-process: drive %zu/%zu %s frame %d/%d (%.1f frames/s, ETA %.0f s, all %.0f s)\n",
                   p.index, p.count, p.drive.c_str(), p.frame, p.frames, p.frames_per_second, p.drive_eta_s,
                   p.batch_eta_s);
    }
  };
  events.skipped = [](const std::string& out_dir) {
    std::cerr << "dps-process: " << out_dir << " is complete; skipped (--force redoes it)\n";
  };
  events.finished = [](const dps::DriveSummary& s) {
    std::cerr << "dps-process: " << s.output_dir << ": " << s.frames << " frames, " << s.detections << " detections, "
              << s.frames_per_second << " frames/s";
    if (!s.warnings.empty()) std::cerr << ", " << s.warnings.size() << " warning(s) in summary.json";
    std::cerr << "\n";
  };
  return events;
}

}  // namespace

int main(int argc, char** argv) {
  return dps_cli::Run("dps-process", [&] {
    const dps_cli::Args args(argc, argv,
                             {"out", "list", "shard", "jobs", "image-fps", "speed-column", "speed-scale", "yaw-column",
                              "yaw-scale", "time-column", "yaw-file", "mask-seconds", "grid-every", "extrinsic-seconds"},
                             {"force", "map-png", "no-video", "truncate", "allow-gaps", "quiet", "diagnostics", "no-mask-estimate",
                              "no-extrinsic-correction", "remember", "rear", "reach-forward"});
    if (args.help()) {
      std::cout << kUsage;
      return 0;
    }
    args.Require("out", "OUT_DIR");
    std::vector<std::string> drives = args.positional();
    if (args.Has("list")) {
      for (const std::string& d : dps::ReadDriveList(args.Get("list"))) drives.push_back(d);
    }
    if (drives.empty()) throw dps::Error("no drives given (see --help)");
    dps::BatchOptions batch;
    batch.out_root = args.Get("out");
    if (args.Has("shard")) dps::ParseShard(args.Get("shard"), &batch.shard, &batch.shards);
    batch.jobs = args.Integer("jobs", 1);
    if (batch.jobs < 1) throw dps::Error("option --jobs: expected >= 1");
    batch.force = args.Has("force");
    dps::DriveOptions& options = batch.drive;
    options.map_video = !args.Has("no-video");
    options.map_png = args.Has("map-png");
    options.diagnostics = args.Has("diagnostics");
    options.grid_every = args.Integer("grid-every", 0);
    if (options.grid_every < 0) throw dps::Error("option --grid-every: expected >= 0");
    options.grid_obstacles = args.Has("remember");
    options.rear = args.Has("rear");
    options.reach_forward = args.Has("reach-forward");
    options.truncate = args.Has("truncate");
    options.allow_frame_gaps = args.Has("allow-gaps");
    options.estimate_masks = !args.Has("no-mask-estimate");
    options.mask_estimate_s = args.Number("mask-seconds", 2.0);
    if (!(options.mask_estimate_s > 0)) throw dps::Error("option --mask-seconds: expected > 0");
    options.correct_extrinsics = !args.Has("no-extrinsic-correction");
    options.extrinsic_estimate_s = args.Number("extrinsic-seconds", 1.0);
    if (!(options.extrinsic_estimate_s > 0)) throw dps::Error("option --extrinsic-seconds: expected > 0");
    options.image_fps = args.Number("image-fps", 30.0);
    if (!(options.image_fps > 0)) throw dps::Error("option --image-fps: expected > 0");
    options.can.time_column = args.Get("time-column", "t");
    options.can.speed_column = args.Get("speed-column", "speed");
    options.can.speed_scale = args.Number("speed-scale", 1.0);
    options.can.yaw_rate_column = args.Get("yaw-column", "yaw_rate");
    options.can.yaw_rate_scale = args.Number("yaw-scale", 1.0);
    options.can.yaw_rate_file = args.Get("yaw-file");
    options.can.yaw_rate_time_column = options.can.time_column;
    const dps::BatchResult result = dps::RunBatch(drives, batch, Reporter(args.Has("quiet"), batch.jobs));
    if (!args.Has("quiet")) {
      std::cerr << "dps-process: " << result.processed << " processed, " << result.skipped << " skipped, "
                << result.failed << " failed\n";
    }
    return std::min(result.failed, 125);
  });
}
