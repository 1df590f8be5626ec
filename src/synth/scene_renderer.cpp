#include "dps/synth/scene_renderer.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

namespace dps {
namespace {

// The own car: a lower body (bonnet / boot height, RenderOptions) over the full length and width,
// and a cabin, so that cameras at the side mirrors see forward over the bonnet, as on a real car.
constexpr double kOwnCabinRearFraction = -0.40;  // cabin from -0.40 L to +0.12 L along Z
constexpr double kOwnCabinFrontFraction = 0.12;
constexpr double kOwnCabinInsetM = 0.1;          // narrower than the body on each side
// A mirror housing: behind its camera by this gap, this high above it, and this far beyond it
// outwards.
constexpr double kHousingGapM = 0.04;
constexpr double kHousingHeightM = 0.15;
constexpr double kHousingMarginM = 0.03;
constexpr double kTwoPi = 6.28318530717958647692;

// Integer hash (lowbias32 by C. Wellons) of up to three integers and a seed.
inline std::uint32_t Hash(std::uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352dU;
  x ^= x >> 15;
  x *= 0x846ca68bU;
  x ^= x >> 16;
  return x;
}
inline std::uint32_t Hash(std::int64_t a, std::int64_t b, std::uint32_t seed) {
  return Hash(static_cast<std::uint32_t>(a) ^ Hash(static_cast<std::uint32_t>(b) ^ Hash(seed)));
}
inline double Unit(std::uint32_t h) { return (h >> 8) * (1.0 / 16777216.0); }  // [0, 1)

// Smooth value noise in [0, 1] on a unit lattice.
double ValueNoise(double x, double y, std::uint32_t seed) {
  const double fx = std::floor(x), fy = std::floor(y);
  const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy);
  double tx = x - fx, ty = y - fy;
  tx = tx * tx * (3 - 2 * tx);
  ty = ty * ty * (3 - 2 * ty);
  const double a = Unit(Hash(ix, iy, seed)), b = Unit(Hash(ix + 1, iy, seed));
  const double c = Unit(Hash(ix, iy + 1, seed)), d = Unit(Hash(ix + 1, iy + 1, seed));
  return (a + (b - a) * tx) + ((c + (d - c) * tx) - (a + (b - a) * tx)) * ty;
}

// Fractal noise in about [0, 1]: octaves of value noise from `scale_m` down by halves.
double Fbm(double x, double y, double scale_m, int octaves, std::uint32_t seed) {
  double sum = 0.0, amp = 0.5, norm = 0.0, f = 1.0 / scale_m;
  for (int i = 0; i < octaves; ++i) {
    sum += amp * ValueNoise(x * f, y * f, seed + 977u * i);
    norm += amp;
    amp *= 0.55;
    f *= 2.0;
  }
  return sum / norm;
}

// Body colours (BGR, 0..1) of the palette.
const cv::Vec3f kPalette[] = {{0.20f, 0.22f, 0.80f}, {0.75f, 0.45f, 0.20f}, {0.72f, 0.72f, 0.70f},
                              {0.92f, 0.92f, 0.90f}, {0.25f, 0.45f, 0.20f}, {0.15f, 0.75f, 0.85f},
                              {0.45f, 0.30f, 0.55f}, {0.35f, 0.35f, 0.38f}};

// Slab test of a ray against an axis-aligned box [lo, hi] in box coordinates; returns the entry
// distance (or +inf) and the axis of the entry face.
double SlabEntry(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& lo,
                 const Eigen::Vector3d& hi, int* axis) {
  double t_near = -std::numeric_limits<double>::infinity();
  double t_far = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    if (std::abs(d[k]) < 1e-12) {
      if (o[k] < lo[k] || o[k] > hi[k]) return std::numeric_limits<double>::infinity();
      continue;
    }
    double t0 = (lo[k] - o[k]) / d[k], t1 = (hi[k] - o[k]) / d[k];
    if (t0 > t1) std::swap(t0, t1);
    if (t0 > t_near) {
      t_near = t0;
      *axis = k;
    }
    t_far = std::min(t_far, t1);
    // The interval only shrinks: once empty or behind the origin, it stays so.
    if (t_near > t_far || t_far <= 1e-9) return std::numeric_limits<double>::infinity();
  }
  if (t_near > t_far || t_far <= 1e-9 || t_near <= 1e-9) return std::numeric_limits<double>::infinity();
  return t_near;
}

}  // namespace

