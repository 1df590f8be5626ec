#include "dps/camera/calibration_import.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "dps/camera/rig_io.h"
#include "dps/util/error.h"
#include "util/yaml_fields.h"

namespace dps {
namespace {

using internal::FieldReader;
using internal::OpenForReading;

// The numbers of one line; throws naming the file, line and field when a token is not a number.
std::vector<double> Numbers(const std::string& line, const std::string& where) {
  std::istringstream in(line);
  std::vector<double> out;
  std::string token;
  while (in >> token) {
    size_t used = 0;
    double v = 0.0;
    try {
      v = std::stod(token, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != token.size() || !std::isfinite(v)) throw Error(Str(where, ": '", token, "' is not a finite number"));
    out.push_back(v);
  }
  return out;
}

// A list whose first number is the count of the rest (calib_results.txt and its YAML form).
std::vector<double> Counted(const std::vector<double>& values, const std::string& where) {
  if (values.empty()) throw Error(where + ": empty");
  const double n = values[0];
  if (n != std::floor(n) || n < 1 || n > 64) throw Error(Str(where, ": count ", n, " is not an integer in 1..64"));
  if (values.size() != static_cast<size_t>(n) + 1) {
    throw Error(Str(where, ": the count says ", n, " coefficients, the line has ", values.size() - 1));
  }
  return std::vector<double>(values.begin() + 1, values.end());
}

CameraModel OCamFromText(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(path + ": cannot open");
  static const char* const kFields[] = {"ss (cam2world polynomial)", "invpol (world2cam polynomial)",
                                        "center (row column)", "affine (c d e)", "image size (height width)"};
  std::vector<std::vector<double>> data;
  std::string line;
  int number = 0;
  while (data.size() < 5 && std::getline(in, line)) {
    ++number;
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    data.push_back(Numbers(line, Str(path, ": line ", number, " (", kFields[data.size()], ")")));
  }
  if (data.size() < 5) throw Error(Str(path, ": field '", kFields[data.size()], "': missing (an OCamCalib calib_results.txt has 5 data lines)"));
  OCamParameters p;
  p.ss = Counted(data[0], Str(path, ": field 'ss'"));
  p.invpol = Counted(data[1], Str(path, ": field 'invpol'"));
  auto exactly = [&](size_t i, size_t n) {
    if (data[i].size() != n) throw Error(Str(path, ": field '", kFields[i], "': expected ", n, " numbers, got ", data[i].size()));
  };
  exactly(2, 2);
  exactly(3, 3);
  exactly(4, 2);
  p.xc = data[2][0];
  p.yc = data[2][1];
  p.c = data[3][0];
  p.d = data[3][1];
  p.e = data[3][2];
  const double h = data[4][0], w = data[4][1];
  if (h != std::floor(h) || w != std::floor(w) || h < 1 || w < 1 || h > 65536 || w > 65536) {
    throw Error(Str(path, ": field 'image size (height width)': ", h, " x ", w, " is not a positive integer size"));
  }
  return MakeModel(path, [&] { return CameraModel::OCam(static_cast<int>(w), static_cast<int>(h), p); });
}

// A plain YAML file of `key: [n, n, ...]` lists (a list may span lines) and `key: n` numbers, as
// numpy-based tools write them (no %YAML header, spaces before the colon, flow lists over several
// lines: OpenCV's parser refuses these).
std::map<std::string, std::vector<double>> FlatYamlLists(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(path + ": file not found or not readable");
  std::map<std::string, std::vector<double>> lists;
  std::string line, key, values;
  int number = 0, start = 0;
  bool open_list = false;
  while (std::getline(in, line)) {
    ++number;
    const size_t hash = line.find('#');
    if (hash != std::string::npos) line.erase(hash);
    if (!open_list) {
      const size_t first = line.find_first_not_of(" \t\r");
      if (first == std::string::npos || line[first] == '%' || line.compare(first, 3, "---") == 0) continue;
      const size_t colon = line.find(':');
      if (colon == std::string::npos) throw Error(Str(path, ": line ", number, ": expected 'key: [numbers]' or 'key: number'"));
      key = line.substr(first, colon - first);
      key.erase(key.find_last_not_of(" \t") + 1);
      values = line.substr(colon + 1);
      start = number;
      open_list = values.find('[') != std::string::npos;
    } else {
      values += " " + line;
    }
    if (open_list && values.find(']') == std::string::npos) continue;
    open_list = false;
    for (char& c : values) c = c == ',' || c == '[' || c == ']' ? ' ' : c;
    lists[key] = Numbers(values, Str(path, ": line ", start, " (", key, ")"));
  }
  if (open_list) throw Error(Str(path, ": line ", start, " (", key, "): the list is not closed"));
  return lists;
}

std::vector<double> FlatList(const std::map<std::string, std::vector<double>>& lists, const std::string& path,
                             std::initializer_list<const char*> keys, size_t n) {
  for (const char* key : keys) {
    const auto it = lists.find(key);
    if (it == lists.end()) continue;
    if (n > 0 && it->second.size() != n) throw Error(Str(path, ": field '", key, "': expected ", n, " numbers, got ", it->second.size()));
    return it->second;
  }
  throw Error(Str(path, ": field '", *keys.begin(), "': missing"));
}

// The OCam numbers in YAML (`ss`, `invpol` with their counts first, `xy`, `cde`, `shape`).
CameraModel OCamFromYaml(const std::string& path) {
  const std::map<std::string, std::vector<double>> lists = FlatYamlLists(path);
  auto list = [&](const char* key, size_t n) { return FlatList(lists, path, {key}, n); };
  OCamParameters p;
  p.ss = Counted(list("ss", 0), path + ": field 'ss'");
  p.invpol = Counted(list("invpol", 0), path + ": field 'invpol'");
  const std::vector<double> xy = list("xy", 2), cde = list("cde", 3), shape = list("shape", 2);
  p.xc = xy[0];
  p.yc = xy[1];
  p.c = cde[0];
  p.d = cde[1];
  p.e = cde[2];
  for (double v : shape) {
    if (v != std::floor(v) || v < 1 || v > 65536) throw Error(path + ": field 'shape': expected [height, width] in pixels");
  }
  return MakeModel(path, [&] { return CameraModel::OCam(static_cast<int>(shape[1]), static_cast<int>(shape[0]), p); });
}

// The single top-level map of a PJLab JSON file, and its key.
cv::FileNode OnlyEntry(const cv::FileStorage& fs, const std::string& path, std::string* key) {
  const cv::FileNode root = fs.root();
  if (!root.isMap() || root.size() != 1) throw Error(path + ": expected one top-level key (e.g. \"front_camera-intrinsic\")");
  const cv::FileNode entry = *root.begin();
  *key = entry.name();
  return entry;
}

// The two kinds of PJLab file, from their single top-level entry named `key`.
constexpr const char* kBevPrefix = "bev-to-";
CameraModel PJLabIntrinsic(const cv::FileNode& entry, const std::string& key, const std::string& path,
                           std::string* camera_name);
Pose PJLabExtrinsic(const cv::FileNode& entry, const std::string& key, const std::string& path, std::string* camera_name);

// A matrix written as a list of rows, rows x cols.
Eigen::MatrixXd Rows(const FieldReader& f, const cv::FileNode& node, const std::string& key, int rows, int cols) {
  if (!node.isSeq() || static_cast<int>(node.size()) != rows) f.Fail(key, Str("expected ", rows, " rows"));
  Eigen::MatrixXd m(rows, cols);
  int r = 0;
  for (const cv::FileNode& row : node) {
    if (!row.isSeq() || static_cast<int>(row.size()) != cols) f.Fail(key, Str("expected rows of ", cols, " numbers"));
    int c = 0;
    for (const cv::FileNode& v : row) {
      if (!v.isReal() && !v.isInt()) f.Fail(key, "expected numbers");
      m(r, c++) = static_cast<double>(v);
      if (!std::isfinite(m(r, c - 1))) f.Fail(key, "has a non-finite entry");
    }
    ++r;
  }
  return m;
}

Eigen::Matrix3d Axes(const Eigen::Vector3d& x, const Eigen::Vector3d& y, const Eigen::Vector3d& z) {
  Eigen::Matrix3d R;
  R << x, y, z;
  return R;
}

// Vehicle frame (X right, Y down, Z forward) from KITTI-360's pose frame (x forward, y right, z down).
const Eigen::Matrix3d kVehicleFromKittiPose = Axes({0, 0, 1}, {1, 0, 0}, {0, 1, 0});
// Vehicle frame from PJLab's bird's-eye camera frame (x right, y backward, z down).
const Eigen::Matrix3d kVehicleFromBev = Axes({1, 0, 0}, {0, 0, -1}, {0, 1, 0});

}  // namespace

CalibrationFormat CalibrationFormatFromName(const std::string& name) {
  if (name == "ocam") return CalibrationFormat::kOCam;
  if (name == "omnidir") return CalibrationFormat::kOmnidir;
  if (name == "opencv-fisheye") return CalibrationFormat::kOpenCVFisheye;
  if (name == "kitti360") return CalibrationFormat::kKitti360;
  if (name == "pjlab-ocam") return CalibrationFormat::kPJLabOCam;
  throw Error("unknown calibration format '" + name + "' (expected ocam, omnidir, opencv-fisheye, kitti360 or pjlab-ocam)");
}

CameraModel ReadOCamCalibResults(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(path + ": file not found or not readable");
  // calib_results.txt's data lines are numbers; the YAML form's first data line has a key.
  std::string line;
  while (std::getline(in, line)) {
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    break;
  }
  const bool yaml = line.rfind("%YAML", 0) == 0 || line.find(':') != std::string::npos;
  return yaml ? OCamFromYaml(path) : OCamFromText(path);
}

CameraModel ReadKitti360Fisheye(const std::string& path, std::string* camera_name) {
  cv::FileStorage fs = OpenForReading(path);
  const FieldReader f(fs.root(), path);
  const std::string type = f.TextOr("model_type", "MEI");
  if (type != "MEI") f.Fail("model_type", "'" + type + "': only MEI is supported");
  if (camera_name) *camera_name = f.TextOr("camera_name", "");
  const FieldReader mirror = f.Child(f.Required("mirror_parameters"), "mirror_parameters");
  const FieldReader dist = f.Child(f.Required("distortion_parameters"), "distortion_parameters");
  const FieldReader proj = f.Child(f.Required("projection_parameters"), "projection_parameters");
  const double xi = mirror.Number("xi");
  const std::array<double, 4> d{dist.Number("k1"), dist.Number("k2"), dist.Number("p1"), dist.Number("p2")};
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  K(0, 0) = proj.Number("gamma1");
  K(1, 1) = proj.Number("gamma2");
  K(0, 2) = proj.Number("u0");
  K(1, 2) = proj.Number("v0");
  const int w = f.Integer("image_width"), h = f.Integer("image_height");
  return MakeModel(path, [&] { return CameraModel::Unified(w, h, K, xi, 0.0, d); });
}

std::map<std::string, Pose> ReadKitti360CamToPose(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(path + ": file not found or not readable");
  std::map<std::string, Pose> poses;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    const size_t colon = line.find(':');
    if (colon == std::string::npos) throw Error(Str(path, ": line ", number, ": expected 'image_0N: r11 r12 r13 t1 ...'"));
    const std::string name = line.substr(0, colon);
    const std::vector<double> v = Numbers(line.substr(colon + 1), Str(path, ": line ", number, " (", name, ")"));
    if (v.size() != 12) throw Error(Str(path, ": line ", number, " (", name, "): expected 12 numbers (3x4 [R t]), got ", v.size()));
    Pose pose;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) pose.R(r, c) = v[r * 4 + c];
      pose.t(r) = v[r * 4 + 3];
    }
    const std::string problem = RotationProblem(pose.R, 1e-6);
    if (!problem.empty()) throw Error(Str(path, ": line ", number, " (", name, "): R ", problem));
    poses[name] = pose;
  }
  if (poses.empty()) throw Error(path + ": no camera poses");
  return poses;
}

