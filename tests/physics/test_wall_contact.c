/*
 * test_wall_contact.c - a particle against a wall through the wall's triangle BVH (thesis section
 * 5.6; kernels/wall_bvh.h, np_wall_local in kernels/narrow_phase.h, OVL_OPEN_B in
 * kernels/overlap_predicates.h): only the wall's triangles near the particle take part, and
 * whether a particle's vertex lies inside the wall comes from the segment to its centroid plus
 * one ray through the tree. Checked against two independent answers for the same poses:
 *   - pd_overlap_host on the explicitly posed meshes (the whole closed wall as B): agreement to
 *     round-off, 1e-10 relative on V, 1e-10 of the particle size on centroid and depth, 1e-9 on
 *     the normal (as tests/physics/test_narrow_phase.c: different roundings of the same transform);
 *   - the narrow phase with the whole wall as a closed B: the same triangles, the same order of
 *     cusps, so agreement to 1e-12 (only the snapping resolution, set by the coordinates in play,
 *     differs).
 * Walls: a slab whose faces are fine grids (flat, coplanar with aligned cubes: the degenerate
 * case), and a large non-convex rock. Particles straddle the surface, hang over edges, and sink
 * with their centroids inside the wall (where the centroid's ray decides).
 */
#define PD_DOUBLE 1
#include <stdint.h>
#include <string.h>

#include "narrow_phase.h"
#include "overlap_run.h"
#include "polydem.h"
#include "grid_box.h"
#include "test.h"
#define TEST_RANDOM_SEED 11
#include "test_random.h"
#include "unit_shape.h"
#include "wall_tree.h"

static const double slab_h[3] = {1, 1, 0.2};

/* The closed box [-h, h] with every face an n x n grid, as a welded mesh. */
static pd_mesh *grid_box(const double h[3], int n)
{
    double *v, c[3] = {0, 0, 0};
    int *t, nv, nt;
    grid_box_arrays(c, h, n, &v, &t, &nv, &nt);
    pd_mesh *m = NULL;
    pd_error err = {0};
    if (pd_mesh_from_arrays(v, nv, t, nt, "grid box", &m, &err) != PD_OK)
        printf("  grid box: %s\n", err.msg);
    free(v);
    free(t);
    return m;
}

/* Shape tables of the particle shapes then one wall (about its centroid), as the engine has. */
typedef struct tables {
    np_shapes sh;
    double *vert, unit_vol[4];
    int *tri, voff[5], toff[5], *vt_off, *vt;
} tables;

static void tables_make(pd_mesh *const *m, int ns, tables *t)
{
    memset(t, 0, sizeof *t);
    for (int s = 0; s < ns; s++) {
        t->voff[s + 1] = t->voff[s] + m[s]->nverts;
        t->toff[s + 1] = t->toff[s] + m[s]->ntris;
    }
    t->vert = malloc(sizeof(double) * 3 * t->voff[ns]);
    t->tri = malloc(sizeof(int) * 3 * t->toff[ns]);
    t->vt_off = calloc((size_t)(t->voff[ns] + ns), sizeof(int));
    t->vt = malloc(sizeof(int) * 3 * t->toff[ns]);
    for (int s = 0; s < ns; s++) {
        memcpy(t->vert + 3 * t->voff[s], m[s]->verts, sizeof(double) * 3 * m[s]->nverts);
        memcpy(t->tri + 3 * t->toff[s], m[s]->tris, sizeof(int) * 3 * m[s]->ntris);
        pd_mass_props mp;
        pd_mesh_mass_props(m[s], &mp);
        t->unit_vol[s] = mp.volume;
        int *off, *list;
        ovl_vertex_triangles(m[s], &off, &list);
        memcpy(t->vt_off + t->voff[s] + s, off, sizeof(int) * (m[s]->nverts + 1));
        memcpy(t->vt + 3 * t->toff[s], list, sizeof(int) * 3 * m[s]->ntris);
        free(off);
        free(list);
    }
    np_shapes sh = {t->vert, t->tri, t->voff, t->toff, t->vt_off, t->vt, NULL, NULL, NULL};
    t->sh = sh;
}

static void tables_free(tables *t)
{
    free(t->vert);
    free(t->tri);
    free(t->vt_off);
    free(t->vt);
}

/* A copy of m scaled by k. */
static pd_mesh *scaled(const pd_mesh *m, double k)
{
    pd_mesh *c = NULL;
    pd_error err = {0};
    pd_mesh_from_arrays(m->verts, m->nverts, m->tris, m->ntris, "copy", &c, &err);
    for (int i = 0; i < 3 * c->nverts; i++)
        c->verts[i] *= k;
    return c;
}

