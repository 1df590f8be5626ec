// Tests of the tracker: the Hungarian assignment on known answers, and tracks of synthetic
// detections with known motion while the ego vehicle drives and turns: a parked object has zero
// ground velocity, a moving one its true velocity, one id each, gating keeps two objects apart;
// the standing model holds a noisy standing object still and lets a moving one move.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>

#include "check.h"
#include "dps/detect/detection.h"
#include "dps/map/tracker.h"
#include "dps/map/tracks_io.h"
#include "dps/util/error.h"

namespace {

constexpr double kVelocityTolMps = 0.3;

void TestHungarian() {
  // The greedy choice (row 0 -> col 0, cost 1) is not optimal: 0 -> 1, 1 -> 0 costs 2 + 2 = 4 < 1 + 9.
  std::vector<int> a = dps::HungarianAssignment({{1, 2}, {2, 9}}, 1e9);
  CHECK_EQ(a[0], 1);
  CHECK_EQ(a[1], 0);
  // Rectangular, with forbidden pairs.
  a = dps::HungarianAssignment({{5, 1e9, 3}, {1e9, 1e9, 1e9}}, 1e9);
  CHECK_EQ(a[0], 2);
  CHECK_EQ(a[1], -1);
  a = dps::HungarianAssignment({{4}, {1}, {3}}, 1e9);
  CHECK_EQ(a[0], -1);
  CHECK_EQ(a[1], 0);
  CHECK_EQ(a[2], -1);
  CHECK(dps::HungarianAssignment({}, 1e9).empty());
  dps::TrackerOptions bad;
  bad.confirm_hits = 0;
  CHECK_THROWS_WITH(dps::Tracker{bad}, dps::Error, "confirm_hits");
}

// The ego drives at 8 m/s turning at 0.1 rad/s; object A is parked at world (3, 20), object B
// drives along world z at 12 m/s from (-3, 5). Detections are their positions in the current
// vehicle frame with 0.15 m noise.
void TestTracks() {
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.15);
  dps::Tracker tracker;
  dps::PlanarPose ego;
  const double dt = 1.0 / 15;
  std::vector<int> ids_a, ids_b;
  std::vector<double> err_a, err_b;
  for (int f = 0; f < 60; ++f) {
    const double t = f * dt;
    if (f > 0) ego = dps::Compose(ego, dps::MotionProfile({{0, 8.0, 0.1}}).Integrate({}, 0, dt));
    const Eigen::Vector2d a_world(3, 20), b_world(-3, 5 + 12 * t);
    std::vector<dps::Detection> dets;
    for (const Eigen::Vector2d& w : {a_world, b_world}) {
      const Eigen::Vector2d v = dps::WorldToBody(ego, w);
      dps::Detection d = dps::DetectionFromPoints({{v.x() + noise(rng), v.y() + noise(rng)}}, "front");
      d.frame = f;
      dets.push_back(d);
    }
    const std::vector<dps::TrackState> tracks = tracker.Update(f, t, ego, dets);
    if (f < 20) continue;  // converged by then
    const Eigen::Vector2d a_now = dps::WorldToBody(ego, a_world), b_now = dps::WorldToBody(ego, b_world);
    const Eigen::Vector2d b_velocity = dps::WorldToBodyDirection(ego, {0, 12});
    for (const dps::TrackState& s : tracks) {
      if (!s.confirmed) continue;
      if ((Eigen::Vector2d(s.x_m, s.z_m) - a_now).norm() < 1.0) {
        ids_a.push_back(s.id);
        err_a.push_back(std::hypot(s.vx_mps, s.vz_mps));  // parked: zero ground velocity
      } else if ((Eigen::Vector2d(s.x_m, s.z_m) - b_now).norm() < 1.0) {
        ids_b.push_back(s.id);
        err_b.push_back((Eigen::Vector2d(s.vx_mps, s.vz_mps) - b_velocity).norm());
        // The prediction 1 s ahead lands near where B will be (in the current vehicle frame).
        CHECK((s.predicted - dps::WorldToBody(ego, b_world + Eigen::Vector2d(0, 12))).norm() < 1.0);
      }
    }
  }
  CHECK_EQ(ids_a.size(), size_t{40});
  CHECK_EQ(ids_b.size(), size_t{40});
  CHECK(std::all_of(ids_a.begin(), ids_a.end(), [&](int i) { return i == ids_a[0]; }));
  CHECK(std::all_of(ids_b.begin(), ids_b.end(), [&](int i) { return i == ids_b[0]; }));
  std::sort(err_a.begin(), err_a.end());
  std::sort(err_b.begin(), err_b.end());
  std::printf("tracks: parked object median |v| %.3f m/s, moving object median velocity error %.3f m/s\n",
              err_a[err_a.size() / 2], err_b[err_b.size() / 2]);
  CHECK(err_a[err_a.size() / 2] < kVelocityTolMps);
  CHECK(err_b[err_b.size() / 2] < kVelocityTolMps);
  // No detections: tracks die after max_misses frames.
  std::vector<dps::TrackState> left;
  for (int f = 60; f < 70; ++f) left = tracker.Update(f, f * dt, ego, {});
  CHECK(left.empty());
}

