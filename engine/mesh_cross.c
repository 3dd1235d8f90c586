/*
 * mesh_cross.c - refusing surfaces that pass through themselves: two closed parts of a file that
 * cut through each other (an assembly exported without a boolean union) or one shell folded
 * through itself. Volume, centroid and inertia integrate over the surface, and the overlap's
 * crossing parity counts surfaces along rays, so both count a region enclosed twice twice.
 *
 * Candidate pairs come from a bounding-volume tree over the triangles' boxes in Morton order
 * (one sort, then levels of pairwise unions) walked against itself, opening only pairs of nodes
 * whose boxes meet: O(n log n) for the sort, about O(n) pairs for a surface, whose triangles'
 * boxes meet those of their neighbours only. The pair test works to a tolerance (mesh_touch_eps)
 * so that parts touching within rounding are accepted, and decides exactly aligned parts (CAD
 * assemblies: coplanar faces, an edge lying on a face or crossing an edge) by the triangles
 * around the contact. Crossings that pass only through corners lying exactly on the other
 * surface are not seen; a corner resting on a face is taken as a touch.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#include "mesh_internal.h"

#define PD_DOUBLE 1
#include "bvh.h" /* bvh_spread3: the kernels' own Morton bits */

/* Triangles per leaf of the candidate tree. */
#define CROSS_LEAF 4

typedef struct {
    const double *v;
    const int *t;
    const int *nb;
    const double *n; /* unit normal per triangle, outward */
    int ntris;
    double eps;
} xctx;

/* One triangle's corners and unit normal, looked up once per pair. */
typedef struct {
    int t;
    const int *ix;
    const double *p[3];
    const double *n;
} xtri;

static xtri tri_view(const xctx *c, int t)
{
    const int *ix = &c->t[3 * t];
    return (xtri){t, ix, {&c->v[3 * ix[0]], &c->v[3 * ix[1]], &c->v[3 * ix[2]]}, &c->n[3 * t]};
}

static double dmin(double a, double b)
{
    return a < b ? a : b;
}

static double dmax(double a, double b)
{
    return a > b ? a : b;
}

static double dot(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void cross(const double *a, const double *b, double *r)
{
    r[0] = a[1] * b[2] - a[2] * b[1];
    r[1] = a[2] * b[0] - a[0] * b[2];
    r[2] = a[0] * b[1] - a[1] * b[0];
}

/* Signed distance of x from the plane of triangle a (outward positive). */
static double plane_dist(const xtri *a, const double *x)
{
    const double *p = a->p[0], *n = a->n;
    return n[0] * (x[0] - p[0]) + n[1] * (x[1] - p[1]) + n[2] * (x[2] - p[2]);
}

/* Distance of x (in or near a's plane) inside a's edge k, negative outside it. */
static double edge_dist(const xtri *a, int k, const double *x)
{
    const double *p = a->p[k], *q = a->p[(k + 1) % 3];
    double e[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]}, m[3];
    double d[3] = {x[0] - p[0], x[1] - p[1], x[2] - p[2]};
    cross(a->n, e, m); /* in the plane, pointing into a counter-clockwise triangle */
    return dot(m, d) / sqrt(dot(e, e));
}

/* Whether some of the segment pq lies inside a by more than the tolerance (pq in a's plane). */
static int segment_inside_by(const xctx *c, const xtri *a, const double *p, const double *q)
{
    double lo = 0, hi = 1;
    for (int k = 0; k < 3; k++) {
        double fp = edge_dist(a, k, p) - c->eps, fq = edge_dist(a, k, q) - c->eps;
        if (fp <= 0 && fq <= 0) return 0;
        if (fp > 0 && fq > 0) continue;
        double s = fp / (fp - fq);
        if (fp > 0)
            hi = dmin(hi, s);
        else
            lo = dmax(lo, s);
    }
    return lo < hi;
}

