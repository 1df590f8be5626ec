// dps — which ground-truth objects the rig's cameras see (DESIGN.md §5): an object counts for
// scoring when at least 5 % of its box's surface projects into one camera's valid pixels (the
// model's domain, its field, its mask) without being hidden by the own car or by another object,
// whatever views the pipeline builds.
//
// Each of the box's six faces is sampled on a grid of cell centres, each point weighted by its
// cell's area; a point is seen by a camera when its face turns towards the camera (the box hides
// its own far side), the segment from the camera's viewpoint to it passes through no other
// object's box and not through the own car (a box of the rig's length and width, from the road up
// to own_car_height_m, around the vehicle origin; ignored for a camera inside that box, whose
// mask must then say what the car hides), and it projects into a valid pixel.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "dps/camera/rig.h"
#include "dps/synth/truth.h"

namespace dps {

struct VisibilityOptions {
  double min_seen_fraction = 0.05;  // of the box's surface, DESIGN.md §5; in (0, 1]
  int samples_per_edge = 10;        // grid points along each edge of a face; >= 1
  double own_car_height_m = 1.5;    // the own car's box, metres above the road; >= 0

  // Throws dps::Error naming the field, its value and the violated constraint.
  void Check() const;
};

class Visibility {
 public:
  // Every camera of the rig with its valid pixels (CameraValidMask: model, rim and the camera's
  // mask when rig.yaml or the caller set one).
  explicit Visibility(const Rig& rig, const VisibilityOptions& options = VisibilityOptions());

  // The fraction of `object`'s box surface that camera `camera` (an index into the rig) sees;
  // `scene` holds the frame's objects (the object itself may be among them: it is skipped by id).
  double SeenFraction(const TruthRow& object, const std::vector<const TruthRow*>& scene, size_t camera) const;
  // True when some camera sees at least min_seen_fraction of the object.
  bool Sees(const TruthRow& object, const std::vector<const TruthRow*>& scene) const;

  const Rig& rig() const { return rig_; }

 private:
  Rig rig_;
  VisibilityOptions options_;
  std::vector<cv::Mat> valid_;        // per camera, CV_8U, 255 = sees the world
  std::vector<bool> inside_own_car_;  // per camera: its viewpoint lies inside the own car's box
};

}  // namespace dps