// Track sizes: a car crossing ahead (heading +X at 6 m/s, 4.5 m x 1.8 m) and a parked one (along
// +Z), each detected as the outline of its footprint: length along the track's axis, width across
// it; written to tracks.csv and read back.
void TestTrackSize() {
  dps::Tracker tracker;
  const dps::PlanarPose ego;
  const double dt = 1.0 / 15;
  std::vector<dps::TrackState> last;
  for (int f = 0; f < 40; ++f) {
    const double t = f * dt;
    auto outline = [](double cx, double cz, double half_x, double half_z) {
      std::vector<Eigen::Vector2d> p;
      for (double u = -1; u <= 1.0001; u += 0.1) {
        p.emplace_back(cx + u * half_x, cz - half_z);
        p.emplace_back(cx + u * half_x, cz + half_z);
        p.emplace_back(cx - half_x, cz + u * half_z);
        p.emplace_back(cx + half_x, cz + u * half_z);
      }
      return p;
    };
    dps::Detection crossing = dps::DetectionFromPoints(outline(-10 + 6 * t, 15, 2.25, 0.9), "front");
    dps::Detection parked = dps::DetectionFromPoints(outline(4, 8, 0.9, 2.25), "front");
    crossing.frame = parked.frame = f;
    last = tracker.Update(f, t, ego, {crossing, parked});
  }
  CHECK_EQ(last.size(), size_t{2});
  for (const dps::TrackState& s : last) {
    std::printf("track at (%.1f, %.1f): length %.2f m, width %.2f m\n", s.x_m, s.z_m, s.length_m, s.width_m);
    CHECK_NEAR(s.length_m, 4.5, 0.05);
    CHECK_NEAR(s.width_m, 1.8, 0.05);
  }
  const std::string path = (std::filesystem::temp_directory_path() / "dps_test_tracker_sizes.csv").string();
  dps::WriteTracks(last, path);
  const std::vector<dps::TrackState> back = dps::ReadTracks(path);
  CHECK_EQ(back.size(), size_t{2});
  for (size_t i = 0; i < back.size() && i < last.size(); ++i) {
    CHECK_NEAR(back[i].length_m, last[i].length_m, 1e-6);
    CHECK_NEAR(back[i].width_m, last[i].width_m, 1e-6);
  }
  std::filesystem::remove(path);
}

}  // namespace

// Passing a parked car at 8 m/s: the side view sees the stretch of its side within 1.5 m of the
// camera's z, so the visible stretch moves with us while the car stands still. Motion stereo's
// velocity along the displacement (0 for a parked car) keeps the track still.
double ParkedPassSpeed(double extent_sigma_fraction, bool motion_stereo_velocity = false) {
  dps::TrackerOptions o;
  o.extent_sigma_fraction = extent_sigma_fraction;
  dps::Tracker tracker(o);
  const double dt = 1.0 / 15, speed = 8.0;
  const double car_z0 = 2.0, car_z1 = 6.5, side_x = 2.5;  // world, the car's side facing us
  std::vector<double> speeds;
  for (int f = 0; f < 8; ++f) {
    const double t = f * dt;
    const dps::PlanarPose ego{0.0, speed * t, 0.0};
    // The car's visible stretch in the vehicle frame: z in [-1.5, 1.5] of the camera at z 0.9;
    // before the car comes alongside, its rear end faces the front view.
    const double lo = std::max(car_z0 - ego.z_m, 0.9 - 1.5), hi = std::min(car_z1 - ego.z_m, 0.9 + 1.5);
    std::vector<dps::Detection> dets;
    if (lo < hi) {
      const double near_z = std::clamp(0.0, lo, hi);
      std::vector<Eigen::Vector2d> points;
      for (double z = lo; z <= hi + 1e-9; z += 0.1) points.emplace_back(side_x, z);
      points.emplace_back(side_x, near_z);
      dps::Detection d = dps::DetectionFromPoints(points, "right");
      if (motion_stereo_velocity) {  // side_detection.h: 0 m/s along the displacement, +- 0.2
        d.has_motion = true;
        d.motion_direction = Eigen::Vector2d(0, 1);
        d.motion_mps = 0.0;
        d.motion_sigma_mps = 0.2;
      }
      dets.push_back(d);
    }
    for (const dps::TrackState& s : tracker.Update(f, t, ego, dets)) {
      if (s.confirmed) speeds.push_back(std::hypot(s.vx_mps, s.vz_mps));
    }
  }
  if (speeds.empty()) return 1e9;
  std::sort(speeds.begin(), speeds.end());
  return speeds[speeds.size() / 2];
}

