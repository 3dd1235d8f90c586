/*
 * cl_device.c - an OpenCL device with the polydem kernels compiled for it (pd_device_*), and the
 * overlap kernel's host side (ovl_run_cl, pd_overlap_cl).
 *
 * The kernel sources are embedded at build time (tools/embed_cl.sh), so the binaries run from any
 * directory. Programs are compiled once per precision, on first use, and kept for the device's
 * life.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cl_internal.h"
#include "cl_sources.h"
#include "overlap_run.h"

const char *cl_errstr(cl_int e)
{
    switch (e) {
    case CL_DEVICE_NOT_FOUND:
        return "CL_DEVICE_NOT_FOUND";
    case CL_OUT_OF_RESOURCES:
        return "CL_OUT_OF_RESOURCES";
    case CL_OUT_OF_HOST_MEMORY:
        return "CL_OUT_OF_HOST_MEMORY";
    case CL_MEM_OBJECT_ALLOCATION_FAILURE:
        return "CL_MEM_OBJECT_ALLOCATION_FAILURE";
    case CL_BUILD_PROGRAM_FAILURE:
        return "CL_BUILD_PROGRAM_FAILURE";
    case CL_INVALID_VALUE:
        return "CL_INVALID_VALUE";
    case CL_INVALID_BUFFER_SIZE:
        return "CL_INVALID_BUFFER_SIZE";
    case CL_INVALID_KERNEL_ARGS:
        return "CL_INVALID_KERNEL_ARGS";
    case CL_INVALID_WORK_GROUP_SIZE:
        return "CL_INVALID_WORK_GROUP_SIZE";
    case -1001:
        return "CL_PLATFORM_NOT_FOUND_KHR (no OpenCL driver installed)";
    default:
        return "OpenCL error";
    }
}

/* Every OpenCL device of every platform, in the order --device N counts them. */
#define MAX_DEVICES 64
typedef struct device_ref {
    cl_device_id id;
    cl_platform_id platform;
} device_ref;

static int enumerate_devices(device_ref *out, int *n, pd_error *err)
{
    cl_platform_id plats[16];
    cl_uint nplat = 0;
    cl_int e = clGetPlatformIDs(16, plats, &nplat);
    *n = 0;
    if (e != CL_SUCCESS || nplat == 0)
        return pd_error_set(err, PD_ECL,
                            "opencl: no platform found (%s); install an OpenCL "
                            "driver, e.g. pocl-opencl-icd",
                            cl_errstr(e));
    for (cl_uint p = 0; p < nplat && p < 16; p++) {
        cl_device_id devs[32];
        cl_uint ndev = 0;
        if (clGetDeviceIDs(plats[p], CL_DEVICE_TYPE_ALL, 32, devs, &ndev) != CL_SUCCESS) continue;
        for (cl_uint d = 0; d < ndev && d < 32 && *n < MAX_DEVICES; d++) {
            out[*n].id = devs[d];
            out[*n].platform = plats[p];
            (*n)++;
        }
    }
    return PD_OK;
}

/* The error of a failed device or platform query, naming it. */
static int info_fail(pd_error *err, const char *what, cl_int e)
{
    return pd_error_set(err, PD_ECL, "opencl: querying %s failed: %s (%d)", what, cl_errstr(e),
                        (int)e);
}

/* A fixed-size device query (INFO_VALUE: the query's name in the error). */
static int info_value(cl_device_id id, cl_device_info what, const char *name, size_t size,
                      void *out, pd_error *err)
{
    cl_int e = clGetDeviceInfo(id, what, size, out, NULL);
    return e == CL_SUCCESS ? PD_OK : info_fail(err, name, e);
}
#define INFO_VALUE(id, what, v, err) info_value(id, what, #what, sizeof(v), &(v), err)

/*
 * A string query of device id (or, where id is NULL, of platform plat), whole, into *out
 * (malloc'ed; NULL on error). Asked into a fixed buffer, a string longer than the buffer is
 * refused (CL_INVALID_VALUE) and was taken for an empty one: an extension list longer than 8 KiB
 * would have hidden cl_khr_fp64.
 */
static int info_string(cl_device_id id, cl_platform_id plat, cl_uint what, const char *name,
                       char **out, pd_error *err)
{
    size_t len = 0;
    *out = NULL;
    cl_int e = id ? clGetDeviceInfo(id, what, 0, NULL, &len)
                  : clGetPlatformInfo(plat, what, 0, NULL, &len);
    if (e != CL_SUCCESS) return info_fail(err, name, e);
    char *s = malloc(len + 1);
    if (!s) return pd_error_set(err, PD_ENOMEM, "opencl: out of memory querying %s", name);
    e = id ? clGetDeviceInfo(id, what, len, s, NULL) : clGetPlatformInfo(plat, what, len, s, NULL);
    if (e != CL_SUCCESS) {
        free(s);
        return info_fail(err, name, e);
    }
    s[len] = '\0';
    *out = s;
    return PD_OK;
}

