/* device_sort.c - prefix sums and radix sort on a device (see device_sort.h, kernels/sort.cl). */
#include <string.h>

#include "device_sort.h"

/* Chunked work: at most this many work-items scan serially inside scan_top. */
#define SCAN_MAX_WORK 1024

/*
 * Work-groups of a fixed size, the global size rounded up to it (every kernel checks its range).
 * A fixed shape matters on PoCL, which compiles a kernel anew for each work-group size it picks,
 * and it would pick a new one whenever the number of pairs changes.
 */
#define LAUNCH_GROUP 64

int cl_launch(pd_device *dev, cl_kernel k, size_t n, const char *what, pd_error *err)
{
    if (n == 0) return PD_OK;
    size_t local = LAUNCH_GROUP, global = (n + local - 1) / local * local;
    cl_int e = clEnqueueNDRangeKernel(dev->queue, k, 1, NULL, &global, &local, 0, NULL, NULL);
    return e == CL_SUCCESS ? PD_OK : CL_FAIL(err, what, e);
}

int dsort_init(dsort *s, pd_device *dev, int dbl, pd_error *err)
{
    memset(s, 0, sizeof *s);
    s->dev = dev;
    cl_program p;
    int rc = cl_program_get(dev, "sort", dbl, &p, err);
    if (rc != PD_OK) return rc;
    cl_int e = CL_SUCCESS;
    const char *names[5] = {"scan_partial", "scan_top", "scan_apply", "radix_count",
                            "radix_scatter"};
    cl_kernel *ks[5] = {&s->k_partial, &s->k_top, &s->k_apply, &s->k_count, &s->k_scatter};
    for (int i = 0; i < 5; i++) {
        *ks[i] = clCreateKernel(p, names[i], &e);
        if (e != CL_SUCCESS) {
            dsort_free(s);
            return CL_FAIL(err, names[i], e);
        }
    }
    s->part = clCreateBuffer(dev->ctx, CL_MEM_READ_WRITE, sizeof(int) * SCAN_MAX_WORK, NULL, &e);
    if (e != CL_SUCCESS) {
        dsort_free(s);
        return CL_FAIL(err, "clCreateBuffer(scan)", e);
    }
    return PD_OK;
}

void dsort_free(dsort *s)
{
    cl_kernel ks[5] = {s->k_partial, s->k_top, s->k_apply, s->k_count, s->k_scatter};
    for (int i = 0; i < 5; i++)
        if (ks[i]) clReleaseKernel(ks[i]);
    if (s->part) clReleaseMemObject(s->part);
    if (s->count) clReleaseMemObject(s->count);
    if (s->first) clReleaseMemObject(s->first);
    memset(s, 0, sizeof *s);
}

/* Splits n items into nwork chunks of chunk items, at most max_work and at least min_chunk each. */
static void split(int n, int max_work, int min_chunk, int *nwork, int *chunk)
{
    int w = (n + min_chunk - 1) / min_chunk;
    if (w > max_work) w = max_work;
    if (w < 1) w = 1;
    *chunk = (n + w - 1) / w;
    if (*chunk < 1) *chunk = 1;
    *nwork = (n + *chunk - 1) / *chunk;
    if (*nwork < 1) *nwork = 1;
}

