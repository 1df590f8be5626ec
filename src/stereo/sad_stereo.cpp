#include "dps/stereo/sad_stereo.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core/hal/intrin.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include "dps/util/error.h"
#include "sad_stereo_kernel.h"

namespace dps {
namespace {

cv::Mat ToGrey(const cv::Mat& image, const char* which) {
  if (image.empty()) throw Error(Str("stereo: the ", which, " image is empty"));
  if (image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3)) {
    throw Error(Str("stereo: the ", which, " image must be 8-bit grey or BGR"));
  }
  if (image.channels() == 1) return image;
  cv::Mat grey;
  cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  return grey;
}

// The columns (inclusive) where the window of every disparity lies inside both images.
struct ColumnRange {
  int lo = 0, hi = -1;
};
ColumnRange MatchableColumns(int width, int d_min, int n, int block_width) {
  const int rw = block_width / 2, d_max = d_min + n - 1;
  return {rw + std::max(0, d_max), std::min(width - 1 - rw, width - 1 - rw + d_min)};
}

// Throws dps::Error unless a width x height image leaves columns to match.
void RequireMatchable(int width, int height, const StereoOptions& o) {
  const ColumnRange columns = MatchableColumns(width, o.min_disparity, o.num_disparities, o.block_width);
  if (columns.hi <= columns.lo || height <= o.block_height) {
    throw Error(Str("stereo: a ", width, "x", height, " image is too small for ", o.num_disparities,
                    " disparities from ", o.min_disparity, " with a ", o.block_width, "x", o.block_height, " block"));
  }
}

}  // namespace

// Buffers of one stripe of rows, kept between calls (allocating them anew each time costs as much
// as a good part of the matching: fresh pages fault in).
struct StripeBuffers {
  std::vector<std::uint16_t> hsad, sad, cost2;
  std::vector<std::uint8_t> padded, padded_out;
  std::vector<int> disp2, best_d;
  std::vector<float> row_disp;

  internal::SadKernelBuffers Prepare(int width, int n_padded, int pad) {
    hsad.resize(static_cast<size_t>(width) * n_padded);
    sad.resize(n_padded);
    cost2.resize(width);
    padded.resize(static_cast<size_t>(width) + 2 * pad);
    padded_out.resize(padded.size());
    disp2.resize(width);
    best_d.resize(width);
    row_disp.resize(width);
    return {hsad.data(), sad.data(), cost2.data(), padded.data(), padded_out.data(),
            disp2.data(), best_d.data(), row_disp.data()};
  }
};

// Everything one pyramid level's matching needs between calls.
struct LevelBuffers {
  cv::Mat out;
  std::vector<StripeBuffers> stripes;
};

struct SadStereoMatcher::Workspace {
  LevelBuffers levels[2];
  PreparedView left, right;  // Compute of two images prepares them here
};

namespace internal {

const SadKernel& BestSadKernel(bool baseline_only) {
#ifdef DPS_HAVE_AVX2_KERNEL
  static const bool has_avx2 = cv::checkHardwareSupport(CV_CPU_AVX2);
  if (has_avx2 && !baseline_only) return avx2::kKernel;
#else
  (void)baseline_only;
#endif
  return baseline::kKernel;
}

}  // namespace internal

StereoOptions DetectionStereoOptions() {
  StereoOptions o;
  o.num_disparities = 64;
  o.texture_threshold = 4.5;
  return o;
}