/*
 * What pd_device_list reports of device d (number index), and, in *max_alloc where not NULL, its
 * largest allocation in bytes. Every query is checked: a device that cannot say what it is is an
 * error, not a device of no memory and no double precision.
 */
static int device_describe(const device_ref *d, int index, pd_device_info *o, cl_ulong *max_alloc,
                           pd_error *err)
{
    char *name = NULL, *plat = NULL, *ext = NULL;
    cl_device_type type = 0;
    cl_uint cu = 0;
    cl_ulong mem = 0, amax = 0;
    cl_device_fp_config fp = 0;
    int rc = info_string(d->id, NULL, CL_DEVICE_NAME, "CL_DEVICE_NAME", &name, err);
    if (rc == PD_OK)
        rc = info_string(NULL, d->platform, CL_PLATFORM_NAME, "CL_PLATFORM_NAME", &plat, err);
    if (rc == PD_OK)
        rc = info_string(d->id, NULL, CL_DEVICE_EXTENSIONS, "CL_DEVICE_EXTENSIONS", &ext, err);
    if (rc == PD_OK) rc = INFO_VALUE(d->id, CL_DEVICE_TYPE, type, err);
    if (rc == PD_OK) rc = INFO_VALUE(d->id, CL_DEVICE_MAX_COMPUTE_UNITS, cu, err);
    if (rc == PD_OK) rc = INFO_VALUE(d->id, CL_DEVICE_GLOBAL_MEM_SIZE, mem, err);
    if (rc == PD_OK) rc = INFO_VALUE(d->id, CL_DEVICE_MAX_MEM_ALLOC_SIZE, amax, err);
    if (rc == PD_OK) rc = INFO_VALUE(d->id, CL_DEVICE_SINGLE_FP_CONFIG, fp, err);
    if (rc == PD_OK) {
        memset(o, 0, sizeof *o);
        o->index = index;
        snprintf(o->name, sizeof o->name, "%s", name);
        snprintf(o->platform, sizeof o->platform, "%s", plat);
        strcpy(o->type, (type & CL_DEVICE_TYPE_GPU)   ? "GPU"
                        : (type & CL_DEVICE_TYPE_CPU) ? "CPU"
                                                      : "other");
        o->compute_units = cu > 0 ? (int)cu : 1;
        o->global_mem_bytes = (double)mem;
        o->fp64 = strstr(ext, "cl_khr_fp64") != NULL;
        o->fp32_rounded = (fp & CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT) != 0;
        if (max_alloc) *max_alloc = amax;
    }
    free(name);
    free(plat);
    free(ext);
    return rc;
}

int pd_device_list(pd_device_info *out, int max, int *n, pd_error *err)
{
    device_ref devs[MAX_DEVICES];
    int rc = enumerate_devices(devs, n, err);
    for (int i = 0; rc == PD_OK && i < *n && i < max; i++)
        rc = device_describe(&devs[i], i, &out[i], NULL, err);
    return rc;
}

int pd_device_open(int index, pd_device **out, pd_error *err)
{
    device_ref devs[MAX_DEVICES];
    int n = 0;
    cl_int e;
    *out = NULL;
    int rc = enumerate_devices(devs, &n, err);
    if (rc != PD_OK) return rc;
    int pick = index;
    if (index < 0) { /* the first GPU, else the first device */
        pick = n > 0 ? 0 : -1;
        for (int i = n - 1; i >= 0; i--) {
            cl_device_type type = 0;
            rc = INFO_VALUE(devs[i].id, CL_DEVICE_TYPE, type, err);
            if (rc != PD_OK) return rc;
            if (type & CL_DEVICE_TYPE_GPU) pick = i;
        }
    }
    if (pick < 0 || pick >= n) {
        if (index >= 0)
            return pd_error_set(err, PD_EINVAL, "opencl: device %d does not exist (%d found)",
                                index, n);
        return pd_error_set(err, PD_ECL, "opencl: no device found");
    }
    pd_device_info info;
    cl_ulong amax = 0;
    rc = device_describe(&devs[pick], pick, &info, &amax, err);
    if (rc != PD_OK) return rc;
    cl_device_id pickd = devs[pick].id;
    pd_device *dev = calloc(1, sizeof *dev);
    if (!dev) return pd_error_set(err, PD_ENOMEM, "opencl: out of memory");
    dev->platform = devs[pick].platform;
    dev->device = pickd;
    snprintf(dev->name, sizeof dev->name, "%s", info.name);
    dev->fp64 = info.fp64;
    dev->fp32_rounded = info.fp32_rounded;
    dev->gpu = strcmp(info.type, "GPU") == 0;
    dev->compute_units = info.compute_units;
    dev->global_mem = info.global_mem_bytes;
    dev->max_alloc = (double)amax;
    dev->ctx = clCreateContext(NULL, 1, &pickd, NULL, NULL, &e);
    if (e != CL_SUCCESS) {
        free(dev);
        return CL_FAIL(err, "clCreateContext", e);
    }
    dev->queue = clCreateCommandQueue(dev->ctx, pickd, 0, &e);
    if (e != CL_SUCCESS) {
        clReleaseContext(dev->ctx);
        free(dev);
        return CL_FAIL(err, "clCreateCommandQueue", e);
    }
    *out = dev;
    return PD_OK;
}

