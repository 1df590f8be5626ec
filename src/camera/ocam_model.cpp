#include "dps/camera/ocam_model.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

namespace dps {
namespace {

constexpr double kHalfPi = 1.57079632679489661923;

double Derivative(const std::vector<double>& a, double x) {
  double value = 0.0;
  for (size_t i = a.size(); i-- > 1;) value = value * x + static_cast<double>(i) * a[i];
  return value;
}

// The largest distance of an image corner from the centre, in the toolbox's undistorted units.
double CornerRadius(const OCamParameters& p, int width, int height) {
  const double det = p.c - p.d * p.e;
  double r = 0.0;
  for (double row : {-0.5, height - 0.5}) {
    for (double col : {-0.5, width - 0.5}) {
      const double dr = row - p.xc, dc = col - p.yc;
      r = std::max(r, std::hypot((dr - p.d * dc) / det, (-p.e * dr + p.c * dc) / det));
    }
  }
  return r;
}

// Least-squares polynomial of degree n through (x / scale, y) with weights w, returned for x
// itself (ascending), by QR with column pivoting.
std::vector<double> FitPolynomial(const std::vector<double>& x, const std::vector<double>& y,
                                  const std::vector<double>& w, int n, double scale) {
  Eigen::MatrixXd A(x.size(), n + 1);
  Eigen::VectorXd b(x.size());
  for (size_t i = 0; i < x.size(); ++i) {
    double power = 1.0;
    for (int j = 0; j <= n; ++j, power *= x[i] / scale) A(i, j) = w[i] * power;
    b(i) = w[i] * y[i];
  }
  const Eigen::VectorXd s = A.colPivHouseholderQr().solve(b);
  std::vector<double> out(n + 1);
  for (int j = 0; j <= n; ++j) out[j] = s(j) / std::pow(scale, j);
  return out;
}

constexpr int kMaxDegree = 24;
constexpr int kSamples = 1000;

}  // namespace

double EvaluatePolynomial(const std::vector<double>& a, double x) {
  double value = 0.0;
  for (size_t i = a.size(); i-- > 0;) value = value * x + a[i];
  return value;
}

OCamRange OCamValidRange(const OCamParameters& p, int width, int height) {
  const double corner = CornerRadius(p, width, height);
  constexpr int kSteps = 20000;
  OCamRange range;
  range.limit = "the image's farthest corner";
  for (int i = 1; i <= kSteps; ++i) {
    const double r = corner * i / kSteps;
    const double f = EvaluatePolynomial(p.ss, r);
    const bool angle_grows = Derivative(p.ss, r) * r - f > 0.0;
    const double theta = std::atan2(f, r);
    const bool rho_grows = p.invpol.empty() || Derivative(p.invpol, theta) > 0.0;
    const bool agree = p.invpol.empty() || std::abs(EvaluatePolynomial(p.invpol, theta) - r) <= kOCamAgreementPx;
    if (!angle_grows || !(theta < kHalfPi)) range.limit = "the ray's angle from the axis stops growing (ss)";
    if (!rho_grows) range.limit = "invpol stops growing";
    if (!agree) range.limit = "ss and invpol disagree by more than 0.05 px";
    if (!angle_grows || !rho_grows || !agree || !(theta < kHalfPi)) break;
    range.r_max = r;
    range.theta_max = theta;
  }
  return range;
}

std::vector<double> FitOCamInverse(const OCamParameters& p, int width, int height, double max_error_px) {
  OCamParameters forward = p;
  forward.invpol.clear();
  const OCamRange range = OCamValidRange(forward, width, height);
  std::vector<double> theta, r, w(kSamples + 1, 1.0);
  for (int i = 0; i <= kSamples; ++i) {
    r.push_back(range.r_max * i / kSamples);
    theta.push_back(std::atan2(EvaluatePolynomial(p.ss, r.back()), r.back()));
  }
  std::vector<double> best;
  double best_error = HUGE_VAL;
  for (int n = 1; n <= kMaxDegree; ++n) {
    std::vector<double> fit = FitPolynomial(theta, r, w, n, 1.0);
    double error = 0.0;
    for (size_t i = 0; i < r.size(); ++i) error = std::max(error, std::abs(EvaluatePolynomial(fit, theta[i]) - r[i]));
    if (error < best_error) {
      best_error = error;
      best = std::move(fit);
    }
    if (best_error <= max_error_px) break;
  }
  return best;
}

std::vector<double> FitOCamForward(const OCamParameters& p, int width, int height, double max_error_px) {
  // The range of invpol: from the axis to where rho stops growing or leaves the image.
  const double corner = CornerRadius(p, width, height);
  double theta_end = -kHalfPi;
  constexpr int kSteps = 20000;
  for (int i = 1; i <= kSteps; ++i) {
    const double theta = -kHalfPi + 2.0 * kHalfPi * i / kSteps;
    if (!(Derivative(p.invpol, theta) > 0.0) || EvaluatePolynomial(p.invpol, theta) > corner) break;
    theta_end = theta;
  }
  // Samples (r, f = r tan(theta)), weighted so that the residual is the error in theta times
  // d rho / d theta: pixels.
  std::vector<double> r, f, w;
  for (int i = 1; i <= kSamples; ++i) {
    const double theta = -kHalfPi + (theta_end + kHalfPi) * i / kSamples;
    r.push_back(EvaluatePolynomial(p.invpol, theta));
    f.push_back(r.back() * std::tan(theta));
    w.push_back(r.back() / (r.back() * r.back() + f.back() * f.back()) * Derivative(p.invpol, theta));
  }
  const double scale = std::max(r.back(), 1.0);
  std::vector<double> best;
  double best_error = HUGE_VAL;
  for (int n = 2; n <= kMaxDegree; ++n) {
    std::vector<double> fit = FitPolynomial(r, f, w, n, scale);
    double error = 0.0;
    for (size_t i = 0; i < r.size(); ++i) {
      if (r[i] < 1.0) continue;  // the axis itself maps to the centre, whatever rho(-pi/2) is
      const double theta = std::atan2(EvaluatePolynomial(fit, r[i]), r[i]);
      error = std::max(error, std::abs(EvaluatePolynomial(p.invpol, theta) - r[i]));
    }
    if (!(fit[0] < 0.0)) continue;
    if (error < best_error) {
      best_error = error;
      best = std::move(fit);
    }
    if (best_error <= max_error_px) break;
  }
  return best;
}

bool OCamWorldToCam(const OCamParameters& p, double theta_max, const Eigen::Vector3d& point, Eigen::Vector2d* pixel) {
  // The toolbox's frame: x = Y (rows), y = X (columns), z = -Z.
  const double x = point.y(), y = point.x(), z = -point.z();
  const double n = std::hypot(x, y);
  if (!std::isfinite(n) || !std::isfinite(z)) return false;
  if (n == 0.0) {
    if (!(z < 0.0)) return false;
    *pixel = Eigen::Vector2d(p.yc, p.xc);
    return true;
  }
  const double theta = std::atan(z / n);
  if (theta > theta_max) return false;
  const double rho = EvaluatePolynomial(p.invpol, theta);
  const double row = (p.c * x + p.d * y) * rho / n + p.xc;
  const double col = (p.e * x + y) * rho / n + p.yc;
  *pixel = Eigen::Vector2d(col, row);
  return true;
}

bool OCamCamToWorld(const OCamParameters& p, double r_max, const Eigen::Vector2d& pixel, Eigen::Vector3d* ray) {
  const double det = p.c - p.d * p.e;
  const double dr = pixel.y() - p.xc, dc = pixel.x() - p.yc;
  const double xp = (dr - p.d * dc) / det;
  const double yp = (-p.e * dr + p.c * dc) / det;
  const double r = std::hypot(xp, yp);
  if (!(r <= r_max)) return false;
  const double z = EvaluatePolynomial(p.ss, r);
  // Back to dps's frame: X = y, Y = x, Z = -z.
  *ray = Eigen::Vector3d(yp, xp, -z).normalized();
  return true;
}

}  // namespace dps
