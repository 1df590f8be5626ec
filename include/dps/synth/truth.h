// dps — ground truth of synthetic or annotated drives: one object in one frame (DESIGN.md §3.6).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

namespace dps {

// One row of truth.csv (DESIGN.md §3.6).
struct TruthRow {
  int frame = 0;
  double t_s = 0.0;
  int id = 0;
  std::string kind;
  double x_m = 0.0, z_m = 0.0;  // footprint centre, vehicle frame at that frame
  double heading_deg = 0.0;     // from the vehicle's +Z to the object's length axis, towards +X
  double length_m = 0.0, width_m = 0.0, height_m = 0.0;
  double vx_mps = 0.0, vz_mps = 0.0;  // ground velocity in the vehicle frame
};

// The footprint's point nearest to the vehicle origin (its near point), vehicle frame (x, z).
Eigen::Vector2d NearPoint(const TruthRow& object);
// Distance from a ground point (x, z) to the footprint rectangle (0 inside it).
double DistanceToFootprint(const TruthRow& object, const Eigen::Vector2d& point);

}  // namespace dps
