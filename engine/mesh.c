/*
 * mesh.c - building meshes from arrays: welding, validation, mass properties and the body frame.
 *
 * Every mesh in polydem, loaded or generated, passes through mesh_finish, so the overlap code can
 * rely on a closed, edge-manifold, consistently outward-oriented surface that encloses each
 * point once (no triangles crossing: mesh_cross.c).
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "mesh_internal.h"

/* Principal moments closer than this (relative) are treated as equal: the mesh's own axes are
 * kept inside their eigenspace, so a cube stays axis-aligned instead of taking whatever rotation
 * rounding noise would pick. */
#define MESH_EIG_TOL 1e-9

static const char *mesh_label(const char *label)
{
    return label && *label ? label : "mesh";
}

/* ---- welding ------------------------------------------------------------------------------- */

typedef struct {
    double x, y, z;
    int idx;
} weld_key;

/* Orders by value (so -0.0 and +0.0 weld: they are the same point), then by index so the first
 * occurrence of every point leads its run. */
static int weld_cmp(const void *pa, const void *pb)
{
    const weld_key *a = pa, *b = pb;
    if (a->x != b->x) return a->x < b->x ? -1 : 1;
    if (a->y != b->y) return a->y < b->y ? -1 : 1;
    if (a->z != b->z) return a->z < b->z ? -1 : 1;
    return (a->idx > b->idx) - (a->idx < b->idx);
}

/*
 * Merges exactly equal vertices (sorting, O(n log n)) and drops unreferenced ones. Survivors keep
 * their relative order, so a mesh without duplicates comes out unchanged. On success verts holds
 * *nverts_out compacted vertices and tris is renumbered.
 */
static int mesh_weld(double *verts, int nverts, int *tris, int ntris, int *nverts_out)
{
    weld_key *keys = malloc((size_t)nverts * sizeof *keys);
    int *rep = malloc((size_t)nverts * sizeof *rep);
    if (!keys || !rep) {
        free(keys);
        free(rep);
        return PD_ENOMEM;
    }
    for (int i = 0; i < nverts; i++) {
        keys[i] = (weld_key){verts[3 * i], verts[3 * i + 1], verts[3 * i + 2], i};
    }
    qsort(keys, (size_t)nverts, sizeof *keys, weld_cmp);
    for (int i = 0; i < nverts;) {
        int j = i;
        while (j < nverts && keys[j].x == keys[i].x && keys[j].y == keys[i].y &&
               keys[j].z == keys[i].z) {
            rep[keys[j].idx] = keys[i].idx;
            j++;
        }
        i = j;
    }
    free(keys);

    /* Reuse rep's storage afterwards: newidx[i] is the compacted index of representative i, or
     * -1 while unreferenced. Representatives are numbered in increasing original order. */
    int *newidx = malloc((size_t)nverts * sizeof *newidx);
    if (!newidx) {
        free(rep);
        return PD_ENOMEM;
    }
    for (int i = 0; i < nverts; i++)
        newidx[i] = -1;
    for (int k = 0; k < 3 * ntris; k++)
        newidx[rep[tris[k]]] = 0;
    int n = 0;
    for (int i = 0; i < nverts; i++) {
        if (newidx[i] < 0) continue;
        newidx[i] = n;
        /* n <= i, so moving forward never overwrites a vertex still to be read. */
        memmove(&verts[3 * n], &verts[3 * i], 3 * sizeof *verts);
        n++;
    }
    for (int k = 0; k < 3 * ntris; k++)
        tris[k] = newidx[rep[tris[k]]];
    free(rep);
    free(newidx);
    *nverts_out = n;
    return PD_OK;
}

/* ---- validation ---------------------------------------------------------------------------- */

static const double *vtx(const double *verts, int i)
{
    return &verts[3 * i];
}

static void sub3(const double *a, const double *b, double *r)
{
    r[0] = a[0] - b[0];
    r[1] = a[1] - b[1];
    r[2] = a[2] - b[2];
}

static void cross3(const double *a, const double *b, double *r)
{
    r[0] = a[1] * b[2] - a[2] * b[1];
    r[1] = a[2] * b[0] - a[0] * b[2];
    r[2] = a[0] * b[1] - a[1] * b[0];
}

