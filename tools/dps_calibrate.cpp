// dps-calibrate: extrinsic rotations of the rig's cameras from vanishing points of marked lines.
#include <iostream>

#include "cli.h"
#include "dps/rig_io.h"
#include "dps/vanishing_points.h"

namespace {

const char* kUsage = R"(usage: dps-calibrate --rig rig.yaml --marks marks.csv --out rig_calibrated.yaml [options]

Estimates each marked camera's rotation R (camera -> vehicle) from points marked along straight
lines parallel to the vehicle's axes (Gandhi & Trivedi 2006, section IV): marks.csv has columns
camera,line,axis,u,v with axis X, Y or Z. Positions t and intrinsics come from rig.yaml and are
kept; the signs of the vanishing directions come from rig.yaml's (nominal) R. Prints per camera
each line's fit residual, the spread of each vanishing point, the orthogonality error before the
SVD fix and the change from the nominal rotation.

  --rig FILE             nominal rig (intrinsics, t, rough R)
  --marks FILE           marked points
  --out FILE             calibrated rig (written atomically)
  --drop-outliers        refit without lines whose residual is an outlier
  --outlier-factor F     outlier: residual > F x the median line residual (default 4)
  --help                 this text
)";

}  // namespace

int main(int argc, char** argv) {
  return dps_cli::Run("dps-calibrate", [&] {
    const dps_cli::Args args(argc, argv, {"rig", "marks", "out", "outlier-factor"}, {"drop-outliers"});
    if (args.help()) {
      std::cout << kUsage;
      return 0;
    }
    for (const char* required : {"rig", "marks", "out"}) {
      if (!args.Has(required)) throw dps::Error(std::string("missing --") + required + " (see --help)");
    }
    if (!args.positional().empty()) throw dps::Error("unexpected argument '" + args.positional()[0] + "'");
    dps::CalibrationOptions options;
    options.drop_outliers = args.Has("drop-outliers");
    options.outlier_factor = args.Number("outlier-factor", options.outlier_factor);
    const dps::Rig nominal = dps::ReadRig(args.Get("rig"));
    const std::vector<dps::Mark> marks = dps::ReadMarks(args.Get("marks"));
    std::vector<dps::CameraCalibration> results;
    const dps::Rig rig = dps::CalibrateRig(nominal, marks, options, args.Get("marks"), &results);
    if (results.empty()) throw dps::Error(args.Get("marks") + ": no marks");
    for (const dps::CameraCalibration& r : results) std::cout << dps::CalibrationReport(r);
    dps::WriteRig(rig, args.Get("out"));
    std::cout << "wrote " << args.Get("out") << "\n";
    return 0;
  });
}
