// dps — planar motion on the ground: speed / yaw-rate profiles and their integration into poses.
//
// Conventions (DESIGN.md §1)
// - The ground plane is spanned by the vehicle frame's X (right) and Z (forward); a planar pose is
//   (x_m, z_m, heading_rad) in a fixed world frame, which for a drive is the vehicle frame at t = 0.
// - heading_rad: angle from the world's +Z axis to the body's forward axis, positive towards +X
//   (as truth.csv's heading_deg). Forward direction = (sin h, cos h) in (x, z).
// - yaw_rate_radps: positive when turning left (counter-clockwise seen from above), so
//   d heading / dt = -yaw_rate.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "dps/camera/rig.h"

namespace dps {

// A pose on the ground plane.
struct PlanarPose {
  double x_m = 0.0;
  double z_m = 0.0;
  double heading_rad = 0.0;

  // The 3-D transform world_from_body: a rotation about Y by heading and a shift on the ground.
  Pose ToPose3() const;
};

// One sample of a speed / yaw-rate profile.
struct MotionSample {
  double t_s = 0.0;              // time, seconds
  double speed_mps = 0.0;        // forward speed, m/s (negative = reversing)
  double yaw_rate_radps = 0.0;   // rad/s, positive = turning left
};

// A speed / yaw-rate profile: samples sorted by time, linearly interpolated between them and held
// constant before the first and after the last.
class MotionProfile {
 public:
  MotionProfile() = default;
  // Throws std::invalid_argument when the samples are empty, unsorted or not finite.
  explicit MotionProfile(std::vector<MotionSample> samples);

  // Speed and yaw rate at t_s, linear between samples, held beyond them; throws
  // std::invalid_argument for a time that is not finite.
  MotionSample At(double t_s) const;
  const std::vector<MotionSample>& samples() const { return samples_; }

  // The pose at time t_s of a body that is at `start` at time t0_s and follows this profile
  // (integrated with the midpoint rule in steps of at most step_s; exact for constant speed and
  // yaw rate up to rounding, second order otherwise).
  PlanarPose Integrate(const PlanarPose& start, double t0_s, double t_s,
                       double step_s = 1e-3) const;

 private:
  std::vector<MotionSample> samples_{MotionSample{}};
};

// The pose `b`, given in the body frame of `a`, in the frame `a` is given in: a * b.
PlanarPose Compose(const PlanarPose& a, const PlanarPose& b);

// The rotation taking body (x, z) directions into the world: BodyToWorld without the shift.
Eigen::Matrix2d BodyToWorldRotation(const PlanarPose& pose);
// Expresses a point of the body frame of `pose` in the world (the inverse of WorldToBody).
Eigen::Vector2d BodyToWorld(const PlanarPose& pose, const Eigen::Vector2d& body_xz);
// Expresses a world point in the body frame of `pose` (ground plane, x right, z forward).
Eigen::Vector2d WorldToBody(const PlanarPose& pose, const Eigen::Vector2d& world_xz);
// Expresses a world direction (e.g. a velocity) in the body frame of `pose`.
Eigen::Vector2d WorldToBodyDirection(const PlanarPose& pose, const Eigen::Vector2d& world_xz);

}  // namespace dps
