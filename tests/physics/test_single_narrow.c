/*
 * test_single_narrow.c - the engine's narrow phase in single precision, on the host, for pairs of
 * 2 cm cubes taken from single-precision runs of examples/cube_lattice.json and variants of it.
 *
 * Each pair is set up as kernels/contact.cl sets it up: np_setup from the particles' poses as
 * the device held them (single precision), and, where the pair touched in the last step, the
 * cusps summed about that step's contact point (OVL_ORIGIN). This reproduces the engine's
 * /stats/max_overlap_ratio of those runs to every printed digit (bench/RESULTS.md, 2026-12-07,
 * night), where the host path of pd_overlap_host --single, which maps B in double precision, does
 * not. Each answer is checked against the double-precision overlap of the same poses.
 *
 * Tolerances, for pairs whose side faces lie within single precision's tie band of each other:
 * - volume: 10 resolutions over the contact's area. 2 are the tie band's (the faces' offsets
 *   are decided symbolically to within it); up to 8 more where the answer comes from B moved one
 *   way by 8 resolutions (ovl_compute), whose first-order term is (u . n) A;
 * - normal: within what side strips inside the tie band can turn it, 2 W h^2 / V (W the side, h
 *   double's depth), and at least 1e-3, as in tests/physics/test_overlap.c;
 * - effective depth (the force law's): sqrt(2) W times the angle the normal actually turned,
 *   plus the same 10 resolutions;
 * - the force's point (effective point) within the cube's side of double's, on the contact's face;
 * - a miss only where double's contact is within 10 resolutions deep: ovl_compute counts a pair
 *   whose every try leaves its faces open, and which moving B by 8 resolutions does not settle,
 *   as not touching yet.
 * The answers these pairs had before were 34 to 47 000 times double's depth, or a centroid 12 m
 * away; each test fails with its change to kernels/overlap.h taken out.
 */
#define PD_DOUBLE 0
#include <stdlib.h>
#include <string.h>

#include "narrow_phase.h"
#include "overlap_run.h"
#include "polydem.h"
#include "lattice_cube.h"
#include "test.h"

/* One pair as a run left it: A's x y z qw qx qy qz, then B's (single-precision values), whether
 * it touched in the last step, and there its contact point (world, m). */
typedef struct lattice_case {
    const char *what;
    double pose[14];
    int touched;
    double last[3];
} lattice_case;

static np_body body(const double *p)
{
    np_body b;
    b.x = v3((float)p[0], (float)p[1], (float)p[2]);
    for (int k = 0; k < 4; k++)
        b.q[k] = (float)p[3 + k];
    b.size = (float)LATTICE_SIZE;
    b.shape = 0;
    return b;
}

/* The engine's single-precision overlap of case c (world coordinates) into *o; 0 on no memory. */
static int engine_single(const pd_mesh *unit, const int *vt_off, const int *vt,
                         const lattice_case *c, ovl_out *o)
{
    float vert[24];
    for (int i = 0; i < 24; i++)
        vert[i] = (float)unit->verts[i];
    int voff[2] = {0, 8}, toff[2] = {0, 12};
    np_shapes sh = {vert, lattice_cube_tris, voff, toff, vt_off, vt, NULL, NULL, NULL};
    np_body a = body(c->pose), b = body(c->pose + 7);
    ovl_in in;
    float ra[9];
    np_setup(&sh, &a, &b, 0, &in, ra);
    if (c->touched) {
        in.flags |= OVL_ORIGIN;
        in.org = np_to_body(&a, ra, v3((float)c->last[0], (float)c->last[1], (float)c->last[2]));
    }
    int cap = ovl_pts_cap(12, 12);
    int ilen = ovl_iscratch_len(12, 12, 8, 8) + ovl_places_ilen(cap);
    int rlen = ovl_rscratch_len(12, 12, 8, 8, cap) + ovl_places_rlen(cap);
    in.iscr = malloc(sizeof(int) * (size_t)ilen);
    in.rscr = malloc(sizeof(float) * (size_t)rlen);
    in.pts_cap = cap;
    int ok = in.iscr && in.rscr;
    if (ok) {
        ovl_compute(&in, o);
        np_to_world(&a, ra, o);
    }
    free(in.iscr);
    free(in.rscr);
    return ok;
}

