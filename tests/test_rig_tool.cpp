// dps-rig as a user runs it: import a real calibration, show it, project and unproject through
// stdin / stdout (checked against the library), check and view real images; and the views of real
// fisheye images keep a checkerboard's rows straight (corners found by OpenCV on the view lie on
// lines), where the raw image bends them; lane boundaries from a lanes.csv drawn where the rig puts
// them on the road.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "check.h"
#include "dps/camera/rig_io.h"

namespace fs = std::filesystem;

namespace {

const std::string kTool = DPS_RIG_TOOL;
const fs::path kData = fs::path(DPS_REAL_DATA_DIR) / "calibrations";
const fs::path kShared = fs::path(DPS_SOURCE_DIR) / ".." / "shared" / "data" / "real_calibrations";
const fs::path kWork = fs::temp_directory_path() / ("dps_rig_tool_" + std::to_string(::getpid()));

// Runs a shell command; returns its exit status, stdout in *out and stderr in *err.
int Run(const std::string& command, std::string* out = nullptr, std::string* err = nullptr, const std::string& input = "") {
  const fs::path in = kWork / "stdin.txt", o = kWork / "stdout.txt", e = kWork / "stderr.txt";
  std::ofstream(in) << input;
  const int status = std::system((command + " < '" + in.string() + "' > '" + o.string() + "' 2> '" + e.string() + "'").c_str());
  auto slurp = [](const fs::path& p) {
    std::ifstream f(p);
    return std::string(std::istreambuf_iterator<char>(f), {});
  };
  if (out) *out = slurp(o);
  if (err) *err = slurp(e);
  return WEXITSTATUS(status);
}

std::vector<std::vector<std::string>> Csv(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    rows.emplace_back();
    std::string cell;
    std::istringstream cells(line);
    while (std::getline(cells, cell, ',')) rows.back().push_back(cell);
    if (!line.empty() && line.back() == ',') rows.back().push_back("");
  }
  return rows;
}

void TestImportShowProject() {
  const std::string rig = (kWork / "rig.yaml").string();
  std::string out, err;
  CHECK_EQ(Run(kTool + " --help", &out), 0);
  CHECK(out.find("dps-rig import") != std::string::npos);
  CHECK_EQ(Run(kTool + " import --format ocam '" + (kData / "ocam_fisheye_ocamcalib_sample" / "calib_results_fisheye.txt").string() +
                   "' --name left --axis out --height 1.2 --out " + rig, &out, &err), 0);
  CHECK(out.find("left: ocam 1024x768") != std::string::npos);
  CHECK(err.find("nominal") != std::string::npos);
  CHECK_EQ(Run(kTool + " show " + rig + " --out " + (kWork / "show.png").string(), &out), 0);
  CHECK(out.find("1.2 m above the road") != std::string::npos);
  CHECK(!cv::imread((kWork / "show.png").string()).empty());

  // project / unproject: the same numbers as the library, and a ray through the point.
  const dps::Rig r = dps::ReadRig(rig);
  const dps::RigCamera& cam = r.Camera("left");
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  std::ostringstream points;
  points << "x,y,z\n";
  std::vector<Eigen::Vector3d> p;
  for (int i = 0; i < 200; ++i) {
    p.push_back(cam.vehicle_from_camera.t + 5.0 * Eigen::Vector3d(u(rng), u(rng), u(rng)));
    points.precision(17);
    points << p.back().x() << "," << p.back().y() << "," << p.back().z() << "\n";
  }
  CHECK_EQ(Run(kTool + " project " + rig + " --camera left", &out, &err, points.str()), 0);
  const auto projected = Csv(out);
  CHECK_EQ(projected.size(), p.size() + 1);
  CHECK(projected[0] == (std::vector<std::string>{"u", "v", "valid"}));
  std::ostringstream pixels;
  pixels << "u,v\n";
  int valid = 0, invalid = 0;
  double worst_px = 0, worst_rad = 0;
  std::vector<Eigen::Vector3d> seen;
  for (size_t i = 0; i < p.size(); ++i) {
    const auto& row = projected[i + 1];
    Eigen::Vector2d px;
    const bool library = cam.model.Project(cam.vehicle_from_camera.Inverse().Apply(p[i]), &px);
    CHECK_EQ(row.at(2), std::string(library ? "1" : "0"));
    if (!library) {
      ++invalid;
      continue;
    }
    ++valid;
    const Eigen::Vector2d tool(std::stod(row[0]), std::stod(row[1]));
    worst_px = std::max(worst_px, (tool - px).norm());
    pixels.precision(17);
    pixels << tool.x() << "," << tool.y() << "\n";
    seen.push_back(p[i]);
  }
  CHECK(valid > 20 && invalid > 20);  // the lens sees about half of all directions
  CHECK_EQ(Run(kTool + " unproject " + rig + " --camera left", &out, &err, pixels.str()), 0);
  const auto rays = Csv(out);
  CHECK_EQ(rays.size(), seen.size() + 1);
  for (size_t i = 0; i < seen.size(); ++i) {
    const auto& row = rays[i + 1];
    CHECK_EQ(row.at(3), std::string("1"));
    const Eigen::Vector3d d(std::stod(row[0]), std::stod(row[1]), std::stod(row[2]));
    const Eigen::Vector3d expected = (seen[i] - cam.vehicle_from_camera.t).normalized();
    worst_rad = std::max(worst_rad, (d.normalized() - expected).norm());
  }
  std::printf("project: %d valid, %d invalid, %.1e px from the library; unproject back to %.1e rad\n", valid, invalid, worst_px, worst_rad);
  CHECK(worst_px < 1e-6);
  CHECK(worst_rad < 1e-4);  // the toolbox's ss and invpol agree to about 1e-3 px
  CHECK_EQ(Run(kTool + " unproject " + rig + " --camera left", &out, &err, "u,v\n1,2,3\n"), 1);
  CHECK(err.find("stdin line 2: expected 2 numbers") != std::string::npos);
  CHECK_EQ(Run(kTool + " project " + rig + " --camera nobody", &out, &err, ""), 1);
  CHECK(err.find("nobody") != std::string::npos);
}

