/*
 * test_narrow_phase.c - the pipeline's narrow phase (kernels/narrow_phase.h): particles of
 * several shapes, sizes and poses, every pair against pd_overlap_host on explicitly scaled and
 * posed meshes. The two paths compute the same overlap in the same frame but reach B's transform
 * through different roundings, so they agree to round-off: 1e-10 relative on V, 1e-10 of the size
 * on the centroid, 1e-9 on the normal.
 */
#define PD_DOUBLE 1
#include <stdint.h>
#include <string.h>

#include "contact_pair.h" /* cp_mesh_gap; includes narrow_phase.h */
#include "overlap_run.h"
#include "polydem.h"
#include "test.h"
#define TEST_RANDOM_SEED 7
#include "test_random.h"
#include "unit_shape.h"

enum { NSHAPE = 3, NBODY = 24 };

/* The NSHAPE test shapes concatenated as the engine stores them (narrow_phase.h). */
typedef struct shape_set {
    pd_mesh *m[NSHAPE];
    int voff[NSHAPE + 1], toff[NSHAPE + 1];
    double *vert, radius[NSHAPE]; /* radius: circumradius at size 1 */
    int *tri, *vt_off, *vt;
    np_shapes sh;
} shape_set;

static void shapes_free(shape_set *t)
{
    free(t->vert);
    free(t->tri);
    free(t->vt_off);
    free(t->vt);
    for (int s = 0; s < NSHAPE; s++)
        pd_mesh_destroy(t->m[s]);
}

static int shapes_build(shape_set *t)
{
    const char *names[NSHAPE] = {"schonhardt", "rock", "cube"};
    memset(t, 0, sizeof *t);
    int *voff = t->voff, *toff = t->toff;
    for (int s = 0; s < NSHAPE; s++) {
        t->m[s] = unit_shape(names[s], s == 1 ? 80 : 0);
        if (!t->m[s]) {
            TEST_FAILF("builtin %s", names[s]);
            shapes_free(t);
            return -1;
        }
        voff[s + 1] = voff[s] + t->m[s]->nverts;
        toff[s + 1] = toff[s] + t->m[s]->ntris;
    }
    pd_mesh **m = t->m;
    double *vert = t->vert = malloc(sizeof(double) * 3 * voff[NSHAPE]);
    int *tri = t->tri = malloc(sizeof(int) * 3 * toff[NSHAPE]);
    int *vt_off = t->vt_off = calloc((size_t)(voff[NSHAPE] + NSHAPE), sizeof(int));
    int *vt = t->vt = malloc(sizeof(int) * 3 * toff[NSHAPE]);
    for (int s = 0; s < NSHAPE; s++) {
        memcpy(vert + 3 * voff[s], m[s]->verts, sizeof(double) * 3 * m[s]->nverts);
        memcpy(tri + 3 * toff[s], m[s]->tris, sizeof(int) * 3 * m[s]->ntris);
        t->radius[s] = 0;
        for (int v = 0; v < m[s]->nverts; v++) {
            const double *x = m[s]->verts + 3 * v;
            t->radius[s] = fmax(t->radius[s], sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]));
        }
        /* CSR vertex -> triangle table, local to the shape */
        int *off = vt_off + voff[s] + s, *list = vt + 3 * toff[s], nv = m[s]->nverts;
        for (int i = 0; i < 3 * m[s]->ntris; i++)
            off[m[s]->tris[i] + 1]++;
        for (int v = 0; v < nv; v++)
            off[v + 1] += off[v];
        int *fill = calloc(nv > 0 ? (size_t)nv : 1, sizeof(int));
        for (int k = 0; k < m[s]->ntris; k++)
            for (int c = 0; c < 3; c++) {
                int v = m[s]->tris[3 * k + c];
                list[off[v] + fill[v]++] = k;
            }
        free(fill);
    }
    np_shapes sh = {vert, tri, voff, toff, vt_off, vt};
    t->sh = sh;
    return 0;
}

