#include "dps/synth/randomize.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

#include "dps/util/error.h"
#include "dps/util/math.h"
#include "util/yaml_fields.h"

namespace dps {
namespace {

// splitmix64: the same numbers on every platform (std's distributions are not).
class Draws {
 public:
  Draws(std::uint64_t seed, RandomizedScene* out) : state_(seed), out_(out) {}
  std::uint64_t Next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  // Uniform in [lo, hi), recorded under `name` (empty: not recorded).
  double Uniform(double lo, double hi, const std::string& name = "") {
    const double v = lo + (hi - lo) * static_cast<double>(Next() >> 11) * 0x1.0p-53;
    if (!name.empty()) out_->draws.emplace_back(name, v);
    return v;
  }
  int Index(int n) { return static_cast<int>(Next() % static_cast<std::uint64_t>(n)); }
  void Record(const std::string& name, double value) { out_->draws.emplace_back(name, value); }
  bool Chance(double p) { return Uniform(0.0, 1.0) < p; }
  // A rotation by an angle uniform in [0, max_rad] about a uniformly drawn axis.
  Eigen::Matrix3d Rotation(double max_rad, const std::string& name) {
    const double z = Uniform(-1.0, 1.0), phi = Uniform(0.0, 2 * kPi);
    const double r = std::sqrt(std::max(0.0, 1 - z * z));
    const double angle = Uniform(0.0, max_rad);
    out_->draws.emplace_back(name, angle * kDegPerRad);
    return AxisAngle(Eigen::Vector3d(r * std::cos(phi), r * std::sin(phi), z), angle);
  }

 private:
  std::uint64_t state_;
  RandomizedScene* out_;
};

const char* const kFamilies[] = {"hyperbolic", "unified", "fisheye_down", "fisheye_side"};

// Radius on the normalised image plane of a ray at angle theta from a mirror's axis.
double MirrorRadius(double a, double b, double theta) { return std::sin(theta) / (a * std::cos(theta) + b); }

double FisheyeRadius(const std::array<double, 4>& k, double theta) {
  const double t2 = theta * theta;
  return theta * (1 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))));
}

// One camera's intrinsics for the family, with the field's end and image circle drawn.
CameraModel DrawModel(const std::string& family, int w, int h, const RandomizeOptions& o, const std::string& name,
                      Draws* d) {
  const double scale = w / 640.0;
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  K(0, 2) = (w - 1) / 2.0 + d->Uniform(-1, 1, name + ".cx_offset_px") * o.principal_offset_max_px * scale;
  K(1, 2) = (h - 1) / 2.0 + d->Uniform(-1, 1, name + ".cy_offset_px") * o.principal_offset_max_px * scale;
  const double aspect = 1.0 + d->Uniform(-o.aspect_max_deviation, o.aspect_max_deviation, name + ".aspect");
  if (family == "fisheye_side") {
    // A lens of 190-200 degrees whose image circle may be cut by the image's top and bottom.
    const std::array<double, 4> k{d->Uniform(-0.02, 0.02, name + ".k1"), d->Uniform(-0.002, 0.002, name + ".k2"), 0, 0};
    const double half_fov = d->Uniform(95.0, 100.0, name + ".half_fov_deg") * kRadPerDeg;
    const double rim = d->Uniform(0.95, 1.25, name + ".circle_fraction") * h / 2.0;
    K(0, 0) = rim / FisheyeRadius(k, half_fov);
    K(1, 1) = K(0, 0) * aspect;
    return CameraModel::Fisheye(w, h, K, k, rim);
  }
  // Axis down: the field ends field_edge degrees above the horizon, at the image circle.
  const double edge = d->Uniform(o.field_edge_min_deg, o.field_edge_max_deg, name + ".field_edge_deg") * kRadPerDeg;
  const double theta = kPi / 2 + edge;
  const double rim = d->Uniform(0.88, 0.98, name + ".circle_fraction") * std::min(w, h) / 2.0;
  if (family == "fisheye_down") {
    const std::array<double, 4> k{d->Uniform(-0.02, 0.02, name + ".k1"), d->Uniform(-0.002, 0.002, name + ".k2"), 0, 0};
    K(0, 0) = rim / FisheyeRadius(k, theta);
    K(1, 1) = K(0, 0) * aspect;
    return CameraModel::Fisheye(w, h, K, k, rim);
  }
  // Mirrors: xi = b / a from 0.75 (the field reaches at least 48 degrees above the horizon) to 0.97.
  const double xi = d->Uniform(0.75, 0.97, name + ".xi");
  const double a = family == "unified" ? 1.0 : d->Uniform(1.0, 1.3, name + ".a");
  K(0, 0) = rim / MirrorRadius(a, xi * a, theta);
  K(1, 1) = K(0, 0) * aspect;
  if (family == "unified") return CameraModel::Unified(w, h, K, xi, rim);
  return CameraModel::Hyperbolic(w, h, K, a, xi * a, rim);
}

