/*
 * bvh.cl - the broad phase's build stages over kernels/bvh.h, one work-item per box or node.
 * Built with -DPD_DOUBLE=0 or 1. Boxes are 6 floats (lo xyz, hi xyz). The host sorts (code, index)
 * between bvh_codes and bvh_nodes and scatters the leaf boxes to positions n - 1 + k.
 */
#include "pd_real.h"
#include "bvh.h"

/* Morton code of each particle's centre x (its box's) in the scene box [lo, lo + 1/inv), without
 * its `drop` low bits (fewer bits to sort; Karras orders equal codes by index). */
__kernel void bvh_codes(__global const pd_real *x, int n, pd_real lox, pd_real loy, pd_real loz,
                        pd_real invx, pd_real invy, pd_real invz, __global bvh_code *codes,
                        __global int *index, int drop)
{
    int i = (int)get_global_id(0);
    if (i >= n) return;
    codes[i] = bvh_morton(v3_load(x, i), v3(lox, loy, loz), v3(invx, invy, invz)) >> drop;
    index[i] = i;
}

/* Internal node i's children from the sorted codes (Karras 2012). */
__kernel void bvh_nodes(__global const bvh_code *codes, int n, __global int *left,
                        __global int *right, __global int *parent)
{
    int i = (int)get_global_id(0);
    if (i >= n - 1) return;
    bvh_build_node(codes, n, i, left, right, parent);
}

/*
 * Refit from each leaf upwards: the first child to reach a node stops, the second computes the
 * node's box and goes on. The fence before the counter makes this child's box visible before the
 * counter says so; the one after keeps the second child's loads of the other box from being
 * moved before the counter told it the box is there; and those loads are volatile (bvh_node_box).
 * arrivals must be zero on entry (n - 1 ints).
 */
__kernel void bvh_refit(__global volatile float *box, __global const int *left,
                        __global const int *right, __global const int *parent, int n,
                        __global volatile int *arrivals)
{
    int s = (int)get_global_id(0);
    if (s >= n || n < 2) return;
    int node = n - 1 + s;
    while (node != 0) {
        int p = parent[node];
        mem_fence(CLK_GLOBAL_MEM_FENCE);
        if (atomic_inc(&arrivals[p]) == 0) return;
        mem_fence(CLK_GLOBAL_MEM_FENCE);
        bvh_node_box(box, left, right, p);
        node = p;
    }
}
