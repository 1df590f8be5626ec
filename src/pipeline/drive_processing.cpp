#include "dps/pipeline/drive_processing.h"

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <mutex>
#include <sstream>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "dps/camera/rig_io.h"
#include "dps/detect/detection_io.h"
#include "dps/detect/object_attributes.h"
#include "dps/map/tracks_io.h"
#include "dps/util/atomic_file.h"
#include "dps/util/error.h"
#include "dps/util/lanes_csv.h"
#include "dps/util/math.h"

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
    << ",\n  \"frames_without_motion\": " << frames_without_motion << ",\n  \"frames_side_skipped\": {";
  bool first_side = true;
  for (const auto& [camera, n] : frames_side_skipped) {
    o << (first_side ? "" : ", ") << JsonString(camera) << ": " << n;
    first_side = false;
  }
  o << "},\n  \"detections\": " << detections
    << ",\n  \"front_vertical_offset_px\": " << front_vertical_offset_px << ",\n  \"map_video\": " << JsonString(map_video)
    << ",\n  \"seconds\": " << seconds << ",\n  \"frames_per_second\": " << frames_per_second
    << ",\n  \"masks\": {";
  bool first_mask = true;
  for (const auto& [camera, m] : masks) {
    o << (first_mask ? "" : ", ") << JsonString(camera) << ": {\"source\": " << JsonString(m.source)
      << ", \"valid_fraction\": " << m.valid_fraction << ", \"own_car\": " << JsonString(m.own_car_source)
      << ", \"own_car_fraction\": " << m.own_car_fraction << "}";
    first_mask = false;
  }
  o << "},\n  \"coverage\": [";
  for (size_t k = 0; k < coverage.sectors.size(); ++k) {
    const Sector& c = coverage.sectors[k];
    o << (k ? ", " : "") << "{\"name\": " << JsonString(c.name) << ", \"apex_m\": [" << c.apex.x() << ", " << c.apex.y()
      << "], \"direction_deg\": " << c.direction_rad / kRadPerDeg << ", \"half_angle_deg\": " << c.half_angle_rad / kRadPerDeg
      << ", \"start_m\": " << c.start_m;
    if (c.max_depth_m > 0) {
      o << ", \"max_depth_m\": " << c.max_depth_m << ", \"depth_direction_deg\": " << c.depth_direction_rad / kRadPerDeg;
    }
    o << "}";
  }
  o << "]";
  if (!extrinsics.empty()) {
    o << ",\n  \"extrinsic_correction\": {";
    bool first_camera = true;
    for (const auto& [camera, e] : extrinsics) {
      o << (first_camera ? "" : ", ") << JsonString(camera) << ": {\"applied\": " << (e.applied ? "true" : "false")
        << ", \"verified\": " << (e.verified ? "true" : "false")
        << ", \"pitch_deg\": " << e.rotation_deg.x() << ", \"yaw_deg\": " << e.rotation_deg.y()
        << ", \"roll_deg\": " << e.rotation_deg.z() << ", \"sigma_deg\": [" << e.sigma_deg.x() << ", "
        << e.sigma_deg.y() << ", " << e.sigma_deg.z() << "], \"tracks\": " << e.tracks << ", \"frame_pairs\": " << e.pairs
        << ", \"rms_px\": " << e.rms_px << ", \"rms_before_px\": " << e.rms_before_px
        << ", \"reason\": " << JsonString(e.reason) << "}";
      first_camera = false;
    }
    o << "}";
  }
  if (grid_every > 0) {
    o << ",\n  \"grid\": {\"files\": \"grid/NNNNNN.png, grid/grid.csv\", \"every\": " << grid_every
      << ", \"cell_m\": " << grid_cell_m << ", \"cells\": " << grid_cells << ", \"evidence_per_step\": "
      << 1.0 / grid_scale << ", \"zero\": 32768}";
  }
  o << ",\n  \"stage_seconds\": {";
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
  // The drive's own name, also for "." or "d/".
  return (fs::path(out_root) / fs::path(AbsolutePath(drive_dir)).filename()).string();
}

bool DriveOutputComplete(const std::string& output_dir) {
  return fs::exists(fs::path(output_dir) / "summary.json");
}

