/*
 * cl_internal.h - the OpenCL side of a pd_device, shared by the engine files that enqueue work
 * (cl_device.c, device_sort.c, sim*.c). Engine-internal.
 */
#ifndef PD_CL_INTERNAL_H
#define PD_CL_INTERNAL_H

#define CL_TARGET_OPENCL_VERSION 120
#include <CL/cl.h>

#include "polydem.h"

#define CL_MAX_PROGRAMS 16

struct pd_device {
    cl_platform_id platform;
    cl_device_id device;
    cl_context ctx;
    cl_command_queue queue;
    cl_program prog[4]; /* overlap program by variant (CL_DOUBLE, CL_PLACES) */
    cl_kernel k_overlap[4];
    /*
     * ovl_run_cl's per-pair buffers (integer scratch, real scratch, results), kept from call to
     * call and grown when a batch needs more. Created afresh for each call, a CPU device (PoCL)
     * faulted in every page of them again: half of a Schonhardt batch's time went to the kernel's
     * page faults (bench/RESULTS.md, 2026-12-07, sixth session).
     */
    cl_mem ovl_buf[3];
    size_t ovl_bytes[3];
    cl_program cache[CL_MAX_PROGRAMS][4]; /* programs by pd_cl_sources index and variant */
    int fp64;
    /*
     * CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT: the device can round single-precision / and sqrt as
     * the host does, and its programs are built with -cl-fp32-correctly-rounded-divide-sqrt, so
     * that its single-precision answers are the host's to the bit (bench/overlap and
     * tests/physics/test_overlap.c check; bench/replay relies on it). Without the option OpenCL
     * allows them 2.5 and 3 ulps. The H200's single-precision overlap, built without it, differed
     * from the host's by 6.3e-7 where its double agreed to all 17 digits (bench/RESULTS.md,
     * 2026-11-30, late); PoCL's / and sqrt are the CPU's and agree either way.
     */
    int fp32_rounded;
    int gpu;           /* a GPU (wide parallelism) rather than a CPU */
    int compute_units; /* CL_DEVICE_MAX_COMPUTE_UNITS */
    double global_mem; /* CL_DEVICE_GLOBAL_MEM_SIZE, bytes */
    double max_alloc;  /* CL_DEVICE_MAX_MEM_ALLOC_SIZE, bytes */
    char name[256];
};

/* The name of an OpenCL error code, for messages. */
const char *cl_errstr(cl_int e);

#define CL_FAIL(err, what, e)                                                                      \
    pd_error_set(err, PD_ECL, "opencl: %s failed: %s (%d)", what, cl_errstr(e), (int)(e))

/* Sets argument i of kernel k to the value v (a variable: its size is taken). */
#define CL_ARG(k, i, v) (clSetKernelArg(k, i, sizeof(v), &(v)))

/* The error for kernel arguments that could not be set (CL_ARG's results or'ed together). */
#define CL_ARG_FAIL(err, kernel)                                                                   \
    pd_error_set(err, PD_ECL, "opencl: setting the arguments of %s failed", kernel)

/*
 * A program's build variant: bit 0 double precision (PD_DOUBLE), CL_PLACES the overlap's separate
 * places compiled in (OVL_PLACES_BUILD, kernels/overlap_predicates.h; off, an overlap costs what
 * it did before them). 0 and 1 are the plain single and double builds. Programs with the overlap
 * are asked for in single precision only with CL_PLACES (sim_create, ovl_run_cl), whose rescue of
 * small contacts needs them (OVL_RESCUE); the caller sizes the overlap scratch for the places.
 */
#define CL_DOUBLE 1
#define CL_PLACES 2

/* Builds one embedded program in a variant; on failure the error quotes the build log. */
int cl_build_program(pd_device *dev, const char *name, const char *src, int variant,
                     cl_program *out, pd_error *err);

/* The embedded program `name` (kernels/<name>.cl) built for dev in a variant, compiled on first
 * use and kept for the device's life (released by pd_device_close). CL_PLACES is dropped for a
 * program that does not contain the overlap (the same build). */
int cl_program_get(pd_device *dev, const char *name, int variant, cl_program *out, pd_error *err);

#endif
