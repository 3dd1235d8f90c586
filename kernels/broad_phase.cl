/*
 * broad_phase.cl - boxes, leaf placement and traversal of the broad phase (kernels/bvh.h), one
 * work-item per particle. Built with -DPD_DOUBLE=0 or 1.
 *
 * Particle boxes are cubes around bounding spheres (circumradius plus margin), and a candidate
 * pair must also have its bounding spheres meet. Candidate pairs are found twice (from either
 * particle), so each particle keeps only partners with a larger index; walls (few, tested box
 * against box) follow its particle partners. A pass counts each particle's pairs, the host scans
 * the counts into offsets, and a second pass writes the keys, sorted within each particle's
 * segment: the step's keys come out globally sorted (first body, then second) without a global
 * sort.
 */
#include "pd_real.h"
#include "bvh.h"
#include "contact_history.h"

/*
 * The particles' boxes are not stored (a dense bed's 24 bytes per particle): particle i's is its
 * centre plus or minus its circumradius and a margin (m), rounded outwards to floats (bvh_cube),
 * computed where it is needed from the bodies' arrays: the kernels take those as five arguments
 * (x, size, shape, radius_ratio, margin; sim_body_box_args on the host sets them).
 */
typedef struct bp_bodies {
    __global const pd_real *x, *size, *radius_ratio;
    __global const int *shape;
    pd_real margin;
} bp_bodies;

PD_FN bp_bodies bp_bodies_of(__global const pd_real *x, __global const pd_real *size,
                             __global const int *shape, __global const pd_real *radius_ratio,
                             pd_real margin)
{
    bp_bodies b = {x, size, radius_ratio, shape, margin};
    return b;
}

PD_FN void bp_box(const bp_bodies *b, int i, float *q)
{
    bvh_cube(v3_load(b->x, i), b->radius_ratio[b->shape[i]] * b->size[i] + b->margin, q);
}

/* Leaf k of the tree is the box of particle idx[k] (sorted by Morton code). */
__kernel void bvh_leaves(__global const pd_real *x, __global const pd_real *size,
                         __global const int *shape, __global const pd_real *radius_ratio,
                         pd_real margin, __global const int *idx, int n, __global float *box)
{
    int k = (int)get_global_id(0);
    if (k >= n) return;
    bp_bodies b = bp_bodies_of(x, size, shape, radius_ratio, margin);
    float q[6];
    bp_box(&b, idx[k], q);
    for (int c = 0; c < 6; c++)
        box[6 * (n - 1 + k) + c] = q[c];
}

PD_FN int walls_meeting(__global const float *wbox, int nwall, const float *q, __global ch_key *out,
                        unsigned self)
{
    int m = 0;
    for (int w = 0; w < nwall; w++)
        if (bvh_boxes_meet(wbox + 6 * w, q)) {
            if (out) out[m] = ch_make(self, CH_WALL + (unsigned)w);
            m++;
        }
    return m;
}

/*
 * Partners above i found by testing every later particle's box, written up to cap: for runs of
 * a few particles (the host's `brute` flag), the same pairs in the same order as the tree gives,
 * without the tree's ~25 kernel launches per step, which dominate such a step.
 */
PD_FN int brute_after(const bp_bodies *b, int n, const float *q, int i, __global int *out, int cap)
{
    int m = 0;
    for (int j = i + 1; j < n; j++) {
        float a[6];
        bp_box(b, j, a);
        if (bvh_boxes_meet_priv(a, q) && bvh_spheres_meet_priv(a, q)) {
            if (m < cap) out[m] = j;
            m++;
        }
    }
    return m;
}

/*
 * Number of candidate pairs of particle i (partners above i, then walls). The first BROAD_CAP
 * partners are kept in cand[i * BROAD_CAP ..], so broad_write traverses again only for particles
 * with more.
 */
#define BROAD_CAP BVH_CAND
__kernel void broad_count(__global const float *box, __global const int *left,
                          __global const int *right, __global const int *idx, int n,
                          __global const pd_real *x, __global const pd_real *size,
                          __global const int *shape, __global const pd_real *radius_ratio,
                          pd_real margin, __global const float *wbox, int nwall,
                          __global int *count, __global int *cand, int brute)
{
    int i = (int)get_global_id(0);
    if (i >= n) return;
    bp_bodies b = bp_bodies_of(x, size, shape, radius_ratio, margin);
    float q[6];
    bp_box(&b, i, q);
    __global int *keep = cand + (size_t)i * BROAD_CAP;
    int m = brute ? brute_after(&b, n, q, i, keep, BROAD_CAP)
                  : bvh_query_after(box, left, right, n, q, idx, i, 1, keep, BROAD_CAP);
    count[i] = m + walls_meeting(wbox, nwall, q, 0, (unsigned)i);
}