SceneRenderer::SceneRenderer(const Scene& scene) : scene_(scene) {
  // The own car: the body (narrower below the sill when one is drawn), the cabin, and a mirror
  // housing behind each camera reaching from the body's side to just outside the camera.
  const RenderOptions& render = scene.render;
  const Vehicle& car = scene.rig.vehicle;
  const double hw = car.width_m / 2, hl = car.length_m / 2;
  const double sill = std::clamp(render.own_sill_height_m, 0.0, render.own_body_height_m);
  own_boxes_.push_back({{-hw, -render.own_body_height_m, -hl}, {hw, -sill, hl}});
  own_boxes_.push_back({{-hw + kOwnCabinInsetM, -render.own_cabin_height_m, kOwnCabinRearFraction * car.length_m},
                        {hw - kOwnCabinInsetM, 0.0, kOwnCabinFrontFraction * car.length_m}});
  if (sill > 0.0) {
    const double inset = std::min(render.own_sill_inset_m, hw / 2);
    own_boxes_.push_back({{-hw + inset, -sill, -hl}, {hw - inset, 0.0, hl}});
  }
  if (render.mirror_housing_m > 0.0) {
    for (const RigCamera& cam : scene.rig.cameras) {
      const Eigen::Vector3d& c = cam.vehicle_from_camera.t;
      const double side = c.x() < 0 ? -1.0 : 1.0;
      const double inner = side * std::min(hw, std::abs(c.x()) - 0.05), outer = c.x() + side * kHousingMarginM;
      own_boxes_.push_back({{std::min(inner, outer), c.y() - kHousingHeightM, c.z() - kHousingGapM - render.mirror_housing_m},
                            {std::max(inner, outer), c.y() + render.mirror_housing_drop_m, c.z() - kHousingGapM}});
    }
  }
  const int ss = scene.render.supersample;
  samples_ = ss * ss;
  for (const RigCamera& cam : scene.rig.cameras) {
    CameraRays r;
    r.width = cam.model.width();
    r.height = cam.model.height();
    r.dirs.resize(static_cast<size_t>(r.width) * r.height * (samples_ + 1));
    r.own_car_t.resize(r.dirs.size());
    const Eigen::Matrix3d R = cam.vehicle_from_camera.R;
    cv::parallel_for_(cv::Range(0, r.height), [&](const cv::Range& rows) {
      for (int v = rows.start; v < rows.end; ++v) {
        for (int u = 0; u < r.width; ++u) {
          Eigen::Vector3f* out = &r.dirs[(static_cast<size_t>(v) * r.width + u) * (samples_ + 1)];
          for (int s = 0; s <= samples_; ++s) {
            // Sample 0 is the pixel centre; the others a regular ss x ss grid inside the pixel.
            const double du = s == 0 ? 0.0 : ((s - 1) % ss + 0.5) / ss - 0.5;
            const double dv = s == 0 ? 0.0 : ((s - 1) / ss + 0.5) / ss - 0.5;
            Eigen::Vector3d ray;
            if (cam.model.Unproject({u + du, v + dv}, &ray)) {
              out[s] = (R * ray).cast<float>();
            } else {
              out[s].setConstant(std::numeric_limits<float>::quiet_NaN());
            }
          }
        }
      }
    });
    const Eigen::Vector3d origin = cam.vehicle_from_camera.t;
    cv::parallel_for_(cv::Range(0, r.height), [&](const cv::Range& rows) {
      const size_t per_row = static_cast<size_t>(r.width) * (samples_ + 1);
      for (size_t i = rows.start * per_row; i < rows.end * per_row; ++i) {
        const Eigen::Vector3d d = r.dirs[i].cast<double>();
        r.own_car_t[i] = std::isnan(d.x()) ? std::numeric_limits<double>::infinity() : OwnCarEntry(origin, d);
      }
    });
    rays_.push_back(std::move(r));
  }
}

