// Automatic calibration marks on rendered calibration scenes (issue: R within 0.5 degrees of the
// truth from one image per camera, no clicking): each seed turns every camera of the nominal rig
// by 1-3 degrees about a random axis (PerturbedRig), renders the parking lot with that true rig
// (supersampled, with image noise, as dps-synth does), finds the painted lines with the nominal
// rig only, and calibrates from them.
#include <algorithm>
#include <cstdio>
#include <vector>

#include "check.h"
#include "fixtures.h"
#include "dps/calib/auto_marks.h"
#include "dps/calib/vanishing_points.h"
#include "dps/synth/scene_io.h"
#include "dps/synth/scene_renderer.h"
#include "dps/synth/synth.h"
#include "dps/util/error.h"

namespace {

using dps_test::kSource;
constexpr double kMaxErrorDeg = 0.5;
constexpr int kSeeds = 5;

// width x height: the image size rendered (0: the scene's own, 640x480); max_error_deg: the
// target for every camera.
void TestRenderedScenes(int width, int height, double max_error_deg) {
  std::vector<double> errors;
  for (int seed = 1; seed <= kSeeds; ++seed) {
    dps::Scene nominal = dps::ReadScene(kSource + "/data/scenes/calibration.yaml");
    if (width > 0) dps::ResizeScene(&nominal, width, height);
    nominal.seed = static_cast<std::uint64_t>(seed);
    dps::Scene scene = nominal;
    scene.rig = dps::PerturbedRig(nominal);
    const dps::SceneRenderer renderer(scene);
    const dps::FrameState state = renderer.StateAt(0.0);
    for (size_t c = 0; c < scene.rig.cameras.size(); ++c) {
      const std::string& name = scene.rig.cameras[c].name;
      const cv::Mat image = renderer.Render(state, c, 0).image;
      std::vector<dps::AutoMarkLine> lines;
      const std::vector<dps::Mark> marks = dps::DetectMarks(image, nominal.rig, name, dps::AutoMarkOptions(), 0, &lines);
      int z = 0, x = 0;
      double worst_rms = 0;
      for (const dps::AutoMarkLine& l : lines) {
        (l.axis == 'Z' ? z : x) += 1;
        worst_rms = std::max(worst_rms, l.great_circle_rms_deg);
      }
      const dps::RigCamera& nominal_camera = nominal.rig.Camera(name);
      const dps::CameraCalibration cal =
          dps::CalibrateCamera(name, nominal_camera.model, nominal_camera.vehicle_from_camera.R, marks,
                               dps::CalibrationOptions(), "auto marks");
      const double error = dps::RotationAngleDeg(cal.R, scene.rig.Camera(name).vehicle_from_camera.R);
      const double nominal_error = dps::RotationAngleDeg(nominal_camera.vehicle_from_camera.R,
                                                         scene.rig.Camera(name).vehicle_from_camera.R);
      std::printf("seed %d %-5s: %d Z + %d X lines (worst great-circle rms %.3f deg), %zu marks; "
                  "error %.3f deg (nominal rig: %.2f deg)\n",
                  seed, name.c_str(), z, x, worst_rms, marks.size(), error, nominal_error);
      CHECK(z >= 2 && x >= 2);
      CHECK(error <= max_error_deg);
      errors.push_back(error);
    }
  }
  std::sort(errors.begin(), errors.end());
  std::printf("automatic marks at %dx%d: median %.3f deg, worst %.3f deg over %zu cameras\n", width ? width : 640,
              height ? height : 480, errors[errors.size() / 2], errors.back(), errors.size());
}

void TestBadInput() {
  const dps::Scene scene = dps::ReadScene(kSource + "/data/scenes/calibration.yaml");
  CHECK_THROWS_WITH(dps::DetectMarks(cv::Mat(10, 10, CV_8UC3), scene.rig, "left"), dps::Error, "image is 10x10");
  CHECK_THROWS_WITH(dps::DetectMarks(cv::Mat(480, 640, CV_8UC3), scene.rig, "rear"), dps::Error, "rear");
  dps::AutoMarkOptions o;
  o.tophat_px = 4;
  CHECK_THROWS_WITH(o.Check(), dps::Error, "tophat_px");
  // A blank image has no lines: no marks (CalibrateCamera then names the missing axes).
  CHECK(dps::DetectMarks(cv::Mat(480, 640, CV_8UC3, cv::Scalar(90, 90, 90)), scene.rig, "left").empty());
}

}  // namespace

int main() {
  TestBadInput();
  TestRenderedScenes(0, 0, kMaxErrorDeg);
  // At the paper's 320x240 (half the pixels across, so about twice the angular error per pixel).
  TestRenderedScenes(320, 240, 2 * kMaxErrorDeg);
  return dps_test::Report();
}