namespace {

// A drive's inputs: the rig, both image streams, frame times and the CAN log.
struct DriveInput {
  Rig rig;
  std::unique_ptr<FrameSource> left, right;
  int frames = 0;
  std::vector<long> numbers;  // the image numbers processed, left and right alike
  std::vector<int> ids;       // each one's frame in the outputs: its number - the first one's
  std::vector<double> times;
  CanLog can;
};

// Consecutive frames more than max_gap median intervals apart, named by their ids.
std::vector<std::string> FrameGaps(const std::vector<double>& times, const std::vector<int>& ids, double max_gap) {
  if (times.size() < 3) return {};  // two steps at least
  std::vector<double> steps;
  for (size_t i = 1; i < times.size(); ++i) steps.push_back(times[i] - times[i - 1]);
  std::vector<double> sorted = steps;  // the lower median: a missing frame only lengthens steps
  std::nth_element(sorted.begin(), sorted.begin() + (sorted.size() - 1) / 2, sorted.end());
  const double median = sorted[(sorted.size() - 1) / 2];
  std::vector<std::string> gaps;
  for (size_t i = 0; i < steps.size(); ++i) {
    if (steps[i] > max_gap * median) {
      gaps.push_back(Str("frames ", ids[i], " and ", ids[i + 1], " are ", steps[i], " s apart, ", steps[i] / median,
                         " times the median interval of ", median, " s: a frame is missing"));
    }
  }
  return gaps;
}

DriveInput OpenDrive(const std::string& drive_dir, const DriveOptions& o, DriveSummary* s) {
  if (!fs::is_directory(drive_dir)) throw Error(Str(drive_dir, ": not a folder"));
  DriveInput in;
  in.rig = ReadRig((fs::path(drive_dir) / "rig.yaml").string());
  in.left = FrameSource::Open(drive_dir, "left", o.allow_frame_gaps);
  in.right = FrameSource::Open(drive_dir, "right", o.allow_frame_gaps);
  // Left and right frames pair by number (image folders; videos carry none and start at 0).
  const std::vector<long> ln = in.left->numbers(), rn = in.right->numbers();
  if (ln.empty() || rn.empty()) throw Error(Str(drive_dir, ": ", (ln.empty() ? in.left : in.right)->description(), " has no frames"));
  std::set_intersection(ln.begin(), ln.end(), rn.begin(), rn.end(), std::back_inserter(in.numbers));
  const std::string frames = Str(in.left->description(), " has frames ", ln.front(), "..", ln.back(), ", ",
                                 in.right->description(), " has ", rn.front(), "..", rn.back());
  if (ln.front() != rn.front() || ln.back() != rn.back()) {
    if (!o.truncate) throw Error(Str(drive_dir, ": ", frames, " (--truncate keeps the frame numbers both have)"));
    if (in.numbers.empty()) throw Error(Str(drive_dir, ": ", frames, ": no frame number in both"));
    s->warnings.push_back(Str(frames, "; processing frames ", in.numbers.front(), "..", in.numbers.back(),
                              ", those both have, as frames 0..", in.numbers.back() - in.numbers.front()));
  }
  const long first = in.numbers.front(), base = std::min(ln.front(), rn.front());
  const long span = in.numbers.back() - first + 1;
  if (static_cast<long>(in.numbers.size()) != span) {
    // Only with allow_frame_gaps: image folders with gaps open only then.
    s->warnings.push_back(Str(span - static_cast<long>(in.numbers.size()), " of frames ", first, "..", in.numbers.back(),
                              " missing in ", in.left->description(), " or ", in.right->description(),
                              "; processing the ", in.numbers.size(), " both have, across the gaps"));
  }
  in.frames = static_cast<int>(in.numbers.size());
  for (const long n : in.numbers) in.ids.push_back(static_cast<int>(n - first));
  const fs::path frames_csv = fs::path(drive_dir) / "frames.csv";
  if (fs::exists(frames_csv)) {
    // Frame k of frames.csv is image number (the smaller first number) + k.
    const std::vector<double> listed = ReadFrameTimes(frames_csv.string());
    if (static_cast<long>(listed.size()) < in.numbers.back() - base + 1) {
      throw Error(Str(frames_csv.string(), ": ", listed.size(), " frames listed, the images have ", in.numbers.back() - base + 1));
    }
    for (const long n : in.numbers) in.times.push_back(listed[static_cast<size_t>(n - base)]);
    for (const std::string& gap : FrameGaps(in.times, in.ids, o.max_frame_gap)) {
      if (!o.allow_frame_gaps) throw Error(Str(frames_csv.string(), ": ", gap, " (--allow-gaps processes across it)"));
      s->warnings.push_back(Str("frames.csv: ", gap));
    }
  } else {
    const double fps = in.left->fps() > 0 ? in.left->fps() : o.image_fps;
    for (const long n : in.numbers) in.times.push_back(static_cast<double>(n - base) / fps);
  }
  in.can = ReadCanLog((fs::path(drive_dir) / "can.csv").string(), o.can);
  for (const std::string& w : in.can.warnings) s->warnings.push_back(w);
  // A log that covers none of the frames is on another clock or in another unit (nanoseconds,
  // milliseconds): every frame would silently lose its motion.
  if (in.frames > 0 && (in.can.t_end < in.times.front() || in.can.t_begin > in.times.back())) {
    throw Error(Str((fs::path(drive_dir) / "can.csv").string(), ": its times ", in.can.t_begin, "..", in.can.t_end,
                    " s do not overlap the frames' ", in.times.front(), "..", in.times.back(),
                    " s (another clock or unit? frames.csv gives frame times on the CAN clock)"));
  }
  return in;
}

// A camera's first frames, over the drive's first `seconds`.
std::vector<cv::Mat> FirstFrames(const std::string& drive_dir, const RigCamera& camera, const DriveInput& in,
                                 double seconds) {
  std::unique_ptr<FrameSource> source = FrameSource::Open(drive_dir, camera.name, true);
  std::vector<cv::Mat> frames;
  cv::Mat image;
  for (int i = 0; i < in.frames && (i == 0 || in.times[i] - in.times[0] <= seconds); ++i) {
    source->SkipTo(in.numbers[i]);
    if (!source->Read(&image)) break;
    if (image.cols != camera.model.width() || image.rows != camera.model.height()) {
      throw Error(Str(drive_dir, ": frame ", in.ids[i], ": ", camera.name, " is ", image.cols, "x", image.rows,
                      " but rig.yaml's camera is ", camera.model.width(), "x", camera.model.height()));
    }
    frames.push_back(image.clone());
  }
  if (frames.empty()) throw Error(Str(drive_dir, ": ", source->description(), " has no frame to estimate its mask from"));
  return frames;
}

// How many of the drive's first `available` frames lie within `seconds` of the first (at least one).
size_t FramesWithin(const DriveInput& in, size_t available, double seconds) {
  size_t n = std::min<size_t>(available, 1);
  while (n < available && in.times[n] - in.times[0] <= seconds) ++n;
  return n;
}

// The correction of a camera's rotation from `frames`, the drive's first (EstimateExtrinsicCorrection),
// over those of them within o.extrinsic_estimate_s of the first whose motion the CAN log gives.
ExtrinsicCorrection EstimateCorrection(const std::vector<cv::Mat>& frames, const RigCamera& camera, const DriveInput& in,
                                       const DriveOptions& o) {
  std::vector<cv::Mat> used;
  std::vector<PlanarPose> poses;
  for (size_t k = 0; k < FramesWithin(in, frames.size(), o.extrinsic_estimate_s); ++k) {
    PlanarPose pose;
    std::string why;
    if (k > 0 && !MotionBetween(in.can, in.times[0], in.times[k], &pose, &why)) break;
    used.push_back(frames[k]);
    poses.push_back(pose);
  }
  return EstimateExtrinsicCorrection(used, poses, camera, in.rig.vehicle, o.extrinsic);
}

// Each camera's mask (DESIGN.md §3.2): the drive's masks/<camera>.png, else rig.yaml's, else
// estimated from the drive's first seconds; its own car: the drive's masks/<camera>_own_car.png,
// else estimated from the same frames when the car moved over them; and, with
// o.correct_extrinsics, its rotation corrected from the road's motion in those frames.
// Returns, by camera name, its valid pixels (CameraValidMask) and its own car (empty: none).
std::map<std::string, std::pair<cv::Mat, cv::Mat>> PrepareCameras(const std::string& drive_dir, const DriveOptions& o,
                                                               DriveInput* in, DriveSummary* s) {
  std::map<std::string, std::pair<cv::Mat, cv::Mat>> masks;
  for (RigCamera& camera : in->rig.cameras) {
    if (camera.name != "left" && camera.name != "right") continue;
    const fs::path dir = fs::path(drive_dir) / "masks";
    const fs::path file = dir / (camera.name + ".png"), own_file = dir / (camera.name + "_own_car.png");
    MaskSummary& m = s->masks[camera.name];
    const bool estimate = o.estimate_masks && in->frames > 0;
    const bool field_given = fs::exists(file) || !camera.mask.empty(), own_given = fs::exists(own_file);
    // Read only when something is estimated from them.
    const bool masks_estimated = estimate && !(field_given && own_given);
    const bool correct = o.correct_extrinsics && in->frames > 1;
    std::vector<cv::Mat> frames;
    if (masks_estimated || correct) {
      frames = FirstFrames(drive_dir, camera, *in,
                           std::max(masks_estimated ? o.mask_estimate_s : 0.0, correct ? o.extrinsic_estimate_s : 0.0));
    }
    const std::vector<cv::Mat> mask_frames(frames.begin(), frames.begin() + FramesWithin(*in, frames.size(), o.mask_estimate_s));
    if (fs::exists(file)) {
      camera.mask = ReadCameraMask(file.string(), camera.model);
      m.source = "drive";
    } else if (!camera.mask.empty()) {
      m.source = "rig.yaml";
    } else if (estimate) {
      camera.mask = EstimateFieldMask(mask_frames, camera.model, o.field_mask);
      m.source = "estimated";
    } else {
      m.source = "model";
    }
    if (own_given) {
      camera.own_car = ReadCameraMask(own_file.string(), camera.model);
      m.own_car_source = "drive";
    } else if (estimate) {
      // From how far the car travelled over those frames (none known: no estimate).
      PlanarPose moved;
      std::string why;
      if (MotionBetween(in->can, in->times[0], in->times[mask_frames.size() - 1], &moved, &why)) {
        camera.own_car = EstimateOwnCarMask(mask_frames, camera, in->rig.vehicle, std::hypot(moved.x_m, moved.z_m),
                                            o.own_car_mask);
      }
      if (!camera.own_car.empty()) m.own_car_source = "estimated";
    }
    if (!camera.own_car.empty()) {
      m.own_car_fraction = static_cast<double>(cv::countNonZero(camera.own_car)) / static_cast<double>(camera.own_car.total());
    }
    if (correct) {
      const ExtrinsicCorrection& e = s->extrinsics[camera.name] = EstimateCorrection(frames, camera, *in, o);
      if (e.applied) camera = CorrectedCamera(camera, e);
    }
    const cv::Mat valid = CameraValidMask(camera);
    m.valid_fraction = static_cast<double>(cv::countNonZero(valid)) / static_cast<double>(valid.total());
    masks[camera.name] = {valid, camera.own_car};
  }
  return masks;
}

// The masks used, as pictures a user can check and correct (and put into the drive's masks/).
void WriteMasks(const std::map<std::string, std::pair<cv::Mat, cv::Mat>>& masks, const fs::path& dir) {
  fs::create_directories(dir);
  for (const auto& [name, mask] : masks) {
    for (const auto& [suffix, image] : {std::pair<const char*, const cv::Mat&>{".png", mask.first},
                                        std::pair<const char*, const cv::Mat&>{"_own_car.png", mask.second}}) {
      const std::string path = (dir / (name + suffix)).string();
      if (!image.empty() && !cv::imwrite(path, image)) throw Error(Str(path, ": cannot write the mask"));
    }
  }
}

// The pictures a drive writes into its temporary folder: the map video (H.264 in MP4 where
// OpenCV has an encoder for it, a fiftieth of MJPG's size on these pictures, else MPEG-4 part 2
// in MP4, else MJPG in AVI, else PNGs with a warning), map PNGs and the diagnostics video.
class PictureOutputs {
 public:
  PictureOutputs(const fs::path& tmp, const DriveOptions& o, const DriveInput& in, DriveSummary* s)
      : tmp_(tmp), options_(o), output_dir_(s->output_dir), diagnostics_tmp_((tmp / ".diagnostics.tmp.avi").string()) {
    if (o.map_video) OpenVideo(in, s);
    png_ = o.map_png || (o.map_video && !video_.isOpened());
    if (png_) fs::create_directories(tmp / "map");
  }