static void rotate(const double q[4], const double v[3], double out[3])
{
    double r[3][3];
    pd_quat_to_matrix(q, r);
    for (int i = 0; i < 3; i++)
        out[i] = r[i][0] * v[0] + r[i][1] * v[1] + r[i][2] * v[2];
}

enum { NPART = 3 };

/*
 * n particles of random shape, size and orientation placed by `place` (their centroid in the
 * wall's frame) against wall mesh `wall` (about its centroid) posed at (xw, qw). Returns the
 * number of overlapping placements; counts failures through the CHECK macros.
 */
static int run_wall(pd_mesh *wall, const double xw[3], const double qw[4], int n,
                    int (*place)(double size, double p[3]), int aligned_every)
{
    const char *names[NPART] = {"cube", "rock", "schonhardt"};
    pd_mesh *m[NPART + 1];
    for (int s = 0; s < NPART; s++)
        m[s] = unit_shape(names[s], s == 1 ? 80 : 0);
    m[NPART] = wall;
    tables t;
    tables_make(m, NPART + 1, &t);
    wall_tree tree;
    pd_error err = {0};
    int ntw = wall->ntris;
    if (wall_tree_build(wall->verts, wall->tris, ntw, &tree, "wall", &err) != PD_OK) {
        TEST_FAILF("%s", err.msg);
        return 0;
    }
    double rmax = 0; /* the largest particle: circumradius at size 0.3 */
    for (int s = 0; s < NPART; s++)
        for (int i = 0; i < m[s]->nverts; i++) {
            const double *p = m[s]->verts + 3 * i;
            rmax = fmax(rmax, 0.3 * sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]));
        }
    int cap = wall_tree_max_near(&tree, wall->verts, wall->tris, ntw, 2 * rmax * (1 + 2e-5));
    printf("  wall of %d triangles: at most %d near one particle\n", ntw, cap);
    CHECK(cap > 0 && cap < ntw);
    int maxv = 0, maxt = 0;
    for (int s = 0; s <= NPART; s++) {
        maxv = m[s]->nverts > maxv ? m[s]->nverts : maxv;
        maxt = m[s]->ntris > maxt ? m[s]->ntris : maxt;
    }
    int pts_cap = ovl_pts_cap(maxt, maxt);
    int ilen = np_wall_ilen(cap) + ovl_iscratch_len(maxt, maxt, maxv, maxv);
    int rlen = np_wall_rlen(cap) + ovl_rscratch_len(maxt, maxt, maxv, maxv, pts_cap);
    int *iscr = malloc(sizeof(int) * ilen);
    double *rscr = malloc(sizeof(double) * rlen);
    np_body wb;
    wb.x = v3(xw[0], xw[1], xw[2]);
    memcpy(wb.q, qw, sizeof wb.q);
    wb.size = 1;
    wb.shape = NPART;
    wb_tree wt = {tree.box, tree.kid, tree.order, t.vert + 3 * t.voff[NPART],
                  t.tri + 3 * t.toff[NPART]};
    int hits = 0, deep = 0, most = 0, buried = 0;
    for (int k = 0; k < n; k++) {
        np_body a;
        a.shape = k % NPART;
        a.size = 0.1 + 0.2 * rnd();
        double pl[3], pw[3];
        int under = place(a.size, pl);
        rotate(qw, pl, pw);
        a.x = v3(pw[0] + xw[0], pw[1] + xw[1], pw[2] + xw[2]);
        if (aligned_every && k % aligned_every == 0)
            memcpy(a.q, qw, sizeof a.q); /* faces parallel to the wall's: coplanar contacts */
        else
            rnd_quat(a.q);
        /* through the tree */
        ovl_in in;
        double ra[9];
        np_setup(&t.sh, &a, &wb, 0, &in, ra);
        double reach = 0;
        for (int i = 0; i < m[a.shape]->nverts; i++) {
            const double *p = m[a.shape]->verts + 3 * i;
            reach = fmax(reach, a.size * sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]));
        }
        int nt = np_wall_local(&wt, reach, cap, iscr, rscr, &in);
        CHECK(nt >= 0);
        if (nt < 0) break;
        most = nt > most ? nt : most;
        ovl_out lo = {0};
        if (nt > 0) {
            in.iscr = iscr + np_wall_ilen(cap);
            in.rscr = rscr + np_wall_rlen(cap);
            in.pts_cap = pts_cap;
            ovl_compute(&in, &lo);
            np_to_world(&a, ra, &lo);
        }
        /* the whole wall as a closed B */
        ovl_out wo;
        np_setup(&t.sh, &a, &wb, 0, &in, ra);
        in.iscr = iscr + np_wall_ilen(cap);
        in.rscr = rscr + np_wall_rlen(cap);
        in.pts_cap = pts_cap;
        ovl_compute(&in, &wo);
        np_to_world(&a, ra, &wo);
        /* pd_overlap_host on the posed meshes */
        pd_mesh *ma = scaled(m[a.shape], a.size);
        pd_pose pa = {{a.x.x, a.x.y, a.x.z}, {a.q[0], a.q[1], a.q[2], a.q[3]}};
        pd_pose pb = {{xw[0], xw[1], xw[2]}, {qw[0], qw[1], qw[2], qw[3]}};
        pd_contact r;
        pd_overlap_host(ma, &pa, wall, &pb, 0, &r, &err);
        pd_mesh_destroy(ma);
        double vol_a = t.unit_vol[a.shape] * a.size * a.size * a.size;
        int inside = r.hit && r.volume > (1 - 1e-9) * vol_a; /* the particle wholly in the wall */
        if (nt == 0 && inside) {
            /* no wall triangle within the particle's reach: not seen (a known limit; the
             * overlap would be the whole particle, with no normal to push it out along) */
            buried++;
            continue;
        }
        CHECK_EQ_INT(r.hit, lo.hit);
        CHECK_EQ_INT(wo.hit, lo.hit);
        if (getenv("WT_DEBUG") && (r.hit != lo.hit || fabs(r.normal[0] - lo.normal.x) > 1e-6))
            printf("  k %d shape %d: ref hit %d V %.9g n %.6f %.6f %.6f | local hit %d V %.9g n "
                   "%.6f %.6f %.6f ka %d kb %d | whole V %.9g ka %d kb %d\n",
                   k, a.shape, r.hit, r.volume, r.normal[0], r.normal[1], r.normal[2], lo.hit,
                   lo.volume, lo.normal.x, lo.normal.y, lo.normal.z, lo.kept_a, lo.kept_b,
                   wo.volume, wo.kept_a, wo.kept_b);
        if (!(r.hit && lo.hit && wo.hit)) continue;
        hits++;
        deep += under;
        double sz = a.size;
        CHECK_REL(r.volume, lo.volume, 1e-10);
        CHECK_NEAR(r.centroid[0], lo.centroid.x, 1e-10 * sz);
        CHECK_NEAR(r.centroid[1], lo.centroid.y, 1e-10 * sz);
        CHECK_NEAR(r.centroid[2], lo.centroid.z, 1e-10 * sz);
        CHECK_REL(wo.volume, lo.volume, 1e-12);
        CHECK_NEAR(wo.centroid.x, lo.centroid.x, 1e-12 * sz);
        CHECK_NEAR(wo.centroid.y, lo.centroid.y, 1e-12 * sz);
        CHECK_NEAR(wo.centroid.z, lo.centroid.z, 1e-12 * sz);
        /* wholly inside, the faces' area vectors cancel: the normal is rounding noise in every
         * path (and the depth its extent), so only V and the centroid are compared */
        if (inside) continue;
        CHECK_NEAR(r.normal[0], lo.normal.x, 1e-9);
        CHECK_NEAR(r.normal[1], lo.normal.y, 1e-9);
        CHECK_NEAR(r.normal[2], lo.normal.z, 1e-9);
        CHECK_NEAR(r.depth, lo.depth, 1e-9 * sz);
        CHECK_NEAR(wo.normal.x, lo.normal.x, 1e-12);
        CHECK_NEAR(wo.normal.y, lo.normal.y, 1e-12);
        CHECK_NEAR(wo.normal.z, lo.normal.z, 1e-12);
        CHECK_NEAR(wo.depth, lo.depth, 1e-12 * sz);
    }
    printf("  %d placements, %d overlapping (%d with the centroid inside the wall, %d wholly "
           "inside the wall); at most %d wall triangles near one particle\n",
           n, hits, deep, buried, most);
    free(iscr);
    free(rscr);
    wall_tree_free(&tree);
    tables_free(&t);
    for (int s = 0; s < NPART; s++)
        pd_mesh_destroy(m[s]);
    return hits;
}

