#include "dps/camera/ego_motion.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "dps/util/error.h"

namespace dps {

Pose PlanarPose::ToPose3() const {
  // Rotation about the vehicle's Y axis (down) that turns +Z towards +X by heading.
  const double c = std::cos(heading_rad), s = std::sin(heading_rad);
  Pose p;
  p.R << c, 0, s, 0, 1, 0, -s, 0, c;
  p.t = Eigen::Vector3d(x_m, 0.0, z_m);
  return p;
}

MotionProfile::MotionProfile(std::vector<MotionSample> samples) : samples_(std::move(samples)) {
  if (samples_.empty()) throw std::invalid_argument("motion profile: no samples");
  for (size_t i = 0; i < samples_.size(); ++i) {
    const MotionSample& s = samples_[i];
    if (!std::isfinite(s.t_s) || !std::isfinite(s.speed_mps) || !std::isfinite(s.yaw_rate_radps)) {
      throw std::invalid_argument(Str("motion profile: sample ", i, " is not finite"));
    }
    if (i > 0 && s.t_s < samples_[i - 1].t_s) {
      throw std::invalid_argument(Str("motion profile: sample ", i, " at t = ", s.t_s,
                                      " s comes before the previous one at ",
                                      samples_[i - 1].t_s, " s"));
    }
  }
}

MotionSample MotionProfile::At(double t) const {
  if (!std::isfinite(t)) throw std::invalid_argument(Str("motion profile: time ", t, " is not finite"));
  if (t <= samples_.front().t_s) return {t, samples_.front().speed_mps, samples_.front().yaw_rate_radps};
  if (t >= samples_.back().t_s) return {t, samples_.back().speed_mps, samples_.back().yaw_rate_radps};
  const auto it = std::upper_bound(samples_.begin(), samples_.end(), t,
                                   [](double v, const MotionSample& s) { return v < s.t_s; });
  const MotionSample& b = *it;
  const MotionSample& a = *(it - 1);
  const double w = b.t_s > a.t_s ? (t - a.t_s) / (b.t_s - a.t_s) : 1.0;
  return {t, a.speed_mps + w * (b.speed_mps - a.speed_mps),
          a.yaw_rate_radps + w * (b.yaw_rate_radps - a.yaw_rate_radps)};
}

PlanarPose MotionProfile::Integrate(const PlanarPose& start, double t0, double t1,
                                    double step_s) const {
  PlanarPose p = start;
  if (t1 == t0) return p;
  const int steps = std::max(1, static_cast<int>(std::ceil(std::abs(t1 - t0) / step_s)));
  const double dt = (t1 - t0) / steps;
  for (int i = 0; i < steps; ++i) {
    const MotionSample m = At(t0 + (i + 0.5) * dt);
    // Midpoint rule on the heading; the chord of an arc of constant curvature over the step.
    const double dh = -m.yaw_rate_radps * dt;
    const double h_mid = p.heading_rad + 0.5 * dh;
    const double chord = std::abs(dh) > 1e-12 ? m.speed_mps * dt * std::sin(0.5 * dh) / (0.5 * dh)
                                              : m.speed_mps * dt;
    p.x_m += chord * std::sin(h_mid);
    p.z_m += chord * std::cos(h_mid);
    p.heading_rad += dh;
  }
  return p;
}

Eigen::Matrix2d BodyToWorldRotation(const PlanarPose& pose) {
  const double c = std::cos(pose.heading_rad), s = std::sin(pose.heading_rad);
  Eigen::Matrix2d R;
  R << c, s, -s, c;
  return R;
}

Eigen::Vector2d BodyToWorld(const PlanarPose& pose, const Eigen::Vector2d& b) {
  return Eigen::Vector2d(pose.x_m, pose.z_m) + BodyToWorldRotation(pose) * b;
}

PlanarPose Compose(const PlanarPose& a, const PlanarPose& b) {
  const Eigen::Vector2d p = BodyToWorld(a, {b.x_m, b.z_m});
  return {p.x(), p.y(), a.heading_rad + b.heading_rad};
}

Eigen::Vector2d WorldToBody(const PlanarPose& pose, const Eigen::Vector2d& w) {
  return WorldToBodyDirection(pose, w - Eigen::Vector2d(pose.x_m, pose.z_m));
}

Eigen::Vector2d WorldToBodyDirection(const PlanarPose& pose, const Eigen::Vector2d& d) {
  // Inverse of the rotation that takes body (0, 1) to world (sin h, cos h).
  const double c = std::cos(pose.heading_rad), s = std::sin(pose.heading_rad);
  return Eigen::Vector2d(c * d.x() - s * d.y(), s * d.x() + c * d.y());
}

}  // namespace dps