void StereoOptions::Check() const {
  const OptionCheck Require("stereo");
  // Bounded so that the column arithmetic cannot overflow (no image is that wide).
  Require(num_disparities >= 2 && num_disparities <= 16384, "num_disparities", num_disparities, "2..16384");
  Require(std::abs(min_disparity) <= 16384, "min_disparity", min_disparity, "-16384..16384");
  Require(block_width % 2 == 1 && block_width >= 3 && block_width <= 31, "block_width", block_width,
          "odd and 3..31");
  Require(block_height % 2 == 1 && block_height >= 3 && block_height <= 31, "block_height",
          block_height, "odd and 3..31");
  Require(log_sigma_px > 0.0, "log_sigma_px", log_sigma_px, "> 0");
  Require(prefilter_gain > 0.0, "prefilter_gain", prefilter_gain, "> 0");
  Require(prefilter_cap >= 1 && prefilter_cap <= 63, "prefilter_cap", prefilter_cap, "1..63");
  Require(texture_threshold >= 0.0, "texture_threshold", texture_threshold, ">= 0");
  Require(uniqueness_ratio >= 0.0 && uniqueness_ratio <= 100.0, "uniqueness_ratio", uniqueness_ratio,
          "0..100");
  Require(left_right_max_diff >= 0.0, "left_right_max_diff", left_right_max_diff, ">= 0");
  Require(!std::isnan(cross_level_max_diff), "cross_level_max_diff", cross_level_max_diff, "a number (< 0: no check)");
  // The window's cost must fit 16 bits: (2 cap) * area < 65536.
  Require(2 * prefilter_cap * block_width * block_height < 65536, "prefilter_cap", prefilter_cap,
          "2 cap * block area < 65536");
}

