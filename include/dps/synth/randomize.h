// dps — randomised drives for the robustness battery (docs/robustness.md): a shipped scene's story
// (who drives where) rendered with a camera, a mounting, a calibration error, an appearance and
// objects drawn reproducibly from a seed, so that the pipeline is judged on rigs and roads it was
// not tuned on.
//
// What is drawn (RandomizeOptions holds the ranges):
// - the camera family — hyperbolic mirror, unified (Mei) mirror, Kannala-Brandt fisheye with its
//   axis down, or a fisheye looking sideways and tilted down — and its parameters: mirror shape or
//   lens distortion, where the field of view ends (for a camera with its axis down, this many
//   degrees above the horizon; black beyond), the image circle's radius, the principal point off
//   centre, the pixel aspect;
// - the mounting of each camera (left and right drawn apart): height, lateral and longitudinal
//   position, a rotation off the nominal orientation; the vehicle's length and width;
// - the calibration error: the rig written for processing is the rendering rig with each camera
//   turned by a further small rotation;
// - the appearance: sky and asphalt brightness, the asphalt texture's contrast and grain size,
//   shadows, worn markings, clouds, sun glare, grass or gravel verges, repair patches, cracks,
//   kerbs with a raised pavement, exposure, vignetting, sensor noise, blur, the texture seed, and
//   whether the drive is written as video (MJPG or H.264) instead of PNG images;
// - the own car as the cameras see it: bonnet and cabin height, the sill under the doors, a mirror
//   housing behind each camera, paint;
// - the objects: cars of the story may become vans (kind car), buses (truck) or motorbikes
//   (motorbike); sizes, paint brightness and colour, positions and speeds around the scene's
//   own; up to three poles, walls or walking pedestrians beside the road (not on the empty roads);
//   and the whole story mirrored left to right (overtaking on either side, turns both ways).
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "dps/synth/scene.h"

namespace dps {

struct RandomizeOptions {
  double field_edge_min_deg = 5.0;     // axis-down cameras: field ends this far above the horizon
  double field_edge_max_deg = 40.0;    //   (min <= max, within 0..60)
  double side_fisheye_tilt_min_deg = 20.0;  // sideways fisheyes: axis this far below the horizon
  double side_fisheye_tilt_max_deg = 60.0;
  double mount_rotation_max_deg = 5.0;      // off the nominal orientation, >= 0
  double calibration_error_max_deg = 0.5;   // processing rig vs rendering rig, per camera, >= 0
  double height_min_m = 0.9;                // camera height above the road, 0 < min <= max
  double height_max_m = 1.4;
  double principal_offset_max_px = 4.0;     // principal point off the image centre, >= 0, at 640 px
  double aspect_max_deviation = 0.02;       // |fy / fx - 1|, 0..0.2
  double object_size_fraction = 0.15;       // objects' sizes scaled by 1 +- this, 0..0.5
  double object_speed_fraction = 0.2;       // objects' speeds scaled by 1 +- this, 0..0.5
  double object_shift_m = 0.5;              // objects moved across and along by up to this, >= 0
  double video_fraction = 0.5;              // share of drives written as video (half MJPG, half H.264), 0..1

  // Throws dps::Error naming the field, its value and the violated constraint.
  void Check() const;
};

struct RandomizedScene {
  Scene scene;                 // what renders; scene.rig is the true rig
  Rig processing_rig;          // what rig.yaml holds: the true rig with a calibration error
  std::string camera_family;   // "hyperbolic", "unified", "fisheye_down", "fisheye_side"
  bool mirrored = false;       // the story mirrored left to right
  bool video = false;          // written as video instead of PNG images
  std::string video_codec;     // then "MJPG" or "H264" (SynthOptions::video_codec)
  std::vector<std::pair<std::string, double>> draws;  // every drawn number, by name
  // The draws as a JSON object (family, seed, mirrored, video, draws).
  std::string ToJson(std::uint64_t seed) const;
};

// The ranges of a scene file's `randomize:` block (keys as the fields above; absent keys keep the
// defaults, no block gives the defaults). Throws dps::Error naming the file and the field.
RandomizeOptions ReadRandomizeOptions(const std::string& scene_path);

// Draws a randomised version of `scene` (a drive scene) from `seed`: the same seed and scene give
// the same result on every machine. The scene's image size is kept.
RandomizedScene Randomize(const Scene& scene, std::uint64_t seed, const RandomizeOptions& options = {});

}  // namespace dps
