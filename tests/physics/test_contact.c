/*
 * test_contact.c - the contact force laws of kernels/contact_force.h against analytic collisions.
 *
 * Each test integrates a head-on collision with velocity Verlet (thesis section 3.4) at a time
 * step of 1/2000 of the analytic contact time, so the integration error of durations and peaks is
 * O(1e-3) relative (the collision's first and last steps are resolved to dt/t_c = 5e-4); the
 * tolerances below are 2e-3 for those, unless stated otherwise.
 */
#define PD_DOUBLE 1
#include <string.h>

#include "contact_force.h"
#include "polydem.h"
#include "test.h"

static const double PI = 3.14159265358979323846;

/* A 1D head-on collision: x is the gap-closing coordinate (overlap delta = x while x > 0), m the
 * effective mass, force(delta, vn) the repulsive normal force. Returns the contact duration, the
 * peak overlap and the separation speed. */
typedef double (*normal_law)(const void *ctx, double delta, double vn);

static void collide(normal_law law, const void *ctx, double m, double v0, double dt, double *t_c,
                    double *peak, double *v_out)
{
    double x = 0, v = v0, a = 0, t = 0;
    *peak = 0;
    for (long step = 0; step < 100000000; step++) {
        v += 0.5 * a * dt; /* velocity Verlet: kick, drift, force, kick */
        x += v * dt;
        t += dt;
        a = x > 0 ? -law(ctx, x, v) / m : 0;
        v += 0.5 * a * dt;
        if (x > *peak) *peak = x;
        if (x <= 0 && t > dt) break;
    }
    /* place the separation at the zero crossing inside the last step */
    *t_c = t - (-x) / (v < 0 ? -v : 1e300);
    *v_out = v;
}

typedef struct {
    double estar, rstar, mstar, gamma;
} hertz_ctx;

static double hertz_law(const void *p, double delta, double vn)
{
    const hertz_ctx *c = p;
    double kn;
    return cf_hertz_sphere_normal(c->estar, c->rstar, delta, c->mstar, c->gamma, vn, &kn);
}

TEST(hertz_spheres_duration_and_peak_overlap)
{
    /* two equal glass-like spheres, R = 0.1 m, E = 1 MPa, nu = 0.25, 5 m/s each (thesis 6.1):
     * peak delta = (15 m* v^2 / (16 E* sqrt(R*)))^(2/5), t_c = 2.9432 delta_max / v (Hertz;
     * Johnson, Contact Mechanics, section 11.4: 2.9432 = 2 int_0^1 (1 - x^(5/2))^(-1/2) dx) */
    double R = 0.1, E = 1e6, nu = 0.25, rho = 2600, v = 10;
    double m = rho * 4.0 / 3.0 * PI * R * R * R;
    hertz_ctx c = {cf_effective_modulus(E, nu, E, nu), R / 2, cf_effective_mass(1 / m, 1 / m), 0};
    double peak = pow(15 * c.mstar * v * v / (16 * c.estar * sqrt(c.rstar)), 0.4);
    double tc = 2.9432 * peak / v;
    double t_c, pk, vout;
    collide(hertz_law, &c, c.mstar, v, tc / 2000, &t_c, &pk, &vout);
    CHECK_REL(peak, pk, 2e-3);
    CHECK_REL(tc, t_c, 2e-3);
    CHECK_REL(v, -vout, 2e-3); /* undamped: elastic rebound */
}

TEST(hertz_damping_dissipates_and_is_monotone)
{
    double R = 0.01, E = 2e7, nu = 0.25, m = 1e-2, v = 1;
    double e_prev = 1.0;
    double gammas[] = {0.05, 0.2, 0.382097};
    for (int i = 0; i < 3; i++) {
        hertz_ctx c = {cf_effective_modulus(E, nu, E, nu), R / 2, m / 2, gammas[i]};
        double t_c, pk, vout;
        collide(hertz_law, &c, c.mstar, v, 1e-7, &t_c, &pk, &vout);
        double e = -vout / v;
        CHECK(e > 0 && e < e_prev);
        e_prev = e;
    }
}

typedef struct {
    double ke, eta;
} linear_ctx;

static double linear_law(const void *p, double delta, double vn)
{
    const linear_ctx *c = p;
    return cf_linear_normal(c->ke, c->eta, delta, vn);
}

TEST(linear_model_restitution_and_duration)
{
    /* seed 004 A.2, A.3: a = -eta/(2m), b = sqrt(4 m ke - eta^2)/(2m), t_col = pi/b,
     * e = exp(a pi / b) */
    double m = 2e-3, ke = 1e4;
    double etas[] = {0, 0.1, 0.5};
    for (int i = 0; i < 3; i++) {
        linear_ctx c = {ke, etas[i]};
        double a = -c.eta / (2 * m), b = sqrt(4 * m * ke - c.eta * c.eta) / (2 * m);
        double tcol = PI / b, e = exp(a * PI / b);
        double t_c, pk, vout;
        collide(linear_law, &c, m, 1.0, tcol / 2000, &t_c, &pk, &vout);
        CHECK_REL(tcol, t_c, 2e-3);
        CHECK_REL(e, -vout / 1.0, 2e-3);
    }
}

