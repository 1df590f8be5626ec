// dps — scoring detections against ground truth (DESIGN.md §5), as dps-eval and the regression
// tests do.
//
// Per frame, a truth object counts when its near point (the footprint point nearest to the
// vehicle origin) lies within max_range_m and a camera of the rig sees it (Visibility,
// visibility.h: 5 % of its box's surface in a camera's valid pixels, not hidden by the own car or
// another object), whatever views the pipeline processes; a detection is in the zone when its
// (x, z) lies within max_range_m. A detection matches an object when its (x, z) lies within
// max(0.75 m, 0.1 * range of the object's near point) of the footprint (0 inside); pairs are
// taken nearest first, each object and each detection at most once: first with the counted
// objects, then what is left with the objects that do not count (beyond the range, or seen by no
// camera) — a detection of such an object is a true one, though the object is not counted for
// recall. Counted objects still unmatched are then matched with the detections outside the zone:
// §5 matches detections and objects regardless of the zone (a car whose near point is 19.5 m
// away, detected at 20.3 m, is found); such detections are not counted for precision.
// recall = matched counted objects / counted objects; precision = matched detections / detections
// in the zone; range error = |detection range - near-point range| of the counted matches, per band
// of the near point's range and per zone (front: near point ahead of the own car's front, z >
// length / 2; rear: behind its back; side: between; a false detection by its own point).

#pragma once

#include <array>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "dps/detect/coverage.h"
#include "dps/detect/detection.h"
#include "dps/eval/visibility.h"
#include "dps/synth/truth.h"
#include "dps/util/lanes_csv.h"

namespace dps {

struct EvaluationOptions {
  double max_range_m = 20.0;   // > 0
  // Which objects the cameras see; null: every object within range counts.
  std::shared_ptr<const Visibility> visibility;
  double vehicle_length_m = 4.8;  // for the zones (> 0); the visibility's rig's when it is set
  // > 0: the drive has frames 0 .. frame_count - 1 (its frames.csv), and each counts in
  // EvaluationResult::frames, also one without truth rows or detections (on an empty road, a frame
  // without a false detection); 0: the frames with truth rows or detections. >= 0.
  int frame_count = 0;
  // The matches' velocity errors are also given for the objects moving over the ground at least
  // this fast (a walking pedestrian's 1.4 m/s; a parked car's 0): the error of a moving object's
  // velocity is not drowned by the many matches of static ones. m/s, >= 0.
  double moving_speed_mps = 0.5;
  // Optional, not DESIGN.md §5: objects and detections count only inside these sectors too (empty:
  // every direction) - for regression tests of what a pipeline does where it looks
  // (PipelineCoverage).
  Coverage coverage;
  // Optional: the truth's lane boundaries by frame (truth_lanes.csv), for scoring the detections'
  // lanes (object_attributes.h's LaneOfPoint of each object's footprint centre).
  std::map<int, std::vector<LaneBoundaryRow>> truth_lanes;

