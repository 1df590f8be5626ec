#include "dps/sad_stereo.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
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

// hsad[x][k] += |L(y, x) - R(y, x - d_max + k)| for x in [x0, x1): the column sums of a new row.
// Costs are stored with k = d_max - d so that the right pixels of consecutive k are consecutive.
void AddRow(const LevelInput& in, const std::uint8_t* left_row, const std::uint8_t* right_padded,
            int x0, int x1, std::uint16_t* hsad) {
  const int np = in.n_padded;
  const int d_max = in.d_min + in.n - 1;
  for (int x = x0; x < x1; ++x) {
    std::uint16_t* h = hsad + static_cast<size_t>(x) * np;
    const std::uint8_t* r = right_padded + in.pad + x - d_max;
    const int l = left_row[x];
    for (int k = 0; k < np; ++k) h[k] = static_cast<std::uint16_t>(h[k] + std::abs(l - r[k]));
  }
}

// The window moves down one row: hsad += |L(y_in) - R(y_in)| - |L(y_out) - R(y_out)|, in one
// pass over the column sums.
void SlideRows(const LevelInput& in, const std::uint8_t* left_in, const std::uint8_t* right_in,
               const std::uint8_t* left_out, const std::uint8_t* right_out, int x0, int x1,
               std::uint16_t* hsad) {
  const int np = in.n_padded;
  const int d_max = in.d_min + in.n - 1;
  for (int x = x0; x < x1; ++x) {
    std::uint16_t* h = hsad + static_cast<size_t>(x) * np;
    const std::uint8_t* ri = right_in + in.pad + x - d_max;
    const std::uint8_t* ro = right_out + in.pad + x - d_max;
    int k = 0;
#if CV_SIMD
    const Cost li = cv::vx_setall_u16(left_in[x]), lo = cv::vx_setall_u16(left_out[x]);
    for (; k < np; k += kLanes) {
      const Cost add = cv::v_absdiff(li, cv::vx_load_expand(ri + k));
      const Cost sub = cv::v_absdiff(lo, cv::vx_load_expand(ro + k));
      cv::v_store(h + k, cv::vx_load(h + k) + add - sub);
    }
#endif
    for (; k < np; ++k) {
      h[k] = static_cast<std::uint16_t>(h[k] + std::abs(left_in[x] - ri[k]) - std::abs(left_out[x] - ro[k]));
    }
  }
}

// sad[k] += hin[k] - hout[k]: the window moves one column to the right.
inline void SlideWindow(std::uint16_t* sad, const std::uint16_t* hin, const std::uint16_t* hout, int np) {
  int k = 0;
#if CV_SIMD
  for (; k < np; k += kLanes) cv::v_store(sad + k, cv::vx_load(sad + k) + cv::vx_load(hin + k) - cv::vx_load(hout + k));
#endif
  for (; k < np; ++k) sad[k] = static_cast<std::uint16_t>(sad[k] + hin[k] - hout[k]);
}

}  // namespace

// Buffers of one stripe of rows, kept between calls (allocating them anew each time costs as much
// as a good part of the matching: fresh pages fault in).
struct StripeBuffers {
  std::vector<std::uint16_t> hsad, sad, cost2;
  std::vector<std::uint8_t> padded, padded_out;
  std::vector<int> disp2, best_d;
  std::vector<float> row_disp;
};

// Everything one pyramid level needs between calls.
struct LevelBuffers {
  cv::Mat f, blurred, log, shifted;  // prefilter temporaries
  cv::Mat left, right, magnitude, mean, textured, out;
  std::vector<StripeBuffers> stripes;
};

struct SadStereoMatcher::Workspace {
  LevelBuffers levels[2];
  cv::Mat left_grey, right_grey, left_half, right_half;
};

