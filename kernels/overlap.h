/*
 * overlap.h - exact volumetric overlap of two closed triangle meshes (thesis
 * sections 4.2, 5.2-5.3).
 *
 * Compiles as OpenCL C and as host C (see pd_real.h). Given polyhedra A and B, it finds the nodes
 * of A n B with Algorithm 1 on the triangles that survive the half-plane filter (eqs. 5.3-5.5), and
 * accumulates the overlap's mass properties with the cusp model (eqs. 5.7-5.11) without building
 * the intersection polyhedron: every node contributes one signed simplex per (face, incident edge).
 * Shapes may be non-convex; nothing is decomposed.
 *
 * Frame (figure 5.4): everything is evaluated in A's frame, where A's vertices are given as they
 * are and B's vertices are mapped by p = rot * v + tr. Callers put A's centroid near the origin so
 * the cusp simplices, which all have a node at the origin, stay small.
 *
 * Degenerate configurations (coplanar faces, a vertex on a face, an edge on an edge, coincident
 * shapes) are resolved by simulation of simplicity: every predicate is evaluated for B displaced by
 * eps * w with w = (1, d, d^2) and eps >> d infinitesimal, so each zero determinant takes the sign
 * of its first non-zero symbolic term. Volume and centroid are continuous in the displacement, so
 * the perturbed configuration's combinatorics evaluated at eps = 0 give the exact answer. The
 * normal of eq. 4.19 is not continuous where faces of A and B are coplanar (which of the two owns
 * the shared face flips with w), so when a degenerate predicate was met the pass is repeated with
 * -w and the two normals are averaged: shared faces then cancel, as they must.
 *
 * A determinant within the configuration's rounding resolution (OVL_SNAP times the coordinate
 * scale L to the power of its length dimension) is taken as exactly zero and resolved the same
 * way: nearly coplanar or nearly coincident faces, which rounding of the pose produces, then
 * behave like exactly coplanar ones instead of taking random signs from rounding noise. The
 * bound is one absolute resolution for the whole configuration (features closer than about
 * OVL_SNAP * L count as touching), not a per-determinant one: a determinant whose own factors are
 * noise-sized would otherwise see the noise while its neighbours snap.
 *
 * Every predicate shared between neighbouring triangles (edge-edge orientation, ray-edge
 * orientation, crossing points) is computed from the edge's canonical orientation (lower vertex
 * index first), so the two triangles of an edge always agree bit for bit on what crosses where.
 */
#ifndef PD_OVERLAP_H
#define PD_OVERLAP_H

#include "pd_real.h"

#define OVL_NO_FILTER 2 /* same value as PD_OVERLAP_NO_FILTER */
/* Reals cached per near triangle of B: raw normal, box (lo, hi), raw inward edge normals. */
#define OVL_TRI_CACHE 18

/* Input of one overlap computation. Scratch sizes: see ovl_iscratch_len / ovl_rscratch_len. */
typedef struct ovl_in {
    PD_GLOBAL const pd_real *va; /* A's vertices, xyz, in A's frame */
    PD_GLOBAL const int *ta;     /* A's triangles, outward counter-clockwise */
    int nva, nta;
    PD_GLOBAL const pd_real *vb; /* B's vertices in B's own frame */
    PD_GLOBAL const int *tb;
    int nvb, ntb;
    /* optional vertex -> triangle tables (CSR: the triangles of vertex i are
     * vt[vt_off[i] .. vt_off[i+1]-1]); with them the filter visits only the triangles of the
     * vertices that reach into the other's half-plane; NULL: it classifies every triangle */
    PD_GLOBAL const int *vt_a_off, *vt_a, *vt_b_off, *vt_b;
    pd_real rot[9]; /* B's frame -> A's frame, row-major: p = rot * v + tr */
    pd_real tr[3];
    pd_v3 ca, cb;         /* centroids of A and B in A's frame (filter direction, eq. 5.3) */
    pd_real vol_a, vol_b; /* mesh volumes; set the "no overlap" threshold */
    int flags;
    PD_GLOBAL int *iscr;     /* ovl_iscratch_len ints */
    PD_GLOBAL pd_real *rscr; /* ovl_rscratch_len reals */
    int pts_cap;             /* capacity for overlap nodes kept for the depth */
} ovl_in;

typedef struct ovl_out {
    int hit;        /* overlap volume above round-off */
    int degenerate; /* a zero predicate was resolved symbolically */
    int kept_a;     /* triangles of A that survived the filters */
    int kept_b;     /* triangles of B that survived the filters */
    pd_real volume; /* V */
    pd_v3 centroid; /* centre of mass of the overlap, A's frame */
    pd_v3 normal;   /* unit, from A into B (eq. 4.19), A's frame */
    pd_real depth;  /* extent of the overlap along normal */
} ovl_out;

PD_FN int ovl_iscratch_len(int nta, int ntb, int nva, int nvb)
{
    return 2 * (nta + ntb) + nva + nvb;
}
PD_FN int ovl_rscratch_len(int nva, int nvb, int ntb, int pts_cap)
{
    return nva + nvb + 3 * nvb + 3 * pts_cap + OVL_TRI_CACHE * ntb;
}

/* Vertex state bits (per pass). */
#define OVL_V_READY 1  /* B only: transformed into A's frame */
#define OVL_V_TESTED 2 /* inside test done in this pass */
#define OVL_V_INSIDE 4 /* inside the other polyhedron */

typedef struct ovl_ctx {
    const ovl_in *in;
    pd_v3 d; /* filter direction, eq. 5.3 */
    pd_real e1, e2;
    int filter;
    int ka, kb; /* triangles kept by the half-plane filter: the ray casts' candidates */
    int na, nb; /* of those, the ones meeting the box where A n B can lie: the pair loop's */
    PD_GLOBAL int *kept_a, *kept_b, *near_a, *near_b, *st_a, *st_b;
    pd_v3 box_lo, box_hi;     /* box of A's kept part n box of B's kept part, padded */
    pd_v3 alo, ahi, blo, bhi; /* boxes of A's and B's kept parts, padded */
    PD_GLOBAL pd_real *proj_a, *proj_b, *vbt, *pts, *ucache;
    int npts, pts_overflow, store_pts;
    pd_real pad;        /* OVL_SNAP * L: the configuration's length resolution */
    pd_real tol2, tol3; /* snap bounds for determinants of length^2 and length^3 */
    int flip;           /* 0: B displaced by +eps w, 1: by -eps w */
    int degenerate;     /* a predicate was exactly zero */
    /* cusp sums */
    pd_real vol;
    pd_v3 moment; /* first moment of volume */
    pd_v3 area_a; /* sum of area * outward normal over A's faces inside B */
    pd_v3 area_b; /* the same over B's faces inside A */
    /* depth mode: project nodes on n instead of storing them */
    int depth_mode;
    pd_v3 n;
    pd_real lo, hi;
} ovl_ctx;

