// dps — synthetic scenes: what dps-synth renders (docs/synth.md describes the file format).
//
// A scene is a rig driving over a textured ground plane with lane markings, among box-shaped
// objects (cars, trucks, poles, walls, pedestrians) that move with their own speed / yaw-rate
// profiles. A calibration scene is a parked rig in a parking lot with painted lines along the
// vehicle's Z and X axes and vertical poles. World frame = vehicle frame at t = 0 (see
// ego_motion.h for the planar conventions).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "dps/camera/ego_motion.h"
#include "dps/camera/rig.h"

namespace dps {

// Lane markings on a straight road along the world's Z axis.
struct RoadMarkings {
  bool enabled = true;
  double lane_width_m = 3.5;        // > 0
  int lanes_left = 1;               // lanes left of the ego lane, >= 0
  int lanes_right = 1;              // lanes right of the ego lane, >= 0
  double ego_lane_center_x_m = 0.0; // world x of the ego lane's centre
  double marking_width_m = 0.15;    // > 0
  double dash_length_m = 3.0;       // > 0; lines between lanes are dashed, road edges solid
  double dash_gap_m = 6.0;          // >= 0
};

// A box-shaped object standing on the ground.
struct SceneObject {
  int id = 1;                  // >= 1, unique; truth.csv's id
  std::string kind = "car";    // car | truck | motorbike | pole | wall | pedestrian (texture, truth kind)
  double length_m = 4.5;       // along its heading, > 0
  double width_m = 1.8;        // across, > 0
  double height_m = 1.5;       // > 0
  PlanarPose start;            // centre of the footprint and heading at t = 0, world frame
  MotionProfile motion;        // speed along the heading and yaw rate over time
  double brightness = 0.6;     // body colour brightness (0, 1]
  int colour = 0;              // palette index for the body colour

  // Footprint centre and heading at time t_s, world frame.
  PlanarPose PoseAt(double t_s) const { return motion.Integrate(start, 0.0, t_s); }
};

// A straight painted line on the ground (calibration scenes), parallel to a vehicle axis.
struct PaintedLine {
  char axis = 'Z';               // 'X' or 'Z': the vehicle axis the line is parallel to
  Eigen::Vector2d from_xz{0, 0}; // end points on the ground, world (x, z), metres
  Eigen::Vector2d to_xz{0, 0};
  double width_m = 0.12;         // > 0
};

// How images are rendered. The appearance settings scale the renderer's own sky, asphalt and
// exposure; their defaults (1, 0) render the shipped look.
struct RenderOptions {
  int supersample = 2;        // samples per pixel along each axis, 1..8 (anti-aliasing)
  double noise_sigma = 2.0;   // Gaussian image noise, grey levels, >= 0
  double blur_sigma_px = 0.0; // Gaussian blur after rendering, pixels, >= 0 (0 = none)
  double sky_brightness = 1.0;    // factor on the sky's colour, > 0
  double ground_brightness = 1.0; // factor on the asphalt's mean grey, > 0
  double ground_contrast = 1.0;   // factor on the asphalt texture's amplitude, >= 0
  double texture_scale = 1.0;     // factor on the asphalt texture's feature sizes, > 0
  double exposure = 1.0;          // factor on every rendered colour (before noise), > 0
  double vignetting = 0.0;        // darkening at the image corners, fraction 0..1 (cos^4-like)
  // The own car as the cameras see it: a body (bonnet and boot) over its whole length and width,
  // a cabin above it, and its paint.
  double own_body_height_m = 0.8;    // > 0
  double own_cabin_height_m = 1.45;  // >= own_body_height_m
  double own_car_brightness = 1.0;   // factor on its dark grey, > 0
  // Its shape below the doors and at the mirrors (0: none, the shipped look).
  double own_sill_height_m = 0.0;    // below this height the body is narrower, 0..own_body_height_m
  double own_sill_inset_m = 0.0;     // by this much on each side (the road shows under the doors), >= 0
  double mirror_housing_m = 0.0;     // each camera's mirror housing: this deep behind the camera (0 = none)
  double mirror_housing_drop_m = 0.0;  // how far the housing reaches below the camera, >= 0
  // Scene detail (0 / false: none, the shipped look).
  bool shadows = false;           // objects and the own car cast shadows from the sun on the ground
  double marking_wear = 0.0;      // fraction of lane markings worn away, 0..1
  double clouds = 0.0;            // cloud cover of the sky, 0..1
  double sun_glare = 0.0;         // brightness of the halo around the sun, 0..1
  double verge_m = 0.0;           // grass beyond the road's outer edges from this far out, m (0 = asphalt)
  bool gravel_verge = false;      // the verge is gravel instead of grass
  double ground_patches = 0.0;    // share of the road's 3 m x 5 m cells holding a repair patch, 0..1
  double cracks = 0.0;            // share of the road crossed by cracks, 0..1
  double kerb_height_m = 0.0;     // kerbs along the road's outer edges, raised pavement beyond (0 = none)
  double kerb_offset_left_m = 0.3;   // each kerb this far beyond its outer edge marking's centre, >= 0
  double kerb_offset_right_m = 0.3;
};

// Calibration-scene settings (kind == kCalibration).
struct CalibrationSettings {
  double mark_noise_px = 0.5;     // Gaussian noise added to each mark, pixels, >= 0
  double mark_spacing_m = 0.5;    // spacing of sampled points along a line, metres, > 0
  double min_rotation_deg = 1.0;  // the true rig = nominal rig rotated by a random angle
  double max_rotation_deg = 3.0;  //   in [min, max] about a random axis, per camera
};

enum class SceneKind { kDrive, kCalibration };

struct Scene {
  std::string name = "scene";
  SceneKind kind = SceneKind::kDrive;
  Rig rig;                         // the rig that renders (for calibration: the nominal rig)
  double fps = 15.0;               // frames per second, > 0
  double duration_s = 3.0;         // > 0; frames = round(duration * fps) (at least 1)
  std::uint64_t seed = 1;          // textures, noise, calibration perturbations
  RenderOptions render;
  MotionProfile ego;               // the vehicle's speed / yaw rate
  RoadMarkings road;
  std::vector<SceneObject> objects;
  std::vector<PaintedLine> lines;  // calibration: painted lines
  CalibrationSettings calibration;

  int FrameCount() const;
  double FrameTime(int frame) const { return frame / fps; }
  // The vehicle's pose in the world at time t_s (world = vehicle frame at t = 0).
  PlanarPose EgoPoseAt(double t_s) const { return ego.Integrate(PlanarPose{}, 0.0, t_s); }
};

// Resizes every camera of the scene's rig to width x height (ResizeCameraModel).
void ResizeScene(Scene* scene, int width, int height);

}  // namespace dps