static double dot3(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* Rejects triangles with a repeated vertex or (nearly) collinear vertices: the cross product is
 * compared with the longest edge squared so the test does not depend on the mesh's scale. */
static int check_degenerate(const double *verts, const int *tris, int ntris, const char *label,
                            pd_error *err)
{
    for (int t = 0; t < ntris; t++) {
        const int *f = &tris[3 * t];
        const double *a = vtx(verts, f[0]), *b = vtx(verts, f[1]), *c = vtx(verts, f[2]);
        const char *why = NULL;
        if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2]) {
            why = "is degenerate (repeated vertex)";
        } else {
            double ab[3], bc[3], ca[3], n[3];
            sub3(b, a, ab);
            sub3(c, b, bc);
            sub3(a, c, ca);
            cross3(ab, bc, n);
            double lmax = fmax(dot3(ab, ab), fmax(dot3(bc, bc), dot3(ca, ca)));
            if (!(sqrt(dot3(n, n)) > 1e-12 * lmax)) why = "has zero area";
        }
        if (why) {
            return pd_error_set(err, PD_EMESH,
                                "%s: triangle %d %s: (%g,%g,%g) (%g,%g,%g) (%g,%g,%g)", label, t,
                                why, a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2]);
        }
    }
    return PD_OK;
}

typedef struct {
    int lo, hi; /* undirected key, lo < hi */
    int tri;
    int from; /* the directed edge runs from -> other end */
} edge_rec;

static int edge_cmp(const void *pa, const void *pb)
{
    const edge_rec *a = pa, *b = pb;
    if (a->lo != b->lo) return a->lo < b->lo ? -1 : 1;
    if (a->hi != b->hi) return a->hi < b->hi ? -1 : 1;
    return (a->tri > b->tri) - (a->tri < b->tri);
}

/* Every undirected edge must be used by exactly two triangles, once in each direction. Counts
 * each defect over the whole mesh and reports the first one found in sorted edge order. */
static int check_edges(const double *verts, const int *tris, int ntris, const char *label,
                       edge_rec **sorted, pd_error *err)
{
    *sorted = NULL;
    size_t ne = 3 * (size_t)ntris;
    edge_rec *e = malloc(ne * sizeof *e);
    if (!e) return pd_error_set(err, PD_ENOMEM, "%s: out of memory checking edges", label);
    for (int t = 0; t < ntris; t++) {
        for (int k = 0; k < 3; k++) {
            int a = tris[3 * t + k], b = tris[3 * t + (k + 1) % 3];
            e[3 * (size_t)t + k] = (edge_rec){a < b ? a : b, a < b ? b : a, t, a};
        }
    }
    qsort(e, ne, sizeof *e, edge_cmp);

    int nopen = 0, nmulti = 0, nflip = 0;
    const edge_rec *open1 = NULL, *multi1 = NULL, *flip1 = NULL;
    int multi_count = 0;
    for (size_t i = 0; i < ne;) {
        size_t j = i + 1;
        while (j < ne && e[j].lo == e[i].lo && e[j].hi == e[i].hi)
            j++;
        size_t cnt = j - i;
        if (cnt == 1) {
            if (!nopen++) open1 = &e[i];
        } else if (cnt > 2) {
            if (!nmulti++) {
                multi1 = &e[i];
                multi_count = (int)cnt;
            }
        } else if (e[i].from == e[i + 1].from) {
            if (!nflip++) flip1 = &e[i];
        }
        i = j;
    }

    int rc = PD_OK;
    if (nopen) {
        int to = open1->from == open1->lo ? open1->hi : open1->lo;
        const double *a = vtx(verts, open1->from), *b = vtx(verts, to);
        rc = pd_error_set(err, PD_EMESH, "%s: %d open edge%s, first from (%g,%g,%g) to (%g,%g,%g)",
                          label, nopen, nopen == 1 ? "" : "s", a[0], a[1], a[2], b[0], b[1], b[2]);
    } else if (nmulti) {
        const double *a = vtx(verts, multi1->lo), *b = vtx(verts, multi1->hi);
        rc = pd_error_set(err, PD_EMESH,
                          "%s: %d non-manifold edge%s (shared by more than 2 triangles), first "
                          "(%g,%g,%g)-(%g,%g,%g) shared by %d triangles",
                          label, nmulti, nmulti == 1 ? "" : "s", a[0], a[1], a[2], b[0], b[1], b[2],
                          multi_count);
    } else if (nflip) {
        const double *a = vtx(verts, flip1->lo), *b = vtx(verts, flip1->hi);
        rc = pd_error_set(err, PD_EMESH,
                          "%s: inconsistently oriented triangles at edge (%g,%g,%g)-(%g,%g,%g) "
                          "(triangles %d and %d)",
                          label, a[0], a[1], a[2], b[0], b[1], b[2], flip1[0].tri, flip1[1].tri);
    }
    if (rc == PD_OK)
        *sorted = e; /* for orient_shells */
    else
        free(e);
    return rc;
}

