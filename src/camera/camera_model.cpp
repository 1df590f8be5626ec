#include "dps/camera/camera_model.h"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "dps/util/error.h"
#include "dps/util/math.h"

namespace dps {
namespace {

void Require(bool ok, const std::string& field, double value, const std::string& constraint) {
  if (!ok) {
    throw std::invalid_argument(
        Str("field '", field, "' = ", value, ": violated constraint ", constraint));
  }
}

// theta_d(theta) of the Kannala–Brandt polynomial, and its derivative.
double FisheyeThetaD(const std::array<double, 4>& k, double theta) {
  const double t2 = theta * theta;
  return theta * (1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))));
}
double FisheyeThetaDDerivative(const std::array<double, 4>& k, double theta) {
  const double t2 = theta * theta;
  return 1.0 + t2 * (3.0 * k[0] + t2 * (5.0 * k[1] + t2 * (7.0 * k[2] + t2 * 9.0 * k[3])));
}

// Smallest w such that a ray is valid iff cos(theta) > -w, for the mirror parameter xi = b / a.
// For xi <= 1 this is the sign of the denominator a Z + b r; for xi > 1 a pixel sees two rays and
// only the one with xi Z + r > 0 (the near sheet of the mirror) is kept.
double MirrorW(double xi) { return xi <= 1.0 ? xi : 1.0 / xi; }

}  // namespace

std::string ModelName(CameraModelType type) {
  switch (type) {
    case CameraModelType::kHyperbolic: return "hyperbolic";
    case CameraModelType::kUnified: return "unified";
    case CameraModelType::kFisheye: return "fisheye";
    case CameraModelType::kOCam: return "ocam";
  }
  return "unknown";
}

CameraModelType ModelTypeFromName(const std::string& name) {
  if (name == "hyperbolic") return CameraModelType::kHyperbolic;
  if (name == "unified") return CameraModelType::kUnified;
  if (name == "fisheye") return CameraModelType::kFisheye;
  if (name == "ocam") return CameraModelType::kOCam;
  throw std::invalid_argument("unknown model '" + name +
                              "' (expected hyperbolic, unified, fisheye or ocam)");
}

void CameraModel::CheckCommon() const {
  Require(width_ > 0, "width", width_, "width > 0");
  Require(height_ > 0, "height", height_, "height > 0");
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) Require(std::isfinite(K_(r, c)), "K", K_(r, c), "finite");
  }
  // A focal length of more than 1000 image sizes is a field of view under 0.06 degrees: no camera
  // dps is for, but a unit error or a corrupt file.
  const double max_focal = 1000.0 * std::max(width_, height_);
  Require(K_(0, 0) > 0.0 && K_(0, 0) <= max_focal, "K[0][0] (fx)", K_(0, 0), Str("0 < fx <= ", max_focal, " (1000 image sizes)"));
  Require(K_(1, 1) > 0.0 && K_(1, 1) <= max_focal, "K[1][1] (fy)", K_(1, 1), Str("0 < fy <= ", max_focal, " (1000 image sizes)"));
  Require(K_(1, 0) == 0.0, "K[1][0]", K_(1, 0), "== 0 (upper triangular)");
  Require(K_(2, 0) == 0.0, "K[2][0]", K_(2, 0), "== 0 (upper triangular)");
  Require(K_(2, 1) == 0.0, "K[2][1]", K_(2, 1), "== 0 (upper triangular)");
  Require(K_(2, 2) == 1.0, "K[2][2]", K_(2, 2), "== 1");
  Require(rim_radius_px_ >= 0.0 && std::isfinite(rim_radius_px_), "rim_radius", rim_radius_px_,
          "finite and >= 0 (0 = no rim)");
}

CameraModel CameraModel::Common(CameraModelType type, int width, int height, const Eigen::Matrix3d& K,
                                double rim_radius_px) {
  CameraModel m;
  m.type_ = type;
  m.width_ = width;
  m.height_ = height;
  m.K_ = K;
  m.rim_radius_px_ = rim_radius_px;
  m.CheckCommon();
  return m;
}

