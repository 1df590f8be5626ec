// dps — calibration marks (DESIGN.md §3.3): marks.csv with columns camera,line,axis,u,v.
#pragma once

#include <string>
#include <vector>

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

// Reads marks.csv; throws dps::Error naming the file, the line and the column for missing
// columns, non-numeric values, a non-integer line id or an axis other than X, Y, Z.
std::vector<Mark> ReadMarks(const std::string& path);

// Writes marks.csv atomically.
void WriteMarks(const std::vector<Mark>& marks, const std::string& path);

}  // namespace dps