/* ---- shells ---------------------------------------------------------------------------------- */

/* Reverses triangle t's orientation (its outward side). */
static void flip_triangle(int *tris, int t)
{
    int s = tris[3 * t + 1];
    tris[3 * t + 1] = tris[3 * t + 2];
    tris[3 * t + 2] = s;
}

static int shell_find(int *par, int x)
{
    while (par[x] != x) {
        par[x] = par[par[x]];
        x = par[x];
    }
    return x;
}

/* Whether the ray from p along a fixed generic direction crosses the shell's triangles an odd
 * number of times (1: p inside it, 0: outside), or -1 when p lies on one of them within eps: a
 * corner of a part that touches this one, which says nothing about the nesting. Plain floating
 * point: this decides how a file's shells nest, where a ray grazing an edge costs a wrong message
 * at worst, never a wrong overlap. */
static int shell_contains(const double *verts, const int *tris, const int *shell_of, int shell,
                          int ntris, const double *p, double eps)
{
    static const double dir[3] = {0.5772156649015329, 0.6180339887498949, 0.5336475097539283};
    int odd = 0;
    for (int t = 0; t < ntris; t++) {
        if (shell_of[t] != shell) continue;
        const double *a = vtx(verts, tris[3 * t]), *b = vtx(verts, tris[3 * t + 1]),
                     *c = vtx(verts, tris[3 * t + 2]);
        double e1[3], e2[3], q[3], s[3], r[3], n[3]; /* Moller-Trumbore */
        sub3(b, a, e1);
        sub3(c, a, e2);
        sub3(p, a, s);
        cross3(e1, e2, n);
        double nn = sqrt(dot3(n, n));
        if (fabs(dot3(n, s)) <= eps * nn) { /* within eps of the plane: inside the triangle? */
            const double *corner[3] = {a, b, c};
            int k = 0;
            for (; k < 3; k++) {
                double ed[3], d[3], m[3];
                sub3(corner[(k + 1) % 3], corner[k], ed);
                sub3(p, corner[k], d);
                cross3(n, ed, m);
                if (dot3(m, d) < -eps * nn * sqrt(dot3(ed, ed))) break;
            }
            if (k == 3) return -1;
        }
        cross3(dir, e2, q);
        double det = dot3(e1, q);
        if (det == 0) continue;
        double u = dot3(s, q) / det;
        if (u < 0 || u > 1) continue;
        cross3(s, e1, r);
        double v = dot3(dir, r) / det;
        if (v < 0 || u + v > 1) continue;
        odd ^= dot3(e2, r) / det > 0;
    }
    return odd;
}

/* Corners of each shell to judge its depth from, spread over its triangles: a corner of a part
 * resting on another lies on it and decides nothing, so the next is tried. */
#define SHELL_SAMPLES 32

/*
 * A file may hold several closed shells (edge-connected parts): separate solids, or a hollow
 * solid whose inner shell faces inward. Each shell's orientation must agree with how deep it
 * lies inside the others: facing out at even depth, in at odd. A shell at depth 0 that faces in
 * is flipped (the per-shell form of the inward-mesh fix; before this, such a part subtracted its
 * volume from the rest and gave negative moments of inertia). A nested shell facing the wrong
 * way is refused: a second solid inside a solid, or a hole facing out, has no one meaning.
 * Depth is judged from a corner of each shell that lies off the other (touching parts are
 * accepted), so shells that cut through each other are left to mesh_check_crossings; every shell
 * is oriented before the first wrong one is reported, so that check sees final orientations and
 * its clearer message can come first. Call on an outward mesh as a whole (total signed volume >
 * 0), or on one whose shells' volumes cancel (mesh_finish), with check_edges' sorted edges. On
 * PD_OK or PD_EMESH, *shell_out holds each triangle's shell (0, 1, ...; malloc'd).
 */