CameraModel CameraModel::Hyperbolic(int width, int height, const Eigen::Matrix3d& K, double a,
                                    double b, double rim_radius_px) {
  CameraModel m = Common(CameraModelType::kHyperbolic, width, height, K, rim_radius_px);
  Require(a > 0.0 && std::isfinite(a), "a", a, "finite and a > 0");
  Require(b >= 0.0 && std::isfinite(b), "b", b, "finite and b >= 0");
  m.a_ = a;
  m.b_ = b;
  m.K_inv_ = K.inverse();
  m.max_theta_rad_ = std::acos(-MirrorW(b / a));
  return m;
}

CameraModel CameraModel::Unified(int width, int height, const Eigen::Matrix3d& K, double xi,
                                 double rim_radius_px, const std::array<double, 4>& dist) {
  Require(xi >= 0.0 && std::isfinite(xi), "xi", xi, "finite and xi >= 0");
  for (int i = 0; i < 4; ++i) {
    Require(std::isfinite(dist[i]), Str("dist[", i, "] (", i < 2 ? "k" : "p", i % 2 + 1, ")"), dist[i], "finite");
  }
  CameraModel m = Hyperbolic(width, height, K, 1.0, xi, rim_radius_px);
  m.type_ = CameraModelType::kUnified;
  m.dist_ = dist;
  if (dist != std::array<double, 4>{0, 0, 0, 0}) {
    // The radial factor r (1 + k1 r^2 + k2 r^4) grows while 1 + 3 k1 r^2 + 5 k2 r^4 > 0; the
    // normalised radius never exceeds 1 / (1 - xi) for xi < 1 (the ray at 180 degrees), or grows
    // without bound for xi >= 1. Search up to the first turn, or a radius no camera reaches.
    const double limit = xi < 1.0 ? 1.0 / (1.0 - xi) : 1e3;
    constexpr int kSteps = 100000;
    double r_max = limit;
    for (int i = 1; i <= kSteps; ++i) {
      const double r = limit * i / kSteps, r2 = r * r;
      if (1.0 + 3.0 * dist[0] * r2 + 5.0 * dist[1] * r2 * r2 <= 0.0) {
        r_max = limit * (i - 1) / kSteps;
        break;
      }
    }
    Require(r_max > 0.0, "dist[0] (k1)", dist[0], "a distortion that grows near the axis");
    m.max_r2_ = r_max * r_max;
  }
  return m;
}

Eigen::Vector2d CameraModel::Distort(const Eigen::Vector2d& m) const {
  const double k1 = dist_[0], k2 = dist_[1], p1 = dist_[2], p2 = dist_[3];
  const double x = m.x(), y = m.y(), r2 = x * x + y * y;
  const double radial = 1.0 + k1 * r2 + k2 * r2 * r2;
  return {x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
          y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y};
}

bool CameraModel::Undistort(const Eigen::Vector2d& md, Eigen::Vector2d* m) const {
  // Newton's method on Distort(m) = md from m = md, with the analytic Jacobian.
  const double k1 = dist_[0], k2 = dist_[1], p1 = dist_[2], p2 = dist_[3];
  Eigen::Vector2d x = md;
  for (int it = 0; it < 50; ++it) {
    const Eigen::Vector2d f = Distort(x) - md;
    if (f.norm() < 1e-12) {
      if (x.squaredNorm() > max_r2_) return false;
      *m = x;
      return true;
    }
    const double u = x.x(), v = x.y(), r2 = u * u + v * v;
    const double radial = 1.0 + k1 * r2 + k2 * r2 * r2, dradial = 2.0 * k1 + 4.0 * k2 * r2;  // d radial / d(r2)
    Eigen::Matrix2d J;
    J(0, 0) = radial + u * dradial * 2.0 * u + 2.0 * p1 * v + p2 * 6.0 * u;
    J(0, 1) = u * dradial * 2.0 * v + 2.0 * p1 * u + p2 * 2.0 * v;
    J(1, 0) = v * dradial * 2.0 * u + p1 * 2.0 * u + 2.0 * p2 * v;
    J(1, 1) = radial + v * dradial * 2.0 * v + p1 * 6.0 * v + 2.0 * p2 * u;
    const double det = J.determinant();
    if (!(std::abs(det) > 1e-12)) return false;
    x -= J.inverse() * f;
    if (!x.allFinite()) return false;
  }
  return false;
}

