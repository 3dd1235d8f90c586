/*
 * mesh_builtin.c - shapes generated in code (cube, tetrahedron, Schonhardt polyhedron,
 * icosphere, seeded rock) and the small convex hull the rock is triangulated with.
 *
 * Every built-in goes through pd_mesh_from_arrays, so it is validated like a loaded file.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mesh_internal.h"

#define PI 3.14159265358979323846

/* The rock's triangle count is capped because its hull is O(n^2) in the vertex count. */
#define ROCK_MAX_TRIS 20000

#define BUILTIN_NAMES "cube, tetrahedron, schonhardt, icosphere, rock"

/* ---- convex hull --------------------------------------------------------------------------- */

typedef struct {
    int v[3];
    double n[3]; /* (v1-v0) x (v2-v0), outward */
    int alive;
} hull_face;

typedef struct {
    const double *pts;
    hull_face *f;
    size_t nf, cap;
} hull;

static void hull_sub(const double *a, const double *b, double *r)
{
    for (int k = 0; k < 3; k++)
        r[k] = a[k] - b[k];
}

static void hull_cross(const double *a, const double *b, double *r)
{
    r[0] = a[1] * b[2] - a[2] * b[1];
    r[1] = a[2] * b[0] - a[0] * b[2];
    r[2] = a[0] * b[1] - a[1] * b[0];
}

/* Height of p above the plane of the face, times twice the face's area. */
static double hull_orient(const hull *h, const hull_face *f, const double *p)
{
    double d[3];
    hull_sub(p, &h->pts[3 * f->v[0]], d);
    return f->n[0] * d[0] + f->n[1] * d[1] + f->n[2] * d[2];
}

static int hull_add(hull *h, int a, int b, int c)
{
    if (h->nf == h->cap) {
        size_t ncap = h->cap ? 2 * h->cap : 64;
        hull_face *nf = realloc(h->f, ncap * sizeof *nf);
        if (!nf) return PD_ENOMEM;
        h->f = nf;
        h->cap = ncap;
    }
    hull_face *f = &h->f[h->nf++];
    f->v[0] = a;
    f->v[1] = b;
    f->v[2] = c;
    f->alive = 1;
    double u[3], w[3];
    hull_sub(&h->pts[3 * b], &h->pts[3 * a], u);
    hull_sub(&h->pts[3 * c], &h->pts[3 * a], w);
    hull_cross(u, w, f->n);
    return PD_OK;
}

static int u64_cmp(const void *pa, const void *pb)
{
    uint64_t a = *(const uint64_t *)pa, b = *(const uint64_t *)pb;
    return (a > b) - (a < b);
}

/* Top bit of an edge key: set on horizon edges while the sorted keys are walked. */
#define HULL_MARK ((uint64_t)1 << 63)

static int edge_key_cmp(const void *pa, const void *pb)
{
    uint64_t a = *(const uint64_t *)pa & ~HULL_MARK, b = *(const uint64_t *)pb & ~HULL_MARK;
    return (a > b) - (a < b);
}

/* Picks four affinely independent points to start from; 0 when all are (nearly) coplanar. */
static int hull_seed(const double *p, int n, double ext, int s[4])
{
    const double tol = 1e-12 * ext; /* relative to the extent, per power of length */
    double best = 0;
    s[0] = 0;
    s[1] = -1;
    for (int i = 1; i < n; i++) {
        double d[3];
        hull_sub(&p[3 * i], &p[0], d);
        double l = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        if (l > best) best = l, s[1] = i;
    }
    if (s[1] < 0 || sqrt(best) <= tol) return 0;
    double e[3];
    hull_sub(&p[3 * s[1]], &p[0], e);
    best = 0;
    s[2] = -1;
    for (int i = 1; i < n; i++) {
        double d[3], c[3];
        hull_sub(&p[3 * i], &p[0], d);
        hull_cross(e, d, c);
        double l = c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
        if (l > best) best = l, s[2] = i;
    }
    if (s[2] < 0 || sqrt(best) <= tol * ext) return 0;
    double nrm[3], f[3];
    hull_sub(&p[3 * s[2]], &p[0], f);
    hull_cross(e, f, nrm);
    best = 0;
    s[3] = -1;
    for (int i = 1; i < n; i++) {
        double d[3];
        hull_sub(&p[3 * i], &p[0], d);
        double o = fabs(nrm[0] * d[0] + nrm[1] * d[1] + nrm[2] * d[2]);
        if (o > best) best = o, s[3] = i;
    }
    return s[3] >= 0 && best > tol * ext * ext;
}

