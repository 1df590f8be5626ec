#include "dps/detect/ground_projection.h"

#include <cmath>

#include "dps/stereo/sad_stereo.h"

namespace dps {

bool PixelToGround(const VirtualView& view, double x, double y, Eigen::Vector3d* ground) {
  return RayMeetsRoad(view.viewpoint_vehicle(), view.RayVehicle(x, y), ground);
}

double ViewDepth(const VirtualView& view, const Eigen::Vector3d& p) {
  return (view.spec().vehicle_from_view.transpose() * (p - view.viewpoint_vehicle())).z();
}

bool ColumnToGround(const VirtualView& view, double x, double disparity, double baseline_m, Eigen::Vector2d* ground) {
  if (!(disparity > 0)) return false;
  const ViewSpec& s = view.spec();
  const double depth = s.focal_px * baseline_m / disparity;
  const double lateral = (x - s.cx) * depth / s.focal_px;
  // The view-frame point (lateral, h, depth) whose vehicle-frame height is 0 (the ground): the
  // vertical line of the column at that depth, dropped onto the road.
  const Eigen::Matrix3d& R = s.vehicle_from_view;
  const Eigen::Vector3d& t = view.viewpoint_vehicle();
  const double h = std::abs(R(1, 1)) > 1e-9 ? -(t.y() + R(1, 0) * lateral + R(1, 2) * depth) / R(1, 1) : 0.0;
  const Eigen::Vector3d p = t + R * Eigen::Vector3d(lateral, h, depth);
  *ground = Eigen::Vector2d(p.x(), p.z());
  return true;
}

cv::Mat RoadInverseDepth(const VirtualView& view) {
  const ViewSpec& spec = view.spec();
  cv::Mat inverse_depth(spec.height, spec.width, CV_32F, cv::Scalar(0));
  for (int y = 0; y < spec.height; ++y) {
    for (int x = 0; x < spec.width; ++x) {
      Eigen::Vector3d p;
      if (!PixelToGround(view, x, y, &p)) continue;
      const double depth = ViewDepth(view, p);
      if (depth > 0) inverse_depth.at<float>(y, x) = static_cast<float>(1.0 / depth);
    }
  }
  return inverse_depth;
}

cv::Mat RoadDisparity(const VirtualView& view, double baseline_m) {
  const ViewSpec& spec = view.spec();
  cv::Mat road(spec.height, spec.width, CV_32F, cv::Scalar(kInvalidDisparity));
  for (int y = 0; y < spec.height; ++y) {
    for (int x = 0; x < spec.width; ++x) {
      Eigen::Vector3d p;
      if (!PixelToGround(view, x, y, &p)) continue;
      const double depth = ViewDepth(view, p);
      if (depth > 0) road.at<float>(y, x) = static_cast<float>(spec.focal_px * baseline_m / depth);
    }
  }
  return road;
}

cv::Mat RoadDisparity(const cv::Mat& inverse_depth, double focal_px, double baseline_m) {
  cv::Mat road = inverse_depth * (focal_px * baseline_m);
  road.setTo(kInvalidDisparity, inverse_depth == 0);
  return road;
}

}  // namespace dps