CameraModel CameraModel::Fisheye(int width, int height, const Eigen::Matrix3d& K,
                                 const std::array<double, 4>& dist, double rim_radius_px) {
  CameraModel m = Common(CameraModelType::kFisheye, width, height, K, rim_radius_px);
  for (int i = 0; i < 4; ++i) {
    Require(std::isfinite(dist[i]), Str("dist[", i, "] (k", i + 1, ")"), dist[i], "finite");
  }
  Require(dist[0] > -1.0 / 3.0, "dist[0] (k1)", dist[0], "k1 > -1/3 (monotonic near the axis)");
  m.dist_ = dist;
  m.K_inv_ = K.inverse();
  // The lens is usable up to the first theta where theta_d stops growing (or pi).
  constexpr int kSteps = 20000;
  m.max_theta_rad_ = kPi;
  for (int i = 1; i <= kSteps; ++i) {
    const double theta = kPi * i / kSteps;
    if (FisheyeThetaDDerivative(dist, theta) <= 0.0) {
      m.max_theta_rad_ = kPi * (i - 1) / kSteps;
      break;
    }
  }
  m.max_theta_d_ = FisheyeThetaD(dist, m.max_theta_rad_);
  return m;
}

CameraModel CameraModel::OCam(int width, int height, const OCamParameters& p, double rim_radius_px) {
  Require(!p.ss.empty(), "ss", 0, "at least one coefficient");
  for (size_t i = 0; i < p.ss.size(); ++i) Require(std::isfinite(p.ss[i]), Str("ss[", i, "]"), p.ss[i], "finite");
  for (size_t i = 0; i < p.invpol.size(); ++i) {
    Require(std::isfinite(p.invpol[i]), Str("invpol[", i, "]"), p.invpol[i], "finite");
  }
  Require(p.ss[0] < 0.0, "ss[0] (a0)", p.ss[0], "a0 < 0 (the optical axis is the toolbox's -z)");
  Require(std::isfinite(p.xc), "center[0] (xc, row)", p.xc, "finite");
  Require(std::isfinite(p.yc), "center[1] (yc, column)", p.yc, "finite");
  Require(std::isfinite(p.c) && std::isfinite(p.d) && std::isfinite(p.e), "affine", p.c, "finite c, d, e");
  Require(std::abs(p.c - p.d * p.e) > 1e-9, "affine[0] (c)", p.c, "c - d e != 0");
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  K(0, 0) = K(1, 1) = -p.ss[0];
  K(0, 2) = p.yc;
  K(1, 2) = p.xc;
  CameraModel m = Common(CameraModelType::kOCam, width, height, K, rim_radius_px);
  m.K_inv_ = K.inverse();
  m.ocam_ = p;
  if (m.ocam_.invpol.empty()) m.ocam_.invpol = FitOCamInverse(p, width, height);
  m.ocam_range_ = OCamValidRange(m.ocam_, width, height);
  Require(m.ocam_range_.r_max > 0.0, "ss", p.ss[0], Str("a valid range around the centre (it ends at once: ", m.ocam_range_.limit, ")"));
  m.max_theta_rad_ = m.ocam_range_.theta_max + kPi / 2.0;
  return m;
}

bool CameraModel::InsideRim(const Eigen::Vector2d& pixel) const {
  if (rim_radius_px_ <= 0.0) return true;
  const double du = pixel.x() - K_(0, 2);
  const double dv = pixel.y() - K_(1, 2);
  return du * du + dv * dv <= rim_radius_px_ * rim_radius_px_;
}

