#include "dps/eval/evaluation.h"

#include "dps/detect/object_attributes.h"
#include "dps/map/tracker.h"
#include "dps/util/error.h"
#include "dps/util/math.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <sstream>

namespace dps {
namespace {

std::string Number(double v, int digits = 3) {
  if (std::isnan(v)) return "null";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", digits, v);
  return buf;
}

// The matching distance of an object (DESIGN.md §5).
double MatchTolerance(const TruthRow& object) { return std::max(0.75, 0.1 * NearPoint(object).norm()); }

// Matches objects with the detections not taken yet (det_object[j] < 0): pairs within
// max(0.75 m, 0.1 * range of the near point) of the footprint, nearest first, each object and
// each detection at most once. Sets det_object[j] to the index of detection j's object and
// returns each object's detection (-1: none).
std::vector<int> MatchNearestFirst(const std::vector<const TruthRow*>& objects, const std::vector<const Detection*>& dets,
                                   std::vector<int>* det_object) {
  struct Pair {
    double distance;
    size_t object, detection;
  };
  std::vector<Pair> pairs;
  for (size_t i = 0; i < objects.size(); ++i) {
    const double tolerance = MatchTolerance(*objects[i]);
    for (size_t j = 0; j < dets.size(); ++j) {
      if ((*det_object)[j] >= 0) continue;
      const double d = DistanceToFootprint(*objects[i], {dets[j]->x_m, dets[j]->z_m});
      if (d <= tolerance) pairs.push_back({d, i, j});
    }
  }
  std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) { return a.distance < b.distance; });
  std::vector<int> object_match(objects.size(), -1);
  for (const Pair& p : pairs) {
    if (object_match[p.object] >= 0 || (*det_object)[p.detection] >= 0) continue;
    object_match[p.object] = static_cast<int>(p.detection);
    (*det_object)[p.detection] = static_cast<int>(p.object);
  }
  return object_match;
}

// The result before any frame: the overall score, the range bands and the three sources.
EvaluationResult EmptyResult(const EvaluationOptions& options) {
  EvaluationResult result;
  result.overall.name = "all";
  result.overall.hi_m = options.max_range_m;
  const double edges[] = {0, 10, 20, 30, 50};
  for (int b = 0; b < 4; ++b) {
    BandScore s;
    s.lo_m = edges[b];
    s.hi_m = edges[b + 1];
    s.name = Number(s.lo_m, 0) + "-" + Number(s.hi_m, 0);
    result.bands.push_back(s);
  }
  for (const char* name : {"front", "side", "rear"}) {
    BandScore z;
    z.name = name;
    z.hi_m = options.max_range_m;
    result.zones.push_back(z);
  }
  for (const char* name : {"front", "left", "right"}) result.sources.push_back({name, 0, 0});
  return result;
}

double VehicleLength(const EvaluationOptions& options) {
  return options.visibility ? options.visibility->rig().vehicle.length_m : options.vehicle_length_m;
}

// DESIGN.md §5's zones by the point's z: ahead of the own car's front, behind its back, between.
BandScore* ZoneOf(EvaluationResult* result, double z, double vehicle_length_m) {
  if (z > vehicle_length_m / 2) return &result->zones[0];
  if (z < -vehicle_length_m / 2) return &result->zones[2];
  return &result->zones[1];
}

// A detection's point is in the zone when it lies within range (and the optional coverage).
bool InZone(const Eigen::Vector2d& p, const EvaluationOptions& options) {
  return p.norm() <= options.max_range_m && options.coverage.Contains(p);
}

// Which truth rows count (by index): the near point in the zone and a camera seeing the object
// among the other objects of its frame.
std::vector<bool> CountedRows(const std::vector<TruthRow>& truth, const EvaluationOptions& options) {
  std::map<int, std::vector<const TruthRow*>> scenes;
  for (const TruthRow& t : truth) scenes[t.frame].push_back(&t);
  std::vector<bool> counted(truth.size());
  for (size_t i = 0; i < truth.size(); ++i) {
    counted[i] = InZone(NearPoint(truth[i]), options) &&
                 (!options.visibility || options.visibility->Sees(truth[i], scenes[truth[i].frame]));
  }
  return counted;
}

BandScore* BandOf(EvaluationResult* result, double range) {
  for (BandScore& b : result->bands) {
    if (range >= b.lo_m && range < b.hi_m) return &b;
  }
  return nullptr;
}

