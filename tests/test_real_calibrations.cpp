// Real cameras' calibrations (data/real/calibrations; the non-permissive ones from
// ../shared/data/real_calibrations when that folder exists): each imported with dps's readers and
// compared with its toolbox's own formula, written here again from the toolbox's documentation
// (OCamCalib's ocam_functions, camodocal's MEI camera, PJLab's run_avm, cv::omnidir), on a grid over
// the valid field; the extrinsics checked against what the cameras are known to look at.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "check.h"
#include "dps/camera/calibration_import.h"
#include "dps/camera/rig_io.h"
#include "dps/util/error.h"

namespace fs = std::filesystem;

namespace {

constexpr double kPixelTol = 0.01;  // px, the target

const fs::path kData = fs::path(DPS_REAL_DATA_DIR) / "calibrations";
const fs::path kShared = fs::path(DPS_SOURCE_DIR) / ".." / "shared" / "data" / "real_calibrations";

double Poly(const std::vector<double>& a, double x) {
  double v = 0;
  for (size_t i = a.size(); i-- > 0;) v = v * x + a[i];
  return v;
}

// ---- OCamCalib, from its documentation (calib_results.txt layout, ocam_functions.c) ----------
struct Toolbox {
  std::vector<double> ss, invpol;
  double xc = 0, yc = 0, c = 1, d = 0, e = 0;
  int height = 0, width = 0;
};

Toolbox ParseCalibResults(const fs::path& file) {
  std::ifstream in(file);
  std::vector<std::vector<double>> lines;
  std::string line;
  while (lines.size() < 5 && std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line.find_first_not_of(" \r") == std::string::npos) continue;
    std::istringstream s(line);
    std::vector<double> v;
    double x;
    while (s >> x) v.push_back(x);
    lines.push_back(v);
  }
  Toolbox t;
  t.ss.assign(lines[0].begin() + 1, lines[0].end());
  t.invpol.assign(lines[1].begin() + 1, lines[1].end());
  t.xc = lines[2][0];
  t.yc = lines[2][1];
  t.c = lines[3][0];
  t.d = lines[3][1];
  t.e = lines[3][2];
  t.height = static_cast<int>(lines[4][0]);
  t.width = static_cast<int>(lines[4][1]);
  return t;
}

// m = (row, column) -> point (x, y, z) in the toolbox's frame.
cv::Vec3d Cam2World(const Toolbox& t, double row, double col) {
  const double inv_det = 1.0 / (t.c - t.d * t.e);
  const double xp = inv_det * ((row - t.xc) - t.d * (col - t.yc));
  const double yp = inv_det * (-t.e * (row - t.xc) + t.c * (col - t.yc));
  const double r = std::sqrt(xp * xp + yp * yp);
  const cv::Vec3d v(xp, yp, Poly(t.ss, r));
  return v / cv::norm(v);
}

// point -> (row, column)
cv::Vec2d World2Cam(const Toolbox& t, const cv::Vec3d& p) {
  const double norm = std::sqrt(p[0] * p[0] + p[1] * p[1]);
  if (norm == 0) return {t.xc, t.yc};
  const double theta = std::atan(p[2] / norm);
  const double rho = Poly(t.invpol, theta);
  const double x = p[0] / norm * rho, y = p[1] / norm * rho;
  return {x * t.c + y * t.d + t.xc, x * t.e + y + t.yc};
}

// dps's camera frame is the toolbox's turned: (X, Y, Z) = (y, x, -z).
Eigen::Vector3d ToDps(const cv::Vec3d& p) { return {p[1], p[0], -p[2]}; }

// The imported model agrees with the toolbox over a grid of pixels the model calls valid: the
// toolbox's ray of each pixel projects, by dps, where the toolbox projects it, and dps's ray of the
// pixel is the toolbox's. Returns how many grid pixels were compared.
int CompareOCam(const dps::CameraModel& m, const Toolbox& t, const std::string& label) {
  double worst_px = 0, worst_rad = 0;
  int compared = 0, total = 0;
  const int step = std::max(4, t.width / 60);
  for (int row = 0; row < t.height; row += step) {
    for (int col = 0; col < t.width; col += step) {
      ++total;
      Eigen::Vector3d ray;
      if (!m.Unproject({static_cast<double>(col), static_cast<double>(row)}, &ray)) continue;
      const cv::Vec3d toolbox_ray = Cam2World(t, row, col);
      const cv::Vec2d expected = World2Cam(t, toolbox_ray);
      Eigen::Vector2d got;
      CHECK(m.Project(ToDps(toolbox_ray), &got));
      worst_px = std::max(worst_px, std::hypot(got.x() - expected[1], got.y() - expected[0]));
      worst_rad = std::max(worst_rad, (ray - ToDps(toolbox_ray)).norm());  // unit rays: the angle
      ++compared;
    }
  }
  std::printf("%s: %d of %d grid pixels valid, world2cam agrees to %.2e px, cam2world to %.2e rad, field %.1f deg from the axis\n",
              label.c_str(), compared, total, worst_px, worst_rad, m.max_theta_rad() * 180 / M_PI);
  CHECK(worst_px <= kPixelTol);
  CHECK(worst_rad <= 1e-9);
  return compared;
}

