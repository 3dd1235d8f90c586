/*
 * ref_overlap.h - an independent reference for the overlap of two closed meshes, used only by the
 * tests. It shares no code with kernels/overlap.h and uses a different method:
 *
 * Each mesh is decomposed into signed tetrahedra (a fixed apex O joined to every triangle); the
 * indicator function of the solid equals the signed sum of the tetrahedra's indicators, so
 *   V(A n B) = sum_ij s_i s_j V(tA_i n tB_j),
 * and every tA_i n tB_j is convex: tA_i clipped by the four planes of tB_j (Sutherland-Hodgman on
 * its face polygons, plus the cap). The first moment sums the same way. The normal of eq. 4.19 is
 * rebuilt from the area of each of A's triangles inside B (the triangle clipped against B's
 * tetrahedra, again signed) minus the same for B. The depth comes from the clipped pieces' vertices,
 * which is exact when every tetrahedron is positive (star-shaped about the apex).
 *
 * Valid for generic positions (no face of one mesh coplanar with a face or a decomposition plane
 * of the other), which is how the tests use it.
 */
#ifndef PD_REF_OVERLAP_H
#define PD_REF_OVERLAP_H

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define REF_MAXP 64 /* points per polygon */
#define REF_MAXF 16 /* faces per convex piece */

typedef struct {
    double p[REF_MAXP][3];
    int n;
} ref_poly;

typedef struct {
    ref_poly f[REF_MAXF];
    int nf;
} ref_convex;

typedef struct {
    double a[3][3]; /* posed vertices of one signed tetrahedron: apex, v1, v2, v3 */
    double o[3];
    double n[4][3], c[4]; /* planes n.x <= c, outward */
    double lo[3], hi[3];
    int sign;
} ref_tet;

