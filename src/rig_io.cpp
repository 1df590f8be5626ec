#include "dps/rig_io.h"

#include <cmath>
#include <filesystem>
#include <set>
#include <stdexcept>
#include <vector>

#include "dps/atomic_file.h"
#include "dps/error.h"

namespace dps {
namespace {

// One line of an OpenCV error, without OpenCV's own "file:line: error: (-2:...)" prefix noise.
std::string OneLine(const cv::Exception& e) {
  std::string msg = e.err.empty() ? e.what() : e.err;
  for (char& c : msg) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  return msg;
}

cv::FileStorage OpenForReading(const std::string& path) {
  if (!std::filesystem::exists(path)) throw Error(Str(path, ": file not found"));
  cv::FileStorage fs;
  try {
    fs.open(path, cv::FileStorage::READ);
  } catch (const cv::Exception& e) {
    throw Error(Str(path, ": not a valid OpenCV YAML/XML file: ", OneLine(e)));
  }
  if (!fs.isOpened()) throw Error(Str(path, ": cannot open as an OpenCV YAML/XML file"));
  return fs;
}

// Reads fields of one node, prefixing every error with `where` ("rig.yaml: camera 'left'").
class FieldReader {
 public:
  FieldReader(const cv::FileNode& node, std::string where)
      : node_(node), where_(std::move(where)) {}

  bool Has(const std::string& key) const { return !node_[key].empty(); }

  [[noreturn]] void Fail(const std::string& key, const std::string& problem) const {
    throw Error(Str(where_, ": field '", key, "': ", problem));
  }

  cv::FileNode Required(const std::string& key) const {
    cv::FileNode n = node_[key];
    if (n.empty()) Fail(key, "missing");
    return n;
  }

  double Number(const std::string& key) const {
    const cv::FileNode n = Required(key);
    if (!n.isReal() && !n.isInt()) Fail(key, "expected a number");
    const double v = static_cast<double>(n);
    if (!std::isfinite(v)) Fail(key, "expected a finite number");
    return v;
  }

  double NumberOr(const std::string& key, double fallback) const {
    return Has(key) ? Number(key) : fallback;
  }

  int Integer(const std::string& key) const {
    const cv::FileNode n = Required(key);
    if (!n.isInt()) Fail(key, "expected an integer");
    return static_cast<int>(n);
  }

  std::string Text(const std::string& key) const {
    const cv::FileNode n = Required(key);
    if (!n.isString()) Fail(key, "expected a string");
    return static_cast<std::string>(n);
  }

  // A matrix as !!opencv-matrix or as a plain list (row-major); `rows` x `cols` expected.
  Eigen::MatrixXd Matrix(const std::string& key, int rows, int cols) const {
    const cv::FileNode n = Required(key);
    std::vector<double> values;
    int got_rows = 0;
    int got_cols = 0;
    if (n.isSeq()) {
      for (const cv::FileNode& item : n) {
        if (!item.isReal() && !item.isInt()) Fail(key, "expected a list of numbers");
        values.push_back(static_cast<double>(item));
      }
      got_rows = static_cast<int>(values.size());
      got_cols = 1;
      if (static_cast<int>(values.size()) == rows * cols) {
        got_rows = rows;
        got_cols = cols;
      }
    } else if (n.isMap()) {
      cv::Mat m;
      try {
        n >> m;
      } catch (const cv::Exception& e) {
        Fail(key, "not a readable !!opencv-matrix: " + OneLine(e));
      }
      if (m.empty()) Fail(key, "expected an !!opencv-matrix or a list of numbers");
      m.convertTo(m, CV_64F);
      got_rows = m.rows;
      got_cols = m.cols;
      // A vector may be stored as a row or a column.
      if ((rows == 1 || cols == 1) && static_cast<int>(m.total()) == rows * cols) {
        got_rows = rows;
        got_cols = cols;
      }
      values.assign(m.begin<double>(), m.end<double>());
    } else {
      Fail(key, "expected an !!opencv-matrix or a list of numbers");
    }
    if (got_rows != rows || got_cols != cols) {
      Fail(key, Str("expected a ", rows, "x", cols, " matrix, got ", got_rows, "x", got_cols));
    }
    Eigen::MatrixXd out(rows, cols);
    for (int r = 0; r < rows; ++r) {
      for (int c = 0; c < cols; ++c) {
        out(r, c) = values[r * cols + c];
        if (!std::isfinite(out(r, c))) Fail(key, "has a non-finite entry");
      }
    }
    return out;
  }