// The nominal orientation: axis down (omni, fisheye_down) or looking out sideways and tilted down.
Eigen::Matrix3d NominalRotation(const std::string& family, bool left, double tilt_rad) {
  Eigen::Matrix3d R;
  if (family != "fisheye_side") {
    R.col(0) = Eigen::Vector3d(1, 0, 0);
    R.col(1) = Eigen::Vector3d(0, 0, -1);
    R.col(2) = Eigen::Vector3d(0, 1, 0);
    return R;
  }
  const double s = std::sin(tilt_rad), c = std::cos(tilt_rad);
  // Columns: image x, image y (down), optical axis, in the vehicle frame (Y down, Z forward).
  if (left) {
    R.col(0) = Eigen::Vector3d(0, 0, 1);
    R.col(1) = Eigen::Vector3d(s, c, 0);
    R.col(2) = Eigen::Vector3d(-c, s, 0);
  } else {
    R.col(0) = Eigen::Vector3d(0, 0, -1);
    R.col(1) = Eigen::Vector3d(-s, c, 0);
    R.col(2) = Eigen::Vector3d(c, s, 0);
  }
  return R;
}

void DrawRig(const RandomizeOptions& o, RandomizedScene* r, Draws* d) {
  Rig& rig = r->scene.rig;
  rig.vehicle.length_m = d->Uniform(4.2, 5.2, "vehicle.length_m");
  rig.vehicle.width_m = d->Uniform(1.7, 2.0, "vehicle.width_m");
  for (RigCamera& c : rig.cameras) {
    const bool left = c.name == "left";
    const std::string name = c.name;
    c.model = DrawModel(r->camera_family, c.model.width(), c.model.height(), o, name, d);
    const double tilt =
        d->Uniform(o.side_fisheye_tilt_min_deg, o.side_fisheye_tilt_max_deg,
                   r->camera_family == "fisheye_side" ? name + ".tilt_deg" : "") * kRadPerDeg;
    c.vehicle_from_camera.R =
        d->Rotation(o.mount_rotation_max_deg * kRadPerDeg, name + ".mount_rotation_deg") * NominalRotation(r->camera_family, left, tilt);
    const double out = rig.vehicle.width_m / 2 + d->Uniform(0.05, 0.25, name + ".outside_m");
    c.vehicle_from_camera.t = Eigen::Vector3d(left ? -out : out, -d->Uniform(o.height_min_m, o.height_max_m, name + ".height_m"),
                                              d->Uniform(0.5, 1.3, name + ".forward_m"));
  }
  r->processing_rig = rig;
  for (RigCamera& c : r->processing_rig.cameras) {
    c.vehicle_from_camera.R =
        d->Rotation(o.calibration_error_max_deg * kRadPerDeg, c.name + ".calibration_error_deg") * c.vehicle_from_camera.R;
  }
}

void DrawAppearance(const RandomizeOptions& o, RandomizedScene* r, Draws* d) {
  RenderOptions& render = r->scene.render;
  render.noise_sigma = d->Uniform(1.0, 4.0, "render.noise_sigma");
  render.blur_sigma_px = d->Chance(0.5) ? d->Uniform(0.3, 0.9, "render.blur_sigma_px") : 0.0;
  render.sky_brightness = d->Uniform(0.8, 1.15, "render.sky_brightness");
  render.ground_brightness = d->Uniform(0.7, 1.3, "render.ground_brightness");
  render.ground_contrast = d->Uniform(0.5, 1.5, "render.ground_contrast");
  render.texture_scale = d->Uniform(0.6, 1.6, "render.texture_scale");
  render.exposure = d->Uniform(0.8, 1.2, "render.exposure");
  render.vignetting = d->Uniform(0.0, 0.4, "render.vignetting");
  render.own_body_height_m = d->Uniform(0.6, 1.0, "render.own_body_height_m");
  render.own_cabin_height_m = d->Uniform(1.35, 1.7, "render.own_cabin_height_m");
  render.own_car_brightness = d->Uniform(0.5, 4.0, "render.own_car_brightness");
  render.shadows = d->Chance(0.7);
  d->Record("render.shadows", render.shadows);
  render.marking_wear = d->Uniform(0.0, 0.5, "render.marking_wear");
  render.clouds = d->Chance(0.5) ? d->Uniform(0.2, 0.8, "render.clouds") : 0.0;
  render.sun_glare = d->Chance(0.3) ? d->Uniform(0.2, 0.8, "render.sun_glare") : 0.0;
  render.verge_m = d->Chance(0.5) ? d->Uniform(0.3, 2.0, "render.verge_m") : 0.0;
  r->scene.seed = d->Next() % 1000000;
  r->video = d->Chance(o.video_fraction);
  r->video_codec = r->video ? (d->Chance(0.5) ? "H264" : "MJPG") : "";
}

