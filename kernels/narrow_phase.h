/*
 * narrow_phase.h - the narrow phase of the pipeline (thesis section 5.2-5.3): one candidate pair
 * of particles, each a shape (a mesh in its body frame at size 1) scaled by its size and placed by
 * its pose, turned into an overlap problem (kernels/overlap.h) in the first particle's body frame
 * (figure 5.4) and its answer turned back into world coordinates. Shared by OpenCL and host C.
 *
 * Shapes are concatenated: shape s has vertices vert[3 voff[s] ..], triangles tri[3 toff[s] ..]
 * with indices local to the shape, the vertex -> triangle table vt_off[voff[s] + s ..] (nv + 1
 * entries, local) over vt[3 toff[s] ..]. The filter's vertex clusters (ovl_in's vc_*, disc_*),
 * where vc is not NULL: shape s's at vc[2 voff[s] ..] and disc[OVL_DISC coff[s] ..], none where
 * coff[s + 1] == coff[s] (walls, spheres).
 */
#ifndef PD_NARROW_PHASE_H
#define PD_NARROW_PHASE_H

#include "overlap.h"

typedef struct np_shapes {
    PD_GLOBAL const pd_real *vert;
    PD_GLOBAL const int *tri, *voff, *toff, *vt_off, *vt;
    PD_GLOBAL const int *vc, *coff; /* NULL vc: no clusters */
    PD_GLOBAL const pd_real *disc;
} np_shapes;

/* Shape s's vertex clusters into *vc and *disc, or NULLs where it has none. */
PD_FN void np_clusters(const np_shapes *sh, int s, PD_GLOBAL const int **vc,
                       PD_GLOBAL const pd_real **disc)
{
    int has = sh->vc && sh->coff[s + 1] > sh->coff[s];
    *vc = has ? sh->vc + 2 * sh->voff[s] : 0;
    *disc = has ? sh->disc + OVL_DISC * sh->coff[s] : 0;
}

/* Pose of one particle: position (m), orientation [w, x, y, z] (unit), size (m), shape index. */
typedef struct np_body {
    pd_v3 x;
    pd_real q[4];
    pd_real size;
    int shape;
} np_body;

/* Row-major rotation matrix (r[9]) of a unit quaternion q[4] = [w, x, y, z]. Pointers, not array
 * parameters: OpenCL C 2.0+ compilers (NVIDIA's by default) put array parameters in __private,
 * and q is often a generic pointer into a struct. */
PD_FN void np_quat_matrix(const pd_real *q, pd_real *r)
{
    pd_real w = q[0], x = q[1], y = q[2], z = q[3];
    r[0] = 1 - 2 * (y * y + z * z);
    r[1] = 2 * (x * y - w * z);
    r[2] = 2 * (x * z + w * y);
    r[3] = 2 * (x * y + w * z);
    r[4] = 1 - 2 * (x * x + z * z);
    r[5] = 2 * (y * z - w * x);
    r[6] = 2 * (x * z - w * y);
    r[7] = 2 * (y * z + w * x);
    r[8] = 1 - 2 * (x * x + y * y);
}

/*
 * Fills in (all but the scratch) for the pair (a, b): A's frame is a's body frame, B is mapped
 * by rot = size_b R(conj(q_a) q_b) and tr = R(q_a)^T (x_b - x_a). The relative quaternion's
 * terms are paired so that equal orientations give exactly the identity (aligned shapes stay
 * exactly degenerate, see overlap_predicates.h). ra receives R(q_a) for np_to_world.
 */
PD_FN void np_setup(const np_shapes *sh, const np_body *a, const np_body *b, int flags, ovl_in *in,
                    pd_real ra[9])
{
    int sa = a->shape, sb = b->shape;
    in->va = sh->vert + 3 * sh->voff[sa];
    in->ta = sh->tri + 3 * sh->toff[sa];
    in->nva = sh->voff[sa + 1] - sh->voff[sa];
    in->nta = sh->toff[sa + 1] - sh->toff[sa];
    in->vt_a_off = sh->vt_off + sh->voff[sa] + sa;
    in->vt_a = sh->vt + 3 * sh->toff[sa];
    in->vb = sh->vert + 3 * sh->voff[sb];
    in->tb = sh->tri + 3 * sh->toff[sb];
    in->nvb = sh->voff[sb + 1] - sh->voff[sb];
    in->ntb = sh->toff[sb + 1] - sh->toff[sb];
    in->vt_b_off = sh->vt_off + sh->voff[sb] + sb;
    in->vt_b = sh->vt + 3 * sh->toff[sb];
    np_clusters(sh, sa, &in->vc_a, &in->disc_a);
    np_clusters(sh, sb, &in->vc_b, &in->disc_b);
    in->sa = a->size;
    const pd_real *qa = a->q, *qb = b->q;
    pd_real qr[4];
    qr[0] = qa[0] * qb[0] + qa[1] * qb[1] + qa[2] * qb[2] + qa[3] * qb[3];
    qr[1] = (qa[0] * qb[1] - qa[1] * qb[0]) + (qa[3] * qb[2] - qa[2] * qb[3]);
    qr[2] = (qa[0] * qb[2] - qa[2] * qb[0]) + (qa[1] * qb[3] - qa[3] * qb[1]);
    qr[3] = (qa[0] * qb[3] - qa[3] * qb[0]) + (qa[2] * qb[1] - qa[1] * qb[2]);
    pd_real rr[9];
    np_quat_matrix(qr, rr);
    np_quat_matrix(qa, ra);
    for (int k = 0; k < 9; k++)
        in->rot[k] = rr[k] * b->size;
    pd_v3 dx = v3_sub(b->x, a->x);
    in->tr[0] = ra[0] * dx.x + ra[3] * dx.y + ra[6] * dx.z;
    in->tr[1] = ra[1] * dx.x + ra[4] * dx.y + ra[7] * dx.z;
    in->tr[2] = ra[2] * dx.x + ra[5] * dx.y + ra[8] * dx.z;
    in->ca = v3(0, 0, 0); /* body frames have the centroid at the origin */
    in->cb = v3(in->tr[0], in->tr[1], in->tr[2]);
    in->flags = flags;
    wb_tree_none(&in->wall);
}

