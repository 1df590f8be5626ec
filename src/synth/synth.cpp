#include "dps/synth/synth.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "dps/calib/marks_io.h"
#include "dps/camera/rig_io.h"
#include "dps/synth/lane_truth.h"
#include "dps/synth/truth_io.h"
#include "dps/util/atomic_file.h"
#include "dps/util/error.h"
#include "dps/util/image.h"
#include "dps/util/math.h"

namespace dps {
namespace {

namespace fs = std::filesystem;

constexpr double kCanRateHz = 100.0;

// A deterministic stream of uniform and Gaussian numbers (splitmix64), the same on every
// platform, unlike std:: distributions.
class Random {
 public:
  explicit Random(std::uint64_t seed) : state_(seed * 0x9e3779b97f4a7c15ULL + 0x632be59bd9b4e019ULL) {}
  double Uniform() {
    std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    z ^= z >> 31;
    return (z >> 11) * (1.0 / 9007199254740992.0);
  }
  double Gaussian() {
    const double u1 = Uniform() + 1e-300, u2 = Uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.28318530717958647692 * u2);
  }

 private:
  std::uint64_t state_;
};

std::string FrameName(int frame) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%06d.png", frame);
  return buf;
}

// The range buffer as 16-bit millimetres (0 = nothing, saturating at 65535).
cv::Mat RangeToMillimetres(const cv::Mat& range_m) {
  cv::Mat mm;
  range_m.convertTo(mm, CV_16U, 1000.0);
  return mm;
}

// CAN log: the ego profile sampled at 100 Hz over the frames' time span and a little beyond.
void WriteCanLog(const Scene& scene, int frames, const std::string& path) {
  AtomicOutputFile can(path);
  can.stream() << "t,speed,yaw_rate\n";
  const double t_end = scene.FrameTime(frames - 1) + 0.2;
  for (int i = 0; i * (1.0 / kCanRateHz) <= t_end + 1e-9; ++i) {
    const MotionSample m = scene.ego.At(i / kCanRateHz);
    can.stream() << i / kCanRateHz << "," << m.speed_mps << "," << m.yaw_rate_radps << "\n";
  }
  can.Commit();
}

// Each camera's outputs in the temporary folder: image folders, MJPG videos, truth images.
class CameraOutputs {
 public:
  CameraOutputs(const Rig& rig, double fps, const fs::path& tmp, const SynthOptions& options, const std::string& out_dir)
      : tmp_(tmp), options_(options) {
    for (const RigCamera& c : rig.cameras) {
      names_.push_back(c.name);
      if (options.write_png) fs::create_directories(tmp / c.name);
      if (options.write_truth_images) {
        fs::create_directories(tmp / "range" / c.name);
        fs::create_directories(tmp / "ids" / c.name);
      }
      if (options.write_video) OpenVideo(c, fps, out_dir);
    }
  }

  void Write(size_t c, int f, const RenderedView& view) {
    if (options_.write_png) WriteImageAtomically((tmp_ / names_[c] / FrameName(f)).string(), view.image);
    if (options_.write_video) videos_[c]->write(view.image);
    if (options_.write_truth_images) {
      WriteImageAtomically((tmp_ / "range" / names_[c] / FrameName(f)).string(), RangeToMillimetres(view.range_m));
      WriteImageAtomically((tmp_ / "ids" / names_[c] / FrameName(f)).string(), view.ids);
    }
  }

  // The videos under their final names, and the codec they were written with (video_codec.txt).
  void Close() {
    for (size_t c = 0; c < videos_.size(); ++c) {
      videos_[c]->release();
      RenameReplacing(video_tmp_[c], (tmp_ / (names_[c] + video_ext_)).string());
    }
    if (!videos_.empty()) WriteFileAtomically((tmp_ / "video_codec.txt").string(), codec_ + "\n");
  }

 private:
  // MJPG in AVI, or H.264 in MP4 (MPEG-4 part 2 where OpenCV has no H.264 encoder).
  void OpenVideo(const RigCamera& c, double fps, const std::string& out_dir) {
    struct Format {
      const char* codec;
      const char* ext;
      int fourcc;
    };
    const std::vector<Format> formats =
        options_.video_codec == "H264"
            ? std::vector<Format>{{"H.264", ".mp4", cv::VideoWriter::fourcc('a', 'v', 'c', '1')},
                                  {"MPEG-4 part 2", ".mp4", cv::VideoWriter::fourcc('m', 'p', '4', 'v')}}
            : std::vector<Format>{{"MJPG", ".avi", cv::VideoWriter::fourcc('M', 'J', 'P', 'G')}};
    for (const Format& f : formats) {
      if (!codec_.empty() && codec_ != f.codec) continue;  // both cameras with the same codec
      const std::string tmp = (tmp_ / ("." + c.name + ".tmp" + f.ext)).string();
      auto writer = std::make_unique<cv::VideoWriter>(tmp, f.fourcc, fps, cv::Size(c.model.width(), c.model.height()));
      if (!writer->isOpened()) continue;
      codec_ = f.codec;
      video_ext_ = f.ext;
      video_tmp_.push_back(tmp);
      videos_.push_back(std::move(writer));
      return;
    }
    throw Error(Str(out_dir, ": cannot open a video writer (", options_.video_codec, ")"));
  }

