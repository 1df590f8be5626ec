// dps — an occupancy grid on the ground, fused over time with the ego motion (the fisheye
// obstacle-detection summary, AJAST 2017, after Häne et al., IROS 2015, sections 4.4-4.5).
//
// The grid is fixed to the ground (the tracker's world frame: the vehicle's pose integrated from
// CAN) and re-centred by whole cells when the vehicle nears its edge, so nothing smears as the car
// moves. Each frame, for every bearing of every processed view (sector), the nearest obstacle
// point on that bearing is found: cells before it get a free (negative) weight, cells at it and a
// little behind (thickness unknown) an occupied (positive) weight, shaped by the range
// uncertainty of the measurement (disparity noise: sigma grows with range squared); bearings
// without an obstacle are free up to free_range_m; unseen cells get nothing. The sum decays with
// time (half_life_s, whatever the frame rate) and is clamped, so a vehicle that leaves does not
// stay as a ghost. Cells > 0 are occupied, < 0 free, 0 unknown; obstacles are the cells above
// strength_threshold.
#pragma once

#include <limits>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "dps/camera/ego_motion.h"
#include "dps/detect/coverage.h"
#include "dps/detect/detection.h"

namespace dps {

// The grid's colours on the map: occupied cells blend towards grey, free ones towards light
// green (B = R = kGridFreeBlueRed, G = kGridFreeGreen), by their evidence.
constexpr int kGridOccupiedGrey = 90, kGridFreeBlueRed = 215, kGridFreeGreen = 240;

struct OccupancyOptions {
  double cell_m = 0.2;            // > 0
  int cells = 400;                // grid side, cells (80 m at 0.2 m), >= 16
  double bearing_step_deg = 0.5;  // bearings sampled per sector, > 0
  double free_range_m = 20.0;     // bearings without an obstacle are free up to here, > 0
  double free_weight = -0.4;      // per frame, < 0
  double occupied_weight = 1.0;   // per frame, > 0
  double thickness_m = 0.6;       // occupied evidence behind the measured surface, >= 0
  double sigma0_m = 0.1;          // range sigma = sigma0 + sigma_per_m2 * range^2
  double sigma_per_m2 = 0.002;
  // Without new evidence the sum halves in this time (0.95 per frame at 15 frames/s), > 0.
  double half_life_s = 0.9;
  double clamp = 6.0;             // |sum| <= clamp, > 0
  double strength_threshold = 2.0;  // obstacle cells: sum above this (T_strength)

  void Check() const;
};

class OccupancyGrid {
 public:
  explicit OccupancyGrid(const OccupancyOptions& options = OccupancyOptions());

  // Adds one frame: its time (seconds; the evidence decays over the time since the previous
  // frame), the vehicle's pose in the world, the views' sectors (vehicle frame) and the frame's
  // detections (their ground points, vehicle frame).
  void Update(double t_s, const PlanarPose& world_from_vehicle, const Coverage& coverage,
              const std::vector<Detection>& detections);

  // The evidence at a world point (0 outside the grid).
  double At(const Eigen::Vector2d& world_xz) const;
  // The evidence at a point of the current vehicle frame.
  double AtVehicle(const Eigen::Vector2d& vehicle_xz) const;
  // The evidence (CV_32F, cells x cells): cell (column c, row r) covers world x in origin.x +
  // [c, c + 1) cell_m and z in origin.z + [r, r + 1) cell_m.
  const cv::Mat& Evidence() const { return sum_; }
  // Obstacle cells (sum > strength_threshold) as world points.
  std::vector<Eigen::Vector2d> ObstacleCells() const;

  // The evidence as a 16-bit picture for files (grid/NNNNNN.png): cell (column c, row r) covers
  // world x in origin.x + [c, c + 1) cell_m and z in origin.z + [cells - 1 - r, cells - r) cell_m
  // (+Z up, as on the map); value = 32768 + evidence * EvidenceScale(), rounded (0 unknown ->
  // 32768; the clamp keeps it within 1..65535).
  cv::Mat EvidenceImage() const;
  double EvidenceScale() const { return 32767.0 / options_.clamp; }
  // The world (x, z) of cell (0, 0)'s corner (it moves when the grid re-centres).
  const Eigen::Vector2d& origin() const { return origin_; }
  const OccupancyOptions& options() const { return options_; }

  // Draws the grid onto a map picture (MapOptions geometry: +Z up, vehicle at the centre):
  // occupied cells dark grey, free cells light green, unknown left as it is.
  void Draw(cv::Mat& map, double map_range_m) const;
  // The same over a copy of `background` (CV_8UC3) into `map` (its buffer reused), in one pass.
  void Draw(const cv::Mat& background, cv::Mat& map, double map_range_m) const;

 private:
  void Recentre(const Eigen::Vector2d& world);
  OccupancyOptions options_;
  cv::Mat sum_;                       // CV_32F evidence
  cv::Mat delta_;                     // CV_32F, one frame's evidence (kept to save its allocation)
  Eigen::Vector2d origin_{0, 0};      // world (x, z) of cell (0, 0)'s corner
  PlanarPose pose_;                   // the latest vehicle pose
  double last_t_s_ = std::numeric_limits<double>::quiet_NaN();  // the latest frame's time
};

}  // namespace dps
