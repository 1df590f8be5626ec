// The occupancy grid of the parked-cars scene (issue: the cars' sides are occupied cells within
// 0.5 m of truth, the road between is free): rendered frames through the whole pipeline (front
// stereo, both side motion stereos) into the grid, with the ego motion of the scene. Checked at
// the last frame against the truth footprints of that frame.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <vector>

#include "check.h"
#include "fixtures.h"
#include "dps/map/occupancy_grid.h"
#include "dps/pipeline/surround_pipeline.h"
#include "dps/synth/scene_io.h"
#include "dps/synth/scene_renderer.h"
#include "dps/synth/synth.h"
#include "dps/synth/truth.h"
#include "dps/util/error.h"

namespace {

using dps_test::kSource;
constexpr double kNearTruthM = 0.5;       // occupied cells within this of a footprint
constexpr double kOccupiedFraction = 0.9; // of the occupied cells near the cars
constexpr double kSideCoverage = 0.7;     // of the points along the cars' sides seen so far
constexpr double kFreeFraction = 0.9;     // of the cells of the lane ahead and beside

void TestParkedCarsGrid() {
  dps::Scene scene = dps_test::SmallScene("parked_cars");
  const int frames = 30;  // 2 s at 8 m/s: car 1 passed, car 2 beside, cars 3-4 ahead
  const dps::SceneRenderer renderer(scene);
  size_t left = 0, right = 0;
  for (size_t i = 0; i < scene.rig.cameras.size(); ++i) {
    if (scene.rig.cameras[i].name == "left") left = i;
    if (scene.rig.cameras[i].name == "right") right = i;
  }
  dps::SurroundPipeline pipeline(scene.rig, dps::DefaultPipelineOptions(scene.rig));
  dps::OccupancyGrid grid;
  // The same frames as dps-process runs them: a second pipeline, each frame's grid update done
  // alongside the next frame's stereo. Its detections and its grid must be the same.
  dps::SurroundPipeline overlapped(scene.rig, dps::DefaultPipelineOptions(scene.rig));
  dps::OccupancyGrid overlapped_grid;
  dps::FrameOutput pending;
  dps::PlanarPose pending_ego;
  double pending_t = 0.0;
  int alongside_runs = 0, mismatches = 0;
  dps::FrameInput last;
  dps::FrameState state;
  for (int f = 0; f < frames; ++f) {
    state = renderer.StateAt(scene.FrameTime(f));
    const dps::FrameInput in = dps_test::RenderedInput(scene, renderer, state, f, left, right);
    const dps::FrameOutput out = pipeline.Process(in);
    grid.Update(in.t_s, state.ego, out.coverage, out.detections);
    std::vector<std::function<void()>> alongside;
    if (f > 0) {
      alongside.push_back([&] {
        overlapped_grid.Update(pending_t, pending_ego, pending.coverage, pending.detections);
        ++alongside_runs;
      });
    }
    dps::FrameOutput out2 = overlapped.Process(in, alongside);
    bool same = out2.detections.size() == out.detections.size();
    for (size_t i = 0; same && i < out.detections.size(); ++i) {
      same = out2.detections[i].x_m == out.detections[i].x_m && out2.detections[i].z_m == out.detections[i].z_m;
    }
    mismatches += !same;
    pending = std::move(out2);
    pending_ego = state.ego;
    pending_t = in.t_s;
    last = in;
  }
  overlapped_grid.Update(pending_t, pending_ego, pending.coverage, pending.detections);
  CHECK_EQ(alongside_runs, frames - 1);
  CHECK_EQ(mismatches, 0);
  int differing_cells = 0;
  for (double z = -30.0; z <= 30.0; z += 0.1) {
    for (double x = -30.0; x <= 30.0; x += 0.1) differing_cells += overlapped_grid.AtVehicle({x, z}) != grid.AtVehicle({x, z});
  }
  CHECK_EQ(differing_cells, 0);
  // An exception in the work alongside reaches the caller.
  const auto failing = [&] { return overlapped.Process(last, {[] { throw dps::Error("alongside failed"); }}); };
  CHECK_THROWS_WITH(failing(), dps::Error, "alongside failed");
  const std::vector<dps::TruthRow> truth = dps::TruthAt(state, frames - 1);
  const auto distance_to_cars = [&](const Eigen::Vector2d& p) {
    double best = 1e9;
    for (const dps::TruthRow& t : truth) best = std::min(best, dps::DistanceToFootprint(t, p));
    return best;
  };
  // Occupied cells (vehicle frame now) within 20 m: near a car's footprint.
  int occupied = 0, near_truth = 0;
  for (const Eigen::Vector2d& w : grid.ObstacleCells()) {
    const Eigen::Vector2d p = dps::WorldToBody(state.ego, w);
    if (p.norm() > 20.0) continue;
    ++occupied;
    near_truth += distance_to_cars(p) <= kNearTruthM;
  }
  // The cars' sides facing the road (x = 2.5) from 2 m behind to 15 m ahead, wherever a car is:
  // an occupied cell within 0.5 m of each point.
  const std::vector<Eigen::Vector2d> cells = grid.ObstacleCells();
  int side_points = 0, side_hits = 0;
  for (double z = -2.0; z <= 15.0; z += 0.25) {
    const Eigen::Vector2d p(2.5, z);
    if (distance_to_cars(p) > 1e-9) continue;  // not on a car's side
    ++side_points;
    for (const Eigen::Vector2d& w : cells) {
      if ((dps::WorldToBody(state.ego, w) - p).norm() <= kNearTruthM) {
        ++side_hits;
        break;
      }
    }
  }
  // The lane we drive in and the space up to the cars: x in [-1.5, 2.0], z in [3, 15] ahead,
  // clear of every footprint by 0.5 m: free.
  int lane = 0, free = 0, lane_occupied = 0;
  for (double z = 3.0; z <= 15.0; z += 0.2) {
    for (double x = -1.5; x <= 2.0; x += 0.2) {
      const Eigen::Vector2d p(x, z);
      if (distance_to_cars(p) < kNearTruthM) continue;
      ++lane;
      const double e = grid.AtVehicle(p);
      free += e < 0;
      lane_occupied += e > dps::OccupancyOptions().strength_threshold;
    }
  }
  std::printf("parked cars grid after %d frames: %d occupied cells within 20 m, %d within %.1f m of a car; "
              "car sides %d/%d points covered; lane %d/%d cells free, %d occupied\n",
              frames, occupied, near_truth, kNearTruthM, side_hits, side_points, free, lane, lane_occupied);
  CHECK(occupied > 0);
  CHECK(near_truth >= kOccupiedFraction * occupied);
  CHECK(side_points > 0);
  CHECK(side_hits >= kSideCoverage * side_points);
  CHECK(free >= kFreeFraction * lane);
  CHECK_EQ(lane_occupied, 0);
}

}  // namespace

int main() {
  TestParkedCarsGrid();
  return dps_test::Report();
}
