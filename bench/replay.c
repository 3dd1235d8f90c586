/*
 * bench/replay.c - a single-precision run's particle contacts replayed on the host, step by step,
 * as the engine computed them: to find which pair made a step's largest overlap, and to trace it.
 *
 * The engine maps B into A's frame in single precision on the device (np_setup), and sums a pair
 * that touched in the last step about that step's contact point (OVL_ORIGIN). bench/contacts and
 * `polydem overlap --single` map B in double precision and sum about A's centre, so in the tie
 * band of degenerate contacts they decide differently and cannot show a spike the engine had.
 * This tool runs np_setup and ovl_compute compiled in single precision, exactly as
 * kernels/contact.cl runs them, over consecutive frames, carrying each touching pair's contact
 * point to the next. Given a run written with every step as a frame ("output_interval" equal to
 * the time step), its per-frame largest depth / size is the run's /stats/max_overlap_ratio row,
 * to every printed digit with PoCL (bench/RESULTS.md, 2026-12-07, night), and on any device whose
 * single-precision / and sqrt are correctly rounded (`polydem devices`: fp32_rounded; the engine
 * builds its programs to round them so). Without that, OpenCL allows them 2.5 and 3 ulps, and a
 * device that takes them computes other bits than the host. Start some frames
 * before the step of interest: the first frame replayed has no last contact point. Walls and
 * analytic spheres are not replayed; separate places ("contact_places") are refused.
 *
 * Prints, per frame: the touching pairs and the largest depth / smaller size with its pair.
 * --above R also lists every pair above R, --pair I J that pair in every frame, with the poses
 * (x, q of I then J) and the last contact point as C initialisers, for a test
 * (tests/physics/test_single_narrow.c).
 *
 * usage: build/bench/replay RESULT.h5 FROM TO [--above R] [--pair I J]
 */
#define PD_DOUBLE 0
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "narrow_phase.h"
#include "overlap_run.h"
#include "polydem.h"
#include "result_read.h"

#define MAX_SHAPES 64

/* The file's particle shapes as the engine's tables hold them (narrow_phase.h), in single
 * precision, at size 1. */
typedef struct replay_shapes {
    shape sh[MAX_SHAPES];
    int ns;
    float *vert;
    int *tri, *voff, *toff, *vt_off, *vt;
    int max_v, max_t;
    np_shapes tables;
} replay_shapes;

static void shapes_free(replay_shapes *r)
{
    for (int s = 0; s < r->ns; s++) {
        free(r->sh[s].v);
        free(r->sh[s].t);
    }
    free(r->vert);
    free(r->tri);
    free(r->voff);
    free(r->toff);
    free(r->vt_off);
    free(r->vt);
}

