// dps — from a virtual view to the ground (Gandhi & Trivedi 2006, eq. 16-18).
//
// The road is the vehicle frame's plane Y = 0. A view pixel's ray meets it at one ground point
// (the side detector's contact points, eq. 17-18); a column and a disparity of a stereo pair give
// a depth along the view axis (f B / d) and, dropped onto the road along the column's vertical
// line, a ground point (the front detector's obstacles, eq. 16). The road itself has a disparity
// at every pixel below the horizon, f B over the depth of its ground point: what an obstacle's
// disparity is compared with.
#pragma once

#include <opencv2/core.hpp>

#include <Eigen/Core>

#include "dps/stereo/virtual_view.h"

namespace dps {

// Where the ray of view pixel (x, y) meets the road, vehicle frame; false at or above the horizon.
bool PixelToGround(const VirtualView& view, double x, double y, Eigen::Vector3d* ground);

// Depth of a vehicle-frame point along the view's axis (from its viewpoint).
double ViewDepth(const VirtualView& view, const Eigen::Vector3d& point);

// Eq. 16: the ground point (x, z) under column x of `view` at `disparity` (px) for a pair
// `baseline_m` apart: depth f B / d, lateral offset (x - cx) depth / f, and the height along the
// column's vertical line where the point meets the road. False for a disparity <= 0.
bool ColumnToGround(const VirtualView& view, double x, double disparity, double baseline_m, Eigen::Vector2d* ground);

// The inverse depth (1/m, CV_32F) of the road along the view axis at every pixel, 0 where the
// pixel sees no road: the road's disparity for any baseline is f B times it.
cv::Mat RoadInverseDepth(const VirtualView& view);

// The road's disparity (CV_32F, px) for a pair `baseline_m` apart: f B / depth, kInvalidDisparity
// where the pixel sees no road.
cv::Mat RoadDisparity(const VirtualView& view, double baseline_m);
// The same from RoadInverseDepth's image.
cv::Mat RoadDisparity(const cv::Mat& inverse_depth, double focal_px, double baseline_m);

}  // namespace dps
