// Obstacles the occupancy grid remembers (grid_obstacles.h): a pole and a parked car measured by a
// right side view while the vehicle drives past stay, after they leave the view, where they stand
// (their position in the current vehicle frame known from the ego motion), as detections of the
// right side; nothing is remembered inside the view, nor a part of an object the frame measures;
// a wall whose cells the grid lost in places is one object; remembered objects fade; a pole
// measured with range noise is remembered at its surface, not over the depth its evidence spans;
// beyond a side view's depth limit what the front pair measured is remembered.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "check.h"
#include "dps/map/grid_obstacles.h"
#include "dps/util/error.h"

namespace {

constexpr double kFrame = 1.0 / 15;  // the frame interval the drives below are sampled at

constexpr double kDeg = M_PI / 180.0;

// A right side view looking out from the right mirror, 45 degrees either way.
dps::Coverage RightSector() {
  dps::Coverage c;
  c.sectors.push_back({"right", {1.0, 0.0}, 90.0 * kDeg, 45.0 * kDeg});
  return c;
}

// The faces of a box on the ground that a viewpoint at the vehicle's right mirror sees (its near
// long side), world (x, z) from x0 outwards and z0..z1, as vehicle-frame points; only the points
// inside the sector, as a side view measures them.
std::vector<dps::Detection> Measured(const dps::PlanarPose& ego, double x0, double z0, double z1) {
  std::vector<Eigen::Vector2d> pts;
  const dps::Coverage view = RightSector();
  for (double z = z0; z <= z1 + 1e-9; z += 0.05) {
    const Eigen::Vector2d p = dps::WorldToBody(ego, {x0, z});
    if (view.Contains(p)) pts.push_back(p);
  }
  if (pts.empty()) return {};
  return {dps::DetectionFromPoints(pts, "right")};
}

void TestRemembered() {
  double t = 0.0;  // seconds, 15 frames/s
  dps::OccupancyGrid grid;
  dps::PlanarPose ego;
  const dps::SameObject same;
  // A pole at world (3, 6), 0.2 m across; the vehicle drives along +Z at 0.6 m per frame (9 m/s at
  // 15 frames/s) and passes it.
  int in_view = 0, remembered_frames = 0;
  for (int f = 0; f < 25; ++f) {
    ego.z_m = 0.6 * f;
    const std::vector<dps::Detection> frame = Measured(ego, 2.9, 5.9, 6.1);
    grid.Update(t += kFrame, ego, RightSector(), frame);
    const std::vector<dps::Detection> r = dps::GridObstacles(grid, ego, RightSector(), frame, same);
    if (!frame.empty()) {
      ++in_view;
      CHECK(r.empty());  // measured now: not remembered as well
      continue;
    }
    if (r.empty()) continue;
    ++remembered_frames;
    CHECK_EQ(r.size(), size_t{1});
    CHECK_EQ(r[0].source, std::string("right"));
    // Where the pole stands in this frame's vehicle frame (within the grid's cell and the evidence
    // behind the surface, its assumed thickness).
    const Eigen::Vector2d truth = dps::WorldToBody(ego, {3.0, 6.0});
    CHECK_NEAR(r[0].z_m, truth.y(), 0.3);
    CHECK(r[0].x_m > truth.x() - 0.4 && r[0].x_m < truth.x() + 0.8);
    CHECK(truth.y() < 0);  // only behind the view, which covers the side abeam
  }
  std::printf("pole: in view %d frames, remembered %d frames after\n", in_view, remembered_frames);
  CHECK(in_view >= 5);
  CHECK(remembered_frames >= 5);
  // Left alone, it fades (no ghost): the grid's decay takes the evidence below its threshold.
  for (int f = 0; f < 60; ++f) grid.Update(t += kFrame, ego, RightSector(), {});
  CHECK(dps::GridObstacles(grid, ego, RightSector(), {}, same).empty());
}

// A parked car (4.5 m) the view still measures in part is that car, not a second object; a wall
// whose cells have a gap under the merge distance is one object.
void TestSameObject() {
  double t = 0.0;  // seconds, 15 frames/s
  dps::OccupancyGrid grid;
  dps::PlanarPose ego;
  // The car's near side at world x = 2.5, z = 0..4.5; the vehicle passes it.
  for (int f = 0; f <= 8; ++f) {
    ego.z_m = 0.6 * f;
    grid.Update(t += kFrame, ego, RightSector(), Measured(ego, 2.5, 0.0, 4.5));
  }
  // Its front part is in view now, its rear part behind the view: one detection, the measured one.
  const std::vector<dps::Detection> frame = Measured(ego, 2.5, 0.0, 4.5);
  CHECK(!frame.empty());
  const dps::Coverage view = RightSector();
  bool rear_part = false;
  for (const Eigen::Vector2d& w : grid.ObstacleCells()) rear_part = rear_part || !view.Contains(dps::WorldToBody(ego, w));
  CHECK(rear_part);
  CHECK(dps::GridObstacles(grid, ego, RightSector(), frame, {}).empty());
  // Without the frame's detection the rear part is remembered, as one object.
  const std::vector<dps::Detection> alone = dps::GridObstacles(grid, ego, RightSector(), {}, {});
  CHECK_EQ(alone.size(), size_t{1});

  // A wall at x = 3 from z = 0 to 9 with a 1 m gap (z 4..5) in what was measured; once behind the
  // view it is one remembered object spanning both stretches.
  dps::OccupancyGrid walls;
  ego = {};
  for (int f = 0; f < 30; ++f) {
    ego.z_m = 0.6 * f;
    std::vector<dps::Detection> parts = Measured(ego, 3.0, 0.0, 4.0);
    for (dps::Detection& d : Measured(ego, 3.0, 5.0, 9.0)) parts.push_back(d);
    walls.Update(t += kFrame, ego, RightSector(), parts);
  }
  const std::vector<dps::Detection> wall = dps::GridObstacles(walls, ego, RightSector(), {}, {});
  CHECK_EQ(wall.size(), size_t{1});
  if (wall.size() == 1) CHECK(wall[0].z_max_m - wall[0].z_min_m > 6.0);
  // With no merging distance the two stretches stay apart.
  dps::SameObject apart;
  apart.merge_distance_m = 0.0;
  CHECK_EQ(dps::GridObstacles(walls, ego, RightSector(), {}, apart).size(), size_t{2});

  dps::GridObstacleOptions bad;
  bad.max_range_m = 0;
  CHECK_THROWS_WITH(dps::GridObstacles(walls, ego, RightSector(), {}, {}, bad), dps::Error, "max_range_m");
}

// The pole of TestRemembered, 0.2 m deep, measured with range noise as motion stereo's (each
// frame's points moved along their rays from the mirror by up to +-0.8 m, a fixed sequence
// averaging zero) while the vehicle waits beside it for 3 s and drives off: the grid's evidence
// spreads over the noise and the thickness it assumes behind each hit, and the remembered pole is
// where the hits put its surface on average, not the whole depth its evidence spans.
void TestNoisyRange() {
  double t = 0.0;
  dps::OccupancyGrid grid;
  dps::PlanarPose ego;
  const double offsets[] = {0.8, -0.8, 0.4, -0.6, 0.6, -0.4, 0.0, 0.2, -0.2};
  int remembered_frames = 0;
  double worst = 0.0;
  for (int f = 0; f < 75; ++f) {
    // Waiting beside the pole for 3 s (as in stop-and-go traffic), then driving off at 9 m/s.
    ego.z_m = f < 45 ? 6.0 : 6.0 + 0.6 * (f - 45);
    std::vector<dps::Detection> frame = Measured(ego, 2.9, 5.9, 6.1);
    for (dps::Detection& d : frame) {
      std::vector<Eigen::Vector2d> moved;
      for (const Eigen::Vector2d& p : d.points) {
        const Eigen::Vector2d ray = (p - Eigen::Vector2d(1.0, 0.0)).normalized();
        moved.push_back(p + offsets[f % 9] * ray);
      }
      d = dps::DetectionFromPoints(moved, "right");
    }
    grid.Update(t += kFrame, ego, RightSector(), frame);
    const std::vector<dps::Detection> r = dps::GridObstacles(grid, ego, RightSector(), frame, {});
    if (!frame.empty() || r.empty()) continue;
    ++remembered_frames;
    CHECK_EQ(r.size(), size_t{1});
    // The surface facing the mirror, in this frame's vehicle frame: the remembered pole begins there.
    const Eigen::Vector2d face = dps::WorldToBody(ego, {2.9, 6.0});
    worst = std::max({worst, face.x() - r[0].x_min_m, r[0].x_max_m - (face.x() + 0.2)});
  }
  std::printf("noisy pole: remembered %d frames, at most %.2f m before or behind it\n", remembered_frames, worst);
  CHECK(remembered_frames >= 10);
  CHECK(worst <= 0.3);  // the noise reaches 0.8 m, the evidence 0.6 m behind each hit
}

// A side view sees no deeper than its depth limit (Sector::max_depth_m): a pole 8 m out that the
// front sector measured while ahead is remembered when it turns into the right view's bearings
// beyond its 6 m, and not when the right sector is taken to see to any depth (as before it knew
// its limit): there the view would have measured it.
void TestBeyondDepthLimit() {
  dps::Sector right{"right", {1.0, 0.0}, 90.0 * kDeg, 50.0 * kDeg};
  dps::Sector limited = right;
  limited.max_depth_m = 6.0;
  limited.depth_direction_rad = 90.0 * kDeg;
  // The sector's geometry: abeam 5 m out inside, 8 m out not; along 30 degrees off its axis it
  // reaches 6 / cos(30 degrees).
  CHECK(limited.Contains({6.0, 0.0}));
  CHECK(!limited.Contains({9.0, 0.0}));
  CHECK(!limited.Contains({1.0 + 6.5, 3.0}));
  CHECK_NEAR(limited.Reach(60.0 * kDeg), 6.0 / std::cos(30.0 * kDeg), 1e-9);
  CHECK(std::isinf(right.Reach(90.0 * kDeg)));
  const dps::Sector front{"front", {0.0, 1.0}, 0.0, 50.0 * kDeg};
  for (const bool knows_limit : {true, false}) {
    double t = 0.0;
    dps::OccupancyGrid grid;
    dps::PlanarPose ego;
    dps::Coverage coverage;
    coverage.sectors = {front, knows_limit ? limited : right};
    int beside = 0, remembered = 0;
    for (int f = 0; f < 46; ++f) {
      ego.z_m = 0.3 * f;  // 4.5 m/s; the pole at world (9, 20), 0.2 m across
      const Eigen::Vector2d pole = dps::WorldToBody(ego, {9.0, 20.0});
      std::vector<dps::Detection> frame;
      if (front.Contains(pole)) frame.push_back(dps::DetectionFromPoints({pole}, "front"));
      grid.Update(t += kFrame, ego, coverage, frame);
      const std::vector<dps::Detection> r = dps::GridObstacles(grid, ego, coverage, frame, {});
      if (!frame.empty()) continue;
      ++beside;  // in the right view's bearings, 8 m out
      if (r.size() == 1 && (Eigen::Vector2d(r[0].x_m, r[0].z_m) - pole).norm() < 0.5) ++remembered;
    }
    std::printf("pole 8 m out, %s: %d frames after the front, remembered in %d\n",
                knows_limit ? "side view to 6 m" : "side view to any depth", beside, remembered);
    CHECK(beside >= 5);
    if (knows_limit) {
      CHECK(remembered >= 3);
    } else {
      CHECK_EQ(remembered, 0);
    }
  }
}

}  // namespace

int main() {
  TestRemembered();
  TestSameObject();
  TestNoisyRange();
  TestBeyondDepthLimit();
  return dps_test::Report();
}
