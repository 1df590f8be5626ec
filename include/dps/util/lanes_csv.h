// dps — lane files: lanes.csv / truth_lanes.csv (each lane boundary near the car per frame) and
// ego_lane.csv / truth_ego_lane.csv (the ego's lateral position in its lane), shared by the lane
// truth dps-synth writes and dps-eval's lane scores.
//
// lanes.csv: frame,t,boundary,offset,heading_deg,curvature,type,confidence
//   boundary: left2, left, right, right2 (the ego lane's boundaries and its neighbours' outer
//   ones); offset: where the boundary crosses the vehicle's X axis (lateral, metres, + right);
//   heading_deg: its direction there, from the vehicle's +Z towards +X; curvature: 1/m, + turning
//   towards +X; type: solid or dashed; confidence: 0..1.
// ego_lane.csv: frame,t,lp,lane_width,heading_deg,event
//   lp: the vehicle origin's lateral position from the ego lane's centre, metres, + right;
//   lane_width: metres, across the lane; heading_deg: the vehicle's heading relative to the lane,
//   + towards the right; event: empty, or left / right at the frame the vehicle's centre crossed
//   into the lane on that side.
#pragma once

#include <string>
#include <vector>

namespace dps {

struct LaneBoundaryRow {
  int frame = 0;
  double t_s = 0.0;
  std::string boundary;  // left2 | left | right | right2
  double offset_m = 0.0, heading_deg = 0.0, curvature = 0.0;
  std::string type;      // solid | dashed
  double confidence = 1.0;
};

struct EgoLaneRow {
  int frame = 0;
  double t_s = 0.0;
  double lp_m = 0.0, lane_width_m = 0.0, heading_deg = 0.0;
  std::string event;     // "" | left | right
};

// Written atomically; read by column name. Throw dps::Error naming the file, line and field
// (a boundary or type not among the names above, a confidence outside 0..1).
void WriteLaneBoundaries(const std::vector<LaneBoundaryRow>& rows, const std::string& path);
std::vector<LaneBoundaryRow> ReadLaneBoundaries(const std::string& path);
void WriteEgoLane(const std::vector<EgoLaneRow>& rows, const std::string& path);
std::vector<EgoLaneRow> ReadEgoLane(const std::string& path);

}  // namespace dps