/* Reads ns shapes and builds the tables; returns 0, or -1 with a message on stderr. */
static int shapes_load(hid_t f, const char *path, int ns, replay_shapes *r)
{
    memset(r, 0, sizeof *r);
    for (int s = 0; s < ns; s++, r->ns++)
        if (read_shape(f, s, &r->sh[s]) < 0) {
            r->ns++;
            fprintf(stderr, "replay: %s: cannot read shape %d under /shapes\n", path, s);
            return -1;
        }
    int nv = 0, nt = 0;
    for (int s = 0; s < ns; s++) {
        nv += r->sh[s].nv;
        nt += r->sh[s].nt;
        r->max_v = r->sh[s].nv > r->max_v ? r->sh[s].nv : r->max_v;
        r->max_t = r->sh[s].nt > r->max_t ? r->sh[s].nt : r->max_t;
    }
    r->vert = malloc(sizeof(float) * 3 * (size_t)nv);
    r->tri = malloc(sizeof(int) * 3 * (size_t)nt);
    r->voff = calloc((size_t)ns + 1, sizeof(int));
    r->toff = calloc((size_t)ns + 1, sizeof(int));
    r->vt_off = calloc((size_t)(nv + ns), sizeof(int));
    r->vt = malloc(sizeof(int) * 3 * (size_t)nt);
    if (!r->vert || !r->tri || !r->voff || !r->toff || !r->vt_off || !r->vt) {
        fprintf(stderr, "replay: out of memory\n");
        return -1;
    }
    for (int s = 0; s < ns; s++) {
        const shape *h = &r->sh[s];
        r->voff[s + 1] = r->voff[s] + h->nv;
        r->toff[s + 1] = r->toff[s] + h->nt;
        for (int i = 0; i < 3 * h->nv; i++)
            r->vert[3 * r->voff[s] + i] = (float)h->v[i];
        memcpy(r->tri + 3 * r->toff[s], h->t, sizeof(int) * 3 * (size_t)h->nt);
        /* the vertex -> triangle table as the engine builds it (ovl_vertex_triangles) */
        pd_mesh *m = NULL;
        pd_error err = {0};
        int *off = NULL, *list = NULL;
        if (pd_mesh_from_arrays(h->v, h->nv, h->t, h->nt, h->name, &m, &err) != PD_OK ||
            ovl_vertex_triangles(m, &off, &list) != PD_OK) {
            fprintf(stderr, "replay: %s: shape %s: %s\n", path, h->name,
                    err.msg[0] ? err.msg : "out of memory");
            pd_mesh_destroy(m);
            free(off);
            free(list);
            return -1;
        }
        memcpy(r->vt_off + r->voff[s] + s, off, sizeof(int) * ((size_t)h->nv + 1));
        memcpy(r->vt + 3 * r->toff[s], list, sizeof(int) * 3 * (size_t)h->nt);
        pd_mesh_destroy(m);
        free(off);
        free(list);
    }
    /* no vertex clusters: the filter keeps the same triangles without them, bit for bit */
    np_shapes t = {r->vert, r->tri, r->voff, r->toff, r->vt_off, r->vt, NULL, NULL, NULL};
    r->tables = t;
    return 0;
}

/*
 * The pairs of a frame whose bounding spheres meet (cand, ascending key i n + j, i < j: the order
 * the pairs were replayed in when every pair was tried), and the touching pairs with their last
 * contact points, the previous frame's (prev, ascending) and this frame's (cur). A run of tens of
 * thousands of particles replays in memory that grows with its contacts, not with n^2.
 */
typedef struct pair_touch {
    uint64_t key;
    pd_v3 pt; /* the contact point, world frame */
} pair_touch;

typedef struct replay_pairs {
    uint64_t *cand;
    int ncand, cap_cand;
    pair_touch *prev, *cur;
    int nprev, ncur, cap_touch;
} replay_pairs;

static void pairs_free(replay_pairs *p)
{
    free(p->cand);
    free(p->prev);
    free(p->cur);
}

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

/* sort_lo's keys: the particles are sorted by the low end of their spheres' x extents */
static const double *sort_lo;
static int cmp_lo(const void *a, const void *b)
{
    double x = sort_lo[*(const int *)a], y = sort_lo[*(const int *)b];
    return (x > y) - (x < y);
}

/*
 * Lists in p->cand every pair of polyhedra (analytic spheres are not replayed) whose bounding
 * spheres meet, d^2 <= (r_i + r_j)^2 computed as it always was, by a sweep along x: such spheres'
 * x extents overlap. order and lo hold n. Returns 0, or -1 out of memory.
 */