/* Relative size below which a determinant is rounding noise: its inputs carry a few ulps from the
 * pose transform and the determinant adds about ten more; 64 ulps leaves a margin. */
#define OVL_SNAP (PD_R(64) * PD_EPS)

PD_FN pd_real ovl_det(pd_v3 a, pd_v3 b, pd_v3 c)
{
    return v3_dot(a, v3_cross(b, c));
}

/*
 * Sign of q0 + eps * (g . w) for w = (1, d, d^2): the sign of q0 when |q0| exceeds the snap bound
 * tol (ovl_sign), else of the first non-zero component of g (ovl_tie; negated for the -w pass).
 * Zero only when g vanishes, which the callers' geometry rules out (a parallel edge or ray, already
 * rejected by a plane test). g is computed by the caller only inside the band.
 */
PD_FN int ovl_sign(pd_real q0, pd_real tol)
{
    return q0 > tol ? 1 : q0 < -tol ? -1 : 0;
}

PD_FN int ovl_tie(ovl_ctx *c, pd_v3 g)
{
    c->degenerate = 1;
    /* components of g within rounding of its largest are zero too (near-aligned geometry) */
    pd_real gt = OVL_SNAP * v3_amax(g);
    int s = g.x > gt    ? 1
            : g.x < -gt ? -1
            : g.y > gt  ? 1
            : g.y < -gt ? -1
            : g.z > gt  ? 1
            : g.z < -gt ? -1
                        : 0;
    return c->flip ? -s : s;
}

PD_FN pd_v3 ovl_va(const ovl_ctx *c, int i)
{
    return v3_load(c->in->va, i);
}
PD_FN pd_v3 ovl_vb(const ovl_ctx *c, int j)
{
    return v3_load(c->vbt, j);
}

/*
 * Orientation of A's edge a0->a1 against B's edge b0->b1, both canonical (lower index first):
 * sign of det(a1 - a0, b0 - a0, b1 - a0) with B displaced. The eps term is
 * det(a1 - a0, w, b1 - b0) = w . ((b1 - b0) x (a1 - a0)).
 */
PD_FN int ovl_edge_edge(ovl_ctx *c, int ia0, int ia1, int ib0, int ib1)
{
    pd_v3 a0 = ovl_va(c, ia0), da = v3_sub(ovl_va(c, ia1), a0);
    pd_v3 b0 = ovl_vb(c, ib0), b1 = ovl_vb(c, ib1);
    int s = ovl_sign(ovl_det(da, v3_sub(b0, a0), v3_sub(b1, a0)), c->tol3);
    return s ? s : ovl_tie(c, v3_cross(v3_sub(b1, b0), da));
}

/* Directed edge-edge orientation from canonical evaluation: A edge i->j against B edge k->l. */
PD_FN int ovl_edge_edge_dir(ovl_ctx *c, int i, int j, int k, int l)
{
    int s = i < j ? 1 : -1;
    if (k > l) s = -s;
    return s * ovl_edge_edge(c, i < j ? i : j, i < j ? j : i, k < l ? k : l, k < l ? l : k);
}

/* Side of A's point p against B's triangle plane (u0, raw normal nu): eps term is -w . nu. */
PD_FN int ovl_side_a(ovl_ctx *c, pd_v3 p, pd_v3 u0, pd_v3 nu, pd_real *q0)
{
    *q0 = v3_dot(v3_sub(p, u0), nu);
    int s = ovl_sign(*q0, c->tol3);
    return s ? s : ovl_tie(c, v3_scale(nu, PD_R(-1)));
}

/* Side of B's point u against A's triangle plane (t0, raw normal nt): eps term is +w . nt. */
PD_FN int ovl_side_b(ovl_ctx *c, pd_v3 u, pd_v3 t0, pd_v3 nt, pd_real *q0)
{
    *q0 = v3_dot(v3_sub(u, t0), nt);
    int s = ovl_sign(*q0, c->tol3);
    return s ? s : ovl_tie(c, nt);
}

/* Adds the cusp (p, t, n, b = -nu) of a face with outward unit normal nu (eqs. 5.8-5.11). */
PD_FN void ovl_cusp(ovl_ctx *c, pd_v3 p, pd_v3 t, pd_v3 n, pd_v3 nu, int on_b)
{
    pd_real tp = v3_dot(t, p), np = v3_dot(n, p), hp = v3_dot(nu, p);
    pd_real area = PD_R(0.5) * tp * np;  /* eq. 5.9 */
    pd_real vol = area * hp / PD_R(3.0); /* eq. 5.10: -(1/6)(t.p)(n.p)(b.p) */
    c->vol += vol;
    /*
     * eq. 5.11: the simplex of eq. 5.8 has nodes p, p - (t.p)t, p - (t.p)t - (n.p)n and the
     * origin, so its centroid is (3p - 2(t.p)t - (n.p)n)/4 (the printed eq. 5.11 flips both signs).
     */
    pd_v3 cen = v3_sub(v3_sub(v3_scale(p, PD_R(3)), v3_scale(t, PD_R(2) * tp)), v3_scale(n, np));
    c->moment = v3_add(c->moment, v3_scale(cen, vol * PD_R(0.25)));
    if (on_b)
        c->area_b = v3_add(c->area_b, v3_scale(nu, area));
    else
        c->area_a = v3_add(c->area_a, v3_scale(nu, area));
}

/* Records a node of the overlap for the depth (or projects it in depth mode). */
PD_FN void ovl_node(ovl_ctx *c, pd_v3 p)
{
    if (c->depth_mode) {
        pd_real s = v3_dot(p, c->n);
        if (s < c->lo) c->lo = s;
        if (s > c->hi) c->hi = s;
    } else if (c->store_pts) {
        if (c->npts < c->in->pts_cap)
            v3_store(c->pts, c->npts++, p);
        else
            c->pts_overflow = 1;
    }
}

