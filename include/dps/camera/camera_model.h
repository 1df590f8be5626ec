// dps — central camera models: hyperbolic mirror, unified (Mei), fisheye (Kannala–Brandt),
// OCamCalib (Scaramuzza).
//
// Conventions
// - Camera frame: origin at the single effective viewpoint, Z along the optical / mirror axis,
//   X along image columns (u), Y along image rows (v). Metres are not needed: a model maps
//   directions.
// - Pixels: (u, v) = (column, row); the centre of the top-left pixel is (0, 0), as in OpenCV.
// - K is the 3x3 upper-triangular calibration matrix [fx s cx; 0 fy cy; 0 0 1].
// - A model maps a 3-D point in the camera frame to a pixel (Project) and a pixel to a unit ray
//   (Unproject). Both return false, leaving the output untouched, where the model has no answer:
//   behind the mirror or lens, outside the field of view, beyond the rim, no real root.
//
// Models (DESIGN.md §2)
// - hyperbolic (Gandhi & Trivedi 2006, eq. 3):
//       [u v 1]^T ~ K [X, Y, a Z + b sqrt(X^2 + Y^2 + Z^2)]^T,  a > 0, b >= 0.
//   The inverse (eq. 4) as printed in the paper is exact only when a^2 - b^2 = 1; Unproject solves
//   the general quadratic (see camera_model.cpp and docs/camera_models.md).
// - unified (Mei / Geyer, exactly as cv::omnidir): the hyperbolic model with a = 1, b = xi, and
//   optional distortion dist = [k1 k2 p1 p2] of the normalised point m = (X, Y) / (Z + xi r):
//       m_d = m (1 + k1 r^2 + k2 r^4) + [2 p1 mx my + p2 (r^2 + 2 mx^2), p1 (r^2 + 2 my^2) + 2 p2 mx my],
//   r = |m|, then [u v 1]^T = K [m_d, 1]^T. Rays are valid up to the largest r at which the
//   radial factor r (1 + k1 r^2 + k2 r^4) still grows; Unproject inverts the distortion by
//   Newton's method and reports no ray where it does not converge to 1e-12 (beyond that radius, or
//   where the tangential terms fold the image). Without distortion, a hyperbolic (K, a, b) equals a
//   unified (K diag(1/a, 1/a, 1), xi = b / a).
// - fisheye (Kannala–Brandt, as cv::fisheye): theta = angle of the ray to +Z,
//       theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8),
//       [u v 1]^T = K [theta_d cos(phi), theta_d sin(phi), 1]^T;  all k = 0 is equidistant.
//   Rays are valid up to the largest theta (<= pi) below which theta_d grows monotonically.
// - ocam (Scaramuzza's OCamCalib, exactly as its cam2world / world2cam): see ocam_model.h. It has
//   no K of its own; K() is the pinhole that matches it at the axis (focal -a0, centre (yc, xc)),
//   which is where the rim is centred.
//
// Every model may have a rim: a circle of radius rim_radius_px around the principal point
// (cx, cy) outside which no pixel sees the scene (the mirror's rim, the lens' image circle).
// rim_radius_px = 0 means no rim.
#pragma once

#include <array>
#include <stdexcept>
#include <string>

#include <Eigen/Core>

#include "dps/camera/ocam_model.h"
#include "dps/util/error.h"

namespace dps {

enum class CameraModelType { kHyperbolic, kUnified, kFisheye, kOCam };

// "hyperbolic", "unified", "fisheye" or "ocam", as in rig.yaml.
std::string ModelName(CameraModelType type);
// Inverse of ModelName; throws std::invalid_argument for any other string.
CameraModelType ModelTypeFromName(const std::string& name);

// An immutable, validated intrinsic camera model. Build one with the static factories, which
// throw std::invalid_argument naming the field and the violated constraint.
class CameraModel {
 public:
  // Hyperbolic mirror, paper eq. 3. width, height: image size in pixels (> 0). K: fx, fy > 0,
  // K(1,0) = K(2,0) = K(2,1) = 0, K(2,2) = 1. a > 0, b >= 0. rim_radius_px >= 0 (0 = no rim).
  static CameraModel Hyperbolic(int width, int height, const Eigen::Matrix3d& K, double a,
                                double b, double rim_radius_px = 0.0);
  // Unified (Mei) model, xi >= 0, dist = [k1 k2 p1 p2] (finite; all 0 = none). Same constraints on
  // the other arguments as Hyperbolic.
  static CameraModel Unified(int width, int height, const Eigen::Matrix3d& K, double xi,
                             double rim_radius_px = 0.0, const std::array<double, 4>& dist = {0, 0, 0, 0});
  // Kannala–Brandt fisheye, dist = [k1 k2 k3 k4] (finite; k1 > -1/3 so that the lens is
  // monotonic near the axis). Same constraints on the other arguments as Hyperbolic.
  static CameraModel Fisheye(int width, int height, const Eigen::Matrix3d& K,
                             const std::array<double, 4>& dist, double rim_radius_px = 0.0);
  // OCamCalib model: ss non-empty with a0 < 0, all coefficients finite, c - d e != 0; invpol is
  // fitted (FitOCamInverse) when empty. The valid range is OCamValidRange's.
  static CameraModel OCam(int width, int height, const OCamParameters& parameters, double rim_radius_px = 0.0);

