// The SAD kernel compiled for AVX2 (see sad_stereo_kernel.h): the same universal-intrinsics
// source with 256-bit registers. OpenCV's headers enable only SSE2 intrinsics outside OpenCV's own
// build, so this file announces the instruction sets it is compiled for (CMake adds -mavx2 ...),
// and puts OpenCV's intrinsics in their own hal_AVX2 namespace, as OpenCV's dispatched files do,
// so that nothing inline is shared with the baseline build. It runs only on CPUs with AVX2.
#include <immintrin.h>
#define CV_CPU_DISPATCH_MODE AVX2
#define CV_SSE3 1
#define CV_SSSE3 1
#define CV_SSE4_1 1
#define CV_SSE4_2 1
#define CV_POPCNT 1
#define CV_AVX 1
#define CV_FP16 1
#define CV_FMA3 1
#define CV_AVX2 1
#define DPS_KERNEL_NAMESPACE avx2
#define DPS_KERNEL_NAME "avx2"
#include "sad_stereo_kernel.inl"