  // True when the frame's map picture is wanted (--no-video without PNGs: the CSVs alone).
  bool WantsMap() const { return video_.isOpened() || png_; }

  void WriteMap(const cv::Mat& map, int f) {
    if (video_.isOpened()) video_.write(map);
    if (png_) {
      char name[32];
      std::snprintf(name, sizeof(name), "%06d.png", f);
      if (!cv::imwrite((tmp_ / "map" / name).string(), map)) throw Error(Str(output_dir_, ": cannot write map image"));
    }
  }

  // The six diagnostic panels of each source, side by side; frame `middle`'s also as a PNG.
  void WriteDiagnostics(const FrameOutput& out, const PipelineOptions& po, int f, int middle) {
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
    if (po.rears) {
      // The rear views: current and warped earlier view, their composite, what is not road (white)
      // and the contacts (grey).
      cv::hconcat(std::vector<cv::Mat>{all,
                                       DrawDiagnostics("left rear", out.left_rear.view, out.left_rear.warped, {}, {},
                                                       out.left_rear.obstacle, 0, 1, panel),
                                       DrawDiagnostics("right rear", out.right_rear.view, out.right_rear.warped, {},
                                                       {}, out.right_rear.obstacle, 0, 1, panel)},
                  all);
    }
    if (!diagnostics_.isOpened()) {
      diagnostics_.open(diagnostics_tmp_, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10.0, all.size());
      if (!diagnostics_.isOpened()) throw Error(Str(output_dir_, ": cannot open a video writer for diagnostics"));
    }
    diagnostics_.write(all);
    if (f == middle) cv::imwrite((tmp_ / "diagnostics_middle.png").string(), all);
  }