/*
 * An edge pq of the other surface passes strictly through the plane of triangle a at x, on a's
 * edge k (within the tolerance; the exact alignments of grid-meshed CAD parts): the surfaces
 * cross when pq goes from inside the solid's wedge at that edge (between a and the triangle
 * across it) to outside. dpa, dqa: p's and q's distances from a's plane; the edge is convex
 * where the triangle across bends below a's plane.
 */
static int through_edge(const xctx *c, const xtri *a, int k, const double *p, const double *q,
                        double dpa, double dqa)
{
    xtri u = tri_view(c, c->nb[3 * a->t + k]);
    int w = 0; /* u's corner off the shared edge */
    while (w < 2 && (u.ix[w] == a->ix[k] || u.ix[w] == a->ix[(k + 1) % 3]))
        w++;
    int convex = plane_dist(a, u.p[w]) < 0;
    double dpu = plane_dist(&u, p), dqu = plane_dist(&u, q), eps = c->eps;
    int pin = convex ? dpa < -eps && dpu < -eps : dpa < -eps || dpu < -eps;
    int pout = convex ? dpa > eps || dpu > eps : dpa > eps && dpu > eps;
    int qin = convex ? dqa < -eps && dqu < -eps : dqa < -eps || dqu < -eps;
    int qout = convex ? dqa > eps || dqu > eps : dqa > eps && dqu > eps;
    return (pin && qout) || (qin && pout);
}

/* Whether an edge of triangle b passes through the inside of triangle a: its ends lie beyond the
 * tolerance on opposite sides of a's plane (d, s: b's corners' distances and sides) and it meets
 * the plane inside a by more than the tolerance, or on one of a's edges going through it. */
static int pierces(const xctx *c, const xtri *a, const xtri *b, const double d[3], const int s[3])
{
    for (int k = 0; k < 3; k++) {
        int k1 = (k + 1) % 3;
        if (s[k] * s[k1] >= 0) continue;
        const double *p = b->p[k], *q = b->p[k1];
        double f = d[k] / (d[k] - d[k1]), x[3], ed[3];
        for (int j = 0; j < 3; j++)
            x[j] = p[j] + f * (q[j] - p[j]);
        int in = 0, on = -1;
        for (int j = 0; j < 3; j++) {
            ed[j] = edge_dist(a, j, x);
            if (ed[j] > c->eps)
                in++;
            else if (ed[j] >= -c->eps)
                on = j;
        }
        if (in == 3 || (in == 2 && on >= 0 && through_edge(c, a, on, p, q, d[k], d[k1]))) return 1;
    }
    return 0;
}

/*
 * Triangle b has an edge lying on triangle a's plane (s: b's corners' sides of it), inside a by
 * more than the tolerance somewhere, and its third corner beyond the tolerance on one side: the
 * exact alignments of CAD parts, where no edge passes strictly through a face. The surface
 * crosses a along that edge when the triangle across it reaches beyond the tolerance to the
 * other side (near the edge a is the only part of the other surface, so the two solids share
 * volume there); otherwise it touches a (a solid resting on a face). Returns the triangle
 * across, or -1. A corner lying on a with the triangles around it on both sides needs no rule
 * of its own: one of them straddles a's plane and passes through a or is passed through by an
 * edge of a.
 */
static int edge_touch_crosses(const xctx *c, const xtri *a, const xtri *b, const int s[3])
{
    int nz = 0, other = -1;
    for (int k = 0; k < 3; k++) {
        if (s[k] == 0)
            nz++;
        else
            other = k;
    }
    if (nz != 2) return -1;
    int e = (other + 1) % 3; /* the edge from corner e to e + 1 is the one on the plane */
    if (!segment_inside_by(c, a, b->p[e], b->p[(e + 1) % 3])) return -1;
    int u = c->nb[3 * b->t + e];
    for (int k = 0; k < 3; k++) {
        int w = c->t[3 * u + k];
        if (w == b->ix[e] || w == b->ix[(e + 1) % 3]) continue;
        if (s[other] * plane_dist(a, &c->v[3 * w]) < -c->eps) return u;
    }
    return -1;
}

