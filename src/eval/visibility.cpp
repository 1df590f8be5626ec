#include "dps/eval/visibility.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "dps/camera/box.h"
#include "dps/camera/valid_mask.h"
#include "dps/util/error.h"
#include "dps/util/math.h"

namespace dps {
namespace {

// An oriented box standing on the road: centre, unit axes (width, down, length) and half sizes.
struct Box {
  Eigen::Vector3d centre;
  Eigen::Matrix3d axes;  // columns: across, Y (down), along the length
  Eigen::Vector3d half;

  Eigen::Vector3d Local(const Eigen::Vector3d& p) const { return axes.transpose() * (p - centre); }
  bool Contains(const Eigen::Vector3d& p) const {
    const Eigen::Vector3d q = Local(p);
    return (q.array().abs() <= half.array()).all();
  }
  // True when the open segment a -> b (its ends excluded by a small margin) passes through the box.
  bool Blocks(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const {
    const Eigen::Vector3d p = Local(a);
    return RayMeetsBox(p, Local(b) - p, -half, half, 1e-6, 1.0 - 1e-6);
  }
};

Box ObjectBox(const TruthRow& o) {
  const double h = o.heading_deg * kPi / 180.0;
  Box b;
  b.centre = Eigen::Vector3d(o.x_m, -o.height_m / 2, o.z_m);
  b.axes.col(0) = Eigen::Vector3d(std::cos(h), 0, -std::sin(h));
  b.axes.col(1) = Eigen::Vector3d(0, 1, 0);
  b.axes.col(2) = Eigen::Vector3d(std::sin(h), 0, std::cos(h));
  b.half = Eigen::Vector3d(o.width_m / 2, o.height_m / 2, o.length_m / 2);
  return b;
}

Box OwnCarBox(const Vehicle& v, double height_m) {
  Box b;
  b.centre = Eigen::Vector3d(0, -height_m / 2, 0);
  b.axes = Eigen::Matrix3d::Identity();
  b.half = Eigen::Vector3d(v.width_m / 2, height_m / 2, v.length_m / 2);
  return b;
}

}  // namespace

void VisibilityOptions::Check() const {
  const OptionCheck Require("visibility");
  Require(min_seen_fraction > 0 && min_seen_fraction <= 1, "min_seen_fraction", min_seen_fraction, "0 < f <= 1");
  Require(samples_per_edge >= 1 && samples_per_edge <= 1000, "samples_per_edge", samples_per_edge, "1 <= n <= 1000");
  Require(own_car_height_m >= 0 && own_car_height_m <= 10, "own_car_height_m", own_car_height_m, "0 <= h <= 10 m");
}

Visibility::Visibility(const Rig& rig, const VisibilityOptions& options) : rig_(rig), options_(options) {
  options_.Check();
  const Box own = OwnCarBox(rig_.vehicle, options_.own_car_height_m);
  for (const RigCamera& c : rig_.cameras) {
    valid_.push_back(CameraValidMask(c));
    inside_own_car_.push_back(own.Contains(c.vehicle_from_camera.t));
  }
}

double Visibility::SeenFraction(const TruthRow& object, const std::vector<const TruthRow*>& scene,
                                size_t camera) const {
  const RigCamera& cam = rig_.cameras.at(camera);
  const Eigen::Vector3d& eye = cam.vehicle_from_camera.t;
  const Pose camera_from_vehicle = cam.vehicle_from_camera.Inverse();
  const cv::Mat& valid = valid_[camera];
  std::vector<Box> occluders;
  if (!inside_own_car_[camera] && options_.own_car_height_m > 0) {
    occluders.push_back(OwnCarBox(rig_.vehicle, options_.own_car_height_m));
  }
  for (const TruthRow* other : scene) {
    if (other->id == object.id) continue;
    const Box b = ObjectBox(*other);
    if (!b.Contains(eye)) occluders.push_back(b);
  }
  const Box box = ObjectBox(object);
  const int n = options_.samples_per_edge;
  double seen = 0.0, total = 0.0;
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const double cell = (2 * box.half[u] / n) * (2 * box.half[v] / n);
    for (const double sign : {-1.0, 1.0}) {
      const Eigen::Vector3d normal = sign * box.axes.col(axis);
      for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
          total += cell;
          Eigen::Vector3d local;
          local[axis] = sign * box.half[axis];
          local[u] = box.half[u] * ((2.0 * i + 1) / n - 1);
          local[v] = box.half[v] * ((2.0 * j + 1) / n - 1);
          const Eigen::Vector3d p = box.centre + box.axes * local;
          if ((eye - p).dot(normal) <= 0) continue;  // the face turns away: the box hides it
          Eigen::Vector2d px;
          if (!cam.model.Project(camera_from_vehicle.Apply(p), &px) || !cam.model.InImage(px)) continue;
          const int col = std::clamp(static_cast<int>(std::lround(px.x())), 0, valid.cols - 1);
          const int row = std::clamp(static_cast<int>(std::lround(px.y())), 0, valid.rows - 1);
          if (!valid.at<unsigned char>(row, col)) continue;
          if (std::any_of(occluders.begin(), occluders.end(), [&](const Box& b) { return b.Blocks(eye, p); })) continue;
          seen += cell;
        }
      }
    }
  }
  return total > 0 ? seen / total : 0.0;
}

bool Visibility::Sees(const TruthRow& object, const std::vector<const TruthRow*>& scene) const {
  for (size_t c = 0; c < rig_.cameras.size(); ++c) {
    if (SeenFraction(object, scene, c) >= options_.min_seen_fraction) return true;
  }
  return false;
}

}  // namespace dps