  // Throws dps::Error naming the field, its value and the violated constraint.
  void Check() const;
};

// How many of the matched detections' attributes were judged and right.
struct AttributeScore {
  int judged = 0, correct = 0;
  double Accuracy() const;  // NaN when none judged
};

// The class a detection of an object of this truth kind should have: car -> vehicle, truck and
// bus -> truck, pedestrian, cyclist and motorbike -> pedestrian, pole and post -> pole, anything
// else (a wall) -> unknown.
std::string ExpectedClass(const std::string& kind);

// What a false detection is, by the frame's objects (counted or not) within twice the matching
// distance of it (max(0.75 m, 0.1 x the object's range), DESIGN.md §5), the nearest: a second
// detection of an object another detection matched (kDuplicate: a part of one object, or one object
// seen by two sources, not merged); an object no detection matched (kMisplaced: found but put
// beyond the matching distance); none (kPhantom: nothing there).
enum class FalseCause { kDuplicate, kMisplaced, kPhantom };
const char* FalseCauseName(FalseCause cause);  // "duplicate", "misplaced", "phantom"
constexpr int kFalseCauses = 3;

struct BandScore {
  std::string name;            // "0-10", ...
  double lo_m = 0, hi_m = 0;
  int objects = 0, matched_objects = 0;
  int detections = 0, matched_detections = 0;
  std::vector<double> range_errors_m;
  double Recall() const;       // 1 when there is no object
  double Precision() const;    // 1 when there is no detection
  double MedianRangeError() const;  // NaN when no match
  double RangeErrorP90() const;
  double MedianRelativeRangeError() const;  // |error| / object range, NaN when no match
  std::vector<double> relative_errors;
  std::vector<double> velocity_errors_mps;  // |v_detection - v_truth| of matches with a velocity
  double MedianVelocityError() const;       // NaN when none
  // ... of the matches whose object moves (EvaluationOptions::moving_speed_mps)
  std::vector<double> moving_velocity_errors_mps;
  double MedianMovingVelocityError() const;  // NaN when none
  double MovingVelocityErrorP90() const;
};

struct SourceScore {
  std::string source;
  int detections = 0, matched = 0;  // in the zone
  std::array<int, kFalseCauses> false_causes{};  // the false ones by FalseCause
  double Precision() const;
};

// One scoring error, for finding out why: a counted object no detection matched, or a detection
// in the zone that matched no object.
struct ScoringError {
  int frame = 0;
  bool missed = false;        // true: a missed object; false: a false detection
  int object_id = -1;         // missed: the truth id
  std::string kind;           // missed: the truth kind; false: the detection's source
  Eigen::Vector2d point{0, 0};  // missed: the near point; false: the detection's (x, z)
  double range_m = 0.0;
  // False detections: what it is, and the object that says so (its truth id and the distance from
  // the detection's point to its footprint; -1 and NaN for a phantom).
  FalseCause cause = FalseCause::kPhantom;
  int near_object_id = -1;
  double near_object_m = std::numeric_limits<double>::quiet_NaN();
};

struct EvaluationResult {
  BandScore overall;                 // all objects / detections in the zone
  std::vector<BandScore> bands;      // 0-10, 10-20, 20-30, 30-50 m (object near-point range)
  std::vector<BandScore> zones;      // front, side, rear (object near point; a false detection's point)
  std::vector<SourceScore> sources;  // front, left, right
  std::vector<BandScore> kinds;      // recall and range errors by the objects' truth kind (car, pole, ...),
                                     // in order of first appearance; detections are not split by kind
  int frames = 0;                    // frames with truth rows or detections (and the options' frame_count)
  int frames_with_detections = 0;    // frames with at least one detection in the zone
  std::vector<ScoringError> errors;  // by frame: missed objects, then false detections
  std::array<int, kFalseCauses> false_causes{};  // the false detections in the zone by FalseCause
  // The counted objects' matches in the zone: their class (those with a class; right when it is
  // ExpectedClass of the object's kind) and their lane (those whose object has a lane in
  // options.truth_lanes; right when the detection's lane is the object's).
  AttributeScore classes, lanes;
  // The judged classes by the class expected: class_confusion[expected][given] matches.
  std::map<std::string, std::map<std::string, int>> class_confusion;
};

// Throws dps::Error when results (frame, time pairs of detections or tracks, read from `results`)
// and truth (read from `truth_file`) cannot be of one drive: a frame both list at times more than
// half a frame interval apart (the truth's median interval; 1 ms when it has one frame), or a
// result frame beyond the truth's last frame by more than one.
void CheckSameDrive(const std::vector<std::pair<int, double>>& results, const std::vector<TruthRow>& truth,
                    const std::string& results_file, const std::string& truth_file);

// Scores detections against truth (frames matched by index).
EvaluationResult Evaluate(const std::vector<Detection>& detections, const std::vector<TruthRow>& truth,
                          const EvaluationOptions& options);

// Tracks scored like detections (DESIGN.md §5: the same matching on (x, z)), with the velocity
// error |v_track - v_truth| of each match; also counts identity switches: a truth object matched
// by a different track id than in its previous matched frame.
struct TrackEvaluation {
  EvaluationResult positions;
  int id_switches = 0;
  int objects_tracked = 0;   // truth ids matched at least once
};
struct TrackState;
TrackEvaluation EvaluateTracks(const std::vector<TrackState>& tracks, const std::vector<TruthRow>& truth,
                               const EvaluationOptions& options);

// A table for people (per band and per source) and a JSON document for scripts.
std::string EvaluationTable(const EvaluationResult& result);
std::string EvaluationJson(const EvaluationResult& result);
// The scoring errors as CSV: frame,error,id,kind,x,z,range,cause,near_id,near_m (error "missed"
// with the object's id, kind and near point, the last three empty; or "false" with the detection's
// source as kind, id -1, its point, its FalseCause and the object behind it, empty for a phantom).
std::string ScoringErrorsCsv(const EvaluationResult& result);

}  // namespace dps