void TestSlidingNearPoint() {
  const double speed_mps = 8.0;  // ParkedPassSpeed's ego speed
  const double with_extent = ParkedPassSpeed(dps::TrackerOptions().extent_sigma_fraction);
  const double point_only = ParkedPassSpeed(0.0);
  std::printf("parked car passed at 8 m/s: median track speed %.3f m/s (extent in the noise), %.3f m/s (point only)\n",
              with_extent, point_only);
  // Without a velocity measurement the sliding still pulls the track (docs/tracking.md): once the
  // followed point leaves the view, the nearest visible point moves with us.
  CHECK(with_extent < speed_mps && point_only < speed_mps);
  // With motion stereo's velocity along the displacement the track holds still.
  const double with_motion = ParkedPassSpeed(dps::TrackerOptions().extent_sigma_fraction, true);
  std::printf("  with the motion-stereo velocity: %.3f m/s\n", with_motion);
  CHECK(with_motion <= kVelocityTolMps);
}

// Driving at 8 m/s beside a parked truck longer than the side view's window: the window
// (z in [-0.6, 2.4] of the vehicle) shows a stretch of its side cut at both ends. Median track
// speed with the window's edges marked as cut (Detection::clipped_ends, as the detectors do) and
// without; no motion-stereo velocity.
double LongObjectBesideSpeed(bool mark_clipped) {
  dps::Tracker tracker;
  const double dt = 1.0 / 15, speed = 8.0, side_x = 2.5, lo = -0.6, hi = 2.4;
  const double truck_z0 = -6.0, truck_z1 = 12.0;  // world
  std::vector<double> speeds;
  for (int f = 0; f < 15; ++f) {
    const double t = f * dt;
    const dps::PlanarPose ego{0.0, speed * t, 0.0};
    CHECK(truck_z0 - ego.z_m < lo && truck_z1 - ego.z_m > hi);  // both ends out of view
    std::vector<Eigen::Vector2d> points;
    for (double z = lo; z <= hi + 1e-9; z += 0.1) points.emplace_back(side_x, z);
    dps::Detection d = dps::DetectionFromPoints(points, "right");
    if (mark_clipped) d.clipped_ends = {points.front(), points.back()};
    for (const dps::TrackState& s : tracker.Update(f, t, ego, {d})) {
      if (s.confirmed) speeds.push_back(std::hypot(s.vx_mps, s.vz_mps));
    }
  }
  if (speeds.empty()) return 1e9;
  std::sort(speeds.begin(), speeds.end());
  return speeds[speeds.size() / 2];
}

void TestClippedEnds() {
  const double marked = LongObjectBesideSpeed(true), unmarked = LongObjectBesideSpeed(false);
  std::printf("parked truck longer than the window, passed at 8 m/s: median track speed %.3f m/s (edges marked), "
              "%.3f m/s (not marked)\n", marked, unmarked);
  // Marked, the followed point may go out of view: only the offset across the axis is measured.
  CHECK(marked <= kVelocityTolMps);
  // Unmarked, the window's edge is taken for the object's and the track slides with us.
  CHECK(unmarked > 1.0);
}

