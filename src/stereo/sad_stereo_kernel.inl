// The SAD matching kernel (Gandhi & Trivedi 2006, eq. 13 and section V step 3), included by
// sad_stereo_kernel_baseline.cpp and sad_stereo_kernel_avx2.cpp with DPS_KERNEL_NAMESPACE set.
// Everything here has internal linkage but the kernel table, so the two builds share no code.
//
// Costs are kept per column: hsad[x][k] = sum over the window's rows of |L(y, x) - R(y, x - d)|
// with k = d_max - d (so that the right pixels of consecutive k are consecutive in memory); the
// window's cost is the sum of hsad over its columns, updated as the window moves right (sad) and
// down (hsad). Both updates and the search for the best k run over k with universal intrinsics.
#include <cstdint>
#include <limits>

#include <opencv2/core/hal/intrin.hpp>

#include "sad_stereo_kernel.h"

namespace dps {
namespace internal {
namespace DPS_KERNEL_NAMESPACE {
namespace {

constexpr std::uint16_t kMaxCost = 0xFFFF;
constexpr float kInvalid = std::numeric_limits<float>::infinity();

#if CV_SIMD
using Cost = cv::v_uint16;
constexpr int kLanes = cv::v_uint16::nlanes;
#else
constexpr int kLanes = 1;
#endif

inline int Abs(int v) { return v < 0 ? -v : v; }
inline int Max(int a, int b) { return a > b ? a : b; }
inline int Min(int a, int b) { return a < b ? a : b; }

const std::uint8_t* Row(const std::uint8_t* data, std::size_t step, int y) { return data + step * y; }

// Copies one right row into `dst` with `pad` replicated columns on each side.
void PadRow(const SadKernelInput& in, int y, std::uint8_t* dst) {
  const std::uint8_t* src = Row(in.right, in.right_step, y);
  const int w = in.width;
  for (int i = 0; i < in.pad; ++i) dst[i] = src[0];
  for (int i = 0; i < w; ++i) dst[in.pad + i] = src[i];
  for (int i = 0; i < in.pad; ++i) dst[in.pad + w + i] = src[w - 1];
}

// hsad[x][k] += |L(y, x) - R(y, x - d_max + k)| for x in [x0, x1): the column sums of a new row.
void AddRow(const SadKernelInput& in, const std::uint8_t* left_row, const std::uint8_t* right_padded,
            int x0, int x1, std::uint16_t* hsad) {
  const int np = in.n_padded;
  const int d_max = in.d_min + in.n - 1;
  for (int x = x0; x < x1; ++x) {
    std::uint16_t* h = hsad + static_cast<std::size_t>(x) * np;
    const std::uint8_t* r = right_padded + in.pad + x - d_max;
    const int l = left_row[x];
    int k = 0;
#if CV_SIMD
    const Cost vl = cv::vx_setall_u16(static_cast<std::uint16_t>(l));
    for (; k < np; k += kLanes) {
      cv::v_store(h + k, cv::vx_load(h + k) + cv::v_absdiff(vl, cv::vx_load_expand(r + k)));
    }
#endif
    for (; k < np; ++k) h[k] = static_cast<std::uint16_t>(h[k] + Abs(l - r[k]));
  }
}

// The window moves down one row: hsad += |L(y_in) - R(y_in)| - |L(y_out) - R(y_out)|, in one
// pass over the column sums.
void SlideRows(const SadKernelInput& in, const std::uint8_t* left_in, const std::uint8_t* right_in,
               const std::uint8_t* left_out, const std::uint8_t* right_out, int x0, int x1,
               std::uint16_t* hsad) {
  const int np = in.n_padded;
  const int d_max = in.d_min + in.n - 1;
  for (int x = x0; x < x1; ++x) {
    std::uint16_t* h = hsad + static_cast<std::size_t>(x) * np;
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
      h[k] = static_cast<std::uint16_t>(h[k] + Abs(left_in[x] - ri[k]) - Abs(left_out[x] - ro[k]));
    }
  }
}

// sad[k] += hin[k] - hout[k]: the window moves one column to the right.
inline void SlideWindow(std::uint16_t* sad, const std::uint16_t* hin, const std::uint16_t* hout, int np) {
  int k = 0;
#if CV_SIMD
  for (; k < np; k += kLanes) {
    cv::v_store(sad + k, cv::vx_load(sad + k) + cv::vx_load(hin + k) - cv::vx_load(hout + k));
  }
#endif
  for (; k < np; ++k) sad[k] = static_cast<std::uint16_t>(sad[k] + hin[k] - hout[k]);
}

// The lane indices and constants of the search over k (vectors only).
struct LaneConstants {
#if CV_SIMD
  Cost ramp, step, limit;
  explicit LaneConstants(int n) {
    alignas(64) std::uint16_t ramp_values[kLanes];
    for (int i = 0; i < kLanes; ++i) ramp_values[i] = static_cast<std::uint16_t>(i);
    ramp = cv::vx_load_aligned(ramp_values);
    step = cv::vx_setall_u16(static_cast<std::uint16_t>(kLanes));
    limit = cv::vx_setall_u16(static_cast<std::uint16_t>(n));
  }
#else
  explicit LaneConstants(int) {}
#endif
};

// Slides the window (when `slide`: sad += hin - hout) and finds the best disparity (smallest
// cost; lanes k >= n, padding outside the range, are excluded) in one pass; sets *c_best and
// returns k_best.
inline int SlideAndFindBest(std::uint16_t* sad, const std::uint16_t* hin, const std::uint16_t* hout, bool slide,
                            int n, int np, const LaneConstants& lanes, int* c_best) {
  int k_best = 0;
  *c_best = kMaxCost;
#if CV_SIMD
  Cost vmin = cv::vx_setall_u16(kMaxCost), vidx = cv::vx_setzero_u16();
  Cost kv = lanes.ramp;
  for (int k = 0; k < np; k += kLanes) {
    Cost c = cv::vx_load(sad + k);
    if (slide) {
      c = c + cv::vx_load(hin + k) - cv::vx_load(hout + k);
      cv::v_store(sad + k, c);
    }
    if (k + kLanes > n) c = cv::v_select(kv < lanes.limit, c, cv::vx_setall_u16(kMaxCost));
    vidx = cv::v_select(c < vmin, kv, vidx);
    vmin = cv::v_min(vmin, c);
    kv += lanes.step;
  }
  // The smallest cost and, among its lanes, the smallest k, in one reduction of cost:k keys.
  cv::v_uint32 c0, c1, k0, k1;
  cv::v_expand(vmin, c0, c1);
  cv::v_expand(vidx, k0, k1);
  const unsigned best = cv::v_reduce_min(cv::v_min((c0 << 16) | k0, (c1 << 16) | k1));
  *c_best = static_cast<int>(best >> 16);
  k_best = static_cast<int>(best & 0xFFFF);
#else
  (void)lanes;
  if (slide) SlideWindow(sad, hin, hout, np);
  for (int k = 0; k < n; ++k) {
    if (sad[k] < *c_best) *c_best = sad[k], k_best = k;
  }
#endif
  return k_best;
}

// Uniqueness: no non-adjacent disparity's cost within `thresh`.
inline bool Unique(const std::uint16_t* sad, int n, int k_best, int thresh, const LaneConstants& lanes) {
  int k = 0;
#if CV_SIMD
  const Cost vthresh = cv::vx_setall_u16(static_cast<std::uint16_t>(thresh));
  // Lanes k_best - 1 .. k_best + 1 may be close: (k - (k_best - 1)) <= 2, unsigned.
  const Cost lo = cv::vx_setall_u16(static_cast<std::uint16_t>(k_best - 1));
  const Cost two = cv::vx_setall_u16(2);
  Cost kv = lanes.ramp;
  for (; k + kLanes <= n; k += kLanes) {
    const Cost close = cv::vx_load(sad + k) <= vthresh;
    const Cost neighbour = (kv - lo) <= two;
    if (cv::v_check_any(close & ~neighbour)) return false;
    kv += lanes.step;
  }
#else
  (void)lanes;
#endif
  for (; k < n; ++k) {
    if (sad[k] <= thresh && (k < k_best - 1 || k > k_best + 1)) return false;
  }
  return true;
}

// Equiangular fit: SAD is V-shaped around its minimum, so a V through the three costs (the steeper
// side's slope) locates it; a parabola would pull towards integers.
inline float Subpixel(const std::uint16_t* sad, int n, int k_best, int c_best, int d) {
  float disp = static_cast<float>(d);
  if (k_best > 0 && k_best < n - 1) {
    const int c_dm = sad[k_best + 1], c_dp = sad[k_best - 1];  // costs at d - 1 and d + 1
    const int slope = Max(c_dm, c_dp) - c_best;
    if (slope > 0) disp += static_cast<float>(c_dm - c_dp) / (2.0f * slope);
  }
  return disp;
}

// Row y's disparities into in.out, the left-right check applied.
void WriteRow(const SadKernelInput& in, const SadKernelBuffers& buf, int y) {
  float* dst = in.out + in.out_step * y;
  for (int x = in.x_lo; x <= in.x_hi; ++x) {
    if (buf.row_disp[x] == kInvalid) continue;
    if (in.left_right_check) {
      const int xr = x - buf.best_d[x];
      if (xr < 0 || xr >= in.width || buf.cost2[xr] == kMaxCost ||
          Abs(buf.disp2[xr] - buf.best_d[x]) > in.left_right_max_diff) {
        continue;
      }
    }
    dst[x] = buf.row_disp[x];
  }
}

// One row's matching from its column sums hsad: the window slides right along the row.
inline void MatchRow(const SadKernelInput& in, int y, const SadKernelBuffers& buf, const LaneConstants& lanes) {
  const int w = in.width;
  const int np = in.n_padded;
  const int d_max = in.d_min + in.n - 1;
  const std::uint16_t* hsad = buf.hsad;
  std::uint16_t* sad = buf.sad;
  for (int x = 0; x < w; ++x) {
    buf.cost2[x] = kMaxCost;
    buf.row_disp[x] = kInvalid;
    buf.best_d[x] = 0;
  }
  // Row sums over the first window.
  for (int k = 0; k < np; ++k) sad[k] = 0;
  for (int x = in.x_lo - in.rw; x <= in.x_lo + in.rw; ++x) {
    const std::uint16_t* h = hsad + static_cast<std::size_t>(x) * np;
    for (int k = 0; k < np; ++k) sad[k] = static_cast<std::uint16_t>(sad[k] + h[k]);
  }
  const std::uint8_t* textured = Row(in.textured, in.textured_step, y);
  for (int x = in.x_lo; x <= in.x_hi; ++x) {
    const bool slide = x > in.x_lo;
    const std::uint16_t* hin = slide ? hsad + static_cast<std::size_t>(x + in.rw) * np : nullptr;
    const std::uint16_t* hout = slide ? hsad + static_cast<std::size_t>(x - in.rw - 1) * np : nullptr;
    if (!textured[x]) {
      if (slide) SlideWindow(sad, hin, hout, np);
      continue;
    }
    int c_best = kMaxCost;
    const int k_best = SlideAndFindBest(sad, hin, hout, slide, in.n, np, lanes, &c_best);
    const int d = d_max - k_best;
    // The best match of the right pixel x - d seen from the left (for the left-right check).
    const int xr = x - d;
    if (xr >= 0 && xr < w && c_best < buf.cost2[xr]) {
      buf.cost2[xr] = static_cast<std::uint16_t>(c_best);
      buf.disp2[xr] = d;
    }
    // Uniqueness: no non-adjacent disparity within uniq % of the best.
    const int thresh = Min(kMaxCost - 1, c_best + c_best * in.uniqueness_percent / 100);
    if (!Unique(sad, in.n, k_best, thresh, lanes)) continue;
    buf.row_disp[x] = in.subpixel ? Subpixel(sad, in.n, k_best, c_best, d) : static_cast<float>(d);
    buf.best_d[x] = d;
  }
}

// Matches rows [y0, y1) of one level into in.out.
void MatchRows(const SadKernelInput& in, int y0, int y1, const SadKernelBuffers& buf) {
  const int w = in.width;
  const int np = in.n_padded;
  const int xa = Max(0, in.x_lo - in.rw), xb = Min(w, in.x_hi + in.rw + 1);
  std::uint16_t* hsad = buf.hsad;
  for (std::size_t i = 0; i < static_cast<std::size_t>(w) * np; ++i) hsad[i] = 0;
  const LaneConstants lanes(in.n);
  // Column sums over the first window.
  for (int yy = y0 - in.rh; yy <= y0 + in.rh; ++yy) {
    PadRow(in, yy, buf.padded);
    AddRow(in, Row(in.left, in.left_step, yy), buf.padded, xa, xb, hsad);
  }
  for (int y = y0; y < y1; ++y) {
    if (y > y0) {
      PadRow(in, y + in.rh, buf.padded);
      PadRow(in, y - in.rh - 1, buf.padded_out);
      SlideRows(in, Row(in.left, in.left_step, y + in.rh), buf.padded,
                Row(in.left, in.left_step, y - in.rh - 1), buf.padded_out, xa, xb, hsad);
    }
    MatchRow(in, y, buf, lanes);
    WriteRow(in, buf, y);
  }
}

}  // namespace

extern const SadKernel kKernel = {DPS_KERNEL_NAME, kLanes, &MatchRows};

}  // namespace DPS_KERNEL_NAMESPACE
}  // namespace internal
}  // namespace dps