static void ref_sub(const double *a, const double *b, double *r)
{
    for (int k = 0; k < 3; k++) r[k] = a[k] - b[k];
}
static void ref_cross(const double *a, const double *b, double *r)
{
    r[0] = a[1] * b[2] - a[2] * b[1];
    r[1] = a[2] * b[0] - a[0] * b[2];
    r[2] = a[0] * b[1] - a[1] * b[0];
}
static double ref_dot(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* Clips a polygon to n.x <= c; appends the new on-plane points to cut (if non-NULL). */
static void ref_clip_poly(const ref_poly *in, const double *n, double c, ref_poly *out,
                          ref_poly *cut)
{
    out->n = 0;
    for (int i = 0; i < in->n; i++) {
        const double *p = in->p[i], *q = in->p[(i + 1) % in->n];
        double dp = ref_dot(n, p) - c, dq = ref_dot(n, q) - c;
        if (dp <= 0 && out->n < REF_MAXP) memcpy(out->p[out->n++], p, sizeof(double) * 3);
        if ((dp < 0 && dq > 0) || (dp > 0 && dq < 0)) {
            double t = dp / (dp - dq), x[3];
            for (int k = 0; k < 3; k++) x[k] = p[k] + t * (q[k] - p[k]);
            if (out->n < REF_MAXP) memcpy(out->p[out->n++], x, sizeof x);
            if (cut && cut->n < REF_MAXP) memcpy(cut->p[cut->n++], x, sizeof x);
        } else if (dp == 0 && cut && cut->n < REF_MAXP) {
            memcpy(cut->p[cut->n++], p, sizeof(double) * 3);
        }
    }
    if (out->n < 3) out->n = 0;
}

/* Orders points lying on a plane with normal n by angle about their mean. */
static void ref_sort_cap(ref_poly *cap, const double *n)
{
    double m[3] = {0, 0, 0}, u[3], v[3], ang[REF_MAXP];
    for (int i = 0; i < cap->n; i++)
        for (int k = 0; k < 3; k++) m[k] += cap->p[i][k] / cap->n;
    double ax[3] = {1, 0, 0};
    if (fabs(n[0]) > 0.9) ax[0] = 0, ax[1] = 1;
    ref_cross(n, ax, u);
    double un = sqrt(ref_dot(u, u));
    for (int k = 0; k < 3; k++) u[k] /= un;
    ref_cross(n, u, v);
    for (int i = 0; i < cap->n; i++) {
        double d[3];
        ref_sub(cap->p[i], m, d);
        ang[i] = atan2(ref_dot(d, v), ref_dot(d, u));
    }
    for (int i = 1; i < cap->n; i++) /* insertion sort */
        for (int j = i; j > 0 && ang[j] < ang[j - 1]; j--) {
            double t = ang[j], tp[3];
            ang[j] = ang[j - 1];
            ang[j - 1] = t;
            memcpy(tp, cap->p[j], sizeof tp);
            memcpy(cap->p[j], cap->p[j - 1], sizeof tp);
            memcpy(cap->p[j - 1], tp, sizeof tp);
        }
}

static void ref_clip_convex(ref_convex *cv, const double *n, double c)
{
    ref_convex out;
    ref_poly cap;
    out.nf = 0;
    cap.n = 0;
    for (int f = 0; f < cv->nf; f++) {
        ref_poly r;
        ref_clip_poly(&cv->f[f], n, c, &r, &cap);
        if (r.n >= 3 && out.nf < REF_MAXF) out.f[out.nf++] = r;
    }
    if (cap.n >= 3 && out.nf < REF_MAXF) {
        ref_sort_cap(&cap, n);
        out.f[out.nf++] = cap;
    }
    *cv = out;
}

/* Volume, first moment and vertex extent along dir of a convex piece (apex at its mean). */
static double ref_convex_mass(const ref_convex *cv, double mom[3])
{
    double o[3] = {0, 0, 0};
    int np = 0;
    for (int f = 0; f < cv->nf; f++)
        for (int i = 0; i < cv->f[f].n; i++, np++)
            for (int k = 0; k < 3; k++) o[k] += cv->f[f].p[i][k];
    mom[0] = mom[1] = mom[2] = 0;
    if (np == 0) return 0;
    for (int k = 0; k < 3; k++) o[k] /= np;
    double vol = 0;
    for (int f = 0; f < cv->nf; f++) {
        const ref_poly *P = &cv->f[f];
        for (int i = 1; i + 1 < P->n; i++) {
            double a[3], b[3], c[3], x[3];
            ref_sub(P->p[0], o, a);
            ref_sub(P->p[i], o, b);
            ref_sub(P->p[i + 1], o, c);
            ref_cross(b, c, x);
            double v = fabs(ref_dot(a, x)) / 6;
            vol += v;
            for (int k = 0; k < 3; k++)
                mom[k] += v * (o[k] + P->p[0][k] + P->p[i][k] + P->p[i + 1][k]) / 4;
        }
    }
    return vol;
}

static double ref_poly_area(const ref_poly *P)
{
    double s[3] = {0, 0, 0};
    for (int i = 1; i + 1 < P->n; i++) {
        double a[3], b[3], x[3];
        ref_sub(P->p[i], P->p[0], a);
        ref_sub(P->p[i + 1], P->p[0], b);
        ref_cross(a, b, x);
        for (int k = 0; k < 3; k++) s[k] += x[k];
    }
    return 0.5 * sqrt(ref_dot(s, s));
}

/* Signed tetrahedra of a posed mesh (world = R v + x) from apex o (world coordinates). */
static int ref_tets(const pd_mesh *m, const double R[3][3], const double *x, const double *o,
                    ref_tet *out)
{
    int all_positive = 1;
    for (int t = 0; t < m->ntris; t++) {
        ref_tet *T = &out[t];
        memcpy(T->o, o, sizeof T->o);
        for (int q = 0; q < 3; q++) {
            const double *v = m->verts + 3 * m->tris[3 * t + q];
            for (int i = 0; i < 3; i++)
                T->a[q][i] = R[i][0] * v[0] + R[i][1] * v[1] + R[i][2] * v[2] + x[i];
        }
        double e1[3], e2[3], e3[3], cr[3];
        ref_sub(T->a[0], o, e1);
        ref_sub(T->a[1], o, e2);
        ref_sub(T->a[2], o, e3);
        ref_cross(e2, e3, cr);
        double det = ref_dot(e1, cr);
        T->sign = det > 0 ? 1 : det < 0 ? -1 : 0;
        if (T->sign < 0) all_positive = 0;
        /* planes through each face of the tetrahedron, oriented away from the opposite vertex */
        const double *P[4] = {o, T->a[0], T->a[1], T->a[2]};
        for (int f = 0; f < 4; f++) {
            const double *p0 = P[(f + 1) % 4], *p1 = P[(f + 2) % 4], *p2 = P[(f + 3) % 4];
            double u[3], w[3];
            ref_sub(p1, p0, u);
            ref_sub(p2, p0, w);
            ref_cross(u, w, T->n[f]);
            T->c[f] = ref_dot(T->n[f], p0);
            if (ref_dot(T->n[f], P[f]) > T->c[f]) {
                for (int k = 0; k < 3; k++) T->n[f][k] = -T->n[f][k];
                T->c[f] = -T->c[f];
            }
        }
        for (int k = 0; k < 3; k++) {
            T->lo[k] = T->hi[k] = o[k];
            for (int q = 0; q < 3; q++) {
                if (T->a[q][k] < T->lo[k]) T->lo[k] = T->a[q][k];
                if (T->a[q][k] > T->hi[k]) T->hi[k] = T->a[q][k];
            }
        }
    }
    return all_positive;
}

static void ref_tet_convex(const ref_tet *T, ref_convex *cv)
{
    const double *P[4] = {T->o, T->a[0], T->a[1], T->a[2]};
    cv->nf = 4;
    for (int f = 0; f < 4; f++) {
        cv->f[f].n = 3;
        for (int q = 0; q < 3; q++) memcpy(cv->f[f].p[q], P[(f + 1 + q) % 4], sizeof(double) * 3);
    }
}

static int ref_boxes_meet(const ref_tet *a, const ref_tet *b)
{
    for (int k = 0; k < 3; k++)
        if (a->hi[k] < b->lo[k] || b->hi[k] < a->lo[k]) return 0;
    return 1;
}

/* Area of A's tetrahedron t's outer triangle lying inside the solid of tets tb (signed sum). */
static double ref_tri_area_inside(const ref_tet *ta, const ref_tet *tb, int nb)
{
    double area = 0;
    ref_poly tri;
    tri.n = 3;
    for (int q = 0; q < 3; q++) memcpy(tri.p[q], ta->a[q], sizeof(double) * 3);
    for (int j = 0; j < nb; j++) {
        if (!tb[j].sign || !ref_boxes_meet(ta, &tb[j])) continue;
        ref_poly p = tri, r;
        for (int f = 0; f < 4 && p.n; f++) {
            ref_clip_poly(&p, tb[j].n[f], tb[j].c[f], &r, NULL);
            p = r;
        }
        if (p.n) area += tb[j].sign * ref_poly_area(&p);
    }
    return area;
}

typedef struct {
    double volume, centroid[3], normal[3], depth;
    int depth_valid;
} ref_result;

/* Reference overlap of posed meshes; apexes at the given world points. */
static void ref_overlap(const pd_mesh *a, const double Ra[3][3], const double *xa, const double *oa,
                        const pd_mesh *b, const double Rb[3][3], const double *xb, const double *ob,
                        ref_result *res)
{
    ref_tet *ta = malloc(sizeof(ref_tet) * a->ntris);
    ref_tet *tb = malloc(sizeof(ref_tet) * b->ntris);
    int pos = ref_tets(a, Ra, xa, oa, ta) & ref_tets(b, Rb, xb, ob, tb);
    double vol = 0, mom[3] = {0, 0, 0}, sa[3] = {0, 0, 0}, sb[3] = {0, 0, 0};
    /* pieces' vertices, for the depth once the normal is known */
    int cap = 1 << 16, np = 0;
    double(*pts)[3] = malloc(sizeof(double[3]) * cap);
    for (int i = 0; i < a->ntris; i++) {
        if (!ta[i].sign) continue;
        for (int j = 0; j < b->ntris; j++) {
            if (!tb[j].sign || !ref_boxes_meet(&ta[i], &tb[j])) continue;
            ref_convex cv;
            ref_tet_convex(&ta[i], &cv);
            for (int f = 0; f < 4 && cv.nf; f++) ref_clip_convex(&cv, tb[j].n[f], tb[j].c[f]);
            double m[3];
            double v = ref_convex_mass(&cv, m);
            if (v <= 0) continue;
            int s = ta[i].sign * tb[j].sign;
            vol += s * v;
            for (int k = 0; k < 3; k++) mom[k] += s * m[k];
            for (int f = 0; f < cv.nf; f++)
                for (int q = 0; q < cv.f[f].n && np < cap; q++)
                    memcpy(pts[np++], cv.f[f].p[q], sizeof(double) * 3);
        }
    }
    for (int i = 0; i < a->ntris; i++) {
        double e1[3], e2[3], nrm[3];
        ref_sub(ta[i].a[1], ta[i].a[0], e1);
        ref_sub(ta[i].a[2], ta[i].a[0], e2);
        ref_cross(e1, e2, nrm);
        double nn = sqrt(ref_dot(nrm, nrm)), ar = ref_tri_area_inside(&ta[i], tb, b->ntris);
        for (int k = 0; k < 3; k++) sa[k] += ar * nrm[k] / nn;
    }
    for (int j = 0; j < b->ntris; j++) {
        double e1[3], e2[3], nrm[3];
        ref_sub(tb[j].a[1], tb[j].a[0], e1);
        ref_sub(tb[j].a[2], tb[j].a[0], e2);
        ref_cross(e1, e2, nrm);
        double nn = sqrt(ref_dot(nrm, nrm)), ar = ref_tri_area_inside(&tb[j], ta, a->ntris);
        for (int k = 0; k < 3; k++) sb[k] += ar * nrm[k] / nn;
    }
    res->volume = vol;
    double s[3], sn;
    for (int k = 0; k < 3; k++) {
        res->centroid[k] = vol > 0 ? mom[k] / vol : 0;
        s[k] = sa[k] - sb[k];
    }
    sn = sqrt(ref_dot(s, s));
    for (int k = 0; k < 3; k++) res->normal[k] = sn > 0 ? s[k] / sn : 0;
    double lo = 1e300, hi = -1e300;
    for (int q = 0; q < np; q++) {
        double d = ref_dot(pts[q], res->normal);
        lo = d < lo ? d : lo;
        hi = d > hi ? d : hi;
    }
    res->depth = np ? hi - lo : 0;
    res->depth_valid = pos && np < cap;
    free(pts);
    free(ta);
    free(tb);
}

#endif
