/*
 * test_sim.c - the whole device pipeline (engine/sim*.c) against analytic solutions: each test
 * builds a small scenario, steps it on the first OpenCL device (PoCL in CI) and compares with
 * theory. Tolerances are stated where they are used, with where they come from.
 */
#include <hdf5.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#define PD_DOUBLE 1
#include "contact_history.h" /* CH_WALL */
#include "integrate.h"       /* the kinetic energy, as rows summed it on the host */
#include "sim.h"
#include "grid_box.h"
#define TEST_RANDOM_SEED 20261202
#include "test_random.h"
#include "test.h"
#include "u_shape.h"

static pd_device *dev;
static const double PI = 3.14159265358979323846;

typedef struct run {
    pd_scenario *s;
    sim *m;
} run;

static int start(run *r, const char *json)
{
    pd_diags d = {0, 0, NULL};
    pd_error err = {0};
    memset(r, 0, sizeof *r);
    if (pd_scenario_parse(json, NULL, &r->s, &d, &err) != PD_OK) {
        TEST_FAILF("scenario: %s (%s)", d.n ? d.items[0].msg : err.msg, d.n ? d.items[0].path : "");
        pd_diags_free(&d);
        return -1;
    }
    pd_diags_free(&d);
    if (sim_create(dev, r->s, &r->m, &err) != PD_OK || sim_forces(r->m, &err) != PD_OK) {
        TEST_FAILF("sim: %s", err.msg);
        return -1;
    }
    return 0;
}

static void finish(run *r)
{
    sim_destroy(r->m);
    pd_scenario_destroy(r->s);
}

static int step(run *r)
{
    pd_error err = {0};
    int bad = -1;
    if (sim_step(r->m, &bad, &err) != PD_OK || bad >= 0) {
        TEST_FAILF("step %lld: %s (bad particle %d)", r->m->step, err.msg, bad);
        return -1;
    }
    return 0;
}

static void get(run *r, cl_mem b, size_t n, double *out)
{
    pd_error err = {0};
    if (sim_read(r->m, b, 0, n, out, &err) != PD_OK) TEST_FAILF("read: %s", err.msg);
}

static void get_info(run *r, size_t n, double *out)
{
    pd_error err = {0};
    if (sim_read_info(r->m, n, out, &err) != PD_OK) TEST_FAILF("read: %s", err.msg);
}

/* Seed 004 section 5.3.3: the device self-test passes (overlap kernel vs host; Hertz collision
 * vs theory, see engine/selftest.c for its tolerances). */
TEST(device_selftest)
{
    char rep[600];
    pd_error err = {0};
    int rc = pd_device_selftest(dev, rep, sizeof rep, &err);
    printf("  %s\n", rep);
    CHECK_EQ_INT(PD_OK, rc);
}

/*
 * Two spheres, linear spring-dashpot (seed 004 eq. 2.1): contact duration t_col = pi / b (A.2)
 * and restitution e = exp(a pi / b) (A.3), with the reduced mass (eq. 2.12) in a and b.
 * dt = t_col / 1000: the duration is resolved to 2 steps (0.2%), e to well under 0.5%.
 */
TEST(linear_restitution_and_duration)
{
    const double R = 0.01, rho = 2500, k = 1e4, e_want = 0.5, v = 0.1;
    double m = rho * 4.0 / 3 * PI * R * R * R, ms = m / 2;
    double le = log(e_want), eta = -2 * le * sqrt(ms * k / (PI * PI + le * le));
    double a = -eta / (2 * ms), b = sqrt(4 * ms * k - eta * eta) / (2 * ms);
    double tcol = PI / b, dt = tcol / 1000;
    char json[1500];
    snprintf(
        json, sizeof json,
        "{\"name\": \"linear\", \"allow_unstable_dt\": true,"
        " \"time\": {\"dt\": %.17g, \"duration\": 1, \"output_interval\": 1},"
        " \"gravity\": [0, 0, 0],"
        " \"materials\": {\"m\": {\"density\": %g, \"youngs_modulus\": 1e7, \"poisson_ratio\": "
        "0.25}},"
        " \"interactions\": [{\"between\": [\"m\", \"m\"], \"model\": \"linear\", "
        "\"normal_stiffness\": %g, \"damping_coefficient\": %.17g, \"friction\": 0}],"
        " \"shapes\": {\"ball\": {\"sphere\": {}}},"
        " \"particles\": [{\"shape\": \"ball\", \"material\": \"m\", \"list\": ["
        " {\"position\": [0, 0, 0], \"velocity\": [%g, 0, 0], \"size\": %g},"
        " {\"position\": [%.17g, 0, 0], \"velocity\": [%g, 0, 0], \"size\": %g}]}]}",
        dt, rho, k, eta, v, 2 * R, 2 * R + 20 * v * dt, -v, 2 * R);
    run r;
    if (start(&r, json)) return;
    int touching = 0;
    double x[6], vel[6];
    for (int i = 0; i < 3000; i++) {
        if (step(&r)) break;
        get(&r, r.m->x, 6, x);
        if (x[3] - x[0] < 2 * R) touching++;
    }
    get(&r, r.m->v, 6, vel);
    double e_got = (vel[3] - vel[0]) / (2 * v);
    printf("  t_col %.6g s (theory %.6g s), e %.6f (theory %.6f, A.3 %.6f)\n", touching * dt, tcol,
           e_got, e_want, exp(a * PI / b));
    CHECK_NEAR(tcol, touching * dt, 2.5 * dt);
    CHECK_NEAR(exp(a * PI / b), e_got, 5e-3 * e_want);
    finish(&r);
}

/* Seed 004 section 4.3: a sphere settles on a floor (linear model, damped) at the static
 * overlap m g / k_e. After 40 contact times at e = 0.3 the oscillation has decayed by
 * 0.3^40 (far below the 1e-6 checked). Returns the overlap's error relative to theory. */
static double sphere_settle(const char *floor_json, double x0, double y0)
{
    const double R = 0.01, rho = 2500, k = 1e4, g = 9.81;
    double m = rho * 4.0 / 3 * PI * R * R * R, le = log(0.3);
    double eta = -2 * le * sqrt(m * k / (PI * PI + le * le));
    double tcol = PI / sqrt(k / m), dt = tcol / 100;
    char json[1800];
    snprintf(json, sizeof json,
             "{\"name\": \"settle\", \"allow_unstable_dt\": true,"
             " \"time\": {\"dt\": %.17g, \"duration\": 1, \"output_interval\": 1},"
             " \"gravity\": [0, 0, %g],"
             " \"materials\": {\"m\": {\"density\": %g, \"youngs_modulus\": 1e7, "
             "\"poisson_ratio\": 0.25}},"
             " \"interactions\": [{\"between\": [\"m\", \"m\"], \"model\": \"linear\", "
             "\"normal_stiffness\": %g, \"damping_coefficient\": %.17g, \"friction\": 0.3}],"
             " \"shapes\": {\"ball\": {\"sphere\": {}}},"
             " \"particles\": [{\"shape\": \"ball\", \"material\": \"m\", \"list\": ["
             " {\"position\": [%.17g, %.17g, %g], \"size\": %g}]}],"
             " \"walls\": [{\"name\": \"floor\", \"material\": \"m\", %s}]}",
             dt, -g, rho, k, eta, x0, y0, R * 1.01, 2 * R, floor_json);
    run r;
    if (start(&r, json)) return NAN;
    for (int i = 0; i < 4000; i++)
        if (step(&r)) break;
    double x[3];
    get(&r, r.m->x, 3, x);
    double delta = R - x[2], want = m * g / k;
    printf("  floor of %d triangles, at (%g, %g): static overlap %.9g m (theory m g / k_e = %.9g "
           "m), drift %.2g m\n",
           r.s->wall[0].mesh->ntris, x0, y0, delta, want, hypot(x[0] - x0, x[1] - y0));
    finish(&r);
    return fabs(delta - want) / want;
}

TEST(sphere_settles_on_floor)
{
    double e = sphere_settle("\"box\": {\"min\": [-1, -1, -0.1], \"max\": [1, 1, 0]}", 0, 0);
    CHECK(e < 1e-6);
}

/* Issue 3, thesis section 5.6: the same on a floor meshed as a slab of 40 x 40 grids (19 200
 * triangles, 5 mm squares under a 20 mm sphere), resting on a vertex shared by six triangles,
 * on an edge, and inside a triangle: the closest point comes from the wall's triangles near the
 * sphere (its BVH), inside or out from a ray through the tree. */
TEST(sphere_settles_on_a_finely_meshed_floor)
{
    char path[64], floor_json[160];
    snprintf(path, sizeof path, "/tmp/polydem-test-floor-%d.obj", (int)getpid());
    double c[3] = {0, 0, -0.05}, h[3] = {0.1, 0.1, 0.05};
    if (grid_box_obj(path, c, h, 40)) {
        TEST_FAILF("cannot write %s", path);
        return;
    }
    snprintf(floor_json, sizeof floor_json, "\"mesh\": \"%s\"", path);
    CHECK(sphere_settle(floor_json, 0, 0) < 1e-6);      /* a grid vertex */
    CHECK(sphere_settle(floor_json, 0.0025, 0) < 1e-6); /* an edge */
    CHECK(sphere_settle(floor_json, 0.0031, 0.0012) < 1e-6);
    remove(path);
}

/*
 * A sphere on a floor under gravity tilted by theta (an incline), from rest (seed 004's sliding
 * and rolling kinematics; any mechanics text): with mu >= (2/7) tan theta it rolls without
 * slipping, its centre accelerating at a = (5/7) g sin theta, with omega = v / R; below that it
 * slides at a = g (sin theta - mu cos theta) while friction spins it up at 5 mu g cos theta / (2
 * R). This exercises the tangential spring with rotation: the contact point's velocity v + omega x
 * r and the friction torque. The accelerations are fitted between t = 0.05 s and 0.2 s, once the
 * start's normal and tangential oscillations (periods ~9 ms at the resting overlap, damping 0.5)
 * have died down; 1 % is a few times what their remainder and the spring's elastic stick
 * displacement (~1e-6 m against 0.05 m travelled) could leave.
 */
static void sphere_on_incline(double mu, double *a_out, double *alpha_out, double *slip_out)
{
    const double theta = 15 * PI / 180, g = 9.81, R = 0.01, dt = 5e-6, E = 1e7, nu = 0.25;
    const double rho = 2600, m = rho * 4.0 / 3 * PI * R * R * R;
    /* start at the resting overlap of Hertz: m g cos theta = 4/3 E* sqrt(R) delta^(3/2) */
    double es = E / (2 * (1 - nu * nu));
    double delta = pow(m * g * cos(theta) / (4.0 / 3 * es * sqrt(R)), 2.0 / 3);
    char json[1500];
    snprintf(
        json, sizeof json,
        "{\"name\": \"incline\", \"allow_unstable_dt\": true,"
        " \"time\": {\"dt\": %g, \"duration\": 1, \"output_interval\": 1},"
        " \"gravity\": [%.17g, 0, %.17g],"
        " \"materials\": {\"m\": {\"density\": %g, \"youngs_modulus\": %g, \"poisson_ratio\": "
        "%g}},"
        " \"interactions\": [{\"between\": [\"m\", \"m\"], \"friction\": %g, \"damping\": 0.5}],"
        " \"shapes\": {\"b\": {\"sphere\": {}}},"
        " \"particles\": [{\"shape\": \"b\", \"material\": \"m\", \"list\": ["
        " {\"position\": [0, 0, %.17g], \"size\": %g}]}],"
        " \"walls\": [{\"name\": \"floor\", \"material\": \"m\", \"box\": {\"min\": [-1, -1, "
        "-0.1], \"max\": [1, 1, 0]}}]}",
        dt, g * sin(theta), -g * cos(theta), rho, E, nu, mu, R - delta, 2 * R);
    run r;
    *a_out = *alpha_out = *slip_out = NAN;
    if (start(&r, json)) return;
    double I = r.m->p->inertia[0], v[2][3], L[2][3];
    int i1 = (int)(0.05 / dt), i2 = (int)(0.2 / dt);
    for (int i = 1; i <= i2; i++) {
        if (step(&r)) break;
        if (i == i1 || i == i2) {
            get(&r, r.m->v, 3, v[i == i2]);
            get(&r, r.m->L, 3, L[i == i2]);
        }
    }
    double t = (i2 - i1) * dt;
    *a_out = (v[1][0] - v[0][0]) / t;
    *alpha_out = (L[1][1] - L[0][1]) / I / t;
    /* slip velocity of the contact point at the end: v - R omega_y */
    *slip_out = v[1][0] - R * L[1][1] / I;
    printf("  mu %g: a = %.6g m/s^2, angular acceleration %.6g rad/s^2, slip at 0.2 s %.3g m/s "
           "(v %.4g m/s)\n",
           mu, *a_out, *alpha_out, *slip_out, v[1][0]);
    finish(&r);
}

TEST(sphere_rolls_or_slides_down_an_incline)
{
    const double theta = 15 * PI / 180, g = 9.81, R = 0.01;
    double a, alpha, slip;
    /* rolling: mu = 0.3 > (2/7) tan 15 deg = 0.077 */
    sphere_on_incline(0.3, &a, &alpha, &slip);
    double want = 5.0 / 7 * g * sin(theta);
    CHECK_REL(want, a, 0.01);
    CHECK_REL(want / R, alpha, 0.01);
    CHECK(fabs(slip) < 0.01 * a * 0.2); /* rolls: no slip beyond 1 % of its speed */
    /* sliding: mu = 0.05 < 0.077 */
    double mu = 0.05;
    sphere_on_incline(mu, &a, &alpha, &slip);
    CHECK_REL(g * (sin(theta) - mu * cos(theta)), a, 0.01);
    CHECK_REL(5 * mu * g * cos(theta) / (2 * R), alpha, 0.01);
    CHECK(slip > 0.1 * a * 0.2); /* still sliding */
}

/* Cube side for a volume-equivalent diameter d: s^3 = pi d^3 / 6. */
static double cube_side(double d)
{
    return cbrt(PI / 6) * d;
}

/* A 0.02 m cube at `at` (m) sliding along x at vx on a floor: `floor` is the wall's JSON after its
 * name and material (NULL: a 2 x 2 x 0.1 m box under z = 0). */
static void cube_json(char *json, size_t len, double dt, const double at[3], double vx, double mu,
                      double damping, const char *floor)
{
    if (!floor) floor = "\"box\": {\"min\": [-1, -1, -0.1], \"max\": [1, 1, 0]}";
    snprintf(json, len,
             "{\"name\": \"cube\", \"allow_unstable_dt\": true,"
             " \"time\": {\"dt\": %.17g, \"duration\": 1, \"output_interval\": 1},"
             " \"gravity\": [0, 0, -9.81],"
             " \"materials\": {\"m\": {\"density\": 2600, \"youngs_modulus\": 1e7, "
             "\"poisson_ratio\": 0.25}},"
             " \"interactions\": [{\"between\": [\"m\", \"m\"], \"friction\": %g, \"damping\": "
             "%g}],"
             " \"shapes\": {\"c\": {\"builtin\": \"cube\"}},"
             " \"particles\": [{\"shape\": \"c\", \"material\": \"m\", \"list\": ["
             " {\"position\": [%.17g, %.17g, %.17g], \"velocity\": [%g, 0, 0], \"size\": "
             "0.02}]}],"
             " \"walls\": [{\"name\": \"floor\", \"material\": \"m\", %s}]}",
             dt, mu, damping, at[0], at[1], at[2], vx, floor);
}