/* The volumetric law on two real polyhedral icospheres, head-on along x, translation only. */
typedef struct {
    pd_mesh *m;
    double estar, mstar;
    pd_pose pa, pb;
    double sep0;
} poly_ctx;

static double poly_law(const void *p, double delta, double vn)
{
    const poly_ctx *c = p;
    pd_pose pb = c->pb;
    pb.x[0] = c->sep0 - delta; /* closing the gap by delta */
    pd_contact k;
    pd_error err = {0};
    if (pd_overlap_host(c->m, &c->pa, c->m, &pb, 0, &k, &err) != PD_OK || !k.hit) return 0;
    double kn;
    /* force along x only: the icospheres' faceted normal is within a few degrees of x */
    return cf_hertz_volume_normal(c->estar, k.volume, k.depth, c->mstar, 0, vn, &kn) * k.normal[0];
}

TEST(polyhedral_spheres_follow_hertz)
{
    /* thesis section 6.1 / figure 6.2: 1280-triangle icospheres of R = 0.1 m, E = 21.5 MPa,
     * volume-normalised, closing at 1 m/s (peak overlap ~5 % of R; the thesis's 1 MPa at 10 m/s
     * indents by about a radius, outside the small-overlap assumption of eq. 4.14). The volumetric
     * model reproduces the Hertz sphere through V ~ pi delta^2 R*; faceting and that
     * approximation leave a few percent (the order of the thesis's figure 6.4): 5 % on peak depth
     * and duration. */
    double R = 0.1, E = 21.5e6, nu = 0.25, rho = 2600, v = 1;
    pd_error err = {0};
    poly_ctx c;
    memset(&c, 0, sizeof c);
    CHECK(pd_mesh_builtin("icosphere", 1280, 0, &c.m, &err) == PD_OK);
    if (!c.m) return;
    pd_mass_props mp;
    pd_mesh_mass_props(c.m, &mp);
    double s = R * cbrt(4.0 / 3.0 * PI / mp.volume);
    for (int i = 0; i < 3 * c.m->nverts; i++)
        c.m->verts[i] *= s;
    double m = rho * 4.0 / 3.0 * PI * R * R * R;
    c.estar = cf_effective_modulus(E, nu, E, nu);
    c.mstar = m / 2;
    pd_pose pa = {{0, 0, 0}, {0.9, 0.1, -0.3, 0.2}}, pb = {{0, 0, 0}, {0.3, 0.7, 0.5, -0.4}};
    c.pa = pa;
    c.pb = pb;
    /* start where the faceted shapes just touch: bisect the separation */
    double lo = 1.5 * R, hi = 2.5 * R;
    for (int it = 0; it < 60; it++) {
        double mid = 0.5 * (lo + hi);
        c.sep0 = mid;
        if (poly_law(&c, 0, 0) > 0)
            lo = mid;
        else
            hi = mid;
    }
    c.sep0 = hi;
    hertz_ctx h = {c.estar, R / 2, c.mstar, 0};
    double peak = pow(15 * h.mstar * v * v / (16 * h.estar * sqrt(h.rstar)), 0.4);
    double tc = 2.9432 * peak / v;
    double t_c, pk, vout;
    collide(poly_law, &c, c.mstar, v, tc / 400, &t_c, &pk, &vout);
    printf("  icosphere 1280: peak %.5g m (Hertz %.5g), duration %.5g s (Hertz %.5g)\n", pk, peak,
           t_c, tc);
    CHECK_REL(peak, pk, 0.05);
    CHECK_REL(tc, t_c, 0.05);
    CHECK_REL(v, -vout, 0.02); /* undamped: the energy comes back */
    pd_mesh_destroy(c.m);
}

TEST(tangential_spring_sticks_then_slides)
{
    /* a constant tangential displacement rate: elastic (F = kt d) until the Coulomb limit mu F_n,
     * then sliding at the limit (eqs. 4.8, 4.12, 4.13) */
    pd_v3 spring = v3(0, 0, 0), n = v3(0, 0, 1);
    double kt = 1e4, mu = 0.5, fn = 10, step = 1e-5;
    double slip_at = mu * fn / kt; /* displacement where the spring reaches the limit */
    for (int i = 1; i <= 200; i++) {
        pd_v3 f = cf_tangential(&spring, n, kt, kt, 1, v3(step, 0, 0), v3(0, 0, 0), 0, mu, fn);
        double d = i * step;
        double expect = d < slip_at ? -kt * d : -mu * fn;
        CHECK_NEAR(expect, f.x, 1e-9);
        CHECK_NEAR(0, f.z, 1e-12);
    }
    /* unloading (eq. 4.9): a smaller kt scales the stored force down in proportion */
    spring = v3(-2, 0, 0);
    pd_v3 f = cf_tangential(&spring, n, 5e3, 1e4, 0, v3(0, 0, 0), v3(0, 0, 0), 0, mu, fn);
    CHECK_NEAR(-1, f.x, 1e-12);
}