/*
 * Writes particle i's pair keys at offset[i]: partners in ascending order (an insertion sort of
 * the segment: a particle has tens of candidates), then walls. The partner ids are first stored
 * in scratch at the same offsets (an int per pair: the gather's second-body lists, which are
 * filled after this).
 */
__kernel void broad_write(__global const float *box, __global const int *left,
                          __global const int *right, __global const int *idx, int n,
                          __global const pd_real *x, __global const pd_real *size,
                          __global const int *shape, __global const pd_real *radius_ratio,
                          pd_real margin, __global const float *wbox, int nwall,
                          __global const int *offset, __global const int *cand,
                          __global int *scratch, __global ch_key *keys, int brute)
{
    int i = (int)get_global_id(0);
    if (i >= n) return;
    bp_bodies b = bp_bodies_of(x, size, shape, radius_ratio, margin);
    float q[6];
    bp_box(&b, i, q);
    int off = offset[i], cap = offset[i + 1] - off;
    __global int *ids = scratch + off;
    int m = 0;
    for (int w = 0; w < nwall; w++) /* the count included walls; partners are the rest */
        m += bvh_boxes_meet(wbox + 6 * w, q);
    m = cap - m;
    if (m <= BROAD_CAP) {
        for (int a = 0; a < m; a++)
            ids[a] = cand[(size_t)i * BROAD_CAP + a];
    } else {
        m = brute ? brute_after(&b, n, q, i, ids, m)
                  : bvh_query_after(box, left, right, n, q, idx, i, 1, ids, m);
    }
    for (int a = 1; a < m; a++) {
        int v = ids[a], b = a - 1;
        while (b >= 0 && ids[b] > v) {
            ids[b + 1] = ids[b];
            b--;
        }
        ids[b + 1] = v;
    }
    for (int a = 0; a < m; a++)
        keys[off + a] = ch_make((unsigned)i, (unsigned)ids[a]);
    walls_meeting(wbox, nwall, q, keys + off + m, (unsigned)i);
}

/*
 * Batched breadth-first traversal, the alternative the thesis (section 5.5) found 5-10x faster
 * than per-particle depth first on its GPU. Kept for the measurement in bench/step --traversal
 * (bench/RESULTS.md: 2.7-4.2x slower than depth first on a 2-core CPU through PoCL); the
 * pipeline uses broad_count/broad_write. A frontier holds (particle,
 * node) entries whose boxes meet; one level counts each entry's internal children that meet the
 * particle's box (bfs_count), the host scans the counts into offsets, and bfs_write writes them
 * as the next frontier and counts the leaf children that are candidate partners (above the
 * particle, spheres meeting) into count[particle] (integer atomics: the sums are exact).
 */
__kernel void bfs_count(__global const float *box, __global const int *left,
                        __global const int *right, int n, __global const pd_real *x,
                        __global const pd_real *size, __global const int *shape,
                        __global const pd_real *radius_ratio, pd_real margin,
                        __global const int *fp, __global const int *fnode, int nf,
                        __global int *emit)
{
    int e = (int)get_global_id(0);
    if (e >= nf) return;
    int i = fp[e], node = fnode[e], m = 0;
    int kids[2] = {left[node], right[node]};
    bp_bodies b = bp_bodies_of(x, size, shape, radius_ratio, margin);
    float q[6];
    bp_box(&b, i, q);
    for (int k = 0; k < 2; k++)
        m += kids[k] < n - 1 && bvh_boxes_meet(box + 6 * kids[k], q);
    emit[e] = m;
}

__kernel void bfs_write(__global const float *box, __global const int *left,
                        __global const int *right, __global const int *idx, int n,
                        __global const pd_real *x, __global const pd_real *size,
                        __global const int *shape, __global const pd_real *radius_ratio,
                        pd_real margin, __global const int *fp, __global const int *fnode, int nf,
                        __global const int *offset, __global int *np, __global int *nnode,
                        __global int *count)
{
    int e = (int)get_global_id(0);
    if (e >= nf) return;
    int i = fp[e], node = fnode[e], o = offset[e];
    int kids[2] = {left[node], right[node]};
    bp_bodies b = bp_bodies_of(x, size, shape, radius_ratio, margin);
    float q[6];
    bp_box(&b, i, q);
    for (int k = 0; k < 2; k++) {
        int c = kids[k];
        if (!bvh_boxes_meet(box + 6 * c, q)) continue;
        if (c < n - 1) {
            np[o] = i;
            nnode[o++] = c;
        } else if (idx[c - (n - 1)] > i && bvh_spheres_meet(box + 6 * c, q)) {
            atomic_inc(count + i);
        }
    }
}
