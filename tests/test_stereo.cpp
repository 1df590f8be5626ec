// Tests of the stereo matcher: exact answers on shifted textures, prepared views, the interest
// operator (also against OpenCV's filters), options that must be refused, the temporal filter,
// disparity files, and accuracy on real data — Middlebury tsukuba and venus against cv::StereoBM computed in the same run, and the
// real KITTI road pair's road disparity.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "check.h"
#include "fixtures.h"
#include "dps/stereo/disparity_io.h"
#include "dps/stereo/sad_stereo.h"
#include "dps/util/error.h"

namespace {

constexpr double kShiftTolPx = 0.1;       // median error on a pure shift
constexpr double kMinShiftDensity = 0.9;  // valid fraction of the matchable area
constexpr double kBadThresholdPx = 1.0;   // Middlebury: |d - d_gt| > 1 is bad
constexpr double kKittiRoadVsSgbmPx = 1.0;  // road rows: dps's median vs StereoSGBM's
constexpr double kKittiRoadVsLinePx = 2.0;  // ... and vs the documented (approximate) 0.31 (v - 176)

const std::string kReal = dps_test::kRealData;

cv::Mat Texture(int w, int h, unsigned seed) {
  cv::Mat t(h, w, CV_8U);
  cv::RNG rng(seed);
  rng.fill(t, cv::RNG::UNIFORM, 0, 256);
  cv::GaussianBlur(t, t, cv::Size(), 1.2);
  cv::normalize(t, t, 0, 255, cv::NORM_MINMAX);
  return t;
}

// Median disparity error and density over the pixels where every disparity can be searched.
void ShiftStats(const cv::Mat& d, double truth, int x0, int x1, double* median_err, double* density) {
  std::vector<double> err;
  int total = 0;
  for (int y = 10; y < d.rows - 10; ++y) {
    for (int x = x0; x < x1; ++x) {
      ++total;
      const float v = d.at<float>(y, x);
      if (std::isfinite(v)) err.push_back(std::abs(v - truth));
    }
  }
  std::nth_element(err.begin(), err.begin() + err.size() / 2, err.end());
  *median_err = err.empty() ? 1e9 : err[err.size() / 2];
  *density = static_cast<double>(err.size()) / total;
}

void TestShifts() {
  const cv::Mat big = Texture(420, 200, 3);
  // Integer and fractional shifts; a negative one needs a negative range (motion stereo).
  for (const double shift : {0.0, 5.0, 12.0, 7.25, 3.5, -3.0, -6.75}) {
    // right(x) = left(x + shift)  =>  left(x) = right(x - shift): disparity = shift.
    cv::Mat right;
    const cv::Matx23d m(1, 0, shift, 0, 1, 0);
    cv::warpAffine(big, right, m, big.size(), cv::INTER_CUBIC | cv::WARP_INVERSE_MAP, cv::BORDER_REFLECT);
    dps::StereoOptions o;
    o.num_disparities = 16;
    o.min_disparity = shift < 0 ? -8 : 0;
    dps::SadStereoMatcher matcher(o);
    const cv::Mat d = matcher.Compute(big, right);
    CHECK_EQ(d.type(), CV_32F);
    double err = 0, density = 0;
    ShiftStats(d, shift, 40, big.cols - 40, &err, &density);
    std::printf("shift %6.2f px: median error %.3f px, density %.3f\n", shift, err, density);
    CHECK(err <= kShiftTolPx);
    CHECK(density >= kMinShiftDensity);
  }
}

// Prepared views (prefiltered once, matched several times) on the real tsukuba pair: prepared
// into buffers that held another image, the same disparities as matching the images; from a
// first column on, the columns before invalid and the
// rest as in the whole match (but for the left-right check next to it); mirrored, the right view
// as the reference, as matching the images turned left to right (the half-resolution grid of a
// mirrored view lies one pixel over, so the coarse fill may differ there).
void TestPreparedViews() {
  const std::string dir = kReal + "/middlebury/tsukuba/";
  const cv::Mat l = cv::imread(dir + "im3.png", cv::IMREAD_GRAYSCALE);
  const cv::Mat r = cv::imread(dir + "im4.png", cv::IMREAD_GRAYSCALE);
  CHECK(!l.empty() && !r.empty());
  if (l.empty() || r.empty()) return;
  dps::StereoOptions o;
  o.num_disparities = 16;
  dps::SadStereoMatcher matcher(o);
  dps::SadStereoMatcher::PreparedView pl, pr, ml, mr;
  matcher.Prepare(r, &pl);  // then the left image into the same buffers
  matcher.Prepare(l, &pl);
  matcher.Prepare(r, &pr);
  const cv::Mat whole = matcher.Compute(l, r);
  CHECK_EQ(cv::countNonZero(matcher.Compute(pl, pr) != whole), 0);

  const int first = 150;
  const cv::Mat part = matcher.Compute(pl, pr, first);
  CHECK_EQ(cv::countNonZero(part.colRange(0, first) != dps::kInvalidDisparity), 0);
  const cv::Mat inner = part.colRange(first + 16, l.cols), whole_inner = whole.colRange(first + 16, l.cols);
  const int same = inner.rows * inner.cols - cv::countNonZero(inner != whole_inner);
  std::printf("prepared views from column %d: %.4f of the pixels 16 columns on as in the whole match\n", first,
              same / static_cast<double>(inner.rows * inner.cols));
  CHECK(same >= 0.995 * inner.rows * inner.cols);

  dps::SadStereoMatcher::Mirror(pr, &mr);
  dps::SadStereoMatcher::Mirror(pl, &ml);
  cv::Mat fr, fl, mirrored_images, mirrored_prepared;
  cv::flip(r, fr, 1);
  cv::flip(l, fl, 1);
  cv::flip(matcher.Compute(fr, fl), mirrored_images, 1);
  cv::flip(matcher.Compute(mr, ml), mirrored_prepared, 1);
  int both = 0, agree = 0;
  for (int y = 0; y < l.rows; ++y) {
    for (int x = 0; x < l.cols; ++x) {
      const float a = mirrored_images.at<float>(y, x), b = mirrored_prepared.at<float>(y, x);
      if (!std::isfinite(a) || !std::isfinite(b)) continue;
      ++both;
      agree += std::abs(a - b) <= 1.0f;
    }
  }
  std::printf("mirrored prepared views: %d pixels valid in both, %.4f within 1 px of matching the turned images\n",
              both, agree / static_cast<double>(std::max(both, 1)));
  CHECK(both > 0.5 * l.rows * l.cols);
  CHECK(agree >= 0.98 * both);

  dps::SadStereoMatcher::PreparedView small;
  matcher.Prepare(l.colRange(0, 200), &small);
  CHECK_THROWS_WITH(matcher.Compute(pl, small), dps::Error, "of one size");
  CHECK_THROWS_WITH(matcher.Compute(pl, pr, l.cols), dps::Error, "first_column");
  dps::StereoOptions one = o;
  one.two_levels = false;
  CHECK_THROWS_WITH(dps::SadStereoMatcher(one).Compute(pl, pr), dps::Error, "prepared with these options");
}

// The kernel is built for the baseline instruction set and (on x86-64) for AVX2; both must give
// the same disparities to the bit.
void TestKernelsAgree() {
  const cv::Mat big = Texture(400, 160, 11);
  cv::Mat right;
  cv::warpAffine(big, right, cv::Matx23d(1, 0, 9.3, 0, 1, 0), big.size(), cv::INTER_CUBIC | cv::WARP_INVERSE_MAP,
                 cv::BORDER_REFLECT);
  dps::StereoOptions o;
  o.num_disparities = 40;  // not a multiple of the lane count: the padded lanes are exercised
  o.min_disparity = -5;
  dps::SadStereoMatcher matcher(o);
  const cv::Mat best = matcher.Compute(big, right);
  o.baseline_kernel = true;
  dps::SadStereoMatcher baseline_matcher(o);
  const cv::Mat baseline = baseline_matcher.Compute(big, right);
  cv::Mat differ;
  cv::compare(best, baseline, differ, cv::CMP_NE);
  CHECK_EQ(cv::countNonZero(differ), 0);
  CHECK(cv::countNonZero(best != dps::kInvalidDisparity) > 30000);
}

void TestInterestOperator() {
  // A uniform image has no texture: every pixel is invalid.
  const cv::Mat flat(120, 160, CV_8U, cv::Scalar(128));
  dps::StereoOptions o;
  o.num_disparities = 16;
  dps::SadStereoMatcher matcher(o);
  const cv::Mat d = matcher.Compute(flat, flat);
  CHECK_EQ(cv::countNonZero(d != dps::kInvalidDisparity), 0);
  // The prefilter of a constant image is its zero level, cap.
  const cv::Mat p = dps::LogPrefilter(flat, 1.0, 6.0, 31);
  double lo = 0, hi = 0;
  cv::minMaxLoc(p, &lo, &hi);
  CHECK_EQ(lo, 31.0);
  CHECK_EQ(hi, 31.0);
  // Texture on the left half only: the flat half stays invalid at the fine level and without
  // the coarse fill.
  cv::Mat half = flat.clone();
  Texture(80, 120, 5).copyTo(half(cv::Rect(0, 0, 80, 120)));
  o.two_levels = false;
  dps::SadStereoMatcher one(o);
  const cv::Mat dh = one.Compute(half, half);
  CHECK_EQ(cv::countNonZero(dh(cv::Rect(100, 0, 60, 120)) != dps::kInvalidDisparity), 0);
  CHECK(cv::countNonZero(dh(cv::Rect(20, 10, 50, 100)) != dps::kInvalidDisparity) > 4000);
  // The prefilter's rounding and clamping pass against OpenCV's: the LoG in floating point,
  // converted to 8 bits about 128, then clamped by a table to +-cap and offset by cap.
  for (const cv::Size size : {cv::Size(37, 23), cv::Size(200, 100)}) {
    const cv::Mat grey = Texture(size.width, size.height, 9);
    cv::Mat f, blurred, log, shifted, expected;
    grey.convertTo(f, CV_32F);
    cv::GaussianBlur(f, blurred, cv::Size(7, 7), 1.0, 1.0, cv::BORDER_REPLICATE);
    cv::Laplacian(blurred, log, CV_32F, 1, 6.0, 0.0, cv::BORDER_REPLICATE);
    log.convertTo(shifted, CV_8U, 1.0, 128.0);
    cv::Mat table(1, 256, CV_8U);
    for (int v = 0; v < 256; ++v) table.at<std::uint8_t>(v) = static_cast<std::uint8_t>(std::clamp(v - 128, -31, 31) + 31);
    cv::LUT(shifted, table, expected);
    const cv::Mat prefiltered = dps::LogPrefilter(grey, 1.0, 6.0, 31);
    CHECK_EQ(cv::countNonZero(prefiltered != expected), 0);
    CHECK(cv::countNonZero(expected == 0) > 0 && cv::countNonZero(expected == 62) > 0);  // both clamps reached
  }
  // The operator's one-pass mask against OpenCV's filters composed as step 3 defines it: the
  // horizontal change (Sobel, dx 1, ksize 1), its magnitude, the window's sum, the threshold;
  // edges replicated. Sizes from smaller than the window to wider than several vectors, widths
  // that leave a scalar tail.
  for (const cv::Size size : {cv::Size(3, 2), cv::Size(9, 9), cv::Size(37, 23), cv::Size(200, 100), cv::Size(101, 51)}) {
    for (const cv::Size block : {cv::Size(9, 9), cv::Size(5, 11)}) {
      dps::StereoOptions t;
      t.block_width = block.width;
      t.block_height = block.height;
      t.texture_threshold = 3.3;
      cv::Mat log(size, CV_8U);
      cv::RNG rng(size.area() + block.width);
      rng.fill(log, cv::RNG::UNIFORM, 28, 35);  // weak texture on the left, strong on the right
      rng.fill(log.colRange(size.width / 2, size.width), cv::RNG::UNIFORM, 0, 63);
      cv::Mat gradient, magnitude, sum, expected;
      cv::Sobel(log, gradient, CV_16S, 1, 0, 1, 1.0, 0.0, cv::BORDER_REPLICATE);
      cv::convertScaleAbs(gradient, magnitude);
      cv::boxFilter(magnitude, sum, CV_32S, block, cv::Point(-1, -1), false, cv::BORDER_REPLICATE);
      cv::compare(sum, 3.3 * block.area(), expected, cv::CMP_GE);
      const cv::Mat mask = dps::TextureMask(log, t);
      CHECK_EQ(cv::countNonZero(mask != expected), 0);
      if (size.area() > 1000) CHECK(cv::countNonZero(expected) > 0 && cv::countNonZero(expected) < size.area());
    }
  }
}

// The two levels' cross check on a pair whose fine pattern (white noise) moves with another
// disparity than its coarse structure (blobs): the full-resolution level follows the fine pattern,
// the half-resolution one, where pyrDown has blurred most of the noise away, the structure. The
// check drops the full level's disparities where the two disagree; without it they stay.
void TestCrossLevelCheck() {
  const int w = 320, h = 160, d_coarse = 8, d_fine = 20;
  cv::Mat blobs(h, w + d_fine, CV_8U), noise(h, w + d_fine, CV_8U);
  cv::RNG rng(7);
  rng.fill(blobs, cv::RNG::UNIFORM, 0, 256);
  cv::GaussianBlur(blobs, blobs, cv::Size(), 3.0);
  cv::normalize(blobs, blobs, 0, 160, cv::NORM_MINMAX);
  rng.fill(noise, cv::RNG::UNIFORM, 0, 96);
  // left(x) matches right(x - d): right(x) = left(x + d), the blobs with d_coarse, the noise d_fine.
  const cv::Mat l = blobs.colRange(0, w) + noise.colRange(0, w);
  const cv::Mat r = blobs.colRange(d_coarse, d_coarse + w) + noise.colRange(d_fine, d_fine + w);
  dps::StereoOptions o = dps::DetectionStereoOptions();
  o.num_disparities = 32;
  // Pixels within 1 px of the noise's disparity, over the area where all disparities are searched.
  auto at_fine = [&](double max_diff) {
    o.cross_level_max_diff = max_diff;
    const cv::Mat d = dps::SadStereoMatcher(o).Compute(l, r);
    int valid = 0, n = 0;
    for (int y = 10; y < h - 10; ++y) {
      for (int x = 50; x < w - 10; ++x) {
        const float v = d.at<float>(y, x);
        valid += std::isfinite(v);
        n += std::isfinite(v) && std::abs(v - d_fine) <= 1.0f;
      }
    }
    std::printf("cross check %s: %d valid, %d at the noise's disparity\n", max_diff < 0 ? "off" : "on ", valid, n);
    return n;
  };
  const int off = at_fine(-1.0), on = at_fine(4.0);
  CHECK(off > 30000);     // the full level alone follows the noise nearly everywhere (of 36400)
  CHECK(on < off / 20);   // the check leaves almost none of it
}

void TestBadOptions() {
  auto with = [](auto change) {
    dps::StereoOptions o;
    change(o);
    return o;
  };
  CHECK_THROWS_WITH(dps::SadStereoMatcher(with([](auto& o) { o.block_width = 8; })), dps::Error, "block_width");
  CHECK_THROWS_WITH(dps::SadStereoMatcher(with([](auto& o) { o.block_height = 1; })), dps::Error, "block_height");
  CHECK_THROWS_WITH(dps::SadStereoMatcher(with([](auto& o) { o.num_disparities = 1; })), dps::Error,
                    "num_disparities = 1");
  // Values whose column arithmetic would overflow int (dps-stereo --num-disparities 2147483647).
  CHECK_THROWS_WITH(dps::SadStereoMatcher(with([](auto& o) { o.num_disparities = 2147483647; })), dps::Error,
                    "num_disparities");
  CHECK_THROWS_WITH(dps::SadStereoMatcher(with([](auto& o) { o.min_disparity = -2147483647; })), dps::Error,
                    "min_disparity");
  CHECK_THROWS_WITH(dps::SadStereoMatcher(with([](auto& o) { o.uniqueness_ratio = 101; })), dps::Error,
                    "uniqueness_ratio");
  CHECK_THROWS_WITH(dps::SadStereoMatcher(with([](auto& o) { o.log_sigma_px = 0; })), dps::Error, "log_sigma_px");
  CHECK_THROWS_WITH(dps::SadStereoMatcher(with([](auto& o) { o.prefilter_cap = 64; })), dps::Error, "prefilter_cap");
  CHECK_THROWS_WITH(dps::SadStereoMatcher(with([](auto& o) { o.cross_level_max_diff = std::nan(""); })), dps::Error,
                    "cross_level_max_diff");
  dps::SadStereoMatcher m(dps::StereoOptions{});
  CHECK_THROWS_WITH(m.Compute(cv::Mat(50, 60, CV_8U), cv::Mat(51, 60, CV_8U)), dps::Error, "the left's rows");
  CHECK_THROWS_WITH(m.Compute(cv::Mat(50, 60, CV_8U), cv::Mat(50, 60, CV_8U)), dps::Error, "too small");
  CHECK_THROWS_WITH(m.Compute(cv::Mat(), cv::Mat()), dps::Error, "empty");
  CHECK_THROWS_WITH(dps::TemporalConsistencyFilter(0.0, 1.0), dps::Error, "forgetting");
}

void TestTemporalFilter() {
  dps::TemporalConsistencyFilter filter(0.5, 1.0);
  cv::Mat d(4, 4, CV_32F, cv::Scalar(10.0f));
  int suppressed = 0;
  for (int frame = 0; frame < 10; ++frame) {
    d.at<float>(1, 1) = frame % 2 ? 4.0f : 16.0f;  // flickers by 12 px
    d.at<float>(2, 2) = 10.0f + 0.1f * frame;       // drifts slowly (an approaching object)
    d.at<float>(3, 3) = frame == 5 ? dps::kInvalidDisparity : 7.0f;
    const cv::Mat out = filter.Apply(d);
    if (frame >= 2) {
      suppressed += !std::isfinite(out.at<float>(1, 1));
      CHECK(std::isfinite(out.at<float>(2, 2)));
      CHECK_NEAR(out.at<float>(0, 0), 10.0, 0);
    }
    if (frame == 6) CHECK(std::isfinite(out.at<float>(3, 3)));  // restarts after a gap
  }
  CHECK_EQ(suppressed, 8);
  // Every column of a wider image given the same sequence gives the same answer (the filter runs
  // over vectors of pixels and a scalar tail).
  dps::TemporalConsistencyFilter wide(0.5, 1.0);
  cv::Mat w(3, 13, CV_32F);
  for (int frame = 0; frame < 10; ++frame) {
    w.row(0).setTo(frame % 2 ? 4.0f : 16.0f);
    w.row(1).setTo(10.0f + 0.1f * frame);
    w.row(2).setTo(frame == 5 ? dps::kInvalidDisparity : 7.0f);
    const cv::Mat out = wide.Apply(w);
    for (int y = 0; y < 3; ++y) {
      for (int x = 1; x < w.cols; ++x) {
        const float a = out.at<float>(y, 0), b = out.at<float>(y, x);
        CHECK(a == b || (!std::isfinite(a) && !std::isfinite(b)));
      }
    }
    if (frame >= 2) CHECK(!std::isfinite(out.at<float>(0, 12)));
  }
}

void TestDisparityFiles() {
  const auto dir = std::filesystem::temp_directory_path() / "dps_test_stereo";
  std::filesystem::create_directories(dir);
  cv::Mat d(3, 4, CV_32F, cv::Scalar(12.5f));
  d.at<float>(0, 0) = dps::kInvalidDisparity;
  d.at<float>(2, 3) = 0.3f;
  for (const char* name : {"d.png", "d.pfm"}) {
    const std::string p = (dir / name).string();
    dps::WriteDisparity(p, d);
    const cv::Mat back = dps::ReadDisparity(p);
    CHECK(!std::isfinite(back.at<float>(0, 0)));
    CHECK_NEAR(back.at<float>(1, 1), 12.5, 1.0 / 512);
    CHECK_NEAR(back.at<float>(2, 3), 0.3, 1.0 / 512);
  }
  cv::Mat negative = d.clone();
  negative.at<float>(1, 2) = -2.0f;
  CHECK_THROWS_WITH(dps::WriteDisparity((dir / "n.png").string(), negative), dps::Error, "use .pfm");
  CHECK(!std::filesystem::exists(dir / "n.png"));
  CHECK_THROWS_WITH(dps::WriteDisparity((dir / "n.tif").string(), d), dps::Error, "unknown disparity format");
  std::filesystem::remove_all(dir);
}

struct Score {
  double bad = 0, density = 0;
};

// Fraction of pixels with known truth (and 18 px from the border) whose disparity is off by more
// than 1 px, counting invalid pixels as bad.
Score Middlebury(const cv::Mat& d, const cv::Mat& gt, double gt_scale) {
  int known = 0, bad = 0, valid = 0;
  for (int y = 18; y < gt.rows - 18; ++y) {
    for (int x = 18; x < gt.cols - 18; ++x) {
      const int g = gt.at<std::uint8_t>(y, x);
      if (g == 0) continue;
      ++known;
      const float v = d.at<float>(y, x);
      if (!std::isfinite(v)) {
        ++bad;
        continue;
      }
      ++valid;
      bad += std::abs(v - g / gt_scale) > kBadThresholdPx;
    }
  }
  return {static_cast<double>(bad) / known, static_cast<double>(valid) / known};
}

cv::Mat FromOpenCV(const cv::Mat& d16) {
  cv::Mat d;
  d16.convertTo(d, CV_32F, 1.0 / 16);
  d.setTo(dps::kInvalidDisparity, d16 < 0);
  return d;
}

void TestMiddlebury(const std::string& name, const std::string& left, const std::string& right,
                    const std::string& truth, double scale, int disparities) {
  const std::string dir = kReal + "/middlebury/" + name + "/";
  const cv::Mat l = cv::imread(dir + left, cv::IMREAD_GRAYSCALE);
  const cv::Mat r = cv::imread(dir + right, cv::IMREAD_GRAYSCALE);
  const cv::Mat gt = cv::imread(dir + truth, cv::IMREAD_GRAYSCALE);
  CHECK(!l.empty() && !r.empty() && !gt.empty());
  if (l.empty() || r.empty() || gt.empty()) return;
  dps::StereoOptions o;
  o.num_disparities = disparities;
  o.block_width = o.block_height = 9;
  dps::SadStereoMatcher matcher(o);
  const Score ours = Middlebury(matcher.Compute(l, r), gt, scale);
  cv::Mat d16;
  cv::StereoBM::create(disparities, 9)->compute(l, r, d16);
  const Score bm = Middlebury(FromOpenCV(d16), gt, scale);
  cv::StereoSGBM::create(0, disparities, 9)->compute(l, r, d16);
  const Score sgbm = Middlebury(FromOpenCV(d16), gt, scale);
  std::printf("middlebury %-8s D=%d block 9: dps bad %.4f density %.3f | StereoBM bad %.4f density %.3f"
              " | StereoSGBM bad %.4f density %.3f\n",
              name.c_str(), disparities, ours.bad, ours.density, bm.bad, bm.density, sgbm.bad, sgbm.density);
  CHECK(ours.bad <= bm.bad);
}

// The median valid disparity of a row segment (NaN when fewer than 50 are valid).
double RowMedian(const cv::Mat& d, int v, int u0, int u1) {
  std::vector<float> row;
  for (int u = u0; u < u1; ++u) {
    if (std::isfinite(d.at<float>(v, u))) row.push_back(d.at<float>(v, u));
  }
  if (row.size() < 50) return std::nan("");
  std::nth_element(row.begin(), row.begin() + row.size() / 2, row.end());
  return row[row.size() / 2];
}

void TestKittiRoad() {
  const cv::Mat l = cv::imread(kReal + "/kitti_pair/imgKittyl.bmp", cv::IMREAD_GRAYSCALE);
  const cv::Mat r = cv::imread(kReal + "/kitti_pair/imgKitty.bmp", cv::IMREAD_GRAYSCALE);
  CHECK(!l.empty() && !r.empty());
  if (l.empty() || r.empty()) return;
  dps::StereoOptions o;
  o.num_disparities = 64;
  dps::SadStereoMatcher matcher(o);
  const cv::Mat d = matcher.Compute(l, r);
  cv::Mat d16;
  cv::StereoSGBM::create(0, 64, 9)->compute(l, r, d16);
  const cv::Mat sgbm = FromOpenCV(d16);
  // The road in front of the car, rows 250..355, columns 500..750: per row, dps's median
  // disparity agrees with StereoSGBM's and roughly with the documented d = 0.31 (v - 176).
  int rows = 0, good = 0;
  double worst_sgbm = 0, worst_line = 0;
  for (int v = 250; v < 360; v += 5) {
    const double ours = RowMedian(d, v, 500, 750), ref = RowMedian(sgbm, v, 500, 750);
    if (std::isnan(ours) || std::isnan(ref)) continue;
    const double line = 0.31 * (v - 176);
    worst_sgbm = std::max(worst_sgbm, std::abs(ours - ref));
    worst_line = std::max(worst_line, std::abs(ours - line));
    if (std::getenv("DPS_VERBOSE")) std::printf("  v %d dps %.2f sgbm %.2f line %.2f\n", v, ours, ref, line);
    ++rows;
    good += std::abs(ours - ref) <= kKittiRoadVsSgbmPx && std::abs(ours - line) <= kKittiRoadVsLinePx;
  }
  std::printf("kitti road: %d rows, worst |dps - StereoSGBM| %.2f px, worst |dps - 0.31 (v - 176)| %.2f px\n",
              rows, worst_sgbm, worst_line);
  CHECK(rows >= 20);
  CHECK_EQ(good, rows);
}

}  // namespace

int main() {
  TestShifts();
  TestPreparedViews();
  TestKernelsAgree();
  TestInterestOperator();
  TestCrossLevelCheck();
  TestBadOptions();
  TestTemporalFilter();
  TestDisparityFiles();
  TestMiddlebury("tsukuba", "im3.png", "im4.png", "disp3.pgm", 16.0, 16);
  TestMiddlebury("tsukuba", "im3.png", "im4.png", "disp3.pgm", 16.0, 32);
  TestMiddlebury("venus", "im2.png", "im6.png", "disp2.pgm", 8.0, 16);
  TestMiddlebury("venus", "im2.png", "im6.png", "disp2.pgm", 8.0, 32);
  TestKittiRoad();
  return dps_test::Report();
}
