// dps — rays against axis-aligned boxes (the own car, objects in their own frame): the slab test
// that the renderer's own-car shadows, the views' own-car masks, the automatic marks, the lane
// view and the visibility rule share.
#pragma once

#include <limits>

#include <Eigen/Core>

namespace dps {

// Whether the ray o + t d lies inside the box [lo, hi] for some t in [t_min, t_max] (a segment
// from o to o + d: t in [0, 1]). Directions with a zero component are inside that slab only where
// o is.
bool RayMeetsBox(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                 double t_min = 0.0, double t_max = std::numeric_limits<double>::infinity());

}  // namespace dps
