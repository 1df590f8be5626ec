// dps — the lane boundaries tracked over time with the ego motion (the lanes issue's Kalman
// filter), so that a gap in the markings, a worn stretch or a car covering them does not lose the
// lane.
//
// Each line near the car is a state (offset at the vehicle's X axis, slope = tan of its heading)
// with its covariance. Per frame the lines are carried into the new vehicle frame by the motion
// since the previous frame (CAN speed and yaw rate: two of each line's points moved with the
// vehicle, the line through them; the covariance through that map's Jacobian), plus process noise
// for what the motion does not explain (the road's own curvature, steering between samples); while
// the car stands still (no motion at all) the lines stay where they are, without drift, and the
// time standing is not coasting time (a car stopped beside a gap in the dashes keeps them). The
// frame's measured lines (LaneDetector) update the line nearest within gate_m where they were seen
// (across, at the middle of the stretch their evidence covers: a line seen only far ahead is
// compared there, not where its heading extrapolates it to at the car), nearest pairs first, as a
// point there (offset_sigma_m) and a heading known the less the shorter that stretch (its two ends
// each off by offset_sigma_m); a measurement farther than gate_m from every line starts one; a
// line not measured for max_coast_s is dropped, one measured in fewer than min_measurements frames
// not reported yet, one not measured this frame only when measured in min_coast_share of its
// frames until then. The
// frame's lanes are then named from the reported lines as the detector names its own
// (NameLaneLines): a coasting line keeps its type and loses confidence linearly over max_coast_s.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "dps/camera/ego_motion.h"
#include "dps/detect/lane_detection.h"

namespace dps {

struct LaneTrackerOptions {
  double max_coast_s = 1.5;           // a line unmeasured this long is dropped, s > 0
  double gate_m = 0.5;                // a measurement this close in offset updates a line, m > 0
  double offset_sigma_m = 0.05;       // a measured offset's noise, m > 0
  double heading_sigma_deg = 1.0;     // a measured heading's noise when the stretch it was fitted on
                                      // is not known (LaneFrame::seen; else from its length), deg > 0
  double offset_drift_mps = 0.3;      // process noise: lateral drift the motion does not explain, m/s > 0
  double heading_drift_dps = 2.0;     // ... and turning, deg/s > 0
  int min_measurements = 2;           // a line is reported once measured in this many frames (>= 1;
                                      // the first frame's lines at once, nothing earlier to confirm
                                      // them, but they coast only when measured this often too): one
                                      // stray measurement does not stay on for max_coast_s
  double min_coast_share = 0.5;       // ... and, in a frame that did not measure it, only when measured
                                      // in this share of its frames up to its last measurement (0..1):
                                      // a line seen now and then (a shadow's edge) does not stand in
                                      // for the lane's between its sightings
  double min_lane_width_m = 2.5;      // naming, as LaneDetectorOptions' (> 0)

  // Throws dps::Error naming the field, its value and the violated constraint.
  void Check() const;
};

class LaneTracker {
 public:
  explicit LaneTracker(const LaneTrackerOptions& options = {});

  // One frame at t_s: the detector's lanes of the frame (their boundaries are the measurements)
  // and the vehicle's pose now in the previous frame's vehicle frame (nullptr: unknown; the lines
  // then stay where they were). Returns the tracked lanes (frame, t left 0) with lp, lane width,
  // heading and lane changes from the tracked ego boundaries.
  LaneFrame Update(const LaneFrame& measured, const PlanarPose* current_in_previous, double t_s);

 private:
  struct Track {
    Eigen::Vector2d x{0, 0};  // offset, slope
    Eigen::Matrix2d P = Eigen::Matrix2d::Identity();
    double last_measured_s = 0.0;
    int measurements = 0, frames = 0;  // frames measured, frames lived
    int frames_when_measured = 0;      // `frames` at the last measurement
    bool confirmed = false;            // started in the tracker's first frame
    std::string type;
    double confidence = 1.0;
  };
  LaneTrackerOptions options_;
  std::vector<Track> tracks_;
  std::optional<double> last_t_s_;
  std::optional<double> previous_lp_;
};

}  // namespace dps
