// dps — extrinsic rotation of a camera from vanishing points of marked lines
// (Gandhi & Trivedi 2006, section IV, eq. 9-10).
//
// Each marked point is unprojected to a unit ray on the viewing sphere. A straight world line is
// a great circle there: its normal l is the left singular vector of the smallest singular value
// of L = (p1 ... pK) (eq. 9). The lines of one direction meet at a vanishing point: the direction
// m with m^T l_i = 0 for all of them, from the SVD of M = (l1 ... lN) (eq. 10). The vanishing
// point of lines along vehicle axis k is, in the camera frame, R^T e_k = r_k, the k-th row of
// R = vehicle_from_camera.R. Lines along Z give r3, along X give r1, vertical lines give r2 (or
// r2 = r3 x r1 without them). The sign of each vanishing direction is ambiguous (m and -m span the
// same point); dps takes the one closer to the nominal rig's r_k. The rows are then replaced by
// the nearest rotation, R = U V^T from the SVD R = U S V^T (det +1), with each row weighted by
// how well its vanishing point is determined (Wahba's problem; equal weights give the paper's
// fix exactly). The position t is not changed.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "dps/calib/marks.h"
#include "dps/camera/camera_model.h"
#include "dps/camera/rig.h"

namespace dps {

// The normal of the great circle through unit rays (eq. 9). `rms_rad` (optional) receives the
// RMS angle between the rays and the fitted plane, radians. At least 2 rays.
Eigen::Vector3d FitGreatCircle(const std::vector<Eigen::Vector3d>& rays, double* rms_rad = nullptr);

// The common direction of great circles with these normals (eq. 10): the unit m minimising
// sum (m^T l_i)^2. `singular_values` (optional) receives the singular values of M, largest first
// (a small second value means the circles are nearly the same: degenerate), each to within about
// 1e-8 of the largest (they come from M M^T's, which are their squares).
Eigen::Vector3d VanishingDirection(const std::vector<Eigen::Vector3d>& normals,
                                   Eigen::Vector3d* singular_values = nullptr);

// The rotation nearest to M (Frobenius), det +1: U V^T from M's SVD.
Eigen::Matrix3d NearestRotation(const Eigen::Matrix3d& M);

struct CalibrationOptions {
  // A line is an outlier when its residual exceeds this many times the median line residual
  // (and outlier_min_deg); > 1.
  double outlier_factor = 4.0;
  double outlier_min_deg = 0.05;  // >= 0: residuals below this are never outliers
  bool drop_outliers = false;      // refit without the flagged lines
  // An axis is degenerate when the second singular value of its normals' matrix is below this
  // fraction of the first (all lines nearly the same great circle); in (0, 1).
  double degenerate_ratio = 0.02;
  // Each vanishing direction is weighted by lines / max(spread, min_spread_deg)^2 in the final
  // nearest-rotation fit; degrees, > 0.
  double min_spread_deg = 0.01;
  // A line whose points span less than this coincide (one point marked again, below any marking
  // tool's precision) and give the line no direction. Short real lines are kept: automatic marks
  // near the edge of a 320x240 omni image span under a pixel. > 0.
  double min_line_span_px = 0.01;
  // Vanishing points of the three axes further than this from orthogonal are closer to another
  // axis than to their own: the marks are not lines along the axes their `axis` column names.
  // (Real marks at 320x240 reach 7 degrees, which the nearest-rotation fit absorbs.) In (0, 90].
  double max_orthogonality_error_deg = 45.0;

  // Throws dps::Error naming the field and the violated constraint.
  void Check() const;
};

// The fit of one marked line.
struct LineFit {
  int line = 0;
  char axis = 'Z';
  int points = 0;
  Eigen::Vector3d normal{0, 0, 1};  // camera frame, unit
  double rms_deg = 0.0;             // RMS angle of the rays to the fitted great circle
  double rms_px = 0.0;              // the same in pixels, approximately (local image scale)
  bool outlier = false;
  bool used = true;                 // false when dropped as an outlier
};

// The vanishing point of one axis.
struct AxisFit {
  char axis = 'Z';
  int lines = 0;                         // lines used
  Eigen::Vector3d direction{0, 0, 1};    // camera frame, unit, sign from the nominal rig
  double spread_deg = 0.0;               // RMS angle between the direction and the lines' planes
};

// The result for one camera.
struct CameraCalibration {
  std::string camera;
  std::vector<LineFit> lines;
  std::vector<AxisFit> axes;                     // the axes that had >= 2 lines
  Eigen::Matrix3d R_before_fix = Eigen::Matrix3d::Identity();  // rows r1, r2, r3 as fitted
                                                 // (a missing row from the cross product)
  double orthogonality_error_deg = 0.0;          // max |angle(ri, rj) - 90 deg| before the fix
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  // vehicle_from_camera rotation
  double change_from_nominal_deg = 0.0;          // angle of R_nominal^T R
};

// Estimates one camera's R from its marks. `marks` must all belong to this camera.
// Throws dps::Error (prefixed with `source`, e.g. the marks file) for: a line with fewer than 3
// points, a point outside the image or without a ray, one line marked with two axes, fewer than
// 2 lines on X or Z (or on Y when one of them is missing), all lines of an axis nearly the same
// great circle.
CameraCalibration CalibrateCamera(const std::string& camera, const CameraModel& model,
                                  const Eigen::Matrix3d& nominal_R, const std::vector<Mark>& marks,
                                  const CalibrationOptions& options, const std::string& source);

// Calibrates every camera of `nominal` that has marks; cameras without marks keep their R.
// Throws dps::Error (prefixed with `source`) for marks of a camera the rig does not have, and
// for everything CalibrateCamera refuses. `results` (optional) receives one entry per
// calibrated camera, in rig order.
Rig CalibrateRig(const Rig& nominal, const std::vector<Mark>& marks,
                 const CalibrationOptions& options, const std::string& source,
                 std::vector<CameraCalibration>* results = nullptr);

// A human-readable report of one camera's calibration: lines per axis, each line's residual
// (degrees and approximate pixels, outliers flagged), the spread of the normals around each
// vanishing point, the orthogonality error before the SVD fix and the change from the nominal
// rotation.
std::string CalibrationReport(const CameraCalibration& result);

}  // namespace dps
