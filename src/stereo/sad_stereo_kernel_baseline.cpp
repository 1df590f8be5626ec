// The SAD kernel for the baseline instruction set (see sad_stereo_kernel.h).
#define DPS_KERNEL_NAMESPACE baseline
#define DPS_KERNEL_NAME "baseline"
#include "sad_stereo_kernel.inl"
