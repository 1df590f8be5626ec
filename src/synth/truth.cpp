#include "dps/synth/truth.h"

#include "dps/util/math.h"

#include <algorithm>
#include <cmath>

namespace dps {
namespace {

// The point of the footprint nearest to `p` (both vehicle frame x, z).
Eigen::Vector2d ClosestOnFootprint(const TruthRow& o, const Eigen::Vector2d& p) {
  const double h = o.heading_deg * kRadPerDeg;
  const Eigen::Vector2d along(std::sin(h), std::cos(h)), across(std::cos(h), -std::sin(h));
  const Eigen::Vector2d centre(o.x_m, o.z_m), d = p - centre;
  const double a = std::clamp(d.dot(along), -o.length_m / 2, o.length_m / 2);
  const double c = std::clamp(d.dot(across), -o.width_m / 2, o.width_m / 2);
  return centre + a * along + c * across;
}

}  // namespace

Eigen::Vector2d NearPoint(const TruthRow& o) { return ClosestOnFootprint(o, Eigen::Vector2d::Zero()); }

double DistanceToFootprint(const TruthRow& o, const Eigen::Vector2d& p) {
  return (ClosestOnFootprint(o, p) - p).norm();
}

}  // namespace dps