BandScore* KindOf(EvaluationResult* result, const std::string& kind) {
  for (BandScore& k : result->kinds) {
    if (k.name == kind) return &k;
  }
  result->kinds.emplace_back();
  result->kinds.back().name = kind;
  return &result->kinds.back();
}

SourceScore* SourceOf(EvaluationResult* result, const std::string& name) {
  for (SourceScore& s : result->sources) {
    if (s.source == name) return &s;
  }
  result->sources.push_back({name, 0, 0});
  return &result->sources.back();
}

// One frame's objects (counted: near point in the zone; uncounted: the others) and detections (in
// the zone, outside it), and how they matched.
struct FrameMatch {
  std::vector<const TruthRow*> objects, uncounted;
  std::vector<const Detection*> dets, outside;
  std::vector<int> det_match;                 // detection j's counted object, -1: none
  std::vector<int> det_seen;                  // >= 0: detection j saw an object, counted or not
  std::vector<const Detection*> matched_by;   // counted object i's detection (in the zone or not)
  std::vector<bool> uncounted_seen;           // uncounted object k is what a detection in the zone saw
};

void Match(FrameMatch* m) {
  m->det_match.assign(m->dets.size(), -1);
  const std::vector<int> object_match = MatchNearestFirst(m->objects, m->dets, &m->det_match);
  // A counted object no detection in the zone matched may still be matched by one just outside
  // it (a car whose near point is 19.5 m away, detected at 20.3 m): §5 matches detections and
  // objects without regard to the zone, which only decides what is counted.
  std::vector<const TruthRow*> unmatched;
  std::vector<size_t> unmatched_index;
  for (size_t i = 0; i < m->objects.size(); ++i) {
    if (object_match[i] < 0) unmatched.push_back(m->objects[i]), unmatched_index.push_back(i);
  }
  std::vector<int> outside_match(m->outside.size(), -1);
  const std::vector<int> late = MatchNearestFirst(unmatched, m->outside, &outside_match);
  // Then the detections left over against the uncounted objects.
  m->det_seen = m->det_match;
  MatchNearestFirst(m->uncounted, m->dets, &m->det_seen);
  m->uncounted_seen.assign(m->uncounted.size(), false);
  for (size_t j = 0; j < m->dets.size(); ++j) {
    if (m->det_match[j] < 0 && m->det_seen[j] >= 0) m->uncounted_seen[m->det_seen[j]] = true;
  }
  m->matched_by.assign(m->objects.size(), nullptr);
  for (size_t i = 0; i < m->objects.size(); ++i) {
    if (object_match[i] >= 0) m->matched_by[i] = m->dets[object_match[i]];
  }
  for (size_t k = 0; k < unmatched.size(); ++k) {
    if (late[k] >= 0) m->matched_by[unmatched_index[k]] = m->outside[late[k]];
  }
}

// Recall, range errors and velocity errors (all, and the moving objects' apart) of the counted
// objects, overall, by the band and zone of their near point and by their kind.
void ScoreObjects(int f, const FrameMatch& m, double vehicle_length_m, double moving_speed_mps,
                  EvaluationResult* result) {
  for (size_t i = 0; i < m.objects.size(); ++i) {
    const TruthRow& object = *m.objects[i];
    const Eigen::Vector2d near = NearPoint(object);
    const double range = near.norm();
    if (!m.matched_by[i]) result->errors.push_back({f, true, object.id, object.kind, near, range});
    for (BandScore* b : {&result->overall, BandOf(result, range), ZoneOf(result, near.y(), vehicle_length_m),
                         KindOf(result, object.kind)}) {
      if (!b) continue;
      ++b->objects;
      if (!m.matched_by[i]) continue;
      ++b->matched_objects;
      const Detection& d = *m.matched_by[i];
      const double error = std::abs(d.range_m - range);
      b->range_errors_m.push_back(error);
      b->relative_errors.push_back(error / std::max(range, 1e-6));
      if (!d.has_velocity) continue;
      const double velocity_error = std::hypot(d.vx_mps - object.vx_mps, d.vz_mps - object.vz_mps);
      b->velocity_errors_mps.push_back(velocity_error);
      if (std::hypot(object.vx_mps, object.vz_mps) >= moving_speed_mps) b->moving_velocity_errors_mps.push_back(velocity_error);
    }
  }
}