/* Checks the cases against double precision with the tolerances of the file's comment. */
static void check_cases(const lattice_case *cs, int n)
{
    pd_mesh *unit = lattice_cube_mesh(1), *m = lattice_cube_mesh(LATTICE_SIZE);
    int *vt_off = NULL, *vt = NULL;
    CHECK(unit && m && ovl_vertex_triangles(unit, &vt_off, &vt) == PD_OK);
    const double w = 2 * LATTICE_H;
    for (int k = 0; k < n && vt; k++) {
        const lattice_case *c = &cs[k];
        pd_pose pa = {{c->pose[0], c->pose[1], c->pose[2]},
                      {c->pose[3], c->pose[4], c->pose[5], c->pose[6]}};
        pd_pose pb = {{c->pose[7], c->pose[8], c->pose[9]},
                      {c->pose[10], c->pose[11], c->pose[12], c->pose[13]}};
        pd_contact d;
        pd_error err = {0};
        CHECK(pd_overlap_host(m, &pa, m, &pb, 0, &d, &err) == PD_OK);
        CHECK(d.hit);
        ovl_out s;
        CHECK(engine_single(unit, vt_off, vt, c, &s));
        if (!d.hit) continue;
        if (!s.hit) {
            printf("  %s: double %.3e m deep; single: not touching yet\n", c->what,
                   d.effective_depth);
            CHECK(d.effective_depth <= 10 * LATTICE_RES);
            continue;
        }
        double sn[3] = {s.normal.x, s.normal.y, s.normal.z};
        double angle = angle_between(d.normal, sn);
        double turn = fmax(1e-3, 2 * w * d.depth * d.depth / d.volume);
        printf("  %s: double V %.3e m^3, depth %.3e m; single %+.1e relative, normal %.1e rad "
               "apart (at most %.1e), depth %.3e m\n",
               c->what, d.volume, d.effective_depth, s.vol_eff / d.volume - 1, angle, turn,
               (double)s.depth_eff);
        double dp = 0;
        for (int q = 0; q < 3; q++) {
            double e = d.effective_point[q] - (q == 0   ? (double)s.point_eff.x
                                               : q == 1 ? (double)s.point_eff.y
                                                        : (double)s.point_eff.z);
            dp += e * e;
        }
        CHECK_NEAR(d.volume, (double)s.vol_eff, 10 * LATTICE_RES * LATTICE_AREA);
        /* a solid of positive volume has a positive extent along any normal: a touching answer
         * of depth 0 is no force at all (cp_pair) */
        CHECK(s.depth_eff > 0);
        CHECK(sqrt(dp) <= w); /* within the contact's face */
        CHECK(angle <= turn);
        CHECK_NEAR(d.effective_depth, (double)s.depth_eff, sqrt(2) * w * angle + 10 * LATTICE_RES);
    }
    free(vt_off);
    free(vt);
    pd_mesh_destroy(unit);
    pd_mesh_destroy(m);
}

/*
 * Cube 47 standing on 31 as the lattice lands (time step 1.9e-5 s, steps 6 738 and 6 749).
 * - 6 738: the first try's passes did not close; the first direction that agreed both ways had
 *   a way whose -w pass left faces open, its normal 0.023 rad off, and the mean's 0.0083: a depth
 *   of 1.9e-4 m for 5.5e-6 m. A way whose faces do not close no longer agrees.
 * - 6 749: the first try closed, but both passes left faces open: the normal 0.18 rad off, a
 *   depth of 3.0e-3 m for 1.9e-6 m. Such a try is no longer taken.
 */
TEST(faces_open_in_the_moves)
{
    static const lattice_case cs[] = {
        {"6 738",
         {0.0978444442, 0.0978705212, 0.0241750367, 0.999999046, -0.000153054934, -0.00037274629,
          0.00136461272, 0.0978364795, 0.0976697579, 0.0402940661, 0.999999166, -0.000309712894,
          -0.000288296636, 0.00127766037},
         1,
         {0.0998127088, 0.101670198, 0.0322340615}},
        {"6 749",
         {0.0978429988, 0.0978732482, 0.0241742004, 0.999999046, -0.000257240608, -0.00037068766,
          0.00136816269, 0.0978342369, 0.0976749584, 0.0402948, 0.999999106, -0.00035728683,
          -0.000318109494, 0.00127428479},
         0,
         {0, 0, 0}},
    };
    check_cases(cs, 2);
}

