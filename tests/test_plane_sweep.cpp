// Plane-sweep motion stereo on raw omni images (stereo/plane_sweep.h) against the renderer's
// truth: two consecutive frames of the parked-cars drive, the camera's motion from the scene's
// ego profile. The distances of the parked cars beside and behind the car, the road as free space,
// the motion's epipoles said to be unobservable, and bad inputs refused.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "check.h"
#include "dps/stereo/plane_sweep.h"
#include "dps/synth/scene_renderer.h"
#include "dps/util/error.h"
#include "dps/util/image.h"
#include "fixtures.h"

namespace {

constexpr double kMaxMedianDistanceError = 0.05;  // the project's range-error target
constexpr double kMaxRoadAsObstacle = 0.05;       // road pixels called obstacles, at most

double Median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

struct Frames {
  dps::SweepResult sweep;
  dps::RenderedView truth;
  dps::FrameState state;
};

// Frames k - gap and k of `scene` seen by camera `camera`, swept.
Frames Sweep(const dps::Scene& scene, size_t camera, int k, int gap, const dps::PlaneSweepOptions& o = {}) {
  const dps::SceneRenderer renderer(scene);
  const dps::FrameState before = renderer.StateAt(scene.FrameTime(k - gap));
  Frames f;
  f.state = renderer.StateAt(scene.FrameTime(k));
  const dps::RenderedView previous = renderer.Render(before, camera, k - gap);
  f.truth = renderer.Render(f.state, camera, k);
  const dps::Pose previous_from_current = before.world_from_vehicle.Inverse() * f.state.world_from_vehicle;
  const dps::RigCamera& cam = scene.rig.cameras[camera];
  f.sweep = dps::PlaneSweep(cam.model, cam.vehicle_from_camera, dps::GreyImage(previous.image),
                            dps::GreyImage(f.truth.image), previous_from_current, cv::Mat(), o);
  return f;
}

struct Scores {
  std::vector<double> errors;  // relative distance errors of object pixels called obstacles
  int objects = 0, covered = 0, road = 0, road_as_obstacle = 0;
};

// Object pixels within `max_range_m` whose truth point lies in [z_min, z_max] along the vehicle,
// and road pixels within the same range.
Scores Score(const Frames& f, const dps::Scene& scene, size_t camera, double max_range_m, double z_min, double z_max) {
  Scores s;
  const dps::RigCamera& cam = scene.rig.cameras[camera];
  for (int v = 0; v < f.truth.ids.rows; ++v) {
    for (int u = 0; u < f.truth.ids.cols; ++u) {
      const std::uint16_t id = f.truth.ids.at<std::uint16_t>(v, u);
      const double range = f.truth.range_m.at<float>(v, u);
      const std::uint8_t label = f.sweep.label.at<std::uint8_t>(v, u);
      if (range <= 0 || range > max_range_m || label == dps::kSweepUnobservable || label == dps::kSweepNoRay) continue;
      Eigen::Vector3d ray;
      if (!cam.model.Unproject({u, v}, &ray)) continue;
      const Eigen::Vector3d p = cam.vehicle_from_camera.Apply(range * ray);
      if (p.z() < z_min || p.z() > z_max) continue;
      if (id == dps::kIdGround || id == dps::kIdPaint) {
        if (label == dps::kSweepRoad || label == dps::kSweepObstacle) ++s.road;
        if (label == dps::kSweepObstacle) ++s.road_as_obstacle;
      } else if (id >= dps::kIdObjectBase) {
        ++s.objects;
        if (label != dps::kSweepObstacle) continue;
        ++s.covered;
        s.errors.push_back(std::abs(f.sweep.distance_m.at<float>(v, u) - range) / range);
      }
    }
  }
  return s;
}

void Report(const char* what, const Scores& s) {
  std::printf("%s: %d object pixels, %d (%.2f) with a distance, median error %.3f; road %d, %.3f called obstacle\n", what,
              s.objects, s.covered, s.objects ? double(s.covered) / s.objects : 0.0, Median(s.errors), s.road,
              s.road ? double(s.road_as_obstacle) / s.road : 0.0);
}

void TestParkedCars() {
  const dps::Scene scene = dps_test::SmallScene("parked_cars", 320, 240);
  const size_t right = scene.rig.cameras[0].name == "right" ? 0 : 1;
  const double half_length = scene.rig.vehicle.length_m / 2;
  // Early: the parked cars beside and ahead; late: the first ones behind the car. Beside, the
  // previous frame gives parallax enough; behind, near the epipole, the frame three back does.
  for (const int k : {8, 36}) {
    const Frames f = Sweep(scene, right, k, 1);
    const Scores side = Score(f, scene, right, 12.0, -half_length, half_length);
    std::printf("frame %d against %d\n", k, k - 1);
    Report("  beside", side);
    CHECK(side.objects > 300);
    CHECK(Median(side.errors) <= kMaxMedianDistanceError);
    CHECK(side.road > 1000);
    CHECK(side.road_as_obstacle <= kMaxRoadAsObstacle * side.road);
    // Straight ahead and straight behind (the motion's epipoles, the car driving straight): no
    // distance can be measured there, and the sweep says so.
    const dps::RigCamera& cam = scene.rig.cameras[right];
    for (const double z : {30.0, -30.0}) {
      Eigen::Vector2d px;
      const Eigen::Vector3d point(cam.vehicle_from_camera.t.x(), cam.vehicle_from_camera.t.y(), z);
      CHECK(cam.model.Project(cam.vehicle_from_camera.Inverse().Apply(point), &px));
      const std::uint8_t label = f.sweep.label.at<std::uint8_t>(static_cast<int>(std::lround(px.y())),
                                                               static_cast<int>(std::lround(px.x())));
      CHECK_EQ(int{label}, int{dps::kSweepUnobservable});
    }
  }
  const Frames late = Sweep(scene, right, 36, 3);
  const Scores rear = Score(late, scene, right, 12.0, -100.0, -half_length);
  std::printf("frame 36 against 33\n");
  Report("  behind", rear);
  CHECK(rear.objects > 300);
  CHECK(Median(rear.errors) <= kMaxMedianDistanceError);
  // Short of kMaxRoadAsObstacle behind (docs/stereo.md): road next to the parked cars' ends, where
  // the window straddles the car, is called obstacle; printed, not asserted.
}

// Two earlier frames at once (33 and 31 against 36): the distances behind the car hold; and a
// region limits the work to its pixels without changing what they get.
void TestSeveralFramesAndRegion() {
  const dps::Scene scene = dps_test::SmallScene("parked_cars", 320, 240);
  const size_t right = scene.rig.cameras[0].name == "right" ? 0 : 1;
  const dps::RigCamera& cam = scene.rig.cameras[right];
  const dps::SceneRenderer renderer(scene);
  const dps::FrameState now = renderer.StateAt(scene.FrameTime(36));
  std::vector<dps::EarlierFrame> earlier;
  for (const int k : {33, 31}) {
    const dps::FrameState st = renderer.StateAt(scene.FrameTime(k));
    earlier.push_back({dps::GreyImage(renderer.Render(st, right, k).image),
                       st.world_from_vehicle.Inverse() * now.world_from_vehicle});
  }
  Frames f;
  f.truth = renderer.Render(now, right, 36);
  const cv::Mat current = dps::GreyImage(f.truth.image);
  f.sweep = dps::PlaneSweeper(cam.model, cam.vehicle_from_camera, cv::Mat(), cv::Mat()).Sweep(earlier, current);
  const Scores rear = Score(f, scene, right, 12.0, -100.0, -scene.rig.vehicle.length_m / 2);
  std::printf("frame 36 against 33 and 31\n");
  Report("  behind", rear);
  CHECK(rear.objects > 300);
  CHECK(Median(rear.errors) <= kMaxMedianDistanceError);
  // The left half of the image only: the same labels there, nothing elsewhere.
  cv::Mat region(current.size(), CV_8U, cv::Scalar(0));
  region(cv::Rect(0, 0, current.cols / 2, current.rows)).setTo(255);
  const dps::SweepResult part =
      dps::PlaneSweeper(cam.model, cam.vehicle_from_camera, cv::Mat(), region).Sweep(earlier, current);
  const cv::Mat outside = region == 0;
  CHECK_EQ(cv::countNonZero((part.label != dps::kSweepNoRay) & outside), 0);
  CHECK_EQ(cv::countNonZero((part.label != f.sweep.label) & region), 0);
}

void TestBadInputs() {
  const dps::Scene scene = dps_test::SmallScene("parked_cars", 320, 240);
  const dps::RigCamera& cam = scene.rig.cameras[0];
  const cv::Mat grey(240, 320, CV_8U, cv::Scalar(0)), small(120, 160, CV_8U, cv::Scalar(0));
  CHECK_THROWS_WITH(dps::PlaneSweep(cam.model, cam.vehicle_from_camera, small, grey, dps::Pose(), cv::Mat()),
                    dps::Error, "camera's size");
  dps::PlaneSweepOptions o;
  o.window_px = 4;
  CHECK_THROWS_WITH(dps::PlaneSweep(cam.model, cam.vehicle_from_camera, grey, grey, dps::Pose(), cv::Mat(), o),
                    dps::Error, "window_px");
}

}  // namespace

