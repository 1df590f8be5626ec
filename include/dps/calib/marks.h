// dps — calibration marks (DESIGN.md §3.3): points marked along straight world lines.
#pragma once

#include <string>

namespace dps {

// One manually (or automatically) marked point on a straight world line.
struct Mark {
  std::string camera;  // a camera name from the rig
  int line = 0;        // groups the points of one straight world line
  char axis = 'Z';     // 'X', 'Y' or 'Z': the vehicle axis the line is parallel to
  double u = 0.0;      // pixel, sub-pixel allowed
  double v = 0.0;
  int file_line = 0;   // line number in marks.csv (0 when not read from a file)
};

}  // namespace dps
