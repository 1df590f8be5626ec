// dps-calibrate: extrinsic rotations of the rig's cameras from vanishing points of marked lines.
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>
#include <utility>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "cli.h"
#include "dps/calib/auto_marks.h"
#include "dps/calib/marks_io.h"
#include "dps/calib/vanishing_points.h"
#include "dps/camera/rig_io.h"

namespace {

const char* kUsage = R"(usage: dps-calibrate --rig rig.yaml --marks marks.csv --out rig_calibrated.yaml [options]
       dps-calibrate --rig rig.yaml --images left=left.png,right=right.png --out rig_calibrated.yaml [options]

Estimates each marked camera's rotation R (camera -> vehicle) from points marked along straight
lines parallel to the vehicle's axes (Gandhi & Trivedi 2006, section IV): marks.csv has columns
camera,line,axis,u,v with axis X, Y or Z. Positions t and intrinsics come from rig.yaml and are
kept; the signs of the vanishing directions come from rig.yaml's (nominal) R. Prints per camera
each line's fit residual, the spread of each vanishing point, the orthogonality error before the
SVD fix and the change from the nominal rotation.

With --images instead of --marks the marks are found automatically: one image per camera of
painted lines along the vehicle's X and Z axes on a flat road (a parking lot), the nominal R
within a few degrees (docs/calibration.md).

  --rig FILE             nominal rig (intrinsics, t, rough R)
  --marks FILE           marked points
  --images LIST          CAMERA=IMAGE[,CAMERA=IMAGE...]: find the marks in these images
  --write-marks FILE     write the marks found in --images (to check, edit, reuse with --marks)
  --draw DIR             write DIR/<camera>_marks.png: each image with its marks drawn
  --out FILE             calibrated rig (written atomically)
  --drop-outliers        refit without lines whose residual is an outlier
  --outlier-factor F     outlier: residual > F x the median line residual (default 4)
  --help                 this text
)";

}  // namespace

int main(int argc, char** argv) {
  return dps_cli::Run("dps-calibrate", [&] {
    const dps_cli::Args args(argc, argv, {"rig", "marks", "images", "write-marks", "draw", "out", "outlier-factor"},
                              {"drop-outliers"});
    if (args.help()) {
      std::cout << kUsage;
      return 0;
    }
    args.Require("rig");
    args.Require("out");
    if (args.Has("marks") == args.Has("images")) throw dps::Error("give either --marks or --images (see --help)");
    if (args.Has("write-marks") && !args.Has("images")) throw dps::Error("--write-marks needs --images");
    if (!args.positional().empty()) throw dps::Error("unexpected argument '" + args.positional()[0] + "'");
    dps::CalibrationOptions options;
    options.drop_outliers = args.Has("drop-outliers");
    options.outlier_factor = args.Number("outlier-factor", options.outlier_factor);
    const dps::Rig nominal = dps::ReadRig(args.Get("rig"));
    std::vector<dps::Mark> marks;
    std::map<std::string, cv::Mat> images;
    std::string source = args.Get("marks");
    if (args.Has("marks")) {
      marks = dps::ReadMarks(source);
    } else {
      source = "--images";
      for (const auto& [camera, path] : args.Pairs("images", "IMAGE")) {
        if (!std::filesystem::is_regular_file(path)) throw dps::Error(path + ": cannot read the image (no such file)");
        const cv::Mat image = cv::imread(path, cv::IMREAD_COLOR);
        if (image.empty()) throw dps::Error(path + ": cannot read the image");
        std::vector<dps::AutoMarkLine> lines;
        std::vector<dps::Mark> found;
        try {
          found = dps::DetectMarks(image, nominal, camera, dps::AutoMarkOptions(),
                                   marks.empty() ? 0 : marks.back().line + 1, &lines);
        } catch (const dps::Error& e) {
          throw dps::Error(path + ": " + e.what());
        }
        std::cout << camera << ": " << path << ": " << lines.size() << " painted lines found\n";
        for (const dps::AutoMarkLine& l : lines) {
          std::cout << "  line " << l.line << " axis " << l.axis << ": " << l.pixels << " pixels over " << std::fixed
                    << std::setprecision(1) << l.length_m << " m, great-circle rms " << std::setprecision(3)
                    << l.great_circle_rms_deg << " deg\n";
        }
        marks.insert(marks.end(), found.begin(), found.end());
        images[camera] = image;
      }
      if (args.Has("write-marks")) {
        dps::WriteMarks(marks, args.Get("write-marks"));
        std::cout << "wrote " << args.Get("write-marks") << "\n";
      }
      if (args.Has("draw")) {
        std::filesystem::create_directories(args.Get("draw"));
        for (const auto& [camera, image] : images) {
          std::vector<dps::Mark> own;
          for (const dps::Mark& m : marks) {
            if (m.camera == camera) own.push_back(m);
          }
          const std::string path = (std::filesystem::path(args.Get("draw")) / (camera + "_marks.png")).string();
          if (!cv::imwrite(path, dps::DrawMarks(image, own))) throw dps::Error(path + ": cannot write");
          std::cout << "wrote " << path << "\n";
        }
      }
    }
    std::vector<dps::CameraCalibration> results;
    const dps::Rig rig = dps::CalibrateRig(nominal, marks, options, source, &results);
    if (results.empty()) throw dps::Error(source + ": no marks");
    for (const dps::CameraCalibration& r : results) std::cout << dps::CalibrationReport(r);
    dps::WriteRig(rig, args.Get("out"));
    std::cout << "wrote " << args.Get("out") << "\n";
    return 0;
  });
}
