#include "dps/detect/lane_tracking.h"

#include <algorithm>
#include <cmath>

#include <Eigen/LU>

#include "dps/util/error.h"
#include "dps/util/math.h"

namespace dps {
namespace {

// A line x = offset + slope z of the previous vehicle frame in the current one: two of its points
// (z = 0 and 10 m) moved into the current frame, the line through them.
Eigen::Vector2d Carried(const Eigen::Vector2d& line, const PlanarPose& current_in_previous) {
  const Eigen::Vector2d a = WorldToBody(current_in_previous, {line.x(), 0.0});
  const Eigen::Vector2d b = WorldToBody(current_in_previous, {line.x() + 10.0 * line.y(), 10.0});
  const double slope = (b.x() - a.x()) / (b.y() - a.y());
  return {a.x() - slope * a.y(), slope};
}

}  // namespace

void LaneTrackerOptions::Check() const {
  const OptionCheck Require("lane tracker");
  Require(max_coast_s > 0, "max_coast_s", max_coast_s, "> 0 s");
  Require(gate_m > 0, "gate_m", gate_m, "> 0 m");
  Require(offset_sigma_m > 0, "offset_sigma_m", offset_sigma_m, "> 0 m");
  Require(heading_sigma_deg > 0, "heading_sigma_deg", heading_sigma_deg, "> 0 deg");
  Require(offset_drift_mps > 0, "offset_drift_mps", offset_drift_mps, "> 0 m/s");
  Require(heading_drift_dps > 0, "heading_drift_dps", heading_drift_dps, "> 0 deg/s");
  Require(min_measurements >= 1, "min_measurements", min_measurements, ">= 1");
  Require(min_coast_share >= 0 && min_coast_share <= 1, "min_coast_share", min_coast_share, "0..1");
  Require(min_lane_width_m > 0, "min_lane_width_m", min_lane_width_m, "> 0 m");
}

LaneTracker::LaneTracker(const LaneTrackerOptions& options) : options_(options) { options_.Check(); }

LaneFrame LaneTracker::Update(const LaneFrame& measured, const PlanarPose* current_in_previous, double t_s) {
  const LaneTrackerOptions& o = options_;
  // The first frame's lines stand as the detector found them: no earlier frame to confirm them.
  const bool first = !last_t_s_;
  // A car standing still (CAN speed and yaw rate 0) sees its lines where they were: they do not
  // drift, and standing beside a gap in the dashes does not use up their coasting time.
  const bool standing = current_in_previous && current_in_previous->x_m == 0 && current_in_previous->z_m == 0 &&
                        current_in_previous->heading_rad == 0;
  const double dt = last_t_s_ && !standing ? std::max(0.0, t_s - *last_t_s_) : 0.0;
  if (standing && last_t_s_) {
    for (Track& t : tracks_) t.last_measured_s += t_s - *last_t_s_;
  }
  last_t_s_ = t_s;
  // Predict: carried by the motion, with the drift the motion does not explain.
  const double slope_sigma = std::tan(o.heading_sigma_deg * kRadPerDeg);
  Eigen::Matrix2d Q = Eigen::Matrix2d::Zero();
  Q(0, 0) = std::pow(o.offset_drift_mps * dt, 2);
  Q(1, 1) = std::pow(std::tan(o.heading_drift_dps * kRadPerDeg) * dt, 2);
  for (Track& t : tracks_) {
    if (current_in_previous) {
      const Eigen::Vector2d x = Carried(t.x, *current_in_previous);
      Eigen::Matrix2d F;
      for (int k = 0; k < 2; ++k) {
        Eigen::Vector2d step = Eigen::Vector2d::Zero();
        step(k) = 1e-4;
        F.col(k) = (Carried(t.x + step, *current_in_previous) - Carried(t.x - step, *current_in_previous)) / 2e-4;
      }
      t.x = x;
      t.P = F * t.P * F.transpose();
    }
    t.P += Q;
    ++t.frames;
  }
  // Measurements, nearest pairs in offset first.
  struct Pair {
    double distance;
    size_t track, measurement;
  };
  const std::vector<LaneBoundaryRow>& m = measured.boundaries;
  // Each measurement where it was seen: its point at the middle of its stretch and its slope
  // (y = H x of a line x = (offset, slope)); a line's heading is known the less the shorter the
  // stretch it was fitted on (its ends each off by the offset's noise).
  std::vector<Eigen::Matrix2d> H(m.size()), R(m.size());
  std::vector<Eigen::Vector2d> y(m.size());
  for (size_t j = 0; j < m.size(); ++j) {
    const LaneStretch seen = j < measured.seen.size() ? measured.seen[j] : LaneStretch{};
    const double slope = std::tan(m[j].heading_deg * kRadPerDeg), z = seen.Middle();
    H[j] << 1.0, z, 0.0, 1.0;
    y[j] = Eigen::Vector2d(m[j].offset_m + slope * z, slope);
    const double sigma = seen.Length() > 0 ? 2 * o.offset_sigma_m / seen.Length() : slope_sigma;
    R[j] = Eigen::Vector2d(o.offset_sigma_m * o.offset_sigma_m, sigma * sigma).asDiagonal();
  }
  std::vector<Pair> pairs;
  // A measurement within gate_m of a line that another measurement updates does not start a line
  // of its own (two measurements of one boundary).
  std::vector<bool> near_a_line(m.size(), false);
  for (size_t i = 0; i < tracks_.size(); ++i) {
    for (size_t j = 0; j < m.size(); ++j) {
      const double d = std::abs((H[j] * tracks_[i].x - y[j]).x());
      if (d > o.gate_m) continue;
      near_a_line[j] = true;
      pairs.push_back({d, i, j});
    }
  }
  std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) { return a.distance < b.distance; });
  std::vector<bool> track_used(tracks_.size(), false), measurement_used(m.size(), false);
  for (const Pair& p : pairs) {
    if (track_used[p.track] || measurement_used[p.measurement]) continue;
    track_used[p.track] = measurement_used[p.measurement] = true;
    Track& t = tracks_[p.track];
    const LaneBoundaryRow& b = m[p.measurement];
    const size_t j = p.measurement;
    const Eigen::Matrix2d K = t.P * H[j].transpose() * (H[j] * t.P * H[j].transpose() + R[j]).inverse();
    t.x += K * (y[j] - H[j] * t.x);
    t.P = (Eigen::Matrix2d::Identity() - K * H[j]) * t.P;
    t.last_measured_s = t_s;
    ++t.measurements;
    t.frames_when_measured = t.frames;
    t.type = b.type;
    t.confidence = b.confidence;
  }
  for (size_t j = 0; j < m.size(); ++j) {
    if (measurement_used[j] || near_a_line[j]) continue;
    Track t;
    // At the axis, extrapolated from where it was seen.
    const Eigen::Matrix2d Hinv = H[j].inverse();
    t.x = Hinv * y[j];
    t.P = Hinv * R[j] * Hinv.transpose();
    t.last_measured_s = t_s;
    t.measurements = 1;
    t.frames = t.frames_when_measured = 1;
    t.confirmed = first;
    t.type = m[j].type;
    t.confidence = m[j].confidence;
    tracks_.push_back(t);
  }
  tracks_.erase(std::remove_if(tracks_.begin(), tracks_.end(),
                               [&](const Track& t) { return t_s - t.last_measured_s > o.max_coast_s; }),
                tracks_.end());
  std::vector<LaneLine> lines;
  for (const Track& t : tracks_) {
    if (!t.confirmed && t.measurements < o.min_measurements) continue;
    // Unmeasured this frame: only a line measured min_measurements times, in min_coast_share of its
    // frames until then.
    if (t.last_measured_s != t_s &&
        (t.measurements < o.min_measurements || t.measurements < o.min_coast_share * t.frames_when_measured)) {
      continue;
    }
    const double coast = (t_s - t.last_measured_s) / o.max_coast_s;
    lines.push_back({t.x.x(), t.x.y(), t.type, t.confidence * std::max(0.0, 1.0 - coast)});
  }
  return NameLaneLines(lines, o.min_lane_width_m, &previous_lp_);
}

}  // namespace dps