/*
 * The three cusps at a node where edge (of face F, unit direction te pointing into the other solid,
 * in-face inward normal m) pierces face G of the other solid: one along the edge, and one on each
 * face along their line of intersection, heading into F (eq. 5.7's t, n, b at that node).
 */
PD_FN void ovl_crossing_cusps(ovl_ctx *c, pd_v3 p, pd_v3 te, pd_v3 m, pd_v3 nf, pd_v3 ng,
                              int f_on_b)
{
    pd_v3 cr = v3_cross(nf, ng);
    pd_real len = v3_norm(cr);
    pd_real cs = v3_dot(nf, ng);
    if (len <= OVL_SNAP) {
        /* faces parallel to within rounding have no line of intersection; predicates that
         * disagree by rounding can still report a crossing, which carries no area */
        ovl_cusp(c, p, te, m, nf, f_on_b);
        ovl_node(c, p);
        return;
    }
    pd_v3 l = v3_scale(cr, PD_R(1) / len);
    if (v3_dot(l, m) < PD_R(0)) l = v3_scale(l, PD_R(-1));
    /* In F's plane the other solid lies towards -ng; in G's plane this solid lies towards -nf. */
    pd_v3 n_f = v3_scale(v3_sub(v3_scale(nf, cs), ng), PD_R(1) / len);
    pd_v3 n_g = v3_scale(v3_sub(v3_scale(ng, cs), nf), PD_R(1) / len);
    ovl_cusp(c, p, te, m, nf, f_on_b);
    ovl_cusp(c, p, l, n_f, nf, f_on_b);
    ovl_cusp(c, p, l, n_g, ng, !f_on_b);
    ovl_node(c, p);
}

/*
 * Box of the ray p + t r (t >= 0) up to where it leaves the box [lo, hi]: the kept triangles it
 * can cross all lie inside [lo, hi], so a triangle whose box misses this one is not crossed.
 */
PD_FN void ovl_ray_box(pd_v3 p, pd_v3 r, pd_v3 lo, pd_v3 hi, pd_real pad, pd_v3 *rlo, pd_v3 *rhi)
{
    pd_real t = PD_REAL_MAX;
    if (r.x != PD_R(0)) t = pd_min(t, ((r.x > 0 ? hi.x : lo.x) - p.x) / r.x);
    if (r.y != PD_R(0)) t = pd_min(t, ((r.y > 0 ? hi.y : lo.y) - p.y) / r.y);
    if (r.z != PD_R(0)) t = pd_min(t, ((r.z > 0 ? hi.z : lo.z) - p.z) / r.z);
    t = pd_max(t, PD_R(0));
    pd_v3 q = v3_add(p, v3_scale(r, t));
    *rlo = v3(pd_min(p.x, q.x) - pad, pd_min(p.y, q.y) - pad, pd_min(p.z, q.z) - pad);
    *rhi = v3(pd_max(p.x, q.x) + pad, pd_max(p.y, q.y) + pad, pd_max(p.z, q.z) + pad);
}

/* Whether triangle (u0, u1, u2) can meet the box [lo, hi]. */
PD_FN int ovl_tri_meets(pd_v3 u0, pd_v3 u1, pd_v3 u2, pd_v3 lo, pd_v3 hi)
{
    return !(pd_max(pd_max(u0.x, u1.x), u2.x) < lo.x || pd_min(pd_min(u0.x, u1.x), u2.x) > hi.x ||
             pd_max(pd_max(u0.y, u1.y), u2.y) < lo.y || pd_min(pd_min(u0.y, u1.y), u2.y) > hi.y ||
             pd_max(pd_max(u0.z, u1.z), u2.z) < lo.z || pd_min(pd_min(u0.z, u1.z), u2.z) > hi.z);
}

PD_FN int ovl_in_box(const ovl_ctx *c, pd_v3 p)
{
    return p.x >= c->box_lo.x && p.x <= c->box_hi.x && p.y >= c->box_lo.y && p.y <= c->box_hi.y &&
           p.z >= c->box_lo.z && p.z <= c->box_hi.z;
}

/* Point-in-B test for A's vertex i: parity of a ray cast along -d against B's kept triangles. */
PD_FN int ovl_inside_b(ovl_ctx *c, int i)
{
    PD_GLOBAL const int *tb = c->in->tb;
    pd_v3 p = ovl_va(c, i);
    if (c->filter && c->proj_a[i] < c->e2) return 0; /* below B's half-plane: outside */
    if (c->filter && !ovl_in_box(c, p)) return 0;    /* outside B's kept part's box */
    pd_v3 r = v3_scale(c->d, PD_R(-1));
    pd_v3 rlo, rhi;
    ovl_ray_box(p, r, c->blo, c->bhi, c->pad, &rlo, &rhi);
    int odd = 0;
    for (int k = 0; k < c->kb; k++) {
        int u = c->kept_b[k];
        int i0 = tb[3 * u], i1 = tb[3 * u + 1], i2 = tb[3 * u + 2];
        pd_v3 u0 = ovl_vb(c, i0), u1 = ovl_vb(c, i1), u2 = ovl_vb(c, i2);
        if (c->filter && !ovl_tri_meets(u0, u1, u2, rlo, rhi)) continue;
        pd_v3 nu = v3_cross(v3_sub(u1, u0), v3_sub(u2, u0));
        pd_real rn = v3_dot(r, nu);
        /* a ray parallel to the plane, to within rounding, never crosses it (exactly parallel
         * it would cross only if it lay in the plane, which the perturbation rules out) */
        if (PD_FABS(rn) <= c->tol2) continue;
        pd_real q0;
        int s = ovl_side_a(c, p, u0, nu, &q0);
        if ((s > 0) != (rn < PD_R(0))) continue; /* plane behind the ray's start */
        int idx[3] = {i0, i1, i2};
        int sg[3] = {0, 0, 0};
        for (int e = 0; e < 3; e++) {
            if (e > 0 && sg[e - 1] != sg[0]) break; /* turns differ: the ray misses */
            int k0 = idx[e], k1 = idx[(e + 1) % 3];
            int lo = k0 < k1 ? k0 : k1, hi = k0 < k1 ? k1 : k0;
            pd_v3 b0 = ovl_vb(c, lo), b1 = ovl_vb(c, hi);
            /* det(r, b0 - q, b1 - q) for q = p - eps w: eps term w . ((b1 - b0) x r) */
            int sv = ovl_sign(ovl_det(r, v3_sub(b0, p), v3_sub(b1, p)), c->tol2);
            if (!sv) sv = ovl_tie(c, v3_cross(v3_sub(b1, b0), r));
            sg[e] = k0 < k1 ? sv : -sv;
        }
        if (sg[0] != 0 && sg[0] == sg[1] && sg[1] == sg[2]) odd ^= 1;
    }
    return odd;
}

