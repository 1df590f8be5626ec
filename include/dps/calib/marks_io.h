// dps — marks.csv (DESIGN.md §3.3): calibration marks as a file, columns camera,line,axis,u,v.
#pragma once

#include <string>
#include <vector>

#include "dps/calib/marks.h"

namespace dps {

// Reads marks.csv; throws dps::Error naming the file, the line and the column for missing
// columns, non-numeric values, a non-integer line id or an axis other than X, Y, Z.
std::vector<Mark> ReadMarks(const std::string& path);

// Writes marks.csv atomically.
void WriteMarks(const std::vector<Mark>& marks, const std::string& path);

}  // namespace dps
