#include "dps/synth/lane_truth.h"

#include "dps/util/math.h"

#include <cmath>

namespace dps {
namespace {

// Where the world line x = line_x crosses the vehicle's X axis (lateral offset, vehicle frame).
double OffsetAtVehicle(const PlanarPose& ego, double line_x) {
  // The vehicle's X axis runs through the world along (cos h, -sin h) (the heading h turns +Z
  // towards +X): the point e + u (cos h, -sin h) lies on the line where u = (line_x - e.x) / cos h.
  return (line_x - ego.x_m) / std::cos(ego.heading_rad);
}

}  // namespace

LaneTruth LaneTruthOf(const Scene& scene) {
  LaneTruth out;
  const RoadMarkings& r = scene.road;
  if (!r.enabled || scene.kind != SceneKind::kDrive) return out;
  // Line k (k = -lanes_left .. lanes_right + 1) at world x = centre + (k - 1/2) w; lane k
  // (-lanes_left .. lanes_right) lies between lines k and k + 1.
  const int first = -r.lanes_left, last = r.lanes_right + 1;
  const auto line_x = [&](int k) { return r.ego_lane_center_x_m + (k - 0.5) * r.lane_width_m; };
  int previous_lane = 0;
  bool had_lane = false;
  for (int f = 0; f < scene.FrameCount(); ++f) {
    const double t = scene.FrameTime(f);
    const PlanarPose ego = scene.EgoPoseAt(t);
    const int lane = static_cast<int>(std::floor((ego.x_m - line_x(0)) / r.lane_width_m));
    if (lane < first || lane > last - 1) {
      had_lane = false;  // off the road: no ego lane
      continue;
    }
    const double heading = -ego.heading_rad * kDegPerRad;  // the lines' direction seen from the vehicle
    const char* names[] = {"left2", "left", "right", "right2"};
    for (int i = 0; i < 4; ++i) {
      const int k = lane + i - 1;  // left2: lane - 1, left: lane, right: lane + 1, right2: lane + 2
      if (k < first || k > last) continue;
      const bool solid = k == first || k == last;
      out.boundaries.push_back({f, t, names[i], OffsetAtVehicle(ego, line_x(k)), heading, 0.0, solid ? "solid" : "dashed", 1.0});
    }
    const double left = OffsetAtVehicle(ego, line_x(lane)), right = OffsetAtVehicle(ego, line_x(lane + 1));
    EgoLaneRow e{f, t, -(left + right) / 2, r.lane_width_m, ego.heading_rad * kDegPerRad, ""};
    if (had_lane && lane != previous_lane) e.event = lane < previous_lane ? "left" : "right";
    out.ego.push_back(e);
    previous_lane = lane;
    had_lane = true;
  }
  return out;
}

}  // namespace dps
