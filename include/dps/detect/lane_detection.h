// dps — lane markings beside the car and the ego's lateral position (the DPS map's lanes and LP,
// seed 000 Fig. 1). Both cameras look down at the road beside the car, the best view of the
// markings any camera on the car has: each frame the road around the car is resampled into a
// bird's-eye view (each ground cell from the camera on its side, else the other; never where the
// own car hides the road or outside the cameras' valid pixels); bright stripes between
// min_marking_width_m and max_marking_width_m wide are marking evidence; straight lines x = offset
// + tan(heading) z through it (offsets every cell, headings up to max_heading_deg) are voted for,
// one vote per bird's-eye row, and the lines whose votes cover min_support of the rows where they
// are seen, refined by least squares on their evidence, are candidates. Boundaries are parallel (a
// line turned away from the frame's heading is an upright edge of an object, which points at the
// camera) and a lane apart (of two lines closer, the one with less evidence is none); of those left
// the nearest on each side of the car is the ego lane's (left, right), the next beyond at least
// min_lane_width_m out its neighbour's (left2, right2). A boundary is solid when its evidence
// covers solid_support of its rows. From left and right: the lateral position (lp), the lane's
// width and the heading; a jump of lp by more than half a lane is a lane change (a "lane" wider
// than twice min_lane_width_m is two, the line between them missed, and one narrower than
// min_lane_width_m across is none, one of its lines no boundary: no lp then).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "dps/camera/rig.h"
#include "dps/util/lanes_csv.h"

namespace dps {

struct LaneDetectorOptions {
  double cell_m = 0.05;              // bird's-eye cell, > 0
  double lateral_m = 7.0;            // the view reaches this far left and right, > 0
  double behind_m = 4.0;             // ... this far behind the vehicle origin and
  double ahead_m = 10.0;             //     this far ahead, > 0
  double min_marking_width_m = 0.08;  // stripes of this width ...
  double max_marking_width_m = 0.3;   // ... up to this, > min
  double max_heading_deg = 40.0;     // lines turned further from the car's axis are not sought, 0..60
  // A frame's boundaries are parallel: a line turned further than this from the heading that most
  // of the frame's evidence agrees on is none (an object's upright edge seen on the road, which
  // points at the camera). Straight fits of parallel lines on a 50 m radius seen over different
  // stretches of the view differ by up to 4 degrees; deg, > 0.
  double max_heading_spread_deg = 8.0;
  double min_support = 0.15;         // share of its seen rows a boundary's evidence must cover, 0..1
  double solid_support = 0.6;        // ... and a solid line's, 0..1
  double min_lane_width_m = 2.5;     // the neighbour's outer boundary at least this beyond, > 0
  double own_car_height_m = 1.0;     // ground hidden by the rig's vehicle box this high is not used

  // Throws dps::Error naming the field, its value and the violated constraint.
  void Check() const;
};

// Where along the car (the vehicle frame's Z, m) a line's evidence lies: from near_m to far_m.
// Its offset and heading are extrapolated from there to the car's axis (near_m = far_m = 0: seen
// at the axis).
struct LaneStretch {
  double near_m = 0.0, far_m = 0.0;
  double Middle() const { return (near_m + far_m) / 2; }
  double Length() const { return far_m - near_m; }
};

// One frame's lanes (frame and t left 0: the caller's).
struct LaneFrame {
  std::vector<LaneBoundaryRow> boundaries;
  std::vector<LaneStretch> seen;  // per boundary where it was seen (empty: each at the car's axis)
  bool has_ego = false;  // both of the ego lane's boundaries found
  EgoLaneRow ego;
};

// A straight boundary near the car: x = offset + slope z in the vehicle frame, solid or dashed,
// with a confidence 0..1.
struct LaneLine {
  double offset_m = 0.0, slope = 0.0;
  std::string type = "dashed";
  double confidence = 1.0;
  LaneStretch seen{};
};

// Which of a frame's lines (slopes: tan of their headings) are parallel to the frame's heading:
// within max_spread_deg of the line whose lines within max_spread_deg of it weigh the most (weights:
// their evidence; at equal weight the earlier line's).
std::vector<bool> ParallelLines(const std::vector<double>& slopes, const std::vector<double>& weights,
                                double max_spread_deg);

// A frame's lanes from its lines: a line less confident than another one closer to it than
// min_lane_width_m across is none (two boundaries lie a lane apart: e.g. a line the car straddles,
// measured where a camera sees a little of it, with a wrong heading, next to where it is known to
// be); of the others, the nearest on each side of the car are the ego lane's (left,
// right), the next beyond at least min_lane_width_m out its neighbours' (left2, right2). No lane is
// wider than twice min_lane_width_m and the car is inside its own: when the nearest lines on the
// two sides lie farther apart than that (the ego lane's line on one side missed), the one farther
// from the car is not the ego lane's, and neither is a line farther than that from the car; the
// first line beyond twice min_lane_width_m from the other side's boundary is then the
// neighbour's. The ego's lp, lane width and heading from left and right (none when the lane is
// narrower than min_lane_width_m across: one of them is no boundary); a jump of lp from
// *previous_lp by more than half a lane is a lane change (event); *previous_lp then becomes lp.
LaneFrame NameLaneLines(const std::vector<LaneLine>& lines, double min_lane_width_m,
                        std::optional<double>* previous_lp);

class LaneDetector {
 public:
  // The rig's cameras (their masks, if any, limit the pixels); the views' tables are built here.
  LaneDetector(const Rig& rig, const LaneDetectorOptions& options = {});

  // Both cameras' grey images of one frame (the rig's cameras named left and right, else the first
  // two); lane changes are judged against the previous call's lateral position.
  LaneFrame Detect(const cv::Mat& left_grey, const cv::Mat& right_grey);

 private:
  LaneDetectorOptions options_;
  int width_ = 0, height_ = 0;  // bird's-eye cells across and along
  cv::Mat map_[2], fraction_[2];  // per camera: each cell's image pixel (remap's fixed point; -1: not seen)
  cv::Mat use_[2];              // CV_8U: the cells taken from that camera
  cv::Rect used_[2];            // ... and their bounding box (the part of the view resampled from it)
  cv::Mat valid_;               // CV_8U: the cells either camera gives
  std::vector<double> slopes_;  // the lines' slopes sought (tan of their headings)
  std::vector<int> shift_;      // per row and slope: the offset cell a cell votes for, less its column
  std::optional<double> previous_lp_;
};

}  // namespace dps
