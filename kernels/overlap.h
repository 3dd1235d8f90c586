/*
 * overlap.h - exact volumetric overlap of two closed triangle meshes (thesis
 * sections 4.2, 5.2-5.3).
 *
 * Compiles as OpenCL C and as host C (see pd_real.h). Given polyhedra A and B, it finds the nodes
 * of A n B with Algorithm 1 on the triangles that survive the half-plane filter (eqs. 5.3-5.5) and
 * meet the box where the two kept parts overlap, and accumulates the overlap's mass properties with
 * the cusp model (eqs. 5.7-5.11) without building the intersection polyhedron: every node
 * contributes one signed simplex per (face, incident edge). Shapes may be non-convex; nothing is
 * decomposed.
 *
 * Frame (figure 5.4): everything is evaluated in A's frame, where A's vertices are given as they
 * are and B's vertices are mapped by p = rot * v + tr. Callers put A's centroid near the origin so
 * the cusp simplices, which all have a node at the origin, stay small; an overlap much smaller than
 * its simplices (a corner just pressed in) is summed again about its own nodes (ovl_compute).
 *
 * The predicates, and how degenerate contacts are resolved, are in overlap_predicates.h.
 */
#ifndef PD_OVERLAP_H
#define PD_OVERLAP_H

#include "overlap_predicates.h"

/* Adds the cusp (p, t, n, b = -nu) of a face with outward unit normal nu (eqs. 5.8-5.11). */
PD_FN void ovl_cusp(ovl_ctx *c, pd_v3 p, pd_v3 t, pd_v3 n, pd_v3 nu, int on_b)
{
    pd_v3 o = c->origin; /* the simplices' common node: exact while it is 0 */
    if (OVL_RESCUE && c->node_org && c->cur_node >= 0)
        o = v3_load(ovl_ndr(c, OVL_ND_ORG), c->cur_node); /* its place's centre */
    p = v3_sub(p, o);
    pd_real tp = v3_dot(t, p), np = v3_dot(n, p), hp = v3_dot(nu, p);
    pd_real area = PD_R(0.5) * tp * np;  /* eq. 5.9 */
    pd_real vol = area * hp / PD_R(3.0); /* eq. 5.10: -(1/6)(t.p)(n.p)(b.p) */
    c->vol += vol;
    c->vol_abs += PD_FABS(vol);
    /*
     * eq. 5.11: the simplex of eq. 5.8 has nodes p, p - (t.p)t, p - (t.p)t - (n.p)n and the
     * origin, so its centroid is (3p - 2(t.p)t - (n.p)n)/4 (the printed eq. 5.11 flips both signs).
     */
    pd_v3 cen = v3_sub(v3_sub(v3_scale(p, PD_R(3)), v3_scale(t, PD_R(2) * tp)), v3_scale(n, np));
    pd_v3 mom = v3_scale(cen, vol * PD_R(0.25));
    if (OVL_RESCUE && c->node_org) /* the moment stays about c->origin */
        mom = v3_add(mom, v3_scale(v3_sub(o, c->origin), vol));
    c->moment = v3_add(c->moment, mom);
    if (OVL_PLACES_BUILD && c->cur_node >= 0) { /* its node's share (ovl_places) */
        int x = c->cur_node;
        PD_GLOBAL pd_real *ar = ovl_ndr(c, OVL_ND_AREA), *mo = ovl_ndr(c, OVL_ND_MOM);
        ovl_ndr(c, OVL_ND_VOL)[x] += vol;
        v3_store(ar, x, v3_add(v3_load(ar, x), v3_scale(nu, on_b ? -area : area)));
        v3_store(mo, x, v3_add(v3_load(mo, x), mom));
    }
    if (on_b)
        c->area_b = v3_add(c->area_b, v3_scale(nu, area));
    else
        c->area_a = v3_add(c->area_a, v3_scale(nu, area));
    c->area_abs += PD_FABS(area);
#if !PD_DOUBLE
    /* ovl_faces_close: this cusp's share of n (t . p) on its face, kept apart by the face's
     * normal (single precision only: see there) */
    pd_real nv[3] = {nu.x, nu.y, nu.z}, qv[3] = {n.x * tp, n.y * tp, n.z * tp};
    for (int r = 0; r < 3; r++)
        for (int q = 0; q < 3; q++)
            c->gap[on_b][3 * r + q] += nv[r] * qv[q];
    c->gap_abs += PD_FABS(tp);
#endif
}

/*
 * Records a node of the overlap for the depth (or projects it in depth mode) and returns its index
 * in this pass (-1 in depth mode).
 *
 * A node is recorded within the box where the kept parts of both solids meet (c->box_lo,
 * c->box_hi, padded by the cull margin), where every node of A n B lies. A crossing of an edge
 * that lies in the other's face plane to within the resolution can be computed anywhere along the
 * edge: its place there is the ratio of two side values within the tie band of 0. Which
 * triangles it crosses is then decided by the tie-breaking, not by that place, and its cusps
 * still sum the right volume. But as a node it made the depth: in a lattice of cubes settling in
 * single precision, a cube's diagonal edge in a side face coplanar with the other cube's side
 * face to a few resolutions crossed at 1.8 mm below the contact, and the contact's depth came out
 * 1.86e-3 m for 1.0e-5 m. A one-step force spike followed (tests/physics/test_overlap.c,
 * single_precision_depth_of_a_grazing_crossing). The cusps keep the point as computed.
 */
PD_FN int ovl_node(ovl_ctx *c, pd_v3 p)
{
    p = v3(pd_min(pd_max(p.x, c->box_lo.x), c->box_hi.x),
           pd_min(pd_max(p.y, c->box_lo.y), c->box_hi.y),
           pd_min(pd_max(p.z, c->box_lo.z), c->box_hi.z));
    if (c->depth_mode) {
        pd_real s = v3_dot(p, c->n);
        if (s < c->lo) c->lo = s;
        if (s > c->hi) c->hi = s;
        return -1;
    }
    if (c->store_pts) {
        if (c->npts < c->in->pts_cap)
            v3_store(c->pts, c->npts++, p);
        else
            c->pts_overflow = 1;
    }
    return OVL_PLACES_BUILD ? c->inode++ : 0;
}

/* OVL_PLACES, where a recording pass emits the cusps of node idx: their volume is summed to it. */
PD_FN void ovl_cusps_of(ovl_ctx *c, int idx)
{
    c->cur_node = idx >= 0 && idx < c->in->pts_cap ? idx : -1;
}

/*
 * OVL_PLACES: keeps what ovl_places needs of node idx (key, end, fl, lam: see ovl_ctx) in the pass
 * that stores the nodes, and starts its sums in a recording pass. Returns whether it is kept.
 */
PD_FN int ovl_node_key(ovl_ctx *c, int idx, int key, int end, int fl, pd_real lam)
{
    if (idx < 0 || idx >= c->in->pts_cap) return 0;
    if (c->store_pts) {
        ovl_ndi(c, OVL_ND_KEY)[idx] = key;
        ovl_ndi(c, OVL_ND_END)[idx] = end;
        ovl_ndi(c, OVL_ND_FL)[idx] = fl;
        ovl_ndr(c, OVL_ND_LAM)[idx] = lam;
        ovl_ndi(c, OVL_ND_PAR)[idx] = idx;
    }
    if (c->rec) {
        ovl_ndr(c, OVL_ND_VOL)[idx] = PD_R(0);
        v3_store(ovl_ndr(c, OVL_ND_AREA), idx, v3(0, 0, 0));
        v3_store(ovl_ndr(c, OVL_ND_MOM), idx, v3(0, 0, 0));
        c->cur_node = idx;
    }
    return 1;
}

/* Union-find over the nodes (ovl_places): the smaller index is the root, so the result does not
 * depend on the order of the unions. */
PD_FN int ovl_find(PD_GLOBAL int *par, int x)
{
    while (par[x] != x) {
        par[x] = par[par[x]];
        x = par[x];
    }
    return x;
}

PD_FN void ovl_union(PD_GLOBAL int *par, int a, int b)
{
    a = ovl_find(par, a);
    b = ovl_find(par, b);
    if (a < b) par[b] = a;
    if (b < a) par[a] = b;
}

/*
 * The three cusps at a node (the caller emits it: ovl_node) where edge (of face F, unit direction
 * te pointing into the other solid, in-face inward normal m) pierces face G of the other solid:
 * one along the edge, and one on each face along their line of intersection, heading into F
 * (eq. 5.7's t, n, b at that node).
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
        return;
    }
    pd_v3 l = v3_scale(cr, PD_R(1) / len);
    l = v3_scale(l, (pd_real)(1 - 2 * (v3_dot(l, m) < PD_R(0)))); /* towards m; no branch */
    /* In F's plane the other solid lies towards -ng; in G's plane this solid lies towards -nf. */
    pd_v3 n_f = v3_scale(v3_sub(v3_scale(nf, cs), ng), PD_R(1) / len);
    pd_v3 n_g = v3_scale(v3_sub(v3_scale(ng, cs), nf), PD_R(1) / len);
    ovl_cusp(c, p, te, m, nf, f_on_b);
    ovl_cusp(c, p, l, n_f, nf, f_on_b);
    ovl_cusp(c, p, l, n_g, ng, !f_on_b);
}

/*
 * Emits the node of vertex v of A (side 0) or B (side 1), known to lie inside the other solid, the
 * first time one of its triangles asks in this pass; later asks find it emitted.
 */
PD_FN void ovl_vertex_emit(ovl_ctx *c, int side, int v)
{
    PD_GLOBAL int *st = side ? c->st_b : c->st_a;
    int s = st[v];
    if (s & OVL_V_EMITTED) return;
    int idx = ovl_node(c, ovl_vx(c, side, v));
    if (OVL_PLACES_BUILD && c->places) ovl_node_key(c, idx, 2 * v + side, -1, 0, PD_R(0));
    st[v] = s | OVL_V_EMITTED | (idx + 1) * OVL_V_NODE;
}

/* Settles the side of corner j from its neighbour i along an edge crossed `odd` times (mod 2),
 * when i is known and j is not; returns 1 when it did. */
PD_FN int ovl_spread(PD_GLOBAL int *st, int i, int j, int odd)
{
    if (!(st[i] & OVL_V_TESTED) || (st[j] & OVL_V_TESTED)) return 0;
    st[j] |= OVL_V_TESTED | (((st[i] & OVL_V_INSIDE) != 0) != odd) * OVL_V_INSIDE;
    return 1;
}

/* One side's near triangles, their crossing parities and vertex states, as ovl_resolve walks
 * them (side 0: A's, 1: B's). */
typedef struct ovl_walk {
    PD_GLOBAL const int *tri, *near, *x, *slot, *vt_off, *vt;
    PD_GLOBAL int *st;
    int n;
} ovl_walk;

PD_FN void ovl_walk_make(ovl_walk *w, const ovl_ctx *c, int side)
{
    w->tri = side ? c->in->tb : c->in->ta;
    w->near = side ? c->near_b : c->near_a;
    w->x = side ? c->xb : c->xa;
    w->slot = side ? c->slot_b : c->slot_a;
    w->vt_off = side ? c->in->vt_b_off : c->in->vt_a_off;
    w->vt = side ? c->in->vt_b : c->in->vt_a;
    w->st = side ? c->st_b : c->st_a;
    w->n = side ? c->nb : c->na;
}

/*
 * Corner u's neighbours along the two edges at u of triangle t, and for each the parity of the
 * edge's crossings with the other surface; 0 when t is not near (slot holds places only for near
 * triangles; others: any value).
 */
PD_FN int ovl_walk_edges(const ovl_walk *w, int t, int u, int nb[2], int odd[2])
{
    int k = w->slot[t];
    if (k < 0 || k >= w->n || w->near[k] != t) return 0;
    PD_GLOBAL const int *v = w->tri + 3 * t;
    int q = v[0] == u ? 0 : v[1] == u ? 1 : 2;
    /* edge q runs u -> v[q + 1], edge q + 2 runs v[q + 2] -> u */
    nb[0] = v[(q + 1) % 3];
    nb[1] = v[(q + 2) % 3];
    odd[0] = (w->x[k] >> q) & 1;
    odd[1] = (w->x[k] >> ((q + 2) % 3)) & 1;
    return 1;
}

/* Settles unknown corner u from a known neighbour along an edge of a near triangle at u (found
 * through the vertex -> triangle tables); returns 1 when it did. */
PD_FN int ovl_pull(const ovl_walk *w, int u)
{
    for (int e = w->vt_off[u]; e < w->vt_off[u + 1]; e++) {
        int nb[2], odd[2];
        if (ovl_walk_edges(w, w->vt[e], u, nb, odd) &&
            (ovl_spread(w->st, nb[0], u, odd[0]) || ovl_spread(w->st, nb[1], u, odd[1])))
            return 1;
    }
    return 0;
}

/* Spreads known corner v's side to everything it reaches through near triangles, breadth first
 * (queue: room for each corner once). */
