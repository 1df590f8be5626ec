// dps — obstacle detections on the ground plane, the unit of detections.csv (DESIGN.md §3.4).
//
// A detection is one obstacle component of one source in one frame, described by the ground
// points it projected to (vehicle frame of that frame, metres): its point nearest to the vehicle
// origin (x, z), the range of that point, the extent of all points and their number.
#pragma once

#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace dps {

struct Detection {
  int frame = 0;
  double t_s = 0.0;
  std::string source;   // "front" (binocular stereo), "left" / "right" (motion stereo)
  int id = 0;           // index within the frame and source
  double x_m = 0.0, z_m = 0.0, range_m = 0.0;  // nearest point
  double x_min_m = 0.0, x_max_m = 0.0, z_min_m = 0.0, z_max_m = 0.0;
  int n_points = 0;
  std::vector<Eigen::Vector2d> points;  // ground points (x, z), for the map; not in the CSV
  // The end points (among `points`) where the view's edge, not the object, ends the detection:
  // the object may go on beyond them unseen (the tracker then measures only across its axis).
  // Not in the CSV.
  std::vector<Eigen::Vector2d> clipped_ends;
  // The top's height above the road as the source measured it (NaN: not measured), and the
  // attributes the pipeline gives from it (object_attributes.h): the lane (nullopt: unknown) and
  // the class name. detections.csv's extra columns height, lane, class.
  double height_m = std::numeric_limits<double>::quiet_NaN();
  std::optional<int> lane;
  std::string object_class;
  bool has_velocity = false;            // tracks scored as detections carry their velocity
  double vx_mps = 0.0, vz_mps = 0.0;
  // Motion stereo also measures the object's ground velocity along the camera's displacement
  // (side_detection.h); the tracker uses it. Not in the CSV.
  bool has_motion = false;
  Eigen::Vector2d motion_direction{0, 0};  // unit, vehicle frame (x, z)
  double motion_mps = 0.0;                 // ground velocity along motion_direction
  double motion_sigma_mps = 0.0;
};

// A detection summarising ground points (at least one): nearest point, extent, count.
Detection DetectionFromPoints(const std::vector<Eigen::Vector2d>& points, const std::string& source);

// Whether a ground point of each detection comes within distance_m of one of the other's (a
// detection without points: its nearest point).
bool Near(const Detection& a, const Detection& b, double distance_m);

// Merges the detections of one frame whose ground points come within merge_distance_m of each
// other (the parts of one object: a car's back and side, or one car seen by the front pair and a
// side camera at once), so that each object is one entry of the map. The merged detection keeps
// the source of the part holding the nearest point; ids are renumbered per source.
std::vector<Detection> FuseDetections(const std::vector<Detection>& detections, double merge_distance_m);

// Merges parts of one frame that together fit into one vehicle's footprint (the smallest rotated
// rectangle around their points no longer than max_length_m and no wider than max_width_m),
// parts of different sources first (each source has kept its own parts apart), then the smallest
// union, until no pair fits: a car seen partly by a side camera and partly by the front pair, with
// the stretch between unseen. `across_sources_only`: only parts from different sources. Ids are
// renumbered per source.
// `viewpoints` (optional, by source): two parts of one source are not merged when that source
// saw through the stretch between them (points of the source behind it on the same bearings).
// `depth_error_per_m2` (optional, by source, with its viewpoint): a part's depth along the line of
// sight is uncertain by k r^2 at range r from its source's viewpoint (stereo: k = sigma_d / (f B)),
// so a union may be longer than max_length_m by k r^2 at each part's farthest point: a 5 m car
// measured at 14 m stretches over 5.5 m with a pixel of disparity's error at its far end.
std::vector<Detection> MergeVehicleParts(std::vector<Detection> detections, double max_length_m, double max_width_m,
                                         bool across_sources_only,
                                         const std::map<std::string, Eigen::Vector2d>& viewpoints = {},
                                         const std::map<std::string, double>& depth_error_per_m2 = {});

// Drops the detections of `source` that lie wholly behind another of its detections as seen from
// `eye` (x, z; the source's cameras, eye_height_m above the road): within that one's bearings,
// farther from eye than it by more than the depth error (depth_error_per_m2 x r^2 at each, as
// MergeVehicleParts) and with their top below the sight line over its top. An opaque object hides
// what lies there; what stereo reports there was matched on the object's face at the wrong
// disparity (a repeated texture, e.g. the ribs of a truck's back close ahead). Detections without
// a measured height neither hide nor are hidden.
std::vector<Detection> DropHidden(std::vector<Detection> detections, const std::string& source,
                                  const Eigen::Vector2d& eye, double eye_height_m, double depth_error_per_m2);

}  // namespace dps