// The picture of a sweep: each label's colour where the label says, an obstacle's colour by its
// distance (turbo: red near, blue far, even in inverse distance), the legend in the corner.
void TestPicture() {
  const cv::Mat image(120, 400, CV_8U, cv::Scalar(100));
  dps::SweepResult sweep;
  sweep.label = cv::Mat(image.size(), CV_8U, cv::Scalar(dps::kSweepNoRay));
  sweep.distance_m = cv::Mat(image.size(), CV_32F, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  sweep.score = sweep.distance_m.clone();
  const cv::Point near(300, 100), far(310, 100), middle(320, 100), road(330, 100), epipole(340, 100), none(350, 100);
  for (const cv::Point& p : {near, far, middle}) sweep.label.at<std::uint8_t>(p) = dps::kSweepObstacle;
  sweep.distance_m.at<float>(near) = 1.0f;
  sweep.distance_m.at<float>(far) = 40.0f;
  sweep.distance_m.at<float>(middle) = 2.0f;  // inverse distance halfway between 1 m and infinity
  sweep.label.at<std::uint8_t>(road) = dps::kSweepRoad;
  sweep.label.at<std::uint8_t>(epipole) = dps::kSweepUnobservable;
  sweep.label.at<std::uint8_t>(none) = dps::kSweepAmbiguous;
  const cv::Mat picture = dps::SweepPicture(image, sweep, 1.0, 40.0);
  CHECK_EQ(picture.type(), CV_8UC3);
  CHECK(picture.size() == image.size());
  cv::Mat ramp(1, 256, CV_8U), turbo;
  for (int i = 0; i < 256; ++i) ramp.at<std::uint8_t>(0, i) = static_cast<std::uint8_t>(i);
  cv::applyColorMap(ramp, turbo, cv::COLORMAP_TURBO);
  CHECK(picture.at<cv::Vec3b>(near) == turbo.at<cv::Vec3b>(0, 255));
  CHECK(picture.at<cv::Vec3b>(far) == turbo.at<cv::Vec3b>(0, 0));
  // 1/2 m between 1/1 and 1/40: (0.5 - 0.025) / (1 - 0.025) of the ramp.
  CHECK(picture.at<cv::Vec3b>(middle) == turbo.at<cv::Vec3b>(0, static_cast<int>(std::lround(255 * 0.475 / 0.975))));
  const cv::Vec3b r = picture.at<cv::Vec3b>(road), e = picture.at<cv::Vec3b>(epipole);
  CHECK(r[1] > r[0] + 50 && r[1] > r[2] + 50);                      // green
  CHECK(e[0] > e[1] + 50 && e[2] > e[1] + 50);                      // magenta
  CHECK(picture.at<cv::Vec3b>(none) == cv::Vec3b(100, 100, 100));  // the image
  CHECK(picture.at<cv::Vec3b>(119, 399) == cv::Vec3b(0, 0, 0));    // no ray
  CHECK(picture.at<cv::Vec3b>(2, 2) != cv::Vec3b(0, 0, 0));        // the legend
  CHECK_THROWS_WITH(dps::SweepPicture(image, sweep, 40.0, 1.0), dps::Error, "expected 0 < min < max");
}

int main() {
  TestPicture();
  TestParkedCars();
  TestSeveralFramesAndRegion();
  TestBadInputs();
  return dps_test::Report();
}
