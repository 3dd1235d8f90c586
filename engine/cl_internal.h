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
    cl_program prog[2]; /* overlap program: [0] single, [1] double */
    cl_kernel k_overlap[2];
    cl_program cache[CL_MAX_PROGRAMS][2]; /* programs by pd_cl_sources index and precision */
    int fp64;
    int gpu;           /* a GPU (wide parallelism) rather than a CPU */
    int compute_units; /* CL_DEVICE_MAX_COMPUTE_UNITS */
    char name[256];
};

/* The name of an OpenCL error code, for messages. */
const char *cl_errstr(cl_int e);

#define CL_FAIL(err, what, e)                                                                      \
    pd_error_set(err, PD_ECL, "opencl: %s failed: %s (%d)", what, cl_errstr(e), (int)(e))

/* Builds one embedded program; on failure the error quotes the build log. */
int cl_build_program(pd_device *dev, const char *name, const char *src, int dbl, cl_program *out,
                     pd_error *err);

/* The embedded program `name` (kernels/<name>.cl) built for dev in one precision, compiled on
 * first use and kept for the device's life (released by pd_device_close). */
int cl_program_get(pd_device *dev, const char *name, int dbl, cl_program *out, pd_error *err);

#endif
