#include "dps/calib/vanishing_points.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <sstream>

#include <Eigen/Geometry>
#include <Eigen/SVD>

#include "dps/util/error.h"
#include "dps/util/math.h"

namespace dps {
namespace {

int AxisIndex(char axis) { return axis == 'X' ? 0 : axis == 'Y' ? 1 : 2; }

// Pixels per radian of the image near `ray` for a small turn towards `towards` (unit, orthogonal
// to the ray); 0 when the model cannot tell.
double PixelsPerRadian(const CameraModel& model, const Eigen::Vector3d& ray,
                       const Eigen::Vector3d& towards) {
  constexpr double kStep = 1e-4;
  Eigen::Vector2d a, b;
  if (!model.Project(ray, &a) || !model.Project((ray + kStep * towards).normalized(), &b)) return 0.0;
  return (b - a).norm() / kStep;
}

// The marked points of each line as rays, and each line's axis; throws dps::Error naming the
// file's line for a point outside the image or without a ray, and a line marked with two axes.
struct MarkedRays {
  std::map<int, std::vector<Eigen::Vector3d>> rays;
  std::map<int, char> axis_of;
};

MarkedRays LineRays(const std::string& camera, const CameraModel& model, const std::vector<Mark>& marks,
                    const std::string& source) {
  const std::string where = Str(source, ": camera '", camera, "'");
  MarkedRays out;
  for (const Mark& m : marks) {
    const std::string at = m.file_line > 0 ? Str(source, ":", m.file_line) : where;
    const Eigen::Vector2d px(m.u, m.v);
    if (!model.InImage(px)) {
      throw Error(Str(at, ": line ", m.line, ": point (", m.u, ", ", m.v, ") is outside the ",
                      model.width(), "x", model.height(), " image of camera '", camera, "'"));
    }
    Eigen::Vector3d ray;
    if (!model.Unproject(px, &ray)) {
      throw Error(Str(at, ": line ", m.line, ": point (", m.u, ", ", m.v,
                      ") has no ray (outside the rim / field of view of camera '", camera, "')"));
    }
    const auto it = out.axis_of.find(m.line);
    if (it != out.axis_of.end() && it->second != m.axis) {
      throw Error(Str(at, ": line ", m.line, " is marked with axis ", m.axis, " here and ",
                      it->second, " before"));
    }
    out.axis_of[m.line] = m.axis;
    out.rays[m.line].push_back(ray);
  }
  return out;
}

// Eq. 9 per line: the great circle through its rays, with its residual in degrees and pixels.
std::vector<LineFit> FitLines(const MarkedRays& marked, const CameraModel& model, const CalibrationOptions& options,
                              const std::string& where) {
  std::vector<LineFit> lines;
  for (const auto& [line, r] : marked.rays) {
    if (r.size() < 3) {
      throw Error(Str(where, ": line ", line, " has ", r.size(), " point(s); at least 3 are needed"));
    }
    LineFit fit;
    fit.line = line;
    fit.axis = marked.axis_of.at(line);
    fit.points = static_cast<int>(r.size());
    double rms = 0.0;
    fit.normal = FitGreatCircle(r, &rms);
    fit.rms_deg = rms * kDegPerRad;
    double scale = 0.0;
    for (const Eigen::Vector3d& p : r) scale += PixelsPerRadian(model, p, (fit.normal - fit.normal.dot(p) * p).normalized());
    fit.rms_px = rms * scale / r.size();
    // A line's points must span enough of the image to give it a direction (a point marked again
    // and again gives none).
    double span_rad = 0.0;
    for (const Eigen::Vector3d& p : r) span_rad = std::max(span_rad, std::acos(std::clamp(p.dot(r.front()), -1.0, 1.0)));
    const double span_px = span_rad * scale / r.size();
    if (!(span_px >= options.min_line_span_px)) {
      throw Error(Str(where, ": line ", line, ": its ", r.size(), " points span ", span_px, " px (at least ",
                      options.min_line_span_px, " px along the line are needed)"));
    }
    lines.push_back(fit);
  }
  return lines;
}

// Outliers: residuals far above the camera's typical line.
void MarkOutliers(const CalibrationOptions& options, std::vector<LineFit>* lines) {
  std::vector<double> residuals;
  for (const LineFit& f : *lines) residuals.push_back(f.rms_deg);
  std::nth_element(residuals.begin(), residuals.begin() + residuals.size() / 2, residuals.end());
  const double median = residuals[residuals.size() / 2];
  for (LineFit& f : *lines) {
    f.outlier = f.rms_deg > options.outlier_factor * median && f.rms_deg > options.outlier_min_deg;
    f.used = !(f.outlier && options.drop_outliers);
  }
}

// The rotation's rows measured: one per axis with at least two used lines.
struct AxisRows {
  Eigen::Vector3d row[3];
  bool have[3] = {false, false, false};
};

// Eq. 10 per axis, signs from the nominal rig; throws when fewer than two axes are measured or an
// axis's lines are degenerate.
AxisRows FitAxes(const std::vector<LineFit>& lines, const Eigen::Matrix3d& nominal_R, const CalibrationOptions& options,
                 const std::string& where, std::vector<AxisFit>* axes) {
  int counts[3] = {0, 0, 0};
  for (const LineFit& f : lines) counts[AxisIndex(f.axis)] += f.used;
  AxisRows rows;
  for (int k = 0; k < 3; ++k) {
    if (counts[k] < 2) continue;
    const char axis = "XYZ"[k];
    std::vector<Eigen::Vector3d> normals;
    for (const LineFit& f : lines) {
      if (f.used && f.axis == axis) normals.push_back(f.normal);
    }
    Eigen::Vector3d sv;
    Eigen::Vector3d m = VanishingDirection(normals, &sv);
    if (sv(1) < options.degenerate_ratio * sv(0)) {
      throw Error(Str(where, ": the ", normals.size(), " lines of axis ", axis,
                      " are nearly the same great circle (degenerate; mark lines farther apart)"));
    }
    const Eigen::Vector3d nominal_row = nominal_R.row(k).transpose();
    if (m.dot(nominal_row) < 0) m = -m;
    AxisFit a;
    a.axis = axis;
    a.lines = static_cast<int>(normals.size());
    a.direction = m;
    double ss = 0.0;
    for (const Eigen::Vector3d& l : normals) ss += std::pow(std::asin(std::min(1.0, std::abs(l.dot(m)))), 2);
    a.spread_deg = std::sqrt(ss / normals.size()) * kDegPerRad;
    axes->push_back(a);
    rows.row[k] = m;
    rows.have[k] = true;
  }
  if (rows.have[0] + rows.have[1] + rows.have[2] < 2) {
    throw Error(Str(where, ": lines per axis X ", counts[0], ", Y ", counts[1], ", Z ", counts[2],
                    ": at least 2 lines are needed on two axes (X and Z, or one of them and Y)"));
  }
  return rows;
}

// The left singular vectors of a 3 x N matrix whose columns are `v` are those of its 3 x 3 scatter
// matrix sum v v^T, whose singular values are the matrix's squared: the same SVD on a fixed-size
// matrix (a dynamic-size JacobiSVD costs this file most of its compile time).
Eigen::JacobiSVD<Eigen::Matrix3d> ScatterSvd(const std::vector<Eigen::Vector3d>& v) {
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& x : v) scatter.noalias() += x * x.transpose();
  return Eigen::JacobiSVD<Eigen::Matrix3d>(scatter, Eigen::ComputeFullU);
}

}  // namespace