/* Equilibrium depth of a cube of side s (density rho) resting flat: m g = 4/(3 sqrt(pi)) E*
 * sqrt(V delta) with V = s^2 delta (eq. 4.16 at rest) gives delta = 3 sqrt(pi) m g / (4 E* s). */
static double cube_rest_depth(double s, double rho, double estar)
{
    double m = rho * s * s * s;
    return 3 * sqrt(PI) * m * 9.81 / (4 * estar * s);
}

/*
 * A cube resting flat on an incline of 15 degrees (gravity tilted), from rest at its resting
 * depth: with mu = 0.35 > tan 15 deg = 0.268 static friction holds it, the tangential spring
 * taking m g sin theta with a stick displacement F / k_t of micrometres (k_t ~ 2/3 of k_n =
 * 2 E* s here); with mu = 0.2 it slides at a = g (sin theta - mu cos theta), fitted between
 * 0.05 s and 0.15 s once the start's oscillations (period ~1.4 ms, damping 0.5) have died: 1 %.
 * The face lies flat on the floor, the coplanar case of the overlap (issue 2) under a
 * tangential load.
 */
static void cube_on_incline(double mu, double *creep, double *a_out)
{
    const double theta = 15 * PI / 180, g = 9.81;
    double s = cube_side(0.02), estar = 1e7 / (2 * (1 - 0.25 * 0.25));
    double m = 2600 * s * s * s, kn = 2 * estar * s, dt = 2 * PI * sqrt(m / kn) / 50;
    /* resting depth under the normal component of gravity (cube_rest_depth at g cos theta) */
    double rest = cube_rest_depth(s, 2600, estar) * cos(theta);
    char json[1500];
    snprintf(
        json, sizeof json,
        "{\"name\": \"incline\", \"allow_unstable_dt\": true,"
        " \"time\": {\"dt\": %.17g, \"duration\": 1, \"output_interval\": 1},"
        " \"gravity\": [%.17g, 0, %.17g],"
        " \"materials\": {\"m\": {\"density\": 2600, \"youngs_modulus\": 1e7, "
        "\"poisson_ratio\": 0.25}},"
        " \"interactions\": [{\"between\": [\"m\", \"m\"], \"friction\": %g, \"damping\": 0.5}],"
        " \"shapes\": {\"c\": {\"builtin\": \"cube\"}},"
        " \"particles\": [{\"shape\": \"c\", \"material\": \"m\", \"list\": ["
        " {\"position\": [0, 0, %.17g], \"size\": 0.02}]}],"
        " \"walls\": [{\"name\": \"floor\", \"material\": \"m\", \"box\": {\"min\": [-1, -1, "
        "-0.1], \"max\": [1, 1, 0]}}]}",
        dt, g * sin(theta), -g * cos(theta), mu, 0.5 * s - rest);
    run r;
    *creep = *a_out = NAN;
    if (start(&r, json)) return;
    int i1 = (int)(0.05 / dt), i2 = (int)(0.15 / dt);
    double x[2][3], v[2][3];
    for (int i = 1; i <= i2; i++) {
        if (step(&r)) break;
        if (i == i1 || i == i2) {
            get(&r, r.m->x, 3, x[i == i2]);
            get(&r, r.m->v, 3, v[i == i2]);
        }
    }
    *creep = x[1][0] - x[0][0];
    *a_out = (v[1][0] - v[0][0]) / ((i2 - i1) * dt);
    printf("  mu %g: moved %.3g m between 0.05 s and 0.15 s (%.3g m in all), a = %.6g m/s^2\n", mu,
           *creep, x[1][0], *a_out);
    finish(&r);
}

TEST(cube_holds_or_slides_on_an_incline)
{
    const double theta = 15 * PI / 180, g = 9.81;
    double creep, a;
    cube_on_incline(0.35, &creep, &a);
    /* held: the stick displacement is m g sin theta / k_t ~ 1e-7 m; no creep beyond 1 um */
    CHECK(fabs(creep) < 1e-6);
    cube_on_incline(0.2, &creep, &a);
    CHECK_REL(g * (sin(theta) - 0.2 * cos(theta)), a, 0.01);
}

/*
 * Friction between two particles: a cube launched at u0 along the top face of another cube
 * resting on the floor stops after u0^2 / (2 mu g) (seed 004 A.6), with mu the cubes' own
 * friction (0.3); the floor holds the lower cube (mu 0.8: its friction 0.8 x 2 m g exceeds the
 * 0.3 m g the upper one drags it with), which moves only by its stick displacement. Both
 * contacts are face on face, coplanar, and the upper one carries the tangential spring between
 * two moving bodies. The 2 % of cube_slides_to_rest: the slide starts while the contact's
 * normal oscillation (period ~1.4 ms) is still dying out.
 */
TEST(cube_slides_to_rest_on_a_cube)
{
    const double u0 = 0.1, mu = 0.3, g = 9.81;
    double s = cube_side(0.02), estar = 1e7 / (2 * (1 - 0.25 * 0.25));
    double rest = cube_rest_depth(s, 2600, estar), m = 2600 * s * s * s, kn = 2 * estar * s;
    double dt = 2 * PI * sqrt(m / kn) / 50;
    /* the lower cube carries both weights: twice the depth */
    double z1 = 0.5 * s - 2 * rest, z2 = z1 + s - rest;
    char json[2000];
    snprintf(json, sizeof json,
             "{\"name\": \"stack\", \"allow_unstable_dt\": true,"
             " \"time\": {\"dt\": %.17g, \"duration\": 1, \"output_interval\": 1},"
             " \"gravity\": [0, 0, -9.81],"
             " \"materials\": {\"c\": {\"density\": 2600, \"youngs_modulus\": 1e7, "
             "\"poisson_ratio\": 0.25}, \"f\": {\"density\": 2600, \"youngs_modulus\": 1e7, "
             "\"poisson_ratio\": 0.25}},"
             " \"interactions\": [{\"between\": [\"c\", \"c\"], \"friction\": %g, \"damping\": "
             "0.5}, {\"between\": [\"c\", \"f\"], \"friction\": 0.8, \"damping\": 0.5}],"
             " \"shapes\": {\"c\": {\"builtin\": \"cube\"}},"
             " \"particles\": [{\"shape\": \"c\", \"material\": \"c\", \"list\": ["
             " {\"position\": [0, 0, %.17g], \"size\": 0.02},"
             " {\"position\": [0, 0, %.17g], \"velocity\": [%g, 0, 0], \"size\": 0.02}]}],"
             " \"walls\": [{\"name\": \"floor\", \"material\": \"f\", \"box\": {\"min\": [-1, -1, "
             "-0.1], \"max\": [1, 1, 0]}}]}",
             dt, mu, z1, z2, u0);
    run r;
    if (start(&r, json)) return;
    double t_stop = u0 / (mu * g), want = u0 * u0 / (2 * mu * g);
    int n = (int)(1.5 * t_stop / dt);
    for (int i = 0; i < n; i++)
        if (step(&r)) break;
    double x[6], v[6];
    get(&r, r.m->x, 6, x);
    get(&r, r.m->v, 6, v);
    printf("  the upper cube slid %.6g m on the lower (theory %.6g m), which moved %.3g m; final "
           "speeds %.3g and %.3g m/s\n",
           x[3] - x[0], want, x[0], fabs(v[3]), fabs(v[0]));
    CHECK_NEAR(want, x[3] - x[0], 0.02 * want);
    CHECK(fabs(x[0]) < 1e-5); /* the floor held the lower cube (stick: ~1e-7 m) */
    /* at rest but for rocking: the drag tilted the lower cube on its single volumetric contact
     * point, and it rocks at a few mm/s (period ~8 ms), little damped (damping acts along the
     * normal at that point, which barely moves as it rocks); the upper cube rides it */
    CHECK(fabs(v[3]) < 0.05 * u0 && fabs(v[0]) < 0.05 * u0);
    finish(&r);
}

/* Issue 3: a cube resting flat on a wall settles at the volumetric model's static balance. The
 * contact is flat, so V = A delta exactly; the 0.1% tolerance covers the remaining oscillation
 * after 60 periods at damping 0.5. */
TEST(cube_rests_flat_on_wall)
{
    double s = cube_side(0.02), estar = 1e7 / (2 * (1 - 0.25 * 0.25));
    double want = cube_rest_depth(s, 2600, estar);
    double m = 2600 * s * s * s, kn = 2 * estar * s; /* eq. 4.17 with V/delta = s^2 */
    double period = 2 * PI * sqrt(m / kn), dt = period / 100;
    char json[2000];
    double at[3] = {0, 0, 0.5 * s + 0.5 * want};
    cube_json(json, sizeof json, dt, at, 0, 0.5, 0.5, NULL);
    run r;
    if (start(&r, json)) return;
    for (int i = 0; i < 6000; i++)
        if (step(&r)) break;
    double x[3];
    get(&r, r.m->x, 3, x);
    double depth = 0.5 * s - x[2];
    printf("  resting depth %.9g m (theory %.9g m)\n", depth, want);
    CHECK_NEAR(want, depth, 1e-3 * want);
    finish(&r);
}

/*
 * Thesis section 5.4, "contact_places": a U (tests/u_shape.h, size 0.02 m) standing on its two
 * prongs on a box floor. At rest each prong tip, a flat contact of area A = 2.5 k^2 (k the mesh's
 * scale), carries m g / 2. Pressed separately, eq. 4.16 with V = A delta per place gives
 *   m g / 2 = 4/(3 sqrt(pi)) E* sqrt(A) delta  ->  delta = 3 sqrt(pi) m g / (8 E* sqrt(A)).
 * Merged into one contact (the thesis's model, "merged"), V = 2 A delta over the same depth:
 *   m g = 4/(3 sqrt(pi)) E* sqrt(2 A) delta  ->  delta sqrt(2) times deeper.
 * Both are checked to cube_rests_flat_on_wall's 0.1 % after 60 periods of the stiffer mode.
 */
static double u_rest_depth(const char *places, double want)
{
    double d = 0.02, k = cbrt(PI * d * d * d / 6 / U_VOLUME), estar = 1e7 / (2 * (1 - 0.25 * 0.25));
    double m = 2600 * PI * d * d * d / 6, area = U_LY * k * k;
    double kn = 2 * 2 * estar * sqrt(area / PI); /* eq. 4.17, both places at V/delta = A */
    double period = 2 * PI * sqrt(m / kn), dt = period / 100;
    char shape[2000], json[4000];
    u_shape_json(shape, sizeof shape);
    snprintf(json, sizeof json,
             "{\"name\": \"u\", \"allow_unstable_dt\": true,"
             " \"time\": {\"dt\": %.17g, \"duration\": 1, \"output_interval\": 1},"
             " \"gravity\": [0, 0, -9.81],"
             " \"materials\": {\"m\": {\"density\": 2600, \"youngs_modulus\": 1e7, "
             "\"poisson_ratio\": 0.25}},"
             " \"interactions\": [{\"between\": [\"m\", \"m\"], \"friction\": 0.5, \"damping\": "
             "0.5, \"contact_places\": \"%s\"}],"
             " \"shapes\": {\"u\": %s},"
             " \"particles\": [{\"shape\": \"u\", \"material\": \"m\", \"list\": ["
             " {\"position\": [0, 0, %.17g], \"size\": %g}]}],"
             " \"walls\": [{\"name\": \"floor\", \"material\": \"m\", "
             "\"box\": {\"min\": [-1, -1, -0.1], \"max\": [1, 1, 0]}}]}",
             dt, places, shape, U_CENTROID_Z * k - want, d);
    run r;
    if (start(&r, json)) return -1;
    for (int i = 0; i < 6000; i++)
        if (step(&r)) break;
    double x[3];
    get(&r, r.m->x, 3, x);
    finish(&r);
    return U_CENTROID_Z * k - x[2];
}

TEST(u_rests_on_two_separate_places)
{
    double d = 0.02, k = cbrt(PI * d * d * d / 6 / U_VOLUME), estar = 1e7 / (2 * (1 - 0.25 * 0.25));
    double m = 2600 * PI * d * d * d / 6, area = U_LY * k * k;
    double want = 3 * sqrt(PI) * m * 9.81 / (8 * estar * sqrt(area));
    double sep = u_rest_depth("separate", want), mer = u_rest_depth("merged", sqrt(2) * want);
    printf("  resting depth: separate %.9g m (theory %.9g m), merged %.9g m (theory %.9g m)\n", sep,
           want, mer, sqrt(2) * want);
    CHECK_NEAR(want, sep, 1e-3 * want);
    CHECK_NEAR(sqrt(2) * want, mer, 1e-3 * sqrt(2) * want);
}

/* Seed 004 A.6: a cube launched along a floor at u0 slides u0^2 / (2 mu g) before it stops.
 * It starts at its resting depth; 2% covers the tangential spring's stretch and the cube's
 * slight pitch under the friction torque. */
TEST(cube_slides_to_rest)
{
    const double u0 = 0.2, mu = 0.3, g = 9.81;
    double s = cube_side(0.02), estar = 1e7 / (2 * (1 - 0.25 * 0.25));
    double rest = cube_rest_depth(s, 2600, estar), m = 2600 * s * s * s, kn = 2 * estar * s;
    double period = 2 * PI * sqrt(m / kn), dt = period / 50;
    char json[2000];
    double at[3] = {0, 0, 0.5 * s - rest};
    cube_json(json, sizeof json, dt, at, u0, mu, 0.5, NULL);
    run r;
    if (start(&r, json)) return;
    double t_stop = u0 / (mu * g), want = u0 * u0 / (2 * mu * g);
    int n = (int)(1.3 * t_stop / dt);
    for (int i = 0; i < n; i++)
        if (step(&r)) break;
    double x[3], v[3];
    get(&r, r.m->x, 3, x);
    get(&r, r.m->v, 3, v);
    printf("  slid %.6g m (theory %.6g m), final speed %.3g m/s\n", x[0], want, fabs(v[0]));
    CHECK_NEAR(want, x[0], 0.02 * want);
    CHECK(fabs(v[0]) < 0.01 * u0);
    finish(&r);
}

/*
 * Issue 3, thesis section 5.6: walls are met through their own triangle BVH. The slide of
 * cube_slides_to_rest on a floor meshed as a closed slab whose faces are 60 x 60 grids (43 200
 * triangles; 6.7 mm squares under the 16 mm cube, so it crosses grid edges all the way, flat on
 * their coplanar triangles) ends where the 12-triangle box floor's does: the same surface, so
 * the same overlaps to round-off, which the damped slide does not amplify (1e-9 of the distance),
 * and both within cube_slides_to_rest's 2% of the analytic distance.
 */
