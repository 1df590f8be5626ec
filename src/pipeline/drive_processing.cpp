#include "dps/pipeline/drive_processing.h"

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <sstream>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "dps/camera/rig_io.h"
#include "dps/detect/detection_io.h"
#include "dps/map/tracks_io.h"
#include "dps/util/atomic_file.h"
#include "dps/util/error.h"

namespace dps {
namespace {

namespace fs = std::filesystem;

using Clock = std::chrono::steady_clock;
double Seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

std::string JsonString(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (c == '\n') {
      out += "\\n";
      continue;
    }
    out += c;
  }
  return out + "\"";
}

}  // namespace

std::string DriveSummary::ToJson() const {
  std::ostringstream o;
  o.precision(6);
  o << "{\n  \"drive\": " << JsonString(drive) << ",\n  \"frames\": " << frames
    << ",\n  \"frames_without_motion\": " << frames_without_motion << ",\n  \"detections\": " << detections
    << ",\n  \"front_vertical_offset_px\": " << front_vertical_offset_px << ",\n  \"map_video\": " << JsonString(map_video)
    << ",\n  \"seconds\": " << seconds << ",\n  \"frames_per_second\": " << frames_per_second
    << ",\n  \"stage_seconds\": {";
  bool first = true;
  for (const auto& [k, v] : stage_seconds) {
    o << (first ? "" : ", ") << JsonString(k) << ": " << v;
    first = false;
  }
  o << "},\n  \"warnings\": [";
  for (size_t i = 0; i < warnings.size(); ++i) o << (i ? ", " : "") << JsonString(warnings[i]);
  o << "]\n}\n";
  return o.str();
}

std::string DriveOutputDir(const std::string& drive_dir, const std::string& out_root) {
  fs::path d = fs::path(drive_dir);
  if (d.filename().empty()) d = d.parent_path();
  return (fs::path(out_root) / d.filename()).string();
}

bool DriveOutputComplete(const std::string& output_dir) {
  return fs::exists(fs::path(output_dir) / "summary.json");
}

