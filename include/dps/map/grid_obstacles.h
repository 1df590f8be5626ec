// dps — obstacles the occupancy grid remembers where no view looks this frame (seed 004, §4.4:
// obstacles are extracted from the grid with the strength threshold). A parked car, a pole or a
// wall the side views measured while the car passed stays in the grid, carried by the ego motion,
// after it leaves their sectors for the rear and the wedges between the views; its cells there
// become detections. What a view sees this frame is measured, not remembered: cells inside the
// frame's coverage, and objects the frame detects in part (a parked car's front still in view),
// are left out. Moving objects leave trails in the grid, which this reports too where no view
// clears them (docs/detection.md).
#pragma once

#include <vector>

#include "dps/camera/ego_motion.h"
#include "dps/detect/coverage.h"
#include "dps/detect/detection.h"
#include "dps/map/occupancy_grid.h"

namespace dps {

struct GridObstacleOptions {
  double max_range_m = 20.0;    // remembered cells this near the vehicle origin, > 0
  double min_area_m2 = 0.08;    // a group of cells covering less: not reported, >= 0

  // Throws dps::Error naming the field, its value and the violated constraint.
  void Check() const;
};

// When a remembered object is one the frame measures: within merge_distance_m of it, or together
// with it within one vehicle's footprint (vehicle_length_m = 0: no such test); the pipeline's own
// (PipelineOptions).
struct SameObject {
  double merge_distance_m = 1.5;
  double vehicle_length_m = 5.5;
  double vehicle_width_m = 2.2;
};

// The objects the grid remembers around the vehicle that `world_from_vehicle` places: each
// 8-connected region of occupied cells (evidence > 0, so that a wall whose evidence fell below
// the threshold in places stays one region) with obstacle cells (above the grid's strength
// threshold) outside `coverage`, within max_range_m and covering at least min_area_m2; regions
// within merge_distance_m of each other one object (FuseDetections). Each a detection (vehicle
// frame, its surface as points: in strips along the side view's axis, the evidence-weighted mean
// depth of its obstacle cells less half the grid's thickness; source "left" or "right" by the side
// of its centre; frame, time and id left to the caller), unless it is measured now: its region
// holds a point of one of `frame`'s detections, or it is one object with one of them (SameObject).
std::vector<Detection> GridObstacles(const OccupancyGrid& grid, const PlanarPose& world_from_vehicle,
                                     const Coverage& coverage, const std::vector<Detection>& frame,
                                     const SameObject& same, const GridObstacleOptions& options = {});

}  // namespace dps