  const std::string& where() const { return where_; }

 private:
  cv::FileNode node_;
  std::string where_;
};

// Calls a CameraModel factory and turns its std::invalid_argument into a dps::Error with context.
template <typename Factory>
CameraModel MakeModel(const std::string& where, Factory&& factory) {
  try {
    return factory();
  } catch (const std::invalid_argument& e) {
    throw Error(Str(where, ": ", e.what()));
  }
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
  const Eigen::Matrix3d K = f.Matrix("K", 3, 3);
  const double rim = f.NumberOr("rim_radius_px", 0.0);
  switch (type) {
    case CameraModelType::kHyperbolic: {
      const double a = f.Number("a");
      const double b = f.Number("b");
      return MakeModel(f.where(), [&] { return CameraModel::Hyperbolic(width, height, K, a, b, rim); });
    }
    case CameraModelType::kUnified: {
      const double xi = f.Number("xi");
      return MakeModel(f.where(), [&] { return CameraModel::Unified(width, height, K, xi, rim); });
    }
    case CameraModelType::kFisheye: {
      const Eigen::MatrixXd d = f.Matrix("dist", 4, 1);
      const std::array<double, 4> dist{d(0), d(1), d(2), d(3)};
      return MakeModel(f.where(),
                       [&] { return CameraModel::Fisheye(width, height, K, dist, rim); });
    }
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
  if (f.Has("resolution")) {
    const Eigen::MatrixXd r = f.Matrix("resolution", 2, 1);
    return cv::Size(static_cast<int>(r(0)), static_cast<int>(r(1)));
  }
  if (f.Has("image_width") && f.Has("image_height")) {
    return cv::Size(f.Integer("image_width"), f.Integer("image_height"));
  }
  f.Fail("resolution", "missing (no 'resolution' or 'image_width'/'image_height'; give the image "
                       "size explicitly)");
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
  const cv::FileNode root = fs.root();
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
    rig.cameras.push_back(RigCamera{name, std::move(model), pose});
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
    WriteMatrix(fs, "K", m.K());
    switch (m.type()) {
      case CameraModelType::kHyperbolic: fs << "a" << m.a() << "b" << m.b(); break;
      case CameraModelType::kUnified: fs << "xi" << m.xi(); break;
      case CameraModelType::kFisheye:
        fs << "dist" << "[:";
        for (double k : m.dist()) fs << k;
        fs << "]";
        break;
    }
    if (m.rim_radius_px() > 0.0) fs << "rim_radius_px" << m.rim_radius_px();
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
  const FieldReader f(fs.root(), path);
  const Eigen::Matrix3d K = f.Matrix(FirstPresent(f, {"K", "camera_matrix"}), 3, 3);
  const std::string xi_key = "xi";
  const double xi = f.Required(xi_key).isMap() ? f.Matrix(xi_key, 1, 1)(0) : f.Number(xi_key);
  const std::string d_key = FirstPresent(f, {"D", "distortion_coefficients"});
  if (f.Has(d_key)) {
    const Eigen::MatrixXd d = f.Matrix(d_key, 1, 4);
    for (int i = 0; i < 4; ++i) {
      if (std::abs(d(i)) > 1e-9) {
        f.Fail(d_key, Str("distortion D = [", d(0), ", ", d(1), ", ", d(2), ", ", d(3),
                          "] is not supported: dps's unified model has no distortion (recalibrate "
                          "with cv::omnidir::CALIB_FIX_K1 | K2 | P1 | P2)"));
      }
    }
  }
  const cv::Size s = ReadImageSize(f, size);
  return MakeModel(path, [&] { return CameraModel::Unified(s.width, s.height, K, xi); });
}

}  // namespace dps