/*
 * Pass taken alone, and a one-way answer, with faces open: the sums closed, but the faces of every
 * pass did not, and the normal was 0.038 to 0.30 rad off.
 * - Cubes 2 and 18, time step 1.8e-5 s, step 6 470: no move closed, and the first try's +w pass
 *   alone was taken: normal 0.096 rad off, depth 1.5e-3 m for 1.8e-6 m.
 * - Cubes 31 and 47, region moved by (-2, 3) mm, step 6 382: one way of one direction closed,
 *   with its faces open: normal 0.30 rad off, depth 4.9e-3 m for 1.3e-6 m.
 * - Cubes 3 and 19 of the same run, step 6 603: a first try whose sums closed and whose faces did
 *   not: normal 0.038 rad off, depth 6.1e-4 m for 7.0e-7 m.
 * Single precision no longer answers from open faces.
 */
TEST(faces_open_in_the_fallbacks)
{
    static const lattice_case cs[] = {
        {"2-18",
         {0.0699583888, 0.0141208209, 0.00805336889, 1, 6.58340505e-05, 5.78549661e-05,
          -3.10972937e-05, 0.0699612424, 0.0141190831, 0.0241727177, 1, 8.24664749e-05,
          9.52943228e-05, 2.47483658e-05},
         1,
         {0.0715455934, 0.0133822393, 0.0161124021}},
        {"31-47",
         {0.0958822072, 0.100874923, 0.0241726432, 1, 1.12910593e-05, 5.04968511e-06,
          -1.25599108e-05, 0.0958821476, 0.100878783, 0.0402921624, 1, 5.6306093e-05,
          1.23590792e-06, 2.57287365e-06},
         1,
         {0.0956175029, 0.0963497087, 0.0322321467}},
        {"3-19",
         {0.0958821923, 0.017119538, 0.00805034209, 1, 6.1534447e-06, 9.81465109e-06,
          2.35958996e-05, 0.0958809182, 0.0171179902, 0.0241703, 1, 2.35826865e-05, -1.76006888e-05,
          -2.60102443e-05},
         1,
         {0.0899117291, 0.0123269707, 0.0161101483}},
    };
    check_cases(cs, 3);
}

/*
 * Cubes 29 and 45 (time step 1.9e-5 s, step 6 108): the first try did not close, and no direction
 * closed both ways; the first try's +w pass, taken alone, left faces open: normal 0.13 rad off,
 * depth 2.1e-3 m for 1.1e-5 m. One way of a direction closed with every face closing, and is now
 * taken first (its volume carries the move's first-order term).
 */
TEST(one_way_with_faces_closed)
{
    static const lattice_case cs[] = {
        {"29-45",
         {0.0420287438, 0.0978614539, 0.0241869763, 0.999998987, 0.000744769583, 0.000661228725,
          0.00111579837, 0.0420537964, 0.0976419598, 0.0403057747, 0.999998569, 0.00104175182,
          0.000974256371, 0.000967906555},
         1,
         {0.0472059771, 0.0942033976, 0.0322542787}},
    };
    check_cases(cs, 1);
}

/*
 * Passes taken alone that summed a sliver: cubes 28 and 44 at step 18 993 (friction 0.4) and 44 and
 * 60 at step 7 557 (region moved by (1, 4) mm). The +w pass alone summed 6.8e-16 and 1.1e-16 m^3
 * (double: 7.3e-11 and 1.9e-11) over cusps of 1.2e-12 and 3.5e-13 m^2 in all, with a normal of
 * +x: the depth along it was the cube's whole side, 1.6e-2 m. A volume beyond what its cusps'
 * area can enclose (the isoperimetric inequality, ovl_compute_try) is no longer taken.
 */