  // Closes the videos under their final names in the temporary folder.
  void Close() {
    if (video_.isOpened()) {
      video_.release();
      RenameReplacing(video_tmp_, (tmp_ / video_name_).string());
    }
    if (diagnostics_.isOpened()) {
      diagnostics_.release();
      RenameReplacing(diagnostics_tmp_, (tmp_ / "diagnostics.avi").string());
    }
  }

 private:
  void OpenVideo(const DriveInput& in, DriveSummary* s) {
    const int frames = in.frames;
    const std::vector<double>& times = in.times;
    const double fps = frames > 1 ? std::max(1.0, (frames - 1) / std::max(1e-6, times[frames - 1] - times[0])) : 10.0;
    const struct {
      const char* name;
      const char* codec;
      int fourcc;
    } formats[] = {{"map.mp4", "H.264", cv::VideoWriter::fourcc('a', 'v', 'c', '1')},
                   {"map.mp4", "MPEG-4 part 2", cv::VideoWriter::fourcc('m', 'p', '4', 'v')},
                   {"map.avi", "MJPG", cv::VideoWriter::fourcc('M', 'J', 'P', 'G')}};
    for (const auto& f : formats) {
      video_name_ = f.name;
      video_tmp_ = (tmp_ / (".tmp." + video_name_)).string();  // the extension picks the container
      if (video_.open(video_tmp_, f.fourcc, fps, cv::Size(options_.map.size_px, options_.map.size_px))) {
        s->map_video = Str(f.name, " (", f.codec, ")");
        break;
      }
    }
    if (!video_.isOpened()) s->warnings.push_back("no video encoder; writing map/ PNGs instead");
  }

