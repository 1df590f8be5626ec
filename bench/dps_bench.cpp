// dps-bench: times dps's stereo matcher against cv::StereoBM on the same pairs in the same run
// (same disparity range and block size), with and without the left-right check, and the virtual
// view rectification. Prints a Markdown table for docs/performance.md.
#include <algorithm>
#include <chrono>
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

#include "dps/rig_io.h"
#include "dps/sad_stereo.h"
#include "dps/virtual_view.h"

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
  const std::string data = argc > 1 ? argv[1] : "data/real";
  if (argc > 1 && (std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h")) {
    std::printf("usage: dps-bench [DATA_DIR [RIG]]   (DATA_DIR holds kitti_pair/, default data/real;\n"
                "       RIG for the view timing, default data/rigs/omni_pair.yaml; run from the source)\n");
    return 0;
  }
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
    for (const auto [lr, levels] : {std::pair{false, 2}, std::pair{true, 2}, std::pair{true, 1}}) {
      dps::StereoOptions o;
      o.num_disparities = c.d;
      o.left_right_check = lr;
      o.two_levels = levels == 2;
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
  const std::string rig_path = argc > 2 ? argv[2] : "data/rigs/omni_pair.yaml";
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
  return 0;
}