  // Projects a point in the camera frame to a pixel. Returns false when the point has no image
  // (at the viewpoint, behind the mirror / outside the field of view, or beyond the rim).
  // A valid pixel may still lie outside the image; see InImage.
  bool Project(const Eigen::Vector3d& point_camera, Eigen::Vector2d* pixel) const;

  // Unprojects a pixel to a unit ray in the camera frame. Returns false when the pixel sees
  // nothing (beyond the rim, no real root, outside the field of view).
  bool Unproject(const Eigen::Vector2d& pixel, Eigen::Vector3d* ray) const;

  // True when the pixel lies inside the image, [-0.5, width - 0.5) x [-0.5, height - 0.5).
  bool InImage(const Eigen::Vector2d& pixel) const;

  CameraModelType type() const { return type_; }
  int width() const { return width_; }
  int height() const { return height_; }
  const Eigen::Matrix3d& K() const { return K_; }
  // Mirror parameters of the hyperbolic model; for a unified model a = 1 and b = xi.
  double a() const { return a_; }
  double b() const { return b_; }
  double xi() const { return b_ / a_; }
  // fisheye: [k1 k2 k3 k4]; unified: [k1 k2 p1 p2] (zeros: none); hyperbolic: zeros.
  const std::array<double, 4>& dist() const { return dist_; }
  double rim_radius_px() const { return rim_radius_px_; }
  // Largest valid angle between a ray and +Z, radians (fisheye: monotonic range; others: from
  // the mirror's validity condition).
  double max_theta_rad() const { return max_theta_rad_; }
  // ocam: its parameters (empty polynomials for the other models).
  const OCamParameters& ocam() const { return ocam_; }

 private:
  CameraModel() = default;
  // The fields every model has, checked (CheckCommon).
  static CameraModel Common(CameraModelType type, int width, int height, const Eigen::Matrix3d& K,
                            double rim_radius_px);
  void CheckCommon() const;
  bool InsideRim(const Eigen::Vector2d& pixel) const;

  CameraModelType type_ = CameraModelType::kHyperbolic;
  int width_ = 0;
  int height_ = 0;
  Eigen::Matrix3d K_ = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d K_inv_ = Eigen::Matrix3d::Identity();
  double a_ = 1.0;
  double b_ = 0.0;
  std::array<double, 4> dist_{};
  double rim_radius_px_ = 0.0;
  double max_theta_rad_ = 0.0;
  double max_theta_d_ = 0.0;  // fisheye: theta_d at max_theta_rad_
  double max_r2_ = 0.0;       // unified with distortion: largest squared undistorted radius, else 0
  OCamParameters ocam_;
  OCamRange ocam_range_;
  bool Distorted() const { return type_ == CameraModelType::kUnified && max_r2_ > 0.0; }
  Eigen::Vector2d Distort(const Eigen::Vector2d& m) const;
  bool Undistort(const Eigen::Vector2d& md, Eigen::Vector2d* m) const;
};

// Calls a CameraModel factory, turning its std::invalid_argument into a dps::Error prefixed by
// `where` (the file and camera): how the readers of calibration files report a bad parameter.
template <typename Factory>
CameraModel MakeModel(const std::string& where, Factory&& factory) {
  try {
    return factory();
  } catch (const std::invalid_argument& e) {
    throw Error(Str(where, ": ", e.what()));
  }
}

// The unified model that gives the same pixels as a hyperbolic one: xi = b / a,
// K' = K diag(1/a, 1/a, 1). Throws std::invalid_argument for a model of another type.
CameraModel HyperbolicToUnified(const CameraModel& hyperbolic);

// The hyperbolic model with mirror parameter a that gives the same pixels as a unified one:
// b = xi a, K = K' diag(a, a, 1). Throws std::invalid_argument for a model of another type.
CameraModel UnifiedToHyperbolic(const CameraModel& unified, double a);

// The same model for images resized to width x height: K is scaled about the pixel grid
// (u' + 0.5 = s (u + 0.5)), the rim by the smaller of the two scales.
CameraModel ResizeCameraModel(const CameraModel& model, int width, int height);

// The paper's own inverse, eq. 4, for a hyperbolic (or unified) model:
// p = [u', v', a - b sqrt(u'^2 + v'^2 + 1)] with [u' v' 1]^T = K^-1 [u v 1]^T, normalised.
// Exact only when a^2 - b^2 = 1; kept to document and test that special case.
Eigen::Vector3d PaperEq4Ray(const CameraModel& model, const Eigen::Vector2d& pixel);

}  // namespace dps