void pd_device_close(pd_device *dev)
{
    if (!dev) return;
    for (int i = 0; i < 4; i++) {
        if (dev->k_overlap[i]) clReleaseKernel(dev->k_overlap[i]);
        if (dev->prog[i]) clReleaseProgram(dev->prog[i]);
    }
    for (int p = 0; p < CL_MAX_PROGRAMS; p++)
        for (int v = 0; v < 4; v++)
            if (dev->cache[p][v]) clReleaseProgram(dev->cache[p][v]);
    for (int i = 0; i < 3; i++)
        if (dev->ovl_buf[i]) clReleaseMemObject(dev->ovl_buf[i]);
    clReleaseCommandQueue(dev->queue);
    clReleaseContext(dev->ctx);
    free(dev);
}

const char *pd_device_name(const pd_device *dev)
{
    return dev->name;
}
int pd_device_has_fp64(const pd_device *dev)
{
    return dev->fp64;
}
int pd_device_fp32_rounded(const pd_device *dev)
{
    return dev->fp32_rounded;
}
int pd_device_is_gpu(const pd_device *dev)
{
    return dev->gpu;
}
void pd_device_capacity(const pd_device *dev, int *work_items, double *scratch_bytes)
{
    /* the contact stage's launch (engine/sim_state.c) */
    *work_items = 256 * dev->compute_units;
    double m = dev->global_mem / 4;
    *scratch_bytes = dev->max_alloc > 0 && dev->max_alloc < m ? dev->max_alloc : m;
}

static void to_real(void *buf, const double *x, size_t n, int dbl);

/* Builds one embedded program; on failure the error quotes the build log. */
int cl_build_program(pd_device *dev, const char *name, const char *src, int variant,
                     cl_program *out, pd_error *err)
{
    cl_int e;
    cl_program prog = clCreateProgramWithSource(dev->ctx, 1, &src, NULL, &e);
    if (e != CL_SUCCESS) return CL_FAIL(err, "clCreateProgramWithSource", e);
    char opts[128];
    snprintf(opts, sizeof opts, "-DPD_DOUBLE=%d -DOVL_PLACES_BUILD=%d%s",
             (variant & CL_DOUBLE) != 0, (variant & CL_PLACES) != 0,
             dev->fp32_rounded ? " -cl-fp32-correctly-rounded-divide-sqrt" : "");
    e = clBuildProgram(prog, 1, &dev->device, opts, NULL, NULL);
    if (e != CL_SUCCESS) {
        char log[4096] = {0};
        clGetProgramBuildInfo(prog, dev->device, CL_PROGRAM_BUILD_LOG, sizeof log - 1, log, NULL);
        clReleaseProgram(prog);
        return pd_error_set(err, PD_ECL, "opencl: building %s.cl (%s%s) failed: %.400s", name,
                            (variant & CL_DOUBLE) ? "double" : "single",
                            (variant & CL_PLACES) ? ", places" : "", log);
    }
    *out = prog;
    return PD_OK;
}

/* Whether embedded program i contains the overlap (its sources carry their headers), and so
 * has a CL_PLACES build of its own. */
static int program_has_places(int i)
{
    return strstr(pd_cl_sources[i].source, "OVL_PLACES_BUILD") != NULL;
}

int cl_program_get(pd_device *dev, const char *name, int variant, cl_program *out, pd_error *err)
{
    int dbl = variant & CL_DOUBLE;
    if (dbl && !dev->fp64)
        return pd_error_set(err, PD_EINVAL,
                            "opencl: device '%s' has no cl_khr_fp64; use \"precision\": \"single\"",
                            dev->name);
    int n = (int)(sizeof pd_cl_sources / sizeof pd_cl_sources[0]);
    for (int i = 0; i < n && i < CL_MAX_PROGRAMS; i++)
        if (strcmp(pd_cl_sources[i].name, name) == 0) {
            if (!program_has_places(i)) variant &= ~CL_PLACES;
            if (!dev->cache[i][variant]) {
                int rc = cl_build_program(dev, name, pd_cl_sources[i].source, variant,
                                          &dev->cache[i][variant], err);
                if (rc != PD_OK) return rc;
            }
            *out = dev->cache[i][variant];
            return PD_OK;
        }
    return pd_error_set(err, PD_EINVAL, "opencl: no program named %s", name);
}

