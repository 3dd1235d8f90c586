/*
 * pd_real.h - the scalar and 3-vector types shared by OpenCL C kernels and host C.
 *
 * The including file defines PD_DOUBLE to 1 (double) or 0 (single) before including this header;
 * every kernel header then compiles unchanged as OpenCL C (on the device) and as C11 (on the host,
 * once per precision), so tests and CLI tools run exactly the code the kernels run.
 */
#ifndef PD_REAL_H
#define PD_REAL_H

#ifndef PD_DOUBLE
#error "define PD_DOUBLE to 0 or 1 before including pd_real.h"
#endif

#ifdef __OPENCL_VERSION__
#if PD_DOUBLE
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#endif
/* The host builds with -ffp-contract=off; fusing here would make host and device disagree. */
#pragma OPENCL FP_CONTRACT OFF
#define PD_GLOBAL __global
#define PD_FN static inline
#define PD_STAGE_FN static inline
#define PD_SQRT(x) sqrt(x)
#define PD_FABS(x) fabs(x)
#define PD_FLOOR(x) floor(x)
#else
#include <math.h>
#define PD_GLOBAL
#if defined(__GNUC__)
/* the kernels' small helpers must inline on the host as they do on devices */
#define PD_FN static inline __attribute__((always_inline))
/*
 * A stage of the overlap (one pass of the pair loop, one try of ovl_compute) is called from
 * several places: inlined at each, ovl_compute held 32 copies of the pair loop, overlap_f64.o was
 * 750 kB and took ~2 min to compile (~45 min under the sanitizers). The host keeps one copy; a
 * call per pass costs nothing against a pass (bench/RESULTS.md, 2026-12-06 night).
 */
#define PD_STAGE_FN static __attribute__((noinline, unused))
#else
#define PD_FN static inline
#define PD_STAGE_FN static inline
#endif
#if PD_DOUBLE
#define PD_SQRT(x) sqrt(x)
#define PD_FABS(x) fabs(x)
#define PD_FLOOR(x) floor(x)
#else
#define PD_SQRT(x) sqrtf(x)
#define PD_FABS(x) fabsf(x)
#define PD_FLOOR(x) floorf(x)
#endif
#endif

#if PD_DOUBLE
typedef double pd_real;
#define PD_EPS 2.220446049250313e-16
#define PD_REAL_MAX 1.7976931348623157e308
#else
typedef float pd_real;
#define PD_EPS 1.1920929e-7f
#define PD_REAL_MAX 3.4028235e38f
#endif

#define PD_R(x) ((pd_real)(x))

typedef struct pd_v3 {
    pd_real x, y, z;
} pd_v3;

PD_FN pd_v3 v3(pd_real x, pd_real y, pd_real z)
{
    pd_v3 r;
    r.x = x;
    r.y = y;
    r.z = z;
    return r;
}
PD_FN pd_v3 v3_add(pd_v3 a, pd_v3 b)
{
    return v3(a.x + b.x, a.y + b.y, a.z + b.z);
}
PD_FN pd_v3 v3_sub(pd_v3 a, pd_v3 b)
{
    return v3(a.x - b.x, a.y - b.y, a.z - b.z);
}
PD_FN pd_v3 v3_scale(pd_v3 a, pd_real s)
{
    return v3(a.x * s, a.y * s, a.z * s);
}
PD_FN pd_real v3_dot(pd_v3 a, pd_v3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
PD_FN pd_v3 v3_cross(pd_v3 a, pd_v3 b)
{
    return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
/* min/max without libm calls (fmin/fmax are not inlined without fast-math; no NaNs reach these) */
PD_FN pd_real pd_min(pd_real a, pd_real b)
{
    return a < b ? a : b;
}
PD_FN pd_real pd_max(pd_real a, pd_real b)
{
    return a > b ? a : b;
}

/* Largest component magnitude (the max-norm), for cheap error bounds. */
PD_FN pd_real v3_amax(pd_v3 a)
{
    /* the same maximum as nested ternaries, in the form compilers turn into max instructions
     * rather than branches (a sixth of a bed contact's mispredicted branches were here) */
    return pd_max(pd_max(PD_FABS(a.x), PD_FABS(a.y)), PD_FABS(a.z));
}
PD_FN pd_real v3_norm(pd_v3 a)
{
    return PD_SQRT(v3_dot(a, a));
}
/* Unit vector along a; a zero vector stays zero (callers never pass one on a live path). */
PD_FN pd_v3 v3_unit(pd_v3 a)
{
    pd_real n = v3_norm(a);
    return n > PD_R(0) ? v3_scale(a, PD_R(1) / n) : a;
}
/* Loads vertex i of a packed xyz array. */
PD_FN pd_v3 v3_load(PD_GLOBAL const pd_real *p, int i)
{
    return v3(p[3 * i], p[3 * i + 1], p[3 * i + 2]);
}
PD_FN void v3_store(PD_GLOBAL pd_real *p, int i, pd_v3 a)
{
    p[3 * i] = a.x;
    p[3 * i + 1] = a.y;
    p[3 * i + 2] = a.z;
}

#endif /* PD_REAL_H */