// A car of the story may be another road vehicle: a van, a bus (rendered as a box body) or a
// motorbike, with that class's size (before the size draw).
void DrawVehicleClass(const std::string& name, SceneObject* obj, Draws* d) {
  const double u = d->Uniform(0.0, 1.0);
  struct Class {
    const char* render_kind;
    double upto, length, width, height;
  };
  static const Class classes[] = {{"car", 0.55, 4.5, 1.8, 1.5},
                                  {"car", 0.75, 5.2, 2.0, 2.2},
                                  {"truck", 0.85, 12.0, 2.5, 3.2},
                                  {"motorbike", 1.0, 2.1, 0.8, 1.4}};
  int k = 0;
  while (u >= classes[k].upto && k < 3) ++k;
  d->Record(name + ".class", k);  // 0 car, 1 van, 2 bus, 3 motorbike
  if (k == 0) return;
  obj->kind = classes[k].render_kind;
  obj->length_m = classes[k].length;
  obj->width_m = classes[k].width;
  obj->height_m = classes[k].height;
}

// Speeds (and yaw rates when mirrored) of a motion profile.
MotionProfile Scaled(const MotionProfile& m, double speed_factor, bool mirror) {
  std::vector<MotionSample> samples = m.samples();
  for (MotionSample& s : samples) {
    s.speed_mps *= speed_factor;
    if (mirror) s.yaw_rate_radps = -s.yaw_rate_radps;
  }
  return MotionProfile(samples);
}

void DrawObjects(const RandomizeOptions& o, RandomizedScene* r, Draws* d) {
  Scene& s = r->scene;
  r->mirrored = d->Chance(0.5);
  const bool m = r->mirrored;
  s.ego = Scaled(s.ego, d->Uniform(0.85, 1.15, "ego.speed_factor"), m);
  if (m) {
    std::swap(s.road.lanes_left, s.road.lanes_right);
    s.road.ego_lane_center_x_m = -s.road.ego_lane_center_x_m;
  }
  for (SceneObject& obj : s.objects) {
    const std::string name = "object" + std::to_string(obj.id);
    const double size = o.object_size_fraction;
    if (obj.kind == "car") DrawVehicleClass(name, &obj, d);
    if (obj.kind != "pole") {
      obj.length_m *= 1 + d->Uniform(-size, size, name + ".length_factor");
      obj.width_m *= 1 + d->Uniform(-size, size, name + ".width_factor");
    }
    obj.height_m *= 1 + d->Uniform(-size, size, name + ".height_factor");
    obj.brightness = d->Uniform(0.2, 1.0, name + ".brightness");
    obj.colour = d->Index(8);
    obj.start.x_m += d->Uniform(-o.object_shift_m, o.object_shift_m, name + ".shift_x_m");
    obj.start.z_m += d->Uniform(-o.object_shift_m, o.object_shift_m, name + ".shift_z_m");
    if (m) {
      obj.start.x_m = -obj.start.x_m;
      obj.start.heading_rad = -obj.start.heading_rad;
    }
    obj.motion = Scaled(obj.motion, 1 + d->Uniform(-o.object_speed_fraction, o.object_speed_fraction, name + ".speed_factor"), m);
  }
}

// The footprint of a box of length x width at a pose on the ground (x across, z along), as OpenCV's
// rotated rectangle.
cv::RotatedRect Footprint(const PlanarPose& p, double length_m, double width_m) {
  return cv::RotatedRect(cv::Point2f(static_cast<float>(p.x_m), static_cast<float>(p.z_m)),
                         cv::Size2f(static_cast<float>(width_m), static_cast<float>(length_m)),
                         static_cast<float>(-p.heading_rad / kRadPerDeg));
}

