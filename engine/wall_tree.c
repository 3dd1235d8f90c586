/* wall_tree.c - a wall's triangle BVH, built once on the host (see wall_tree.h). */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define PD_DOUBLE 1
#include "wall_bvh.h"
#include "wall_tree.h"

typedef struct build_ctx {
    const double *vert;
    const int *tri;
    double *cen; /* 3 per triangle */
    wall_tree *t;
    struct keyed *tmp; /* one per triangle, for sorting a range */
} build_ctx;

/* A triangle and its centroid's coordinate on the split axis (qsort has no context argument). */
struct keyed {
    double c;
    int i;
};

static int by_key(const void *pa, const void *pb)
{
    const struct keyed *a = pa, *b = pb;
    if (a->c != b->c) return a->c < b->c ? -1 : 1;
    return a->i < b->i ? -1 : a->i > b->i; /* a total order: the same tree every time */
}

/* Node over order[lo, hi); returns its index. Nodes are numbered in pre-order. */
static int build_node(build_ctx *c, int lo, int hi)
{
    wall_tree *t = c->t;
    int k = t->nnode++;
    double *b = t->box + 6 * k;
    double clo[3] = {INFINITY, INFINITY, INFINITY}, chi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int q = 0; q < 3; q++) {
        b[q] = INFINITY;
        b[3 + q] = -INFINITY;
    }
    for (int i = lo; i < hi; i++) {
        int tr = t->order[i];
        for (int v = 0; v < 3; v++) {
            const double *p = c->vert + 3 * c->tri[3 * tr + v];
            for (int q = 0; q < 3; q++) {
                b[q] = fmin(b[q], p[q]);
                b[3 + q] = fmax(b[3 + q], p[q]);
            }
        }
        for (int q = 0; q < 3; q++) {
            clo[q] = fmin(clo[q], c->cen[3 * tr + q]);
            chi[q] = fmax(chi[q], c->cen[3 * tr + q]);
        }
    }
    if (hi - lo <= WB_LEAF) {
        t->kid[2 * k] = -1 - lo;
        t->kid[2 * k + 1] = hi - lo;
        return k;
    }
    int axis = 0;
    for (int q = 1; q < 3; q++)
        if (chi[q] - clo[q] > chi[axis] - clo[axis]) axis = q;
    for (int i = lo; i < hi; i++) {
        c->tmp[i].i = t->order[i];
        c->tmp[i].c = c->cen[3 * t->order[i] + axis];
    }
    qsort(c->tmp + lo, (size_t)(hi - lo), sizeof *c->tmp, by_key);
    for (int i = lo; i < hi; i++)
        t->order[i] = c->tmp[i].i;
    int mid = lo + (hi - lo) / 2;
    t->kid[2 * k] = build_node(c, lo, mid);
    t->kid[2 * k + 1] = build_node(c, mid, hi);
    return k;
}

int wall_tree_build(const double *vert, const int *tri, int nt, wall_tree *t, const char *what,
                    pd_error *err)
{
    memset(t, 0, sizeof *t);
    /* median splits: depth ceil(log2(nt / WB_LEAF)) + 1, far inside WB_STACK for any int nt */
    size_t cap = 2 * (size_t)(nt > 0 ? nt : 1);
    size_t n1 = (size_t)(nt > 0 ? nt : 1);
    build_ctx c = {vert, tri, malloc(sizeof(double) * 3 * n1), t,
                   malloc(sizeof(struct keyed) * n1)};
    t->box = malloc(sizeof(double) * 6 * cap);
    t->kid = malloc(sizeof(int) * 2 * cap);
    t->order = malloc(sizeof(int) * (size_t)(nt > 0 ? nt : 1));
    if (!c.cen || !c.tmp || !t->box || !t->kid || !t->order) {
        free(c.cen);
        free(c.tmp);
        wall_tree_free(t);
        return pd_error_set(err, PD_ENOMEM, "%s: out of memory for its triangle tree", what);
    }
    for (int i = 0; i < nt; i++) {
        t->order[i] = i;
        for (int q = 0; q < 3; q++)
            c.cen[3 * i + q] = (vert[3 * tri[3 * i] + q] + vert[3 * tri[3 * i + 1] + q] +
                                vert[3 * tri[3 * i + 2] + q]) /
                               3;
    }
    build_node(&c, 0, nt);
    free(c.cen);
    free(c.tmp);
    return PD_OK;
}