// A match's class and lane against its object's.
void ScoreAttributes(const Detection& d, const TruthRow& object, const std::vector<LaneBoundaryRow>* lanes,
                     EvaluationResult* result) {
  if (!d.object_class.empty()) {
    const std::string expected = ExpectedClass(object.kind);
    ++result->classes.judged;
    result->classes.correct += d.object_class == expected;
    ++result->class_confusion[expected][d.object_class];
  }
  const std::optional<int> lane = lanes ? LaneOfPoint(*lanes, {object.x_m, object.z_m}) : std::nullopt;
  if (lane) {
    ++result->lanes.judged;
    result->lanes.correct += d.lane == lane;
  }
}

// A false detection's cause (FalseCause): the nearest of the frame's objects within twice its
// matching distance, and whether a detection (in the zone or not) matched it.
void FalseCauseOf(const FrameMatch& m, const Detection& d, ScoringError* e) {
  double best = std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < m.objects.size() + m.uncounted.size(); ++k) {
    const bool counted = k < m.objects.size();
    const TruthRow& object = counted ? *m.objects[k] : *m.uncounted[k - m.objects.size()];
    const double distance = DistanceToFootprint(object, {d.x_m, d.z_m});
    if (distance > 2 * MatchTolerance(object) || distance >= best) continue;
    best = distance;
    const bool found = counted ? m.matched_by[k] != nullptr : m.uncounted_seen[k - m.objects.size()];
    e->cause = found ? FalseCause::kDuplicate : FalseCause::kMisplaced;
    e->near_object_id = object.id;
    e->near_object_m = distance;
  }
}

// Precision of the detections in the zone, overall, by band and zone (of their object's near
// point, or their own point when false) and by source; the matches' attributes.
void ScoreDetections(int f, const FrameMatch& m, double vehicle_length_m, const std::vector<LaneBoundaryRow>* lanes,
                     EvaluationResult* result) {
  for (size_t j = 0; j < m.dets.size(); ++j) {
    const Detection& d = *m.dets[j];
    if (m.det_match[j] >= 0) ScoreAttributes(d, *m.objects[m.det_match[j]], lanes, result);
    const Eigen::Vector2d point =
        m.det_match[j] >= 0 ? NearPoint(*m.objects[m.det_match[j]]) : Eigen::Vector2d(d.x_m, d.z_m);
    const double range = m.det_match[j] >= 0 ? point.norm() : d.range_m;
    for (BandScore* b : {&result->overall, BandOf(result, range), ZoneOf(result, point.y(), vehicle_length_m)}) {
      if (!b) continue;
      ++b->detections;
      b->matched_detections += m.det_seen[j] >= 0;
    }
    SourceScore* s = SourceOf(result, d.source);
    ++s->detections;
    s->matched += m.det_seen[j] >= 0;
    if (m.det_seen[j] >= 0) continue;
    ScoringError e{f, false, -1, d.source, {d.x_m, d.z_m}, d.range_m};
    FalseCauseOf(m, d, &e);
    ++s->false_causes[static_cast<int>(e.cause)];
    ++result->false_causes[static_cast<int>(e.cause)];
    result->errors.push_back(e);
  }
}

// Evaluate with the counted rows given (EvaluateTracks reuses them).
EvaluationResult EvaluateCounted(const std::vector<Detection>& detections, const std::vector<TruthRow>& truth,
                                 const std::vector<bool>& counted, const EvaluationOptions& options) {
  EvaluationResult result = EmptyResult(options);
  const double length = VehicleLength(options);
  std::map<int, std::vector<size_t>> truth_by_frame;
  for (size_t i = 0; i < truth.size(); ++i) truth_by_frame[truth[i].frame].push_back(i);
  std::map<int, std::vector<const Detection*>> det_by_frame;
  for (const Detection& d : detections) det_by_frame[d.frame].push_back(&d);
  std::vector<int> frames;
  for (const auto& [f, v] : truth_by_frame) frames.push_back(f);
  for (const auto& [f, v] : det_by_frame) frames.push_back(f);
  for (int f = 0; f < options.frame_count; ++f) frames.push_back(f);
  std::sort(frames.begin(), frames.end());
  frames.erase(std::unique(frames.begin(), frames.end()), frames.end());
  result.frames = static_cast<int>(frames.size());
  for (const int f : frames) {
    // Objects in range that a camera sees count (recall); the others can still be what a
    // detection in the zone sees, and such a detection is not a false one.
    FrameMatch m;
    for (const size_t i : truth_by_frame[f]) (counted[i] ? m.objects : m.uncounted).push_back(&truth[i]);
    for (const Detection* d : det_by_frame[f]) {
      (InZone({d->x_m, d->z_m}, options) ? m.dets : m.outside).push_back(d);
    }
    if (!m.dets.empty()) ++result.frames_with_detections;
    Match(&m);
    ScoreObjects(f, m, length, options.moving_speed_mps, &result);
    const auto lanes = options.truth_lanes.find(f);
    ScoreDetections(f, m, length, lanes == options.truth_lanes.end() ? nullptr : &lanes->second, &result);
  }
  return result;
}

}  // namespace