  fs::path tmp_;
  const SynthOptions& options_;
  std::vector<std::string> names_, video_tmp_;
  std::string codec_, video_ext_;
  std::vector<std::unique_ptr<cv::VideoWriter>> videos_;
};

}  // namespace

std::vector<TruthRow> TruthAt(const FrameState& state, int frame) {
  std::vector<TruthRow> rows;
  for (size_t i = 0; i < state.boxes.size(); ++i) {
    const BoxInstance& b = state.boxes[i];
    const SceneObject& o = *b.object;
    const double speed = o.motion.At(state.t_s).speed_mps;
    const Eigen::Vector2d v_world(speed * std::sin(b.world.heading_rad),
                                  speed * std::cos(b.world.heading_rad));
    const Eigen::Vector2d v = WorldToBodyDirection(state.ego, v_world);
    double heading = std::remainder(b.heading_rad, 2.0 * kPi);
    rows.push_back({frame, state.t_s, o.id, o.kind, b.centre_xz.x(), b.centre_xz.y(),
                    heading * kDegPerRad, o.length_m, o.width_m, o.height_m, v.x(), v.y()});
  }
  return rows;
}

Rig PerturbedRig(const Scene& scene) {
  Rig rig = scene.rig;
  Random rng(scene.seed ^ 0xca11b7a7e5ULL);
  const CalibrationSettings& c = scene.calibration;
  for (RigCamera& cam : rig.cameras) {
    // A uniformly distributed axis on the sphere.
    const double z = 2.0 * rng.Uniform() - 1.0, phi = 6.28318530717958647692 * rng.Uniform();
    const Eigen::Vector3d axis(std::sqrt(1 - z * z) * std::cos(phi), std::sqrt(1 - z * z) * std::sin(phi), z);
    const double angle_deg = c.min_rotation_deg + (c.max_rotation_deg - c.min_rotation_deg) * rng.Uniform();
    cam.vehicle_from_camera.R = cam.vehicle_from_camera.R * AxisAngle(axis, angle_deg * kRadPerDeg);
  }
  return rig;
}

std::vector<Mark> SampleMarks(const SceneRenderer& renderer, const FrameState& state,
                              double noise_px, double margin_px) {
  const Scene& scene = renderer.scene();
  Random rng(scene.seed ^ 0x3a4b5c6d7eULL);
  std::vector<Mark> marks;
  const double spacing = scene.calibration.mark_spacing_m;
  for (const RigCamera& cam : scene.rig.cameras) {
    const Pose camera_from_vehicle = cam.vehicle_from_camera.Inverse();
    const CameraModel& model = cam.model;
    // A world line's visible points, as pixels.
    auto sample = [&](int line, char axis, const Eigen::Vector3d& from, const Eigen::Vector3d& to,
                      std::uint16_t expected_id) {
      const double length = (to - from).norm();
      const int n = std::max(2, static_cast<int>(length / spacing) + 1);
      std::vector<Mark> found;
      for (int i = 0; i < n; ++i) {
        const Eigen::Vector3d p_world = from + (to - from) * (i / (n - 1.0));
        const Eigen::Vector3d p = state.world_from_vehicle.Inverse().Apply(p_world);
        Eigen::Vector2d px;
        if (!model.Project(camera_from_vehicle.Apply(p), &px)) continue;
        if (px.x() < margin_px || px.y() < margin_px || px.x() > model.width() - 1 - margin_px ||
            px.y() > model.height() - 1 - margin_px) {
          continue;
        }
        if (model.rim_radius_px() > 0.0 &&
            (px - model.K().block<2, 1>(0, 2)).norm() > model.rim_radius_px() - margin_px) {
          continue;
        }
        // Visible: the ray towards the point meets the line's own surface first.
        const Eigen::Vector3d d = (p - cam.vehicle_from_camera.t).normalized();
        const RayHit hit = renderer.Cast(state, cam.vehicle_from_camera.t, d);
        const double dist = (p - cam.vehicle_from_camera.t).norm();
        if (hit.id != expected_id) continue;
        if (axis != 'Y' && std::abs(hit.distance_m - dist) > 0.02 * dist) continue;
        found.push_back({cam.name, line, axis, px.x(), px.y(), 0});
      }
      if (found.size() < 3) return;
      for (Mark& m : found) {
        m.u += noise_px * rng.Gaussian();
        m.v += noise_px * rng.Gaussian();
        marks.push_back(m);
      }
    };
    int line = 1;
    for (const PaintedLine& l : scene.lines) {
      sample(line++, l.axis, {l.from_xz.x(), 0.0, l.from_xz.y()}, {l.to_xz.x(), 0.0, l.to_xz.y()},
             kIdPaint);
    }
    for (const SceneObject& o : scene.objects) {
      if (o.kind != "pole") continue;
      const PlanarPose p = o.PoseAt(state.t_s);
      sample(100 + o.id, 'Y', {p.x_m, -0.1, p.z_m}, {p.x_m, -(o.height_m - 0.1), p.z_m},
             static_cast<std::uint16_t>(kIdObjectBase + o.id));
    }
  }
  return marks;
}

