// dps — obstacles behind the mirrors: each camera's rear view against its own earlier frames
// (the blind spots of Gandhi & Trivedi 2006, section I; seed 004 §4.2's motion of one camera).
//
// Behind the car the camera moves along its viewing direction: the motion's epipole lies in the
// view, and depth from parallax is coarse or unobservable there. What the motion does tell, in
// every direction, is whether a pixel is road. The earlier frame's view is warped onto the current
// one through the road plane (each pixel's ray meets the road; that point, carried by the ego
// motion from CAN speed and yaw rate, is looked up in the earlier view; rays above the horizon are
// taken as far away). Where the road explains the current image, the two agree; where something
// stands on the road, moving or not, they do not (zero-mean normalised cross-correlation, robust
// to exposure change, in textured windows only). Against two earlier frames at once, only what is
// there now disagrees with both: the place where an object stood in one earlier frame (its ghost
// in that warp) agrees with the other.
//
// As in the paper's side detection, a column's bottom-most region of such pixels, standing on
// road, is where the object meets the road; its ray on the road plane places it (eq. 17-18),
// whatever the object's own speed. Adjacent columns with contacts close on the ground are one
// detection (source = the camera's name). What holds still in the view while the road moves (the
// own car's edges, its shadow) is not judged.
//
// Opt-in (dps-process --rear): on the tuning drives it finds more behind the car but adds more
// false detections than it finds (docs/detection.md, docs/experiments/detection-history.md).
#pragma once

#include <deque>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "dps/camera/ego_motion.h"
#include "dps/camera/rig.h"
#include "dps/detect/coverage.h"
#include "dps/detect/detection.h"
#include "dps/stereo/virtual_view.h"

namespace dps {

struct RearDetectorOptions {
  // The rear view: a pinhole view at the camera's viewpoint looking backwards on the camera's side,
  // its columns from `outer_deg` outward of straight back (where the side view's matched columns
  // end) to `inner_deg` inward of it (behind the own car), its rows from `up_deg` above the
  // horizon to `down_deg` below it. focal_px as the side views' (the omni image's resolution).
  double focal_px = 170.0;        // > 0
  double outer_deg = 45.0;        // (0, 80]
  double inner_deg = 10.0;        // [0, 45]
  double up_deg = 20.0;           // (0, 60]
  double down_deg = 40.0;         // (0, 80]
  double max_range_m = 20.0;      // contacts farther from the camera are dropped, > 0
  // Each pixel is judged against the two latest earlier frames (within `max_interval_s`) in which
  // the road at its distance has moved by at least `min_road_shift_windows` ZNCC windows in the
  // view, the second 1.5 times as far back as the first; without such frames it is not judged.
  double min_road_shift_windows = 0.5;  // > 0
  double max_interval_s = 0.6;          // > 0
  int window_px = 7;               // ZNCC window, odd, >= 3
  // A window correlating less than this with the road's prediction from both earlier frames is not
  // road.
  double max_road_zncc = 0.5;      // (-1, 1)
  // A window correlating at least this with the oldest earlier frame as it is (no warp) holds
  // still while the road moves: the own car (a mirror housing's edge, the body's flank) or
  // something keeping pace exactly; it is not judged.
  double min_still_zncc = 0.8;     // (-1, 1)
  // Windows whose grey-level standard deviation is under this many times the images' noise (the
  // frame's robust spread of current minus warped earlier) are not judged.
  double min_contrast_sigmas = 2.5;  // > 0
  double min_width_m = 0.3;            // > 0: narrower detections are dropped
  double max_contact_jump_m = 1.0;     // > 0: neighbouring contacts farther apart (and more than
                                       // two rows' depth) split a detection
  double own_car_height_m = 0.9;       // the own car's box (OwnCarMask), > 0

  // Throws dps::Error naming the field, its value and the violated constraint.
  void Check() const;
};

struct RearResult {
  bool skipped = false;  // no earlier frames far enough back (see reason)
  std::string reason;
  cv::Mat view;          // the current rear view (grey)
  cv::Mat warped;        // the nearest earlier frame's view warped onto it through the road (grey)
  cv::Mat obstacle;      // CV_8U over the view: 255 not road, 128 contact pixels
  double noise_sigma = 0.0;
  double baseline_m = 0.0;  // the camera's displacement to the nearer earlier frame
  Sector sector;
  std::vector<Detection> detections;  // source = the camera's name
};

// The rear view of a camera on the given side.
ViewSpec RearViewSpec(const Rig& rig, const std::string& camera, Side side, const RearDetectorOptions& options);

class RearDetector {
 public:
  RearDetector(const Rig& rig, const std::string& camera, Side side, const RearDetectorOptions& options);

  // One frame: the camera's omni image (grey) and the vehicle's motion since the previous call
  // (nullptr: unknown, which forgets the earlier frames).
  RearResult Detect(const cv::Mat& omni, const PlanarPose* current_in_previous, double t_s);

  const VirtualView& view() const { return view_; }

 private:
  struct Earlier {
    cv::Mat view;
    PlanarPose current_in_earlier;  // the current vehicle frame in that frame's
    double t_s = 0.0;
  };
  // The earlier view warped onto the current one through the road; `invalid` (CV_8U, 255) where
  // it has no source or its source is ignored.
  cv::Mat WarpEarlier(const Earlier& earlier, cv::Mat* invalid) const;

  RigCamera camera_;
  RearDetectorOptions options_;
  VirtualView view_;
  cv::Mat ignore_;      // CV_8U: own car or no source, dilated by half a window
  cv::Mat road_;        // CV_32FC3: each pixel's ray on the road (vehicle frame), NaN above the horizon
  cv::Mat rays_;        // CV_32FC3: each pixel's ray (vehicle frame, unit)
  double camera_height_m_ = 1.0;
  std::deque<Earlier> history_;  // most recent first
};

}  // namespace dps