/* Over the slab's top face, straddling it (centroids down to 0.4 sizes below, so inside the
 * wall), some hanging over its edges. */
static int place_slab(double size, double p[3])
{
    p[0] = (2 * rnd() - 1) * (slab_h[0] + 0.2 * size);
    p[1] = (2 * rnd() - 1) * (slab_h[1] + 0.2 * size);
    p[2] = slab_h[2] + (rnd() - 0.4) * size;
    return fabs(p[0]) < slab_h[0] && fabs(p[1]) < slab_h[1] && p[2] < slab_h[2];
}

TEST(particles_on_a_fine_grid_slab)
{
    pd_mesh *wall = grid_box(slab_h, 24);
    if (!wall) {
        TEST_FAILF("grid box");
        return;
    }
    double x[3] = {0.3, -0.2, 1.5}, q[4] = {1, 0, 0, 0};
    int hits = run_wall(wall, x, q, 240, place_slab, 4);
    CHECK(hits >= 100); /* the test must exercise real contacts */
    /* the same wall turned: the tree is searched in the wall's frame */
    rnd_quat(q);
    hits = run_wall(wall, x, q, 120, place_slab, 4);
    CHECK(hits >= 50);
    pd_mesh_destroy(wall);
}

static double rock_r;

/* Around a large rock: along random directions at 0.8-1.2 times its mean radius (inside or
 * not, by the rock's star shape: the radius along u below the surface's). */
