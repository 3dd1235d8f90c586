/*
 * vertex_clusters.c - a mesh's vertices in small groups of neighbours, each bounded by a disc (a
 * flat cylinder about its least spread), for the overlap filter (ovl_in's vc_* and disc_*,
 * kernels/overlap_predicates.h): at a contact's depth only a few groups reach the other
 * particle's half-plane (eq. 5.5) or hold a mesh's extreme along the filter's direction (eq. 5.4),
 * and the filter projects only their vertices.
 */
#include <math.h>
#include <stdlib.h>

#define PD_DOUBLE 1 /* the kernels' cluster sizes (overlap_predicates.h); the discs are doubles */
#include "mesh_internal.h"
#include "overlap_predicates.h"
#include "overlap_run.h"

_Static_assert(NP_DISC_LEN == OVL_DISC, "overlap_run.h's NP_DISC_LEN is the kernels' OVL_DISC");

/*
 * The vertices' order: halves of halves, each cut at the median of its box's longest side, so that
 * every run of OVL_CLUSTER is a compact patch (a Morton order's runs jumped across a sphere).
 */
typedef struct {
    double x; /* the coordinate being split on */
    int v;
} vc_key;

static int vc_key_cmp(const void *a, const void *b)
{
    const vc_key *p = a, *q = b;
    if (p->x != q->x) return p->x < q->x ? -1 : 1;
    return (p->v > q->v) - (p->v < q->v); /* ties by index: the same order on every platform */
}

/* Orders ord[0..n-1] (vertex indices) into clusters; key is scratch of n. */
static void vc_split(const double *v, int *ord, int n, vc_key *key)
{
    while (n > OVL_CLUSTER) {
        double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
        for (int h = 0; h < n; h++)
            for (int k = 0; k < 3; k++) {
                lo[k] = fmin(lo[k], v[3 * ord[h] + k]);
                hi[k] = fmax(hi[k], v[3 * ord[h] + k]);
            }
        int ax = 0;
        for (int k = 1; k < 3; k++)
            if (hi[k] - lo[k] > hi[ax] - lo[ax]) ax = k;
        for (int h = 0; h < n; h++) {
            key[h].x = v[3 * ord[h] + ax];
            key[h].v = ord[h];
        }
        qsort(key, (size_t)n, sizeof *key, vc_key_cmp);
        for (int h = 0; h < n; h++)
            ord[h] = key[h].v;
        /* the lower half rounded up to whole clusters: only the last cluster is short */
        int left = (n / 2 + OVL_CLUSTER - 1) / OVL_CLUSTER * OVL_CLUSTER;
        vc_split(v, ord, left, key);
        ord += left; /* the upper half, without recursing */
        n -= left;
    }
}

size_t ovl_discs_len(int nv)
{
    return OVL_DISC * (size_t)ovl_nclusters(nv);
}

/*
 * The disc of the vertices vc[0..n-1] into b (OVL_DISC reals, as ovl_cluster_bounds reads them):
 * centre m at the middle of their box, normal n along their least spread (a surface patch's
 * normal), radius r in the plane and half-thickness h along n, and a bound on |v| and |m|.
 */
