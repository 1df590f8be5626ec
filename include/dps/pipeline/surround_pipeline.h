// dps — one frame of the Dynamic Panoramic Surround map (Gandhi & Trivedi 2006, section V-C):
// front obstacles by binocular stereo, left and right obstacles by motion stereo, all on the
// ground plane of the current vehicle frame.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "dps/detect/coverage.h"
#include "dps/detect/front_detection.h"
#include "dps/detect/lane_detection.h"
#include "dps/detect/lane_tracking.h"
#include "dps/detect/object_attributes.h"
#include "dps/detect/rear_detection.h"
#include "dps/detect/side_detection.h"

namespace dps {

struct PipelineOptions {
  FrontDetectorOptions front;
  SideDetectorOptions side;
  bool sides = true;           // run motion stereo on the side views
  // Also match the front pair at half its views' size over the disparities beyond its range
  // (NearFrontOptions), where it left pixels unmatched: objects nearer than f B / (its largest
  // disparity), e.g. a car stopping close ahead.
  bool front_near = true;
  RearDetectorOptions rear;
  // Look behind the mirrors with each camera's rear view (rear_detection.h). Off by default: it
  // adds more false detections than it finds (docs/detection.md).
  bool rears = false;
  LaneDetectorOptions lane;
  bool lanes = true;           // find the lane markings beside the car (lane_detection.h)
  LaneTrackerOptions lane_tracking;
  bool track_lanes = true;     // ... and track them over time with the ego motion (lane_tracking.h)
  // > 0: the side views reach forward over what the front pair does not see (SideOptionsForRig),
  // at most this far in front of their axes (kSideForwardReachDeg); 0: as `side` gives. Off by
  // default: docs/detection.md. deg, 0 <= a < 80.
  double side_forward_max_deg = 0.0;
  double merge_distance_m = 1.5;  // detections this close are one object (FuseDetections)
  // Then parts that fit into one vehicle's footprint are one object (MergeVehicleParts);
  // vehicle_length_m = 0: no such merging.
  double vehicle_length_m = 5.5;
  double vehicle_width_m = 2.2;
  bool vehicle_across_sources_only = false;
  // The footprint's length allows for the front pair's depth error at each part's far end: this
  // much disparity (MergeVehicleParts' depth_error_per_m2, k = this / (f B)); half a pixel each,
  // the two ends of a union together one pixel. px, >= 0 (0: the footprint as it is).
  double vehicle_disparity_slack_px = 0.5;
  // Each detection's lane (from the frame's lanes) and class (object_attributes.h).
  ClassOptions classes;

