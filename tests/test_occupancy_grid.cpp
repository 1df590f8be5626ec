// Tests of the occupancy grid: a wall seen ahead becomes occupied at its range and free before
// it, unknown behind it; it stays in place on the ground while the vehicle drives; after it is
// gone, free evidence and decay clear it (no ghost).
#include <cmath>
#include <cstdio>

#include "check.h"
#include "dps/map/occupancy_grid.h"
#include "dps/util/error.h"

namespace {

constexpr double kFrame = 1.0 / 15;  // the frame interval the drives below are sampled at

dps::Coverage FrontSector() {
  dps::Coverage c;
  c.sectors.push_back({"front", {0, 0.9}, 0.0, 50.0 * M_PI / 180.0});
  return c;
}

// A wall across the front at world z = wall_z, as detection points in the vehicle frame.
std::vector<dps::Detection> Wall(const dps::PlanarPose& ego, double wall_z) {
  std::vector<Eigen::Vector2d> pts;
  for (double x = -4; x <= 4; x += 0.05) pts.push_back(dps::WorldToBody(ego, {x, wall_z}));
  return {dps::DetectionFromPoints(pts, "front")};
}

void TestWall() {
  double t = 0.0;  // seconds, 15 frames/s
  dps::OccupancyOptions o;
  dps::OccupancyGrid grid(o);
  dps::PlanarPose ego;
  // The vehicle drives at 0.5 m per frame towards a wall at world z = 15 (ending 10.5 m from it,
  // where the range sigma is 0.1 + 0.002 * 10.5^2 = 0.32 m).
  for (int f = 0; f < 10; ++f) {
    ego.z_m = f * 0.5;
    grid.Update(t += kFrame, ego, FrontSector(), Wall(ego, 15.0));
  }
  CHECK(grid.At({0.0, 15.05}) > o.strength_threshold);   // at the wall
  CHECK(grid.At({2.0, 15.1}) > o.strength_threshold);
  CHECK(grid.At({0.0, 11.0}) < 0);                       // free before it
  CHECK(grid.At({0.0, 18.0}) == 0);                      // never seen behind it
  CHECK(grid.AtVehicle({0.0, 15.05 - ego.z_m}) > o.strength_threshold);
  // The obstacle cells lie within half a metre of the wall's surface (or its assumed thickness).
  const std::vector<Eigen::Vector2d> cells = grid.ObstacleCells();
  CHECK(!cells.empty());
  for (const Eigen::Vector2d& c : cells) CHECK(c.y() >= 15.0 - 0.5 && c.y() <= 15.0 + o.thickness_m + 0.5);
  // The wall is gone: free evidence and decay clear it.
  for (int f = 0; f < 30; ++f) grid.Update(t += kFrame, ego, FrontSector(), {});
  CHECK(grid.At({0.0, 15.05}) <= 0);
  CHECK(grid.ObstacleCells().empty());
  // Driving far re-centres the grid; the old area falls off, the new one works.
  for (int f = 0; f < 10; ++f) {
    ego.z_m = 100 + f;
    grid.Update(t += kFrame, ego, FrontSector(), Wall(ego, 125.0));
  }
  CHECK(grid.At({0.0, 125.05}) > o.strength_threshold);
  dps::OccupancyOptions bad;
  bad.free_weight = 0.5;
  CHECK_THROWS_WITH(dps::OccupancyGrid{bad}, dps::Error, "free_weight");
}

// The evidence fades with time, whatever the frame rate: a wall left unseen for 1 s keeps
// 0.5^(1 / half_life_s) of its evidence after 15 frames at 15 frames/s and after 30 at 30 frames/s.
void TestFadesWithTime() {
  dps::OccupancyOptions o;
  dps::PlanarPose ego;
  const dps::Coverage nothing_seen{{dps::Sector{"front", {0, 0.9}, 0.0, 1e-3}}, {}};  // a sliver beside the wall
  for (const int fps : {15, 30}) {
    dps::OccupancyGrid grid(o);
    grid.Update(0.0, ego, FrontSector(), Wall(ego, 10.0));
    const double seen = grid.At({2.0, 10.05});
    CHECK(seen > 0);
    for (int f = 1; f <= fps; ++f) grid.Update(static_cast<double>(f) / fps, ego, nothing_seen, {});
    CHECK_NEAR(grid.At({2.0, 10.05}), seen * std::pow(0.5, 1.0 / o.half_life_s), 1e-4);
  }
  dps::OccupancyOptions bad;
  bad.half_life_s = 0;
  CHECK_THROWS_WITH(dps::OccupancyGrid{bad}, dps::Error, "half_life_s");
}

// The drawing: a turned vehicle in front of a wall; every map pixel that shows the grid must show
// the cell under it, found the long way (map pixel -> vehicle -> world -> At). Pixels on cell
// borders may land in the neighbouring cell.
void TestDraw() {
  double t = 0.0;  // seconds, 15 frames/s
  dps::OccupancyGrid grid;
  dps::PlanarPose ego{1.3, 2.1, 0.4};
  for (int f = 0; f < 6; ++f) grid.Update(t += kFrame, ego, FrontSector(), Wall(ego, 12.0));
  const double range = 20.0;
  cv::Mat map(300, 300, CV_8UC3, cv::Scalar(255, 255, 255));
  grid.Draw(map, range);
  const double scale = map.cols / (2 * range);
  int occupied = 0, free = 0, agree = 0, shown = 0;
  for (int v = 0; v < map.rows; ++v) {
    for (int u = 0; u < map.cols; ++u) {
      const double e = grid.AtVehicle({(u - map.cols / 2.0) / scale, (map.rows / 2.0 - v) / scale});
      const cv::Vec3b px = map.at<cv::Vec3b>(v, u);
      const bool grey = px[0] == px[1] && px[1] == px[2] && px[0] < 255;
      const bool green = px[1] > px[0];
      occupied += e > 0;
      free += e < 0;
      shown += e != 0;
      agree += (e > 0 && grey) || (e < 0 && green) || (e == 0 && px == cv::Vec3b(255, 255, 255));
    }
  }
  std::printf("grid drawing: %d occupied and %d free pixels expected; %d of %d pixels agree\n", occupied, free, agree,
              map.rows * map.cols);
  CHECK(occupied > 100 && free > 1000 && shown > 0);
  CHECK(agree >= 0.99 * map.rows * map.cols);
  // Drawn over a background into another picture (its old buffer of another size reused), the
  // same picture, and the background untouched.
  const cv::Mat background(300, 300, CV_8UC3, cv::Scalar(255, 255, 255));
  cv::Mat into(10, 20, CV_8UC3, cv::Scalar(1, 2, 3));
  grid.Draw(background, into, range);
  CHECK_EQ(cv::norm(into, map, cv::NORM_INF), 0.0);
  CHECK_EQ(cv::countNonZero(background.reshape(1) != 255), 0);
}

}  // namespace

int main() {
  TestWall();
  TestFadesWithTime();
  TestDraw();
  return dps_test::Report();
}
