// The tracking targets on the shipped scenes, as a user measures them: each scene rendered by the
// synthesiser at its shipped settings (640x480), processed like dps-process does, tracks.csv
// scored against truth.csv within 20 m and the pipeline's field of view (dps-eval --tracks):
// - lead car and overtaking car: one track id over the whole time (no switch), median velocity
//   error <= 0.5 m/s;
// - parked cars: median velocity error <= 0.3 m/s while the ego drives at 8 m/s (ego motion
//   compensation);
// - empty road: no confirmed track.
#include <cstdio>
#include <filesystem>
#include <string>

#include "check.h"
#include "dps/drive_processing.h"
#include "dps/evaluation.h"
#include "dps/rig_io.h"
#include "dps/scene_io.h"
#include "dps/surround_pipeline.h"
#include "dps/synth.h"
#include "dps/tracker.h"
#include "dps/truth.h"

namespace {

const std::string kSource = DPS_SOURCE_DIR;
const std::string kWork = DPS_WORK_DIR;
constexpr double kMovingVelocityTolMps = 0.5;
constexpr double kParkedVelocityTolMps = 0.3;

struct Scored {
  size_t rows = 0;
  dps::TrackEvaluation eval;
};

Scored Run(const std::string& name) {
  const std::string drive = kWork + "/drives/" + name, out = kWork + "/out";
  dps::SynthOptions so;
  so.overwrite = true;
  dps::Synthesize(dps::ReadScene(kSource + "/data/scenes/" + name + ".yaml"), drive, so);
  dps::DriveOptions po;
  po.map_video = false;
  dps::ProcessDrive(drive, out, po);
  const dps::Rig rig = dps::ReadRig(drive + "/rig.yaml");
  dps::EvaluationOptions eo;
  eo.max_range_m = 20.0;
  eo.coverage = dps::PipelineCoverage(rig, dps::DefaultPipelineOptions(rig));
  Scored s;
  const std::vector<dps::TrackState> tracks = dps::ReadTracks(out + "/" + name + "/tracks.csv");
  s.rows = tracks.size();
  s.eval = dps::EvaluateTracks(tracks, dps::ReadTruth(drive + "/truth.csv"), eo);
  const dps::BandScore& o = s.eval.positions.overall;
  std::printf("%s: %zu track rows, recall %.3f, precision %.3f, velocity error median %.3f m/s, %d object(s) "
              "tracked, %d identity switch(es)\n",
              name.c_str(), s.rows, o.Recall(), o.Precision(), o.MedianVelocityError(), s.eval.objects_tracked,
              s.eval.id_switches);
  return s;
}

}  // namespace

int main() {
  for (const char* name : {"lead_car", "overtaking"}) {
    const Scored s = Run(name);
    CHECK_EQ(s.eval.objects_tracked, 1);
    CHECK_EQ(s.eval.id_switches, 0);
    CHECK(s.eval.positions.overall.MedianVelocityError() <= kMovingVelocityTolMps);
  }
  const Scored parked = Run("parked_cars");
  CHECK(parked.eval.objects_tracked >= 4);  // the four cars (and the pole, when it is tracked)
  CHECK(parked.eval.positions.overall.MedianVelocityError() <= kParkedVelocityTolMps);
  const Scored empty = Run("empty_road");
  CHECK_EQ(empty.rows, size_t{0});
  std::filesystem::remove_all(kWork);
  return dps_test::Report();
}