namespace {

// The LoG prefilter into `out`, reusing the temporaries scratch[0..2].
void LogPrefilterInto(const cv::Mat& grey, double sigma_px, double gain, int cap, cv::Mat* scratch, cv::Mat& out) {
  cv::Mat &f = scratch[0], &blurred = scratch[1], &log = scratch[2];
  // In floating point: blurring into 8 bits first would quantise the image, and the Laplacian
  // would amplify the rounding into noise that swamps weak texture.
  grey.convertTo(f, CV_32F);
  const int ksize = 2 * static_cast<int>(std::ceil(3.0 * sigma_px)) + 1;  // +-3 sigma
  cv::GaussianBlur(f, blurred, cv::Size(ksize, ksize), sigma_px, sigma_px, cv::BORDER_REPLICATE);
  cv::Laplacian(blurred, log, CV_32F, 1, gain, 0.0, cv::BORDER_REPLICATE);
  // Rounded about 128 (in float, to nearest, ties to even: as convertTo to 8 bits with an offset
  // of 128), clamped to +-cap and offset by cap.
  out.create(log.size(), CV_8U);
  for (int y = 0; y < log.rows; ++y) {
    const float* l = log.ptr<float>(y);
    std::uint8_t* o = out.ptr<std::uint8_t>(y);
    int x = 0;
#if CV_SIMD
    const cv::v_float32 mid = cv::vx_setall_f32(128.0f);
    const cv::v_int32 lo = cv::vx_setall_s32(128 - cap), hi = cv::vx_setall_s32(128 + cap);
    const cv::v_int32 offset = cv::vx_setall_s32(cap - 128);
    constexpr int n = cv::v_int32::nlanes;
    for (; x + 4 * n <= log.cols; x += 4 * n) {
      cv::v_int32 r[4];
      for (int i = 0; i < 4; ++i) {
        r[i] = cv::v_min(cv::v_max(cv::v_round(cv::vx_load(l + x + i * n) + mid), lo), hi) + offset;
      }
      cv::v_store(o + x, cv::v_pack_u(cv::v_pack(r[0], r[1]), cv::v_pack(r[2], r[3])));
    }
#endif
    for (; x < log.cols; ++x) {
      o[x] = static_cast<std::uint8_t>(std::clamp(cvRound(l[x] + 128.0f) - 128, -cap, cap) + cap);
    }
  }
}

// Interest operator: matching along rows needs structure along the rows, so the measure is the
// window's mean horizontal change of the LoG image, |LoG(x + 1) - LoG(x - 1)|: zero in uniform
// areas and along horizontal edges (where every disparity fits), large on texture. The window's
// sum (exact, in 16 bits) is compared with threshold x area; the image's edges are replicated.
// Running sums down the columns and prefix sums along each row, into `textured`, with the change
// image in `change`: the same as cv::Sobel (dx 1, ksize 1), cv::convertScaleAbs, cv::boxFilter
// (unnormalised) and cv::compare, which cost several times more on views this small.
void TextureMaskInto(const cv::Mat& log, const StereoOptions& o, cv::Mat& change, cv::Mat& textured) {
  CV_Assert(log.type() == CV_8U);
  const int w = log.cols, h = log.rows, rw = o.block_width / 2, rh = o.block_height / 2;
  change.create(h, w, CV_8U);
  for (int y = 0; y < h; ++y) {
    const std::uint8_t* l = log.ptr<std::uint8_t>(y);
    std::uint8_t* g = change.ptr<std::uint8_t>(y);
    g[0] = static_cast<std::uint8_t>(std::abs(l[std::min(1, w - 1)] - l[0]));
    int x = 1;
#if CV_SIMD
    for (; x + cv::v_uint8::nlanes + 1 <= w; x += cv::v_uint8::nlanes) {
      cv::v_store(g + x, cv::v_absdiff(cv::vx_load(l + x + 1), cv::vx_load(l + x - 1)));
    }
#endif
    for (; x < w; ++x) g[x] = static_cast<std::uint8_t>(std::abs(l[std::min(x + 1, w - 1)] - l[x - 1]));
  }
  const int threshold = static_cast<int>(std::ceil(o.texture_threshold * o.block_width * o.block_height - 1e-9));
  textured.create(h, w, CV_8U);
  if (threshold > 0xFFFF) {  // above any window's sum
    textured.setTo(0);
    return;
  }
  std::vector<std::uint16_t> column(w, 0);  // the window's column sums (2 cap x block area < 65536)
  const auto row = [&](int y) { return change.ptr<std::uint8_t>(std::clamp(y, 0, h - 1)); };
  // Adds (sign +1) or removes (-1) one row of changes from the column sums.
  const auto add = [&](const std::uint8_t* g, int sign) {
    int x = 0;
#if CV_SIMD
    for (; x + cv::v_uint16::nlanes <= w; x += cv::v_uint16::nlanes) {
      const cv::v_uint16 c = cv::vx_load(column.data() + x), v = cv::vx_load_expand(g + x);
      cv::v_store(column.data() + x, sign > 0 ? c + v : c - v);
    }
#endif
    for (; x < w; ++x) column[x] = static_cast<std::uint16_t>(column[x] + sign * g[x]);
  };
  // Along the row: prefix sums of the column sums with the edges replicated (16 bits, modulo
  // 2^16: a window's difference of two prefixes is exact), prefix[i] = sum of padded[0 .. i).
  std::vector<std::uint16_t> prefix(w + 2 * rw + 1);
  for (int dy = -rh; dy <= rh; ++dy) add(row(dy), 1);
  for (int y = 0; y < h; ++y) {
    if (y > 0) {
      add(row(y + rh), 1);
      add(row(y - rh - 1), -1);
    }
    std::uint16_t running = 0;
    for (int i = 0; i < w + 2 * rw; ++i) {
      prefix[i] = running;
      running = static_cast<std::uint16_t>(running + column[std::clamp(i - rw, 0, w - 1)]);
    }
    prefix[w + 2 * rw] = running;
    // The window of x covers padded [x, x + 2 rw].
    std::uint8_t* t = textured.ptr<std::uint8_t>(y);
    const std::uint16_t* p = prefix.data();
    int x = 0;
#if CV_SIMD
    const cv::v_uint16 limit = cv::vx_setall_u16(static_cast<std::uint16_t>(std::max(threshold, 0)));
    constexpr int n = cv::v_uint16::nlanes;
    for (; x + 2 * n <= w; x += 2 * n) {
      const cv::v_uint16 a = cv::vx_load(p + x + 2 * rw + 1) - cv::vx_load(p + x);
      const cv::v_uint16 b = cv::vx_load(p + x + n + 2 * rw + 1) - cv::vx_load(p + x + n);
      cv::v_store(t + x, cv::v_pack(cv::v_reinterpret_as_u16(a >= limit), cv::v_reinterpret_as_u16(b >= limit)));
    }
#endif
    for (; x < w; ++x) t[x] = static_cast<std::uint16_t>(p[x + 2 * rw + 1] - p[x]) >= threshold ? 255 : 0;
  }
}

// 255 where the matching window of `o` (and the interest operator's one column either side) holds
// valid pixels only. Outside the image counts as valid:
// the matcher's own column and row limits handle the borders.
void WindowValidInto(const cv::Mat& valid, const StereoOptions& o, cv::Mat& out) {
  const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(o.block_width + 2, o.block_height));
  cv::erode(valid, out, kernel, cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(255));
}