PD_FN void ovl_walk_from(const ovl_walk *w, int v, PD_GLOBAL int *queue)
{
    int head = 0, tail = 0;
    queue[tail++] = v;
    while (head < tail) {
        int u = queue[head++];
        for (int e = w->vt_off[u]; e < w->vt_off[u + 1]; e++) {
            int nb[2], odd[2];
            if (!ovl_walk_edges(w, w->vt[e], u, nb, odd)) continue;
            for (int h = 0; h < 2; h++)
                if (ovl_spread(w->st, u, nb[h], odd[h])) queue[tail++] = nb[h];
        }
    }
}

/* Without vertex -> triangle tables: sweeps over the near triangles' edges, each corner settled
 * from a known neighbour, until one settles nothing or leaves nothing unknown. */
PD_FN void ovl_sweeps(const ovl_walk *w)
{
    for (int changed = 1, unknown = 1; changed && unknown;) {
        changed = unknown = 0;
        for (int k = 0; k < w->n; k++)
            for (int q = 0; q < 3; q++) {
                int i = w->tri[3 * w->near[k] + q], j = w->tri[3 * w->near[k] + (q + 1) % 3];
                int odd = (w->x[k] >> q) & 1;
                changed |= ovl_spread(w->st, i, j, odd) | ovl_spread(w->st, j, i, odd);
                unknown |= !(w->st[i] & OVL_V_TESTED);
            }
    }
}

/*
 * The side of the other solid of every corner of side's near triangles (st: TESTED, and INSIDE
 * inside), with as few ray casts as can be. A corner beyond the other's half-plane or outside the
 * box where A n B lies is outside (ovl_outside_known). Any other corner takes its side from a
 * neighbour along an edge of a near triangle: the two differ exactly when the edge crosses the
 * other solid's surface an odd number of times, and the pair loop has counted those crossings
 * (x: a crossing point lies on both solids, so in both kept boxes, and the two triangles it lies
 * on are near and their boxes meet; with the symbolic perturbation the crossings and the casts
 * describe one configuration). A corner that no known one reaches is cast (ovl_inside_b / _a)
 * and spread from in turn.
 *
 * Between particles the unknown corners are the few near the overlap, each an edge or two from a
 * known one: they are listed, and each takes its side from a known neighbour, found through the
 * vertex -> triangle tables, until none can (sweeps over every near triangle's edges when there
 * are no tables, as for a wall's triangles). Where the filter knows nothing (a particle against a
 * wall, or no filter), one cast settles the whole connected part, walked through the tables.
 */
PD_FN void ovl_resolve(ovl_ctx *c, int side)
{
    ovl_walk w;
    ovl_walk_make(&w, c, side);
    PD_GLOBAL int *st = w.st;
    /* the unknown corners, each once, in the order of the near triangles; the walk's queue
     * after them (each holds a corner at most once) */
    PD_GLOBAL int *list = c->queue, *queue = c->queue + (side ? c->in->nvb : c->in->nva);
    int m = 0;
    for (int k = 0; k < w.n; k++)
        for (int q = 0; q < 3; q++) {
            int v = w.tri[3 * w.near[k] + q];
            if (st[v] & (OVL_V_TESTED | OVL_V_LISTED)) continue;
            if (ovl_outside_known(c, side, v)) {
                st[v] |= OVL_V_TESTED;
            } else {
                st[v] |= OVL_V_LISTED;
                list[m++] = v;
            }
        }
    if (m == 0) return;
    int walk = w.vt_off && !(c->filter && (side || !(c->in->flags & OVL_OPEN_B)));
    if (!walk && w.vt_off) {
        /* rounds over the list until one settles nothing or leaves nothing unknown */
        for (int changed = 1; changed && m > 0;) {
            int left = 0;
            changed = 0;
            for (int i = 0; i < m; i++) {
                int u = list[i];
                if (st[u] & OVL_V_TESTED) continue;
                if (ovl_pull(&w, u))
                    changed = 1;
                else
                    list[left++] = u;
            }
            m = left;
        }
    } else if (!walk) {
        ovl_sweeps(&w);
    }
    for (int i = 0; i < m; i++) {
        int v = list[i];
        if (st[v] & OVL_V_TESTED) continue;
        /* the first corner still unknown, cast */
        int in = side ? ovl_inside_a(c, v) : ovl_inside_b(c, v);
        st[v] |= OVL_V_TESTED | in * OVL_V_INSIDE;
        if (w.vt_off)
            ovl_walk_from(&w, v, queue); /* everything this cast reaches */
        else
            ovl_sweeps(&w);
    }
}

/*
 * Geometry of one triangle. The corners, raw normal and box are all the pair loop needs to reject
 * a pair; the unit vectors are computed only when a cusp needs them (ovl_tri_full), which keeps
 * the O(kept_a * kept_b) loop cheap.
 */
typedef struct ovl_tri {
    int id[3];
    int slot; /* its place in near_a / near_b (ovl_pass) */
    pd_v3 p[3];
    pd_v3 nraw;   /* (p1 - p0) x (p2 - p0) */
    pd_real ptol; /* snap bound of sides of its plane (ovl_plane_tol); set by the pair loop */
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
    t->ptol = PD_R(0);
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
    /* all three edges, combined without branches: for a new pair which edge rejects the point
     * is unpredictable (as in ovl_sign) */
    int inside = 1, outside = 0;
    for (int k = 0; k < 3; k++) {
        pd_real v = v3_dot(t->me[k], v3_sub(p, t->p[k]));
        pd_real margin = PD_R(4) * v3_amax(t->me[k]) * err;
        outside |= v < -margin;
        inside &= v > margin;
    }
    return inside - outside; /* exclusive: inside needs every edge's v above its margin */
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
    t->ptol = uc[18];
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
    return ovl_boxes_meet(t->lo, t->hi, c->box_lo, c->box_hi);
}

/* Where canonical edge lo->hi crosses a plane, from its ends' signed distances: 0 at lo, 1 at hi.
 */
PD_FN pd_real ovl_cross_lam(pd_real slo, pd_real shi)
{
    pd_real den = slo - shi;
    pd_real lam = den != PD_R(0) ? slo / den : PD_R(0);
    /* the crossing lies on the edge; when both ends are within rounding of the plane the
     * quotient is noise, and must not throw the node off the edge */
    return lam < PD_R(0) ? PD_R(0) : lam > PD_R(1) ? PD_R(1) : lam;
}

/* Crossing point of canonical edge lo->hi with a plane, from the edge ends' signed distances. */
PD_FN pd_v3 ovl_cross_point(pd_v3 plo, pd_v3 phi, pd_real slo, pd_real shi)
{
    return v3_add(plo, v3_scale(v3_sub(phi, plo), ovl_cross_lam(slo, shi)));
}

/*
 * Emits the node where T's edge k (side 0: of A; 1: of B) crosses the other triangle, before its
 * cusps; with OVL_PLACES also keeps its key and joins it to the pair's first crossing (a segment
 * of the faces' intersection joins them). sk1: the side of the edge's end k + 1. Returns the
 * updated first crossing.
 */
PD_FN int ovl_crossing_node(ovl_ctx *c, const ovl_tri *T, int k, int lo, pd_v3 p, const pd_real *q,
                            int sk1, int side, int first)
{
    int idx = ovl_node(c, p);
    if (!(OVL_PLACES_BUILD && c->places)) return first;
    int k1 = (k + 1) % 3, hi = k + k1 - lo;
    int vlo = T->id[lo], vhi = T->id[hi];
    /* heading into the other solid towards the higher end: edge k runs k -> k1, and the other
     * solid lies away from k1's side */
    int fl = (lo == k) == (sk1 < 0);
    if (ovl_node_key(c, idx, 2 * vlo + side, vhi, fl, ovl_cross_lam(q[lo], q[hi])) &&
        c->store_pts) {
        if (first >= 0)
            ovl_union(ovl_ndi(c, OVL_ND_PAR), first, idx);
        else
            first = idx;
    }
    return first;
}

/*
 * Error bound (max-norm) of ovl_cross_point's node: the side values carry up to the plane's snap
 * bound tol each, which moves the node along the edge by |a1 - a0| tol / |s0 - s1|; plus the
 * coordinates' own rounding.
 */
PD_FN pd_real ovl_cross_err(const ovl_ctx *c, pd_v3 a0, pd_v3 a1, pd_real s0, pd_real s1,
                            pd_real tol)
{
    pd_real ds = PD_FABS(s0 - s1);
    pd_real len = v3_amax(v3_sub(a1, a0));
    return ds > PD_R(0) ? c->pad + PD_R(2) * len * tol / ds : PD_REAL_MAX;
}

/*
 * Narrows [*t0, *t1] to where a + t d lies within the box [lo, hi]; 0 when the segment it spans
 * there never enters the box.
 */
PD_FN int ovl_span_in_box(pd_v3 a, pd_v3 d, pd_v3 lo, pd_v3 hi, pd_real *t0, pd_real *t1)
{
    const pd_real av[3] = {a.x, a.y, a.z}, dv[3] = {d.x, d.y, d.z};
    const pd_real lv[3] = {lo.x, lo.y, lo.z}, hv[3] = {hi.x, hi.y, hi.z};
    for (int k = 0; k < 3; k++) {
        if (dv[k] == PD_R(0)) {
            if (av[k] < lv[k] || av[k] > hv[k]) return 0;
            continue;
        }
        pd_real u = (lv[k] - av[k]) / dv[k], v = (hv[k] - av[k]) / dv[k];
        *t0 = pd_max(*t0, pd_min(u, v));
        *t1 = pd_min(*t1, pd_max(u, v));
    }
    return *t0 <= *t1;
}

/*
 * The pair loop's rare path: a crossing p = a + lam (b - a) of an edge (a its canonical end) that
 * lies outside the box where the kept parts of both solids meet (c->box_lo, c->box_hi, padded by
 * the cull margin), which holds every node of A n B. A stage of its own on the host, so the
 * common path is laid out as without it. Returns 0 when the crossing is dropped.
 *
 * An edge that never enters that box crosses nothing of the other solid, and its crossing is
 * dropped. Such crossings come only from predicates that describe no one geometry. An edge lying
 * in a plane of the other solid to within the resolution straddles it when one end is decided by
 * its coordinates and the other by the tie-breaking, and its crossing point is then a ratio of
 * side values inside the tie band: anywhere along the edge. Whether the edge's line passes
 * through the other's triangle is decided by the edge-edge predicates, which are all ties for
 * coplanar lines however far apart they lie in the plane. In a single-precision lattice of 2 cm
 * cubes, the bottom edges of the lower cube and the top edges of the upper one crossed each
 * other's side faces so, coplanar to 3.6e-7 m: four cusps 16 mm from a contact 1e-5 m deep,
 * whose faces' polygons were open on both solids alike (so the sum of both solids' area vectors
 * still vanished) and turned the normal by 14 degrees; the depth along it was 3.9e-3 m, a
 * one-step force spike (tests/physics/test_overlap.c, single_precision_normal_of_coplanar_columns;
 * bench/RESULTS.md, 2026-12-07).
 *
 * A crossing whose place on the other triangle was decided by the edge-edge predicates
 * (ovl_point_in_tri could not tell: tied) is moved along its edge into the box of that triangle
 * (lo_t, hi_t) and of A n B, where the edge enters both. Such an edge is nearly parallel to the
 * other's plane, so a resolution moves its crossing by the resolution over their angle, while the
 * predicates, all ties near the other's edges, have placed it on the triangle. In a single-
 * precision lattice of cubes, a cube's vertical edges, 1e-4 rad from the other's side faces and
 * within the resolution of their bottom edges, crossed them 4.6 mm below the contact, where the
 * line of the faces' intersection lies millimetres away: the pass's side polygons were open and
 * a resting contact's normal turned by 11 degrees (tests/physics/test_overlap.c,
 * single_precision_crossings_near_parallel_faces; bench/RESULTS.md, 2026-12-07 (later still)).
 *
 * Any other crossing is kept where it was computed (ovl_node records its node within the box):
 * moving every one along its edge into the box was tried, and opened other faces' polygons (a
 * resting pair of that lattice got a normal turned by 40 degrees).
 */
PD_STAGE_FN int ovl_crossing_outside(const ovl_ctx *c, pd_v3 *p, pd_v3 a, pd_v3 b, pd_real lam,
                                     int tied, pd_v3 lo_t, pd_v3 hi_t)
{
    pd_v3 d = v3_sub(b, a);
    pd_real t0 = PD_R(0), t1 = PD_R(1);
    if (!ovl_span_in_box(a, d, c->box_lo, c->box_hi, &t0, &t1)) return 0;
    /* the span within A n B's box, narrowed to the other triangle's */
    if (tied && ovl_span_in_box(a, d, lo_t, hi_t, &t0, &t1))
        *p = v3_add(a, v3_scale(d, pd_min(pd_max(lam, t0), t1)));
    return 1;
}

/*
 * Whether edge i -> j, whose crossing ovl_point_in_tri could not place (too near an edge of the
 * triangle with corners id), passes through that triangle: the edge's line turns the same way
 * about all three of the triangle's edges (exact canonical predicates, so the two triangles of
 * the edge agree bit for bit). side 0: the edge is A's and the triangle B's; 1: the edge is B's,
 * where det(u_j - u_i, t_a - u_i, t_b - u_i) equals the orientation of the triangle's edge
 * a -> b against the edge i -> j, so the shared canonical predicate decides both tests.
 * Rare, and a stage of its own on the host: inlined twice into the pair loop, it cost 2 % of a
 * Schonhardt overlap's instructions in how gcc laid the loop out (bench/RESULTS.md, 2026-12-07,
 * evening).
 */
