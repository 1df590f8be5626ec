#include "dps/map/tracker.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "dps/util/error.h"

namespace dps {
// A detection's velocity along one direction (motion stereo, Detection::has_motion) updates the
// track's velocity in that direction: H = [0 0 u], one scalar measurement, unless it lies outside
// the gate (motion stereo of a part that moves differently, e.g. the background at a car's end).
void Tracker::ApplyMotion(const Detection& d, const Eigen::Matrix2d& world_from_vehicle, double gate_chi2, Track* t) {
  if (!d.has_motion || !(d.motion_sigma_mps > 0)) return;
  const Eigen::Vector2d u = world_from_vehicle * d.motion_direction;
  Eigen::Matrix<double, 1, 5> H;
  H << 0, 0, u.x(), u.y(), 0;
  ScalarUpdate(H, d.motion_mps - (H * t->x)(0, 0), d.motion_sigma_mps * d.motion_sigma_mps, gate_chi2, t);
}

double Tracker::StandingProbability(const Track& t) { return 1.0 / (1.0 + std::exp(-t.standing_log_odds)); }

// A measurement of H x in M dimensions: its innovation and covariance; skipped outside the gate.
template <int M>
void Tracker::Update(const Eigen::Matrix<double, M, 5>& H, const Eigen::Matrix<double, M, 1>& innovation,
                     const Eigen::Matrix<double, M, M>& covariance, double gate_chi2, Track* t) {
  const Eigen::Matrix<double, M, M> S = H * t->P * H.transpose() + covariance;
  const double d2 = innovation.dot(S.ldlt().solve(innovation));
  if (d2 > gate_chi2) return;
  // The same measurement (value innovation + H x) under the standing model, whose state is the
  // position alone (velocity 0): the models' likelihood ratio, then its own update.
  const Eigen::Matrix<double, M, 2> Hs = H.template leftCols<2>();
  const Eigen::Matrix<double, M, 1> is = innovation + H * t->x - Hs * t->standing;
  const Eigen::Matrix<double, M, M> Ss = Hs * t->standing_P * Hs.transpose() + covariance;
  t->standing_log_odds += 0.5 * (d2 + std::log(S.determinant())) -
                          0.5 * (is.dot(Ss.ldlt().solve(is)) + std::log(Ss.determinant()));
  if (Hs.squaredNorm() > 0) {
    const Eigen::Matrix<double, 2, M> Ks = t->standing_P * Hs.transpose() * Ss.inverse();
    t->standing += Ks * is;
    t->standing_P = (Eigen::Matrix2d::Identity() - Ks * Hs) * t->standing_P;
  }
  const Eigen::Matrix<double, 5, M> K = t->P * H.transpose() * S.inverse();
  t->x += K * innovation;
  t->P = (Cov::Identity() - K * H) * t->P;
}

void Tracker::ScalarUpdate(const Eigen::Matrix<double, 1, 5>& H, double innovation, double variance, double gate_chi2,
                           Track* t) {
  Update<1>(H, Eigen::Matrix<double, 1, 1>(innovation), Eigen::Matrix<double, 1, 1>(variance), gate_chi2, t);
}

bool RegisterPoints(const std::vector<Eigen::Vector2d>& from, const std::vector<Eigen::Vector2d>& to,
                    const Eigen::Vector2d& initial, double gate_m, double min_overlap, Eigen::Vector2d* shift,
                    double* rms_m) {
  if (from.size() < 3 || to.size() < 3) return false;
  Eigen::Vector2d s = initial;
  int pairs = 0;
  double sum_d2 = 0.0;
  for (int round = 0; round < 10; ++round) {
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    pairs = 0;
    sum_d2 = 0.0;
    for (const Eigen::Vector2d& p : from) {
      const Eigen::Vector2d moved = p + s;
      const Eigen::Vector2d* nearest = nullptr;
      double best = gate_m * gate_m;
      for (const Eigen::Vector2d& q : to) {
        const double d2 = (q - moved).squaredNorm();
        if (d2 <= best) best = d2, nearest = &q;
      }
      if (!nearest) continue;
      sum += *nearest - p;
      sum_d2 += best;
      ++pairs;
    }
    if (pairs < 3) return false;
    const Eigen::Vector2d next = sum / pairs;
    const bool settled = (next - s).norm() < 1e-6;
    s = next;
    if (settled) break;
  }
  if (pairs < min_overlap * from.size()) return false;
  *shift = s;
  *rms_m = std::sqrt(sum_d2 / pairs);
  return true;
}

// The registration velocity (see tracker.h) from this hit's points, then this hit kept.
void Tracker::ApplyRegistration(double t_s, const std::vector<Eigen::Vector2d>& points, bool cut,
                                const Eigen::Matrix2d& world_from_vehicle, Track* t) const {
  if (options_.registration_span_s <= 0) return;
  const double span = options_.registration_span_s;
  for (const auto& [t_old, old_points] : t->shapes) {  // oldest first
    const double dt = t_s - t_old;
    if (dt < 0.99 * span || dt > 2 * span) continue;
    Eigen::Vector2d shift;
    double rms = 0.0;
    if (RegisterPoints(old_points, points, t->x.segment<2>(2) * dt, options_.registration_gate_m,
                       options_.registration_min_overlap, &shift, &rms)) {
      const double sigma = (options_.registration_sigma_m + rms) / dt;
      // The shift is the mean velocity over dt: the velocity now differs from it by the
      // acceleration over about dt / 2.
      const Eigen::Matrix2d R =
          Eigen::Matrix2d::Identity() * sigma * sigma + AccelCovariance(*t, world_from_vehicle) * (dt * dt / 4);
      const Eigen::Vector2d innovation = shift / dt - t->x.segment<2>(2);
      if (cut) {
        const Eigen::Vector2d a = Axis(*t, world_from_vehicle), n(-a.y(), a.x());
        Eigen::Matrix<double, 1, 5> H;
        H << 0, 0, n.x(), n.y(), 0;
        ScalarUpdate(H, n.dot(innovation), n.dot(R * n), options_.gate_chi2, t);
      } else {
        Eigen::Matrix<double, 2, 5> H = Eigen::Matrix<double, 2, 5>::Zero();
        H(0, 2) = H(1, 3) = 1;
        Update<2>(H, innovation, R, options_.gate_chi2, t);
      }
    }
    break;
  }
  t->shapes.push_back({t_s, points});
  while (t_s - t->shapes.front().first > 2 * span) t->shapes.erase(t->shapes.begin());
}

void TrackerOptions::Check() const {
  const OptionCheck Require("tracker");
  Require(accel_sigma_mps2 > 0, "accel_sigma_mps2", accel_sigma_mps2, "> 0");
  Require(across_accel_sigma_mps2 > 0, "across_accel_sigma_mps2", across_accel_sigma_mps2, "> 0");
  Require(turn_accel_sigma_radps2 >= 0, "turn_accel_sigma_radps2", turn_accel_sigma_radps2, ">= 0");
  Require(init_turn_sigma_radps >= 0, "init_turn_sigma_radps", init_turn_sigma_radps, ">= 0");
  Require(meas_sigma_m > 0, "meas_sigma_m", meas_sigma_m, "> 0");
  Require(meas_sigma_per_m >= 0, "meas_sigma_per_m", meas_sigma_per_m, ">= 0");
  Require(local_radius_m >= 0, "local_radius_m", local_radius_m, ">= 0");
  Require(clip_radius_m >= 0, "clip_radius_m", clip_radius_m, ">= 0");
  Require(max_hidden_m >= 0, "max_hidden_m", max_hidden_m, ">= 0");
  Require(axis_min_speed_mps >= 0, "axis_min_speed_mps", axis_min_speed_mps, ">= 0");
  Require(extent_sigma_fraction >= 0, "extent_sigma_fraction", extent_sigma_fraction, ">= 0");
  Require(init_speed_sigma_mps > 0, "init_speed_sigma_mps", init_speed_sigma_mps, "> 0");
  Require(init_across_speed_sigma_mps > 0, "init_across_speed_sigma_mps", init_across_speed_sigma_mps, "> 0");
  Require(gate_chi2 > 0, "gate_chi2", gate_chi2, "> 0");
  Require(motion_gate_chi2 > 0, "motion_gate_chi2", motion_gate_chi2, "> 0");
  Require(registration_span_s >= 0, "registration_span_s", registration_span_s, ">= 0");
  Require(registration_sigma_m > 0, "registration_sigma_m", registration_sigma_m, "> 0");
  Require(registration_gate_m > 0, "registration_gate_m", registration_gate_m, "> 0");
  Require(registration_min_overlap >= 0 && registration_min_overlap <= 1, "registration_min_overlap",
          registration_min_overlap, "in [0, 1]");
  Require(confirm_hits >= 1, "confirm_hits", confirm_hits, ">= 1");
  Require(max_misses >= 1, "max_misses", max_misses, ">= 1");
  Require(predict_ahead_s >= 0, "predict_ahead_s", predict_ahead_s, ">= 0");
  Require(model_switch_per_s >= 0, "model_switch_per_s", model_switch_per_s, ">= 0");
  Require(standing_drift_sigma > 0, "standing_drift_sigma", standing_drift_sigma, "> 0");
}

std::vector<int> HungarianAssignment(const std::vector<std::vector<double>>& cost, double forbidden) {
  const int rows = static_cast<int>(cost.size());
  if (rows == 0) return {};
  const int cols = static_cast<int>(cost[0].size());
  const int n = std::max(rows, cols);
  // Square matrix; padding and forbidden entries get a large cost (never preferred to a real one).
  const double big = forbidden * 2 + 1;
  auto a = [&](int i, int j) {
    if (i >= rows || j >= cols) return big;
    return cost[i][j] >= forbidden ? big : cost[i][j];
  };
  // Potentials method (1-based), O(n^3).
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> u(n + 1, 0), v(n + 1, 0);
  std::vector<int> p(n + 1, 0), way(n + 1, 0);
  for (int i = 1; i <= n; ++i) {
    p[0] = i;
    int j0 = 0;
    std::vector<double> minv(n + 1, inf);
    std::vector<char> used(n + 1, false);
    do {
      used[j0] = true;
      const int i0 = p[j0];
      double delta = inf;
      int j1 = 0;
      for (int j = 1; j <= n; ++j) {
        if (used[j]) continue;
        const double cur = a(i0 - 1, j - 1) - u[i0] - v[j];
        if (cur < minv[j]) minv[j] = cur, way[j] = j0;
        if (minv[j] < delta) delta = minv[j], j1 = j;
      }
      for (int j = 0; j <= n; ++j) {
        if (used[j]) {
          u[p[j]] += delta;
          v[j] -= delta;
        } else {
          minv[j] -= delta;
        }
      }
      j0 = j1;
    } while (p[j0] != 0);
    do {
      const int j1 = way[j0];
      p[j0] = p[j1];
      j0 = j1;
    } while (j0);
  }
  std::vector<int> out(rows, -1);
  for (int j = 1; j <= n; ++j) {
    const int i = p[j] - 1;
    if (i >= 0 && i < rows && j - 1 < cols && cost[i][j - 1] < forbidden) out[i] = j - 1;
  }
  return out;
}

Tracker::Tracker(const TrackerOptions& options) : options_(options) { options_.Check(); }

// A track's axis (world): along its velocity when it moves, else along the road (the vehicle's
// heading); objects beside the road are long along it and move along it.
Eigen::Vector2d Tracker::Axis(const Track& t, const Eigen::Matrix2d& world_from_vehicle) const {
  const Eigen::Vector2d v = t.x.segment<2>(2);
  return v.norm() >= options_.axis_min_speed_mps ? Eigen::Vector2d(v.normalized())
                                                 : Eigen::Vector2d(world_from_vehicle.col(1));
}

// The acceleration's covariance (world): accel_sigma_mps2 along the axis, across_accel_sigma_mps2
// across it.
Eigen::Matrix2d Tracker::AccelCovariance(const Track& t, const Eigen::Matrix2d& world_from_vehicle) const {
  const Eigen::Vector2d a = Axis(t, world_from_vehicle), n(-a.y(), a.x());
  return options_.accel_sigma_mps2 * options_.accel_sigma_mps2 * a * a.transpose() +
         options_.across_accel_sigma_mps2 * options_.across_accel_sigma_mps2 * n * n.transpose();
}

// White acceleration of covariance `accel` and white turn acceleration over dt.
Tracker::Cov Tracker::ProcessNoise(const Eigen::Matrix2d& accel, double dt) const {
  Cov Q = Cov::Zero();
  Q.topLeftCorner<2, 2>() = accel * (dt * dt * dt * dt / 4);
  Q.block<2, 2>(0, 2) = Q.block<2, 2>(2, 0) = accel * (dt * dt * dt / 2);
  Q.block<2, 2>(2, 2) = accel * (dt * dt);
  Q(4, 4) = options_.turn_accel_sigma_radps2 * options_.turn_accel_sigma_radps2 * dt * dt;
  return Q;
}

// The constant-turn motion over dt: the velocity turns by w dt (towards +x for w > 0), the
// position advances by the mean of the old and the new velocity. F receives the Jacobian.
Tracker::State Tracker::Predict(const State& x, double dt, Cov* F) {
  const double a = x(4) * dt, c = std::cos(a), s = std::sin(a);
  Eigen::Matrix2d rot, drot;
  rot << c, s, -s, c;
  drot << -s, c, -c, -s;
  const Eigen::Vector2d v = x.segment<2>(2), v1 = rot * v;
  State out = x;
  out.head<2>() += dt / 2 * (v + v1);
  out.segment<2>(2) = v1;
  if (F) {
    *F = Cov::Identity();
    F->block<2, 2>(0, 2) = dt / 2 * (Eigen::Matrix2d::Identity() + rot);
    F->block<2, 1>(0, 4) = dt * dt / 2 * drot * v;
    F->block<2, 2>(2, 2) = rot;
    F->block<2, 1>(2, 4) = dt * drot * v;
  }
  return out;
}

// Predict (constant turn, white acceleration noise, smaller across the track's axis).
void Tracker::PredictTracks(double dt, const Eigen::Matrix2d& Rwv) {
  const double switch_probability = 1.0 - std::exp(-options_.model_switch_per_s * dt);
  for (Track& t : tracks_) {
    Cov F;
    t.x = Predict(t.x, dt, &F);
    t.P = F * t.P * F.transpose() + ProcessNoise(AccelCovariance(t, Rwv), dt);
    // The standing model: the object may have started or stopped since, and its followed point
    // drifts a little.
    const double standing = StandingProbability(t);
    const double next = std::clamp(standing + switch_probability * (1 - 2 * standing), 1e-9, 1 - 1e-9);
    t.standing_log_odds = std::log(next / (1 - next));
    t.standing_P += Eigen::Matrix2d::Identity() * options_.standing_drift_sigma * options_.standing_drift_sigma * dt;
    ++t.age;
  }
}

// Measurements in the world. A track follows one point of its object: the measurement for a
// track is the detection's ground point nearest to the track's prediction (a new track starts at
// the detection's nearest point to the vehicle). The nearest point to the vehicle alone would
// slide along the object as other parts come into view (passing a parked car it moves with us).
// The followed point leaving the view is handled by the cut ends (FollowedPoint); what is left of
// the sliding is covered by an uncertainty of a fraction of the detection's extent.
Tracker::Measurements Tracker::InWorld(const std::vector<Detection>& detections, const PlanarPose& ego,
                                       const Eigen::Matrix2d& Rwv) const {
  Measurements m;
  m.points.resize(detections.size());
  m.clipped_ends.resize(detections.size());
  for (size_t j = 0; j < detections.size(); ++j) {
    const Detection& d = detections[j];
    m.z.push_back(BodyToWorld(ego, {d.x_m, d.z_m}));
    for (const Eigen::Vector2d& p : d.points) m.points[j].push_back(BodyToWorld(ego, p));
    for (const Eigen::Vector2d& p : d.clipped_ends) m.clipped_ends[j].push_back(BodyToWorld(ego, p));
    if (m.points[j].empty()) m.points[j].push_back(m.z.back());
    const double s = options_.meas_sigma_m + options_.meas_sigma_per_m * d.range_m;
    Eigen::Matrix2d r = Eigen::Matrix2d::Identity() * s * s;
    if (options_.extent_sigma_fraction > 0 && std::isfinite(d.x_max_m - d.x_min_m) && std::isfinite(d.z_max_m - d.z_min_m)) {
      const double ex = options_.extent_sigma_fraction * (d.x_max_m - d.x_min_m);
      const double ez = options_.extent_sigma_fraction * (d.z_max_m - d.z_min_m);
      r(0, 0) += ex * ex;
      r(1, 1) += ez * ez;
    }
    m.R.push_back(Rwv * r * Rwv.transpose());
  }
  return m;
}

// The followed point: the detection's point nearest to the prediction, averaged with its
// neighbours within local_radius_m (single points are noisy, and picking the one nearest to the
// prediction alone would favour the prediction). When that point is an end where the view cut
// the object (Detection::clipped_ends), the followed point may lie beyond it unseen: only the
// offset across the track's axis is measured, and only up to max_hidden_m along it.
Tracker::Measured Tracker::FollowedPoint(const Measurements& m, size_t j, const Eigen::Vector2d& p) const {
  const std::vector<Eigen::Vector2d>& points = m.points[j];
  Eigen::Vector2d best = points.front();
  for (const Eigen::Vector2d& q : points) {
    if ((q - p).squaredNorm() < (best - p).squaredNorm()) best = q;
  }
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  int n = 0;
  for (const Eigen::Vector2d& q : points) {
    if ((q - best).norm() <= options_.local_radius_m) {
      sum += q;
      ++n;
    }
  }
  Measured out{sum / n, false};
  for (const Eigen::Vector2d& e : m.clipped_ends[j]) out.clipped = out.clipped || (e - best).norm() <= options_.clip_radius_m;
  return out;
}

// Gated Mahalanobis costs and the optimal assignment.
Tracker::Association Tracker::Associate(const Measurements& m, const Eigen::Matrix2d& Rwv) const {
  const double forbidden = 1e12;
  const size_t n = m.z.size();
  std::vector<std::vector<double>> cost(tracks_.size(), std::vector<double>(n, forbidden));
  Association a;
  a.measured.assign(tracks_.size(), std::vector<Measured>(n));
  a.across.resize(tracks_.size());
  for (size_t i = 0; i < tracks_.size(); ++i) {
    const Eigen::Vector2d axis = Axis(tracks_[i], Rwv);
    a.across[i] = Eigen::Vector2d(-axis.y(), axis.x());
    for (size_t j = 0; j < n; ++j) {
      a.measured[i][j] = FollowedPoint(m, j, tracks_[i].x.head<2>());
      const Eigen::Vector2d innovation = a.measured[i][j].point - tracks_[i].x.head<2>();
      const Eigen::Matrix2d S = tracks_[i].P.topLeftCorner<2, 2>() + m.R[j];
      double d2;
      if (a.measured[i][j].clipped) {
        if (std::abs(innovation.dot(axis)) > options_.max_hidden_m) continue;
        const double e = innovation.dot(a.across[i]);
        d2 = e * e / a.across[i].dot(S * a.across[i]);
      } else {
        d2 = innovation.dot(S.ldlt().solve(innovation));
      }
      if (d2 <= options_.gate_chi2) cost[i][j] = d2;
    }
  }
  a.assigned = HungarianAssignment(cost, forbidden);
  return a;
}

namespace {

// The object's size from its hits' extents (each an axis-aligned box in its frame's vehicle axes):
// the 80th percentile of their extents along `axis` (unit, world) and across it.
Eigen::Vector2d SizeOf(const std::vector<std::pair<Eigen::Vector2d, Eigen::Matrix2d>>& extents,
                       const Eigen::Vector2d& axis) {
  if (extents.empty()) return {0, 0};
  std::vector<double> along, across;
  for (const auto& [box, Rwv] : extents) {
    const Eigen::Vector2d a = (Rwv.transpose() * axis).cwiseAbs();  // the axis in that frame
    along.push_back(box.x() * a.x() + box.y() * a.y());
    across.push_back(box.x() * a.y() + box.y() * a.x());
  }
  const size_t at = static_cast<size_t>(0.8 * (along.size() - 1) + 0.5);
  std::nth_element(along.begin(), along.begin() + at, along.end());
  std::nth_element(across.begin(), across.begin() + at, across.end());
  return {along[at], across[at]};
}

// Keeps a hit's extent (x, z sizes in the vehicle frame) with that frame's world_from_vehicle.
void AddExtent(const Detection& d, const Eigen::Matrix2d& Rwv,
               std::vector<std::pair<Eigen::Vector2d, Eigen::Matrix2d>>* extents) {
  constexpr size_t kKept = 30;
  extents->emplace_back(Eigen::Vector2d(d.x_max_m - d.x_min_m, d.z_max_m - d.z_min_m), Rwv);
  if (extents->size() > kKept) extents->erase(extents->begin());
}

// Keeps a hit's measured height (the last 30 measured).
void AddHeight(const Detection& d, std::vector<double>* heights) {
  constexpr size_t kKept = 30;
  if (std::isnan(d.height_m)) return;
  heights->push_back(d.height_m);
  if (heights->size() > kKept) heights->erase(heights->begin());
}

double HeightOf(std::vector<double> heights) {
  if (heights.empty()) return std::numeric_limits<double>::quiet_NaN();
  const size_t at = static_cast<size_t>(0.8 * (heights.size() - 1) + 0.5);
  std::nth_element(heights.begin(), heights.begin() + at, heights.end());
  return heights[at];
}

}  // namespace

// Updates the tracks with their detections (the others count a miss) and drops the lost ones;
// returns which detections were used.
std::vector<bool> Tracker::UpdateTracks(double t_s, const std::vector<Detection>& detections, const Measurements& ms,
                                        const Association& a, const Eigen::Matrix2d& Rwv) {
  std::vector<bool> used(ms.z.size(), false);
  for (size_t i = 0; i < tracks_.size(); ++i) {
    Track& t = tracks_[i];
    const int j = i < a.assigned.size() ? a.assigned[i] : -1;
    if (j < 0) {
      ++t.misses;
      continue;
    }
    used[j] = true;
    const Measured& m = a.measured[i][j];
    const Eigen::Vector2d& across = a.across[i];
    if (m.clipped) {
      // Only the offset across the axis: H = [n^T 0], one scalar measurement.
      Eigen::Matrix<double, 1, 5> H;
      H << across.x(), across.y(), 0, 0, 0;
      ScalarUpdate(H, across.dot(m.point - t.x.head<2>()), across.dot(ms.R[j] * across),
                   std::numeric_limits<double>::infinity(), &t);
    } else {
      // Update (H = [I 0]); gated already by the assignment.
      Eigen::Matrix<double, 2, 5> H = Eigen::Matrix<double, 2, 5>::Zero();
      H.leftCols<2>().setIdentity();
      Update<2>(H, m.point - t.x.head<2>(), ms.R[j], std::numeric_limits<double>::infinity(), &t);
    }
    ApplyMotion(detections[j], Rwv, options_.motion_gate_chi2, &t);
    ApplyRegistration(t_s, ms.points[j], !ms.clipped_ends[j].empty(), Rwv, &t);
    AddExtent(detections[j], Rwv, &t.extents);
    AddHeight(detections[j], &t.heights);
    ++t.hits;
    t.misses = 0;
    if (t.hits >= options_.confirm_hits) t.confirmed = true;
  }
  tracks_.erase(std::remove_if(tracks_.begin(), tracks_.end(),
                               [&](const Track& t) { return t.misses > options_.max_misses || (!t.confirmed && t.misses > 0); }),
                tracks_.end());
  return used;
}


// A new track for each detection no track took.
void Tracker::StartTracks(double t_s, const std::vector<Detection>& detections, const Measurements& m,
                          const std::vector<bool>& used, const Eigen::Matrix2d& Rwv) {
  for (size_t j = 0; j < m.z.size(); ++j) {
    if (used[j]) continue;
    Track t;
    t.id = next_id_++;
    t.x << m.z[j], 0, 0, 0;
    t.P = Cov::Zero();
    t.P.topLeftCorner<2, 2>() = m.R[j];
    t.standing = m.z[j];
    t.standing_P = m.R[j];
    const Eigen::Vector2d sigma_v(options_.init_across_speed_sigma_mps, options_.init_speed_sigma_mps);
    t.P.block<2, 2>(2, 2) = Rwv * sigma_v.cwiseAbs2().asDiagonal() * Rwv.transpose();
    t.P(4, 4) = options_.init_turn_sigma_radps * options_.init_turn_sigma_radps;
    ApplyMotion(detections[j], Rwv, std::numeric_limits<double>::infinity(), &t);
    ApplyRegistration(t_s, m.points[j], !m.clipped_ends[j].empty(), Rwv, &t);
    AddExtent(detections[j], Rwv, &t.extents);
    AddHeight(detections[j], &t.heights);
    t.hits = 1;
    t.confirmed = options_.confirm_hits <= 1;
    tracks_.push_back(t);
  }
}

// The tracks in the current vehicle frame.
std::vector<TrackState> Tracker::Report(int frame, double t_s, const PlanarPose& ego, const Eigen::Matrix2d& Rwv) const {
  std::vector<TrackState> out;
  const Eigen::Matrix2d Rv = Rwv.transpose();
  for (const Track& t : tracks_) {
    TrackState s;
    s.frame = frame;
    s.t_s = t_s;
    s.id = t.id;
    // The velocity reported is the models' mixture: the moving model's, times its probability.
    State x = t.x;
    if (options_.model_switch_per_s > 0) x.segment<2>(2) *= 1.0 - StandingProbability(t);
    const Eigen::Vector2d p = WorldToBody(ego, x.head<2>()), v = WorldToBodyDirection(ego, x.segment<2>(2));
    const Eigen::Matrix2d cov = Rv * t.P.topLeftCorner<2, 2>() * Rv.transpose();
    s.x_m = p.x();
    s.z_m = p.y();
    s.vx_mps = v.x();
    s.vz_mps = v.y();
    s.sigma_x_m = std::sqrt(std::max(0.0, cov(0, 0)));
    s.sigma_z_m = std::sqrt(std::max(0.0, cov(1, 1)));
    s.age = t.age;
    const Eigen::Vector2d size = SizeOf(t.extents, Axis(t, Rwv));
    s.length_m = size.x();
    s.width_m = size.y();
    s.height_m = HeightOf(t.heights);
    s.confirmed = t.confirmed;
    // Prediction ahead, in the current vehicle frame (the ego's own motion is not predicted).
    const double h = options_.predict_ahead_s;
    Cov Fh;
    const State xh = Predict(x, h, &Fh);
    const Cov Ph = Fh * t.P * Fh.transpose() + ProcessNoise(AccelCovariance(t, Rwv), h);
    s.predicted = WorldToBody(ego, xh.head<2>());
    s.predicted_cov = Rv * Ph.topLeftCorner<2, 2>() * Rv.transpose();
    out.push_back(s);
  }
  return out;
}

std::vector<TrackState> Tracker::Update(int frame, double t_s, const PlanarPose& ego,
                                        const std::vector<Detection>& detections) {
  const double dt = started_ ? std::max(0.0, t_s - last_t_) : 0.0;
  started_ = true;
  last_t_ = t_s;
  const Eigen::Matrix2d Rwv = BodyToWorldRotation(ego);
  PredictTracks(dt, Rwv);
  const Measurements m = InWorld(detections, ego, Rwv);
  const Association a = Associate(m, Rwv);
  const std::vector<bool> used = UpdateTracks(t_s, detections, m, a, Rwv);
  StartTracks(t_s, detections, m, used, Rwv);
  return Report(frame, t_s, ego, Rwv);
}

}  // namespace dps