  fs::path tmp_;
  const DriveOptions& options_;
  std::string output_dir_;
  cv::VideoWriter video_, diagnostics_;
  std::string video_tmp_, video_name_, diagnostics_tmp_;
  bool png_ = false;
};

// The pipeline's options for a drive. When both front cameras' rotations were verified from the
// road (the three angles of each; corrected or found right), the front pair's drift correction -
// the rows' offset alone, measured on a few corners that may lie on the own car - has nothing left
// to correct and only adds its noise: it is off.
PipelineOptions DrivePipelineOptions(const DriveOptions& o, const Rig& rig, const DriveSummary& s) {
  PipelineOptions p = o.default_pipeline ? DefaultPipelineOptions(rig) : o.pipeline;
  if (o.default_pipeline) {
    p.rears = o.rear;
    if (o.reach_forward) p.side_forward_max_deg = kSideForwardReachDeg;
  }
  bool verified = true;
  for (const char* camera : {"left", "right"}) {
    const auto it = s.extrinsics.find(camera);
    verified = verified && it != s.extrinsics.end() && it->second.verified;
  }
  if (verified) p.front.drift_interval = 0;
  return p;
}

// One drive's run: the pipeline over its frames, then tracking, the grid, the map and the files.
class DriveRun {
 public:
  DriveRun(const std::string& drive_dir, const DriveOptions& o, DriveInput& in, const fs::path& tmp, DriveSummary* s)
      : drive_dir_(drive_dir),
        o_(o),
        in_(in),
        tmp_(tmp),
        s_(*s),
        pipeline_options_(DrivePipelineOptions(o, in.rig, *s)),
        pipeline_(in.rig, pipeline_options_),
        tracker_(o.tracker),
        grid_(o.occupancy),
        pictures_(tmp, o, in, s),
        map_backgrounds_(in.rig.vehicle, o.map, 16,
                         pictures_.WantsMap() ? RoadNoCameraSees(in.rig, pipeline_options_.lane.own_car_height_m, o.map)
                                              : cv::Mat()) {}