Eigen::Vector3d FitGreatCircle(const std::vector<Eigen::Vector3d>& rays, double* rms_rad) {
  const Eigen::Vector3d l = ScatterSvd(rays).matrixU().col(2);  // smallest singular value (eq. 9)
  if (rms_rad) {
    double ss = 0.0;
    for (const Eigen::Vector3d& p : rays) ss += std::pow(std::asin(std::min(1.0, std::abs(l.dot(p)))), 2);
    *rms_rad = std::sqrt(ss / rays.size());
  }
  return l;
}

Eigen::Vector3d VanishingDirection(const std::vector<Eigen::Vector3d>& normals,
                                   Eigen::Vector3d* singular_values) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd = ScatterSvd(normals);
  if (singular_values) *singular_values = svd.singularValues().cwiseMax(0.0).cwiseSqrt();
  return svd.matrixU().col(2);  // eq. 10
}

Eigen::Matrix3d NearestRotation(const Eigen::Matrix3d& M) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d U = svd.matrixU();
  const Eigen::Matrix3d V = svd.matrixV();
  if ((U * V.transpose()).determinant() < 0) U.col(2) *= -1.0;
  return U * V.transpose();
}

void CalibrationOptions::Check() const {
  if (!(outlier_factor > 1.0)) throw Error(Str("outlier_factor = ", outlier_factor, ": violated constraint > 1"));
  if (!(outlier_min_deg >= 0.0)) throw Error(Str("outlier_min_deg = ", outlier_min_deg, ": violated constraint >= 0"));
  if (!(min_spread_deg > 0.0)) throw Error(Str("min_spread_deg = ", min_spread_deg, ": violated constraint > 0"));
  if (!(min_line_span_px > 0.0)) throw Error(Str("min_line_span_px = ", min_line_span_px, ": violated constraint > 0"));
  if (!(max_orthogonality_error_deg > 0.0 && max_orthogonality_error_deg <= 90.0)) {
    throw Error(Str("max_orthogonality_error_deg = ", max_orthogonality_error_deg, ": violated constraint 0 < e <= 90"));
  }
  if (!(degenerate_ratio > 0.0 && degenerate_ratio < 1.0)) {
    throw Error(Str("degenerate_ratio = ", degenerate_ratio, ": violated constraint 0 < ratio < 1"));
  }
}