PD_STAGE_FN int ovl_tied_in(ovl_ctx *c, int i, int j, const int *id, int side)
{
    int s0 = 0;
    for (int k = 0; k < 3; k++) {
        int a = id[k], b = id[(k + 1) % 3];
        int s = side ? ovl_edge_edge_dir(c, a, b, i, j) : ovl_edge_edge_dir(c, i, j, a, b);
        if (k == 0) s0 = s;
        if (s == 0 || s != s0) return 0; /* as soon as one tells, as the predicates set flags */
    }
    return 1;
}

/* The corner alone on its side of a plane, given three sides (+-1); 3 when all are equal. */
PD_FN int ovl_lone(const int sd[3])
{
    return 2 * (sd[0] == sd[1]) + (sd[0] == sd[2]);
}

/* Edge h (0, 1) of the two at corner `lone` (edge k runs from corner k to k + 1), ascending. */
PD_FN int ovl_lone_edge(int lone, int h)
{
    /* lone 0: edges 0, 2; lone 1: 0, 1; lone 2: 1, 2 */
    return h ? lone + 2 * (lone == 0) : lone - (lone != 0);
}

/*
 * The crossings of E's two edges at its lone corner (lone: ovl_lone of its sides sd, with side
 * values q against F's plane) through F, each emitted with its node and cusps. side 0: E is A's
 * triangle and F is B's; 1: the other way. first: the pair's first crossing node so far (-1:
 * none; OVL_PLACES joins the pair's crossings); returns it updated.
 */
PD_FN int ovl_edges_through(ovl_ctx *c, ovl_tri *E, ovl_tri *F, const pd_real *q, const int *sd,
                            int lone, int side, int first)
{
    for (int h = 0; h < 2; h++) {
        int k = ovl_lone_edge(lone, h);
        int k1 = (k + 1) % 3;
        int i = E->id[k], j = E->id[k1];
        int lo = i < j ? k : k1; /* the canonical end, chosen by index (no branch) */
        int hi = k + k1 - lo;
        pd_v3 p = ovl_cross_point(E->p[lo], E->p[hi], q[lo], q[hi]);
        int in = ovl_point_in_tri(F, p, ovl_cross_err(c, E->p[k], E->p[k1], q[k], q[k1], F->ptol));
        /* near F's edges: the edge's line passes inside F when it turns the same way about all
         * three of F's edges (exact canonical predicates) */
        int tied = in == 0;
        if (tied) in = ovl_tied_in(c, i, j, F->id, side);
        if (in != 1) continue;
        /* rare: an edge nearly in the other's plane */
        if (!ovl_in_box(c, p) &&
            !ovl_crossing_outside(c, &p, E->p[lo], E->p[hi], ovl_cross_lam(q[lo], q[hi]), tied,
                                  F->lo, F->hi))
            continue;
        ovl_tri_full(E);
        ovl_tri_full(F);
        (side ? c->xb : c->xa)[E->slot] ^= 1 << k; /* for ovl_resolve */
        first = ovl_crossing_node(c, E, k, lo, p, q, sd[k1], side, first);
        pd_v3 te = v3_scale(E->e[k], (pd_real)-sd[k1]); /* into F's solid; sd is +-1 */
        ovl_crossing_cusps(c, p, te, E->m[k], E->nu, F->nu, side);
    }
    return first;
}

/* All cusps between A's triangle T and B's triangle U from edges of one crossing the other (the
 * caller has checked that their boxes meet). */
PD_FN void ovl_pair(ovl_ctx *c, ovl_tri *T, ovl_tri *U)
{
    pd_real qa[3], qb[3];
    int sa[3], sb[3];
    /* a triangle wholly on one side of the other's plane: no edge of either crosses the other */
    for (int k = 0; k < 3; k++)
        sa[k] = ovl_side_a(c, T->p[k], U->p[0], U->nraw, U->ptol, &qa[k]);
    /*
     * Both triangles' sides first, then one branch (lone 3: all on one side): the two rejections
     * are unpredictable, and one mispredicted branch cost more than U's sides (bench/RESULTS.md).
     * U's sides count as a degenerate predicate only where T straddles, as when they were
     * evaluated only then (a tie forces the mirrored second pass).
     */
    int dg = c->degenerate, la = ovl_lone(sa), t_cross = la < 3;
    for (int k = 0; k < 3; k++)
        sb[k] = ovl_side_b(c, U->p[k], T->p[0], T->nraw, T->ptol, &qb[k]);
    c->degenerate = dg | (c->degenerate & t_cross);
    int lb = ovl_lone(sb);
    if (!(t_cross & (lb < 3))) return;

    /*
     * The sides are 0 only all together (a vanishing normal, returned above; ties are broken
     * otherwise), so exactly one corner of each triangle lies alone on its side, and the two
     * edges at it are the ones that cross: chosen by arithmetic, in ascending order (the
     * summation order of an edge-by-edge loop), because which edges cross is unpredictable for
     * a new pair.
     */
    int first = ovl_edges_through(c, T, U, qa, sa, la, 0, -1); /* T's edges through U */
    ovl_edges_through(c, U, T, qb, sb, lb, 1, first);          /* U's edges through T */
}