int dsort_scan(dsort *s, cl_mem in, int n, cl_mem out, pd_error *err)
{
    int nwork, chunk;
    split(n, SCAN_MAX_WORK, 64, &nwork, &chunk);
    cl_int e = CL_SUCCESS;
    e |= CL_ARG(s->k_partial, 0, in);
    e |= CL_ARG(s->k_partial, 1, n);
    e |= CL_ARG(s->k_partial, 2, chunk);
    e |= CL_ARG(s->k_partial, 3, nwork);
    e |= CL_ARG(s->k_partial, 4, s->part);
    e |= CL_ARG(s->k_top, 0, s->part);
    e |= CL_ARG(s->k_top, 1, nwork);
    e |= CL_ARG(s->k_top, 2, out);
    e |= CL_ARG(s->k_top, 3, n);
    e |= CL_ARG(s->k_apply, 0, in);
    e |= CL_ARG(s->k_apply, 1, n);
    e |= CL_ARG(s->k_apply, 2, chunk);
    e |= CL_ARG(s->k_apply, 3, nwork);
    e |= CL_ARG(s->k_apply, 4, s->part);
    e |= CL_ARG(s->k_apply, 5, out);
    if (e != CL_SUCCESS) return CL_ARG_FAIL(err, "scan_partial, scan_top and scan_apply");
    int rc = cl_launch(s->dev, s->k_partial, (size_t)nwork, "scan_partial", err);
    if (rc == PD_OK) rc = cl_launch(s->dev, s->k_top, 1, "scan_top", err);
    if (rc == PD_OK) rc = cl_launch(s->dev, s->k_apply, (size_t)nwork, "scan_apply", err);
    return rc;
}

int dsort_radix(dsort *s, cl_mem *key, cl_mem *val, cl_mem *key_tmp, cl_mem *val_tmp, int n,
                const int *shifts, int npass, pd_error *err)
{
    if (n <= 1) return PD_OK;
    pd_device *dev = s->dev;
    int max_work = dev->gpu ? 64 * dev->compute_units : 4 * dev->compute_units;
    int nwork, chunk;
    split(n, max_work, 256, &nwork, &chunk);
    size_t need = 256 * (size_t)nwork;
    if (need > s->count_cap) {
        if (s->count) clReleaseMemObject(s->count);
        if (s->first) clReleaseMemObject(s->first);
        s->count = s->first = NULL;
        s->count_cap = 0;
        cl_int e;
        s->count = clCreateBuffer(dev->ctx, CL_MEM_READ_WRITE, sizeof(int) * need, NULL, &e);
        if (e == CL_SUCCESS)
            s->first =
                clCreateBuffer(dev->ctx, CL_MEM_READ_WRITE, sizeof(int) * (need + 1), NULL, &e);
        if (e != CL_SUCCESS) return CL_FAIL(err, "clCreateBuffer(radix counts)", e);
        s->count_cap = need;
    }
    for (int p = 0; p < npass; p++) {
        int shift = shifts[p];
        cl_int e = CL_SUCCESS;
        e |= CL_ARG(s->k_count, 0, *key);
        e |= CL_ARG(s->k_count, 1, n);
        e |= CL_ARG(s->k_count, 2, chunk);
        e |= CL_ARG(s->k_count, 3, nwork);
        e |= CL_ARG(s->k_count, 4, shift);
        e |= CL_ARG(s->k_count, 5, s->count);
        e |= CL_ARG(s->k_scatter, 0, *key);
        e |= CL_ARG(s->k_scatter, 1, *val);
        e |= CL_ARG(s->k_scatter, 2, n);
        e |= CL_ARG(s->k_scatter, 3, chunk);
        e |= CL_ARG(s->k_scatter, 4, nwork);
        e |= CL_ARG(s->k_scatter, 5, shift);
        e |= CL_ARG(s->k_scatter, 6, s->first);
        e |= CL_ARG(s->k_scatter, 7, *key_tmp);
        e |= CL_ARG(s->k_scatter, 8, *val_tmp);
        if (e != CL_SUCCESS) return CL_ARG_FAIL(err, "radix_count and radix_scatter");
        int rc = cl_launch(dev, s->k_count, (size_t)nwork, "radix_count", err);
        if (rc == PD_OK) rc = dsort_scan(s, s->count, (int)need, s->first, err);
        if (rc == PD_OK) rc = cl_launch(dev, s->k_scatter, (size_t)nwork, "radix_scatter", err);
        if (rc != PD_OK) return rc;
        cl_mem t = *key;
        *key = *key_tmp;
        *key_tmp = t;
        t = *val;
        *val = *val_tmp;
        *val_tmp = t;
    }
    return PD_OK;
}