int pd_device_compile_all(pd_device *dev, pd_error *err)
{
    for (size_t i = 0; i < sizeof pd_cl_sources / sizeof pd_cl_sources[0]; i++)
        for (int v = 0; v < 4; v++) {
            if ((v & CL_DOUBLE) && !dev->fp64) continue;
            if ((v & CL_PLACES) && !program_has_places((int)i)) continue;
            /* single precision is built with the places only (cl_internal.h) */
            if (!(v & (CL_DOUBLE | CL_PLACES)) && program_has_places((int)i)) continue;
            cl_program p;
            int rc =
                cl_build_program(dev, pd_cl_sources[i].name, pd_cl_sources[i].source, v, &p, err);
            if (rc != PD_OK) return rc;
            clReleaseProgram(p);
        }
    return PD_OK;
}

int pd_forces_cl(pd_device *dev, const double *in, int n, int dbl, double *out, pd_error *err)
{
    if (dbl && !dev->fp64)
        return pd_error_set(err, PD_ECL, "opencl: device '%s' has no cl_khr_fp64", dev->name);
    cl_program prog;
    int rc = cl_build_program(dev, "forces", pd_cl_source_forces, dbl, &prog, err);
    if (rc != PD_OK) return rc;
    size_t rs = dbl ? sizeof(double) : sizeof(float);
    void *hin = malloc(rs * 6 * (size_t)n), *hout = malloc(rs * 2 * (size_t)n);
    cl_mem bin = NULL, bout = NULL;
    cl_kernel k = NULL;
    cl_int e = CL_SUCCESS;
    if (!hin || !hout) {
        rc = pd_error_set(err, PD_ENOMEM, "opencl forces: out of memory");
        goto done;
    }
    to_real(hin, in, 6 * (size_t)n, dbl);
    k = clCreateKernel(prog, "hertz_volume_normal", &e);
    if (e == CL_SUCCESS)
        bin =
            clCreateBuffer(dev->ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, rs * 6 * n, hin, &e);
    if (e == CL_SUCCESS) bout = clCreateBuffer(dev->ctx, CL_MEM_WRITE_ONLY, rs * 2 * n, NULL, &e);
    if (e == CL_SUCCESS) e = clSetKernelArg(k, 0, sizeof bin, &bin);
    if (e == CL_SUCCESS) e = clSetKernelArg(k, 1, sizeof n, &n);
    if (e == CL_SUCCESS) e = clSetKernelArg(k, 2, sizeof bout, &bout);
    size_t global = (size_t)n;
    if (e == CL_SUCCESS)
        e = clEnqueueNDRangeKernel(dev->queue, k, 1, NULL, &global, NULL, 0, NULL, NULL);
    if (e == CL_SUCCESS)
        e = clEnqueueReadBuffer(dev->queue, bout, CL_TRUE, 0, rs * 2 * n, hout, 0, NULL, NULL);
    if (e != CL_SUCCESS) {
        rc = CL_FAIL(err, "hertz_volume_normal", e);
        goto done;
    }
    for (size_t i = 0; i < 2 * (size_t)n; i++)
        out[i] = dbl ? ((double *)hout)[i] : (double)((float *)hout)[i];
done:
    if (bin) clReleaseMemObject(bin);
    if (bout) clReleaseMemObject(bout);
    if (k) clReleaseKernel(k);
    clReleaseProgram(prog);
    free(hin);
    free(hout);
    return rc;
}

/* Compiles the overlap program in one variant (CL_DOUBLE, CL_PLACES) on first use. */
static int device_program(pd_device *dev, int variant, pd_error *err)
{
    if (dev->k_overlap[variant]) return PD_OK;
    if ((variant & CL_DOUBLE) && !dev->fp64)
        return pd_error_set(
            err, PD_ECL, "opencl: device '%s' has no cl_khr_fp64; use single precision", dev->name);
    cl_program prog;
    cl_int e;
    int rc = cl_build_program(dev, "overlap", pd_cl_source_overlap, variant, &prog, err);
    if (rc != PD_OK) return rc;
    cl_kernel k = clCreateKernel(prog, "overlap_pairs", &e);
    if (e != CL_SUCCESS) {
        clReleaseProgram(prog);
        return CL_FAIL(err, "clCreateKernel(overlap_pairs)", e);
    }
    dev->prog[variant] = prog;
    dev->k_overlap[variant] = k;
    return PD_OK;
}

/* Converts n doubles into the device's scalar type in buf (sizeof scalar = sz). */
static void to_real(void *buf, const double *x, size_t n, int dbl)
{
    if (dbl)
        memcpy(buf, x, n * sizeof(double));
    else
        for (size_t i = 0; i < n; i++)
            ((float *)buf)[i] = (float)x[i];
}