// For every pixel the nearest valid pixel (CV_32FC2 coordinates for cv::remap; a valid pixel maps
// to itself): the invalid area then takes the values of the valid area's edge, so that the
// prefilter finds no edge where the valid area ends.
cv::Mat NearestValidMap(const cv::Mat& valid) {
  cv::Mat distance, labels;
  // Labels of the zero pixels (the valid ones here) in raster order, and for every pixel the label
  // of the nearest one.
  cv::distanceTransform(valid == 0, distance, labels, cv::DIST_L2, cv::DIST_MASK_5, cv::DIST_LABEL_PIXEL);
  std::vector<cv::Vec2f> at(1);
  for (int y = 0; y < valid.rows; ++y) {
    const std::uint8_t* v = valid.ptr<std::uint8_t>(y);
    for (int x = 0; x < valid.cols; ++x) {
      if (v[x]) at.emplace_back(static_cast<float>(x), static_cast<float>(y));
    }
  }
  cv::Mat map(valid.size(), CV_32FC2);
  for (int y = 0; y < valid.rows; ++y) {
    const int* l = labels.ptr<int>(y);
    cv::Vec2f* m = map.ptr<cv::Vec2f>(y);
    for (int x = 0; x < valid.cols; ++x) {
      m[x] = l[x] > 0 && l[x] < static_cast<int>(at.size()) ? at[l[x]] : cv::Vec2f(static_cast<float>(x), static_cast<float>(y));
    }
  }
  return map;
}

// Validity at half resolution: a coarse pixel is valid when every fine pixel under cv::pyrDown's
// 5x5 kernel is.
void HalveValidity(const cv::Mat& valid, cv::Size coarse_size, cv::Mat& scratch, cv::Mat& out) {
  cv::erode(valid, scratch, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(5, 5)), cv::Point(-1, -1), 1,
            cv::BORDER_CONSTANT, cv::Scalar(255));
  cv::resize(scratch, out, coarse_size, 0, 0, cv::INTER_NEAREST);
}

// Invalidates the disparities whose reference window or matched window (at the nearer whole
// columns either side of the sub-pixel match) is not wholly valid.
void KeepValidWindows(const cv::Mat& left_valid, const cv::Mat& right_valid, cv::Mat& disparity) {
  if (left_valid.empty() && right_valid.empty()) return;
  cv::parallel_for_(cv::Range(0, disparity.rows), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      float* d = disparity.ptr<float>(y);
      const std::uint8_t* l = left_valid.empty() ? nullptr : left_valid.ptr<std::uint8_t>(y);
      const std::uint8_t* r = right_valid.empty() ? nullptr : right_valid.ptr<std::uint8_t>(y);
      for (int x = 0; x < disparity.cols; ++x) {
        if (d[x] == kInvalidDisparity) continue;
        const double at = x - static_cast<double>(d[x]);
        const int lo = static_cast<int>(std::floor(at)), hi = static_cast<int>(std::ceil(at));
        const bool ok = (!l || l[x]) && (!r || (lo >= 0 && hi < disparity.cols && r[lo] && r[hi]));
        if (!ok) d[x] = kInvalidDisparity;
      }
    }
  });
}

// The options the half-resolution level matches with: the same, or with windows of half the rows
// (coarse_same_rows). Its interest operator and valid-window test keep the full window: a window is
// matched only where the usual coarse window has texture and lies wholly in the valid pixels.
StereoOptions CoarseOptions(const StereoOptions& o) {
  StereoOptions c = o;
  if (o.coarse_same_rows) c.block_height = 2 * std::max(1, o.block_height / 4) + 1;
  return c;
}