/* Point-in-A test for B's vertex j: ray along +d against A's kept triangles. */
PD_FN int ovl_inside_a(ovl_ctx *c, int j)
{
    PD_GLOBAL const int *ta = c->in->ta;
    pd_v3 u = ovl_vb(c, j);
    if (c->filter && c->proj_b[j] > c->e1) return 0; /* above A's half-plane: outside */
    if (c->filter && !ovl_in_box(c, u)) return 0;

    pd_v3 r = c->d;
    pd_v3 rlo, rhi;
    ovl_ray_box(u, r, c->alo, c->ahi, c->pad, &rlo, &rhi);
    int odd = 0;
    for (int k = 0; k < c->ka; k++) {
        int t = c->kept_a[k];
        int i0 = ta[3 * t], i1 = ta[3 * t + 1], i2 = ta[3 * t + 2];
        pd_v3 t0 = ovl_va(c, i0), t1 = ovl_va(c, i1), t2 = ovl_va(c, i2);
        if (c->filter && !ovl_tri_meets(t0, t1, t2, rlo, rhi)) continue;
        pd_v3 nt = v3_cross(v3_sub(t1, t0), v3_sub(t2, t0));
        pd_real rn = v3_dot(r, nt);
        if (PD_FABS(rn) <= c->tol2) continue; /* parallel */
        pd_real q0;
        int s = ovl_side_b(c, u, t0, nt, &q0);
        if ((s > 0) != (rn < PD_R(0))) continue;
        int idx[3] = {i0, i1, i2};
        int sg[3] = {0, 0, 0};
        for (int e = 0; e < 3; e++) {
            if (e > 0 && sg[e - 1] != sg[0]) break;
            int k0 = idx[e], k1 = idx[(e + 1) % 3];
            int lo = k0 < k1 ? k0 : k1, hi = k0 < k1 ? k1 : k0;
            pd_v3 a0 = ovl_va(c, lo), a1 = ovl_va(c, hi);
            /* det(r, a0 - q, a1 - q) for q = u + eps w: eps term -w . ((a1 - a0) x r) */
            int sv = ovl_sign(ovl_det(r, v3_sub(a0, u), v3_sub(a1, u)), c->tol2);
            if (!sv) sv = ovl_tie(c, v3_scale(v3_cross(v3_sub(a1, a0), r), PD_R(-1)));
            sg[e] = k0 < k1 ? sv : -sv;
        }
        if (sg[0] != 0 && sg[0] == sg[1] && sg[1] == sg[2]) odd ^= 1;
    }
    return odd;
}

PD_FN int ovl_vertex_in_b(ovl_ctx *c, int i)
{
    int st = c->st_a[i];
    if (!(st & OVL_V_TESTED)) {
        st |= OVL_V_TESTED;
        if (ovl_inside_b(c, i)) {
            st |= OVL_V_INSIDE;
            ovl_node(c, ovl_va(c, i));
        }
        c->st_a[i] = st;
    }
    return (st & OVL_V_INSIDE) != 0;
}

PD_FN int ovl_vertex_in_a(ovl_ctx *c, int j)
{
    int st = c->st_b[j];
    if (!(st & OVL_V_TESTED)) {
        st |= OVL_V_TESTED;
        if (ovl_inside_a(c, j)) {
            st |= OVL_V_INSIDE;
            ovl_node(c, ovl_vb(c, j));
        }
        c->st_b[j] = st;
    }
    return (st & OVL_V_INSIDE) != 0;
}

/*
 * Geometry of one triangle. The corners, raw normal and box are all the pair loop needs to reject
 * a pair; the unit vectors are computed only when a cusp needs them (ovl_tri_full), which keeps
 * the O(kept_a * kept_b) loop cheap.
 */
typedef struct ovl_tri {
    int id[3];
    pd_v3 p[3];
    pd_v3 nraw; /* (p1 - p0) x (p2 - p0) */
    pd_v3 lo, hi;
    int full;
    pd_v3 nu;    /* unit outward normal */
    pd_v3 e[3];  /* unit direction of edge k: p[k] -> p[k+1] */
    pd_v3 m[3];  /* unit in-plane normal of edge k pointing into the triangle */
    int edges;   /* me[] computed */
    pd_v3 me[3]; /* nraw x (p[k+1] - p[k]): raw inward normal of edge k's plane */
} ovl_tri;

PD_FN void ovl_tri_make(ovl_tri *t, pd_v3 p0, pd_v3 p1, pd_v3 p2, pd_real pad)
{
    t->p[0] = p0;
    t->p[1] = p1;
    t->p[2] = p2;
    t->nraw = v3_cross(v3_sub(p1, p0), v3_sub(p2, p0));
    t->full = 0;
    t->edges = 0;
    t->nu = t->nraw; /* set by ovl_tri_full; initialised for the compilers' flow analysis */
    /* Culling is a predicate too: pad by the resolution so boxes that touch to within rounding
     * reach the symbolic tests instead of being rejected by noise. */
    t->lo = v3(pd_min(pd_min(p0.x, p1.x), p2.x) - pad, pd_min(pd_min(p0.y, p1.y), p2.y) - pad,
               pd_min(pd_min(p0.z, p1.z), p2.z) - pad);
    t->hi = v3(pd_max(pd_max(p0.x, p1.x), p2.x) + pad, pd_max(pd_max(p0.y, p1.y), p2.y) + pad,
               pd_max(pd_max(p0.z, p1.z), p2.z) + pad);
}

PD_FN void ovl_tri_edges(ovl_tri *t)
{
    if (t->edges) return;
    t->edges = 1;
    for (int k = 0; k < 3; k++)
        t->me[k] = v3_cross(t->nraw, v3_sub(t->p[(k + 1) % 3], t->p[k]));
}