void wall_tree_free(wall_tree *t)
{
    free(t->box);
    free(t->kid);
    free(t->order);
    memset(t, 0, sizeof *t);
}

static int cmp_u64(const void *pa, const void *pb)
{
    uint64_t a = *(const uint64_t *)pa, b = *(const uint64_t *)pb;
    return a < b ? -1 : a > b;
}

int wall_tree_max_near(const wall_tree *t, const double *vert, const int *tri, int nt, double side)
{
    enum { MAX_CELLS = 4000000 };
    if (nt <= 0 || !(side > 0)) return nt > 0 ? nt : 0;
    const double *root = t->box;
    /* cells of the grid anchored at the root's low corner; index ranges must fit 21 bits */
    for (int q = 0; q < 3; q++)
        if ((root[3 + q] - root[q]) / side > 1e6) return nt;
    size_t ncell = 0;
    for (int i = 0; i < nt; i++) {
        size_t m = 1;
        for (int q = 0; q < 3; q++) {
            double lo = INFINITY, hi = -INFINITY;
            for (int v = 0; v < 3; v++) {
                lo = fmin(lo, vert[3 * tri[3 * i + v] + q]);
                hi = fmax(hi, vert[3 * tri[3 * i + v] + q]);
            }
            m *= (size_t)(floor((hi - root[q]) / side) - floor((lo - root[q]) / side) + 2);
        }
        ncell += m;
        if (ncell > MAX_CELLS) return nt;
    }
    uint64_t *key = malloc(sizeof *key * (ncell + 1));
    if (!key) return -1;
    size_t nk = 0;
    for (int i = 0; i < nt; i++) {
        long lo[3], hi[3];
        for (int q = 0; q < 3; q++) {
            double a = INFINITY, b = -INFINITY;
            for (int v = 0; v < 3; v++) {
                a = fmin(a, vert[3 * tri[3 * i + v] + q]);
                b = fmax(b, vert[3 * tri[3 * i + v] + q]);
            }
            /* the cubes of side 2 side starting one cell below reach the triangle too */
            lo[q] = (long)floor((a - root[q]) / side) - 1;
            hi[q] = (long)floor((b - root[q]) / side);
        }
        for (long x = lo[0]; x <= hi[0]; x++)
            for (long y = lo[1]; y <= hi[1]; y++)
                for (long z = lo[2]; z <= hi[2]; z++)
                    key[nk++] =
                        (uint64_t)(x + 2) << 42 | (uint64_t)(y + 2) << 21 | (uint64_t)(z + 2);
    }
    qsort(key, nk, sizeof *key, cmp_u64);
    wb_tree w = {t->box, t->kid, t->order, vert, tri};
    int best = 0;
    for (size_t k = 0; k < nk; k++) {
        if (k > 0 && key[k] == key[k - 1]) continue;
        long idx[3] = {(long)(key[k] >> 42) - 2, (long)(key[k] >> 21 & 0x1fffff) - 2,
                       (long)(key[k] & 0x1fffff) - 2};
        double lo[3], hi[3];
        for (int q = 0; q < 3; q++) {
            /* widened a little: the bound must hold for the kernel's rounding too */
            lo[q] = root[q] + (double)idx[q] * side - 1e-9 * side;
            hi[q] = root[q] + (double)(idx[q] + 2) * side + 1e-9 * side;
        }
        int m = wb_query_box(&w, v3(lo[0], lo[1], lo[2]), v3(hi[0], hi[1], hi[2]), NULL, 0);
        if (m < 0) {
            best = nt;
            break;
        }
        best = m > best ? m : best;
    }
    free(key);
    return best;
}