bool CameraModel::InImage(const Eigen::Vector2d& pixel) const {
  return pixel.x() >= -0.5 && pixel.y() >= -0.5 && pixel.x() < width_ - 0.5 &&
         pixel.y() < height_ - 0.5;
}

bool CameraModel::Project(const Eigen::Vector3d& p, Eigen::Vector2d* pixel) const {
  const double r = p.norm();
  if (!(r > 0.0) || !std::isfinite(r)) return false;
  if (type_ == CameraModelType::kOCam) {
    Eigen::Vector2d out;
    if (!OCamWorldToCam(ocam_, ocam_range_.theta_max, p, &out) || !InsideRim(out)) return false;
    *pixel = out;
    return true;
  }
  double mx = 0.0;
  double my = 0.0;
  if (type_ == CameraModelType::kFisheye) {
    const double rho = std::hypot(p.x(), p.y());
    const double theta = std::atan2(rho, p.z());
    if (theta > max_theta_rad_) return false;
    if (rho > 0.0) {
      const double scale = FisheyeThetaD(dist_, theta) / rho;
      mx = scale * p.x();
      my = scale * p.y();
    }
  } else {
    // Paper eq. 3: valid on the near sheet, cos(theta) > -w (see MirrorW).
    if (p.z() <= -MirrorW(b_ / a_) * r) return false;
    const double denom = a_ * p.z() + b_ * r;
    if (!(denom > 0.0)) return false;
    mx = p.x() / denom;
    my = p.y() / denom;
    if (Distorted()) {
      if (mx * mx + my * my > max_r2_) return false;
      const Eigen::Vector2d d = Distort({mx, my});
      mx = d.x();
      my = d.y();
    }
  }
  const Eigen::Vector2d out(K_(0, 0) * mx + K_(0, 1) * my + K_(0, 2), K_(1, 1) * my + K_(1, 2));
  if (!InsideRim(out)) return false;
  *pixel = out;
  return true;
}

bool CameraModel::Unproject(const Eigen::Vector2d& pixel, Eigen::Vector3d* ray) const {
  if (!InsideRim(pixel)) return false;
  if (type_ == CameraModelType::kOCam) return OCamCamToWorld(ocam_, ocam_range_.r_max, pixel, ray);
  double my = (pixel.y() - K_(1, 2)) * K_inv_(1, 1);
  double mx = (pixel.x() - K_(0, 2) - K_(0, 1) * my) / K_(0, 0);
  if (Distorted()) {
    Eigen::Vector2d m;
    if (!Undistort({mx, my}, &m)) return false;
    mx = m.x();
    my = m.y();
  }
  const double rho2 = mx * mx + my * my;
  if (type_ == CameraModelType::kFisheye) {
    const double theta_d = std::sqrt(rho2);
    if (theta_d > max_theta_d_) return false;
    if (theta_d == 0.0) {
      *ray = Eigen::Vector3d(0.0, 0.0, 1.0);
      return true;
    }
    // theta_d(theta) grows monotonically on [0, max_theta]: Newton's method kept inside a
    // shrinking bracket converges to machine precision in a few steps.
    double lo = 0.0;
    double hi = max_theta_rad_;
    double theta = std::min(theta_d, hi);
    for (int it = 0; it < 60; ++it) {
      const double f = FisheyeThetaD(dist_, theta) - theta_d;
      if (f > 0.0) hi = theta; else lo = theta;
      const double df = FisheyeThetaDDerivative(dist_, theta);
      double next = df > 0.0 ? theta - f / df : 0.5 * (lo + hi);
      if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
      if (std::abs(next - theta) < 1e-15) {
        theta = next;
        break;
      }
      theta = next;
    }
    const double s = std::sin(theta) / theta_d;
    *ray = Eigen::Vector3d(s * mx, s * my, std::cos(theta));
    return true;
  }
  // Hyperbolic / unified: the unit ray is (s mx, s my, z) with a z + b = s (eq. 3 with r = 1),
  // so s^2 rho^2 + ((s - b) / a)^2 = 1, i.e. (1 + a^2 rho^2) s^2 - 2 b s + b^2 - a^2 = 0, whose
  // discriminant / 4 is a^2 (1 + rho^2 (a^2 - b^2)). The larger root is the near-sheet ray.
  const double disc = 1.0 + rho2 * (a_ * a_ - b_ * b_);
  if (disc < 0.0) return false;
  const double s = (b_ + a_ * std::sqrt(disc)) / (1.0 + a_ * a_ * rho2);
  const Eigen::Vector3d out(s * mx, s * my, (s - b_) / a_);
  if (out.z() <= -MirrorW(b_ / a_) - 1e-12) return false;
  *ray = out.normalized();  // unit by construction; normalising removes rounding only
  return true;
}