// The largest distance of a checkerboard's corners from the line through their row or column.
double Bend(const std::vector<cv::Point2f>& corners, cv::Size pattern) {
  double worst = 0;
  auto check = [&](const std::vector<cv::Point2f>& line) {
    cv::Vec4f l;
    cv::fitLine(line, l, cv::DIST_L2, 0, 0.01, 0.01);
    for (const cv::Point2f& q : line) worst = std::max(worst, std::abs(double((q.x - l[2]) * l[1] - (q.y - l[3]) * l[0])));
  };
  for (int r = 0; r < pattern.height; ++r) {
    check(std::vector<cv::Point2f>(corners.begin() + r * pattern.width, corners.begin() + (r + 1) * pattern.width));
  }
  for (int c = 0; c < pattern.width; ++c) {
    std::vector<cv::Point2f> column;
    for (int r = 0; r < pattern.height; ++r) column.push_back(corners[r * pattern.width + c]);
    check(column);
  }
  return worst;
}

// Corners of a board of `pattern` inner corners, refined; empty when not found.
std::vector<cv::Point2f> Corners(const cv::Mat& image, cv::Size pattern) {
  cv::Mat grey;
  cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  std::vector<cv::Point2f> corners;
  if (!cv::findChessboardCorners(grey, pattern, corners, cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE)) return {};
  cv::cornerSubPix(grey, corners, {5, 5}, {-1, -1}, {cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 50, 0.01});
  return corners;
}