/* Replaces the faces visible from point i by a fan from i to their horizon. The horizon must be
 * one simple loop; anything else means rounding broke convexity and the hull gives up. */
static int hull_insert(hull *h, int i, double eps, uint64_t **ebuf, size_t *ecap, int n)
{
    const double *p = &h->pts[3 * i];
    size_t nvis = 0;
    for (size_t k = 0; k < h->nf; k++) {
        if (h->f[k].alive && hull_orient(h, &h->f[k], p) > eps) {
            h->f[k].alive = 2; /* visible */
            nvis++;
        }
    }
    if (!nvis) return PD_OK; /* inside or on the hull */
    if (*ecap < 3 * nvis) {
        uint64_t *nb = realloc(*ebuf, 3 * nvis * sizeof *nb);
        if (!nb) return PD_ENOMEM;
        *ebuf = nb;
        *ecap = 3 * nvis;
    }
    uint64_t *e = *ebuf;
    size_t ne = 0;
    for (size_t k = 0; k < h->nf; k++) {
        if (h->f[k].alive != 2) continue;
        for (int j = 0; j < 3; j++)
            e[ne++] = (uint64_t)h->f[k].v[j] * (uint64_t)n + (uint64_t)h->f[k].v[(j + 1) % 3];
    }
    qsort(e, ne, sizeof *e, edge_key_cmp);
    /* Horizon edges are visible directed edges whose twin is not visible; mark them by setting
     * the top bit (ignored by the comparisons) so they can be walked below. */
    const uint64_t mark = HULL_MARK;
    size_t nh = 0;
    for (size_t k = 0; k < ne; k++) {
        uint64_t a = e[k] / (uint64_t)n, b = e[k] % (uint64_t)n, twin = b * (uint64_t)n + a;
        if (!bsearch(&twin, e, ne, sizeof *e, edge_key_cmp)) {
            e[k] |= mark;
            nh++;
        }
    }
    /* Walk the loop: from each horizon edge (a,b) the next one starts at b. */
    size_t start = 0;
    while (start < ne && !(e[start] & mark))
        start++;
    if (nh < 3 || start == ne) return PD_EMESH;
    uint64_t cur = e[start] & ~mark;
    int first = (int)(cur / (uint64_t)n);
    for (size_t step = 0; step < nh; step++) {
        int a = (int)(cur / (uint64_t)n), b = (int)(cur % (uint64_t)n);
        int rc = hull_add(h, a, b, i);
        if (rc != PD_OK) return rc;
        if (step + 1 == nh) {
            if (b != first) return PD_EMESH;
            break;
        }
        /* The unique horizon edge starting at b: search the sorted range of edges from b. */
        uint64_t lo = (uint64_t)b * (uint64_t)n, next = UINT64_MAX;
        size_t l = 0, r = ne;
        while (l < r) {
            size_t mid = (l + r) / 2;
            if ((e[mid] & ~mark) < lo)
                l = mid + 1;
            else
                r = mid;
        }
        int found = 0;
        for (size_t k = l; k < ne && (e[k] & ~mark) / (uint64_t)n == (uint64_t)b; k++) {
            if (e[k] & mark) {
                next = e[k] & ~mark;
                found++;
            }
        }
        if (found != 1) return PD_EMESH;
        cur = next;
    }
    for (size_t k = 0; k < h->nf; k++)
        if (h->f[k].alive == 2) h->f[k].alive = 0;
    return PD_OK;
}

