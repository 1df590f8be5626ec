// dps — synthetic drives and calibration scenes with exact ground truth (dps-synth).
//
// A drive folder (DESIGN.md §3.2) holds rig.yaml, left/ and right/ (PNG) and/or left.avi and
// right.avi (MJPG), can.csv, frames.csv and truth.csv; optionally the per-pixel truth of every
// frame: range/<camera>/NNNNNN.png (16-bit, millimetres along the pixel's centre ray, 0 = sky or
// no ray, 65535 = 65.535 m or farther) and ids/<camera>/NNNNNN.png (16-bit SurfaceId).
// A calibration scene's folder holds rig.yaml (the nominal rig a user would start from),
// rig_true.yaml (the rig that rendered the images, each camera rotated 1-3 degrees away from the
// nominal one), the images and marks.csv (DESIGN.md §3.3).
#pragma once

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "dps/calib/marks.h"
#include "dps/synth/scene.h"
#include "dps/synth/scene_renderer.h"
#include "dps/synth/truth.h"

namespace dps {

// The truth rows of every object at one instant.
std::vector<TruthRow> TruthAt(const FrameState& state, int frame);

// Points sampled along the painted lines (axes X and Z) and the poles (Y, their vertical axis)
// that the camera sees unoccluded, at least `margin_px` inside the image and the rim, every
// scene.calibration.mark_spacing_m; lines with fewer than 3 visible points are left out.
// `noise_px` is the standard deviation of the Gaussian noise added to u and v (seeded by the
// scene's seed). Rendering and visibility use `renderer`, whose scene is the true rig.
std::vector<Mark> SampleMarks(const SceneRenderer& renderer, const FrameState& state,
                              double noise_px, double margin_px = 2.0);

// The true rig of a calibration scene: every camera's R turned by a random angle in
// [min_rotation_deg, max_rotation_deg] about a random axis (camera frame), seeded by the scene.
Rig PerturbedRig(const Scene& scene);

struct SynthOptions {
  bool write_png = true;          // left/, right/ image folders
  bool write_video = false;       // left.avi, right.avi (MJPG), or left.mp4, right.mp4 (H264)
  // "MJPG", or "H264" (lossy, as recorded drives are; MPEG-4 part 2 where OpenCV has no H.264
  // encoder). The codec used is written to video_codec.txt.
  std::string video_codec = "MJPG";
  bool write_truth_images = false;// range/ and ids/ folders
  int frames = -1;                // > 0: render only this many frames
  bool overwrite = false;         // replace an existing output folder that dps-synth wrote
  // A drive processed with another rig than the one that renders (a calibration error): that rig
  // is written as rig.yaml and the rendering rig as rig_true.yaml. Unset: rig.yaml renders. For a
  // calibration scene it is the nominal rig and the scene's own rig renders (no drawn perturbation).
  std::optional<Rig> processing_rig;
  // More files written into the folder with it (name -> content), e.g. randomization.json.
  std::map<std::string, std::string> extra_files;
  // Called after each frame with (frames done, frames in all); may print progress.
  std::function<void(int, int)> progress;
};

// The file that marks a folder as written by Synthesize (overwrite replaces only such folders).
inline constexpr const char* kSynthMarker = ".dps-synth";

// Renders the scene into `out_dir`, built under a temporary name beside it and renamed when
// complete, so that a killed run never leaves a folder that looks finished. Throws dps::Error when
// the folder exists (without overwrite, or not written by Synthesize), is or contains the current
// folder, or cannot be written.
void Synthesize(const Scene& scene, const std::string& out_dir, const SynthOptions& options);

}  // namespace dps