static double slide_on(const char *floor_json, double *speed)
{
    const double u0 = 0.2, mu = 0.3, g = 9.81;
    double s = cube_side(0.02), estar = 1e7 / (2 * (1 - 0.25 * 0.25));
    double rest = cube_rest_depth(s, 2600, estar), m = 2600 * s * s * s, kn = 2 * estar * s;
    double period = 2 * PI * sqrt(m / kn), dt = period / 50;
    char json[2000];
    /* off the grid's lines, so the cube's edges cross the floor's edges all the way */
    double at[3] = {0.0013, 0.0021, 0.5 * s - rest};
    cube_json(json, sizeof json, dt, at, u0, mu, 0.5, floor_json);
    run r;
    if (start(&r, json)) return NAN;
    int n = (int)(1.3 * u0 / (mu * g) / dt);
    for (int i = 0; i < n; i++)
        if (step(&r)) break;
    double x[3], v[3];
    get(&r, r.m->x, 3, x);
    get(&r, r.m->v, 3, v);
    printf("  floor of %d triangles (at most %d near the cube): slid %.12g m\n",
           r.s->wall[0].mesh->ntris, r.m->wall_cap, x[0] - 0.0013);
    *speed = fabs(v[0]);
    finish(&r);
    return x[0] - 0.0013;
}

TEST(cube_slides_on_a_finely_meshed_floor)
{
    const double u0 = 0.2, mu = 0.3, g = 9.81, want = u0 * u0 / (2 * mu * g);
    char path[64], floor_json[160];
    snprintf(path, sizeof path, "/tmp/polydem-test-floor-%d.obj", (int)getpid());
    double c[3] = {0, 0, -0.025}, h[3] = {0.2, 0.2, 0.025}, v_box, v_mesh;
    if (grid_box_obj(path, c, h, 60)) {
        TEST_FAILF("cannot write %s", path);
        return;
    }
    double box =
        slide_on("\"box\": {\"min\": [-0.2, -0.2, -0.05], \"max\": [0.2, 0.2, 0]}", &v_box);
    snprintf(floor_json, sizeof floor_json, "\"mesh\": \"%s\"", path);
    double mesh = slide_on(floor_json, &v_mesh);
    remove(path);
    CHECK_NEAR(want, box, 0.02 * want);
    CHECK_NEAR(box, mesh, 1e-9 * want);
    CHECK(v_mesh < 0.01 * u0);
}

/* A particle whose centre starts inside a wall is refused with a message naming both; one that
 * only overlaps a wall's surface starts (and is pushed out). */
TEST(particle_inside_wall_is_refused)
{
    char json[1500];
    double inside[3] = {0, 0, -0.05}, sunk[3] = {0, 0, 0.001}; /* sunk 9 mm into the floor */
    cube_json(json, sizeof json, 1e-5, inside, 0, 0.5, 0.5, NULL);
    pd_scenario *s = NULL;
    pd_diags d = {0, 0, NULL};
    pd_error err = {0};
    sim *m = NULL;
    /* validation refuses it first, naming the particle's field */
    CHECK_EQ_INT(PD_EINVAL, pd_scenario_parse(json, NULL, &s, &d, &err));
    CHECK(d.n == 1 && !strcmp(d.items[0].path, "/particles/0/list/0/position") &&
          strstr(d.items[0].msg, "inside wall 'floor'"));
    pd_diags_free(&d);
    /* and a run (which validation skips above 2e5 particles): the same scenario, valid, with
     * its particle moved into the floor after parsing */
    cube_json(json, sizeof json, 1e-5, sunk, 0, 0.5, 0.5, NULL);
    CHECK_EQ_INT(PD_OK, pd_scenario_parse(json, NULL, &s, &d, &err));
    pd_diags_free(&d);
    if (!s) return;
    memcpy(s->group[0].list[0].position, inside, sizeof inside);
    CHECK_EQ_INT(PD_EINVAL, sim_create(dev, s, &m, &err));
    printf("  %s\n", err.msg);
    CHECK(strstr(err.msg, "particle 0") && strstr(err.msg, "inside wall 'floor'"));
    CHECK(m == NULL);
    pd_scenario_destroy(s);
    cube_json(json, sizeof json, 1e-5, sunk, 0, 0.5, 0.5, NULL);
    run r;
    if (start(&r, json)) return;
    finish(&r);
}

/* Seed 004 A.7: a sphere at rest in a uniform flow approaches it as u = u_f (1 - exp(-t/tau)),
 * tau = rho d^2 / (18 mu) (eq. 1.2). The drag is evaluated at the half-step velocity, so the
 * error is O(dt / tau) = 1e-3 at dt = tau / 1000: tolerance 2e-3. */
TEST(stokes_drag_relaxation)
{
    const double d = 1e-3, rho = 1000, mu = 1e-3, uf = 0.5;
    double tau = rho * d * d / (18 * mu), dt = tau / 1000;
    char json[1500];
    snprintf(
        json, sizeof json,
        "{\"name\": \"drag\", \"allow_unstable_dt\": true,"
        " \"time\": {\"dt\": %.17g, \"duration\": 1, \"output_interval\": 1},"
        " \"gravity\": [0, 0, 0], \"fluid\": {\"viscosity\": %g, \"velocity\": [%g, 0, 0]},"
        " \"materials\": {\"m\": {\"density\": %g, \"youngs_modulus\": 1e7, \"poisson_ratio\": "
        "0.25}},"
        " \"interactions\": [{\"between\": [\"m\", \"m\"]}],"
        " \"shapes\": {\"ball\": {\"sphere\": {}}},"
        " \"particles\": [{\"shape\": \"ball\", \"material\": \"m\", \"list\": ["
        " {\"position\": [0, 0, 0], \"size\": %g}]}]}",
        dt, mu, uf, rho, d);
    run r;
    if (start(&r, json)) return;
    for (int i = 0; i < 1000; i++)
        if (step(&r)) break;
    double x[3], v[3];
    get(&r, r.m->x, 3, x);
    get(&r, r.m->v, 3, v);
    double t = 1000 * dt, vw = uf * (1 - exp(-t / tau)),
           xw = uf * tau * (exp(-t / tau) - 1) + uf * t;
    printf("  u(tau) %.9g m/s (theory %.9g), x(tau) %.9g m (theory %.9g)\n", v[0], vw, x[0], xw);
    CHECK_NEAR(vw, v[0], 2e-3 * vw);
    CHECK_NEAR(xw, x[0], 2e-3 * xw);
    finish(&r);
}

/*
 * Seed 004 A.5: two spheres with cohesion stick when the stickiness number
 * Sy = L_e sqrt(k_c) / (e sqrt(L_e^2 k_c + u0^2 m*)) exceeds 1 and separate below. A.5 is an
 * estimate (it takes the rebound speed as e times the impact speed), so the runs sit at
 * Sy = 1.3 and 0.75, well clear of the threshold; k_c = k_e / 1000 keeps cohesion a small
 * perturbation during the contact as A.4.2 assumes.
 */
static int cohesion_sticks(double sy)
{
    const double R = 0.01, rho = 2500, k = 1e4, e = 0.5, Le = 1e-3, kc = k / 1000;
    double m = rho * 4.0 / 3 * PI * R * R * R, ms = m / 2, le = log(e);
    double eta = -2 * le * sqrt(ms * k / (PI * PI + le * le));
    double u0 = sqrt(Le * Le * kc * (1 / (e * e * sy * sy) - 1) / ms);
    double dt = PI / sqrt(k / ms) / 200;
    char json[1600];
    snprintf(
        json, sizeof json,
        "{\"name\": \"cohesion\", \"allow_unstable_dt\": true,"
        " \"time\": {\"dt\": %.17g, \"duration\": 1, \"output_interval\": 1},"
        " \"gravity\": [0, 0, 0],"
        " \"materials\": {\"m\": {\"density\": %g, \"youngs_modulus\": 1e7, \"poisson_ratio\": "
        "0.25}},"
        " \"interactions\": [{\"between\": [\"m\", \"m\"], \"model\": \"linear\", "
        "\"normal_stiffness\": %g, \"damping_coefficient\": %.17g, \"friction\": 0, "
        "\"cohesion\": %g, \"cohesion_range\": %g}],"
        " \"shapes\": {\"ball\": {\"sphere\": {}}},"
        " \"particles\": [{\"shape\": \"ball\", \"material\": \"m\", \"list\": ["
        " {\"position\": [0, 0, 0], \"velocity\": [%.17g, 0, 0], \"size\": %g},"
        " {\"position\": [%.17g, 0, 0], \"velocity\": [%.17g, 0, 0], \"size\": %g}]}]}",
        dt, rho, k, eta, kc, Le, u0 / 2, 2 * R, 2 * R + Le * 0.999, -u0 / 2, 2 * R);
    run r;
    if (start(&r, json)) return -1;
    /* long enough to cross the range four times over at the rebound speed */
    int n = (int)(4 * Le / (e * u0) / dt) + 1000;
    double x[6], v[6];
    for (int i = 0; i < n; i++)
        if (step(&r)) break;
    get(&r, r.m->x, 6, x);
    get(&r, r.m->v, 6, v);
    double gap = x[3] - x[0] - 2 * R, vsep = v[3] - v[0];
    printf("  Sy %.2f: gap %.3g m (range %.3g m), separation speed %.3g m/s\n", sy, gap, Le, vsep);
    finish(&r);
    return gap < Le ? 1 : 0;
}

TEST(cohesion_stickiness_threshold)
{
    CHECK_EQ_INT(1, cohesion_sticks(1.3));
    CHECK_EQ_INT(0, cohesion_sticks(0.75));
}

static const char *bed_json = "{\"name\": \"bed\", \"precision\": \"%s\", \"seed\": 7,"
                              " \"time\": {\"dt\": 2e-6, \"duration\": 1, \"output_interval\": 1},"
                              " \"gravity\": [0, 0, -9.81],"
                              " \"materials\": {\"m\": {\"density\": 2600, \"youngs_modulus\": "
                              "2e7, \"poisson_ratio\": 0.25}},"
                              " \"interactions\": [{\"between\": [\"m\", \"m\"], \"friction\": "
                              "0.4, \"damping\": 0.3, \"contact_places\": \"%s\"}],"
                              " \"shapes\": {\"s\": {\"builtin\": \"schonhardt\"}, \"r\": "
                              "{\"builtin\": \"rock\", \"triangles\": 40}, \"b\": {\"sphere\": "
                              "{}}},"
                              " \"particles\": ["
                              "{\"shape\": \"s\", \"material\": \"m\", \"count\": 24, \"size\": "
                              "0.01, \"region\": {\"min\": [0, 0, 0.0], \"max\": [0.08, 0.08, "
                              "0.04]}, \"orientation\": \"random\", \"velocity\": [0, 0, -2]},"
                              "{\"shape\": \"r\", \"material\": \"m\", \"count\": 8, \"size\": "
                              "0.01, \"region\": {\"min\": [0, 0, 0.04], \"max\": [0.08, 0.08, "
                              "0.065]}, \"orientation\": \"random\", \"velocity\": [0, 0, -2]},"
                              "{\"shape\": \"b\", \"material\": \"m\", \"count\": 8, \"size\": "
                              "0.01, \"region\": {\"min\": [0, 0, 0.065], \"max\": [0.08, 0.08, "
                              "0.08]}, \"velocity\": [0, 0, -2]}],"
                              " \"walls\": [{\"name\": \"floor\", \"material\": \"m\", \"box\": "
                              "{\"min\": [-1, -1, -0.1], \"max\": [1, 1, -0.002]}}%s]}";

/* run_bed's extra walls (JSON array items after the floor, each with a leading comma) */
static const char *bed_walls = "";
static const char *bed_places = "merged"; /* run_bed's "contact_places" */

static int bed_no_skin;      /* run_bed builds the pair list every step */
static long long bed_builds; /* pair lists run_bed built */
static long bed_certified;   /* pairs skipped as certified apart, summed over every 10th step */

/* Pairs the last step skipped as certified apart (info -2, kernels/contact.cl). */
static long bed_waiting; /* pairs whose surfaces' gap search waits (CP_GAP_RETRY), likewise */

static long certified_pairs(run *r)
{
    double info[4096];
    int np = r->m->npairs < 4096 ? r->m->npairs : 4096;
    long k = 0;
    if (np > 0) get_info(r, (size_t)np, info);
    for (int c = 0; c < np; c++) {
        k += info[c] == -2;
        bed_waiting += info[c] <= -3;
    }
    return k;
}

/* Runs the mixed bed for nsteps; x and q receive the final state of its 40 particles. */
static int run_bed(const char *precision, int nsteps, double *x, double *q, long *contacts)
{
    char json[3000];
    snprintf(json, sizeof json, bed_json, precision, bed_places, bed_walls);
    run r;
    if (start(&r, json)) return -1;
    if (bed_no_skin) r.m->skin = 0;
    bed_certified = bed_waiting = 0;
    for (int i = 0; i < nsteps; i++) {
        if (step(&r)) break;
        if (i % 10 == 0) bed_certified += certified_pairs(&r);
    }
    bed_builds = r.m->builds;
    get(&r, r.m->x, 3 * 40, x);
    get(&r, r.m->q, 4 * 40, q);
    double info[4096];
    int np = r.m->npairs < 4096 ? r.m->npairs : 4096;
    *contacts = 0;
    if (np > 0) {
        pd_error err = {0};
        sim_read_info(r.m, (size_t)np, info, &err);
        for (int c = 0; c < np; c++)
            *contacts += info[c] >= 0; /* depth / size when touching, -1 when not */
    }
    finish(&r);
    return 0;
}

/*
 * A stats row is summed on the device (kernels/stats.cl, engine/sim_stats.c): it must give what
 * summing the state read back gives, as rows were computed before. The bed with a second wall
 * (a strip of floor under part of the bed, so both walls carry force), after 2 000 steps (4 ms:
 * particles on the floor and on each other). Kinetic energy within 1e-12 relative in double
 * precision (the device's 1 / inv_m and inverse inertia against the host's mass and inertia,
 * and a different order of summation: a few ulps per term) and 1e-5 in single (the device sums
 * float energies, Kahan-compensated; the host, the same floats in double: ~1e-7 per term); the
 * contacts and the largest depth / size exactly (integer counts, a maximum of the same floats);
 * the wall forces within the same relative bounds of the summed magnitudes. A particle whose
 * velocity is NaN makes the energy not finite and is the one named.
 */