CameraModel HyperbolicToUnified(const CameraModel& h) {
  if (h.type() != CameraModelType::kHyperbolic) {
    throw std::invalid_argument("HyperbolicToUnified: model is " + ModelName(h.type()));
  }
  const Eigen::Matrix3d K = h.K() * Eigen::Vector3d(1.0 / h.a(), 1.0 / h.a(), 1.0).asDiagonal();
  return CameraModel::Unified(h.width(), h.height(), K, h.b() / h.a(), h.rim_radius_px());
}

CameraModel UnifiedToHyperbolic(const CameraModel& u, double a) {
  if (u.type() != CameraModelType::kUnified) {
    throw std::invalid_argument("UnifiedToHyperbolic: model is " + ModelName(u.type()));
  }
  if (u.dist() != std::array<double, 4>{0, 0, 0, 0}) {
    throw std::invalid_argument("UnifiedToHyperbolic: the unified model has distortion, which no mirror model has");
  }
  const Eigen::Matrix3d K = u.K() * Eigen::Vector3d(a, a, 1.0).asDiagonal();
  return CameraModel::Hyperbolic(u.width(), u.height(), K, a, u.xi() * a, u.rim_radius_px());
}

CameraModel ResizeCameraModel(const CameraModel& m, int width, int height) {
  const double sx = static_cast<double>(width) / m.width();
  const double sy = static_cast<double>(height) / m.height();
  Eigen::Matrix3d K = m.K();
  K.row(0) *= sx;
  K.row(1) *= sy;
  K(0, 2) += 0.5 * (sx - 1.0);
  K(1, 2) += 0.5 * (sy - 1.0);
  K(2, 2) = 1.0;
  const double rim = m.rim_radius_px() * std::min(sx, sy);
  switch (m.type()) {
    case CameraModelType::kHyperbolic: return CameraModel::Hyperbolic(width, height, K, m.a(), m.b(), rim);
    case CameraModelType::kUnified: return CameraModel::Unified(width, height, K, m.xi(), rim, m.dist());
    case CameraModelType::kFisheye: return CameraModel::Fisheye(width, height, K, m.dist(), rim);
    case CameraModelType::kOCam: {
      // Columns scale the radius by sx; the rows' extra factor sy / sx goes into the affine part.
      OCamParameters p = m.ocam();
      for (size_t i = 0; i < p.ss.size(); ++i) p.ss[i] *= std::pow(sx, 1.0 - static_cast<double>(i));
      for (double& c : p.invpol) c *= sx;
      p.xc = sy * (p.xc + 0.5) - 0.5;
      p.yc = sx * (p.yc + 0.5) - 0.5;
      p.c *= sy / sx;
      p.d *= sy / sx;
      return CameraModel::OCam(width, height, p, rim);
    }
  }
  throw std::invalid_argument("ResizeCameraModel: unknown model type");
}

Eigen::Vector3d PaperEq4Ray(const CameraModel& model, const Eigen::Vector2d& pixel) {
  const Eigen::Vector3d m = model.K().inverse() * Eigen::Vector3d(pixel.x(), pixel.y(), 1.0);
  const double rho2 = m.x() * m.x() + m.y() * m.y();
  return Eigen::Vector3d(m.x(), m.y(), model.a() - model.b() * std::sqrt(rho2 + 1.0))
      .normalized();
}

}  // namespace dps