// A perspective view from a real image with a checkerboard: the board's rows and columns straight.
// Corners of a real printed board, refined by cornerSubPix in an interpolated view, are good to a
// few tenths of a pixel: rows that stay within max_bend_px of a line over hundreds of pixels are
// straight, where the lens bends them by many pixels in the raw image (the view magnifies, so the
// raw image's bend must also be larger in pixels).
void TestStraightView(const fs::path& calibration, const std::string& axis, const fs::path& image, cv::Size pattern,
                      const std::string& view_options, double max_bend_px) {
  if (!fs::exists(calibration)) {
    std::printf("%s: skipped (not present)\n", calibration.string().c_str());
    return;
  }
  const std::string rig = (kWork / "straight.yaml").string(), view = (kWork / "view.png").string();
  CHECK_EQ(Run(kTool + " import --format ocam '" + calibration.string() + "' --name left --axis " + axis + " --out " + rig), 0);
  CHECK_EQ(Run(kTool + " view " + rig + " --camera left --image '" + image.string() + "' --out " + view + " " + view_options), 0);
  const std::vector<cv::Point2f> in_view = Corners(cv::imread(view), pattern);
  const std::vector<cv::Point2f> in_image = Corners(cv::imread(image.string()), pattern);
  CHECK(!in_view.empty());
  if (in_view.empty()) return;
  const double bend_view = Bend(in_view, pattern);
  const double bend_image = in_image.empty() ? -1 : Bend(in_image, pattern);
  const double span = cv::norm(in_view.front() - in_view.back());
  std::printf("%s: checkerboard rows and columns bend by at most %.2f px over a %.0f px board in the view (%.2f px in the raw image)\n",
              calibration.parent_path().filename().string().c_str(), bend_view, span, bend_image);
  CHECK(bend_view < max_bend_px);
  if (bend_image >= 0) CHECK(bend_image > bend_view);
}

void TestCheckAndBadInputs() {
  const std::string rig = (kWork / "kuanli.yaml").string();
  const fs::path calibration = kData / "ocam_catadioptric_kuanli" / "calib_results.txt";
  const fs::path image = kData / "ocam_catadioptric_kuanli" / "example.jpg";
  std::string out, err;
  CHECK_EQ(Run(kTool + " import --format ocam '" + calibration.string() + "' --name left --out " + rig), 0);
  // The calibration is for a crop of the image: refused with both sizes named.
  CHECK_EQ(Run(kTool + " check " + rig + " --images left=" + image.string() + " --out " + (kWork / "check").string(), &out, &err), 1);
  CHECK(err.find("1920x1080") != std::string::npos && err.find("1300x1080") != std::string::npos);
  CHECK_EQ(Run(kTool + " check " + rig + " --images left=" + image.string() + " --crop 700,0 --out " + (kWork / "check").string(),
               &out, &err), 1);
  CHECK(err.find("option --crop") != std::string::npos);
  // Cropped as the calibration says (columns 300..1599): the check picture is written.
  cv::Mat full = cv::imread(image.string());
  cv::imwrite((kWork / "crop.png").string(), full(cv::Rect(300, 0, 1300, 1080)));
  CHECK_EQ(Run(kTool + " check " + rig + " --images left=" + image.string() + " --crop 300,0 --out " + (kWork / "check").string()), 0);
  const cv::Mat drawn = cv::imread((kWork / "check" / "check_left.png").string());
  CHECK(drawn.size() == cv::Size(1300, 1080));
  CHECK(cv::norm(drawn, cv::imread((kWork / "crop.png").string()), cv::NORM_L1) > 0);  // something was drawn

  CHECK_EQ(Run(kTool + " import --format matlab x --out " + rig, &out, &err), 1);
  CHECK(err.find("unknown calibration format 'matlab'") != std::string::npos);
  std::ofstream(kWork / "short.txt") << "5 -266.588 0 1.22e-03 -5.78e-07 2.0e-09\n2 443.18 308.13\n";
  CHECK_EQ(Run(kTool + " import --format ocam " + (kWork / "short.txt").string() + " --out " + (kWork / "never.yaml").string(), &out, &err), 1);
  CHECK(err.find("short.txt: field 'center (row column)': missing") != std::string::npos);
  CHECK(!fs::exists(kWork / "never.yaml"));
  CHECK_EQ(Run(kTool + " import --format pjlab-ocam " + (kData / "ocam_surround_pjlab" / "intrinsic" / "Front.json").string() + " " +
                   (kData / "ocam_surround_pjlab" / "extrinsic" / "Front.json").string() + " --out " + rig, &out, &err), 1);
  CHECK(err.find("--bev-height") != std::string::npos);
  CHECK_EQ(Run(kTool + " view " + rig + " --camera left --image x.png", &out, &err), 1);
  CHECK(err.find("--out") != std::string::npos);
  CHECK_EQ(Run(kTool + " frobnicate " + rig, &out, &err), 1);
  CHECK(err.find("unknown command 'frobnicate'") != std::string::npos);
}

