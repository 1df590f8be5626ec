// dps — reading a recorded drive (DESIGN.md §3.2): a folder with rig.yaml, each camera as a video
// file (left.<ext>, anything cv::VideoCapture reads) or a folder of numbered images (left/),
// can.csv (t, speed, yaw_rate), optional frames.csv (frame, t) and truth.csv.
//
// Frame times: frames.csv when present; otherwise frame i is at i / fps of the video (image
// folders: 30 fps unless told). CAN samples are interpolated to frame times; a frame interval
// outside the log's time span, or touching a gap longer than max_gap_s, has no known motion.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

#include "dps/camera/ego_motion.h"

namespace dps {

// One camera's frames, streamed (memory does not grow with the drive's length).
class FrameSource {
 public:
  // Opens <drive>/<camera>/ (numbered images in the order of their numbers: 000000.png, ... or
  // 0.png, 1.png, ...) or <drive>/<camera>.<ext> (video). Throws dps::Error naming what is missing,
  // an image without a number, a frame number found twice or - unless allow_gaps - missing
  // between the first and last.
  static std::unique_ptr<FrameSource> Open(const std::string& drive_dir, const std::string& camera,
                                           bool allow_gaps = false);
  // The path Open would read (the image folder, else the video); empty when the drive has neither.
  static std::string Find(const std::string& drive_dir, const std::string& camera);
  virtual ~FrameSource() = default;
  // The next frame, or false at the end. Throws dps::Error naming an unreadable image.
  virtual bool Read(cv::Mat* image) = 0;
  virtual int count() const = 0;       // frames in all (videos: as the container reports)
  // The number of the first frame (image folders: its file's number; videos: 0).
  virtual long first_number() const { return 0; }
  // The frames' numbers in order (image folders: their files' numbers; videos: 0, 1, ...).
  virtual std::vector<long> numbers() const;
  // Skips the next `frames` frames.
  virtual void Skip(int frames) = 0;
  // Skips to frame `number`: the next Read returns it (or the first frame after it, when it is
  // absent). Never goes back.
  virtual void SkipTo(long number) = 0;
  virtual double fps() const = 0;      // 0 when unknown (image folders)
  virtual std::string description() const = 0;
};

// Column names and units of a CAN log (real logs rarely use ours).
struct CanLogFormat {
  std::string time_column = "t";
  std::string speed_column = "speed";
  double speed_scale = 1.0;           // to m/s (km/h: 1 / 3.6)
  std::string yaw_rate_column = "yaw_rate";  // absent column: 0 (unless yaw_rate_file is given)
  double yaw_rate_scale = 1.0;        // to rad/s, positive = left (deg/s: pi / 180; flip: -1)
  std::string yaw_rate_file;          // optional: take the yaw rate from another CSV (a gyro log)
  std::string yaw_rate_time_column = "t";
  double max_gap_s = 0.5;             // longer gaps between samples: motion unknown there
};

// Bounds on what a road vehicle's CAN log can say: a speed above 100 m/s (360 km/h) or a yaw rate
// above 3 rad/s (a car turning on the spot at walking pace stays under 1.5 rad/s) is another unit
// or a corrupt log, and is refused rather than processed.
constexpr double kMaxSpeedMps = 100.0;
constexpr double kMaxYawRateRadps = 3.0;

struct CanLog {
  MotionProfile profile;
  double t_begin = 0.0, t_end = 0.0;
  std::vector<std::pair<double, double>> gaps;  // (start, end) of gaps longer than max_gap_s
  std::vector<std::string> warnings;            // dropped NaN rows, duplicate times, ...
};

// Reads a CAN log (and the optional gyro log). Throws dps::Error naming file, line and column for
// missing columns, non-numbers, time going backwards, or a speed or yaw rate beyond the bounds
// above; NaN rows and duplicate times are dropped with a warning.
CanLog ReadCanLog(const std::string& path, const CanLogFormat& format = CanLogFormat());

// The vehicle's pose at t1 in its frame at t0, when the log covers [t0, t1] without a long gap;
// otherwise false and `why` says why.
bool MotionBetween(const CanLog& log, double t0, double t1, PlanarPose* pose, std::string* why);

// frames.csv: time of each frame index (frames listed in order, times finite and increasing).
// Throws dps::Error naming the file and line.
std::vector<double> ReadFrameTimes(const std::string& path);

}  // namespace dps
