/*
 * wall_bvh.h - the static bounding volume hierarchy over one wall's triangles (thesis section
 * 5.6: a wall's triangles go into a BVH one by one, where a particle goes in whole), and the two
 * queries the narrow phase makes of it: the triangles meeting a box, and the nodes a ray crosses.
 * Shared by OpenCL kernels and host C (see pd_real.h); built on the host (engine/wall_bvh.c) in
 * the wall's own frame, where it never changes however the wall moves.
 *
 * Layout, per wall (the walls' trees are concatenated; node indices are local to the wall):
 *   box[6 k ..]  node k's box, lo xyz then hi xyz, metres in the wall frame (node 0 the root);
 *   kid[2 k ..]  an internal node's children, or for a leaf (-1 - first, count): its triangles
 *                are order[first .. first + count), indices into the wall's triangles.
 */
#ifndef PD_WALL_BVH_H
#define PD_WALL_BVH_H

#include "pd_real.h"

/* Depth bound of the traversal stack: the host builder splits at the median, so a tree over n
 * triangles is about log2(n / WB_LEAF) deep, and it refuses to build one deeper than this. */
#define WB_STACK 48
#define WB_LEAF 4 /* triangles per leaf at most */

typedef struct wb_tree {
    PD_GLOBAL const pd_real *box;
    PD_GLOBAL const int *kid, *order;
    PD_GLOBAL const pd_real *vert; /* the wall's vertices (wall frame) */
    PD_GLOBAL const int *tri;      /* its triangles */
} wb_tree;

/*
 * The box the narrow phase searches around point o (a wall's frame) for what lies within `reach`
 * of it: the cube of half-side reach, widened well beyond the rounding of o and reach (relative
 * 1e-5 of reach plus 64 ulps of o). The host's bound on near triangles (wall_tree_max_near, its
 * caller in sim_state.c) allows for this widening.
 */
PD_FN void wb_reach_box(pd_v3 o, pd_real reach, pd_v3 *lo, pd_v3 *hi)
{
    pd_real h = reach * (PD_R(1) + PD_R(1e-5)) + PD_R(64) * PD_EPS * v3_amax(o);
    *lo = v3_sub(o, v3(h, h, h));
    *hi = v3_add(o, v3(h, h, h));
}

/* No tree (ovl_in.wall of a closed B). */
PD_FN void wb_tree_none(wb_tree *w)
{
    w->box = 0;
    w->kid = w->order = w->tri = 0;
    w->vert = 0;
}

PD_FN int wb_box_meets(PD_GLOBAL const pd_real *b, pd_v3 lo, pd_v3 hi)
{
    return !(b[3] < lo.x || b[0] > hi.x || b[4] < lo.y || b[1] > hi.y || b[5] < lo.z ||
             b[2] > hi.z);
}

/* Whether the box of triangle t meets [lo, hi]. */
PD_FN int wb_tri_meets(const wb_tree *w, int t, pd_v3 lo, pd_v3 hi)
{
    pd_v3 a = v3_load(w->vert, w->tri[3 * t]), b = v3_load(w->vert, w->tri[3 * t + 1]),
          c = v3_load(w->vert, w->tri[3 * t + 2]);
    return !(pd_max(pd_max(a.x, b.x), c.x) < lo.x || pd_min(pd_min(a.x, b.x), c.x) > hi.x ||
             pd_max(pd_max(a.y, b.y), c.y) < lo.y || pd_min(pd_min(a.y, b.y), c.y) > hi.y ||
             pd_max(pd_max(a.z, b.z), c.z) < lo.z || pd_min(pd_min(a.z, b.z), c.z) > hi.z);
}

/*
 * The triangles whose boxes meet [lo, hi], written to out[0 .. cap) in the tree's order.
 * Returns how many there are (more than cap: the caller's scratch is too small; only cap were
 * written), or -1 when the tree is deeper than WB_STACK (the builder rules that out).
 */
PD_FN int wb_query_box(const wb_tree *w, pd_v3 lo, pd_v3 hi, PD_GLOBAL int *out, int cap)
{
    int stack[WB_STACK], sp = 0, m = 0;
    if (!wb_box_meets(w->box, lo, hi)) return 0;
    stack[sp++] = 0;
    while (sp > 0) {
        int k = stack[--sp];
        int k0 = w->kid[2 * k], k1 = w->kid[2 * k + 1];
        if (k0 < 0) {
            for (int i = -1 - k0; i < -1 - k0 + k1; i++) {
                int t = w->order[i];
                if (!wb_tri_meets(w, t, lo, hi)) continue;
                if (m < cap) out[m] = t;
                m++;
            }
            continue;
        }
        /* right first, so the left subtree is visited first */
        if (wb_box_meets(w->box + 6 * k1, lo, hi)) {
            if (sp == WB_STACK) return -1;
            stack[sp++] = k1;
        }
        if (wb_box_meets(w->box + 6 * k0, lo, hi)) {
            if (sp == WB_STACK) return -1;
            stack[sp++] = k0;
        }
    }
    return m;
}

/*
 * Whether the ray o + t r (t >= 0) meets box b widened by pad on every side (slab test). The
 * widening makes it conservative: the caller's exact predicates decide, this only prunes.
 */
PD_FN int wb_ray_meets(PD_GLOBAL const pd_real *b, pd_v3 o, pd_v3 r, pd_real pad)
{
    pd_real t0 = 0, t1 = PD_REAL_MAX;
    pd_real oo[3] = {o.x, o.y, o.z}, rr[3] = {r.x, r.y, r.z};
    for (int k = 0; k < 3; k++) {
        pd_real lo = b[k] - pad, hi = b[3 + k] + pad;
        if (rr[k] == PD_R(0)) {
            if (oo[k] < lo || oo[k] > hi) return 0;
            continue;
        }
        pd_real inv = PD_R(1) / rr[k];
        pd_real ta = (lo - oo[k]) * inv, tb = (hi - oo[k]) * inv;
        if (ta > tb) {
            pd_real s = ta;
            ta = tb;
            tb = s;
        }
        t0 = pd_max(t0, ta);
        t1 = pd_min(t1, tb);
        if (t0 > t1) return 0;
    }
    return 1;
}

#endif /* PD_WALL_BVH_H */
