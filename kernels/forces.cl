/*
 * forces.cl - per-contact force evaluation (the forces stage), one work-item per contact.
 * Built with -DPD_DOUBLE=0 or 1. hertz_volume_normal: for each contact, the normal force of
 * thesis eq. 4.16 from (V, delta, E*, m*, gamma, vn) packed as 6 reals; writes F_n and k_n.
 */
#include "pd_real.h"
#include "contact_force.h"

__kernel void hertz_volume_normal(__global const pd_real *in, int n, __global pd_real *out)
{
    int g = (int)get_global_id(0);
    if (g >= n) return;
    __global const pd_real *c = in + 6 * g;
    pd_real kn;
    out[2 * g] = cf_hertz_volume_normal(c[2], c[0], c[1], c[3], c[4], c[5], &kn);
    out[2 * g + 1] = kn;
}