  void Run(const std::function<void(int, int)>& progress);
  void WriteFiles();

 private:
  void Finish(FrameOutput& out, int f);
  void WriteGrid(int f);
  void Read(FrameSource& source, cv::Mat* image, int f);
  FrameInput Input(const cv::Mat& l, const cv::Mat& r, int f);

  const std::string& drive_dir_;
  const DriveOptions& o_;
  DriveInput& in_;
  fs::path tmp_;
  DriveSummary& s_;
  const PipelineOptions pipeline_options_;
  SurroundPipeline pipeline_;
  std::vector<Detection> detections_;
  Tracker tracker_;
  std::vector<TrackState> tracks_;
  std::vector<LaneBoundaryRow> lanes_;  // lanes.csv's rows
  std::vector<EgoLaneRow> ego_lane_;    // ego_lane.csv's rows
  PlanarPose ego_;  // the vehicle in the tracker's world (its pose at frame 0)
  OccupancyGrid grid_;
  PictureOutputs pictures_;
  MapBackgrounds map_backgrounds_;  // per frame: the sectors it measured, its motion's blind wedges
  cv::Mat map_;  // the frame's map picture, drawn into the same buffer every frame
  std::ostringstream grid_index_;  // grid/grid.csv's rows
  double decode_ = 0, front_ = 0, sides_ = 0, map_s_ = 0, write_ = 0;
  std::mutex decode_mutex_;
};

// What follows the stereo for one frame: tracking, the occupancy grid, the map picture and
// writing. It runs alongside the next frame's stereo (SurroundPipeline::Process), in order.
void DriveRun::Finish(FrameOutput& out, int f) {
  auto t2 = Clock::now();
  s_.frames_side_skipped["left"] += out.left.skipped;
  s_.frames_side_skipped["right"] += out.right.skipped;
  std::vector<TrackState> frame_tracks = tracker_.Update(in_.ids[f], in_.times[f], ego_, out.detections);
  for (TrackState& t : frame_tracks) {
    t.lane = LaneOfPoint(out.lanes.boundaries, {t.x_m, t.z_m});
    t.object_class = ObjectClassName(
        ClassifyObject(std::max(t.length_m, t.width_m), t.height_m, pipeline_options_.classes));
  }
  char caption[128];
  std::snprintf(caption, sizeof(caption), "%s  frame %d  t %.2f s  %zu objects", s_.drive.c_str(), in_.ids[f], in_.times[f],
                out.detections.size());
  grid_.Update(in_.times[f], ego_, out.coverage, out.detections);
  if (o_.grid_obstacles) {
    std::map<std::string, int> next_id;
    for (const Detection& d : out.detections) next_id[d.source] = std::max(next_id[d.source], d.id + 1);
    const SameObject same{pipeline_options_.merge_distance_m, pipeline_options_.vehicle_length_m,
                          pipeline_options_.vehicle_width_m};
    for (Detection& d : GridObstacles(grid_, ego_, out.coverage, out.detections, same, o_.grid_obstacle)) {
      d.frame = in_.ids[f];
      d.t_s = in_.times[f];
      d.id = next_id[d.source]++;
      SetAttributes(out.lanes.boundaries, pipeline_options_.classes, &d);
      out.detections.push_back(std::move(d));
    }
  }
  if (o_.grid_every > 0 && f % o_.grid_every == 0) WriteGrid(f);
  if (pictures_.WantsMap()) {
    DrawFrameMap(map_backgrounds_.For(out.coverage), grid_, in_.rig.vehicle, out.detections, frame_tracks, o_.map,
                 caption, map_);
    DrawLanes(map_, out.lanes.boundaries, o_.map);
    if (out.lanes.has_ego) DrawEgoLane(map_, out.lanes.ego);
  }
  for (const TrackState& t : frame_tracks) {
    if (t.confirmed) tracks_.push_back(t);
  }
  auto t3 = Clock::now();
  map_s_ += Seconds(t2, t3);
  if (pictures_.WantsMap()) pictures_.WriteMap(map_, in_.ids[f]);
  if (o_.diagnostics) pictures_.WriteDiagnostics(out, pipeline_options_, f, in_.frames / 2);
  write_ += Seconds(t3, Clock::now());
  for (Detection& d : out.detections) detections_.push_back(std::move(d));
  for (LaneBoundaryRow b : out.lanes.boundaries) {
    b.frame = in_.ids[f], b.t_s = in_.times[f];
    lanes_.push_back(b);
  }
  if (out.lanes.has_ego) {
    EgoLaneRow e = out.lanes.ego;
    e.frame = in_.ids[f], e.t_s = in_.times[f];
    ego_lane_.push_back(e);
  }
}

// Frame f's grid as grid/<frame>.png, with its row of grid.csv.
void DriveRun::WriteGrid(int f) {
  if (grid_index_.tellp() == 0) {
    fs::create_directories(tmp_ / "grid");
    grid_index_ << "frame,t,file,origin_x,origin_z,vehicle_x,vehicle_z,vehicle_heading_deg\n";
  }
  char name[32];
  std::snprintf(name, sizeof(name), "%06d.png", in_.ids[f]);
  if (!cv::imwrite((tmp_ / "grid" / name).string(), grid_.EvidenceImage())) {
    throw Error(Str(s_.output_dir, ": cannot write grid/", name));
  }
  grid_index_ << in_.ids[f] << ',' << Str(in_.times[f]) << ",grid/" << name << ',' << Str(grid_.origin().x()) << ','
              << Str(grid_.origin().y()) << ',' << Str(ego_.x_m) << ',' << Str(ego_.z_m) << ','
              << Str(ego_.heading_rad * kDegPerRad) << '\n';
}

// Decoding: frame f + 1's two images are read alongside frame f's stereo, each by its own task
// (seconds summed over both).
void DriveRun::Read(FrameSource& source, cv::Mat* image, int f) {
  const auto t0 = Clock::now();
  source.SkipTo(in_.numbers[f]);
  if (!source.Read(image)) {
    throw Error(Str(drive_dir_, ": frame ", in_.ids[f], " could not be read (the stream ended early)"));
  }
  const double seconds = Seconds(t0, Clock::now());
  std::lock_guard<std::mutex> lock(decode_mutex_);
  decode_ += seconds;
}

// Frame f's images checked against each other and the rig, with the motion since frame f - 1.
FrameInput DriveRun::Input(const cv::Mat& l, const cv::Mat& r, int f) {
  const CameraModel& model = in_.rig.Camera("left").model;
  if (l.size() != r.size()) {
    throw Error(Str(drive_dir_, ": frame ", in_.ids[f], ": left is ", l.cols, "x", l.rows, ", right ", r.cols, "x", r.rows));
  }
  if (l.cols != model.width() || l.rows != model.height()) {
    throw Error(Str(drive_dir_, ": frame ", in_.ids[f], " is ", l.cols, "x", l.rows, " but rig.yaml's cameras are ",
                    model.width(), "x", model.height()));
  }
  FrameInput input;
  input.frame = in_.ids[f];
  input.t_s = in_.times[f];
  input.left = l;
  input.right = r;
  if (f > 0) {
    std::string why;
    input.motion_known = MotionBetween(in_.can, in_.times[f - 1], in_.times[f], &input.current_in_previous, &why);
    if (!input.motion_known) {
      ++s_.frames_without_motion;
      s_.warnings.push_back(Str("frame ", in_.ids[f], ": no known motion (", why, "); side detection skipped"));
    }
  }
  return input;
}

void DriveRun::Run(const std::function<void(int, int)>& progress) {
  const int frames = in_.frames;
  FrameOutput pending;  // the previous frame's, not yet finished
  cv::Mat l, r, next_l, next_r;
  if (frames > 0) {
    Read(*in_.left, &l, 0);
    Read(*in_.right, &r, 0);
  }
  for (int f = 0; f < frames; ++f) {
    const FrameInput input = Input(l, r, f);
    std::vector<std::function<void()>> alongside;
    if (f > 0) alongside.push_back([&] { Finish(pending, f - 1); });
    if (f + 1 < frames) {
      alongside.push_back([&] { Read(*in_.left, &next_l, f + 1); });
      alongside.push_back([&] { Read(*in_.right, &next_r, f + 1); });
    }
    FrameOutput out = pipeline_.Process(input, alongside);
    if (input.motion_known) ego_ = Compose(ego_, input.current_in_previous);
    s_.front_vertical_offset_px = out.front.vertical_offset_px;
    front_ += out.front_ms / 1000.0;
    sides_ += out.sides_ms / 1000.0;
    pending = std::move(out);
    std::swap(l, next_l);
    std::swap(r, next_r);
    if (progress && f > 0) progress(f, frames);
  }
  if (frames > 0) Finish(pending, frames - 1);
  if (progress && frames > 0) progress(frames, frames);
}

void DriveRun::WriteFiles() {
  auto t4 = Clock::now();
  pictures_.Close();
  WriteDetections(detections_, (tmp_ / "detections.csv").string());
  WriteTracks(tracks_, (tmp_ / "tracks.csv").string());
  if (pipeline_options_.lanes) {
    WriteLaneBoundaries(lanes_, (tmp_ / "lanes.csv").string());
    WriteEgoLane(ego_lane_, (tmp_ / "ego_lane.csv").string());
  }
  if (o_.grid_every > 0) {
    WriteFileAtomically((tmp_ / "grid" / "grid.csv").string(), grid_index_.str());
    s_.grid_every = o_.grid_every;
    s_.grid_cell_m = grid_.options().cell_m;
    s_.grid_cells = grid_.options().cells;
    s_.grid_scale = grid_.EvidenceScale();
  }
  write_ += Seconds(t4, Clock::now());
  s_.coverage = pipeline_.coverage();
  s_.frames = in_.frames;
  s_.detections = static_cast<int>(detections_.size());
  s_.stage_seconds = {{"decode", decode_}, {"front", front_}, {"sides", sides_}, {"map", map_s_}, {"write", write_}};
}

}  // namespace

