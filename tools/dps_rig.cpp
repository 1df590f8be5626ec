// dps-rig: bring a real rig's calibration in, look at it, and use it from scripts.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

#include <Eigen/Geometry>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "cli.h"
#include "dps/camera/calibration_import.h"
#include "dps/camera/rig_io.h"
#include "dps/camera/rig_report.h"
#include "dps/pipeline/drive_io.h"
#include "dps/stereo/virtual_view.h"
#include "dps/util/atomic_file.h"
#include "dps/util/image.h"
#include "dps/util/math.h"

namespace {

const char* kUsage = R"(usage: dps-rig COMMAND ...

  dps-rig import --format FORMAT FILE... --out rig.yaml [options]
      Reads a calibration from another toolbox into rig.yaml (DESIGN.md §3.1). FORMAT:
        ocam            OCamCalib calib_results.txt (or the same numbers in YAML: ss, invpol, xy, cde, shape)
        omnidir         cv::omnidir result (K, D, xi; also plain YAML as numpy writes it)
        opencv-fisheye  cv::fisheye result (K, D)
        kitti360        KITTI-360 image_0N.yaml (MEI) files and calib_cam_to_pose.txt
        pjlab-ocam      PJLab SensorsCalibration surround JSON: intrinsic/*.json and extrinsic/*.json
      One camera per intrinsics file. Extrinsics come from the files where they have them
      (kitti360, pjlab-ocam), converted into the vehicle frame (X right, Y down, Z forward, origin
      on the road below the car's centre); other cameras get a nominal side-mirror mount.
        --name A,B,...          the cameras' names in file order (dps-process uses left and right)
        --vehicle-length M      the own car, metres (default 4.8)
        --vehicle-width M       (default 1.8)
        --size WxH              image size for files that have none
        --origin X,Y,Z          kitti360: where the pose frame's origin (the GPS/IMU) lies in the
                                vehicle frame, metres (default 0,0,0)
        --bev-height H | CAMERA=H,...
                                pjlab-ocam: the bird's-eye camera's height above the road in the
                                files' units, for all cameras or per camera (source names; required)
        --unit-m U              metres per unit of the files' translations (default 1)
        --axis down|out         nominal mount: axis down (mirror cameras, default) or looking out
        --height M              nominal mount: camera height above the road (default 1.0)

  dps-rig show rig.yaml [--out footprints.png] [--range M]
      One line per camera (model, field, position, where its axis points, how much of the road
      within 10 m it sees) and, with --out, a top-down picture of every camera's footprint on the
      road around the own car (--range metres, default 12).

  dps-rig project rig.yaml --camera NAME      stdin: x,y,z (vehicle frame, m)  stdout: u,v,valid
  dps-rig unproject rig.yaml --camera NAME    stdin: u,v (pixels)              stdout: dx,dy,dz,valid
      CSV with a header line; the ray is a unit vector in the vehicle frame from the camera's
      viewpoint. valid = 0 where the model has no answer (the other columns are then empty).

  dps-rig check rig.yaml (--images NAME=IMAGE[,NAME=IMAGE...] | --drive DRIVE) --out DIR [--frame N]
               [--range M] [--grid M] [--crop X,Y] [--ext png|jpg] [--lanes lanes.csv]
      Draws the valid field's outline (green), the horizon (yellow), a road grid (cyan, every
      --grid metres within --range) and the own car (red) over each camera's image:
      DIR/check_NAME.png (or .jpg). If the grid is not on the road, the calibration or mounting is
      wrong. --drive: the images are frame N of a recorded drive (each rig camera's video or image
      folder the drive has, DESIGN.md 3.2; default the first of lanes.csv or of the drive).
      --lanes: also the lane boundaries dps-process found (its lanes.csv) in frame N (default the
      file's first), magenta and named, within --range along the car.

  dps-rig view rig.yaml --camera NAME --image IMAGE --out VIEW.png [--yaw-deg A] [--pitch-deg P]
               [--fov-deg F] [--size WxH] [--crop X,Y]
      A virtual perspective view from the camera's image: looking at azimuth A (degrees from
      straight ahead, + = right; default 0) and P degrees below the horizon (default 0), F degrees
      across (default 90), WxH pixels (default 640x480). Straight edges must come out straight.
      --crop X,Y: the calibration is for a crop of the image, from column X, row Y.

  --help    this text
)";

std::vector<std::string> SplitList(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

std::vector<double> Numbers(const std::string& option, const std::string& text) {
  std::vector<double> out;
  for (const std::string& item : SplitList(text)) {
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (*end != '\0' || !std::isfinite(v)) throw dps::Error("option --" + option + ": '" + item + "' is not a number");
    out.push_back(v);
  }
  return out;
}

int Import(const dps_cli::Args& args) {
  if (!args.Has("format")) throw dps::Error("import: missing --format (see --help)");
  if (!args.Has("out")) throw dps::Error("import: missing --out rig.yaml");
  dps::ImportOptions o;
  o.format = dps::CalibrationFormatFromName(args.Get("format"));
  o.files.assign(args.positional().begin() + 1, args.positional().end());
  o.names = SplitList(args.Get("name"));
  o.vehicle.length_m = args.Number("vehicle-length", o.vehicle.length_m);
  o.vehicle.width_m = args.Number("vehicle-width", o.vehicle.width_m);
  o.size = args.Size("size", cv::Size());
  if (args.Has("origin")) {
    const std::vector<double> v = Numbers("origin", args.Get("origin"));
    if (v.size() != 3) throw dps::Error("option --origin: expected X,Y,Z");
    o.source_origin = Eigen::Vector3d(v[0], v[1], v[2]);
  }
  if (args.Get("bev-height").find('=') == std::string::npos) {
    o.bev_height_m = args.Number("bev-height", 0.0);
  } else {
    for (const auto& [camera, h] : args.Pairs("bev-height", "H")) {
      const std::vector<double> v = Numbers("bev-height", h);
      if (v.size() != 1) throw dps::Error("option --bev-height: expected H or CAMERA=H,..., got '" + h + "'");
      o.bev_height_by_camera[camera] = v[0];
    }
  }
  o.source_unit_m = args.Number("unit-m", 1.0);
  const std::string axis = args.Get("axis", "down");
  if (axis != "down" && axis != "out") throw dps::Error("option --axis: expected down or out, got '" + axis + "'");
  o.nominal_axis = axis == "down" ? dps::NominalAxis::kDown : dps::NominalAxis::kOut;
  o.nominal_height_m = args.Number("height", o.nominal_height_m);
  std::vector<std::string> notes;
  const dps::Rig rig = dps::ImportRig(o, &notes);
  dps::WriteRig(rig, args.Get("out"));
  for (const std::string& n : notes) std::cerr << n << "\n";
  std::cout << dps::RigSummary(rig);
  return 0;
}

int Show(const dps_cli::Args& args, const dps::Rig& rig) {
  std::cout << dps::RigSummary(rig);
  if (args.Has("out")) {
    dps::WriteImageAtomically(args.Get("out"), dps::DrawRigFootprints(rig, args.Number("range", 12.0)));
    std::cerr << "footprints: " << args.Get("out") << "\n";
  }
  return 0;
}

// Reads CSV rows of `columns` numbers from stdin (a header line first, skipped when it is not
// numeric) and writes one output row per input row.
template <typename Row>
int Stream(int columns, const std::string& header, Row&& row) {
  std::cout << header << "\n";
  std::cout.precision(15);
  std::string line;
  int number = 0;
  while (std::getline(std::cin, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    std::vector<double> v;
    bool numeric = true;
    for (const std::string& item : SplitList(line)) {
      char* end = nullptr;
      v.push_back(std::strtod(item.c_str(), &end));
      numeric = numeric && end != item.c_str() && *end == '\0';
    }
    if (!numeric && number == 1) continue;  // the header
    if (!numeric || static_cast<int>(v.size()) != columns) {
      throw dps::Error(dps::Str("stdin line ", number, ": expected ", columns, " numbers, got '", line, "'"));
    }
    row(v);
  }
  return 0;
}

int Project(const dps_cli::Args& args, const dps::Rig& rig) {
  const dps::RigCamera& c = rig.Camera(args.Get("camera"));
  const dps::Pose camera_from_vehicle = c.vehicle_from_camera.Inverse();
  return Stream(3, "u,v,valid", [&](const std::vector<double>& p) {
    Eigen::Vector2d px;
    if (c.model.Project(camera_from_vehicle.Apply({p[0], p[1], p[2]}), &px)) {
      std::cout << px.x() << "," << px.y() << ",1\n";
    } else {
      std::cout << ",,0\n";
    }
  });
}

int Unproject(const dps_cli::Args& args, const dps::Rig& rig) {
  const dps::RigCamera& c = rig.Camera(args.Get("camera"));
  return Stream(2, "dx,dy,dz,valid", [&](const std::vector<double>& p) {
    Eigen::Vector3d ray;
    if (c.model.Unproject({p[0], p[1]}, &ray)) {
      const Eigen::Vector3d d = c.vehicle_from_camera.Rotate(ray);
      std::cout << d.x() << "," << d.y() << "," << d.z() << ",1\n";
    } else {
      std::cout << ",,,0\n";
    }
  });
}

// An image read (as BGR) for a camera; with --crop X,Y, the model's size from column X, row Y (for
// calibrations of a crop of the camera's frames).
cv::Mat CameraImage(const dps_cli::Args& args, cv::Mat image, const std::string& path, const dps::CameraModel& model) {
  if (image.channels() == 1) cv::cvtColor(image, image, cv::COLOR_GRAY2BGR);
  if (args.Has("crop")) {
    const std::vector<double> xy = Numbers("crop", args.Get("crop"));
    const cv::Rect crop(xy.size() == 2 ? static_cast<int>(xy[0]) : -1, xy.size() == 2 ? static_cast<int>(xy[1]) : -1,
                        model.width(), model.height());
    if (xy.size() != 2 || crop.x != xy[0] || crop.y != xy[1] || crop.x < 0 || crop.y < 0 || crop.br().x > image.cols ||
        crop.br().y > image.rows) {
      throw dps::Error(dps::Str("option --crop: expected X,Y (whole pixels) with the calibration's ", model.width(), "x",
                                model.height(), " inside the ", image.cols, "x", image.rows, " image ", path));
    }
    image = image(crop).clone();
  }
  if (image.cols != model.width() || image.rows != model.height()) {
    throw dps::Error(dps::Str(path, ": ", image.cols, "x", image.rows, ", the calibration is for ", model.width(), "x",
                              model.height(), " (a crop? see --crop)"));
  }
  return image;
}

cv::Mat ReadImage(const dps_cli::Args& args, const std::string& path, const dps::CameraModel& model) {
  cv::Mat image = cv::imread(path, cv::IMREAD_COLOR);
  if (image.empty()) throw dps::Error(path + ": cannot read image");
  return CameraImage(args, image, path, model);
}

// Frame `*number` of each rig camera that a recorded drive has (a video or an image folder; a
// camera it lacks is left out), by camera name; without a number, the first camera's first frame
// (and *number becomes it). Throws dps::Error when the drive has none of the cameras or lacks the
// frame.
std::vector<std::pair<std::string, cv::Mat>> DriveFrames(const dps_cli::Args& args, const dps::Rig& rig,
                                                         const std::string& drive, std::optional<long>* number) {
  std::vector<std::pair<std::string, cv::Mat>> frames;
  for (const dps::RigCamera& c : rig.cameras) {
    if (dps::FrameSource::Find(drive, c.name).empty()) continue;
    const std::unique_ptr<dps::FrameSource> source = dps::FrameSource::Open(drive, c.name);
    if (!*number) *number = source->first_number();
    source->SkipTo(**number);
    cv::Mat image;
    const std::vector<long> numbers = source->numbers();
    const bool listed = numbers.empty() || std::find(numbers.begin(), numbers.end(), **number) != numbers.end();
    if (!source->Read(&image) || !listed) {
      throw dps::Error(dps::Str(source->description(), ": no frame ", **number));
    }
    frames.emplace_back(c.name, CameraImage(args, image, source->description(), c.model));
  }
  if (frames.empty()) throw dps::Error(drive + ": no video or image folder of the rig's cameras");
  return frames;
}

int Check(const dps_cli::Args& args, const dps::Rig& rig) {
  if (args.Has("images") == args.Has("drive") || !args.Has("out")) {
    throw dps::Error("check: needs --images NAME=IMAGE,... or --drive DRIVE, and --out DIR");
  }
  const std::string dir = args.Get("out"), ext = args.Get("ext", "png");
  if (ext != "png" && ext != "jpg") throw dps::Error("option --ext: expected png or jpg, got '" + ext + "'");
  std::vector<std::pair<std::string, std::string>> images;
  if (args.Has("images")) images = args.Pairs("images", "IMAGE");
  std::vector<std::string> inputs{args.positional()[1]};
  for (const auto& [camera, image] : images) inputs.push_back(image);
  if (args.Has("drive")) inputs.push_back(args.Get("drive"));
  if (args.Has("lanes")) inputs.push_back(args.Get("lanes"));
  dps::CheckOutputFolder(dir, inputs);
  std::vector<dps::LaneBoundaryRow> rows;
  if (args.Has("lanes")) {
    rows = dps::ReadLaneBoundaries(args.Get("lanes"));
  } else if (args.Has("frame") && !args.Has("drive")) {
    throw dps::Error("check: --frame needs --lanes or --drive");
  }
  std::optional<long> frame;
  if (args.Has("frame")) {
    frame = args.Integer("frame", 0);
  } else if (!rows.empty()) {
    frame = rows.front().frame;
  }
  std::vector<std::pair<std::string, cv::Mat>> pictures;
  if (args.Has("drive")) {
    pictures = DriveFrames(args, rig, args.Get("drive"), &frame);
    std::cerr << args.Get("drive") << ": frame " << *frame << "\n";
  }
  for (const auto& [camera, image] : images) pictures.emplace_back(camera, ReadImage(args, image, rig.Camera(camera).model));
  std::vector<dps::LaneBoundaryRow> lanes;
  if (args.Has("lanes")) {
    for (const dps::LaneBoundaryRow& b : rows) {
      if (b.frame == frame.value_or(0)) lanes.push_back(b);
    }
    std::cerr << args.Get("lanes") << ": frame " << frame.value_or(0) << ", " << lanes.size() << " boundar"
              << (lanes.size() == 1 ? "y" : "ies") << "\n";
  }
  std::filesystem::create_directories(dir);
  const double range_m = args.Number("range", 20.0), grid_m = args.Number("grid", 1.0);
  for (const auto& [camera, image] : pictures) {
    const dps::RigCamera& c = rig.Camera(camera);
    cv::Mat drawn = dps::DrawRigCheck(c, rig.vehicle, image, range_m, grid_m);
    if (!lanes.empty()) dps::DrawLaneBoundaries(c, lanes, range_m, &drawn);
    const std::string out = (std::filesystem::path(dir) / ("check_" + c.name + "." + ext)).string();
    dps::WriteImageAtomically(out, drawn);
    std::cerr << c.name << ": " << out << "\n";
  }
  return 0;
}

int View(const dps_cli::Args& args, const dps::Rig& rig) {
  if (!args.Has("image") || !args.Has("out")) throw dps::Error("view: needs --image IMAGE and --out VIEW.png");
  const dps::RigCamera& c = rig.Camera(args.Get("camera"));
  const cv::Mat image = ReadImage(args, args.Get("image"), c.model);
  const cv::Size size = args.Size("size", cv::Size(640, 480));
  const double fov = args.Number("fov-deg", 90.0) * dps::kRadPerDeg;
  if (!(fov > 0.0 && fov < dps::kPi * 0.99)) throw dps::Error("option --fov-deg: expected between 0 and 178 degrees");
  const double yaw = args.Number("yaw-deg", 0.0) * dps::kRadPerDeg, pitch = args.Number("pitch-deg", 0.0) * dps::kRadPerDeg;
  dps::ViewSpec spec;
  spec.width = size.width;
  spec.height = size.height;
  spec.focal_px = size.width / 2.0 / std::tan(fov / 2.0);
  spec.cx = (size.width - 1) / 2.0;
  spec.cy = (size.height - 1) / 2.0;
  // Columns: image right, image down, viewing direction (vehicle frame: X right, Y down, Z forward).
  const Eigen::Vector3d z(std::sin(yaw) * std::cos(pitch), std::sin(pitch), std::cos(yaw) * std::cos(pitch));
  const Eigen::Vector3d x = Eigen::Vector3d(0, 1, 0).cross(z).normalized();
  if (!x.allFinite()) throw dps::Error("view: looking straight up or down; give a pitch below 90 degrees");
  spec.vehicle_from_view << x, z.cross(x), z;
  spec.Check();
  dps::WriteImageAtomically(args.Get("out"), dps::VirtualView(c, spec).Render(image));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return dps_cli::Run("dps-rig", [&] {
    const dps_cli::Args args(argc, argv,
                             {"format", "out", "name", "vehicle-length", "vehicle-width", "size", "origin", "bev-height",
                              "unit-m", "axis", "height", "range", "camera", "images", "grid", "image", "yaw-deg",
                              "pitch-deg", "fov-deg", "crop", "ext", "lanes", "frame", "drive"},
                             {});
    if (args.help() || args.positional().empty()) {
      std::cout << kUsage;
      return args.help() ? 0 : 2;
    }
    const std::string command = args.positional()[0];
    if (command == "import") {
      if (args.positional().size() < 2) throw dps::Error("import: no calibration files given");
      return Import(args);
    }
    const std::set<std::string> commands{"show", "project", "unproject", "check", "view"};
    if (!commands.count(command)) throw dps::Error("unknown command '" + command + "' (see --help)");
    if (args.positional().size() != 2) throw dps::Error(command + ": expected one rig.yaml");
    const dps::Rig rig = dps::ReadRig(args.positional()[1]);
    if ((command == "project" || command == "unproject" || command == "view") && !args.Has("camera")) {
      throw dps::Error(command + ": missing --camera NAME");
    }
    if (command == "show") return Show(args, rig);
    if (command == "project") return Project(args, rig);
    if (command == "unproject") return Unproject(args, rig);
    if (command == "check") return Check(args, rig);
    return View(args, rig);
  });
}
