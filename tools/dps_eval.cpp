// dps-eval: scores detections.csv against truth.csv (DESIGN.md §5).
#include <cstdio>
#include <iostream>

#include "cli.h"
#include "dps/camera/rig_io.h"
#include "dps/camera/valid_mask.h"
#include "dps/detect/detection_io.h"
#include "dps/eval/evaluation.h"
#include "dps/eval/lane_evaluation.h"
#include "dps/map/tracker.h"
#include "dps/map/tracks_io.h"
#include "dps/pipeline/drive_io.h"
#include "dps/synth/truth_io.h"
#include "dps/util/atomic_file.h"

namespace {

const char* kUsage = R"(usage: dps-eval --detections detections.csv [--tracks tracks.csv] --truth truth.csv [options]
       dps-eval --lanes lanes.csv --truth-lanes truth_lanes.csv [--ego-lane ego_lane.csv --truth-ego-lane FILE]

Scores detections against ground truth (DESIGN.md §5): per frame, a truth object counts when the
point of its footprint nearest to the vehicle (its near point) is within --max-range and a camera
sees it (with --rig: at least 5 % of its box's surface in the camera's valid pixels - model, field,
mask - not hidden by the own car or another object; without it, every object in range counts),
whatever the pipeline processes. A detection matches an object when its (x, z) lies within
max(0.75 m, 0.1 * range) of the footprint; nearest pairs first, each at most once, the counted
objects first. A detection in the zone (within --max-range) that matches an object not counted is
a true detection: it counts for precision, the object not for recall. A counted object left
unmatched may be matched by a detection outside the zone (its near point at 19.5 m, the detection
at 20.3 m); such a detection is not counted for precision.
Prints recall, precision and range errors per range band, per zone (front: near point ahead of
the own car's front; rear: behind its back; side: between), recall per object kind (truth.csv's
kind: car, truck, pole, wall, pedestrian, ...), precision per source, and for the matches with a
class column the share whose class fits their object's kind (car: vehicle; truck, bus: truck;
pedestrian, cyclist, motorbike: pedestrian; pole, post: pole; others: unknown).

  --detections FILE   detections.csv
  --tracks FILE       tracks.csv: scored the same way on (x, z), plus the median velocity error
                      |v_track - v_truth| (of all matches, and the median and 90th percentile of
                      the matches whose object moves at 0.5 m/s or more) and the identity
                      switches (a truth object matched by a different track than before)
  --truth FILE        truth.csv
  --frames FILE       the drive's frames.csv: every frame it lists counts for the frames with and
                      without a detection, also one without objects or detections (without it, the
                      frames with truth rows or detections: on an empty road, only those with one)
  --max-range M       evaluated zone, metres (default 20)
  --rig FILE          the rig whose cameras see the objects (for a synthetic drive its
                      rig_true.yaml, the rig it was rendered with; else rig.yaml); masks named in
                      it apply; its vehicle length sets the zones (else 4.8 m)
  --masks DIR         masks/<camera>.png of the cameras (e.g. the drive's masks/ or dps-process's
                      OUT/<drive>/masks/), instead of the rig's
  --lanes FILE        lanes.csv (lane boundaries per frame), scored against --truth-lanes (dps-synth's
                      truth_lanes.csv): per boundary the share of the truth's frames where it was
                      reported, the offset error there (median / 90th percentile) and reports of
                      boundaries the truth does not have
  --truth-lanes FILE  with --detections or --tracks also: the share of matches whose lane (the
                      lane column) is their object's (its footprint centre among these boundaries)
  --ego-lane FILE     ego_lane.csv, against --truth-ego-lane: the lateral position error, lane
                      changes found within 0.3 s (same direction) and invented
  --json FILE         also write the scores as JSON (with lanes: {"detections", "tracks", "lanes"})
  --errors FILE       also write each scoring error as CSV, to see what went wrong where:
                      frame,error,id,kind,x,z,range,cause,near_id,near_m — "missed" (a counted
                      object no detection matched: its id, kind and near point) or "false" (a
                      detection in the zone that matched no object: id -1, its source as kind,
                      its point, and what it is by the nearest object within twice the matching
                      distance: "duplicate" of an object another detection matched, "misplaced"
                      near one none matched, with that object's id and distance, or "phantom"
                      with nothing near); of the detections, or of the tracks when only --tracks
                      is given. The table and the JSON count the false detections by cause
  --help              this text
)";

}  // namespace

