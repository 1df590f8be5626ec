// dps-sweep as a user runs it on a drive: the picture and the distances of each camera, the road's
// distances where the road plane is (truth from the rig's geometry), and bad requests refused
// with a one-line reason.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "check.h"
#include "dps/camera/rig_io.h"
#include "dps/stereo/disparity_io.h"

namespace fs = std::filesystem;

namespace {

const fs::path kTools = DPS_TOOLS_DIR;
const fs::path kWork = fs::temp_directory_path() / ("dps_sweep_tool_" + std::to_string(::getpid()));

// Runs a command; its exit status, and its stderr in *err.
int Run(const std::string& command, std::string* err = nullptr) {
  const fs::path e = kWork / "stderr.txt";
  const int status = std::system((command + " > /dev/null 2> '" + e.string() + "'").c_str());
  if (err) {
    std::ifstream f(e);
    *err = std::string(std::istreambuf_iterator<char>(f), {});
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace

int main() {
  fs::create_directories(kWork);
  const fs::path drive = kWork / "d", out = kWork / "out";
  CHECK_EQ(Run((kTools / "dps-synth").string() + " " + DPS_SOURCE_DIR + "/data/scenes/parked_cars.yaml --size 320x240 --frames 8 --out '" +
               drive.string() + "' --quiet"),
           0);
  const std::string sweep = (kTools / "dps-sweep").string() + " '" + drive.string() + "'";
  CHECK_EQ(Run(sweep + " --frame 7 --back 2 --out '" + out.string() + "'"), 0);
  const dps::Rig rig = dps::ReadRig((drive / "rig.yaml").string());
  for (const dps::RigCamera& camera : rig.cameras) {
    const cv::Mat picture = cv::imread((out / (camera.name + "_sweep.png")).string(), cv::IMREAD_COLOR);
    CHECK_EQ(picture.cols, camera.model.width());
    CHECK_EQ(picture.rows, camera.model.height());
    const cv::Mat distance = dps::ReadDisparity((out / (camera.name + "_distance.pfm")).string());
    CHECK_EQ(distance.cols, camera.model.width());
    CHECK_EQ(distance.rows, camera.model.height());
    // The road 2-6 m from the camera (no object there: the parked cars stand beyond the verge on
    // one side, the road is empty on the other): where the sweep gave a distance, it is the
    // distance to the road plane along the pixel's ray in most pixels.
    std::vector<double> errors;
    int road_pixels = 0;
    const Eigen::Vector3d t = camera.vehicle_from_camera.t;
    for (int y = 0; y < distance.rows; y += 2) {
      for (int x = 0; x < distance.cols; x += 2) {
        Eigen::Vector3d ray;
        if (!camera.model.Unproject({x, y}, &ray)) continue;
        const Eigen::Vector3d r = camera.vehicle_from_camera.R * ray;
        if (r.y() <= 0.05) continue;
        const double s = -t.y() / r.y();
        const Eigen::Vector3d ground = t + s * r;
        // Beside the camera on the side away from the car, within the lane next to it.
        if (s < 2.0 || s > 6.0 || std::abs(ground.x()) > 3.0 || std::abs(ground.x()) < std::abs(t.x()) + 0.5) continue;
        ++road_pixels;
        const float d = distance.at<float>(y, x);
        if (std::isfinite(d)) errors.push_back(std::abs(d - s) / s);
      }
    }
    std::sort(errors.begin(), errors.end());
    const double median = errors.empty() ? 1.0 : errors[errors.size() / 2];
    std::printf("dps-sweep %s: %zu of %d road pixels 2-6 m out with a distance, median error %.3f\n", camera.name.c_str(),
                errors.size(), road_pixels, median);
    CHECK(road_pixels > 200);
    CHECK(errors.size() * 5 >= static_cast<size_t>(road_pixels));
    CHECK(median < 0.05);
  }
  // Bad requests: one line naming the problem, no output.
  std::string err;
  CHECK(Run(sweep + " --frame 0 --out '" + (kWork / "bad").string() + "'", &err) != 0);
  CHECK(err.find("frame - back >= 0") != std::string::npos);
  CHECK(Run(sweep + " --frame 99 --out '" + (kWork / "bad").string() + "'", &err) != 0);
  CHECK(err.find("frames.csv: lists 8 frames, no frame 99") != std::string::npos);
  CHECK(Run(sweep + " --frame 3 --camera middle --out '" + (kWork / "bad").string() + "'", &err) != 0);
  CHECK(err.find("no camera 'middle'") != std::string::npos);
  CHECK(!fs::exists(kWork / "bad"));
  CHECK_EQ(Run((kTools / "dps-sweep").string() + " --help"), 0);
  fs::remove_all(kWork);
  return dps_test::Report();
}
