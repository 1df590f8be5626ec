#include "dps/camera/box.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace dps {

bool RayMeetsBox(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                 double t_min, double t_max) {
  for (int k = 0; k < 3; ++k) {
    if (std::abs(d[k]) < 1e-12) {
      if (o[k] < lo[k] || o[k] > hi[k]) return false;
      continue;
    }
    double a = (lo[k] - o[k]) / d[k], b = (hi[k] - o[k]) / d[k];
    if (a > b) std::swap(a, b);
    t_min = std::max(t_min, a);
    t_max = std::min(t_max, b);
    if (t_min > t_max) return false;
  }
  return true;
}

}  // namespace dps
