#include "dps/camera/rig_io.h"

#include <cmath>
#include <filesystem>
#include <set>
#include <stdexcept>
#include <vector>

#include "dps/camera/valid_mask.h"
#include "dps/util/atomic_file.h"
#include "dps/util/error.h"
#include "util/yaml_fields.h"

namespace dps {
namespace {

using internal::FieldReader;
using internal::OneLine;
using internal::OpenForReading;

constexpr size_t kMaxPolynomialTerms = 64;

void WriteList(cv::FileStorage& fs, const std::string& key, const std::vector<double>& values) {
  fs << key << "[:";
  for (double v : values) fs << v;
  fs << "]";
}

CameraModel ReadIntrinsics(const FieldReader& f) {
  const std::string model_name = f.Text("model");
  CameraModelType type;
  try {
    type = ModelTypeFromName(model_name);
  } catch (const std::invalid_argument& e) {
    f.Fail("model", e.what());
  }
  const int width = f.Integer("width");
  const int height = f.Integer("height");
  const double rim = f.NumberOr("rim_radius_px", 0.0);
  if (type == CameraModelType::kOCam) {
    OCamParameters p;
    p.ss = f.List("ss", 1, kMaxPolynomialTerms);
    if (f.Has("invpol")) p.invpol = f.List("invpol", 1, kMaxPolynomialTerms);
    const std::vector<double> center = f.List("center", 2, 2);
    const std::vector<double> affine = f.List("affine", 3, 3);
    p.xc = center[0];
    p.yc = center[1];
    p.c = affine[0];
    p.d = affine[1];
    p.e = affine[2];
    return MakeModel(f.where(), [&] { return CameraModel::OCam(width, height, p, rim); });
  }
  const Eigen::Matrix3d K = f.Matrix("K", 3, 3);
  switch (type) {
    case CameraModelType::kHyperbolic: {
      const double a = f.Number("a");
      const double b = f.Number("b");
      return MakeModel(f.where(), [&] { return CameraModel::Hyperbolic(width, height, K, a, b, rim); });
    }
    case CameraModelType::kUnified: {
      const double xi = f.Number("xi");
      std::array<double, 4> dist{0, 0, 0, 0};
      if (f.Has("dist")) {
        const Eigen::MatrixXd d = f.Matrix("dist", 4, 1);
        dist = {d(0), d(1), d(2), d(3)};
      }
      return MakeModel(f.where(), [&] { return CameraModel::Unified(width, height, K, xi, rim, dist); });
    }
    case CameraModelType::kFisheye: {
      const Eigen::MatrixXd d = f.Matrix("dist", 4, 1);
      const std::array<double, 4> dist{d(0), d(1), d(2), d(3)};
      return MakeModel(f.where(),
                       [&] { return CameraModel::Fisheye(width, height, K, dist, rim); });
    }
    case CameraModelType::kOCam: break;
  }
  f.Fail("model", "unsupported");
}

void WriteMatrix(cv::FileStorage& fs, const std::string& key, const Eigen::MatrixXd& m) {
  cv::Mat mat(static_cast<int>(m.rows()), static_cast<int>(m.cols()), CV_64F);
  for (int r = 0; r < m.rows(); ++r) {
    for (int c = 0; c < m.cols(); ++c) mat.at<double>(r, c) = m(r, c);
  }
  fs << key << mat;
}

cv::Size ReadImageSize(const FieldReader& f, cv::Size size) {
  if (size.width > 0 && size.height > 0) return size;
  for (const char* key : {"resolution", "imageSize"}) {  // [w, h]; imageSize: cv::omnidir's samples
    if (!f.Has(key)) continue;
    const Eigen::MatrixXd r = f.Matrix(key, 2, 1);
    return cv::Size(static_cast<int>(r(0)), static_cast<int>(r(1)));
  }
  if (f.Has("image_width") && f.Has("image_height")) {
    return cv::Size(f.Integer("image_width"), f.Integer("image_height"));
  }
  f.Fail("resolution", "missing (no 'resolution', 'imageSize' or 'image_width'/'image_height'; give the "
                       "image size explicitly)");
}

std::string FirstPresent(const FieldReader& f, std::initializer_list<const char*> keys) {
  for (const char* k : keys) {
    if (f.Has(k)) return k;
  }
  return *keys.begin();
}

}  // namespace

Rig ReadRig(const std::string& path) {
  cv::FileStorage fs = OpenForReading(path);
  Rig rig;
  try {
    rig = ParseRig(fs.root(), path);
  } catch (const cv::Exception& e) {  // an OpenCV assertion on a node of an unexpected shape
    throw Error(Str(path, ": malformed: ", OneLine(e)));
  }
  // Masks named by the file, relative to its folder.
  for (RigCamera& c : rig.cameras) {
    if (c.mask_file.empty()) continue;
    const std::filesystem::path file(c.mask_file);
    const std::string at = file.is_absolute() ? file.string() : (std::filesystem::path(path).parent_path() / file).string();
    c.mask = ReadCameraMask(at, c.model);
  }
  return rig;
}

Rig ParseRig(const cv::FileNode& root, const std::string& path) {
  Rig rig;
  const FieldReader top(root, path);
  if (top.Has("vehicle")) {
    const FieldReader v(root["vehicle"], path + ": vehicle");
    rig.vehicle.length_m = v.NumberOr("length", rig.vehicle.length_m);
    rig.vehicle.width_m = v.NumberOr("width", rig.vehicle.width_m);
    if (!(rig.vehicle.length_m > 0.0)) v.Fail("length", "expected > 0 metres");
    if (!(rig.vehicle.width_m > 0.0)) v.Fail("width", "expected > 0 metres");
  }
  const cv::FileNode cams = top.Required("cameras");
  if (!cams.isSeq() || cams.size() == 0) top.Fail("cameras", "expected a non-empty list");
  std::set<std::string> names;
  int index = 0;
  for (const cv::FileNode& node : cams) {
    const std::string at = Str(path, ": cameras[", index, "]");
    if (!node.isMap()) throw Error(at + ": expected a map of camera fields");
    const std::string name = FieldReader(node, at).Text("name");
    if (name.empty()) throw Error(at + ": field 'name': empty");
    if (!names.insert(name).second) throw Error(at + ": duplicate camera name '" + name + "'");
    const FieldReader f(node, Str(path, ": camera '", name, "'"));
    CameraModel model = ReadIntrinsics(f);
    Pose pose;
    pose.R = f.Matrix("R", 3, 3);
    pose.t = f.Matrix("t", 3, 1);
    const std::string problem = RotationProblem(pose.R, 1e-6);
    if (!problem.empty()) f.Fail("R", problem);
    RigCamera camera{name, std::move(model), pose, cv::Mat(), std::string(), cv::Mat()};
    if (f.Has("mask")) camera.mask_file = f.Text("mask");
    rig.cameras.push_back(std::move(camera));
    ++index;
  }
  return rig;
}

std::string RigToYaml(const Rig& rig) {
  cv::FileStorage fs("rig.yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY |
                                     cv::FileStorage::FORMAT_YAML);
  fs << "vehicle" << "{" << "length" << rig.vehicle.length_m << "width" << rig.vehicle.width_m
     << "}";
  fs << "cameras" << "[";
  for (const RigCamera& c : rig.cameras) {
    const CameraModel& m = c.model;
    fs << "{" << "name" << c.name << "model" << ModelName(m.type()) << "width" << m.width()
       << "height" << m.height();
    if (m.type() != CameraModelType::kOCam) WriteMatrix(fs, "K", m.K());
    switch (m.type()) {
      case CameraModelType::kHyperbolic: fs << "a" << m.a() << "b" << m.b(); break;
      case CameraModelType::kUnified:
        fs << "xi" << m.xi();
        if (m.dist() != std::array<double, 4>{0, 0, 0, 0}) {
          fs << "dist" << "[:";
          for (double k : m.dist()) fs << k;
          fs << "]";
        }
        break;
      case CameraModelType::kFisheye:
        fs << "dist" << "[:";
        for (double k : m.dist()) fs << k;
        fs << "]";
        break;
      case CameraModelType::kOCam:
        WriteList(fs, "ss", m.ocam().ss);
        WriteList(fs, "invpol", m.ocam().invpol);
        WriteList(fs, "center", {m.ocam().xc, m.ocam().yc});
        WriteList(fs, "affine", {m.ocam().c, m.ocam().d, m.ocam().e});
        break;
    }
    if (m.rim_radius_px() > 0.0) fs << "rim_radius_px" << m.rim_radius_px();
    if (!c.mask_file.empty()) fs << "mask" << c.mask_file;
    WriteMatrix(fs, "R", c.vehicle_from_camera.R);
    WriteMatrix(fs, "t", c.vehicle_from_camera.t);
    fs << "}";
  }
  fs << "]";
  return fs.releaseAndGetString();
}

void WriteRig(const Rig& rig, const std::string& path) {
  WriteFileAtomically(path, RigToYaml(rig));
}

CameraModel ReadOpenCVFisheye(const std::string& path, cv::Size size) {
  cv::FileStorage fs = OpenForReading(path);
  const FieldReader f(fs.root(), path);
  const Eigen::Matrix3d K = f.Matrix(FirstPresent(f, {"camera_matrix", "K"}), 3, 3);
  const Eigen::MatrixXd d =
      f.Matrix(FirstPresent(f, {"dist_coeffs", "D", "distortion_coefficients"}), 4, 1);
  const cv::Size s = ReadImageSize(f, size);
  const std::array<double, 4> dist{d(0), d(1), d(2), d(3)};
  return MakeModel(path, [&] { return CameraModel::Fisheye(s.width, s.height, K, dist); });
}

CameraModel ReadOpenCVOmnidir(const std::string& path, cv::Size size) {
  cv::FileStorage fs = OpenForReading(path);
  return ParseOpenCVOmnidir(fs.root(), path, size);
}

CameraModel ParseOpenCVOmnidir(const cv::FileNode& root, const std::string& path, cv::Size size) {
  const FieldReader f(root, path);
  const Eigen::Matrix3d K = f.Matrix(FirstPresent(f, {"K", "camera_matrix"}), 3, 3);
  const std::string xi_key = FirstPresent(f, {"xi", "Xi"});
  const cv::FileNode xi_node = f.Required(xi_key);
  const double xi = xi_node.isMap() || xi_node.isSeq() ? f.Matrix(xi_key, 1, 1)(0) : f.Number(xi_key);
  const std::string d_key = FirstPresent(f, {"D", "distortion_coefficients"});
  std::array<double, 4> dist{0, 0, 0, 0};
  if (f.Has(d_key)) {
    const Eigen::MatrixXd d = f.Matrix(d_key, 1, 4);
    dist = {d(0), d(1), d(2), d(3)};
  }
  const cv::Size s = ReadImageSize(f, size);
  return MakeModel(path, [&] { return CameraModel::Unified(s.width, s.height, K, xi, 0.0, dist); });
}

}  // namespace dps