double BandScore::Recall() const { return objects ? double(matched_objects) / objects : 1.0; }
double BandScore::Precision() const { return detections ? double(matched_detections) / detections : 1.0; }
double BandScore::MedianRangeError() const { return Quantile(range_errors_m, 0.5); }
double BandScore::RangeErrorP90() const { return Quantile(range_errors_m, 0.9); }
double BandScore::MedianRelativeRangeError() const { return Quantile(relative_errors, 0.5); }
double BandScore::MedianVelocityError() const { return Quantile(velocity_errors_mps, 0.5); }
double BandScore::MedianMovingVelocityError() const { return Quantile(moving_velocity_errors_mps, 0.5); }
double BandScore::MovingVelocityErrorP90() const { return Quantile(moving_velocity_errors_mps, 0.9); }
double AttributeScore::Accuracy() const { return judged ? double(correct) / judged : std::nan(""); }

std::string ExpectedClass(const std::string& kind) {
  if (kind == "car") return "vehicle";
  if (kind == "truck" || kind == "bus") return "truck";
  if (kind == "pedestrian" || kind == "cyclist" || kind == "motorbike") return "pedestrian";
  if (kind == "pole" || kind == "post") return "pole";
  return "unknown";
}

const char* FalseCauseName(FalseCause cause) {
  switch (cause) {
    case FalseCause::kDuplicate: return "duplicate";
    case FalseCause::kMisplaced: return "misplaced";
    case FalseCause::kPhantom: break;
  }
  return "phantom";
}

double SourceScore::Precision() const { return detections ? double(matched) / detections : 1.0; }

EvaluationResult Evaluate(const std::vector<Detection>& detections, const std::vector<TruthRow>& truth,
                          const EvaluationOptions& options) {
  options.Check();
  return EvaluateCounted(detections, truth, CountedRows(truth, options), options);
}

TrackEvaluation EvaluateTracks(const std::vector<TrackState>& tracks, const std::vector<TruthRow>& truth,
                               const EvaluationOptions& options) {
  std::vector<Detection> as_detections;
  for (const TrackState& t : tracks) {
    if (!t.confirmed) continue;
    Detection d = DetectionFromPoints({{t.x_m, t.z_m}}, "track");
    d.frame = t.frame;
    d.t_s = t.t_s;
    d.id = t.id;
    d.has_velocity = true;
    d.vx_mps = t.vx_mps;
    d.vz_mps = t.vz_mps;
    d.height_m = t.height_m;
    d.lane = t.lane;
    d.object_class = t.object_class;
    as_detections.push_back(d);
  }
  options.Check();
  const std::vector<bool> counted = CountedRows(truth, options);
  TrackEvaluation out;
  out.positions = EvaluateCounted(as_detections, truth, counted, options);
  // Identity switches: per frame, match each counted object to its nearest track within the
  // tolerance and compare the track id with the object's previous one.
  std::map<int, std::vector<const Detection*>> by_frame;
  for (const Detection& d : as_detections) by_frame[d.frame].push_back(&d);
  std::map<int, int> last_track;  // truth id -> track id
  for (size_t i = 0; i < truth.size(); ++i) {
    if (!counted[i]) continue;
    const TruthRow& t = truth[i];
    const Detection* best = nullptr;
    double best_d = MatchTolerance(t);
    for (const Detection* d : by_frame[t.frame]) {
      const double dist = DistanceToFootprint(t, {d->x_m, d->z_m});
      if (dist <= best_d) best_d = dist, best = d;
    }
    if (!best) continue;
    const auto it = last_track.find(t.id);
    if (it == last_track.end()) {
      ++out.objects_tracked;
    } else if (it->second != best->id) {
      ++out.id_switches;
    }
    last_track[t.id] = best->id;
  }
  return out;
}