// The first frame time at which an object of the story comes within clearance_m of the own car (its
// footprint grown by that much on every side), or a negative time when it never does.
double MeetsOwnCar(const Scene& s, const SceneObject& obj, double clearance_m) {
  for (int f = 0; f < s.FrameCount(); ++f) {
    const double t = s.FrameTime(f);
    std::vector<cv::Point2f> overlap;
    const cv::RotatedRect own =
        Footprint(s.EgoPoseAt(t), s.rig.vehicle.length_m + 2 * clearance_m, s.rig.vehicle.width_m + 2 * clearance_m);
    if (cv::rotatedRectangleIntersection(own, Footprint(obj.PoseAt(t), obj.length_m, obj.width_m), overlap) !=
        cv::INTERSECT_NONE) {
      return t;
    }
  }
  return -1.0;
}

// Randomised speeds and shifts, and a car drawn as a longer vehicle, can close a story's gap to the
// own car (a car following 6 m behind at a fifth more speed, a bus in the place of the car we queue
// behind). Such an object is moved away from the own car along its heading, a quarter metre at a
// time, until it keeps half a metre clear of it in every frame: every drive stays one a car could
// have recorded. The distance moved is recorded (objectN.moved_m).
void KeepClearOfOwnCar(RandomizedScene* r, Draws* d) {
  constexpr double kClearance = 0.5, kStep = 0.25;
  constexpr int kMaxSteps = 160;  // 40 m
  for (SceneObject& obj : r->scene.objects) {
    int steps = 0;
    double t = MeetsOwnCar(r->scene, obj, kClearance);
    while (t >= 0 && steps < kMaxSteps) {
      const PlanarPose at = obj.PoseAt(t), own = r->scene.EgoPoseAt(t);
      const Eigen::Vector2d axis(std::sin(obj.start.heading_rad), std::cos(obj.start.heading_rad));
      const double away = axis.dot(Eigen::Vector2d(at.x_m - own.x_m, at.z_m - own.z_m)) >= 0 ? 1.0 : -1.0;
      obj.start.x_m += away * kStep * axis.x();
      obj.start.z_m += away * kStep * axis.y();
      ++steps;
      t = MeetsOwnCar(r->scene, obj, kClearance);
    }
    if (steps > 0) d->Record("object" + std::to_string(obj.id) + ".moved_m", steps * kStep);
  }
}

// The road's outer edges (world x of the outer markings' centres); +-5 m without markings.
std::pair<double, double> RoadEdges(const RoadMarkings& r) {
  if (!r.enabled) return {-5.0, 5.0};
  return {r.ego_lane_center_x_m - (r.lanes_left + 0.5) * r.lane_width_m,
          r.ego_lane_center_x_m + (r.lanes_right + 0.5) * r.lane_width_m};
}

// Road detail and the own car's shape: repair patches, cracks, a gravel verge, kerbs (beyond every
// object that starts beside the road, so that parked cars stay on the road's level), the sills and
// the mirror housings. Drawn after everything else so that the earlier draws stay as they were.
void DrawDetail(RandomizedScene* r, Draws* d) {
  RenderOptions& render = r->scene.render;
  render.own_sill_height_m = std::min(render.own_body_height_m, d->Uniform(0.2, 0.4, "render.own_sill_height_m"));
  render.own_sill_inset_m = d->Uniform(0.03, 0.12, "render.own_sill_inset_m");
  render.mirror_housing_m = d->Uniform(0.1, 0.25, "render.mirror_housing_m");
  render.mirror_housing_drop_m = d->Uniform(0.0, 0.06, "render.mirror_housing_drop_m");
  render.ground_patches = d->Chance(0.5) ? d->Uniform(0.1, 0.4, "render.ground_patches") : 0.0;
  render.cracks = d->Chance(0.5) ? d->Uniform(0.1, 0.5, "render.cracks") : 0.0;
  render.gravel_verge = d->Chance(0.5);
  d->Record("render.gravel_verge", render.gravel_verge);
  if (!d->Chance(0.5) || !r->scene.road.enabled) return;
  render.kerb_height_m = d->Uniform(0.08, 0.18, "render.kerb_height_m");
  double& on_left = render.kerb_offset_left_m;
  double& on_right = render.kerb_offset_right_m;
  on_left = d->Uniform(0.2, 1.0);
  on_right = d->Uniform(0.2, 1.0);
  const auto [left, right] = RoadEdges(r->scene.road);
  for (const SceneObject& obj : r->scene.objects) {
    const double reach = std::hypot(obj.length_m, obj.width_m) / 2 + 0.3;
    if (obj.start.x_m < left) on_left = std::max(on_left, left - obj.start.x_m + reach);
    if (obj.start.x_m > right) on_right = std::max(on_right, obj.start.x_m - right + reach);
  }
  d->Record("render.kerb_offset_left_m", on_left);
  d->Record("render.kerb_offset_right_m", on_right);
}