static int orient_shells(const double *verts, int nverts, int *tris, int ntris, const edge_rec *e,
                         const char *label, int **shell_out, pd_error *err)
{
    size_t ne = 3 * (size_t)ntris;
    int *shell_of = malloc(sizeof(int) * (size_t)ntris);
    *shell_out = NULL;
    if (!shell_of) return pd_error_set(err, PD_ENOMEM, "%s: out of memory finding shells", label);
    for (int t = 0; t < ntris; t++)
        shell_of[t] = t;
    for (size_t i = 0; i + 1 < ne; i += 2) { /* check_edges: every edge is used exactly twice */
        int a = shell_find(shell_of, e[i].tri), b = shell_find(shell_of, e[i + 1].tri);
        if (a != b) shell_of[a < b ? b : a] = a < b ? a : b;
    }
    /* number the shells: every root is the smallest triangle of its shell, so it comes first and
     * its number is set before any other triangle of the shell looks it up */
    for (int t = 0; t < ntris; t++)
        shell_of[t] = shell_find(shell_of, t);
    int nshell = 0;
    for (int t = 0; t < ntris; t++)
        shell_of[t] = shell_of[t] == t ? -1 - nshell++ : shell_of[shell_of[t]];
    for (int t = 0; t < ntris; t++)
        shell_of[t] = -1 - shell_of[t];
    int rc = PD_OK;
    if (nshell > 1) {
        double *vol = calloc((size_t)nshell, sizeof *vol),
               *box = malloc(sizeof(double) * 6 * (size_t)nshell);
        int *count = calloc((size_t)nshell, sizeof *count),
            *seen = calloc((size_t)nshell, sizeof *seen);
        int *sample = malloc(sizeof(int) * SHELL_SAMPLES * (size_t)nshell);
        if (!vol || !box || !count || !seen || !sample) {
            rc = pd_error_set(err, PD_ENOMEM, "%s: out of memory finding shells", label);
            nshell = 0;
        }
        for (int k = 0; k < nshell; k++) {
            for (int j = 0; j < 3; j++) {
                box[6 * k + j] = INFINITY;
                box[6 * k + 3 + j] = -INFINITY;
            }
        }
        for (int t = 0; t < ntris && nshell; t++) {
            int k = shell_of[t];
            const double *a = vtx(verts, tris[3 * t]);
            double bc[3];
            cross3(vtx(verts, tris[3 * t + 1]), vtx(verts, tris[3 * t + 2]), bc);
            vol[k] += dot3(a, bc) / 6; /* sign only: the origin's round-off does not matter */
            count[k]++;
            for (int q = 0; q < 3; q++)
                for (int j = 0; j < 3; j++) {
                    double x = vtx(verts, tris[3 * t + q])[j];
                    box[6 * k + j] = fmin(box[6 * k + j], x);
                    box[6 * k + 3 + j] = fmax(box[6 * k + 3 + j], x);
                }
        }
        /* sample j of shell k: a corner of its triangle number j * count / SHELL_SAMPLES */
        for (int t = 0; t < ntris && nshell; t++) {
            int k = shell_of[t], i = seen[k]++;
            int n = count[k] < SHELL_SAMPLES ? count[k] : SHELL_SAMPLES;
            int j = (int)(((long long)i * n + count[k] - 1) / count[k]);
            if (j < n && (long long)j * count[k] / n == i)
                sample[SHELL_SAMPLES * k + j] = tris[3 * t + j % 3];
        }
        double eps = nshell ? mesh_touch_eps(verts, nverts) : 0;
        for (int k = 0; k < nshell; k++) {
            int n = count[k] < SHELL_SAMPLES ? count[k] : SHELL_SAMPLES, depth = 0;
            const double *p = vtx(verts, sample[SHELL_SAMPLES * k]), *through = p;
            for (int o = 0; o < nshell; o++) {
                if (o == k) continue;
                int in = -1;
                for (int j = 0; j < n && in < 0; j++) {
                    p = vtx(verts, sample[SHELL_SAMPLES * k + j]);
                    const double *b = &box[6 * o];
                    if (p[0] < b[0] - eps || p[0] > b[3] + eps || p[1] < b[1] - eps ||
                        p[1] > b[4] + eps || p[2] < b[2] - eps || p[2] > b[5] + eps)
                        in = 0;
                    else
                        in = shell_contains(verts, tris, shell_of, o, ntris, p, eps);
                }
                if (in > 0 && !depth++) through = p;
            }
            p = through;
            int out = vol[k] > 0;
            if (depth == 0 && !out) {
                for (int t = 0; t < ntris; t++)
                    if (shell_of[t] == k) flip_triangle(tris, t);
            } else if (depth > 0 && out != (depth % 2 == 0) && rc == PD_OK) {
                rc = pd_error_set(err, PD_EMESH,
                                  "%s: a shell (%d of %d, through (%g,%g,%g)) lies inside another "
                                  "(or cuts through it) facing %s: a hollow's inner shell must "
                                  "face inward, and solids inside or through a solid are not one "
                                  "solid",
                                  label, k + 1, nshell, p[0], p[1], p[2],
                                  out ? "outward" : "inward");
            }
        }
        free(vol);
        free(box);
        free(count);
        free(seen);
        free(sample);
    }
    if (rc == PD_ENOMEM)
        free(shell_of);
    else
        *shell_out = shell_of;
    return rc;
}