dps::Rig Import(dps::CalibrationFormat format, const std::vector<fs::path>& files,
                const std::vector<std::string>& names = {}) {
  dps::ImportOptions o;
  o.format = format;
  for (const fs::path& f : files) o.files.push_back(f.string());
  o.names = names;
  return dps::ImportRig(o);
}

// The rig survives rig.yaml: the same pixels after WriteRig / ReadRig.
void CheckRoundTrip(const dps::Rig& rig) {
  const fs::path file = fs::temp_directory_path() / ("dps_real_calibrations_" + std::to_string(::getpid()) + ".yaml");
  dps::WriteRig(rig, file.string());
  const dps::Rig back = dps::ReadRig(file.string());
  fs::remove(file);
  CHECK_EQ(back.cameras.size(), rig.cameras.size());
  for (size_t i = 0; i < rig.cameras.size(); ++i) {
    const dps::CameraModel& a = rig.cameras[i].model;
    const dps::CameraModel& b = back.cameras[i].model;
    double worst = 0;
    for (int v = 0; v < a.height(); v += 37) {
      for (int u = 0; u < a.width(); u += 37) {
        Eigen::Vector3d ray;
        Eigen::Vector2d pa, pb;
        if (!a.Unproject({double(u), double(v)}, &ray)) continue;
        CHECK(a.Project(ray, &pa) && b.Project(ray, &pb));
        worst = std::max(worst, (pa - pb).norm());
      }
    }
    CHECK(worst <= 1e-9);
    CHECK((back.cameras[i].vehicle_from_camera.R - rig.cameras[i].vehicle_from_camera.R).norm() <= 1e-12);
  }
}

void TestOCamFiles() {
  struct File {
    fs::path path;
    bool shared;
  };
  const File files[] = {{kData / "ocam_catadioptric_kuanli" / "calib_results.txt", false},
                        {kData / "ocam_fisheye_ocamcalib_sample" / "calib_results_fisheye.txt", false},
                        {kShared / "ocam_fisheye_urban" / "calib_results.txt", true}};
  for (const File& f : files) {
    if (!fs::exists(f.path)) {
      CHECK(f.shared);  // the project's own copies are always there
      std::printf("%s: skipped (not present)\n", f.path.string().c_str());
      continue;
    }
    const Toolbox t = ParseCalibResults(f.path);
    const dps::Rig rig = Import(dps::CalibrationFormat::kOCam, {f.path});
    const dps::CameraModel& m = rig.cameras[0].model;
    CHECK(m.type() == dps::CameraModelType::kOCam);
    CHECK_EQ(m.width(), t.width);
    CHECK_EQ(m.height(), t.height);
    const int compared = CompareOCam(m, t, f.path.parent_path().filename().string());
    CHECK(compared > 100);
    CheckRoundTrip(rig);
    // Resized, with another scale across than down: a ray lands on the scaled pixel
    // (u' + 0.5 = s (u + 0.5)).
    const int w2 = t.width * 3 / 5, h2 = t.height * 2 / 3;
    const dps::CameraModel half = dps::ResizeCameraModel(m, w2, h2);
    const double sx = double(w2) / t.width, sy = double(h2) / t.height;
    double worst = 0;
    for (int v = 0; v < t.height; v += 41) {
      for (int u = 0; u < t.width; u += 41) {
        Eigen::Vector3d ray;
        Eigen::Vector2d p, q;
        if (!m.Unproject({double(u), double(v)}, &ray) || !m.Project(ray, &p) || !half.Project(ray, &q)) continue;
        p = {sx * (p.x() + 0.5) - 0.5, sy * (p.y() + 0.5) - 0.5};
        worst = std::max(worst, (p - q).norm());
      }
    }
    std::printf("  resized to %dx%d: rays land on the scaled pixels to %.1e px\n", w2, h2, worst);
    CHECK(worst <= 1e-9);
  }
  // The mirror camera sees above its mirror's horizontal plane (f changes sign at rho ~ 443 px).
  const dps::Rig mirror = Import(dps::CalibrationFormat::kOCam, {kData / "ocam_catadioptric_kuanli" / "calib_results.txt"});
  CHECK(mirror.cameras[0].model.max_theta_rad() > M_PI / 2 + 10 * M_PI / 180);
}