TEST(pairs_match_overlap_of_posed_scaled_meshes)
{
    shape_set set;
    if (shapes_build(&set)) return;
    pd_mesh **m = set.m;
    int *voff = set.voff, *toff = set.toff;
    double *vert = set.vert;
    int *tri = set.tri, *vt_off = set.vt_off, *vt = set.vt;
    np_shapes sh = set.sh;
    np_body b[NBODY];
    for (int i = 0; i < NBODY; i++) {
        b[i].x = v3(0.9 * rnd(), 0.9 * rnd(), 0.9 * rnd());
        rnd_quat(b[i].q);
        if (i % 6 == 5) memcpy(b[i].q, b[i - 1].q, sizeof b[i].q); /* some exactly aligned */
        b[i].size = 0.2 + 0.3 * rnd();
        b[i].shape = i % NSHAPE;
    }
    int ilen = ovl_iscratch_len(toff[NSHAPE], toff[NSHAPE], voff[NSHAPE], voff[NSHAPE]);
    int cap = 1024,
        rlen = ovl_rscratch_len(toff[NSHAPE], toff[NSHAPE], voff[NSHAPE], voff[NSHAPE], cap);
    int *iscr = malloc(sizeof(int) * ilen);
    double *rscr = malloc(sizeof(double) * rlen);
    int hits = 0, checked = 0, npairs = 0;
    int pairs[2 * NBODY * NBODY];
    double host[12 * NBODY * NBODY];
    for (int i = 0; i < NBODY; i++)
        for (int j = i + 1; j < NBODY; j++) {
            ovl_in in;
            double ra[9];
            np_setup(&sh, &b[i], &b[j], 0, &in, ra);
            in.iscr = iscr;
            in.rscr = rscr;
            in.pts_cap = cap;
            ovl_out o;
            ovl_compute(&in, &o);
            np_to_world(&b[i], ra, &o);
            pairs[2 * npairs] = i;
            pairs[2 * npairs + 1] = j;
            double h[12] = {o.hit,      o.degenerate, o.kept_a,     o.kept_b,
                            o.volume,   o.centroid.x, o.centroid.y, o.centroid.z,
                            o.normal.x, o.normal.y,   o.normal.z,   o.depth};
            memcpy(host + 12 * npairs++, h, sizeof h);
            /* reference: the meshes scaled by size, posed by (x, q) */
            pd_mesh *ma = NULL, *mb = NULL;
            pd_error err = {0};
            pd_mesh_from_arrays(m[b[i].shape]->verts, m[b[i].shape]->nverts, m[b[i].shape]->tris,
                                m[b[i].shape]->ntris, "a", &ma, &err);
            pd_mesh_from_arrays(m[b[j].shape]->verts, m[b[j].shape]->nverts, m[b[j].shape]->tris,
                                m[b[j].shape]->ntris, "b", &mb, &err);
            for (int k = 0; k < 3 * ma->nverts; k++)
                ma->verts[k] *= b[i].size;
            for (int k = 0; k < 3 * mb->nverts; k++)
                mb->verts[k] *= b[j].size;
            pd_pose pa = {{b[i].x.x, b[i].x.y, b[i].x.z},
                          {b[i].q[0], b[i].q[1], b[i].q[2], b[i].q[3]}};
            pd_pose pb = {{b[j].x.x, b[j].x.y, b[j].x.z},
                          {b[j].q[0], b[j].q[1], b[j].q[2], b[j].q[3]}};
            pd_contact r;
            pd_overlap_host(ma, &pa, mb, &pb, 0, &r, &err);
            checked++;
            CHECK_EQ_INT(r.hit, o.hit);
            if (r.hit && o.hit) {
                hits++;
                double sz = b[i].size;
                CHECK_REL(r.volume, o.volume, 1e-10);
                CHECK_NEAR(r.centroid[0], o.centroid.x, 1e-10 * sz);
                CHECK_NEAR(r.centroid[1], o.centroid.y, 1e-10 * sz);
                CHECK_NEAR(r.centroid[2], o.centroid.z, 1e-10 * sz);
                CHECK_NEAR(r.normal[0], o.normal.x, 1e-9);
                CHECK_NEAR(r.normal[1], o.normal.y, 1e-9);
                CHECK_NEAR(r.normal[2], o.normal.z, 1e-9);
                CHECK_NEAR(r.depth, o.depth, 1e-9 * sz);
            }
            pd_mesh_destroy(ma);
            pd_mesh_destroy(mb);
        }
    printf("  %d pairs, %d overlapping\n", checked, hits);
    CHECK(hits >= 15); /* the test must exercise real contacts */

    /* the same pairs through the OpenCL kernel: the host build's numbers to 1e-12 (double) */
    pd_device *dev = NULL;
    pd_error err = {0};
    double x[3 * NBODY], q[4 * NBODY], size[NBODY],
        *dout = malloc(sizeof(double) * OVL_RESULT_LEN * npairs);
    int shape[NBODY];
    for (int i = 0; i < NBODY; i++) {
        x[3 * i] = b[i].x.x;
        x[3 * i + 1] = b[i].x.y;
        x[3 * i + 2] = b[i].x.z;
        memcpy(q + 4 * i, b[i].q, sizeof b[i].q);
        size[i] = b[i].size;
        shape[i] = b[i].shape;
    }
    np_tables tabs = {NSHAPE, vert, tri, voff, toff, vt_off, vt};
    if (pd_device_open(-1, &dev, &err) != PD_OK ||
        np_run_cl(dev, &tabs, x, q, size, shape, NBODY, pairs, npairs, 1, dout, &err) != PD_OK) {
        TEST_FAILF("opencl narrow phase: %s", err.msg);
    } else {
        int agree = 1;
        for (int k = 0; k < npairs; k++) {
            const double *h = host + 12 * k, *d = dout + OVL_RESULT_LEN * k;
            agree &= h[0] == d[0];
            for (int c = 4; c < 12; c++)
                agree &= fabs(h[c] - d[c]) <= 1e-12 * (fabs(h[c]) + (c == 4 ? 0 : b[0].size));
        }
        CHECK(agree);
    }
    pd_device_close(dev);
    free(dout);
    free(iscr);
    free(rscr);
    shapes_free(&set);
}