static void check_stats_rows(const char *precision, double tol)
{
    char json[3200];
    snprintf(json, sizeof json, bed_json, precision, "merged",
             ", {\"name\": \"strip\", \"material\": \"m\", \"box\": {\"min\": [-0.5, -1, -0.05], "
             "\"max\": [0.04, 1, -0.002]}}");
    run r;
    if (start(&r, json)) return;
    for (int i = 0; i < 2000; i++)
        if (step(&r)) break;
    sim *m = r.m;
    pd_error err = {0};
    int n = m->n, np = m->npairs;
    double ke_dev, ratio_dev, wf_dev[6];
    int worst_dev;
    long contacts_dev;
    CHECK_EQ_INT(PD_OK, sim_stats_energy(m, &ke_dev, &worst_dev, &err));
    CHECK_EQ_INT(PD_OK, sim_stats_contacts(m, &contacts_dev, &ratio_dev, wf_dev, &err));

    double q[4 * 40], v[3 * 40], L[3 * 40], e_host[40], ke = 0;
    get(&r, m->q, 4 * (size_t)n, q);
    get(&r, m->v, 3 * (size_t)n, v);
    get(&r, m->L, 3 * (size_t)n, L);
    for (int i = 0; i < n; i++) {
        const double *in = m->p->inertia + 3 * i, *vi = v + 3 * i;
        pd_q4 qi = q4(q[4 * i], q[4 * i + 1], q[4 * i + 2], q[4 * i + 3]);
        e_host[i] = 0.5 * m->p->mass[i] * (vi[0] * vi[0] + vi[1] * vi[1] + vi[2] * vi[2]) +
                    int_rot_energy(qi, v3_load(L, i), v3(1 / in[0], 1 / in[1], 1 / in[2]));
        ke += e_host[i];
    }
    double emax = 0;
    for (int i = 0; i < n; i++)
        emax = fmax(emax, e_host[i]);
    CHECK_REL(ke, ke_dev, tol);
    CHECK(worst_dev >= 0 && worst_dev < n);
    if (worst_dev >= 0 && worst_dev < n) CHECK_REL(emax, e_host[worst_dev], tol);

    double *info = malloc(sizeof(double) * (size_t)np), *f = malloc(sizeof(double) * 3 * np);
    cl_ulong *keys = malloc(sizeof(cl_ulong) * (size_t)np);
    if (!info || !f || !keys || np < 1) {
        TEST_FAILF("%d pairs", np);
        goto done;
    }
    get_info(&r, (size_t)np, info);
    get(&r, m->force, 3 * (size_t)np, f);
    clEnqueueReadBuffer(dev->queue, m->pairs.keys, CL_TRUE, 0, sizeof(cl_ulong) * np, keys, 0, NULL,
                        NULL);
    long contacts = 0;
    double ratio = 0, wf[6] = {0}, mag[2] = {0};
    for (int c = 0; c < np; c++) {
        contacts += info[c] >= 0;
        ratio = fmax(ratio, info[c]);
        unsigned b = (unsigned)(keys[c] & 0xffffffffu);
        if (b < CH_WALL) continue;
        for (int k = 0; k < 3; k++) {
            wf[3 * (b - CH_WALL) + k] += f[3 * c + k];
            mag[b - CH_WALL] += fabs(f[3 * c + k]);
        }
    }
    printf("  %s: %ld contacts, kinetic energy %.6g J (device) / %.6g J (host), wall forces "
           "z %.6g / %.6g N (floor), %.6g / %.6g N (strip)\n",
           precision, contacts, ke_dev, ke, wf_dev[2], wf[2], wf_dev[5], wf[5]);
    CHECK(contacts > 0);
    for (int layout = 0; layout < 2; layout++) {
        CHECK(contacts_dev == contacts);
        CHECK(ratio_dev == ratio);
        for (int w = 0; w < 2; w++) {
            CHECK(mag[w] > 0); /* both walls carry force */
            for (int k = 0; k < 3; k++)
                CHECK_NEAR(wf[3 * w + k], wf_dev[3 * w + k], tol * mag[w]);
        }
        if (layout) break;
        /* the other device class's shares (contiguous on a CPU, interleaved on a GPU), three of
         * them, so that each sums many items (the last fewer) */
        m->dev->gpu = !m->dev->gpu;
        m->stat_parts = 3;
        CHECK_EQ_INT(PD_OK, sim_stats_energy(m, &ke_dev, &worst_dev, &err));
        CHECK_EQ_INT(PD_OK, sim_stats_contacts(m, &contacts_dev, &ratio_dev, wf_dev, &err));
        m->dev->gpu = !m->dev->gpu;
        CHECK_REL(ke, ke_dev, tol);
        if (worst_dev >= 0 && worst_dev < n) CHECK_REL(emax, e_host[worst_dev], tol);
    }

    /* a particle gone NaN: not finite, and named, in shares of one particle and of many (with
     * larger energies after it in its share: it stays the one named) */
    double nan3[3] = {NAN, 0, 0};
    CHECK_EQ_INT(PD_OK, sim_write(m, m->v, 3 * 17, 3, nan3, &err));
    for (int parts = 40; parts >= 3; parts -= 37) {
        m->stat_parts = parts;
        CHECK_EQ_INT(PD_OK, sim_stats_energy(m, &ke_dev, &worst_dev, &err));
        CHECK(!isfinite(ke_dev));
        CHECK_EQ_INT(17, worst_dev);
    }
done:
    free(info);
    free(f);
    free(keys);
    finish(&r);
}

TEST(stats_rows_match_host_sums)
{
    if (pd_device_has_fp64(dev)) check_stats_rows("double", 1e-12);
    check_stats_rows("single", 1e-5);
}

/* Issue 3: the same scenario on the same device gives bit-identical states, contacts included
 * (no floating-point atomics; every sum in key order). */
TEST(bit_identical_reruns)
{
    double x1[120], q1[160], x2[120], q2[160];
    long c1 = 0, c2 = 0;
    if (run_bed("double", 1500, x1, q1, &c1) || run_bed("double", 1500, x2, q2, &c2)) return;
    printf("  %ld contacts at the end\n", c1);
    CHECK(c1 > 10); /* the bed is in contact: the check is not vacuous */
    CHECK_EQ_INT(c1, c2);
    CHECK(memcmp(x1, x2, sizeof x1) == 0);
    CHECK(memcmp(q1, q2, sizeof q1) == 0);
}

/* The same with separate places: their bookkeeping is deterministic too. After 6000 steps (12
 * ms, the bed landed; at 1500 steps no contact had touched in two places yet) the bed differs
 * from the merged one's, so places were met. */
TEST(bit_identical_reruns_with_separate_places)
{
    double x1[120], q1[160], x2[120], q2[160], xm[120], qm[160];
    long c1 = 0, c2 = 0, cm = 0;
    bed_places = "separate";
    int rc = run_bed("double", 6000, x1, q1, &c1) || run_bed("double", 6000, x2, q2, &c2);
    bed_places = "merged";
    if (rc || run_bed("double", 6000, xm, qm, &cm)) return;
    printf("  %ld contacts at the end (%ld merged)\n", c1, cm);
    CHECK(c1 > 5);
    CHECK_EQ_INT(c1, c2);
    CHECK(memcmp(x1, x2, sizeof x1) == 0);
    CHECK(memcmp(q1, q2, sizeof q1) == 0);
    CHECK(memcmp(x1, xm, sizeof x1) != 0);
}

/*
 * The Verlet skin: reusing the pair list until a particle has moved half the skin gives the
 * same states, bit for bit, as building it every step (the extra candidates carry no force), and
 * it is reused on most steps. Reused lists also skip polyhedra certified apart (np_hull_gap,
 * cp_mesh_gap, contact.cl) until they have moved that far, and update the tangential history in
 * place; lists built every step skip nothing and carry the history through history_keep. So
 * identical states also check that no skipped pair would have touched and that the carried
 * history is the kept one.
 */
static void reuse_is_exact(const char *precision)
{
    double x1[120], q1[160], x2[120], q2[160];
    long c1 = 0, c2 = 0;
    if (run_bed(precision, 1500, x1, q1, &c1)) return;
    long long reused_builds = bed_builds;
    long skipped = bed_certified, waiting = bed_waiting;
    bed_no_skin = 1;
    int rc = run_bed(precision, 1500, x2, q2, &c2);
    bed_no_skin = 0;
    if (rc) return;
    printf("  %s: pair list built %lld times with the skin, %lld without, in 1500 steps; %ld "
           "contacts; %ld pairs skipped as certified apart and %ld not searched for a gap (every "
           "10th step), %ld and %ld without the skin\n",
           precision, reused_builds, bed_builds, c1, skipped, waiting, bed_certified, bed_waiting);
    CHECK(c1 > 10);
    CHECK_EQ_INT(c1, c2);
    CHECK(memcmp(x1, x2, sizeof x1) == 0);
    CHECK(memcmp(q1, q2, sizeof q1) == 0);
    CHECK(reused_builds < 1500 / 2);
    CHECK(bed_builds > 1400);
    CHECK(skipped > 100); /* the skipping was exercised */
    CHECK_EQ_INT(0, bed_certified);
}

/*
 * Issue 3's memory target (<= 1 KB per Schönhardt particle in a dense bed; bench/RESULTS.md,
 * 2026-12-01: 986 bytes in the 1e3 bed) rests on the layout this checks, so that an array added
 * per particle or per pair shows here rather than in a bench nobody reran. Per particle, besides
 * the pair arrays and the overlap scratch: the state (x, q, v, L, size, inverse mass, shape,
 * material), forces and torques (f holding the traversal's candidates too), the tree and its
 * sort, reference positions, travel and list offsets: 312 bytes in double precision, 224 in
 * single, plus the run's fixed buffers (shapes, walls, stats: under 16 bytes a particle at 8 000).
 * Per pair slot: 8 (key) + 4 reals (spring, stiffness) in the list and in the carried copy, plus
 * the twist (1) with contact moments (the default for polyhedra; checked with and without) and
 * the contact point (3) in single precision; 6 reals + 8 (force, torque, info, second-body list)
 * in the work arrays.
 */
static void check_memory(const char *precision, int moments, double rs, double per_particle)
{
    char json[1500];
    snprintf(json, sizeof json,
             "{\"name\": \"mem\", \"precision\": \"%s\", \"time\": {\"dt\": 1e-5, \"duration\": 1},"
             " \"materials\": {\"m\": {\"density\": 2600, \"youngs_modulus\": 1e6, "
             "\"poisson_ratio\": 0.25}}, \"interactions\": [{\"between\": [\"m\", \"m\"], "
             "\"friction\": 0.5, \"damping\": 0.3, \"contact_moments\": %s}], \"shapes\": {\"s\": "
             "{\"builtin\": "
             "\"schonhardt\"}}, \"particles\": [{\"shape\": \"s\", \"material\": \"m\", \"count\": "
             "8000, \"size\": 0.01, \"region\": {\"min\": [0, 0, 0], \"max\": [0.4, 0.4, 0.4]}, "
             "\"arrangement\": \"lattice\", \"orientation\": \"random\"}], \"walls\": [{\"name\": "
             "\"floor\", \"material\": \"m\", \"box\": {\"min\": [-1, -1, -0.1], \"max\": [1, 1, "
             "-0.01]}}]}",
             precision, moments ? "true" : "false");
    run r;
    if (start(&r, json)) return;
    sim *m = r.m;
    double scratch = (double)m->nwork * (4.0 * m->ilen + rs * m->rlen);
    double kept = 8 + (4 + moments + (rs == 8 ? 0 : 3)) * rs;
    double pairs = (double)m->pairs.cap * kept + (double)m->carry.cap * kept +
                   (double)m->work_cap * (6 * rs + 8);
    double rest = (m->bytes - scratch - pairs) / m->n;
    printf("  %s, contact moments %s: %.1f bytes a particle besides %zu pair slots and the "
           "scratch\n",
           precision, moments ? "on" : "off", rest, m->pairs.cap);
    CHECK_EQ_INT(moments, m->moments);
    CHECK(m->pairs.cap > 0 && m->work_cap > 0);
    CHECK(rest >= per_particle && rest <= per_particle + 16);
    finish(&r);
}

TEST(memory_per_particle_is_bounded)
{
    for (int moments = 0; moments < 2; moments++) {
        if (pd_device_has_fp64(dev)) check_memory("double", moments, 8, 312);
        check_memory("single", moments, 4, 224);
    }
}

TEST(pair_list_reuse_is_exact)
{
    if (pd_device_has_fp64(dev)) reuse_is_exact("double");
    reuse_is_exact("single"); /* the certificates' rounding margins in single precision */
}

/*
 * Two Schönhardt prisms whose convex hulls overlap while their surfaces are still apart (one's
 * corner inside the other's notch; found by bisecting with `polydem overlap` on the meshes and on
 * their hulls: surfaces meet at 11.35 mm between centres along this line, hulls at 14.53 mm),
 * closing at 0.1 m/s from 11.60 mm. The hull gap cannot certify them, so the surfaces' gap is
 * searched (cp_mesh_gap) until it falls within 64 steps' motion, where the search gives up and
 * then waits CP_GAP_RETRY steps between tries until they touch. A sphere flying past keeps the
 * pair lists short-lived, as in a flow, so lists are long-lived enough for searches (list_life)
 * only from the second build on. The same states, bit for bit, as building the list every step
 * (no certificates, no waits): no wait hides a contact or carries stale state.
 */
static const char *nested_json =
    "{\"name\": \"nested\", \"precision\": \"%s\", \"time\": {\"dt\": 5e-6, \"duration\": 1,"
    " \"output_interval\": 1}, \"gravity\": [0, 0, 0],"
    " \"materials\": {\"m\": {\"density\": 2600, \"youngs_modulus\": 2e7, \"poisson_ratio\": "
    "0.25}},"
    " \"interactions\": [{\"between\": [\"m\", \"m\"], \"friction\": 0.4, \"damping\": 0.3}],"
    " \"shapes\": {\"s\": {\"builtin\": \"schonhardt\"}, \"b\": {\"sphere\": {}}},"
    " \"particles\": [{\"shape\": \"s\", \"material\": \"m\", \"list\": ["
    "{\"position\": [0, 0, 0], \"velocity\": [-0.01664, -0.044251, 0.016278], \"size\": 0.01},"
    " {\"position\": [-0.0038596, -0.0102638, 0.0037756], \"velocity\": [0.01664, 0.044251, "
    "-0.016278], \"orientation\": [0.31743014615435367, 0.30088465738789577, 0.89426708239976, "
    "0.09483095801063667], \"size\": 0.01}]},"
    " {\"shape\": \"b\", \"material\": \"m\", \"list\": [{\"position\": [0.1, 0, 0],"
    " \"velocity\": [0.4, 0, 0], \"size\": 0.01}]}]}";

/* Runs the nested pair for nsteps; counts, over every step, pairs certified apart (info -2) and
 * pairs whose gap search waits (info <= -3), and the first step in contact. */
static int run_nested(const char *precision, int no_skin, int nsteps, double *x, double *q,
                      long *certified, long *waiting, int *first_contact)
{
    char json[2000];
    snprintf(json, sizeof json, nested_json, precision);
    run r;
    if (start(&r, json)) return -1;
    if (no_skin) r.m->skin = 0;
    *certified = *waiting = 0;
    *first_contact = -1;
    for (int i = 1; i <= nsteps; i++) {
        if (step(&r)) break;
        double info[16];
        int np = r.m->npairs < 16 ? r.m->npairs : 16;
        if (np > 0) get_info(&r, (size_t)np, info);
        for (int c = 0; c < np; c++) {
            *certified += info[c] == -2;
            *waiting += info[c] <= -3;
            if (info[c] >= 0 && *first_contact < 0) *first_contact = i;
        }
    }
    get(&r, r.m->x, 3 * 3, x);
    get(&r, r.m->q, 4 * 3, q);
    finish(&r);
    return 0;
}

