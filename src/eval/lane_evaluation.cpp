#include "dps/eval/lane_evaluation.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>
#include <utility>

#include "dps/util/error.h"
#include "dps/util/math.h"

namespace dps {
namespace {

const char* const kBoundaries[] = {"left2", "left", "right", "right2"};

std::string Number(double v, const char* format) {
  if (!std::isfinite(v)) return "null";
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), format, v);
  return buffer;
}

// Lane changes: each truth event found by the nearest unused report of its direction within the
// delay; the reports left over are invented.
void ScoreEvents(const std::vector<EgoLaneRow>& ego, const std::vector<EgoLaneRow>& truth_ego, double max_delay_s,
                 LaneEvaluation* e) {
  std::vector<bool> used(ego.size(), false);
  for (const EgoLaneRow& t : truth_ego) {
    if (t.event.empty()) continue;
    ++e->truth_events;
    int best = -1;
    for (size_t j = 0; j < ego.size(); ++j) {
      if (used[j] || ego[j].event != t.event || std::abs(ego[j].t_s - t.t_s) > max_delay_s) continue;
      if (best < 0 || std::abs(ego[j].t_s - t.t_s) < std::abs(ego[best].t_s - t.t_s)) best = static_cast<int>(j);
    }
    if (best >= 0) used[best] = true, ++e->events_found;
  }
  for (size_t j = 0; j < ego.size(); ++j) e->events_invented += !ego[j].event.empty() && !used[j];
}

}  // namespace

void LaneEvaluationOptions::Check() const {
  const OptionCheck Require("lane evaluation");
  Require(max_event_delay_s >= 0, "max_event_delay_s", max_event_delay_s, ">= 0");
}

double BoundaryScore::MedianError() const { return Quantile(errors, 0.5); }
double BoundaryScore::P90Error() const { return Quantile(errors, 0.9); }
double LaneEvaluation::MedianLpError() const { return Quantile(lp_errors, 0.5); }

LaneEvaluation EvaluateLanes(const std::vector<LaneBoundaryRow>& boundaries, const std::vector<LaneBoundaryRow>& truth,
                             const std::vector<EgoLaneRow>& ego, const std::vector<EgoLaneRow>& truth_ego,
                             const LaneEvaluationOptions& options) {
  options.Check();
  LaneEvaluation e;
  std::set<int> frames;
  std::map<std::pair<int, std::string>, double> truth_offset, reported;
  for (const LaneBoundaryRow& r : truth) frames.insert(r.frame), truth_offset[{r.frame, r.boundary}] = r.offset_m;
  for (const EgoLaneRow& r : truth_ego) frames.insert(r.frame);
  for (const LaneBoundaryRow& r : boundaries) reported[{r.frame, r.boundary}] = r.offset_m;
  e.frames = static_cast<int>(frames.size());
  for (const char* name : kBoundaries) {
    BoundaryScore b;
    b.name = name;
    for (const int f : frames) {
      const auto t = truth_offset.find({f, name});
      const auto m = reported.find({f, name});
      if (t != truth_offset.end()) {
        ++b.truth_frames;
        if (m != reported.end()) ++b.found, b.errors.push_back(std::abs(m->second - t->second));
      } else if (m != reported.end()) {
        ++b.false_reports;
      }
    }
    e.boundaries.push_back(b);
  }
  std::map<int, double> truth_lp;
  for (const EgoLaneRow& r : truth_ego) truth_lp[r.frame] = r.lp_m;
  for (const EgoLaneRow& r : ego) {
    const auto t = truth_lp.find(r.frame);
    if (t != truth_lp.end()) e.lp_errors.push_back(std::abs(r.lp_m - t->second));
  }
  ScoreEvents(ego, truth_ego, options.max_event_delay_s, &e);
  return e;
}

std::string LaneEvaluationTable(const LaneEvaluation& e) {
  std::ostringstream o;
  o << "lanes: " << e.frames << " frames\n";
  o << "boundary  truth frames  found  false reports  offset error median / p90 (m)\n";
  for (const BoundaryScore& b : e.boundaries) {
    char line[160];
    std::snprintf(line, sizeof(line), "%-9s %12d  %5.3f  %13d  %s / %s\n", b.name.c_str(), b.truth_frames, b.FoundRate(),
                  b.false_reports, Number(b.MedianError(), "%.3f").c_str(), Number(b.P90Error(), "%.3f").c_str());
    o << line;
  }
  o << "lateral position error median " << Number(e.MedianLpError(), "%.3f") << " m over " << e.lp_errors.size()
    << " frames; lane changes " << e.events_found << " of " << e.truth_events << " found, " << e.events_invented
    << " invented\n";
  return o.str();
}

std::string LaneEvaluationJson(const LaneEvaluation& e) {
  std::ostringstream o;
  o << "{\"frames\": " << e.frames << ", \"boundaries\": [";
  for (size_t i = 0; i < e.boundaries.size(); ++i) {
    const BoundaryScore& b = e.boundaries[i];
    o << (i ? ", " : "") << "{\"boundary\": \"" << b.name << "\", \"truth_frames\": " << b.truth_frames
      << ", \"found\": " << b.found << ", \"false_reports\": " << b.false_reports
      << ", \"offset_error_median_m\": " << Number(b.MedianError(), "%.4f")
      << ", \"offset_error_p90_m\": " << Number(b.P90Error(), "%.4f") << "}";
  }
  o << "], \"lp_error_median_m\": " << Number(e.MedianLpError(), "%.4f") << ", \"lane_changes\": " << e.truth_events
    << ", \"lane_changes_found\": " << e.events_found << ", \"lane_changes_invented\": " << e.events_invented << "}";
  return o.str();
}

}  // namespace dps
