// Tests of virtual perspective views: rectified front geometry (eq. 11) and agreement of the
// remap tables with the camera model, masks, side-view orientation and the yaw cache, vertical
// drift estimation and compensation, and stereo on a rendered front pair scored against the
// renderer's range truth (dps and cv::StereoBM in the same run).
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include <opencv2/imgcodecs.hpp>

#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "check.h"
#include "fixtures.h"
#include "dps/camera/rig_io.h"
#include "dps/stereo/sad_stereo.h"
#include "dps/stereo/virtual_view.h"
#include "dps/synth/scene_io.h"
#include "dps/synth/scene_renderer.h"

namespace {

constexpr double kGeometryTol = 1e-9;
constexpr double kMapTolPx = 1e-3;        // remap table vs CameraModel::Project
constexpr double kOffsetTolPx = 0.15;     // vertical offset of a synthetic pair
constexpr double kRenderedOffsetTolPx = 0.3;
constexpr double kBadThresholdPx = 1.0;

using dps_test::kSource;

using dps_test::OmniRig;

void TestFrontGeometry() {
  const dps::Rig rig = OmniRig();
  const dps::ViewSpec spec = dps::FrontViewSpec(rig, "left", "right", 320, 240, 160.0);
  CHECK_NEAR((spec.vehicle_from_view - Eigen::Matrix3d::Identity()).norm(), 0.0, kGeometryTol);
  const dps::VirtualView left(rig.Camera("left"), spec), right(rig.Camera("right"), spec);
  const double baseline = 2.0;
  for (double x = -3; x <= 3; x += 1.5) {
    for (double y = -1.5; y <= 0.5; y += 0.5) {
      for (double z = 5; z <= 30; z += 5) {
        Eigen::Vector2d pl, pr;
        CHECK(left.ProjectVehicle({x, y, z}, &pl) && right.ProjectVehicle({x, y, z}, &pr));
        CHECK_NEAR(pl.y(), pr.y(), kGeometryTol);                        // y_l = y_r
        CHECK_NEAR(pl.x() - pr.x(), 160.0 * baseline / (z - 0.9), 1e-9);  // x_l - x_r = f B / Z
      }
    }
  }
  // The remap table holds exactly the omni pixel the camera model gives for the view pixel's ray.
  const dps::RigCamera& cam = rig.Camera("left");
  double worst = 0;
  int checked = 0;
  for (int v = 0; v < 240; v += 7) {
    for (int u = 0; u < 320; u += 7) {
      if (!left.mask().at<std::uint8_t>(v, u)) continue;
      const Eigen::Vector3d p = cam.vehicle_from_camera.t + 10.0 * left.RayVehicle(u, v);
      Eigen::Vector2d omni;
      CHECK(cam.model.Project(cam.vehicle_from_camera.Inverse().Apply(p), &omni));
      const cv::Vec2f m = left.omni_coordinates().at<cv::Vec2f>(v, u);
      worst = std::max(worst, (omni - Eigen::Vector2d(m[0], m[1])).norm());
      ++checked;
    }
  }
  CHECK(checked > 500);
  CHECK(worst < kMapTolPx);
  // Rendering: a view of an omni image whose pixel value encodes its column reproduces the map.
  cv::Mat omni(cam.model.height(), cam.model.width(), CV_32F);
  for (int v = 0; v < omni.rows; ++v) {
    for (int u = 0; u < omni.cols; ++u) omni.at<float>(v, u) = static_cast<float>(u);
  }
  const cv::Mat view = left.Render(omni);
  const cv::Vec2f m = left.omni_coordinates().at<cv::Vec2f>(120, 160);
  CHECK_NEAR(view.at<float>(120, 160), m[0], 0.05);
}

void TestMasksAndSides() {
  const dps::Rig rig = OmniRig();
  const dps::VirtualView side(rig.Camera("left"), dps::SideViewSpec(dps::Side::kLeft, 320, 240, 100.0));
  // The mirror shows 15 degrees above the horizon: 40 degrees up is beyond the rim, 30 down is not.
  const double up = 100.0 * std::tan(40.0 * M_PI / 180.0), down = 100.0 * std::tan(30.0 * M_PI / 180.0);
  CHECK_EQ(int(side.mask().at<std::uint8_t>(cvRound(119.5 - up), 160)), 0);
  CHECK_EQ(int(side.mask().at<std::uint8_t>(cvRound(119.5 + down), 160)), 255);
  // The left side view shows the front on the right of the image, the right side view on the left.
  const dps::VirtualView right_side(rig.Camera("right"), dps::SideViewSpec(dps::Side::kRight, 320, 240, 100.0));
  Eigen::Vector2d a, b;
  CHECK(side.ProjectVehicle({-5, 0, 4}, &a));
  CHECK(right_side.ProjectVehicle({5, 0, 4}, &b));
  CHECK(a.x() > 159.5 && b.x() < 159.5);
  CHECK(a.y() > 119.5);  // the ground is below the horizon
  // A yawed side view: positive yaw turns the view towards the front.
  const dps::ViewSpec yawed = dps::SideViewSpec(dps::Side::kLeft, 320, 240, 100.0, 0.2);
  CHECK_NEAR(yawed.vehicle_from_view.col(2).z(), std::sin(0.2), 1e-12);
  // The cache builds one table per quantised yaw and keeps the recent ones.
  dps::SideViewCache cache(rig.Camera("left"), dps::Side::kLeft, 160, 120, 80.0, 0.01, 2);
  cache.Get(0.0);
  cache.Get(0.004);  // same bin
  CHECK_EQ(cache.builds(), size_t{1});
  cache.Get(0.1);
  cache.Get(0.0);    // still cached
  CHECK_EQ(cache.builds(), size_t{2});
  cache.Get(0.2);    // evicts 0.1
  cache.Get(0.1);
  CHECK_EQ(cache.builds(), size_t{4});
  CHECK_NEAR(cache.Get(0.1).spec().vehicle_from_view.col(2).z(), std::sin(0.1), 1e-12);
}

void TestOffsetOnShiftedTexture() {
  cv::Mat t(240, 320, CV_8U);
  cv::RNG rng(9);
  rng.fill(t, cv::RNG::UNIFORM, 0, 256);
  cv::GaussianBlur(t, t, cv::Size(), 1.5);
  cv::normalize(t, t, 0, 255, cv::NORM_MINMAX);
  for (const double dy : {0.0, 1.3, -2.4}) {
    // right(x, y) = left(x + 7, y - dy): disparity 7, the right view shows things dy lower.
    cv::Mat right;
    cv::warpAffine(t, right, cv::Matx23d(1, 0, 7, 0, 1, -dy), t.size(), cv::INTER_CUBIC | cv::WARP_INVERSE_MAP,
                   cv::BORDER_REFLECT);
    const dps::VerticalOffset off = dps::EstimateVerticalOffset(t, right, 0, 32);
    std::printf("vertical offset %.2f px: estimated %.3f px from %d corners (spread %.3f)\n", dy,
                off.offset_px, off.features, off.spread_px);
    CHECK(off.features >= 20);
    CHECK_NEAR(off.offset_px, dy, kOffsetTolPx);
  }
}

// Front views of a rendered frame; the truth disparity of each left-view pixel from the range
// buffer (nearest omni pixel), NaN where unknown (sky, own car, no ray, depth edges).
struct FrontPair {
  cv::Mat left, right, truth;
  cv::Mat on_object;  // CV_8U, 255 where the truth pixel lies on an object (not the road)
};

FrontPair RenderFrontPair(const dps::Scene& scene, const dps::Rig& rectify_rig, double t_s,
                          const dps::ViewSpec& spec, double right_cy_shift = 0.0) {
  const dps::SceneRenderer renderer(scene);
  const dps::FrameState st = renderer.StateAt(t_s);
  const dps::RenderedView l = renderer.Render(st, 0, 0), r = renderer.Render(st, 1, 0);
  dps::ViewSpec right_spec = spec;
  right_spec.cy += right_cy_shift;
  const dps::VirtualView lv(rectify_rig.Camera("left"), spec), rv(rectify_rig.Camera("right"), right_spec);
  FrontPair p;
  cv::Mat lg, rg;
  cv::cvtColor(l.image, lg, cv::COLOR_BGR2GRAY);
  cv::cvtColor(r.image, rg, cv::COLOR_BGR2GRAY);
  p.left = lv.Render(lg);
  p.right = rv.Render(rg);
  p.truth = cv::Mat(spec.height, spec.width, CV_32F, cv::Scalar(std::nan("")));
  p.on_object = cv::Mat(spec.height, spec.width, CV_8U, cv::Scalar(0));
  const double baseline = (scene.rig.Camera("right").vehicle_from_camera.t -
                           scene.rig.Camera("left").vehicle_from_camera.t).norm();
  for (int v = 0; v < spec.height; ++v) {
    for (int u = 0; u < spec.width; ++u) {
      if (!lv.mask().at<std::uint8_t>(v, u)) continue;
      const cv::Vec2f m = lv.omni_coordinates().at<cv::Vec2f>(v, u);
      const int ou = cvRound(m[0]), ov = cvRound(m[1]);
      const auto id = l.ids.at<std::uint16_t>(ov, ou);
      if (id != dps::kIdGround && id != dps::kIdPaint && id < dps::kIdObjectBase) continue;
      // Skip depth edges: the neighbours must show the same surface (ground and paint are one).
      auto surface = [&](int dv, int du) {
        const auto n = l.ids.at<std::uint16_t>(ov + dv, ou + du);
        return n == dps::kIdPaint ? static_cast<std::uint16_t>(dps::kIdGround) : n;
      };
      bool edge = false;
      for (int dv = -1; dv <= 1; ++dv) {
        for (int du = -1; du <= 1; ++du) edge |= surface(dv, du) != surface(0, 0);
      }
      if (edge) continue;
      const float range = l.range_m.at<float>(ov, ou);
      const Eigen::Vector3d p_vehicle = lv.viewpoint_vehicle() + range * lv.RayVehicle(u, v);
      const double depth = (spec.vehicle_from_view.transpose() * (p_vehicle - lv.viewpoint_vehicle())).z();
      p.truth.at<float>(v, u) = static_cast<float>(spec.focal_px * baseline / depth);
      p.on_object.at<std::uint8_t>(v, u) = id >= dps::kIdObjectBase ? 255 : 0;
    }
  }
  return p;
}

void TestDriftOnRenderedPair() {
  dps::Scene scene = dps_test::SmallScene("parked_cars");
  const dps::ViewSpec spec = dps::FrontViewSpec(scene.rig, "left", "right", 400, 200, 170.0);
  // Rectified with the rig that rendered the images: no offset.
  const FrontPair exact = RenderFrontPair(scene, scene.rig, 0.0, spec);
  if (const char* dump = std::getenv("DPS_TEST_DUMP")) {
    cv::imwrite(std::string(dump) + "/front_left.png", exact.left);
    cv::imwrite(std::string(dump) + "/front_right.png", exact.right);
  }
  const dps::VerticalOffset none = dps::EstimateVerticalOffset(exact.left, exact.right, 0, 64);
  // Rectified with a right camera believed 0.4 degrees pitched: the right view's rows move.
  dps::Rig drifted = scene.rig;
  dps::RigCamera& rc = drifted.cameras[1];
  rc.vehicle_from_camera.R = dps::AxisAngle({1, 0, 0}, 0.4 * M_PI / 180.0) * rc.vehicle_from_camera.R;
  const FrontPair bad = RenderFrontPair(scene, drifted, 0.0, spec);
  const dps::VerticalOffset off = dps::EstimateVerticalOffset(bad.left, bad.right, 0, 64);
  // The expected shift: where the drifted right view puts a point 20 m ahead, minus the truth.
  const double expected = dps_test::DriftedRowShift(scene.rig.Camera("right"), rc, spec, {0, -0.5, 20});
  CHECK(std::isfinite(expected));
  // Compensated: the right view built with cy shifted by the estimate.
  const FrontPair fixed = RenderFrontPair(scene, drifted, 0.0, spec, -off.offset_px);
  const dps::VerticalOffset after = dps::EstimateVerticalOffset(fixed.left, fixed.right, 0, 64);
  std::printf("rendered front pair: offset %.3f px (true rig), %.3f px with 0.4 deg pitch drift "
              "(expected %.3f), %.3f px after compensation; %d/%d/%d corners\n",
              none.offset_px, off.offset_px, expected, after.offset_px, none.features, off.features,
              after.features);
  CHECK(none.features >= 10 && off.features >= 10 && after.features >= 10);
  CHECK_NEAR(none.offset_px, 0.0, kRenderedOffsetTolPx);
  CHECK_NEAR(off.offset_px, expected, kRenderedOffsetTolPx);
  CHECK_NEAR(after.offset_px, 0.0, kRenderedOffsetTolPx);
}

// Scores of one matcher on one class of truth pixels.
struct Tally {
  int known = 0, valid = 0, bad = 0;
  void Add(float d, float truth) {
    ++known;
    valid += std::isfinite(d);
    bad += !std::isfinite(d) || std::abs(d - truth) > kBadThresholdPx;
  }
  double BadRate() const { return known ? double(bad) / known : 1.0; }
  double Density() const { return known ? double(valid) / known : 0.0; }
};

void TestStereoOnRenderedPair() {
  // The obstacles are what front stereo is for: the lead car's back, of nearly constant disparity.
  // The road is reported too; with a 2 m baseline its disparity changes by about 2 px per row
  // near the car, which no block matcher follows (the detection stage compares with the road's
  // own disparity instead, eq. 14).
  dps::Scene scene = dps::ReadScene(kSource + "/data/scenes/lead_car.yaml");
  const int d_count = 64;
  const dps::ViewSpec spec = dps::FrontViewSpec(scene.rig, "left", "right", 400, 200, 170.0);
  Tally ours_obj, bm_obj, ours_road, bm_road;
  for (const double t : {0.0, 1.5, 2.5, 3.0, 4.0}) {
    const FrontPair p = RenderFrontPair(scene, scene.rig, t, spec);
    dps::StereoOptions o;
    o.num_disparities = d_count;
    dps::SadStereoMatcher matcher(o);
    const cv::Mat ours = matcher.Compute(p.left, p.right);
    cv::Mat d16, bm;
    cv::StereoBM::create(d_count, 9)->compute(p.left, p.right, d16);
    d16.convertTo(bm, CV_32F, 1.0 / 16);
    bm.setTo(dps::kInvalidDisparity, d16 < 0);
    for (int v = 0; v < spec.height; ++v) {
      for (int u = d_count + 5; u < spec.width - 5; ++u) {
        const float g = p.truth.at<float>(v, u);
        if (std::isnan(g) || g >= d_count - 1) continue;
        const bool object = p.on_object.at<std::uint8_t>(v, u) != 0;
        (object ? ours_obj : ours_road).Add(ours.at<float>(v, u), g);
        (object ? bm_obj : bm_road).Add(bm.at<float>(v, u), g);
      }
    }
  }
  std::printf("rendered front pair (lead_car, 640x480 omni, 400x200 view, D=%d, 5 frames):\n"
              "  obstacles: %d px; dps bad %.4f density %.3f | StereoBM bad %.4f density %.3f\n"
              "  road:      %d px; dps bad %.4f density %.3f | StereoBM bad %.4f density %.3f\n",
              d_count, ours_obj.known, ours_obj.BadRate(), ours_obj.Density(), bm_obj.BadRate(),
              bm_obj.Density(), ours_road.known, ours_road.BadRate(), ours_road.Density(),
              bm_road.BadRate(), bm_road.Density());
  CHECK(ours_obj.known > 1500);
  CHECK(ours_obj.BadRate() <= bm_obj.BadRate());
}

}  // namespace

int main() {
  TestFrontGeometry();
  TestMasksAndSides();
  TestOffsetOnShiftedTexture();
  TestDriftOnRenderedPair();
  TestStereoOnRenderedPair();
  return dps_test::Report();
}
