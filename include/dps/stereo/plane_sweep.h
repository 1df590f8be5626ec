// dps — plane-sweep motion stereo on one camera's raw images (seed 004, §4.2): the current frame
// against an earlier one, the camera's motion between them known (CAN speed and yaw rate), with no
// rectification. Every pixel's ray is tried against a set of surfaces — the road plane, and
// distances along the ray spaced evenly in inverse distance (spheres about the viewpoint, which
// are fronto-parallel planes for each pixel's own direction) — by warping the earlier image
// through the camera model onto the current one and scoring a window with zero-mean normalised
// cross-correlation (robust to exposure change). The best surface per pixel, when it is unique,
// gives its distance; pixels that the road explains are free space, pixels nearer than the road
// along their ray are obstacle evidence.
//
// Near the motion's epipoles (straight ahead and behind for a car driving straight) every
// distance warps to almost the same place: depth is unobservable there and those pixels say so
// (kSweepUnobservable) rather than guess. The sweep assumes a static world: a moving object is
// placed wrongly or, more often, matches no surface (kSweepAmbiguous).
#pragma once

#include <opencv2/core.hpp>

#include "dps/camera/camera_model.h"
#include "dps/camera/rig.h"

namespace dps {

struct PlaneSweepOptions {
  double min_distance_m = 1.0;   // nearest distance hypothesis along a ray, > 0
  double max_distance_m = 40.0;  // farthest, > min
  int distances = 48;            // hypotheses between them, even in inverse distance, >= 2
  int window_px = 7;             // ZNCC window, odd, >= 3
  double min_zncc = 0.6;         // a best score below this: no distance (ambiguous)
  // The best surface must beat every surface that warps the pixel more than 1.5 px away from where
  // the best one does by this much ZNCC (repeated texture, untextured areas).
  double uniqueness = 0.05;
  // Pixels whose nearest and farthest hypotheses warp less than this far apart: unobservable (the
  // wedges about the motion's epipoles). A distance that warps within 1.5 px of where the road
  // does cannot be told from the road, and is taken as road.
  double min_parallax_px = 2.0;
  double min_contrast = 2.0;     // the window's grey-level standard deviation below: ambiguous
  // A best distance within this fraction of the road's distance along the ray counts as road.
  double road_tolerance = 0.1;

  // Throws dps::Error naming the field, its value and the violated constraint.
  void Check() const;
};

// What a pixel is, by the sweep.
enum SweepLabel : std::uint8_t {
  kSweepNoRay = 0,         // outside the camera's valid pixels (or its ray leaves the earlier image)
  kSweepUnobservable = 1,  // near an epipole of the motion: every distance warps alike
  kSweepAmbiguous = 2,     // no surface unique or good enough (no texture, repetition, moving)
  kSweepRoad = 3,          // the road plane explains it: free space
  kSweepObstacle = 4,      // nearer than the road along its ray (or above the horizon): obstacle
};

struct SweepResult {
  cv::Mat distance_m;  // CV_32F, along each pixel's ray from the viewpoint; NaN without one
  cv::Mat label;       // CV_8U, SweepLabel
  cv::Mat score;       // CV_32F, the best ZNCC (NaN where nothing was scored)
};

// An earlier frame to sweep against: its grey image and where the current vehicle frame lies in
// its vehicle frame.
struct EarlierFrame {
  cv::Mat image;
  Pose previous_from_current;
};

// One camera's sweeps: its rays are computed once.
class PlaneSweeper {
 public:
  // A camera of this model mounted at `vehicle_from_camera`. `valid` (CV_8U, 255 = sees the world;
  // empty = every pixel the model unprojects) masks both images; `region` (CV_8U, empty = all)
  // limits the pixels measured (the work is done on their bounding box only).
  PlaneSweeper(const CameraModel& model, const Pose& vehicle_from_camera, const cv::Mat& valid,
               const cv::Mat& region, const PlaneSweepOptions& options = {});

  // The sweep of `current` against `previous` (grey, CV_8U, the camera's image size), the vehicle
  // having moved by `previous_from_current` (the current vehicle frame in the earlier one).
  SweepResult Sweep(const cv::Mat& previous, const cv::Mat& current, const Pose& previous_from_current) const;
  // Against several earlier frames at once: a surface's score is the mean of its ZNCC in each (a
  // window not whole in one of them is not scored), so that only what stays where a static world
  // puts it scores well in all (seed 004: the images against a reference image). The frame with
  // the longest baseline decides what warps where (uniqueness, the road, the epipoles).
  SweepResult Sweep(const std::vector<EarlierFrame>& earlier, const cv::Mat& current) const;

  const CameraModel& model() const { return model_; }
  const Pose& vehicle_from_camera() const { return vehicle_from_camera_; }

 private:
  CameraModel model_;
  Pose vehicle_from_camera_;
  cv::Mat valid_;
  PlaneSweepOptions options_;
  cv::Rect roi_;       // the region's bounding box, widened by half a window
  cv::Mat dirs_;       // CV_32FC3 over roi_: rays in the vehicle frame, NaN outside the region
  cv::Mat road_m_;     // CV_32F over roi_: distance to the road along the ray (+inf above the horizon)
  cv::Mat measured_;   // CV_8U over roi_: the region's valid pixels
};

// A one-off sweep (PlaneSweeper with no region).
SweepResult PlaneSweep(const CameraModel& model, const Pose& vehicle_from_camera, const cv::Mat& previous,
                       const cv::Mat& current, const Pose& previous_from_current, const cv::Mat& valid,
                       const PlaneSweepOptions& options = {});

// A picture of one sweep over the camera's image (grey, CV_8U): obstacle pixels coloured by their
// distance (turbo, red at min_distance_m to blue at max_distance_m, even in inverse distance), road
// pixels tinted green, the unobservable wedges about the epipoles magenta, ambiguous pixels the
// image in grey, no ray black; a legend in the top-left corner. CV_8UC3 of the image's size.
cv::Mat SweepPicture(const cv::Mat& image, const SweepResult& sweep, double min_distance_m, double max_distance_m);

}  // namespace dps
