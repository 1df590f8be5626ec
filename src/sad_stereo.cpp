#include "dps/sad_stereo.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <opencv2/core/hal/intrin.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include "dps/error.h"

namespace dps {
namespace {

constexpr std::uint16_t kMaxCost = 0xFFFF;

void Require(bool ok, const char* field, double value, const char* constraint) {
  if (!ok) throw Error(Str("stereo option ", field, " = ", value, ": violated constraint ", constraint));
}

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

#if CV_SIMD
using Cost = cv::v_uint16;
constexpr int kLanes = cv::v_uint16::nlanes;
#else
constexpr int kLanes = 1;
#endif

// Everything one level of matching needs, shared by the row stripes.
struct LevelInput {
  cv::Mat left;     // prefiltered, CV_8U
  cv::Mat right;    // prefiltered, CV_8U
  cv::Mat textured; // CV_8U, 255 where the window's mean |LoG| reaches the threshold
  int d_min = 0, n = 0, n_padded = 0;
  int rw = 0, rh = 0;
  int x_lo = 0, x_hi = -1;  // columns (inclusive) where every disparity's window is inside
  int pad = 0;              // columns of replicated border on each side of a padded right row
};

// Copies one prefiltered right row into `dst` with `pad` replicated columns on each side.
void PadRow(const cv::Mat& right, int y, int pad, std::uint8_t* dst) {
  const std::uint8_t* src = right.ptr<std::uint8_t>(y);
  const int w = right.cols;
  std::fill(dst, dst + pad, src[0]);
  std::copy(src, src + w, dst + pad);
  std::fill(dst + pad + w, dst + pad + w + pad, src[w - 1]);
}

// hsad[x][k] (+|-)= |L(y, x) - R(y, x - d_max + k)| for x in [x0, x1).
// Costs are stored with k = d_max - d so that the right pixels of consecutive k are consecutive.
void AccumulateRow(const LevelInput& in, const std::uint8_t* left_row, const std::uint8_t* right_padded,
                   int x0, int x1, bool add, std::uint16_t* hsad) {
  const int np = in.n_padded;
  const int d_max = in.d_min + in.n - 1;
  for (int x = x0; x < x1; ++x) {
    std::uint16_t* h = hsad + static_cast<size_t>(x) * np;
    const std::uint8_t* r = right_padded + in.pad + x - d_max;
    const std::uint16_t l = left_row[x];
    int k = 0;
#if CV_SIMD
    const Cost vl = cv::vx_setall_u16(l);
    for (; k < np; k += kLanes) {
      const Cost diff = cv::v_absdiff(vl, cv::vx_load_expand(r + k));
      const Cost cur = cv::vx_load(h + k);
      cv::v_store(h + k, add ? cur + diff : cur - diff);
    }
#endif
    for (; k < np; ++k) {
      const std::uint16_t diff = static_cast<std::uint16_t>(std::abs(static_cast<int>(l) - r[k]));
      h[k] = static_cast<std::uint16_t>(add ? h[k] + diff : h[k] - diff);
    }
  }
}

// Matches rows [y0, y1) of one level; writes sub-pixel disparities into `out` (CV_32F).
void MatchStripe(const LevelInput& in, const StereoOptions& o, int y0, int y1, cv::Mat& out) {
  const int w = in.left.cols;
  const int np = in.n_padded;
  const int d_max = in.d_min + in.n - 1;
  const int xa = std::max(0, in.x_lo - in.rw), xb = std::min(w, in.x_hi + in.rw + 1);
  std::vector<std::uint16_t> hsad(static_cast<size_t>(w) * np, 0);
  std::vector<std::uint16_t> sad(np, 0);
  std::vector<std::uint8_t> padded(static_cast<size_t>(w) + 2 * in.pad);
  std::vector<std::uint16_t> cost2(w);
  std::vector<int> disp2(w), best_d(w);
  std::vector<float> row_disp(w);
  alignas(64) std::uint16_t lane_min[kLanes], lane_idx[kLanes];
  const int uniq = static_cast<int>(std::lround(o.uniqueness_ratio));

  // Column sums over the first window.
  for (int yy = y0 - in.rh; yy <= y0 + in.rh; ++yy) {
    PadRow(in.right, yy, in.pad, padded.data());
    AccumulateRow(in, in.left.ptr<std::uint8_t>(yy), padded.data(), xa, xb, true, hsad.data());
  }
  for (int y = y0; y < y1; ++y) {
    if (y > y0) {
      PadRow(in.right, y + in.rh, in.pad, padded.data());
      AccumulateRow(in, in.left.ptr<std::uint8_t>(y + in.rh), padded.data(), xa, xb, true, hsad.data());
      PadRow(in.right, y - in.rh - 1, in.pad, padded.data());
      AccumulateRow(in, in.left.ptr<std::uint8_t>(y - in.rh - 1), padded.data(), xa, xb, false, hsad.data());
    }
    std::fill(cost2.begin(), cost2.end(), kMaxCost);
    std::fill(row_disp.begin(), row_disp.end(), kInvalidDisparity);
    std::fill(best_d.begin(), best_d.end(), 0);
    // Row sums over the first window.
    std::fill(sad.begin(), sad.end(), 0);
    for (int x = in.x_lo - in.rw; x <= in.x_lo + in.rw; ++x) {
      const std::uint16_t* h = &hsad[static_cast<size_t>(x) * np];
      for (int k = 0; k < np; ++k) sad[k] = static_cast<std::uint16_t>(sad[k] + h[k]);
    }
    const std::uint8_t* textured = in.textured.ptr<std::uint8_t>(y);
    for (int x = in.x_lo; x <= in.x_hi; ++x) {
      if (x > in.x_lo) {
        const std::uint16_t* hin = &hsad[static_cast<size_t>(x + in.rw) * np];
        const std::uint16_t* hout = &hsad[static_cast<size_t>(x - in.rw - 1) * np];
        int k = 0;
#if CV_SIMD
        for (; k < np; k += kLanes) {
          cv::v_store(&sad[k], cv::vx_load(&sad[k]) + cv::vx_load(hin + k) - cv::vx_load(hout + k));
        }
#endif
        for (; k < np; ++k) sad[k] = static_cast<std::uint16_t>(sad[k] + hin[k] - hout[k]);
      }
      if (!textured[x]) continue;
      // Best disparity (smallest cost; padded lanes k >= n are outside the range).
      int k_best = 0;
      std::uint16_t c_best = kMaxCost;
#if CV_SIMD
      {
        Cost vmin = cv::vx_setall_u16(kMaxCost), vidx = cv::vx_setzero_u16();
        alignas(64) std::uint16_t ramp[kLanes];
        for (int i = 0; i < kLanes; ++i) ramp[i] = static_cast<std::uint16_t>(i);
        Cost kv = cv::vx_load_aligned(ramp);
        const Cost step = cv::vx_setall_u16(static_cast<std::uint16_t>(kLanes));
        const Cost limit = cv::vx_setall_u16(static_cast<std::uint16_t>(in.n));
        for (int k = 0; k < np; k += kLanes) {
          Cost c = cv::vx_load(&sad[k]);
          c = cv::v_select(kv < limit, c, cv::vx_setall_u16(kMaxCost));
          const Cost better = c < vmin;
          vmin = cv::v_min(vmin, c);
          vidx = cv::v_select(better, kv, vidx);
          kv += step;
        }
        cv::v_store_aligned(lane_min, vmin);
        cv::v_store_aligned(lane_idx, vidx);
        for (int i = 0; i < kLanes; ++i) {
          if (lane_min[i] < c_best || (lane_min[i] == c_best && lane_idx[i] < k_best)) {
            c_best = lane_min[i];
            k_best = lane_idx[i];
          }
        }
      }
#else
      for (int k = 0; k < in.n; ++k) {
        if (sad[k] < c_best) c_best = sad[k], k_best = k;
      }
#endif
      const int d = d_max - k_best;
      // The best match of the right pixel x - d seen from the left (for the left-right check).
      const int xr = x - d;
      if (xr >= 0 && xr < w && c_best < cost2[xr]) {
        cost2[xr] = c_best;
        disp2[xr] = d;
      }
      // Uniqueness: no non-adjacent disparity within uniq % of the best.
      const int thresh = c_best + c_best * uniq / 100;
      bool unique = true;
      for (int k = 0; k < in.n && unique; ++k) {
        if (sad[k] <= thresh && (k < k_best - 1 || k > k_best + 1)) unique = false;
      }
      if (!unique) continue;
      float disp = static_cast<float>(d);
      if (o.subpixel && k_best > 0 && k_best < in.n - 1) {
        // Equiangular fit: SAD is V-shaped around its minimum, so a V through the three costs
        // (steeper side's slope) locates it exactly; a parabola would be biased to integers.
        const int c_dm = sad[k_best + 1], c_dp = sad[k_best - 1];  // costs at d - 1 and d + 1
        const int slope = std::max(c_dm, c_dp) - c_best;
        if (slope > 0) disp += static_cast<float>(c_dm - c_dp) / (2.0f * slope);
      }
      row_disp[x] = disp;
      best_d[x] = d;
    }
    float* dst = out.ptr<float>(y);
    for (int x = in.x_lo; x <= in.x_hi; ++x) {
      if (!std::isfinite(row_disp[x])) continue;
      if (o.left_right_check) {
        const int xr = x - best_d[x];
        if (xr < 0 || xr >= w || cost2[xr] == kMaxCost ||
            std::abs(disp2[xr] - best_d[x]) > o.left_right_max_diff) {
          continue;
        }
      }
      dst[x] = row_disp[x];
    }
  }
}

}  // namespace

void StereoOptions::Check() const {
  Require(num_disparities >= 2, "num_disparities", num_disparities, ">= 2");
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
  // The window's cost must fit 16 bits: (2 cap) * area < 65536.
  Require(2 * prefilter_cap * block_width * block_height < 65536, "prefilter_cap", prefilter_cap,
          "2 cap * block area < 65536");
}

cv::Mat LogPrefilter(const cv::Mat& grey, double sigma_px, double gain, int cap) {
  // In floating point: blurring into 8 bits first would quantise the image, and the Laplacian
  // would amplify the rounding into noise that swamps weak texture.
  cv::Mat f, blurred, log, out;
  grey.convertTo(f, CV_32F);
  cv::GaussianBlur(f, blurred, cv::Size(), sigma_px, sigma_px, cv::BORDER_REPLICATE);
  cv::Laplacian(blurred, log, CV_32F, 1, gain, 0.0, cv::BORDER_REPLICATE);
  log = cv::min(cv::max(log, -cap), cap);
  log.convertTo(out, CV_8U, 1.0, cap);
  return out;
}

SadStereoMatcher::SadStereoMatcher(const StereoOptions& options) : options_(options) {
  options_.Check();
}

cv::Mat SadStereoMatcher::ComputeLevel(const cv::Mat& left, const cv::Mat& right, int d_min,
                                       int n) const {
  const StereoOptions& o = options_;
  LevelInput in;
  in.left = LogPrefilter(left, o.log_sigma_px, o.prefilter_gain, o.prefilter_cap);
  in.right = LogPrefilter(right, o.log_sigma_px, o.prefilter_gain, o.prefilter_cap);
  cv::Mat magnitude, mean;
  cv::absdiff(in.left, cv::Scalar(o.prefilter_cap), magnitude);
  cv::boxFilter(magnitude, mean, CV_32F, cv::Size(o.block_width, o.block_height), cv::Point(-1, -1),
                true, cv::BORDER_REPLICATE);
  in.textured = mean >= o.texture_threshold;
  in.d_min = d_min;
  in.n = n;
  in.n_padded = (n + kLanes - 1) / kLanes * kLanes;
  in.rw = o.block_width / 2;
  in.rh = o.block_height / 2;
  const int w = left.cols, h = left.rows;
  const int d_max = d_min + n - 1;
  in.x_lo = in.rw + std::max(0, d_max);
  in.x_hi = w - 1 - in.rw - std::max(0, -d_min);
  in.pad = std::max(std::abs(d_min), std::abs(d_max)) + in.n_padded + in.rw + 2;
  cv::Mat out(h, w, CV_32F, cv::Scalar(kInvalidDisparity));
  const int y_lo = in.rh, y_hi = h - in.rh;  // rows [y_lo, y_hi)
  if (in.x_hi < in.x_lo || y_hi <= y_lo) return out;
  const int stripes = std::max(1, std::min((y_hi - y_lo) / 16, 4 * cv::getNumThreads()));
  cv::parallel_for_(cv::Range(0, stripes), [&](const cv::Range& r) {
    for (int s = r.start; s < r.end; ++s) {
      const int a = y_lo + (y_hi - y_lo) * s / stripes, b = y_lo + (y_hi - y_lo) * (s + 1) / stripes;
      if (b > a) MatchStripe(in, o, a, b, out);
    }
  });
  return out;
}

cv::Mat SadStereoMatcher::Compute(const cv::Mat& left_in, const cv::Mat& right_in) const {
  const cv::Mat left = ToGrey(left_in, "left"), right = ToGrey(right_in, "right");
  if (left.size() != right.size()) {
    throw Error(Str("stereo: the images differ in size: ", left.cols, "x", left.rows, " and ",
                    right.cols, "x", right.rows));
  }
  const StereoOptions& o = options_;
  const int span = o.block_width + std::max(0, o.min_disparity + o.num_disparities - 1) +
                   std::max(0, -o.min_disparity);
  if (left.cols <= span || left.rows <= o.block_height) {
    throw Error(Str("stereo: a ", left.cols, "x", left.rows, " image is too small for ",
                    o.num_disparities, " disparities from ", o.min_disparity, " with a ",
                    o.block_width, "x", o.block_height, " block"));
  }
  cv::Mat fine = ComputeLevel(left, right, o.min_disparity, o.num_disparities);
  if (!o.two_levels || left.cols / 2 <= span / 2 + o.block_width || left.rows / 2 <= o.block_height) {
    return fine;
  }
  // Coarse level: half resolution, half the disparities, the same window (twice the area).
  cv::Mat left_half, right_half;
  cv::pyrDown(left, left_half);
  cv::pyrDown(right, right_half);
  const int d_min_half = static_cast<int>(std::floor(o.min_disparity / 2.0));
  const int d_max_half = static_cast<int>(std::ceil((o.min_disparity + o.num_disparities - 1) / 2.0));
  const cv::Mat coarse = ComputeLevel(left_half, right_half, d_min_half, d_max_half - d_min_half + 1);
  const float d_lo = static_cast<float>(o.min_disparity);
  const float d_hi = static_cast<float>(o.min_disparity + o.num_disparities - 1);
  for (int y = 0; y < fine.rows; ++y) {
    float* f = fine.ptr<float>(y);
    const float* c = coarse.ptr<float>(std::min(y / 2, coarse.rows - 1));
    for (int x = 0; x < fine.cols; ++x) {
      if (std::isfinite(f[x])) continue;
      const float d = 2.0f * c[std::min(x / 2, coarse.cols - 1)];
      if (std::isfinite(d) && d >= d_lo && d <= d_hi) f[x] = d;
    }
  }
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
  count_.release();
}

cv::Mat TemporalConsistencyFilter::Apply(const cv::Mat& disparity) {
  CV_Assert(disparity.type() == CV_32F);
  if (mean_.size() != disparity.size()) {
    mean_ = cv::Mat(disparity.size(), CV_32F, cv::Scalar(0));
    var_ = cv::Mat(disparity.size(), CV_32F, cv::Scalar(0));
    count_ = cv::Mat(disparity.size(), CV_8U, cv::Scalar(0));
  }
  cv::Mat out = disparity.clone();
  const float a = static_cast<float>(forgetting_);
  for (int y = 0; y < disparity.rows; ++y) {
    const float* d = disparity.ptr<float>(y);
    float* m = mean_.ptr<float>(y);
    float* v = var_.ptr<float>(y);
    std::uint8_t* n = count_.ptr<std::uint8_t>(y);
    float* o = out.ptr<float>(y);
    for (int x = 0; x < disparity.cols; ++x) {
      if (!std::isfinite(d[x])) {
        n[x] = 0;
        continue;
      }
      if (n[x] == 0) {
        m[x] = d[x];
        v[x] = 0.0f;
      } else {
        // Exponentially weighted mean and variance (West's update).
        const float diff = d[x] - m[x];
        m[x] += a * diff;
        v[x] = (1.0f - a) * (v[x] + a * diff * diff);
      }
      n[x] = static_cast<std::uint8_t>(std::min(255, n[x] + 1));
      if (v[x] > max_variance_) o[x] = kInvalidDisparity;
    }
  }
  return out;
}

}  // namespace dps