std::string EvaluationTable(const EvaluationResult& r) {
  std::ostringstream out;
  out << "band (m)  objects  recall  detections  precision  range error median / p90 (m)\n";
  auto row = [&](const BandScore& b) {
    char buf[160];
    std::snprintf(buf, sizeof(buf), "%-8s  %7d  %6s  %10d  %9s  %s / %s\n", b.name.c_str(), b.objects,
                  b.objects ? Number(b.Recall()).c_str() : "-", b.detections,
                  b.detections ? Number(b.Precision()).c_str() : "-", Number(b.MedianRangeError(), 2).c_str(),
                  Number(b.RangeErrorP90(), 2).c_str());
    out << buf;
  };
  for (const BandScore& b : r.bands) row(b);
  row(r.overall);
  out << "zone      objects  recall  detections  precision  range error median / p90 (m)\n";
  for (const BandScore& z : r.zones) row(z);
  if (!r.kinds.empty()) {
    out << "kind        objects  recall  range error median / p90 (m)\n";
    for (const BandScore& k : r.kinds) {
      char buf[160];
      std::snprintf(buf, sizeof(buf), "%-10s  %7d  %6s  %s / %s\n", k.name.c_str(), k.objects,
                    k.objects ? Number(k.Recall()).c_str() : "-", Number(k.MedianRangeError(), 2).c_str(),
                    Number(k.RangeErrorP90(), 2).c_str());
      out << buf;
    }
  }
  out << "source    detections  matched  precision\n";
  for (const SourceScore& s : r.sources) {
    char buf[120];
    std::snprintf(buf, sizeof(buf), "%-8s  %10d  %7d  %9s\n", s.source.c_str(), s.detections, s.matched,
                  s.detections ? Number(s.Precision()).c_str() : "-");
    out << buf;
  }
  out << "false detections: " << r.false_causes[0] << " duplicate (a second detection of a found object), "
      << r.false_causes[1] << " misplaced (near an object none found), " << r.false_causes[2]
      << " phantom (no object near)\n";
  out << "frames " << r.frames << ", with a detection in the zone " << r.frames_with_detections << "\n";
  if (r.classes.judged) {
    out << "class right for " << r.classes.correct << " of " << r.classes.judged << " matches ("
        << Number(r.classes.Accuracy()) << ")\n";
    for (const auto& [expected, given] : r.class_confusion) {
      out << "  " << expected << ":";
      for (const auto& [c, n] : given) out << " " << c << " " << n;
      out << "\n";
    }
  }
  if (r.lanes.judged) {
    out << "lane right for " << r.lanes.correct << " of " << r.lanes.judged << " matches with a true lane ("
        << Number(r.lanes.Accuracy()) << ")\n";
  }
  return out.str();
}

namespace {
// {"duplicate": n, "misplaced": n, "phantom": n}
std::string CausesJson(const std::array<int, kFalseCauses>& causes) {
  std::string out = "{";
  for (int c = 0; c < kFalseCauses; ++c) {
    out += Str(c ? ", " : "", "\"", FalseCauseName(static_cast<FalseCause>(c)), "\": ", causes[c]);
  }
  return out + "}";
}
}  // namespace