/* Scratch of np_wall_local ahead of the overlap's own, for a cap of local triangles. */
PD_FN int np_wall_ilen(int cap)
{
    return 7 * cap; /* triangle ids, 3 vertex ids each, local triangles */
}
PD_FN int np_wall_rlen(int cap)
{
    return 9 * cap; /* up to 3 vertices per triangle */
}

/*
 * Narrows in (set up by np_setup for a particle a against a wall, whose size is 1) to the wall's
 * part near the particle (OVL_OPEN_B, overlap_predicates.h): the triangles of the wall's BVH whose
 * boxes meet the cube of half-side reach (the particle's circumradius, m) about its centroid, with
 * their vertices copied and renumbered into iscr/rscr (np_wall_ilen/_rlen(cap)). Triangles keep
 * the wall's order and vertices their relative order, so canonical edges and the order of the
 * cusps are those of the whole wall. Returns the number of local triangles (0: nothing of the wall
 * near), or -1 when more than cap are near (the host sizes cap so that this cannot happen).
 */
PD_FN int np_wall_local(const wb_tree *w, pd_real reach, int cap, PD_GLOBAL int *iscr,
                        PD_GLOBAL pd_real *rscr, ovl_in *in)
{
    pd_v3 qlo, qhi; /* a's circumsphere's cube in the wall's frame */
    wb_reach_box(ovl_a_centroid_in_b(in), reach, &qlo, &qhi);
    PD_GLOBAL int *lt = iscr, *lv = iscr + cap, *ltri = iscr + 4 * cap;
    int nt = wb_query_box(w, qlo, qhi, lt, cap);
    if (nt < 0 || nt > cap) return -1;
    if (nt == 0) return 0;
    ovl_sort(lt, nt);
    for (int k = 0; k < nt; k++)
        for (int q = 0; q < 3; q++)
            lv[3 * k + q] = w->tri[3 * lt[k] + q];
    ovl_sort(lv, 3 * nt);
    int nv = 0;
    for (int k = 0; k < 3 * nt; k++)
        if (nv == 0 || lv[k] != lv[nv - 1]) lv[nv++] = lv[k];
    for (int k = 0; k < nt; k++)
        for (int q = 0; q < 3; q++) {
            int g = w->tri[3 * lt[k] + q], lo = 0, hi = nv - 1;
            while (lo < hi) { /* lv is sorted and holds g */
                int mid = (lo + hi) / 2;
                if (lv[mid] < g)
                    lo = mid + 1;
                else
                    hi = mid;
            }
            ltri[3 * k + q] = lo;
        }
    for (int k = 0; k < nv; k++)
        v3_store(rscr, k, v3_load(w->vert, lv[k]));
    in->wall = *w;
    in->vb = rscr;
    in->tb = ltri;
    in->nvb = nv;
    in->ntb = nt;
    in->vt_b_off = in->vt_b = 0;
    in->vc_b = 0; /* nor clusters for the wall's local part */
    in->disc_b = 0;
    in->flags |= OVL_OPEN_B;
    return nt;
}

/*
 * A certified lower bound on the distance between particles A and B of `in` (np_setup, A's
 * frame; rad_a, rad_b their circumradii, m), or 0 when none is found: the gap between their
 * vertices' projections on a direction u, min_j u.b_j - max_i u.a_i, which bounds the distance
 * between their convex hulls and so between the solids. u comes from Gilbert's iteration on the
 * hulls' difference B - A (Gilbert 1966, the first half of GJK): z starts at the centre line
 * (centroids are inside the hulls), moves to the point nearest the origin on the segment to the
 * difference's support point in -z, and every iterate's gap is a valid bound (the best is kept).
 * Stops after `iters` or once the bound is within a quarter of |z| (the hull distance lies between
 * them). A pair whose hulls meet (a vertex in the other's pocket) gets 0. Only the result's sign
 * and size matter, never u itself, so the bound is exact up to the rounding subtracted at the end.
 * Used to skip a separated pair's overlap until the particles have moved that far (contact.cl).
 */
