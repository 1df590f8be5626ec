// dps — tracks.csv (DESIGN.md §3.5): the tracker's confirmed tracks as a file.
#pragma once

#include <string>
#include <vector>

#include "dps/map/tracker.h"

namespace dps {

// tracks.csv (DESIGN.md §3.5) for the confirmed tracks, written atomically, with the extra columns
// length, width (TrackState); read back by column name (length and width optional; throws
// dps::Error naming the file, line and column).
void WriteTracks(const std::vector<TrackState>& tracks, const std::string& path);
std::vector<TrackState> ReadTracks(const std::string& path);

}  // namespace dps