namespace {

// Matches rows [y0, y1) of one level; writes sub-pixel disparities into `out` (CV_32F).
void MatchStripe(const LevelInput& in, const StereoOptions& o, int y0, int y1, StripeBuffers& buf,
                 cv::Mat& out) {
  const int w = in.left.cols;
  const int np = in.n_padded;
  const int d_max = in.d_min + in.n - 1;
  const int xa = std::max(0, in.x_lo - in.rw), xb = std::min(w, in.x_hi + in.rw + 1);
  std::vector<std::uint16_t>& hsad = buf.hsad;
  hsad.assign(static_cast<size_t>(w) * np, 0);
  std::vector<std::uint16_t>& sad = buf.sad;
  sad.assign(np, 0);
  std::vector<std::uint8_t>& padded = buf.padded;
  std::vector<std::uint8_t>& padded_out = buf.padded_out;
  padded.resize(static_cast<size_t>(w) + 2 * in.pad);
  padded_out.resize(padded.size());
  std::vector<std::uint16_t>& cost2 = buf.cost2;
  cost2.resize(w);
  std::vector<int>& disp2 = buf.disp2;
  std::vector<int>& best_d = buf.best_d;
  disp2.resize(w);
  best_d.resize(w);
  std::vector<float>& row_disp = buf.row_disp;
  row_disp.resize(w);
#if CV_SIMD
  alignas(64) std::uint16_t ramp_values[kLanes];
  for (int i = 0; i < kLanes; ++i) ramp_values[i] = static_cast<std::uint16_t>(i);
  const Cost ramp = cv::vx_load_aligned(ramp_values);
  const Cost step = cv::vx_setall_u16(static_cast<std::uint16_t>(kLanes));
  const Cost limit = cv::vx_setall_u16(static_cast<std::uint16_t>(in.n));
#endif
  const int uniq = static_cast<int>(std::lround(o.uniqueness_ratio));

  // Column sums over the first window.
  for (int yy = y0 - in.rh; yy <= y0 + in.rh; ++yy) {
    PadRow(in.right, yy, in.pad, padded.data());
    AddRow(in, in.left.ptr<std::uint8_t>(yy), padded.data(), xa, xb, hsad.data());
  }
  for (int y = y0; y < y1; ++y) {
    if (y > y0) {
      PadRow(in.right, y + in.rh, in.pad, padded.data());
      PadRow(in.right, y - in.rh - 1, in.pad, padded_out.data());
      SlideRows(in, in.left.ptr<std::uint8_t>(y + in.rh), padded.data(),
                in.left.ptr<std::uint8_t>(y - in.rh - 1), padded_out.data(), xa, xb, hsad.data());
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
      const bool slide = x > in.x_lo;
      const std::uint16_t* hin = slide ? &hsad[static_cast<size_t>(x + in.rw) * np] : nullptr;
      const std::uint16_t* hout = slide ? &hsad[static_cast<size_t>(x - in.rw - 1) * np] : nullptr;
      if (!textured[x]) {
        if (slide) SlideWindow(sad.data(), hin, hout, np);
        continue;
      }
      // Slide the window and find the best disparity (smallest cost; lanes k >= n, padding
      // outside the range, are excluded) in one pass.
      int k_best = 0;
      std::uint16_t c_best = kMaxCost;
#if CV_SIMD
      {
        Cost vmin = cv::vx_setall_u16(kMaxCost), vidx = cv::vx_setzero_u16();
        Cost kv = ramp;
        for (int k = 0; k < np; k += kLanes) {
          Cost c = cv::vx_load(&sad[k]);
          if (slide) {
            c = c + cv::vx_load(hin + k) - cv::vx_load(hout + k);
            cv::v_store(&sad[k], c);
          }
          if (k + kLanes > in.n) c = cv::v_select(kv < limit, c, cv::vx_setall_u16(kMaxCost));
          vidx = cv::v_select(c < vmin, kv, vidx);
          vmin = cv::v_min(vmin, c);
          kv += step;
        }
        c_best = cv::v_reduce_min(vmin);
        k_best = cv::v_reduce_min(cv::v_select(vmin == cv::vx_setall_u16(c_best), vidx,
                                               cv::vx_setall_u16(kMaxCost)));
      }
#else
      if (slide) SlideWindow(sad.data(), hin, hout, np);
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
      const int thresh = std::min<int>(kMaxCost - 1, c_best + c_best * uniq / 100);
      bool unique = true;
      int k = 0;
#if CV_SIMD
      {
        const Cost vthresh = cv::vx_setall_u16(static_cast<std::uint16_t>(thresh));
        // Lanes k_best - 1 .. k_best + 1 are allowed to be close: (k - (k_best - 1)) <= 2 unsigned.
        const Cost lo = cv::vx_setall_u16(static_cast<std::uint16_t>(k_best - 1));
        const Cost two = cv::vx_setall_u16(2);
        Cost kv = ramp;
        for (; k + kLanes <= in.n; k += kLanes) {
          const Cost close = cv::vx_load(&sad[k]) <= vthresh;
          const Cost neighbour = (kv - lo) <= two;
          if (cv::v_check_any(close & ~neighbour)) {
            unique = false;
            break;
          }
          kv += step;
        }
      }
#endif
      for (; k < in.n && unique; ++k) {
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

namespace {

// The LoG prefilter into `out`, reusing the temporaries in `buf`.
void LogPrefilterInto(const cv::Mat& grey, double sigma_px, double gain, int cap, LevelBuffers& buf,
                      cv::Mat& out) {
  // In floating point: blurring into 8 bits first would quantise the image, and the Laplacian
  // would amplify the rounding into noise that swamps weak texture.
  grey.convertTo(buf.f, CV_32F);
  cv::GaussianBlur(buf.f, buf.blurred, cv::Size(), sigma_px, sigma_px, cv::BORDER_REPLICATE);
  cv::Laplacian(buf.blurred, buf.log, CV_32F, 1, gain, 0.0, cv::BORDER_REPLICATE);
  // Clamp to +-cap and offset by cap: round to 8 bits around 128 (saturating), then a table.
  buf.log.convertTo(buf.shifted, CV_8U, 1.0, 128.0);
  std::uint8_t table[256];
  for (int v = 0; v < 256; ++v) table[v] = static_cast<std::uint8_t>(std::clamp(v - 128, -cap, cap) + cap);
  cv::LUT(buf.shifted, cv::Mat(1, 256, CV_8U, table), out);
}

}  // namespace

cv::Mat LogPrefilter(const cv::Mat& grey, double sigma_px, double gain, int cap) {
  LevelBuffers buf;
  cv::Mat out;
  LogPrefilterInto(grey, sigma_px, gain, cap, buf, out);
  return out;
}

SadStereoMatcher::SadStereoMatcher(const StereoOptions& options)
    : options_(options), ws_(std::make_unique<Workspace>()) {
  options_.Check();
}

SadStereoMatcher::~SadStereoMatcher() = default;

const cv::Mat& SadStereoMatcher::ComputeLevel(const cv::Mat& left, const cv::Mat& right, int d_min,
                                              int n, int level) {
  const StereoOptions& o = options_;
  LevelBuffers& buf = ws_->levels[level];
  LevelInput in;
  LogPrefilterInto(left, o.log_sigma_px, o.prefilter_gain, o.prefilter_cap, buf, buf.left);
  LogPrefilterInto(right, o.log_sigma_px, o.prefilter_gain, o.prefilter_cap, buf, buf.right);
  in.left = buf.left;
  in.right = buf.right;
  cv::absdiff(buf.left, cv::Scalar(o.prefilter_cap), buf.magnitude);
  cv::boxFilter(buf.magnitude, buf.mean, CV_32F, cv::Size(o.block_width, o.block_height),
                cv::Point(-1, -1), true, cv::BORDER_REPLICATE);
  cv::compare(buf.mean, o.texture_threshold, buf.textured, cv::CMP_GE);
  in.textured = buf.textured;
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
  cv::Mat& out = buf.out;
  out.create(h, w, CV_32F);
  out.setTo(cv::Scalar(kInvalidDisparity));
  const int y_lo = in.rh, y_hi = h - in.rh;  // rows [y_lo, y_hi)
  if (in.x_hi < in.x_lo || y_hi <= y_lo) return out;
  // A few stripes per thread: each starts with a full window of rows, so fewer is cheaper.
  const int stripes = std::max(1, std::min((y_hi - y_lo) / 32, 2 * cv::getNumThreads()));
  buf.stripes.resize(std::max<size_t>(buf.stripes.size(), stripes));
  cv::parallel_for_(cv::Range(0, stripes), [&](const cv::Range& r) {
    for (int s = r.start; s < r.end; ++s) {
      const int a = y_lo + (y_hi - y_lo) * s / stripes, b = y_lo + (y_hi - y_lo) * (s + 1) / stripes;
      if (b > a) MatchStripe(in, o, a, b, buf.stripes[s], out);
    }
  });
  return out;
}

cv::Mat SadStereoMatcher::Compute(const cv::Mat& left_in, const cv::Mat& right_in) {
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
  cv::Mat fine = ComputeLevel(left, right, o.min_disparity, o.num_disparities, 0).clone();
  if (!o.two_levels || left.cols / 2 <= span / 2 + o.block_width || left.rows / 2 <= o.block_height) {
    return fine;
  }
  // Coarse level: half resolution, half the disparities, the same window (twice the area).
  cv::Mat& left_half = ws_->left_half;
  cv::Mat& right_half = ws_->right_half;
  cv::pyrDown(left, left_half);
  cv::pyrDown(right, right_half);
  const int d_min_half = static_cast<int>(std::floor(o.min_disparity / 2.0));
  const int d_max_half = static_cast<int>(std::ceil((o.min_disparity + o.num_disparities - 1) / 2.0));
  const cv::Mat& coarse = ComputeLevel(left_half, right_half, d_min_half, d_max_half - d_min_half + 1, 1);
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