int main(int argc, char** argv) {
  return dps_cli::Run("dps-eval", [&] {
    const dps_cli::Args args(argc, argv,
                             {"detections", "tracks", "truth", "frames", "max-range", "rig", "masks", "json", "errors", "lanes",
                              "truth-lanes", "ego-lane", "truth-ego-lane"},
                             {});
    if (args.help()) {
      std::cout << kUsage;
      return 0;
    }
    const bool lanes = args.Has("lanes") || args.Has("ego-lane");
    if (args.Has("lanes") && !args.Has("truth-lanes")) throw dps::Error("--lanes needs --truth-lanes (see --help)");
    if (args.Has("ego-lane") != args.Has("truth-ego-lane")) {
      throw dps::Error("--ego-lane and --truth-ego-lane go together (see --help)");
    }
    const bool objects = args.Has("detections") || args.Has("tracks");
    if (!objects && !lanes) throw dps::Error("missing --detections, --tracks or --lanes (see --help)");
    if (args.Has("truth-lanes") && !args.Has("lanes") && !objects) {
      throw dps::Error("--truth-lanes needs --lanes, --detections or --tracks (see --help)");
    }
    if (objects) args.Require("truth");
    dps::EvaluationOptions options;
    options.max_range_m = args.Number("max-range", 20.0);
    if (!(options.max_range_m > 0)) throw dps::Error("option --max-range: expected > 0");
    if (args.Has("frames")) options.frame_count = static_cast<int>(dps::ReadFrameTimes(args.Get("frames")).size());
    if (args.Has("masks") && !args.Has("rig")) throw dps::Error("option --masks needs --rig");
    if (args.Has("rig")) {
      dps::Rig rig = dps::ReadRig(args.Get("rig"));
      if (args.Has("masks")) {
        for (dps::RigCamera& c : rig.cameras) {
          c.mask = dps::ReadCameraMask(args.Get("masks") + "/" + c.name + ".png", c.model);
        }
      }
      options.visibility = std::make_shared<const dps::Visibility>(rig);
    }
    if (objects && args.Has("truth-lanes")) {
      for (dps::LaneBoundaryRow& b : dps::ReadLaneBoundaries(args.Get("truth-lanes"))) {
        options.truth_lanes[b.frame].push_back(std::move(b));
      }
    }
    const std::vector<dps::TruthRow> truth = objects ? dps::ReadTruth(args.Get("truth")) : std::vector<dps::TruthRow>{};
    // A file of frames beyond the drive's frames.csv belongs to another drive.
    const auto within_drive = [&](int frame, const std::string& file) {
      if (options.frame_count > 0 && frame >= options.frame_count) {
        throw dps::Error(dps::Str(file, ": frame ", frame, " but ", args.Get("frames"), " lists ", options.frame_count,
                                  " frames (another drive's file?)"));
      }
    };
    for (const dps::TruthRow& t : truth) within_drive(t.frame, args.Get("truth"));
    // The JSON parts: detections alone are written as their object; with tracks or lanes, an object
    // holding each part (null where absent).
    std::string detections_json = "null", tracks_json, lanes_json, errors;
    if (args.Has("detections")) {
      const std::vector<dps::Detection> detections = dps::ReadDetections(args.Get("detections"));
      std::vector<std::pair<int, double>> frames;
      for (const dps::Detection& d : detections) {
        frames.emplace_back(d.frame, d.t_s);
        within_drive(d.frame, args.Get("detections"));
      }
      dps::CheckSameDrive(frames, truth, args.Get("detections"), args.Get("truth"));
      const dps::EvaluationResult r = dps::Evaluate(detections, truth, options);
      std::cout << dps::EvaluationTable(r);
      detections_json = dps::EvaluationJson(r);
      errors = dps::ScoringErrorsCsv(r);
    }
    if (args.Has("tracks")) {
      const std::vector<dps::TrackState> tracks = dps::ReadTracks(args.Get("tracks"));
      std::vector<std::pair<int, double>> frames;
      for (const dps::TrackState& t : tracks) {
        frames.emplace_back(t.frame, t.t_s);
        within_drive(t.frame, args.Get("tracks"));
      }
      dps::CheckSameDrive(frames, truth, args.Get("tracks"), args.Get("truth"));
      const dps::TrackEvaluation r = dps::EvaluateTracks(tracks, truth, options);
      std::cout << "tracks:\n" << dps::EvaluationTable(r.positions);
      const dps::BandScore& o = r.positions.overall;
      std::printf("velocity error median %.3f m/s (moving objects: median %.3f, 90th percentile %.3f m/s, %zu "
                  "matches); %d objects tracked, %d identity switches\n",
                  o.MedianVelocityError(), o.MedianMovingVelocityError(), o.MovingVelocityErrorP90(),
                  o.moving_velocity_errors_mps.size(), r.objects_tracked, r.id_switches);
      tracks_json = ", \"tracks\": " + dps::EvaluationJson(r.positions) + ", \"id_switches\": " + std::to_string(r.id_switches);
      if (errors.empty()) errors = dps::ScoringErrorsCsv(r.positions);
    }
    if (lanes) {
      const auto read = [&](const char* name) {
        return args.Has(name) ? dps::ReadLaneBoundaries(args.Get(name)) : std::vector<dps::LaneBoundaryRow>{};
      };
      const auto read_ego = [&](const char* name) {
        return args.Has(name) ? dps::ReadEgoLane(args.Get(name)) : std::vector<dps::EgoLaneRow>{};
      };
      const dps::LaneEvaluation e =
          dps::EvaluateLanes(read("lanes"), read("truth-lanes"), read_ego("ego-lane"), read_ego("truth-ego-lane"));
      std::cout << dps::LaneEvaluationTable(e);
      lanes_json = ", \"lanes\": " + dps::LaneEvaluationJson(e);
    }
    if (args.Has("json")) {
      const bool parts = !tracks_json.empty() || !lanes_json.empty();
      const std::string tracks = tracks_json.empty() && !lanes_json.empty() ? ", \"tracks\": null" : tracks_json;
      dps::WriteFileAtomically(args.Get("json"), parts ? "{\"detections\": " + detections_json + tracks + lanes_json + "}\n"
                                                       : detections_json);
    }
    if (args.Has("errors")) dps::WriteFileAtomically(args.Get("errors"), errors);
    return 0;
  });
}