/* nb[3 t + k]: the triangle across edge k of t (from corner k to k + 1), from check_edges'
 * sorted edges (each used by exactly two triangles); by vertex pairs, so triangles flipped since
 * are found all the same. NULL when out of memory. */
static int *mesh_neighbours(const int *tris, int ntris, const edge_rec *e)
{
    int *nb = malloc(sizeof(int) * 3 * (size_t)ntris);
    if (!nb) return NULL;
    for (size_t i = 0; i + 1 < 3 * (size_t)ntris; i += 2) {
        for (int h = 0; h < 2; h++) {
            int t = e[i + h].tri, k = 0;
            while (k < 2 &&
                   !((tris[3 * t + k] == e[i].lo && tris[3 * t + (k + 1) % 3] == e[i].hi) ||
                     (tris[3 * t + k] == e[i].hi && tris[3 * t + (k + 1) % 3] == e[i].lo)))
                k++;
            nb[3 * t + k] = e[i + 1 - h].tri;
        }
    }
    return nb;
}

static void bbox(const double *verts, int nverts, double lo[3], double hi[3])
{
    for (int k = 0; k < 3; k++) {
        lo[k] = nverts > 0 ? verts[k] : 0;
        hi[k] = lo[k];
    }
    for (int i = 1; i < nverts; i++) {
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], verts[3 * i + k]);
            hi[k] = fmax(hi[k], verts[3 * i + k]);
        }
    }
}

double mesh_signed_volume(const double *verts, int nverts, const int *tris, int ntris)
{
    /* Tetrahedra from the bounding-box centre rather than the origin: a mesh far from the origin
     * would otherwise sum large terms of opposite sign and lose its digits. */
    double lo[3], hi[3], ref[3];
    bbox(verts, nverts, lo, hi);
    for (int k = 0; k < 3; k++)
        ref[k] = 0.5 * (lo[k] + hi[k]);
    double v6 = 0;
    for (int t = 0; t < ntris; t++) {
        double a[3], b[3], c[3], bc[3];
        sub3(vtx(verts, tris[3 * t]), ref, a);
        sub3(vtx(verts, tris[3 * t + 1]), ref, b);
        sub3(vtx(verts, tris[3 * t + 2]), ref, c);
        cross3(b, c, bc);
        v6 += dot3(a, bc);
    }
    return v6 / 6;
}

