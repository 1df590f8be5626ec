#include "dps/pipeline/drive_io.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <limits>

#include <opencv2/imgcodecs.hpp>

#include "dps/util/csv.h"
#include "dps/util/error.h"

namespace dps {
namespace {

namespace fs = std::filesystem;

// The frame number of an image file: the digits at the end of its name ("000012.png",
// "frame_12.jpg" -> 12), or -1 when there are none.
long FrameNumber(const fs::path& file) {
  const std::string stem = file.stem().string();
  size_t first = stem.size();
  while (first > 0 && std::isdigit(static_cast<unsigned char>(stem[first - 1]))) --first;
  if (first == stem.size() || stem.size() - first > 9) return -1;
  return std::stol(stem.substr(first));
}

class ImageFolder : public FrameSource {
 public:
  // Images in the order of their numbers (so that 2.png comes before 10.png); a file without a
  // number, two files of one number, or (unless allow_gaps) a number missing between the first and
  // the last is an error naming the frame.
  ImageFolder(const fs::path& dir, bool allow_gaps) : dir_(dir) {
    std::vector<std::pair<long, std::string>> numbered;
    for (const auto& e : fs::directory_iterator(dir)) {
      std::string ext = e.path().extension().string();
      std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
      if (e.is_regular_file() && (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".bmp" || ext == ".tif" ||
                                  ext == ".tiff" || ext == ".pgm" || ext == ".ppm")) {
        const long n = FrameNumber(e.path());
        if (n < 0) throw Error(Str(e.path().string(), ": not a numbered frame (expected e.g. 000000.png, 000001.png, ...)"));
        numbered.emplace_back(n, e.path().string());
      }
    }
    if (numbered.empty()) throw Error(Str(dir.string(), ": no images in the folder"));
    std::sort(numbered.begin(), numbered.end());
    for (size_t i = 1; i < numbered.size(); ++i) {
      const long a = numbered[i - 1].first, b = numbered[i].first;
      if (a == b) throw Error(Str(dir.string(), ": frame ", b, " twice (", numbered[i - 1].second, ", ", numbered[i].second, ")"));
      if (b != a + 1 && !allow_gaps) {
        throw Error(Str(dir.string(), ": frame ", a + 1, (b > a + 2 ? Str(" to ", b - 1) : std::string()), " missing (",
                        fs::path(numbered[i - 1].second).filename().string(), " is followed by ",
                        fs::path(numbered[i].second).filename().string(), ")"));
      }
    }
    for (auto& [n, file] : numbered) {
      numbers_.push_back(n);
      files_.push_back(std::move(file));
    }
  }
  long first_number() const override { return numbers_.front(); }
  std::vector<long> numbers() const override { return numbers_; }
  void Skip(int frames) override { next_ = std::min(files_.size(), next_ + static_cast<size_t>(std::max(frames, 0))); }
  void SkipTo(long number) override {
    const size_t at = std::lower_bound(numbers_.begin(), numbers_.end(), number) - numbers_.begin();
    next_ = std::max(next_, at);
  }
  bool Read(cv::Mat* image) override {
    if (next_ >= files_.size()) return false;
    *image = cv::imread(files_[next_], cv::IMREAD_COLOR);
    if (image->empty()) throw Error(Str(files_[next_], ": cannot read image"));
    ++next_;
    return true;
  }
  int count() const override { return static_cast<int>(files_.size()); }
  double fps() const override { return 0.0; }
  std::string description() const override { return dir_.string() + "/"; }

 private:
  fs::path dir_;
  std::vector<std::string> files_;
  std::vector<long> numbers_;  // the files' numbers, ascending
  size_t next_ = 0;
};

class VideoFile : public FrameSource {
 public:
  explicit VideoFile(const std::string& path) : path_(path), capture_(path) {
    if (!capture_.isOpened()) throw Error(Str(path, ": cannot open video"));
    count_ = static_cast<int>(capture_.get(cv::CAP_PROP_FRAME_COUNT));
    fps_ = capture_.get(cv::CAP_PROP_FPS);
  }
  bool Read(cv::Mat* image) override {
    ++next_;
    return capture_.read(*image) && !image->empty();
  }
  void Skip(int frames) override {
    for (int i = 0; i < frames && capture_.grab(); ++i) ++next_;
  }
  void SkipTo(long number) override {
    if (number > next_) Skip(static_cast<int>(std::min<long>(number - next_, std::numeric_limits<int>::max())));
  }
  int count() const override { return count_; }
  double fps() const override { return fps_; }
  std::string description() const override { return path_; }