/* ovl_run_cl's per-pair buffer i (dev->ovl_buf) with room for at least bytes; a larger one
 * replaces it (its contents are not kept). */
static int ovl_buffer(pd_device *dev, int i, size_t bytes, cl_mem_flags flags, pd_error *err)
{
    static const char *const what[3] = {"clCreateBuffer(overlap integer scratch)",
                                        "clCreateBuffer(overlap real scratch)",
                                        "clCreateBuffer(overlap results)"};
    if (dev->ovl_buf[i] && dev->ovl_bytes[i] >= bytes) return PD_OK;
    if (dev->ovl_buf[i]) clReleaseMemObject(dev->ovl_buf[i]);
    dev->ovl_buf[i] = NULL;
    dev->ovl_bytes[i] = 0;
    cl_int e;
    cl_mem b = clCreateBuffer(dev->ctx, flags, bytes ? bytes : 16, NULL, &e);
    if (e != CL_SUCCESS) return CL_FAIL(err, what[i], e);
    dev->ovl_buf[i] = b;
    dev->ovl_bytes[i] = bytes;
    return PD_OK;
}

int ovl_run_cl(pd_device *dev, const ovl_setup *s, const double *xf, int npairs, int dbl,
               double *out, pd_error *err)
{
    /* places (PD_OVERLAP_PLACES in s->flags) only in the build that has them, which single
     * precision always uses (OVL_RESCUE, kernels/overlap_predicates.h) */
    int variant = (dbl ? CL_DOUBLE : 0) | ((s->flags & PD_OVERLAP_PLACES) || !dbl ? CL_PLACES : 0);
    int rc = device_program(dev, variant, err);
    if (rc != PD_OK) return rc;
    size_t rs = dbl ? sizeof(double) : sizeof(float);
    int cap = ovl_pts_cap(s->nta, s->ntb), flags = s->flags;
    size_t ilen, rlen;
    ovl_scratch_len(s, &ilen, &rlen);
    size_t n_va = 3 * (size_t)s->nva, n_vb = 3 * (size_t)s->nvb, n_xf = 18 * (size_t)npairs;
    size_t n_ba = ovl_discs_len(s->nva), n_bb = ovl_discs_len(s->nvb);
    void *hva = malloc(rs * n_va), *hvb = malloc(rs * n_vb), *hxf = malloc(rs * n_xf);
    void *hba = malloc(rs * n_ba), *hbb = malloc(rs * n_bb);
    void *hout = malloc(rs * OVL_RESULT_LEN * (size_t)npairs);
    cl_mem b[16] = {0};
    cl_int e = CL_SUCCESS;
    rc = PD_OK;
    if (!s->vc_a || !s->vc_b) {
        rc = pd_error_set(err, PD_EINVAL, "opencl overlap: the setup has no vertex clusters");
        goto done;
    }
    if (!hva || !hvb || !hxf || !hout || !hba || !hbb) {
        rc = pd_error_set(err, PD_ENOMEM, "opencl overlap: out of memory");
        goto done;
    }
    to_real(hva, s->va, n_va, dbl);
    to_real(hvb, s->vb, n_vb, dbl);
    to_real(hxf, xf, n_xf, dbl);
    to_real(hba, s->disc_a, n_ba, dbl);
    to_real(hbb, s->disc_b, n_bb, dbl);
    const cl_mem_flags ro = CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR;
    b[0] = clCreateBuffer(dev->ctx, ro, rs * n_va, hva, &e);
    if (e == CL_SUCCESS)
        b[1] = clCreateBuffer(dev->ctx, ro, sizeof(int) * 3 * s->nta, (void *)s->ta, &e);
    if (e == CL_SUCCESS) b[2] = clCreateBuffer(dev->ctx, ro, rs * n_vb, hvb, &e);
    if (e == CL_SUCCESS)
        b[3] = clCreateBuffer(dev->ctx, ro, sizeof(int) * 3 * s->ntb, (void *)s->tb, &e);
    if (e == CL_SUCCESS) b[4] = clCreateBuffer(dev->ctx, ro, rs * n_xf, hxf, &e);
    if (e == CL_SUCCESS)
        b[8] = clCreateBuffer(dev->ctx, ro, sizeof(int) * (s->nva + 1), s->vt_a_off, &e);
    if (e == CL_SUCCESS) b[9] = clCreateBuffer(dev->ctx, ro, sizeof(int) * 3 * s->nta, s->vt_a, &e);
    if (e == CL_SUCCESS)
        b[10] = clCreateBuffer(dev->ctx, ro, sizeof(int) * (s->nvb + 1), s->vt_b_off, &e);
    if (e == CL_SUCCESS)
        b[11] = clCreateBuffer(dev->ctx, ro, sizeof(int) * 3 * s->ntb, s->vt_b, &e);
    if (e == CL_SUCCESS)
        b[12] = clCreateBuffer(dev->ctx, ro, sizeof(int) * 2 * s->nva, s->vc_a, &e);
    if (e == CL_SUCCESS) b[13] = clCreateBuffer(dev->ctx, ro, rs * n_ba, hba, &e);
    if (e == CL_SUCCESS)
        b[14] = clCreateBuffer(dev->ctx, ro, sizeof(int) * 2 * s->nvb, s->vc_b, &e);
    if (e == CL_SUCCESS) b[15] = clCreateBuffer(dev->ctx, ro, rs * n_bb, hbb, &e);
    if (e != CL_SUCCESS) {
        rc = CL_FAIL(err, "clCreateBuffer", e);
        goto done;
    }
    /* the per-pair buffers are the device's, kept for its next call */
    rc = ovl_buffer(dev, 0, sizeof(int) * ilen * npairs, CL_MEM_READ_WRITE, err);
    if (rc == PD_OK) rc = ovl_buffer(dev, 1, rs * rlen * npairs, CL_MEM_READ_WRITE, err);
    if (rc == PD_OK) rc = ovl_buffer(dev, 2, rs * OVL_RESULT_LEN * npairs, CL_MEM_WRITE_ONLY, err);
    if (rc != PD_OK) goto done;
    cl_kernel k = dev->k_overlap[variant];
    cl_int args_e = CL_SUCCESS;
    int ai = 0;
    args_e |= clSetKernelArg(k, ai++, sizeof(cl_mem), &b[0]);
    args_e |= clSetKernelArg(k, ai++, sizeof(cl_mem), &b[1]);
    args_e |= clSetKernelArg(k, ai++, sizeof(int), &s->nva);
    args_e |= clSetKernelArg(k, ai++, sizeof(int), &s->nta);
    args_e |= clSetKernelArg(k, ai++, sizeof(cl_mem), &b[2]);
    args_e |= clSetKernelArg(k, ai++, sizeof(cl_mem), &b[3]);
    args_e |= clSetKernelArg(k, ai++, sizeof(int), &s->nvb);
    args_e |= clSetKernelArg(k, ai++, sizeof(int), &s->ntb);
    for (int i = 8; i < 16; i++)
        args_e |= clSetKernelArg(k, ai++, sizeof(cl_mem), &b[i]);
    args_e |= clSetKernelArg(k, ai++, sizeof(cl_mem), &b[4]);
    args_e |= clSetKernelArg(k, ai++, sizeof(int), &npairs);
    args_e |= clSetKernelArg(k, ai++, sizeof(int), &flags);
    args_e |= clSetKernelArg(k, ai++, sizeof(cl_mem), &dev->ovl_buf[0]);
    args_e |= clSetKernelArg(k, ai++, sizeof(cl_mem), &dev->ovl_buf[1]);
    args_e |= clSetKernelArg(k, ai++, sizeof(int), &cap);
    args_e |= clSetKernelArg(k, ai++, sizeof(cl_mem), &dev->ovl_buf[2]);
    if (args_e != CL_SUCCESS) {
        rc = CL_ARG_FAIL(err, "overlap_pairs");
        goto done;
    }
    size_t global = (size_t)npairs;
    e = clEnqueueNDRangeKernel(dev->queue, k, 1, NULL, &global, NULL, 0, NULL, NULL);
    if (e != CL_SUCCESS) {
        rc = CL_FAIL(err, "clEnqueueNDRangeKernel(overlap_pairs)", e);
        goto done;
    }
    e = clEnqueueReadBuffer(dev->queue, dev->ovl_buf[2], CL_TRUE, 0, rs * OVL_RESULT_LEN * npairs,
                            hout, 0, NULL, NULL);
    if (e != CL_SUCCESS) {
        rc = CL_FAIL(err, "clEnqueueReadBuffer", e);
        goto done;
    }
    for (size_t i = 0; i < OVL_RESULT_LEN * (size_t)npairs; i++)
        out[i] = dbl ? ((double *)hout)[i] : (double)((float *)hout)[i];
done:
    for (int i = 0; i < 16; i++)
        if (b[i]) clReleaseMemObject(b[i]);
    free(hva);
    free(hvb);
    free(hba);
    free(hbb);
    free(hxf);
    free(hout);
    return rc;
}