int mesh_finish(double *verts, int nverts, int *tris, int ntris, const char *label, pd_mesh **out,
                pd_error *err)
{
    label = mesh_label(label);
    int rc = PD_OK;
    *out = NULL;
    if (ntris <= 0) {
        rc = pd_error_set(err, PD_EMESH, "%s: no triangles", label);
        goto fail;
    }
    if (ntris > MESH_MAX_TRIS) {
        rc = pd_error_set(err, PD_EMESH, "%s: too many triangles (%d; the limit is %d)", label,
                          ntris, MESH_MAX_TRIS);
        goto fail;
    }
    for (int k = 0; k < 3 * ntris; k++) {
        if (tris[k] < 0 || tris[k] >= nverts) {
            rc = pd_error_set(err, PD_EMESH,
                              "%s: triangle %d: vertex index %d out of range (%d vertices)", label,
                              k / 3, tris[k], nverts);
            goto fail;
        }
    }
    for (int i = 0; i < nverts; i++) {
        const double *p = vtx(verts, i);
        if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2])) {
            rc = pd_error_set(err, PD_EMESH, "%s: vertex %d has a non-finite coordinate (%g,%g,%g)",
                              label, i, p[0], p[1], p[2]);
            goto fail;
        }
    }
    int nv = 0;
    if ((rc = mesh_weld(verts, nverts, tris, ntris, &nv)) != PD_OK) {
        rc = pd_error_set(err, rc, "%s: out of memory welding vertices", label);
        goto fail;
    }
    /* the range first: a mesh too small to hold has "zero area" triangles too */
    double lo[3], hi[3], d[3], reach = 0;
    bbox(verts, nv, lo, hi);
    sub3(hi, lo, d);
    double diag = sqrt(dot3(d, d));
    for (int j = 0; j < 3; j++)
        reach = fmax(reach, fmax(fabs(lo[j]), fabs(hi[j])));
    if (reach > MESH_MAX_COORD) {
        rc = pd_error_set(err, PD_EMESH,
                          "%s: coordinates reach %g m from the origin (at most %g m: coordinates "
                          "are metres)",
                          label, reach, MESH_MAX_COORD);
        goto fail;
    }
    if (!(diag >= MESH_MIN_SPAN)) {
        rc = pd_error_set(err, PD_EMESH,
                          "%s: the mesh spans %g m (its bounding box's diagonal; at least %g m: "
                          "coordinates are metres)",
                          label, diag, MESH_MIN_SPAN);
        goto fail;
    }
    edge_rec *edges = NULL;
    if ((rc = check_degenerate(verts, tris, ntris, label, err)) != PD_OK) goto fail;
    if ((rc = check_edges(verts, tris, ntris, label, &edges, err)) != PD_OK) goto fail;

    double vol = mesh_signed_volume(verts, nv, tris, ntris);
    if (!(fabs(vol) > 1e-12 * diag * diag * diag)) {
        /* Parts facing opposite ways can cancel (an outward cube and an inward one of the same
         * size): orient the shells first, as below, and measure again. Their nesting errors are
         * left to the call below. */
        pd_error ignored = {0};
        int *shell = NULL;
        if (orient_shells(verts, nv, tris, ntris, edges, label, &shell, &ignored) == PD_ENOMEM) {
            rc = pd_error_set(err, PD_ENOMEM, "%s: out of memory finding shells", label);
            free(edges);
            goto fail;
        }
        free(shell);
        vol = mesh_signed_volume(verts, nv, tris, ntris);
    }
    if (!(fabs(vol) > 1e-12 * diag * diag * diag)) {
        rc = pd_error_set(err, PD_EMESH,
                          "%s: enclosed volume is zero (%g for a bounding box "
                          "diagonal of %g)",
                          label, vol, diag);
        free(edges);
        goto fail;
    }
    if (vol < 0) {
        /* Consistently inward: the usual export mistake, fixed rather than rejected. */
        for (int t = 0; t < ntris; t++)
            flip_triangle(tris, t);
    }
    /* the shells' nesting is reported after crossings: a shell cutting through another often
     * has a corner inside it, and the crossing pair says what is wrong more plainly */
    pd_error nesting = {0};
    int *shell = NULL, *nb = NULL;
    int rc_nest = orient_shells(verts, nv, tris, ntris, edges, label, &shell, &nesting);
    if (rc_nest != PD_ENOMEM && !(nb = mesh_neighbours(tris, ntris, edges)))
        rc_nest = pd_error_set(&nesting, PD_ENOMEM, "%s: out of memory finding neighbours", label);
    free(edges);
    rc = rc_nest == PD_ENOMEM ? PD_OK
                              : mesh_check_crossings(verts, nv, tris, ntris, nb, shell, label, err);
    if (rc == PD_OK && rc_nest != PD_OK) {
        rc = rc_nest;
        if (err) *err = nesting;
    }
    free(shell);
    free(nb);
    if (rc != PD_OK) goto fail;

    pd_mesh *m = malloc(sizeof *m);
    if (!m) {
        rc = pd_error_set(err, PD_ENOMEM, "%s: out of memory", label);
        goto fail;
    }
    if (nv < nverts) {
        double *shrunk = realloc(verts, 3 * (size_t)nv * sizeof *verts);
        if (shrunk) verts = shrunk;
    }
    *m = (pd_mesh){nv, ntris, verts, tris};
    *out = m;
    return PD_OK;

fail:
    free(verts);
    free(tris);
    return rc;
}

int pd_mesh_from_arrays(const double *verts, int nverts, const int *tris, int ntris,
                        const char *label, pd_mesh **out, pd_error *err)
{
    label = mesh_label(label);
    if (!out) return pd_error_set(err, PD_EINVAL, "%s: no output pointer", label);
    *out = NULL;
    if (nverts < 0 || ntris < 0) {
        return pd_error_set(err, PD_EINVAL, "%s: negative count (%d vertices, %d triangles)", label,
                            nverts, ntris);
    }
    if (ntris == 0) return pd_error_set(err, PD_EMESH, "%s: no triangles", label);
    if (ntris > MESH_MAX_TRIS || nverts > 3 * MESH_MAX_TRIS) {
        return pd_error_set(
            err, PD_EMESH, "%s: too many triangles or vertices (%d, %d; the limit is %d triangles)",
            label, ntris, nverts, MESH_MAX_TRIS);
    }
    if ((nverts && !verts) || !tris) return pd_error_set(err, PD_EINVAL, "%s: null array", label);
    double *v = malloc((size_t)(nverts ? nverts : 1) * 3 * sizeof *v);
    int *t = malloc(3 * (size_t)ntris * sizeof *t);
    if (!v || !t) {
        free(v);
        free(t);
        return pd_error_set(err, PD_ENOMEM, "%s: out of memory", label);
    }
    if (nverts) memcpy(v, verts, 3 * (size_t)nverts * sizeof *v);
    memcpy(t, tris, 3 * (size_t)ntris * sizeof *t);
    return mesh_finish(v, nverts, t, ntris, label, out, err);
}