// The OCam numbers transcribed to YAML (scara.yaml) read as the text file's would.
void TestOCamYaml() {
  const fs::path file = kData / "omnidir_mei_catadioptric_kuanli" / "scara.yaml";
  const dps::CameraModel m = dps::ReadOCamCalibResults(file.string());
  Toolbox t;
  t.ss = {-1.864565e+02, 0.000000e+00, 2.919291e-03, -6.330598e-06, 8.678134e-09};
  t.invpol = {323.712933, 300.441941, 91.808710, -51.905017, -80.453176, 63.731282, 130.714839, -23.557147, -133.764001,
              -14.408450, 91.162738, 31.999104, -32.157217, -18.885584, 3.285893, 4.131682, 0.746373};
  t.xc = 489.624522;
  t.yc = 608.819613;
  t.c = 0.998454;
  t.d = -0.008966;
  t.e = -0.008322;
  t.height = 1000;
  t.width = 1230;
  CHECK_EQ(m.width(), 1230);
  CHECK(CompareOCam(m, t, "scara.yaml") > 100);
}

// ---- PJLab's surround fisheyes (run_avm.cpp's world2cam: x along columns) -------------------
struct PJLab {
  double c, d, e, u0, v0;
  std::vector<double> p;
};

cv::Vec2d PJLabProject(const PJLab& k, const Eigen::Vector3d& P) {
  const double M0 = P.x() / P.z(), M1 = P.y() / P.z(), M2 = -1;
  const double norm = std::sqrt(M0 * M0 + M1 * M1);
  const double theta = std::atan(M2 / norm);
  const double rho = Poly(k.p, theta);
  const double x = M0 / norm * rho, y = M1 / norm * rho;
  return {k.c * x + k.d * y + k.u0, k.e * x + y + k.v0};  // (u, v)
}

PJLab ParsePJLab(const fs::path& file) {
  cv::FileStorage in(file.string(), cv::FileStorage::READ);
  const cv::FileNode param = (*in.root().begin())["param"];
  std::vector<std::vector<double>> K;
  for (const cv::FileNode& row : param["cam_K"]["data"]) {
    K.emplace_back();
    for (const cv::FileNode& v : row) K.back().push_back(double(v));
  }
  PJLab k{K[0][0], K[0][1], K[1][0], K[0][2], K[1][2], {}};
  for (const cv::FileNode& v : *param["cam_dist"]["data"].begin()) k.p.push_back(double(v));
  return k;
}

