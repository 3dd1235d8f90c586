/*
 * integrate.h - time integration of rigid particles, shared by OpenCL kernels and host C.
 *
 * Translation: velocity Verlet (thesis section 3.4): half kick v += (f/m) dt/2, drift
 * x += v dt, forces at the new positions, half kick. Exact for constant forces, second order.
 *
 * Rotation: the state is the orientation q (body -> world, w first) and the angular momentum L in
 * the world frame. Torques kick L exactly like forces kick v. The drift turns q by the angular
 * velocity of Euler's equations, omega_body = I_body^-1 R(q)^T L, evaluated at the middle of the
 * step (implicit midpoint, one fixed-point iteration): q <- q * exp(omega_body(q_half) dt). This
 * keeps |L| exact between torques, keeps q a unit quaternion, and is second order, where the
 * thesis's forward Euler for orientation is first order and drifts in energy.
 */
#ifndef PD_INTEGRATE_H
#define PD_INTEGRATE_H

#include "pd_real.h"

typedef struct pd_q4 {
    pd_real w, x, y, z;
} pd_q4;

PD_FN pd_q4 q4(pd_real w, pd_real x, pd_real y, pd_real z)
{
    pd_q4 q;
    q.w = w;
    q.x = x;
    q.y = y;
    q.z = z;
    return q;
}

PD_FN pd_q4 q4_mul(pd_q4 a, pd_q4 b)
{
    return q4(a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z,
              a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
              a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
              a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w);
}

PD_FN pd_q4 q4_unit(pd_q4 q)
{
    pd_real n = PD_SQRT(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
    return q4(q.w / n, q.x / n, q.y / n, q.z / n);
}

/* R(q) v: body -> world. */
PD_FN pd_v3 q4_rotate(pd_q4 q, pd_v3 v)
{
    pd_v3 u = v3(q.x, q.y, q.z);
    pd_v3 t = v3_scale(v3_cross(u, v), PD_R(2));
    return v3_add(v3_add(v, v3_scale(t, q.w)), v3_cross(u, t));
}

/* R(q)^T v: world -> body. */
PD_FN pd_v3 q4_unrotate(pd_q4 q, pd_v3 v)
{
    return q4_rotate(q4(q.w, -q.x, -q.y, -q.z), v);
}

/* exp of a rotation vector phi (radians about its direction) as a unit quaternion. */
PD_FN pd_q4 q4_exp(pd_v3 phi)
{
    pd_real a2 = v3_dot(phi, phi);
    pd_real s, c;
    if (a2 < PD_R(1e-4)) {
        /* a step turns by far less than 0.01 rad: the series of cos(a/2) and sin(a/2)/a, whose
         * first omitted terms (a^8 / 10 321 920, a^8 / 185 794 560) are below double rounding
         * there, and need no square root, sine or cosine (the drift's main cost) */
        pd_real h2 = PD_R(0.25) * a2;
        c = PD_R(1) - h2 * (PD_R(0.5) - h2 * (PD_R(1) / 24 - h2 * (PD_R(1) / 720)));
        s = PD_R(0.5) *
            (PD_R(1) - h2 * (PD_R(1) / 6 - h2 * (PD_R(1) / 120 - h2 * (PD_R(1) / 5040))));
    } else {
        pd_real a = PD_SQRT(a2), h = PD_R(0.5) * a;
        s = sin(h) / a;
        c = cos(h);
    }
    return q4(c, phi.x * s, phi.y * s, phi.z * s);
}

/* Half (or whole) kick: v += f inv_m h. The same serves L += torque h with inv_m = 1. */
PD_FN pd_v3 int_kick(pd_v3 v, pd_v3 f, pd_real inv_m, pd_real h)
{
    return v3_add(v, v3_scale(f, inv_m * h));
}

/*
 * Inverse principal moments of inertia of a particle of shape `shape`, density rho and size d:
 * the shape's moments for size 1 and density 1 (unit, 3 per shape) times rho d^5, multiplied in
 * the order particles.c computes a particle's inertia, so that both hold the same numbers.
 */
PD_FN pd_v3 int_inverse_inertia(PD_GLOBAL const pd_real *unit, int shape, pd_real rho, pd_real d)
{
    PD_GLOBAL const pd_real *u = unit + 3 * shape;
    pd_real d3 = d * d * d;
    return v3(PD_R(1) / (rho * u[0] * d3 * d * d), PD_R(1) / (rho * u[1] * d3 * d * d),
              PD_R(1) / (rho * u[2] * d3 * d * d));
}

/* Angular velocity in the body frame from world L (Euler's equations; inv_i: 1/principal I). */
PD_FN pd_v3 int_omega_body(pd_q4 q, pd_v3 L, pd_v3 inv_i)
{
    pd_v3 lb = q4_unrotate(q, L);
    return v3(lb.x * inv_i.x, lb.y * inv_i.y, lb.z * inv_i.z);
}

/*
 * Orientation drift over dt at constant L (implicit midpoint, see the header comment); *turn
 * receives the angle turned, rad (a body point at distance r from the centre moves at most r
 * times it).
 */
PD_FN pd_q4 int_drift_rotation_turn(pd_q4 q, pd_v3 L, pd_v3 inv_i, pd_real dt, pd_real *turn)
{
    pd_v3 w0 = int_omega_body(q, L, inv_i);
    pd_q4 qh = q4_unit(q4_mul(q, q4_exp(v3_scale(w0, PD_R(0.5) * dt))));
    pd_v3 phi = v3_scale(int_omega_body(qh, L, inv_i), dt);
    *turn = v3_norm(phi);
    return q4_unit(q4_mul(q, q4_exp(phi)));
}

PD_FN pd_q4 int_drift_rotation(pd_q4 q, pd_v3 L, pd_v3 inv_i, pd_real dt)
{
    pd_real turn;
    return int_drift_rotation_turn(q, L, inv_i, dt, &turn);
}

/* Rotational kinetic energy 1/2 L . omega. */
PD_FN pd_real int_rot_energy(pd_q4 q, pd_v3 L, pd_v3 inv_i)
{
    pd_v3 lb = q4_unrotate(q, L);
    return PD_R(0.5) * (lb.x * lb.x * inv_i.x + lb.y * lb.y * inv_i.y + lb.z * lb.z * inv_i.z);
}

#endif /* PD_INTEGRATE_H */