// Roadside clutter beside a story with objects: up to three poles, walls or pedestrians beyond the
// road's edges (and its kerbs), along the stretch the ego drives; pedestrians walk along the road.
void DrawClutter(RandomizedScene* r, Draws* d) {
  Scene& s = r->scene;
  const int count = d->Index(4);
  d->Record("clutter.count", count);
  if (s.objects.empty()) return;  // the empty roads stay empty
  int next_id = 1;
  for (const SceneObject& obj : s.objects) next_id = std::max(next_id, obj.id + 1);
  const auto [left, right] = RoadEdges(s.road);
  const double travelled = s.EgoPoseAt(s.duration_s).z_m;
  for (int k = 0; k < count; ++k) {
    SceneObject obj;
    obj.id = next_id++;
    const std::string name = "clutter" + std::to_string(obj.id);
    const int kind = d->Index(3);
    d->Record(name + ".kind", kind);  // 0 pole, 1 wall, 2 pedestrian
    obj.kind = kind == 0 ? "pole" : kind == 1 ? "wall" : "pedestrian";
    obj.length_m = kind == 0 ? 0.2 : kind == 1 ? d->Uniform(3.0, 12.0, name + ".length_m") : 0.5;
    obj.width_m = kind == 0 ? 0.2 : kind == 1 ? 0.3 : 0.6;
    obj.height_m = kind == 0 ? d->Uniform(2.5, 4.0, name + ".height_m")
                             : kind == 1 ? d->Uniform(1.0, 2.5, name + ".height_m") : d->Uniform(1.5, 1.9, name + ".height_m");
    const bool on_left = d->Chance(0.5);
    const double kerb =
        s.render.kerb_height_m > 0.0 ? (on_left ? s.render.kerb_offset_left_m : s.render.kerb_offset_right_m) : 0.0;
    const double out = kerb + obj.width_m / 2 +
                       d->Uniform(0.3, 2.5, name + ".beyond_edge_m");
    obj.start.x_m = on_left ? left - out : right + out;
    obj.start.z_m = d->Uniform(-15.0, std::max(0.0, travelled) + 30.0, name + ".z_m");
    obj.brightness = d->Uniform(0.2, 1.0, name + ".brightness");
    obj.colour = d->Index(8);
    if (kind == 2) {
      obj.start.heading_rad = d->Chance(0.5) ? 0.0 : kPi;
      obj.motion = MotionProfile({MotionSample{0.0, d->Uniform(0.0, 1.5, name + ".speed_mps"), 0.0}});
    }
    s.objects.push_back(obj);
  }
}

}  // namespace

void RandomizeOptions::Check() const {
  const OptionCheck Require("randomize");
  Require(field_edge_min_deg >= 0 && field_edge_min_deg <= field_edge_max_deg, "field_edge_min_deg",
          field_edge_min_deg, "0 <= min <= field_edge_max_deg");
  Require(field_edge_max_deg <= 45, "field_edge_max_deg", field_edge_max_deg, "<= 45 (mirrors with xi >= 0.75)");
  Require(side_fisheye_tilt_min_deg >= 0 && side_fisheye_tilt_min_deg <= side_fisheye_tilt_max_deg,
          "side_fisheye_tilt_min_deg", side_fisheye_tilt_min_deg, "0 <= min <= side_fisheye_tilt_max_deg");
  Require(side_fisheye_tilt_max_deg <= 80, "side_fisheye_tilt_max_deg", side_fisheye_tilt_max_deg, "<= 80");
  Require(mount_rotation_max_deg >= 0, "mount_rotation_max_deg", mount_rotation_max_deg, ">= 0");
  Require(calibration_error_max_deg >= 0, "calibration_error_max_deg", calibration_error_max_deg, ">= 0");
  Require(height_min_m > 0 && height_min_m <= height_max_m, "height_min_m", height_min_m, "0 < min <= height_max_m");
  Require(principal_offset_max_px >= 0, "principal_offset_max_px", principal_offset_max_px, ">= 0");
  Require(aspect_max_deviation >= 0 && aspect_max_deviation <= 0.2, "aspect_max_deviation", aspect_max_deviation,
          "0..0.2");
  Require(object_size_fraction >= 0 && object_size_fraction <= 0.5, "object_size_fraction", object_size_fraction,
          "0..0.5");
  Require(object_speed_fraction >= 0 && object_speed_fraction <= 0.5, "object_speed_fraction",
          object_speed_fraction, "0..0.5");
  Require(object_shift_m >= 0, "object_shift_m", object_shift_m, ">= 0");
  Require(video_fraction >= 0 && video_fraction <= 1, "video_fraction", video_fraction, "0..1");
}