void TestPJLab() {
  const fs::path dir = kData / "ocam_surround_pjlab";
  const char* const names[] = {"Front", "Left", "Back", "Right"};
  std::vector<fs::path> files;
  for (const char* n : names) {
    files.push_back(dir / "intrinsic" / (std::string(n) + ".json"));
    files.push_back(dir / "extrinsic" / (std::string(n) + ".json"));
  }
  dps::ImportOptions o;
  o.format = dps::CalibrationFormat::kPJLabOCam;
  for (const fs::path& f : files) o.files.push_back(f.string());
  CHECK_THROWS_WITH(dps::ImportRig(o), dps::Error, "--bev-height");
  o.bev_height_by_camera = {{"front_camera", 6.07826}, {"left_camera", 6.25217}, {"back_camera", 6.31014},
                            {"right_camera", 6.28116}};  // run_avm.cpp's heights, per camera
  std::vector<std::string> notes;
  const dps::Rig rig = dps::ImportRig(o, &notes);
  CHECK_EQ(rig.cameras.size(), size_t(4));
  CHECK_EQ(rig.cameras[0].name, std::string("front_camera"));
  for (size_t i = 0; i < 4; ++i) {
    const dps::RigCamera& cam = rig.cameras[i];
    const PJLab k = ParsePJLab(dir / "intrinsic" / (std::string(names[i]) + ".json"));
    double worst = 0, worst_round_trip = 0;
    int compared = 0;
    for (int v = 0; v < 960; v += 16) {
      for (int u = 0; u < 1280; u += 16) {
        Eigen::Vector3d ray;
        Eigen::Vector2d px, back;
        if (!cam.model.Unproject({double(u), double(v)}, &ray)) continue;
        CHECK(cam.model.Project(ray, &back));
        worst_round_trip = std::max(worst_round_trip, (back - Eigen::Vector2d(u, v)).norm());
        if (ray.z() < 0.05) continue;  // run_avm's formula is for points in front of the camera
        CHECK(cam.model.Project(ray, &px));
        const cv::Vec2d expected = PJLabProject(k, ray);
        worst = std::max(worst, std::hypot(px.x() - expected[0], px.y() - expected[1]));
        ++compared;
      }
    }
    std::printf("pjlab %s: %d rays agree with run_avm's world2cam to %.2e px; pixel -> ray -> pixel %.2e px; field %.1f deg\n",
                names[i], compared, worst, worst_round_trip, cam.model.max_theta_rad() * 180 / M_PI);
    CHECK(compared > 2000);
    CHECK(worst <= kPixelTol);
    CHECK(worst_round_trip <= kPixelTol);
  }
  // Where each camera looks in the vehicle frame, and that each sees the road on its own side
  // (run_avm: Front sees the bird's-eye rows 0..350, Back 690..990, Left columns 0..500, Right 540..990).
  const Eigen::Vector3d out[] = {{0, 0, 1}, {-1, 0, 0}, {0, 0, -1}, {1, 0, 0}};
  for (size_t i = 0; i < 4; ++i) {
    const dps::RigCamera& cam = rig.cameras[i];
    const Eigen::Vector3d axis = cam.vehicle_from_camera.R.col(2);
    const Eigen::Vector3d position = cam.vehicle_from_camera.t;
    std::printf("pjlab %s: at (%.2f, %.2f, %.2f) m, axis (%.2f, %.2f, %.2f)\n", names[i], position.x(), position.y(),
                position.z(), axis.x(), axis.y(), axis.z());
    CHECK(axis.dot(out[i]) > 0.5);
    CHECK(axis.y() > 0.2);                           // tilted down to the road
    CHECK(position.y() < -0.2 && position.y() > -3.0);  // above the road
    // The road 2 units out from each camera: seen by that camera, not by the opposite one.
    for (size_t j = 0; j < 4; ++j) {
      const Eigen::Vector3d below = rig.cameras[j].vehicle_from_camera.t;
      const Eigen::Vector3d ground = Eigen::Vector3d(below.x(), 0, below.z()) + 2.0 * out[j];
      Eigen::Vector2d px;
      const bool seen = cam.model.Project(cam.vehicle_from_camera.Inverse().Apply(ground), &px) && cam.model.InImage(px);
      if (i == j) CHECK(seen);
      if ((i + 2) % 4 == j) CHECK(!seen);
    }
  }
  CheckRoundTrip(rig);
}

