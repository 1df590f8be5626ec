#include "dps/camera/rig.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>
#include <Eigen/LU>

#include "dps/util/error.h"
#include "dps/util/math.h"

namespace dps {

Pose Pose::Inverse() const {
  Pose inv;
  inv.R = R.transpose();
  inv.t = -(inv.R * t);
  return inv;
}

Pose Pose::operator*(const Pose& other) const {
  Pose out;
  out.R = R * other.R;
  out.t = R * other.t + t;
  return out;
}

const RigCamera& Rig::Camera(const std::string& name) const {
  for (const RigCamera& c : cameras) {
    if (c.name == name) return c;
  }
  std::string present;
  for (const RigCamera& c : cameras) present += (present.empty() ? "" : ", ") + c.name;
  throw Error(Str("rig has no camera named '", name, "' (it has: ",
                  present.empty() ? "none" : present, ")"));
}

bool Rig::Has(const std::string& name) const {
  return std::any_of(cameras.begin(), cameras.end(),
                     [&](const RigCamera& c) { return c.name == name; });
}

std::string RotationProblem(const Eigen::Matrix3d& R, double tolerance) {
  if (!R.allFinite()) return "R has non-finite entries";
  const double ortho = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (ortho > tolerance) {
    return Str("R is not orthonormal: max |R^T R - I| = ", ortho, " > ", tolerance);
  }
  const double det = R.determinant();
  if (det <= 0.0) return Str("R is a reflection: det(R) = ", det, " (expected +1)");
  return "";
}

Eigen::Matrix3d AxisAngle(const Eigen::Vector3d& axis, double angle_rad) {
  return Eigen::AngleAxisd(angle_rad, axis.normalized()).toRotationMatrix();
}

double RotationAngleDeg(const Eigen::Matrix3d& A, const Eigen::Matrix3d& B) {
  const Eigen::Matrix3d D = A.transpose() * B;
  const double c = std::clamp((D.trace() - 1.0) / 2.0, -1.0, 1.0);
  // acos loses precision near 0; use the sine from the skew part as well.
  const double s = 0.5 * Eigen::Vector3d(D(2, 1) - D(1, 2), D(0, 2) - D(2, 0), D(1, 0) - D(0, 1))
                             .norm();
  return std::atan2(s, c) * kDegPerRad;
}

bool RayMeetsRoad(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, Eigen::Vector3d* ground) {
  if (direction.y() <= 1e-9 || origin.y() >= 0) return false;
  *ground = origin + (-origin.y() / direction.y()) * direction;
  return true;
}

}  // namespace dps