int mesh_convex_hull(const double *pts, int n, int **tris_out, int *ntris_out)
{
    *tris_out = NULL;
    *ntris_out = 0;
    if (n < 4) return PD_EMESH;
    double lo[3], hi[3], ext = 0;
    for (int k = 0; k < 3; k++)
        lo[k] = hi[k] = pts[k];
    for (int i = 1; i < n; i++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], pts[3 * i + k]);
            hi[k] = fmax(hi[k], pts[3 * i + k]);
        }
    for (int k = 0; k < 3; k++)
        ext = fmax(ext, hi[k] - lo[k]);
    /* Orientation values scale with length^3; 1e-12 of the extent keeps rounding noise (about
     * 1e-16 relative) from deciding visibility. */
    double eps = 1e-12 * ext * ext * ext;
    int s[4];
    if (!(ext > 0) || !hull_seed(pts, n, ext, s)) return PD_EMESH;

    hull h = {pts, NULL, 0, 0};
    uint64_t *ebuf = NULL;
    size_t ecap = 0;
    int rc = PD_OK;
    /* Orient the seed tetrahedron so the fourth point lies below the first face. */
    hull_face probe = {{s[0], s[1], s[2]}, {0, 0, 0}, 1};
    double u[3], w[3];
    hull_sub(&pts[3 * s[1]], &pts[3 * s[0]], u);
    hull_sub(&pts[3 * s[2]], &pts[3 * s[0]], w);
    hull_cross(u, w, probe.n);
    if (hull_orient(&h, &probe, &pts[3 * s[3]]) > 0) {
        int t = s[1];
        s[1] = s[2];
        s[2] = t;
    }
    if ((rc = hull_add(&h, s[0], s[1], s[2])) || (rc = hull_add(&h, s[0], s[3], s[1])) ||
        (rc = hull_add(&h, s[1], s[3], s[2])) || (rc = hull_add(&h, s[2], s[3], s[0])))
        goto done;
    for (int i = 0; i < n; i++) {
        if (i == s[0] || i == s[1] || i == s[2] || i == s[3]) continue;
        if ((rc = hull_insert(&h, i, eps, &ebuf, &ecap, n)) != PD_OK) goto done;
        size_t alive = 0;
        for (size_t k = 0; k < h.nf; k++)
            alive += h.f[k].alive != 0;
        if (h.nf > 64 && 2 * alive < h.nf) { /* drop dead faces so scans stay O(alive) */
            size_t j = 0;
            for (size_t k = 0; k < h.nf; k++)
                if (h.f[k].alive) h.f[j++] = h.f[k];
            h.nf = j;
        }
    }
    size_t nt = 0;
    for (size_t k = 0; k < h.nf; k++)
        nt += h.f[k].alive != 0;
    int *t = malloc(3 * nt * sizeof *t);
    if (!t) {
        rc = PD_ENOMEM;
        goto done;
    }
    nt = 0;
    for (size_t k = 0; k < h.nf; k++) {
        if (!h.f[k].alive) continue;
        memcpy(&t[3 * nt++], h.f[k].v, sizeof h.f[k].v);
    }
    *tris_out = t;
    *ntris_out = (int)nt;
done:
    free(h.f);
    free(ebuf);
    return rc;
}

/* ---- fixed shapes -------------------------------------------------------------------------- */

static int bad_count(const char *name, int triangles, const char *valid, pd_error *err)
{
    return pd_error_set(err, PD_EINVAL, "builtin:%s: bad triangle count %d (valid: %s)", name,
                        triangles, valid);
}

static int make_cube(pd_mesh **out, pd_error *err)
{
    /* Vertex i has x, y, z = +-0.5 by its bits 0, 1, 2; two triangles per face, CCW outside. */
    double v[8 * 3];
    for (int i = 0; i < 8; i++)
        for (int k = 0; k < 3; k++)
            v[3 * i + k] = (i >> k & 1) ? 0.5 : -0.5;
    static const int t[12 * 3] = {0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4,
                                  2, 6, 7, 2, 7, 3, 0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5};
    return pd_mesh_from_arrays(v, 8, t, 12, "builtin:cube", out, err);
}