/*
 * Where p, a crossing point on t's plane known to within err (max-norm), lies against t: 1 inside,
 * -1 outside, 0 too close to an edge to tell, in which case the caller decides with the exact
 * canonical predicates (so the two triangles of an edge still agree bit for bit).
 */
PD_FN int ovl_point_in_tri(ovl_tri *t, pd_v3 p, pd_real err)
{
    ovl_tri_edges(t);
    int inside = 1;
    for (int k = 0; k < 3; k++) {
        pd_real v = v3_dot(t->me[k], v3_sub(p, t->p[k]));
        pd_real margin = PD_R(4) * v3_amax(t->me[k]) * err;
        if (v < -margin) return -1;
        if (!(v > margin)) inside = 0;
    }
    return inside;
}

PD_FN void ovl_tri_full(ovl_tri *t)
{
    if (t->full) return;
    t->full = 1;
    t->nu = v3_unit(t->nraw);
    for (int k = 0; k < 3; k++) {
        t->e[k] = v3_unit(v3_sub(t->p[(k + 1) % 3], t->p[k]));
        t->m[k] = v3_cross(t->nu, t->e[k]);
    }
}

/* Fills a near triangle of B from its cache entry (corners from the transformed vertices). */
PD_FN void ovl_tri_cached(ovl_tri *t, const ovl_ctx *c, PD_GLOBAL const pd_real *uc)
{
    for (int q = 0; q < 3; q++)
        t->p[q] = ovl_vb(c, t->id[q]);
    t->nraw = v3(uc[0], uc[1], uc[2]);
    t->lo = v3(uc[3], uc[4], uc[5]);
    t->hi = v3(uc[6], uc[7], uc[8]);
    t->me[0] = v3(uc[9], uc[10], uc[11]);
    t->me[1] = v3(uc[12], uc[13], uc[14]);
    t->me[2] = v3(uc[15], uc[16], uc[17]);
    t->edges = 1;
    t->full = 0;
    t->nu = t->nraw;
}

PD_FN int ovl_box_meets(const ovl_ctx *c, const ovl_tri *t)
{
    return !(t->hi.x < c->box_lo.x || t->lo.x > c->box_hi.x || t->hi.y < c->box_lo.y ||
             t->lo.y > c->box_hi.y || t->hi.z < c->box_lo.z || t->lo.z > c->box_hi.z);
}

/* Crossing point of canonical edge lo->hi with a plane, from the edge ends' signed distances. */
PD_FN pd_v3 ovl_cross_point(pd_v3 plo, pd_v3 phi, pd_real slo, pd_real shi)
{
    pd_real den = slo - shi;
    pd_real lam = den != PD_R(0) ? slo / den : PD_R(0);
    /* the crossing lies on the edge; when both ends are within rounding of the plane the
     * quotient is noise, and must not throw the node off the edge */
    lam = lam < PD_R(0) ? PD_R(0) : lam > PD_R(1) ? PD_R(1) : lam;
    return v3_add(plo, v3_scale(v3_sub(phi, plo), lam));
}

/*
 * Error bound (max-norm) of ovl_cross_point's node: the side values carry up to tol3 each, which
 * moves the node along the edge by |a1 - a0| tol3 / |s0 - s1|; plus the coordinates' own rounding.
 */
PD_FN pd_real ovl_cross_err(const ovl_ctx *c, pd_v3 a0, pd_v3 a1, pd_real s0, pd_real s1)
{
    pd_real ds = PD_FABS(s0 - s1);
    pd_real len = v3_amax(v3_sub(a1, a0));
    return ds > PD_R(0) ? c->pad + PD_R(2) * len * c->tol3 / ds : PD_REAL_MAX;
}

/* All cusps between A's triangle T and B's triangle U from edges of one crossing the other. */
PD_FN void ovl_pair(ovl_ctx *c, ovl_tri *T, ovl_tri *U)
{
    if (T->hi.x < U->lo.x || U->hi.x < T->lo.x || T->hi.y < U->lo.y || U->hi.y < T->lo.y ||
        T->hi.z < U->lo.z || U->hi.z < T->lo.z)
        return;
    pd_real qa[3], qb[3];
    int sa[3], sb[3];
    /* a triangle wholly on one side of the other's plane: no edge of either crosses the other */
    for (int k = 0; k < 3; k++)
        sa[k] = ovl_side_a(c, T->p[k], U->p[0], U->nraw, &qa[k]);
    if (sa[0] == sa[1] && sa[1] == sa[2]) return;
    for (int k = 0; k < 3; k++)
        sb[k] = ovl_side_b(c, U->p[k], T->p[0], T->nraw, &qb[k]);
    if (sb[0] == sb[1] && sb[1] == sb[2]) return;

    /* edges of T through U */
    for (int k = 0; k < 3; k++) {
        int k1 = (k + 1) % 3;
        if (sa[k] == sa[k1]) continue;
        int i = T->id[k], j = T->id[k1];
        pd_v3 p = i < j ? ovl_cross_point(T->p[k], T->p[k1], qa[k], qa[k1])
                        : ovl_cross_point(T->p[k1], T->p[k], qa[k1], qa[k]);
        int in = ovl_point_in_tri(U, p, ovl_cross_err(c, T->p[k], T->p[k1], qa[k], qa[k1]));
        /* near U's edges: the edge's line passes inside U when it turns the same way about all
         * three of U's edges (exact canonical predicates) */
        if (in == 0) {
            int s0 = ovl_edge_edge_dir(c, i, j, U->id[0], U->id[1]);
            in = s0 != 0 && s0 == ovl_edge_edge_dir(c, i, j, U->id[1], U->id[2]) &&
                 s0 == ovl_edge_edge_dir(c, i, j, U->id[2], U->id[0]);
        }
        if (in != 1) continue;
        ovl_tri_full(T);
        ovl_tri_full(U);
        pd_v3 te = sa[k1] < 0 ? T->e[k] : v3_scale(T->e[k], PD_R(-1));
        ovl_crossing_cusps(c, p, te, T->m[k], T->nu, U->nu, 0);
    }
    /* edges of U through T */
    for (int k = 0; k < 3; k++) {
        int k1 = (k + 1) % 3;
        if (sb[k] == sb[k1]) continue;
        int i = U->id[k], j = U->id[k1];
        pd_v3 p = i < j ? ovl_cross_point(U->p[k], U->p[k1], qb[k], qb[k1])
                        : ovl_cross_point(U->p[k1], U->p[k], qb[k1], qb[k]);
        int in = ovl_point_in_tri(T, p, ovl_cross_err(c, U->p[k], U->p[k1], qb[k], qb[k1]));
        if (in == 0) {
            /* det(u_j - u_i, t_a - u_i, t_b - u_i) equals the orientation of T's edge a->b
             * against U's edge i->j, so the shared canonical predicate decides both tests */
            int s0 = ovl_edge_edge_dir(c, T->id[0], T->id[1], i, j);
            in = s0 != 0 && s0 == ovl_edge_edge_dir(c, T->id[1], T->id[2], i, j) &&
                 s0 == ovl_edge_edge_dir(c, T->id[2], T->id[0], i, j);
        }
        if (in != 1) continue;
        ovl_tri_full(T);
        ovl_tri_full(U);
        pd_v3 te = sb[k1] < 0 ? U->e[k] : v3_scale(U->e[k], PD_R(-1));
        ovl_crossing_cusps(c, p, te, U->m[k], U->nu, T->nu, 1);
    }
}

