// Internal: the SAD matching kernel of sad_stereo.cpp, written once with OpenCV's universal
// intrinsics and compiled twice — for the baseline instruction set and, on x86-64, for AVX2 —
// like OpenCV's own dispatched code; the matcher picks the widest one the CPU runs. The kernel
// sees raw pointers only, so that the two compilations share no inline code.
#pragma once

#include <cstddef>
#include <cstdint>

namespace dps {
namespace internal {

// One pyramid level of a rectified, prefiltered pair and what to match.
struct SadKernelInput {
  const std::uint8_t* left = nullptr;      // prefiltered left, 0..2 cap
  std::size_t left_step = 0;               // bytes per row
  const std::uint8_t* right = nullptr;     // prefiltered right
  std::size_t right_step = 0;
  const std::uint8_t* textured = nullptr;  // 255 where the interest operator accepts the window
  std::size_t textured_step = 0;
  float* out = nullptr;                    // disparity, rows pre-filled with kInvalidDisparity
  std::size_t out_step = 0;                // floats per row
  int width = 0;
  int d_min = 0, n = 0;     // disparities [d_min, d_min + n)
  int n_padded = 0;         // n rounded up to a multiple of the kernel's lanes
  int rw = 0, rh = 0;       // half window
  int x_lo = 0, x_hi = -1;  // columns (inclusive) where every disparity's window is inside
  int pad = 0;              // replicated columns on each side of a padded right row
  int uniqueness_percent = 10;
  bool subpixel = true;
  bool left_right_check = true;
  double left_right_max_diff = 1.0;
};

// Working memory of one stripe of rows (sizes: hsad width * n_padded, sad n_padded, cost2 /
// disp2 / best_d / row_disp width, padded rows width + 2 pad).
struct SadKernelBuffers {
  std::uint16_t* hsad = nullptr;
  std::uint16_t* sad = nullptr;
  std::uint16_t* cost2 = nullptr;
  std::uint8_t* padded = nullptr;
  std::uint8_t* padded_out = nullptr;
  int* disp2 = nullptr;
  int* best_d = nullptr;
  float* row_disp = nullptr;
};

// A compiled kernel: its lane count and its row matcher.
struct SadKernel {
  const char* name;
  int lanes;  // n_padded must be a multiple of this
  void (*match_rows)(const SadKernelInput& in, int y0, int y1, const SadKernelBuffers& buf);
};
// The kernel the running CPU supports best, or the baseline one when `baseline_only`.
const SadKernel& BestSadKernel(bool baseline_only);

namespace baseline {
extern const SadKernel kKernel;
}
#ifdef DPS_HAVE_AVX2_KERNEL
namespace avx2 {
extern const SadKernel kKernel;
}
#endif

}  // namespace internal
}  // namespace dps
