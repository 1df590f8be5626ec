#include "dps/map/grid_obstacles.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <utility>

#include <opencv2/imgproc.hpp>

#include "dps/detect/object_attributes.h"
#include "dps/util/error.h"
#include "dps/util/math.h"

namespace dps {

void GridObstacleOptions::Check() const {
  const OptionCheck Require("grid obstacles");
  Require(max_range_m > 0, "max_range_m", max_range_m, "> 0");
  Require(min_area_m2 >= 0, "min_area_m2", min_area_m2, ">= 0");
}

namespace {

// Whether a remembered object and a detection of the frame are one object: they come within the
// merge distance, or together fit into one vehicle's footprint (a parked car's part in view and its
// remembered part behind the view's edge, the stretch between them unseen).
bool OneObject(const Detection& remembered, const Detection& measured, const SameObject& same) {
  if (Near(remembered, measured, same.merge_distance_m)) return true;
  if (same.vehicle_length_m <= 0) return false;
  std::vector<Eigen::Vector2d> both = remembered.points;
  both.insert(both.end(), measured.points.begin(), measured.points.end());
  const auto [length, width] = FootprintExtents(both);
  return length <= same.vehicle_length_m && width <= same.vehicle_width_m;
}

struct WeightedCell {
  Eigen::Vector2d point;  // vehicle frame
  float evidence;
};

// Where a remembered region's surface lies: its cells hold the evidence of many frames' hits, each
// spread along its ray by the range noise and occupied for thickness_m behind the measured range,
// so the region is deeper than the object and its nearest cell lies short of it. The side views
// measured it along their axis (across the car, give or take their half-angle), so its cells are
// taken in strips along that axis, a cell's diagonal wide (a cell's extent across any direction);
// in each, the evidence-weighted mean depth along the axis less half the thickness is the surface
// the hits measured: one point per strip, on a wall beside the road or a pole where it stands.
std::vector<Eigen::Vector2d> SurfacePoints(const std::vector<WeightedCell>& cells, const Sector& side,
                                           const OccupancyOptions& grid) {
  const Eigen::Vector2d along(std::sin(side.direction_rad), std::cos(side.direction_rad));
  const Eigen::Vector2d across(along.y(), -along.x());
  const double strip = std::sqrt(2.0) * grid.cell_m;
  struct Strip {
    double weight = 0, depth = 0, nearest = std::numeric_limits<double>::infinity();
  };
  std::map<long, Strip> strips;
  for (const WeightedCell& c : cells) {
    const Eigen::Vector2d rel = c.point - side.apex;
    Strip& s = strips[std::lround(std::floor(rel.dot(across) / strip))];
    s.weight += c.evidence;
    s.depth += c.evidence * rel.dot(along);
    s.nearest = std::min(s.nearest, rel.dot(along));
  }
  std::vector<Eigen::Vector2d> points;
  points.reserve(strips.size());
  for (const auto& [index, s] : strips) {
    const double depth = std::max(s.nearest, s.depth / s.weight - grid.thickness_m / 2);
    points.push_back(side.apex + depth * along + (index + 0.5) * strip * across);
  }
  return points;
}

// The sector of a side (its viewpoint and axis); without one, a view from the vehicle's origin
// straight out to that side.
Sector SideSector(const Coverage& coverage, const std::string& side) {
  for (const Sector& s : coverage.sectors) {
    if (s.name == side) return s;
  }
  Sector s;
  s.name = side;
  s.direction_rad = (side == "left" ? -0.5 : 0.5) * kPi;
  return s;
}

}  // namespace

std::vector<Detection> GridObstacles(const OccupancyGrid& grid, const PlanarPose& world_from_vehicle,
                                     const Coverage& coverage, const std::vector<Detection>& frame,
                                     const SameObject& same, const GridObstacleOptions& o) {
  o.Check();
  const double cell = grid.options().cell_m;
  // Objects are the 8-connected regions of occupied cells (evidence > 0: a wall whose evidence
  // fell below the threshold in places stays one region); their obstacle cells (above the
  // strength threshold) out of every view's sector and near enough are what is remembered.
  const cv::Mat& evidence = grid.Evidence();
  cv::Mat labels;
  cv::connectedComponents(evidence > 0, labels, 8, CV_32S);
  const float strong = static_cast<float>(grid.options().strength_threshold);
  std::map<int, std::vector<WeightedCell>> groups;
  for (int r = 0; r < evidence.rows; ++r) {
    for (int c = 0; c < evidence.cols; ++c) {
      const float e = evidence.at<float>(r, c);
      if (e <= strong) continue;
      const Eigen::Vector2d w = grid.origin() + Eigen::Vector2d(c + 0.5, r + 0.5) * cell;
      const Eigen::Vector2d p = WorldToBody(world_from_vehicle, w);
      if (p.norm() > o.max_range_m || (!coverage.sectors.empty() && coverage.Contains(p))) continue;
      groups[labels.at<int>(r, c)].push_back({p, e});
    }
  }
  // A region holding a point of the frame's detections is an object measured now.
  for (const Detection& d : frame) {
    for (const Eigen::Vector2d& q : d.points) {
      const Eigen::Vector2d c = (BodyToWorld(world_from_vehicle, q) - grid.origin()) / cell;
      const cv::Point at(static_cast<int>(std::floor(c.x())), static_cast<int>(std::floor(c.y())));
      if (at.x >= 0 && at.y >= 0 && at.x < labels.cols && at.y < labels.rows && labels.at<int>(at) > 0) {
        groups.erase(labels.at<int>(at));
      }
    }
  }
  std::vector<Detection> remembered;
  for (const auto& [root, group] : groups) {
    if (group.size() * cell * cell < o.min_area_m2) continue;
    Eigen::Vector2d centre = Eigen::Vector2d::Zero();
    for (const WeightedCell& p : group) centre += p.point;
    const std::string side = centre.x() < 0 ? "left" : "right";
    remembered.push_back(DetectionFromPoints(SurfacePoints(group, SideSector(coverage, side), grid.options()), side));
  }
  // Groups this close are one object (a wall or a car whose cells the grid lost in places); an
  // object this close to one of the frame's detections is that object, measured now.
  std::vector<Detection> out;
  for (Detection& r : FuseDetections(remembered, same.merge_distance_m)) {
    const bool measured =
        std::any_of(frame.begin(), frame.end(), [&](const Detection& d) { return OneObject(r, d, same); });
    if (!measured) out.push_back(std::move(r));
  }
  return out;
}

}  // namespace dps