/* One pass of Algorithm 1 over the kept triangles, accumulating cusps. */
PD_FN void ovl_pass(ovl_ctx *c)
{
    PD_GLOBAL const int *ta = c->in->ta;
    PD_GLOBAL const int *tb = c->in->tb;
    c->vol = PD_R(0);
    c->moment = c->area_a = c->area_b = v3(0, 0, 0);
    /* only the kept triangles' corners are ever tested */
    for (int k = 0; k < c->ka; k++)
        for (int q = 0; q < 3; q++)
            c->st_a[ta[3 * c->kept_a[k] + q]] &= OVL_V_READY;
    for (int l = 0; l < c->kb; l++)
        for (int q = 0; q < 3; q++)
            c->st_b[tb[3 * c->kept_b[l] + q]] &= OVL_V_READY;

    for (int k = 0; k < c->na; k++) {
        int t = c->near_a[k];
        ovl_tri T;
        T.id[0] = ta[3 * t];
        T.id[1] = ta[3 * t + 1];
        T.id[2] = ta[3 * t + 2];
        ovl_tri_make(&T, ovl_va(c, T.id[0]), ovl_va(c, T.id[1]), ovl_va(c, T.id[2]), c->pad);
        /* nodes of A inside B: two cusps per corner, along the triangle's two edges */
        for (int q = 0; q < 3; q++) {
            if (!ovl_vertex_in_b(c, T.id[q])) continue;
            int qp = (q + 2) % 3;
            ovl_tri_full(&T);
            ovl_cusp(c, T.p[q], T.e[q], T.m[q], T.nu, 0);
            ovl_cusp(c, T.p[q], v3_scale(T.e[qp], PD_R(-1)), T.m[qp], T.nu, 0);
        }
        for (int l = 0; l < c->nb; l++) {
            PD_GLOBAL const pd_real *uc = c->ucache + OVL_TRI_CACHE * l;
            /* box first, from the cache: most pairs end here */
            if (T.hi.x < uc[3] || uc[6] < T.lo.x || T.hi.y < uc[4] || uc[7] < T.lo.y ||
                T.hi.z < uc[5] || uc[8] < T.lo.z)
                continue;
            int u = c->near_b[l];
            ovl_tri U;
            U.id[0] = tb[3 * u];
            U.id[1] = tb[3 * u + 1];
            U.id[2] = tb[3 * u + 2];
            ovl_tri_cached(&U, c, uc);
            ovl_pair(c, &T, &U);
        }
    }
    for (int l = 0; l < c->nb; l++) {
        int u = c->near_b[l];
        int id[3] = {tb[3 * u], tb[3 * u + 1], tb[3 * u + 2]};
        int any = 0;
        for (int q = 0; q < 3; q++)
            any |= ovl_vertex_in_a(c, id[q]);
        if (!any) continue;
        ovl_tri U;
        ovl_tri_make(&U, ovl_vb(c, id[0]), ovl_vb(c, id[1]), ovl_vb(c, id[2]), c->pad);
        ovl_tri_full(&U);
        for (int q = 0; q < 3; q++) {
            if (!(c->st_b[id[q]] & OVL_V_INSIDE)) continue;
            int qp = (q + 2) % 3;
            ovl_cusp(c, U.p[q], U.e[q], U.m[q], U.nu, 1);
            ovl_cusp(c, U.p[q], v3_scale(U.e[qp], PD_R(-1)), U.m[qp], U.nu, 1);
        }
    }
}

/*
 * Sorts an index list ascending in place: insertion sort for the short, nearly sorted lists of a
 * DEM contact, Shell sort beyond (no recursion, no extra memory).
 */
PD_FN void ovl_sort(PD_GLOBAL int *a, int n)
{
    for (int gap = n > 64 ? n / 2 : 1; gap > 0; gap = gap == 2 ? 1 : gap * 5 / 11) {
        for (int i = gap; i < n; i++) {
            int x = a[i], j = i;
            for (; j >= gap && a[j - gap] > x; j -= gap)
                a[j] = a[j - gap];
            a[j] = x;
        }
    }
}

PD_FN void ovl_miss(ovl_out *o, const ovl_ctx *c)
{
    o->hit = 0;
    o->degenerate = c->degenerate;
    o->kept_a = c->na;
    o->kept_b = c->nb;
    o->volume = PD_R(0);
    o->centroid = o->normal = v3(0, 0, 0);
    o->depth = PD_R(0);
}

