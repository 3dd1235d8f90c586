/*
 * bvh.h - linear bounding volume hierarchy (LBVH) over axis-aligned boxes: the broad phase of
 * thesis section 5.5, shared by OpenCL kernels and host C (see pd_real.h).
 *
 * Build (Karras 2012, "Maximizing parallelism in the construction of BVHs, octrees and k-d
 * trees"): leaves are the boxes sorted by the 63-bit Morton code of their centres; internal node
 * i (0 .. n-2) finds its key range and split from longest common prefixes alone, so every node is
 * built independently, one work-item each. Equal codes are told apart by the leaf index, as Karras
 * does. Children: an index below n-1 is an internal node, at or above n-1 the leaf (index - (n-1))
 * in sorted order. Refit then takes boxes bottom-up: a node is finished by whichever of its two
 * children arrives second (on a device, an atomic counter per node decides; min/max are exact, so
 * the result does not depend on the order).
 *
 * Traversal: depth first with a fixed stack, reporting every leaf whose box meets the query box.
 */
#ifndef PD_BVH_H
#define PD_BVH_H

#include "pd_real.h"

#ifdef __OPENCL_VERSION__
typedef ulong bvh_code;
#define BVH_CLZ64(x) ((int)clz(x))
#else
#include <float.h>
#include <stdint.h>
typedef uint64_t bvh_code;
#define BVH_CLZ64(x) ((x) ? __builtin_clzll(x) : 64)
#endif

/* Partners the broad phase's counting pass keeps per particle (broad_phase.cl), so its writing
 * pass traverses again only for particles with more: enough for a packing's neighbours above a
 * particle, 32 bytes of device memory per particle. */
#define BVH_CAND 8

/* depth bound: prefixes of 63 code bits plus up to 32 index bits on equal codes */
#define BVH_STACK 128

/*
 * Boxes are floats in either precision, rounded outwards from the positions' reals: a box only
 * has to contain its particle, and floats halve the tree's memory (72 of a dense bed's ~1 170
 * bytes per particle in double precision, bench/RESULTS.md).
 */
PD_FN float bvh_down(pd_real x)
{
#if PD_DOUBLE && defined(__OPENCL_VERSION__)
    return convert_float_rtn(x);
#elif PD_DOUBLE
    float f = (float)x;
    return (double)f > x ? nextafterf(f, -INFINITY) : f;
#else
    return x;
#endif
}

PD_FN float bvh_up(pd_real x)
{
#if PD_DOUBLE && defined(__OPENCL_VERSION__)
    return convert_float_rtp(x);
#elif PD_DOUBLE
    float f = (float)x;
    return (double)f < x ? nextafterf(f, INFINITY) : f;
#else
    return x;
#endif
}

/* Box [c - r, c + r] (a cube) rounded outwards into b (lo xyz, hi xyz). */
PD_FN void bvh_cube(pd_v3 c, pd_real r, float *b)
{
    b[0] = bvh_down(c.x - r);
    b[1] = bvh_down(c.y - r);
    b[2] = bvh_down(c.z - r);
    b[3] = bvh_up(c.x + r);
    b[4] = bvh_up(c.y + r);
    b[5] = bvh_up(c.z + r);
}

/* Spreads the low 21 bits of v so there are two zero bits between each. */
PD_FN bvh_code bvh_spread3(bvh_code v)
{
    v &= 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffull;
    v = (v | v << 16) & 0x1f0000ff0000ffull;
    v = (v | v << 8) & 0x100f00f00f00f00full;
    v = (v | v << 4) & 0x10c30c30c30c30c3ull;
    v = (v | v << 2) & 0x1249249249249249ull;
    return v;
}