/* Whether two triangles lying in one plane (unit normal pn) overlap by more than the tolerance:
 * no edge of either separates them (the separating axis test in the plane). Distances along an
 * edge's normal are kept multiplied by the edge's length, which spares a square root. */
static int coplanar_overlap(const xctx *c, const xtri *a, const xtri *b, const double *pn)
{
    const xtri *tri[2] = {a, b};
    for (int w = 0; w < 2; w++) {
        const xtri *t = tri[w], *o = tri[1 - w];
        double sgn = dot(t->n, pn) > 0 ? 1 : -1;
        for (int k = 0; k < 3; k++) {
            const double *p = t->p[k], *q = t->p[(k + 1) % 3], *r = t->p[(k + 2) % 3];
            double e[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]}, m[3];
            cross(pn, e, m);
            for (int j = 0; j < 3; j++)
                m[j] *= sgn; /* into t, times |e| */
            double h = (r[0] - p[0]) * m[0] + (r[1] - p[1]) * m[1] + (r[2] - p[2]) * m[2];
            double lo = INFINITY, hi = -INFINITY;
            for (int j = 0; j < 3; j++) {
                const double *x = o->p[j];
                double y = (x[0] - p[0]) * m[0] + (x[1] - p[1]) * m[1] + (x[2] - p[2]) * m[2];
                lo = dmin(lo, y);
                hi = dmax(hi, y);
            }
            double depth = dmin(h, hi) - dmax(lo, 0);
            if (!(depth > 0 && depth * depth > c->eps * c->eps * dot(e, e))) return 0;
        }
    }
    return 1;
}

enum { NO_CROSS, CROSSES, SAME_FACE };

/*
 * Whether triangles i and j cross: an edge of one passes through the other, they lie in one
 * plane overlapping and facing the same way (two solids sharing the volume behind), or an edge
 * on the other that the surface goes on through (edge_touch_crosses). *a and *b get the pair to
 * report. Triangles sharing an edge meet along it and nowhere else unless folded flat, which is a
 * touch.
 */
static int pair_crosses(const xctx *c, int i, int j, int *a, int *b)
{
    const int *ti = &c->t[3 * i], *tj = &c->t[3 * j];
    int ini[3], inj[3], shared = 0; /* whether tj[k] is a corner of i, ti[k] one of j */
    for (int k = 0; k < 3; k++) {
        ini[k] = tj[k] == ti[0] || tj[k] == ti[1] || tj[k] == ti[2];
        inj[k] = ti[k] == tj[0] || ti[k] == tj[1] || ti[k] == tj[2];
        shared += ini[k];
    }
    if (shared >= 2) return NO_CROSS;
    xtri A = tri_view(c, i), B = tri_view(c, j);
    /* A shared corner lies on both planes exactly, whatever its rounding. When the other
     * corners of one triangle lie beyond the tolerance on one side of the other's plane, the two
     * meet at most in the shared corner: the common case of neighbours on a curved surface. */
    double di[3], dj[3];
    int si[3], sj[3], posi = 0, negi = 0, posj = 0, negj = 0;
    for (int k = 0; k < 3; k++) {
        dj[k] = ini[k] ? 0 : plane_dist(&A, B.p[k]);
        sj[k] = (dj[k] > c->eps) - (dj[k] < -c->eps);
        posj += sj[k] > 0, negj += sj[k] < 0;
    }
    if (posj == 3 - shared || negj == 3 - shared) return NO_CROSS;
    for (int k = 0; k < 3; k++) {
        di[k] = inj[k] ? 0 : plane_dist(&B, A.p[k]);
        si[k] = (di[k] > c->eps) - (di[k] < -c->eps);
        posi += si[k] > 0, negi += si[k] < 0;
    }
    if (posi == 3 - shared || negi == 3 - shared) return NO_CROSS;
    *a = i;
    *b = j;
    if (posj + negj == 0 || posi + negi == 0) {
        /* facing apart: two solids meeting face to face (or a surface folded flat onto itself),
         * each point enclosed once */
        if (dot(A.n, B.n) <= 0) return NO_CROSS;
        return coplanar_overlap(c, &A, &B, posj + negj == 0 ? A.n : B.n) ? SAME_FACE : NO_CROSS;
    }
    if (pierces(c, &A, &B, dj, sj) || pierces(c, &B, &A, di, si)) return CROSSES;
    int u = edge_touch_crosses(c, &A, &B, sj);
    if (u >= 0) {
        *b = u;
        return CROSSES;
    }
    if ((u = edge_touch_crosses(c, &B, &A, si)) >= 0) {
        *a = j;
        *b = u;
        return CROSSES;
    }
    return NO_CROSS;
}