/* The overlap of A and B: volume, centroid, normal and depth (section 4.2). */
PD_FN void ovl_compute(const ovl_in *in, ovl_out *o)
{
    ovl_ctx cx;
    ovl_ctx *c = &cx;
    c->in = in;
    c->filter = !(in->flags & OVL_NO_FILTER);
    c->kept_a = in->iscr;
    c->kept_b = in->iscr + in->nta;
    c->near_a = c->kept_b + in->ntb;
    c->near_b = c->near_a + in->nta;
    c->st_a = c->near_b + in->ntb;
    c->st_b = c->st_a + in->nva;
    c->proj_a = in->rscr;
    c->proj_b = in->rscr + in->nva;
    c->vbt = c->proj_b + in->nvb;
    c->pts = c->vbt + 3 * in->nvb;
    c->ucache = c->pts + 3 * in->pts_cap;
    c->npts = c->pts_overflow = 0;
    c->store_pts = 1;
    c->flip = c->degenerate = c->depth_mode = 0;
    c->pad = c->tol2 = c->tol3 = PD_R(0);
    c->ka = c->kb = c->na = c->nb = 0;

    /* eq. 5.3: the direction between the centres */
    pd_v3 dc = v3_sub(in->cb, in->ca);
    c->d = v3_dot(dc, dc) > PD_R(0) ? v3_unit(dc) : v3(0, 0, 1);
    pd_v3 d = c->d;
    /* d expressed in B's frame, so B's vertices are projected before being transformed */
    pd_v3 db = v3(in->rot[0] * d.x + in->rot[3] * d.y + in->rot[6] * d.z,
                  in->rot[1] * d.x + in->rot[4] * d.y + in->rot[7] * d.z,
                  in->rot[2] * d.x + in->rot[5] * d.y + in->rot[8] * d.z);
    pd_real trd = in->tr[0] * d.x + in->tr[1] * d.y + in->tr[2] * d.z;

    /* eq. 5.4: extents; eq. 5.5: keep the triangles reaching into the other's half-plane */
    c->e1 = -PD_REAL_MAX;
    c->e2 = PD_REAL_MAX;
    pd_real scale = PD_R(0);
    for (int i = 0; i < in->nva; i++) {
        c->proj_a[i] = v3_dot(v3_load(in->va, i), d);
        if (c->proj_a[i] > c->e1) c->e1 = c->proj_a[i];
        if (PD_FABS(c->proj_a[i]) > scale) scale = PD_FABS(c->proj_a[i]);
        c->st_a[i] = 0;
    }
    for (int j = 0; j < in->nvb; j++) {
        c->proj_b[j] = v3_dot(v3_load(in->vb, j), db) + trd;
        if (c->proj_b[j] < c->e2) c->e2 = c->proj_b[j];
        if (PD_FABS(c->proj_b[j]) > scale) scale = PD_FABS(c->proj_b[j]);
        c->st_b[j] = 0;
    }
    /* The half-planes are widened by the resolution: B's projections are computed in B's frame,
     * and a contact that touches to within rounding must reach the symbolic tests. */
    pd_real pad = OVL_SNAP * scale;
    c->e1 += pad;
    c->e2 -= pad;
    c->pad = pad;
    if (c->filter && !(c->e1 > c->e2)) { /* half-planes disjoint: no volume */
        ovl_miss(o, c);
        return;
    }
    if (c->filter && in->vt_a_off && in->vt_b_off) {
        /* A triangle is kept from its first corner that reaches into the other's half-plane, so
         * each is listed once; the lists are sorted so that the cusps are summed in the same
         * order as without the filter (identical results). */
        for (int i = 0; i < in->nva; i++) {
            if (!(c->proj_a[i] >= c->e2)) continue;
            for (int k = in->vt_a_off[i]; k < in->vt_a_off[i + 1]; k++) {
                int t = in->vt_a[k];
                PD_GLOBAL const int *v = in->ta + 3 * t;
                int first = v[0] == i ? 1
                            : v[1] == i
                                ? !(c->proj_a[v[0]] >= c->e2)
                                : !(c->proj_a[v[0]] >= c->e2) && !(c->proj_a[v[1]] >= c->e2);
                if (first) c->kept_a[c->ka++] = t;
            }
        }
        for (int j = 0; j < in->nvb; j++) {
            if (!(c->proj_b[j] <= c->e1)) continue;
            for (int k = in->vt_b_off[j]; k < in->vt_b_off[j + 1]; k++) {
                int u = in->vt_b[k];
                PD_GLOBAL const int *v = in->tb + 3 * u;
                int first = v[0] == j ? 1
                            : v[1] == j
                                ? !(c->proj_b[v[0]] <= c->e1)
                                : !(c->proj_b[v[0]] <= c->e1) && !(c->proj_b[v[1]] <= c->e1);
                if (first) c->kept_b[c->kb++] = u;
            }
        }
        ovl_sort(c->kept_a, c->ka);
        ovl_sort(c->kept_b, c->kb);
    } else {
        for (int t = 0; t < in->nta; t++) {
            PD_GLOBAL const int *v = in->ta + 3 * t;
            pd_real mx = pd_max(pd_max(c->proj_a[v[0]], c->proj_a[v[1]]), c->proj_a[v[2]]);
            if (!c->filter || mx >= c->e2) c->kept_a[c->ka++] = t;
        }
        for (int u = 0; u < in->ntb; u++) {
            PD_GLOBAL const int *v = in->tb + 3 * u;
            pd_real mn = pd_min(pd_min(c->proj_b[v[0]], c->proj_b[v[1]]), c->proj_b[v[2]]);
            if (!c->filter || mn <= c->e1) c->kept_b[c->kb++] = u;
        }
    }
    if (c->ka == 0 || c->kb == 0) {
        ovl_miss(o, c);
        return;
    }
    pd_v3 alo = v3(PD_REAL_MAX, PD_REAL_MAX, PD_REAL_MAX), ahi = v3_scale(alo, PD_R(-1));
    pd_v3 blo = alo, bhi = ahi;
    for (int k = 0; k < c->ka; k++) {
        PD_GLOBAL const int *v = in->ta + 3 * c->kept_a[k];
        for (int q = 0; q < 3; q++) {
            pd_v3 x = v3_load(in->va, v[q]);
            alo = v3(pd_min(alo.x, x.x), pd_min(alo.y, x.y), pd_min(alo.z, x.z));
            ahi = v3(pd_max(ahi.x, x.x), pd_max(ahi.y, x.y), pd_max(ahi.z, x.z));
        }
    }
    /* map the vertices of B's kept triangles into A's frame */
    for (int l = 0; l < c->kb; l++) {
        PD_GLOBAL const int *v = in->tb + 3 * c->kept_b[l];
        for (int q = 0; q < 3; q++) {
            int j = v[q];
            if (c->st_b[j] & OVL_V_READY) continue;
            pd_v3 x = v3_load(in->vb, j);
            pd_v3 y = v3(in->rot[0] * x.x + in->rot[1] * x.y + in->rot[2] * x.z + in->tr[0],
                         in->rot[3] * x.x + in->rot[4] * x.y + in->rot[5] * x.z + in->tr[1],
                         in->rot[6] * x.x + in->rot[7] * x.y + in->rot[8] * x.z + in->tr[2]);
            v3_store(c->vbt, j, y);
            c->st_b[j] = OVL_V_READY;
            blo = v3(pd_min(blo.x, y.x), pd_min(blo.y, y.y), pd_min(blo.z, y.z));
            bhi = v3(pd_max(bhi.x, y.x), pd_max(bhi.y, y.y), pd_max(bhi.z, y.z));
        }
    }
    /* L: the largest coordinate magnitude in play */
    pd_real lsc = pd_max(pd_max(v3_amax(alo), v3_amax(ahi)), pd_max(v3_amax(blo), v3_amax(bhi)));
    /* the resolution: coordinates carry about OVL_SNAP * L of rounding from the transforms */
    c->pad = OVL_SNAP * lsc;
    c->tol2 = c->pad * lsc;
    c->tol3 = c->tol2 * lsc;

    /*
     * Every node of A n B lies in both solids' parts inside the slab, and a solid's part inside
     * the slab lies in the box of its kept triangles (a ray from an inside point leaves the solid
     * through a kept triangle). So only triangles meeting the intersection of the two boxes can
     * emit cusps, and a vertex outside it is outside the other solid.
     */
    pd_v3 padv = v3(c->pad, c->pad, c->pad);
    c->alo = v3_sub(alo, padv);
    c->ahi = v3_add(ahi, padv);
    c->blo = v3_sub(blo, padv);
    c->bhi = v3_add(bhi, padv);
    c->box_lo = v3(pd_max(alo.x, blo.x) - c->pad, pd_max(alo.y, blo.y) - c->pad,
                   pd_max(alo.z, blo.z) - c->pad);
    c->box_hi = v3(pd_min(ahi.x, bhi.x) + c->pad, pd_min(ahi.y, bhi.y) + c->pad,
                   pd_min(ahi.z, bhi.z) + c->pad);
    if (c->filter &&
        (c->box_lo.x > c->box_hi.x || c->box_lo.y > c->box_hi.y || c->box_lo.z > c->box_hi.z)) {
        ovl_miss(o, c);
        return;
    }
    for (int k = 0; k < c->ka; k++) {
        int t = c->kept_a[k];
        ovl_tri T;
        ovl_tri_make(&T, v3_load(in->va, in->ta[3 * t]), v3_load(in->va, in->ta[3 * t + 1]),
                     v3_load(in->va, in->ta[3 * t + 2]), PD_R(0));
        if (!c->filter || ovl_box_meets(c, &T)) c->near_a[c->na++] = t;
    }
    for (int l = 0; l < c->kb; l++) {
        int u = c->kept_b[l];
        ovl_tri U;
        ovl_tri_make(&U, ovl_vb(c, in->tb[3 * u]), ovl_vb(c, in->tb[3 * u + 1]),
                     ovl_vb(c, in->tb[3 * u + 2]), PD_R(0));
        if (c->filter && !ovl_box_meets(c, &U)) continue;
        /* cache what the pair loop needs of U, with the box padded by the resolution */
        ovl_tri_edges(&U);
        PD_GLOBAL pd_real *uc = c->ucache + OVL_TRI_CACHE * c->nb;
        pd_v3 v[6] = {U.nraw,
                      v3_sub(U.lo, v3(c->pad, c->pad, c->pad)),
                      v3_add(U.hi, v3(c->pad, c->pad, c->pad)),
                      U.me[0],
                      U.me[1],
                      U.me[2]};
        for (int q = 0; q < 6; q++)
            v3_store(uc, q, v[q]);
        c->near_b[c->nb++] = u;
    }

    ovl_pass(c);
    pd_real vol = c->vol;
    pd_v3 mom = c->moment;
    pd_v3 sdiff = v3_sub(c->area_a, c->area_b);
    pd_real smag = v3_norm(sdiff);
    int degenerate = c->degenerate;
    if (degenerate) {
        /* coplanar faces may have been owned by one side only: repeat with -w and average */
        c->flip = 1;
        c->store_pts = 0;
        ovl_pass(c);
        pd_v3 s2 = v3_sub(c->area_a, c->area_b);
        vol = PD_R(0.5) * (vol + c->vol);
        mom = v3_scale(v3_add(mom, c->moment), PD_R(0.5));
        smag = PD_R(0.5) * (smag + v3_norm(s2));
        sdiff = v3_scale(v3_add(sdiff, s2), PD_R(0.5));
    }
    pd_real vmin = in->vol_a < in->vol_b ? in->vol_a : in->vol_b;
    if (!(vol > PD_R(100) * PD_EPS * vmin)) { /* touching, or round-off of a touching contact */
        c->degenerate = degenerate;
        ovl_miss(o, c);
        return;
    }
    o->hit = 1;
    o->degenerate = degenerate;
    o->kept_a = c->na;
    o->kept_b = c->nb;
    o->volume = vol;
    o->centroid = v3_scale(mom, PD_R(1) / vol);
    /* eq. 4.19 from both sides: A's faces inside B minus B's faces inside A (equal and opposite
     * in exact arithmetic; faces shared by both cancel). Coincident shapes have no direction at
     * all: fall back to the centre line, then to +z. */
    pd_real sn = v3_norm(sdiff);
    if (sn > PD_R(1000) * PD_EPS * smag)
        o->normal = v3_scale(sdiff, PD_R(1) / sn);
    else
        o->normal = v3_dot(dc, dc) > PD_R(0) ? c->d : v3(0, 0, 1);

    /* depth: extent of the overlap's nodes along the normal (section 4.2) */
    c->n = o->normal;
    c->lo = PD_REAL_MAX;
    c->hi = -PD_REAL_MAX;
    if (!c->pts_overflow) {
        for (int q = 0; q < c->npts; q++) {
            pd_real s = v3_dot(v3_load(c->pts, q), c->n);
            if (s < c->lo) c->lo = s;
            if (s > c->hi) c->hi = s;
        }
    } else {
        c->flip = 0;
        c->depth_mode = 1;
        ovl_pass(c);
    }
    o->depth = c->hi > c->lo ? c->hi - c->lo : PD_R(0);
}

#endif /* PD_OVERLAP_H */
