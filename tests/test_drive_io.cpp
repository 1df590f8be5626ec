// Tests of drive reading and processing: CAN logs (our format, a real comma2k19 log with its own
// columns and a separate gyro log, bad logs), frame sources, and dps-process's per-drive outputs.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "check.h"
#include "fixtures.h"
#include "dps/detect/detection_io.h"
#include "dps/pipeline/drive_io.h"
#include "dps/synth/truth_io.h"
#include "dps/pipeline/drive_processing.h"
#include "dps/synth/scene_io.h"
#include "dps/synth/synth.h"
#include "dps/util/csv.h"
#include "dps/util/error.h"

namespace {

namespace fs = std::filesystem;

const std::string kReal = dps_test::kRealData;
using dps_test::kSource;
const fs::path kTmp = fs::temp_directory_path() / "dps_test_drive_io";

constexpr double kInsPathM = 1011.8;       // data/real/README.md
constexpr double kPathTolFraction = 0.015; // wheel-speed scale vs INS
constexpr double kDisplacementTolFraction = 0.03;

std::string Write(const std::string& name, const std::string& text) {
  const fs::path p = kTmp / name;
  std::ofstream(p) << text;
  return p.string();
}

void TestCanLogs() {
  const dps::CanLog log = dps::ReadCanLog(
      Write("can.csv", "t,speed,yaw_rate,extra\n0,10,0,x\n0.4,10,0,x\n0.8,10,0.1,y\n1.2,10,0.1,y\n1.6,12,0.1,z\n2,12,0.1,z\n"));
  CHECK_NEAR(log.t_begin, 0, 0);
  CHECK_NEAR(log.t_end, 2, 0);
  dps::PlanarPose p;
  std::string why;
  CHECK(dps::MotionBetween(log, 0.0, 0.5, &p, &why));
  CHECK_NEAR(p.z_m, 5.0, 1e-6);  // 10 m/s for 0.5 s, nearly straight
  CHECK(dps::MotionBetween(log, 1.0, 1.5, &p, &why));
  CHECK_NEAR(p.heading_rad, -0.05, 1e-9);  // 0.1 rad/s to the left for 0.5 s
  CHECK(!dps::MotionBetween(log, 1.5, 2.5, &p, &why));
  CHECK(why.find("outside the CAN log") != std::string::npos);
  // Times that are not finite never reach the integration (a NaN frame time read past the samples).
  CHECK(!dps::MotionBetween(log, 0.5, std::nan(""), &p, &why));
  CHECK(why.find("not finite") != std::string::npos);
  CHECK(!dps::MotionBetween(log, -HUGE_VAL, HUGE_VAL, &p, &why));
  CHECK_THROWS_WITH(log.profile.At(std::nan("")), std::invalid_argument, "not finite");
  // frames.csv: NaN, infinite, repeated or backwards times are errors naming the line.
  CHECK_THROWS_WITH(dps::ReadFrameTimes(Write("frames.csv", "frame,t\n0,0\n1,nan\n")), dps::Error, "frames.csv:3");
  CHECK_THROWS_WITH(dps::ReadFrameTimes(Write("frames.csv", "frame,t\n0,0\n1,inf\n")), dps::Error, "no finite time");
  CHECK_THROWS_WITH(dps::ReadFrameTimes(Write("frames.csv", "frame,t\n0,0\n1,0\n")), dps::Error, "does not come after");
  CHECK_THROWS_WITH(dps::ReadFrameTimes(Write("frames.csv", "frame,t\n0,1\n1,0.5\n")), dps::Error, "does not come after");
  // Whole numbers out of int's range are errors naming the cell, not undefined casts.
  CHECK_THROWS_WITH(dps::ReadTruth(Write("truth.csv", "frame,t,id,kind,x,z,heading_deg,length,width,height,vx,vz\n1e300,0,1,car,0,5,0,4,2,1.5,0,0\n")),
                    dps::Error, "truth.csv:2: column 'frame': '1e300' is not a whole number in range");
  CHECK_THROWS_WITH(dps::ReadDetections(Write("det.csv", "frame,t,source,id,x,z,range,x_min,x_max,z_min,z_max,n_points\n"
                                                         "0,0,front,nan,1,5,5,0,2,4,6,10\n")),
                    dps::Error, "det.csv:2: column 'id'");
  // Units and names of another log: km/h and deg/s.
  dps::CanLogFormat f;
  f.time_column = "time";
  f.speed_column = "v_kmh";
  f.speed_scale = 1 / 3.6;
  f.yaw_rate_column = "yaw_dps";
  f.yaw_rate_scale = M_PI / 180;
  const dps::CanLog kmh = dps::ReadCanLog(Write("kmh.csv", "time,v_kmh,yaw_dps\n0,36,0\n1,36,0\n"), f);
  CHECK_NEAR(kmh.profile.At(0.5).speed_mps, 10.0, 1e-12);
  // NaN rows and duplicate times are dropped with a warning; a gap makes motion unknown.
  const dps::CanLog gappy = dps::ReadCanLog(Write("gappy.csv", "t,speed\n0,5\n0.1,nan\n0.1,5\n0.1,6\n2,5\n2.1,5\n"));
  CHECK_EQ(gappy.warnings.size(), size_t{2});
  CHECK_EQ(gappy.gaps.size(), size_t{1});
  CHECK(!dps::MotionBetween(gappy, 1.0, 1.1, &p, &why));
  CHECK(why.find("gap") != std::string::npos);
  CHECK(dps::MotionBetween(gappy, 2.0, 2.1, &p, &why));
  // Bad logs.
  CHECK_THROWS_WITH(dps::ReadCanLog(Write("back.csv", "t,speed\n0,1\n2,1\n1,1\n")), dps::Error, "back.csv:4: time 1 goes backwards");
  CHECK_THROWS_WITH(dps::ReadCanLog(Write("nospeed.csv", "t,v\n0,1\n1,1\n")), dps::Error, "missing column 'speed'");
  CHECK_THROWS_WITH(dps::ReadCanLog(Write("short.csv", "t,speed\n0,1\n")), dps::Error, "fewer than 2");
}

// The real comma2k19 minute: speed from can_speed.csv, yaw rate from the IMU's gyro. The ego
// motion integrated from them must have the INS path's length and end-to-end displacement.
void TestComma2k19() {
  const std::string dir = kReal + "/can_logs/comma2k19/";
  dps::CanLogFormat f;
  f.time_column = "t_boot_s";
  f.speed_column = "car_speed_mps";
  f.yaw_rate_file = dir + "imu_gyro.csv";
  f.yaw_rate_time_column = "t_boot_s";
  f.yaw_rate_column = "gz";
  const dps::CanLog log = dps::ReadCanLog(dir + "can_speed.csv", f);
  // The INS positions (ECEF) over the same span.
  const dps::CsvTable ins = dps::CsvTable::Read(dir + "frame_poses.csv");
  const int t = ins.Column("t_boot_s"), x = ins.Column("ecef_x"), y = ins.Column("ecef_y"), z = ins.Column("ecef_z");
  std::vector<Eigen::Vector3d> pos;
  std::vector<double> times;
  for (size_t r = 0; r < ins.rows(); ++r) {
    const double tr = ins.Number(r, t);
    if (tr < log.t_begin || tr > log.t_end) continue;
    times.push_back(tr);
    pos.push_back({ins.Number(r, x), ins.Number(r, y), ins.Number(r, z)});
  }
  CHECK(times.size() > 1000);
  double ins_length = 0;
  for (size_t i = 1; i < pos.size(); ++i) ins_length += (pos[i] - pos[i - 1]).norm();
  // Integrate over the INS samples' times, summing the chords like the INS path.
  double length = 0;
  dps::PlanarPose pose;
  for (size_t i = 1; i < times.size(); ++i) {
    dps::PlanarPose step;
    std::string why;
    CHECK(dps::MotionBetween(log, times[i - 1], times[i], &step, &why));
    length += std::hypot(step.x_m, step.z_m);
    // Compose: step is in the vehicle frame at times[i - 1].
    const double c = std::cos(pose.heading_rad), s = std::sin(pose.heading_rad);
    pose.x_m += c * step.x_m + s * step.z_m;
    pose.z_m += -s * step.x_m + c * step.z_m;
    pose.heading_rad += step.heading_rad;
  }
  const double displacement = std::hypot(pose.x_m, pose.z_m);
  const double ins_displacement = (pos.back() - pos.front()).norm();
  std::printf("comma2k19: %.1f s; path %.1f m (INS %.1f m over the same span, %.1f m in all); displacement %.1f m "
              "(INS %.1f m); heading change %.1f deg\n",
              times.back() - times.front(), length, ins_length, kInsPathM, displacement, ins_displacement,
              pose.heading_rad * 180 / M_PI);
  CHECK_NEAR(length / ins_length, 1.0, kPathTolFraction);
  CHECK_NEAR(ins_length, kInsPathM, 15.0);
  CHECK_NEAR(displacement / ins_displacement, 1.0, kDisplacementTolFraction);
}

void CheckEstimatedMasks(const dps::DriveSummary& s, const fs::path& drive, const fs::path& out) {
  const dps::Rig rig = dps::ReadRig((drive / "rig.yaml").string());
  for (const char* name : {"left", "right"}) {
    CHECK_EQ(s.masks.at(name).source, std::string("estimated"));
    const cv::Mat mask = cv::imread((out / "masks" / (std::string(name) + ".png")).string(), cv::IMREAD_GRAYSCALE);
    CHECK(!mask.empty());
    if (mask.empty()) continue;
    const dps::CameraModel& m = rig.Camera(name).model;
    const double margin = std::ceil(dps::FieldMaskOptions().edge_margin_fraction * m.width()) + 1.5;
    int wrong = 0;
    for (int y = 0; y < mask.rows; ++y) {
      for (int x = 0; x < mask.cols; ++x) {
        const double r = std::hypot(x - m.K()(0, 2), y - m.K()(1, 2));
        if (r < m.rim_radius_px() - margin) wrong += mask.at<std::uint8_t>(y, x) == 0;
        if (r > m.rim_radius_px() + 1.0) wrong += mask.at<std::uint8_t>(y, x) != 0;
      }
    }
    CHECK_EQ(wrong, 0);
    // The own car apart (the car drives off, so it is estimated; test_valid_mask checks it against
    // the renderer's own car), written beside the mask.
    const cv::Mat own = cv::imread((out / "masks" / (std::string(name) + "_own_car.png")).string(), cv::IMREAD_GRAYSCALE);
    CHECK_EQ(s.masks.at(name).own_car_source, std::string("estimated"));
    CHECK(!own.empty());
    if (!own.empty()) {
      std::printf("%s: own car %.3f of the pixels\n", name, s.masks.at(name).own_car_fraction);
      CHECK(s.masks.at(name).own_car_fraction > 0.01);
      CHECK_NEAR(s.masks.at(name).own_car_fraction, cv::countNonZero(own) / static_cast<double>(own.total()), 1e-9);
    }
    CHECK_NEAR(s.masks.at(name).valid_fraction, cv::countNonZero(mask) / static_cast<double>(mask.total()), 1e-9);
  }
  CHECK(s.ToJson().find("\"masks\": {\"left\": {\"source\": \"estimated\"") != std::string::npos);
}

// A mask placed in the drive is the one used (and written back).
void CheckDriveMask(const fs::path& drive, const fs::path& out_root, const dps::DriveOptions& o) {
  const dps::Rig rig = dps::ReadRig((drive / "rig.yaml").string());
  const dps::CameraModel& m = rig.Camera("left").model;
  cv::Mat mask(m.height(), m.width(), CV_8U, cv::Scalar(255));
  mask.rowRange(0, m.height() / 3).setTo(0);
  fs::create_directories(drive / "masks");
  cv::imwrite((drive / "masks" / "left.png").string(), mask);
  const dps::DriveSummary s = dps::ProcessDrive(drive.string(), out_root.string(), o);
  CHECK_EQ(s.masks.at("left").source, std::string("drive"));
  CHECK_EQ(s.masks.at("right").source, std::string("estimated"));
  const cv::Mat used = cv::imread((out_root / drive.filename() / "masks" / "left.png").string(), cv::IMREAD_GRAYSCALE);
  CHECK(!used.empty() && cv::countNonZero(used.rowRange(0, m.height() / 3)) == 0);
  // The own car likewise: a drive's masks/<camera>_own_car.png instead of the estimate.
  cv::Mat own(m.height(), m.width(), CV_8U, cv::Scalar(0));
  own.rowRange(m.height() * 3 / 4, m.height()).setTo(255);
  cv::imwrite((drive / "masks" / "right_own_car.png").string(), own);
  const dps::DriveSummary with_own = dps::ProcessDrive(drive.string(), (out_root / "own").string(), o);
  CHECK_EQ(with_own.masks.at("right").own_car_source, std::string("drive"));
  CHECK_NEAR(with_own.masks.at("right").own_car_fraction, 0.25, 1e-9);
  CHECK_EQ(with_own.masks.at("left").own_car_source, std::string("estimated"));
  const cv::Mat own_used =
      cv::imread((out_root / "own" / drive.filename() / "masks" / "right_own_car.png").string(), cv::IMREAD_GRAYSCALE);
  CHECK(!own_used.empty() && cv::countNonZero(own_used != own) == 0);
  fs::remove(drive / "masks" / "right_own_car.png");
  cv::imwrite((drive / "masks" / "left.png").string(), cv::Mat(8, 8, CV_8U, cv::Scalar(255)));
  CHECK_THROWS_WITH(dps::ProcessDrive(drive.string(), (out_root / "bad").string(), o), dps::Error,
                    "left.png: the mask is 8x8");
  fs::remove_all(drive / "masks");
}

// The grid written every 2nd frame: 16-bit pictures of the grid's size, grid.csv naming each with
// its origin and the vehicle's pose, summary.json the encoding; each detection of a written frame
// lies on a cell of positive evidence when mapped through grid.csv's pose and origin.
void CheckGridFiles(const fs::path& drive, const fs::path& out_root, dps::DriveOptions o) {
  o.grid_every = 2;
  o.map_png = false;
  const dps::DriveSummary s = dps::ProcessDrive(drive.string(), out_root.string(), o);
  const fs::path out = out_root / drive.filename();
  const dps::CsvTable index = dps::CsvTable::Read((out / "grid" / "grid.csv").string());
  CHECK_EQ(index.rows(), size_t{3});  // frames 0, 2, 4 of 6
  CHECK(s.ToJson().find("\"grid\": {") != std::string::npos);
  const double per_step = 1.0 / s.grid_scale;
  const std::vector<dps::Detection> dets = dps::ReadDetections((out / "detections.csv").string());
  int checked = 0;
  for (size_t r = 0; r < index.rows(); ++r) {
    const int frame = index.Integer(r, index.Column("frame"));
    const cv::Mat grid = cv::imread((out / index.Text(r, index.Column("file"))).string(), cv::IMREAD_UNCHANGED);
    CHECK_EQ(grid.type(), CV_16U);
    CHECK_EQ(grid.rows, s.grid_cells);
    const dps::PlanarPose pose{index.Number(r, index.Column("vehicle_x")), index.Number(r, index.Column("vehicle_z")),
                               index.Number(r, index.Column("vehicle_heading_deg")) * M_PI / 180.0};
    const Eigen::Vector2d origin(index.Number(r, index.Column("origin_x")), index.Number(r, index.Column("origin_z")));
    for (const dps::Detection& d : dets) {
      if (d.frame != frame) continue;
      const Eigen::Vector2d w = dps::BodyToWorld(pose, {d.x_m, d.z_m});
      const int c = static_cast<int>(std::floor((w.x() - origin.x()) / s.grid_cell_m));
      const int row = s.grid_cells - 1 - static_cast<int>(std::floor((w.y() - origin.y()) / s.grid_cell_m));
      double best = -1e9;  // the nearest point lies on the surface: the cell or its neighbour
      for (int dr = -1; dr <= 1; ++dr) {
        for (int dc = -1; dc <= 1; ++dc) {
          best = std::max(best, (grid.at<unsigned short>(row + dr, c + dc) - 32768.0) * per_step);
        }
      }
      CHECK(best > 0);
      ++checked;
    }
  }
  std::printf("grid files: %zu written, %d detections on occupied cells checked\n", index.rows(), checked);
  CHECK(checked >= 1);
}

void TestProcessDrive() {
  dps::Scene scene = dps_test::SmallScene("lead_car", 320, 240);
  dps::SynthOptions so;
  so.frames = 6;
  so.overwrite = true;
  dps::Synthesize(scene, (kTmp / "drives" / "lead").string(), so);
  dps::DriveOptions o;
  o.map_png = true;
  int calls = 0;
  const dps::DriveSummary s =
      dps::ProcessDrive((kTmp / "drives" / "lead").string(), (kTmp / "out").string(), o, [&](int, int) { ++calls; });
  CHECK_EQ(s.frames, 6);
  CHECK_EQ(calls, 6);
  CHECK(dps::DriveOutputComplete((kTmp / "out" / "lead").string()));
  for (const char* f : {"detections.csv", "summary.json", "map/000005.png"}) CHECK(fs::exists(kTmp / "out" / "lead" / f));
  // The map video: MP4 (or AVI where OpenCV has no MP4 encoder) with every frame, or a warning.
  const fs::path mp4 = kTmp / "out" / "lead" / "map.mp4", avi = kTmp / "out" / "lead" / "map.avi";
  const fs::path video = fs::exists(mp4) ? mp4 : avi;
  if (fs::exists(video)) {
    cv::VideoCapture replay(video.string());
    int read = 0;
    for (cv::Mat m; replay.read(m); ++read) CHECK_EQ(m.cols, 600);
    std::printf("map video %s: %d frames read back\n", s.map_video.c_str(), read);
    CHECK_EQ(read, 6);
    CHECK_EQ(s.map_video.rfind(video.filename().string(), 0), size_t{0});  // summary.json names it
    CHECK(s.ToJson().find("\"map_video\": \"" + s.map_video + "\"") != std::string::npos);
  } else {
    CHECK(!s.warnings.empty());
    CHECK(s.map_video.empty());
  }
  // The masks used: estimated from the images (the rig names none), written for the user; the
  // renderer's rim is where the estimate puts the field's end, within the edge margin.
  CheckEstimatedMasks(s, kTmp / "drives" / "lead", kTmp / "out" / "lead");
  const std::vector<dps::Detection> d = dps::ReadDetections((kTmp / "out" / "lead" / "detections.csv").string());
  CHECK_EQ(static_cast<int>(d.size()), s.detections);
  for (const auto& e : fs::directory_iterator(kTmp / "out")) {
    CHECK(e.path().filename().string().find(".tmp") == std::string::npos);
  }
  // Side views: matched in every frame after the first at the scene's speed; the same drive with a
  // CAN log of 2 m/s (0.13 m between frames at 15 fps, under the 0.21 m at which a static object 6 m
  // out shifts 3 px in 320x240's side views): none matched, and summary.json says so per camera.
  CHECK_EQ(s.frames_side_skipped.at("left"), 0);
  CHECK_EQ(s.frames_side_skipped.at("right"), 0);
  const fs::path slow = kTmp / "drives" / "slow";
  fs::remove_all(slow);
  fs::copy(kTmp / "drives" / "lead", slow, fs::copy_options::recursive);
  {
    std::ofstream can(slow / "can.csv");
    can << "t,speed,yaw_rate\n";
    for (int i = 0; i <= 100; ++i) can << i * 0.01 << ",2,0\n";
  }
  const dps::DriveSummary slow_summary = dps::ProcessDrive(slow.string(), (kTmp / "out_slow").string(), o);
  std::printf("slow drive: side views skipped in %d / %d frames (left / right)\n", slow_summary.frames_side_skipped.at("left"),
              slow_summary.frames_side_skipped.at("right"));
  CHECK_EQ(slow_summary.frames_side_skipped.at("left"), 5);
  CHECK_EQ(slow_summary.frames_side_skipped.at("right"), 5);
  CHECK(slow_summary.ToJson().find("\"frames_side_skipped\": {\"left\": 5, \"right\": 5}") != std::string::npos);
  CheckDriveMask(kTmp / "drives" / "lead", kTmp / "out_masked", o);
  CheckGridFiles(kTmp / "drives" / "lead", kTmp / "out_grid", o);
  // Left and right of different lengths: an error naming both, no output left behind.
  fs::remove(kTmp / "drives" / "lead" / "right" / "000005.png");
  CHECK_THROWS_WITH(dps::ProcessDrive((kTmp / "drives" / "lead").string(), (kTmp / "out2").string(), o), dps::Error,
                    "has frames 0..5");
  CHECK(!fs::exists(kTmp / "out2" / "lead"));
  o.truncate = true;
  CHECK_EQ(dps::ProcessDrive((kTmp / "drives" / "lead").string(), (kTmp / "out2").string(), o).frames, 5);
  // --truncate pairs by number: right without its first frame pairs left 1 with right 1.
  const fs::path pairs = kTmp / "drives" / "pairs";
  fs::copy(kTmp / "drives" / "lead", pairs, fs::copy_options::recursive);
  fs::remove(pairs / "right" / "000000.png");
  const dps::DriveSummary paired = dps::ProcessDrive(pairs.string(), (kTmp / "out_pairs").string(), o);
  CHECK_EQ(paired.frames, 4);
  CHECK(paired.ToJson().find("processing frames 1..4") != std::string::npos);
  // frames.csv with a frame lost between frames 2 and 3 (0.133 s apart, the others 0.067 s): an
  // error naming them; with allow_frame_gaps processed with a warning.
  const fs::path gap = kTmp / "drives" / "gap";
  fs::copy(kTmp / "drives" / "lead", gap, fs::copy_options::recursive);
  std::ofstream(gap / "frames.csv") << "frame,t\n0,0\n1,0.0666667\n2,0.1333333\n3,0.2666667\n4,0.3333333\n5,0.4\n";
  CHECK_THROWS_WITH(dps::ProcessDrive(gap.string(), (kTmp / "out_gap").string(), o), dps::Error,
                    "frames.csv: frames 2 and 3 are 0.1333334 s apart, 2.00000");
  CHECK(!fs::exists(kTmp / "out_gap" / "gap"));
  o.allow_frame_gaps = true;
  const dps::DriveSummary across = dps::ProcessDrive(gap.string(), (kTmp / "out_gap").string(), o);
  CHECK_EQ(across.frames, 5);
  CHECK(across.ToJson().find("frames 2 and 3 are 0.1333334 s apart") != std::string::npos);
  // An image lost from one camera's folder (left 000003.png): an error naming it; with
  // allow_frame_gaps the frames both cameras have (0, 1, 2, 4: right ends at 4), as frames 0, 1, 2
  // and 4 of the outputs - never paired by position.
  const fs::path holes = kTmp / "drives" / "holes";
  fs::copy(kTmp / "drives" / "lead", holes, fs::copy_options::recursive);
  fs::remove(holes / "left" / "000003.png");
  o.allow_frame_gaps = false;
  CHECK_THROWS_WITH(dps::ProcessDrive(holes.string(), (kTmp / "out_holes").string(), o), dps::Error,
                    "left: frame 3 missing (000002.png is followed by 000004.png)");
  o.allow_frame_gaps = true;
  o.map_png = true;
  const dps::DriveSummary holed = dps::ProcessDrive(holes.string(), (kTmp / "out_holes").string(), o);
  CHECK_EQ(holed.frames, 4);
  CHECK(holed.ToJson().find("1 of frames 0..4 missing") != std::string::npos);
  for (const dps::Detection& d : dps::ReadDetections((kTmp / "out_holes" / "holes" / "detections.csv").string())) {
    CHECK(d.frame != 3 && d.frame >= 0 && d.frame <= 4);
  }
  CHECK(fs::exists(kTmp / "out_holes" / "holes" / "map" / "000004.png"));
  CHECK(!fs::exists(kTmp / "out_holes" / "holes" / "map" / "000003.png"));
  o.allow_frame_gaps = false;
  // Numbers without zero padding are ordered by number (2.png before 10.png); a gap, a number
  // twice or a file without a number are errors naming the frame.
  const fs::path plain = kTmp / "plain";
  fs::create_directories(plain);
  const cv::Mat tiny(4, 4, CV_8UC3, cv::Scalar(1, 2, 3));
  for (int i = 0; i <= 11; ++i) cv::imwrite((plain / (std::to_string(i) + ".png")).string(), tiny + cv::Scalar::all(i));
  auto source = dps::FrameSource::Open(kTmp.string(), "plain");
  cv::Mat frame;
  for (int i = 0; i <= 11; ++i) {
    CHECK(source->Read(&frame));
    CHECK_EQ(static_cast<int>(frame.at<cv::Vec3b>(0, 0)[0]), 1 + i);
  }
  cv::imwrite((plain / "003.png").string(), tiny);
  CHECK_THROWS_WITH(dps::FrameSource::Open(kTmp.string(), "plain"), dps::Error, "frame 3 twice");
  fs::remove(plain / "003.png");
  fs::remove(plain / "3.png");
  fs::remove(plain / "4.png");
  CHECK_THROWS_WITH(dps::FrameSource::Open(kTmp.string(), "plain"), dps::Error, "frame 3 to 4 missing (2.png is followed by 5.png)");
  cv::imwrite((plain / "cover.png").string(), tiny);
  CHECK_THROWS_WITH(dps::FrameSource::Open(kTmp.string(), "plain"), dps::Error, "cover.png: not a numbered frame");
  // A drive without can.csv.
  fs::remove(kTmp / "drives" / "lead" / "can.csv");
  CHECK_THROWS_WITH(dps::ProcessDrive((kTmp / "drives" / "lead").string(), (kTmp / "out3").string(), o), dps::Error,
                    "can.csv");
  CHECK_THROWS_WITH(dps::FrameSource::Open((kTmp / "drives").string(), "left"), dps::Error, "no 'left/'");
}

}  // namespace

int main() {
  fs::remove_all(kTmp);
  fs::create_directories(kTmp);
  TestCanLogs();
  TestComma2k19();
  TestProcessDrive();
  fs::remove_all(kTmp);
  return dps_test::Report();
}