// A car 12 m ahead drives a constant turn (7 m/s, 15 deg/s) while the ego drives
// straight: its velocity turns by 1 degree per frame. Median velocity error after convergence
// with the constant-turn model, and with the turn rate held at 0 (constant velocity).
double TurningVelocityError(bool constant_turn) {
  dps::TrackerOptions o;
  if (!constant_turn) o.turn_accel_sigma_radps2 = o.init_turn_sigma_radps = 0.0;
  dps::Tracker tracker(o);
  std::mt19937 rng(9);
  std::normal_distribution<double> noise(0.0, 0.1);
  const double dt = 1.0 / 15, speed = 7.0, rate = 15 * 3.14159265358979 / 180;
  std::vector<double> errors;
  for (int f = 0; f < 60; ++f) {
    const double t = f * dt;
    const dps::PlanarPose ego{0.0, 7.0 * t, 0.0};
    // The car's path: heading rate * t (towards +x), from (0, 12).
    const double h = rate * t;
    const Eigen::Vector2d car(speed / rate * (1 - std::cos(h)), 12 + speed / rate * std::sin(h));
    const Eigen::Vector2d velocity(speed * std::sin(h), speed * std::cos(h));
    const Eigen::Vector2d v = dps::WorldToBody(ego, car);
    dps::Detection d = dps::DetectionFromPoints({{v.x() + noise(rng), v.y() + noise(rng)}}, "front");
    d.frame = f;
    for (const dps::TrackState& s : tracker.Update(f, t, ego, {d})) {
      if (s.confirmed && f >= 30) errors.push_back((Eigen::Vector2d(s.vx_mps, s.vz_mps) - velocity).norm());
    }
  }
  if (errors.size() < 30) return 1e9;
  std::sort(errors.begin(), errors.end());
  return errors[errors.size() / 2];
}

void TestTurning() {
  const double ct = TurningVelocityError(true), cv = TurningVelocityError(false);
  std::printf("car turning at 15 deg/s: median velocity error %.3f m/s (constant turn), %.3f m/s (constant velocity)\n",
              ct, cv);
  CHECK(ct <= kVelocityTolMps);
  CHECK(ct < cv);
}

// Registration (iterative closest points) on point sets with known shifts.
void TestRegisterPoints() {
  // A car's outline seen from behind-left: its back (1.8 m) and its left side (4.5 m), every 0.1 m.
  std::vector<Eigen::Vector2d> outline;
  for (int i = 0; i <= 18; ++i) outline.emplace_back(-0.9 + 0.1 * i, 10.0);
  for (int i = 1; i <= 45; ++i) outline.emplace_back(-0.9, 10.0 + 0.1 * i);
  const Eigen::Vector2d truth(0.23, 0.61);
  std::vector<Eigen::Vector2d> moved;
  for (const Eigen::Vector2d& p : outline) moved.push_back(p + truth);
  Eigen::Vector2d shift;
  double rms = -1;
  // From a start within half the spacing of the truth: exact.
  CHECK(dps::RegisterPoints(outline, moved, truth + Eigen::Vector2d(0.03, -0.04), 0.75, 0.6, &shift, &rms));
  CHECK_NEAR((shift - truth).norm(), 0.0, 1e-9);
  CHECK_NEAR(rms, 0.0, 1e-9);
  // Nothing within the gate: no registration.
  CHECK(!dps::RegisterPoints(outline, moved, Eigen::Vector2d(5, 5), 0.75, 0.6, &shift, &rms));
  // Only the back seen the second time: 19 of 64 points pair (30 %).
  const std::vector<Eigen::Vector2d> back(moved.begin(), moved.begin() + 19);
  CHECK(!dps::RegisterPoints(outline, back, truth, 0.05, 0.6, &shift, &rms));
  CHECK(dps::RegisterPoints(outline, back, truth, 0.05, 0.25, &shift, &rms));
  CHECK_NEAR((shift - truth).norm(), 0.0, 1e-9);
}

// A car 10 m ahead drives at 5 m/s in our lane while the ego stands; it is seen as a row of
// points across its back (x in [0.6, 2.4]) whose left end is hidden more every frame (0.03 m, as
// if something nearer crept across it). The track is born at the nearest point, the left end, and
// that end slides right at 0.45 m/s: with the followed point alone the track takes the slide for
// the car's motion (and overshoots it); the registered shape, whose right end stays, holds it back
// — not to zero: registration pairs the hidden points with the new left end, which pulls the shift
// by about half the hidden stretch.
double CreepingEdgeAcrossSpeed(double registration_span_s) {
  dps::TrackerOptions o;
  o.registration_span_s = registration_span_s;
  dps::Tracker tracker(o);
  std::mt19937 rng(4);
  std::normal_distribution<double> noise(0.0, 0.03);
  const double dt = 1.0 / 15;
  std::vector<double> across;
  for (int f = 0; f < 45; ++f) {
    const double t = f * dt, z = 10.0 + 5.0 * t, left = 0.6 + 0.03 * f;
    std::vector<Eigen::Vector2d> points;
    for (double x = 0.6; x <= 2.4 + 1e-9; x += 0.1) {
      if (x >= left) points.emplace_back(x + noise(rng), z + noise(rng));
    }
    const dps::Detection d = dps::DetectionFromPoints(points, "front");
    for (const dps::TrackState& s : tracker.Update(f, t, dps::PlanarPose{0.0, 0.0, 0.0}, {d})) {
      if (s.confirmed && f >= 15) across.push_back(std::abs(s.vx_mps));
    }
  }
  if (across.empty()) return 1e9;
  std::sort(across.begin(), across.end());
  return across[across.size() / 2];
}