// The coarse level's disparity range: half the fine one's, rounded outwards.
int HalfMin(const StereoOptions& o) { return static_cast<int>(std::floor(o.min_disparity / 2.0)); }
int HalfCount(const StereoOptions& o) {
  return static_cast<int>(std::ceil((o.min_disparity + o.num_disparities - 1) / 2.0)) - HalfMin(o) + 1;
}

}  // namespace

cv::Mat LogPrefilter(const cv::Mat& grey, double sigma_px, double gain, int cap) {
  cv::Mat scratch[3], out;
  LogPrefilterInto(grey, sigma_px, gain, cap, scratch, out);
  return out;
}

std::pair<int, int> MatchedColumns(int width, const StereoOptions& options) {
  const ColumnRange columns = MatchableColumns(width, options.min_disparity, options.num_disparities, options.block_width);
  return {columns.lo, columns.hi};
}

cv::Mat TextureMask(const cv::Mat& log, const StereoOptions& options) {
  if (log.empty() || log.type() != CV_8U) throw Error("stereo: the texture mask needs an 8-bit LoG image");
  cv::Mat change, out;
  TextureMaskInto(log, options, change, out);
  return out;
}

SadStereoMatcher::SadStereoMatcher(const StereoOptions& options)
    : options_(options), ws_(std::make_unique<Workspace>()) {
  options_.Check();
}

SadStereoMatcher::~SadStereoMatcher() = default;

const cv::Mat& SadStereoMatcher::MatchLevel(const PreparedView& left, const PreparedView& right, int d_min, int n,
                                            int level, int first_column) {
  const StereoOptions o = level == 0 ? options_ : CoarseOptions(options_);
  const cv::Mat &left_log = left.log[level], &right_log = right.log[level], &textured = left.textured[level];
  LevelBuffers& buf = ws_->levels[level];
  const int w = left_log.cols, h = left_log.rows;
  cv::Mat& out = buf.out;
  out.create(h, w, CV_32F);
  out.setTo(cv::Scalar(kInvalidDisparity));

  const internal::SadKernel& kernel = internal::BestSadKernel(options_.baseline_kernel);
  internal::SadKernelInput in;
  in.left = left_log.ptr<std::uint8_t>();
  in.left_step = left_log.step;
  in.right = right_log.ptr<std::uint8_t>();
  in.right_step = right_log.step;
  in.textured = textured.ptr<std::uint8_t>();
  in.textured_step = textured.step;
  in.out = out.ptr<float>();
  in.out_step = out.step / sizeof(float);
  in.width = w;
  in.d_min = d_min;
  in.n = n;
  in.n_padded = (n + kernel.lanes - 1) / kernel.lanes * kernel.lanes;
  in.rw = o.block_width / 2;
  in.rh = o.block_height / 2;
  const ColumnRange columns = MatchableColumns(w, d_min, n, o.block_width);
  in.x_lo = std::max(columns.lo, first_column);
  in.x_hi = columns.hi;
  const int d_max = d_min + n - 1;
  in.pad = std::max(std::abs(d_min), std::abs(d_max)) + in.n_padded + in.rw + 2;
  in.uniqueness_percent = static_cast<int>(std::lround(o.uniqueness_ratio));
  in.subpixel = o.subpixel;
  in.left_right_check = o.left_right_check;
  in.left_right_max_diff = o.left_right_max_diff;
  const int y_lo = in.rh, y_hi = h - in.rh;  // rows [y_lo, y_hi)
  if (in.x_hi < in.x_lo || y_hi <= y_lo) return out;
  // One stripe per thread: each starts with a full window of rows, so fewer is cheaper.
  const int stripes = std::max(1, std::min((y_hi - y_lo) / 32, cv::getNumThreads()));
  buf.stripes.resize(std::max<size_t>(buf.stripes.size(), stripes));
  cv::parallel_for_(cv::Range(0, stripes), [&](const cv::Range& r) {
    for (int s = r.start; s < r.end; ++s) {
      const int a = y_lo + (y_hi - y_lo) * s / stripes, b = y_lo + (y_hi - y_lo) * (s + 1) / stripes;
      if (b > a) kernel.match_rows(in, a, b, buf.stripes[s].Prepare(w, in.n_padded, in.pad));
    }
  });
  KeepValidWindows(left.window_valid[level], right.window_valid[level], out);
  return out;
}

