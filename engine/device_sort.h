/*
 * device_sort.h - prefix sums and stable radix sorting of 64-bit keys on an OpenCL device
 * (kernels/sort.cl): the broad phase's Morton sort and the scans of pair counts.
 * Engine-internal. Lifecycle: dsort_init -> dsort_scan / dsort_radix ... -> dsort_free.
 */
#ifndef PD_DEVICE_SORT_H
#define PD_DEVICE_SORT_H

#include "cl_internal.h"

typedef struct dsort {
    pd_device *dev;
    cl_kernel k_partial, k_top, k_apply, k_count, k_scatter;
    cl_mem part;  /* chunk sums of a scan */
    cl_mem count; /* digit counts of a radix pass */
    cl_mem first; /* their exclusive scan */
    size_t count_cap;
} dsort;

int dsort_init(dsort *s, pd_device *dev, int dbl, pd_error *err);
void dsort_free(dsort *s);

/* out[0..n) = exclusive prefix sums of in[0..n) (ints), out[n] = the total; out != in. */
int dsort_scan(dsort *s, cl_mem in, int n, cl_mem out, pd_error *err);

/*
 * Sorts n (key, value) pairs (cl_ulong keys, int values) by the 8-bit digits at the given bit
 * shifts, least significant first; stable. The pairs are in *key, *val and end there: the
 * buffers are swapped with *key_tmp, *val_tmp as passes ping-pong between them.
 */
int dsort_radix(dsort *s, cl_mem *key, cl_mem *val, cl_mem *key_tmp, cl_mem *val_tmp, int n,
                const int *shifts, int npass, pd_error *err);

/* Enqueues kernel k over at least n work-items in groups of 64 (nothing when n is 0); the
 * kernel ignores ids at or above its own count. Names it in errors. */
int cl_launch(pd_device *dev, cl_kernel k, size_t n, const char *what, pd_error *err);

#endif