TEST(volume_beyond_its_surface)
{
    static const lattice_case cs[] = {
        {"28-44",
         {0.014146708, 0.097818099, 0.0241699647, 0.999999583, 2.99736378e-08, 7.05813864e-06,
          -0.000924116757, 0.0141460849, 0.0978725851, 0.0402896032, 0.999999523, 3.7566798e-07,
          8.6457112e-06, -0.00102783588},
         1,
         {0.0180515908, 0.0978152454, 0.0322298259}},
        {"44-60",
         {0.0151316086, 0.101863697, 0.0402865112, 0.99999994, 7.73999345e-05, 3.22244632e-05,
          -0.000318303792, 0.0151327457, 0.101848617, 0.0564063862, 1, 6.78435899e-05,
          4.11322326e-05, -0.000252311176},
         0,
         {0, 0, 0}},
    };
    check_cases(cs, 2);
}

/*
 * Cubes 9 and 25 at step 11 240 of the example: a first try that closed, both passes' faces too,
 * summed 5.6e-15 m^3 for a contact 3.1e-7 m deep (double: 1.4e-11), and its centroid came out 12 m
 * away; the torque about it spun the two cubes apart (kinetic energy 1e-6 -> 4e-3 J). A centroid
 * outside the nodes' box by more than its rounding (ovl_compute_try) is no longer taken.
 */
TEST(centroid_beyond_its_nodes)
{
    static const lattice_case cs[] = {
        {"9-25",
         {0.0420541726, 0.0699589476, 0.00805163104, 1, 5.67998723e-05, 7.85463999e-06,
          -0.00013612445, 0.0420513786, 0.0699635223, 0.0241715498, 1, 6.90498418e-05,
          1.20508785e-05, -0.000271262805},
         0,
         {0, 0, 0}},
    };
    check_cases(cs, 1);
}

/*
 * Cubes 13 and 29 at step 11 029 of the example, resting in a column: faces 8.7e-7 m (3.8
 * resolutions) apart, within the tie band, so the pair is degenerate. The +w pass's ties put B's
 * face just off A's, and it found no node; the -w pass summed the slab. The pair's volume is
 * their mean (half of double's, within the tie band's 2 resolutions over the contact's area),
 * but the depth came from the +w pass's nodes alone: 0, and the contact gave no force. The -w
 * pass's nodes are now kept where the +w pass has none (ovl_sum): depth 8.717e-7 m against
 * double's 8.709e-7. Found replaying steps 11 000-11 400 (bench/replay) of the example run in
 * single precision: 5 of the 20 resting contacts the replay lost were this kind.
 */
TEST(nodes_of_the_pass_that_found_the_overlap)
{
    static const lattice_case cs[] = {
        {"13-29",
         {0.0420353673, 0.0978818536, 0.00805195794, 1, -8.84536036e-08, 5.29215595e-06,
          -2.19725371e-05, 0.0420421585, 0.0978845209, 0.0241715871, 1, 9.82110535e-08,
          6.6394482e-06, 1.38055384e-05},
         1,
         {0.0421825349, 0.0978630111, 0.0161119513}},
    };
    check_cases(cs, 1);
    /* and nearer than check_cases asks: the slab's thickness, to a resolution */
    pd_mesh *unit = lattice_cube_mesh(1);
    int *vt_off = NULL, *vt = NULL;
    CHECK(unit && ovl_vertex_triangles(unit, &vt_off, &vt) == PD_OK);
    ovl_out s;
    int ran = vt && engine_single(unit, vt_off, vt, &cs[0], &s);
    CHECK(ran);
    if (ran) {
        CHECK(s.hit);
        CHECK_NEAR((double)s.depth_eff, 8.709e-7, LATTICE_RES);
    }
    free(vt_off);
    free(vt);
    pd_mesh_destroy(unit);
}

int main(void)
{
    RUN(faces_open_in_the_moves);
    RUN(faces_open_in_the_fallbacks);
    RUN(one_way_with_faces_closed);
    RUN(volume_beyond_its_surface);
    RUN(centroid_beyond_its_nodes);
    RUN(nodes_of_the_pass_that_found_the_overlap);
    return TEST_DONE();
}
