/*
 * test_narrow_phase.c - the pipeline's narrow phase (kernels/narrow_phase.h): particles of
 * several shapes, sizes and poses, every pair against pd_overlap_host on explicitly scaled and
 * posed meshes. The two paths compute the same overlap in the same frame but reach B's transform
 * through different roundings, so they agree to round-off: 1e-10 relative on V, 1e-10 of the size
 * on the centroid, 1e-9 on the normal.
 */
#define PD_DOUBLE 1
#include <float.h>
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

/* The shapes names[s] with tris[s] triangles (0: the built-in's own count). */
static int shapes_build_of(shape_set *t, const char *const names[NSHAPE], const int tris[NSHAPE])
{
    memset(t, 0, sizeof *t);
    int *voff = t->voff, *toff = t->toff;
    for (int s = 0; s < NSHAPE; s++) {
        t->m[s] = unit_shape(names[s], tris[s]);
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
    np_shapes sh = {vert, tri, voff, toff, vt_off, vt, NULL, NULL, NULL};
    t->sh = sh;
    return 0;
}

static int shapes_build(shape_set *t)
{
    static const char *const names[NSHAPE] = {"schonhardt", "rock", "cube"};
    static const int tris[NSHAPE] = {0, 80, 0};
    return shapes_build_of(t, names, tris);
}

/*
 * The overlap of bodies a and b by the engine's narrow phase (host build), in world coordinates,
 * into *o and, where rec is not NULL, as 12 doubles: hit, degenerate, kept_a, kept_b, volume,
 * centroid, normal, depth (the leading fields of the kernels' record).
 */
static void np_host(const np_shapes *sh, const np_body *a, const np_body *b, int *iscr,
                    double *rscr, int cap, ovl_out *o, double *rec)
{
    ovl_in in;
    double ra[9];
    np_setup(sh, a, b, 0, &in, ra);
    in.iscr = iscr;
    in.rscr = rscr;
    in.pts_cap = cap;
    ovl_compute(&in, o);
    np_to_world(a, ra, o);
    if (!rec) return;
    double h[12] = {o->hit,      o->degenerate, o->kept_a,     o->kept_b,
                    o->volume,   o->centroid.x, o->centroid.y, o->centroid.z,
                    o->normal.x, o->normal.y,   o->normal.z,   o->depth};
    memcpy(rec, h, sizeof h);
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
        double draw[3];
        rnd3(draw);
        b[i].x = v3(0.9 * draw[0], 0.9 * draw[1], 0.9 * draw[2]);
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
            ovl_out o;
            np_host(&sh, &b[i], &b[j], iscr, rscr, cap, &o, host + 12 * npairs);
            pairs[2 * npairs] = i;
            pairs[2 * npairs + 1] = j;
            npairs++;
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
                /*
                 * The two sums are of simplices from A's centre (eq. 5.10), each up to A's reach
                 * cubed, in frames rounded differently. A corner just pressed in sums to ~1e-8 of
                 * its terms (overlap.h re-sums only below 2e-12), so its volume agrees only to a
                 * few ulps of the terms: 64 eps R_a^3, and its centroid to that over V. The first
                 * such pair drawn differed by 1.3e-18 m^3 (V 3.4e-10 m^3, 5.5e-4 m deep); a wrong
                 * scale or pose is off by O(V).
                 */
                double ra = set.radius[b[i].shape] * sz, terms = 64 * DBL_EPSILON * ra * ra * ra;
                double ctol = 1e-10 * sz + terms * 2 * ra / r.volume; /* (dM + c dV) / V */
                CHECK_NEAR(r.volume, o.volume, 1e-10 * r.volume + terms);
                CHECK_NEAR(r.centroid[0], o.centroid.x, ctol);
                CHECK_NEAR(r.centroid[1], o.centroid.y, ctol);
                CHECK_NEAR(r.centroid[2], o.centroid.z, ctol);
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
    np_tables tabs = {NSHAPE, vert, tri, voff, toff, vt_off, vt, NULL, NULL, NULL};
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
    ovl_out o;
    np_host(sh, a, b, iscr, rscr, cap, &o, NULL);
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
        double draw[3];
        rnd3(draw);
        a.x = v3(0.3 * draw[0], 0.3 * draw[1], 0.3 * draw[2]);
        /* bounding spheres overlapping: the pairs the contact stage computes */
        rnd3(draw);
        pd_v3 d = v3_unit(v3(draw[0] - 0.5, draw[1] - 0.5, draw[2] - 0.5));
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
            double draw[3];
            rnd3(draw);
            pd_v3 u = v3_unit(v3(draw[0] - 0.5, draw[1] - 0.5, draw[2] - 0.5));
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

/*
 * The filter's vertex clusters in the engine's shape tables (np_cluster_tables, np_shapes' vc,
 * coff, disc): for shapes large enough to use them (OVL_CLUSTER_MIN vertices a pair), the narrow
 * phase gives bit for bit what it gives without them, on the host and through the OpenCL kernel
 * in both precisions (the clusters only spare projections, kernels/overlap.h). The discs are
 * read: with their radius and thickness zeroed, the bounds miss vertices and results change.
 */
TEST(clustered_narrow_phase_matches_unclustered)
{
    static const char *const names[NSHAPE] = {"rock", "icosphere", "rock"};
    static const int tris[NSHAPE] = {2500, 5120, 4000};
    enum { NP = 24 };
    shape_set set;
    if (shapes_build_of(&set, names, tris)) return;
    int *vc = NULL, *coff = NULL;
    double *disc = NULL;
    if (np_cluster_tables(set.vert, set.voff, NSHAPE, NSHAPE, &vc, &coff, &disc) != PD_OK) {
        TEST_FAILF("np_cluster_tables: out of memory");
        shapes_free(&set);
        return;
    }
    np_shapes plain = set.sh, clus = set.sh;
    clus.vc = vc;
    clus.coff = coff;
    clus.disc = disc;
    int nt = set.toff[NSHAPE], nv = set.voff[NSHAPE], cap = 4096;
    int *iscr = malloc(sizeof(int) * ovl_iscratch_len(nt, nt, nv, nv));
    double *rscr = malloc(sizeof(double) * ovl_rscratch_len(nt, nt, nv, nv, cap));
    double x[3 * 2 * NP], q[4 * 2 * NP], size[2 * NP], ref[12 * NP], rec[12];
    int shape[2 * NP], pairs[2 * NP], hits = 0, same = 1;
    np_body b[2 * NP];
    for (int p = 0; p < NP; p++) {
        np_body *a = &b[2 * p], *c = &b[2 * p + 1];
        a->shape = p % NSHAPE;
        c->shape = (p / NSHAPE + 1) % NSHAPE;
        a->size = 0.2 + 0.3 * rnd();
        c->size = 0.2 + 0.3 * rnd();
        rnd_quat(a->q);
        rnd_quat(c->q);
        double draw[3];
        rnd3(draw);
        a->x = v3(draw[0], draw[1], draw[2]);
        /* centres about a size apart: shallow overlaps, the DEM's, and near misses */
        rnd3(draw);
        pd_v3 d = v3_unit(v3(draw[0] - 0.5, draw[1] - 0.5, draw[2] - 0.5));
        c->x = v3_add(a->x, v3_scale(d, 0.5 * (a->size + c->size) * (0.85 + 0.2 * rnd())));
        ovl_out o;
        np_host(&plain, a, c, iscr, rscr, cap, &o, ref + 12 * p);
        np_host(&clus, a, c, iscr, rscr, cap, &o, rec);
        same &= memcmp(rec, ref + 12 * p, sizeof rec) == 0;
        hits += o.hit;
        for (int k = 0; k < 2; k++) {
            const np_body *e = &b[2 * p + k];
            x[3 * (2 * p + k)] = e->x.x;
            x[3 * (2 * p + k) + 1] = e->x.y;
            x[3 * (2 * p + k) + 2] = e->x.z;
            memcpy(q + 4 * (2 * p + k), e->q, sizeof e->q);
            size[2 * p + k] = e->size;
            shape[2 * p + k] = e->shape;
            pairs[2 * p + k] = 2 * p + k;
        }
    }
    printf("  %d pairs of %d-%d triangles, %d overlapping\n", NP, tris[0], tris[1], hits);
    CHECK(same);
    CHECK(hits >= NP / 3);

    /* discs with no radius or thickness: the clusters are what the filter reads */
    double *flat = malloc(sizeof(double) * NP_DISC_LEN * (size_t)coff[NSHAPE]);
    memcpy(flat, disc, sizeof(double) * NP_DISC_LEN * (size_t)coff[NSHAPE]);
    for (int k = 0; k < coff[NSHAPE]; k++)
        flat[NP_DISC_LEN * k + 6] = flat[NP_DISC_LEN * k + 7] = 0;
    np_shapes bad = clus;
    bad.disc = flat;
    int changed = 0;
    for (int p = 0; p < NP; p++) {
        ovl_out o;
        np_host(&bad, &b[2 * p], &b[2 * p + 1], iscr, rscr, cap, &o, rec);
        changed += memcmp(rec, ref + 12 * p, sizeof rec) != 0;
    }
    printf("  with flattened discs %d of %d pairs change\n", changed, NP);
    CHECK(changed > 0);

    /* the OpenCL kernel with the clusters: the host's numbers (double, as in the test above), and
     * in single precision its own numbers without them, bit for bit */
    pd_device *dev = NULL;
    pd_error err = {0};
    double *d1 = malloc(sizeof(double) * OVL_RESULT_LEN * NP),
           *s0 = malloc(sizeof(double) * OVL_RESULT_LEN * NP),
           *s1 = malloc(sizeof(double) * OVL_RESULT_LEN * NP),
           *sf = malloc(sizeof(double) * OVL_RESULT_LEN * NP);
    np_tables tp = {NSHAPE,     set.vert, set.tri, set.voff, set.toff,
                    set.vt_off, set.vt,   NULL,    NULL,     NULL},
              tc = tp, tf;
    tc.vc = vc;
    tc.coff = coff;
    tc.disc = disc;
    tf = tc;
    tf.disc = flat;
    if (pd_device_open(-1, &dev, &err) != PD_OK ||
        np_run_cl(dev, &tc, x, q, size, shape, 2 * NP, pairs, NP, 1, d1, &err) != PD_OK ||
        np_run_cl(dev, &tp, x, q, size, shape, 2 * NP, pairs, NP, 0, s0, &err) != PD_OK ||
        np_run_cl(dev, &tc, x, q, size, shape, 2 * NP, pairs, NP, 0, s1, &err) != PD_OK ||
        np_run_cl(dev, &tf, x, q, size, shape, 2 * NP, pairs, NP, 0, sf, &err) != PD_OK) {
        TEST_FAILF("opencl narrow phase: %s", err.msg);
    } else {
        int agree = 1, single_same = 1, single_hits = 0, flat_changed = 0;
        for (int p = 0; p < NP; p++) {
            const double *h = ref + 12 * p, *d = d1 + OVL_RESULT_LEN * p;
            agree &= h[0] == d[0];
            for (int c = 4; c < 12; c++)
                agree &= fabs(h[c] - d[c]) <= 1e-12 * (fabs(h[c]) + (c == 4 ? 0 : b[0].size));
            for (int c = 0; c < OVL_RESULT_LEN; c++)
                single_same &= s0[OVL_RESULT_LEN * p + c] == s1[OVL_RESULT_LEN * p + c];
            single_hits += s1[OVL_RESULT_LEN * p] != 0;
            flat_changed += memcmp(sf + OVL_RESULT_LEN * p, s0 + OVL_RESULT_LEN * p,
                                   sizeof(double) * OVL_RESULT_LEN) != 0;
        }
        printf("  opencl: double agrees %d, single with and without clusters the same %d (%d "
               "overlapping), %d pairs changed by flattened discs\n",
               agree, single_same, single_hits, flat_changed);
        CHECK(flat_changed > 0); /* the kernel reads the clusters */
        CHECK(agree);
        CHECK(single_same);
        CHECK(single_hits >= NP / 3);
    }
    pd_device_close(dev);
    free(d1);
    free(s0);
    free(s1);
    free(sf);
    free(flat);
    free(vc);
    free(coff);
    free(disc);
    free(iscr);
    free(rscr);
    shapes_free(&set);
}

int main(void)
{
    RUN(pairs_match_overlap_of_posed_scaled_meshes);
    RUN(separation_gaps_are_lower_bounds);
    RUN(clustered_narrow_phase_matches_unclustered);
    return TEST_DONE();
}
