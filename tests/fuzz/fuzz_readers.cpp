// libFuzzer harnesses for dps's readers (-DDPS_FUZZ=ON with clang; scripts/fuzz.sh runs them).
// Built once per reader with DPS_FUZZ_READER set to its name; each input is written to a file (the
// readers take paths) and read. A reader may refuse an input only with dps::Error; anything else
// (a crash, a sanitizer report, another exception type, a hang) is a finding.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "dps/calib/marks_io.h"
#include "dps/camera/calibration_import.h"
#include "dps/camera/rig_io.h"
#include "dps/detect/detection_io.h"
#include "dps/map/tracks_io.h"
#include "dps/pipeline/drive_io.h"
#include "dps/stereo/disparity_io.h"
#include "dps/synth/scene_io.h"
#include "dps/synth/truth_io.h"
#include "dps/util/lanes_csv.h"
#include "dps/util/error.h"

namespace {

const std::string kReader = DPS_FUZZ_READER;

std::string InputPath() {
  static const std::string dir = [] {
    const auto d = std::filesystem::temp_directory_path() / ("dps_fuzz_" + kReader + "_" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    return d.string();
  }();
  const char* ext = kReader == "rig" || kReader == "scene" ? ".yaml" : kReader == "disparity" ? ".pfm"
                    : kReader == "ocam" ? ".txt" : ".csv";
  return dir + "/input" + ext;
}

void Read(const std::string& path) {
  if (kReader == "csv") {
    // Every CSV reader on the same bytes.
    try { dps::ReadCanLog(path); } catch (const dps::Error&) {}
    try { dps::ReadFrameTimes(path); } catch (const dps::Error&) {}
    try { dps::ReadDetections(path); } catch (const dps::Error&) {}
    try { dps::ReadTracks(path); } catch (const dps::Error&) {}
    try { dps::ReadTruth(path); } catch (const dps::Error&) {}
    try { dps::ReadLaneBoundaries(path); } catch (const dps::Error&) {}
    try { dps::ReadEgoLane(path); } catch (const dps::Error&) {}
  } else if (kReader == "marks") {
    dps::ReadMarks(path);
  } else if (kReader == "rig") {
    dps::ReadRig(path);
  } else if (kReader == "scene") {
    dps::ReadScene(path);
  } else if (kReader == "disparity") {
    dps::ReadDisparity(path);
  } else if (kReader == "ocam") {
    dps::ReadOCamCalibResults(path);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = InputPath();
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  try {
    Read(path);
  } catch (const dps::Error&) {
    // refused with a message: what a bad input should get
  }
  return 0;
}