cv::Mat SceneRenderer::WorldMask(size_t camera_index) const {
  const CameraRays& r = rays_.at(camera_index);
  cv::Mat mask(r.height, r.width, CV_8U);
  for (int v = 0; v < r.height; ++v) {
    for (int u = 0; u < r.width; ++u) {
      const size_t first = (static_cast<size_t>(v) * r.width + u) * (samples_ + 1);
      const bool sees = !std::isnan(r.dirs[first].x()) && std::isinf(r.own_car_t[first]);
      mask.at<std::uint8_t>(v, u) = sees ? 255 : 0;
    }
  }
  return mask;
}

FrameState SceneRenderer::StateAt(double t_s) const {
  FrameState st;
  st.t_s = t_s;
  st.ego = scene_.EgoPoseAt(t_s);
  st.world_from_vehicle = st.ego.ToPose3();
  for (const SceneObject& o : scene_.objects) {
    BoxInstance b;
    b.id = o.id;
    b.object = &o;
    b.world = o.PoseAt(t_s);
    b.centre_xz = WorldToBody(st.ego, {b.world.x_m, b.world.z_m});
    b.heading_rad = b.world.heading_rad - st.ego.heading_rad;
    b.bound_radius_m = 0.5 * std::sqrt(o.width_m * o.width_m + o.height_m * o.height_m + o.length_m * o.length_m) *
                       (1.0 + 1e-9) + 1e-9;
    st.boxes.push_back(b);
  }
  return st;
}

RayHit SceneRenderer::Cast(const FrameState& st, const Eigen::Vector3d& o,
                           const Eigen::Vector3d& d) const {
  return CastWithOwnCar(st, o, d, OwnCarEntry(o, d));
}

