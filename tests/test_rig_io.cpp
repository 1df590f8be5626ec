// Tests of rig.yaml reading and writing (DESIGN.md §3.1), the catalogue of broken rig files, the
// OpenCV calibration-file readers, and the pose conventions.
#include <cstdio>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "check.h"
#include "dps/camera/rig_io.h"
#include "dps/util/atomic_file.h"
#include "dps/util/error.h"

namespace {

namespace fs = std::filesystem;

const fs::path kTmp = fs::temp_directory_path() / "dps_test_rig_io";

std::string WriteText(const std::string& name, const std::string& text) {
  const fs::path p = kTmp / name;
  std::ofstream(p) << text;
  return p.string();
}

// A camera block of rig.yaml as key -> YAML value text, so that tests can break one field.
using Fields = std::vector<std::pair<std::string, std::string>>;

const char* kRotDown =  // camera Z = vehicle +Y (down), camera X = vehicle X
    "!!opencv-matrix {rows: 3, cols: 3, dt: d, data: [1, 0, 0, 0, 0, 1, 0, -1, 0]}";

Fields LeftCamera() {
  return {{"name", "left"},
          {"model", "hyperbolic"},
          {"width", "640"},
          {"height", "480"},
          {"K", "!!opencv-matrix {rows: 3, cols: 3, dt: d, data: [150, 0, 320, 0, 150, 240, 0, 0, 1]}"},
          {"a", "1.2"},
          {"b", "0.66"},
          {"rim_radius_px", "235"},
          {"R", kRotDown},
          {"t", "!!opencv-matrix {rows: 3, cols: 1, dt: d, data: [-0.95, -1.0, 0.9]}"}};
}

Fields RightCamera() {
  return {{"name", "right"},
          {"model", "fisheye"},
          {"width", "640"},
          {"height", "480"},
          {"K", "[200, 0, 320, 0, 200, 240, 0, 0, 1]"},  // plain lists are accepted too
          {"dist", "[0.01, -0.002, 0.0, 0.0]"},
          {"R", kRotDown},
          {"t", "[0.95, -1.0, 0.9]"}};
}

Fields With(Fields f, const std::string& key, const std::string& value) {
  for (auto& kv : f) {
    if (kv.first == key) {
      kv.second = value;
      return f;
    }
  }
  f.emplace_back(key, value);
  return f;
}

Fields Without(Fields f, const std::string& key) {
  Fields out;
  for (auto& kv : f) {
    if (kv.first != key) out.push_back(kv);
  }
  return out;
}

std::string RigText(const std::vector<Fields>& cameras, const std::string& vehicle =
                                                            "vehicle:\n   length: 4.8\n   width: 1.8\n") {
  std::string s = "%YAML:1.0\n---\n" + vehicle + "cameras:\n";
  for (const Fields& f : cameras) {
    s += "   -\n";
    for (const auto& kv : f) s += "      " + kv.first + ": " + kv.second + "\n";
  }
  return s;
}

void TestReadValidRig() {
  const std::string path = WriteText("good.yaml", RigText({LeftCamera(), RightCamera()}));
  const dps::Rig rig = dps::ReadRig(path);
  CHECK_EQ(rig.cameras.size(), size_t{2});
  CHECK_NEAR(rig.vehicle.length_m, 4.8, 0);
  const dps::RigCamera& left = rig.Camera("left");
  CHECK(left.model.type() == dps::CameraModelType::kHyperbolic);
  CHECK_NEAR(left.model.a(), 1.2, 0);
  CHECK_NEAR(left.model.b(), 0.66, 0);
  CHECK_NEAR(left.model.rim_radius_px(), 235, 0);
  CHECK_NEAR(left.model.K()(0, 2), 320, 0);
  CHECK_NEAR(left.vehicle_from_camera.t.y(), -1.0, 0);
  const dps::RigCamera& right = rig.Camera("right");
  CHECK(right.model.type() == dps::CameraModelType::kFisheye);
  CHECK_NEAR(right.model.dist()[1], -0.002, 0);
  CHECK_THROWS_WITH(rig.Camera("rear"), dps::Error, "no camera named 'rear'");

  // The pose convention: the camera looks down, so its optical axis (camera +Z) is vehicle +Y,
  // and a point 1 m along it from a camera 1 m above the road lies on the road (Y = 0).
  const Eigen::Vector3d on_road = left.vehicle_from_camera.Apply({0, 0, 1});
  CHECK_NEAR(on_road.x(), -0.95, 1e-15);
  CHECK_NEAR(on_road.y(), 0.0, 1e-15);
  CHECK_NEAR(on_road.z(), 0.9, 1e-15);
  // Camera +Y (image rows going down) points backwards in the vehicle.
  CHECK_NEAR(left.vehicle_from_camera.Rotate({0, 1, 0}).z(), -1.0, 1e-15);
  const dps::Pose inv = left.vehicle_from_camera.Inverse();
  CHECK_NEAR((inv.Apply(on_road) - Eigen::Vector3d(0, 0, 1)).norm(), 0.0, 1e-15);
  CHECK_NEAR(((left.vehicle_from_camera * inv).R - Eigen::Matrix3d::Identity()).norm(), 0, 1e-15);
}

void TestWriteReadRoundTrip() {
  dps::Rig rig = dps::ReadRig(WriteText("good2.yaml", RigText({LeftCamera(), RightCamera()})));
  // Add a unified camera with an awkward rotation and values that need all 17 digits.
  Eigen::Matrix3d K;
  K << 123.456789012345678, 0.3, 321.0987654321, 0, 125.1, 239.9, 0, 0, 1;
  dps::Pose pose;
  pose.R = dps::AxisAngle({0.3, -0.2, 0.9}, 1.2345678901234);
  pose.t = {0.1 / 3.0, -1.0 / 7.0, 2.0 / 3.0};
  rig.cameras.push_back({"rear", dps::CameraModel::Unified(800, 600, K, 0.912345678901), pose, cv::Mat(), "", cv::Mat()});
  rig.vehicle.width_m = 1.95;
  const std::string path = (kTmp / "written.yaml").string();
  dps::WriteRig(rig, path);
  const dps::Rig back = dps::ReadRig(path);
  CHECK_EQ(back.cameras.size(), rig.cameras.size());
  CHECK_NEAR(back.vehicle.width_m, 1.95, 0);
  for (size_t i = 0; i < rig.cameras.size() && i < back.cameras.size(); ++i) {
    const dps::RigCamera& a = rig.cameras[i];
    const dps::RigCamera& b = back.cameras[i];
    CHECK_EQ(a.name, b.name);
    CHECK(a.model.type() == b.model.type());
    CHECK_EQ(a.model.width(), b.model.width());
    CHECK_EQ(a.model.height(), b.model.height());
    CHECK_EQ((a.model.K() - b.model.K()).norm(), 0.0);
    CHECK_EQ(a.model.a(), b.model.a());
    CHECK_EQ(a.model.b(), b.model.b());
    CHECK(a.model.dist() == b.model.dist());
    CHECK_EQ(a.model.rim_radius_px(), b.model.rim_radius_px());
    CHECK_EQ((a.vehicle_from_camera.R - b.vehicle_from_camera.R).norm(), 0.0);
    CHECK_EQ((a.vehicle_from_camera.t - b.vehicle_from_camera.t).norm(), 0.0);
  }
  // No temporary file is left beside the output.
  int files = 0;
  for (const auto& e : fs::directory_iterator(kTmp)) {
    files += e.path().filename().string().find(".tmp-") != std::string::npos;
  }
  CHECK_EQ(files, 0);
}

void TestBrokenRigs() {
  struct Case {
    std::string name;
    std::string text;
    std::string expected;  // a piece of the message
  };
  const Fields L = LeftCamera();
  const Fields R = RightCamera();
  const std::vector<Case> cases = {
      {"garbage", "%YAML:1.0\n---\ncameras: [ {name: left, \n", "not a valid"},
      {"no_cameras", "%YAML:1.0\n---\nvehicle:\n   length: 4.8\n", "field 'cameras': missing"},
      {"empty_cameras", "%YAML:1.0\n---\ncameras: []\n", "non-empty list"},
      {"no_name", RigText({Without(L, "name")}), "cameras[0]: field 'name': missing"},
      {"duplicate", RigText({L, With(R, "name", "left")}), "duplicate camera name 'left'"},
      {"unknown_model", RigText({With(L, "model", "pinhole")}), "unknown model 'pinhole'"},
      {"missing_K", RigText({L, Without(R, "K")}), "camera 'right': field 'K': missing"},
      {"K_2x3",
       RigText({With(L, "K", "!!opencv-matrix {rows: 2, cols: 3, dt: d, data: [1,0,0,0,1,0]}")}),
       "field 'K': expected a 3x3 matrix, got 2x3"},
      {"R_not_orthonormal",
       RigText({With(L, "R", "[1, 0, 0, 0, 0, 1, 0, -1.001, 0]")}), "R is not orthonormal"},
      {"R_reflection", RigText({With(L, "R", "[-1, 0, 0, 0, 0, 1, 0, -1, 0]")}), "det(R)"},
      {"negative_focal", RigText({With(L, "K", "[-150, 0, 320, 0, 150, 240, 0, 0, 1]")}),
       "0 < fx <="},
      {"absurd_focal", RigText({With(L, "K", "[1e300, 0, 320, 0, 150, 240, 0, 0, 1]")}),
       "(1000 image sizes)"},
      {"huge_matrix", RigText({With(L, "K", "!!opencv-matrix {rows: 100000, cols: 100000, dt: d, data: [1]}")}),
       "field 'K': expected a 3x3 matrix, got 100000x100000"},
      {"zero_width", RigText({With(L, "width", "0")}), "width > 0"},
      {"zero_height", RigText({With(R, "height", "-5")}), "height > 0"},
      {"hyperbolic_without_b", RigText({Without(L, "b")}), "field 'b': missing"},
      {"negative_a", RigText({With(L, "a", "-1.2")}), "field 'a' = -1.2"},
      {"unified_without_xi", RigText({With(L, "model", "unified")}), "field 'xi': missing"},
      {"fisheye_dist_3", RigText({With(R, "dist", "[0.1, 0.2, 0.3]")}),
       "field 'dist': expected a 4x1 matrix, got 3x1"},
      {"t_2x1", RigText({With(L, "t", "[1.0, 2.0]")}), "field 't': expected a 3x1 matrix"},
      {"width_text", RigText({With(L, "width", "wide")}), "field 'width': expected an integer"},
      {"vehicle_length", RigText({L}, "vehicle:\n   length: -4.8\n"), "vehicle: field 'length'"},
      {"camera_not_map", "%YAML:1.0\n---\ncameras:\n   - 42\n", "expected a map"},
      {"negative_rim", RigText({With(L, "rim_radius_px", "-3")}), "rim_radius"},
  };
  CHECK(cases.size() >= 10);
  for (const Case& c : cases) {
    const std::string path = WriteText(c.name + ".yaml", c.text);
    // Every message names the file and states the problem on one line.
    CHECK_THROWS_WITH(dps::ReadRig(path), dps::Error, c.expected);
    try {
      dps::ReadRig(path);
    } catch (const dps::Error& e) {
      const std::string msg = e.what();
      CHECK(msg.rfind(path, 0) == 0);
      CHECK(msg.find('\n') == std::string::npos);
    }
  }
  CHECK_THROWS_WITH(dps::ReadRig((kTmp / "absent.yaml").string()), dps::Error, "file not found");
  // 19 bytes on which OpenCV 4.6's YAML parser loops forever: an error within its time limit, not a
  // hang (a batch's other drives must still run).
  const std::string endless = WriteText("endless.yaml", "%YAML:1.\n h:0\n:  -\n");
  const auto start = std::chrono::steady_clock::now();
  CHECK_THROWS_WITH(dps::ReadRig(endless), dps::Error, "endless.yaml: ");  // "did not finish" on OpenCV 4.6
  CHECK(std::chrono::steady_clock::now() - start < std::chrono::seconds(30));
}

void TestOpenCVReaders() {
  // A cv::omnidir-style result, written by cv::FileStorage the way its sample does.
  {
    cv::FileStorage out((kTmp / "omnidir.yaml").string(), cv::FileStorage::WRITE);
    out << "image_width" << 800 << "image_height" << 600;
    out << "camera_matrix" << cv::Mat(cv::Matx33d(400, 0.5, 401, 0, 402, 299, 0, 0, 1));
    out << "distortion_coefficients" << cv::Mat(cv::Matx14d(0, 0, 0, 0));
    out << "xi" << cv::Mat(cv::Matx<double, 1, 1>(1.1));
  }
  const dps::CameraModel m = dps::ReadOpenCVOmnidir((kTmp / "omnidir.yaml").string());
  CHECK(m.type() == dps::CameraModelType::kUnified);
  CHECK_NEAR(m.xi(), 1.1, 0);
  CHECK_EQ(m.width(), 800);
  CHECK_NEAR(m.K()(0, 1), 0.5, 0);
  {
    cv::FileStorage out((kTmp / "omnidir_d.yaml").string(), cv::FileStorage::WRITE);
    out << "K" << cv::Mat(cv::Matx33d(400, 0, 401, 0, 402, 299, 0, 0, 1));
    out << "D" << cv::Mat(cv::Matx14d(-0.2, 0.05, 0, 0));
    out << "xi" << 1.1;
  }
  // With distortion: read as the unified model's [k1 k2 p1 p2], written back to rig.yaml and read
  // again unchanged.
  const dps::CameraModel distorted = dps::ReadOpenCVOmnidir((kTmp / "omnidir_d.yaml").string(), {800, 600});
  CHECK_NEAR(distorted.dist()[0], -0.2, 0);
  CHECK_NEAR(distorted.dist()[1], 0.05, 0);
  dps::Rig with_dist;
  dps::Pose identity;
  with_dist.cameras.push_back({"left", distorted, identity, cv::Mat(), "", cv::Mat()});
  dps::WriteRig(with_dist, (kTmp / "rig_dist.yaml").string());
  const dps::CameraModel back = dps::ReadRig((kTmp / "rig_dist.yaml").string()).Camera("left").model;
  CHECK(back.dist() == distorted.dist());
  CHECK(back.type() == dps::CameraModelType::kUnified);
  {
    cv::FileStorage out((kTmp / "omnidir_nosize.yaml").string(), cv::FileStorage::WRITE);
    out << "K" << cv::Mat(cv::Matx33d(400, 0, 401, 0, 402, 299, 0, 0, 1));
    out << "xi" << 1.1;
  }
  CHECK_THROWS_WITH(dps::ReadOpenCVOmnidir((kTmp / "omnidir_nosize.yaml").string()), dps::Error,
                    "resolution");
  CHECK_EQ(dps::ReadOpenCVOmnidir((kTmp / "omnidir_nosize.yaml").string(), {64, 48}).width(), 64);
}

void TestAtomicFile() {
  const std::string path = (kTmp / "atomic.txt").string();
  {
    dps::AtomicOutputFile f(path);
    f.stream() << "half";
    CHECK(!fs::exists(path));  // nothing under the final name before Commit
  }
  CHECK(!fs::exists(path));  // abandoned: no file, no temporary
  dps::WriteFileAtomically(path, "complete\n");
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  CHECK_EQ(line, std::string("complete"));
  CHECK_THROWS_WITH(dps::WriteFileAtomically((kTmp / "no_dir" / "x.txt").string(), "x"),
                    dps::Error, "no_dir");
}

}  // namespace

int main() {
  fs::remove_all(kTmp);
  fs::create_directories(kTmp);
  TestReadValidRig();
  TestWriteReadRoundTrip();
  TestBrokenRigs();
  TestOpenCVReaders();
  TestAtomicFile();
  fs::remove_all(kTmp);
  return dps_test::Report();
}
