// dps — Scaramuzza's OCamCalib model (DESIGN.md §2 `ocam`): the polynomials, their valid range,
// and fitting one polynomial from the other when a calibration file has only one.
//
// Exactly as OCamCalib's `cam2world` / `world2cam` (ocam_functions.c) and `calib_results.txt`
// define it, in the toolbox's own frame: x along image rows, y along image columns, the optical
// axis towards -z (f(0) = a0 < 0). With m = (row, column):
//   cam2world:  [xp, yp] = A^-1 [m_row - xc, m_col - yc],  A = [c d; e 1],
//               ray = (xp, yp, f(r)) normalised, r = |(xp, yp)|, f(r) = a0 + a1 r + a2 r^2 + ...
//   world2cam:  n = |(x, y)|, theta = atan(z / n), rho = p0 + p1 theta + p2 theta^2 + ...,
//               m_row = (c x + d y) rho / n + xc,  m_col = (e x + y) rho / n + yc.
// dps's camera frame (X along columns, Y along rows, Z along the optical axis) is the toolbox's
// frame turned: (x, y, z)_ocam = (Y, X, -Z) — a rotation, so the two describe the same camera.
//
// Valid range: from the axis out to the smallest of the image's farthest corner, the first radius
// where the ray's angle from the axis stops growing with r (f(r) - r f'(r) <= 0), the first where
// invpol stops growing with theta, and the first where the two polynomials disagree by more than
// kOCamAgreementPx (beyond the radius the toolbox fitted invpol on); rays beyond it have no pixel
// and pixels beyond it no ray.
#pragma once

#include <vector>

#include <Eigen/Core>

namespace dps {

constexpr double kOCamAgreementPx = 0.05;

struct OCamParameters {
  std::vector<double> ss;      // a0 .. aN, ascending: f(r) (cam2world); a0 < 0
  std::vector<double> invpol;  // p0 .. pM, ascending: rho(theta) (world2cam), theta in radians
  double xc = 0.0;             // centre: row, 0-based (the toolbox's order)
  double yc = 0.0;             //         column, 0-based
  double c = 1.0;              // affine part [c d; e 1], c - d e != 0
  double d = 0.0;
  double e = 0.0;
};

// The valid range of a model for an image of width x height: the largest radius r (in the
// toolbox's undistorted units, i.e. pixels when c = 1, d = e = 0) and its theta = atan(f(r) / r),
// in (-pi/2, pi/2). Uses invpol only when it is not empty.
struct OCamRange {
  double r_max = 0.0;
  double theta_max = 0.0;
  const char* limit = "";  // what ends it: "the image's farthest corner", ...
};
OCamRange OCamValidRange(const OCamParameters& p, int width, int height);

// invpol for `p.ss`, as the toolbox's findinvpoly does: the lowest degree whose rho(theta)
// reproduces r within max_error_px over the valid range (at most degree 24; then the best found).
std::vector<double> FitOCamInverse(const OCamParameters& p, int width, int height, double max_error_px = 1e-3);

// ss for `p.invpol` (for files that carry only the inverse polynomial): the lowest degree whose
// f(r) gives back theta with world2cam(cam2world(pixel)) within max_error_px of the pixel over the
// valid range of invpol (theta from the axis to `theta_max`, or to where rho reaches the image's
// farthest corner).
std::vector<double> FitOCamForward(const OCamParameters& p, int width, int height, double max_error_px = 1e-3);

// A polynomial with ascending coefficients at x.
double EvaluatePolynomial(const std::vector<double>& coefficients, double x);

// The two maps, in dps's camera frame (see above); false where the model has no answer.
bool OCamWorldToCam(const OCamParameters& p, double theta_max, const Eigen::Vector3d& point, Eigen::Vector2d* pixel);
bool OCamCamToWorld(const OCamParameters& p, double r_max, const Eigen::Vector2d& pixel, Eigen::Vector3d* ray);

}  // namespace dps
