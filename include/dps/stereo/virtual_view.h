// dps — virtual perspective views rendered from omni (or fisheye) images
// (Gandhi & Trivedi 2006, sections III and V).
//
// A view is a pinhole camera at the omni camera's viewpoint: `focal_px`, principal point
// (cx, cy), size, and an orientation `vehicle_from_view` whose columns are the view's x (image
// right), y (image down) and z (viewing direction) axes in the vehicle frame. The remap table
// from view pixels to omni pixels is built once (CameraModel::Project per view pixel); rendering
// is one cv::remap. View pixels with no omni source (outside the rim or the image, or where the
// camera's mask says the camera does not see the world) are masked.
//
// - Front views of the two cameras share one orientation, looking along +Z with rows parallel to
//   the baseline, so the pair is rectified (eq. 11): x_l - x_r = f B / Z, y_l = y_r, and
//   left(x) matches right(x - d) (FrontViewSpec).
// - Side views look sideways with a vertical image plane parallel to the direction of motion
//   (SideViewSpec); for turning, the plane follows the displacement between two frames, given as a
//   yaw of the viewing direction; SideViewCache keeps the tables per quantised yaw.
// - Drift: small rotation errors make the rows of the two front views disagree. The paper
//   shifted one view by hand; EstimateVerticalOffset measures the shift of the right view from
//   the images, and a right view built with cy - offset compensates it.
#pragma once

#include <list>
#include <memory>
#include <utility>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "dps/camera/rig.h"
#include "dps/util/math.h"

namespace dps {

// A pinhole view: size, intrinsics and orientation in the vehicle frame.
struct ViewSpec {
  int width = 320;           // pixels, > 0
  int height = 240;          // pixels, > 0
  double focal_px = 160.0;   // > 0
  double cx = 159.5;         // principal point, pixels
  double cy = 119.5;
  Eigen::Matrix3d vehicle_from_view = Eigen::Matrix3d::Identity();  // rotation, columns x, y, z

  // Throws dps::Error naming the field when a value is out of range or the rotation is not one.
  void Check() const;
};

// The rectified front view of the rig's cameras `left_camera` and `right_camera`: looking along
// the vehicle's +Z as far as the baseline allows (z orthogonal to the baseline), image x along
// the baseline from left to right, image y down. Principal point at the image centre.
ViewSpec FrontViewSpec(const Rig& rig, const std::string& left_camera,
                       const std::string& right_camera, int width, int height, double focal_px);

// A side view: looking towards -X (left side) or +X (right side), image plane vertical and
// parallel to the vehicle's Z; turned about the vertical axis by yaw_rad (positive = towards the
// front, for either side). Principal point at horizon_fraction of the height (the horizon's row;
// below 0.5 the view looks further down, towards where nearby objects meet the road) and with
// back_fraction of the columns beyond it on the view's backward side (0.5: the centre column;
// more: the view reaches further back, towards the blind spot behind the mirrors).
enum class Side { kLeft, kRight };
ViewSpec SideViewSpec(Side side, int width, int height, double focal_px, double yaw_rad = 0.0,
                      double horizon_fraction = 0.5, double back_fraction = 0.5);

class VirtualView {
 public:
  // Builds the remap table of `camera` (model and vehicle_from_camera) for `spec`.
  VirtualView(const RigCamera& camera, const ViewSpec& spec);

  // Renders the view from an omni image of the camera's size (any type cv::remap takes);
  // bilinear; pixels without a source are 0.
  cv::Mat Render(const cv::Mat& omni) const;
  void Render(const cv::Mat& omni, cv::Mat& out) const;

  // CV_8U, 255 where the view pixel has an omni source.
  const cv::Mat& mask() const { return mask_; }
  // CV_8U, 255 where that source is the camera's estimated own car (RigCamera::own_car); empty
  // without one.
  const cv::Mat& own_car() const { return own_car_; }
  const ViewSpec& spec() const { return spec_; }
  // The view pixel's ray in the vehicle frame (unit).
  Eigen::Vector3d RayVehicle(double x, double y) const;
  // The view pixel of a point in the vehicle frame, seen from the camera's viewpoint; false when
  // it lies behind the view.
  bool ProjectVehicle(const Eigen::Vector3d& p_vehicle, Eigen::Vector2d* pixel) const;
  const Eigen::Vector3d& viewpoint_vehicle() const { return viewpoint_; }
  // Floating-point omni coordinates of each view pixel (CV_32FC2; (-1, -1) = none).
  const cv::Mat& omni_coordinates() const { return map_float_; }

 private:
  ViewSpec spec_;
  Eigen::Vector3d viewpoint_;
  cv::Mat map_float_;   // CV_32FC2
  cv::Mat map1_, map2_; // fixed-point maps for cv::remap
  cv::Mat mask_;
  cv::Mat own_car_;
};

// Side views of one camera for many yaws, built on demand and kept for the most recent
// `capacity` quantised yaws (a steady turn reuses its tables frame after frame).
constexpr double kSideViewYawStepRad = 0.25 * kRadPerDeg;  // 0.25 degrees

class SideViewCache {
 public:
  // yaw_step_rad > 0: yaws are rounded to multiples of it; capacity >= 1; horizon_fraction and
  // back_fraction as for SideViewSpec.
  SideViewCache(const RigCamera& camera, Side side, int width, int height, double focal_px,
                double yaw_step_rad = kSideViewYawStepRad, size_t capacity = 16,
                double horizon_fraction = 0.5, double back_fraction = 0.5);

  // The view for the yaw nearest to yaw_rad on the quantisation grid.
  const VirtualView& Get(double yaw_rad);
  // The grid index of a yaw (equal indices, same view).
  long Key(double yaw_rad) const;
  size_t builds() const { return builds_; }  // tables built so far

 private:
  RigCamera camera_;
  Side side_;
  int width_, height_;
  double focal_px_, horizon_fraction_, back_fraction_, step_;
  size_t capacity_;
  size_t builds_ = 0;
  std::list<std::pair<long, std::unique_ptr<VirtualView>>> views_;  // most recent first
};

// CV_8U, 255 where the view pixel's ray meets the own car, modelled as a box of the rig's
// vehicle length and width and `height_m` (metres above the road) around the vehicle origin:
// the bonnet and doors that every mirror-mounted camera sees, which must not count as obstacles.
// (The camera's own car as estimated from a drive is VirtualView::own_car.)
cv::Mat OwnCarMask(const VirtualView& view, const Vehicle& vehicle, double height_m);

// The vertical misalignment of a rectified pair: the median row shift of the right view relative
// to the left (positive = the right view shows things lower), measured at corners of the left
// view by template matching over the disparity range and +-max_offset_px rows, to sub-pixel.
struct VerticalOffset {
  double offset_px = 0.0;  // median shift
  int features = 0;        // corners that matched reliably
  double spread_px = 0.0;  // median absolute deviation of their shifts
};
VerticalOffset EstimateVerticalOffset(const cv::Mat& left_view, const cv::Mat& right_view,
                                      int min_disparity, int num_disparities,
                                      double max_offset_px = 4.0);

}  // namespace dps
