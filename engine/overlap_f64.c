/* overlap_f64.c - host build of kernels/overlap.h in double precision. */
#define PD_DOUBLE 1
#define OVL_RUN_NAME ovl_run_f64
#include "overlap_precision.inc"