cv::Mat SadStereoMatcher::Compute(const cv::Mat& left_in, const cv::Mat& right_in, const cv::Mat& left_valid,
                                  const cv::Mat& right_valid) {
  const cv::Mat left = ToGrey(left_in, "left"), right = ToGrey(right_in, "right");
  if (left.size() != right.size()) {
    throw Error(Str("stereo: the right image (", right.cols, "x", right.rows, ") must have the left's rows and columns (",
                    left.cols, "x", left.rows, ")"));
  }
  RequireMatchable(left.cols, left.rows, options_);
  // Both images prepared at once (OpenCV runs the filters inside serially then).
  cv::parallel_for_(cv::Range(0, 2), [&](const cv::Range& r) {
    for (int i = r.start; i < r.end; ++i) {
      Prepare(i == 0 ? left : right, i == 0 ? &ws_->left : &ws_->right, i == 0 ? left_valid : right_valid);
    }
  });
  return Compute(ws_->left, ws_->right);
}

void SadStereoMatcher::FillFromCoarse(const cv::Mat& coarse, int first_column, cv::Mat& fine) const {
  const StereoOptions& o = options_;
  const float d_lo = static_cast<float>(o.min_disparity);
  const float d_hi = static_cast<float>(o.min_disparity + o.num_disparities - 1);
  // No check: a tolerance no difference exceeds (the invalid +inf is never compared).
  const float tolerance = o.cross_level_max_diff < 0 ? std::numeric_limits<float>::max()
                                                      : static_cast<float>(o.cross_level_max_diff);
  cv::parallel_for_(cv::Range(0, fine.rows), [&](const cv::Range& rows) {
    // The coarse row doubled and each value repeated over its two fine columns (the last one over
    // the rest), once per coarse row.
    std::vector<float> up(fine.cols);
    int up_row = -1;
    for (int y = rows.start; y < rows.end; ++y) {
      const int cy = std::min(y / 2, coarse.rows - 1);
      if (cy != up_row) {
        up_row = cy;
        const float* c = coarse.ptr<float>(cy);
        const int last = coarse.cols - 1;
        for (int x = 0; x < fine.cols; ++x) up[x] = 2.0f * c[std::min(x >> 1, last)];
      }
      float* f = fine.ptr<float>(y);
      int x = first_column;
#if CV_SIMD
      const cv::v_float32 invalid = cv::vx_setall_f32(kInvalidDisparity);
      const cv::v_float32 lo = cv::vx_setall_f32(d_lo), hi = cv::vx_setall_f32(d_hi), tol = cv::vx_setall_f32(tolerance);
      for (; x + cv::v_float32::nlanes <= fine.cols; x += cv::v_float32::nlanes) {
        const cv::v_float32 v = cv::vx_load(f + x), u = cv::vx_load(up.data() + x);
        // The invalid +inf coarse value fails u <= hi and u < invalid.
        const cv::v_float32 fill = (v == invalid) & (u >= lo) & (u <= hi);
        const cv::v_float32 disagree = (v < invalid) & (u < invalid) & (cv::v_abs(v - u) > tol);
        cv::v_store(f + x, cv::v_select(fill, u, cv::v_select(disagree, invalid, v)));
      }
#endif
      for (; x < fine.cols; ++x) {
        if (f[x] == kInvalidDisparity) {
          if (up[x] >= d_lo && up[x] <= d_hi) f[x] = up[x];  // false for the invalid +inf
        } else if (up[x] != kInvalidDisparity && std::abs(f[x] - up[x]) > tolerance) {
          f[x] = kInvalidDisparity;
        }
      }
    }
  });
}