/* 63-bit Morton code of point p inside the scene box [lo, lo + 1/inv_ext). */
PD_FN bvh_code bvh_morton(pd_v3 p, pd_v3 lo, pd_v3 inv_ext)
{
    pd_real s = PD_R(2097151); /* 2^21 - 1 */
    pd_real fx = (p.x - lo.x) * inv_ext.x * s, fy = (p.y - lo.y) * inv_ext.y * s,
            fz = (p.z - lo.z) * inv_ext.z * s;
    fx = fx < 0 ? 0 : fx > s ? s : fx;
    fy = fy < 0 ? 0 : fy > s ? s : fy;
    fz = fz < 0 ? 0 : fz > s ? s : fz;
    return bvh_spread3((bvh_code)fx) << 2 | bvh_spread3((bvh_code)fy) << 1 |
           bvh_spread3((bvh_code)fz);
}

/* Length of the common prefix of sorted keys i and j (with the index appended on equal codes);
 * -1 when j is out of range. */
PD_FN int bvh_delta(PD_GLOBAL const bvh_code *codes, int n, int i, int j)
{
    if (j < 0 || j >= n) return -1;
    bvh_code a = codes[i], b = codes[j];
    if (a == b) return 64 + BVH_CLZ64((bvh_code)(i ^ j));
    return BVH_CLZ64(a ^ b);
}

/* Internal node i of the n leaves: its children (Karras 2012, figure 4). */
PD_FN void bvh_build_node(PD_GLOBAL const bvh_code *codes, int n, int i, PD_GLOBAL int *left,
                          PD_GLOBAL int *right, PD_GLOBAL int *parent)
{
    /* direction of the node's range */
    int d = bvh_delta(codes, n, i, i + 1) - bvh_delta(codes, n, i, i - 1) >= 0 ? 1 : -1;
    int dmin = bvh_delta(codes, n, i, i - d);
    /* upper bound of the range's length, then its exact other end */
    int lmax = 2;
    while (bvh_delta(codes, n, i, i + lmax * d) > dmin)
        lmax *= 2;
    int l = 0;
    for (int t = lmax / 2; t >= 1; t /= 2)
        if (bvh_delta(codes, n, i, i + (l + t) * d) > dmin) l += t;
    int j = i + l * d;
    /* the split: the highest position sharing more than the range's common prefix */
    int dnode = bvh_delta(codes, n, i, j), s = 0;
    for (int t = (l + 1) / 2;; t = (t + 1) / 2) {
        if (bvh_delta(codes, n, i, i + (s + t) * d) > dnode) s += t;
        if (t == 1) break;
    }
    int gamma = i + s * d + (d < 0 ? d : 0);
    int lo = i < j ? i : j, hi = i < j ? j : i;
    int a = lo == gamma ? n - 1 + gamma : gamma; /* a leaf when the range ends there */
    int b = hi == gamma + 1 ? n - 1 + gamma + 1 : gamma + 1;
    left[i] = a;
    right[i] = b;
    parent[a] = i;
    parent[b] = i;
}

/*
 * Box of internal node i from its children's boxes (6 floats per node: lo xyz, hi xyz; leaves
 * follow the n - 1 internal nodes). min and max are exact: no rounding. volatile: in bvh_refit
 * one child's box was written by another work-item, possibly on another compute unit, whose
 * writes a GPU's non-coherent L1 cache may not show to a cached load (x86 and PoCL never do
 * that; NVIDIA's and AMD's GPUs can); a volatile load goes to the coherent level.
 */
PD_FN void bvh_node_box(PD_GLOBAL volatile float *box, PD_GLOBAL const int *left,
                        PD_GLOBAL const int *right, int i)
{
    PD_GLOBAL const volatile float *a = box + 6 * left[i], *b = box + 6 * right[i];
    PD_GLOBAL volatile float *o = box + 6 * i;
    for (int k = 0; k < 3; k++) {
        o[k] = a[k] < b[k] ? a[k] : b[k];
        o[3 + k] = a[3 + k] > b[3 + k] ? a[3 + k] : b[3 + k];
    }
}

