// dps-synth: renders a synthetic drive or calibration scene with exact ground truth.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <iostream>

#include "cli.h"
#include "dps/camera/rig_io.h"
#include "dps/synth/randomize.h"
#include "dps/synth/scene_io.h"
#include "dps/synth/synth.h"
#include "dps/util/atomic_file.h"

namespace {

const char* kUsage = R"(usage: dps-synth SCENE.yaml --out DIR [options]

Renders the scene (docs/synth.md) into a drive folder: rig.yaml, left/ and right/ PNG images,
can.csv, frames.csv, truth.csv. A calibration scene also writes marks.csv and rig_true.yaml
(rig.yaml is then the nominal rig to calibrate). Options override the scene file.

  --out DIR          output folder (built under a temporary name, renamed when complete; never
                     the current folder or one holding an input)
  --size WxH         image size, e.g. 320x240 (the rig's cameras are rescaled)
  --seed N           random seed of textures, noise and calibration perturbations
  --frames N         render only the first N frames
  --rig FILE         render with this rig instead of the scene's (same image sizes as the scene)
  --processing-rig FILE
                     write this rig as rig.yaml and the rendering rig as rig_true.yaml (a drive
                     processed with a calibration error; for a calibration scene the nominal rig
                     to calibrate from, with no drawn perturbation): e.g. a randomised drive's
                     rig_true.yaml and rig.yaml, to test dps-calibrate on its rig
  --randomize SEED   draw the camera family and model, the field of view, the mounting, a
                     calibration error, the appearance and the objects reproducibly from SEED
                     (docs/robustness.md): rig.yaml is then the rig to process with (the
                     rendering rig turned by the calibration error), rig_true.yaml the rendering
                     rig, randomization.json every draw; drawn video replaces the PNG folders;
                     the scene file's randomize: block sets the ranges
  --video            also write left.avi and right.avi (MJPG)
  --h264             the videos as left.mp4 and right.mp4 in H.264 (lossy, as recorded drives are;
                     MPEG-4 part 2 where OpenCV has no H.264 encoder; video_codec.txt says which)
  --no-png           do not write the PNG folders (needs --video)
  --truth-images     also write range/<camera>/ (16-bit mm) and ids/<camera>/ truth images
  --force            replace DIR if it exists and dps-synth wrote it (it holds .dps-synth)
  --quiet            no progress on stderr
  --help             this text
)";

}  // namespace

int main(int argc, char** argv) {
  return dps_cli::Run("dps-synth", [&] {
    const dps_cli::Args args(argc, argv, {"out", "size", "seed", "frames", "randomize", "rig", "processing-rig"},
                             {"video", "h264", "no-png", "truth-images", "force", "quiet"});
    if (args.help()) {
      std::cout << kUsage;
      return 0;
    }
    if (args.positional().size() != 1) throw dps::Error("expected one scene file (see --help)");
    args.Require("out", "DIR");
    {
      std::vector<std::string> inputs{args.positional()[0]};
      for (const char* rig : {"rig", "processing-rig"}) {
        if (args.Has(rig)) inputs.push_back(args.Get(rig));
      }
      dps::CheckOutputFolder(args.Get("out"), inputs);
    }
    dps::Scene scene = dps::ReadScene(args.positional()[0]);
    if (args.Has("rig")) scene.rig = dps::ReadRig(args.Get("rig"));
    if (args.Has("size")) {
      const cv::Size size = args.Size("size", cv::Size(), 16);
      dps::ResizeScene(&scene, size.width, size.height);
    }
    if (args.Has("seed")) {
      const int seed = args.Integer("seed", 1);
      if (seed < 0) throw dps::Error("option --seed: expected a non-negative integer");
      scene.seed = static_cast<std::uint64_t>(seed);
    }
    dps::SynthOptions options;
    options.frames = args.Integer("frames", -1);
    if (args.Has("frames") && options.frames < 1) throw dps::Error("option --frames: expected >= 1");
    options.write_video = args.Has("video") || args.Has("h264");
    if (args.Has("h264")) options.video_codec = "H264";
    options.write_png = !args.Has("no-png");
    if (args.Has("processing-rig")) options.processing_rig = dps::ReadRig(args.Get("processing-rig"));
    if (args.Has("randomize")) {
      const int seed = args.Integer("randomize", 0);
      if (seed < 0) throw dps::Error("option --randomize: expected a non-negative integer");
      const dps::RandomizedScene r = dps::Randomize(scene, static_cast<std::uint64_t>(seed),
                                                    dps::ReadRandomizeOptions(args.positional()[0]));
      scene = r.scene;
      options.processing_rig = r.processing_rig;
      options.extra_files["randomization.json"] = r.ToJson(static_cast<std::uint64_t>(seed));
      if (r.video) {
        options.write_video = true;
        options.write_png = false;
        options.video_codec = r.video_codec;
      }
    }
    options.write_truth_images = args.Has("truth-images");
    options.overwrite = args.Has("force");
    const bool tty = isatty(STDERR_FILENO);
    const auto start = std::chrono::steady_clock::now();
    if (!args.Has("quiet")) {
      options.progress = [&](int done, int total) {
        const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (tty) {
          std::fprintf(stderr, "\rdps-synth: frame %d/%d  %.1f frames/s  ", done, total, done / s);
          if (done == total) std::fprintf(stderr, "\n");
        } else if (done == total || done % 10 == 0) {
          std::fprintf(stderr, "dps-synth: frame %d/%d (%.1f frames/s)\n", done, total, done / s);
        }
      };
    }
    dps::Synthesize(scene, args.Get("out"), options);
    if (!args.Has("quiet")) std::cerr << "dps-synth: wrote " << args.Get("out") << std::endl;
    return 0;
  });
}