static void gap_waits_are_exact(const char *precision)
{
    double x1[9], q1[12], x2[9], q2[12];
    long cert1, wait1, cert2, wait2;
    int touch1, touch2;
    if (run_nested(precision, 0, 700, x1, q1, &cert1, &wait1, &touch1) ||
        run_nested(precision, 1, 700, x2, q2, &cert2, &wait2, &touch2))
        return;
    printf("  %s: first contact at step %d (%d without the skin); %ld pair-steps certified apart, "
           "%ld waiting for a gap search (%ld and %ld without the skin)\n",
           precision, touch1, touch2, cert1, wait1, cert2, wait2);
    CHECK(touch1 > 300 && touch1 < 700); /* they touch, after closing the 0.25 mm */
    CHECK_EQ_INT(touch1, touch2);
    CHECK(cert1 > 10);  /* the surfaces' gap certified them while far enough apart */
    CHECK(wait1 >= 10); /* and gave up, then waited, once within 64 steps' motion */
    CHECK_EQ_INT(0, cert2 + wait2);
    CHECK(memcmp(x1, x2, sizeof x1) == 0);
    CHECK(memcmp(q1, q2, sizeof q1) == 0);
}

TEST(gap_search_waits_are_exact)
{
    if (pd_device_has_fp64(dev)) gap_waits_are_exact("double");
    gap_waits_are_exact("single");
}

/*
 * Moving walls are followed like particles: their boxes carry skin / 2 and the list is kept
 * until a wall could have moved that far (engine/sim_step.c). A paddle sweeping through the bed
 * while turning, against the same run with the list built every step: identical states.
 */
TEST(moving_wall_list_reuse_is_exact)
{
    double x0[120], q0[160], x1[120], q1[160], x2[120], q2[160];
    long c0 = 0, c1 = 0, c2 = 0;
    if (run_bed("double", 1500, x0, q0, &c0)) return; /* without the paddle */
    bed_walls = ", {\"name\": \"paddle\", \"material\": \"m\", \"velocity\": [0.5, 0, 0],"
                " \"angular_velocity\": [0, 0, 3], \"center\": [0, 0.04, 0.01],"
                " \"box\": {\"min\": [-0.03, 0.035, -0.002], \"max\": [0.03, 0.045, 0.03]}}";
    int rc = run_bed("double", 1500, x1, q1, &c1);
    long long reused_builds = bed_builds;
    bed_no_skin = 1;
    if (rc == 0) rc = run_bed("double", 1500, x2, q2, &c2);
    bed_no_skin = 0;
    bed_walls = "";
    if (rc) return;
    printf("  pair list built %lld times with the skin, %lld without, in 1500 steps; %ld "
           "contacts\n",
           reused_builds, bed_builds, c1);
    CHECK(c1 > 10);
    CHECK_EQ_INT(c1, c2);
    CHECK(memcmp(x1, x2, sizeof x1) == 0);
    CHECK(memcmp(q1, q2, sizeof q1) == 0);
    CHECK(reused_builds < 1500 / 2);
    CHECK(memcmp(x0, x1, sizeof x1) != 0); /* the paddle did push particles */
}

/*
 * Two prisms of examples/packing.json's settled bed (particles 1 and 152 at 0.45 s) touch in
 * three places up to 5 mm apart, 7e-13 m^3 in all. Summed about one origin, single precision
 * could not tell that volume from its cusps' rounding and dropped the contact (61 of the bed's
 * 710 were so); summed about each place's centre (OVL_RESCUE, kernels/overlap.h) it is found.
 * The merged depth spans the places (1.16 mm); single precision gives it to 1e-5 relative (its
 * nodes' coordinates carry a few ulps of the 5 cm bed's; 2e-6 measured), and with separate places
 * the effective depth (59 um) likewise (6e-8 measured: the reported ratio is a float).
 */
static int pair_depth(const char *precision, const char *places, double *depth)
{
    char json[2000];
    snprintf(json, sizeof json,
             "{\"name\": \"pair\", \"precision\": \"%s\", \"allow_unstable_dt\": true,"
             " \"time\": {\"dt\": 1e-6, \"duration\": 1e-5, \"output_interval\": 1e-5},"
             " \"gravity\": [0, 0, 0],"
             " \"materials\": {\"g\": {\"density\": 2500, \"youngs_modulus\": 1e6, "
             "\"poisson_ratio\": 0.25}},"
             " \"interactions\": [{\"between\": [\"g\", \"g\"], \"friction\": 0.5, "
             "\"damping\": 0.3, \"contact_places\": \"%s\"}],"
             " \"shapes\": {\"p\": {\"builtin\": \"schonhardt\"}},"
             " \"particles\": [{\"shape\": \"p\", \"material\": \"g\", \"list\": ["
             " {\"position\": [-0.010615658242810978, -0.04370349320075692, 0.004501654582029738],"
             " \"orientation\": [-0.6693156614811278, 0.5216686763867125, 0.23555142268333987, "
             "0.47370229537640013], \"size\": 0.008307896199474175},"
             " {\"position\": [-0.00485606844845488, -0.046605478128381395, 0.009983204526508653],"
             " \"orientation\": [0.7375883956373755, 0.588736054439012, -0.3298648435199614, "
             "0.023289521983471145], \"size\": 0.009440915057462326}]}]}",
             precision, places);
    run r;
    if (start(&r, json)) return -1;
    double info[16];
    int np = r.m->npairs < 16 ? r.m->npairs : 16, touching = 0;
    if (np > 0) get_info(&r, (size_t)np, info);
    *depth = 0;
    for (int c = 0; c < np; c++)
        if (info[c] >= 0) { /* depth / size when touching, -1 when not */
            touching++;
            *depth = info[c];
        }
    finish(&r);
    return touching;
}

TEST(single_precision_finds_a_contact_in_far_places)
{
    double dd = 0, ds = 0, ed = 0, es = 0;
    int nd = pair_depth("double", "merged", &dd), ns = pair_depth("single", "merged", &ds);
    int md = pair_depth("double", "separate", &ed), ms = pair_depth("single", "separate", &es);
    printf("  touching: double %d (depth / size %.9g), single %d (%.9g); separate places: double "
           "%d (%.9g), single %d (%.9g)\n",
           nd, dd, ns, ds, md, ed, ms, es);
    CHECK_EQ_INT(1, nd);
    CHECK(dd > 0.1); /* the merged depth spans the places: 1.16 mm of 8-9 mm sizes */
    CHECK_EQ_INT(1, ns);
    CHECK_NEAR(dd, ds, 1e-5 * dd);
    CHECK_EQ_INT(1, md);
    CHECK_EQ_INT(1, ms);
    CHECK_NEAR(ed, es, 1e-5 * ed);
}

/*
 * A 2 cm Schönhardt prism falling at ~2 cm/s onto a floor of 2 cm grid squares, in single
 * precision, at two poses a run of 16 particles reached (bench/RESULTS.md, 2026-11-30 evening):
 * returns the velocity change over two steps (m/s), or -1.
 *  1. its face 3.3e-7 m into the floor, about two resolutions: some corners lay within the
 *     resolution of the floor's plane and others not, the cusps closed no surface and the prism
 *     left at 3.45 m/s (caught by refusing an overlap larger than its nodes' box);
 *  2. two corners 2.5e-5 m deep (double precision: depth / size 1.2e-3), whose sides of the
 *     floor's plane two coplanar triangles of the floor decided differently while the plane's
 *     snap bound depended on the frame's axes: a 4 200 N kick.
 * Two steps of gravity and such shallow contacts change the velocity by under 1e-2 m/s (double:
 * 2.7e-3 and 7.7e-3).
 */
static double flat_drop_dv(const char *floor, const double x[3], const double q[4],
                           const double v0[3])
{
    char json[2400];
    snprintf(json, sizeof json,
             "{\"name\": \"flat\", \"precision\": \"single\","
             " \"time\": {\"dt\": 1e-5, \"duration\": 1, \"output_interval\": 1},"
             " \"gravity\": [0, 0, -9.81],"
             " \"materials\": {\"p\": {\"density\": 2500, \"youngs_modulus\": 2e9, "
             "\"poisson_ratio\": 0.25, \"shear_modulus\": 1e9}, \"f\": {\"density\": 2500, "
             "\"youngs_modulus\": 1e9, \"poisson_ratio\": 0.25, \"shear_modulus\": 1e9}},"
             " \"interactions\": [{\"between\": [\"p\", \"p\"], \"friction\": 0.39, \"damping\": "
             "0.453619}, {\"between\": [\"p\", \"f\"], \"friction\": 0.35, \"damping\": 0.382097}],"
             " \"shapes\": {\"s\": {\"builtin\": \"schonhardt\"}},"
             " \"particles\": [{\"shape\": \"s\", \"material\": \"p\", \"list\": [{\"position\": "
             "[%.17g, %.17g, %.17g], \"orientation\": [%.17g, %.17g, %.17g, %.17g], "
             "\"velocity\": [%.17g, %.17g, %.17g], \"size\": 0.02}]}],"
             " \"walls\": [{\"name\": \"floor\", \"material\": \"f\", \"mesh\": \"%s\"}]}",
             x[0], x[1], x[2], q[0], q[1], q[2], q[3], v0[0], v0[1], v0[2], floor);
    run r;
    if (start(&r, json)) return -1;
    for (int i = 0; i < 2; i++)
        if (step(&r)) break;
    double v[3];
    get(&r, r.m->v, 3, v);
    finish(&r);
    return sqrt((v[0] - v0[0]) * (v[0] - v0[0]) + (v[1] - v0[1]) * (v[1] - v0[1]) +
                (v[2] - v0[2]) * (v[2] - v0[2]));
}

TEST(single_precision_flat_face_on_a_meshed_floor)
{
    char path[64];
    snprintf(path, sizeof path, "/tmp/polydem-test-floor-%d.obj", (int)getpid());
    double c[3] = {0, 0, -0.05}, h[3] = {0.2, 0.2, 0.05};
    if (grid_box_obj(path, c, h, 20)) {
        TEST_FAILF("cannot write %s", path);
        return;
    }
    const double x1[3] = {0.073422245681285858, -0.076637379825115204, 0.0084561146795749664};
    const double q1[4] = {-1.2442910701793153e-05, 0.99698179960250854, -0.077636182308197021,
                          1.4436182027566247e-05};
    const double v1[3] = {0.004912381060421467, 0.01549813337624073, -0.010059593245387077};
    const double x2[3] = {0.030577478930354118, -0.091307312250137329, 0.010839909315109253};
    const double q2[4] = {0.573288083076477, 0.7020760178565979, 0.4222853481769562,
                          0.010261725634336472};
    const double v2[3] = {-0.01700553484261036, -0.015737686306238174, -0.012877127155661583};
    double dv1 = flat_drop_dv(path, x1, q1, v1), dv2 = flat_drop_dv(path, x2, q2, v2);
    printf("  velocity change over two steps: %.3g and %.3g m/s\n", dv1, dv2);
    CHECK(dv1 >= 0 && dv1 < 1e-2);
    CHECK(dv2 >= 0 && dv2 < 1e-2);
    remove(path);
}

/* Issue 3: single and double precision agree to single precision. The bed is chaotic once
 * contacts pile up, so this compares the first 300 steps (the first impacts on the floor): a
 * float's 1.2e-7 relative error over 300 steps of forces grows to at most ~1e-5 of a size. */
TEST(single_matches_double)
{
    if (!pd_device_has_fp64(dev)) return;
    double xd[120], qd[160], xs[120], qs[160];
    long cd = 0, cs = 0;
    if (run_bed("double", 300, xd, qd, &cd) || run_bed("single", 300, xs, qs, &cs)) return;
    double worst = 0;
    for (int i = 0; i < 120; i++)
        worst = fmax(worst, fabs(xd[i] - xs[i]));
    printf("  largest position difference %.3g m (%.2g of a particle size)\n", worst, worst / 0.01);
    CHECK(worst < 1e-5 * 0.01 * 10);
}

static int file_exists(const char *p)
{
    return access(p, F_OK) == 0;
}

static int cancel_at_once(const pd_progress *p, void *user)
{
    (void)p;
    (void)user;
    return 1;
}

/*
 * A result kept from a run that stopped early: its root attribute status (into status, cap
 * bytes), its frame count, and whether every kept position is finite. 0 when it could be read.
 */
static int stopped_result(const char *path, char *status, size_t cap, long long *frames,
                          int *finite)
{
    int rc = -1;
    status[0] = 0;
    *frames = 0;
    *finite = 0;
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    if (f < 0) return -1;
    hid_t a = H5Aopen(f, "status", H5P_DEFAULT);
    hid_t t = a >= 0 ? H5Aget_type(a) : -1;
    char *v = NULL;
    if (t >= 0 && H5Aread(a, t, &v) >= 0 && v) {
        snprintf(status, cap, "%s", v);
        H5free_memory(v);
    }
    hid_t d = H5Dopen2(f, "/frames/position", H5P_DEFAULT);
    hid_t sp = d >= 0 ? H5Dget_space(d) : -1;
    hsize_t dims[3] = {0, 0, 0};
    if (sp >= 0 && H5Sget_simple_extent_ndims(sp) == 3 &&
        H5Sget_simple_extent_dims(sp, dims, NULL) == 3) {
        size_t n = (size_t)(dims[0] * dims[1] * dims[2]);
        double *x = malloc(sizeof *x * (n ? n : 1));
        if (x && H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, x) >= 0) {
            *frames = (long long)dims[0];
            *finite = 1;
            for (size_t i = 0; i < n; i++)
                *finite &= isfinite(x[i]) != 0;
            rc = 0;
        }
        free(x);
    }
    if (sp >= 0) H5Sclose(sp);
    if (d >= 0) H5Dclose(d);
    if (t >= 0) H5Tclose(t);
    if (a >= 0) H5Aclose(a);
    H5Fclose(f);
    return rc;
}

/* A time step far above the stable estimate, forced with allow_unstable_dt, must stop with a
 * message naming the step and a particle; the frames written before it are kept (each finite,
 * the divergence being caught before its frame), the file saying "diverged". */
TEST(divergence_is_reported)
{
    char json[3000];
    snprintf(json, sizeof json, bed_json, "double", "merged", "");
    char *p = strstr(json, "2e-6");
    memcpy(p, "9e-3", 4);
    strcpy(strrchr(json, '}'), ", \"allow_unstable_dt\": true}");
    pd_scenario *s = NULL;
    pd_diags d = {0, 0, NULL};
    pd_error err = {0};
    if (pd_scenario_parse(json, NULL, &s, &d, &err) != PD_OK) {
        TEST_FAILF("parse: %s", d.n ? d.items[0].msg : err.msg);
        pd_diags_free(&d);
        return;
    }
    const char *out = "/tmp/polydem_test_diverge.h5";
    pd_run_options opt = {0};
    opt.output_path = out;
    pd_progress fin;
    int rc = pd_run(dev, s, &opt, &fin, &err);
    printf("  %s\n", err.msg);
    CHECK_EQ_INT(PD_EDIVERGED, rc);
    CHECK(strstr(err.msg, "step") && strstr(err.msg, "particle"));
    char status[32];
    long long frames;
    int finite;
    CHECK(fin.result_kept == 1);
    CHECK(stopped_result(out, status, sizeof status, &frames, &finite) == 0);
    CHECK(!strcmp(status, "diverged"));
    CHECK(frames >= 1 && frames == fin.frames && finite);
    CHECK(file_exists("/tmp/polydem_test_diverge.h5.xmf"));
    CHECK(!file_exists("/tmp/polydem_test_diverge.h5.partial"));
    remove(out);
    /* cancelling from the progress callback stops the run and keeps its frames too */
    p = strstr(json, "9e-3");
    memcpy(p, "2e-6", 4);
    pd_scenario_destroy(s);
    s = NULL;
    if (pd_scenario_parse(json, NULL, &s, &d, &err) == PD_OK) {
        opt.progress = cancel_at_once;
        rc = pd_run(dev, s, &opt, &fin, &err);
        CHECK_EQ_INT(PD_ECANCELLED, rc);
        CHECK(fin.result_kept == 1);
        CHECK(stopped_result(out, status, sizeof status, &frames, &finite) == 0);
        CHECK(!strcmp(status, "cancelled"));
        CHECK(frames >= 1 && frames == fin.frames && finite);
        CHECK(!file_exists("/tmp/polydem_test_diverge.h5.partial"));
        remove(out);
        remove("/tmp/polydem_test_diverge.h5.xmf");
    }
    pd_diags_free(&d);
    pd_scenario_destroy(s);
}

