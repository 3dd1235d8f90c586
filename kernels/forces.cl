/*
 * forces.cl - per-contact force evaluation (the forces stage), one work-item per contact.
 * Built with -DPD_DOUBLE=0 or 1. hertz_volume_normal: for each contact, the normal force of
 * thesis eq. 4.16 from (V, delta, E*, m*, gamma, vn) packed as 6 reals; writes F_n and k_n.
 * body_forces: per particle, the deterministic sum of its contacts' forces and torques
 * (kernels/contact_history.h) plus gravity and drag, written as 3 + 3 reals.
 */
#include "pd_real.h"
#include "contact_force.h"
#include "contact_history.h"

__kernel void hertz_volume_normal(__global const pd_real *in, int n, __global pd_real *out)
{
    int g = (int)get_global_id(0);
    if (g >= n) return;
    __global const pd_real *c = in + 6 * g;
    pd_real kn;
    out[2 * g] = cf_hertz_volume_normal(c[2], c[0], c[1], c[3], c[4], c[5], &kn);
    out[2 * g + 1] = kn;
}

/* Contacts per particle as second body (walls are never gathered); counts are exact whatever
 * the order of the atomic increments. */
__kernel void second_count(__global const ch_key *keys, int n, int nparticles,
                           __global volatile int *count)
{
    int c = (int)get_global_id(0);
    if (c >= n) return;
    unsigned s = ch_second(keys[c]);
    if (s < (unsigned)nparticles) atomic_inc(&count[s]);
}

/* Lists each particle's second-body contacts at its offset; the order within a particle's list
 * depends on timing, so ch_gather sorts it before summing. cursor starts at zero. */
__kernel void second_fill(__global const ch_key *keys, int n, int nparticles,
                          __global const int *offset, __global volatile int *cursor,
                          __global int *list)
{
    int c = (int)get_global_id(0);
    if (c >= n) return;
    unsigned s = ch_second(keys[c]);
    if (s < (unsigned)nparticles) list[offset[s] + atomic_inc(&cursor[s])] = c;
}

/*
 * Total force and torque on each particle p: its contacts' sum in a fixed order (ch_gather), plus
 * gravity m g (seed 004 eq. 2.10) and Stokes drag in a uniform flow, F_d = 3 pi mu d (u_f - u)
 * (eqs. 1.2 and 2.9: m / tau_p with tau_p = rho d^2 / (18 mu); for a polyhedron d is its
 * volume-equivalent diameter). Drag exerts no torque in this model.
 */
__kernel void body_forces(__global const int *first, __global const int *second_off,
                          __global int *second_list, __global const ch_key *keys,
                          __global const pd_real *force, __global const pd_real *torque,
                          __global const pd_real *x, int nparticles, __global const pd_real *inv_m,
                          __global const pd_real *size, __global const pd_real *v, pd_real gx,
                          pd_real gy, pd_real gz, pd_real drag_mu, pd_real ufx, pd_real ufy,
                          pd_real ufz, __global pd_real *f_out, __global pd_real *t_out)
{
    int p = (int)get_global_id(0);
    if (p >= nparticles) return;
    pd_v3 f, t;
    ch_gather((unsigned)p, first, second_off, second_list, keys, force, torque, x, &f, &t);
    f = v3_add(f, v3_scale(v3(gx, gy, gz), PD_R(1) / inv_m[p]));
    if (drag_mu > PD_R(0))
        f = v3_add(f, v3_scale(v3_sub(v3(ufx, ufy, ufz), v3_load(v, p)),
                               PD_R(3) * CF_PI * drag_mu * size[p]));
    v3_store(f_out, p, f);
    v3_store(t_out, p, t);
}
