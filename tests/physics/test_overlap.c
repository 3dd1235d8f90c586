/*
 * test_overlap.c - the polyhedral overlap (kernels/overlap.h) against analytic solutions and an
 * independent tetrahedral-decomposition reference (ref_overlap.h).
 *
 * Tolerances: analytic cases with coordinates exact in binary are held to 1e-12 (a few hundred
 * ulps of the cusp sums, whose terms are O(size^3)); the reference comparison to 1e-9 relative
 * (both are exact methods, differing only in round-off of different operation orders); the
 * icosphere cap convergence to the discretisation error bound stated at that test.
 */
#include <stdint.h>
#include <string.h>

#define PD_DOUBLE 1
#include "overlap.h"            /* ovl_compute, for the engine's own path */
#include "overlap_predicates.h" /* OVL_ORIGIN */
#include "overlap_run.h"
#include "box_pairs.h"
#include "cl_internal.h" /* cl_program_get, for the programs' build options */
#include "lattice_cube.h"
#include "polydem.h"
#include "ref_overlap.h"
#include "test.h"
#include "u_shape.h"

static const double PI = 3.14159265358979323846;

static pd_mesh *builtin(const char *name, int tris)
{
    pd_mesh *m = NULL;
    pd_error err = {0};
    if (pd_mesh_builtin(name, tris, 1, &m, &err) != PD_OK) {
        printf("  builtin %s: %s\n", name, err.msg);
        exit(1);
    }
    return m;
}

static pd_mesh *box(double x0, double y0, double z0, double x1, double y1, double z1)
{
    double v[24];
    for (int i = 0; i < 8; i++) {
        v[3 * i] = (i & 1) ? x1 : x0;
        v[3 * i + 1] = (i & 2) ? y1 : y0;
        v[3 * i + 2] = (i & 4) ? z1 : z0;
    }
    static const int t[36] = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                              2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
    pd_mesh *m = NULL;
    pd_error err = {0};
    if (pd_mesh_from_arrays(v, 8, t, 12, "box", &m, &err) != PD_OK) {
        printf("  box: %s\n", err.msg);
        exit(1);
    }
    return m;
}

static pd_pose pose(double x, double y, double z, double qw, double qx, double qy, double qz)
{
    pd_pose p = {{x, y, z}, {qw, qx, qy, qz}};
    return p;
}
static const pd_pose ORIGIN = {{0, 0, 0}, {1, 0, 0, 0}};

static pd_contact overlap(const pd_mesh *a, pd_pose pa, const pd_mesh *b, pd_pose pb, int flags)
{
    pd_contact c;
    pd_error err = {0};
    int rc = pd_overlap_host(a, &pa, b, &pb, flags, &c, &err);
    if (rc != PD_OK) {
        printf("  overlap failed: %s\n", err.msg);
        memset(&c, 0, sizeof c);
    }
    return c;
}

static int finite_contact(const pd_contact *c)
{
    double s = c->volume + c->depth;
    for (int k = 0; k < 3; k++)
        s += c->centroid[k] + c->normal[k];
    return isfinite(s);
}

#define CHECK_VEC(ex, ey, ez, v, tol)                                                              \
    do {                                                                                           \
        CHECK_NEAR(ex, (v)[0], tol);                                                               \
        CHECK_NEAR(ey, (v)[1], tol);                                                               \
        CHECK_NEAR(ez, (v)[2], tol);                                                               \
    } while (0)

/* A deterministic generator for random poses (splitmix64). */
static uint64_t rng_state = 0x9e3779b97f4a7c15ull;
static double rnd(void)
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return (double)(z >> 11) / 9007199254740992.0;
}
static void rnd_quat(double q[4])
{
    double n;
    do {
        for (int k = 0; k < 4; k++)
            q[k] = 2 * rnd() - 1;
        n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    } while (n < 0.1 || n > 1);
    for (int k = 0; k < 4; k++)
        q[k] /= n;
}

/* ---- analytic cases ------------------------------------------------------------------------ */

TEST(offset_cubes_are_a_box)
{
    pd_mesh *c = builtin("cube", 0);
    /* overlap of [-.5,.5]^3 and its translate by (dx,dy,dz): box of sides 1-|d| */
    double offs[][3] = {{0.5, 0, 0}, {0, -0.25, 0}, {0.3, 0.2, 0.1}, {-0.125, 0.375, -0.5}};
    for (int i = 0; i < 4; i++) {
        double *d = offs[i];
        pd_contact r = overlap(c, ORIGIN, c, pose(d[0], d[1], d[2], 1, 0, 0, 0), 0);
        double s[3], vol = 1, sa[3] = {0, 0, 0}, sn = 0;
        for (int k = 0; k < 3; k++) {
            s[k] = 1 - fabs(d[k]);
            vol *= s[k];
        }
        /* A's faces inside B: the face towards B on each axis with d != 0, area = product of the
         * other two sides (eq. 4.19) */
        for (int k = 0; k < 3; k++) {
            if (d[k] != 0) sa[k] = (d[k] > 0 ? 1 : -1) * s[(k + 1) % 3] * s[(k + 2) % 3];
            sn += sa[k] * sa[k];
        }
        sn = sqrt(sn);
        CHECK(r.hit);
        CHECK_NEAR(vol, r.volume, 1e-12);
        CHECK_VEC(d[0] / 2, d[1] / 2, d[2] / 2, r.centroid, 1e-12);
        CHECK_VEC(sa[0] / sn, sa[1] / sn, sa[2] / sn, r.normal, 1e-12);
        double depth = 0;
        for (int k = 0; k < 3; k++)
            depth += s[k] * fabs(sa[k] / sn);
        CHECK_NEAR(depth, r.depth, 1e-12);
    }
    pd_mesh_destroy(c);
}

TEST(rotated_cube_corner_into_face)
{
    /* B = cube turned 45 degrees about z, its vertical edge pushed h into A's face x = 0.5: the
     * overlap is a prism of triangular section (base 2h, height h) and length 1 */
    pd_mesh *c = builtin("cube", 0);
    double h = 0.125, s = sin(PI / 8), co = cos(PI / 8);
    pd_contact r = overlap(c, ORIGIN, c, pose(0.5 + sqrt(0.5) - h, 0, 0, co, 0, 0, s), 0);
    CHECK(r.hit);
    CHECK_REL(h * h, r.volume, 1e-12);
    CHECK_VEC(0.5 - h / 3, 0, 0, r.centroid, 1e-12);
    CHECK_VEC(1, 0, 0, r.normal, 1e-12);
    CHECK_NEAR(h, r.depth, 1e-12);
    pd_mesh_destroy(c);
}

TEST(tetrahedra_along_a_vertex_direction)
{
    /* T n (T + s(1,1,1)) is T shrunk about vertex (1,1,1) by 1 - 3s/4 (the face x+y+z = -1
     * moves to -1 + 3s): V = (8/3) k^3, centroid (3s/4)(1,1,1), normal (1,1,1)/sqrt3 and depth
     * (4 - 3s)/sqrt3. */
    pd_mesh *t = builtin("tetrahedron", 0);
    double svals[] = {0.1, 0.5, 1.0};
    for (int i = 0; i < 3; i++) {
        double sh = svals[i], k = 1 - 0.75 * sh, r3 = 1 / sqrt(3.0);
        pd_contact r = overlap(t, ORIGIN, t, pose(sh, sh, sh, 1, 0, 0, 0), 0);
        CHECK(r.hit);
        CHECK_REL(8.0 / 3.0 * k * k * k, r.volume, 1e-12);
        CHECK_VEC(0.75 * sh, 0.75 * sh, 0.75 * sh, r.centroid, 1e-12);
        CHECK_VEC(r3, r3, r3, r.normal, 1e-12);
        CHECK_REL((4 - 3 * sh) * r3, r.depth, 1e-12);
    }
    pd_mesh_destroy(t);
}

TEST(cube_pressed_into_slab)
{
    /* a unit cube sunk h into a wide slab (a wall-like box of large triangles): V = h, the
     * contact point is the centre of the sunk layer, the normal points from the cube into the
     * slab (-z) */
    pd_mesh *c = builtin("cube", 0), *slab = box(-3, -2, -1, 2, 3, 0);
    double hs[] = {0.01, 0.1, 0.4};
    for (int i = 0; i < 3; i++) {
        double h = hs[i];
        pd_contact r = overlap(c, pose(0.25, -0.5, 0.5 - h, 1, 0, 0, 0), slab, ORIGIN, 0);
        CHECK(r.hit);
        CHECK_REL(h, r.volume, 1e-12);
        CHECK_VEC(0.25, -0.5, -h / 2, r.centroid, 1e-12);
        CHECK_VEC(0, 0, -1, r.normal, 1e-12);
        CHECK_REL(h, r.depth, 1e-12);
        /* and the slab against the cube: the same overlap, the opposite normal */
        pd_contact s = overlap(slab, ORIGIN, c, pose(0.25, -0.5, 0.5 - h, 1, 0, 0, 0), 0);
        CHECK_REL(h, s.volume, 1e-12);
        CHECK_VEC(0, 0, 1, s.normal, 1e-12);
    }
    pd_mesh_destroy(c);
    pd_mesh_destroy(slab);
}

/* ---- degenerate configurations ---------------------------------------------------------- */

TEST(touching_without_overlap_is_zero)
{
    pd_mesh *c = builtin("cube", 0), *t = builtin("tetrahedron", 0);
    /* face on face (cube resting on cube), edge on edge, vertex on vertex */
    double offs[][3] = {{0, 0, 1}, {1, 1, 0}, {1, -1, 1}, {1, 0, 0}};
    for (int i = 0; i < 4; i++) {
        pd_contact r =
            overlap(c, ORIGIN, c, pose(offs[i][0], offs[i][1], offs[i][2], 1, 0, 0, 0), 0);
        CHECK(finite_contact(&r));
        CHECK(!r.hit);
        CHECK_NEAR(0, r.volume, 0);
    }
    /* a tetrahedron whose lowest edge, (1,-1,-1)-(-1,1,-1), lies on the cube's top face
     * along its diagonal once lifted by 1.5 */
    pd_contact r = overlap(c, ORIGIN, t, pose(0, 0, 1.5, 1, 0, 0, 0), 0);
    CHECK(finite_contact(&r));
    CHECK(!r.hit);
    pd_mesh_destroy(c);
    pd_mesh_destroy(t);
}

TEST(vertex_exactly_on_face)
{
    /* B: a tetrahedron with apex (0,0,0) below a base triangle at z = 1 of area 2 (V_B = 2/3).
     * Apex on A's top face: touching. Apex sunk by h: the tip, similar to B with ratio h, has
     * V = (2/3) h^3 and centroid apex + (3/4) h (base centroid direction (0,-1/3,1)). */
    double v[] = {0, 0, 0, -1, -1, 1, 1, -1, 1, 0, 1, 1};
    int tri[] = {0, 2, 1, 0, 3, 2, 0, 1, 3, 1, 2, 3};
    pd_mesh *c = builtin("cube", 0), *b = NULL;
    pd_error err = {0};
    CHECK(pd_mesh_from_arrays(v, 4, tri, 4, "tip", &b, &err) == PD_OK);
    if (!b) return;
    pd_contact r = overlap(c, ORIGIN, b, pose(0.125, 0.25, 0.5, 1, 0, 0, 0), 0);
    CHECK(finite_contact(&r));
    CHECK(!r.hit);
    double h = 0.25;
    r = overlap(c, ORIGIN, b, pose(0.125, 0.25, 0.5 - h, 1, 0, 0, 0), 0);
    CHECK(r.hit);
    CHECK_REL(2.0 / 3.0 * h * h * h, r.volume, 1e-12);
    CHECK_VEC(0.125, 0.25 - h / 4, 0.5 - h / 4, r.centroid, 1e-12);
    CHECK_REL(h, r.depth * r.normal[2], 1e-12); /* extent along z of the tip */
    CHECK(r.normal[2] > 0);
    pd_mesh_destroy(c);
    pd_mesh_destroy(b);
}

TEST(identical_coincident_shapes)
{
    const char *names[] = {"cube", "tetrahedron", "schonhardt", "rock"};
    for (int i = 0; i < 4; i++) {
        pd_mesh *m = builtin(names[i], 0);
        pd_mass_props mp;
        pd_mesh_mass_props(m, &mp);
        pd_pose p = pose(0.5, -2, 3, 0.5, 0.5, -0.5, 0.5);
        /* the same pose, and the same orientation written as 3q: equal only up to rounding */
        pd_pose p3 = pose(0.5, -2, 3, 1.5 * 0.9, 1.5 * 0.9, -1.5 * 0.9, 1.5 * 0.9);
        double q[4];
        rnd_quat(q);
        pd_pose pr = pose(0.1, 0.2, 0.3, q[0], q[1], q[2], q[3]);
        pd_pose pr3 = pose(0.1, 0.2, 0.3, 3 * q[0], 3 * q[1], 3 * q[2], 3 * q[3]);
        pd_contact r3 = overlap(m, p, m, p3, 0), rr = overlap(m, pr, m, pr3, 0);
        CHECK(finite_contact(&r3) && finite_contact(&rr));
        CHECK_REL(mp.volume, r3.volume, 1e-12);
        CHECK_REL(mp.volume, rr.volume, 1e-12);
        pd_contact r = overlap(m, p, m, p, 0);
        CHECK(finite_contact(&r));
        CHECK(r.hit);
        CHECK_REL(mp.volume, r.volume, 1e-12);
        /* the centroid of the shape itself, placed by the pose */
        double R[3][3], cw[3];
        pd_quat_to_matrix(p.q, R);
        for (int k = 0; k < 3; k++)
            cw[k] = R[k][0] * mp.centroid[0] + R[k][1] * mp.centroid[1] + R[k][2] * mp.centroid[2] +
                    p.x[k];
        CHECK_VEC(cw[0], cw[1], cw[2], r.centroid, 1e-12);
        double nn =
            sqrt(r.normal[0] * r.normal[0] + r.normal[1] * r.normal[1] + r.normal[2] * r.normal[2]);
        CHECK_NEAR(1, nn, 1e-12);
        CHECK(r.depth > 0);
        pd_mesh_destroy(m);
    }
}

/* One solid wholly inside the other: the faces inside form a closed surface, eq. 4.19's sum is
 * rounding noise, and the normal used to point anywhere (QA 2026-12-02: [-0.44, -0.87, -0.22]
 * one way and [-0.58, 0.58, 0.58] the other). It is the centre line from A's frame origin to
 * B's: here the cubes' centres, (0.1, 0.05, 0) / |.|, and opposite when they swap. */