void DriveOptions::Check() const {
  const OptionCheck Require("drive");
  Require(image_fps > 0 && image_fps <= 10000, "image_fps", image_fps, "0 < fps <= 10000");
  Require(mask_estimate_s > 0, "mask_estimate_s", mask_estimate_s, "> 0");
  Require(extrinsic_estimate_s > 0, "extrinsic_estimate_s", extrinsic_estimate_s, "> 0");
  extrinsic.Check();
  Require(grid_every >= 0, "grid_every", grid_every, ">= 0");
  Require(max_frame_gap > 1 && max_frame_gap <= 1000, "max_frame_gap", max_frame_gap, "1 < gap <= 1000 intervals");
  Require(can.max_gap_s > 0, "can.max_gap_s", can.max_gap_s, "> 0");
  Require(std::isfinite(can.speed_scale) && can.speed_scale != 0, "can.speed_scale", can.speed_scale, "finite and != 0");
  Require(std::isfinite(can.yaw_rate_scale), "can.yaw_rate_scale", can.yaw_rate_scale, "finite");
  if (!default_pipeline) pipeline.Check();
  map.Check();
  tracker.Check();
  occupancy.Check();
  grid_obstacle.Check();
  field_mask.Check();
  own_car_mask.Check();
}

DriveSummary ProcessDrive(const std::string& drive_dir, const std::string& out_root, const DriveOptions& o,
                          const std::function<void(int, int)>& progress) {
  o.Check();
  const auto start = Clock::now();
  DriveSummary s;
  s.output_dir = DriveOutputDir(drive_dir, out_root);
  s.drive = fs::path(s.output_dir).filename().string();
  CheckOutputFolder(s.output_dir, {drive_dir});
  CheckReplaceable(s.output_dir, "summary.json");
  DriveInput in = OpenDrive(drive_dir, o, &s);
  const auto cameras_start = Clock::now();
  const std::map<std::string, std::pair<cv::Mat, cv::Mat>> masks = PrepareCameras(drive_dir, o, &in, &s);
  const double cameras_s = Seconds(cameras_start, Clock::now());
  // Outputs under a temporary name.
  fs::create_directories(out_root);
  const fs::path tmp = TemporaryFolderFor(s.output_dir);  // (and killed runs' ones removed)
  fs::remove_all(tmp);
  fs::create_directories(tmp);
  try {
    WriteMasks(masks, tmp / "masks");
    DriveRun run(drive_dir, o, in, tmp, &s);
    run.Run(progress);
    run.WriteFiles();
    s.stage_seconds["cameras"] = cameras_s;
    s.seconds = Seconds(start, Clock::now());
    s.frames_per_second = s.seconds > 0 ? in.frames / s.seconds : 0;
    WriteFileAtomically((tmp / "summary.json").string(), s.ToJson());  // last: marks completion
  } catch (...) {
    std::error_code ec;
    fs::remove_all(tmp, ec);
    throw;
  }
  ReplaceFolder(tmp.string(), s.output_dir, "summary.json");
  return s;
}

}  // namespace dps
