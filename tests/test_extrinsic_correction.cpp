// Online extrinsic correction (calib/extrinsic_correction.h) against the renderer's truth: the
// first second of the parked-cars drive (parked cars beside the road: features off the road
// plane) seen by cameras whose rotation in the rig is off by half a degree, corrected back to the
// rendering rig; the rendering rig left where it is; no estimate without motion; bad inputs.
#include <cmath>
#include <vector>

#include <Eigen/Geometry>

#include "check.h"
#include "dps/calib/extrinsic_correction.h"
#include "dps/synth/scene_renderer.h"
#include "dps/util/error.h"
#include "fixtures.h"

namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

// The angle between two rotations, degrees.
double AngleDeg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a * b.transpose()).angle() / kDeg;
}

struct Drive {
  dps::Scene scene;
  std::vector<std::vector<cv::Mat>> frames;  // by camera
  std::vector<dps::PlanarPose> poses;        // in frame 0's vehicle frame
};

// The scene's first second as the cameras see it, and the vehicle's poses.
Drive FirstSecond(const std::string& name) {
  Drive d{dps_test::SmallScene(name), {}, {}};
  const dps::SceneRenderer renderer(d.scene);
  d.frames.resize(d.scene.rig.cameras.size());
  const dps::FrameState first = renderer.StateAt(d.scene.FrameTime(0));
  for (int k = 0; d.scene.FrameTime(k) <= 1.0; ++k) {
    const dps::FrameState state = renderer.StateAt(d.scene.FrameTime(k));
    const Eigen::Vector2d at = dps::WorldToBody(first.ego, {state.ego.x_m, state.ego.z_m});
    d.poses.push_back({at.x(), at.y(), state.ego.heading_rad - first.ego.heading_rad});
    for (size_t c = 0; c < d.scene.rig.cameras.size(); ++c) d.frames[c].push_back(renderer.Render(state, c, k).image);
  }
  return d;
}

void TestCorrectsTurnedCameras(const Drive& d) {
  // Half a degree about an axis that mixes pitch, yaw and roll.
  const Eigen::Matrix3d error = dps::AxisAngle(Eigen::Vector3d(1, -1, 1).normalized(), 0.5 * kDeg);
  for (size_t c = 0; c < d.scene.rig.cameras.size(); ++c) {
    const dps::RigCamera& truth = d.scene.rig.cameras[c];
    dps::RigCamera believed = truth;
    believed.vehicle_from_camera.R = error * truth.vehicle_from_camera.R;
    const dps::ExtrinsicCorrection e = dps::EstimateExtrinsicCorrection(d.frames[c], d.poses, believed, d.scene.rig.vehicle);
    CHECK(e.applied);
    CHECK_EQ(e.camera, truth.name);
    CHECK(e.tracks >= 200);
    CHECK(e.rms_px < e.rms_before_px);
    const dps::RigCamera corrected = dps::CorrectedCamera(believed, e);
    // Corrected to a tenth of the error or better; the standard error says how well.
    const double left = AngleDeg(corrected.vehicle_from_camera.R, truth.vehicle_from_camera.R);
    CHECK(left < 0.05);
    CHECK(e.sigma_deg.maxCoeff() < 0.05);
    std::printf("%s: 0.5 deg off -> %.3f deg (estimate %.3f %.3f %.3f deg, sigma %.3f, %d tracks, %.2f -> %.2f px)\n",
                truth.name.c_str(), left, e.rotation_deg.x(), e.rotation_deg.y(), e.rotation_deg.z(), e.sigma_deg.maxCoeff(),
                e.tracks, e.rms_before_px, e.rms_px);
  }
}

void TestLeavesTheTrueRig(const Drive& d) {
  for (size_t c = 0; c < d.scene.rig.cameras.size(); ++c) {
    const dps::ExtrinsicCorrection e =
        dps::EstimateExtrinsicCorrection(d.frames[c], d.poses, d.scene.rig.cameras[c], d.scene.rig.vehicle);
    CHECK(e.applied);
    CHECK(e.rotation_deg.norm() < 0.05);
  }
}

void TestNoMotion(const Drive& d) {
  // The car standing: the road does not move, nothing tells the rotation.
  const std::vector<dps::PlanarPose> standing(d.poses.size());
  const dps::ExtrinsicCorrection e =
      dps::EstimateExtrinsicCorrection(d.frames[0], standing, d.scene.rig.cameras[0], d.scene.rig.vehicle);
  CHECK(!e.applied);
  CHECK(e.reason.find("frame pairs") != std::string::npos);
  CHECK_EQ(e.rotation_deg.norm(), 0.0);
  const dps::RigCamera same = dps::CorrectedCamera(d.scene.rig.cameras[0], e);
  CHECK(AngleDeg(same.vehicle_from_camera.R, d.scene.rig.cameras[0].vehicle_from_camera.R) < 1e-9);
}

void TestBadInputs(const Drive& d) {
  std::vector<dps::PlanarPose> fewer(d.poses.begin(), d.poses.end() - 1);
  CHECK_THROWS_WITH(dps::EstimateExtrinsicCorrection(d.frames[0], fewer, d.scene.rig.cameras[0], d.scene.rig.vehicle),
                    dps::Error, "poses");
  dps::ExtrinsicCorrectionOptions o;
  o.min_isotropy = 0.0;
  CHECK_THROWS_WITH(o.Check(), dps::Error, "min_isotropy");
  o = {};
  o.max_distance_m = o.min_distance_m;
  CHECK_THROWS_WITH(o.Check(), dps::Error, "max_distance_m");
}

}  // namespace

int main() {
  const Drive d = FirstSecond("parked_cars");
  TestCorrectsTurnedCameras(d);
  TestLeavesTheTrueRig(d);
  TestNoMotion(d);
  TestBadInputs(d);
  return dps_test::Report();
}