TEST(contained_solid_takes_the_centre_line)
{
    pd_mesh *big = builtin("cube", 0), *small = box(-0.1, -0.1, -0.1, 0.1, 0.1, 0.1);
    pd_pose pb = pose(0.1, 0.05, 0, 1, 0, 0, 0);
    double n = sqrt(0.1 * 0.1 + 0.05 * 0.05), e[3] = {0.1 / n, 0.05 / n, 0};
    for (int single = 0; single < 2; single++) {
        int fl = single ? PD_OVERLAP_SINGLE : 0;
        double tol = single ? 1e-6 : 1e-12;
        pd_contact ab = overlap(big, ORIGIN, small, pb, fl),
                   ba = overlap(small, pb, big, ORIGIN, fl);
        CHECK(ab.hit && ba.hit);
        CHECK_REL(0.008, ab.volume, tol);
        CHECK_REL(0.008, ba.volume, tol);
        CHECK_VEC(e[0], e[1], e[2], ab.normal, tol);
        CHECK_VEC(-e[0], -e[1], -e[2], ba.normal, tol);
        /* the small cube's extent along the normal: 0.2 (|e_x| + |e_y|) */
        CHECK_NEAR(0.2 * (e[0] + e[1]), ab.depth, tol);
        CHECK_NEAR(ab.depth, ba.depth, tol);
    }
    pd_mesh_destroy(big);
    pd_mesh_destroy(small);
}

/*
 * A 1 mm cube wholly inside a 10 m one, 2 m from its centre, either way round. About the big
 * cube's centre the cusps reach ~10 m and sum to ~2.4e-11 of their magnitudes, so their rounding
 * is ~1e-5 of the volume: the volume came out 5.4e-6 too large and the centroid 0.5 mm (half the
 * small cube) off, while with A and B swapped both were exact. The sums are now taken again about
 * the overlap's own centre below 1e-8 of the terms (OVL_RESUM). Tolerances: the small cube's
 * corners are known in A's frame to the rounding of coordinates ~2 m, 4.4e-16 m, which moves its
 * faces by 4.4e-13 of its side and its volume by ~1.3e-12 relative: 1e-11 relative, 1e-13 m.
 */
TEST(small_solid_inside_a_large_one)
{
    pd_mesh *big = box(0, 0, 0, 10, 10, 10), *small = box(0, 0, 0, 1e-3, 1e-3, 1e-3);
    pd_pose pb = pose(2, 2, 2, 1, 0, 0, 0);
    pd_contact ab = overlap(big, ORIGIN, small, pb, 0), ba = overlap(small, pb, big, ORIGIN, 0);
    CHECK(ab.hit && ba.hit);
    CHECK_REL(1e-9, ab.volume, 1e-11);
    CHECK_REL(1e-9, ba.volume, 1e-11);
    CHECK_VEC(2.0005, 2.0005, 2.0005, ab.centroid, 1e-13);
    CHECK_VEC(2.0005, 2.0005, 2.0005, ba.centroid, 1e-13);
    /* the small cube's extent along either normal (the centre line: a diagonal) */
    CHECK_NEAR(sqrt(3) * 1e-3, ab.depth, 1e-13);
    CHECK_NEAR(ab.depth, ba.depth, 1e-13);
    pd_mesh_destroy(big);
    pd_mesh_destroy(small);
}

TEST(edge_on_edge_crossing)
{
    /* B = cube turned 90 degrees about x then shifted so its edges lie exactly on A's edges
     * and faces: the same box as the plain offset, every edge of one meeting the other's */
    pd_mesh *c = builtin("cube", 0);
    double s = sqrt(0.5);
    pd_contact r = overlap(c, ORIGIN, c, pose(0.5, 0.5, 0, s, s, 0, 0), 0);
    CHECK(r.hit);
    CHECK_NEAR(0.25, r.volume, 1e-12);
    CHECK_VEC(0.25, 0.25, 0, r.centroid, 1e-12);
    CHECK_VEC(sqrt(0.5), sqrt(0.5), 0, r.normal, 1e-12);
    pd_mesh_destroy(c);
}

/* World point R(q) v + x. */
static void place(const double q[4], const double *x, const double *v, double *out)
{
    double R[3][3];
    pd_quat_to_matrix(q, R);
    for (int i = 0; i < 3; i++)
        out[i] = R[i][0] * v[0] + R[i][1] * v[1] + R[i][2] * v[2] + x[i];
}

TEST(near_degenerate_poses_from_rounding)
{
    /* Rotated copies placed through floating-point rotations are degenerate only up to
     * rounding (1e-16 m); they must behave as the exact configurations, not as noise. */
    pd_mesh *c = builtin("cube", 0);
    for (int trial = 0; trial < 10; trial++) {
        double q[4], x[3] = {0.3, -0.1, 0.2}, xb[3];
        rnd_quat(q);
        pd_pose pa = pose(x[0], x[1], x[2], q[0], q[1], q[2], q[3]);
        /* resting face on face: B one side length along A's rotated z */
        double up[3] = {0, 0, 1}, side[3] = {0.5, 0, 0}, ex[3] = {1, 0, 0}, nx[3];
        place(q, x, up, xb);
        pd_contact r = overlap(c, pa, c, pose(xb[0], xb[1], xb[2], q[0], q[1], q[2], q[3]), 0);
        CHECK(finite_contact(&r));
        CHECK(!r.hit || r.volume < 1e-12);
        /* half a side along A's rotated x: the offset-cube box in A's frame */
        place(q, x, side, xb);
        r = overlap(c, pa, c, pose(xb[0], xb[1], xb[2], q[0], q[1], q[2], q[3]), 0);
        CHECK(r.hit);
        CHECK_NEAR(0.5, r.volume, 1e-12);
        double zero[3] = {0, 0, 0};
        place(q, zero, ex, nx);
        CHECK_VEC(nx[0], nx[1], nx[2], r.normal, 1e-9);
        CHECK_NEAR(0.5, r.depth, 1e-9);
        /* the same orientation written as 3q (normalised with rounding): near-coincident */
        r = overlap(c, pa, c, pose(x[0], x[1], x[2], 3 * q[0], 3 * q[1], 3 * q[2], 3 * q[3]), 0);
        CHECK(finite_contact(&r));
        CHECK_NEAR(1, r.volume, 1e-12);
    }
    /* a cube tilted by 1e-15 rad lying on a slab: touching, then sunk by 1e-3 m */
    pd_mesh *slab = box(-3, -3, -1, 3, 3, 0);
    double t = 0.5e-15;
    pd_contact r = overlap(c, pose(0, 0, 0.5, cos(t), sin(t), 0, 0), slab, ORIGIN, 0);
    CHECK(finite_contact(&r));
    CHECK(!r.hit || r.volume < 1e-12);
    r = overlap(c, pose(0, 0, 0.5 - 1e-3, cos(t), sin(t), 0, 0), slab, ORIGIN, 0);
    CHECK_REL(1e-3, r.volume, 1e-9);
    CHECK_VEC(0, 0, -1, r.normal, 1e-9);
    pd_mesh_destroy(slab);
    pd_mesh_destroy(c);
}

/* ---- symmetry, invariance, filter ------------------------------------------------------- */

/* A random pose of B near A, at a distance where they overlap by a few percent of size. */
static pd_pose near_pose(double dist)
{
    double q[4], dir[3], n;
    rnd_quat(q);
    do {
        for (int k = 0; k < 3; k++)
            dir[k] = 2 * rnd() - 1;
        n = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    } while (n < 0.1 || n > 1);
    return pose(dist * dir[0] / n, dist * dir[1] / n, dist * dir[2] / n, q[0], q[1], q[2], q[3]);
}

TEST(swap_gives_same_volume_and_opposite_normal)
{
    const char *names[] = {"schonhardt", "rock", "icosphere", "cube"};
    int hits = 0;
    for (int i = 0; i < 4; i++) {
        pd_mesh *m = builtin(names[i], 0);
        for (int trial = 0; trial < 20; trial++) {
            double q[4];
            rnd_quat(q);
            pd_pose pa = pose(0.1, 0.2, 0.3, q[0], q[1], q[2], q[3]);
            pd_pose pb = near_pose(0.8);
            pb.x[0] += 0.1, pb.x[1] += 0.2, pb.x[2] += 0.3;
            pd_contact ab = overlap(m, pa, m, pb, 0), ba = overlap(m, pb, m, pa, 0);
            CHECK(finite_contact(&ab) && finite_contact(&ba));
            CHECK_EQ_INT(ab.hit, ba.hit);
            if (!ab.hit || !ba.hit) continue;
            hits++;
            CHECK_REL(ab.volume, ba.volume, 1e-10);
            CHECK_VEC(ab.centroid[0], ab.centroid[1], ab.centroid[2], ba.centroid, 1e-10);
            CHECK_VEC(-ab.normal[0], -ab.normal[1], -ab.normal[2], ba.normal, 1e-9);
            CHECK_REL(ab.depth, ba.depth, 1e-9);
        }
        pd_mesh_destroy(m);
    }
    CHECK(hits > 40); /* the trials must actually exercise overlaps */
}

