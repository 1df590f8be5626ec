#include "dps/detect/coverage.h"

#include <cmath>

#include "dps/util/math.h"

namespace dps {

Eigen::Vector2d Sector::Vertex() const {
  return apex + start_m * Eigen::Vector2d(std::sin(direction_rad), std::cos(direction_rad));
}

bool Sector::Contains(const Eigen::Vector2d& p) const {
  const Eigen::Vector2d d = p - Vertex();
  // A point on an edge is inside (1e-9 rad: the rounding of points computed on an edge's ray).
  return std::abs(std::remainder(std::atan2(d.x(), d.y()) - direction_rad, 2 * kPi)) <= half_angle_rad + 1e-9;
}

bool Coverage::Contains(const Eigen::Vector2d& p) const {
  if (sectors.empty()) return true;
  for (const Sector& s : sectors) {
    if (s.Contains(p)) return true;
  }
  return false;
}

}  // namespace dps