// ---- KITTI-360's side fisheyes: camodocal's MEI model -----------------------------------------
void TestKitti360() {
  const fs::path dir = kShared / "kitti360_fisheye";
  if (!fs::exists(dir)) {
    std::printf("kitti360_fisheye: skipped (not present)\n");
    return;
  }
  dps::ImportOptions o;
  o.format = dps::CalibrationFormat::kKitti360;
  o.files = {(dir / "image_02.yaml").string(), (dir / "image_03.yaml").string(), (dir / "calib_cam_to_pose.txt").string()};
  o.names = {"left", "right"};
  const dps::Rig rig = dps::ImportRig(o);
  // image_02's parameters (image_02.yaml), camodocal CataCamera::spaceToPlane.
  const double xi = 2.2134047507854890e+00, k1 = 1.6798235660113681e-02, k2 = 1.6548773243373522e+00,
               p1 = 4.2223943394772046e-04, p2 = 4.2462134260997584e-04, g1 = 1.3363220825849971e+03,
               g2 = 1.3357883350012958e+03, u0 = 7.1694323510126321e+02, v0 = 7.0576498308221585e+02;
  auto mei = [&](const Eigen::Vector3d& P, bool tangential) {
    const double z = P.z() + xi * P.norm();
    const double mx = P.x() / z, my = P.y() / z;
    const double r2 = mx * mx + my * my, rad = k1 * r2 + k2 * r2 * r2;
    const double t = tangential ? 1.0 : 0.0;
    const double dx = mx * rad + t * (2 * p1 * mx * my + p2 * (r2 + 2 * mx * mx));
    const double dy = my * rad + t * (2 * p2 * mx * my + p1 * (r2 + 2 * my * my));
    return Eigen::Vector2d(g1 * (mx + dx) + u0, g2 * (my + dy) + v0);
  };
  const dps::CameraModel& m = rig.Camera("left").model;
  double worst = 0, devkit = 0;
  int compared = 0;
  for (int v = 0; v < 1400; v += 20) {
    for (int u = 0; u < 1400; u += 20) {
      Eigen::Vector3d ray;
      Eigen::Vector2d px;
      if (!m.Unproject({double(u), double(v)}, &ray)) continue;
      CHECK(m.Project(ray, &px));
      worst = std::max(worst, (px - mei(ray, true)).norm());
      devkit = std::max(devkit, (px - mei(ray, false)).norm());
      ++compared;
    }
  }
  std::printf("kitti360 image_02: %d rays agree with camodocal's MEI projection to %.2e px (the devkit, without p1 p2: %.2f px); field %.1f deg\n",
              compared, worst, devkit, m.max_theta_rad() * 180 / M_PI);
  CHECK(compared > 3000);
  CHECK(worst <= kPixelTol);
  // image_02 looks left and image_03 right, image right = forward / backward, image down = down.
  const dps::RigCamera& left = rig.Camera("left");
  const dps::RigCamera& right = rig.Camera("right");
  CHECK(left.vehicle_from_camera.R.col(2).dot(Eigen::Vector3d(-1, 0, 0)) > std::cos(3 * M_PI / 180));
  CHECK(right.vehicle_from_camera.R.col(2).dot(Eigen::Vector3d(1, 0, 0)) > std::cos(3 * M_PI / 180));
  CHECK(left.vehicle_from_camera.R.col(1).y() > 0.99 && right.vehicle_from_camera.R.col(1).y() > 0.99);
  CHECK(left.vehicle_from_camera.R.col(0).z() > 0.99);
  CHECK_NEAR((left.vehicle_from_camera.t - right.vehicle_from_camera.t).norm(), 0.897, 0.002);
  CHECK(left.vehicle_from_camera.t.x() < right.vehicle_from_camera.t.x());
}

// ---- cv::omnidir: the stored calibration reprojects its own corners with the stored RMS -------
void TestOmnidir() {
  // The hand-written Mei YAML (K, D, Xi) has no image size: refused until one is given.
  const fs::path mei = kData / "omnidir_mei_catadioptric_kuanli" / "mei.yaml";
  dps::ImportOptions o;
  o.format = dps::CalibrationFormat::kOmnidir;
  o.files = {mei.string()};
  CHECK_THROWS_WITH(dps::ImportRig(o), dps::Error, "resolution");
  o.size = cv::Size(1230, 1000);
  const dps::CameraModel m = dps::ImportRig(o).cameras[0].model;
  CHECK_NEAR(m.xi(), 1.518101310566618789, 1e-15);
  CHECK_NEAR(m.K()(0, 1), 9.326437725584912908e-01, 1e-15);
  CHECK_NEAR(m.dist()[1], 6.715185517729774789e-01, 1e-15);

  // cv::omnidir::calibrate's own output: its corners reproject with its stored RMS.
  const fs::path file = kShared / "omnidir_opencv_scanvan" / "out_camera_omni.xml";
  if (!fs::exists(file)) {
    std::printf("omnidir_opencv_scanvan: skipped (not present)\n");
    return;
  }
  const dps::Rig rig = Import(dps::CalibrationFormat::kOmnidir, {file});
  const dps::CameraModel& cam = rig.cameras[0].model;
  CHECK_EQ(cam.width(), 3008);
  cv::FileStorage in(file.string(), cv::FileStorage::READ);
  cv::Mat extrinsics, points;
  in["extrinsic_parameters"] >> extrinsics;
  in["image_points"] >> points;
  const double stored_rms = double(in["rms"]);
  double sum = 0;
  int n = 0;
  for (int view = 0; view < extrinsics.rows; ++view) {
    cv::Mat R;
    cv::Rodrigues(extrinsics.row(view).colRange(0, 3), R);
    Eigen::Matrix3d Re;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) Re(r, c) = R.at<double>(r, c);
    }
    const Eigen::Vector3d t(extrinsics.at<double>(view, 3), extrinsics.at<double>(view, 4), extrinsics.at<double>(view, 5));
    for (int i = 0; i < 6; ++i) {
      for (int j = 0; j < 9; ++j) {
        Eigen::Vector2d px;
        CHECK(cam.Project(Re * Eigen::Vector3d(j * 17.5, i * 17.5, 0) + t, &px));
        const cv::Vec2d seen = points.at<cv::Vec2d>(view, i * 9 + j);
        sum += (px - Eigen::Vector2d(seen[0], seen[1])).squaredNorm();
        ++n;
      }
    }
  }
  const double rms = std::sqrt(sum / n);
  std::printf("omnidir_opencv_scanvan: %d corners reproject with RMS %.10f px (stored %.10f)\n", n, rms, stored_rms);
  CHECK_EQ(n, 20 * 54);
  CHECK_NEAR(rms, stored_rms, 1e-8);
}