PD_FN pd_real np_hull_gap(const ovl_in *in, pd_real rad_a, pd_real rad_b, int iters)
{
    pd_v3 tr = v3(in->tr[0], in->tr[1], in->tr[2]), z = tr;
    const pd_real *r = in->rot;
    pd_real best = 0;
    for (int it = 0; it < iters; it++) {
        pd_real zz = v3_dot(z, z);
        if (!(zz > PD_R(0))) break;
        /* u.b_j = (rot^T u).v_j + u.tr, u.a_i = sa (u.v_i): no vertex is transformed */
        pd_v3 zb = v3(r[0] * z.x + r[3] * z.y + r[6] * z.z, r[1] * z.x + r[4] * z.y + r[7] * z.z,
                      r[2] * z.x + r[5] * z.y + r[8] * z.z);
        pd_real hi = -PD_REAL_MAX, lo = PD_REAL_MAX;
        int ia = 0, jb = 0;
        for (int i = 0; i < in->nva; i++) {
            pd_real s = v3_dot(v3_load(in->va, i), z);
            if (s > hi) {
                hi = s;
                ia = i;
            }
        }
        for (int j = 0; j < in->nvb; j++) {
            pd_real s = v3_dot(v3_load(in->vb, j), zb);
            if (s < lo) {
                lo = s;
                jb = j;
            }
        }
        pd_real zn = PD_SQRT(zz);
        pd_real gap = (lo + v3_dot(tr, z) - in->sa * hi) / zn;
        if (gap > best) best = gap;
        if (!(gap > PD_R(0)) && it > 0 && gap < -PD_R(0.5) * zn) break; /* hulls deep in */
        if (best >= PD_R(0.75) * zn) break;
        /* the support point s = b_j - a_i of B - A in -z, and z <- nearest point of [z, s] */
        pd_v3 sp =
            v3_sub(ovl_b_to_a(in, v3_load(in->vb, jb)), v3_scale(v3_load(in->va, ia), in->sa));
        pd_v3 dz = v3_sub(sp, z);
        pd_real dd = v3_dot(dz, dz);
        if (!(dd > PD_R(0))) break;
        pd_real t = -v3_dot(z, dz) / dd;
        t = t < PD_R(0) ? PD_R(0) : t > PD_R(1) ? PD_R(1) : t;
        z = v3_add(z, v3_scale(dz, t));
    }
    /* the projections' rounding: a few ulps of the magnitudes in play (the centre distance and
     * the circumradii rad_a, rad_b, m), taken generously */
    pd_real scale = v3_norm(tr) + rad_a + rad_b;
    best -= PD_R(1024) * PD_EPS * scale;
    return best > PD_R(0) ? best : PD_R(0);
}

/* World point p in a's body frame (np_setup's A frame): R(q_a)^T (p - x_a), with ra = R(q_a). */
PD_FN pd_v3 np_to_body(const np_body *a, const pd_real ra[9], pd_v3 p)
{
    pd_v3 d = v3_sub(p, a->x);
    return v3(ra[0] * d.x + ra[3] * d.y + ra[6] * d.z, ra[1] * d.x + ra[4] * d.y + ra[7] * d.z,
              ra[2] * d.x + ra[5] * d.y + ra[8] * d.z);
}

/* The overlap's centroid, normal and force point from a's body frame to world coordinates. */
PD_FN void np_to_world(const np_body *a, const pd_real ra[9], ovl_out *o)
{
    pd_v3 c = o->centroid, n = o->normal, e = o->point_eff;
    o->centroid = v3(ra[0] * c.x + ra[1] * c.y + ra[2] * c.z + a->x.x,
                     ra[3] * c.x + ra[4] * c.y + ra[5] * c.z + a->x.y,
                     ra[6] * c.x + ra[7] * c.y + ra[8] * c.z + a->x.z);
    /* without places compiled in, the force point is the centroid (ovl_places) */
    o->point_eff = !OVL_PLACES_BUILD ? o->centroid
                                     : v3(ra[0] * e.x + ra[1] * e.y + ra[2] * e.z + a->x.x,
                                          ra[3] * e.x + ra[4] * e.y + ra[5] * e.z + a->x.y,
                                          ra[6] * e.x + ra[7] * e.y + ra[8] * e.z + a->x.z);
    o->normal = v3(ra[0] * n.x + ra[1] * n.y + ra[2] * n.z, ra[3] * n.x + ra[4] * n.y + ra[5] * n.z,
                   ra[6] * n.x + ra[7] * n.y + ra[8] * n.z);
}

#endif /* PD_NARROW_PHASE_H */