void Synthesize(const Scene& scene_in, const std::string& out_dir, const SynthOptions& options) {
  if (!options.write_png && !options.write_video) {
    throw Error("nothing to write: choose PNG images and/or video");
  }
  if (options.video_codec != "MJPG" && options.video_codec != "H264") {
    throw Error("video codec '" + options.video_codec + "': expected MJPG or H264");
  }
  const fs::path out(AbsolutePath(out_dir));
  if (fs::exists(out) && !options.overwrite) {
    throw Error(Str(out_dir, ": already exists (use --force to replace it)"));
  }
  CheckOutputFolder(out_dir, {});
  CheckReplaceable(out_dir, kSynthMarker);
  const bool calibration = scene_in.kind == SceneKind::kCalibration;
  // The rig that renders: for a calibration scene the perturbed "true" rig.
  Scene scene = scene_in;
  if (calibration && !options.processing_rig) scene.rig = PerturbedRig(scene_in);
  const int frames = options.frames > 0 ? options.frames : scene.FrameCount();
  if (out.has_parent_path() && !out.parent_path().empty()) fs::create_directories(out.parent_path());
  const fs::path tmp = TemporaryFolderFor(out.string());  // (and killed runs' ones removed)
  fs::remove_all(tmp);
  fs::create_directories(tmp);
  try {
    const SceneRenderer renderer(scene);
    WriteFileAtomically((tmp / kSynthMarker).string(), "written by dps-synth; dps-synth --force may replace this folder\n");
    WriteRig(options.processing_rig ? *options.processing_rig : scene_in.rig, (tmp / "rig.yaml").string());
    if (calibration || options.processing_rig) WriteRig(scene.rig, (tmp / "rig_true.yaml").string());
    for (const auto& [name, content] : options.extra_files) WriteFileAtomically((tmp / name).string(), content);
    WriteCanLog(scene, frames, (tmp / "can.csv").string());
    CameraOutputs cameras(scene.rig, scene.fps, tmp, options, out_dir);
    AtomicOutputFile frames_csv((tmp / "frames.csv").string());
    frames_csv.stream() << "frame,t\n";
    std::vector<TruthRow> truth;
    for (int f = 0; f < frames; ++f) {
      const double t = scene.FrameTime(f);
      const FrameState state = renderer.StateAt(t);
      frames_csv.stream() << f << "," << t << "\n";
      for (const TruthRow& r : TruthAt(state, f)) truth.push_back(r);
      for (size_t c = 0; c < scene.rig.cameras.size(); ++c) cameras.Write(c, f, renderer.Render(state, c, f));
      if (calibration && f == 0) {
        WriteMarks(SampleMarks(renderer, state, scene.calibration.mark_noise_px),
                   (tmp / "marks.csv").string());
      }
      if (options.progress) options.progress(f + 1, frames);
    }
    frames_csv.Commit();
    WriteTruth(truth, (tmp / "truth.csv").string());
    if (!calibration) {
      // What each camera sees of the world past the own car: dps-eval --masks (visibility).
      fs::create_directories(tmp / "truth_masks");
      for (size_t c = 0; c < scene.rig.cameras.size(); ++c) {
        const std::string path = (tmp / "truth_masks" / (scene.rig.cameras[c].name + ".png")).string();
        if (!cv::imwrite(path, renderer.WorldMask(c))) throw Error(Str(out_dir, ": cannot write ", path));
      }
    }
    if (!calibration && scene.road.enabled) {
      LaneTruth lanes = LaneTruthOf(scene);
      // The rendered frames only (--frames may cut the drive short).
      const auto rendered = [frames](const auto& row) { return row.frame >= frames; };
      lanes.boundaries.erase(std::remove_if(lanes.boundaries.begin(), lanes.boundaries.end(), rendered), lanes.boundaries.end());
      lanes.ego.erase(std::remove_if(lanes.ego.begin(), lanes.ego.end(), rendered), lanes.ego.end());
      WriteLaneBoundaries(lanes.boundaries, (tmp / "truth_lanes.csv").string());
      WriteEgoLane(lanes.ego, (tmp / "truth_ego_lane.csv").string());
    }
    cameras.Close();
  } catch (...) {
    std::error_code ec;
    fs::remove_all(tmp, ec);
    throw;
  }
  ReplaceFolder(tmp.string(), out_dir, kSynthMarker);
}

}  // namespace dps
