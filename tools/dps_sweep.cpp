// dps-sweep: one frame's plane-sweep depth in every direction each camera sees (seed 004 §4.2).
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <limits>

#include "cli.h"
#include "dps/camera/rig_io.h"
#include "dps/camera/valid_mask.h"
#include "dps/pipeline/drive_io.h"
#include "dps/stereo/disparity_io.h"
#include "dps/stereo/plane_sweep.h"
#include "dps/util/image.h"

namespace fs = std::filesystem;

namespace {

const char* kUsage = R"(usage: dps-sweep DRIVE_DIR --frame N --out DIR [options]

Plane-sweep motion stereo on the raw images (seed 004 §4.2, docs/stereo.md): each camera's frame N
against frame N - K, the camera's motion between them from can.csv (speed and yaw rate), swept
through the road plane and distances along each pixel's ray. Every direction the camera sees gets
a distance, except near the motion's epipoles (straight ahead and behind when driving straight),
which are said to be unobservable rather than guessed. Writes into DIR, per camera:
  <camera>_sweep.png     the image with obstacle pixels coloured by distance, road green,
                         unobservable magenta, no surface found grey (a legend in the corner)
  <camera>_distance.pfm  the distance along each pixel's ray, metres (inf: none)
The cameras' valid pixels: the drive's masks/<camera>.png, else rig.yaml's mask, else the
model's field (dps-process writes the masks it used to OUT/<drive>/masks/).

  --frame N            the frame measured (0-based, by position; N - K >= 0)
  --back K             the earlier frame, K frames before (default 1; farther back for more
                       parallax behind and ahead)
  --camera NAME        only this camera (default: every camera of the rig)
  --max-distance M     farthest distance hypothesis, metres (default 40)
  --image-fps F        frame rate of image folders without frames.csv (default 30)
  --out DIR            output folder (created)
  --help               this text
)";

// Frame `index` (by position) and frame `index - back` of one camera, grey.
std::pair<cv::Mat, cv::Mat> ReadPair(const std::string& drive, const dps::RigCamera& camera, int index, int back) {
  const std::unique_ptr<dps::FrameSource> source = dps::FrameSource::Open(drive, camera.name, true);
  const std::vector<long> numbers = source->numbers();
  if (index >= static_cast<int>(numbers.size())) {
    throw dps::Error(dps::Str(source->description(), ": has ", numbers.size(), " frames, no frame ", index));
  }
  cv::Mat earlier, current;
  source->SkipTo(numbers[static_cast<size_t>(index - back)]);
  if (!source->Read(&earlier)) throw dps::Error(dps::Str(source->description(), ": cannot read frame ", index - back));
  source->SkipTo(numbers[static_cast<size_t>(index)]);
  if (!source->Read(&current)) throw dps::Error(dps::Str(source->description(), ": cannot read frame ", index));
  for (const cv::Mat* m : {&earlier, &current}) {
    if (m->cols != camera.model.width() || m->rows != camera.model.height()) {
      throw dps::Error(dps::Str(source->description(), ": frames are ", m->cols, "x", m->rows, " but rig.yaml's ",
                                camera.name, " is ", camera.model.width(), "x", camera.model.height()));
    }
  }
  return {dps::GreyImage(earlier), dps::GreyImage(current)};
}

// The times of frames `earlier` and `current` (by position): frames.csv, read once, else the
// camera's video frame rate or --image-fps.
std::pair<double, double> FrameTimes(const std::string& drive, const dps::RigCamera& camera, int earlier, int current,
                                     double image_fps) {
  const fs::path frames = fs::path(drive) / "frames.csv";
  if (fs::exists(frames)) {
    const std::vector<double> times = dps::ReadFrameTimes(frames.string());
    if (current >= static_cast<int>(times.size())) {
      throw dps::Error(dps::Str(frames.string(), ": lists ", times.size(), " frames, no frame ", current));
    }
    return {times[static_cast<size_t>(earlier)], times[static_cast<size_t>(current)]};
  }
  const double fps = dps::FrameSource::Open(drive, camera.name, true)->fps();
  const double rate = fps > 0 ? fps : image_fps;
  return {earlier / rate, current / rate};
}

}  // namespace

