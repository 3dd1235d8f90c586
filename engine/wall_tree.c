/* wall_tree.c - a wall's triangle BVH, built once on the host (see wall_tree.h). */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define PD_DOUBLE 1
#include "contact_pair.h" /* cp_inside_tree: the kernels' own inside test */
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

/* Sorted unique cell keys with their counts: the count of cell key[i] is cnt[i]. */
static int cell_count(const uint64_t *key, const int *cnt, size_t n, uint64_t k)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (key[mid] < k)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < n && key[lo] == k ? cnt[lo] : 0;
}

static uint64_t cell_key(long x, long y, long z)
{
    return (uint64_t)(x + 2) << 42 | (uint64_t)(y + 2) << 21 | (uint64_t)(z + 2);
}

int wall_tree_max_near(const wall_tree *t, const double *vert, const int *tri, int nt, double side)
{
    enum { MAX_KEYS = 16000000 }; /* 128 MB of keys while counting */
    if (nt <= 0 || !(side > 0)) return nt > 0 ? nt : 0;
    const double *root = t->box;
    /* cells of side `side` on a grid anchored at the root's low corner (indices in 21 bits) */
    for (int q = 0; q < 3; q++)
        if ((root[3 + q] - root[q]) / side > 1e6) return nt;
    size_t nk = 0;
    long(*range)[6] = malloc(sizeof *range * (size_t)nt);
    if (!range) return -1;
    for (int i = 0; i < nt; i++) {
        size_t m = 1;
        for (int q = 0; q < 3; q++) {
            double lo = INFINITY, hi = -INFINITY;
            for (int v = 0; v < 3; v++) {
                lo = fmin(lo, vert[3 * tri[3 * i + v] + q]);
                hi = fmax(hi, vert[3 * tri[3 * i + v] + q]);
            }
            /* widened a little: the bound must hold for the kernel's rounding too */
            range[i][q] = (long)floor((lo - root[q]) / side - 1e-9);
            range[i][3 + q] = (long)floor((hi - root[q]) / side + 1e-9);
            m *= (size_t)(range[i][3 + q] - range[i][q] + 1);
        }
        nk += m;
        if (nk > MAX_KEYS) {
            free(range);
            return nt;
        }
    }
    uint64_t *key = malloc(sizeof *key * (nk + 1));
    int *cnt = malloc(sizeof *cnt * (nk + 1));
    if (!key || !cnt) {
        free(range);
        free(key);
        free(cnt);
        return -1;
    }
    /* every (triangle, cell its box meets) */
    size_t k = 0;
    for (int i = 0; i < nt; i++)
        for (long x = range[i][0]; x <= range[i][3]; x++)
            for (long y = range[i][1]; y <= range[i][4]; y++)
                for (long z = range[i][2]; z <= range[i][5]; z++)
                    key[k++] = cell_key(x, y, z);
    free(range);
    qsort(key, nk, sizeof *key, cmp_u64);
    size_t nu = 0;
    for (size_t i = 0; i < nk; i++) {
        if (nu > 0 && key[nu - 1] == key[i]) {
            cnt[nu - 1]++;
        } else {
            key[nu] = key[i];
            cnt[nu++] = 1;
        }
    }
    /* A cube of side `side` lies within 2 x 2 x 2 cells, whose counts bound the triangles it can
     * meet; every such block containing an occupied cell is summed. */
    long best = 0;
    for (size_t i = 0; i < nu; i++) {
        long c[3] = {(long)(key[i] >> 42) - 2, (long)(key[i] >> 21 & 0x1fffff) - 2,
                     (long)(key[i] & 0x1fffff) - 2};
        for (int b = 0; b < 8; b++) {
            long o[3] = {c[0] - (b & 1), c[1] - (b >> 1 & 1), c[2] - (b >> 2 & 1)}, sum = 0;
            for (int e = 0; e < 8; e++)
                sum +=
                    cell_count(key, cnt, nu,
                               cell_key(o[0] + (e & 1), o[1] + (e >> 1 & 1), o[2] + (e >> 2 & 1)));
            best = sum > best ? sum : best;
        }
    }
    free(key);
    free(cnt);
    return best < nt ? (int)best : nt;
}

long wall_tree_first_inside(const wall_tree *t, const double *vert, const int *tri,
                            const double *pts, long n, const double origin[3])
{
    wb_tree wt = {t->box, t->kid, t->order, vert, tri};
    const double *b = t->box;
    for (long i = 0; i < n; i++) {
        const double *x = pts + 3 * i;
        pd_v3 p = v3(x[0] - origin[0], x[1] - origin[1], x[2] - origin[2]);
        if (p.x < b[0] || p.x > b[3] || p.y < b[1] || p.y > b[4] || p.z < b[2] || p.z > b[5])
            continue;
        if (cp_inside_tree(&wt, p)) return i;
    }
    return -1;
}
