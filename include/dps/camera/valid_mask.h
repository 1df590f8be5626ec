// dps — which pixels of a camera see the world.
//
// A camera's valid pixels are those its model can unproject (inside its domain and its rim) and
// that its mask, when it has one, marks 255. The mask says what the model cannot: where a mirror's
// or lens's field really ends, and the own car. It comes from rig.yaml (`mask:`), from the drive
// (`masks/<camera>.png`), or is estimated from the drive's images: the area beyond the field
// receives no light, so it stays dark in every frame while the scene changes (EstimateFieldMask);
// the own car moves with the camera, so it stays the same while the road moves past
// (EstimateOwnCarMask: kept apart from the valid pixels, RigCamera::own_car).
// Every view built from the camera inherits its validity (virtual_view.h), and no stereo match
// uses a window touching an invalid pixel (sad_stereo.h).
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "dps/camera/rig.h"

namespace dps {

// CV_8U of the model's image size: 255 where the pixel centre unprojects to a ray (inside the
// model's domain and rim); else 0.
cv::Mat ModelValidMask(const CameraModel& model);

// ModelValidMask where the camera's mask (when set) is 255 too.
cv::Mat CameraValidMask(const RigCamera& camera);

// Whether `camera` sees the road point `ground` (vehicle frame, on Y = 0), and where (`pixel`):
// with `own_car_blocks`, the segment from its viewpoint to the point passes through no part of the
// box [box_lo, box_hi] (the own car); the point projects into the image, onto a pixel that `valid`
// (CameraValidMask of the camera) marks. `camera_from_vehicle`: the camera's pose inverted.
bool SeesRoadPoint(const RigCamera& camera, const Pose& camera_from_vehicle, const cv::Mat& valid,
                   const Eigen::Vector3d& box_lo, const Eigen::Vector3d& box_hi, bool own_car_blocks,
                   const Eigen::Vector3d& ground, Eigen::Vector2d* pixel);

// Reads a mask image for `model`: 8-bit, the model's size; pixels > 127 become 255, the others 0.
// Throws dps::Error naming the file when it is unreadable or of another size.
cv::Mat ReadCameraMask(const std::string& path, const CameraModel& model);

struct FieldMaskOptions {
  // A pixel is dark when it never gets brighter than this fraction of the scene's brightness (the
  // 75th percentile of the brightest value each pixel reaches, over the pixels the model can
  // see). In (0, 1).
  double dark_fraction = 0.15;
  // The field's edge is soft (blur, anti-aliasing, compression): the invalid area grows by this
  // fraction of the image width (at least one pixel). In [0, 0.1].
  double edge_margin_fraction = 0.005;

  // Throws dps::Error naming the field, its value and the violated constraint.
  void Check() const;
};

// The mask of what lies beyond the camera's field, from frames of one camera (grey or BGR, the
// model's size; more frames while the car moves tell dark things from the dark beyond the field):
// the pixels that stay dark in every frame and are connected to the image's border or to what the
// model cannot see, grown by the edge margin. 255 = sees the world. Throws dps::Error when there
// are no frames or their size differs from the model's.
cv::Mat EstimateFieldMask(const std::vector<cv::Mat>& frames, const CameraModel& model,
                          const FieldMaskOptions& options = FieldMaskOptions());

struct OwnCarMaskOptions {
  // The own car's roof is at most this high above the road (m, > 0). Ahead of the cameras the car
  // is lower than they are (they see over the bonnet); the cabin lies behind them.
  double max_roof_height_m = 2.0;
  // A pixel's spread: the standard deviation of its grey level over the frames, relative to its
  // mean (the road's texture is as strong in the car's shadow as in the sun, relative to its
  // brightness), smoothed over a window of window_fraction of the image width (at least 3 px: the
  // image noise averages out, the scene's texture does not). The pixel holds still when its spread
  // is below the geometric mean of the car's (the median over the pixels that must see it) and the
  // road's (the median over the pixels that look down at the road min_road_m .. max_road_m beside
  // the camera).
  double window_fraction = 0.01;   // (0, 0.1]
  double min_road_m = 2.0;         // > 0
  double max_road_m = 8.0;         // > min_road_m
  // The road's spread must be at least this many times the car's (> 1): else no estimate.
  double min_road_to_car = 4.0;
  // The car must move at least this far over the frames (m, > 0): a car standing still holds
  // everything still. The caller measures it (EstimateOwnCarMask's travel_m).
  double min_travel_m = 3.0;

  // Throws dps::Error naming the field, its value and the violated constraint.
  void Check() const;
};

// The own car in one camera (255 = the own car; RigCamera::own_car, which the detectors take no
// obstacle from), from frames of one drive (grey or BGR, the model's size) over which the car
// travelled travel_m: the pixels that hold still while the road moves past, where a ray can meet
// the own car (the footprint up to the camera's height, the cabin behind the camera up to
// max_roof_height_m, and below the camera's level the mirror's housing behind it; rays that do
// not descend to the road: the cabin only), in one piece with the pixels that must see the car
// (their rays reach the road only inside its footprint). Road pixels count only where the road,
// were it there, would have moved by a window over the travel and its texture is resolved as
// finely as in the reference (the footprint of a pixel on the road no coarser than 5-8 m beside
// the camera): the sky, the distance, a smooth verge far off and a vehicle keeping pace hold still
// too. Back by half a window at the end (the smoothing reaches beyond the car's edge). So the
// estimate is the own car below the camera's level where the road around it is resolved; not the
// bonnet's far edge nor what lies above the camera (rendered drives: 0.40 of the own car's pixels,
// test_valid_mask). An empty Mat when it cannot tell: the car travelled less than
// min_travel_m, fewer than two frames, no road in view beside the camera, or the road itself
// holds still (no texture to see it move). Throws dps::Error for frames of another size than the
// model's.
cv::Mat EstimateOwnCarMask(const std::vector<cv::Mat>& frames, const RigCamera& camera, const Vehicle& vehicle,
                           double travel_m, const OwnCarMaskOptions& options = OwnCarMaskOptions());

}  // namespace dps
