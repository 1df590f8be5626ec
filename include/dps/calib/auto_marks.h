// dps — calibration marks found automatically in one image of painted lines (beyond the paper:
// section IV has a person click points along the lines).
//
// Painted lines are narrow and brighter than the asphalt around them: a white top-hat (grey
// level above the local opening) picks them out, while asphalt texture, the sky and the own car
// stay below its threshold. Every paint pixel's ray, turned into the vehicle frame with the
// nominal rotation, meets the road; a rotation error of a few degrees maps a straight ground line
// to a straight line on the road plane (its rays span a plane through the camera centre), only
// turned and shifted a little. So the lines are found on the road plane: per axis a Hough
// transform over directions within max_angle_deg of the nominal axis and offsets, the strongest
// line first, its paint pixels removed, until no line has enough support. Lines through the
// camera's own footprint are radial — the ground image of something vertical (a pole), not a
// line on the road — and dropped. Each line's pixels become the marks of one line of marks.csv
// (DESIGN.md §3.3) with the axis of its family; CalibrateCamera then does the rest.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "dps/calib/marks.h"
#include "dps/camera/rig.h"

namespace dps {

// Settings in pixels are for images 640 px wide and scale with the image: the top-hat kernel with
// its width, pixel counts with its area (a line's paint pixels grow with both its length and its
// width in pixels); DetectMarks applies ScaledTo.
struct AutoMarkOptions {
  int tophat_px = 9;                // top-hat kernel diameter: paint narrower than this, odd >= 3
  double tophat_threshold = 40.0;   // grey levels above the local opening, > 0
  double max_range_m = 15.0;        // paint farther than this from the camera is not used, > 0
  double own_car_height_m = 0.9;    // the own car as a box this high (as OwnCarMask), >= 0
  double own_car_margin_m = 0.2;    // ... grown by this (the nominal R may be off), >= 0
  double max_angle_deg = 8.0;       // lines within this of the nominal axis directions, > 0
  double angle_step_deg = 0.2;      // Hough steps, > 0
  double offset_step_m = 0.05;
  double inlier_m = 0.15;           // road-plane distance of a paint pixel to its line, > 0
  int min_points = 80;              // paint pixels a line needs, >= 3 (at 640 px)
  double min_length_m = 2.0;        // ... spread along at least this, > 0
  double min_offset_m = 0.5;        // lines passing closer to the camera's footprint are radial
  int max_marks_per_line = 300;     // pixels written per line (evenly along it), >= 3

  // Throws dps::Error naming the field and the violated constraint.
  void Check() const;
  // These settings for images `width` px wide (tophat_px odd and >= 3, min_points >= 3).
  AutoMarkOptions ScaledTo(int width) const;
};

// One line found: its axis family, support and extent, and how well its rays fit a great circle.
struct AutoMarkLine {
  int line = 0;
  char axis = 'Z';
  int pixels = 0;
  double length_m = 0.0;            // along the line on the road plane (nominal geometry)
  double great_circle_rms_deg = 0.0;
};

// The marks of `camera` (a rig camera; `image` its picture of painted lines along the vehicle's
// X and Z axes on a flat road), numbered from first_line. `lines` (optional) receives what was
// found. Throws dps::Error for an unknown camera or an image whose size differs from the model's.
std::vector<Mark> DetectMarks(const cv::Mat& image, const Rig& nominal, const std::string& camera,
                              const AutoMarkOptions& options = AutoMarkOptions(), int first_line = 0,
                              std::vector<AutoMarkLine>* lines = nullptr);

// The image with its marks drawn (Z lines green, X lines red, Y blue) and numbered, for a person
// to check what DetectMarks found (or what someone clicked).
cv::Mat DrawMarks(const cv::Mat& image, const std::vector<Mark>& marks);

}  // namespace dps
