// dps — the field of view on the ground: what the pipeline processes, as sectors, each an apex
// (the viewpoint, or the front pair's midpoint), a direction and a half-angle (for the front pair
// atan of half the view width over the focal length, beginning ahead of its apex where both views
// overlap; for a side view the span of the columns motion stereo matches, as deep as its depth
// limit). The grid, the remembered obstacles and the map use it; without a coverage every
// direction counts. The map also draws where this frame's motion stereo cannot tell depth.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "dps/stereo/virtual_view.h"

namespace dps {

struct Sector {
  std::string name;               // "front", "left", "right"
  Eigen::Vector2d apex{0, 0};     // where the source looks from, vehicle frame (x, z)
  double direction_rad = 0.0;     // from +Z towards +X
  double half_angle_rad = 0.0;
  // The sector begins this far ahead of the apex along its direction, at its vertex: a stereo
  // pair sees only where both views overlap, from where their inner edges cross.
  double start_m = 0.0;
  // > 0: the source measures nothing deeper than this along depth_direction_rad from the apex (a
  // side view's depth limit, SideDetectorOptions::max_depth_m): beyond it the sector does not see.
  // 0: no such limit.
  double max_depth_m = 0.0;
  double depth_direction_rad = 0.0;
  Eigen::Vector2d Vertex() const;
  bool Contains(const Eigen::Vector2d& point) const;
  // How far from the apex the sector sees along a bearing (from +Z towards +X): infinity without a
  // depth limit, or where the bearing turns away from its depth direction by 90 degrees or more.
  double Reach(double bearing_rad) const;
};

// Motion stereo from one viewpoint between two frames (a side view's pair): a static point's
// direction turns by about b sin(a) / r between them (b the viewpoint's displacement, a the
// point's angle from it, r its distance), and the point's depth is told only where that turn is
// at least the matcher's noise, sigma / f (SideDetectorOptions::disparity_sigma_px over the
// views' focal length): where r <= D sin(a), D = f b / sigma. That is two discs of diameter D
// touching the line of motion at the viewpoint, one on either side; outside both lie the wedges
// about the motion's epipoles, ahead and behind, widening with distance, where this motion tells
// no depth.
struct MotionSight {
  std::string name;                  // the camera's
  Eigen::Vector2d viewpoint{0, 0};   // vehicle frame (x, z)
  double direction_rad = 0.0;        // the viewpoint's displacement, from +Z towards +X
  double diameter_m = 0.0;           // D
  bool TellsDepth(const Eigen::Vector2d& point) const;
};

struct Coverage {
  std::vector<Sector> sectors;  // empty = everything
  // This frame's motion stereo, one per side view matched (the map draws the wedges about the
  // epipoles); empty when no view was matched by motion stereo.
  std::vector<MotionSight> motion;
  bool Contains(const Eigen::Vector2d& point) const;
  // True when this frame had motion stereo and none of it tells the point's depth (the wedges
  // about the motion's epipoles).
  bool MotionBlind(const Eigen::Vector2d& point) const;
};

// The sector, from `apex` on the ground (vehicle frame), of a view's columns [x_lo, x_hi] (its
// bearings at the principal row), named `name`; max_depth_m > 0: no deeper along the view's axis.
Sector ViewColumnsSector(const std::string& name, const Eigen::Vector2d& apex, const ViewSpec& view, double x_lo,
                         double x_hi, double max_depth_m = 0.0);

}  // namespace dps
