// dps — truth.csv (DESIGN.md §3.6): ground truth of synthetic or annotated drives as a file.
#pragma once

#include <string>
#include <vector>

#include "dps/synth/truth.h"

namespace dps {

// truth.csv, written atomically / read by column name. Throw dps::Error naming file and line.
void WriteTruth(const std::vector<TruthRow>& rows, const std::string& path);
std::vector<TruthRow> ReadTruth(const std::string& path);

}  // namespace dps