/*
 * Thesis section 6.1, figure 6.2: two volume-normalised polyhedral spheres (icosphere, 1280
 * triangles, R = 0.1 m), E = 1 MPa, nu = 0.25, 5 m/s each, normal elastic force only, collide
 * with a kinetic-energy response close to the analytic Hertz sphere: contact time within 5% of
 * t_c = 2.8683 (m*^2 / (R* E*^2 v))^(1/5), the energy at peak compression below 5% of the
 * initial (0 for the exact sphere; the thesis's ensemble minimum at 1280 triangles is a few
 * percent), and the energy after separation within 1% of the initial (elastic: translation and
 * rotation together).
 */
TEST(icosphere_collision_like_hertz_sphere)
{
    const double R = 0.1, E = 1e6, nu = 0.25, rho = 1000, v = 5;
    double m = rho * 4.0 / 3 * PI * R * R * R, ms = m / 2, rs = R / 2;
    double es = E / (2 * (1 - nu * nu));
    double tc = 2.8683 * pow(ms * ms / (rs * es * es * 2 * v), 0.2), dt = tc / 300;
    char json[1600];
    snprintf(json, sizeof json,
             "{\"name\": \"icospheres\", \"allow_unstable_dt\": true,"
             " \"time\": {\"dt\": %.17g, \"duration\": 1, \"output_interval\": 1},"
             " \"gravity\": [0, 0, 0],"
             " \"materials\": {\"m\": {\"density\": %g, \"youngs_modulus\": %g, \"poisson_ratio\": "
             "%g}},"
             " \"interactions\": [{\"between\": [\"m\", \"m\"], \"friction\": 0, \"damping\": 0}],"
             " \"shapes\": {\"ico\": {\"builtin\": \"icosphere\", \"triangles\": 1280}},"
             " \"particles\": [{\"shape\": \"ico\", \"material\": \"m\", \"list\": ["
             " {\"position\": [0, 0, 0], \"orientation\": [0.8, 0.1, 0.5, 0.3], \"velocity\": "
             "[%g, 0, 0], \"size\": %g},"
             " {\"position\": [%.17g, 0, 0], \"orientation\": [0.3, -0.7, 0.2, 0.6], "
             "\"velocity\": [%g, 0, 0], \"size\": %g}]}]}",
             dt, rho, E, nu, v, 2 * R, 2 * R + 2 * v * 10 * dt + 0.002, -v, 2 * R);
    run r;
    if (start(&r, json)) return;
    double ke0 = m * v * v, kmin = ke0, vel[6], L[6], inv_i[6];
    int touching = 0;
    for (int k = 0; k < 6; k++) /* the principal moments the device derives (sim.h) */
        inv_i[k] = 1 / r.m->p->inertia[k];
    for (int i = 0; i < 600; i++) {
        if (step(&r)) break;
        double info[1] = {-1};
        if (r.m->npairs > 0) get_info(&r, 1, info);
        touching += info[0] >= 0;
        get(&r, r.m->v, 6, vel);
        double ke = 0;
        for (int k = 0; k < 6; k++)
            ke += 0.5 * m * vel[k] * vel[k];
        if (ke < kmin) kmin = ke;
    }
    get(&r, r.m->v, 6, vel);
    get(&r, r.m->L, 6, L);
    double ke1 = 0;
    for (int k = 0; k < 6; k++) /* a sphere's inertia is isotropic: 1/2 L^2 / I */
        ke1 += 0.5 * m * vel[k] * vel[k] + 0.5 * L[k] * L[k] * inv_i[k];
    printf("  contact %.5g s (Hertz %.5g s), min KE %.3g of initial, final %.6f of initial\n",
           touching * dt, tc, kmin / ke0, ke1 / ke0);
    CHECK_NEAR(tc, touching * dt, 0.05 * tc);
    CHECK(kmin / ke0 < 0.05);
    CHECK_NEAR(1, ke1 / ke0, 0.01);
    finish(&r);
}

/*
 * Issue 3: with no damping and no friction, a bouncing polyhedral ensemble keeps its energy:
 * 16 polyhedral spheres (icosphere, 320 triangles) in two groups fly into each other inside a
 * closed box (six box walls, no gravity); the kinetic energy at a moment without contacts
 * differs from the initial by less than 1%. Polyhedral spheres, because the thesis's model
 * itself does not conserve energy when impacts make irregular particles turn (see
 * rotating_impact_matches_host_reference); near-spherical shapes isolate the integrator and the
 * pipeline.
 */
TEST(energy_is_conserved_without_damping)
{
    const char *box = "{\"name\": \"%s\", \"material\": \"m\", \"box\": {\"min\": [%g, %g, %g], "
                      "\"max\": [%g, %g, %g]}}";
    char walls[6][200];
    double lo[3] = {-0.03, -0.03, -0.03}, hi[3] = {0.13, 0.07, 0.07}, t = 0.05;
    for (int a = 0; a < 3; a++) {
        double mn[3], mx[3];
        for (int side = 0; side < 2; side++) {
            for (int k = 0; k < 3; k++) {
                mn[k] = lo[k] - t;
                mx[k] = hi[k] + t;
            }
            if (side == 0)
                mx[a] = lo[a];
            else
                mn[a] = hi[a];
            snprintf(walls[2 * a + side], sizeof walls[0], box, side ? "hi" : "lo", mn[0], mn[1],
                     mn[2], mx[0], mx[1], mx[2]);
            /* names must be unique */
            walls[2 * a + side][10] = (char)('0' + 2 * a + side);
        }
    }
    char json[4000];
    snprintf(json, sizeof json,
             "{\"name\": \"energy\", \"seed\": 3, \"allow_unstable_dt\": true,"
             " \"time\": {\"dt\": 2e-6, \"duration\": 1, \"output_interval\": 1},"
             " \"gravity\": [0, 0, 0],"
             " \"materials\": {\"m\": {\"density\": 2600, \"youngs_modulus\": 1e7, "
             "\"poisson_ratio\": 0.25}},"
             " \"interactions\": [{\"between\": [\"m\", \"m\"], \"friction\": 0, \"damping\": 0}],"
             " \"shapes\": {\"s\": {\"builtin\": \"icosphere\", \"triangles\": 320}},"
             " \"particles\": ["
             "{\"shape\": \"s\", \"material\": \"m\", \"count\": 8, \"size\": 0.01, \"region\": "
             "{\"min\": [0, 0, 0], \"max\": [0.04, 0.04, 0.04]}, \"orientation\": \"random\", "
             "\"velocity\": [3, 0.4, 0.2]},"
             "{\"shape\": \"s\", \"material\": \"m\", \"count\": 8, \"size\": 0.01, \"region\": "
             "{\"min\": [0.06, 0, 0], \"max\": [0.1, 0.04, 0.04]}, \"orientation\": \"random\", "
             "\"velocity\": [-3, -0.3, 0.5]}],"
             " \"walls\": [%s, %s, %s, %s, %s, %s]}",
             walls[0], walls[1], walls[2], walls[3], walls[4], walls[5]);
    run r;
    if (start(&r, json)) return;
    double mass[16], inertia[48];
    memcpy(mass, r.m->p->mass, sizeof mass);
    memcpy(inertia, r.m->p->inertia, sizeof inertia);
    double ke0 = 0;
    for (int i = 0; i < 16; i++)
        ke0 += 0.5 * mass[i] *
               (r.m->p->v[3 * i] * r.m->p->v[3 * i] + r.m->p->v[3 * i + 1] * r.m->p->v[3 * i + 1] +
                r.m->p->v[3 * i + 2] * r.m->p->v[3 * i + 2]);
    int collisions = 0, was = 0, i;
    double ke = 0;
    for (i = 0; i < 40000; i++) {
        if (step(&r)) break;
        double info[512];
        int np = r.m->npairs < 512 ? r.m->npairs : 512, touching = 0;
        if (np) get_info(&r, (size_t)np, info);
        for (int c = 0; c < np; c++)
            touching += info[c] >= 0;
        if (touching && !was) collisions++;
        was = touching > 0;
        if (i > 20000 && !touching) break;
    }
    double v[48], q[64], L[48];
    get(&r, r.m->v, 48, v);
    get(&r, r.m->q, 64, q);
    get(&r, r.m->L, 48, L);
    for (int p = 0; p < 16; p++) {
        ke += 0.5 * mass[p] *
              (v[3 * p] * v[3 * p] + v[3 * p + 1] * v[3 * p + 1] + v[3 * p + 2] * v[3 * p + 2]);
        double rm[3][3];
        pd_quat_to_matrix(q + 4 * p, rm);
        for (int k = 0; k < 3; k++) { /* 1/2 Lb_k^2 / I_k in the body frame */
            double lb = rm[0][k] * L[3 * p] + rm[1][k] * L[3 * p + 1] + rm[2][k] * L[3 * p + 2];
            ke += 0.5 * lb * lb / inertia[3 * p + k];
        }
    }
    printf("  %d steps, %d contact episodes: kinetic energy %.6f of the initial\n", i, collisions,
           ke / ke0);
    CHECK(collisions >= 3);
    CHECK_NEAR(1, ke / ke0, 0.01);
    finish(&r);
}

/*
 * Independent check of the pipeline on a rotating impact: a cube at a general orientation hits a
 * wall (volumetric Hertz, no damping, no friction). The reference integrates the same model on
 * the host with its own code: pd_overlap_host on world-space meshes (no narrow phase, no body
 * frames, no kernels), force 4/(3 sqrt(pi)) E* sqrt(V delta) at the overlap centroid, velocity
 * Verlet, and for the cube's isotropic inertia the exact free rotation q <- exp(L/I dt) q. Both
 * must end with the same velocity and angular momentum: 1e-6 relative covers round-off
 * amplified through the ~400 contact steps.
 *
 * The collision also shows that the thesis's model is not energy-conserving once impacts make
 * particles turn: the force acts at the overlap's centroid, not where a potential would put it,
 * so this impact ends with about 9% less kinetic energy (translation alone conserves it to 1e-8).
 */
