// dps — the attributes of the surround map's objects besides position (seed 000, Fig. 1): each
// detection's and track's lane and a coarse class from its measured size and height.
//
// Lane: the boundaries of one frame (lanes.csv's form: offset at the vehicle's X axis, heading,
// curvature) placed at the object's distance along the car; 0 between the ego lane's left and
// right boundaries, -1 the lane beyond the left one, -2 the next, +1, +2 to the right, the lanes
// beyond the ego lane as wide as it. Unknown without both ego boundaries.
// Class: from the footprint's larger and smaller extent on the ground and the top's height above
// the road, against the sizes of road users: poles and posts are thin and tall, pedestrians and
// two-wheelers narrow and at most a person's height, cars and vans up to a van's length and
// height, trucks and buses beyond. A detection sees only the faces turned to the cameras, so its
// extents are lower bounds; a car seen from behind is as wide as a car.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "dps/detect/detection.h"
#include "dps/util/csv.h"
#include "dps/util/lanes_csv.h"

namespace dps {

enum class ObjectClass { kUnknown, kVehicle, kTruck, kPedestrian, kPole };

// "unknown", "vehicle", "truck" (trucks and buses), "pedestrian" (two-wheelers too), "pole".
const char* ObjectClassName(ObjectClass c);
// The class of a name above; nullopt for any other string.
std::optional<ObjectClass> ObjectClassFromName(const std::string& name);

struct ClassOptions {
  double min_height_m = 0.3;          // lower tops: unknown (a kerb, a measurement of the bottom only)
  double pole_max_width_m = 0.45;     // poles and posts: the larger extent at most this ...
  double pole_min_height_m = 2.3;     // ... or, at most person_max_length_m long, taller than this
  double person_max_length_m = 1.3;   // pedestrians, cyclists, motorbikes seen from any side: the
                                      // larger extent at most this (a bicycle's length is more,
                                      // but it is seen as long only from the side) ...
  double person_max_height_m = 2.3;   // ... and the top at most this high
  double vehicle_max_length_m = 6.5;  // cars and vans: the larger extent at most this ...
  double vehicle_max_height_m = 2.6;  // ... and the top at most this high; beyond: truck or bus
                                      // (longer but not higher: unknown, a wall or a fence)
  double truck_max_height_m = 4.5;    // higher tops: unknown (a bridge, a tree)

  // Throws dps::Error naming the field, its value and the violated constraint.
  void Check() const;
};

// length_m: the footprint's larger extent on the ground (the smaller one bounds nothing: a face seen
// edge-on); height_m: the object's height above the road (NaN: not measured, the class then from
// the footprint alone).
ObjectClass ClassifyObject(double length_m, double height_m, const ClassOptions& options = {});

// The larger and smaller extent of ground points: the sides of the smallest rectangle around them
// (any orientation); {0, 0} for fewer than two points.
std::pair<double, double> FootprintExtents(const std::vector<Eigen::Vector2d>& points);

// The lane of a ground point (vehicle frame, metres) among one frame's boundaries (see above);
// nullopt when the frame lacks the ego lane's left or right boundary.
std::optional<int> LaneOfPoint(const std::vector<LaneBoundaryRow>& boundaries, const Eigen::Vector2d& point);

// Sets a detection's lane (of the centre of its points' box) among one frame's lane boundaries and
// its class (its points' larger extent and its height).
void SetAttributes(const std::vector<LaneBoundaryRow>& lanes, const ClassOptions& options, Detection* detection);

// detections.csv's and tracks.csv's extra columns height, lane, class (after DESIGN.md's): the
// cells of one row, each empty when unknown (height in metres with 3 decimals).
std::string AttributeCells(double height_m, const std::optional<int>& lane, const std::string& object_class);
// The columns in a table (-1: absent; a file of another writer may lack them).
struct AttributeColumns {
  explicit AttributeColumns(const CsvTable& table);
  int height = -1, lane = -1, object_class = -1;
};
// Reads a row's attributes from the columns present (the others left as they are); throws
// dps::Error naming the file, line and column for a value that is not a number, a whole number or
// a class name.
void ReadAttributes(const CsvTable& table, size_t row, const AttributeColumns& columns, double* height_m,
                    std::optional<int>* lane, std::string* object_class);

}  // namespace dps
