// The detection and tracking targets on the shipped scenes, as a user measures them: each scene
// rendered by the synthesiser at its shipped settings (640x480), processed like dps-process does,
// detections.csv and tracks.csv scored against truth.csv within 20 m.
// Detections (issue targets), where the pipeline looks (its sectors, PipelineCoverage): recall and
// precision >= 0.95 and median range error <= 5 % in the 0-10 and 10-20 m bands on the lead car,
// the overtaking car, the left turn and the parked row on either side; the empty road without a
// detection in >= 98 % of its frames. The DESIGN.md §5 figures (every object a camera sees, by
// zone: the wedges between the sectors and the rear too) are printed, not asserted: they fall
// short of the whole-surround targets (front and side recall >= 0.95, rear >= 0.9) until the
// pipeline measures those directions (docs/scenarios.md gives them).
// Tracks:
// - lead car and overtaking car: one track id over the whole time (no switch), median velocity
//   error <= 0.5 m/s;
// - parked cars: median velocity error <= 0.3 m/s while the ego drives at 8 m/s (ego motion
//   compensation);
// - empty road: no confirmed track.
#include <cstdio>
#include <filesystem>
#include <string>

#include "check.h"
#include "fixtures.h"
#include "dps/camera/rig_io.h"
#include "dps/camera/valid_mask.h"
#include "dps/detect/detection.h"
#include "dps/detect/detection_io.h"
#include "dps/eval/evaluation.h"
#include "dps/map/tracker.h"
#include "dps/map/tracks_io.h"
#include "dps/pipeline/drive_processing.h"
#include "dps/pipeline/surround_pipeline.h"
#include "dps/synth/scene_io.h"
#include "dps/synth/synth.h"
#include "dps/synth/truth.h"
#include "dps/synth/truth_io.h"

namespace {

using dps_test::kSource;
const std::string kWork = DPS_WORK_DIR;
constexpr double kMovingVelocityTolMps = 0.5;
constexpr double kParkedVelocityTolMps = 0.3;
constexpr double kMinRecall = 0.95, kMinPrecision = 0.95;
constexpr double kMaxMedianRangeError = 0.05;      // of the object's range, per band
constexpr double kMinEmptyFramesFraction = 0.98;  // empty road: frames without a detection

struct Scored {
  size_t rows = 0;
  dps::TrackEvaluation eval;
  dps::EvaluationResult detections;
};

Scored Run(const std::string& name) {
  const std::string drive = kWork + "/drives/" + name, out = kWork + "/out";
  dps::SynthOptions so;
  so.overwrite = true;
  dps::Synthesize(dps::ReadScene(kSource + "/data/scenes/" + name + ".yaml"), drive, so);
  dps::DriveOptions po;
  po.map_video = false;
  dps::ProcessDrive(drive, out, po);
  const dps::Rig rig = dps::ReadRig(drive + "/rig.yaml");  // the rendering rig
  dps::EvaluationOptions eo;
  eo.max_range_m = 20.0;
  dps::Rig seeing = rig;  // with what each camera sees past the own car (dps-synth's truth_masks)
  for (dps::RigCamera& c : seeing.cameras) c.mask = dps::ReadCameraMask(drive + "/truth_masks/" + c.name + ".png", c.model);
  eo.visibility = std::make_shared<const dps::Visibility>(seeing);
  Scored s;
  const std::vector<dps::TruthRow> truth = dps::ReadTruth(drive + "/truth.csv");
  const std::vector<dps::Detection> detections = dps::ReadDetections(out + "/" + name + "/detections.csv");
  const dps::EvaluationResult all = dps::Evaluate(detections, truth, eo);
  const std::vector<dps::BandScore>& z = all.zones;
  std::printf("%s: DESIGN.md 5 (every object a camera sees): recall %.3f, by zone front %.3f of %d, side %.3f of %d, "
              "rear %.3f of %d; precision %.3f\n",
              name.c_str(), all.overall.Recall(), z[0].Recall(), z[0].objects, z[1].Recall(), z[1].objects,
              z[2].Recall(), z[2].objects, all.overall.Precision());
  eo.coverage = dps::PipelineCoverage(rig, dps::DefaultPipelineOptions(rig));
  s.detections = dps::Evaluate(detections, truth, eo);
  const dps::BandScore& d = s.detections.overall;
  std::printf("%s: where the pipeline looks: detections recall %.3f, precision %.3f, median range error 0-10 m "
              "%.1f %%, 10-20 m %.1f %%, %d of %d frames with a detection in the zone\n",
              name.c_str(), d.Recall(), d.Precision(), 100 * s.detections.bands[0].MedianRelativeRangeError(),
              100 * s.detections.bands[1].MedianRelativeRangeError(), s.detections.frames_with_detections,
              s.detections.frames);
  const std::vector<dps::TrackState> tracks = dps::ReadTracks(out + "/" + name + "/tracks.csv");
  s.rows = tracks.size();
  s.eval = dps::EvaluateTracks(tracks, truth, eo);
  const dps::BandScore& o = s.eval.positions.overall;
  std::printf("%s: %zu track rows, recall %.3f, precision %.3f, velocity error median %.3f m/s, %d object(s) "
              "tracked, %d identity switch(es)\n",
              name.c_str(), s.rows, o.Recall(), o.Precision(), o.MedianVelocityError(), s.eval.objects_tracked,
              s.eval.id_switches);
  return s;
}

// The detection targets: recall, precision, and the median range error of each band with matches
// (0-10 and 10-20 m).
void CheckDetections(const Scored& s) {
  const dps::EvaluationResult& r = s.detections;
  CHECK(r.overall.objects >= 40);
  CHECK(r.overall.Recall() >= kMinRecall);
  CHECK(r.overall.Precision() >= kMinPrecision);
  int bands = 0;
  for (int b = 0; b < 2; ++b) {
    if (r.bands[b].matched_objects == 0) continue;
    ++bands;
    CHECK(r.bands[b].MedianRelativeRangeError() <= kMaxMedianRangeError);
  }
  CHECK(bands >= 1);
}

}  // namespace

int main() {
  for (const char* name : {"lead_car", "overtaking"}) {
    const Scored s = Run(name);
    CheckDetections(s);
    CHECK_EQ(s.eval.objects_tracked, 1);
    CHECK_EQ(s.eval.id_switches, 0);
    CHECK(s.eval.positions.overall.MedianVelocityError() <= kMovingVelocityTolMps);
  }
  CheckDetections(Run("left_turn"));
  const Scored parked = Run("parked_cars");
  CheckDetections(parked);
  CHECK(parked.eval.objects_tracked >= 4);  // the four cars (and the pole, when it is tracked)
  CHECK(parked.eval.positions.overall.MedianVelocityError() <= kParkedVelocityTolMps);
  CheckDetections(Run("parked_left"));
  const Scored empty = Run("empty_road");
  CHECK_EQ(empty.rows, size_t{0});
  const int empty_frames = dps::ReadScene(kSource + "/data/scenes/empty_road.yaml").FrameCount();
  CHECK(empty_frames >= 30);
  CHECK(1.0 - double(empty.detections.frames_with_detections) / empty_frames >= kMinEmptyFramesFraction);
  std::filesystem::remove_all(kWork);
  return dps_test::Report();
}