/* ---- candidate pairs ----------------------------------------------------------------------- */

typedef struct {
    uint64_t key;
    int tri;
} morton;

static int morton_cmp(const void *pa, const void *pb)
{
    const morton *a = pa, *b = pb;
    if (a->key != b->key) return a->key < b->key ? -1 : 1;
    return (a->tri > b->tri) - (a->tri < b->tri);
}

static int boxes_meet(const double *a, const double *b)
{
    return a[0] <= b[3] && b[0] <= a[3] && a[1] <= b[4] && b[1] <= a[4] && a[2] <= b[5] &&
           b[2] <= a[5];
}

/* The tree: level 0 has a box per CROSS_LEAF consecutive triangles in Morton order, each level
 * above unites pairs of the one below, up to one box. */
typedef struct {
    double *box;   /* 6 per node, level by level */
    int first[64]; /* index of level l's first node */
    int count[64]; /* nodes on level l */
    int nlevel;
} xtree;

typedef struct {
    int count, a, b, kind; /* pairs found, and the first by (a, b) */
} xfound;

static void found(xfound *f, int kind, int a, int b)
{
    if (a > b) {
        int s = a;
        a = b;
        b = s;
    }
    if (!f->count++ || a < f->a || (a == f->a && b < f->b)) {
        f->a = a;
        f->b = b;
        f->kind = kind;
    }
}

typedef struct {
    const xctx *c;
    const xtree *tr;
    const int *ord;     /* triangles in Morton order */
    const double *sbox; /* their boxes, in that order */
    xfound f;
} xwalk;

static const double *node_box(const xwalk *w, int l, int k)
{
    return &w->tr->box[6 * ((size_t)w->tr->first[l] + k)];
}

/* Triangles at positions [lo, hi) of node k of level 0. */
static void leaf_range(const xwalk *w, int k, int *lo, int *hi)
{
    *lo = k * CROSS_LEAF;
    *hi = *lo + CROSS_LEAF < w->c->ntris ? *lo + CROSS_LEAF : w->c->ntris;
}

static void test_positions(xwalk *w, int p, int q)
{
    if (!boxes_meet(&w->sbox[6 * p], &w->sbox[6 * q])) return;
    int a, b, kind = pair_crosses(w->c, w->ord[p], w->ord[q], &a, &b);
    if (kind != NO_CROSS) found(&w->f, kind, a, b);
}

/* Every pair of triangles, one under node (la, ka) and one under node (lb, kb), whose boxes
 * meet; the higher node (or the larger at one level) is opened first. */
static void walk_pair(xwalk *w, int la, int ka, int lb, int kb)
{
    if (!boxes_meet(node_box(w, la, ka), node_box(w, lb, kb))) return;
    if (la == 0 && lb == 0) {
        int a0, a1, b0, b1;
        leaf_range(w, ka, &a0, &a1);
        leaf_range(w, kb, &b0, &b1);
        const double *bb = node_box(w, lb, kb);
        for (int p = a0; p < a1; p++) {
            if (!boxes_meet(&w->sbox[6 * p], bb)) continue;
            for (int q = b0; q < b1; q++)
                test_positions(w, p, q);
        }
        return;
    }
    if (la < lb) {
        int s = la;
        la = lb;
        lb = s;
        s = ka;
        ka = kb;
        kb = s;
    }
    for (int h = 0; h < 2; h++)
        if (2 * ka + h < w->tr->count[la - 1]) walk_pair(w, la - 1, 2 * ka + h, lb, kb);
}