int main(int argc, char** argv) {
  return dps_cli::Run("dps-sweep", [&] {
    const dps_cli::Args args(argc, argv, {"frame", "back", "camera", "max-distance", "image-fps", "out"}, {});
    if (args.help()) {
      std::cout << kUsage;
      return 0;
    }
    if (args.positional().size() != 1) throw dps::Error("expected one DRIVE_DIR (see --help)");
    args.Require("frame", "N");
    args.Require("out", "DIR");
    const std::string drive = args.positional()[0];
    const int frame = args.Integer("frame", 0), back = args.Integer("back", 1);
    if (back < 1 || frame - back < 0) {
      throw dps::Error(dps::Str("--frame ", frame, " --back ", back, ": expected back >= 1 and frame - back >= 0"));
    }
    const double image_fps = args.Number("image-fps", 30.0);
    if (!(image_fps > 0)) throw dps::Error("option --image-fps: expected > 0");
    dps::PlaneSweepOptions options;
    options.max_distance_m = args.Number("max-distance", options.max_distance_m);
    options.Check();
    dps::Rig rig = dps::ReadRig((fs::path(drive) / "rig.yaml").string());
    const dps::CanLog can = dps::ReadCanLog((fs::path(drive) / "can.csv").string());
    const std::string out = args.Get("out");
    int written = 0;
    for (dps::RigCamera& camera : rig.cameras) {
      if (args.Has("camera") && camera.name != args.Get("camera")) continue;
      const fs::path mask = fs::path(drive) / "masks" / (camera.name + ".png");
      if (fs::exists(mask)) camera.mask = dps::ReadCameraMask(mask.string(), camera.model);
      const auto [t0, t1] = FrameTimes(drive, camera, frame - back, frame, image_fps);
      dps::PlanarPose moved;
      std::string why;
      if (!dps::MotionBetween(can, t0, t1, &moved, &why)) {
        throw dps::Error(dps::Str((fs::path(drive) / "can.csv").string(), ": no motion between frames ", frame - back,
                                  " and ", frame, ": ", why));
      }
      const auto [earlier, current] = ReadPair(drive, camera, frame, back);
      const dps::SweepResult sweep = dps::PlaneSweep(camera.model, camera.vehicle_from_camera, earlier, current,
                                                     moved.ToPose3(), dps::CameraValidMask(camera), options);
      fs::create_directories(out);
      dps::WriteImageAtomically((fs::path(out) / (camera.name + "_sweep.png")).string(),
                                dps::SweepPicture(current, sweep, options.min_distance_m, options.max_distance_m));
      cv::Mat distance = sweep.distance_m.clone();
      distance.setTo(std::numeric_limits<float>::infinity(), distance != distance);  // NaN: none
      dps::WriteDisparity((fs::path(out) / (camera.name + "_distance.pfm")).string(), distance);
      int counts[5] = {0, 0, 0, 0, 0};
      for (int y = 0; y < sweep.label.rows; ++y) {
        for (int x = 0; x < sweep.label.cols; ++x) ++counts[std::min(4, static_cast<int>(sweep.label.at<std::uint8_t>(y, x)))];
      }
      const double seen = std::max(1, counts[1] + counts[2] + counts[3] + counts[4]);
      std::cout << std::fixed << std::setprecision(1) << "dps-sweep: " << camera.name << " frame " << frame << " against " << frame - back << " ("
                << std::hypot(moved.x_m, moved.z_m) << " m): road " << 100.0 * counts[dps::kSweepRoad] / seen
                << " %, obstacle " << 100.0 * counts[dps::kSweepObstacle] / seen << " %, unobservable "
                << 100.0 * counts[dps::kSweepUnobservable] / seen << " %, none " << 100.0 * counts[dps::kSweepAmbiguous] / seen
                << " % of the pixels it sees\n";
      ++written;
    }
    if (written == 0) throw dps::Error(dps::Str("rig.yaml has no camera '", args.Get("camera"), "'"));
    return 0;
  });
}