/*
 * The twisting spring (cf_twist) sticks then slides, as the tangential one: a steady relative
 * spin winds it at k_tw dt per step until it reaches the Coulomb limit, where it stays; the
 * dashpot adds damp * spin while it sticks; a smaller stiffness on unloading scales the stored
 * moment down in proportion; and a zero limit (no friction) leaves no moment at all. Exact
 * within rounding: every case is closed form.
 */
TEST(twisting_spring_sticks_then_slides)
{
    double ktw = 2.0, spin = 3.0, dt = 1e-3, lim = 0.05, tw = 0;
    for (int i = 1; i <= 20; i++) {
        double m = cf_twist(&tw, ktw, ktw, 1, spin, dt, 0, lim);
        double wound = ktw * spin * dt * i; /* 0.006 per step: the limit at the 9th */
        CHECK_NEAR(wound < lim ? -wound : -lim, m, 1e-15);
    }
    tw = 0; /* the dashpot while it sticks */
    CHECK_NEAR(-ktw * spin * dt - 1e-3 * spin, cf_twist(&tw, ktw, ktw, 1, spin, dt, 1e-3, lim),
               1e-15);
    CHECK_NEAR(-ktw * spin * dt, tw, 1e-15); /* the spring keeps only the elastic part */
    tw = -0.04; /* unloading at half the stiffness halves the stored moment */
    CHECK_NEAR(-0.02, cf_twist(&tw, 1.0, 2.0, 0, 0, dt, 0, lim), 1e-15);
    tw = 0;
    CHECK_NEAR(0, cf_twist(&tw, ktw, ktw, 1, spin, dt, 1e-3, 0), 0);
    CHECK_NEAR(0, tw, 0);
    /* Reissner-Sagoci: 16/3 G a^3 */
    CHECK_REL(16.0 / 3 * 4e6 * 1e-6, cf_twist_stiffness(4e6, 1e-2), 1e-15);
}

TEST(effective_properties)
{
    /* eq. 4.2 with equal materials: E* = E / (2 (1 - nu^2)); standard Mindlin G* = G / (2 (2 - nu))
     */
    CHECK_REL(2e7 / (2 * (1 - 0.0625)), cf_effective_modulus(2e7, 0.25, 2e7, 0.25), 1e-15);
    CHECK_REL(8e6 / (2 * 1.75), cf_effective_shear(8e6, 0.25, 8e6, 0.25), 1e-15);
    CHECK_REL(1.0, cf_effective_mass(1.0, 0.0), 1e-15); /* against a wall: the particle's mass */
}

TEST(opencl_forces_match_host)
{
    /* the same header compiled as OpenCL C: every program builds, and the force stage's kernel
     * gives the host's numbers (1e-12 relative in double, float's 1e-6 in single) */
    pd_device *dev = NULL;
    pd_error err = {0};
    if (pd_device_open(-1, &dev, &err) != PD_OK) {
        TEST_FAILF("no OpenCL device: %s", err.msg);
        return;
    }
    if (pd_device_compile_all(dev, &err) != PD_OK) TEST_FAILF("%s", err.msg);
    enum { N = 64 };
    double in[6 * N], out[2 * N];
    for (int i = 0; i < N; i++) {
        double *c = in + 6 * i;
        c[0] = 1e-9 * (1 + i);     /* V, m^3 */
        c[1] = 1e-4 * (1 + i % 7); /* delta, m */
        c[2] = 1e7 * (1 + i % 3);  /* E*, Pa */
        c[3] = 1e-3 * (1 + i % 5); /* m*, kg */
        c[4] = 0.1 * (i % 4);      /* gamma */
        c[5] = 0.5 - 0.03 * i;     /* vn, m/s (some separating) */
    }
    for (int dbl = 0; dbl <= pd_device_has_fp64(dev); dbl++) {
        if (pd_forces_cl(dev, in, N, dbl, out, &err) != PD_OK) {
            TEST_FAILF("%s", err.msg);
            break;
        }
        for (int i = 0; i < N; i++) {
            const double *c = in + 6 * i;
            double kn, f = cf_hertz_volume_normal(c[2], c[0], c[1], c[3], c[4], c[5], &kn);
            CHECK_NEAR(f, out[2 * i], (dbl ? 1e-12 : 1e-5) * fabs(f) + 1e-300);
            CHECK_REL(kn, out[2 * i + 1], dbl ? 1e-12 : 1e-5);
        }
    }
    pd_device_close(dev);
}

int main(void)
{
    RUN(hertz_spheres_duration_and_peak_overlap);
    RUN(hertz_damping_dissipates_and_is_monotone);
    RUN(linear_model_restitution_and_duration);
    RUN(polyhedral_spheres_follow_hertz);
    RUN(tangential_spring_sticks_then_slides);
    RUN(twisting_spring_sticks_then_slides);
    RUN(effective_properties);
    RUN(opencl_forces_match_host);
    return TEST_DONE();
}
