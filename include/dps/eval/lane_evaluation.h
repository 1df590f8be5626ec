// dps — lane scores (dps-eval --lanes): lanes.csv and ego_lane.csv (util/lanes_csv.h) against
// the truth's. Per boundary (left2, left, right, right2): in how many of the frames where the
// truth has it a boundary of that name was reported, the error of its offset there, and how many
// reports name a boundary the truth does not have; the ego's lateral position error; lane changes
// found within max_event_delay_s of the truth's (same direction, each report used once) and
// reported ones the truth does not have.
#pragma once

#include <string>
#include <vector>

#include "dps/util/lanes_csv.h"

namespace dps {

struct LaneEvaluationOptions {
  double max_event_delay_s = 0.3;  // a reported lane change this close to the truth's finds it, >= 0

  // Throws dps::Error naming the field, its value and the violated constraint.
  void Check() const;
};

struct BoundaryScore {
  std::string name;
  int truth_frames = 0;        // frames whose truth has this boundary
  int found = 0;               // ... of them with one reported
  int false_reports = 0;       // reports in frames whose truth does not have it
  std::vector<double> errors;  // |offset - truth offset|, m, where found
  double FoundRate() const { return truth_frames ? static_cast<double>(found) / truth_frames : 1.0; }
  double MedianError() const;  // NaN without errors
  double P90Error() const;
};

struct LaneEvaluation {
  std::vector<BoundaryScore> boundaries;  // left2, left, right, right2
  int frames = 0;                         // frames with truth
  std::vector<double> lp_errors;          // |lp - truth lp|, m, frames with both
  int truth_events = 0, events_found = 0, events_invented = 0;
  double MedianLpError() const;
};

LaneEvaluation EvaluateLanes(const std::vector<LaneBoundaryRow>& boundaries, const std::vector<LaneBoundaryRow>& truth,
                             const std::vector<EgoLaneRow>& ego, const std::vector<EgoLaneRow>& truth_ego,
                             const LaneEvaluationOptions& options = {});

// A plain-text table and a JSON object of the scores.
std::string LaneEvaluationTable(const LaneEvaluation& e);
std::string LaneEvaluationJson(const LaneEvaluation& e);

}  // namespace dps
