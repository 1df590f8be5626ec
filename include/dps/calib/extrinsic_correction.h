// dps — online extrinsic correction: each camera's rotation error estimated from the road's
// motion while the car drives (issue: rigs a little off; Gandhi & Trivedi 2006 section IV's drift
// correction, which keeps the front pair's rows aligned, generalised to a camera's three angles).
//
// A road point seen at pixel u in frame i lies where u's ray meets the road (Y = 0). The vehicle's
// motion from frame i to a later frame j (CAN speed and yaw rate) puts that point at a known place
// in frame j's vehicle frame, and the camera predicts the ray it is seen along there. When the
// camera's rotation in the rig is wrong, the predictions miss the rays along which the point is
// tracked: the road seems nearer or farther than it is (pitch, roll) and its motion turned (yaw).
// The correction is the small rotation dR of the vehicle frame (the rig's R becomes dR R) that
// minimises the pixel distances between predicted and tracked places of road features over a
// drive's first seconds. The features are tracked (Lucas-Kanade, checked by tracking back) from
// the earlier frame warped through the road plane as the rig has it, where road texture keeps its
// scale and shape; a second pass tracks through the first pass's correction. What does not move
// with the road - objects, moving cars, the own car's edge, a line along the motion - misses by
// many pixels and weighs next to nothing (Cauchy weights at the tracker's accuracy).
//
// The camera's position and the CAN speed are taken as right: an error of speed or height reads
// partly as pitch.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "dps/camera/ego_motion.h"
#include "dps/camera/rig.h"

namespace dps {

struct ExtrinsicCorrectionOptions {
  // Road features are taken between these ground distances from the camera (m): nearer, the own
  // car and the pixels' footprint stretch; farther, the road's motion says little about the angles.
  double min_distance_m = 1.5;   // > 0
  double max_distance_m = 12.0;  // > min_distance_m
  double vehicle_margin_m = 0.3; // ... and this far outside the vehicle's footprint, >= 0
  // Frame i is paired with the first later frame the vehicle moved at least this far from: the
  // road's motion must stand out from the tracking noise.
  double min_travel_m = 0.3;     // > 0
  int max_features = 300;        // per frame pair, >= 10
  double max_track_error_px = 0.5;  // tracked forward and back: ends this close to its start, > 0
  // A feature's window must hold texture in every direction: its gradients' smaller eigenvalue at
  // least this fraction of the larger (an edge, e.g. a marking's, lets the tracker slide along it).
  double min_isotropy = 0.2;     // 0 < r <= 1
  double track_sigma_px = 0.1;   // the tracker's accuracy on road texture (robust weights), > 0
  int min_tracks = 200;          // fewer road tracks fitted: no correction, >= 10
  // An estimate whose standard error (any angle) exceeds max_sigma_deg, or whose size exceeds
  // max_correction_deg (something else is wrong: the mounting, the camera's height, the road), is
  // reported and not applied. One smaller than min_correction_deg, the method's resolution (what
  // it finds for cameras whose rig is right: 0.01-0.035 deg on rendered drives), confirms the rig:
  // applying it would move the rig by the estimate's noise.
  double max_sigma_deg = 0.05;   // > 0
  double min_correction_deg = 0.05;  // >= 0
  double max_correction_deg = 2.0;   // > min_correction_deg

  // Throws dps::Error naming the field, its value and the violated constraint.
  void Check() const;
};

struct ExtrinsicCorrection {
  std::string camera;
  bool applied = false;          // the rig's rotation turned by the estimate
  // The rig's rotation agrees with the road's motion: applied, or the estimate sure and smaller
  // than min_correction_deg.
  bool verified = false;
  std::string reason;            // why not applied ("" when applied)
  // The rotation dR (R becomes dR R) as a rotation vector in the vehicle frame, degrees: about X
  // (pitch; positive turns forward rays up), Y (yaw; positive turns forward rays right) and Z
  // (roll; positive turns rightward rays down); and the standard error of each.
  Eigen::Vector3d rotation_deg = Eigen::Vector3d::Zero();
  Eigen::Vector3d sigma_deg = Eigen::Vector3d::Zero();
  int pairs = 0;                 // frame pairs used
  int tracks = 0;                // road tracks fitted (inliers)
  double rms_px = 0.0;           // the inliers' residual, after and before the correction
  double rms_before_px = 0.0;
};

// The correction of `camera` from `frames` (the drive's first frames, as read) with `poses[k]`
// the vehicle's pose at frames[k] in the vehicle frame of frames[0]. The camera's `mask` and
// `own_car` (when set) keep features off what does not see the road.
ExtrinsicCorrection EstimateExtrinsicCorrection(const std::vector<cv::Mat>& frames, const std::vector<PlanarPose>& poses,
                                                const RigCamera& camera, const Vehicle& vehicle,
                                                const ExtrinsicCorrectionOptions& options = ExtrinsicCorrectionOptions());

// `camera` turned by a correction (applied or not): R becomes dR R.
RigCamera CorrectedCamera(const RigCamera& camera, const ExtrinsicCorrection& correction);

}  // namespace dps
