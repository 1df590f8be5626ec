// dps — detections.csv (DESIGN.md §3.4): the pipeline's per-frame detections as a file.
#pragma once

#include <string>
#include <vector>

#include "dps/detect/detection.h"

namespace dps {

// detections.csv: header and one row per detection, written atomically. Throws dps::Error.
void WriteDetections(const std::vector<Detection>& detections, const std::string& path);
// Reads detections.csv (columns by name, extra columns ignored). Throws dps::Error naming the
// file, line and column.
std::vector<Detection> ReadDetections(const std::string& path);

}  // namespace dps