/* Packs a setup's transform into the kernel's 18-real per-pair record. */
void ovl_setup_pack(const ovl_setup *s, double xf[18])
{
    memcpy(xf, s->rot, 9 * sizeof(double));
    memcpy(xf + 9, s->tr, 3 * sizeof(double));
    memcpy(xf + 12, s->ca, 3 * sizeof(double));
    memcpy(xf + 15, s->cb, 3 * sizeof(double));
}

void ovl_result_unpack(const double r[OVL_RESULT_LEN], ovl_result *o)
{
    o->hit = r[0] != 0;
    o->degenerate = r[1] != 0;
    o->kept_a = (int)r[2];
    o->kept_b = (int)r[3];
    o->volume = r[4];
    for (int k = 0; k < 3; k++) {
        o->centroid[k] = r[5 + k];
        o->normal[k] = r[8 + k];
    }
    o->depth = r[11];
    o->places = (int)r[12];
    o->places_known = r[18] != 0;
    o->vol_eff = r[13];
    o->depth_eff = r[14];
    for (int k = 0; k < 3; k++)
        o->point_eff[k] = r[15 + k];
}

int pd_overlap_cl(pd_device *dev, const pd_mesh *a, const pd_pose *pa, const pd_mesh *b,
                  const pd_pose *pb, int flags, pd_contact *out, pd_error *err)
{
    ovl_setup s;
    double xf[18], r[OVL_RESULT_LEN];
    ovl_result res;
    int rc =
        ovl_setup_make(a, pa, b, pb, (flags & ~PD_OVERLAP_SINGLE) | PD_OVERLAP_PLACES, &s, err);
    if (rc != PD_OK) return rc;
    ovl_setup_pack(&s, xf);
    rc = ovl_run_cl(dev, &s, xf, 1, !(flags & PD_OVERLAP_SINGLE), r, err);
    if (rc == PD_OK) {
        ovl_result_unpack(r, &res);
        ovl_result_to_world(&s, &res, out);
    }
    ovl_setup_free(&s);
    return rc;
}