void pd_mesh_destroy(pd_mesh *m)
{
    if (!m) return;
    free(m->verts);
    free(m->tris);
    free(m);
}

/* ---- mass properties ----------------------------------------------------------------------- */

/* Cyclic Jacobi iteration on a symmetric 3x3: w gets the eigenvalues, column k of v the unit
 * eigenvector of w[k]. Converges quadratically; 50 sweeps is far more than ever needed. */
void mesh_sym3_eigen(const double in[3][3], double w[3], double v[3][3])
{
    double a[3][3];
    memcpy(a, in, sizeof a);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            v[i][j] = i == j;
    for (int sweep = 0; sweep < 50; sweep++) {
        if (a[0][1] == 0 && a[0][2] == 0 && a[1][2] == 0) break;
        for (int p = 0; p < 2; p++) {
            for (int q = p + 1; q < 3; q++) {
                double apq = a[p][q];
                if (apq == 0) continue;
                if (fabs(apq) < 1e-18 * (fabs(a[p][p]) + fabs(a[q][q]))) {
                    a[p][q] = a[q][p] = 0; /* below rounding of the diagonal */
                    continue;
                }
                double theta = (a[q][q] - a[p][p]) / (2 * apq);
                double t = 1 / (fabs(theta) + sqrt(theta * theta + 1));
                if (theta < 0) t = -t;
                double c = 1 / sqrt(t * t + 1), s = t * c;
                a[p][p] -= t * apq;
                a[q][q] += t * apq;
                a[p][q] = a[q][p] = 0;
                int r = 3 - p - q;
                double arp = a[r][p], arq = a[r][q];
                a[r][p] = a[p][r] = c * arp - s * arq;
                a[r][q] = a[q][r] = s * arp + c * arq;
                for (int k = 0; k < 3; k++) {
                    double vkp = v[k][p], vkq = v[k][q];
                    v[k][p] = c * vkp - s * vkq;
                    v[k][q] = s * vkp + c * vkq;
                }
            }
        }
    }
    for (int k = 0; k < 3; k++)
        w[k] = a[k][k];
}

static int moments_equal(double a, double b)
{
    return fabs(a - b) < MESH_EIG_TOL * fmax(fabs(a), fabs(b));
}

static void normalize3(double *a)
{
    double n = sqrt(dot3(a, a));
    if (n > 0)
        for (int k = 0; k < 3; k++)
            a[k] /= n;
}

/* Flips a so that its largest component is positive: a reproducible sign for eigenvectors. */
static void canonical_sign(double *a)
{
    int big = 0;
    for (int k = 1; k < 3; k++)
        if (fabs(a[k]) > fabs(a[big])) big = k;
    if (a[big] < 0)
        for (int k = 0; k < 3; k++)
            a[k] = -a[k];
}

/* Principal moments (ascending) and right-handed axes of the inertia tensor I, keeping the
 * coordinate axes inside any eigenspace of coinciding moments. */
static void principal_axes(const double inertia[3][3], double pr[3], double axes[3][3])
{
    double w[3], v[3][3];
    mesh_sym3_eigen(inertia, w, v);
    int ord[3] = {0, 1, 2};
    for (int i = 0; i < 3; i++)
        for (int j = i + 1; j < 3; j++)
            if (w[ord[j]] < w[ord[i]]) {
                int s = ord[i];
                ord[i] = ord[j];
                ord[j] = s;
            }
    for (int i = 0; i < 3; i++) {
        pr[i] = w[ord[i]];
        for (int k = 0; k < 3; k++)
            axes[i][k] = v[k][ord[i]];
    }

    int eq01 = moments_equal(pr[0], pr[1]), eq12 = moments_equal(pr[1], pr[2]);
    if (eq01 && eq12) {
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                axes[i][j] = i == j;
        return;
    }
    if (eq01 || eq12) {
        /* One distinct axis e from the solve; the degenerate plane gets the coordinate axis most
         * perpendicular to e, projected into the plane, and then e x u to close the triad. */
        int k = eq01 ? 2 : 0;
        double e[3], u[3];
        memcpy(e, axes[k], sizeof e);
        int best = 0;
        for (int j = 1; j < 3; j++)
            if (fabs(e[j]) < fabs(e[best])) best = j;
        int big = 0;
        for (int j = 1; j < 3; j++)
            if (fabs(e[j]) > fabs(e[big])) big = j;
        if (e[big] < 0)
            for (int j = 0; j < 3; j++)
                e[j] = -e[j];
        for (int j = 0; j < 3; j++)
            u[j] = (j == best) - e[best] * e[j];
        normalize3(u);
        memcpy(axes[k], e, sizeof e);
        memcpy(axes[(k + 1) % 3], u, sizeof u);
        cross3(e, u, axes[(k + 2) % 3]);
        normalize3(axes[(k + 2) % 3]);
        return;
    }
    canonical_sign(axes[0]);
    canonical_sign(axes[1]);
    cross3(axes[0], axes[1], axes[2]);
    normalize3(axes[2]);
}

