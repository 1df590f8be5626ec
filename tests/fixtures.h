// dps — set-up the tests share: the source tree's data, the shipped rig, small renders of the
// shipped scenes and their frames as the pipeline takes them, scratch folders, and what geometry
// predicts for a drifted camera.
#pragma once

#include <cmath>
#include <filesystem>
#include <string>

#include <Eigen/Core>

#include "dps/camera/rig_io.h"
#include "dps/pipeline/surround_pipeline.h"
#include "dps/stereo/virtual_view.h"
#include "dps/synth/scene_io.h"
#include "dps/synth/scene_renderer.h"

namespace dps_test {

// The source tree (data/, docs/) and the real data the tests score against.
inline const std::string kSource = DPS_SOURCE_DIR;
inline const std::string kRealData = DPS_REAL_DATA_DIR;

// The shipped omni rig (data/rigs/omni_pair.yaml).
inline dps::Rig OmniRig() { return dps::ReadRig(kSource + "/data/rigs/omni_pair.yaml"); }

// A shipped scene (data/scenes/<name>.yaml), resized to width x height when given, rendered
// without supersampling (fast).
inline dps::Scene SmallScene(const std::string& name, int width = 0, int height = 0) {
  dps::Scene scene = dps::ReadScene(kSource + "/data/scenes/" + name + ".yaml");
  if (width > 0 && height > 0) dps::ResizeScene(&scene, width, height);
  scene.render.supersample = 1;
  return scene;
}

// Frame f of a rendered scene (its state `state`) as the pipeline takes it: the images of the rig's
// cameras `left` and `right` (indices) and the ego motion since the previous frame (none for the
// first).
inline dps::FrameInput RenderedInput(const dps::Scene& scene, const dps::SceneRenderer& renderer,
                                     const dps::FrameState& state, int f, int left = 0, int right = 1) {
  dps::FrameInput in;
  in.frame = f;
  in.t_s = scene.FrameTime(f);
  in.left = renderer.Render(state, left, f).image;
  in.right = renderer.Render(state, right, f).image;
  in.motion_known = f > 0;
  if (f > 0) in.current_in_previous = scene.ego.Integrate(dps::PlanarPose{}, scene.FrameTime(f - 1), in.t_s);
  return in;
}

// An empty folder of this name under the system's temporary folder.
inline std::filesystem::path ScratchDir(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// The rows by which a view built for camera `drifted` (believed turned) shows a vehicle-frame
// point, minus the rows where a view of the true camera shows it: the vertical offset a drifted
// front pair has, from geometry alone. NaN when a view does not see the point.
inline double DriftedRowShift(const dps::RigCamera& truth, const dps::RigCamera& drifted, const dps::ViewSpec& spec,
                              const Eigen::Vector3d& point) {
  const dps::VirtualView true_view(truth, spec), drifted_view(drifted, spec);
  // Where the drifted camera's model believes the point is: the true camera's ray, turned.
  const Eigen::Vector3d seen = drifted.vehicle_from_camera.R * truth.vehicle_from_camera.R.transpose() *
                                   (point - truth.vehicle_from_camera.t) + truth.vehicle_from_camera.t;
  Eigen::Vector2d a, b;
  if (!true_view.ProjectVehicle(point, &a) || !drifted_view.ProjectVehicle(seen, &b)) return std::nan("");
  return b.y() - a.y();
}

}  // namespace dps_test
