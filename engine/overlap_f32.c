/* overlap_f32.c - host build of kernels/overlap.h in single precision. */
#define PD_DOUBLE 0
#define OVL_RUN_NAME ovl_run_f32
#include "overlap_precision.inc"
