// dps-stereo: disparity of a rectified pair with dps's LoG + SAD matcher.
#include <cmath>
#include <iostream>

#include <opencv2/imgcodecs.hpp>

#include "cli.h"
#include "dps/stereo/disparity_io.h"
#include "dps/stereo/sad_stereo.h"
#include "dps/util/atomic_file.h"
#include "dps/util/image.h"

namespace {

const char* kUsage = R"(usage: dps-stereo LEFT RIGHT --num-disparities N --out disp.png|disp.pfm [options]

Disparity of a rectified pair (Gandhi & Trivedi 2006, section V): LoG prefilter, SAD block
matching over [min, min + N), sub-pixel, interest operator, uniqueness and left-right checks, two
levels. LEFT is the reference: left(x) matches right(x - d).

Output by extension: .png = 16-bit, KITTI convention (round(d * 256), 0 = invalid; the range
must be non-negative), .pfm = float disparity, invalid = inf.

  --num-disparities N   disparities searched (>= 2)
  --min-disparity M     smallest disparity (default 0; negative for motion stereo, .pfm only)
  --block B             square SAD window, odd (default 9)
  --uniqueness P        uniqueness ratio in % (default 10)
  --texture T           interest operator threshold (default 1)
  --no-lr-check         skip the left-right consistency check
  --one-level           skip the coarse level that fills low-texture areas
  --cross-check PX      drop full-resolution disparities more than PX from the coarse level's
                        (off by default; 4 checks to two coarse pixels)
  --baseline-kernel     the matcher's baseline instruction-set kernel even where AVX2 runs
                        (the same disparities; for timing comparisons)
  --out FILE            disparity output
  --color FILE          also write a colour picture of the disparity (PNG/JPG)
  --help                this text
)";

cv::Mat ReadGrey(const std::string& path) {
  const cv::Mat m = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (m.empty()) throw dps::Error(path + ": cannot read image");
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  return dps_cli::Run("dps-stereo", [&] {
    const dps_cli::Args args(argc, argv,
                             {"num-disparities", "min-disparity", "block", "uniqueness", "texture", "cross-check", "out", "color"},
                             {"no-lr-check", "one-level", "baseline-kernel"});
    if (args.help()) {
      std::cout << kUsage;
      return 0;
    }
    if (args.positional().size() != 2) throw dps::Error("expected LEFT and RIGHT images (see --help)");
    args.Require("num-disparities", "N");
    args.Require("out", "FILE");
    dps::StereoOptions o;
    o.num_disparities = args.Integer("num-disparities", o.num_disparities);
    o.min_disparity = args.Integer("min-disparity", 0);
    o.block_width = o.block_height = args.Integer("block", 9);
    o.uniqueness_ratio = args.Number("uniqueness", o.uniqueness_ratio);
    o.texture_threshold = args.Number("texture", o.texture_threshold);
    o.left_right_check = !args.Has("no-lr-check");
    o.two_levels = !args.Has("one-level");
    o.cross_level_max_diff = args.Number("cross-check", o.cross_level_max_diff);
    o.baseline_kernel = args.Has("baseline-kernel");
    const std::string out = args.Get("out");
    const bool png = out.size() >= 4 && out.compare(out.size() - 4, 4, ".png") == 0;
    if (png && o.min_disparity < 0) {
      throw dps::Error("--min-disparity " + std::to_string(o.min_disparity) +
                       ": a KITTI PNG cannot hold negative disparities; write .pfm");
    }
    dps::SadStereoMatcher matcher(o);
    const cv::Mat left = ReadGrey(args.positional()[0]), right = ReadGrey(args.positional()[1]);
    const cv::Mat disparity = matcher.Compute(left, right);
    dps::WriteDisparity(out, disparity);
    if (args.Has("color")) {
      dps::WriteImageAtomically(args.Get("color"), dps::ColourDisparity(disparity, o.min_disparity,
                                                                         o.min_disparity + o.num_disparities - 1));
    }
    int valid = 0;
    for (int y = 0; y < disparity.rows; ++y) {
      for (int x = 0; x < disparity.cols; ++x) valid += std::isfinite(disparity.at<float>(y, x));
    }
    std::cout << "dps-stereo: " << disparity.cols << "x" << disparity.rows << ", "
              << 100.0 * valid / disparity.total() << " % valid, wrote " << out << "\n";
    return 0;
  });
}