/* One pass of Algorithm 1 over the kept triangles, accumulating cusps. */
PD_STAGE_FN void ovl_pass(ovl_ctx *c)
{
    PD_GLOBAL const int *ta = c->in->ta;
    PD_GLOBAL const int *tb = c->in->tb;
    int open_b = (c->in->flags & OVL_OPEN_B) != 0;
    c->vol = c->vol_abs = PD_R(0);
    c->moment = c->area_a = c->area_b = v3(0, 0, 0);
    c->area_abs = PD_R(0);
#if !PD_DOUBLE
    for (int r = 0; r < 9; r++)
        c->gap[0][r] = c->gap[1][r] = PD_R(0);
    c->gap_abs = PD_R(0);
#endif
    c->origin_in_b = -1; /* its ties follow c->flip */
    c->inode = 0;
    c->rec = c->places && !c->flip && !c->depth_mode;
    c->cur_node = -1;
    /* only the kept triangles' corners are ever tested (A's have no READY bit to keep) */
    for (int k = 0; k < c->ka; k++)
        for (int q = 0; q < 3; q++)
            c->st_a[ta[3 * c->kept_a[k] + q]] = 0;
    for (int l = 0; l < c->kb; l++)
        for (int q = 0; q < 3; q++)
            c->st_b[tb[3 * c->kept_b[l] + q]] &= OVL_V_READY;

    for (int k = 0; k < c->na; k++)
        c->xa[k] = 0;
    for (int l = 0; l < c->nb; l++)
        c->xb[l] = 0;

    /* the crossings: edges of one solid through faces of the other; T's box and U's (cached)
     * are each padded by half the cull margin (OVL_CULL) */
    pd_real tpad = PD_R(OVL_CULL / 2) * c->pad;
    for (int k = 0; k < c->na; k++) {
        int t = c->near_a[k];
        ovl_tri T;
        T.id[0] = ta[3 * t];
        T.id[1] = ta[3 * t + 1];
        T.id[2] = ta[3 * t + 2];
        T.slot = k;
        ovl_tri_make(&T, ovl_va(c, T.id[0]), ovl_va(c, T.id[1]), ovl_va(c, T.id[2]), tpad);
        /* B open (a wall's part): A is not filtered, so most of its triangles lie beside all
         * of B's near ones; between particles the box where the kept parts meet did that */
        if (open_b && !ovl_boxes_meet(T.lo, T.hi, c->nblo, c->nbhi)) continue;
        /* Boxes first, from the cache: most pairs end there. Whether two boxes meet is
         * unpredictable, so the ones that do are listed without a branch (a branch per box
         * was the most mispredicted in a 1280-triangle icosphere pair), then paired in order. */
        int nh = 0;
        if (c->sweep) {
            /* the boxes whose low ends on the sweep's axis lie from T's low end less the widest
             * box (and a resolution for the rounding of the width) to T's high end: every box
             * that can meet T's, then tested as below and put back in near_b's order, the order
             * the cusps are summed in */
            int a = c->sweep_axis;
            pd_real tlo = a == 0 ? T.lo.x : a == 1 ? T.lo.y : T.lo.z;
            pd_real thi = a == 0 ? T.hi.x : a == 1 ? T.hi.y : T.hi.z;
            int k = ovl_first_key(c->sweep_key, c->nb, tlo - c->sweep_width - c->pad);
            for (; k < c->nb && c->sweep_key[k] <= thi; k++) {
                int l = c->sweep_ord[k];
                PD_GLOBAL const pd_real *uc = c->ucache + OVL_TRI_CACHE * l;
                c->hits[nh] = l;
                nh += ovl_boxes_meet(T.lo, T.hi, v3_load(uc, 1), v3_load(uc, 2));
            }
            ovl_sort(c->hits, nh);
        } else {
            for (int l = 0; l < c->nb; l++) {
                PD_GLOBAL const pd_real *uc = c->ucache + OVL_TRI_CACHE * l;
                c->hits[nh] = l;
                nh += ovl_boxes_meet(T.lo, T.hi, v3_load(uc, 1), v3_load(uc, 2));
            }
        }
        if (nh > 0) T.ptol = ovl_plane_tol(c, v3_norm(T.nraw));
        for (int h = 0; h < nh; h++) {
            int l = c->hits[h];
            PD_GLOBAL const pd_real *uc = c->ucache + OVL_TRI_CACHE * l;
            int u = c->near_b[l];
            ovl_tri U;
            U.id[0] = tb[3 * u];
            U.id[1] = tb[3 * u + 1];
            U.id[2] = tb[3 * u + 2];
            U.slot = l;
            ovl_tri_cached(&U, c, uc);
            ovl_pair(c, &T, &U);
        }
    }
    /* nodes of each solid inside the other: two cusps per corner, along the triangle's two
     * edges (A's, then B's) */
    for (int side = 0; side < 2; side++) {
        PD_GLOBAL const int *tri = side ? tb : ta;
        PD_GLOBAL const int *near = side ? c->near_b : c->near_a;
        PD_GLOBAL const int *st = side ? c->st_b : c->st_a;
        int n = side ? c->nb : c->na;
        ovl_resolve(c, side);
        for (int k = 0; k < n; k++) {
            int t = near[k];
            int id[3] = {tri[3 * t], tri[3 * t + 1], tri[3 * t + 2]};
            if (!((st[id[0]] | st[id[1]] | st[id[2]]) & OVL_V_INSIDE)) continue;
            ovl_tri V; /* its box is not needed */
            V.p[0] = ovl_vx(c, side, id[0]);
            V.p[1] = ovl_vx(c, side, id[1]);
            V.p[2] = ovl_vx(c, side, id[2]);
            V.nraw = v3_cross(v3_sub(V.p[1], V.p[0]), v3_sub(V.p[2], V.p[0]));
            V.full = 0;
            ovl_tri_full(&V);
            for (int q = 0; q < 3; q++) {
                if (!(st[id[q]] & OVL_V_INSIDE)) continue;
                int qp = (q + 2) % 3;
                ovl_vertex_emit(c, side, id[q]);
                if (OVL_PLACES_BUILD && c->rec) ovl_cusps_of(c, st[id[q]] / OVL_V_NODE - 1);
                ovl_cusp(c, V.p[q], V.e[q], V.m[q], V.nu, side);
                ovl_cusp(c, V.p[q], v3_scale(V.e[qp], PD_R(-1)), V.m[qp], V.nu, side);
            }
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
    o->area = PD_R(0);
    o->places = 0;
    o->places_known = 1;
    o->vol_eff = o->depth_eff = PD_R(0);
    o->point_eff = v3(0, 0, 0);
}

/* Writes o as the kernels' OVL_OUT_LEN-real result record: hit, degenerate, kept_a, kept_b,
 * volume, centroid[3], normal[3], depth, places, vol_eff, depth_eff, point_eff[3], places_known
 * (read back by ovl_result_unpack on the host). */
PD_FN void ovl_out_store(PD_GLOBAL pd_real *r, const ovl_out *o)
{
    r[0] = (pd_real)o->hit;
    r[1] = (pd_real)o->degenerate;
    r[2] = (pd_real)o->kept_a;
    r[3] = (pd_real)o->kept_b;
    r[4] = o->volume;
    r[5] = o->centroid.x;
    r[6] = o->centroid.y;
    r[7] = o->centroid.z;
    r[8] = o->normal.x;
    r[9] = o->normal.y;
    r[10] = o->normal.z;
    r[11] = o->depth;
    r[12] = (pd_real)o->places;
    r[13] = o->vol_eff;
    r[14] = o->depth_eff;
    r[15] = o->point_eff.x;
    r[16] = o->point_eff.y;
    r[17] = o->point_eff.z;
    r[18] = (pd_real)o->places_known;
}

/* The cusp sums of one configuration: both of a degenerate one's passes averaged. */
typedef struct ovl_sums {
    pd_real vol, vol_abs, smag; /* smag: the sum of |area| its terms came from */
    pd_v3 mom, sdiff;           /* mom about A's frame origin */
    pd_real open;               /* the larger |area_a + area_b| of the passes (ovl_compute_try) */
    int closed;                 /* bit k: pass k (0: +w, 1: -w) closes on its own (ovl_closes) */
    pd_real vdiff;              /* |volume of the +w pass - the -w pass's| (0: one pass) */
    pd_real surf;               /* the larger |area_a| + |area_b| of the passes */
    int faces;                  /* bit k: pass k's faces close (ovl_faces_close) */
} ovl_sums;

/* Whether cusps whose area vectors sum to a vector of norm open, from terms of summed norm mag,
 * close a surface: to their sums' rounding (see ovl_compute_try). */
PD_FN int ovl_closes(pd_real open, pd_real mag)
{
    return !(open > PD_R(1e4) * PD_EPS * mag);
}

/*
 * Whether every face's part inside the other solid is a closed polygon, in single precision.
 * A closed polygon's cusps sum n (t . p) to 0 whatever the origin (each edge of length L gives
 * +n L at one end and -n L at the other), so each solid's sum of nu (x) n (t . p) vanishes when
 * all its faces close, faces of different normals kept apart by nu. ovl_closes cannot see this:
 * its test is that A's and B's area vectors cancel, and in single precision one pass of a resting
 * pair sometimes leaves both solids' side faces open alike, near-coplanar faces within the tie
 * band crossing each other at places that are a ratio of side values inside the band, anywhere
 * along the edge: the area vectors still cancel, but their difference, eq. 4.19's normal, carried
 * the open polygons' area, and the normal turned by 7 to 11 degrees in a lattice of cubes
 * landing (tests/physics/test_overlap.c, single_precision_faces_open_alike; bench/RESULTS.md,
 * 2026-12-07 (later still)). Such passes measured 2 400 to 25 000 resolutions, closed ones up to
 * 35: the bound is 256, plus the sums' rounding. ovl_compute takes no answer whose faces are
 * open (ovl_faces_good; a contact a few resolutions deep whose every try leaves them open counts
 * as not touching for that step). Double precision's tie band is 1e-16 of the configuration, too
 * narrow for a crossing computed that far off, and skips the sums.
 */
PD_FN int ovl_faces_close(const ovl_ctx *c)
{
#if PD_DOUBLE
    (void)c;
    return 1;
#else
    pd_real ga = PD_R(0), gb = PD_R(0);
    for (int r = 0; r < 9; r++) {
        ga += c->gap[0][r] * c->gap[0][r];
        gb += c->gap[1][r] * c->gap[1][r];
    }
    pd_real bound = PD_R(256) * c->pad + PD_R(64) * PD_EPS * c->gap_abs;
    return !(pd_max(ga, gb) > bound * bound);
#endif
}

/* Sums the cusps about c->origin (c->flip must be 0; c->degenerate is set by the first pass; with
 * c->one_pass a degenerate pair keeps its first pass alone). */
PD_STAGE_FN void ovl_sum(ovl_ctx *c, ovl_sums *s)
{
    ovl_pass(c);
    s->vol = c->vol;
    s->vol_abs = c->vol_abs;
    s->mom = c->moment;
    s->sdiff = v3_sub(c->area_a, c->area_b);
    s->smag = c->area_abs;
    s->open = v3_norm(v3_add(c->area_a, c->area_b));
    s->closed = ovl_closes(s->open, c->area_abs);
    s->faces = ovl_faces_close(c);
    s->vdiff = s->surf = PD_R(0);
    if (c->degenerate && !c->one_pass) {
        pd_real surf = v3_norm(c->area_a) + v3_norm(c->area_b);
        /* coplanar faces may have been owned by one side only: repeat with -w and average */
        int store = c->store_pts;
        c->flip = 1;
        /*
         * The nodes (for the depth and the guards on the nodes' box) are the +w pass's. Where
         * it had none, its ties having put B's faces just off A's, the -w pass's are stored
         * instead: faces 3.8 resolutions apart in a single-precision lattice of cubes summed
         * the slab in the -w pass alone, and with no node the contact got half its volume and
         * a depth of 0, so no force (tests/physics/test_single_narrow.c,
         * nodes_of_the_pass_that_found_the_overlap). OVL_PLACES' sums per node are a +w
         * pass's, so ovl_places then answers with one place.
         */
        if (store && c->npts == 0 && !c->pts_overflow)
            c->pts_flip = 1; /* and store_pts stays on */
        else
            c->store_pts = 0;
        ovl_pass(c);
        pd_v3 s2 = v3_sub(c->area_a, c->area_b);
        pd_real open2 = v3_norm(v3_add(c->area_a, c->area_b));
        s->open = pd_max(s->open, open2);
        s->closed |= 2 * ovl_closes(open2, c->area_abs);
        s->faces |= 2 * ovl_faces_close(c);
        s->vdiff = PD_FABS(s->vol - c->vol);
        s->surf = pd_max(surf, v3_norm(c->area_a) + v3_norm(c->area_b));
        s->vol = PD_R(0.5) * (s->vol + c->vol);
        s->vol_abs = pd_max(s->vol_abs, c->vol_abs);
        s->mom = v3_scale(v3_add(s->mom, c->moment), PD_R(0.5));
        s->smag = PD_R(0.5) * (s->smag + c->area_abs);
        s->sdiff = v3_scale(v3_add(s->sdiff, s2), PD_R(0.5));
        c->flip = 0;
        c->store_pts = store;
    }
    s->mom = v3_add(s->mom, v3_scale(c->origin, s->vol));
}

/* Order of crossing nodes for ovl_places: by edge (key, then higher end), then along it. */
PD_FN int ovl_node_before(PD_GLOBAL const int *key, PD_GLOBAL const int *end,
                          PD_GLOBAL const pd_real *lam, int x, int y)
{
    if (key[x] != key[y]) return key[x] < key[y];
    if (end[x] != end[y]) return end[x] < end[y];
    return lam[x] < lam[y];
}

/* Node of vertex v (side 0: of A, 1: of B) when it lies inside the other solid, else -1. */
PD_FN int ovl_vertex_node(const ovl_ctx *c, int side, int v)
{
    int st = side ? c->st_b[v] : c->st_a[v];
    return (st & OVL_V_INSIDE) ? st / OVL_V_NODE - 1 : -1;
}

/* Whether any of the m crossings listed in ord (sorted by ovl_node_before) lies on edge
 * (k, e): binary search. */
PD_FN int ovl_edge_crossed(PD_GLOBAL const int *key, PD_GLOBAL const int *end,
                           PD_GLOBAL const int *ord, int m, int k, int e)
{
    int lo = 0, up = m;
    while (lo < up) {
        int mid = (lo + up) / 2, x = ord[mid];
        if (key[x] < k || (key[x] == k && end[x] < e))
            lo = mid + 1;
        else
            up = mid;
    }
    return lo < m && key[ord[lo]] == k && end[ord[lo]] == e;
}

/*
 * OVL_PLACES (thesis section 5.4): splits the overlap into its connected places and gives the
 * force law the volume and depth that make it the sum of each place's own (o->vol_eff, depth_eff).
 *
 * The surface of A n B is a graph whose vertices are the nodes: pieces of edges lying inside the
 * other solid join consecutive nodes along an edge, and a segment where two faces cross joins the
 * two crossings of a triangle pair (joined as they are found, ovl_crossing_node). Its connected
 * components are the places. Along an edge the crossings are sorted from the lower end, and a
 * piece is inside when either of its ends says so (a vertex inside, or a crossing heading in that
 * way): where rounding made the two disagree, joining keeps the pair's single-place behaviour.
 * An edge with both ends inside and no crossing joins its ends. (A place could in principle be
 * joined only through the middle of a face, a ring of one face inside the other solid; it is then
 * counted as two. That takes a solid curved around a flat face, rare among DEM particles.)
 *
 * Each place k has its volume V_k (its nodes' cusps: a closed part of the boundary sums to its
 * own volume), its own normal n_k (eq. 4.19 over its own cusps) and its depth d_k, the extent of
 * its nodes along n_k: a thin place tilted against the pair's normal n is as thin along n_k as it
 * is, where along n its width would count. Eq. 4.16's force grows as sqrt(V d) and eqs.
 * 4.17-4.18's stiffnesses as sqrt(V / d); a place pushes along n_k, so along n its force counts
 * with c_k = n_k . n and its stiffness with c_k^2. With S1 = sum sqrt(V_k d_k) c_k and
 * S2 = sum sqrt(V_k / d_k) c_k^2, the volume S1 S2 and depth S1 / S2 give eqs. 4.16-4.18 along n
 * exactly the places' summed force and normal stiffness (the tangential stiffness follows the
 * normal one's form). The summed force acts at the places' centroids weighted by their forces
 * (o->point_eff), so that its torque is theirs. Places whose volume is round-off (the same bound
 * as a contact's) are not counted.
 *
 * A degenerate pair's places are those of its first pass (B displaced by +eps w), whose nodes
 * already give the depth: volumes are continuous in the displacement, so that pass's are exact;
 * its normals are not (a face shared with the other solid counts on one side), so every place of
 * a degenerate pair takes the pair's normal.
 *
 * ovl_places_join joins the nodes that the first pass stored into their places (OVL_ND_PAR:
 * ovl_find gives a node's place, named by its smallest node); ovl_places sums them.
 */
PD_FN void ovl_places_join(ovl_ctx *c)
{
    if (c->joined) return;
    c->joined = 1;
    PD_GLOBAL int *key = ovl_ndi(c, OVL_ND_KEY), *end = ovl_ndi(c, OVL_ND_END),
                  *fl = ovl_ndi(c, OVL_ND_FL), *par = ovl_ndi(c, OVL_ND_PAR),
                  *ord = ovl_ndi(c, OVL_ND_ORD);
    PD_GLOBAL pd_real *lam = ovl_ndr(c, OVL_ND_LAM);
    /* the vertices' nodes as the first pass found them (a later pass, degenerate or summed again,
     * tested them again): cleared on every near triangle, then set from the vertex nodes */
    for (int side = 0; side < 2; side++) {
        int nt = side ? c->nb : c->na;
        PD_GLOBAL int *st = side ? c->st_b : c->st_a;
        for (int k = 0; k < nt; k++) {
            PD_GLOBAL const int *v =
                side ? c->in->tb + 3 * c->near_b[k] : c->in->ta + 3 * c->near_a[k];
            for (int q = 0; q < 3; q++)
                st[v[q]] &= OVL_V_READY;
        }
    }
    int m = 0; /* the crossings, listed in ord */
    for (int x = 0; x < c->npts; x++) {
        if (end[x] >= 0) {
            ord[m++] = x;
        } else {
            PD_GLOBAL int *st = (key[x] & 1) ? c->st_b : c->st_a;
            st[key[x] >> 1] |= OVL_V_INSIDE | (x + 1) * OVL_V_NODE;
        }
    }
    for (int gap = m > 64 ? m / 2 : 1; gap > 0; gap = gap == 2 ? 1 : gap * 5 / 11) {
        for (int i = gap; i < m; i++) { /* Shell sort, as ovl_sort */
            int x = ord[i], j = i;
            for (; j >= gap && ovl_node_before(key, end, lam, x, ord[j - gap]); j -= gap)
                ord[j] = ord[j - gap];
            ord[j] = x;
        }
    }
    /* along each crossed edge, from its lower end */
    for (int g = 0; g < m;) {
        int k = key[ord[g]], e = end[ord[g]], side = k & 1;
        int prev = ovl_vertex_node(c, side, k >> 1), prev_in = prev >= 0, last = -1;
        for (; g < m && key[ord[g]] == k && end[ord[g]] == e; g++) {
            int x = ord[g];
            if (last >= 0 && lam[x] == lam[last]) {
                ovl_union(par, x, last); /* the same crossing, from the edge's other face */
                continue;
            }
            if (prev >= 0 && (prev_in || !fl[x])) ovl_union(par, prev, x);
            prev = last = x;
            prev_in = fl[x];
        }
        int ve = ovl_vertex_node(c, side, e);
        if (ve >= 0 && prev >= 0) ovl_union(par, prev, ve);
    }
    /* edges wholly inside */
    for (int side = 0; side < 2; side++) {
        int nt = side ? c->nb : c->na;
        for (int k = 0; k < nt; k++) {
            PD_GLOBAL const int *v =
                side ? c->in->tb + 3 * c->near_b[k] : c->in->ta + 3 * c->near_a[k];
            for (int q = 0; q < 3; q++) {
                int i = v[q], j = v[(q + 1) % 3];
                int ni = ovl_vertex_node(c, side, i), nj = ovl_vertex_node(c, side, j);
                if (ni < 0 || nj < 0) continue;
                if (!ovl_edge_crossed(key, end, ord, m, 2 * (i < j ? i : j) + side, i < j ? j : i))
                    ovl_union(par, ni, nj);
            }
        }
    }
}

/* The places of a hit (o filled but for them): o->places, vol_eff, depth_eff, point_eff. */
PD_STAGE_FN void ovl_places(ovl_ctx *c, ovl_out *o, pd_real vol_abs)
{
    int asked = OVL_PLACES_BUILD && c->places, unknown = c->pts_overflow || c->pts_flip;
    o->places = 1;
    o->places_known = !(asked && unknown);
    o->vol_eff = o->volume;
    o->depth_eff = o->depth;
    o->point_eff = o->centroid;
    if (!asked || unknown || c->npts < 2) return;
    ovl_places_join(c);
    PD_GLOBAL int *par = ovl_ndi(c, OVL_ND_PAR);
    /* each place's volume and eq. 4.19 vector, summed into its root's (the smallest index) */
    PD_GLOBAL pd_real *vol = ovl_ndr(c, OVL_ND_VOL), *elo = ovl_ndr(c, OVL_ND_LO),
                      *ehi = ovl_ndr(c, OVL_ND_HI), *ar = ovl_ndr(c, OVL_ND_AREA),
                      *mo = ovl_ndr(c, OVL_ND_MOM);
    for (int x = 0; x < c->npts; x++) {
        int r = ovl_find(par, x);
        if (r == x) continue;
        vol[r] += vol[x];
        v3_store(ar, r, v3_add(v3_load(ar, r), v3_load(ar, x)));
        v3_store(mo, r, v3_add(v3_load(mo, r), v3_load(mo, x)));
    }
    /* its own normal, unless the pair is degenerate (the first pass's faces shared with the
     * other solid count on one side only; the pair's normal averages both passes) */
    for (int x = 0; x < c->npts; x++) {
        if (par[x] != x) continue;
        pd_v3 a = v3_load(ar, x);
        pd_real an = v3_norm(a);
        v3_store(ar, x, an > PD_R(0) && !c->degenerate ? v3_scale(a, PD_R(1) / an) : o->normal);
        elo[x] = PD_REAL_MAX;
        ehi[x] = -PD_REAL_MAX;
    }
    for (int x = 0; x < c->npts; x++) { /* its depth: its nodes' extent along its normal */
        int r = ovl_find(par, x);
        pd_real s = v3_dot(v3_load(c->pts, x), v3_load(ar, r));
        elo[r] = pd_min(elo[r], s);
        ehi[r] = pd_max(ehi[r], s);
    }
    pd_real s1 = PD_R(0), s2 = PD_R(0), floor = PD_R(100) * PD_EPS * vol_abs;
    pd_v3 fm = v3(0, 0, 0); /* sum of each place's force times its centroid (about origin) */
    int places = 0;
    for (int x = 0; x < c->npts; x++) {
        pd_real v = vol[x], d = ehi[x] - elo[x], cs = v3_dot(v3_load(ar, x), o->normal);
        if (par[x] != x || !(v > floor) || !(d > PD_R(0))) continue;
        places++;
        /* a place pushes along its own normal: its force's part along the pair's (cs), and its
         * stiffness along the pair's normal (cs^2) */
        cs = cs > PD_R(0) ? cs : PD_R(0);
        pd_real f = PD_SQRT(v * d) * cs;
        s1 += f;
        s2 += PD_SQRT(v / d) * cs * cs;
        fm = v3_add(fm, v3_scale(v3_load(mo, x), f / v));
    }
    if (places < 2 || !(s1 > PD_R(0)) || !(s2 > PD_R(0))) return;
    o->places = places;
    o->vol_eff = s1 * s2;
    o->depth_eff = s1 / s2;
    o->point_eff = v3_add(c->origin, v3_scale(fm, PD_R(1) / s1));
}

/*
 * OVL_RESCUE (single precision): a pair whose cusps, even about the centre of the nodes' box,
 * leave its volume within their rounding is summed once more with each place's cusps about that
 * place's own centre. Each cusp is a simplex reaching from its origin to its node, so its volume
 * grows as the cube of that distance: for a pair touching in places a few millimetres apart, each
 * a few hundred micrometres across, about their common centre the cusps are 10^3-10^5 times the
 * volume, which single precision (100 ulps: 1.2e-5) cannot tell from round-off; about their own
 * centres they are of the order of their places. A place's boundary is closed, so its cusps sum to
 * its volume about any origin (in exact arithmetic the result is unchanged). Not for degenerate
 * pairs (their second pass numbers its nodes differently) nor when the nodes overflowed.
 */
PD_STAGE_FN void ovl_rescue(ovl_ctx *c, ovl_sums *sm)
{
    if (!OVL_RESCUE || c->degenerate || c->pts_overflow || c->npts < 2) return;
    int places = c->places;
    if (!places) { /* a pass that stores the nodes' keys and joins each pair's crossings */
        c->places = 1;
        c->npts = 0;
        c->store_pts = 1;
        ovl_pass(c);
        c->store_pts = 0;
        if (c->pts_overflow || c->degenerate) { /* (the same nodes as before: not expected) */
            c->places = places;
            return;
        }
    }
    ovl_places_join(c);
    PD_GLOBAL int *par = ovl_ndi(c, OVL_ND_PAR);
    PD_GLOBAL pd_real *org = ovl_ndr(c, OVL_ND_ORG), *lo = ovl_ndr(c, OVL_ND_AREA);
    /* each place's box, at its root (lo in AREA, hi in ORG); a root is its place's smallest node,
     * so these ascending loops meet it before the place's other nodes */
    int nplaces = 0;
    for (int x = 0; x < c->npts; x++) {
        int r = ovl_find(par, x);
        pd_v3 p = v3_load(c->pts, x), l = r == x ? p : v3_load(lo, r),
              h = r == x ? p : v3_load(org, r);
        nplaces += r == x;
        v3_store(lo, r, v3(pd_min(l.x, p.x), pd_min(l.y, p.y), pd_min(l.z, p.z)));
        v3_store(org, r, v3(pd_max(h.x, p.x), pd_max(h.y, p.y), pd_max(h.z, p.z)));
    }
    if (nplaces < 2) { /* one place: its centre is the nodes' box's, as summed already */
        c->places = places;
        return;
    }
    for (int x = 0; x < c->npts; x++) { /* its centre, for every node of it */
        int r = ovl_find(par, x);
        v3_store(org, x,
                 r == x ? v3_scale(v3_add(v3_load(lo, x), v3_load(org, x)), PD_R(0.5))
                        : v3_load(org, r));
    }
    c->node_org = 1;  /* about the places' centres; the recording pass redoes the nodes' sums */
    c->store_pts = 0; /* of the nodes stored already */
    ovl_sum(c, sm);
    c->node_org = 0;
    c->places = places;
}

/*
 * Lists in out the vertices whose projections reach into the other's half-plane (sgn 1: proj >= e,
 * -1: proj <= e), without a branch, in two runs of independent counts (the halves of the
 * vertices, joined at the end); returns their number. out holds n.
 */
PD_FN int ovl_beyond(PD_GLOBAL const pd_real *proj, int n, pd_real e, int sgn, PD_GLOBAL int *out)
{
    int h = n / 2, n0 = 0, n1 = 0;
    pd_real es = sgn * e;
    for (int i = 0; i < h; i++) {
        out[n0] = i;
        out[h + n1] = h + i;
        n0 += sgn * proj[i] >= es;
        n1 += sgn * proj[h + i] >= es;
    }
    if (n & 1) {
        out[h + n1] = n - 1;
        n1 += sgn * proj[n - 1] >= es;
    }
    for (int k = 0; k < n1; k++)
        out[n0 + k] = out[h + k];
    return n0 + n1;
}

/*
 * The filter's vertex clusters (ovl_in's vc_*, disc_*). Every vertex v of a cluster lies in its
 * disc: within h of the plane through its centre m with unit normal n, and within r of m in that
 * plane. So p(v) = v . dd (+ off for B) lies within h |n . dd| + r |dd x n| of m . dd (+ off):
 * about the patch's sag where dd runs along n, as at the tip of a particle that reaches into the
 * other's half-plane, where a ball's bound r |dd| reached a third of a sphere's radius for 16
 * vertices of a 1280-triangle icosphere, ten times a contact's depth, and bounded nothing. The
 * values computed differ from the exact ones by a few roundings, 3 eps (|v| + |m|) |dd| for the
 * dot products and eps |p| for the offset, and the bounds below allow 64 eps of each. So a
 * cluster whose bounds lie short of the other's half-plane holds no vertex that the filter, with
 * the very values it computes, would find beyond it, and the clusters whose bounds cannot reach
 * a mesh's lowest or highest projection need not be projected to find it.
 */
PD_FN void ovl_cluster_bounds(PD_GLOBAL const pd_real *disc, int ncl, pd_v3 dd, pd_real off,
                              PD_GLOBAL pd_real *bnd, PD_GLOBAL int *done, int *k_hi, int *k_lo)
{
    pd_real dn = v3_norm(dd), tol = PD_R(64) * PD_EPS;
    pd_real hh = -PD_REAL_MAX, ll = PD_REAL_MAX;
    *k_hi = *k_lo = 0;
    for (int k = 0; k < ncl; k++) {
        PD_GLOBAL const pd_real *b = disc + OVL_DISC * k;
        pd_v3 n = v3(b[3], b[4], b[5]);
        pd_real m = b[0] * dd.x + b[1] * dd.y + b[2] * dd.z + off;
        pd_real w = b[7] * PD_FABS(v3_dot(n, dd)) + b[6] * v3_norm(v3_cross(dd, n));
        w = (w + tol * (b[8] * dn + PD_FABS(off))) * (PD_R(1) + tol);
        bnd[2 * k] = m - w;
        bnd[2 * k + 1] = m + w;
        done[k] = 0;
        /* the clusters that reach highest and lowest: the likeliest to hold the extremes */
        if (m + w > hh) *k_hi = k;
        if (m - w < ll) *k_lo = k;
        hh = pd_max(hh, m + w);
        ll = pd_min(ll, m - w);
    }
}

/* The end of cluster k's run in vc (OVL_CLUSTER a cluster, the last one shorter). */
PD_FN int ovl_cluster_end(int k, int nv)
{
    return (k + 1) * OVL_CLUSTER < nv ? (k + 1) * OVL_CLUSTER : nv;
}

/* Projects the vertices of cluster k of v (side 0: A, without an offset; 1: B, plus off) into
 * proj, with the filter's own expressions, and flags the cluster projected. */
PD_FN void ovl_cluster_project(PD_GLOBAL const pd_real *v, PD_GLOBAL const int *vc, int nv, int k,
                               pd_v3 dd, pd_real off, int side, PD_GLOBAL pd_real *proj,
                               PD_GLOBAL int *done)
{
    int end = ovl_cluster_end(k, nv);
    for (int h = k * OVL_CLUSTER; h < end; h++) {
        int i = vc[h];
        pd_real p = v3_dot(v3_load(v, i), dd);
        proj[i] = side ? p + off : p;
    }
    done[k] = 1;
}

/*
 * The lowest and highest projection over all vertices of v, exactly (max and min do not round).
 * The clusters that reach highest and lowest are projected first; the highest projection is at
 * least their highest, so it lies in a cluster whose upper bound reaches that, and likewise the
 * lowest; only those are projected. (The largest of the clusters' lower bounds, taken first,
 * fell a disc's width short of the extreme and let half of a 1280-triangle icosphere's clusters
 * through.)
 */
PD_FN void ovl_cluster_extremes(PD_GLOBAL const pd_real *v, PD_GLOBAL const int *vc,
                                PD_GLOBAL const pd_real *disc, int nv, pd_v3 dd, pd_real off,
                                int side, PD_GLOBAL pd_real *proj, PD_GLOBAL pd_real *bnd,
                                PD_GLOBAL int *done, pd_real *lo, pd_real *hi)
{
    int ncl = ovl_nclusters(nv), k_hi, k_lo;
    pd_real mn = PD_REAL_MAX, mx = -PD_REAL_MAX;
    ovl_cluster_bounds(disc, ncl, dd, off, bnd, done, &k_hi, &k_lo);
    /* j = -2, -1: the highest- and lowest-reaching clusters; then every cluster in order */
    for (int j = -2; j < ncl; j++) {
        int k = j == -2 ? k_hi : j == -1 ? k_lo : j;
        if (done[k] || (j >= 0 && !(bnd[2 * k + 1] >= mx || bnd[2 * k] <= mn))) continue;
        ovl_cluster_project(v, vc, nv, k, dd, off, side, proj, done);
        int end = ovl_cluster_end(k, nv);
        for (int h = k * OVL_CLUSTER; h < end; h++) {
            mn = pd_min(mn, proj[vc[h]]);
            mx = pd_max(mx, proj[vc[h]]);
        }
    }
    *lo = mn;
    *hi = mx;
}

/*
 * ovl_beyond over the clusters that can reach the other's half-plane (sgn 1: A's, proj >= e;
 * -1: B's, proj <= e), projecting those not projected yet; the others hold no such vertex.
 */
PD_FN int ovl_cluster_beyond(PD_GLOBAL const pd_real *v, PD_GLOBAL const int *vc, int nv, pd_v3 dd,
                             pd_real off, int side, PD_GLOBAL pd_real *proj,
                             PD_GLOBAL const pd_real *bnd, PD_GLOBAL int *done, pd_real e, int sgn,
                             PD_GLOBAL int *out)
{
    int n = 0, ncl = ovl_nclusters(nv);
    pd_real es = sgn * e;
    for (int k = 0; k < ncl; k++) {
        if (sgn > 0 ? bnd[2 * k + 1] < e : bnd[2 * k] > e) continue;
        if (!done[k]) ovl_cluster_project(v, vc, nv, k, dd, off, side, proj, done);
        int end = ovl_cluster_end(k, nv);
        for (int h = k * OVL_CLUSTER; h < end; h++) {
            int i = vc[h];
            out[n] = i;
            n += sgn * proj[i] >= es;
        }
    }
    return n;
}

/*
 * eq. 5.4's projections of all n vertices of v on dd into proj (side 0: A's, as they are; 1: B's,
 * plus off), with the running extreme *ext (A's highest, B's lowest) and the largest magnitude
 * *scale. These loops are the part of a pair's cost that grows with the meshes whatever the
 * overlap (a quarter of a 1280-triangle icosphere pair's time): locals, not the context's fields
 * (which the stores might alias), and max instructions rather than branches keep them to a few
 * instructions a vertex. Two vertices a round into two sets of extremes halve the chain of
 * dependent max instructions that bounded them; max and min are exact, so the extremes do not
 * depend on the order. side is a constant where this inlines (PD_FN), so it costs no branch.
 */
PD_FN void ovl_project_all(PD_GLOBAL const pd_real *v, int n, pd_v3 dd, pd_real off, int side,
                           PD_GLOBAL pd_real *proj, pd_real *ext, pd_real *scale)
{
    pd_real e = *ext, eo = e, sc = *scale, so = sc;
    int i = 0;
    for (; i + 1 < n; i += 2) {
        pd_real p = v3_dot(v3_load(v, i), dd), q = v3_dot(v3_load(v, i + 1), dd);
        p = side ? p + off : p;
        q = side ? q + off : q;
        proj[i] = p;
        proj[i + 1] = q;
        e = side ? pd_min(e, p) : pd_max(e, p);
        eo = side ? pd_min(eo, q) : pd_max(eo, q);
        sc = pd_max(sc, PD_FABS(p));
        so = pd_max(so, PD_FABS(q));
    }
    if (i < n) {
        pd_real p = v3_dot(v3_load(v, i), dd);
        p = side ? p + off : p;
        proj[i] = p;
        e = side ? pd_min(e, p) : pd_max(e, p);
        sc = pd_max(sc, PD_FABS(p));
    }
    *ext = side ? pd_min(e, eo) : pd_max(e, eo);
    *scale = pd_max(sc, so);
}

/*
 * One evaluation of the overlap (ovl_compute). Returns 0 when the predicates were found to
 * disagree about the geometry (the overlap's surface does not close), 1 otherwise; *pad: the
 * resolution it worked at; *sides: which of a degenerate pair's passes closed on their own
 * (ovl_sums.closed); *faces: which of them closed face by face (ovl_sums.faces, both passes
 * taken). one_side 1 (2): a degenerate pair takes its first pass alone, with B displaced by
 * +eps w (-eps w), not the average with the other.
 */
PD_STAGE_FN int ovl_compute_try(const ovl_in *in, ovl_out *o, pd_real *pad_out, int one_side,
                                int *sides, int *faces)
{
    *pad_out = PD_R(0);
    *sides = *faces = 0;
    ovl_ctx cx;
    ovl_ctx *c = &cx;
    c->one_pass = one_side != 0;
    c->wneg = one_side == 2;
    c->in = in;
    c->filter = !(in->flags & OVL_NO_FILTER);
    c->kept_a = in->iscr;
    c->kept_b = in->iscr + in->nta;
    c->near_a = c->kept_b + in->ntb;
    c->near_b = c->near_a + in->nta;
    c->st_a = c->near_b + in->ntb;
    c->st_b = c->st_a + in->nva;
    c->hits = c->st_b + in->nvb;
    c->strip_a.ord = c->hits + in->ntb;
    c->strip_b.ord = c->strip_a.ord + in->nta;
    c->sweep_ord = c->strip_b.ord + in->ntb;
    c->xa = c->sweep_ord + in->ntb;
    c->xb = c->xa + in->nta;
    c->slot_a = c->xb + in->ntb;
    c->slot_b = c->slot_a + in->nta;
    c->queue = c->slot_b + in->ntb;
    c->done_a = c->queue + 2 * (in->nva + in->nvb);
    c->done_b = c->done_a + ovl_nclusters(in->nva);
    c->strip_a.built = c->strip_b.built = 0; /* built by the first cast that needs one */
    c->strip_a.eu = c->strip_b.eu = v3(0, 0, 0);
    c->strip_a.width = c->strip_b.width = PD_R(0);
    c->proj_a = in->rscr;
    c->proj_b = in->rscr + in->nva;
    c->vat = c->proj_b + in->nvb;
    c->vbt = c->vat + 3 * in->nva;
    c->pts = c->vbt + 3 * in->nvb;
    c->ucache = c->pts + 3 * in->pts_cap;
    c->strip_a.key = c->ucache + OVL_TRI_CACHE * in->ntb;
    c->strip_b.key = c->strip_a.key + in->nta;
    c->sweep_key = c->strip_b.key + in->ntb;
    c->bnd_a = c->sweep_key + in->ntb;
    c->bnd_b = c->bnd_a + 2 * ovl_nclusters(in->nva);
    c->sweep = c->sweep_axis = 0;
    c->sweep_width = PD_R(0);
    c->npts = c->pts_overflow = c->pts_flip = 0;
    c->store_pts = 1;
    /* OVL_PLACES: its scratch follows the usual */
    c->places = OVL_PLACES_BUILD && (in->flags & OVL_PLACES) != 0;
    c->rec = c->inode = c->joined = c->node_org = 0;
    c->cur_node = -1;
    c->nd_i = in->iscr + ovl_iscratch_len(in->nta, in->ntb, in->nva, in->nvb);
    c->nd_r = in->rscr + ovl_rscratch_len(in->nta, in->ntb, in->nva, in->nvb, in->pts_cap);
    c->flip = c->degenerate = c->depth_mode = 0;
    c->pad = PD_R(0);
    c->ka = c->kb = c->na = c->nb = 0;
    c->origin_in_b = -1;
    int open_b = (in->flags & OVL_OPEN_B) != 0;

    /* eq. 5.3: the direction between the centres, on a grid (ovl_dir_grid) */
    pd_v3 dc = v3_sub(in->cb, in->ca);
    c->d = v3_dot(dc, dc) > PD_R(0) ? ovl_dir_grid(v3_unit(dc)) : v3(0, 0, 1);
    pd_v3 d = c->d;
    /* d expressed in B's frame, so B's vertices are projected before being transformed */
    pd_v3 db = v3(in->rot[0] * d.x + in->rot[3] * d.y + in->rot[6] * d.z,
                  in->rot[1] * d.x + in->rot[4] * d.y + in->rot[7] * d.z,
                  in->rot[2] * d.x + in->rot[5] * d.y + in->rot[8] * d.z);
    pd_real trd = in->tr[0] * d.x + in->tr[1] * d.y + in->tr[2] * d.z;

    /* eq. 5.4: extents; eq. 5.5: keep the triangles reaching into the other's half-plane */
    pd_real e1 = -PD_REAL_MAX, e2 = PD_REAL_MAX, scale = PD_R(0);
    pd_v3 da = v3_scale(d, in->sa); /* A's projections are (sa v) . d, for the padded filter */
    /*
     * With the vertex clusters, only those that can hold an extreme are projected here (the
     * scale wants both extremes of each mesh) and later those that can reach the other's
     * half-plane: at a contact's depth a few clusters of each mesh, where ovl_project_all
     * projects every vertex. The same values come out, so the same triangles are kept.
     */
    c->clustered = c->filter && !open_b && in->vt_a_off && in->vt_b_off && in->vc_a && in->vc_b &&
                   in->disc_a && in->disc_b && in->nva + in->nvb >= OVL_CLUSTER_MIN;
    if (c->clustered) {
        pd_real amin, bmax; /* for the scale: the largest projection's magnitude */
        ovl_cluster_extremes(in->va, in->vc_a, in->disc_a, in->nva, da, PD_R(0), 0, c->proj_a,
                             c->bnd_a, c->done_a, &amin, &e1);
        ovl_cluster_extremes(in->vb, in->vc_b, in->disc_b, in->nvb, db, trd, 1, c->proj_b, c->bnd_b,
                             c->done_b, &e2, &bmax);
        scale = pd_max(pd_max(PD_FABS(amin), PD_FABS(e1)), pd_max(PD_FABS(e2), PD_FABS(bmax)));
    } else {
        ovl_project_all(in->va, in->nva, da, PD_R(0), 0, c->proj_a, &e1, &scale);
        ovl_project_all(in->vb, in->nvb, db, trd, 1, c->proj_b, &e2, &scale);
    }
    /*
     * The half-planes are widened by OVL_CULL resolutions (OVL_SNAP L, L the largest coordinate
     * of the kept parts: known only once they are kept). B's projections are computed in B's
     * frame, and a contact that touches to within the predicates' ties must reach the symbolic
     * tests. The first try takes the projections' largest magnitude for L, doubled; where the
     * kept parts turn out to reach further (elongated shapes across d), the filter is run again
     * with their L.
     */
    pd_real pad = PD_R(2 * OVL_CULL) * OVL_SNAP * scale;
refilter:
    c->e1 = e1 + pad;
    c->e2 = e2 - pad;
    c->pad = pad;
    c->ka = c->kb = 0;
    /* B open: its local part's lowest vertex does not bound the wall's solid inside A's cube, so
     * A is not filtered (every A triangle kept); B's triangles still must reach below e1 */
    if (open_b) c->e2 = -PD_REAL_MAX;
    if (c->filter && !(c->e1 > c->e2)) { /* half-planes disjoint: no volume */
        ovl_miss(o, c);
        return 1;
    }
    /* A triangle is kept from its first corner that reaches into the other's half-plane, so
     * each is listed once; the lists are sorted so that the cusps are summed in the same order
     * as without the filter (identical results). */
    /* The corners reaching into the other's half-plane are listed first, without a branch
     * (in queue, free until ovl_resolve): which of an icosphere's corners do is scattered over
     * its vertex order, and a branch per corner mispredicted at each of them. */
    PD_GLOBAL int *cand = c->queue;
    if (c->filter && in->vt_a_off && !open_b) {
        int nc = c->clustered ? ovl_cluster_beyond(in->va, in->vc_a, in->nva, da, PD_R(0), 0,
                                                   c->proj_a, c->bnd_a, c->done_a, c->e2, 1, cand)
                              : ovl_beyond(c->proj_a, in->nva, c->e2, 1, cand);
        for (int h = 0; h < nc; h++) {
            int i = cand[h];
            for (int k = in->vt_a_off[i]; k < in->vt_a_off[i + 1]; k++) {
                int t = in->vt_a[k];
                PD_GLOBAL const int *v = in->ta + 3 * t;
                int first = v[0] == i   ? 1
                            : v[1] == i ? !(ovl_proj(c, 0, v[0]) >= c->e2)
                                        : !(ovl_proj(c, 0, v[0]) >= c->e2) &&
                                              !(ovl_proj(c, 0, v[1]) >= c->e2);
                if (first) c->kept_a[c->ka++] = t;
            }
        }
        ovl_sort(c->kept_a, c->ka);
    } else {
        for (int t = 0; t < in->nta; t++) {
            PD_GLOBAL const int *v = in->ta + 3 * t;
            pd_real mx = pd_max(pd_max(c->proj_a[v[0]], c->proj_a[v[1]]), c->proj_a[v[2]]);
            if (!c->filter || mx >= c->e2) c->kept_a[c->ka++] = t;
        }
    }
    if (c->filter && in->vt_b_off) {
        int nc = c->clustered ? ovl_cluster_beyond(in->vb, in->vc_b, in->nvb, db, trd, 1, c->proj_b,
                                                   c->bnd_b, c->done_b, c->e1, -1, cand)
                              : ovl_beyond(c->proj_b, in->nvb, c->e1, -1, cand);
        for (int h = 0; h < nc; h++) {
            int j = cand[h];
            for (int k = in->vt_b_off[j]; k < in->vt_b_off[j + 1]; k++) {
                int u = in->vt_b[k];
                PD_GLOBAL const int *v = in->tb + 3 * u;
                int first = v[0] == j   ? 1
                            : v[1] == j ? !(ovl_proj(c, 1, v[0]) <= c->e1)
                                        : !(ovl_proj(c, 1, v[0]) <= c->e1) &&
                                              !(ovl_proj(c, 1, v[1]) <= c->e1);
                if (first) c->kept_b[c->kb++] = u;
            }
        }
        ovl_sort(c->kept_b, c->kb);
    } else {
        for (int u = 0; u < in->ntb; u++) {
            PD_GLOBAL const int *v = in->tb + 3 * u;
            pd_real mn = pd_min(pd_min(c->proj_b[v[0]], c->proj_b[v[1]]), c->proj_b[v[2]]);
            if (!c->filter || mn <= c->e1) c->kept_b[c->kb++] = u;
        }
    }
    if (c->ka == 0 || c->kb == 0) {
        ovl_miss(o, c);
        return 1;
    }
    /* B's vertex states, before the transforms mark theirs READY: only the kept triangles'
     * corners are ever looked at (A's are cleared by each pass) */
    for (int l = 0; l < c->kb; l++)
        for (int q = 0; q < 3; q++)
            c->st_b[in->tb[3 * c->kept_b[l] + q]] = 0;
    pd_v3 alo = v3(PD_REAL_MAX, PD_REAL_MAX, PD_REAL_MAX), ahi = v3_scale(alo, PD_R(-1));
    pd_v3 blo = alo, bhi = ahi;
    for (int k = 0; k < c->ka; k++) {
        PD_GLOBAL const int *v = in->ta + 3 * c->kept_a[k];
        for (int q = 0; q < 3; q++) {
            /* A's kept corners, scaled once (a corner may be stored more than once: same value) */
            pd_v3 x = v3_scale(v3_load(in->va, v[q]), in->sa);
            v3_store(c->vat, v[q], x);
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
    if (c->filter && pad < OVL_CULL * OVL_SNAP * lsc) {
        pad = PD_R(2 * OVL_CULL) * OVL_SNAP * lsc;
        goto refilter;
    }
    c->pad = OVL_SNAP * lsc;

    /*
     * Every node of A n B lies in both solids' parts inside the slab, and a solid's part inside
     * the slab lies in the box of its kept triangles (a ray from an inside point leaves the solid
     * through a kept triangle). So only triangles meeting the intersection of the two boxes can
     * emit cusps, and a vertex outside it is outside the other solid.
     */
    pd_real cull = OVL_CULL * c->pad;
    pd_v3 padv = v3(cull, cull, cull);
    c->alo = v3_sub(alo, padv);
    c->ahi = v3_add(ahi, padv);
    c->blo = v3_sub(blo, padv);
    c->bhi = v3_add(bhi, padv);
    c->box_lo =
        v3(pd_max(alo.x, blo.x) - cull, pd_max(alo.y, blo.y) - cull, pd_max(alo.z, blo.z) - cull);
    c->box_hi =
        v3(pd_min(ahi.x, bhi.x) + cull, pd_min(ahi.y, bhi.y) + cull, pd_min(ahi.z, bhi.z) + cull);
    if (open_b) { /* the wall's solid reaches beyond its local triangles' box: A's box bounds */
        c->box_lo = c->alo;
        c->box_hi = c->ahi;
    }
    if (c->filter &&
        (c->box_lo.x > c->box_hi.x || c->box_lo.y > c->box_hi.y || c->box_lo.z > c->box_hi.z)) {
        ovl_miss(o, c);
        return 1;
    }
    for (int k = 0; k < c->ka; k++) {
        int t = c->kept_a[k];
        ovl_tri T;
        ovl_tri_make(&T, ovl_va(c, in->ta[3 * t]), ovl_va(c, in->ta[3 * t + 1]),
                     ovl_va(c, in->ta[3 * t + 2]), PD_R(0));
        if (!c->filter || ovl_box_meets(c, &T)) c->near_a[c->na++] = t;
    }
    pd_real hpad = PD_R(OVL_CULL / 2) * c->pad; /* half the cull margin, as ovl_pass pads T */
    c->nblo = v3(PD_REAL_MAX, PD_REAL_MAX, PD_REAL_MAX);
    c->nbhi = v3_scale(c->nblo, PD_R(-1));
    for (int l = 0; l < c->kb; l++) {
        int u = c->kept_b[l];
        ovl_tri U;
        ovl_tri_make(&U, ovl_vb(c, in->tb[3 * u]), ovl_vb(c, in->tb[3 * u + 1]),
                     ovl_vb(c, in->tb[3 * u + 2]), PD_R(0));
        if (c->filter && !ovl_box_meets(c, &U)) continue;
        if (open_b) {
            c->nblo = v3(pd_min(c->nblo.x, U.lo.x - hpad), pd_min(c->nblo.y, U.lo.y - hpad),
                         pd_min(c->nblo.z, U.lo.z - hpad));
            c->nbhi = v3(pd_max(c->nbhi.x, U.hi.x + hpad), pd_max(c->nbhi.y, U.hi.y + hpad),
                         pd_max(c->nbhi.z, U.hi.z + hpad));
        }
        /* cache what the pair loop needs of U, with the box padded by half the cull margin */
        ovl_tri_edges(&U);
        PD_GLOBAL pd_real *uc = c->ucache + OVL_TRI_CACHE * c->nb;
        pd_v3 v[6] = {U.nraw,
                      v3_sub(U.lo, v3(hpad, hpad, hpad)),
                      v3_add(U.hi, v3(hpad, hpad, hpad)),
                      U.me[0],
                      U.me[1],
                      U.me[2]};
        for (int q = 0; q < 6; q++)
            v3_store(uc, q, v[q]);
        uc[18] = ovl_plane_tol(c, v3_norm(U.nraw));
        c->near_b[c->nb++] = u;
    }
    for (int k = 0; k < c->na; k++) /* for ovl_resolve */
        c->slot_a[c->near_a[k]] = k;
    for (int l = 0; l < c->nb; l++)
        c->slot_b[c->near_b[l]] = l;
    if (c->filter && c->nb >= OVL_STRIP_MIN) {
        /* the pair loop's sweep (ovl_ctx), across the contact */
        int a = ovl_least_axis(d);
        pd_real width = PD_R(0);
        for (int l = 0; l < c->nb; l++) {
            PD_GLOBAL const pd_real *uc = c->ucache + OVL_TRI_CACHE * l;
            c->sweep_key[l] = uc[3 + a];
            c->sweep_ord[l] = l;
            width = pd_max(width, uc[6 + a] - uc[3 + a]);
        }
        ovl_sort_keyed(c->sweep_key, c->sweep_ord, c->nb);
        c->sweep = 1;
        c->sweep_axis = a;
        c->sweep_width = width;
    }

    c->origin = (in->flags & OVL_ORIGIN) ? in->org : v3(0, 0, 0);
    ovl_sums sm;
    ovl_sum(c, &sm);
    /*
     * Every cusp is a simplex reaching from the origin (A's centre) to a node, so each is of the
     * order of a particle's volume however small the overlap, and their sum is known only to a
     * few ulps of their magnitudes (vol_abs). A corner pressed into a face has a volume ~ depth^3:
     * in single precision, summed about A's centre, it was lost in that rounding until ~2.5 % of
     * a size deep (a Schönhardt corner in another's notch, tests/physics/test_sim.c). When the
     * sum is that small against its terms, the cusps are summed again about the centre of the
     * nodes' box, which holds the overlap (a polyhedron lies in its vertices' hull): each cusp
     * is then of the order of the overlap. The sum's rounding is about eps vol_abs, so the
     * volume's relative error is about eps vol_abs / vol, and the centroid's error that times
     * the cusps' reach from the origin. Double precision sums again below 1e-8 of the terms
     * (OVL_RESUM: errors up to ~1e-8 of the volume, and ~2e-8 of the reach in the centroid): a
     * 1 mm cube wholly inside a 10 m one, summed about the big one's centre at 2.4e-11 of the
     * terms, came out 5.4e-6 too large with its centroid 0.5 mm off
     * (tests/physics/test_overlap.c, small_solid_inside_a_large_one). At 1e-6, a tenth of
     * bench/overlap's Schonhardt pairs (a corner 1 % deep) summed twice, +8 % of instructions;
     * at 1e-8, 1 %. Single precision's 1e4 eps is 1.2e-3: nearly every touching pair of a
     * settled bed takes it (bench/RESULTS.md), unless the caller gives a better first origin
     * (OVL_ORIGIN).
     */
    int nodes_known = c->npts > 0 && !c->pts_overflow;
    pd_v3 nlo = v3(0, 0, 0), nhi = nlo; /* the nodes' box */
    if (nodes_known) {
        nlo = nhi = v3_load(c->pts, 0);
        for (int q = 1; q < c->npts; q++) {
            pd_v3 p = v3_load(c->pts, q);
            nlo = v3(pd_min(nlo.x, p.x), pd_min(nlo.y, p.y), pd_min(nlo.z, p.z));
            nhi = v3(pd_max(nhi.x, p.x), pd_max(nhi.y, p.y), pd_max(nhi.z, p.z));
        }
    }
    if (!(sm.vol > OVL_RESUM * sm.vol_abs) && nodes_known) {
        c->origin = v3_scale(v3_add(nlo, nhi), PD_R(0.5));
        c->store_pts = 0; /* the same nodes */
        ovl_sum(c, &sm);
    }
    if (!(sm.vol > PD_R(100) * PD_EPS * sm.vol_abs)) ovl_rescue(c, &sm);
    pd_real vol = sm.vol, smag = sm.smag;
    pd_v3 mom = sm.mom, sdiff = sm.sdiff;
    int degenerate = c->degenerate;
    *pad_out = c->pad;
    /*
     * The overlap's surface is A's faces inside B and B's faces inside A, and a closed surface's
     * area vectors sum to 0: area_a = -area_b, to the sums' rounding. Where they do not, the
     * predicates described two different geometries (ties broken one way by some and decided by
     * the coordinates in others: faces near-coplanar in two directions at once, each just inside
     * the tie band; bench/degenerate), and the cusps' sums are no overlap at all: in a lattice of
     * stacked cubes one contact 1.2e-7 m deep got its centroid 34 m away and a depth of 1 mm.
     * The misses below are no answer either when the surface is open: ovl_compute tries again
     * (two boxes with faces coplanar in z and 1.9e-14 m apart in x overlapping by 0.69 m^3 came
     * out as a miss, the sum exceeding the nodes' box).
     */
    int closed = ovl_closes(sm.open, smag);
    /*
     * A degenerate pair's two passes describe configurations an infinitesimal apart, each within
     * the tie band (2 pad) of the coordinates, so their volumes differ by at most about 4 pad
     * times the overlap's surface, which is at least |area_a| + |area_b|, plus the sums'
     * rounding. Beyond that the predicates described two geometries even where each pass closed:
     * in a single-precision lattice of cubes the -w pass of a resting contact summed 4.1e-10 m^3
     * against the +w pass's 1.3e-10 (double: 1.3e-10), and the mean was twice the volume with a
     * 16-degree normal (tests/physics/test_overlap.c, single_precision_passes_that_disagree,
     * which ovl_faces_close also catches). Of eight variants of that lattice run in single
     * precision by a build without this check, one was thrown apart (kinetic energy 0.06 J
     * against 1e-6 J) and two had steps with a depth of a whole side; with it, none. In double
     * precision it mends the last wrong one of bench/degenerate's 48 000 near-coplanar box pairs
     * (bench/RESULTS.md, 2026-12-07 (later still)). ovl_compute takes such a pair again on B
     * moved.
     */
    if (sm.vdiff > PD_R(4) * c->pad * sm.surf + PD_R(1000) * PD_EPS * sm.vol_abs) closed = 0;
    *sides = degenerate ? sm.closed : 0;
    *faces = degenerate && !c->one_pass ? sm.faces : 0;
    /* touching, or round-off of a touching contact: within 100 ulps of the cusps' magnitudes */
    if (!(vol > PD_R(100) * PD_EPS * sm.vol_abs)) {
        ovl_miss(o, c);
        return closed;
    }
    /*
     * A n B is a polyhedron whose corners are the nodes, so it lies in their box. A volume beyond
     * the box's (and the sums' rounding) means the predicates disagreed about the geometry: seen
     * in single precision for faces resting on a wall's within about the resolution pad, where
     * some corners are snapped onto the other's plane and others not, and the cusps no longer
     * close a surface (a 2 cm prism got a force of 3 600 N). No force can be taken from such a
     * sum: ovl_compute takes the overlap again on B moved, and where that does not help either,
     * the contact counts as not yet touching, as when it lies within the resolution.
     */
    if (nodes_known) {
        pd_v3 ext = v3_sub(nhi, nlo);
        if (vol > ext.x * ext.y * ext.z + PD_R(1000) * PD_EPS * sm.vol_abs) {
            ovl_miss(o, c);
            return 0;
        }
    }
    /* The same of the two solids' boxes' intersection (their kept parts' with the filter), which
     * holds A n B whatever the nodes: without the filter, two boxes with faces coplanar or
     * within the tie band along all three axes gave a closed surface of 2.5 times their overlap,
     * whose stray nodes had widened the nodes' box (bench/degenerate). */
    pd_v3 bext = v3_sub(c->box_hi, c->box_lo);
    if (vol > bext.x * bext.y * bext.z + PD_R(1000) * PD_EPS * sm.vol_abs) {
        ovl_miss(o, c);
        return 0;
    }
    /*
     * And of its surface: a solid of surface area S holds at most S^(3/2) / (6 sqrt(pi)) (the
     * isoperimetric inequality), and S is at most smag, each face's area being the sum of its
     * cusps' signed areas; smag is the mean of a degenerate pair's two passes', whose bounds are
     * then at most 2^(3/2) times that of the mean. A pass whose few cusps enclose more was no
     * solid: in a single-precision lattice of cubes, a pass taken alone summed 6.8e-16 m^3 over
     * cusps of 1.2e-12 m^2 in all (a bound of 3.4e-19 m^3), with a normal along the faces it
     * rested on, and the depth along that normal was the cube's whole side
     * (tests/physics/test_single_narrow.c, volume_beyond_its_surface; bench/RESULTS.md,
     * 2026-12-07, night).
     */
    if (vol > PD_R(0.266) * smag * PD_SQRT(smag) + PD_R(1000) * PD_EPS * sm.vol_abs) {
        ovl_miss(o, c);
        return 0;
    }
    /*
     * A n B lies in its nodes' box, and so does its centroid. One computed outside the box by
     * more than the box's own extent, a resolution and the rounding of the moment's sum was
     * divided out of sums that describe no solid: in a single-precision lattice of cubes, a
     * first try that closed summed 5.6e-15 m^3 for a pair 3e-7 m deep (double: 1.4e-11), and its
     * centroid came out 12 m away from nodes 2 cm apart; the torque about it spun two cubes
     * apart (tests/physics/test_single_narrow.c, centroid_beyond_its_nodes; bench/RESULTS.md,
     * 2026-12-07, night). The moment's terms reach to the coordinates' magnitude L
     * (pad = OVL_SNAP L), so its sum's rounding over the volume, taken as the guards above take
     * 1000 ulps, can move a thin overlap's centroid by millimetres in single precision, and is
     * allowed for.
     */
    pd_v3 cen = v3_scale(mom, PD_R(1) / vol);
    if (nodes_known) {
        pd_real slack = c->pad + PD_R(2000) * PD_EPS * sm.vol_abs * (c->pad / OVL_SNAP) / vol;
        pd_v3 ext = v3_add(v3_sub(nhi, nlo), v3(slack, slack, slack));
        pd_v3 lo = v3_sub(nlo, ext), hi = v3_add(nhi, ext);
        if (!(cen.x >= lo.x && cen.x <= hi.x && cen.y >= lo.y && cen.y <= hi.y && cen.z >= lo.z &&
              cen.z <= hi.z)) {
            ovl_miss(o, c);
            return 0;
        }
    }
    o->hit = 1;
    o->degenerate = degenerate;
    o->kept_a = c->na;
    o->kept_b = c->nb;
    o->volume = vol;
    o->centroid = cen;
    /* eq. 4.19 from both sides: A's faces inside B minus B's faces inside A (equal and opposite
     * in exact arithmetic; faces shared by both cancel). Where one solid lies wholly inside the
     * other, the faces inside form a closed surface and the sum is rounding noise against its
     * terms (coincident shapes have none at all): fall back to the centre line, then to +z, so
     * the normal is still deterministic and opposite when A and B swap. */
    pd_real sn = v3_norm(sdiff);
    o->area = PD_R(0.5) * sn;
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
        c->flip = c->pts_flip; /* the pass whose nodes were stored */
        c->depth_mode = 1;
        ovl_pass(c);
    }
    o->depth = c->hi > c->lo ? c->hi - c->lo : PD_R(0);
    ovl_places(c, o, sm.vol_abs);
    return closed;
}

/*
 * o becomes the mean of o and p, two overlaps (hits) of B moved by +u and by -u (ovl_compute):
 * volume, moments and area vectors are smooth in the displacement, so their means are the
 * overlap's at u = 0 up to terms in u^2.
 */
PD_FN void ovl_out_mean(ovl_out *o, const ovl_out *p)
{
    pd_real v = o->volume + p->volume, ve = o->vol_eff + p->vol_eff;
    if (v > PD_R(0))
        o->centroid =
            v3_scale(v3_add(v3_scale(o->centroid, o->volume), v3_scale(p->centroid, p->volume)),
                     PD_R(1) / v);
    if (ve > PD_R(0))
        o->point_eff =
            v3_scale(v3_add(v3_scale(o->point_eff, o->vol_eff), v3_scale(p->point_eff, p->vol_eff)),
                     PD_R(1) / ve);
    pd_v3 n = v3_add(v3_scale(o->normal, o->area), v3_scale(p->normal, p->area));
    pd_real nn = v3_norm(n);
    if (nn > PD_R(0)) o->normal = v3_scale(n, PD_R(1) / nn);
    o->volume = PD_R(0.5) * v;
    o->vol_eff = PD_R(0.5) * ve;
    o->depth = PD_R(0.5) * (o->depth + p->depth);
    o->depth_eff = PD_R(0.5) * (o->depth_eff + p->depth_eff);
    o->area = PD_R(0.5) * (o->area + p->area);
    o->places = o->places > p->places ? o->places : p->places;
    o->places_known &= p->places_known;
    o->degenerate |= p->degenerate;
}

/*
 * Single precision: whether a closed try of B at sh (*o, with ovl_compute_try's *faces) can be
 * taken, every face of its passes closing (ovl_faces_close). A degenerate try one of whose two
 * passes' faces close is taken again from that pass alone (*o). Double precision's tie band is
 * too narrow for open faces (ovl_faces_close): always.
 */
PD_FN int ovl_faces_good(const ovl_in *sh, ovl_out *o, int faces)
{
#if PD_DOUBLE
    (void)sh, (void)o, (void)faces;
    return 1;
#else
    if (!o->hit || !o->degenerate || faces == 3) return 1;
    pd_real pad;
    int sides, f2;
    ovl_out alone;
    if ((faces == 1 || faces == 2) && ovl_compute_try(sh, &alone, &pad, faces, &sides, &f2) &&
        alone.hit) {
        *o = alone;
        return 1;
    }
    return 0;
#endif
}

/*
 * The overlap of A and B: volume, centroid, normal and depth (section 4.2). Where the
 * predicates disagree (ovl_compute_try: the surface does not close, or the volume exceeds the
 * nodes' box), B is moved by 8 resolutions along one of three fixed
 * directions of unrelated components and the overlap taken again: offsets that lay at the edge
 * of the tie band (2 resolutions) are then either well inside it or well out of it. The last
 * three directions also turn d, the filter's direction and the rays', by ~0.3 rad (any d bounds
 * the filter): without the filter, two boxes 3e-13 m from coplanar summed to a closed half of one
 * box in every try, a corner's side decided by one ray along d.
 *
 * Each direction is taken both ways, B moved by +u and by -u, and where both agree the answer is
 * their mean (ovl_out_mean), in which the displacement cancels to first order; where one way
 * touches and the other does not, the pair lies within the move of touching and counts as not
 * touching yet (the mean of a miss and a hit gave a resting Schonhardt prism on a meshed floor a
 * kick of 0.016 m/s in single precision, tests/physics/test_sim.c,
 * single_precision_flat_face_on_a_meshed_floor). 8 resolutions are
 * 5e-16 m for 2 cm particles in double precision, but ~1.5e-6 m in single, a fifth to a half of
 * a resting contact's depth: one way alone came out 10-86 % off in volume for 27 of 567 resting
 * contacts of a lattice of cubes settling in single precision (bench/RESULTS.md, 2026-12-06
 * evening). A direction that agrees one way only is kept for last. In single precision both
 * ways must also agree on the normal, to 0.1 rad: B moved 8 resolutions away from a contact 9
 * resolutions deep left a sliver of 1.8e-12 m^3 whose normal was rounding noise (-x for a
 * contact along z), and the mean took its depth, the cube's whole side, for half the answer's
 * (tests/physics/test_overlap.c, single_precision_moves_that_disagree). Double precision's
 * moves are 5e-16 m, and its ways may differ in normal by a shared face counted one way: requiring
 * the agreement there lost 55 of 48 000 near-coplanar box pairs (bench/degenerate).
 *
 * Where no direction agrees both ways, a degenerate pair one of whose two passes (B displaced by
 * +eps w and by -eps w) closed on its own in the first try is taken from that pass alone: its
 * combinatorics describe one configuration, B displaced, whose volume and centroid are the
 * exact ones at eps = 0, and its normal counts a face shared with the other solid on one side
 * only (what the second pass is averaged in for). Resting faces nearly parallel, a few tenths of
 * a milliradian apart, with corners within the tie band of the other's face, lead there in
 * single precision, where a resolution is ~2e-7 m for 2 cm particles and 8 of them move B by
 * a fifth of a resting contact's depth: 11 of the 48 contacts of a settled lattice of cubes
 * (examples/cube_lattice.json) had each of their tries' -w or +w pass open, and were lost
 * (tests/physics/test_overlap.c, resting_cubes_in_single_precision). Failing that, the first
 * direction that agreed one way is the answer; where none did, the pair counts as not touching
 * this step.
 *
 * Single precision also asks every answer for closed faces (ovl_faces_close, ovl_faces_good),
 * not only closed sums. Its tie band is wide enough for a pass to leave both solids' faces open
 * alike, and such a pass's normal can be anything: in lattices of cubes landing, answers whose
 * sums closed and whose faces did not were 0.0088 to 0.31 rad off, with depths along them 34 to
 * 3 900 times the contact's (tests/physics/test_single_narrow.c). So there:
 * - a first try whose faces are open goes on to the moves, and a way whose faces are open does
 *   not agree;
 * - a direction one of whose ways has its faces closed keeps that way as a one-way answer;
 * - the fallbacks are, in order, the first try's pass alone where that pass's faces close, and a
 *   one-way answer whose faces close (biased by the move to first order: 8 resolutions of depth,
 *   a fifth to a half of a resting contact's, in volume and depth);
 * - answers with open faces are not taken: the pair counts as not touching this step.
 * Over sixteen variants of examples/cube_lattice.json in single precision, 0.4 s each, steps
 * whose largest overlap exceeded 0.05 of a size went from 8 to 0 (bench/RESULTS.md, 2026-12-07,
 * night). Double precision's faces always close, so its answers are the ones above.
 */
PD_FN void ovl_compute(const ovl_in *in, ovl_out *o)
{
    pd_real pad = PD_R(0);
    int sides = 0, first, faces0, faces;
    if (ovl_compute_try(in, o, &pad, 0, &first, &faces0)) {
        if (ovl_faces_good(in, o, faces0)) return;
    }
    /* the first direction that answered one way with its faces closed (double precision's
     * always are) */
    ovl_out lone, back;
    int lone_good = 0;
    const pd_real dir[9] = {PD_R(0.5377), PD_R(0.7183), PD_R(0.4412),  PD_R(-0.6626), PD_R(0.2361),
                            PD_R(0.7107), PD_R(0.3119), PD_R(-0.8231), PD_R(0.4745)};
    ovl_in sh = *in;
    pd_real span = v3_norm(v3_sub(in->cb, in->ca));
    for (int k = 0; k < 6; k++) {
        pd_real m = PD_R(8) * pad, pad_back;
        int kd = k % 3;
        pd_v3 e = v3(dir[3 * kd], dir[3 * kd + 1], dir[3 * kd + 2]), u = v3_scale(e, m);
        /* the last three also turn d (the filter's direction and the rays') by ~0.3 rad: the
         * centre line moves with B by u and sideways by the turn, the same both ways */
        pd_v3 turn = v3_scale(e, k < 3 ? PD_R(0) : PD_R(0.3) * span);
        sh.tr[0] = in->tr[0] + u.x;
        sh.tr[1] = in->tr[1] + u.y;
        sh.tr[2] = in->tr[2] + u.z;
        sh.cb = v3_add(v3_add(in->cb, u), turn);
        if (!ovl_compute_try(&sh, o, &pad, 0, &sides, &faces)) continue;
        int good = ovl_faces_good(&sh, o, faces);
        sh.tr[0] = in->tr[0] - u.x;
        sh.tr[1] = in->tr[1] - u.y;
        sh.tr[2] = in->tr[2] - u.z;
        sh.cb = v3_add(v3_sub(in->cb, u), turn);
        if (ovl_compute_try(&sh, &back, &pad_back, 0, &sides, &faces)) {
            int good_back = ovl_faces_good(&sh, &back, faces);
            /* single precision: a way whose faces close where the other's do not answers one
             * way, before any answer whose faces are open */
            if (o->hit && back.hit && good != good_back && !lone_good) {
                lone = good ? *o : back;
                lone_good = 1;
            }
            /* single precision, both ways touching with normals more than 0.1 rad apart: one of
             * them is no contact direction (see above), and the next direction is taken */
            if (!PD_DOUBLE && o->hit && back.hit && v3_dot(o->normal, back.normal) < PD_R(0.995))
                continue;
            if (o->hit && back.hit)
                ovl_out_mean(o, &back);
            else if (!back.hit) /* touching at most one way: the miss */
                *o = back;
            if (good && good_back) return;
            continue; /* single precision: faces open one way or both */
        }
        if (good && !lone_good) {
            lone = *o;
            lone_good = 1;
        }
    }
    /* one pass alone, where exactly one closed (where both did, the box guards found them
     * disagreeing otherwise, and neither is trusted), where its faces close */
    if ((first == 1 || first == 2) && (faces0 & first) &&
        ovl_compute_try(in, o, &pad, first, &sides, &faces))
        return;
    /* moved one way only, biased by the move to first order (in double precision every way's
     * faces close, so these two are the fallbacks they were before faces were asked for) */
    if (lone_good) {
        *o = lone;
        return;
    }
    o->hit = 0; /* no force from sums the predicates could not agree on */
    o->volume = o->depth = o->area = o->vol_eff = o->depth_eff = PD_R(0);
    o->places = 0;
    o->places_known = 1;
    o->centroid = o->normal = o->point_eff = v3(0, 0, 0);
}

#endif /* PD_OVERLAP_H */