// Bad calibration files: a one-line error naming the file and the field.
void TestBadFiles() {
  const fs::path dir = fs::temp_directory_path() / ("dps_bad_calibrations_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir / name) << text;
    return (dir / name).string();
  };
  CHECK_THROWS_WITH(dps::ReadOCamCalibResults(write("disagree.txt", "2 -266.588 0\n2 443.18 308.13\n545.8 674.3\n1 0 0\n1080 1300\n")),
                    dps::Error, "ss and invpol disagree");
  CHECK_THROWS_WITH(dps::ReadOCamCalibResults(write("short.txt", "#ss\n5 -266.588 0 1.22e-03 -5.78e-07 2.0e-09\n#invpol\n2 443.18 308.13\n#center\n545.8 674.3\n#affine\n1 0 0\n")),
                    dps::Error, "image size (height width)");
  CHECK_THROWS_WITH(dps::ReadOCamCalibResults(write("count.txt", "5 -266.588 0 1.22e-03\n2 1 2\n1 2\n1 0 0\n10 10\n")), dps::Error,
                    "field 'ss': the count says 5");
  CHECK_THROWS_WITH(dps::ReadOCamCalibResults(write("token.txt", "2 -266.588 0x\n2 1 2\n1 2\n1 0 0\n10 10\n")), dps::Error,
                    "line 1 (ss (cam2world polynomial))");
  CHECK_THROWS_WITH(dps::ReadOCamCalibResults(write("sign.txt", "2 266.588 0\n2 1 2\n1 2\n1 0 0\n10 10\n")), dps::Error, "a0 < 0");
  CHECK_THROWS_WITH(dps::ReadOCamCalibResults(write("affine.txt", "2 -266.588 0\n2 1 2\n1 2\n1 2\n10 10\n")), dps::Error,
                    "field 'affine (c d e)'");
  CHECK_THROWS_WITH(dps::ReadOCamCalibResults(write("scara.yaml", "ss: [2, -100, 0]\nxy: [1, 2]\ncde: [1, 0, 0]\nshape: [10, 10]\n")),
                    dps::Error, "field 'invpol': missing");
  CHECK_THROWS_WITH(dps::ReadKitti360Fisheye(write("k.yaml", "%YAML:1.0\nmodel_type: MEI\nimage_width: 10\nimage_height: 10\n"
                                                             "mirror_parameters:\n   chi: 1.0\ndistortion_parameters:\n   k1: 0\n"
                                                             "projection_parameters:\n   gamma1: 1\n")),
                    dps::Error, "mirror_parameters: field 'xi': missing");
  CHECK_THROWS_WITH(dps::ReadKitti360CamToPose(write("pose.txt", "image_02: 1 0 0 0 0 1 0 0 0 0 1\n")), dps::Error, "expected 12 numbers");
  CHECK_THROWS_WITH(dps::ReadPJLabOCamIntrinsic(write("i.json", "{\"cam-intrinsic\": {\"param\": {\"img_dist_w\": 10, \"img_dist_h\": 10}}}")),
                    dps::Error, "field 'cam_K': missing");
  CHECK_THROWS_WITH(dps::ReadPJLabExtrinsic(write("e.json", "{\"cam-extrinsic\": {}}")), dps::Error, "bev-to-<camera>-extrinsic");
  CHECK_THROWS_WITH(dps::CalibrationFormatFromName("matlab"), dps::Error, "expected ocam, omnidir");
  fs::remove_all(dir);
}

}  // namespace

int main() {
  TestBadFiles();
  TestOCamFiles();
  TestOCamYaml();
  TestPJLab();
  TestKitti360();
  TestOmnidir();
  return dps_test::Report();
}