/* Overlap of bodies a and b (the engine's narrow phase, host build): 1 when they overlap. */
static int overlaps(const np_shapes *sh, const np_body *a, const np_body *b, int *iscr,
                    double *rscr, int cap)
{
    ovl_in in;
    double ra[9];
    np_setup(sh, a, b, 0, &in, ra);
    in.iscr = iscr;
    in.rscr = rscr;
    in.pts_cap = cap;
    ovl_out o;
    ovl_compute(&in, &o);
    return o.hit;
}

/* Least distance between a vertex of posed body a and one of b: an upper bound on the distance
 * between the solids, computed without any of the code under test. */
static double vertex_distance(const shape_set *t, const np_body *a, const np_body *b)
{
    double best = INFINITY, ra[9], rb[9];
    np_quat_matrix(a->q, ra);
    np_quat_matrix(b->q, rb);
    const pd_mesh *ma = t->m[a->shape], *mb = t->m[b->shape];
    for (int i = 0; i < ma->nverts; i++) {
        const double *u = ma->verts + 3 * i;
        double p[3];
        for (int k = 0; k < 3; k++)
            p[k] = a->size * (ra[3 * k] * u[0] + ra[3 * k + 1] * u[1] + ra[3 * k + 2] * u[2]) +
                   (k == 0   ? a->x.x
                    : k == 1 ? a->x.y
                             : a->x.z);
        for (int j = 0; j < mb->nverts; j++) {
            const double *w = mb->verts + 3 * j;
            double d2 = 0;
            for (int k = 0; k < 3; k++) {
                double q =
                    b->size * (rb[3 * k] * w[0] + rb[3 * k + 1] * w[1] + rb[3 * k + 2] * w[2]) +
                    (k == 0   ? b->x.x
                     : k == 1 ? b->x.y
                              : b->x.z);
                d2 += (p[k] - q) * (p[k] - q);
            }
            best = fmin(best, d2);
        }
    }
    return sqrt(best);
}

/*
 * The gaps that let the contact stage skip a separated pair (np_hull_gap for convex hulls apart,
 * cp_mesh_gap for surfaces apart) are lower bounds on the distance between the solids: for pairs
 * of random shapes, poses and sizes whose overlap is empty, no gap exceeds the least vertex-vertex
 * distance (an upper bound on the distance), and B moved by 0.999 of the gap in any of 24 random
 * directions still does not overlap A. Two aligned cubes a known distance apart: cp_mesh_gap
 * gives it to 1 % (which it takes off by design); np_hull_gap's few Gilbert steps, zigzagging
 * between the cubes' corners, a looser bound.
 */