void SadStereoMatcher::Prepare(const cv::Mat& image, PreparedView* view, const cv::Mat& valid) const {
  const StereoOptions& o = options_;
  cv::Mat grey = ToGrey(image, "prepared");
  if (!valid.empty() && (valid.size() != grey.size() || valid.type() != CV_8U)) {
    throw Error(Str("stereo: the validity mask (", valid.cols, "x", valid.rows,
                    ") must be 8-bit and of the image's size (", grey.cols, "x", grey.rows, ")"));
  }
  // What the mask implies, derived once per mask.
  const bool new_mask = !valid.empty() && (valid.data != view->mask_seen.data || valid.size() != view->mask_seen.size());
  if (valid.empty()) {
    view->mask_seen.release();
    view->mask_has_invalid = false;
    for (cv::Mat& v : view->window_valid) v.release();
  } else if (new_mask) {
    view->mask_seen = valid;
    view->mask_has_invalid = cv::countNonZero(valid) < static_cast<int>(valid.total());
    for (cv::Mat& v : view->window_valid) v.release();
    view->fill_map.release();
    if (view->mask_has_invalid) {
      view->fill_map = NearestValidMap(valid);
      WindowValidInto(valid, o, view->window_valid[0]);
      if (o.two_levels) {
        cv::Mat coarse;
        HalveValidity(valid, cv::Size((valid.cols + 1) / 2, (valid.rows + 1) / 2), view->scratch[0], coarse);
        WindowValidInto(coarse, o, view->window_valid[1]);
      }
    }
  }
  cv::Mat filled;
  if (view->mask_has_invalid) {
    cv::remap(grey, filled, view->fill_map, cv::noArray(), cv::INTER_NEAREST);
    grey = filled;
  }
  LogPrefilterInto(grey, o.log_sigma_px, o.prefilter_gain, o.prefilter_cap, view->scratch, view->log[0]);
  TextureMaskInto(view->log[0], o, view->scratch[0], view->textured[0]);
  if (!o.two_levels) {
    view->log[1].release();
    view->textured[1].release();
    return;
  }
  cv::pyrDown(grey, view->scratch[3]);
  LogPrefilterInto(view->scratch[3], o.log_sigma_px, o.prefilter_gain, o.prefilter_cap, view->scratch, view->log[1]);
  TextureMaskInto(view->log[1], o, view->scratch[0], view->textured[1]);
}

void SadStereoMatcher::Mirror(const PreparedView& view, PreparedView* mirrored) {
  for (int level = 0; level < 2; ++level) {
    if (view.log[level].empty()) {
      mirrored->log[level].release();
      mirrored->textured[level].release();
      mirrored->window_valid[level].release();
      continue;
    }
    cv::flip(view.log[level], mirrored->log[level], 1);
    cv::flip(view.textured[level], mirrored->textured[level], 1);
    if (view.window_valid[level].empty()) {
      mirrored->window_valid[level].release();
    } else {
      cv::flip(view.window_valid[level], mirrored->window_valid[level], 1);
    }
  }
}

cv::Mat SadStereoMatcher::Compute(const PreparedView& left, const PreparedView& right, int first_column) {
  const StereoOptions& o = options_;
  if (left.log[0].empty() || right.log[0].empty() || left.log[0].size() != right.log[0].size() ||
      left.log[1].empty() == o.two_levels || right.log[1].empty() == o.two_levels) {
    throw Error("stereo: the prepared views must be of one size and prepared with these options");
  }
  const int w = left.log[0].cols;
  if (first_column < 0 || first_column >= w) {
    throw Error(Str("stereo: first_column = ", first_column, ": violated constraint 0..", w - 1));
  }
  RequireMatchable(w, left.log[0].rows, o);
  cv::Mat fine = MatchLevel(left, right, o.min_disparity, o.num_disparities, 0, first_column).clone();
  // Coarse level: half resolution, half the disparities, the same window (twice the area).
  const ColumnRange coarse_columns = MatchableColumns(w / 2, HalfMin(o), HalfCount(o), o.block_width);
  if (!o.two_levels || coarse_columns.hi - coarse_columns.lo < o.block_width ||
      left.log[0].rows / 2 <= CoarseOptions(o).block_height) {
    return fine;
  }
  FillFromCoarse(MatchLevel(left, right, HalfMin(o), HalfCount(o), 1, first_column / 2), first_column, fine);
  return fine;
}