/* Whether boxes a and q meet; a in private memory (OpenCL 1.2 has no generic pointers). */
PD_FN int bvh_boxes_meet_priv(const float *a, const float *q)
{
    return a[0] <= q[3] && q[0] <= a[3] && a[1] <= q[4] && q[1] <= a[4] && a[2] <= q[5] &&
           q[2] <= a[5];
}

/* Whether box a (a tree node's or a wall's) meets box q. */
PD_FN int bvh_boxes_meet(PD_GLOBAL const float *a, const float *q)
{
    float b[6] = {a[0], a[1], a[2], a[3], a[4], a[5]};
    return bvh_boxes_meet_priv(b, q);
}

/*
 * For boxes that are cubes centred on bounding spheres (the engine's particle boxes): 1 when the
 * spheres inscribed in box a and query box q meet. a in private memory; bvh_spheres_meet for a
 * tree's leaf.
 */
PD_FN int bvh_spheres_meet_priv(const float *a, const float *q)
{
    float dx = (a[0] + a[3]) - (q[0] + q[3]), dy = (a[1] + a[4]) - (q[1] + q[4]),
          dz = (a[2] + a[5]) - (q[2] + q[5]);
    /*
     * All doubled: centres and radii. Rounding the boxes outwards grows each radius but can move
     * a centre by up to an ulp of the coordinates per axis, and the sums here round too: the sum
     * of radii is grown by a few ulps of itself and 32 ulps of the largest coordinate, so no
     * touching pair is dropped.
     */
    float m = 0;
    for (int k = 0; k < 6; k++) {
        float u = a[k] < 0 ? -a[k] : a[k], v = q[k] < 0 ? -q[k] : q[k];
        m = u > m ? u : m;
        m = v > m ? v : m;
    }
    float r = ((a[3] - a[0]) + (q[3] - q[0])) * (1.0f + 64 * FLT_EPSILON) + 32 * FLT_EPSILON * m;
    return dx * dx + dy * dy + dz * dz <= r * r;
}

PD_FN int bvh_spheres_meet(PD_GLOBAL const float *a, const float *q)
{
    float b[6] = {a[0], a[1], a[2], a[3], a[4], a[5]};
    return bvh_spheres_meet_priv(b, q);
}

/*
 * Leaves whose boxes meet query box q (lo xyz, hi xyz), as the ids idx[sorted position] (or the
 * sorted positions when idx is NULL), keeping only ids above `after` (-1: all). With `spheres`,
 * the boxes are cubes around bounding spheres and a leaf must also pass bvh_spheres_meet. They are
 * written to out up to cap; returns how many there are (more than cap means the caller retries with
 * more room), -1 when the stack would overflow (it cannot for an LBVH of 2^31 leaves).
 */
PD_FN int bvh_query_after(PD_GLOBAL const float *box, PD_GLOBAL const int *left,
                          PD_GLOBAL const int *right, int n, const float *q,
                          PD_GLOBAL const int *idx, int after, int spheres, PD_GLOBAL int *out,
                          int cap)
{
    int count = 0;
    int stack[BVH_STACK], top = 0;
    stack[top++] = 0;
    while (top > 0) {
        int node = stack[--top];
        if (!bvh_boxes_meet(box + 6 * node, q)) continue;
        if (node >= n - 1) {
            int k = node - (n - 1), id = idx ? idx[k] : k;
            if (id > after && (!spheres || bvh_spheres_meet(box + 6 * node, q))) {
                if (count < cap) out[count] = id;
                count++;
            }
            continue;
        }
        if (top + 2 > BVH_STACK) return -1;
        stack[top++] = right[node];
        stack[top++] = left[node];
    }
    return count;
}

/* Leaves (sorted positions) whose boxes meet q; see bvh_query_after. */
PD_FN int bvh_query(PD_GLOBAL const float *box, PD_GLOBAL const int *left,
                    PD_GLOBAL const int *right, int n, const float *q, PD_GLOBAL int *out, int cap)
{
    return bvh_query_after(box, left, right, n, q, 0, -1, 0, out, cap);
}

#endif /* PD_BVH_H */
