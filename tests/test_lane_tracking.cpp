// Lane tracking: measured boundaries (the road's lines seen from the car's true poses, with noise)
// fed to the tracker with the car's motion, and the tracked lanes compared with the truth: on a
// straight drive through a 1.3 s gap in the measurements, standing beside a gap, through a lane
// change whose middle is not measured, with a stray line measured once and with a line measured far
// ahead with a wrong heading.
#include <cmath>
#include <cstdio>
#include <random>

#include "check.h"
#include "dps/camera/ego_motion.h"
#include "dps/detect/lane_tracking.h"
#include "dps/util/error.h"

namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;
constexpr double kFps = 15.0;

// The road's lines x = line_x (world) seen from `ego`: offset where each crosses the vehicle's X
// axis and heading, from two of its points carried into the vehicle frame.
dps::LaneBoundaryRow Seen(const dps::PlanarPose& ego, double line_x, const char* name) {
  const Eigen::Vector2d a = dps::WorldToBody(ego, {line_x, ego.z_m}), b = dps::WorldToBody(ego, {line_x, ego.z_m + 10.0});
  const double slope = (b.x() - a.x()) / (b.y() - a.y());
  dps::LaneBoundaryRow r;
  r.boundary = name;
  r.offset_m = a.x() - slope * a.y();
  r.heading_deg = std::atan(slope) / kDeg;
  r.type = "dashed";
  return r;
}

double OffsetOf(const dps::LaneFrame& f, const char* name, bool* found) {
  for (const dps::LaneBoundaryRow& b : f.boundaries) {
    if (b.boundary == name) {
      *found = true;
      return b.offset_m;
    }
  }
  *found = false;
  return 0.0;
}

struct Run {
  double worst_error_m = 0.0;  // of the ego boundaries over the frames with both
  int frames_without = 0;      // frames where an ego boundary was missing
  int left_changes = 0, right_changes = 0;
};

// Drives `profile` for `seconds`, measuring the lines at world x = -5.25, -1.75, 1.75, 5.25 with
// noise, except in frames where `measured(frame)` is false; compares the tracked ego boundaries
// with the truth from frame `from` on.
template <typename Measured>
Run Drive(const dps::MotionProfile& profile, double seconds, Measured measured, int from = 2) {
  dps::LaneTracker tracker;
  std::mt19937 rng(7);
  std::normal_distribution<double> offset_noise(0.0, 0.03), heading_noise(0.0, 0.5);
  Run run;
  dps::PlanarPose ego;
  for (int f = 0; f <= static_cast<int>(seconds * kFps); ++f) {
    const double t = f / kFps;
    dps::PlanarPose motion;
    if (f > 0) {
      motion = profile.Integrate({}, (f - 1) / kFps, t);
      ego = dps::Compose(ego, motion);
    }
    // The truth: the nearest lines either side.
    dps::LaneFrame truth;
    for (const double x : {-5.25, -1.75, 1.75, 5.25}) truth.boundaries.push_back(Seen(ego, x, "line"));
    dps::LaneFrame m;
    if (measured(f)) {
      for (dps::LaneBoundaryRow b : truth.boundaries) {
        b.offset_m += offset_noise(rng);
        b.heading_deg += heading_noise(rng);
        m.boundaries.push_back(b);
      }
    }
    const dps::LaneFrame out = tracker.Update(m, f > 0 ? &motion : nullptr, t);
    if (out.has_ego && out.ego.event == "left") ++run.left_changes;
    if (out.has_ego && out.ego.event == "right") ++run.right_changes;
    if (f < from) continue;
    double true_left = -1e9, true_right = 1e9;
    for (const dps::LaneBoundaryRow& b : truth.boundaries) {
      if (b.offset_m < 0) true_left = std::max(true_left, b.offset_m);
      if (b.offset_m > 0) true_right = std::min(true_right, b.offset_m);
    }
    bool has_left = false, has_right = false;
    const double left = OffsetOf(out, "left", &has_left), right = OffsetOf(out, "right", &has_right);
    if (!has_left || !has_right) {
      ++run.frames_without;
      continue;
    }
    run.worst_error_m = std::max({run.worst_error_m, std::abs(left - true_left), std::abs(right - true_right)});
  }
  return run;
}

void TestGap() {
  // 10 m/s straight, 0.4 m right of the lane's centre after a slight drift; no measurement in
  // frames 30-49 (1.33 s).
  const dps::MotionProfile drift({{0.0, 10.0, 0.0}, {1.0, 10.0, 0.0}, {1.001, 10.0, -0.02}, {1.5, 10.0, -0.02},
                                  {1.501, 10.0, 0.02}, {2.0, 10.0, 0.02}, {2.001, 10.0, 0.0}});
  const Run r = Drive(drift, 5.0, [](int f) { return f < 30 || f >= 50; });
  std::printf("gap of 1.33 s: worst ego boundary error %.3f m, %d frames without both\n", r.worst_error_m,
              r.frames_without);
  CHECK(r.frames_without == 0);
  CHECK(r.worst_error_m < 0.1);
  CHECK_EQ(r.left_changes + r.right_changes, 0);
  // A gap longer than max_coast_s: the lines are dropped, then found again.
  const Run long_gap = Drive(drift, 5.0, [](int f) { return f < 15 || f >= 45; });
  CHECK(long_gap.frames_without >= 5);
  CHECK(long_gap.frames_without <= 10);
}

