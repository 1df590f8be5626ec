// dps — numeric helpers the stages share: angle units and a quantile.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

namespace dps {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kRadPerDeg = kPi / 180.0;
inline constexpr double kDegPerRad = 180.0 / kPi;

// The q-quantile (0 <= q <= 1) of v by nearest rank; NaN when v is empty.
inline double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(q * (v.size() - 1) + 0.5))];
}

}  // namespace dps