DriveSummary ProcessDrive(const std::string& drive_dir, const std::string& out_root, const DriveOptions& o,
                          const std::function<void(int, int)>& progress) {
  const auto start = Clock::now();
  DriveSummary s;
  s.output_dir = DriveOutputDir(drive_dir, out_root);
  s.drive = fs::path(s.output_dir).filename().string();
  if (!fs::is_directory(drive_dir)) throw Error(Str(drive_dir, ": not a folder"));
  const Rig rig = ReadRig((fs::path(drive_dir) / "rig.yaml").string());
  std::unique_ptr<FrameSource> left = FrameSource::Open(drive_dir, "left");
  std::unique_ptr<FrameSource> right = FrameSource::Open(drive_dir, "right");
  int frames = left->count();
  if (left->count() != right->count()) {
    if (!o.truncate) {
      throw Error(Str(drive_dir, ": ", left->description(), " has ", left->count(), " frames, ",
                      right->description(), " has ", right->count(), " (--truncate uses the shorter)"));
    }
    frames = std::min(left->count(), right->count());
    s.warnings.push_back(Str("left and right differ in length; truncated to ", frames, " frames"));
  }
  // Frame times.
  std::vector<double> times;
  const fs::path frames_csv = fs::path(drive_dir) / "frames.csv";
  if (fs::exists(frames_csv)) {
    times = ReadFrameTimes(frames_csv.string());
    if (static_cast<int>(times.size()) < frames) {
      throw Error(Str(frames_csv.string(), ": ", times.size(), " frames listed, the videos have ", frames));
    }
  } else {
    const double fps = left->fps() > 0 ? left->fps() : o.image_fps;
    for (int i = 0; i < frames; ++i) times.push_back(i / fps);
  }
  const CanLog can = ReadCanLog((fs::path(drive_dir) / "can.csv").string(), o.can);
  for (const std::string& w : can.warnings) s.warnings.push_back(w);

  // Outputs under a temporary name.
  fs::create_directories(out_root);
  const fs::path tmp = fs::path(out_root) / Str(".", s.drive, ".tmp-", ::getpid());
  fs::remove_all(tmp);
  fs::create_directories(tmp);
  try {
    const PipelineOptions pipeline_options = o.default_pipeline ? DefaultPipelineOptions(rig) : o.pipeline;
    SurroundPipeline pipeline(rig, pipeline_options);
    std::vector<Detection> detections;
    Tracker tracker(o.tracker);
    std::vector<TrackState> tracks;
    PlanarPose ego;  // the vehicle in the tracker's world (its pose at frame 0)
    OccupancyGrid grid(o.occupancy);
    // The map video: H.264 in MP4 where OpenCV has an encoder for it (a fiftieth of MJPG's size
    // on these pictures), else MPEG-4 part 2 in MP4, else MJPG in AVI, else PNGs with a warning.
    cv::VideoWriter video;
    std::string video_tmp, video_name;
    if (o.map_video) {
      const double fps = frames > 1 ? std::max(1.0, (frames - 1) / std::max(1e-6, times[frames - 1] - times[0])) : 10.0;
      const struct {
        const char* name;
        const char* codec;
        int fourcc;
      } formats[] = {{"map.mp4", "H.264", cv::VideoWriter::fourcc('a', 'v', 'c', '1')},
                     {"map.mp4", "MPEG-4 part 2", cv::VideoWriter::fourcc('m', 'p', '4', 'v')},
                     {"map.avi", "MJPG", cv::VideoWriter::fourcc('M', 'J', 'P', 'G')}};
      for (const auto& f : formats) {
        video_name = f.name;
        video_tmp = (tmp / (".tmp." + video_name)).string();  // the extension picks the container
        if (video.open(video_tmp, f.fourcc, fps, cv::Size(o.map.size_px, o.map.size_px))) {
          s.map_video = Str(f.name, " (", f.codec, ")");
          break;
        }
      }
      if (!video.isOpened()) s.warnings.push_back("no video encoder; writing map/ PNGs instead");
    }
    const bool png = o.map_png || (o.map_video && !video.isOpened());
    const cv::Mat map_background = DrawMapBackground(rig.vehicle, pipeline.coverage(), o.map);
    cv::Mat map;  // the frame's map picture, drawn into the same buffer every frame
    cv::VideoWriter diagnostics;
    const std::string diagnostics_tmp = (tmp / ".diagnostics.tmp.avi").string();
    if (png) fs::create_directories(tmp / "map");
    double decode = 0, front = 0, sides = 0, map_s = 0, write = 0;
    std::mutex decode_mutex;
    // What follows the stereo for one frame: tracking, the occupancy grid, the map picture and
    // writing. It runs alongside the next frame's stereo (SurroundPipeline::Process), in order.
    const auto finish = [&](FrameOutput& out, int f) {
      auto t2 = Clock::now();
      const std::vector<TrackState> frame_tracks = tracker.Update(f, times[f], ego, out.detections);
      char caption[128];
      std::snprintf(caption, sizeof(caption), "%s  frame %d  t %.2f s  %zu objects", s.drive.c_str(), f, times[f],
                    out.detections.size());
      grid.Update(ego, out.coverage, out.detections);
      // The picture only when it is written (--no-video without PNGs: the CSVs alone).
      if (video.isOpened() || png) {
        DrawFrameMap(map_background, grid, rig.vehicle, out.detections, frame_tracks, o.map, caption, map);
      }
      for (const TrackState& t : frame_tracks) {
        if (t.confirmed) tracks.push_back(t);
      }
      auto t3 = Clock::now();
      map_s += Seconds(t2, t3);
      if (video.isOpened()) video.write(map);
      if (o.diagnostics) {
        const PipelineOptions& po = pipeline_options;
        const cv::Size panel(po.front.view_width, po.front.view_height);
        const double fd0 = po.front.stereo.min_disparity, fd1 = fd0 + po.front.stereo.num_disparities;
        const double sd0 = po.side.stereo.min_disparity, sd1 = sd0 + po.side.stereo.num_disparities;
        cv::Mat all;
        cv::hconcat(std::vector<cv::Mat>{
                        DrawDiagnostics("front (left view)", out.front.left_view, out.front.right_view,
                                        out.front.by_left.disparity, out.front.by_left.histogram,
                                        out.front.by_left.obstacle, fd0, fd1, panel),
                        DrawDiagnostics("front (right view)", out.front.right_view, out.front.left_view,
                                        out.front.by_right.disparity, out.front.by_right.histogram,
                                        out.front.by_right.obstacle, fd0, fd1, panel),
                        DrawDiagnostics("left", out.left.reference_view, out.left.other_view, out.left.disparity,
                                        out.left.histogram, out.left.obstacle, sd0, sd1, panel),
                        DrawDiagnostics("right", out.right.reference_view, out.right.other_view, out.right.disparity,
                                        out.right.histogram, out.right.obstacle, sd0, sd1, panel)},
                    all);
        if (!diagnostics.isOpened()) {
          diagnostics.open(diagnostics_tmp, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10.0, all.size());
          if (!diagnostics.isOpened()) throw Error(Str(s.output_dir, ": cannot open a video writer for diagnostics"));
        }
        diagnostics.write(all);
        if (f == frames / 2) cv::imwrite((tmp / "diagnostics_middle.png").string(), all);
      }
      if (png) {
        char name[32];
        std::snprintf(name, sizeof(name), "%06d.png", f);
        if (!cv::imwrite((tmp / "map" / name).string(), map)) throw Error(Str(s.output_dir, ": cannot write map image"));
      }
      write += Seconds(t3, Clock::now());
      for (Detection& d : out.detections) detections.push_back(std::move(d));
    };
    // Decoding: frame f + 1's two images are read alongside frame f's stereo, each by its own
    // task (seconds summed over both).
    const auto read = [&](FrameSource& source, cv::Mat* image, int f) {
      const auto t0 = Clock::now();
      if (!source.Read(image)) throw Error(Str(drive_dir, ": frame ", f, " could not be read (the stream ended early)"));
      const double seconds = Seconds(t0, Clock::now());
      std::lock_guard<std::mutex> lock(decode_mutex);
      decode += seconds;
    };
    FrameOutput pending;  // the previous frame's, not yet finished
    cv::Mat l, r, next_l, next_r;
    if (frames > 0) {
      read(*left, &l, 0);
      read(*right, &r, 0);
    }
    for (int f = 0; f < frames; ++f) {
      if (l.size() != r.size()) {
        throw Error(Str(drive_dir, ": frame ", f, ": left is ", l.cols, "x", l.rows, ", right ", r.cols, "x", r.rows));
      }
      if (l.cols != rig.Camera("left").model.width() || l.rows != rig.Camera("left").model.height()) {
        throw Error(Str(drive_dir, ": frame ", f, " is ", l.cols, "x", l.rows, " but rig.yaml's cameras are ",
                        rig.Camera("left").model.width(), "x", rig.Camera("left").model.height()));
      }
      FrameInput in;
      in.frame = f;
      in.t_s = times[f];
      in.left = l;
      in.right = r;
      if (f > 0) {
        std::string why;
        in.motion_known = MotionBetween(can, times[f - 1], times[f], &in.current_in_previous, &why);
        if (!in.motion_known) {
          ++s.frames_without_motion;
          s.warnings.push_back(Str("frame ", f, ": no known motion (", why, "); side detection skipped"));
        }
      }
      std::vector<std::function<void()>> alongside;
      if (f > 0) alongside.push_back([&] { finish(pending, f - 1); });
      if (f + 1 < frames) {
        alongside.push_back([&] { read(*left, &next_l, f + 1); });
        alongside.push_back([&] { read(*right, &next_r, f + 1); });
      }
      FrameOutput out = pipeline.Process(in, alongside);
      if (in.motion_known) ego = Compose(ego, in.current_in_previous);
      s.front_vertical_offset_px = out.front.vertical_offset_px;
      front += out.front_ms / 1000.0;
      sides += out.sides_ms / 1000.0;
      pending = std::move(out);
      std::swap(l, next_l);
      std::swap(r, next_r);
      if (progress && f > 0) progress(f, frames);
    }
    if (frames > 0) finish(pending, frames - 1);
    if (progress && frames > 0) progress(frames, frames);
    auto t4 = Clock::now();
    if (video.isOpened()) {
      video.release();
      RenameReplacing(video_tmp, (tmp / video_name).string());
    }
    if (diagnostics.isOpened()) {
      diagnostics.release();
      RenameReplacing(diagnostics_tmp, (tmp / "diagnostics.avi").string());
    }
    WriteDetections(detections, (tmp / "detections.csv").string());
    WriteTracks(tracks, (tmp / "tracks.csv").string());
    write += Seconds(t4, Clock::now());
    s.frames = frames;
    s.detections = static_cast<int>(detections.size());
    s.stage_seconds = {{"decode", decode}, {"front", front}, {"sides", sides}, {"map", map_s}, {"write", write}};
    s.seconds = Seconds(start, Clock::now());
    s.frames_per_second = s.seconds > 0 ? frames / s.seconds : 0;
    WriteFileAtomically((tmp / "summary.json").string(), s.ToJson());  // last: marks completion
  } catch (...) {
    std::error_code ec;
    fs::remove_all(tmp, ec);
    throw;
  }
  if (fs::exists(s.output_dir)) fs::remove_all(s.output_dir);
  fs::rename(tmp, s.output_dir);
  return s;
}

}  // namespace dps