  // Throws dps::Error naming the field, its value and the violated constraint (the detectors'
  // options included).
  void Check() const;
};

// Options scaled to the rig's image size: at 640 px wide omni images, 400x200 views with a focal
// length of 170 px (about the omni image's own resolution near the horizon), 96 disparities and
// 9x9 windows; proportionally smaller views, ranges (multiples of 16) and windows for smaller
// images (e.g. 200x100, f = 85 px, 48 disparities, 7x7 at the paper's 320x240).
PipelineOptions DefaultPipelineOptions(const Rig& rig);

// The front pair's options for objects nearer than `front` reaches: views of half the size and
// focal length (the field of view kept) with the windows DefaultPipelineOptions picks for views
// that size (7x7), searching from where `front`'s range ends (half its disparity there) over half
// as many disparities, which is `front`'s range over again at full size: objects down to half its
// nearest distance (1.8 m from the cameras at 640x480 with a 2 m baseline). Disparities within a
// pixel of either end of that search are dropped (FrontDetectorOptions::range_edge_px); no drift
// correction of its own.
FrontDetectorOptions NearFrontOptions(const FrontDetectorOptions& front);

// How far in front of their axes the side views may reach with PipelineOptions::side_forward_max_deg
// (dps-process --reach-forward): tan 76 deg = 4 focal lengths, so a view at most 2.5 times as wide
// as the default (its cost grows with its width); a column there spans 1 / cos^2 = 17 times less
// angle than one at the view's axis.
constexpr double kSideForwardReachDeg = 76.0;

// The side detector's options for one side of `rig`: the side view reaches forward
// (forward_half_angle_deg) over the directions the front pair does not see on that side, at
// least as far as options.side gives and at most side_forward_max_deg. The front pair sees a
// column of its views where both views have a source that is not the own car on the horizon's row;
// the outermost such column on the side is where the side view's reach ends. Cameras in the
// mirrors looking down see the road ahead in both views, and the views stay as options.side
// gives; fisheyes looking sideways see ahead only near their field's edge, where the two fields
// barely overlap, and their side views then cover the road ahead-left and ahead-right by motion
// stereo.
SideDetectorOptions SideOptionsForRig(const Rig& rig, const PipelineOptions& options, Side side);

// The ground sectors the pipeline processes (summary.json's coverage, regression tests' zones; each
// frame's own sectors, FrameOutput::coverage, go to the map, the occupancy grid and the remembered
// obstacles): the front pair from the cameras' midpoint,
// beginning where both cameras' views overlap, over the views' width or, where the cameras' fields
// or the own car end its sight within the views, over the columns both views see on the horizon's
// row; each side view from its camera, over the columns motion stereo matches at the views' full
// size (a strip at either edge is never matched: a match there could lie outside the previous
// view), as deep as its depth limit.
Coverage PipelineCoverage(const Rig& rig, const PipelineOptions& options);

// One frame's input: both omni images and, for motion stereo, the vehicle's motion since the
// previous frame (unknown for the first frame, or when the CAN log has no data for it).
struct FrameInput {
  int frame = 0;
  double t_s = 0.0;
  cv::Mat left, right;
  bool motion_known = false;
  PlanarPose current_in_previous;  // vehicle pose now, in the previous frame's vehicle frame
};

struct FrameOutput {
  std::vector<Detection> detections;  // all sources, frame and t filled in
  FrontResult front;
  SideResult left, right;
  RearResult left_rear, right_rear;
  LaneFrame lanes;             // the lane boundaries and the ego's lane position (frame, t unset)
  std::vector<std::string> warnings;
  // What this frame processed: the front pair's sector and each side's matched columns (none for a
  // side skipped); the occupancy grid marks free space only there.
  Coverage coverage;
  // Time spent per stage: the front pair's, both side pairs' and both rear views' work (the
  // sources run concurrently, so these may add up to more than detect_ms, their wall time).
  double front_ms = 0.0, sides_ms = 0.0, rears_ms = 0.0, lanes_ms = 0.0, detect_ms = 0.0;  // detect_ms includes `alongside`
};

class SurroundPipeline {
 public:
  SurroundPipeline(const Rig& rig, const PipelineOptions& options);
  ~SurroundPipeline();

  // Processes the next frame (frames must come in order; the previous images are kept for
  // motion stereo). `alongside` (optional): work that runs concurrently with the frame's stereo,
  // each function as its own task — e.g. the previous frame's tracking and map, or decoding the
  // next frame, which do not depend on this frame. All of it is done when Process returns; the
  // first exception from it or from a source is rethrown here.
  FrameOutput Process(const FrameInput& input, const std::vector<std::function<void()>>& alongside = {});

  const Rig& rig() const { return rig_; }
  // The sectors the pipeline can process (PipelineCoverage).
  const Coverage& coverage() const { return coverage_; }

 private:
  // The frame's detections from the sources that ran, stamped with the frame and fused; the
  // frame's grey images kept for the next frame's side views.
  void Collect(const FrameInput& in, bool sides, const cv::Mat grey[2], FrameOutput* out);
  Rig rig_;
  PipelineOptions options_;
  Coverage coverage_;
  std::map<std::string, Eigen::Vector2d> viewpoints_;
  std::map<std::string, double> depth_error_per_m2_;  // MergeVehicleParts' depth error by source
  Eigen::Vector2d front_eye_{0, 0};  // the front cameras' midpoint (x, z) and its height (DropHidden)
  double front_eye_height_m_ = 0.0;
  std::unique_ptr<FrontDetector> front_;
  std::unique_ptr<FrontDetector> front_near_;  // NearFrontOptions; null when off
  std::unique_ptr<SideDetector> left_, right_;
  std::unique_ptr<RearDetector> left_rear_, right_rear_;
  std::unique_ptr<LaneDetector> lanes_;
  std::unique_ptr<LaneTracker> lane_tracker_;
  cv::Mat previous_left_, previous_right_;  // the previous frame's omni images, grey
  double previous_t_s_ = 0.0;
  bool sides_last_ = false;  // the side detectors ran on the previous frame (Detect's `continuing`)
};

}  // namespace dps