RayHit SceneRenderer::CastWithOwnCar(const FrameState& st, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                                     double t_car) const {
  RayHit best;
  double best_t = std::numeric_limits<double>::infinity();
  if (d.y() > 1e-12 && o.y() < 0.0) {  // the ground plane Y = 0 (Y points down)
    best_t = -o.y() / d.y();
    best.id = kIdGround;
  }
  int axis = 0;
  if (scene_.render.kerb_height_m > 0.0 && scene_.road.enabled) {
    const double t_kerb = KerbEntry(st, o, d, &axis);
    if (t_kerb < best_t) {
      best_t = t_kerb;
      best.id = kIdKerb;
      best.face = axis == 1 ? 2 : 0;
    }
  }
  // The own car, fixed in the vehicle frame.
  if (t_car < best_t) {
    best_t = t_car;
    best.id = kIdOwnCar;
  }
  const double dd = d.squaredNorm();
  for (size_t i = 0; i < st.boxes.size(); ++i) {
    const BoxInstance& b = st.boxes[i];
    const SceneObject& obj = *b.object;
    // The box lies in its bounding sphere: a ray that meets the sphere nowhere ahead of the origin,
    // or only beyond the nearest hit so far, cannot hit the box first.
    {
      const Eigen::Vector3d oc(b.centre_xz.x() - o.x(), -obj.height_m / 2 - o.y(), b.centre_xz.y() - o.z());
      const double r = b.bound_radius_m;
      const double along = oc.dot(d), outside = oc.squaredNorm() - r * r;
      if (outside > 0.0) {  // the origin outside the sphere
        const double disc = along * along - dd * outside;
        if (along <= 0.0 || disc < 0.0) continue;                   // behind the origin, or missed
        if ((along - std::sqrt(disc)) / dd > best_t) continue;      // entered beyond the nearest hit
      }
    }
    // Box coordinates: x across (right), y down, z along the heading; origin at the footprint
    // centre on the ground.
    const double c = std::cos(b.heading_rad), s = std::sin(b.heading_rad);
    const Eigen::Vector3d rel(o.x() - b.centre_xz.x(), o.y(), o.z() - b.centre_xz.y());
    const Eigen::Vector3d ol(c * rel.x() - s * rel.z(), rel.y(), s * rel.x() + c * rel.z());
    const Eigen::Vector3d dl(c * d.x() - s * d.z(), d.y(), s * d.x() + c * d.z());
    const double t = SlabEntry(ol, dl, {-obj.width_m / 2, -obj.height_m, -obj.length_m / 2},
                               {obj.width_m / 2, 0.0, obj.length_m / 2}, &axis);
    if (t < best_t) {
      best_t = t;
      best.id = static_cast<std::uint16_t>(kIdObjectBase + b.id);
      best.box = static_cast<int>(i);
      const Eigen::Vector3d p = ol + t * dl;
      best.face = axis == 0 ? 0 : axis == 2 ? 1 : 2;
      best.face_a_m = axis == 0 ? p.z() : p.x();
      best.face_h_m = -p.y();
    }
  }
  if (!std::isfinite(best_t)) {
    best.id = kIdSky;
    return best;
  }
  best.distance_m = best_t;
  best.point_vehicle = o + best_t * d;
  if (best.id == kIdKerb) best.point_world = st.world_from_vehicle.Apply(best.point_vehicle);
  if (best.id == kIdGround) {
    // Paint or asphalt: decided in world coordinates.
    best.point_world = st.world_from_vehicle.Apply(best.point_vehicle);
    const double x = best.point_world.x(), z = best.point_world.z();
    bool paint = false;
    if (scene_.road.enabled) {
      const RoadMarkings& r = scene_.road;
      const double half = r.marking_width_m / 2;
      for (int k = -r.lanes_left; k <= r.lanes_right + 1 && !paint; ++k) {
        const double line_x = r.ego_lane_center_x_m + (k - 0.5) * r.lane_width_m;
        if (std::abs(x - line_x) > half) continue;
        const bool edge = k == -r.lanes_left || k == r.lanes_right + 1;
        const double period = r.dash_length_m + r.dash_gap_m;
        paint = edge || std::fmod(std::fmod(z, period) + period, period) < r.dash_length_m;
      }
    }
    for (const PaintedLine& l : scene_.lines) {
      if (paint) break;
      const Eigen::Vector2d a = l.from_xz, ab = l.to_xz - l.from_xz;
      const double u = std::clamp((Eigen::Vector2d(x, z) - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
      paint = (Eigen::Vector2d(x, z) - (a + u * ab)).norm() <= l.width_m / 2;
    }
    if (paint && scene_.render.marking_wear > 0.0) {
      const auto wear_seed = static_cast<std::uint32_t>(scene_.seed * 2654435761u) + 53u;
      paint = Fbm(x, z, 0.3, 2, wear_seed) >= scene_.render.marking_wear;
    }
    if (paint) best.id = kIdPaint;
  }
  return best;
}

namespace {

// Exposure gain and vignetting (1 - v r^4 with r the distance from the centre over the half
// diagonal) on a rendered CV_32FC3 image; nothing at the defaults.
void ApplyExposure(const RenderOptions& render, cv::Mat* image) {
  if (render.exposure != 1.0) *image *= render.exposure;
  if (render.vignetting <= 0.0) return;
  const double cx = (image->cols - 1) / 2.0, cy = (image->rows - 1) / 2.0;
  const double r2_max = cx * cx + cy * cy;
  for (int v = 0; v < image->rows; ++v) {
    cv::Vec3f* row = image->ptr<cv::Vec3f>(v);
    for (int u = 0; u < image->cols; ++u) {
      const double r2 = ((u - cx) * (u - cx) + (v - cy) * (v - cy)) / r2_max;
      row[u] *= static_cast<float>(1.0 - render.vignetting * r2 * r2);
    }
  }
}

}  // namespace

bool SceneRenderer::InShadow(const FrameState& st, const Eigen::Vector3d& p, const Eigen::Vector3d& light) const {
  // A box shades the ground at most its height x (horizontal / vertical of the light) beyond its
  // footprint: boxes farther away are skipped without a ray test.
  const double reach = std::hypot(light.x(), light.z()) / std::max(1e-3, -light.y());
  const Eigen::Vector3d o = p + 1e-4 * light;
  int axis = 0;
  const Vehicle& car = scene_.rig.vehicle;
  const double hw = car.width_m / 2, hl = car.length_m / 2;
  if (std::hypot(p.x(), p.z()) <= std::hypot(hw, hl) + reach * scene_.render.own_cabin_height_m &&
      std::isfinite(OwnCarEntry(o, light))) {
    return true;
  }
  for (const BoxInstance& b : st.boxes) {
    const SceneObject& obj = *b.object;
    const Eigen::Vector2d rel2(p.x() - b.centre_xz.x(), p.z() - b.centre_xz.y());
    if (rel2.norm() > std::hypot(obj.length_m, obj.width_m) / 2 + reach * obj.height_m) continue;
    const double c = std::cos(b.heading_rad), s = std::sin(b.heading_rad);
    const Eigen::Vector3d rel(rel2.x(), o.y(), rel2.y());
    const Eigen::Vector3d ol(c * rel.x() - s * rel.z(), rel.y(), s * rel.x() + c * rel.z());
    const Eigen::Vector3d dl(c * light.x() - s * light.z(), light.y(), s * light.x() + c * light.z());
    if (std::isfinite(SlabEntry(ol, dl, {-obj.width_m / 2, -obj.height_m, -obj.length_m / 2},
                                {obj.width_m / 2, 0.0, obj.length_m / 2}, &axis))) {
      return true;
    }
  }
  return false;
}

double SceneRenderer::OwnCarEntry(const Eigen::Vector3d& o, const Eigen::Vector3d& d) const {
  int axis = 0;
  double t = std::numeric_limits<double>::infinity();
  for (const auto& [lo, hi] : own_boxes_) t = std::min(t, SlabEntry(o, d, lo, hi, &axis));
  return t;
}

double SceneRenderer::KerbEntry(const FrameState& st, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                                int* face) const {
  // The pavement beyond each outer edge is a slab kerb_height_m high, unbounded along the road.
  const RoadMarkings& r = scene_.road;
  const Eigen::Vector3d ow = st.world_from_vehicle.Apply(o), dw = st.world_from_vehicle.R * d;
  const double h = scene_.render.kerb_height_m, far = 1e7;
  const double left = r.ego_lane_center_x_m - (r.lanes_left + 0.5) * r.lane_width_m - scene_.render.kerb_offset_left_m;
  const double right = r.ego_lane_center_x_m + (r.lanes_right + 0.5) * r.lane_width_m + scene_.render.kerb_offset_right_m;
  int axis_left = 0, axis_right = 0;
  const double t_left = SlabEntry(ow, dw, {-far, -h, -far}, {left, 0.0, far}, &axis_left);
  const double t_right = SlabEntry(ow, dw, {right, -h, -far}, {far, 0.0, far}, &axis_right);
  *face = t_left <= t_right ? axis_left : axis_right;
  return std::min(t_left, t_right);
}

cv::Vec3f SceneRenderer::GroundColour(const Eigen::Vector3d& w, bool pavement, std::uint32_t seed) const {
  const RenderOptions& render = scene_.render;
  const double k = render.texture_scale, c = render.ground_contrast;
  const double n = Fbm(w.x(), w.z(), 0.8 * k, 4, seed + 11);
  // Asphalt: patches at 0.8 m, and aggregate at 0.25 m and 0.06 m that correlation stereo can
  // lock on to (real asphalt is textured down to the pixel).
  const double mid = Fbm(w.x(), w.z(), 0.25 * k, 2, seed + 23);
  const double grain = Fbm(w.x(), w.z(), 0.06 * k, 2, seed + 37);
  if (render.verge_m > 0.0 && scene_.road.enabled && OnVerge(w.x())) {
    if (!render.gravel_verge) {
      return cv::Vec3f(0.16f, 0.34f, 0.26f) * static_cast<float>(0.7 + 0.6 * mid + 0.3 * (grain - 0.5));
    }
    const double stones = Fbm(w.x(), w.z(), 0.03, 2, seed + 41);
    return cv::Vec3f(0.40f, 0.43f, 0.46f) * static_cast<float>(0.75 + 0.3 * (mid - 0.5) + 0.8 * (stones - 0.5));
  }
  if (pavement) {
    // Paving slabs of 0.6 m with darker joints.
    const double jx = std::fmod(std::abs(w.x()), 0.6), jz = std::fmod(std::abs(w.z()), 0.6);
    const bool joint = jx < 0.02 || jz < 0.02;
    const float g = static_cast<float>((joint ? 0.28 : 0.48) + c * 0.10 * (mid - 0.5) + c * 0.08 * (grain - 0.5));
    return cv::Vec3f(g, g * 1.02f, g * 1.04f);
  }
  double tone = 0.30 * render.ground_brightness + c * 0.14 * (n - 0.5) + c * 0.16 * (mid - 0.5) + c * 0.14 * (grain - 0.5);
  if (render.ground_patches > 0.0) {
    // Repair patches: a rectangle inside some cells of a 3 m x 5 m grid, their own shade, smoother.
    const double cx = std::floor(w.x() / 3.0), cz = std::floor(w.z() / 5.0);
    const std::uint32_t cell = Hash(static_cast<std::int64_t>(cx), static_cast<std::int64_t>(cz), seed + 59);
    if (Unit(cell) < render.ground_patches) {
      const double inset_x = 0.2 + 0.6 * Unit(Hash(cell + 1)), inset_z = 0.3 + 1.2 * Unit(Hash(cell + 2));
      const double u = w.x() - cx * 3.0, v = w.z() - cz * 5.0;
      if (u > inset_x && u < 3.0 - inset_x && v > inset_z && v < 5.0 - inset_z) {
        tone = 0.30 * render.ground_brightness * (0.7 + 0.6 * Unit(Hash(cell + 3))) + c * 0.10 * (grain - 0.5);
      }
    }
  }
  if (render.cracks > 0.0 && Fbm(w.x(), w.z(), 4.0, 1, seed + 97) < render.cracks &&
      std::abs(Fbm(w.x(), w.z(), 1.2, 3, seed + 91) - 0.5) < 0.006) {
    tone *= 0.5;  // a crack about 1.5 cm wide along a line of the noise
  }
  const float g = static_cast<float>(tone);
  return cv::Vec3f(g, g * 1.01f, g * 1.03f);
}

bool SceneRenderer::OnVerge(double world_x) const {
  const RoadMarkings& r = scene_.road;
  const double left = r.ego_lane_center_x_m - (r.lanes_left + 0.5) * r.lane_width_m;
  const double right = r.ego_lane_center_x_m + (r.lanes_right + 0.5) * r.lane_width_m;
  return world_x < left - scene_.render.verge_m || world_x > right + scene_.render.verge_m;
}

cv::Vec3f SceneRenderer::SkyDetail(const RenderOptions& render, const Eigen::Vector3d& d, const Eigen::Vector3d& light,
                                   float elevation, std::uint32_t seed, cv::Vec3f sky) const {
  if (render.clouds > 0.0) {
    // Clouds on a plane above: coordinates of the ray's crossing, noise thresholded by the cover.
    const double up = std::max(0.05, -d.y());
    const double cloud = Fbm(d.x() / up * 40.0, d.z() / up * 40.0, 60.0, 3, seed + 61);
    const float c = static_cast<float>(std::clamp((cloud - (1.0 - render.clouds)) * 3.0, 0.0, 1.0)) *
                    std::min(1.0f, 4.0f * elevation + 0.2f);
    sky = sky * (1 - c) + cv::Vec3f(0.92f, 0.92f, 0.93f) * c;
  }
  if (render.sun_glare > 0.0) {
    const double off = 1.0 - std::clamp(d.dot(light), -1.0, 1.0);  // 0 towards the sun
    sky += cv::Vec3f::all(static_cast<float>(render.sun_glare * std::exp(-off / 0.01)));
  }
  return sky;
}

cv::Vec3f SceneRenderer::Shade(const FrameState& st, const Eigen::Vector3d& d, const RayHit& hit,
                               const Eigen::Vector3d& light) const {
  const auto seed = static_cast<std::uint32_t>(scene_.seed * 2654435761u);
  const RenderOptions& render = scene_.render;
  switch (hit.id) {
    case kIdSky: {
      const float e = static_cast<float>(std::clamp(-d.y(), 0.0, 1.0));
      cv::Vec3f sky = cv::Vec3f(0.86f, 0.82f, 0.76f) * (1 - e) + cv::Vec3f(0.80f, 0.58f, 0.35f) * e;
      if (render.clouds > 0.0 || render.sun_glare > 0.0) sky = SkyDetail(render, d, light, e, seed, sky);
      return render.sky_brightness == 1.0 ? sky : sky * static_cast<float>(render.sky_brightness);
    }
    case kIdOwnCar: {
      const double n = Fbm(hit.point_vehicle.x() + hit.point_vehicle.y(), hit.point_vehicle.z(), 0.3, 2, seed + 5);
      const cv::Vec3f paint = cv::Vec3f::all(static_cast<float>(0.12 + 0.08 * n));
      return render.own_car_brightness == 1.0 ? paint : paint * static_cast<float>(render.own_car_brightness);
    }
    case kIdGround:
    case kIdPaint: {
      const Eigen::Vector3d& w = hit.point_world;
      if (hit.id == kIdPaint) {
        const double n = Fbm(w.x(), w.z(), 0.8 * render.texture_scale, 4, seed + 11);
        const cv::Vec3f paint = cv::Vec3f::all(static_cast<float>(0.78 + 0.12 * n));
        return render.shadows && InShadow(st, hit.point_vehicle, light) ? paint * 0.5f : paint;
      }
      cv::Vec3f ground = GroundColour(w, false, seed);
      if (render.shadows && InShadow(st, hit.point_vehicle, light)) ground *= 0.5f;
      return ground;
    }
    case kIdKerb: {
      if (hit.face == 2) {
        cv::Vec3f top = GroundColour(hit.point_world, true, seed);
        return render.shadows && InShadow(st, hit.point_vehicle, light) ? top * 0.5f : top;
      }
      // The kerb's face: light concrete, lit from above at a slant.
      const Eigen::Vector3d& w = hit.point_world;
      const double n = Fbm(w.z(), w.y(), 0.05, 2, seed + 43);
      return cv::Vec3f::all(static_cast<float>(0.55 + 0.2 * (n - 0.5)));
    }
    default: break;
  }
  const BoxInstance& b = st.boxes[hit.box];
  const SceneObject& obj = *b.object;
  const std::uint32_t oseed = seed + 7919u * static_cast<std::uint32_t>(obj.id) + 131u * hit.face;
  const double a = hit.face_a_m, h = hit.face_h_m;
  cv::Vec3f base = kPalette[static_cast<size_t>(obj.colour) % (sizeof(kPalette) / sizeof(kPalette[0]))];
  base *= static_cast<float>(obj.brightness / 0.6);
  // Surface detail for correlation stereo: noise at 0.25 m and at 0.07 m (dirt, reflections).
  const double detail = Fbm(a, h, 0.25, 3, oseed);
  const double fine = Fbm(a, h, 0.07, 2, oseed + 71);
  double tone = 0.75 + 0.6 * (detail - 0.5) + 0.35 * (fine - 0.5);
  // A motorbike and its rider are one box drawn like a small car (tyres, a band of glass).
  const bool car = obj.kind == "car" || obj.kind == "motorbike";
  if (car || obj.kind == "truck") {
    const double frac = h / obj.height_m;
    if (hit.face != 2 && h < 0.35) {
      // Tyres and sills: darker than the body but with structure (tread, rims, dirt), as real
      // wheels have; a featureless band would hide where the vehicle meets the road.
      const double tread = Fbm(a, h, 0.05, 2, oseed + 313);
      tone = 0.10 + 0.30 * detail + 0.35 * (tread - 0.5) * 2.0 * 0.5;
      base = cv::Vec3f::all(0.5f);
    } else if (hit.face != 2 && car && frac > 0.6 && frac < 0.92) {
      tone = 0.35 + 0.4 * detail;  // windows
      base = cv::Vec3f(0.45f, 0.42f, 0.40f);
    } else if (obj.kind == "truck" && std::fmod(std::abs(a) + 10.0, 0.6) < 0.08) {
      tone *= 0.6;  // ribs of the box body
    } else if (car && std::fmod(std::abs(a) + 10.0, 1.3) < 0.05) {
      tone *= 0.65;  // panel gaps
    }
  } else if (obj.kind == "pole") {
    tone = std::fmod(h, 0.5) < 0.25 ? 0.35 + 0.3 * detail : 0.9 + 0.1 * detail;
  } else if (obj.kind == "wall") {
    const double row = std::floor(h / 0.25);
    const double col = (a + (static_cast<int>(row) % 2) * 0.3) / 0.6;
    const bool mortar = h - row * 0.25 < 0.03 || col - std::floor(col) < 0.05;
    tone = mortar ? 0.9 : 0.55 + 0.5 * Unit(Hash(static_cast<std::int64_t>(std::floor(col)),
                                                 static_cast<std::int64_t>(row), oseed));
  }
  // Lambertian shading by the face normal (vehicle frame) against a light from above.
  Eigen::Vector3d n(0, -1, 0);
  if (hit.face != 2) {
    const double c = std::cos(b.heading_rad), s = std::sin(b.heading_rad);
    const Eigen::Vector3d along(s, 0, c), across(c, 0, -s);
    n = hit.face == 0 ? across : along;
    if (n.dot(d) > 0) n = -n;
  }
  const double shade = 0.55 + 0.45 * std::max(0.0, n.dot(light));
  return base * static_cast<float>(tone * shade);
}

RenderedView SceneRenderer::Render(const FrameState& st, size_t camera_index,
                                   int frame_index) const {
  const CameraRays& r = rays_.at(camera_index);
  const RigCamera& cam = scene_.rig.cameras[camera_index];
  const Eigen::Vector3d origin = cam.vehicle_from_camera.t;
  // A fixed sun in the world, expressed in the vehicle frame of this instant.
  const Eigen::Vector3d light =
      st.world_from_vehicle.R.transpose() * Eigen::Vector3d(-0.35, -1.0, 0.45).normalized();
  RenderedView out;
  out.image.create(r.height, r.width, CV_32FC3);
  out.ids.create(r.height, r.width, CV_16U);
  out.range_m.create(r.height, r.width, CV_32F);
  cv::parallel_for_(cv::Range(0, r.height), [&](const cv::Range& rows) {
    for (int v = rows.start; v < rows.end; ++v) {
      for (int u = 0; u < r.width; ++u) {
        const size_t first = (static_cast<size_t>(v) * r.width + u) * (samples_ + 1);
        const Eigen::Vector3f* dirs = &r.dirs[first];
        const double* own_car_t = &r.own_car_t[first];
        cv::Vec3f colour(0, 0, 0);
        for (int s = 1; s <= samples_; ++s) {
          if (std::isnan(dirs[s].x())) continue;
          const Eigen::Vector3d d = dirs[s].cast<double>();
          colour += Shade(st, d, CastWithOwnCar(st, origin, d, own_car_t[s]), light);
        }
        // Sub-samples outside the rim count as black: the rim is anti-aliased too.
        out.image.at<cv::Vec3f>(v, u) = colour * (1.0f / samples_);
        if (std::isnan(dirs[0].x())) {
          out.ids.at<std::uint16_t>(v, u) = kIdNoRay;
          out.range_m.at<float>(v, u) = 0.0f;
        } else {
          const RayHit hit = CastWithOwnCar(st, origin, dirs[0].cast<double>(), own_car_t[0]);
          out.ids.at<std::uint16_t>(v, u) = hit.id;
          out.range_m.at<float>(v, u) = static_cast<float>(hit.distance_m);
        }
      }
    }
  });
  ApplyExposure(scene_.render, &out.image);
  if (scene_.render.blur_sigma_px > 0.0) {
    cv::GaussianBlur(out.image, out.image, cv::Size(), scene_.render.blur_sigma_px);
  }
  // Image noise: a Gaussian per pixel and channel from a hash of (seed, frame, camera, pixel), so
  // that the result does not depend on how rows are split between threads.
  const double sigma = scene_.render.noise_sigma / 255.0;
  const std::uint32_t nseed = Hash(static_cast<std::uint32_t>(scene_.seed) ^
                                   Hash(static_cast<std::uint32_t>(frame_index) * 2u + camera_index));
  cv::Mat image8(r.height, r.width, CV_8UC3);
  cv::parallel_for_(cv::Range(0, r.height), [&](const cv::Range& rows) {
    for (int v = rows.start; v < rows.end; ++v) {
      for (int u = 0; u < r.width; ++u) {
        const cv::Vec3f c = out.image.at<cv::Vec3f>(v, u);
        cv::Vec3b& o = image8.at<cv::Vec3b>(v, u);
        const bool dark = out.ids.at<std::uint16_t>(v, u) == kIdNoRay && c[0] + c[1] + c[2] == 0;
        for (int k = 0; k < 3; ++k) {
          double n = 0.0;
          if (sigma > 0.0 && !dark) {
            const std::uint32_t h1 = Hash(v * 8192 + u, k, nseed);
            const double u1 = (Unit(h1) + 1e-9), u2 = Unit(Hash(h1));
            n = sigma * std::sqrt(-2.0 * std::log(u1)) * std::cos(kTwoPi * u2);
          }
          o[k] = cv::saturate_cast<std::uint8_t>(std::lround(255.0 * (c[k] + n)));
        }
      }
    }
  });
  out.image = image8;
  return out;
}

}  // namespace dps