static int make_tetrahedron(pd_mesh **out, pd_error *err)
{
    static const double v[4 * 3] = {1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1};
    static const int t[4 * 3] = {1, 3, 2, 0, 2, 3, 0, 3, 1, 0, 1, 2};
    return pd_mesh_from_arrays(v, 4, t, 4, "builtin:tetrahedron", out, err);
}

/*
 * Schonhardt polyhedron: bottom triangle b_i at z = -1/2 at angles 90, 210, 330 degrees, top
 * triangle t_i at z = +1/2 turned by +30 degrees (120, 240, 360), circumradius 1. Each side quad
 * (b_i, b_i+1, t_i+1, t_i) is split along b_i - t_i+1, which spans 150 degrees and passes 0.26
 * from the axis, inside the hull's diagonal b_i+1 - t_i (90 degrees): every side edge is reflex,
 * so no diagonal of the polyhedron lies inside it and it cannot be tetrahedralised.
 */
static int make_schonhardt(pd_mesh **out, pd_error *err)
{
    const double h = 0.5, s3 = sqrt(3.0) / 2;
    const double v[6 * 3] = {0,    1,  -h, -s3,  -0.5, -h, s3, -0.5, -h,
                             -0.5, s3, h,  -0.5, -s3,  h,  1,  0,    h};
    int t[8 * 3] = {0, 2, 1, 3, 4, 5};
    for (int i = 0; i < 3; i++) {
        int b0 = i, b1 = (i + 1) % 3, t0 = 3 + i, t1 = 3 + (i + 1) % 3;
        int *f = &t[6 + 6 * i];
        f[0] = b0, f[1] = b1, f[2] = t1;
        f[3] = b0, f[4] = t1, f[5] = t0;
    }
    int rc = pd_mesh_from_arrays(v, 6, t, 8, "builtin:schonhardt", out, err);
    if (rc != PD_OK) return rc;
    /* By its D3 symmetry the centroid is the origin up to rounding; remove the rounding too. */
    pd_mass_props mp;
    pd_mesh_mass_props(*out, &mp);
    for (int i = 0; i < (*out)->nverts; i++)
        for (int k = 0; k < 3; k++)
            (*out)->verts[3 * i + k] -= mp.centroid[k];
    return PD_OK;
}

/* ---- icosphere ----------------------------------------------------------------------------- */

static void normalize(double *p)
{
    double n = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    for (int k = 0; k < 3; k++)
        p[k] /= n;
}

