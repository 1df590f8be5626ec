// dps — processing one recorded drive into detections.csv, tracks.csv, the surround-map video
// and summary.json (what dps-process does for each drive).
#pragma once

#include <functional>
#include <map>
#include <string>
#include <vector>

#include "dps/calib/extrinsic_correction.h"
#include "dps/camera/valid_mask.h"
#include "dps/map/grid_obstacles.h"
#include "dps/map/occupancy_grid.h"
#include "dps/map/surround_map.h"
#include "dps/map/tracker.h"
#include "dps/pipeline/drive_io.h"
#include "dps/pipeline/surround_pipeline.h"

namespace dps {

struct DriveOptions {
  bool default_pipeline = true;   // DefaultPipelineOptions(rig) instead of `pipeline`
  PipelineOptions pipeline;
  CanLogFormat can;
  double image_fps = 30.0;        // frame rate of image folders without frames.csv, > 0
  bool map_video = true;          // map.avi (MJPG)
  bool map_png = false;           // map/NNNNNN.png
  bool diagnostics = false;       // diagnostics.avi: six panels per source (DrawDiagnostics)
  // Every grid_every-th frame (0 = none): the occupancy grid as grid/NNNNNN.png (16-bit evidence,
  // OccupancyGrid::EvidenceImage) and a row of grid/grid.csv (its origin and the vehicle's pose).
  int grid_every = 0;             // >= 0
  MapOptions map;
  TrackerOptions tracker;
  OccupancyOptions occupancy;
  // Obstacles the grid remembers where no view looks this frame (behind the car, the wedges between
  // the views) reported as detections (grid_obstacles.h; off by default: docs/detection.md).
  bool grid_obstacles = false;
  GridObstacleOptions grid_obstacle;
  // Each camera's rear view against its earlier frames (rear_detection.h; off by default:
  // docs/detection.md). Sets PipelineOptions::rears of the default pipeline.
  bool rear = false;
  // The side views also cover the road ahead that the front pair does not see (sideways fisheyes:
  // SideOptionsForRig; off by default: docs/detection.md). Sets PipelineOptions::side_forward_max_deg
  // of the default pipeline to kSideForwardReachDeg.
  bool reach_forward = false;
  bool truncate = false;          // left and right with different frames: keep the frame numbers both have
  // frames.csv with two consecutive frames more than max_frame_gap intervals (its median) apart -
  // a frame lost in recording - is an error naming them, unless allow_frame_gaps: then a warning,
  // and motion stereo spans the gap with the CAN motion over its real time.
  bool allow_frame_gaps = false;
  double max_frame_gap = 1.5;     // > 1
  // Cameras with no mask (neither masks/<camera>.png in the drive nor `mask:` in rig.yaml): estimate
  // what lies beyond the field from the drive's first mask_estimate_s seconds (EstimateFieldMask).
  bool estimate_masks = true;
  double mask_estimate_s = 2.0;   // > 0
  FieldMaskOptions field_mask;
  // ... and, for cameras without masks/<camera>_own_car.png in the drive, the own car from the
  // same frames (EstimateOwnCarMask), when the car moved over them.
  OwnCarMaskOptions own_car_mask;
  // Each camera's rotation in the rig corrected from the road's motion over the drive's first
  // extrinsic_estimate_s seconds (EstimateExtrinsicCorrection), when the estimate is sure enough;
  // the estimate is reported in summary.json either way.
  bool correct_extrinsics = true;
  double extrinsic_estimate_s = 1.0;  // > 0
  ExtrinsicCorrectionOptions extrinsic;

  // Throws dps::Error naming the field, its value and the violated constraint (the nested options
  // included; `pipeline` only when it is used).
  void Check() const;
};

// Where a camera's mask came from, and the share of its pixels that see the world.
struct MaskSummary {
  std::string source;             // "drive" (masks/<camera>.png), "rig.yaml", "estimated", "model"
  double valid_fraction = 0.0;
  // Where its own car came from: "drive" (masks/<camera>_own_car.png), "estimated" or "none" (the
  // car did not move over the frames the masks are estimated from, or nothing told it apart), and
  // the share of its pixels that see the own car.
  std::string own_car_source = "none";
  double own_car_fraction = 0.0;
};

struct DriveSummary {
  std::string drive;              // the drive folder's name
  std::string output_dir;
  int frames = 0;
  int frames_without_motion = 0;  // side detection skipped for them
  // By camera: frames whose side views were not matched though the motion was known, the camera
  // having moved too little (SideDetectorOptions::min_baseline_m: driving slowly or standing).
  std::map<std::string, int> frames_side_skipped;
  int detections = 0;
  double front_vertical_offset_px = 0.0;  // drift correction of the front pair at the end
  std::string map_video;          // the map video's file name and codec ("map.mp4 (H.264)"); "" = none
  std::map<std::string, MaskSummary> masks;  // by camera; the masks used are written to masks/
  std::map<std::string, ExtrinsicCorrection> extrinsics;  // by camera, when estimated
  // Where the pipeline looks (PipelineCoverage): the front pair's sector and each side view's
  // columns at its full size, as deep as its depth limit (each frame's map shades the sectors that
  // frame measured).
  Coverage coverage;
  // The grid files' geometry when they are written (grid_every > 0): cell size, cells per side,
  // evidence per 16-bit step, the stride.
  double grid_cell_m = 0.0, grid_scale = 0.0;
  int grid_cells = 0, grid_every = 0;
  std::vector<std::string> warnings;
  // cameras (masks and extrinsic correction from the first seconds), decode, front, sides, map, write
  std::map<std::string, double> stage_seconds;
  double seconds = 0.0;
  double frames_per_second = 0.0;
  std::string ToJson() const;
};

// The folder a drive's outputs go to: <out_root>/<drive folder name> (the folder's own name, also
// when it is given as "." or with a trailing slash).
std::string DriveOutputDir(const std::string& drive_dir, const std::string& out_root);
// True when that folder holds a complete run (summary.json is written last).
bool DriveOutputComplete(const std::string& output_dir);

// Processes a drive. Each camera's validity: its mask from the drive, rig.yaml or estimated (see
// DriveOptions); the masks used are written to <output>/masks/<camera>.png. The outputs are built
// in a temporary folder and renamed into place when complete; an existing output folder is
// replaced only when it holds an earlier run's summary.json, and an output folder that is,
// contains or lies inside the drive, or the current folder, is refused before anything is
// written. `progress(done, total)` is called after each frame. Throws dps::Error (naming the
// drive's file) for bad input.
DriveSummary ProcessDrive(const std::string& drive_dir, const std::string& out_root, const DriveOptions& options,
                          const std::function<void(int, int)>& progress = nullptr);

}  // namespace dps
