// dps-bench: times dps's stereo matcher against cv::StereoBM on the same pairs in the same run
// (same disparity range and block size), with and without the left-right check, the virtual
// view rectification, and the whole per-frame pipeline (what dps-process does between decoding
// the images and encoding the map) against one StereoBM call at the same omni size, and the plane
// sweep (one camera, one earlier frame) beside a plain SAD cost volume of the same size, and the
// masks estimated once per drive. Prints Markdown tables for docs/performance.md.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <thread>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "dps/camera/rig_io.h"
#include "dps/camera/valid_mask.h"
#include "dps/map/occupancy_grid.h"
#include "dps/map/surround_map.h"
#include "dps/map/tracker.h"
#include "dps/pipeline/surround_pipeline.h"
#include "dps/stereo/plane_sweep.h"
#include "dps/stereo/sad_stereo.h"
#include "dps/stereo/virtual_view.h"
#include "dps/synth/scene_io.h"
#include "dps/synth/scene_renderer.h"

namespace {

// Median wall times (ms) of `runs` calls of a and b, interleaved (a, b, a, b, ...) so that both
// see the same machine load; one warm-up call each first.
std::pair<double, double> MedianMs(int runs, const std::function<void()>& a, const std::function<void()>& b) {
  a();
  b();
  std::vector<double> ta, tb;
  auto time = [](const std::function<void()>& f) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  };
  for (int i = 0; i < runs; ++i) {
    ta.push_back(time(a));
    tb.push_back(time(b));
  }
  std::sort(ta.begin(), ta.end());
  std::sort(tb.begin(), tb.end());
  return {ta[ta.size() / 2], tb[tb.size() / 2]};
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args;
  bool baseline_kernel = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::printf("usage: dps-bench [--baseline-kernel] [DATA_DIR [RIG [SCENE]]]   (DATA_DIR holds kitti_pair/,\n"
                  "       default data/real; RIG for the view timing, default data/rigs/omni_pair.yaml; SCENE\n"
                  "       for the pipeline, default data/scenes/lead_car.yaml; run from the source)\n"
                  "  --baseline-kernel   dps's matcher with its baseline instruction-set kernel, not AVX2\n");
      return 0;
    }
    if (a == "--baseline-kernel") {
      baseline_kernel = true;
    } else {
      args.push_back(a);
    }
  }
  const std::string data = args.size() > 0 ? args[0] : "data/real";
  const cv::Mat left = cv::imread(data + "/kitti_pair/imgKittyl.bmp", cv::IMREAD_GRAYSCALE);
  const cv::Mat right = cv::imread(data + "/kitti_pair/imgKitty.bmp", cv::IMREAD_GRAYSCALE);
  if (left.empty() || right.empty()) {
    std::fprintf(stderr, "dps-bench: error: cannot read %s/kitti_pair/imgKitty[l].bmp\n", data.c_str());
    return 1;
  }
  const int runs = 31;
  std::printf("OpenCV %s, %d threads, %u hardware threads; median of %d runs\n\n", CV_VERSION,
              cv::getNumThreads(), std::thread::hardware_concurrency(), runs);
  std::printf("| size | D | block | LR check | dps levels | dps ms | StereoBM ms | ratio dps/BM |\n");
  std::printf("| --- | --- | --- | --- | --- | --- | --- | --- |\n");
  struct Case { int w, h, d; };
  for (const Case c : {Case{320, 240, 64}, Case{640, 480, 64}, Case{1024, 768, 128}}) {
    cv::Mat l, r;
    cv::resize(left, l, cv::Size(c.w, c.h), 0, 0, cv::INTER_AREA);
    cv::resize(right, r, cv::Size(c.w, c.h), 0, 0, cv::INTER_AREA);
    for (const auto& [lr, levels] : {std::pair{false, 2}, std::pair{true, 2}, std::pair{true, 1}}) {
      dps::StereoOptions o;
      o.num_disparities = c.d;
      o.left_right_check = lr;
      o.two_levels = levels == 2;
      o.baseline_kernel = baseline_kernel;
      dps::SadStereoMatcher matcher(o);
      auto bm = cv::StereoBM::create(c.d, 9);
      bm->setDisp12MaxDiff(lr ? 1 : -1);
      cv::Mat out;
      const auto [dps_ms, bm_ms] = MedianMs(runs, [&] { matcher.Compute(l, r); }, [&] { bm->compute(l, r, out); });
      std::printf("| %dx%d | %d | 9 | %s | %d | %.2f | %.2f | %.2f |\n", c.w, c.h, c.d, lr ? "yes" : "no",
                  levels, dps_ms, bm_ms, dps_ms / bm_ms);
    }
  }

  // View rectification: one cv::remap per view from the omni image (tables built once per rig).
  const std::string rig_path = args.size() > 1 ? args[1] : "data/rigs/omni_pair.yaml";
  const dps::Rig rig = dps::ReadRig(rig_path);
  std::printf("\n| omni size | view | view size | remap ms | table build ms |\n| --- | --- | --- | --- | --- |\n");
  for (const int scale : {1, 2}) {
    const int ow = 640 / scale, oh = 480 / scale;
    dps::Rig r = rig;
    for (dps::RigCamera& c : r.cameras) c.model = dps::ResizeCameraModel(c.model, ow, oh);
    cv::Mat omni;
    cv::resize(left, omni, cv::Size(ow, oh));
    struct View { const char* name; dps::ViewSpec spec; const char* camera; };
    const int vw = 400 / scale, vh = 200 / scale;
    const double f = 170.0 / scale;
    for (const View& v : {View{"front", dps::FrontViewSpec(r, "left", "right", vw, vh, f), "left"},
                          View{"side", dps::SideViewSpec(dps::Side::kLeft, vw, vh, f), "left"}}) {
      std::unique_ptr<dps::VirtualView> view;
      cv::Mat out;
      const auto [build_ms, remap_ms] = MedianMs(
          9, [&] { view = std::make_unique<dps::VirtualView>(r.Camera(v.camera), v.spec); },
          [&] { view->Render(omni, out); });
      std::printf("| %dx%d | %s | %dx%d | %.3f | %.2f |\n", ow, oh, v.name, vw, vh, remap_ms, build_ms);
    }
  }

  // The whole pipeline per frame: lead_car rendered at each omni size (20 frames, run once to warm
  // up and once timed), front stereo, both side motion stereos, histograms, fusion, tracking, the
  // occupancy grid and the map picture; each frame interleaved with one cv::StereoBM call (D 64,
  // block 9) on the KITTI pair resized to the omni size.
  const std::string scene_path = args.size() > 2 ? args[2] : "data/scenes/lead_car.yaml";
  std::printf("\n| omni size | views | front ms | sides ms | lanes ms | fusion ms | tracks ms | grid ms | picture ms | frame ms | frames/s | StereoBM ms | frame / BM |\n"
              "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n");
  for (const auto& [ow, oh] : {std::pair{320, 240}, std::pair{640, 480}, std::pair{1024, 1024}}) {
    dps::Scene scene = dps::ReadScene(scene_path);
    dps::ResizeScene(&scene, ow, oh);
    scene.render.supersample = 1;
    const dps::SceneRenderer renderer(scene);
    const int frames = 20;
    std::vector<dps::FrameInput> inputs;
    for (int f = 0; f < frames; ++f) {
      const dps::FrameState st = renderer.StateAt(scene.FrameTime(f));
      dps::FrameInput in;
      in.frame = f;
      in.t_s = scene.FrameTime(f);
      in.left = renderer.Render(st, 0, f).image;
      in.right = renderer.Render(st, 1, f).image;
      in.motion_known = f > 0;
      in.current_in_previous = scene.ego.Integrate(dps::PlanarPose{}, scene.FrameTime(std::max(0, f - 1)), in.t_s);
      inputs.push_back(in);
    }
    dps::PipelineOptions po = dps::DefaultPipelineOptions(scene.rig);
    po.front.stereo.baseline_kernel = po.side.stereo.baseline_kernel = baseline_kernel;
    dps::SurroundPipeline pipeline(scene.rig, po);
    dps::Tracker tracker;
    dps::OccupancyGrid grid;
    const dps::MapOptions mo;
    const cv::Mat background = dps::DrawMapBackground(scene.rig.vehicle, pipeline.coverage(), mo);
    cv::Mat l, r, bm_out;
    cv::resize(left, l, cv::Size(ow, oh), 0, 0, cv::INTER_AREA);
    cv::resize(right, r, cv::Size(ow, oh), 0, 0, cv::INTER_AREA);
    auto bm = cv::StereoBM::create(64, 9);
    std::vector<double> front, sides, lanes, fusion, tracking, gridding, drawing, whole, bm_ms;
    dps::PlanarPose ego;
    const auto span = [](auto a, auto b) { return std::chrono::duration<double, std::milli>(b - a).count(); };
    // As dps-process: a frame's tracking, grid and picture run alongside the next frame's stereo.
    dps::FrameOutput pending;
    int pending_frame = -1;
    double track_ms = 0, grid_ms = 0, picture_ms = 0;
    cv::Mat picture;  // as dps-process: one buffer for every frame's picture
    const auto finish = [&] {
      const dps::FrameInput& in = inputs[pending_frame % frames];
      const auto t0 = std::chrono::steady_clock::now();
      ego = dps::Compose(ego, in.current_in_previous);
      const double t_s = in.t_s + (pending_frame / frames) * 10.0;  // the drive repeated, time going on
      const std::vector<dps::TrackState> tracks = tracker.Update(pending_frame, t_s, ego, pending.detections);
      const auto t1 = std::chrono::steady_clock::now();
      grid.Update(t_s, ego, pending.coverage, pending.detections);
      const auto t2 = std::chrono::steady_clock::now();
      dps::DrawFrameMap(background, grid, scene.rig.vehicle, pending.detections, tracks, mo, "bench", picture);
      const auto t3 = std::chrono::steady_clock::now();
      track_ms = span(t0, t1);
      grid_ms = span(t1, t2);
      picture_ms = span(t2, t3);
    };
    for (int pass = 0; pass < 2; ++pass) {
      for (const dps::FrameInput& in : inputs) {
        const auto t0 = std::chrono::steady_clock::now();
        dps::FrameOutput out = pipeline.Process(in, pending_frame >= 0 ? std::vector<std::function<void()>>{finish}
                                                                         : std::vector<std::function<void()>>{});
        const auto tp = std::chrono::steady_clock::now();
        const double ms = span(t0, tp);
        const auto t1 = std::chrono::steady_clock::now();
        bm->compute(l, r, bm_out);
        const double bms = span(t1, std::chrono::steady_clock::now());
        const bool timed = pass == 1 && pending_frame >= frames;  // the previous frame's work is in this pass
        pending = std::move(out);
        pending_frame = in.frame + pass * frames;
        if (!timed) continue;
        front.push_back(pending.front_ms);
        sides.push_back(pending.sides_ms);
        lanes.push_back(pending.lanes_ms);
        fusion.push_back(ms - pending.detect_ms);
        tracking.push_back(track_ms);
        gridding.push_back(grid_ms);
        drawing.push_back(picture_ms);
        whole.push_back(ms);
        bm_ms.push_back(bms);
      }
    }
    auto median = [](std::vector<double> v) {
      std::sort(v.begin(), v.end());
      return v[v.size() / 2];
    };
    const double frame_ms = median(whole), bm_median = median(bm_ms);
    std::printf("| %dx%d | %dx%d, D %d | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.0f | %.2f | %.2f |\n", ow, oh,
                po.front.view_width, po.front.view_height, po.front.stereo.num_disparities, median(front), median(sides),
                median(lanes), median(fusion), median(tracking), median(gridding), median(drawing), frame_ms, 1000.0 / frame_ms, bm_median,
                frame_ms / bm_median);
  }

  // The plane sweep on one camera's raw omni images (its rays built once), frame 1 against frame
  // 0 of the scene, its 48 distances and the road, 7x7 ZNCC windows; beside dps's matcher as a
  // plain SAD cost volume of the same size (the same two images, 48 disparities, 7x7, one level,
  // no left-right check).
  std::printf("\n| omni size | sweep ms | ns per pixel and surface | SAD volume ms (D 48) | ns per pixel and disparity | sweep / SAD |\n"
              "| --- | --- | --- | --- | --- | --- |\n");
  for (const auto& [ow, oh] : {std::pair{320, 240}, std::pair{640, 480}}) {
    dps::Scene scene = dps::ReadScene(scene_path);
    dps::ResizeScene(&scene, ow, oh);
    scene.render.supersample = 1;
    const dps::SceneRenderer renderer(scene);
    const dps::FrameState a = renderer.StateAt(scene.FrameTime(0)), b = renderer.StateAt(scene.FrameTime(1));
    cv::Mat previous, current;
    cv::cvtColor(renderer.Render(a, 0, 0).image, previous, cv::COLOR_BGR2GRAY);
    cv::cvtColor(renderer.Render(b, 0, 1).image, current, cv::COLOR_BGR2GRAY);
    const dps::RigCamera& cam = scene.rig.cameras[0];
    const dps::PlaneSweepOptions so;
    const dps::PlaneSweeper sweeper(cam.model, cam.vehicle_from_camera, cv::Mat(), cv::Mat(), so);
    const dps::Pose motion = a.world_from_vehicle.Inverse() * b.world_from_vehicle;
    dps::StereoOptions st;
    st.num_disparities = 48;
    st.block_width = st.block_height = 7;
    st.two_levels = false;
    st.left_right_check = false;
    st.baseline_kernel = baseline_kernel;
    dps::SadStereoMatcher matcher(st);
    const auto [sweep_ms, sad_ms] =
        MedianMs(7, [&] { sweeper.Sweep(previous, current, motion); }, [&] { matcher.Compute(current, previous); });
    const double pixels = static_cast<double>(ow) * oh, surfaces = so.distances + 1;
    std::printf("| %dx%d | %.1f | %.1f | %.2f | %.2f | %.0f |\n", ow, oh, sweep_ms, 1e6 * sweep_ms / (pixels * surfaces),
                sad_ms, 1e6 * sad_ms / (pixels * st.num_disparities), sweep_ms / sad_ms);
  }

  // The masks dps-process estimates once per camera and drive from the first two seconds (every
  // frame of them, as it does): the field's edge and the own car.
  std::printf("\n| omni size | frames | field mask ms | own car ms |\n| --- | --- | --- | --- |\n");
  for (const auto& [ow, oh] : {std::pair{320, 240}, std::pair{640, 480}}) {
    dps::Scene scene = dps::ReadScene(scene_path);
    dps::ResizeScene(&scene, ow, oh);
    scene.render.supersample = 1;
    const dps::SceneRenderer renderer(scene);
    std::vector<cv::Mat> frames;
    for (int f = 0; f < scene.FrameCount() && scene.FrameTime(f) <= 2.0; ++f) {
      frames.push_back(renderer.Render(renderer.StateAt(scene.FrameTime(f)), 0, f).image);
    }
    const dps::FrameState first = renderer.StateAt(0.0), last = renderer.StateAt(scene.FrameTime(static_cast<int>(frames.size()) - 1));
    const double travel = std::hypot(last.ego.x_m - first.ego.x_m, last.ego.z_m - first.ego.z_m);
    const dps::RigCamera& cam = scene.rig.cameras[0];
    const auto [field_ms, own_ms] = MedianMs(
        7, [&] { dps::EstimateFieldMask(frames, cam.model); },
        [&] { dps::EstimateOwnCarMask(frames, cam, scene.rig.vehicle, travel); });
    std::printf("| %dx%d | %zu | %.1f | %.1f |\n", ow, oh, frames.size(), field_ms, own_ms);
  }
  return 0;
}
