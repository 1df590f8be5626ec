// Tests of ground projection (eq. 16-18): view pixels to the road and back, a column and a
// disparity of the front pair to the ground point they were made from, and the road's disparity
// image against the disparity the two views actually give a ground point; on the shipped rig and
// on the same rig with the cameras pitched, rolled and raised differently.
#include <cmath>

#include <Eigen/Geometry>

#include "check.h"
#include "fixtures.h"
#include "dps/camera/rig_io.h"
#include "dps/detect/ground_projection.h"
#include "dps/stereo/sad_stereo.h"
#include "dps/stereo/virtual_view.h"

namespace {

constexpr double kTolM = 1e-7;    // ground points from exact pixels
constexpr double kTolPx = 1e-4;   // float road disparity
using dps_test::kSource;

using dps_test::OmniRig;

// The shipped rig with both cameras turned (pitch about X, roll about Z) and the right one lower.
dps::Rig TurnedRig() {
  dps::Rig rig = OmniRig();
  for (dps::RigCamera& c : rig.cameras) {
    const Eigen::Matrix3d turn = dps::AxisAngle(Eigen::Vector3d::UnitX(), 0.04) * dps::AxisAngle(Eigen::Vector3d::UnitZ(), -0.03);
    c.vehicle_from_camera.R = turn * c.vehicle_from_camera.R;
    if (c.name == "right") c.vehicle_from_camera.t.y() += 0.05;
  }
  return rig;
}

void TestRayMeetsRoad() {
  Eigen::Vector3d g;
  CHECK(dps::RayMeetsRoad({0.5, -1.0, 0.0}, {0.0, 1.0, 1.0}, &g));
  CHECK_NEAR((g - Eigen::Vector3d(0.5, 0.0, 1.0)).norm(), 0.0, 1e-12);
  CHECK(!dps::RayMeetsRoad({0.5, -1.0, 0.0}, {0.0, -0.1, 1.0}, &g));  // looks up
  CHECK(!dps::RayMeetsRoad({0.5, -1.0, 0.0}, {0.0, 0.0, 1.0}, &g));   // the horizon
  CHECK(!dps::RayMeetsRoad({0.5, 0.2, 0.0}, {0.0, 1.0, 1.0}, &g));    // below the road
}

// Every road point a view sees comes back from its pixel.
void CheckPixelRoundTrip(const dps::VirtualView& view, const char* what) {
  int checked = 0;
  for (double x = -12; x <= 12; x += 1.5) {
    for (double z = -12; z <= 40; z += 2.0) {
      const Eigen::Vector3d p(x, 0.0, z);
      Eigen::Vector2d pixel;
      if (!view.ProjectVehicle(p, &pixel) || dps::ViewDepth(view, p) <= 0.5) continue;
      const dps::ViewSpec& s = view.spec();
      if (pixel.x() < 0 || pixel.y() < 0 || pixel.x() > s.width - 1 || pixel.y() > s.height - 1) continue;
      Eigen::Vector3d g;
      CHECK(dps::PixelToGround(view, pixel.x(), pixel.y(), &g));
      CHECK_NEAR((g - p).norm(), 0.0, kTolM * p.norm());
      ++checked;
    }
  }
  std::printf("%s: %d road points round-tripped\n", what, checked);
  CHECK(checked > 20);
  // A pixel above the horizon sees no road.
  Eigen::Vector3d g;
  Eigen::Vector2d sky;
  const Eigen::Vector3d far_up = view.viewpoint_vehicle() + 50.0 * (view.spec().vehicle_from_view.col(2) -
                                                                    0.3 * Eigen::Vector3d::UnitY());
  if (view.ProjectVehicle(far_up, &sky)) CHECK(!dps::PixelToGround(view, sky.x(), sky.y(), &g));
}

// Eq. 16: a point of the front pair's left view, with the disparity the two views give it, goes to
// the ground point under it; and the road's disparity image holds the ground points' disparity.
void CheckFrontPair(const dps::Rig& rig, const char* what) {
  const dps::ViewSpec spec = dps::FrontViewSpec(rig, "left", "right", 400, 200, 170.0);
  const dps::VirtualView left(rig.Camera("left"), spec), right(rig.Camera("right"), spec);
  const double baseline = (rig.Camera("right").vehicle_from_camera.t - rig.Camera("left").vehicle_from_camera.t).norm();
  CheckPixelRoundTrip(left, what);
  const cv::Mat road = dps::RoadDisparity(left, baseline);
  const cv::Mat road_from_inverse = dps::RoadDisparity(dps::RoadInverseDepth(left), spec.focal_px, baseline);
  int checked = 0;
  for (double x = -6; x <= 6; x += 1.0) {
    for (double z = 4; z <= 40; z += 3.0) {
      for (const double height : {0.0, 0.8}) {  // the road, and the side of an obstacle above it
        // Above the road only where the view is not tilted: the column's vertical line is the
        // view's y axis, which is the vehicle's vertical only then.
        if (height > 0 && std::abs(spec.vehicle_from_view(1, 1) - 1.0) > 1e-12) continue;
        const Eigen::Vector3d p(x, -height, z);
        Eigen::Vector2d pl, pr;
        if (!left.ProjectVehicle(p, &pl) || !right.ProjectVehicle(p, &pr)) continue;
        if (pl.x() < 0 || pl.x() > spec.width - 1 || pl.y() < 0 || pl.y() > spec.height - 1) continue;
        const double disparity = pl.x() - pr.x();
        Eigen::Vector2d g;
        CHECK(dps::ColumnToGround(left, pl.x(), disparity, baseline, &g));
        CHECK_NEAR((g - Eigen::Vector2d(x, z)).norm(), 0.0, kTolM * z);
        ++checked;
      }
    }
  }
  // The road image at whole pixels against the disparity the views give that pixel's ground point.
  int road_checked = 0;
  for (int y = 0; y < spec.height; y += 9) {
    for (int x = 0; x < spec.width; x += 13) {
      Eigen::Vector3d g;
      const float d = road.at<float>(y, x);
      if (!dps::PixelToGround(left, x, y, &g)) {
        CHECK(d == dps::kInvalidDisparity);
        continue;
      }
      Eigen::Vector2d pl, pr;
      if (!left.ProjectVehicle(g, &pl) || !right.ProjectVehicle(g, &pr)) continue;
      CHECK_NEAR(d, pl.x() - pr.x(), kTolPx * std::max(1.0, double(d)));
      CHECK_NEAR(road_from_inverse.at<float>(y, x), d, kTolPx * std::max(1.0, double(d)));
      ++road_checked;
    }
  }
  std::printf("%s: %d columns to the ground, %d road disparities\n", what, checked, road_checked);
  CHECK(checked > 50);
  CHECK(road_checked > 100);
  Eigen::Vector2d g;
  CHECK(!dps::ColumnToGround(left, 200, 0.0, baseline, &g));
}

void TestSideViews() {
  for (const dps::Rig& rig : {OmniRig(), TurnedRig()}) {
    for (const auto& [side, name] : {std::pair{dps::Side::kLeft, "left"}, std::pair{dps::Side::kRight, "right"}}) {
      for (const double yaw : {0.0, 0.2}) {
        const dps::VirtualView view(rig.Camera(name), dps::SideViewSpec(side, 320, 160, 120.0, yaw, 0.4));
        CheckPixelRoundTrip(view, name);
      }
    }
  }
}

}  // namespace

int main() {
  TestRayMeetsRoad();
  CheckFrontPair(OmniRig(), "front, shipped rig");
  CheckFrontPair(TurnedRig(), "front, turned rig");
  TestSideViews();
  return dps_test::Report();
}