/* Applies world motion (R, x) to a pose. */
static pd_pose moved(pd_pose p, const double q[4], const double x[3])
{
    double R[3][3];
    pd_quat_to_matrix(q, R);
    pd_pose r;
    for (int i = 0; i < 3; i++)
        r.x[i] = R[i][0] * p.x[0] + R[i][1] * p.x[1] + R[i][2] * p.x[2] + x[i];
    /* q_r = q * p.q */
    const double *a = q, *b = p.q;
    r.q[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
    r.q[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
    r.q[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
    r.q[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
    return r;
}

TEST(invariant_under_common_rigid_motion_even_1e3_m_away)
{
    pd_mesh *m = builtin("rock", 80);
    double far[][3] = {{0.3, -0.2, 0.1}, {1e3, -1e3, 1e3}, {1e3, 0, 0}};
    int hits = 0;
    for (int trial = 0; trial < 10; trial++) {
        pd_pose pa = ORIGIN, pb = near_pose(0.8);
        pd_contact ref = overlap(m, pa, m, pb, 0);
        if (!ref.hit) continue;
        hits++;
        for (int f = 0; f < 3; f++) {
            double q[4], R[3][3];
            rnd_quat(q);
            pd_quat_to_matrix(q, R);
            pd_contact r = overlap(m, moved(pa, q, far[f]), m, moved(pb, q, far[f]), 0);
            CHECK(r.hit);
            /* 1e3 m away, positions carry ~1e3 * 2^-52 = 2e-13 m of round-off; the overlap is
             * computed in A's frame, so V keeps ~1e-10 relative (figure 5.4's lesson) */
            CHECK_REL(ref.volume, r.volume, 1e-9);
            for (int i = 0; i < 3; i++) {
                double c = R[i][0] * ref.centroid[0] + R[i][1] * ref.centroid[1] +
                           R[i][2] * ref.centroid[2] + far[f][i];
                double n =
                    R[i][0] * ref.normal[0] + R[i][1] * ref.normal[1] + R[i][2] * ref.normal[2];
                CHECK_NEAR(c, r.centroid[i], 1e-9);
                CHECK_NEAR(n, r.normal[i], 1e-8);
            }
            CHECK_REL(ref.depth, r.depth, 1e-8);
        }
    }
    CHECK(hits >= 5);
    pd_mesh_destroy(m);
}

/*
 * Degenerate poses of non-convex shapes, checked against the poses around them. B is a copy of A
 * placed so that faces, edges or corners of the two coincide: slid within the plane of one of
 * its faces, along the line of one of its edges, spun about a face's normal through the face's
 * corner (so that face stays in its plane), a corner on a corner or on a face, or on top of A.
 * The exact overlap's volume V and first moment M = V c are Lipschitz in B's position: moving B
 * by d sweeps its surface (area S) through at most S |d| of volume, all of it inside A, within
 * r_A (A's farthest corner) of the origin. So the answer at the degenerate pose must lie within
 * S delta of V and within S delta r_A of M at each of four generic poses delta away in random
 * directions, plus the cusp sums' rounding. Double precision: delta = 1e-6 m, far outside the
 * predicates' tie band of ~1e-14 m, and 1e-12 for rounding. Single precision: delta = 1e-3 m,
 * 40 times its band of ~2.5e-5 m, and 1e-4 for rounding (2^-23 times sums of O(size^3) terms).
 * A tie broken the wrong way drops or doubles a face's share: for these shapes, a face's area
 * times its distance to the far side, of order 0.1 to 1 m^3.
 */
TEST(degenerate_non_convex_poses_are_limits_of_generic_ones)
{
    pd_mesh *ms[3] = {builtin("schonhardt", 0), builtin("rock", 80), u_shape_mesh()};
    int tried = 0, overlapping = 0;
    for (int run = 0; run < 6; run++) {
        int s = run % 3, flags = run < 3 ? 0 : PD_OVERLAP_SINGLE;
        double delta = flags ? 1e-3 : 1e-6, rounding = flags ? 1e-4 : 1e-12;
        const pd_mesh *m = ms[s];
        double S = 0, ra = 0;
        for (int k = 0; k < m->ntris; k++) {
            const int *f = m->tris + 3 * k;
            double e1[3], e2[3];
            for (int i = 0; i < 3; i++) {
                e1[i] = m->verts[3 * f[1] + i] - m->verts[3 * f[0] + i];
                e2[i] = m->verts[3 * f[2] + i] - m->verts[3 * f[0] + i];
            }
            S += 0.5 * sqrt(pow(e1[1] * e2[2] - e1[2] * e2[1], 2) +
                            pow(e1[2] * e2[0] - e1[0] * e2[2], 2) +
                            pow(e1[0] * e2[1] - e1[1] * e2[0], 2));
        }
        for (int k = 0; k < m->nverts; k++)
            ra = fmax(ra, sqrt(pow(m->verts[3 * k], 2) + pow(m->verts[3 * k + 1], 2) +
                               pow(m->verts[3 * k + 2], 2)));
        for (int trial = 0; trial < 70; trial++) {
            int family = trial % 7;
            const int *f = m->tris + 3 * (int)(rnd() * m->ntris);
            const double *v0 = m->verts + 3 * f[0];
            const double *vi = m->verts + 3 * (int)(rnd() * m->nverts);
            const double *vj = m->verts + 3 * (int)(rnd() * m->nverts);
            double e1[3], e2[3], n[3], t[3] = {0, 0, 0}, q[4] = {1, 0, 0, 0};
            for (int i = 0; i < 3; i++) {
                e1[i] = m->verts[3 * f[1] + i] - v0[i];
                e2[i] = m->verts[3 * f[2] + i] - v0[i];
            }
            n[0] = e1[1] * e2[2] - e1[2] * e2[1];
            n[1] = e1[2] * e2[0] - e1[0] * e2[2];
            n[2] = e1[0] * e2[1] - e1[1] * e2[0];
            double a = 1.4 * rnd() - 0.7, b = 1.4 * rnd() - 0.7;
            if (family == 2 || family == 3) { /* spun about face f's normal through v0 */
                const double angles[4] = {PI / 2, PI, 2 * PI / 3, 2 * PI * rnd()};
                double th = angles[trial % 4], nn = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
                double R[3][3];
                q[0] = cos(th / 2);
                for (int i = 0; i < 3; i++)
                    q[i + 1] = sin(th / 2) * n[i] / nn;
                pd_quat_to_matrix(q, R);
                for (int i = 0; i < 3; i++)
                    t[i] = v0[i] - (R[i][0] * v0[0] + R[i][1] * v0[1] + R[i][2] * v0[2]);
            }
            for (int i = 0; i < 3; i++) {
                if (family == 0 || family == 3) t[i] += a * e1[i] + b * e2[i]; /* face plane */
                if (family == 1) t[i] = a * e1[i];                             /* edge line */
                if (family == 4) t[i] = vi[i] - vj[i]; /* corner on corner */
                if (family == 5)                       /* corner on face f */
                    t[i] = v0[i] + fabs(a) * 0.7 * e1[i] + fabs(b) * 0.3 * e2[i] - vj[i];
            } /* family 6: coincident */
            pd_pose pb = pose(t[0], t[1], t[2], q[0], q[1], q[2], q[3]);
            pd_contact c0 = overlap(m, ORIGIN, m, pb, flags);
            CHECK(finite_contact(&c0));
            tried++;
            overlapping += c0.hit && c0.volume > 1e-3;
            for (int k = 0; k < 4; k++) {
                double d[4];
                rnd_quat(d); /* a random direction: the quaternion's vector part, normalised */
                double dn = sqrt(d[1] * d[1] + d[2] * d[2] + d[3] * d[3]);
                pd_pose pk = pb;
                for (int i = 0; i < 3; i++)
                    pk.x[i] += delta * d[i + 1] / dn;
                pd_contact ck = overlap(m, ORIGIN, m, pk, flags);
                double v0c = c0.hit ? c0.volume : 0, vkc = ck.hit ? ck.volume : 0;
                if (!(fabs(v0c - vkc) <= S * delta + rounding)) {
                    TEST_FAILF("%s, shape %d, family %d, trial %d: V %.15g at the pose, %.15g "
                               "%g m away (allowed %.3g)",
                               flags ? "single" : "double", s, family, trial, v0c, vkc, delta,
                               S * delta + rounding);
                    break;
                }
                for (int i = 0; i < 3; i++) {
                    double m0 = v0c * (c0.hit ? c0.centroid[i] : 0);
                    double mk = vkc * (ck.hit ? ck.centroid[i] : 0);
                    if (!(fabs(m0 - mk) <= S * delta * ra + rounding)) {
                        TEST_FAILF("%s, shape %d, family %d, trial %d: moment %d %.15g at the "
                                   "pose, %.15g %g m away",
                                   flags ? "single" : "double", s, family, trial, i, m0, mk, delta);
                        break;
                    }
                }
            }
        }
    }
    /* most of these poses overlap by a good part of a particle (not a vacuous test) */
    CHECK(tried == 420);
    CHECK(overlapping >= 240);
    printf("  %d degenerate poses, %d with V > 1e-3 m^3\n", tried, overlapping);
    for (int s = 0; s < 3; s++)
        pd_mesh_destroy(ms[s]);
}

TEST(filter_on_and_off_agree)
{
    const char *names[] = {"schonhardt", "rock", "icosphere"};
    int hits = 0, filtered = 0;
    for (int i = 0; i < 3; i++) {
        pd_mesh *m = builtin(names[i], i == 2 ? 320 : 0);
        for (int trial = 0; trial < 20; trial++) {
            pd_pose pb = near_pose(i == 2 ? 1.9 : 0.85);
            pd_contact on = overlap(m, ORIGIN, m, pb, 0);
            pd_contact off = overlap(m, ORIGIN, m, pb, PD_OVERLAP_NO_FILTER);
            CHECK_EQ_INT(off.hit, on.hit);
            if (!on.hit) continue;
            hits++;
            filtered += on.tris_a < m->ntris;
            /* the filter only removes triangles that contribute no cusp: identical sums */
            CHECK_NEAR(off.volume, on.volume, 1e-15 * off.volume);
            CHECK_VEC(off.centroid[0], off.centroid[1], off.centroid[2], on.centroid, 1e-14);
            CHECK_VEC(off.normal[0], off.normal[1], off.normal[2], on.normal, 1e-14);
            CHECK_NEAR(off.depth, on.depth, 1e-14);
        }
        pd_mesh_destroy(m);
    }
    CHECK(hits > 20);
    CHECK(filtered > 10); /* and the filter really did remove triangles */
}

/*
 * Equal cubes stacked face on face and offset sideways, their side faces coplanar to within the
 * resolution (a cube slid along the top of another in a simulation: tests/physics/test_sim.c
 * cube_slides_to_rest_on_a_cube, whose step 1126 is the first pose here). A corner of B lies
 * within rounding of A's side face plane and of its box, the plane predicates tie, and the
 * symbolic displacement decides its side; the filter must decide it the same way (it once
 * called such a corner outside in the pass that puts it inside: centroid 394 m off, depth 0.11 m
 * for a 1 m cube). Filter on and off must agree (the unfiltered sums are the reference, as in
 * filter_on_and_off_agree), and the contact must be the thin slab it is: centroid inside the
 * overlap's box, normal along A's z, depth about the sinking. The poses sweep B's side faces
 * across A's planes by +-2e-14 m, inside the plane predicates' tie band (2 pad = 128 eps L, ~4e-14
 * m here). Known open: offsets at the band's edge (~4.27e-14) still disagree, because the line
 * predicate's band (2 pad |e| across the ray, ovl_line_through) is wider than the plane's for a
 * ray not square to the edge: a cast ties where the crossings do not.
 */
TEST(stacked_cubes_with_coplanar_sides)
{
    pd_mesh *c = builtin("cube", 0);
    int hits = 0;
    for (int trial = 0; trial < 301; trial++) {
        pd_pose pa, pb;
        double sink, off;
        if (trial == 0) { /* the simulation's pose, in units of the cube's side */
            pa = pose(0.00021082500361168006, -3.191844290881871e-15, 0.49983204920762941,
                      0.99999999771984593, -1.5111336972538839e-16, 6.7530054886070893e-05,
                      8.6730104943386182e-15);
            pb = pose(0.10563225066849495, -1.5279242095714143e-15, 1.4997420369915935,
                      0.9999999924115609, 3.0342302657507285e-15, 0.00012319447271984436,
                      -1.0183595600270638e-14);
            sink = 1.4e-4;
            off = 0.105;
        } else { /* tilted by up to 1e-3 rad about random axes, sunk 1e-5 to 1e-3, offset */
            double qa[4], qb[4], ax[3], t;
            for (int s = 0; s < 2; s++) {
                double *q = s ? qb : qa, n = 0;
                for (int k = 0; k < 3; k++) {
                    ax[k] = 2 * rnd() - 1;
                    n += ax[k] * ax[k];
                }
                t = 1e-3 * rnd() * (trial % 3 != 0); /* a third not tilted at all */
                q[0] = cos(t / 2);
                for (int k = 0; k < 3; k++)
                    q[k + 1] = sin(t / 2) * ax[k] / sqrt(n);
            }
            sink = pow(10, -5 + 2 * rnd());
            off = 0.8 * rnd();
            double at[3] = {off, 4e-14 * (rnd() - 0.5), 1 - sink}, xa[3] = {0, 0, 0.5}, xb[3];
            place(qa, xa, at, xb);
            pa = pose(xa[0], xa[1], xa[2], qa[0], qa[1], qa[2], qa[3]);
            pb = pose(xb[0], xb[1], xb[2], qb[0], qb[1], qb[2], qb[3]);
        }
        pd_contact on = overlap(c, pa, c, pb, 0);
        pd_contact ref = overlap(c, pa, c, pb, PD_OVERLAP_NO_FILTER);
        CHECK(finite_contact(&on));
        CHECK_EQ_INT(ref.hit, on.hit);
        if (!on.hit || !ref.hit) continue;
        hits++;
        CHECK_NEAR(ref.volume, on.volume, 1e-12 * ref.volume);
        CHECK_VEC(ref.centroid[0], ref.centroid[1], ref.centroid[2], on.centroid, 1e-12);
        CHECK_VEC(ref.normal[0], ref.normal[1], ref.normal[2], on.normal, 1e-12);
        CHECK_NEAR(ref.depth, on.depth, 1e-12);
        /* a slab about (1 - off) x 1 x sink at A's top (tilts of 1e-3 rad move its faces by
         * up to 1e-3 m: the bounds below allow that) */
        double za[3], top[3] = {0, 0, 0.5};
        place(pa.q, pa.x, top, za);
        CHECK(fabs(on.centroid[2] - za[2]) < 2e-3 && fabs(on.centroid[1] - pa.x[1]) < 0.51);
        CHECK(on.normal[2] > 0.999);
        CHECK(on.depth < sink + 3e-3);
        if (test_cur_failed_) {
            printf("  trial %d: sink %g, offset %g\n", trial, sink, off);
            break;
        }
    }
    printf("  %d of 301 stacked poses overlapping\n", hits);
    CHECK(hits > 200);
    pd_mesh_destroy(c);
}

/*
 * Two axis-aligned unit cubes, B on A's top face sunk by s, shifted by `off` along x and by
 * delta along y, so that their y faces lie delta apart: the overlap is the box
 * (1 - off) x (1 - |delta|) x s, with its centroid at (off / 2, delta / 2, 0.5 - s / 2). delta is
 * swept across the predicates' tie band (2 resolutions, about 4e-14 m here) and its edges, where
 * each predicate snaps to a tie or not on its own: every one must measure the same distance
 * against the same band, or some see the faces coplanar and others apart (the cube of a
 * simulation's lattice was given 0.509 m^3 for 6.6e-5, or nothing). The snap may move a face by
 * the band, so the volume is exact to the band times the faces' size: 1e-9 relative is far
 * above that and far below a lost or extra piece. The normal's y part (A's side face inside B)
 * changes sign with delta and may take either sign, or vanish, inside the band.
 */
TEST(cube_sides_across_the_tie_band)
{
    pd_mesh *c = builtin("cube", 0);
    static const double offs[3] = {0.1, 0.46469170949068306, 0.7};
    static const double sinks[2] = {1.2301584082445e-4, 1.7e-3};
    /* the pair as given, and turned 0.7 rad about (1, 2, 3) 10 m from the origin (the
     * transforms add rounding of 1e-15 m to every offset) */
    double qr[4] = {cos(0.35), sin(0.35) / sqrt(14), 2 * sin(0.35) / sqrt(14),
                    3 * sin(0.35) / sqrt(14)};
    double x0[3] = {10, -3, 2}, origin[3] = {0, 0, 0};
    int bad = 0;
    for (int frame = 0; frame < 2 && !bad; frame++) {
        const double *q = frame ? qr : ORIGIN.q, *x = frame ? x0 : origin;
        for (int io = 0; io < 3 && !bad; io++) {
            for (int is = 0; is < 2 && !bad; is++) {
                for (int k = -100; k <= 100 && !bad; k++) {
                    double off = offs[io], s = sinks[is], delta = k * 1e-15;
                    double rel[3] = {off, delta, 1 - s}, xb[3];
                    place(q, x, rel, xb);
                    pd_pose pa = pose(x[0], x[1], x[2], q[0], q[1], q[2], q[3]);
                    pd_pose pb = pose(xb[0], xb[1], xb[2], q[0], q[1], q[2], q[3]);
                    /* in A's frame: A's top face (area (1 - off)(1 - |delta|)) and its x side
                     * (s (1 - |delta|)) inside B, and its y side (s (1 - off)) on one side of
                     * the band */
                    double v = (1 - off) * (1 - fabs(delta)) * s;
                    double ctr[3] = {off / 2, delta / 2, 0.5 - s / 2};
                    double nz = (1 - off) * (1 - fabs(delta)), nx = s * (1 - fabs(delta));
                    double ny = s * (1 - off), nn = sqrt(nx * nx + nz * nz);
                    for (int flags = 0; flags < 2 && !bad; flags++) {
                        pd_contact o = overlap(c, pa, c, pb, flags ? PD_OVERLAP_NO_FILTER : 0);
                        double lc[3], ln[3], R[3][3];
                        pd_quat_to_matrix(q, R);
                        for (int i = 0; i < 3; i++) { /* back to A's frame */
                            lc[i] = ln[i] = 0;
                            for (int j = 0; j < 3; j++) {
                                lc[i] += R[j][i] * (o.centroid[j] - x[j]);
                                ln[i] += R[j][i] * o.normal[j];
                            }
                        }
                        CHECK(o.hit);
                        CHECK_NEAR(v, o.volume, 1e-9 * v);
                        CHECK_VEC(ctr[0], ctr[1], ctr[2], lc, 1e-9);
                        CHECK(fabs(ln[1]) <= ny / nn * (1 + 1e-9));
                        double ry = ln[1] / (ny / sqrt(nn * nn + ny * ny));
                        if (fabs(delta) > 1e-13) CHECK_NEAR(delta > 0 ? 1 : -1, ry, 1e-6);
                        double m = sqrt(1 - ln[1] * ln[1]);
                        CHECK_NEAR(nx / nn * m, ln[0], 1e-9);
                        CHECK_NEAR(nz / nn * m, ln[2], 1e-9);
                        if (test_cur_failed_) {
                            printf("  frame %d, off %.17g, sink %g, delta %g, filter %s: volume "
                                   "%.17g\n",
                                   frame, off, s, delta, flags ? "off" : "on", o.volume);
                            bad = 1;
                        }
                    }
                }
            }
        }
    }
    pd_mesh_destroy(c);
}

/*
 * Boxes whose faces lie within the predicates' tie band (2 resolutions, ~3e-14 m for these
 * sizes) of each other's along one to three axes (tests/box_pairs.h, which bench/degenerate runs
 * at scale): the overlap is their box intersection, to 1e-9 relative in volume and 1e-9 m plus
 * 1e-14 m^4 / V in the centroid (the cusp sums' rounding). The first case came out as no contact
 * for 0.69 m^3: faces coplanar in z and 1.9e-14 m apart in x made the predicates disagree, and
 * the volume guard took the sum (beyond the nodes' box) for a miss instead of trying again; about
 * 1 % of such pairs were wrong before. The engine's path (filter on), as given and turned 3 m
 * away.
 */
TEST(boxes_within_the_tie_band_on_several_axes)
{
    static const double fixed[9] = {
        1.1185762732607427,     1.180661077677883,    0.86983255271126414,
        1.9206955459325559e-14, -0.16209474884990133, 0,
        1.1420682457813216,     1.3427558265278008,   0.52537774380524882};
    static const double scales[4] = {2e-14, 4e-14, 6e-14, 1e-13};
    int wrong = 0, trials = 0;
    for (int t = 0; t < 4001; t++) {
        box_pair bp;
        int turned = t % 2;
        box_pair_draw(&bp, scales[(t / 2) % 4], rnd);
        if (t == 4000) { /* the case found by bench/degenerate */
            for (int k = 0; k < 3; k++) {
                bp.a[k] = fixed[k];
                bp.lo[k] = fixed[3 + k];
                bp.hi[k] = fixed[3 + k] + fixed[6 + k];
            }
            box_pair_exact(&bp);
            turned = 0;
        }
        double zero[3] = {0, 0, 0};
        pd_mesh *ma = NULL, *mb = NULL;
        pd_error err = {0};
        CHECK_EQ_INT(PD_OK, pd_mesh_box(zero, bp.a, &ma, &err));
        CHECK_EQ_INT(PD_OK, pd_mesh_box(bp.lo, bp.hi, &mb, &err));
        if (!ma || !mb) {
            pd_mesh_destroy(ma);
            pd_mesh_destroy(mb);
            return;
        }
        pd_pose p = ORIGIN;
        if (turned) {
            rnd_quat(p.q);
            p.x[0] = 3 * rnd();
            p.x[1] = -2 * rnd();
            p.x[2] = rnd();
        }
        pd_contact o = overlap(ma, p, mb, p, 0);
        double rel;
        int bad = box_pair_wrong(&bp, &p, &o, &rel) != 0;
        if (bad && wrong < 3)
            printf("  trial %d (%s): volume %.17g for %.17g; a %.17g %.17g %.17g, B from %.17g "
                   "%.17g %.17g to %.17g %.17g %.17g\n",
                   t, turned ? "turned" : "as given", o.hit ? o.volume : 0, bp.volume, bp.a[0],
                   bp.a[1], bp.a[2], bp.lo[0], bp.lo[1], bp.lo[2], bp.hi[0], bp.hi[1], bp.hi[2]);
        wrong += bad;
        trials++;
        pd_mesh_destroy(ma);
        pd_mesh_destroy(mb);
    }
    printf("  %d of %d box pairs wrong\n", wrong, trials);
    CHECK_EQ_INT(0, wrong);

    /* the judge itself: the exact answer passes, 2e-9 off in volume or 2e-9 m off in the
     * centroid (or a miss) fails */
    box_pair bp = {{1, 1, 1}, {0.5, 0.25, 0}, {1.5, 1.25, 1}, 0, {0, 0, 0}};
    box_pair_exact(&bp);
    pd_pose p = ORIGIN;
    pd_contact o = {0};
    o.hit = 1;
    o.volume = bp.volume;
    memcpy(o.centroid, bp.centroid, sizeof o.centroid);
    double rel;
    CHECK_NEAR(0.375, bp.volume, 1e-15);
    CHECK_EQ_INT(0, box_pair_wrong(&bp, &p, &o, &rel));
    o.volume = bp.volume * (1 + 2e-9);
    CHECK_EQ_INT(1, box_pair_wrong(&bp, &p, &o, &rel));
    o.volume = bp.volume;
    o.centroid[1] += 2e-9;
    CHECK_EQ_INT(2, box_pair_wrong(&bp, &p, &o, &rel));
    o.hit = 0;
    CHECK_EQ_INT(1, box_pair_wrong(&bp, &p, &o, &rel) & 1);
    CHECK_NEAR(1, rel, 0);
}

/*
 * Two 2 cm cubes of a column in a simulated lattice (bench/RESULTS.md, 2026-12-05), 1.1e-6 m
 * deep, their side faces within rounding of each other's in two directions and turned against
 * each other by 3e-14 rad: the predicates tied some of the near-coplanar corners and decided
 * others, and the cusps summed to the right volume with the centroid 1.8 m away and a depth of
 * 1 mm (the engine's path: kernels/overlap.h without OVL_PLACES, as a contact's first pass), a
 * force 20 times too large acting 1.8 m off. The overlap is a slab of the top face: its centroid
 * lies within the faces (to 1e-9 m, far below a lost face's 8e-3 m and far above the slab's
 * 1e-16 m of tilt), its normal along z and its depth 1.1e-6 m, up to what side faces counted
 * inside can add (below).
 */
TEST(stacked_cubes_turned_by_rounding)
{
    const double h = LATTICE_H;
    pd_mesh *m = lattice_cube_mesh(LATTICE_SIZE);
    pd_error err = {0};
    CHECK(m != NULL);
    if (!m) return;
    pd_pose pa = pose(0.097880779486231376, 0.014119220513768948, 0.0081566141984404095, 1,
                      -2.2006552011452189e-14, -2.1276666313378531e-14, -2.2336635949922225e-26);
    pd_pose pb = pose(0.097880779486231376, 0.014119220513768621, 0.024275407571551062, 1,
                      3.4086967609546662e-15, 1.6234128099210543e-15, 1.5515941798291303e-26);
    double gap = pb.x[2] - pa.x[2] - 2 * h; /* -1.1e-6 m: overlapping */
    ovl_setup su;
    CHECK_EQ_INT(PD_OK, ovl_setup_make(m, &pa, m, &pb, 0, &su, &err));
    int pc = ovl_pts_cap(12, 12);
    int *iscr =
        malloc(sizeof(int) * (size_t)(ovl_iscratch_len(12, 12, 8, 8) + ovl_places_ilen(pc)));
    double *rscr =
        malloc(sizeof(double) * (size_t)(ovl_rscratch_len(12, 12, 8, 8, pc) + ovl_places_rlen(pc)));
    if (iscr && rscr) {
        ovl_in in;
        ovl_out o;
        ovl_in_from_setup(&in, &su, su.va, su.vb, 0, iscr, rscr, pc);
        ovl_compute(&in, &o); /* in A's frame: A's centroid at the origin, A's axes */
        CHECK(o.hit);
        CHECK_NEAR(4 * h * h * -gap, o.volume, 1e-6 * 4 * h * h * -gap);
        double cc[3] = {o.centroid.x, o.centroid.y, o.centroid.z};
        CHECK_VEC(0, 0, h + gap / 2, cc, 1e-9);
        /* side faces within rounding of each other's may count as inside: strips of at most
         * the depth on two sides (2 (2h) d of area against the top's (2h)^2) tilt the normal by
         * at most sqrt(2) d / h and add at most 2 sqrt(2) h times that to the depth */
        double d = -gap, tilt = sqrt(o.normal.x * o.normal.x + o.normal.y * o.normal.y);
        CHECK(o.normal.z > 0 && tilt <= sqrt(2) * d / h);
        CHECK(o.depth >= d * (1 - 1e-9) && o.depth <= d * (1 + 4 + 1e-9));
        if (test_cur_failed_)
            printf("  volume %.6g m^3, centroid (%.6g, %.6g, %.6g) m, normal tilt %.3g, depth "
                   "%.6g m\n",
                   o.volume, o.centroid.x, o.centroid.y, o.centroid.z, tilt, o.depth);
    }
    free(iscr);
    free(rscr);
    ovl_setup_free(&su);
    pd_mesh_destroy(m);
}

/*
 * Contacts of many triangles take the sorted paths (OVL_STRIP_MIN in kernels/overlap_predicates.h):
 * ray casts through the strip of kept triangles along eu, the pair loop's sweep over B's boxes.
 * Both only skip work, so they must reproduce the unfiltered computation, which takes neither,
 * as the filter does for small contacts; including poses along the axes, whose casts run exactly
 * through vertices and edges of the other mesh (the ties the strip's margin must keep).
 */
TEST(sorted_casts_and_sweep_agree_with_the_unfiltered_overlap)
{
    pd_mesh *m = builtin("icosphere", 1280);
    pd_pose poses[16];
    int np = 0;
    poses[np++] = pose(0, 0, 1.6, 1, 0, 0, 0);
    poses[np++] = pose(1.6, 0, 0, 1, 0, 0, 0);
    poses[np++] = pose(0, 1.6, 0, sqrt(0.5), 0, 0, sqrt(0.5)); /* 90 degrees about z */
    poses[np++] = pose(1.2, 0, 1.2, 1, 0, 0, 0);
    while (np < 16)
        poses[np++] = near_pose(1.6);
    int sorted = 0;
    for (int i = 0; i < np; i++) {
        pd_contact on = overlap(m, ORIGIN, m, poses[i], 0);
        pd_contact off = overlap(m, ORIGIN, m, poses[i], PD_OVERLAP_NO_FILTER);
        CHECK(on.hit && off.hit);
        sorted += on.tris_a >= 64 && on.tris_b >= 64; /* near triangles: both paths taken */
        /* the same cusps summed in the same order: equal to the last bit (the sweep puts the
         * boxes it finds back in index order; bench/overlap's 4 096 pairs agree so too) */
        CHECK_NEAR(off.volume, on.volume, 0);
        for (int k = 0; k < 3; k++) {
            CHECK_NEAR(off.centroid[k], on.centroid[k], 0);
            CHECK_NEAR(off.normal[k], on.normal[k], 0);
        }
        CHECK_NEAR(off.depth, on.depth, 0);
    }
    CHECK_EQ_INT(np, sorted);
    pd_mesh_destroy(m);
}

/* ---- independent cross-check of non-convex overlaps ------------------------------------- */

static void compare_with_reference(const char *na, int ta, const char *nb, int tb, double dist,
                                   int trials, int *hits)
{
    pd_mesh *a = builtin(na, ta), *b = builtin(nb, tb);
    pd_mass_props ma, mb;
    pd_mesh_mass_props(a, &ma);
    pd_mesh_mass_props(b, &mb);
    for (int trial = 0; trial < trials; trial++) {
        double q[4];
        rnd_quat(q);
        pd_pose pa = pose(0.01, 0.02, -0.03, q[0], q[1], q[2], q[3]);
        pd_pose pb = near_pose(dist);
        pd_contact r = overlap(a, pa, b, pb, 0);
        double Ra[3][3], Rb[3][3], oa[3], ob[3];
        pd_quat_to_matrix(pa.q, Ra);
        pd_quat_to_matrix(pb.q, Rb);
        /* apexes at the posed centroids (any point gives a valid signed decomposition) */
        for (int i = 0; i < 3; i++) {
            oa[i] = pa.x[i] + Ra[i][0] * ma.centroid[0] + Ra[i][1] * ma.centroid[1] +
                    Ra[i][2] * ma.centroid[2];
            ob[i] = pb.x[i] + Rb[i][0] * mb.centroid[0] + Rb[i][1] * mb.centroid[1] +
                    Rb[i][2] * mb.centroid[2];
        }
        ref_result ref;
        ref_overlap(a, Ra, pa.x, oa, b, Rb, pb.x, ob, &ref);
        double vmin = ma.volume < mb.volume ? ma.volume : mb.volume;
        if (ref.volume < 1e-6 * vmin) { /* a graze: only demand agreement on "small" */
            CHECK(!r.hit || r.volume < 1e-5 * vmin);
            continue;
        }
        (*hits)++;
        CHECK(r.hit);
        CHECK_REL(ref.volume, r.volume, 1e-9);
        CHECK_VEC(ref.centroid[0], ref.centroid[1], ref.centroid[2], r.centroid, 1e-9);
        CHECK_VEC(ref.normal[0], ref.normal[1], ref.normal[2], r.normal, 1e-8);
        if (ref.depth_valid) CHECK_REL(ref.depth, r.depth, 1e-8);
    }
    pd_mesh_destroy(a);
    pd_mesh_destroy(b);
}

TEST(schonhardt_pairs_match_tetrahedral_reference)
{
    int hits = 0;
    compare_with_reference("schonhardt", 0, "schonhardt", 0, 1.0, 40, &hits);
    CHECK(hits > 15);
}

TEST(rock_pairs_match_tetrahedral_reference)
{
    int hits = 0;
    compare_with_reference("rock", 80, "rock", 320, 0.8, 15, &hits);
    compare_with_reference("rock", 20, "schonhardt", 0, 0.9, 15, &hits);
    CHECK(hits > 15);
}

TEST(rock_against_closed_wall_mesh)
{
    /* particle against a closed triangle-mesh wall (section 5.6): a rock pressed into a wide
     * box whose faces are a few large triangles, checked against the reference; the normal
     * points from the particle into the wall */
    pd_mesh *rock = builtin("rock", 80), *wall = box(-5, -5, -2, 5, 5, 0);
    int hits = 0;
    for (int trial = 0; trial < 10; trial++) {
        double q[4], Ra[3][3], I[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
        rnd_quat(q);
        double u0 = rnd(), u1 = rnd(), u2 = rnd(); /* in order: a call's is unspecified */
        pd_pose pa = pose(0.2 * u0, 0.2 * u1, 0.35 + 0.1 * u2, q[0], q[1], q[2], q[3]);
        pd_contact r = overlap(rock, pa, wall, ORIGIN, 0);
        pd_quat_to_matrix(pa.q, Ra);
        double o[3] = {0, 0, -1};
        ref_result ref;
        ref_overlap(rock, Ra, pa.x, pa.x, wall, I, ORIGIN.x, o, &ref);
        if (ref.volume < 1e-6) continue;
        hits++;
        CHECK_REL(ref.volume, r.volume, 1e-9);
        CHECK_VEC(ref.centroid[0], ref.centroid[1], ref.centroid[2], r.centroid, 1e-9);
        CHECK_VEC(0, 0, -1, r.normal, 1e-9); /* a flat wall: the normal is the wall's */
    }
    CHECK(hits >= 5);
    pd_mesh_destroy(rock);
    pd_mesh_destroy(wall);
}

/* ---- convergence to the sphere ---------------------------------------------------------- */

TEST(icosphere_overlap_converges_to_spherical_caps)
{
    /* two spheres of radius R at distance 2R - delta overlap in two caps of height delta/2:
     * V = 2 pi h^2 (3R - h) / 3. Icospheres are scaled to the sphere's volume (as the thesis's
     * section 6.1 normalises) and the error must fall with every subdivision; the observed rate
     * is about 4x per level (error ~ edge^2), and level 4 must be within 2 %. */
    double R = 1, delta = 0.2, h = delta / 2, exact = 2 * PI * h * h * (3 * R - h) / 3;
    int levels[] = {80, 320, 1280, 5120};
    double prev = 1e9;
    for (int l = 0; l < 4; l++) {
        pd_mesh *m = builtin("icosphere", levels[l]);
        pd_mass_props mp;
        pd_mesh_mass_props(m, &mp);
        double s = cbrt(4.0 / 3.0 * PI / mp.volume);
        for (int i = 0; i < 3 * m->nverts; i++)
            m->verts[i] *= s;
        /* average over orientations: the faceting error depends on which feature faces */
        double err = 0;
        int n = 8;
        for (int t = 0; t < n; t++) {
            double qa[4], qb[4];
            rnd_quat(qa);
            rnd_quat(qb);
            pd_contact r = overlap(m, pose(0, 0, 0, qa[0], qa[1], qa[2], qa[3]), m,
                                   pose(2 * R - delta, 0, 0, qb[0], qb[1], qb[2], qb[3]), 0);
            err += fabs(r.volume - exact) / exact / n;
        }
        printf("  icosphere %4d triangles: mean |V - V_caps| / V_caps = %.4f\n", levels[l], err);
        CHECK(err < prev);
        prev = err;
        pd_mesh_destroy(m);
    }
    CHECK(prev < 0.02);
}

/* ---- precision and OpenCL ---------------------------------------------------------------- */

TEST(single_precision_close_to_double)
{
    pd_mesh *m = builtin("rock", 80);
    int hits = 0;
    for (int trial = 0; trial < 20; trial++) {
        pd_pose pb = near_pose(0.8);
        pd_contact d = overlap(m, ORIGIN, m, pb, 0);
        pd_contact s = overlap(m, ORIGIN, m, pb, PD_OVERLAP_SINGLE);
        if (!d.hit || d.volume < 1e-3) continue;
        hits++;
        /* float carries 2^-23 = 1.2e-7; the cusp sums cancel O(size^3) terms down to V, so
         * about 1e-7 * size^3 / V relative, below 1e-3 for overlaps above 1e-3 of the volume */
        CHECK_REL(d.volume, s.volume, 1e-3);
        CHECK_VEC(d.normal[0], d.normal[1], d.normal[2], s.normal, 1e-3);
    }
    CHECK(hits > 5);
    pd_mesh_destroy(m);
}

/*
 * Fine meshes: 1280- and 5120-triangle shapes pressed 1 % of their size deep at random poses.
 * Each predicate's snap bound once scaled with the configuration's size L instead of its own
 * edges, so a point within pad (L / e)^2 of a plane counted as on it: harmless in double, but in
 * single precision ~1e-3 of a size for 5120-triangle rocks, whose volumes came out 3 % wrong at
 * the median and up to 90 times the true one (bench/RESULTS.md). The tolerance is the test
 * above's 1e-7 size^3 / V with V ~ 1e-3 of the volume: 1e-4, with a factor of ten to spare.
 */
TEST(single_precision_close_to_double_on_fine_meshes)
{
    const char *names[] = {"icosphere", "rock"};
    int tris[] = {1280, 5120};
    for (int k = 0; k < 2; k++) {
        pd_mesh *m = builtin(names[k], tris[k]);
        pd_mass_props mp;
        pd_mesh_mass_props(m, &mp);
        double size = cbrt(6 * mp.volume / PI), worst = 0;
        for (int trial = 0; trial < 6; trial++) {
            pd_pose pa = ORIGIN, pb = near_pose(1);
            rnd_quat(pa.q);
            double u[3] = {pb.x[0], pb.x[1], pb.x[2]}, lo = 0, hi = 2 * size;
            pd_contact d;
            for (int it = 0; it < 30; it++) { /* depth(lo) > 1 % of the size >= depth(hi) */
                double mid = 0.5 * (lo + hi);
                for (int q = 0; q < 3; q++)
                    pb.x[q] = mid * u[q];
                d = overlap(m, pa, m, pb, 0);
                if (d.hit && d.depth > 0.01 * size)
                    lo = mid;
                else
                    hi = mid;
            }
            for (int q = 0; q < 3; q++)
                pb.x[q] = lo * u[q];
            d = overlap(m, pa, m, pb, 0);
            pd_contact s = overlap(m, pa, m, pb, PD_OVERLAP_SINGLE);
            CHECK(d.hit && s.hit);
            if (!d.hit || !s.hit) continue;
            CHECK_REL(d.volume, s.volume, 1e-3);
            CHECK_VEC(d.normal[0], d.normal[1], d.normal[2], s.normal, 1e-3);
            double e = fabs(s.volume / d.volume - 1);
            worst = e > worst ? e : worst;
        }
        printf("  %s %d: single against double, worst volume %.1e relative\n", names[k], tris[k],
               worst);
        pd_mesh_destroy(m);
    }
}

/*
 * A cube's corner pressed h into another's face, along its body diagonal: the overlap is the
 * corner's trirectangular tetrahedron with legs sqrt(3) h, V = (sqrt(3)/2) h^3. Its cusps reach
 * from A's centre, so they are of the order of the cube whatever h; summed there, single
 * precision lost V below ~1e-5 of the cube (h < 0.024) and returned no contact. Tolerances:
 * double, 1e-4, the re-summing bound (sums are kept about A's centre only above 1e4 ulps of their
 * terms); single, the corner's position carrying ~8 ulps of its 1.37 m distance, tripled by h^3,
 * plus that bound.
 */
TEST(corner_into_face_at_small_depths)
{
    pd_mesh *c = builtin("cube", 0);
    double ang = acos(1 / sqrt(3.0)), sn = sin(ang / 2) / sqrt(2.0);
    for (double h = 1e-2; h > 5e-5; h /= 10) {
        pd_pose pb = pose(0.5 + sqrt(3.0) / 2 - h, 0, 0, cos(ang / 2), 0, sn, -sn);
        double exact = sqrt(3.0) / 2 * h * h * h;
        pd_contact d = overlap(c, ORIGIN, c, pb, 0);
        pd_contact f = overlap(c, ORIGIN, c, pb, PD_OVERLAP_SINGLE);
        double tol_f = 3 * 8 * 1.1920929e-7 * 1.37 / h + 1e-4;
        printf("  h %.0e m: V %.3e m^3, double %+.1e, single %+.1e relative (tolerance %.1e)\n", h,
               exact, d.volume / exact - 1, f.volume / exact - 1, tol_f);
        CHECK(d.hit && f.hit);
        CHECK_REL(exact, d.volume, 1e-4);
        CHECK_REL(exact, f.volume, tol_f);
        CHECK_VEC(1, 0, 0, f.normal, 1e-3); /* from A into B (eq. 4.19) */
    }
    pd_mesh_destroy(c);
}

/*
 * OVL_ORIGIN (the engine sums a pair that touched in the last step about its contact point then):
 * the cusps summed about another origin give the same overlap, within the rounding of the sums.
 * Rocks overlapping by at least 1e-3 of their volume, against the plain sum in double precision:
 * about the overlap's own centroid 1e-10, about a point 3.5 sizes away 1e-9 (cusps of up to
 * 3.5^3 / 6 each and a hundred of them, 1e-16 each, against 1e-3); the centroid also checks the
 * moment's shift back to A's frame. The cube's corner 1e-3 deep (the test above), against its
 * exact tetrahedron, V = (sqrt(3)/2) h^3 with centroid (0.5 - h/4, 0, 0): about that centroid
 * 1e-10 (the plain sum is 1.4e-9 off, its cusps being of the cube's size), about the far point
 * 1e-4, the bound above which a sum is kept without summing again about the nodes (the
 * centroid, a moment over V, to those times its lever arm: 4 from the far point). Single
 * precision: 1e-3 for the rocks as above (about the far point the sum is redone about the nodes'
 * centre), the corner to its tolerance in the test above.
 */
TEST(first_origin_leaves_the_overlap_unchanged)
{
    pd_mesh *rock = builtin("rock", 80), *cube = builtin("cube", 0);
    double ang = acos(1 / sqrt(3.0)), sn = sin(ang / 2) / sqrt(2.0), h = 1e-3;
    const double far[3] = {2, -2, 2};
    int hits = 0;
    for (int trial = 0; trial < 21; trial++) {
        int corner = trial == 20;
        pd_mesh *m = corner ? cube : rock;
        pd_pose pb =
            corner ? pose(0.5 + sqrt(3.0) / 2 - h, 0, 0, cos(ang / 2), 0, sn, -sn) : near_pose(0.8);
        ovl_setup s;
        pd_error err = {0};
        if (ovl_setup_make(m, &ORIGIN, m, &pb, 0, &s, &err) != PD_OK) {
            TEST_FAILF("setup: %s", err.msg);
            break;
        }
        ovl_result d, o;
        CHECK(ovl_run_f64(&s, &d) == PD_OK);
        if (!d.hit || (!corner && d.volume < 1e-3)) {
            ovl_setup_free(&s);
            continue;
        }
        hits++;
        if (corner) { /* the exact tetrahedron (depth and normal are exact already) */
            d.volume = sqrt(3.0) / 2 * h * h * h;
            d.centroid[0] = 0.5 - h / 4;
            d.centroid[1] = d.centroid[2] = 0;
        }
        for (int k = 0; k < 4; k++) {
            int single = k >= 2, at_far = k % 2;
            s.flags = OVL_ORIGIN;
            memcpy(s.org, at_far ? far : d.centroid, sizeof s.org);
            CHECK((single ? ovl_run_f32(&s, &o) : ovl_run_f64(&s, &o)) == PD_OK);
            double tol = single   ? (corner ? 3 * 8 * 1.1920929e-7 * 1.37 / h + 1e-4 : 1e-3)
                         : at_far ? (corner ? 1e-4 : 1e-9)
                                  : 1e-10;
            CHECK(o.hit);
            CHECK_REL(d.volume, o.volume, tol);
            CHECK_VEC(d.normal[0], d.normal[1], d.normal[2], o.normal, single ? 1e-3 : tol);
            if (!single) {
                /* the centroid is the moment over V, and the moment's rounding grows with the
                 * lever arm: relative to 4 (the far point's distance) or to the overlap's size */
                double ct = tol * (at_far ? 4 : corner ? h : 1);
                CHECK_VEC(d.centroid[0], d.centroid[1], d.centroid[2], o.centroid, ct);
                CHECK_REL(d.depth, o.depth, tol);
            }
        }
        ovl_setup_free(&s);
    }
    CHECK(hits > 5);
    pd_mesh_destroy(rock);
    pd_mesh_destroy(cube);
}

/* ---- separate places (thesis section 5.4, OVL_PLACES) -----------------------------------------
 */

/* S1 = sum sqrt(V_k d_k), S2 = sum sqrt(V_k / d_k) of single-place contacts with one normal
 * (ovl_places), and the centroids weighted by sqrt(V_k d_k), where their summed force acts. */
static void places_sums(const pd_contact *c, int n, double *vol_eff, double *depth_eff,
                        double point[3])
{
    double s1 = 0, s2 = 0, m[3] = {0, 0, 0};
    for (int k = 0; k < n; k++) {
        double f = sqrt(c[k].volume * c[k].depth);
        s1 += f;
        s2 += sqrt(c[k].volume / c[k].depth);
        for (int i = 0; i < 3; i++)
            m[i] += f * c[k].centroid[i];
    }
    *vol_eff = s1 * s2;
    *depth_eff = s1 / s2;
    for (int i = 0; i < 3; i++)
        point[i] = m[i] / s1;
}

/*
 * A U standing on a slightly tilted slab touches it in two places, one under each prong, 10 and
 * 14 mm deep. The independent computation: each prong alone (a box, one place) against the same
 * slab, whose overlaps with the U's are the same solids. The U's overlap must find the two places
 * and give volume V1 + V2, effective volume and depth from S1 and S2 of those two, and the point
 * where their summed force acts (ovl_places; 1e-10: the cusps of one solid summed in two orders
 * and over two different meshes). Pressed in
 * past the U's crotch (z = 1), the overlap is one connected U itself: one place, its effective
 * volume and depth exactly its volume and depth.
 */
TEST(separate_places_of_a_u_on_a_tilted_slab)
{
    pd_mesh *u = u_shape_mesh();
    pd_mesh *slab = box(-1, -1, -1, 4, 4, 0);
    pd_mesh *prong[2] = {box(0, 0, 0, 1, U_LY, 1), box(2, 0, 0, 3, U_LY, 1)};
    if (!u) return;
    double a = 0.002; /* tilt about y, rad: the slab's top rises towards +x */
    pd_pose ps = pose(0, 0, 0.008, cos(a / 2), 0, -sin(a / 2), 0);
    pd_contact c = overlap(u, ORIGIN, slab, ps, 0), one[2];
    for (int k = 0; k < 2; k++) {
        one[k] = overlap(prong[k], ORIGIN, slab, ps, 0);
        CHECK(one[k].hit && one[k].places == 1);
    }
    double ve, de, pe[3];
    places_sums(one, 2, &ve, &de, pe);
    printf("  U: V %.6e m^3, depth %.4g m, %d places: effective V %.6e m^3, depth %.4g m\n",
           c.volume, c.depth, c.places, c.effective_volume, c.effective_depth);
    CHECK(c.hit);
    CHECK_EQ_INT(2, c.places);
    CHECK_REL(one[0].volume + one[1].volume, c.volume, 1e-10);
    CHECK_REL(ve, c.effective_volume, 1e-10);
    CHECK_REL(de, c.effective_depth, 1e-10);
    CHECK_REL(fmax(one[0].depth, one[1].depth), c.depth, 1e-10);
    CHECK_VEC(pe[0], pe[1], pe[2], c.effective_point, 1e-10);
    pd_contact f = overlap(u, ORIGIN, slab, ps, PD_OVERLAP_SINGLE);
    CHECK_EQ_INT(2, f.places);
    CHECK_REL(ve, f.effective_volume, 1e-4); /* single_precision_close_to_double's bound */
    CHECK_REL(de, f.effective_depth, 1e-4);

    pd_pose deep = pose(0, 0, 1.2, cos(a / 2), 0, -sin(a / 2), 0);
    pd_contact d = overlap(u, ORIGIN, slab, deep, 0);
    CHECK(d.hit);
    CHECK_EQ_INT(1, d.places);
    CHECK(d.effective_volume == d.volume && d.effective_depth == d.depth);
    pd_mesh_destroy(u);
    pd_mesh_destroy(slab);
    pd_mesh_destroy(prong[0]);
    pd_mesh_destroy(prong[1]);
}

/*
 * Places are a property of the overlap, not of which solid is A: random poses of two U's (many
 * touch in two or three places) give the same count, effective volume, depth and point with A
 * and B swapped, though the nodes are then found from the other solid's edges (1e-9, as the depth
 * in swap_gives_same_volume_and_opposite_normal). A single place keeps volume and depth exactly.
 */
TEST(places_agree_when_the_solids_swap)
{
    pd_mesh *u = u_shape_mesh();
    if (!u) return;
    int hits = 0, multi = 0;
    for (int trial = 0; trial < 150; trial++) {
        pd_pose pa = near_pose(0.1), pb = near_pose(2.2);
        pd_contact ab = overlap(u, pa, u, pb, 0), ba = overlap(u, pb, u, pa, 0);
        CHECK_EQ_INT(ab.hit, ba.hit);
        if (!ab.hit || !ba.hit) continue;
        hits++;
        multi += ab.places > 1;
        CHECK(ab.places >= 1);
        CHECK_EQ_INT(ab.places, ba.places);
        /* the two frames round the cusps differently: 1e-9 relative, and ~1e-15 m^3 absolute,
         * a few ulps of cusps of these solids' size (a 4.7e-8 m^3 overlap differed by 4.6e-16) */
        CHECK_NEAR(ab.effective_volume, ba.effective_volume, 1e-9 * ab.effective_volume + 1e-14);
        CHECK_REL(ab.effective_depth, ba.effective_depth, 1e-9);
        /* a place's centroid is its moment over its volume, both summed from cusps of the
         * solids' size, so a small place's carries their rounding over its volume: 1e-9 m
         * measured on most of these 3 m solids' poses, and for the moment a few ulps of the
         * cusps' moments, about the volume's 1e-15 m^3 above times the solids' 3 m, over V
         * (a single place of 6.3e-9 m^3 differed by 4.4e-8 m: a fixed 1e-8 failed there) */
        CHECK_VEC(ab.effective_point[0], ab.effective_point[1], ab.effective_point[2],
                  ba.effective_point, 1e-8 + 4e-15 / ab.effective_volume);
        if (ab.places == 1)
            CHECK(ab.effective_volume == ab.volume && ab.effective_depth == ab.depth);
    }
    printf("  %d overlaps, %d of them in several places\n", hits, multi);
    CHECK(hits > 40 && multi > 5); /* the trials must exercise several places */
    pd_mesh_destroy(u);
}

/* Whether two contacts are the same to the bit (a NaN in either is not). */
static int same_contact(const pd_contact *a, const pd_contact *b)
{
    int same = a->hit == b->hit && a->volume == b->volume && a->depth == b->depth &&
               a->degenerate == b->degenerate && a->tris_a == b->tris_a && a->tris_b == b->tris_b &&
               a->places == b->places && a->places_known == b->places_known &&
               a->effective_volume == b->effective_volume &&
               a->effective_depth == b->effective_depth;
    for (int k = 0; k < 3; k++)
        same = same && a->centroid[k] == b->centroid[k] && a->normal[k] == b->normal[k] &&
               a->effective_point[k] == b->effective_point[k];
    return same;
}

/* n unit cubes in a row along x, 2 m apart, as one mesh */
static pd_mesh *cube_row(int n)
{
    double *v = malloc(sizeof(double) * 24 * (size_t)n);
    int *t = malloc(sizeof(int) * 36 * (size_t)n);
    static const int ct[36] = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                               2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
    pd_mesh *m = NULL;
    pd_error err = {0};
    if (v && t) {
        for (int c = 0; c < n; c++) {
            for (int i = 0; i < 8; i++) {
                v[24 * c + 3 * i] = 2 * c + (i & 1);
                v[24 * c + 3 * i + 1] = (i & 2) ? 1 : 0;
                v[24 * c + 3 * i + 2] = (i & 4) ? 1 : 0;
            }
            for (int k = 0; k < 36; k++)
                t[36 * c + k] = 8 * c + ct[k];
        }
        if (pd_mesh_from_arrays(v, 8 * n, t, 12 * n, "row", &m, &err) != PD_OK)
            printf("  cube_row: %s\n", err.msg);
    }
    free(v);
    free(t);
    return m;
}

/*
 * A row of n cubes against itself moved by half a cube overlaps in n separate places. Beyond the
 * nodes the scratch holds (256 + half the triangles; with these cubes' diagonals, from 10 cubes
 * on), the places cannot be told apart and the answer is one place, the whole overlap's: it said
 * so as if it were known (QA 2026-12-08). places_known now tells, host and OpenCL alike: every
 * answer is either n known places or one unknown, and both kinds occur in the range.
 */
TEST(places_unknown_beyond_the_node_scratch)
{
    pd_device *dev = NULL;
    pd_error err = {0};
    int have_cl = pd_device_open(-1, &dev, &err) == PD_OK, known = 0, unknown = 0;
    if (!have_cl) TEST_FAILF("no OpenCL device: %s", err.msg);
    for (int n = 2; n <= 15; n++) {
        pd_mesh *m = cube_row(n);
        CHECK(m != NULL);
        if (!m) continue;
        pd_pose pb = pose(0.5, 0, 0, 1, 0, 0, 0);
        pd_contact h = overlap(m, ORIGIN, m, pb, 0), d;
        CHECK(h.hit);
        CHECK_NEAR(0.5 * n, h.volume, 1e-12);
        CHECK_EQ_INT(h.places_known ? n : 1, h.places);
        known += h.places_known;
        unknown += !h.places_known;
        if (have_cl && pd_overlap_cl(dev, m, &ORIGIN, m, &pb, 0, &d, &err) == PD_OK) {
            CHECK_EQ_INT(h.places, d.places);
            CHECK_EQ_INT(h.places_known, d.places_known);
        }
        pd_mesh_destroy(m);
    }
    printf("  %d rows with their places known, %d without\n", known, unknown);
    CHECK(known > 0 && unknown > 0);
    pd_device_close(dev);
}

TEST(opencl_kernel_agrees_with_host)
{
    pd_device *dev = NULL;
    pd_error err = {0};
    if (pd_device_open(-1, &dev, &err) != PD_OK) {
        TEST_FAILF("no OpenCL device: %s", err.msg);
        return;
    }
    const char *names[] = {"schonhardt", "rock", "cube"};
    int hits = 0, singles = 0;
    for (int i = 0; i < 3; i++) {
        pd_mesh *m = builtin(names[i], 0);
        for (int trial = 0; trial < 6; trial++) {
            pd_pose pa = near_pose(0.1), pb = near_pose(0.8);
            pd_contact h = overlap(m, pa, m, pb, 0), c;
            if (pd_overlap_cl(dev, m, &pa, m, &pb, 0, &c, &err) != PD_OK) {
                TEST_FAILF("pd_overlap_cl: %s", err.msg);
                break;
            }
            CHECK_EQ_INT(h.hit, c.hit);
            if (!h.hit) continue;
            hits++;
            /* the issue's contract: 1e-12 relative in double precision */
            CHECK_REL(h.volume, c.volume, 1e-12);
            CHECK_VEC(h.centroid[0], h.centroid[1], h.centroid[2], c.centroid, 1e-12);
            CHECK_VEC(h.normal[0], h.normal[1], h.normal[2], c.normal, 1e-12);
            CHECK_REL(h.depth, c.depth, 1e-12);
            CHECK_EQ_INT(h.places, c.places);
            CHECK_REL(h.effective_volume, c.effective_volume, 1e-12);
            CHECK_REL(h.effective_depth, c.effective_depth, 1e-12);
            CHECK_VEC(h.effective_point[0], h.effective_point[1], h.effective_point[2],
                      c.effective_point, 1e-12);
            /* single precision: the host's single-precision answer to the bit where the device
             * rounds / and sqrt as the host does (the engine then builds its programs to), as
             * every device so far but NVIDIA's driver without the build option (6.3e-7 on an
             * H200); and any device's volume within single's 2e-3 of double's */
            pd_contact hs, cs;
            if (pd_overlap_host(m, &pa, m, &pb, PD_OVERLAP_SINGLE, &hs, &err) != PD_OK ||
                pd_overlap_cl(dev, m, &pa, m, &pb, PD_OVERLAP_SINGLE, &cs, &err) != PD_OK) {
                TEST_FAILF("single precision: %s", err.msg);
                break;
            }
            CHECK_REL(h.volume, cs.volume, 2e-3);
            if (pd_device_fp32_rounded(dev)) {
                CHECK(same_contact(&hs, &cs));
                singles += same_contact(&hs, &cs);
            }
        }
        pd_mesh_destroy(m);
    }
    printf("  %d of 18 single-precision overlaps the host's to the bit%s\n", singles,
           pd_device_fp32_rounded(dev) ? "" : " (not checked: / and sqrt not correctly rounded)");
    CHECK(hits > 5);
    pd_device_close(dev);
}

/*
 * A device that rounds single-precision / and sqrt correctly is asked to, in every program and
 * both precisions (cl_build_program): PoCL's / and sqrt are the CPU's either way, so the
 * bit-for-bit agreement above cannot show the option missing, but the programs' build options
 * do. A device without the capability must not be given it (the specification allows only those
 * that report it).
 */
TEST(programs_ask_for_correctly_rounded_single_precision)
{
    pd_device *dev = NULL;
    pd_error err = {0};
    if (pd_device_open(-1, &dev, &err) != PD_OK) {
        TEST_FAILF("no OpenCL device: %s", err.msg);
        return;
    }
    const char *opt = "-cl-fp32-correctly-rounded-divide-sqrt";
    const struct {
        const char *name;
        int variant;
    } progs[] = {{"integrate", 0}, {"contact", CL_PLACES}, {"integrate", CL_DOUBLE}};
    for (int i = 0; i < 3; i++) {
        if ((progs[i].variant & CL_DOUBLE) && !pd_device_has_fp64(dev)) continue;
        cl_program prog;
        if (cl_program_get(dev, progs[i].name, progs[i].variant, &prog, &err) != PD_OK) {
            TEST_FAILF("%s: %s", progs[i].name, err.msg);
            continue;
        }
        char opts[512] = {0};
        CHECK_EQ_INT(CL_SUCCESS, clGetProgramBuildInfo(prog, dev->device, CL_PROGRAM_BUILD_OPTIONS,
                                                       sizeof opts - 1, opts, NULL));
        printf("  %s (variant %d): \"%s\"\n", progs[i].name, progs[i].variant, opts);
        CHECK_EQ_INT(pd_device_fp32_rounded(dev), strstr(opts, opt) != NULL);
    }
    pd_device_close(dev);
}

TEST(bad_pose_is_an_error_not_a_nan)
{
    pd_mesh *c = builtin("cube", 0);
    pd_pose bad = pose(0, 0, 0, 0, 0, 0, 0);
    pd_contact r;
    pd_error err = {0};
    CHECK_EQ_INT(PD_EINVAL, pd_overlap_host(c, &ORIGIN, c, &bad, 0, &r, &err));
    CHECK_STR_CONTAINS(err.msg, "quaternion");
    pd_mesh_destroy(c);
}

/*
 * The filter's vertex clusters (engine/vertex_clusters.c; kernels/overlap.h, ovl_cluster_bounds):
 * every vertex is listed once, in its cluster, and its projection as the filter computes it lies
 * within its cluster's bounds for any direction, scale and offset, 1e3 m from the origin too; the
 * extremes found through them are every vertex's; and on a curved particle they spare most of its
 * vertices (else the clusters would cost without saving: OVL_CLUSTER_MIN).
 */
TEST(vertex_clusters_bound_their_vertices)
{
    struct {
        const char *name;
        int tris;
        double shift;
    } ms[] = {{"icosphere", 5120, 0},
              {"rock", 5000, 0},
              {"cube", 0, 0},
              {"schonhardt", 0, 0},
              {"rock", 1000, 1e3}};
    for (int im = 0; im < 5; im++) {
        pd_mesh *m = builtin(ms[im].name, ms[im].tris);
        int nv = m->nverts, ncl = ovl_nclusters(nv), *vc = NULL;
        double *disc = NULL, *v = malloc(sizeof(double) * 3 * (size_t)nv);
        for (int k = 0; k < 3 * nv; k++)
            v[k] = m->verts[k] + ms[im].shift;
        CHECK_EQ_INT(PD_OK, ovl_vertex_clusters(v, nv, &vc, &disc));
        int *seen = calloc((size_t)nv, sizeof *seen), *done = malloc(sizeof(int) * ncl);
        double *bnd = malloc(sizeof(double) * 2 * ncl), *proj = malloc(sizeof(double) * nv);
        int bad_list = 0, bad_bound = 0, bad_extreme = 0;
        for (int h = 0; h < nv; h++) {
            seen[vc[h]]++;
            bad_list += vc[nv + vc[h]] != h / OVL_CLUSTER;
        }
        for (int i = 0; i < nv; i++)
            bad_list += seen[i] != 1;
        double spared = 0;
        for (int trial = 0; trial < 100; trial++) {
            double q[4], sc = 0.5 + 1.5 * rnd();
            rnd_quat(q); /* a random unit direction: q's vector part, normalised */
            double qn = sqrt(q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
            pd_v3 dd = v3(sc * q[1] / qn, sc * q[2] / qn, sc * q[3] / qn);
            int side = trial & 1; /* B's projections carry an offset, A's none */
            double off = side ? 2e3 * (rnd() - 0.5) : 0;
            int khi, klo;
            ovl_cluster_bounds(disc, ncl, dd, off, bnd, done, &khi, &klo);
            double lo = HUGE_VAL, hi = -HUGE_VAL;
            for (int i = 0; i < nv; i++) {
                double p = v3_dot(v3_load(v, i), dd);
                if (side) p = p + off; /* the filter's own expressions (ovl_cluster_project) */
                int k = vc[nv + i];
                bad_bound += p < bnd[2 * k] || p > bnd[2 * k + 1];
                lo = fmin(lo, p);
                hi = fmax(hi, p);
            }
            double mn, mx;
            ovl_cluster_extremes(v, vc, disc, nv, dd, off, side, proj, bnd, done, &mn, &mx);
            bad_extreme += mn != lo || mx != hi;
            int projected = 0;
            for (int k = 0; k < ncl; k++)
                projected += done[k] ? OVL_CLUSTER : 0;
            spared += 1 - (double)projected / nv;
        }
        CHECK_EQ_INT(0, bad_list);
        CHECK_EQ_INT(0, bad_bound);
        CHECK_EQ_INT(0, bad_extreme);
        /* an icosphere's two extremes: a few clusters at either pole (measured: 0.8 spared) */
        if (im == 0) CHECK(spared / 100 > 0.6);
        free(v);
        free(vc);
        free(disc);
        free(seen);
        free(done);
        free(bnd);
        free(proj);
        pd_mesh_destroy(m);
    }
}

/*
 * With the clusters the filter projects a few clusters' vertices instead of all, and must keep the
 * very triangles it keeps without them: the same bits in double and single precision, for
 * meshes large enough to use them (OVL_CLUSTER_MIN), 1e3 m from the origin too.
 */
TEST(clustered_filter_keeps_what_every_vertex_keeps)
{
    pd_mesh *ico = builtin("icosphere", 5120), *rock = builtin("rock", 5000);
    CHECK(ico->nverts * 2 >= OVL_CLUSTER_MIN && rock->nverts * 2 >= OVL_CLUSTER_MIN);
    const pd_mesh *pa_m[3] = {ico, rock, ico}, *pb_m[3] = {ico, rock, rock};
    const double dist[3] = {1.97, 0.9, 1.45};
    int hits = 0, differ = 0, clustered = 0;
    for (int i = 0; i < 3; i++)
        for (int trial = 0; trial < 12; trial++) {
            double q[4];
            rnd_quat(q);
            double sh = trial & 1 ? 1e3 : 0;
            pd_pose pa = pose(sh, sh, sh, q[0], q[1], q[2], q[3]);
            pd_pose pb = near_pose(dist[i]);
            for (int k = 0; k < 3; k++)
                pb.x[k] += sh;
            ovl_setup s;
            pd_error err = {0};
            if (ovl_setup_make(pa_m[i], &pa, pb_m[i], &pb, 0, &s, &err) != PD_OK) {
                TEST_FAILF("setup: %s", err.msg);
                continue;
            }
            ovl_setup every = s; /* the same problem without the clusters */
            every.vc_a = every.vc_b = NULL;
            clustered += s.vc_a && s.vc_b;
            ovl_result r1, r2, f1, f2;
            memset(&r1, 0, sizeof r1);
            r2 = f1 = f2 = r1;
            CHECK_EQ_INT(PD_OK, ovl_run_f64(&s, &r1));
            CHECK_EQ_INT(PD_OK, ovl_run_f64(&every, &r2));
            CHECK_EQ_INT(PD_OK, ovl_run_f32(&s, &f1));
            CHECK_EQ_INT(PD_OK, ovl_run_f32(&every, &f2));
            differ += !ovl_result_equal(&r1, &r2) + !ovl_result_equal(&f1, &f2);
            hits += r1.hit;
            ovl_setup_free(&s);
        }
    CHECK_EQ_INT(0, differ);
    CHECK_EQ_INT(36, clustered);
    CHECK(hits >= 20);
    pd_mesh_destroy(ico);
    pd_mesh_destroy(rock);
}

/* A lattice cube pair (q: A's x y z qw qx qy qz, then B's) in double (*d) and single (*s). */
static void lattice_pair(const pd_mesh *m, const double *q, pd_contact *d, pd_contact *s)
{
    pd_pose pa = pose(q[0], q[1], q[2], q[3], q[4], q[5], q[6]);
    pd_pose pb = pose(q[7], q[8], q[9], q[10], q[11], q[12], q[13]);
    *d = overlap(m, pa, m, pb, 0);
    *s = overlap(m, pa, m, pb, PD_OVERLAP_SINGLE);
}

/*
 * Overlaps of lattice cube pairs (poses: A's x y z qw qx qy qz, then B's) in double and in single
 * precision: double must touch by more than vmin (m^3), single where double does, with the volume
 * within vres resolutions over the contact's area (A's top face), the depth and the effective
 * depth (OVL_PLACES, which the engine's force law takes) within 2 resolutions, the normal within
 * 1e-3.
 */
static void lattice_single_matches_double(const double (*poses)[14], int n, double vmin,
                                          double vres)
{
    pd_mesh *m = lattice_cube_mesh(LATTICE_SIZE);
    CHECK(m != NULL);
    if (!m) return;
    const double res = LATTICE_RES, area = LATTICE_AREA;
    for (int k = 0; k < n; k++) {
        pd_contact d, s;
        lattice_pair(m, poses[k], &d, &s);
        CHECK(d.hit && d.volume > vmin);
        CHECK(s.hit);
        if (!d.hit || !s.hit) continue;
        CHECK_NEAR(d.volume, s.volume, vres * res * area);
        CHECK_NEAR(d.depth, s.depth, 2 * res);
        CHECK_NEAR(d.effective_depth, s.effective_depth, 2 * res); /* what the force law takes */
        CHECK_VEC(d.normal[0], d.normal[1], d.normal[2], s.normal, 1e-3);
        printf("  pair %d: V %.4e m^3, single %+.1e relative (tolerance %.1e); depth %.3e m, "
               "single %+.1e m\n",
               k, d.volume, s.volume / d.volume - 1, vres * res * area / d.volume, d.depth,
               s.depth - d.depth);
    }
    pd_mesh_destroy(m);
}

/*
 * Cubes resting on each other in the columns of a settled lattice (examples/cube_lattice.json
 * after 0.4 s: the poses of its last frame), 2.5-8.7 um deep, the upper cube's bottom face tilted
 * against the lower's top by ~2e-4 rad, so that a corner of each lies within single precision's
 * tie band (2 resolutions, 3.7e-7 m) of the other's face. In single precision one of each try's
 * two passes (B displaced by +eps w and by -eps w) did not close, in every retry, and these
 * contacts were lost (11 of the lattice's 48; bench/RESULTS.md, 2026-12-06 evening); the pass
 * that closed is now the answer (ovl_compute). Tolerances against double precision: the volume
 * to 2 resolutions times the contact's area (the predicates snap features within that band, so
 * the configuration they describe may differ by that much), the depth to 2 resolutions, the
 * normal to 1e-3 as in single_precision_close_to_double.
 */
TEST(resting_cubes_in_single_precision)
{
    static const double poses[4][14] = {
        /* lattice particles 1 and 17: the +w pass closes */
        {0.041993783054748414, 0.014073263395621692, 0.0080579626850091467, 0.99999999416934537,
         7.6358736882810836e-05, -7.6358710026000671e-05, 1.029830994601275e-11,
         0.04201517781042588, 0.014094658149478852, 0.02417537089085945, 0.99999997507772054,
         0.00015786794612858375, -0.00015786788785712342, -4.0279750306695294e-11},
        /* 17 and 33 */
        {0.04201517781042588, 0.014094658149478852, 0.02417537089085945, 0.99999997507772054,
         0.00015786794612858375, -0.00015786788785712342, -4.0279750306695294e-11,
         0.04222059583075314, 0.014300076159210287, 0.040293765937520744, 0.99999996017217219,
         0.0001995691415408661, -0.00019956906533508456, 1.0981164274186682e-10},
        /* 24 and 40 */
        {0.013793807207535546, 0.070285674872507808, 0.024176041707430221, 0.99999989560078462,
         -0.00032311088674942296, -0.00032310644384299028, 2.7936041647906803e-08,
         0.013860620622837973, 0.070218861364550536, 0.040294329141751108, 0.99999985170638528,
         -0.00038509190351559091, -0.00038508626461591358, 4.7883471765243453e-08},
        /* 40 and 56: the -w pass closes */
        {0.013860620622837973, 0.070218861364550536, 0.040294329141751108, 0.99999985170638528,
         -0.00038509190351559091, -0.00038508626461591358, 4.7883471765243453e-08,
         0.013789254240334441, 0.070290227518440773, 0.056413282163957648, 0.99999983877012666,
         -0.00040153737180585633, -0.00040153138903333186, 5.8702269163270949e-08},
    };
    lattice_single_matches_double(poses, 4, 2e-10, 2);
}

/*
 * Three contacts of the settled lattice (examples/cube_lattice.json, frame 20, run in double
 * precision: particles 8 and 24, 14 and 30, 19 and 35), each a cube resting on the one below with
 * the two shifted sideways by about 0.2-0.5 mm and turned against each other by ~2e-4 rad. Their
 * facing side edges are nearly parallel and about a thousand single-precision resolutions apart.
 * The edges' band (ovl_edge_tol) used to snap them to a tie: its floor, 2 pad amax(da) amax(db),
 * is 2 pad / sin(angle) ~ 2 mm in distance at that angle, and the tie contradicted the side
 * tests of the same corners, which the coordinates decided. No try closed and single precision
 * lost all three (5 of the frame's 48 with the other two like them). The tolerances are those of
 * resting_cubes_in_single_precision.
 */
TEST(single_precision_finds_shifted_column_contacts)
{
    static const double poses[3][14] = {
        {0.014129860278901785, 0.069949620861402884, 0.0080588127931061626, 0.99999997573839638,
         -0.00015576234501901002, -0.0001557603869355707, 2.4565683352783338e-08,
         0.013793807207535546, 0.070285674872507808, 0.024176041707430221, 0.99999989560078462,
         -0.00032311088674942296, -0.00032310644384299028, 2.7936041647906803e-08},
        {0.070182396942052958, 0.097658642366875589, 0.0080576912056109559, 0.99999999327014433,
         -8.2035693134555919e-05, -8.2035702432815184e-05, 7.8328304128339352e-11,
         0.069963456488018105, 0.097877582824992648, 0.024174522003822925, 0.99999996338656016,
         -0.00019134637479716922, -0.00019134639576660442, 2.0980363840116229e-10},
        {0.098121663179650778, 0.013878333332913734, 0.024180120494410578, 0.99999964031024546,
         -0.00059968894116953838, -0.00059979375901889162, 1.7729382609558213e-08,
         0.098099059193029414, 0.01390093257849186, 0.040298763535803507, 0.99999943980054973,
         -0.00074840230563287622, -0.00074852693491523996, 5.8870487678323357e-08},
    };
    lattice_single_matches_double(poses, 3, 2e-10, 2);
}

/*
 * Particles 6 and 22 of the lattice settling in single precision (examples/cube_lattice.json with
 * "precision": "single", step 12 444): B rests on A, their front faces coplanar to a few
 * resolutions. A's diagonal edge in that face crosses B's front face plane at a place that is the
 * ratio of two side values within the tie band: single precision put the crossing node 1.8 mm
 * below the contact. The volume was right (+1e-4) but the depth came out 1.86e-3 m for 1.03e-5 m,
 * a one-step force spike in the run. The nodes are now kept within the box where both solids'
 * kept parts meet (ovl_node), which holds every node of A n B. Tolerances as in
 * resting_cubes_in_single_precision.
 */
TEST(single_precision_depth_of_a_grazing_crossing)
{
    static const double poses[1][14] = {
        {0.070090115070343018, 0.041982084512710571, 0.0080552734434604645, 0.99999731779098511,
         -5.980365676805377e-05, -1.6903089999686927e-05, 0.0023495466448366642,
         0.070100806653499603, 0.041986037045717239, 0.024171547964215279, 0.99999755620956421,
         -8.2688769907690585e-05, -3.6047480534762144e-05, 0.0022269641049206257},
    };
    lattice_single_matches_double(poses, 1, 2e-10, 2);
}

/*
 * Single against double precision for lattice pairs whose faces lie within single precision's tie
 * band of each other's, where the two may differ by which thin strips of side faces lie inside
 * the other solid: within that band the tie-breaking decides it. Double's own normal flips as B's
 * side face passes A's (pair 14-30 below: from +2.2e-4 to -1.9e-4 in x within 5e-8 m of motion),
 * and where two cubes stand flush its strips tilt the normal by h / W and triple the depth
 * (bench/RESULTS.md, 2026-12-07 (later)). Tolerances:
 * - volume: 2 resolutions times the contact's area, as in resting_cubes_in_single_precision;
 * - normal: what the strips can turn it by. A strip is at most W long (W the cube's side) and h
 *   high (h double's depth), each of the four sides adds one to eq. 4.19's sum or not, and that
 *   sum is twice the contact's area A >= V / h: so at most 4 W h / (2 V / h) = 2 W h^2 / V, and
 *   never below 1e-3 (single_precision_close_to_double);
 * - effective depth: what the normal actually turned by moves it across the face's diagonal,
 *   sqrt(2) W, plus 2 resolutions. A stray node or a turned normal is far outside: the spikes
 *   these pairs gave were 0.2 to 0.7 rad and 100 to 7 000 times the depth.
 */
static void lattice_single_within_strips(const double (*poses)[14], int n)
{
    pd_mesh *m = lattice_cube_mesh(LATTICE_SIZE);
    CHECK(m != NULL);
    if (!m) return;
    const double res = LATTICE_RES, w = 2 * LATTICE_H;
    for (int k = 0; k < n; k++) {
        pd_contact d, s;
        lattice_pair(m, poses[k], &d, &s);
        CHECK(d.hit && s.hit);
        if (!d.hit || !s.hit) continue;
        CHECK_NEAR(d.volume, s.volume, 2 * res * LATTICE_AREA);
        double turn = fmax(1e-3, 2 * w * d.depth * d.depth / d.volume);
        double angle = angle_between(d.normal, s.normal);
        CHECK(angle <= turn);
        CHECK_NEAR(d.effective_depth, s.effective_depth, sqrt(2) * w * angle + 2 * res);
        printf("  pair %d: V %.4e m^3, single %+.1e relative; normal %.1e rad apart (at most "
               "%.1e); depth %.3e m, single %.3e m\n",
               k, d.volume, s.volume / d.volume - 1, angle, turn, d.effective_depth,
               s.effective_depth);
    }
    pd_mesh_destroy(m);
}

/*
 * Particles 14 and 30 of the same single-precision run (steps 9 330 and 9 452): B rests on A, the
 * side faces of the column coplanar to 3.6e-7 m in x, two resolutions. A's bottom edges and B's
 * top edges, 16 mm from the contact, straddled the other's side planes (one end decided by its
 * coordinates, the other by the tie-breaking), and the edge-edge predicates, all ties for
 * coplanar lines, let them cross those faces there. Their cusps left the side faces' polygons
 * open on both solids alike, so the closure test passed, and the normal turned by 14 and 19
 * degrees: depths of 3.9e-3 and 4.6e-3 m for 1e-5 m, force spikes in the run. A crossing on an
 * edge that never enters the box where the kept parts meet is now dropped (ovl_crossing_outside).
 */
TEST(single_precision_normal_of_coplanar_columns)
{
    static const double poses[4][14] = {
        {0.069962963461875916, 0.097885444760322571, 0.0080510219559073448, 1,
         -7.0447640609927475e-06, 5.8579471442499198e-06, 2.7665507786878152e-06,
         0.069963537156581879, 0.097886174917221069, 0.024167638272047043, 1,
         -1.1928332241950557e-05, 6.2180529312172439e-06, 1.4578079117200105e-06},
        {0.069964177906513214, 0.097885243594646454, 0.008053894154727459, 1,
         -1.019051296680118e-06, -7.5965965606883401e-07, 4.7873204493953381e-06,
         0.069964542984962463, 0.097886018455028534, 0.0241706483066082, 1, -1.9892061118298443e-06,
         -3.2068915061245207e-06, 1.0180740446230629e-06},
        /* 42 and 58 at step 9 175, 33 and 49 at step 9 025: with such crossings kept, single
         * precision misses these contacts (double: 1.6e-6 and 1.8e-6 m deep); the two above
         * ovl_faces_close now catches without the drop, these not */
        {0.069970346987247467, 0.069975994527339935, 0.040288332849740982, 1,
         -2.5657045625848696e-05, 1.5078332580742426e-05, -2.2947178877075203e-05,
         0.069968461990356445, 0.069969631731510162, 0.056407704949378967, 1,
         -3.2638316042721272e-05, 2.1193858628976159e-05, 1.4640650078945328e-05},
        {0.04209001362323761, 0.014135869219899178, 0.040287084877490997, 1,
         -3.3645563235040754e-05, 6.059993029339239e-05, -9.3650189228355885e-05,
         0.042052499949932098, 0.014122654683887959, 0.056406408548355103, 1,
         -4.4175958464620635e-05, 7.8809833212289959e-05, -8.0068522947840393e-05},
    };
    lattice_single_within_strips(poses, 4);
}

/*
 * Two pairs of the single-precision lattice run as the cubes land (steps 5 225 and 6 320,
 * particles 24-40 and 33-49): a cube's edges, 1e-4 rad from the other's side faces and within
 * the resolution of their bottom edges, were placed on those faces by the edge-edge predicates
 * while their crossing points, from the side values, lay millimetres below the contact. The
 * normal turned by 11 and 40 degrees (depths 3.2e-3 and 1.0e-2 m for 1.6e-4 and 1.4e-6 m). Such a
 * crossing is now moved along its edge into the other triangle's box (ovl_crossing_outside).
 */
TEST(single_precision_crossings_near_parallel_faces)
{
    static const double poses[2][14] = {
        {0.014119203202426434, 0.069960258901119232, 0.024561749771237373, 1,
         2.8853954063379206e-05, -1.7950056871995912e-06, -4.1402479666885483e-08,
         0.014119208790361881, 0.069960169494152069, 0.040628481656312943, 1,
         -2.7127944690619188e-07, 1.2572736522997729e-06, -2.2463945981154865e-10},
        {0.042063523083925247, 0.014116641134023666, 0.040284503251314163, 1,
         7.8259581641759723e-05, -1.4285807083069813e-05, 0.0001331434614257887,
         0.042033709585666656, 0.014115079306066036, 0.056405831128358841, 1,
         4.7945912228897214e-05, -0.00015563367924187332, 0.00011046313011320308},
    };
    lattice_single_within_strips(poses, 2);
}

/*
 * Particles 0 and 16 at step 5 733 of the same run: B's bottom face overlaps part of A's top face,
 * edges of each within the tie band of the other's plane. Both passes' area vectors closed, but
 * the -w pass's faces did not (2.5e4 resolutions by ovl_faces_close, the +w pass's 21): it
 * summed 4.1e-10 m^3 against the +w pass's 1.3e-10 (double: 1.3e-10), both solids' side
 * polygons open alike, and the mean was twice the volume with a 16-degree normal. Passes whose
 * volumes differ by more than their tie bands allow now count as not closed, and the pair is taken
 * again on B moved (ovl_compute_try; measured: +3.5 % in volume); without that check the +w pass,
 * whose faces close, would be taken alone (ovl_compute), and the test fails only without both.
 */
TEST(single_precision_passes_that_disagree)
{
    static const double poses[1][14] = {
        {0.014118443243205547, 0.014115436933934689, 0.0080553255975246429, 1,
         5.3206069424049929e-05, -2.0654966647271067e-05, 5.6307821978407446e-06,
         0.014118730090558529, 0.01411591749638319, 0.024177690967917442, 1,
         -0.00031289900653064251, 1.9539538698154502e-05, 1.6334954580088379e-06},
    };
    lattice_single_within_strips(poses, 1);
}

/*
 * Pairs of single-precision lattice runs as the cubes land (particles 39-55 at step 5 555 of
 * examples/cube_lattice.json with a time step of 1.9e-5 s; 31-47 at step 6 383 of the example
 * itself). Both passes' area vectors closed, but the +w pass left a side face of each solid open
 * alike (2e4 and 2.4e3 resolutions by ovl_faces_close; the -w pass 3.5 and 3.7), and the mean
 * turned the normal by 11 and 7 degrees (depths 3.2e-3 and 8.4e-4 m for 3.3e-5 and 2.8e-6 m). The
 * pass whose faces close is now taken alone.
 */
TEST(single_precision_faces_open_alike)
{
    static const double poses[2][14] = {
        {0.097880780696868896, 0.042044464498758316, 0.040743011981248856, 0.99999767541885376,
         -0.0021662665531039238, 3.6373050534166396e-05, 9.0154962890665047e-06,
         0.097880780696868896, 0.042038474231958389, 0.056874871253967285, 1,
         -4.8783211241243407e-05, -2.3557771783089265e-05, -1.4684147799925995e-06},
        {0.097876362502574921, 0.097876802086830139, 0.024176018312573433, 1,
         -8.2862286944873631e-05, 7.1955430030357093e-05, 5.6131348173948936e-06,
         0.097881682217121124, 0.097883857786655426, 0.040300320833921432, 0.99999994039535522,
         -0.000330720329657197, 0.0002719756739679724, 1.4991481293691322e-05},
    };
    lattice_single_within_strips(poses, 2);
}

/*
 * Particles 40 and 56 at step 6 911 of a single-precision lattice run (examples/cube_lattice.json
 * with the region moved by 3 mm and 1 mm in x and y), resting 1.7e-6 m deep, about 7 resolutions.
 * Summed about its contact point (OVL_ORIGIN, the engine's path for a contact that lasts), no try
 * closed at the coordinates, and B moved by 8 resolutions one way left a sliver of
 * 1.8e-12 m^3 whose normal was -x, rounding noise, and whose depth along it the cube's whole
 * side: the mean of the two ways had a depth of 8.1e-3 m. Ways whose normals differ by more than
 * 0.1 rad no longer agree (ovl_compute). Checked, about the contact point (single precision's
 * own where it touches plainly, else double's): the volume within 10 resolutions over the
 * contact's area and the depth within sqrt(2) W times the normal's angle to double's plus 10
 * resolutions, the tolerances of a one-way answer (tests/physics/test_single_narrow.c); the
 * mean's depth was 1.2e-4 m over that. Since single precision asks every answer for closed
 * faces (ovl_faces_good), that sliver's way no longer agrees in any case, and this test passes
 * without the normal rule too; the rule stays, as cheap as it is. Summed plainly, every try of
 * this pair leaves faces open, and single precision no longer answers from open faces: it counts
 * as not touching yet, which a contact within 10 resolutions may (printed).
 */
TEST(single_precision_moves_that_disagree)
{
    pd_mesh *m = lattice_cube_mesh(LATTICE_SIZE);
    CHECK(m != NULL);
    if (!m) return;
    const double res = LATTICE_RES, w = 2 * LATTICE_H;
    pd_pose pa =
        pose(0.017113270238041878, 0.071007564663887024, 0.040291648358106613, 0.99999994039535522,
             -0.00013927438703831285, -2.8593171009561047e-05, -0.00034774848609231412);
    pd_pose pb = pose(0.017114743590354919, 0.070959724485874176, 0.05641121044754982, 1,
                      -9.1993628302589059e-05, -3.4402866731397808e-05, -0.00018487373017705977);
    ovl_setup su;
    pd_error err = {0};
    if (ovl_setup_make(m, &pa, m, &pb, 0, &su, &err) != PD_OK) {
        TEST_FAILF("setup: %s", err.msg);
        pd_mesh_destroy(m);
        return;
    }
    ovl_result d, s, o;
    CHECK(ovl_run_f64(&su, &d) == PD_OK && ovl_run_f32(&su, &s) == PD_OK);
    CHECK(d.hit);
    if (!s.hit) {
        printf("  plain: double %.3e m deep; single: not touching yet\n", d.depth_eff);
        CHECK(d.depth_eff <= 10 * res);
    }
    if (d.hit) {
        /* as the engine takes a contact that lasts: about its last contact point, the one
         * single precision found plainly before it asked for closed faces (A's frame) */
        static const double last[3] = {8.6205705883912742e-05, -0.0032887826673686504,
                                       0.0080596413463354111};
        su.flags = OVL_ORIGIN;
        memcpy(su.org, last, sizeof su.org);
        CHECK(ovl_run_f32(&su, &o) == PD_OK);
        CHECK(o.hit);
        for (int k = 0; k < 2 && o.hit; k++) {
            const ovl_result *r = k ? &o : &s;
            if (!r->hit) continue;
            CHECK_NEAR(d.volume, r->volume, 10 * res * LATTICE_AREA);
            double angle = angle_between(d.normal, r->normal);
            CHECK_NEAR(d.depth_eff, r->depth_eff, sqrt(2) * w * angle + 10 * res);
            printf("  %s: V %.4e m^3, single %+.1e relative; normal %.1e rad apart; depth "
                   "%.3e m, single %.3e m\n",
                   k ? "about the contact point" : "plain", d.volume, r->volume / d.volume - 1,
                   angle, d.depth_eff, r->depth_eff);
        }
    }
    ovl_setup_free(&su);
    pd_mesh_destroy(m);
}

/*
 * Two cubes of a lattice settling in single precision (particles 11 and 27 at step 5 560 of
 * examples/cube_lattice.json run with "precision": "single"), 1.0e-10 m^3 of overlap, a
 * resolution (res, 1.8e-7 m) or so deep at its thin end. Single precision's first try disagreed
 * and the retries moved B by 8 resolutions: one way alone gave 1.6e-11 m^3 (-86 %) with the
 * centroid 5 mm off, the first-order term 8 res (e . n) A of the move, as large as the overlap.
 * The mean of the two ways (ovl_out_mean) cancels that term; what is left is below one resolution
 * over the contact's area A, the tolerance here (measured: -0.13 %, 0.003 of it). Since nearly
 * parallel edges are decided by their own bound in single precision (ovl_edge_tol), this pair's
 * first try closes on its own (measured: -13 %, 0.24 of the tolerance), and the second pair, 5
 * and 21 of the same lattice settled in double precision (frame 20), is the one whose first try
 * disagrees and whose retries agree both ways (measured: +0.6 %).
 */
TEST(retries_move_the_resting_cube_both_ways)
{
    static const double poses[2][14] = {
        {0.097880959510803223, 0.069960452616214752, 0.0080686742439866066, 1,
         4.778124548465712e-06, -4.6380200728890486e-06, 3.2073566025303535e-09,
         0.097880475223064423, 0.069959953427314758, 0.024188285693526268, 1,
         -3.9042839489411563e-05, 3.7812613300047815e-05, -6.2132299305517336e-09},
        {0.042198383962681989, 0.042207461005295759, 0.0080576695438508324, 0.99999999084792568,
         -0.00012065637051536563, 4.830590304478111e-05, -3.7586283568415388e-05,
         0.041955843480750148, 0.041959117255004952, 0.024174735271054047, 0.99999978241666754,
         -0.00024569563495456596, 8.916303962740795e-05, -0.00060568162023952158},
    };
    lattice_single_matches_double(poses, 2, 1e-10, 1);
}

int main(void)
{
    RUN(offset_cubes_are_a_box);
    RUN(rotated_cube_corner_into_face);
    RUN(tetrahedra_along_a_vertex_direction);
    RUN(cube_pressed_into_slab);
    RUN(touching_without_overlap_is_zero);
    RUN(vertex_exactly_on_face);
    RUN(identical_coincident_shapes);
    RUN(contained_solid_takes_the_centre_line);
    RUN(small_solid_inside_a_large_one);
    RUN(edge_on_edge_crossing);
    RUN(near_degenerate_poses_from_rounding);
    RUN(swap_gives_same_volume_and_opposite_normal);
    RUN(invariant_under_common_rigid_motion_even_1e3_m_away);
    RUN(filter_on_and_off_agree);
    RUN(stacked_cubes_with_coplanar_sides);
    RUN(cube_sides_across_the_tie_band);
    RUN(boxes_within_the_tie_band_on_several_axes);
    RUN(stacked_cubes_turned_by_rounding);
    RUN(sorted_casts_and_sweep_agree_with_the_unfiltered_overlap);
    RUN(schonhardt_pairs_match_tetrahedral_reference);
    RUN(rock_pairs_match_tetrahedral_reference);
    RUN(rock_against_closed_wall_mesh);
    RUN(icosphere_overlap_converges_to_spherical_caps);
    RUN(single_precision_close_to_double);
    RUN(single_precision_close_to_double_on_fine_meshes);
    RUN(corner_into_face_at_small_depths);
    RUN(first_origin_leaves_the_overlap_unchanged);
    RUN(separate_places_of_a_u_on_a_tilted_slab);
    RUN(places_agree_when_the_solids_swap);
    RUN(places_unknown_beyond_the_node_scratch);
    RUN(opencl_kernel_agrees_with_host);
    RUN(programs_ask_for_correctly_rounded_single_precision);
    RUN(bad_pose_is_an_error_not_a_nan);
    /* last: they draw from the shared random sequence, and the tests above keep their samples */
    RUN(vertex_clusters_bound_their_vertices);
    RUN(clustered_filter_keeps_what_every_vertex_keeps);
    RUN(resting_cubes_in_single_precision);
    RUN(single_precision_finds_shifted_column_contacts);
    RUN(single_precision_depth_of_a_grazing_crossing);
    RUN(retries_move_the_resting_cube_both_ways);
    RUN(single_precision_normal_of_coplanar_columns);
    RUN(single_precision_crossings_near_parallel_faces);
    RUN(single_precision_passes_that_disagree);
    RUN(single_precision_faces_open_alike);
    RUN(single_precision_moves_that_disagree);
    /* last: its draws from rnd() leave the other tests' poses as they were */
    RUN(degenerate_non_convex_poses_are_limits_of_generic_ones);
    return TEST_DONE();
}
