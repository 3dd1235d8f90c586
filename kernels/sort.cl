/*
 * sort.cl - prefix sums and a stable least-significant-digit radix sort of 64-bit keys with int
 * values, for the broad phase (Morton codes) and the counts of candidate pairs.
 *
 * Both work the same way: the input is cut into nwork contiguous chunks, one per work-item, each
 * processed in order. Scans: chunk sums, one work-item scans the sums, chunks add their base.
 * Radix (8-bit digits): per chunk digit counts laid out digit-major (count[d * nwork + g]), an
 * exclusive scan of those gives every (digit, chunk) its first output slot, and each chunk
 * scatters its keys in order. The result is stable and the same on every run and device: no
 * atomics. Built with -DPD_DOUBLE=0 or 1 (no reals are used).
 */
#include "pd_real.h"

/* part[g] = sum of in over chunk g. */
__kernel void scan_partial(__global const int *in, int n, int chunk, int nwork, __global int *part)
{
    int g = (int)get_global_id(0);
    if (g >= nwork) return;
    int lo = g * chunk, hi = min(n, lo + chunk), s = 0;
    for (int i = lo; i < hi; i++)
        s += in[i];
    part[g] = s;
}

/* Exclusive scan of the nwork chunk sums in place; out[n] receives the total. */
__kernel void scan_top(__global int *part, int nwork, __global int *out, int n)
{
    if (get_global_id(0) != 0) return;
    int s = 0;
    for (int g = 0; g < nwork; g++) {
        int v = part[g];
        part[g] = s;
        s += v;
    }
    out[n] = s;
}

/* out[i] = exclusive prefix sum of in at i (out may not alias in). */
__kernel void scan_apply(__global const int *in, int n, int chunk, int nwork,
                         __global const int *part, __global int *out)
{
    int g = (int)get_global_id(0);
    if (g >= nwork) return;
    int lo = g * chunk, hi = min(n, lo + chunk), s = part[g];
    for (int i = lo; i < hi; i++) {
        out[i] = s;
        s += in[i];
    }
}

__kernel void radix_count(__global const ulong *key, int n, int chunk, int nwork, int shift,
                          __global int *count)
{
    int g = (int)get_global_id(0);
    if (g >= nwork) return;
    int c[256];
    for (int d = 0; d < 256; d++)
        c[d] = 0;
    int lo = g * chunk, hi = min(n, lo + chunk);
    for (int i = lo; i < hi; i++)
        c[(int)((key[i] >> shift) & 255)]++;
    for (int d = 0; d < 256; d++)
        count[d * nwork + g] = c[d];
}

__kernel void radix_scatter(__global const ulong *key, __global const int *val, int n, int chunk,
                            int nwork, int shift, __global const int *first,
                            __global ulong *key_out, __global int *val_out)
{
    int g = (int)get_global_id(0);
    if (g >= nwork) return;
    int o[256];
    for (int d = 0; d < 256; d++)
        o[d] = first[d * nwork + g];
    int lo = g * chunk, hi = min(n, lo + chunk);
    for (int i = lo; i < hi; i++) {
        ulong k = key[i];
        int p = o[(int)((k >> shift) & 255)]++;
        key_out[p] = k;
        val_out[p] = val[i];
    }
}