/* Every pair of triangles under node (l, k) whose boxes meet. */
static void walk_self(xwalk *w, int l, int k)
{
    if (l == 0) {
        int lo, hi;
        leaf_range(w, k, &lo, &hi);
        for (int p = lo; p < hi; p++)
            for (int q = p + 1; q < hi; q++)
                test_positions(w, p, q);
        return;
    }
    walk_self(w, l - 1, 2 * k);
    if (2 * k + 1 < w->tr->count[l - 1]) {
        walk_self(w, l - 1, 2 * k + 1);
        walk_pair(w, l - 1, 2 * k, l - 1, 2 * k + 1);
    }
}

/*
 * The scale is the larger of the bounding box's diagonal and the largest coordinate's magnitude,
 * because vertices stored as float32 (binary STL) are rounded to 6e-8 of their coordinates, not
 * of the mesh: two parts that touch in a CAD assembly, rotated before export, come back up to
 * ~1e-7 of the coordinates apart or into each other. MESH_TOUCH_TOL = 1e-6 leaves a factor ten
 * above that, and is far below any feature a DEM mesh resolves (a 1e6-triangle box has edges of
 * 1e-3 of its size) and far above double rounding in the tests (~1e-15 of it). A crossing
 * shallower than this is accepted: it counts at most that depth times its area twice.
 */
double mesh_touch_eps(const double *verts, int nverts)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    double big = 0;
    for (int i = 0; i < nverts; i++)
        for (int k = 0; k < 3; k++) {
            double x = verts[3 * i + k];
            lo[k] = dmin(lo[k], x);
            hi[k] = dmax(hi[k], x);
            big = dmax(big, fabs(x));
        }
    double d2 = 0;
    for (int k = 0; k < 3 && nverts > 0; k++)
        d2 += (hi[k] - lo[k]) * (hi[k] - lo[k]);
    return MESH_TOUCH_TOL * dmax(sqrt(d2), big);
}