static void vc_disc(const double *v, const int *vc, int n, double *b)
{
    double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    for (int h = 0; h < n; h++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], v[3 * vc[h] + k]);
            hi[k] = fmax(hi[k], v[3 * vc[h] + k]);
        }
    double m[3], cov[3][3] = {{0}};
    for (int k = 0; k < 3; k++)
        m[k] = 0.5 * (lo[k] + hi[k]);
    for (int h = 0; h < n; h++)
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                cov[i][j] += (v[3 * vc[h] + i] - m[i]) * (v[3 * vc[h] + j] - m[j]);
    double w[3], ev[3][3];
    mesh_sym3_eigen(cov, w, ev);
    int least = w[0] <= w[1] && w[0] <= w[2] ? 0 : w[1] <= w[2] ? 1 : 2;
    double nrm[3] = {ev[0][least], ev[1][least], ev[2][least]};
    double r = 0, th = 0, spread = 0;
    for (int h = 0; h < n; h++) {
        double q[3], a = 0, q2 = 0;
        for (int k = 0; k < 3; k++)
            q[k] = v[3 * vc[h] + k] - m[k];
        for (int k = 0; k < 3; k++)
            a += q[k] * nrm[k];
        for (int k = 0; k < 3; k++)
            q2 += (q[k] - a * nrm[k]) * (q[k] - a * nrm[k]);
        r = fmax(r, sqrt(q2));
        th = fmax(th, fabs(a));
        spread = fmax(spread, sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]));
    }
    double mn = sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]), reach = mn + spread;
    /*
     * r and h padded by 1e-6 of the reach: the decomposition's own rounding is far below it, and
     * the kernel's single precision rounds the vertices, the centre and the normal each by 6e-8
     * of it (or of 1), which the padded disc still covers; the kernel's bound adds its own
     * arithmetic's rounding (ovl_cluster_bounds).
     */
    for (int k = 0; k < 3; k++) {
        b[k] = m[k];
        b[3 + k] = nrm[k];
    }
    b[6] = r * (1 + 1e-6) + 1e-6 * reach;
    b[7] = th * (1 + 1e-6) + 1e-6 * reach;
    b[8] = reach * (1 + 1e-6);
}

/* The clusters of the nv vertices v into vc (2 nv ints) and disc (ovl_discs_len(nv) reals), as
 * ovl_in's vc_* and disc_* read them. Returns PD_OK or PD_ENOMEM (for its scratch). */
static int vc_build(const double *v, int nv, int *vc, double *disc)
{
    vc_key *key = malloc(sizeof *key * (size_t)(nv > 0 ? nv : 1));
    if (!key) return PD_ENOMEM;
    for (int h = 0; h < nv; h++)
        vc[h] = h;
    vc_split(v, vc, nv, key);
    for (int h = 0; h < nv; h++)
        vc[nv + vc[h]] = h / OVL_CLUSTER;
    free(key);
    for (int c = 0; c < ovl_nclusters(nv); c++) {
        int end = (c + 1) * OVL_CLUSTER < nv ? (c + 1) * OVL_CLUSTER : nv;
        vc_disc(v, vc + c * OVL_CLUSTER, end - c * OVL_CLUSTER, disc + OVL_DISC * c);
    }
    return PD_OK;
}

int ovl_vertex_clusters(const double *v, int nv, int **vc_out, double **disc_out)
{
    int ncl = ovl_nclusters(nv);
    int *vc = malloc(sizeof *vc * 2 * (size_t)(nv > 0 ? nv : 1));
    double *disc = malloc(sizeof *disc * OVL_DISC * (size_t)(ncl > 0 ? ncl : 1));
    if (!vc || !disc || vc_build(v, nv, vc, disc) != PD_OK) {
        free(vc);
        free(disc);
        return PD_ENOMEM;
    }
    *vc_out = vc;
    *disc_out = disc;
    return PD_OK;
}

int np_cluster_tables(const double *vert, const int *voff, int nshape, int nclust, int **vc_out,
                      int **coff_out, double **disc_out)
{
    int *coff = calloc((size_t)nshape + 1, sizeof *coff);
    if (!coff) return PD_ENOMEM;
    for (int s = 0; s < nshape; s++)
        coff[s + 1] = coff[s] + (s < nclust ? ovl_nclusters(voff[s + 1] - voff[s]) : 0);
    /* one element at least, and zeroed: an empty table is still a buffer the kernels get */
    int *vc = calloc(2 * (size_t)voff[nclust] + 1, sizeof *vc);
    double *disc = calloc(OVL_DISC * (size_t)coff[nshape] + 1, sizeof *disc);
    int rc = vc && disc ? PD_OK : PD_ENOMEM;
    /* each shape's straight into its place (an analytic sphere has no vertices, nothing to do) */
    for (int s = 0; s < nclust && rc == PD_OK; s++)
        rc = vc_build(vert + 3 * (size_t)voff[s], voff[s + 1] - voff[s], vc + 2 * (size_t)voff[s],
                      disc + OVL_DISC * (size_t)coff[s]);
    if (rc != PD_OK) {
        free(coff);
        free(vc);
        free(disc);
        return rc;
    }
    *vc_out = vc;
    *coff_out = coff;
    *disc_out = disc;
    return PD_OK;
}