static int make_icosphere(int triangles, pd_mesh **out, pd_error *err)
{
    if (triangles <= 0) triangles = 80;
    int levels = -1;
    for (int l = 0, c = 20; l <= 4; l++, c *= 4)
        if (c == triangles) levels = l;
    if (levels < 0) return bad_count("icosphere", triangles, "20, 80, 320, 1280, 5120", err);

    const double g = (1 + sqrt(5.0)) / 2;
    static const int ico[20 * 3] = {0, 11, 5, 0, 5,  1,  0,  1,  7,  0,  7, 10, 0, 10, 11,
                                    1, 5,  9, 5, 11, 4,  11, 10, 2,  10, 7, 6,  7, 1,  8,
                                    3, 9,  4, 3, 4,  2,  3,  2,  6,  3,  6, 8,  3, 8,  9,
                                    4, 9,  5, 2, 4,  11, 6,  2,  10, 8,  6, 7,  9, 8,  1};
    const double base[12 * 3] = {-1, g,  0,  1, g, 0,  -1, -g, 0,  1, -g, 0, 0,  -1, g,  0,  1, g,
                                 0,  -1, -g, 0, 1, -g, g,  0,  -1, g, 0,  1, -g, 0,  -1, -g, 0, 1};
    int nv_final = triangles / 2 + 2; /* V = F/2 + 2 for a closed genus-0 triangulation */
    double *v = malloc(3 * (size_t)nv_final * sizeof *v);
    int *t = malloc(3 * (size_t)triangles * sizeof *t);
    int *nt_buf = malloc(3 * (size_t)triangles * sizeof *nt_buf);
    uint64_t *keys = malloc(3 * (size_t)triangles * sizeof *keys);
    int rc = PD_OK;
    if (!v || !t || !nt_buf || !keys) {
        rc = pd_error_set(err, PD_ENOMEM, "builtin:icosphere: out of memory");
        goto done;
    }
    memcpy(v, base, sizeof base);
    for (int i = 0; i < 12; i++)
        normalize(&v[3 * i]);
    memcpy(t, ico, sizeof ico);
    int nv = 12, nt = 20;
    for (int l = 0; l < levels; l++) {
        /* Number the edges by sorting their keys; midpoint of edge j becomes vertex nv + j. */
        size_t ne = 0;
        for (int f = 0; f < nt; f++)
            for (int k = 0; k < 3; k++) {
                int a = t[3 * f + k], b = t[3 * f + (k + 1) % 3];
                if (a < b) keys[ne++] = (uint64_t)a << 32 | (uint64_t)b;
            }
        qsort(keys, ne, sizeof *keys, u64_cmp);
        for (size_t j = 0; j < ne; j++) {
            int a = (int)(keys[j] >> 32), b = (int)(keys[j] & 0xffffffffu);
            double *m = &v[3 * (nv + j)];
            for (int k = 0; k < 3; k++)
                m[k] = 0.5 * (v[3 * a + k] + v[3 * b + k]);
            normalize(m);
        }
        for (int f = 0; f < nt; f++) {
            int c[3], mid[3];
            for (int k = 0; k < 3; k++)
                c[k] = t[3 * f + k];
            for (int k = 0; k < 3; k++) {
                int a = c[k], b = c[(k + 1) % 3];
                uint64_t key =
                    a < b ? (uint64_t)a << 32 | (uint64_t)b : (uint64_t)b << 32 | (uint64_t)a;
                uint64_t *hit = bsearch(&key, keys, ne, sizeof *keys, u64_cmp);
                mid[k] = nv + (int)(hit - keys);
            }
            int q[12] = {c[0], mid[0], mid[2], c[1],   mid[1], mid[0],
                         c[2], mid[2], mid[1], mid[0], mid[1], mid[2]};
            memcpy(&nt_buf[12 * f], q, sizeof q);
        }
        nv += (int)ne;
        nt *= 4;
        memcpy(t, nt_buf, 3 * (size_t)nt * sizeof *t);
    }
    rc = pd_mesh_from_arrays(v, nv, t, nt, "builtin:icosphere", out, err);
done:
    free(v);
    free(t);
    free(nt_buf);
    free(keys);
    return rc;
}

/* ---- rock ---------------------------------------------------------------------------------- */