int mesh_check_crossings(const double *verts, int nverts, const int *tris, int ntris, const int *nb,
                         const int *shell, const char *label, pd_error *err)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int i = 0; i < nverts; i++)
        for (int k = 0; k < 3; k++) {
            lo[k] = dmin(lo[k], verts[3 * i + k]);
            hi[k] = dmax(hi[k], verts[3 * i + k]);
        }
    double ext = dmax(hi[0] - lo[0], dmax(hi[1] - lo[1], hi[2] - lo[2]));
    xctx c = {verts, tris, nb, NULL, ntris, mesh_touch_eps(verts, nverts)};

    int nleaf = (ntris + CROSS_LEAF - 1) / CROSS_LEAF, nnode = 0;
    xtree tr = {0};
    for (int m = nleaf;; m = (m + 1) / 2) {
        tr.first[tr.nlevel] = nnode;
        tr.count[tr.nlevel++] = m;
        nnode += m;
        if (m == 1) break;
    }
    double *nrm = malloc(sizeof(double) * 3 * (size_t)ntris);
    double *sbox = malloc(sizeof(double) * 6 * (size_t)ntris);
    morton *mk = malloc(sizeof *mk * (size_t)ntris);
    int *ord = malloc(sizeof(int) * (size_t)ntris);
    tr.box = malloc(sizeof(double) * 6 * (size_t)nnode);
    if (!nrm || !sbox || !mk || !ord || !tr.box) {
        free(nrm);
        free(sbox);
        free(mk);
        free(ord);
        free(tr.box);
        return pd_error_set(err, PD_ENOMEM, "%s: out of memory checking for crossings", label);
    }
    c.n = nrm;
    double scale = ext > 0 ? 2097151.0 / ext : 0;
    for (int t = 0; t < ntris; t++) {
        const double *p = &verts[3 * tris[3 * t]], *q = &verts[3 * tris[3 * t + 1]],
                     *r = &verts[3 * tris[3 * t + 2]];
        double u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
        double w[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]}, *n = &nrm[3 * t];
        cross(u, w, n);
        double len = sqrt(dot(n, n)); /* > 0: zero-area triangles are refused before */
        uint64_t key = 0;
        for (int k = 0; k < 3; k++) {
            n[k] /= len;
            double mid = (dmin(p[k], dmin(q[k], r[k])) + dmax(p[k], dmax(q[k], r[k]))) / 2;
            key |= bvh_spread3((uint64_t)((mid - lo[k]) * scale)) << k;
        }
        mk[t] = (morton){key, t};
    }
    qsort(mk, (size_t)ntris, sizeof *mk, morton_cmp);
    for (int p = 0; p < ntris; p++) {
        int t = ord[p] = mk[p].tri;
        double *b = &sbox[6 * p];
        for (int k = 0; k < 3; k++) {
            double x = verts[3 * tris[3 * t] + k], y = verts[3 * tris[3 * t + 1] + k],
                   z = verts[3 * tris[3 * t + 2] + k];
            /* grown by the tolerance: a touch within it is still examined */
            b[k] = dmin(x, dmin(y, z)) - c.eps;
            b[3 + k] = dmax(x, dmax(y, z)) + c.eps;
        }
    }
    free(mk);
    for (int l = 0; l < tr.nlevel; l++) {
        for (int k = 0; k < tr.count[l]; k++) {
            double *b = &tr.box[6 * ((size_t)tr.first[l] + k)];
            int nkid = l == 0 ? CROSS_LEAF : 2;
            for (int q = 0; q < 3; q++) {
                b[q] = INFINITY;
                b[3 + q] = -INFINITY;
            }
            for (int h = 0; h < nkid; h++) {
                long x = (long)k * nkid + h;
                if (x >= (l == 0 ? ntris : tr.count[l - 1])) break;
                const double *kid =
                    l == 0 ? &sbox[6 * x] : &tr.box[6 * ((size_t)tr.first[l - 1] + x)];
                for (int q = 0; q < 3; q++) {
                    b[q] = dmin(b[q], kid[q]);
                    b[3 + q] = dmax(b[3 + q], kid[3 + q]);
                }
            }
        }
    }

    xwalk w = {&c, &tr, ord, sbox, {0}};
    walk_self(&w, tr.nlevel - 1, 0);
    xfound f = w.f;
    free(nrm);
    free(sbox);
    free(ord);
    free(tr.box);
    if (!f.count) return PD_OK;

    const double *a0 = &verts[3 * tris[3 * f.a]], *a1 = &verts[3 * tris[3 * f.a + 1]],
                 *a2 = &verts[3 * tris[3 * f.a + 2]], *b0 = &verts[3 * tris[3 * f.b]],
                 *b1 = &verts[3 * tris[3 * f.b + 1]], *b2 = &verts[3 * tris[3 * f.b + 2]];
    int apart = shell[f.a] != shell[f.b];
    return pd_error_set(err, PD_EMESH,
                        "%s: the surface passes through itself (%d pair%s of triangles): triangle "
                        "%d ((%g,%g,%g) (%g,%g,%g) (%g,%g,%g)) %s triangle %d ((%g,%g,%g) "
                        "(%g,%g,%g) (%g,%g,%g))%s",
                        label, f.count, f.count == 1 ? "" : "s", f.a, a0[0], a0[1], a0[2], a1[0],
                        a1[1], a1[2], a2[0], a2[1], a2[2],
                        f.kind == SAME_FACE ? "overlaps (in one plane, facing the same way)"
                                            : "crosses",
                        f.b, b0[0], b0[1], b0[2], b1[0], b1[1], b1[2], b2[0], b2[1], b2[2],
                        apart ? " of another closed part: join the parts into one solid (a "
                                "boolean union) before export"
                              : " of the same closed surface: repair the mesh so that it "
                                "encloses each point once");
}
