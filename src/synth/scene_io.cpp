#include "dps/synth/scene_io.h"

#include <cmath>
#include <filesystem>
#include <set>

#include "dps/camera/rig_io.h"
#include "dps/util/math.h"
#include "util/yaml_fields.h"

namespace dps {
namespace {

using internal::FieldReader;

double Positive(const FieldReader& f, const std::string& key, double fallback) {
  const double v = f.NumberOr(key, fallback);
  if (!(v > 0.0)) f.Fail(key, Str("= ", v, ": violated constraint > 0"));
  return v;
}

double NonNegative(const FieldReader& f, const std::string& key, double fallback) {
  const double v = f.NumberOr(key, fallback);
  if (!(v >= 0.0)) f.Fail(key, Str("= ", v, ": violated constraint >= 0"));
  return v;
}

// A motion given as `speed` / `yaw_rate_deg` numbers, or as a list of keyframes under `key`.
MotionProfile ReadMotion(const FieldReader& f, const std::string& key) {
  std::vector<MotionSample> samples;
  if (f.Has(key)) {
    const cv::FileNode list = f.Required(key);
    if (!list.isSeq() || list.size() == 0) f.Fail(key, "expected a non-empty list of {t, speed, yaw_rate_deg}");
    int i = 0;
    for (const cv::FileNode& item : list) {
      const FieldReader k = f.Child(item, Str(key, "[", i++, "]"));
      samples.push_back({k.Number("t"), k.Number("speed"), k.NumberOr("yaw_rate_deg", 0.0) * kRadPerDeg});
    }
  } else {
    samples.push_back({0.0, f.NumberOr("speed", 0.0), f.NumberOr("yaw_rate_deg", 0.0) * kRadPerDeg});
  }
  try {
    return MotionProfile(samples);
  } catch (const std::invalid_argument& e) {
    f.Fail(key, e.what());
  }
}

struct KindDefaults {
  const char* kind;
  double length, width, height, brightness;
};
constexpr KindDefaults kKinds[] = {
    {"car", 4.5, 1.8, 1.5, 0.6},  {"truck", 10.0, 2.5, 3.5, 0.7}, {"pole", 0.2, 0.2, 3.0, 0.5},
    {"wall", 10.0, 0.3, 2.0, 0.55}, {"pedestrian", 0.5, 0.6, 1.8, 0.45}, {"motorbike", 2.1, 0.8, 1.4, 0.6}};

SceneObject ReadObject(const FieldReader& f) {
  SceneObject o;
  o.kind = f.TextOr("kind", "car");
  const KindDefaults* d = nullptr;
  for (const KindDefaults& k : kKinds) {
    if (o.kind == k.kind) d = &k;
  }
  if (!d) f.Fail("kind", "unknown kind '" + o.kind + "' (expected car, truck, motorbike, pole, wall or pedestrian)");
  o.id = f.Integer("id");
  if (o.id < 1) f.Fail("id", Str("= ", o.id, ": violated constraint >= 1"));
  o.length_m = Positive(f, "length", d->length);
  o.width_m = Positive(f, "width", d->width);
  o.height_m = Positive(f, "height", d->height);
  o.start.x_m = f.Number("x");
  o.start.z_m = f.Number("z");
  o.start.heading_rad = f.NumberOr("heading_deg", 0.0) * kRadPerDeg;
  o.motion = ReadMotion(f, "motion");
  o.brightness = f.NumberOr("brightness", d->brightness);
  if (!(o.brightness > 0.0 && o.brightness <= 1.0)) f.Fail("brightness", "expected a value in (0, 1]");
  o.colour = f.IntegerOr("colour", o.id);
  return o;
}

PaintedLine ReadLine(const FieldReader& f) {
  PaintedLine l;
  const std::string axis = f.Text("axis");
  if (axis != "X" && axis != "Z") f.Fail("axis", "expected X or Z (poles give the Y direction)");
  l.axis = axis[0];
  if (l.axis == 'Z') {
    const double x = f.Number("x");
    l.from_xz = {x, f.Number("z_from")};
    l.to_xz = {x, f.Number("z_to")};
  } else {
    const double z = f.Number("z");
    l.from_xz = {f.Number("x_from"), z};
    l.to_xz = {f.Number("x_to"), z};
  }
  if ((l.to_xz - l.from_xz).norm() < 1.0) f.Fail("axis", "line shorter than 1 m");
  l.width_m = Positive(f, "width", l.width_m);
  return l;
}

// The scene's rig: a path to a rig.yaml (relative to the scene file) or the rig's fields inline.
Rig ReadSceneRig(const FieldReader& f, const std::string& path) {
  const cv::FileNode rig = f.Required("rig");
  if (rig.isString()) {
    const std::filesystem::path rel(static_cast<std::string>(rig));
    const std::filesystem::path rig_path =
        rel.is_absolute() ? rel : std::filesystem::path(path).parent_path() / rel;
    try {
      return ReadRig(rig_path.string());
    } catch (const Error& e) {
      f.Fail("rig", e.what());
    }
  } else if (rig.isMap()) {
    return ParseRig(rig, path + ": rig");
  }
  f.Fail("rig", "expected a path to rig.yaml or a map with its fields");
}

// road: a map of lane settings, or 'none'.
void ReadRoad(const FieldReader& f, RoadMarkings* road) {
  const cv::FileNode node = f.Required("road");
  if (node.isString() && static_cast<std::string>(node) == "none") {
    road->enabled = false;
  } else if (node.isMap()) {
    const FieldReader r = f.Child(node, "road");
    road->lane_width_m = Positive(r, "lane_width", road->lane_width_m);
    road->lanes_left = r.IntegerOr("lanes_left", road->lanes_left);
    road->lanes_right = r.IntegerOr("lanes_right", road->lanes_right);
    if (road->lanes_left < 0) r.Fail("lanes_left", "expected >= 0");
    if (road->lanes_right < 0) r.Fail("lanes_right", "expected >= 0");
    road->ego_lane_center_x_m = r.NumberOr("ego_lane_center_x", 0.0);
    road->marking_width_m = Positive(r, "marking_width", road->marking_width_m);
    road->dash_length_m = Positive(r, "dash_length", road->dash_length_m);
    road->dash_gap_m = NonNegative(r, "dash_gap", road->dash_gap_m);
  } else {
    f.Fail("road", "expected a map of lane settings or 'none'");
  }
}

// objects (unique ids), painted lines and the calibration block.
void ReadContents(const FieldReader& f, Scene* s) {
  std::set<int> ids;
  if (f.Has("objects")) {
    const cv::FileNode list = f.Required("objects");
    if (!list.isSeq()) f.Fail("objects", "expected a list");
    int i = 0;
    for (const cv::FileNode& item : list) {
      SceneObject o = ReadObject(f.Child(item, Str("objects[", i++, "]")));
      if (!ids.insert(o.id).second) f.Fail("objects", Str("duplicate id ", o.id));
      s->objects.push_back(std::move(o));
    }
  }
  if (f.Has("lines")) {
    const cv::FileNode list = f.Required("lines");
    if (!list.isSeq()) f.Fail("lines", "expected a list");
    int i = 0;
    for (const cv::FileNode& item : list) s->lines.push_back(ReadLine(f.Child(item, Str("lines[", i++, "]"))));
  }
  if (f.Has("calibration")) {
    const FieldReader c = f.Child(f.Required("calibration"), "calibration");
    CalibrationSettings& cal = s->calibration;
    cal.mark_noise_px = NonNegative(c, "mark_noise_px", cal.mark_noise_px);
    cal.mark_spacing_m = Positive(c, "mark_spacing", cal.mark_spacing_m);
    cal.min_rotation_deg = NonNegative(c, "min_rotation_deg", cal.min_rotation_deg);
    cal.max_rotation_deg = NonNegative(c, "max_rotation_deg", cal.max_rotation_deg);
    if (cal.max_rotation_deg < cal.min_rotation_deg) c.Fail("max_rotation_deg", "expected >= min_rotation_deg");
  }
}

// The scene in an opened file (ReadScene turns OpenCV's assertions into errors naming it).
Scene ParseScene(const cv::FileStorage& fs, const std::string& path) {
  const FieldReader f(fs.root(), path);
  Scene s;
  s.name = f.TextOr("name", std::filesystem::path(path).stem().string());
  const std::string kind = f.TextOr("kind", "drive");
  if (kind == "drive") {
    s.kind = SceneKind::kDrive;
  } else if (kind == "calibration") {
    s.kind = SceneKind::kCalibration;
  } else {
    f.Fail("kind", "expected drive or calibration, got '" + kind + "'");
  }
  s.rig = ReadSceneRig(f, path);
  if (f.Has("size")) {
    const Eigen::MatrixXd size = f.Matrix("size", 2, 1);
    if (size(0) < 16 || size(1) < 16) f.Fail("size", "expected [width, height], each >= 16");
    ResizeScene(&s, static_cast<int>(size(0)), static_cast<int>(size(1)));
  }
  s.fps = Positive(f, "fps", s.fps);
  s.duration_s = Positive(f, "duration_s", s.duration_s);
  const double seed = f.NumberOr("seed", 1.0);
  if (seed < 0 || seed != std::floor(seed)) f.Fail("seed", "expected a non-negative integer");
  s.seed = static_cast<std::uint64_t>(seed);
  if (f.Has("render")) {
    const FieldReader r = f.Child(f.Required("render"), "render");
    s.render.supersample = r.IntegerOr("supersample", s.render.supersample);
    if (s.render.supersample < 1 || s.render.supersample > 8) r.Fail("supersample", "expected 1..8");
    s.render.noise_sigma = NonNegative(r, "noise_sigma", s.render.noise_sigma);
    s.render.blur_sigma_px = NonNegative(r, "blur_sigma_px", s.render.blur_sigma_px);
    s.render.sky_brightness = Positive(r, "sky_brightness", s.render.sky_brightness);
    s.render.ground_brightness = Positive(r, "ground_brightness", s.render.ground_brightness);
    s.render.ground_contrast = NonNegative(r, "ground_contrast", s.render.ground_contrast);
    s.render.texture_scale = Positive(r, "texture_scale", s.render.texture_scale);
    s.render.exposure = Positive(r, "exposure", s.render.exposure);
    s.render.vignetting = NonNegative(r, "vignetting", s.render.vignetting);
    if (s.render.vignetting > 1) r.Fail("vignetting", "expected 0..1");
    s.render.own_body_height_m = Positive(r, "own_body_height", s.render.own_body_height_m);
    s.render.own_cabin_height_m = Positive(r, "own_cabin_height", s.render.own_cabin_height_m);
    if (s.render.own_cabin_height_m < s.render.own_body_height_m) r.Fail("own_cabin_height", "expected >= own_body_height");
    s.render.own_car_brightness = Positive(r, "own_car_brightness", s.render.own_car_brightness);
    s.render.shadows = r.IntegerOr("shadows", s.render.shadows ? 1 : 0) != 0;
    s.render.marking_wear = NonNegative(r, "marking_wear", s.render.marking_wear);
    s.render.clouds = NonNegative(r, "clouds", s.render.clouds);
    s.render.sun_glare = NonNegative(r, "sun_glare", s.render.sun_glare);
    s.render.verge_m = NonNegative(r, "verge", s.render.verge_m);
    s.render.gravel_verge = r.IntegerOr("gravel_verge", s.render.gravel_verge ? 1 : 0) != 0;
    s.render.ground_patches = NonNegative(r, "ground_patches", s.render.ground_patches);
    s.render.cracks = NonNegative(r, "cracks", s.render.cracks);
    s.render.kerb_height_m = NonNegative(r, "kerb_height", s.render.kerb_height_m);
    s.render.kerb_offset_left_m = NonNegative(r, "kerb_offset_left", s.render.kerb_offset_left_m);
    s.render.kerb_offset_right_m = NonNegative(r, "kerb_offset_right", s.render.kerb_offset_right_m);
    s.render.own_sill_height_m = NonNegative(r, "own_sill_height", s.render.own_sill_height_m);
    if (s.render.own_sill_height_m > s.render.own_body_height_m) r.Fail("own_sill_height", "expected <= own_body_height");
    s.render.own_sill_inset_m = NonNegative(r, "own_sill_inset", s.render.own_sill_inset_m);
    s.render.mirror_housing_m = NonNegative(r, "mirror_housing", s.render.mirror_housing_m);
    s.render.mirror_housing_drop_m = NonNegative(r, "mirror_housing_drop", s.render.mirror_housing_drop_m);
    for (const auto& [key, value] : {std::pair{"marking_wear", s.render.marking_wear}, std::pair{"clouds", s.render.clouds},
                                     std::pair{"sun_glare", s.render.sun_glare}, std::pair{"ground_patches", s.render.ground_patches},
                                     std::pair{"cracks", s.render.cracks}}) {
      if (value > 1) r.Fail(key, "expected 0..1");
    }
  }
  s.ego = ReadMotion(f, "ego");
  if (f.Has("road")) {
    ReadRoad(f, &s.road);
  } else if (s.kind == SceneKind::kCalibration) {
    s.road.enabled = false;
  }
  ReadContents(f, &s);
  if (s.kind == SceneKind::kCalibration && s.lines.empty()) {
    f.Fail("lines", "a calibration scene needs painted lines");
  }
  return s;
}

}  // namespace

Scene ReadScene(const std::string& path) {
  cv::FileStorage fs = internal::OpenForReading(path);
  try {
    return ParseScene(fs, path);
  } catch (const cv::Exception& e) {  // an OpenCV assertion on a node of an unexpected shape
    throw Error(Str(path, ": malformed: ", internal::OneLine(e)));
  }
}

}  // namespace dps
