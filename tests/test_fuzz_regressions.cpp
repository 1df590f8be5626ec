// Inputs that fuzzing found (tests/fuzz/regressions/<reader>/, scripts/fuzz.sh): each read by its
// reader in the ordinary build must be refused with dps::Error (one line naming the file), never
// crash or throw anything else.
#include <filesystem>
#include <string>

#include "check.h"
#include "dps/calib/marks_io.h"
#include "dps/camera/calibration_import.h"
#include "dps/camera/rig_io.h"
#include "dps/pipeline/drive_io.h"
#include "dps/stereo/disparity_io.h"
#include "dps/synth/scene_io.h"
#include "dps/util/error.h"

namespace fs = std::filesystem;

namespace {

void Read(const std::string& reader, const std::string& path) {
  if (reader == "rig") dps::ReadRig(path);
  else if (reader == "scene") dps::ReadScene(path);
  else if (reader == "marks") dps::ReadMarks(path);
  else if (reader == "disparity") dps::ReadDisparity(path);
  else if (reader == "ocam") dps::ReadOCamCalibResults(path);
  else if (reader == "csv") dps::ReadCanLog(path);
}

}  // namespace

int main() {
  int inputs = 0;
  for (const auto& dir : fs::directory_iterator(fs::path(DPS_SOURCE_DIR) / "tests" / "fuzz" / "regressions")) {
    for (const auto& file : fs::directory_iterator(dir.path())) {
      ++inputs;
      const std::string reader = dir.path().filename().string(), path = file.path().string();
      std::string message;
      try {
        Read(reader, path);
      } catch (const dps::Error& e) {
        message = e.what();
      } catch (const std::exception& e) {
        std::fprintf(stderr, "%s: %s threw %s\n", reader.c_str(), path.c_str(), e.what());
        CHECK(false);
        continue;
      }
      std::printf("%s: %s\n", reader.c_str(), message.c_str());
      CHECK(message.find(file.path().filename().string()) != std::string::npos);  // refused, naming the file
      CHECK(message.find('\n') == std::string::npos);
    }
  }
  CHECK(inputs >= 1);
  return dps_test::Report();
}
