/*
 * integrate.cl - the integration stage (kernels/integrate.h), one work-item per particle, on
 * packed arrays: x, v, L, f, torque as 3 reals per particle, q as 4 (w first), inv_i as the 3
 * inverse principal moments, inv_m one real. Built with -DPD_DOUBLE=0 or 1.
 */
#include "pd_real.h"
#include "integrate.h"

/* Half kick (h = dt/2): v += f/m h, L += torque h. */
__kernel void integrate_kick(__global pd_real *v, __global pd_real *L, __global const pd_real *f,
                             __global const pd_real *torque, __global const pd_real *inv_m, int n,
                             pd_real h)
{
    int i = (int)get_global_id(0);
    if (i >= n) return;
    v3_store(v, i, int_kick(v3_load(v, i), v3_load(f, i), inv_m[i], h));
    v3_store(L, i, int_kick(v3_load(L, i), v3_load(torque, i), PD_R(1), h));
}

/*
 * Drift: x += v dt, and q turned by Euler's equations at constant L (the contact stage takes the
 * angular velocity at the new orientation from q and L: cp_omega, contact_pair.h).
 * A particle whose position, velocity or angular momentum is not finite is reported by the
 * lowest such index in status[1] (atomic_min: the host names the first one). A particle that has
 * moved more than half the broad phase's skin from x_ref (its position when the pair list was
 * built) sets status[0]: the list must be built again (sim_step.c). travel sums, since the list
 * was built, a bound on how far any point of each particle has moved: separated pairs are skipped
 * until their particles' travel reaches their certified gap (contact.cl).
 */
__kernel void integrate_drift(__global pd_real *x, __global const pd_real *v, __global pd_real *q,
                              __global const pd_real *L, __global const int *material, int n,
                              pd_real dt, __global int *status, __global const pd_real *x_ref,
                              pd_real half_skin2, __global const pd_real *size,
                              __global const int *shape, __global const pd_real *radius_ratio,
                              __global pd_real *travel, __global const pd_real *unit_inertia,
                              __global const pd_real *density)
{
    int i = (int)get_global_id(0);
    if (i >= n) return;
    pd_v3 xi = v3_add(v3_load(x, i), v3_scale(v3_load(v, i), dt)), Li = v3_load(L, i);
    v3_store(x, i, xi);
    __global pd_real *qi = q + 4 * i;
    pd_v3 ii = int_inverse_inertia(unit_inertia, shape[i], density[material[i]], size[i]);
    pd_real turn;
    pd_q4 r = int_drift_rotation_turn(q4(qi[0], qi[1], qi[2], qi[3]), Li, ii, dt, &turn);
    qi[0] = r.w;
    qi[1] = r.x;
    qi[2] = r.y;
    qi[3] = r.z;
    pd_real s = xi.x + xi.y + xi.z + v3_dot(v3_load(v, i), v3(1, 1, 1)) + Li.x + Li.y + Li.z;
    if (!isfinite(s)) atomic_min(status + 1, i);
    pd_v3 moved = v3_sub(xi, v3_load(x_ref, i));
    if (!(v3_dot(moved, moved) <= half_skin2)) atomic_or(status, 1);
    /* how far any point of the particle can have moved: its centre's step plus the circumradius
     * times the turn, plus the rounding of the new position and orientation (a few ulps of the
     * position and of the radius); summed upwards (each addition's rounding added back), so the
     * sum never falls short of the true path */
    pd_real rad = radius_ratio[shape[i]] * size[i], t = travel[i];
    pd_real d = v3_norm(v3_load(v, i)) * dt + rad * turn + PD_R(8) * PD_EPS * (v3_norm(xi) + rad);
    travel[i] = t + d + PD_R(4) * PD_EPS * (t + d);
}