 private:
  std::string path_;
  cv::VideoCapture capture_;
  int count_ = 0;
  double fps_ = 0.0;
  long next_ = 0;  // the number of the next frame Read returns
};

}  // namespace

std::vector<long> FrameSource::numbers() const {
  std::vector<long> n(static_cast<size_t>(std::max(count(), 0)));
  for (size_t i = 0; i < n.size(); ++i) n[i] = first_number() + static_cast<long>(i);
  return n;
}

std::string FrameSource::Find(const std::string& drive_dir, const std::string& camera) {
  const fs::path folder = fs::path(drive_dir) / camera;
  if (fs::is_directory(folder)) return folder.string();
  if (fs::is_directory(drive_dir)) {
    for (const auto& e : fs::directory_iterator(drive_dir)) {
      if (e.is_regular_file() && e.path().stem() == camera && e.path().extension() != ".yaml") return e.path().string();
    }
  }
  return {};
}

std::unique_ptr<FrameSource> FrameSource::Open(const std::string& drive_dir, const std::string& camera,
                                               bool allow_gaps) {
  const std::string path = Find(drive_dir, camera);
  if (path.empty()) throw Error(Str(drive_dir, ": no '", camera, "/' image folder or '", camera, ".<ext>' video"));
  if (fs::is_directory(path)) return std::make_unique<ImageFolder>(path, allow_gaps);
  return std::make_unique<VideoFile>(path);
}

CanLog ReadCanLog(const std::string& path, const CanLogFormat& f) {
  const CsvTable t = CsvTable::Read(path);
  const int tc = t.Column(f.time_column), sc = t.Column(f.speed_column);
  const bool own_yaw = f.yaw_rate_file.empty() && t.HasColumn(f.yaw_rate_column);
  const int yc = own_yaw ? t.Column(f.yaw_rate_column) : -1;
  CanLog log;
  std::vector<MotionSample> samples;
  int nan_rows = 0, duplicates = 0;
  for (size_t r = 0; r < t.rows(); ++r) {
    const double time = t.Number(r, tc), speed = t.Number(r, sc) * f.speed_scale;
    const double yaw = yc >= 0 ? t.Number(r, yc) * f.yaw_rate_scale : 0.0;
    if (!std::isfinite(time) || !std::isfinite(speed) || !std::isfinite(yaw)) {
      ++nan_rows;
      continue;
    }
    if (std::abs(speed) > kMaxSpeedMps) {
      throw Error(Str(path, ":", t.Line(r), ": column '", f.speed_column, "': ", speed, " m/s is no road vehicle's speed (at most ",
                      kMaxSpeedMps, " m/s; another unit? see --speed-scale)"));
    }
    if (std::abs(yaw) > kMaxYawRateRadps) {
      throw Error(Str(path, ":", t.Line(r), ": column '", f.yaw_rate_column, "': ", yaw, " rad/s is no road vehicle's yaw rate (at most ",
                      kMaxYawRateRadps, " rad/s; degrees? see --yaw-scale)"));
    }
    if (!samples.empty() && time < samples.back().t_s) {
      throw Error(Str(path, ":", t.Line(r), ": time ", time, " goes backwards (previous ", samples.back().t_s,
                      "); sort the log"));
    }
    if (!samples.empty() && time == samples.back().t_s) {
      ++duplicates;
      continue;
    }
    samples.push_back({time, speed, yaw});
  }
  if (samples.size() < 2) throw Error(Str(path, ": fewer than 2 usable samples"));
  if (nan_rows) log.warnings.push_back(Str(path, ": ", nan_rows, " row(s) with NaN dropped"));
  if (duplicates) log.warnings.push_back(Str(path, ": ", duplicates, " duplicate time(s) dropped (first kept)"));
  if (!f.yaw_rate_file.empty()) {
    // Yaw rate from a second log, interpolated to the speed samples' times.
    const CsvTable g = CsvTable::Read(f.yaw_rate_file);
    const int gt = g.Column(f.yaw_rate_time_column), gy = g.Column(f.yaw_rate_column);
    std::vector<MotionSample> gyro;
    for (size_t r = 0; r < g.rows(); ++r) {
      const double time = g.Number(r, gt), yaw = g.Number(r, gy) * f.yaw_rate_scale;
      if (!std::isfinite(time) || !std::isfinite(yaw)) continue;
      if (!gyro.empty() && time < gyro.back().t_s) {
        throw Error(Str(f.yaw_rate_file, ":", g.Line(r), ": time goes backwards; sort the log"));
      }
      if (!gyro.empty() && time == gyro.back().t_s) continue;
      gyro.push_back({time, 0.0, yaw});
    }
    if (gyro.size() < 2) throw Error(Str(f.yaw_rate_file, ": fewer than 2 usable samples"));
    const MotionProfile gyro_profile(gyro);
    for (MotionSample& s : samples) s.yaw_rate_radps = gyro_profile.At(s.t_s).yaw_rate_radps;
    // Outside the gyro log the yaw rate is unknown: shrink the span.
    const double g0 = gyro.front().t_s, g1 = gyro.back().t_s;
    samples.erase(std::remove_if(samples.begin(), samples.end(),
                                 [&](const MotionSample& s) { return s.t_s < g0 || s.t_s > g1; }),
                  samples.end());
    if (samples.size() < 2) throw Error(Str(path, " and ", f.yaw_rate_file, ": the logs do not overlap in time"));
  }
  for (size_t i = 1; i < samples.size(); ++i) {
    if (samples[i].t_s - samples[i - 1].t_s > f.max_gap_s) log.gaps.emplace_back(samples[i - 1].t_s, samples[i].t_s);
  }
  log.t_begin = samples.front().t_s;
  log.t_end = samples.back().t_s;
  log.profile = MotionProfile(samples);
  return log;
}

bool MotionBetween(const CanLog& log, double t0, double t1, PlanarPose* pose, std::string* why) {
  if (!std::isfinite(t0) || !std::isfinite(t1)) {
    if (why) *why = Str("frame time not finite (", t0, " .. ", t1, " s)");
    return false;
  }
  if (t0 < log.t_begin || t1 > log.t_end) {
    if (why) *why = Str("outside the CAN log (", log.t_begin, " .. ", log.t_end, " s)");
    return false;
  }
  for (const auto& [a, b] : log.gaps) {
    if (a < t1 && b > t0) {
      if (why) *why = Str("inside a CAN gap of ", b - a, " s (", a, " .. ", b, " s)");
      return false;
    }
  }
  *pose = log.profile.Integrate(PlanarPose{}, t0, t1);
  return true;
}

std::vector<double> ReadFrameTimes(const std::string& path) {
  const CsvTable t = CsvTable::Read(path);
  const int fc = t.Column("frame"), tc = t.Column("t");
  std::vector<double> times;
  for (size_t r = 0; r < t.rows(); ++r) {
    const double frame = t.Number(r, fc);
    if (frame != static_cast<double>(times.size())) {
      throw Error(Str(path, ":", t.Line(r), ": expected frame ", times.size(), ", got ", frame));
    }
    const double time = t.Number(r, tc);
    if (!std::isfinite(time)) throw Error(Str(path, ":", t.Line(r), ": frame ", frame, " has no finite time (", time, ")"));
    if (!times.empty() && time <= times.back()) {
      throw Error(Str(path, ":", t.Line(r), ": frame ", frame, " at t = ", time, " s does not come after frame ",
                      frame - 1, " at ", times.back(), " s"));
    }
    times.push_back(time);
  }
  return times;
}

}  // namespace dps