static void q_mul(const double a[4], const double b[4], double o[4])
{
    o[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
    o[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
    o[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
    o[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
}

TEST(rotating_impact_matches_host_reference)
{
    const double size = 0.01, rho = 2600, E = 1e7, nu = 0.25, dt = 2e-6;
    const int nsteps = 2500;
    double side = cube_side(size), m = rho * side * side * side, I = m * side * side / 6;
    double es = E / (2 * (1 - nu * nu)), q0[4] = {0.8, 0.1, 0.5, 0.3}, qn = 0;
    for (int k = 0; k < 4; k++)
        qn += q0[k] * q0[k];
    for (int k = 0; k < 4; k++)
        q0[k] /= sqrt(qn);
    char json[1500];
    snprintf(json, sizeof json,
             "{\"name\": \"impact\", \"allow_unstable_dt\": true,"
             " \"time\": {\"dt\": %g, \"duration\": 1, \"output_interval\": 1},"
             " \"gravity\": [0, 0, 0],"
             " \"materials\": {\"m\": {\"density\": %g, \"youngs_modulus\": %g, \"poisson_ratio\": "
             "%g}},"
             " \"interactions\": [{\"between\": [\"m\", \"m\"], \"friction\": 0, \"damping\": 0}],"
             " \"shapes\": {\"c\": {\"builtin\": \"cube\"}},"
             " \"particles\": [{\"shape\": \"c\", \"material\": \"m\", \"list\": ["
             " {\"position\": [0, 0, 0], \"orientation\": [%.17g, %.17g, %.17g, %.17g], "
             "\"velocity\": [3, 0, 0], \"size\": %g}]}],"
             " \"walls\": [{\"name\": \"w\", \"material\": \"m\", \"box\": {\"min\": [0.01, -1, "
             "-1], \"max\": [0.1, 1, 1]}}]}",
             dt, rho, E, nu, q0[0], q0[1], q0[2], q0[3], size);
    run r;
    if (start(&r, json)) return;
    for (int i = 0; i < nsteps; i++)
        if (step(&r)) break;
    double v_dev[3], L_dev[3];
    get(&r, r.m->v, 3, v_dev);
    get(&r, r.m->L, 3, L_dev);
    finish(&r);

    /* the host reference */
    pd_mesh *cube = NULL, *wall = NULL;
    pd_error err = {0};
    if (pd_mesh_builtin("cube", 0, 0, &cube, &err) || pd_mesh_builtin("cube", 0, 0, &wall, &err)) {
        TEST_FAILF("%s", err.msg);
        pd_mesh_destroy(cube);
        pd_mesh_destroy(wall);
        return;
    }
    for (int i = 0; i < cube->nverts; i++)
        for (int k = 0; k < 3; k++) {
            cube->verts[3 * i + k] *= side;
            double *w = &wall->verts[3 * i + k]; /* unit cube -> [0.01, 0.1] x [-1, 1]^2 */
            *w = k == 0 ? 0.055 + 0.09 * *w : 2 * *w;
        }
    pd_pose pc = {{0, 0, 0}, {q0[0], q0[1], q0[2], q0[3]}}, pw = {{0, 0, 0}, {1, 0, 0, 0}};
    double v[3] = {3, 0, 0}, L[3] = {0, 0, 0}, f[3] = {0, 0, 0}, tq[3] = {0, 0, 0};
    for (int i = 0; i <= nsteps; i++) {
        if (i > 0) { /* kick, drift */
            for (int k = 0; k < 3; k++) {
                v[k] += f[k] / m * dt / 2;
                L[k] += tq[k] * dt / 2;
                pc.x[k] += v[k] * dt;
            }
            double phi[3] = {L[0] / I * dt, L[1] / I * dt, L[2] / I * dt};
            double a = sqrt(phi[0] * phi[0] + phi[1] * phi[1] + phi[2] * phi[2]);
            if (a > 0) {
                double dq[4] = {cos(a / 2), phi[0] / a * sin(a / 2), phi[1] / a * sin(a / 2),
                                phi[2] / a * sin(a / 2)},
                       qn2[4];
                q_mul(dq, pc.q, qn2);
                memcpy(pc.q, qn2, sizeof qn2);
            }
        }
        pd_contact c;
        if (pd_overlap_host(cube, &pc, wall, &pw, 0, &c, &err) != PD_OK) {
            TEST_FAILF("%s", err.msg);
            break;
        }
        double F = c.hit ? 4 / (3 * sqrt(PI)) * es * sqrt(c.volume * c.depth) : 0;
        for (int k = 0; k < 3; k++)
            f[k] = -F * c.normal[k]; /* on the cube: the normal points from it into the wall */
        double arm[3] = {c.centroid[0] - pc.x[0], c.centroid[1] - pc.x[1], c.centroid[2] - pc.x[2]};
        tq[0] = c.hit ? arm[1] * f[2] - arm[2] * f[1] : 0;
        tq[1] = c.hit ? arm[2] * f[0] - arm[0] * f[2] : 0;
        tq[2] = c.hit ? arm[0] * f[1] - arm[1] * f[0] : 0;
        if (i > 0)
            for (int k = 0; k < 3; k++) {
                v[k] += f[k] / m * dt / 2;
                L[k] += tq[k] * dt / 2;
            }
    }
    pd_mesh_destroy(cube);
    pd_mesh_destroy(wall);
    double ke0 = 0.5 * m * 9, ke_ref = 0.5 * m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) +
                                       0.5 * (L[0] * L[0] + L[1] * L[1] + L[2] * L[2]) / I;
    double lmag = sqrt(L[0] * L[0] + L[1] * L[1] + L[2] * L[2]);
    printf("  device v %.9f m/s, reference %.9f m/s; |L| %.6g kg m^2/s; kinetic energy after "
           "the impact %.4f of before\n",
           v_dev[0], v[0], lmag, ke_ref / ke0);
    CHECK(lmag > 0); /* the impact did make it turn */
    for (int k = 0; k < 3; k++) {
        CHECK_NEAR(v[k], v_dev[k], 1e-6 * 3);
        CHECK_NEAR(L[k], L_dev[k], 1e-6 * lmag);
    }
}

/*
 * Momentum conservation: free particles (no gravity, walls or fluid) colliding with friction,
 * damping and, for spheres, cohesion. Every contact force acts on its two particles equal and
 * opposite at one point, so the total linear momentum sum m v and the total angular momentum
 * about the origin, sum (x cross m v + L), are constant however much energy the contacts
 * dissipate; velocity Verlet keeps both exactly (a drift leaves x cross m v unchanged, and the
 * half-kicks add sum (x_i cross f_i + t_i) dt / 2 = sum over contacts (c cross F - c cross F),
 * and the contact moments, equal and opposite couples, cancel too).
 * A torque taken about a point other than the force's, a tangential force applied to one side
 * only, or a force gathered twice would show at once (the contacts' impulses are ~1e-3 of
 * the momenta's scale at least). What is left is rounding: each step rounds every velocity and
 * angular momentum to ~1e-16 of its value, so over ~1e5 particle-steps the sums drift by at most
 * ~1e-11 of their scale; 1e-9 leaves a hundredfold margin.
 */
#define MC_N 24
static void momentum_is_conserved(const char *label, const char *materials, const char *shapes,
                                  const char *const *shape_names, int nshapes, const char *walls,
                                  int nsteps)
{
    /* a cloud converging on the origin, each particle spinning (in a box: bursting towards the
     * walls, then coming back from them) */
    const double vr = walls ? 150 : -150;
    char parts[MC_N * 400 + 800] = "", json[sizeof parts + 2000];
    size_t len = 0;
    for (int g = 0; g < nshapes; g++) {
        len += (size_t)snprintf(parts + len, sizeof parts - len,
                                "%s{\"shape\": \"%s\", \"material\": \"m\", \"list\": [",
                                g ? ", " : "", shape_names[g]);
        for (int i = g; i < MC_N; i += nshapes) {
            /* on a jittered 3 x 3 x 3 lattice of pitch 0.016 m (less its centre), sizes 8-12 mm */
            int c = i + (i >= 13);
            double x[3], q[4], w[3], v[3];
            rnd3(x);
            x[0] = 0.016 * (c % 3 - 1) + 0.002 * (x[0] - 0.5);
            x[1] = 0.016 * (c / 3 % 3 - 1) + 0.002 * (x[1] - 0.5);
            x[2] = 0.016 * (c / 9 - 1) + 0.002 * (x[2] - 0.5);
            double s = 0.008 + 0.004 * rnd();
            rnd_quat(q);
            for (int k = 0; k < 3; k++)
                w[k] = 200 * (rnd() - 0.5);
            for (int k = 0; k < 3; k++)
                v[k] = vr * x[k] + 0.3 * (rnd() - 0.5);
            len += (size_t)snprintf(
                parts + len, sizeof parts - len,
                "%s{\"position\": [%.17g, %.17g, %.17g], \"orientation\": [%.17g, %.17g, %.17g, "
                "%.17g], \"velocity\": [%.17g, %.17g, %.17g], \"angular_velocity\": [%.17g, "
                "%.17g, %.17g], \"size\": %.17g}",
                i >= nshapes ? ", " : "", x[0], x[1], x[2], q[0], q[1], q[2], q[3], v[0], v[1],
                v[2], w[0], w[1], w[2], s);
        }
        len += (size_t)snprintf(parts + len, sizeof parts - len, "]}");
    }
    const double dt = 2e-6, g = walls ? -9.81 : 0;
    snprintf(json, sizeof json,
             "{\"name\": \"momentum\", \"time\": {\"dt\": %g, \"duration\": 1, "
             "\"output_interval\": 1}, \"gravity\": [0, 0, %g], %s,"
             " \"shapes\": {%s}, \"particles\": [%s]%s%s}",
             dt, g, materials, shapes, parts, walls ? ", \"walls\": " : "", walls ? walls : "");
    run r;
    if (start(&r, json)) return;
    int n = r.m->p->n;
    double mass[MC_N];
    memcpy(mass, r.m->p->mass, sizeof mass);
    double P0[3], L0[3], P[3], L[3], scale_p = 0, scale_l = 0, total_m = 0;
    /* with walls: the impulse the particles gave the walls, by the trapezoid rule that velocity
     * Verlet's two half-kicks make of the forces at the step's two ends, and its scale */
    double wf[2][3 * 6] = {{0}}, J[3] = {0, 0, 0}, scale_j = 0;
    int nw = r.m->nwall, touching_steps = 0, most = 0;
    for (int p = 0; p < n; p++)
        total_m += mass[p];
    for (int i = 0; i <= nsteps; i++) {
        if (i > 0 && step(&r)) break;
        if (nw > 0) {
            long contacts;
            double ratio, *now = wf[i % 2], *before = wf[(i + 1) % 2];
            pd_error err = {0};
            if (nw > 6 || sim_stats_contacts(r.m, &contacts, &ratio, now, &err) != PD_OK) {
                TEST_FAILF("wall forces: %s", nw > 6 ? "more than 6 walls" : err.msg);
                break;
            }
            for (int w = 0; i > 0 && w < nw; w++)
                for (int k = 0; k < 3; k++) {
                    J[k] += 0.5 * dt * (before[3 * w + k] + now[3 * w + k]);
                    scale_j += 0.5 * dt * (fabs(before[3 * w + k]) + fabs(now[3 * w + k]));
                }
        }
        if (i % 50 == 0 && r.m->npairs > 0) {
            double info[4096];
            int np = r.m->npairs < 4096 ? r.m->npairs : 4096, touching = 0;
            get_info(&r, (size_t)np, info);
            for (int c = 0; c < np; c++)
                touching += info[c] >= 0;
            touching_steps += touching > 0;
            most = touching > most ? touching : most;
        }
        if (i != 0 && i != nsteps) continue;
        double x[3 * MC_N], v[3 * MC_N], Lb[3 * MC_N];
        get(&r, r.m->x, 3 * (size_t)n, x);
        get(&r, r.m->v, 3 * (size_t)n, v);
        get(&r, r.m->L, 3 * (size_t)n, Lb);
        double *pp = i ? P : P0, *ll = i ? L : L0;
        for (int k = 0; k < 3; k++)
            pp[k] = ll[k] = 0;
        for (int p = 0; p < n; p++) {
            double mv[3] = {mass[p] * v[3 * p], mass[p] * v[3 * p + 1], mass[p] * v[3 * p + 2]},
                   *xp = x + 3 * p;
            double xl[3] = {xp[1] * mv[2] - xp[2] * mv[1], xp[2] * mv[0] - xp[0] * mv[2],
                            xp[0] * mv[1] - xp[1] * mv[0]};
            for (int k = 0; k < 3; k++) {
                pp[k] += mv[k];
                ll[k] += xl[k] + Lb[3 * p + k];
            }
            if (i == 0) {
                scale_p += sqrt(mv[0] * mv[0] + mv[1] * mv[1] + mv[2] * mv[2]);
                scale_l += sqrt(xl[0] * xl[0] + xl[1] * xl[1] + xl[2] * xl[2]) +
                           sqrt(Lb[3 * p] * Lb[3 * p] + Lb[3 * p + 1] * Lb[3 * p + 1] +
                                Lb[3 * p + 2] * Lb[3 * p + 2]);
            }
        }
    }
    double dp = 0, dl = 0;
    for (int k = 0; k < 3; k++) {
        /* the walls took J from the particles, gravity gave them M g t */
        double expect = P0[k] - J[k] + (k == 2 ? total_m * g * dt * nsteps : 0);
        dp = fmax(dp, fabs(P[k] - expect));
        dl = fmax(dl, fabs(L[k] - L0[k]));
    }
    scale_p += scale_j + total_m * fabs(g) * dt * nsteps;
    printf("  %s: %d particles, %d steps, contacts seen in %d of %d samples (at most %d at once); "
           "momentum drift %.2e of sum |m v| = %.4g kg m/s",
           label, n, nsteps, touching_steps, nsteps / 50 + 1, most, dp / scale_p, scale_p);
    if (nw == 0) /* (the walls' torques are not read) */
        printf(", angular momentum drift %.2e of %.4g kg m^2/s", dl / scale_l, scale_l);
    printf("\n");
    CHECK(touching_steps >= 10 && most >= 10); /* the cloud did collide, in many pairs at once */
    CHECK(dp <= 1e-9 * scale_p);
    if (nw > 0) { /* the walls pushed hard enough to count, and their torques are not checked */
        printf("  the walls took %.4g kg m/s (sum of |F| dt %.4g), gravity gave %.4g\n",
               sqrt(J[0] * J[0] + J[1] * J[1] + J[2] * J[2]), scale_j,
               total_m * fabs(g) * dt * nsteps);
        CHECK(scale_j > 0.1 * scale_p);
    } else {
        CHECK(dl <= 1e-9 * scale_l);
    }
    finish(&r);
}

TEST(momentum_is_conserved_by_polyhedra)
{
    static const char *const names[] = {"s", "r", "i"};
    momentum_is_conserved(
        "Schonhardt prisms, rocks, icospheres; friction 0.5, damping 0.3",
        "\"materials\": {\"m\": {\"density\": 2600, \"youngs_modulus\": 1e7, \"poisson_ratio\": "
        "0.25}},"
        " \"interactions\": [{\"between\": [\"m\", \"m\"], \"friction\": 0.5, \"damping\": 0.3}]",
        "\"s\": {\"builtin\": \"schonhardt\"}, \"r\": {\"builtin\": \"rock\", \"triangles\": 80}, "
        "\"i\": {\"builtin\": \"icosphere\", \"triangles\": 80}",
        names, 3, NULL, 3000);
}

TEST(momentum_is_conserved_by_spheres)
{
    static const char *const names[] = {"b"};
    momentum_is_conserved(
        "spheres, linear model with friction 0.5, damping and cohesion",
        "\"materials\": {\"m\": {\"density\": 2600, \"youngs_modulus\": 1e7, \"poisson_ratio\": "
        "0.25}},"
        " \"interactions\": [{\"between\": [\"m\", \"m\"], \"friction\": 0.5, \"model\": "
        "\"linear\", \"normal_stiffness\": 2e4, \"tangential_stiffness\": 1e4, "
        "\"damping_coefficient\": 0.5, \"cohesion\": 2e3, \"cohesion_range\": 0.001}]",
        "\"b\": {\"sphere\": {}}", names, 1, NULL, 3000);
}

/*
 * The same cloud inside a closed box, under gravity: the particles' momentum changes by what
 * gravity gives them less the impulse of the walls' load cells (/stats/wall_force: the force the
 * particles exert on each wall), so the load cells must read every contact's force with its sign,
 * on the right wall. Same rounding bound (the impulses add to the scale).
 */
TEST(wall_forces_balance_momentum)
{
    static const char *const names[] = {"s", "r", "i"};
    /* still walls, then the lid pressing down and one side wall turning about its own centre */
    for (int moving = 0; moving < 2; moving++) {
        char walls[6][320], all[2000];
        const double lo = -0.03, hi = 0.03, t = 0.02;
        for (int w = 0; w < 6; w++) {
            int a = w / 2;
            double mn[3] = {lo - t, lo - t, lo - t}, mx[3] = {hi + t, hi + t, hi + t};
            if (w % 2 == 0)
                mx[a] = lo;
            else
                mn[a] = hi;
            const char *motion = !moving  ? ""
                                 : w == 5 ? ", \"velocity\": [0, 0, -0.5]"
                                 : w == 0 ? ", \"angular_velocity\": [0, 0, 2], \"center\": "
                                            "[-0.04, 0, 0]"
                                          : "";
            snprintf(walls[w], sizeof walls[w],
                     "{\"name\": \"w%d\", \"material\": \"m\", \"box\": {\"min\": [%g, %g, "
                     "%g], \"max\": [%g, %g, %g]}%s}",
                     w, mn[0], mn[1], mn[2], mx[0], mx[1], mx[2], motion);
        }
        snprintf(all, sizeof all, "[%s, %s, %s, %s, %s, %s]", walls[0], walls[1], walls[2],
                 walls[3], walls[4], walls[5]);
        momentum_is_conserved(
            moving ? "the cloud in a closed box under gravity, the lid and a side moving"
                   : "the cloud in a closed box under gravity",
            "\"materials\": {\"m\": {\"density\": 2600, \"youngs_modulus\": 1e7, "
            "\"poisson_ratio\": 0.25}},"
            " \"interactions\": [{\"between\": [\"m\", \"m\"], \"friction\": 0.5, \"damping\": "
            "0.3}]",
            "\"s\": {\"builtin\": \"schonhardt\"}, \"r\": {\"builtin\": \"rock\", \"triangles\": "
            "80}, \"i\": {\"builtin\": \"icosphere\", \"triangles\": 80}",
            names, 3, all, 6000);
    }
}

/*
 * A moving wall: a box wall advancing at V hits a sphere at rest; with no damping the collision
 * is elastic in the wall's frame, so the sphere leaves at 2 V (the wall's mass is infinite).
 * Hertz resolved with ~100 steps per contact: 1e-3 relative.
 */
TEST(moving_wall_pushes_sphere)
{
    const double V = 0.3, R = 0.01;
    char json[1500];
    snprintf(json, sizeof json,
             "{\"name\": \"piston\", \"allow_unstable_dt\": true,"
             " \"time\": {\"dt\": 2e-6, \"duration\": 1, \"output_interval\": 1},"
             " \"gravity\": [0, 0, 0],"
             " \"materials\": {\"m\": {\"density\": 2500, \"youngs_modulus\": 1e7, "
             "\"poisson_ratio\": 0.25}},"
             " \"interactions\": [{\"between\": [\"m\", \"m\"], \"friction\": 0, \"damping\": 0}],"
             " \"shapes\": {\"ball\": {\"sphere\": {}}},"
             " \"particles\": [{\"shape\": \"ball\", \"material\": \"m\", \"list\": ["
             " {\"position\": [0, 0, 0], \"size\": %g}]}],"
             " \"walls\": [{\"name\": \"piston\", \"material\": \"m\", \"velocity\": [%g, 0, 0],"
             " \"box\": {\"min\": [-0.2, -0.1, -0.1], \"max\": [%g, 0.1, 0.1]}}]}",
             2 * R, V, -R - 1e-4);
    run r;
    if (start(&r, json)) return;
    for (int i = 0; i < 3000; i++)
        if (step(&r)) break;
    double v[3];
    get(&r, r.m->v, 3, v);
    printf("  sphere leaves at %.6f m/s (2 V = %.6f m/s)\n", v[0], 2 * V);
    CHECK_NEAR(2 * V, v[0], 1e-3 * 2 * V);
    finish(&r);
}

/*
 * Twisting friction (contact_moments; kernels/contact_force.h, cf_twist): a cube spinning about
 * the vertical on a floor, its contact point under its centre so that no sliding resists the
 * spin, slows at the Coulomb limit M = 3 pi/16 mu m g a of a disc of radius a = sqrt(V /
 * (pi delta)) = side / sqrt(pi) (a flat contact's V = side^2 delta): alpha = M / I with
 * I = m side^2 / 6, so it stops after w0 / alpha, turned by w0^2 / (2 alpha). Tolerances: 1 % on
 * the rate while sliding (the normal force is m g to the contact's small settling), 3 % on the
 * angle (the spring's wind-up at the start and its few steps of creep at the end). With the
 * moments off (the thesis's point contact) only the wandering of the contact point slows the spin
 * (a tilt of 1e-4 rad moves a resting cube's overlap centroid by 2 mm off its axis, where
 * friction then acts): it measured 1.8 rad/s after 40 ms, where twisting friction stops it in 16.
 */
TEST(cube_spin_stops_by_twisting_friction)
{
    const double d = 0.02, a = cube_side(d), rho = 2500, E = 1e7, nu = 0.25, mu = 0.5, g = 9.81;
    const double w0 = 10, dt = 1e-5;
    double m = rho * a * a * a, I = m * a * a / 6;
    double estar = E / (2 * (1 - nu * nu));
    /* resting depth: m g = 4/(3 sqrt(pi)) E* sqrt(V delta) with V = a^2 delta */
    double depth = m * g * 3 * sqrt(PI) / (4 * estar * a);
    double mlim = 3 * PI / 16 * mu * m * g * a / sqrt(PI), alpha = mlim / I;
    for (int moments = 1; moments >= 0; moments--) {
        char json[1500];
        snprintf(json, sizeof json,
                 "{\"name\": \"spin\", \"time\": {\"dt\": %g, \"duration\": 1, "
                 "\"output_interval\": 1},"
                 " \"materials\": {\"m\": {\"density\": %g, \"youngs_modulus\": %g, "
                 "\"poisson_ratio\": %g}},"
                 " \"interactions\": [{\"between\": [\"m\", \"m\"], \"friction\": %g, "
                 "\"damping\": 0.5, \"contact_moments\": %s}],"
                 " \"shapes\": {\"c\": {\"builtin\": \"cube\"}},"
                 " \"particles\": [{\"shape\": \"c\", \"material\": \"m\", \"list\": ["
                 " {\"position\": [0, 0, %.12g], \"angular_velocity\": [0, 0, %g], "
                 "\"size\": %g}]}],"
                 " \"walls\": [{\"name\": \"floor\", \"material\": \"m\", \"box\": {\"min\": "
                 "[-0.1, -0.1, -0.02], \"max\": [0.1, 0.1, 0]}}]}",
                 dt, rho, E, nu, mu, moments ? "true" : "false", 0.5 * a - depth, w0, d);
        run r;
        if (start(&r, json)) return;
        double L[3], q[4], wz[2] = {0, 0};
        int marks[2] = {200, 1200}; /* 2 ms and 12 ms: both while sliding (stop at ~16 ms) */
        for (int i = 1, k = 0; i <= 4000; i++) {
            if (step(&r)) break;
            if (k < 2 && i == marks[k]) {
                get(&r, r.m->L, 3, L);
                wz[k++] = L[2] / I;
            }
        }
        get(&r, r.m->L, 3, L);
        get(&r, r.m->q, 4, q);
        double turned = 2 * atan2(q[3], q[0]), rate = (wz[0] - wz[1]) / (1000 * dt);
        if (moments) {
            printf("  slowing at %.2f rad/s^2 (M / I = %.2f); stopped at %.3g rad/s, turned "
                   "%.5f rad (w0^2 / (2 alpha) = %.5f)\n",
                   rate, alpha, L[2] / I, turned, w0 * w0 / (2 * alpha));
            CHECK_NEAR(alpha, rate, 0.01 * alpha);
            CHECK(fabs(L[2] / I) < 1e-3 * w0);
            CHECK_NEAR(w0 * w0 / (2 * alpha), turned, 0.03 * w0 * w0 / (2 * alpha));
        } else {
            printf("  without contact moments: %.6f rad/s after 40 ms (w0 = %g)\n", L[2] / I, w0);
            CHECK(L[2] / I > 0.1 * w0);
        }
        finish(&r);
    }
}

/*
 * A turning wall: a cube resting on a table that turns at W about z (through the origin), with
 * friction enough to hold it (mu g = 4.9 m/s^2 against the W^2 r = 0.4 m/s^2 it needs), is carried
 * round with it once it has caught up: its centre moves at W r, across the radius. The table's
 * surface moves at W x r, so this checks the wall's contact velocity. Tolerance 1 %: the
 * tangential spring that holds the cube gives a little (a creep of ~2e-3 of the speed was
 * measured) and the spin-up takes ~0.05 s of the 0.3 s. The cube also turns with the table
 * about its own axis, at W to 1 %: twisting friction (contact_moments) carries it. (The thesis's
 * point contact, the overlap's centroid nearly under the cube's centre, does not resist a turn
 * about the normal: without the contact moments the cube ended at 1.05 rad/s, not W = 2.)
 */
TEST(cube_rides_a_turntable)
{
    const double W = 2, r0 = 0.1, d = 0.02, a = d * cbrt(PI / 6); /* a: the cube's side */
    char json[1500];
    snprintf(json, sizeof json,
             "{\"name\": \"turntable\", \"time\": {\"dt\": 1e-5, \"duration\": 1, "
             "\"output_interval\": 1},"
             " \"materials\": {\"m\": {\"density\": 2500, \"youngs_modulus\": 1e7}},"
             " \"interactions\": [{\"between\": [\"m\", \"m\"], \"friction\": 0.5, \"damping\": "
             "0.5}],"
             " \"shapes\": {\"c\": {\"builtin\": \"cube\"}},"
             " \"particles\": [{\"shape\": \"c\", \"material\": \"m\", \"list\": ["
             " {\"position\": [%g, 0, %.9g], \"size\": %g}]}],"
             " \"walls\": [{\"name\": \"table\", \"material\": \"m\", \"angular_velocity\": [0, 0, "
             "%g], \"box\": {\"min\": [-0.3, -0.3, -0.02], \"max\": [0.3, 0.3, 0]}}]}",
             r0, 0.5 * a - 1e-6, d, W);
    run r;
    if (start(&r, json)) return;
    for (int i = 0; i < 30000; i++)
        if (step(&r)) break;
    double x[3], v[3], L[3];
    get(&r, r.m->x, 3, x);
    get(&r, r.m->v, 3, v);
    get(&r, r.m->L, 3, L);
    double m = 2500 * a * a * a, spin = L[2] / (m * a * a / 6);
    double rad = hypot(x[0], x[1]), speed = hypot(v[0], v[1]);
    double along = (x[0] * v[0] + x[1] * v[1]) / rad; /* radial velocity */
    double turn = atan2(x[1], x[0]);                  /* how far round it has gone */
    printf("  at r = %.5f m: speed %.5f m/s (W r = %.5f), radial %.2e m/s, turned %.4f rad "
           "(the table %.4f), spinning at %.5f rad/s\n",
           rad, speed, W * rad, along, turn, W * 0.3, spin);
    CHECK_NEAR(W, spin, 0.01 * W);
    CHECK_NEAR(W * rad, speed, 0.01 * W * rad);
    CHECK_NEAR(0, along, 0.01 * W * rad);
    CHECK_NEAR(r0, rad, 0.01 * r0);
    /* behind the table by what the spin-up lost, less than its first 0.05 s of turning */
    CHECK(turn < W * 0.3 && turn > W * 0.25);
    finish(&r);
}

/*
 * Particles whose pairs reach OVL_CLUSTER_MIN vertices use the overlap filter's vertex clusters
 * (engine/vertex_clusters.c, np_shapes' vc, coff, disc); they only spare projections, so a
 * glancing, spinning collision of two 2500-triangle rocks with friction and damping ends bit
 * for bit where it ends without them (the cluster table released: NULL in the kernel), in
 * either precision. With the discs zeroed it ends elsewhere: the contact stage reads them.
 */
static int rock_collision(const char *precision, int variant, double *state)
{
    const double R = 0.05, E = 1e7, nu = 0.25, rho = 2600, v = 2;
    double m = rho * 4.0 / 3 * PI * R * R * R, es = E / (2 * (1 - nu * nu));
    double tc = 2.8683 * pow(m * m / 4 / (R / 2 * es * es * 2 * v), 0.2), dt = tc / 200;
    char json[1800];
    snprintf(json, sizeof json,
             "{\"name\": \"rocks\", \"precision\": \"%s\", \"allow_unstable_dt\": true,"
             " \"time\": {\"dt\": %.17g, \"duration\": 1, \"output_interval\": 1},"
             " \"gravity\": [0, 0, 0],"
             " \"materials\": {\"m\": {\"density\": %g, \"youngs_modulus\": %g, \"poisson_ratio\": "
             "%g}},"
             " \"interactions\": [{\"between\": [\"m\", \"m\"], \"friction\": 0.5, \"damping\": "
             "0.3}],"
             " \"shapes\": {\"r\": {\"builtin\": \"rock\", \"triangles\": 2500}},"
             " \"particles\": [{\"shape\": \"r\", \"material\": \"m\", \"list\": ["
             " {\"position\": [0, 0, 0], \"orientation\": [0.8, 0.1, 0.5, 0.3], \"velocity\": "
             "[%g, 0, 0], \"angular_velocity\": [0, 20, 40], \"size\": %g},"
             " {\"position\": [%.17g, %g, 0], \"orientation\": [0.3, -0.7, 0.2, 0.6], "
             "\"velocity\": [%g, 0, 0], \"size\": %g}]}]}",
             precision, dt, rho, E, nu, v, 2 * R, 2 * R + 2 * v * 10 * dt + 0.004, 0.4 * R, -v,
             2 * R);
    run r;
    if (start(&r, json)) return -1;
    if (variant == 1) { /* no clusters */
        clReleaseMemObject(r.m->vc);
        r.m->vc = NULL;
    } else if (variant == 2) { /* discs zeroed */
        size_t bytes = 0;
        cl_int e = clGetMemObjectInfo(r.m->disc, CL_MEM_SIZE, sizeof bytes, &bytes, NULL);
        if (e == CL_SUCCESS) e = sim_zero_reals(r.m, r.m->disc, bytes / r.m->rs);
        if (e != CL_SUCCESS) TEST_FAILF("zeroing the discs: OpenCL error %d", (int)e);
    }
    int touching = 0;
    for (int i = 0; i < 300; i++) {
        if (step(&r)) break;
        double info[1] = {-1};
        if (r.m->npairs > 0) get_info(&r, 1, info);
        touching += info[0] >= 0;
    }
    get(&r, r.m->x, 6, state);
    get(&r, r.m->q, 8, state + 6);
    get(&r, r.m->v, 6, state + 14);
    get(&r, r.m->L, 6, state + 20);
    finish(&r);
    return touching;
}

TEST(large_meshes_collide_the_same_with_filter_clusters)
{
    static const char *const prec[2] = {"double", "single"};
    for (int p = 0; p < 2; p++) {
        double with[26], without[26], zeroed[26];
        int t0 = rock_collision(prec[p], 0, with), t1 = rock_collision(prec[p], 1, without),
            t2 = rock_collision(prec[p], 2, zeroed);
        printf("  %s: in contact %d steps; final |v| %.9g m/s, |L| %.6g kg m^2/s; with the discs "
               "zeroed in contact %d steps\n",
               prec[p], t0, sqrt(with[14] * with[14] + with[15] * with[15] + with[16] * with[16]),
               sqrt(with[20] * with[20] + with[21] * with[21] + with[22] * with[22]), t2);
        CHECK(t0 >= 20); /* they did collide */
        CHECK_EQ_INT(t0, t1);
        CHECK(memcmp(with, without, sizeof with) == 0);
        CHECK(memcmp(with, zeroed, sizeof with) != 0);
    }
}

int main(void)
{
    pd_error err = {0};
    if (pd_device_open(-1, &dev, &err) != PD_OK) {
        printf("no OpenCL device: %s\n0 passed, 1 failed\n", err.msg);
        return 1;
    }
    RUN(device_selftest);
    RUN(linear_restitution_and_duration);
    RUN(sphere_settles_on_floor);
    RUN(sphere_settles_on_a_finely_meshed_floor);
    RUN(cube_rests_flat_on_wall);
    RUN(u_rests_on_two_separate_places);
    RUN(cube_slides_to_rest);
    RUN(sphere_rolls_or_slides_down_an_incline);
    RUN(cube_holds_or_slides_on_an_incline);
    RUN(cube_slides_to_rest_on_a_cube);
    RUN(cube_slides_on_a_finely_meshed_floor);
    RUN(particle_inside_wall_is_refused);
    RUN(stokes_drag_relaxation);
    RUN(moving_wall_pushes_sphere);
    RUN(cube_rides_a_turntable);
    RUN(cube_spin_stops_by_twisting_friction);
    RUN(cohesion_stickiness_threshold);
    RUN(icosphere_collision_like_hertz_sphere);
    RUN(energy_is_conserved_without_damping);
    RUN(rotating_impact_matches_host_reference);
    RUN(momentum_is_conserved_by_polyhedra);
    RUN(momentum_is_conserved_by_spheres);
    RUN(wall_forces_balance_momentum);
    RUN(bit_identical_reruns);
    RUN(bit_identical_reruns_with_separate_places);
    RUN(pair_list_reuse_is_exact);
    RUN(gap_search_waits_are_exact);
    RUN(moving_wall_list_reuse_is_exact);
    RUN(single_matches_double);
    RUN(single_precision_finds_a_contact_in_far_places);
    RUN(single_precision_flat_face_on_a_meshed_floor);
    RUN(divergence_is_reported);
    RUN(stats_rows_match_host_sums);
    RUN(memory_per_particle_is_bounded);
    RUN(large_meshes_collide_the_same_with_filter_clusters);
    pd_device_close(dev);
    return TEST_DONE();
}