void TestStanding() {
  // Braking from 8 m/s to a stop beside a gap in the dashes, standing 4 s and pulling away: no
  // measurement from the stop until 0.5 s after pulling away (4.5 s, three times max_coast_s).
  const dps::MotionProfile stop({{0.0, 8.0, 0.0}, {1.0, 8.0, 0.0}, {2.0, 0.0, 0.0}, {6.0, 0.0, 0.0}, {7.0, 5.0, 0.0}});
  const Run r = Drive(stop, 8.0, [](int f) { return f < 30 || f >= 98; });
  std::printf("standing 4 s beside a gap: worst ego boundary error %.3f m, %d frames without both\n", r.worst_error_m,
              r.frames_without);
  CHECK_EQ(r.frames_without, 0);
  CHECK(r.worst_error_m < 0.1);
  CHECK_EQ(r.left_changes + r.right_changes, 0);
}

void TestLaneChange() {
  // One lane to the right at 15 m/s: yaw right for 1.5 s, back for 1.5 s (3.6 m across); the
  // frames of its middle (1.5 s to 2.1 s after it starts) not measured.
  const double rate = 0.107;
  const dps::MotionProfile change({{0.0, 15.0, 0.0}, {1.0, 15.0, 0.0}, {1.001, 15.0, -rate}, {2.5, 15.0, -rate},
                                   {2.501, 15.0, rate}, {4.0, 15.0, rate}, {4.001, 15.0, 0.0}});
  const Run r = Drive(change, 6.0, [](int f) { return f < 37 || f >= 46; });
  std::printf("lane change: worst ego boundary error %.3f m, %d frames without both, %d right, %d left\n",
              r.worst_error_m, r.frames_without, r.right_changes, r.left_changes);
  CHECK(r.frames_without == 0);
  CHECK(r.worst_error_m < 0.15);
  CHECK_EQ(r.right_changes, 1);
  CHECK_EQ(r.left_changes, 0);
}

void TestStray() {
  dps::LaneTracker tracker;
  dps::LaneFrame m;
  dps::LaneBoundaryRow left, right, stray;
  left.boundary = "left", left.offset_m = -1.75, left.type = "solid";
  right.boundary = "right", right.offset_m = 1.75, right.type = "dashed";
  stray.boundary = "right", stray.offset_m = 0.8, stray.type = "dashed";
  const dps::PlanarPose still;
  int stray_reported = 0, frames_with_ego = 0;
  for (int f = 0; f < 20; ++f) {
    m.boundaries = {left, right};
    if (f == 5) m.boundaries.push_back(stray);
    const dps::LaneFrame out = tracker.Update(m, f > 0 ? &still : nullptr, f / kFps);
    bool found = false;
    const double r = OffsetOf(out, "right", &found);
    stray_reported += found && std::abs(r - 0.8) < 0.2;
    frames_with_ego += out.has_ego;
  }
  CHECK_EQ(stray_reported, 0);
  CHECK_EQ(frames_with_ego, 20);  // the first frame's lines at once
  dps::LaneTrackerOptions bad;
  bad.gate_m = 0.0;
  CHECK_THROWS_WITH(bad.Check(), dps::Error, "gate_m");
}

// The right line, in four frames, measured only far ahead (7-10 m) and fitted there with a heading
// 10 degrees off, so that it extrapolates to 0.25 m at the car's axis: compared where it was seen it
// is the tracked line, and neither a line beside the car nor the loss of the right boundary follows.
void TestSeenAhead() {
  dps::LaneTracker tracker;
  dps::PlanarPose ahead_10mps;  // straight on at 10 m/s
  ahead_10mps.z_m = 10.0 / kFps;
  dps::LaneBoundaryRow left, right;
  left.boundary = "left", left.offset_m = -1.75, left.type = "solid";
  right.boundary = "right", right.offset_m = 1.75, right.type = "dashed";
  const dps::LaneStretch whole{-4.0, 10.0}, ahead{7.0, 10.0};
  double worst = 0.0;
  int inside = 0, frames_with_right = 0;
  for (int f = 0; f < 30; ++f) {
    dps::LaneFrame m;
    m.boundaries = {left, right};
    m.seen = {whole, whole};
    if (f >= 10 && f < 14) {
      m.boundaries[1].heading_deg = 10.0;
      m.boundaries[1].offset_m = 1.75 - std::tan(10.0 * kDeg) * ahead.Middle();
      m.seen[1] = ahead;
    }
    const dps::LaneFrame out = tracker.Update(m, f > 0 ? &ahead_10mps : nullptr, f / kFps);
    for (const dps::LaneBoundaryRow& b : out.boundaries) inside += std::abs(b.offset_m) < 1.0;
    bool found = false;
    const double r = OffsetOf(out, "right", &found);
    frames_with_right += found;
    if (found) worst = std::max(worst, std::abs(r - 1.75));
  }
  std::printf("seen ahead: right boundary in %d of 30 frames, worst offset error %.3f m, %d lines inside 1 m\n",
              frames_with_right, worst, inside);
  CHECK_EQ(frames_with_right, 30);
  CHECK(worst < 0.15);
  CHECK_EQ(inside, 0);
}

}  // namespace

int main() {
  TestGap();
  TestStanding();
  TestLaneChange();
  TestStray();
  TestSeenAhead();
  return dps_test::Report();
}
