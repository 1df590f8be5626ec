// dps — the rig: the vehicle and its cameras, and the frames that tie them together.
//
// Conventions (DESIGN.md §1, Gandhi & Trivedi 2006 section III)
// - Vehicle frame: origin on the ground directly below the centre of the vehicle; X to the right,
//   Y down, Z forward; metres. A point on the road has Y = 0; a camera 1 m above the road has
//   Y = -1.
// - Camera frame: see camera_model.h.
// - Extrinsics (paper eq. 1, P0 = Ri Pi + Di): P_vehicle = R * P_camera + t, with R the rotation
//   vehicle_from_camera (orthonormal, det +1) and t the camera viewpoint in the vehicle frame.
// - Yaw rate: rad/s, positive when the vehicle turns left (counter-clockwise seen from above).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "dps/camera/camera_model.h"

namespace dps {

// A rigid transform P_to = R * P_from + t; named after what it maps, e.g. vehicle_from_camera.
struct Pose {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  // rotation, orthonormal, det +1
  Eigen::Vector3d t = Eigen::Vector3d::Zero();      // translation, metres

  // Maps a point of the source frame into the target frame.
  Eigen::Vector3d Apply(const Eigen::Vector3d& p) const { return R * p + t; }
  // Maps a direction (no translation).
  Eigen::Vector3d Rotate(const Eigen::Vector3d& d) const { return R * d; }
  // The inverse transform (from the target frame back to the source frame).
  Pose Inverse() const;
  // Composition: (this * other)(p) = this(other(p)).
  Pose operator*(const Pose& other) const;
};

// Where the ray from `origin` along `direction` (vehicle frame) meets the road, the plane Y = 0
// (Y points down): false when the origin is not above the road or the ray does not descend.
bool RayMeetsRoad(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, Eigen::Vector3d* ground);

// Size of the own vehicle, used to draw it on the map.
struct Vehicle {
  double length_m = 4.8;  // > 0
  double width_m = 1.8;   // > 0
};

// One camera of the rig: its name, intrinsics and extrinsics.
struct RigCamera {
  std::string name;                 // "left", "right", ...
  CameraModel model;                // intrinsics
  Pose vehicle_from_camera;         // extrinsics, P_vehicle = R P_camera + t
  // Optional: which pixels see the world (CV_8U of the model's size; 255 = sees it, 0 = never
  // does: beyond the mirror's or lens's field, the own car). Empty: the model's domain alone.
  cv::Mat mask;
  std::string mask_file;            // the file rig.yaml names for it (as written there), or empty
  // Optional: the own car as estimated from a drive's images (EstimateOwnCarMask; CV_8U of the
  // model's size, 255 = the own car). Not in rig.yaml. Unlike `mask`, it does not stop matching
  // windows at its edge: the detectors only take no obstacle from it (OwnCarMask).
  cv::Mat own_car;
};

// The vehicle and its cameras, as in rig.yaml (DESIGN.md §3.1).
struct Rig {
  Vehicle vehicle;
  std::vector<RigCamera> cameras;

  // The camera with this name; throws dps::Error naming the missing camera and the ones present.
  const RigCamera& Camera(const std::string& name) const;
  // True when a camera of this name exists.
  bool Has(const std::string& name) const;
};

// Checks that R is a rotation: |R^T R - I| <= tolerance (max abs entry) and det(R) > 0.
// Returns an empty string when it is, else a description of the violation.
std::string RotationProblem(const Eigen::Matrix3d& R, double tolerance = 1e-6);

// Rotation about an axis by an angle (radians), right-handed.
Eigen::Matrix3d AxisAngle(const Eigen::Vector3d& axis, double angle_rad);

// Angle of the rotation A^T B in degrees: the angular distance between two rotations
// (DESIGN.md §5, calibration score).
double RotationAngleDeg(const Eigen::Matrix3d& A, const Eigen::Matrix3d& B);

}  // namespace dps
