#include "dps/detect/coverage.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "dps/util/math.h"

namespace dps {

Eigen::Vector2d Sector::Vertex() const {
  return apex + start_m * Eigen::Vector2d(std::sin(direction_rad), std::cos(direction_rad));
}

bool Sector::Contains(const Eigen::Vector2d& p) const {
  const Eigen::Vector2d d = p - Vertex();
  // A point on an edge is inside (1e-9 rad: the rounding of points computed on an edge's ray).
  if (std::abs(std::remainder(std::atan2(d.x(), d.y()) - direction_rad, 2 * kPi)) > half_angle_rad + 1e-9) return false;
  return max_depth_m <= 0.0 ||
         (p - apex).dot(Eigen::Vector2d(std::sin(depth_direction_rad), std::cos(depth_direction_rad))) <= max_depth_m;
}

double Sector::Reach(double bearing_rad) const {
  const double c = std::cos(bearing_rad - depth_direction_rad);
  return max_depth_m > 0.0 && c > 0.0 ? max_depth_m / c : std::numeric_limits<double>::infinity();
}

bool Coverage::Contains(const Eigen::Vector2d& p) const {
  if (sectors.empty()) return true;
  for (const Sector& s : sectors) {
    if (s.Contains(p)) return true;
  }
  return false;
}

bool MotionSight::TellsDepth(const Eigen::Vector2d& point) const {
  // r <= D sin(a), i.e. r^2 <= D |m x p| with m the unit displacement.
  const Eigen::Vector2d p = point - viewpoint, m(std::sin(direction_rad), std::cos(direction_rad));
  return p.squaredNorm() <= diameter_m * std::abs(m.x() * p.y() - m.y() * p.x());
}

bool Coverage::MotionBlind(const Eigen::Vector2d& p) const {
  if (motion.empty()) return false;
  for (const MotionSight& m : motion) {
    if (m.TellsDepth(p)) return false;
  }
  return true;
}

Sector ViewColumnsSector(const std::string& name, const Eigen::Vector2d& apex, const ViewSpec& view, double x_lo,
                         double x_hi, double max_depth_m) {
  const auto bearing = [&](double x) {
    const Eigen::Vector3d ray = view.vehicle_from_view * Eigen::Vector3d((x - view.cx) / view.focal_px, 0.0, 1.0);
    return Eigen::Vector2d(ray.x(), ray.z()).normalized();
  };
  const Eigen::Vector2d a = bearing(x_lo), b = bearing(x_hi), mid = a + b;
  Sector s;
  s.name = name;
  s.apex = apex;
  s.direction_rad = std::atan2(mid.x(), mid.y());
  s.half_angle_rad = std::acos(std::clamp(a.dot(b), -1.0, 1.0)) / 2;
  s.max_depth_m = max_depth_m;
  const Eigen::Vector3d axis = view.vehicle_from_view.col(2);
  s.depth_direction_rad = std::atan2(axis.x(), axis.z());
  return s;
}

}  // namespace dps