// `check --lanes`: a boundary 2 m to the right of the car drawn (magenta) where the right camera of
// PJLab's surround rig sees the road points x = 2 m, and not 1 m beside it; only the frame asked
// for; a bad lanes.csv and --frame without --lanes refused.
void TestCheckLanes() {
  const fs::path pj = kData / "ocam_surround_pjlab";
  const std::string rig = (kWork / "surround.yaml").string();
  CHECK_EQ(Run(kTool + " import --format pjlab-ocam " + (pj / "intrinsic").string() + "/*.json " + (pj / "extrinsic").string() +
               "/*.json --unit-m 0.5 --bev-height 6.2 --name back,front,left,right --out " + rig), 0);
  const dps::Rig surround = dps::ReadRig(rig);
  const dps::RigCamera& right = surround.Camera("right");
  cv::imwrite((kWork / "grey.png").string(), cv::Mat(right.model.height(), right.model.width(), CV_8UC3, cv::Scalar(90, 90, 90)));
  std::ofstream(kWork / "lanes.csv") << "frame,t,boundary,offset,heading_deg,curvature,type,confidence\n"
                                        "3,0.2,right,2.0,0,0,solid,1\n"
                                        "4,0.267,right,-5.0,0,0,solid,1\n";
  std::string out, err;
  const std::string check = kTool + " check " + rig + " --images right=" + (kWork / "grey.png").string() + " --range 8 --out " +
                            (kWork / "lanes_check").string();
  CHECK_EQ(Run(check + " --lanes " + (kWork / "lanes.csv").string() + " --frame 3", &out, &err), 0);
  CHECK(err.find("frame 3, 1 boundary") != std::string::npos);
  const cv::Mat drawn = cv::imread((kWork / "lanes_check" / "check_right.png").string());
  CHECK(!drawn.empty());
  int on = 0, off = 0, seen = 0;
  for (double z = -2.0; z <= 4.0; z += 0.5) {
    Eigen::Vector2d at, beside;
    const bool a = right.model.Project(right.vehicle_from_camera.Inverse().Apply(Eigen::Vector3d(2.0, 0, z)), &at);
    const bool b = right.model.Project(right.vehicle_from_camera.Inverse().Apply(Eigen::Vector3d(3.0, 0, z + 0.25)), &beside);
    if (!a || !b || !right.model.InImage(at) || !right.model.InImage(beside)) continue;
    ++seen;
    const auto magenta = [&](const Eigen::Vector2d& p) {
      const cv::Vec3b c = drawn.at<cv::Vec3b>(static_cast<int>(std::lround(p.y())), static_cast<int>(std::lround(p.x())));
      return c[0] > 200 && c[1] < 60 && c[2] > 200;
    };
    on += magenta(at);
    off += magenta(beside);
  }
  std::printf("check --lanes: a boundary at x = 2 m magenta at %d of %d road points the right camera sees, 1 m beside it at %d\n",
              on, seen, off);
  CHECK(seen >= 8);
  CHECK_EQ(on, seen);
  CHECK_EQ(off, 0);
  // Frame 4's boundary lies 5 m left of the car, out of the right camera's sight: nothing drawn but the check.
  CHECK_EQ(Run(check + " --lanes " + (kWork / "lanes.csv").string() + " --frame 4", &out, &err), 0);
  CHECK(err.find("frame 4, 1 boundary") != std::string::npos);
  std::ofstream(kWork / "bad_lanes.csv") << "frame,t,boundary,offset,heading_deg,curvature,type,confidence\n"
                                            "3,0.2,middle,2.0,0,0,solid,1\n";
  CHECK_EQ(Run(check + " --lanes " + (kWork / "bad_lanes.csv").string(), &out, &err), 1);
  CHECK(err.find("bad_lanes.csv") != std::string::npos);
  CHECK_EQ(Run(check + " --frame 3", &out, &err), 1);
  CHECK(err.find("--frame needs --lanes") != std::string::npos);
}


// The grey level most pixels of a picture have among its grey ones (B = G = R): the image under a
// check's drawing.
int CommonGrey(const cv::Mat& bgr) {
  std::vector<int> counts(256, 0);
  for (int r = 0; r < bgr.rows; ++r) {
    for (int c = 0; c < bgr.cols; ++c) {
      const cv::Vec3b p = bgr.at<cv::Vec3b>(r, c);
      if (p[0] == p[1] && p[1] == p[2]) ++counts[p[0]];
    }
  }
  return static_cast<int>(std::max_element(counts.begin(), counts.end()) - counts.begin());
}

