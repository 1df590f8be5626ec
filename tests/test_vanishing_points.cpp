// Tests of extrinsic calibration from vanishing points (paper section IV): the SVD steps on exact
// inputs, accuracy on dps-synth calibration scenes over many random rigs (exact and 0.5 px
// marks), outlier flagging, and the errors users meet.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include <Eigen/Geometry>

#include "check.h"
#include "dps/calib/marks_io.h"
#include "dps/calib/vanishing_points.h"
#include "dps/synth/scene_io.h"
#include "dps/synth/synth.h"
#include "dps/util/error.h"

namespace {

namespace fs = std::filesystem;

constexpr double kExactTolDeg = 0.01;        // issue: exact marks
constexpr double kNoisyMedianTolDeg = 0.3;   // issue: 0.5 px marks, median over rigs
constexpr int kRigs = 12;
constexpr double kMaxVerticalDisparityPx = 1.0;  // rectified front pair, median RMS

const std::string kScenes = std::string(DPS_SOURCE_DIR) + "/data/scenes/";
const fs::path kTmp = fs::temp_directory_path() / "dps_test_vanishing_points";

void TestSvdSteps() {
  // Rays on the great circle with normal n, plus the circle fit.
  const Eigen::Vector3d n = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
  const Eigen::Vector3d a = n.unitOrthogonal(), b = n.cross(a);
  std::vector<Eigen::Vector3d> rays;
  for (double t = 0.1; t < 2.0; t += 0.2) rays.push_back(std::cos(t) * a + std::sin(t) * b);
  double rms = 1;
  const Eigen::Vector3d l = dps::FitGreatCircle(rays, &rms);
  CHECK_NEAR(std::abs(l.dot(n)), 1.0, 1e-12);
  CHECK_NEAR(rms, 0.0, 1e-12);
  // Great circles through a common direction d meet there.
  const Eigen::Vector3d d = Eigen::Vector3d(-0.2, 0.9, 0.1).normalized();
  std::vector<Eigen::Vector3d> normals;
  for (double phi : {0.1, 0.9, 2.0}) {
    normals.push_back(std::cos(phi) * d.unitOrthogonal() + std::sin(phi) * d.cross(d.unitOrthogonal()));
  }
  Eigen::Vector3d sv;
  const Eigen::Vector3d m = dps::VanishingDirection(normals, &sv);
  CHECK_NEAR(std::abs(m.dot(d)), 1.0, 1e-12);
  CHECK(sv(2) < 1e-7 && sv(1) > 0.1);  // from M M^T's squares: zero to within sqrt(machine epsilon)
  // Nearest rotation: a rotation is its own nearest; a perturbed one becomes orthonormal.
  const Eigen::Matrix3d R = dps::AxisAngle({1, 2, 3}, 0.7);
  CHECK_NEAR((dps::NearestRotation(R) - R).norm(), 0.0, 1e-12);
  Eigen::Matrix3d P = R;
  P(0, 1) += 0.01;
  P(2, 2) -= 0.02;
  const Eigen::Matrix3d Q = dps::NearestRotation(P);
  CHECK(dps::RotationProblem(Q, 1e-12).empty());
  CHECK(dps::RotationAngleDeg(Q, R) < 1.0);
  CHECK(dps::RotationProblem(dps::NearestRotation(-R), 1e-12).empty());  // det -1 input
}

struct Setup {
  dps::Scene nominal;
  dps::Rig truth;
  std::vector<dps::Mark> exact, noisy;
};

Setup MakeSetup(std::uint64_t seed) {
  Setup s;
  s.nominal = dps::ReadScene(kScenes + "calibration.yaml");
  s.nominal.seed = seed;
  dps::Scene scene = s.nominal;
  scene.rig = dps::PerturbedRig(s.nominal);
  s.truth = scene.rig;
  const dps::SceneRenderer renderer(scene);
  const dps::FrameState st = renderer.StateAt(0.0);
  s.exact = dps::SampleMarks(renderer, st, 0.0);
  s.noisy = dps::SampleMarks(renderer, st, scene.calibration.mark_noise_px);
  return s;
}

// The residual vertical disparity of a rectified front pair (a virtual pinhole view looking along
// +Z, rows parallel to the baseline, focal length f_px) built with estimated rotations: a world
// point is seen by each true camera and mapped into the view through the estimated rotation;
// the rows of the two views then disagree. Returns the RMS over points 8-30 m ahead.
double FrontViewVerticalDisparityPx(const dps::Rig& estimate, const dps::Rig& truth, double f_px) {
  auto row = [&](const std::string& name, const Eigen::Vector3d& p) {
    const dps::RigCamera& t = truth.Camera(name);
    const dps::RigCamera& e = estimate.Camera(name);
    // The true ray to p in the camera frame, turned into the vehicle frame with the estimate.
    const Eigen::Vector3d ray = t.vehicle_from_camera.R.transpose() * (p - t.vehicle_from_camera.t);
    const Eigen::Vector3d d = e.vehicle_from_camera.R * ray;
    return f_px * d.y() / d.z();
  };
  double ss = 0;
  int n = 0;
  for (double x = -6; x <= 6; x += 1.5) {
    for (double y = -2.0; y <= 0.0; y += 0.5) {
      for (double z = 8; z <= 30; z += 2) {
        const double dv = row("left", {x, y, z}) - row("right", {x, y, z});
        ss += dv * dv;
        ++n;
      }
    }
  }
  return std::sqrt(ss / n);
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

void TestAccuracy() {
  std::vector<double> exact_err, noisy_err, noisy_no_poles, nominal_err, vdisp_px, vdisp_nominal_px;
  for (int seed = 1; seed <= kRigs; ++seed) {
    const Setup s = MakeSetup(seed);
    const dps::CalibrationOptions options;
    // A front view of about the omni image's own resolution near the horizon (f = 170 px at
    // 640x480).
    vdisp_px.push_back(FrontViewVerticalDisparityPx(
        dps::CalibrateRig(s.nominal.rig, s.noisy, options, "noisy"), s.truth, 170.0));
    vdisp_nominal_px.push_back(FrontViewVerticalDisparityPx(s.nominal.rig, s.truth, 170.0));
    std::vector<dps::CameraCalibration> results;
    for (const dps::RigCamera& c : s.truth.cameras) {
      exact_err.push_back(dps::RotationAngleDeg(
          dps::CalibrateRig(s.nominal.rig, s.exact, options, "exact").Camera(c.name).vehicle_from_camera.R,
          c.vehicle_from_camera.R));
      noisy_err.push_back(dps::RotationAngleDeg(
          dps::CalibrateRig(s.nominal.rig, s.noisy, options, "noisy").Camera(c.name).vehicle_from_camera.R,
          c.vehicle_from_camera.R));
      std::vector<dps::Mark> no_poles;
      for (const dps::Mark& m : s.noisy) {
        if (m.axis != 'Y') no_poles.push_back(m);
      }
      noisy_no_poles.push_back(dps::RotationAngleDeg(
          dps::CalibrateRig(s.nominal.rig, no_poles, options, "noisy").Camera(c.name).vehicle_from_camera.R,
          c.vehicle_from_camera.R));
      nominal_err.push_back(dps::RotationAngleDeg(s.nominal.rig.Camera(c.name).vehicle_from_camera.R,
                                                  c.vehicle_from_camera.R));
    }
  }
  const double exact_max = *std::max_element(exact_err.begin(), exact_err.end());
  std::printf("calibration over %d rigs x 2 cameras: nominal error median %.3f deg; exact marks max "
              "%.5f deg; 0.5 px marks median %.3f deg (max %.3f); without poles median %.3f deg\n",
              kRigs, Median(nominal_err), exact_max, Median(noisy_err),
              *std::max_element(noisy_err.begin(), noisy_err.end()), Median(noisy_no_poles));
  std::printf("front view (f = 170 px) residual vertical disparity, RMS: calibrated median %.2f px "
              "(max %.2f), nominal rig median %.2f px\n",
              Median(vdisp_px), *std::max_element(vdisp_px.begin(), vdisp_px.end()),
              Median(vdisp_nominal_px));
  CHECK(Median(vdisp_px) < kMaxVerticalDisparityPx);
  CHECK(Median(nominal_err) > 1.0);  // the nominal rig really was off by 1-3 degrees
  CHECK(exact_max <= kExactTolDeg);
  CHECK(Median(noisy_err) <= kNoisyMedianTolDeg);
  CHECK(Median(noisy_no_poles) <= kNoisyMedianTolDeg);
}

void TestOutliers() {
  Setup s = MakeSetup(3);
  // A mis-typed line id: three points of line 9 of the left camera typed as line 7.
  int moved = 0;
  for (dps::Mark& m : s.noisy) {
    if (m.camera == "left" && m.line == 9 && moved < 3) {
      m.line = 7;
      ++moved;
    }
  }
  CHECK_EQ(moved, 3);
  dps::CalibrationOptions options;
  std::vector<dps::CameraCalibration> kept;
  const dps::Rig with = dps::CalibrateRig(s.nominal.rig, s.noisy, options, "marks", &kept);
  bool flagged = false;
  int flagged_lines = 0;
  for (const dps::LineFit& f : kept[0].lines) {
    flagged |= f.line == 7 && f.outlier;
    flagged_lines += f.outlier;
  }
  CHECK(flagged);
  CHECK_EQ(flagged_lines, 1);
  CHECK(dps::CalibrationReport(kept[0]).find("OUTLIER") != std::string::npos);
  options.drop_outliers = true;
  std::vector<dps::CameraCalibration> dropped;
  const dps::Rig without = dps::CalibrateRig(s.nominal.rig, s.noisy, options, "marks", &dropped);
  const double err_with = dps::RotationAngleDeg(with.Camera("left").vehicle_from_camera.R,
                                                s.truth.Camera("left").vehicle_from_camera.R);
  const double err_without = dps::RotationAngleDeg(without.Camera("left").vehicle_from_camera.R,
                                                   s.truth.Camera("left").vehicle_from_camera.R);
  std::printf("mis-typed line: error %.3f deg kept, %.3f deg dropped\n", err_with, err_without);
  CHECK(err_without <= kNoisyMedianTolDeg);
  CHECK(err_without < err_with);
}

void TestErrors() {
  const Setup s = MakeSetup(1);
  const dps::CalibrationOptions options;
  const dps::CameraModel& model = s.nominal.rig.Camera("left").model;
  const Eigen::Matrix3d R = s.nominal.rig.Camera("left").vehicle_from_camera.R;
  std::vector<dps::Mark> left;
  for (const dps::Mark& m : s.exact) {
    if (m.camera == "left") left.push_back(m);
  }
  auto first_of = [&](char axis) {
    for (const dps::Mark& m : left) {
      if (m.axis == axis) return m.line;
    }
    return -1;
  };
  auto only = [&](auto keep) {
    std::vector<dps::Mark> out;
    for (const dps::Mark& m : left) {
      if (keep(m)) out.push_back(m);
    }
    return out;
  };
  // A line with 2 points.
  const int z_line = first_of('Z');
  int count = 0;
  auto two = only([&](const dps::Mark& m) { return m.line != z_line || count++ < 2; });
  CHECK_THROWS_WITH(dps::CalibrateCamera("left", model, R, two, options, "m.csv"), dps::Error,
                    "has 2 point(s)");
  // Outside the image, and beyond the rim.
  auto outside = left;
  outside[5].u = 700;
  CHECK_THROWS_WITH(dps::CalibrateCamera("left", model, R, outside, options, "m.csv"), dps::Error,
                    "outside the 640x480 image");
  auto no_ray = left;
  no_ray[5].u = 5;
  no_ray[5].v = 5;
  CHECK_THROWS_WITH(dps::CalibrateCamera("left", model, R, no_ray, options, "m.csv"), dps::Error,
                    "has no ray");
  // Only one axis.
  CHECK_THROWS_WITH(dps::CalibrateCamera("left", model, R, only([](const dps::Mark& m) { return m.axis == 'Z'; }),
                                         options, "m.csv"),
                    dps::Error, "at least 2 lines are needed");
  // Degenerate: the Z lines are copies of one line under different ids.
  std::vector<dps::Mark> degenerate = only([](const dps::Mark& m) { return m.axis == 'X'; });
  for (const dps::Mark& m : left) {
    if (m.line == z_line) {
      for (int copy = 0; copy < 3; ++copy) {
        dps::Mark c = m;
        c.line = 500 + copy;
        c.u += 0.01 * copy;
        degenerate.push_back(c);
      }
    }
  }
  CHECK_THROWS_WITH(dps::CalibrateCamera("left", model, R, degenerate, options, "m.csv"), dps::Error,
                    "nearly the same great circle");
  // One line with two axes.
  auto mixed = left;
  for (dps::Mark& m : mixed) {
    if (m.line == z_line) {
      m.axis = 'X';
      break;
    }
  }
  CHECK_THROWS_WITH(dps::CalibrateCamera("left", model, R, mixed, options, "m.csv"), dps::Error,
                    "is marked with axis");
  // Unknown camera.
  auto rear = s.exact;
  rear[0].camera = "rear";
  CHECK_THROWS_WITH(dps::CalibrateRig(s.nominal.rig, rear, options, "m.csv"), dps::Error,
                    "unknown camera 'rear'");
  // Files: missing columns, bad axis, bad numbers.
  fs::create_directories(kTmp);
  const std::vector<std::pair<std::string, std::string>> files = {
      {"camera,line,u,v\nleft,1,10,10\n", "missing column 'axis'"},
      {"camera,line,axis,u,v\nleft,1,W,10,10\n", "column 'axis': expected X, Y or Z"},
      {"camera,line,axis,u,v\nleft,1,X,ten,10\n", ":2: column 'u': 'ten' is not a number"},
      {"camera,line,axis,u,v\nleft,1.5,X,10,10\n", "column 'line': '1.5' is not a whole number"},
      {"camera,line,axis,u,v\nleft,1e300,X,10,10\n", ":2: column 'line': '1e300' is not a whole number in range"},
      {"camera,line,axis,u,v\nleft,1,X,10\n", ":2: 4 fields, the header has 5"},
  };
  int i = 0;
  for (const auto& [text, needle] : files) {
    const fs::path p = kTmp / ("marks" + std::to_string(i++) + ".csv");
    std::ofstream(p) << text;
    CHECK_THROWS_WITH(dps::ReadMarks(p.string()), dps::Error, needle);
  }
  CHECK_THROWS_WITH(dps::ReadMarks((kTmp / "none.csv").string()), dps::Error, "cannot open");
  // Marks survive a write -> read round trip.
  dps::WriteMarks(s.noisy, (kTmp / "round.csv").string());
  const std::vector<dps::Mark> back = dps::ReadMarks((kTmp / "round.csv").string());
  CHECK_EQ(back.size(), s.noisy.size());
  CHECK_NEAR(back[3].u, s.noisy[3].u, 1e-6);
  fs::remove_all(kTmp);
}

}  // namespace

int main() {
  TestSvdSteps();
  TestAccuracy();
  TestOutliers();
  TestErrors();
  return dps_test::Report();
}