TEST(separation_gaps_are_lower_bounds)
{
    shape_set set;
    if (shapes_build(&set)) return;
    int cap = 1024, nt = set.toff[NSHAPE], nv = set.voff[NSHAPE];
    int *iscr = malloc(sizeof(int) * ovl_iscratch_len(nt, nt, nv, nv));
    double *rscr = malloc(sizeof(double) * ovl_rscratch_len(nt, nt, nv, nv, cap));
    int misses = 0, hull = 0, mesh_only = 0, moved = 0;
    for (int trial = 0; trial < 400; trial++) {
        np_body a, b;
        a.shape = trial % NSHAPE;
        b.shape = (trial / NSHAPE) % NSHAPE;
        a.size = 0.2 + 0.3 * rnd();
        b.size = 0.2 + 0.3 * rnd();
        rnd_quat(a.q);
        rnd_quat(b.q);
        a.x = v3(0.3 * rnd(), 0.3 * rnd(), 0.3 * rnd());
        /* bounding spheres overlapping: the pairs the contact stage computes */
        pd_v3 d = v3_unit(v3(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5));
        double reach = set.radius[a.shape] * a.size + set.radius[b.shape] * b.size;
        b.x = v3_add(a.x, v3_scale(d, reach * (0.55 + 0.45 * rnd())));
        if (overlaps(&set.sh, &a, &b, iscr, rscr, cap)) continue;
        misses++;
        ovl_in in;
        double ra[9];
        np_setup(&set.sh, &a, &b, 0, &in, ra);
        double hg = np_hull_gap(&in, set.radius[a.shape] * a.size, set.radius[b.shape] * b.size,
                                CP_GAP_ITERS);
        double mg = cp_mesh_gap(&in, 0.2 * reach, 0, rscr, iscr);
        hull += hg > 0;
        mesh_only += hg <= 0 && mg > 0;
        double vd = vertex_distance(&set, &a, &b);
        CHECK(hg <= vd);
        CHECK(mg <= vd);
        double g = fmax(hg, mg);
        if (!(g > 0)) continue;
        for (int k = 0; k < 24; k++) {
            np_body c = b;
            pd_v3 u = v3_unit(v3(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5));
            c.x = v3_add(b.x, v3_scale(u, 0.999 * g));
            int hit = overlaps(&set.sh, &a, &c, iscr, rscr, cap);
            CHECK(!hit);
            moved += !hit;
        }
    }
    printf("  %d separated pairs: %d with a hull gap, %d more with a surface gap only; %d moves "
           "by 0.999 of the gap, none overlapping\n",
           misses, hull, mesh_only, moved);
    CHECK(misses > 100);
    CHECK(hull > 20); /* both kinds of gap are exercised */
    CHECK(mesh_only > 10);

    /* aligned cubes of size 0.3 m (edge cbrt(pi / 6) times that), faces 0.05 m apart */
    double edge = cbrt(3.14159265358979323846 / 6) * 0.3;
    np_body a = {v3(0, 0, 0), {1, 0, 0, 0}, 0.3, 2},
            b = {v3(edge + 0.05, 0.01, -0.02), {1, 0, 0, 0}, 0.3, 2};
    ovl_in in;
    double ra[9];
    np_setup(&set.sh, &a, &b, 0, &in, ra);
    double hg = np_hull_gap(&in, set.radius[2] * 0.3, set.radius[2] * 0.3, CP_GAP_ITERS);
    double mg = cp_mesh_gap(&in, 0.1, 0, rscr, iscr);
    printf("  cubes 0.05 m apart: hull gap %.6g m, surface gap %.6g m\n", hg, mg);
    CHECK(hg <= 0.05 && hg > 0.2 * 0.05); /* a bound, not the distance (CP_GAP_ITERS steps) */
    CHECK(mg <= 0.05 && mg >= 0.989 * 0.05);
    /* the search gives up (0) once two triangles are within `least`, and not before */
    CHECK(cp_mesh_gap(&in, 0.1, 0.06, rscr, iscr) == 0);
    CHECK(cp_mesh_gap(&in, 0.1, 0.04, rscr, iscr) == mg);
    free(iscr);
    free(rscr);
    shapes_free(&set);
}

int main(void)
{
    RUN(pairs_match_overlap_of_posed_scaled_meshes);
    RUN(separation_gaps_are_lower_bounds);
    return TEST_DONE();
}