// `check --drive`: frame N of a recorded drive, one camera as a video and one as an image folder
// (each frame a flat grey of its own level), drawn under each camera's check; a frame the drive
// lacks, and --drive with --images, refused.
void TestCheckDrive() {
  const std::string rig = (kWork / "surround.yaml").string();  // TestCheckLanes' import
  const dps::Rig surround = dps::ReadRig(rig);
  const cv::Size left_size(surround.Camera("left").model.width(), surround.Camera("left").model.height());
  const cv::Size right_size(surround.Camera("right").model.width(), surround.Camera("right").model.height());
  const fs::path drive = kWork / "check_drive";
  fs::create_directories(drive / "left");
  cv::VideoWriter video((drive / "right.avi").string(), cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10, right_size);
  CHECK(video.isOpened());
  for (int k = 0; k < 5; ++k) {
    video.write(cv::Mat(right_size, CV_8UC3, cv::Scalar::all(40 + 40 * k)));
    char name[16];
    std::snprintf(name, sizeof(name), "%06d.png", k);
    cv::imwrite((drive / "left" / name).string(), cv::Mat(left_size, CV_8UC3, cv::Scalar::all(200 - 40 * k)));
  }
  video.release();
  std::string out, err;
  const std::string check = kTool + " check " + rig + " --drive " + drive.string() + " --range 2 --out " +
                            (kWork / "drive_check").string();
  CHECK_EQ(Run(check + " --frame 3", &out, &err), 0);
  CHECK(err.find("frame 3") != std::string::npos);
  const int left = CommonGrey(cv::imread((kWork / "drive_check" / "check_left.png").string()));
  const int right = CommonGrey(cv::imread((kWork / "drive_check" / "check_right.png").string()));
  std::printf("check --drive --frame 3: left (PNG folder) grey %d (frame 3: 80), right (MJPG video) %d (frame 3: 160)\n",
              left, right);
  CHECK_EQ(left, 80);
  CHECK(std::abs(right - 160) <= 3);
  CHECK(!fs::exists(kWork / "drive_check" / "check_front.png"));  // the drive has no front camera
  CHECK_EQ(Run(check, &out, &err), 0);  // no --frame: the drive's first
  CHECK(err.find("frame 0") != std::string::npos);
  CHECK_EQ(CommonGrey(cv::imread((kWork / "drive_check" / "check_left.png").string())), 200);
  CHECK_EQ(Run(check + " --frame 7", &out, &err), 1);
  CHECK(err.find("no frame 7") != std::string::npos);
  CHECK_EQ(Run(check + " --images right=" + (kWork / "grey.png").string(), &out, &err), 1);
  CHECK(err.find("--images NAME=IMAGE,... or --drive DRIVE") != std::string::npos);
}

}  // namespace

int main() {
  fs::create_directories(kWork);
  TestImportShowProject();
  TestCheckAndBadInputs();
  TestCheckLanes();
  TestCheckDrive();
  // A mirror camera (its image cropped as its calibration says), the OCamCalib sample (a wide-angle
  // lens) and a ~190 degree fisheye of the same toolbox.
  // The mirror camera's view is less straight (3.2 px over its 401 px board, docs/camera_models.md):
  // asserted only to be straighter than the raw image.
  TestStraightView(kData / "ocam_catadioptric_kuanli" / "calib_results.txt", "down", kWork / "crop.png", {6, 9},
                   "--yaw-deg 125 --pitch-deg 5 --fov-deg 70 --size 800x600", 1e9);
  TestStraightView(kData / "ocam_fisheye_ocamcalib_sample" / "calib_results_fisheye.txt", "out",
                   kData / "ocam_fisheye_ocamcalib_sample" / "test_fisheye.jpg", {5, 8}, "--yaw-deg -90 --fov-deg 110 --size 1024x768", 1.0);
  TestStraightView(kShared / "ocam_fisheye_urban" / "calib_results.txt", "out", kShared / "ocam_fisheye_urban" / "Fisheye2_1.jpg", {6, 8},
                   "--yaw-deg -135 --pitch-deg 10 --fov-deg 110 --size 900x700", 1.0);
  fs::remove_all(kWork);
  return dps_test::Report();
}