int np_run_cl(pd_device *dev, const np_tables *t, const double *x, const double *q,
              const double *size, const int *shape, int nbody, const int *pairs, int npairs,
              int dbl, double *out, pd_error *err)
{
    if (dbl && !dev->fp64)
        return pd_error_set(err, PD_ECL, "opencl: device '%s' has no cl_khr_fp64", dev->name);
    cl_program prog;
    int rc = cl_build_program(dev, "narrow", pd_cl_source_narrow, dbl, &prog, err);
    if (rc != PD_OK) return rc;
    int nv = t->voff[t->nshape], nt = t->toff[t->nshape], maxv = 0, maxt = 0;
    for (int s = 0; s < t->nshape; s++) {
        int v = t->voff[s + 1] - t->voff[s], tr = t->toff[s + 1] - t->toff[s];
        maxv = v > maxv ? v : maxv;
        maxt = tr > maxt ? tr : maxt;
    }
    int cap = ovl_pts_cap(maxt, maxt);
    ovl_setup big; /* scratch lengths depend only on the largest shape */
    memset(&big, 0, sizeof big);
    big.nva = big.nvb = maxv;
    big.nta = big.ntb = maxt;
    size_t ilen, rlen;
    ovl_scratch_len(&big, &ilen, &rlen);
    size_t rs = dbl ? sizeof(double) : sizeof(float);
    /* real-valued inputs converted to the device's scalar */
    /* the clusters' tables where t has them (np_cluster_tables), else NULL arguments */
    int ncl = t->vc ? t->coff[t->nshape] : 0;
    const double *src[5] = {x, q, size, t->vert, t->disc};
    size_t len[5] = {3 * (size_t)nbody, 4 * (size_t)nbody, (size_t)nbody, 3 * (size_t)nv,
                     NP_DISC_LEN * (size_t)ncl};
    void *host[5] = {0};
    cl_mem b[16] = {0};
    cl_kernel k = NULL;
    cl_int e = CL_SUCCESS;
    void *hout = malloc(rs * OVL_RESULT_LEN * (size_t)npairs);
    rc = PD_OK;
    for (int i = 0; i < 5; i++) {
        host[i] = calloc(len[i] ? len[i] : 1, rs);
        if (!host[i])
            rc = PD_ENOMEM;
        else if (len[i])
            to_real(host[i], src[i], len[i], dbl);
    }
    if (rc != PD_OK || !hout) {
        rc = pd_error_set(err, PD_ENOMEM, "opencl narrow phase: out of memory");
        goto done;
    }
    const cl_mem_flags ro = CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR;
    b[0] = clCreateBuffer(dev->ctx, ro, sizeof(int) * 2 * npairs, (void *)pairs, &e);
    for (int i = 0; i < 3 && e == CL_SUCCESS; i++) /* x, q, size */
        b[1 + i] = clCreateBuffer(dev->ctx, ro, rs * len[i], host[i], &e);
    if (e == CL_SUCCESS)
        b[4] = clCreateBuffer(dev->ctx, ro, sizeof(int) * nbody, (void *)shape, &e);
    if (e == CL_SUCCESS) b[5] = clCreateBuffer(dev->ctx, ro, rs * len[3], host[3], &e);
    if (e == CL_SUCCESS)
        b[6] = clCreateBuffer(dev->ctx, ro, sizeof(int) * 3 * nt, (void *)t->tri, &e);
    if (e == CL_SUCCESS)
        b[7] = clCreateBuffer(dev->ctx, ro, sizeof(int) * (t->nshape + 1), (void *)t->voff, &e);
    if (e == CL_SUCCESS)
        b[8] = clCreateBuffer(dev->ctx, ro, sizeof(int) * (t->nshape + 1), (void *)t->toff, &e);
    if (e == CL_SUCCESS)
        b[9] = clCreateBuffer(dev->ctx, ro, sizeof(int) * (nv + t->nshape), (void *)t->vt_off, &e);
    if (e == CL_SUCCESS)
        b[10] = clCreateBuffer(dev->ctx, ro, sizeof(int) * 3 * nt, (void *)t->vt, &e);
    if (e == CL_SUCCESS && t->vc) {
        /* every shape's vc span, clustered or not, lies below the last clustered one's end */
        size_t nvc = 0;
        for (int s = 0; s < t->nshape; s++)
            if (t->coff[s + 1] > t->coff[s]) nvc = 2 * (size_t)t->voff[s + 1];
        b[11] = clCreateBuffer(dev->ctx, ro, sizeof(int) * (nvc ? nvc : 1), (void *)t->vc, &e);
        if (e == CL_SUCCESS)
            b[12] =
                clCreateBuffer(dev->ctx, ro, sizeof(int) * (t->nshape + 1), (void *)t->coff, &e);
        if (e == CL_SUCCESS)
            b[13] = clCreateBuffer(dev->ctx, ro, rs * (len[4] ? len[4] : 1), host[4], &e);
    }
    if (e == CL_SUCCESS)
        b[14] = clCreateBuffer(dev->ctx, CL_MEM_READ_WRITE, sizeof(int) * ilen * npairs, NULL, &e);
    if (e == CL_SUCCESS)
        b[15] = clCreateBuffer(dev->ctx, CL_MEM_READ_WRITE, rs * rlen * npairs, NULL, &e);
    cl_mem bout = NULL;
    if (e == CL_SUCCESS)
        bout = clCreateBuffer(dev->ctx, CL_MEM_WRITE_ONLY, rs * OVL_RESULT_LEN * npairs, NULL, &e);
    if (e == CL_SUCCESS) k = clCreateKernel(prog, "narrow_phase", &e);
    if (e != CL_SUCCESS) {
        if (bout) clReleaseMemObject(bout);
        rc = CL_FAIL(err, "narrow phase set-up", e);
        goto done;
    }
    int flags = 0, il = (int)ilen, rl = (int)rlen, ai = 0;
    cl_int ae = CL_SUCCESS;
    ae |= clSetKernelArg(k, ai++, sizeof(cl_mem), &b[0]);
    ae |= clSetKernelArg(k, ai++, sizeof(int), &npairs);
    for (int i = 1; i <= 13; i++) /* b[11..13], the clusters, may be NULL buffers */
        ae |= clSetKernelArg(k, ai++, sizeof(cl_mem), &b[i]);
    ae |= clSetKernelArg(k, ai++, sizeof(int), &flags);
    ae |= clSetKernelArg(k, ai++, sizeof(cl_mem), &b[14]);
    ae |= clSetKernelArg(k, ai++, sizeof(cl_mem), &b[15]);
    ae |= clSetKernelArg(k, ai++, sizeof(int), &il);
    ae |= clSetKernelArg(k, ai++, sizeof(int), &rl);
    ae |= clSetKernelArg(k, ai++, sizeof(int), &cap);
    ae |= clSetKernelArg(k, ai++, sizeof(cl_mem), &bout);
    size_t global = (size_t)npairs;
    if (ae == CL_SUCCESS)
        e = clEnqueueNDRangeKernel(dev->queue, k, 1, NULL, &global, NULL, 0, NULL, NULL);
    if (ae == CL_SUCCESS && e == CL_SUCCESS)
        e = clEnqueueReadBuffer(dev->queue, bout, CL_TRUE, 0, rs * OVL_RESULT_LEN * npairs, hout, 0,
                                NULL, NULL);
    clReleaseMemObject(bout);
    if (ae != CL_SUCCESS || e != CL_SUCCESS) {
        rc = ae != CL_SUCCESS ? CL_ARG_FAIL(err, "narrow_phase") : CL_FAIL(err, "narrow_phase", e);
        goto done;
    }
    for (size_t i = 0; i < OVL_RESULT_LEN * (size_t)npairs; i++)
        out[i] = dbl ? ((double *)hout)[i] : (double)((float *)hout)[i];
done:
    for (int i = 0; i < 16; i++)
        if (b[i]) clReleaseMemObject(b[i]);
    for (int i = 0; i < 5; i++)
        free(host[i]);
    free(hout);
    if (k) clReleaseKernel(k);
    clReleaseProgram(prog);
    return rc;
}