TemporalConsistencyFilter::TemporalConsistencyFilter(double forgetting, double max_variance_px2)
    : forgetting_(forgetting), max_variance_(max_variance_px2) {
  if (!(forgetting > 0.0 && forgetting <= 1.0)) {
    throw Error(Str("temporal filter: forgetting = ", forgetting, ": violated constraint 0 < f <= 1"));
  }
  if (!(max_variance_px2 > 0.0)) {
    throw Error(Str("temporal filter: max_variance_px2 = ", max_variance_px2, ": violated constraint > 0"));
  }
}

void TemporalConsistencyFilter::Reset() {
  mean_.release();
  var_.release();
  seen_.release();
}

cv::Mat TemporalConsistencyFilter::Apply(const cv::Mat& disparity) {
  CV_Assert(disparity.type() == CV_32F);
  if (mean_.size() != disparity.size()) {
    mean_ = cv::Mat(disparity.size(), CV_32F, cv::Scalar(0));
    var_ = cv::Mat(disparity.size(), CV_32F, cv::Scalar(0));
    seen_ = cv::Mat(disparity.size(), CV_32F, cv::Scalar(0));
  }
  cv::Mat out(disparity.size(), CV_32F);
  const float a = static_cast<float>(forgetting_);
  // The float whose "v > it" says v > max_variance_ (a double) for every float v.
  float max_variance = static_cast<float>(max_variance_);
  if (max_variance > max_variance_) max_variance = std::nextafter(max_variance, -kInvalidDisparity);
  // Per pixel: an invalid disparity resets it; the first valid one starts the mean (variance 0);
  // later ones update both by West's exponentially weighted formulas; a variance above the limit
  // suppresses the pixel. The vector and the scalar loop compute the same operations in the same
  // order.
  for (int y = 0; y < disparity.rows; ++y) {
    const float* d = disparity.ptr<float>(y);
    float* m = mean_.ptr<float>(y);
    float* v = var_.ptr<float>(y);
    float* seen = seen_.ptr<float>(y);
    float* o = out.ptr<float>(y);
    int x = 0;
#if CV_SIMD
    const cv::v_float32 va = cv::vx_setall_f32(a), vb = cv::vx_setall_f32(1.0f - a);
    const cv::v_float32 inf = cv::vx_setall_f32(kInvalidDisparity), ninf = cv::vx_setall_f32(-kInvalidDisparity);
    const cv::v_float32 limit = cv::vx_setall_f32(max_variance);
    const cv::v_float32 zero = cv::vx_setzero_f32(), one = cv::vx_setall_f32(1.0f);
    for (; x + cv::v_float32::nlanes <= disparity.cols; x += cv::v_float32::nlanes) {
      const cv::v_float32 dv = cv::vx_load(d + x), mv = cv::vx_load(m + x), vv = cv::vx_load(v + x);
      const cv::v_float32 valid = (dv < inf) & (dv > ninf);  // false for +-inf and NaN
      const cv::v_float32 first = cv::vx_load(seen + x) == zero;
      const cv::v_float32 diff = dv - mv;
      const cv::v_float32 mean = cv::v_select(first, dv, mv + va * diff);
      const cv::v_float32 var = cv::v_select(first, zero, vb * (vv + va * diff * diff));
      cv::v_store(m + x, cv::v_select(valid, mean, mv));
      cv::v_store(v + x, cv::v_select(valid, var, vv));
      cv::v_store(seen + x, cv::v_select(valid, one, zero));
      cv::v_store(o + x, cv::v_select(valid & (var > limit), inf, dv));
    }
#endif
    for (; x < disparity.cols; ++x) {
      o[x] = d[x];
      if (!std::isfinite(d[x])) {
        seen[x] = 0.0f;
        continue;
      }
      if (seen[x] == 0.0f) {
        m[x] = d[x];
        v[x] = 0.0f;
      } else {
        const float diff = d[x] - m[x];
        m[x] += a * diff;
        v[x] = (1.0f - a) * (v[x] + a * diff * diff);
      }
      seen[x] = 1.0f;
      if (v[x] > max_variance) o[x] = kInvalidDisparity;
    }
  }
  return out;
}

}  // namespace dps