std::string EvaluationJson(const EvaluationResult& r) {
  std::ostringstream out;
  auto band = [&](const BandScore& b) {
    out << "{\"band\": \"" << b.name << "\", \"objects\": " << b.objects << ", \"matched_objects\": "
        << b.matched_objects << ", \"recall\": " << Number(b.Recall(), 4) << ", \"detections\": " << b.detections
        << ", \"matched_detections\": " << b.matched_detections << ", \"precision\": " << Number(b.Precision(), 4)
        << ", \"range_error_median_m\": " << Number(b.MedianRangeError(), 4)
        << ", \"range_error_p90_m\": " << Number(b.RangeErrorP90(), 4)
        << ", \"range_error_median_relative\": " << Number(b.MedianRelativeRangeError(), 4)
        << ", \"velocity_error_median_mps\": " << Number(b.MedianVelocityError(), 4)
        << ", \"moving_velocity_matches\": " << b.moving_velocity_errors_mps.size()
        << ", \"moving_velocity_error_median_mps\": " << Number(b.MedianMovingVelocityError(), 4)
        << ", \"moving_velocity_error_p90_mps\": " << Number(b.MovingVelocityErrorP90(), 4) << "}";
  };
  out << "{\n  \"overall\": ";
  band(r.overall);
  out << ",\n  \"bands\": [";
  for (size_t i = 0; i < r.bands.size(); ++i) {
    out << (i ? ", " : "");
    band(r.bands[i]);
  }
  out << "],\n  \"zones\": [";
  for (size_t i = 0; i < r.zones.size(); ++i) {
    out << (i ? ", " : "");
    band(r.zones[i]);
  }
  out << "],\n  \"kinds\": [";
  for (size_t i = 0; i < r.kinds.size(); ++i) {
    out << (i ? ", " : "");
    band(r.kinds[i]);
  }
  out << "],\n  \"sources\": [";
  for (size_t i = 0; i < r.sources.size(); ++i) {
    const SourceScore& s = r.sources[i];
    out << (i ? ", " : "") << "{\"source\": \"" << s.source << "\", \"detections\": " << s.detections
        << ", \"matched\": " << s.matched << ", \"precision\": " << Number(s.Precision(), 4)
        << ", \"false_causes\": " << CausesJson(s.false_causes) << "}";
  }
  out << "],\n  \"false_causes\": " << CausesJson(r.false_causes);
  out << ",\n  \"frames\": " << r.frames << ",\n  \"frames_with_detections\": " << r.frames_with_detections;
  for (const auto& [name, a] : {std::make_pair("classes", &r.classes), std::make_pair("lanes", &r.lanes)}) {
    out << ",\n  \"" << name << "\": {\"judged\": " << a->judged << ", \"correct\": " << a->correct
        << ", \"accuracy\": " << Number(a->Accuracy(), 4) << "}";
  }
  out << ",\n  \"class_confusion\": {";
  bool first = true;
  for (const auto& [expected, given] : r.class_confusion) {
    out << (first ? "" : ", ") << "\"" << expected << "\": {";
    first = false;
    bool first_given = true;
    for (const auto& [c, n] : given) {
      out << (first_given ? "" : ", ") << "\"" << c << "\": " << n;
      first_given = false;
    }
    out << "}";
  }
  out << "}";
  out << "\n}\n";
  return out.str();
}

std::string ScoringErrorsCsv(const EvaluationResult& r) {
  std::ostringstream out;
  out << "frame,error,id,kind,x,z,range,cause,near_id,near_m\n";
  for (const ScoringError& e : r.errors) {
    out << e.frame << ',' << (e.missed ? "missed" : "false") << ',' << e.object_id << ',' << e.kind << ','
        << Number(e.point.x()) << ',' << Number(e.point.y()) << ',' << Number(e.range_m) << ',';
    if (!e.missed) {
      out << FalseCauseName(e.cause) << ',';
      if (e.near_object_id >= 0) out << e.near_object_id << ',' << Number(e.near_object_m);
      else out << ',';
    } else {
      out << ",,";
    }
    out << '\n';
  }
  return out.str();
}

void CheckSameDrive(const std::vector<std::pair<int, double>>& results, const std::vector<TruthRow>& truth,
                    const std::string& results_file, const std::string& truth_file) {
  if (truth.empty() || results.empty()) return;
  std::map<int, double> truth_time;
  for (const TruthRow& r : truth) truth_time.emplace(r.frame, r.t_s);
  std::vector<double> steps;
  for (auto it = truth_time.begin(), next = std::next(it); next != truth_time.end(); ++it, ++next) {
    if (next->second > it->second) steps.push_back((next->second - it->second) / (next->first - it->first));
  }
  double tolerance = 1e-3;
  if (!steps.empty()) {
    std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
    tolerance = 0.5 * steps[steps.size() / 2];
  }
  const int last = truth_time.rbegin()->first;
  for (const auto& [frame, t] : results) {
    const auto it = truth_time.find(frame);
    if (it != truth_time.end() && !(std::abs(it->second - t) <= tolerance)) {
      throw Error(Str(results_file, ": frame ", frame, " is at t = ", t, " s, in ", truth_file, " at ", it->second,
                      " s: not the same drive (or not the same clock)"));
    }
    if (frame > last + 1 && std::abs(t - truth_time.rbegin()->second) > tolerance) {
      throw Error(Str(results_file, ": frame ", frame, " lies beyond ", truth_file, "'s last frame ", last,
                      ": not the same drive"));
    }
  }
}

void EvaluationOptions::Check() const {
  const OptionCheck Require("evaluation");
  Require(max_range_m > 0 && max_range_m <= 1000, "max_range_m", max_range_m, "0 < range <= 1000 m");
  Require(vehicle_length_m > 0 && vehicle_length_m <= 100, "vehicle_length_m", vehicle_length_m, "0 < length <= 100 m");
  Require(frame_count >= 0, "frame_count", frame_count, ">= 0");
  Require(moving_speed_mps >= 0, "moving_speed_mps", moving_speed_mps, ">= 0");
}

}  // namespace dps
