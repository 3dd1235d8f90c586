/*
 * test_integrate.c - kernels/integrate.h against analytic motion. Velocity Verlet is exact for
 * constant forces (free fall, constant torque about a principal axis: 1e-12); for the rest the
 * scheme is second order, so errors scale as (omega dt)^2 and the tolerances below are a few
 * times that estimate.
 */
#define PD_DOUBLE 1
#include "integrate.h"
#include "test.h"

static const double PI = 3.14159265358979323846;

TEST(free_fall_is_exact)
{
    pd_v3 x = v3(1, 2, 3), v = v3(0.5, -0.25, 4), g = v3(0, 0, -9.81);
    double dt = 1e-3;
    int n = 1000;
    for (int i = 0; i < n; i++) {
        v = int_kick(v, g, 1, 0.5 * dt);
        x = v3_add(x, v3_scale(v, dt));
        v = int_kick(v, g, 1, 0.5 * dt);
    }
    double t = n * dt;
    CHECK_NEAR(1 + 0.5 * t, x.x, 1e-12);
    CHECK_NEAR(3 + 4 * t - 0.5 * 9.81 * t * t, x.z, 1e-12);
    CHECK_NEAR(4 - 9.81 * t, v.z, 1e-12);
}

TEST(harmonic_oscillator_energy_and_period)
{
    /* m = 1, k = (2 pi)^2: period 1 s. Verlet's energy error stays bounded by ~(w dt)^2 / 4
     * (no drift); its frequency obeys sin(w' dt / 2) = w dt / 2, so the period is shorter by
     * (w dt)^2 / 24 relative. */
    double k = 4 * PI * PI, dt = 1e-3, wdt = 2 * PI * dt;
    pd_v3 x = v3(1, 0, 0), v = v3(0, 0, 0);
    pd_v3 f = v3_scale(x, -k);
    double e0 = 0.5 * k, emax = 0, last_cross = 0, t = 0;
    int crossings = 0;
    for (int i = 0; i < 100000; i++) { /* 100 periods */
        double xprev = x.x;
        v = int_kick(v, f, 1, 0.5 * dt);
        x = v3_add(x, v3_scale(v, dt));
        f = v3_scale(x, -k);
        v = int_kick(v, f, 1, 0.5 * dt);
        t += dt;
        double e = 0.5 * v3_dot(v, v) + 0.5 * k * v3_dot(x, x);
        if (fabs(e - e0) / e0 > emax) emax = fabs(e - e0) / e0;
        if (xprev < 0 && x.x >= 0) { /* upward zero crossing, interpolated */
            last_cross = t - dt * x.x / (x.x - xprev);
            crossings++;
        }
    }
    CHECK(emax < 0.5 * wdt * wdt);
    double period = (last_cross - 0.75) / (crossings - 1); /* first upward crossing at 3/4 s */
    CHECK_REL(1 - wdt * wdt / 24, period, 1e-7);
}

TEST(symmetric_top_precesses_at_the_euler_rate)
{
    /* I = (1, 1, 2), omega_body(0) = (w, 0, w3): omega_3 stays, (omega_1, omega_2) turns at
     * Omega = w3 (I3 - I1) / I1 = 1 rad/s in the body frame (Euler's equations). */
    pd_v3 inv_i = v3(1, 1, 0.5);
    double w = 0.3, w3 = 1.0, dt = 1e-3, T = 5;
    pd_q4 q = q4_unit(q4(0.9, 0.1, -0.3, 0.2));
    pd_v3 L = q4_rotate(q, v3(w * 1, 0, w3 * 2)); /* L = R I omega */
    double e0 = int_rot_energy(q, L, inv_i);
    int n = (int)(T / dt + 0.5);
    for (int i = 0; i < n; i++)
        q = int_drift_rotation(q, L, inv_i, dt);
    pd_v3 wb = int_omega_body(q, L, inv_i);
    /* second order: error ~ (w dt)^2 T per unit rate, ~1e-6 here */
    CHECK_NEAR(w * cos(T), wb.x, 1e-5);
    CHECK_NEAR(w * sin(T), wb.y, 1e-5);
    CHECK_NEAR(w3, wb.z, 1e-9);
    CHECK_REL(e0, int_rot_energy(q, L, inv_i), 1e-9);
    CHECK_NEAR(1, sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z), 1e-14);
}

TEST(asymmetric_body_conserves_energy)
{
    /* torque-free tumbling of I = (1, 2, 3) near its unstable middle axis: energy must not drift */
    pd_v3 inv_i = v3(1, 0.5, 1.0 / 3);
    pd_q4 q = q4(1, 0, 0, 0);
    pd_v3 L = v3(0.1, 2.0, 0.05);
    double e0 = int_rot_energy(q, L, inv_i), dt = 1e-3, emax = 0;
    for (int i = 0; i < 20000; i++) {
        q = int_drift_rotation(q, L, inv_i, dt);
        double e = int_rot_energy(q, L, inv_i);
        if (fabs(e - e0) / e0 > emax) emax = fabs(e - e0) / e0;
    }
    /* bounded at (w dt)^2 ~ 1e-6 by the midpoint rule */
    CHECK(emax < 1e-5);
}

TEST(constant_torque_spin_up_is_exact)
{
    /* torque tau about the body z axis (a principal axis, I3 = 2): omega = tau t / I3 and the
     * angle is tau t^2 / (2 I3), exactly, as for free fall */
    pd_v3 inv_i = v3(1, 1.5, 0.5), tau = v3(0, 0, 0.8), L = v3(0, 0, 0);
    pd_q4 q = q4(1, 0, 0, 0);
    double dt = 1e-3;
    int n = 2000;
    for (int i = 0; i < n; i++) {
        L = int_kick(L, tau, 1, 0.5 * dt);
        q = int_drift_rotation(q, L, inv_i, dt);
        L = int_kick(L, tau, 1, 0.5 * dt);
    }
    double t = n * dt, angle = 0.8 * t * t / 4;
    CHECK_NEAR(0.8 * t / 2, int_omega_body(q, L, inv_i).z, 1e-12);
    CHECK_NEAR(cos(angle / 2), q.w, 1e-12);
    CHECK_NEAR(sin(angle / 2), q.z, 1e-12);
}

int main(void)
{
    RUN(free_fall_is_exact);
    RUN(harmonic_oscillator_energy_and_period);
    RUN(symmetric_top_precesses_at_the_euler_rate);
    RUN(asymmetric_body_conserves_energy);
    RUN(constant_torque_spin_up_is_exact);
    return TEST_DONE();
}