/* splitmix64: tiny, seedable and identical on every platform (rand() is none of these). */
static uint64_t rng_next(uint64_t *s)
{
    uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static double rng_uniform(uint64_t *s, double lo, double hi)
{
    return lo + (hi - lo) * (double)(rng_next(s) >> 11) * 0x1.0p-53;
}

static void rng_direction(uint64_t *s, double d[3])
{
    double z = rng_uniform(s, -1, 1), phi = rng_uniform(s, 0, 2 * PI), r = sqrt(1 - z * z);
    d[0] = r * cos(phi);
    d[1] = r * sin(phi);
    d[2] = z;
}

#define ROCK_MAX_DENTS 8
#define ROCK_BUMPS 4
#define ROCK_AXIS_MIN 0.7  /* smaller semi-axes of the base ellipsoid, relative to the largest */
#define ROCK_DENT_MIN 0.15 /* dent depth, relative to the local radius */
#define ROCK_DENT_MAX 0.3
/* Dent width (Gaussian sigma, radians). depth / sigma^2 > 1 makes the dent's floor concave, not
 * just flatter, so the rock is clearly non-convex (hull volume 0.2-3 % larger at 80 triangles and
 * up, for every seed tried). */
#define ROCK_WIDTH_MIN 0.3
#define ROCK_WIDTH_MAX 0.45

/* r(u): a randomly oriented ellipsoid, times seeded Gaussian dents, times gentle bumps. */
typedef struct {
    double rot[3][3];
    double inv_axis2[3];
    int ndent;
    double dent_dir[ROCK_MAX_DENTS][3], dent_depth[ROCK_MAX_DENTS], dent_width[ROCK_MAX_DENTS];
    double bump_dir[ROCK_BUMPS][3], bump_freq[ROCK_BUMPS], bump_phase[ROCK_BUMPS],
        bump_amp[ROCK_BUMPS];
} rock_shape;

/* Draws every parameter in a fixed order from the seed alone, so every resolution samples the
 * same shape. */
static void rock_shape_init(rock_shape *s, unsigned seed)
{
    uint64_t st = 0x5eed0f0c4a11ull ^ ((uint64_t)seed << 17) ^ seed;
    double q[4];
    double u1 = rng_uniform(&st, 0, 1), u2 = rng_uniform(&st, 0, 2 * PI),
           u3 = rng_uniform(&st, 0, 2 * PI);
    q[0] = sqrt(1 - u1) * sin(u2);
    q[1] = sqrt(1 - u1) * cos(u2);
    q[2] = sqrt(u1) * sin(u3);
    q[3] = sqrt(u1) * cos(u3);
    if (pd_quat_to_matrix(q, s->rot) != PD_OK)
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                s->rot[i][j] = i == j;
    s->inv_axis2[0] = 1;
    for (int k = 1; k < 3; k++) {
        double a = rng_uniform(&st, ROCK_AXIS_MIN, 1.0);
        s->inv_axis2[k] = 1 / (a * a);
    }
    s->ndent = 4 + (int)(rng_next(&st) % (ROCK_MAX_DENTS - 4 + 1));
    for (int i = 0; i < ROCK_MAX_DENTS; i++) {
        rng_direction(&st, s->dent_dir[i]);
        s->dent_depth[i] = rng_uniform(&st, ROCK_DENT_MIN, ROCK_DENT_MAX);
        s->dent_width[i] = rng_uniform(&st, ROCK_WIDTH_MIN, ROCK_WIDTH_MAX);
    }
    for (int i = 0; i < ROCK_BUMPS; i++) {
        rng_direction(&st, s->bump_dir[i]);
        s->bump_freq[i] = rng_uniform(&st, 2, 5);
        s->bump_phase[i] = rng_uniform(&st, 0, 2 * PI);
        s->bump_amp[i] = rng_uniform(&st, 0.01, 0.03);
    }
}

static double rock_radius(const rock_shape *s, const double u[3])
{
    double q = 0;
    for (int i = 0; i < 3; i++) {
        double w = s->rot[i][0] * u[0] + s->rot[i][1] * u[1] + s->rot[i][2] * u[2];
        q += w * w * s->inv_axis2[i];
    }
    double r = 1 / sqrt(q);
    for (int i = 0; i < s->ndent; i++) {
        const double *d = s->dent_dir[i];
        double c = u[0] * d[0] + u[1] * d[1] + u[2] * d[2];
        double th = acos(c > 1 ? 1 : c < -1 ? -1 : c), w = s->dent_width[i];
        r *= 1 - s->dent_depth[i] * exp(-th * th / (2 * w * w)); /* product: never <= 0 */
    }
    double b = 1;
    for (int i = 0; i < ROCK_BUMPS; i++) {
        const double *d = s->bump_dir[i];
        double c = u[0] * d[0] + u[1] * d[1] + u[2] * d[2];
        b += s->bump_amp[i] * sin(s->bump_freq[i] * c + s->bump_phase[i]);
    }
    return r * b;
}

static int make_rock(int triangles, unsigned seed, pd_mesh **out, pd_error *err)
{
    if (triangles <= 0) triangles = 80;
    if (triangles < 20 || triangles % 2 || triangles > ROCK_MAX_TRIS) {
        char valid[64];
        snprintf(valid, sizeof valid, "any even number from 20 to %d", ROCK_MAX_TRIS);
        return bad_count("rock", triangles, valid, err);
    }
    /* A closed triangulation of n points on a sphere has 2n - 4 triangles. Fibonacci-sphere
     * directions are quasi-uniform and deterministic; their hull is the connectivity. */
    int n = triangles / 2 + 2;
    double *dir = malloc(3 * (size_t)n * sizeof *dir);
    int *t = NULL, nt = 0, rc = PD_OK;
    if (!dir) return pd_error_set(err, PD_ENOMEM, "builtin:rock: out of memory");
    const double golden = PI * (3 - sqrt(5.0));
    for (int i = 0; i < n; i++) {
        double z = 1 - (2.0 * i + 1) / n, r = sqrt(1 - z * z), phi = golden * i;
        dir[3 * i] = r * cos(phi);
        dir[3 * i + 1] = r * sin(phi);
        dir[3 * i + 2] = z;
    }
    rc = mesh_convex_hull(dir, n, &t, &nt);
    if (rc == PD_OK && nt != triangles) rc = PD_EMESH;
    if (rc != PD_OK) {
        rc = pd_error_set(err, rc, "builtin:rock: triangulating %d directions failed", n);
        goto done;
    }
    /* Star-shaped about the origin: each hull triangle keeps its cone, so the mesh stays closed,
     * embedded and outward whatever positive radii the vertices get. */
    rock_shape shape;
    rock_shape_init(&shape, seed);
    for (int i = 0; i < n; i++) {
        double r = rock_radius(&shape, &dir[3 * i]);
        for (int k = 0; k < 3; k++)
            dir[3 * i + k] *= r;
    }
    if ((rc = pd_mesh_from_arrays(dir, n, t, nt, "builtin:rock", out, err)) != PD_OK) goto done;
    /* Volume-equivalent diameter 1 (volume pi/6), centroid at the origin. */
    pd_mass_props mp;
    pd_mesh_mass_props(*out, &mp);
    double sc = cbrt(PI / 6 / mp.volume);
    for (int i = 0; i < (*out)->nverts; i++)
        for (int k = 0; k < 3; k++)
            (*out)->verts[3 * i + k] = sc * ((*out)->verts[3 * i + k] - mp.centroid[k]);
done:
    free(dir);
    free(t);
    return rc;
}

int pd_mesh_builtin(const char *name, int triangles, unsigned seed, pd_mesh **out, pd_error *err)
{
    if (!out) return pd_error_set(err, PD_EINVAL, "pd_mesh_builtin: no output pointer");
    *out = NULL;
    if (!name) name = "";
    if (triangles < 0) /* 0 is the default; a negative count is a mistake, not a default */
        return pd_error_set(err, PD_EINVAL, "builtin:%s: bad triangle count %d (not negative)",
                            name, triangles);
    if (!strcmp(name, "cube")) {
        if (triangles > 0 && triangles != 12) return bad_count(name, triangles, "12", err);
        return make_cube(out, err);
    }
    if (!strcmp(name, "tetrahedron")) {
        if (triangles > 0 && triangles != 4) return bad_count(name, triangles, "4", err);
        return make_tetrahedron(out, err);
    }
    if (!strcmp(name, "schonhardt")) {
        if (triangles > 0 && triangles != 8) return bad_count(name, triangles, "8", err);
        return make_schonhardt(out, err);
    }
    if (!strcmp(name, "icosphere")) return make_icosphere(triangles, out, err);
    if (!strcmp(name, "rock")) return make_rock(triangles, seed, out, err);
    return pd_error_set(err, PD_EINVAL, "unknown builtin '%s' (valid: " BUILTIN_NAMES ")", name);
}

int pd_mesh_box(const double lo[3], const double hi[3], pd_mesh **out, pd_error *err)
{
    static const int t[36] = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                              2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
    double v[24];
    for (int i = 0; i < 8; i++)
        for (int k = 0; k < 3; k++)
            v[3 * i + k] = (i >> k) & 1 ? hi[k] : lo[k];
    return pd_mesh_from_arrays(v, 8, t, 12, "box", out, err);
}