RandomizeOptions ReadRandomizeOptions(const std::string& scene_path) {
  cv::FileStorage fs = internal::OpenForReading(scene_path);
  const internal::FieldReader f(fs.root(), scene_path);
  RandomizeOptions o;
  if (!f.Has("randomize")) return o;
  const internal::FieldReader r = f.Child(f.Required("randomize"), "randomize");
  const std::pair<const char*, double*> fields[] = {
      {"field_edge_min_deg", &o.field_edge_min_deg},
      {"field_edge_max_deg", &o.field_edge_max_deg},
      {"side_fisheye_tilt_min_deg", &o.side_fisheye_tilt_min_deg},
      {"side_fisheye_tilt_max_deg", &o.side_fisheye_tilt_max_deg},
      {"mount_rotation_max_deg", &o.mount_rotation_max_deg},
      {"calibration_error_max_deg", &o.calibration_error_max_deg},
      {"height_min_m", &o.height_min_m},
      {"height_max_m", &o.height_max_m},
      {"principal_offset_max_px", &o.principal_offset_max_px},
      {"aspect_max_deviation", &o.aspect_max_deviation},
      {"object_size_fraction", &o.object_size_fraction},
      {"object_speed_fraction", &o.object_speed_fraction},
      {"object_shift_m", &o.object_shift_m},
      {"video_fraction", &o.video_fraction}};
  for (const auto& [key, value] : fields) *value = r.NumberOr(key, *value);
  try {
    o.Check();
  } catch (const Error& e) {
    throw Error(Str(scene_path, ": randomize: ", e.what()));
  }
  return o;
}

std::string RandomizedScene::ToJson(std::uint64_t seed) const {
  std::ostringstream o;
  o.precision(10);
  o << "{\n  \"scene\": \"" << scene.name << "\",\n  \"seed\": " << seed << ",\n  \"camera_family\": \""
    << camera_family << "\",\n  \"mirrored\": " << (mirrored ? "true" : "false")
    << ",\n  \"video\": " << (video ? "true" : "false") << ",\n  \"video_codec\": \"" << video_codec
    << "\",\n  \"draws\": {";
  for (size_t i = 0; i < draws.size(); ++i) {
    o << (i ? ",\n" : "\n") << "    \"" << draws[i].first << "\": " << draws[i].second;
  }
  o << "\n  }\n}\n";
  return o.str();
}

RandomizedScene Randomize(const Scene& scene, std::uint64_t seed, const RandomizeOptions& options) {
  options.Check();
  if (scene.kind != SceneKind::kDrive) throw Error(Str(scene.name, ": only drive scenes can be randomised"));
  if (!scene.rig.Has("left") || !scene.rig.Has("right")) {
    throw Error(Str(scene.name, ": randomising needs a rig with cameras 'left' and 'right'"));
  }
  RandomizedScene r;
  r.scene = scene;
  // One stream per seed, the scene's name mixed in so that families differ at the same seed.
  std::uint64_t mix = seed * 0x9E3779B97F4A7C15ull;
  for (const char ch : scene.name) mix = (mix ^ static_cast<unsigned char>(ch)) * 0x100000001B3ull;
  Draws d(mix, &r);
  r.camera_family = kFamilies[d.Index(4)];
  DrawRig(options, &r, &d);
  DrawAppearance(options, &r, &d);
  DrawObjects(options, &r, &d);
  KeepClearOfOwnCar(&r, &d);
  DrawDetail(&r, &d);
  DrawClutter(&r, &d);
  return r;
}

}  // namespace dps