void pd_mesh_mass_props(const pd_mesh *m, pd_mass_props *mp)
{
    memset(mp, 0, sizeof *mp);
    for (int i = 0; i < 3; i++)
        mp->axes[i][i] = 1;
    if (!m || m->ntris <= 0 || m->nverts <= 0) return;

    /* Signed tetrahedra from the bounding-box centre (precision far from the origin). For the
     * tetrahedron (0, a, b, c) with det = a.(b x c): volume det/6, first moment det/24 (a+b+c),
     * second moment det/120 (a_i a_j + b_i b_j + c_i c_j + s_i s_j) with s = a+b+c. */
    double lo[3], hi[3], ref[3];
    bbox(m->verts, m->nverts, lo, hi);
    for (int k = 0; k < 3; k++)
        ref[k] = 0.5 * (lo[k] + hi[k]);
    double v6 = 0, s1[3] = {0, 0, 0}, s2[3][3] = {{0}};
    for (int t = 0; t < m->ntris; t++) {
        double a[3], b[3], c[3], bc[3], s[3];
        sub3(vtx(m->verts, m->tris[3 * t]), ref, a);
        sub3(vtx(m->verts, m->tris[3 * t + 1]), ref, b);
        sub3(vtx(m->verts, m->tris[3 * t + 2]), ref, c);
        cross3(b, c, bc);
        double det = dot3(a, bc);
        for (int i = 0; i < 3; i++)
            s[i] = a[i] + b[i] + c[i];
        v6 += det;
        for (int i = 0; i < 3; i++) {
            s1[i] += det * s[i];
            for (int j = i; j < 3; j++)
                s2[i][j] += det * (a[i] * a[j] + b[i] * b[j] + c[i] * c[j] + s[i] * s[j]);
        }
    }
    double vol = v6 / 6;
    mp->volume = vol;
    double d[3] = {0, 0, 0};
    if (vol != 0)
        for (int i = 0; i < 3; i++)
            d[i] = s1[i] / 24 / vol;
    for (int i = 0; i < 3; i++)
        mp->centroid[i] = ref[i] + d[i];

    /* Second moment about the centroid (parallel-axis shift), then I = tr(C) 1 - C, the diagonal
     * summed as C_jj + C_kk rather than tr(C) - C_ii: for a long thin body the smallest moment
     * is tiny against the trace, and the subtraction lost its digits (a 1 x 1e-4 x 1e-4 box:
     * 4.5e-9 relative; now to rounding). */
    double cm[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = i; j < 3; j++)
            cm[i][j] = cm[j][i] = s2[i][j] / 120 - vol * d[i] * d[j];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            mp->inertia[i][j] =
                i == j ? cm[(i + 1) % 3][(i + 1) % 3] + cm[(i + 2) % 3][(i + 2) % 3] : -cm[i][j];
    principal_axes(mp->inertia, mp->principal, mp->axes);
}

void pd_mesh_to_body_frame(pd_mesh *m, pd_mass_props *mp, double rot[3][3])
{
    pd_mass_props p;
    pd_mesh_mass_props(m, &p);
    if (m) {
        for (int i = 0; i < m->nverts; i++) {
            double *v = &m->verts[3 * i], d[3];
            sub3(v, p.centroid, d);
            for (int k = 0; k < 3; k++)
                v[k] = dot3(p.axes[k], d);
        }
    }
    if (rot) memcpy(rot, p.axes, sizeof p.axes);
    if (mp) {
        *mp = p;
        memset(mp->centroid, 0, sizeof mp->centroid);
        for (int i = 0; i < 3; i++) {
            for (int j = 0; j < 3; j++) {
                mp->inertia[i][j] = i == j ? p.principal[i] : 0;
                mp->axes[i][j] = i == j;
            }
        }
    }
}