static int pairs_find(replay_pairs *p, const replay_shapes *rs, const int *pshape,
                      const double *psize, const double *x, int n, int *order, double *lo)
{
    int m = 0;
    for (int i = 0; i < n; i++) {
        const shape *si = &rs->sh[pshape[i]];
        if (si->sphere) continue;
        lo[i] = x[3 * i] - si->radius * psize[i];
        order[m++] = i;
    }
    sort_lo = lo;
    qsort(order, (size_t)m, sizeof(int), cmp_lo);
    p->ncand = 0;
    for (int a = 0; a < m; a++) {
        int i = order[a];
        double ri = rs->sh[pshape[i]].radius * psize[i], hi = x[3 * i] + ri;
        for (int b = a + 1; b < m && lo[order[b]] <= hi; b++) {
            int j = order[b];
            int u = i < j ? i : j, v = i < j ? j : i;
            double d2 = 0,
                   r = rs->sh[pshape[u]].radius * psize[u] + rs->sh[pshape[v]].radius * psize[v];
            for (int c = 0; c < 3; c++)
                d2 += (x[3 * u + c] - x[3 * v + c]) * (x[3 * u + c] - x[3 * v + c]);
            if (d2 > r * r) continue;
            if (p->ncand == p->cap_cand) {
                int cap = p->cap_cand ? 2 * p->cap_cand : 1024;
                uint64_t *c = realloc(p->cand, sizeof(uint64_t) * (size_t)cap);
                if (!c) return -1;
                p->cand = c;
                p->cap_cand = cap;
            }
            p->cand[p->ncand++] = (uint64_t)u * (uint64_t)n + (uint64_t)v;
        }
    }
    qsort(p->cand, (size_t)p->ncand, sizeof(uint64_t), cmp_u64);
    /* this frame's touching pairs are at most its candidates */
    if (p->ncand > p->cap_touch) {
        pair_touch *cur = realloc(p->cur, sizeof(pair_touch) * (size_t)p->ncand);
        if (cur) p->cur = cur;
        pair_touch *prev = realloc(p->prev, sizeof(pair_touch) * (size_t)p->ncand);
        if (prev) p->prev = prev;
        if (!cur || !prev) return -1;
        p->cap_touch = p->ncand;
    }
    p->ncur = 0;
    return 0;
}

/* The last contact point of pair key if it touched in the previous frame, else NULL. */
static pd_v3 *pairs_last(replay_pairs *p, uint64_t key)
{
    int a = 0, b = p->nprev;
    while (a < b) {
        int h = a + (b - a) / 2;
        if (p->prev[h].key < key)
            a = h + 1;
        else
            b = h;
    }
    return a < p->nprev && p->prev[a].key == key ? &p->prev[a].pt : NULL;
}

/* Pair key touches in this frame, at pt (called in ascending key order). */
static void pairs_touch(replay_pairs *p, uint64_t key, pd_v3 pt)
{
    p->cur[p->ncur].key = key;
    p->cur[p->ncur++].pt = pt;
}

/* This frame's touching pairs become the previous frame's. */
static void pairs_next_frame(replay_pairs *p)
{
    pair_touch *t = p->prev;
    p->prev = p->cur;
    p->cur = t;
    p->nprev = p->ncur;
    p->ncur = 0;
}

static int usage(const char *prog)
{
    fprintf(stderr, "usage: %s RESULT.h5 FROM TO [--above R] [--pair I J]\n", prog);
    return 2;
}

/* Whether the run's scenario (JSON) asks any interaction for separate places. */
static int asks_places(const char *scenario)
{
    json_t *root = json_loads(scenario, 0, NULL);
    json_t *list = json_object_get(root, "interactions"), *it;
    size_t k;
    int places = 0;
    json_array_foreach(list, k, it)
    {
        const char *cp = json_string_value(json_object_get(it, "contact_places"));
        places |= cp && strcmp(cp, "separate") == 0;
    }
    json_decref(root);
    return places;
}