void TestCreepingEdge() {
  const double with = CreepingEdgeAcrossSpeed(dps::TrackerOptions().registration_span_s);
  const double without = CreepingEdgeAcrossSpeed(0.0);
  std::printf("car ahead whose left end is hidden at 0.45 m/s: median |vx| %.3f m/s (registration), %.3f m/s "
              "(followed point only)\n", with, without);
  CHECK(with < 0.45);
}

// An object ahead seen with noisy positions (0.6 m per axis, as a far car's nearest point
// jumps) while we drive at 8 m/s: standing still until start_s, then driving off along the road
// at 6 m/s. Returns the median error of the reported velocity over frames [from, to).
double NoisyObjectVelocityError(double model_switch_per_s, double start_s, int from, int to) {
  dps::TrackerOptions o;
  o.model_switch_per_s = model_switch_per_s;
  dps::Tracker tracker(o);
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.6);
  const double dt = 1.0 / 15, ego_speed = 8.0, speed = 6.0;
  std::vector<double> errors;
  for (int f = 0; f < to; ++f) {
    const double t = f * dt;
    const dps::PlanarPose ego{0.0, ego_speed * t, 0.0};
    const double moved = std::max(0.0, t - start_s) * speed;
    const Eigen::Vector2d world(1.5, 40.0 + moved), velocity(0.0, t >= start_s ? speed : 0.0);
    const Eigen::Vector2d v = dps::WorldToBody(ego, world);
    dps::Detection d = dps::DetectionFromPoints({{v.x() + noise(rng), v.y() + noise(rng)}}, "front");
    d.frame = f;
    for (const dps::TrackState& s : tracker.Update(f, t, ego, {d})) {
      if (s.confirmed && f >= from) errors.push_back((Eigen::Vector2d(s.vx_mps, s.vz_mps) - velocity).norm());
    }
  }
  if (errors.empty()) return 1e9;
  std::sort(errors.begin(), errors.end());
  return errors[errors.size() / 2];
}

void TestStandingModel() {
  const double on = dps::TrackerOptions().model_switch_per_s;
  // Standing all along: the standing model holds the velocity near zero.
  const double standing = NoisyObjectVelocityError(on, 1e9, 10, 60);
  const double standing_moving_only = NoisyObjectVelocityError(0.0, 1e9, 10, 60);
  std::printf("standing object, noisy positions: median velocity error %.3f m/s (standing model), %.3f m/s "
              "(moving model only)\n", standing, standing_moving_only);
  CHECK(standing < 0.15 && standing < 0.5 * standing_moving_only);
  // Driving all along: the same as with the moving model alone.
  const double driving = NoisyObjectVelocityError(on, 0.0, 10, 60);
  const double driving_moving_only = NoisyObjectVelocityError(0.0, 0.0, 10, 60);
  std::printf("driving object: %.3f m/s (standing model), %.3f m/s (moving model only)\n", driving,
              driving_moving_only);
  CHECK(driving < driving_moving_only + 0.05);
  // Driving off after 2 s: within a second the velocity is the moving one again.
  const double started = NoisyObjectVelocityError(on, 2.0, 45, 75);
  const double started_moving_only = NoisyObjectVelocityError(0.0, 2.0, 45, 75);
  std::printf("driving off after 2 s, from 1 s after: %.3f m/s (standing model), %.3f m/s (moving model only)\n",
              started, started_moving_only);
  CHECK(started < started_moving_only + 0.2);
}

int main() {
  TestHungarian();
  TestTracks();
  TestSlidingNearPoint();
  TestClippedEnds();
  TestTurning();
  TestRegisterPoints();
  TestCreepingEdge();
  TestStandingModel();
  TestTrackSize();
  return dps_test::Report();
}