CameraModel ReadPJLabOCamIntrinsic(const std::string& path, std::string* camera_name) {
  cv::FileStorage fs = OpenForReading(path);
  std::string key;
  const cv::FileNode entry = OnlyEntry(fs, path, &key);
  return PJLabIntrinsic(entry, key, path, camera_name);
}

Pose ReadPJLabExtrinsic(const std::string& path, std::string* camera_name) {
  cv::FileStorage fs = OpenForReading(path);
  std::string key;
  const cv::FileNode entry = OnlyEntry(fs, path, &key);
  return PJLabExtrinsic(entry, key, path, camera_name);
}

namespace {

CameraModel PJLabIntrinsic(const cv::FileNode& entry, const std::string& key, const std::string& path,
                           std::string* camera_name) {
  const FieldReader top(entry, path + ": " + key);
  if (camera_name) *camera_name = top.TextOr("sensor_name", "");
  const FieldReader f = top.Child(top.Required("param"), "param");
  const int w = f.Integer("img_dist_w"), h = f.Integer("img_dist_h");
  const FieldReader k = f.Child(f.Required("cam_K"), "cam_K");
  const Eigen::MatrixXd K = Rows(k, k.Required("data"), "data", 3, 3);
  if (K(1, 1) != 1.0 || K(2, 0) != 0.0 || K(2, 1) != 0.0 || K(2, 2) != 1.0) {
    k.Fail("data", "expected [[c, d, u0], [e, 1, v0], [0, 0, 1]]");
  }
  const FieldReader dist = f.Child(f.Required("cam_dist"), "cam_dist");
  const cv::FileNode rows = dist.Required("data");
  if (!rows.isSeq() || rows.size() != 1) dist.Fail("data", "expected one row of coefficients");
  const Eigen::MatrixXd poly = Rows(dist, rows, "data", 1, static_cast<int>((*rows.begin()).size()));
  if (poly.cols() < 2 || poly.cols() > 64) dist.Fail("data", "expected 2 to 64 coefficients");
  const double c = K(0, 0), d = K(0, 1), e = K(1, 0);
  if (!(c > 0.0)) k.Fail("data", Str("c = ", c, ": expected > 0"));
  OCamParameters p;  // OCamCalib's axes: rows first (see the header)
  p.xc = K(1, 2);
  p.yc = K(0, 2);
  p.c = 1.0 / c;
  p.d = e / c;
  p.e = d / c;
  for (int i = 0; i < poly.cols(); ++i) p.invpol.push_back(c * poly(0, i));
  p.ss = FitOCamForward(p, w, h);
  if (p.ss.empty()) dist.Fail("data", "no forward polynomial fits this inverse polynomial");
  return MakeModel(path, [&] { return CameraModel::OCam(w, h, p); });
}

Pose PJLabExtrinsic(const cv::FileNode& entry, const std::string& key, const std::string& path,
                    std::string* camera_name) {
  const std::string prefix = kBevPrefix, suffix = "-extrinsic";
  if (key.rfind(prefix, 0) != 0 || key.size() <= prefix.size() + suffix.size() ||
      key.compare(key.size() - suffix.size(), suffix.size(), suffix) != 0) {
    throw Error(path + ": top-level key '" + key + "': expected 'bev-to-<camera>-extrinsic'");
  }
  if (camera_name) *camera_name = key.substr(prefix.size(), key.size() - prefix.size() - suffix.size());
  const FieldReader top(entry, path + ": " + key);
  const FieldReader f = top.Child(top.Required("param"), "param");
  const FieldReader calib = f.Child(f.Required("sensor_calib"), "sensor_calib");
  const Eigen::MatrixXd T = Rows(calib, calib.Required("data"), "data", 4, 4);
  if ((T.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() != 0.0) calib.Fail("data", "last row must be [0, 0, 0, 1]");
  Pose camera_from_bev;
  camera_from_bev.R = T.block<3, 3>(0, 0);
  camera_from_bev.t = T.block<3, 1>(0, 3);
  const std::string problem = RotationProblem(camera_from_bev.R, 1e-5);
  if (!problem.empty()) calib.Fail("data", "rotation " + problem);
  return camera_from_bev;
}

}  // namespace

CameraModel ReadOmnidirCalibration(const std::string& path, cv::Size size) {
  cv::FileStorage fs;
  try {
    fs = OpenForReading(path);
  } catch (const Error&) {
    // not a file OpenCV parses: read below as plain YAML
  }
  if (fs.isOpened()) return ParseOpenCVOmnidir(fs.root(), path, size);
  const std::map<std::string, std::vector<double>> lists = FlatYamlLists(path);
  const std::vector<double> k = FlatList(lists, path, {"K", "camera_matrix"}, 9);
  const std::vector<double> xi = FlatList(lists, path, {"xi", "Xi"}, 1);
  std::array<double, 4> dist{0, 0, 0, 0};
  if (lists.count("D") || lists.count("distortion_coefficients")) {
    const std::vector<double> d = FlatList(lists, path, {"D", "distortion_coefficients"}, 4);
    dist = {d[0], d[1], d[2], d[3]};
  }
  if (size.width <= 0 || size.height <= 0) {
    throw Error(path + ": field 'resolution': missing (the file has no image size; give it explicitly)");
  }
  Eigen::Matrix3d K;
  K << k[0], k[1], k[2], k[3], k[4], k[5], k[6], k[7], k[8];
  return MakeModel(path, [&] { return CameraModel::Unified(size.width, size.height, K, xi[0], 0.0, dist); });
}

Pose NominalMount(const Vehicle& vehicle, bool left, NominalAxis axis, double height_m) {
  Pose pose;
  const double side = left ? -1.0 : 1.0;
  pose.t = Eigen::Vector3d(side * (vehicle.width_m / 2.0 + 0.1), -height_m, 1.0);
  if (axis == NominalAxis::kDown) {
    pose.R = Axes({1, 0, 0}, {0, 0, -1}, {0, 1, 0});
  } else {
    pose.R = Axes({0, 0, -side}, {0, 1, 0}, {side, 0, 0});
  }
  return pose;
}

void ImportOptions::Check() const {
  if (files.empty()) throw Error("import: no calibration files given");
  if (!(bev_height_m >= 0.0 && bev_height_m < 1e6)) throw Error(Str("import: bird's-eye height ", bev_height_m, ": expected > 0"));
  for (const auto& [name, h] : bev_height_by_camera) {
    if (!(h > 0.0 && h < 1e6)) throw Error(Str("import: bird's-eye height of '", name, "' ", h, ": expected > 0"));
  }
  if (!source_origin.allFinite()) throw Error("import: the source frame's origin must be finite");
  if (!(source_unit_m > 0.0 && source_unit_m < 1e6)) throw Error(Str("import: unit ", source_unit_m, " m: expected > 0"));
  if (!(nominal_height_m > 0.0 && nominal_height_m < 100.0)) {
    throw Error(Str("import: nominal camera height ", nominal_height_m, " m: expected > 0"));
  }
  if (!(vehicle.length_m > 0.0) || !(vehicle.width_m > 0.0)) throw Error("import: vehicle length and width must be > 0");
}

namespace {

struct Source {
  std::string name;  // the source's own name, or empty
  CameraModel model;
  std::optional<Pose> vehicle_from_camera;
  std::string pose_note;
};

std::vector<Source> ReadKitti360(const ImportOptions& o) {
  std::vector<Source> sources;
  std::map<std::string, Pose> poses;
  std::string poses_file;
  for (const std::string& file : o.files) {
    if (std::filesystem::path(file).extension() == ".txt") {
      poses = ReadKitti360CamToPose(file);
      poses_file = file;
      continue;
    }
    std::string name;
    CameraModel model = ReadKitti360Fisheye(file, &name);
    sources.push_back(Source{name, std::move(model), std::nullopt, ""});
  }
  for (Source& s : sources) {
    const auto it = poses.find(s.name);
    if (it == poses.end()) continue;
    Pose p;
    p.R = kVehicleFromKittiPose * it->second.R;
    p.t = kVehicleFromKittiPose * it->second.t * o.source_unit_m + o.source_origin;
    s.vehicle_from_camera = p;
    s.pose_note = Str("from ", poses_file, " (", s.name, "; pose origin at ", o.source_origin.transpose(), " in the vehicle frame)");
  }
  return sources;
}

std::vector<Source> ReadPJLab(const ImportOptions& o) {
  std::vector<Source> sources;
  std::map<std::string, std::pair<Pose, std::string>> extrinsics;
  for (const std::string& file : o.files) {
    // One parse per file: its single entry says whether it holds intrinsics or extrinsics.
    cv::FileStorage fs = OpenForReading(file);
    std::string key, name;
    const cv::FileNode entry = OnlyEntry(fs, file, &key);
    if (key.rfind(kBevPrefix, 0) == 0) {
      const Pose camera_from_bev = PJLabExtrinsic(entry, key, file, &name);
      extrinsics[name] = {camera_from_bev, file};
      continue;
    }
    CameraModel model = PJLabIntrinsic(entry, key, file, &name);
    sources.push_back(Source{name, std::move(model), std::nullopt, ""});
  }
  for (size_t i = 0; i < sources.size(); ++i) {
    const auto it = extrinsics.find(sources[i].name);
    if (it == extrinsics.end()) continue;
    const auto given = o.bev_height_by_camera.find(sources[i].name);
    const double h = given != o.bev_height_by_camera.end() ? given->second : o.bev_height_m;
    if (!(h > 0.0)) {
      throw Error("import pjlab-ocam: camera '" + sources[i].name + "': the extrinsics are relative to a bird's-eye camera: "
                  "give its height above the road (--bev-height H or --bev-height " + sources[i].name + "=H,...)");
    }
    const Pose bev_from_camera = it->second.first.Inverse();
    Pose p;
    p.R = kVehicleFromBev * bev_from_camera.R;
    p.t = (kVehicleFromBev * bev_from_camera.t + Eigen::Vector3d(0, -h, 0)) * o.source_unit_m;
    sources[i].vehicle_from_camera = p;
    sources[i].pose_note = Str("from ", it->second.second, " (bird's-eye camera ", h, " units above the road, ",
                               o.source_unit_m, " m per unit)");
  }
  return sources;
}

}  // namespace

Rig ImportRig(const ImportOptions& o, std::vector<std::string>* notes) {
  o.Check();
  std::vector<Source> sources;
  switch (o.format) {
    case CalibrationFormat::kKitti360: sources = ReadKitti360(o); break;
    case CalibrationFormat::kPJLabOCam: sources = ReadPJLab(o); break;
    default:
      for (const std::string& file : o.files) {
        CameraModel m = o.format == CalibrationFormat::kOCam      ? ReadOCamCalibResults(file)
                        : o.format == CalibrationFormat::kOmnidir ? ReadOmnidirCalibration(file, o.size)
                                                                  : ReadOpenCVFisheye(file, o.size);
        sources.push_back(Source{"", std::move(m), std::nullopt, ""});
      }
  }
  if (sources.empty()) throw Error("import: the files hold no camera intrinsics");
  if (!o.names.empty() && o.names.size() != sources.size()) {
    throw Error(Str("import: ", o.names.size(), " names (--name) for ", sources.size(), " cameras"));
  }
  Rig rig;
  rig.vehicle = o.vehicle;
  for (size_t i = 0; i < sources.size(); ++i) {
    Source& s = sources[i];
    std::string name = !o.names.empty() ? o.names[i] : !s.name.empty() ? s.name : i == 0 ? "left" : i == 1 ? "right" : Str("camera", i);
    if (rig.Has(name)) throw Error("import: two cameras named '" + name + "' (give --name)");
    std::string note = s.pose_note;
    if (!s.vehicle_from_camera) {
      const bool left = name == "left" || (name != "right" && i % 2 == 0);
      s.vehicle_from_camera = NominalMount(o.vehicle, left, o.nominal_axis, o.nominal_height_m);
      note = Str("nominal: ", left ? "left" : "right", " mirror, axis ", o.nominal_axis == NominalAxis::kDown ? "down" : "out",
                 ", ", o.nominal_height_m, " m above the road (the files have no extrinsics; refine with dps-calibrate)");
    }
    if (notes) notes->push_back(name + ": pose " + note);
    rig.cameras.push_back(RigCamera{name, std::move(s.model), *s.vehicle_from_camera, cv::Mat(), std::string(), cv::Mat()});
  }
  return rig;
}

}  // namespace dps