CameraCalibration CalibrateCamera(const std::string& camera, const CameraModel& model,
                                  const Eigen::Matrix3d& nominal_R, const std::vector<Mark>& marks,
                                  const CalibrationOptions& options, const std::string& source) {
  options.Check();
  const std::string where = Str(source, ": camera '", camera, "'");
  CameraCalibration out;
  out.camera = camera;
  out.lines = FitLines(LineRays(camera, model, marks, source), model, options, where);
  MarkOutliers(options, &out.lines);
  const AxisRows rows = FitAxes(out.lines, nominal_R, options, where, &out.axes);
  // For the report: the missing row from the other two (right-handed: r1 x r2 = r3), and how far
  // the fitted rows are from orthogonal.
  Eigen::Vector3d full[3] = {rows.row[0], rows.row[1], rows.row[2]};
  if (!rows.have[0]) full[0] = rows.row[1].cross(rows.row[2]).normalized();
  if (!rows.have[1]) full[1] = rows.row[2].cross(rows.row[0]).normalized();
  if (!rows.have[2]) full[2] = rows.row[0].cross(rows.row[1]).normalized();
  for (int k = 0; k < 3; ++k) out.R_before_fix.row(k) = full[k].transpose();
  for (int i = 0; i < 3; ++i) {
    for (int j = i + 1; j < 3; ++j) {
      const double angle = std::acos(std::clamp(full[i].dot(full[j]), -1.0, 1.0)) * kDegPerRad;
      out.orthogonality_error_deg = std::max(out.orthogonality_error_deg, std::abs(angle - 90.0));
    }
  }
  if (!(out.orthogonality_error_deg <= options.max_orthogonality_error_deg)) {
    throw Error(Str(where, ": the vanishing points of the axes are ", out.orthogonality_error_deg,
                    " deg from orthogonal (at most ", options.max_orthogonality_error_deg,
                    "): the marked lines do not run along the vehicle's axes as their axis column says"));
  }
  // The nearest rotation to the measured rows (the paper's R = U V^T), each row weighted by how
  // well its vanishing point is determined (lines / spread^2; short pole lines count less). This
  // is Wahba's problem: maximise sum_k w_k m_k^T R^T e_k, solved by the SVD of diag(w) [m_k^T].
  Eigen::Matrix3d weighted = Eigen::Matrix3d::Zero();
  for (const AxisFit& a : out.axes) {
    const double spread = std::max(a.spread_deg, options.min_spread_deg);
    weighted.row(AxisIndex(a.axis)) = a.direction.transpose() * (a.lines / (spread * spread));
  }
  out.R = NearestRotation(weighted);
  out.change_from_nominal_deg = RotationAngleDeg(nominal_R, out.R);
  return out;
}

Rig CalibrateRig(const Rig& nominal, const std::vector<Mark>& marks,
                 const CalibrationOptions& options, const std::string& source,
                 std::vector<CameraCalibration>* results) {
  for (const Mark& m : marks) {
    if (!nominal.Has(m.camera)) {
      std::string names;
      for (const RigCamera& c : nominal.cameras) names += (names.empty() ? "" : ", ") + c.name;
      throw Error(Str(source, m.file_line > 0 ? Str(":", m.file_line) : std::string(),
                      ": unknown camera '", m.camera, "' (the rig has: ", names, ")"));
    }
  }
  Rig rig = nominal;
  for (RigCamera& cam : rig.cameras) {
    std::vector<Mark> own;
    for (const Mark& m : marks) {
      if (m.camera == cam.name) own.push_back(m);
    }
    if (own.empty()) continue;
    CameraCalibration c = CalibrateCamera(cam.name, cam.model, cam.vehicle_from_camera.R, own,
                                          options, source);
    cam.vehicle_from_camera.R = c.R;
    if (results) results->push_back(std::move(c));
  }
  return rig;
}

std::string CalibrationReport(const CameraCalibration& c) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(3);
  int per_axis[3] = {0, 0, 0};
  for (const LineFit& f : c.lines) per_axis[AxisIndex(f.axis)]++;
  out << "camera " << c.camera << ": lines X " << per_axis[0] << ", Y " << per_axis[1] << ", Z "
      << per_axis[2] << "\n";
  out << "  line axis points  rms_deg  rms_px\n";
  for (const LineFit& f : c.lines) {
    out << "  " << std::setw(4) << f.line << "    " << f.axis << " " << std::setw(6) << f.points
        << " " << std::setw(8) << f.rms_deg << " " << std::setw(7) << f.rms_px;
    if (f.outlier) out << (f.used ? "  OUTLIER (kept; --drop-outliers refits without it)" : "  OUTLIER (dropped)");
    out << "\n";
  }
  for (const AxisFit& a : c.axes) {
    out << "  vanishing point " << a.axis << ": " << a.lines << " lines, spread " << a.spread_deg
        << " deg, direction (" << a.direction.x() << ", " << a.direction.y() << ", "
        << a.direction.z() << ")\n";
  }
  out << "  orthogonality error before SVD fix: " << c.orthogonality_error_deg << " deg\n";
  out << "  rotation change from nominal: " << c.change_from_nominal_deg << " deg\n";
  return out.str();
}

}  // namespace dps