static int place_rock(double size, double p[3])
{
    double u[3], n = 0;
    (void)size;
    for (int k = 0; k < 3; k++) {
        u[k] = rnd() - 0.5;
        n += u[k] * u[k];
    }
    double r = rock_r * (0.8 + 0.4 * rnd()) / sqrt(n);
    for (int k = 0; k < 3; k++)
        p[k] = u[k] * r;
    return 0; /* not counted */
}

TEST(particles_against_a_large_nonconvex_rock)
{
    pd_mesh *rock = NULL;
    pd_error err = {0};
    if (pd_mesh_builtin("rock", 1280, 3, &rock, &err) != PD_OK) {
        TEST_FAILF("%s", err.msg);
        return;
    }
    /* about its centroid, scaled to a mean radius of 1 m */
    pd_mass_props mp;
    pd_mesh_mass_props(rock, &mp);
    double rsum = 0;
    for (int i = 0; i < rock->nverts; i++) {
        double *p = rock->verts + 3 * i, d = 0;
        for (int k = 0; k < 3; k++)
            d += (p[k] - mp.centroid[k]) * (p[k] - mp.centroid[k]);
        rsum += sqrt(d);
    }
    for (int i = 0; i < rock->nverts; i++)
        for (int k = 0; k < 3; k++)
            rock->verts[3 * i + k] =
                (rock->verts[3 * i + k] - mp.centroid[k]) * rock->nverts / rsum;
    rock_r = 1;
    double x[3] = {-2, 0.5, 0.25}, q[4];
    rnd_quat(q);
    int hits = run_wall(rock, x, q, 300, place_rock, 0);
    CHECK(hits >= 60);
    pd_mesh_destroy(rock);
}

/* More near triangles than the scratch holds: reported, never written past. */
TEST(too_many_near_triangles_is_reported)
{
    pd_mesh *wall = grid_box(slab_h, 40);
    wall_tree tree;
    pd_error err = {0};
    CHECK_EQ_INT(PD_OK, wall_tree_build(wall->verts, wall->tris, wall->ntris, &tree, "w", &err));
    wb_tree wt = {tree.box, tree.kid, tree.order, wall->verts, wall->tris};
    int cap = 8, guard = 12345;
    int *iscr = malloc(sizeof(int) * (np_wall_ilen(cap) + 1));
    double *rscr = malloc(sizeof(double) * np_wall_rlen(cap));
    iscr[np_wall_ilen(cap)] = guard;
    ovl_in in;
    memset(&in, 0, sizeof in);
    in.rot[0] = in.rot[4] = in.rot[8] = 1;
    in.tr[2] = -slab_h[2]; /* the particle's centroid on the top face */
    CHECK_EQ_INT(-1, np_wall_local(&wt, 0.2, cap, iscr, rscr, &in));
    CHECK_EQ_INT(guard, iscr[np_wall_ilen(cap)]);
    /* and the bound: no query box of that size meets more than it says */
    int bound = wall_tree_max_near(&tree, wall->verts, wall->tris, wall->ntris, 0.4 * (1 + 2e-5));
    int worst = 0;
    for (int k = 0; k < 2000; k++) {
        double c[3];
        for (int j = 0; j < 3; j++)
            c[j] = (2 * rnd() - 1) * (slab_h[j] + 0.1);
        int n = wb_query_box(&wt, v3(c[0] - 0.2, c[1] - 0.2, c[2] - 0.2),
                             v3(c[0] + 0.2, c[1] + 0.2, c[2] + 0.2), NULL, 0);
        worst = n > worst ? n : worst;
    }
    printf("  cubes of 0.4 m: at most %d of %d triangles met, bound %d\n", worst, wall->ntris,
           bound);
    CHECK(worst <= bound);
    CHECK(bound < wall->ntris / 3); /* a bound that is of use (it sizes scratch memory) */
    free(iscr);
    free(rscr);
    wall_tree_free(&tree);
    pd_mesh_destroy(wall);
}

int main(void)
{
    RUN(particles_on_a_fine_grid_slab);
    RUN(particles_against_a_large_nonconvex_rock);
    RUN(too_many_near_triangles_is_reported);
    return TEST_DONE();
}