int main(int argc, char **argv)
{
    const char *path = NULL;
    long from = -1, to = -1;
    int pi = -1, pj = -1, npos = 0;
    double above = -1;
    for (int i = 1; i < argc; i++) {
        char *end;
        if (!strcmp(argv[i], "--above") && i + 1 < argc) {
            above = strtod(argv[++i], &end);
            if (*end || !(above >= 0)) return usage(argv[0]);
        } else if (!strcmp(argv[i], "--pair") && i + 2 < argc) {
            pi = (int)strtol(argv[++i], &end, 10);
            if (*end) return usage(argv[0]);
            pj = (int)strtol(argv[++i], &end, 10);
            if (*end || pi < 0 || pj < 0 || pi == pj) return usage(argv[0]);
            if (pi > pj) {
                int t = pi;
                pi = pj;
                pj = t;
            }
        } else if (argv[i][0] != '-' && npos < 3) {
            if (npos == 0) {
                path = argv[i];
            } else {
                long v = strtol(argv[i], &end, 10);
                if (*end || v < 0) return usage(argv[0]);
                if (npos == 1)
                    from = v;
                else
                    to = v;
            }
            npos++;
        } else {
            return usage(argv[0]);
        }
    }
    if (npos != 3 || to < from) return usage(argv[0]);
    hid_t f = result_open("replay", path);
    if (f < 0) return 1;
    char precision[16];
    read_string_attr(f, "/", "precision", precision, sizeof precision);
    if (strcmp(precision, "single") != 0) {
        fprintf(stderr,
                "replay: %s: a %s-precision run; replay reproduces single precision "
                "(bench/contacts takes any run)\n",
                path, precision[0] ? precision : "unknown");
        H5Fclose(f);
        return 1;
    }
    char *scenario = malloc(1 << 20);
    if (scenario) read_string_attr(f, "/", "scenario", scenario, 1 << 20);
    if (!scenario || asks_places(scenario)) {
        fprintf(stderr, "replay: %s: %s\n", path,
                scenario ? "separate contact places are not replayed" : "out of memory");
        free(scenario);
        H5Fclose(f);
        return 1;
    }
    free(scenario);
    hsize_t dims[3];
    int rank = 0;
    int *pshape = read_all(f, "/particles/shape", H5T_NATIVE_INT, sizeof(int), dims, &rank);
    int n = pshape && rank == 1 ? (int)dims[0] : 0;
    double *psize = read_all(f, "/particles/size", H5T_NATIVE_DOUBLE, sizeof(double), dims, &rank);
    if (!pshape || !psize || rank != 1 || (int)dims[0] != n || n < 2) {
        fprintf(stderr, "replay: %s: no /particles/shape and /particles/size of 2 or more\n", path);
        free(pshape);
        free(psize);
        H5Fclose(f);
        return 1;
    }
    if (pi >= n || pj >= n) {
        fprintf(stderr, "replay: --pair %d %d: the run has %d particles\n", pi, pj, n);
        free(pshape);
        free(psize);
        H5Fclose(f);
        return 2;
    }
    int ns = 0;
    for (int i = 0; i < n; i++)
        ns = pshape[i] + 1 > ns ? pshape[i] + 1 : ns;
    replay_shapes rs;
    int rc = 1;
    double *x = malloc(sizeof(double) * 3 * (size_t)n), *q = malloc(sizeof(double) * 4 * (size_t)n);
    replay_pairs pairs = {0};
    int *order = malloc(sizeof(int) * (size_t)n);
    double *lo = malloc(sizeof(double) * (size_t)n);
    int *iscr = NULL;
    float *rscr = NULL;
    if (ns > MAX_SHAPES) {
        fprintf(stderr, "replay: %s: more than %d shapes\n", path, MAX_SHAPES);
        memset(&rs, 0, sizeof rs);
        goto done;
    }
    if (shapes_load(f, path, ns, &rs) < 0) goto done;
    int cap = ovl_pts_cap(rs.max_t, rs.max_t);
    size_t ilen =
        (size_t)(ovl_iscratch_len(rs.max_t, rs.max_t, rs.max_v, rs.max_v) + ovl_places_ilen(cap));
    size_t rlen = (size_t)(ovl_rscratch_len(rs.max_t, rs.max_t, rs.max_v, rs.max_v, cap) +
                           ovl_places_rlen(cap));
    iscr = malloc(sizeof(int) * ilen);
    rscr = malloc(sizeof(float) * rlen);
    if (!x || !q || !order || !lo || !iscr || !rscr) {
        fprintf(stderr, "replay: out of memory\n");
        goto done;
    }
    for (long fr = from; fr <= to; fr++) {
        int k = (int)fr;
        if (read_frame(f, "position", &k, n, 3, x) < 0 ||
            read_frame(f, "orientation", &k, n, 4, q) < 0) {
            fprintf(stderr,
                    "replay: %s: frame %ld of /frames/position and /frames/orientation not found "
                    "(both fields must be in the output)\n",
                    path, fr);
            goto done;
        }
        if (pairs_find(&pairs, &rs, pshape, psize, x, n, order, lo) < 0) {
            fprintf(stderr, "replay: out of memory\n");
            goto done;
        }
        int ntouch = 0, bi = -1, bj = -1;
        double best = 0;
        for (int k = 0; k < pairs.ncand; k++) {
            uint64_t key = pairs.cand[k];
            int i = (int)(key / (uint64_t)n), j = (int)(key % (uint64_t)n);
            pd_v3 *last = pairs_last(&pairs, key); /* NULL: not touching before */
            np_body a, b;
            a.x = v3((float)x[3 * i], (float)x[3 * i + 1], (float)x[3 * i + 2]);
            b.x = v3((float)x[3 * j], (float)x[3 * j + 1], (float)x[3 * j + 2]);
            for (int c = 0; c < 4; c++) {
                a.q[c] = (float)q[4 * i + c];
                b.q[c] = (float)q[4 * j + c];
            }
            a.size = (float)psize[i];
            b.size = (float)psize[j];
            a.shape = pshape[i];
            b.shape = pshape[j];
            ovl_in in;
            float ra[9];
            np_setup(&rs.tables, &a, &b, 0, &in, ra);
            if (last) { /* as contact.cl: about last step's contact point */
                in.flags |= OVL_ORIGIN;
                in.org = np_to_body(&a, ra, *last);
            }
            in.iscr = iscr;
            in.rscr = rscr;
            in.pts_cap = cap;
            if (i == pi && j == pj)
                printf("  pair %d %d, frame %ld: poses {%.9g, %.9g, %.9g, %.9g, %.9g, %.9g, "
                       "%.9g, %.9g, %.9g, %.9g, %.9g, %.9g, %.9g, %.9g}, last %d {%.9g, "
                       "%.9g, %.9g} m\n",
                       i, j, fr, (double)a.x.x, (double)a.x.y, (double)a.x.z, (double)a.q[0],
                       (double)a.q[1], (double)a.q[2], (double)a.q[3], (double)b.x.x, (double)b.x.y,
                       (double)b.x.z, (double)b.q[0], (double)b.q[1], (double)b.q[2],
                       (double)b.q[3], last != NULL, last ? (double)last->x : 0.0,
                       last ? (double)last->y : 0.0, last ? (double)last->z : 0.0);
            ovl_out o;
            ovl_compute(&in, &o);
            if (!(o.hit && o.depth_eff > 0)) continue;
            np_to_world(&a, ra, &o);
            pairs_touch(&pairs, key, o.point_eff);
            ntouch++;
            double ratio = o.depth_eff / (psize[i] < psize[j] ? psize[i] : psize[j]);
            if (ratio > best) {
                best = ratio;
                bi = i;
                bj = j;
            }
            if ((above >= 0 && ratio > above) || (i == pi && j == pj))
                printf("  pair %d %d, frame %ld: depth / size %.6g, volume %.6g m^3, depth "
                       "%.6g m, normal (%.6g, %.6g, %.6g), point (%.9g, %.9g, %.9g) m%s\n",
                       i, j, fr, ratio, (double)o.vol_eff, (double)o.depth_eff, (double)o.normal.x,
                       (double)o.normal.y, (double)o.normal.z, (double)o.point_eff.x,
                       (double)o.point_eff.y, (double)o.point_eff.z,
                       o.degenerate ? ", degenerate" : "");
        }
        pairs_next_frame(&pairs);
        printf("frame %ld: %d touching pairs, largest depth / size %.6g (pair %d %d)\n", fr, ntouch,
               best, bi, bj);
    }
    rc = 0;
done:
    shapes_free(&rs);
    free(x);
    free(q);
    pairs_free(&pairs);
    free(order);
    free(lo);
    free(iscr);
    free(rscr);
    free(pshape);
    free(psize);
    H5Fclose(f);
    return rc;
}
