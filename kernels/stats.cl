/*
 * stats.cl - a stats row's sums on the device (engine/sim_stats.c), so that a row reads back a
 * few numbers per work-item instead of every particle's state and every pair. Built with
 * -DPD_DOUBLE=0 or 1.
 *
 * Deterministic: work-item g of `parts` sums its share of the items in a fixed order
 * (Kahan-compensated, so a single-precision sum over a million particles keeps its digits), and
 * the host adds the shares in order; parts and the shares are fixed by the device and the counts,
 * so a run repeats bit for bit on one device. On a GPU a share is every parts-th item from g, so
 * that neighbouring work-items read neighbouring items (coalesced loads); on a CPU, where a core
 * runs a work-group's items one after another, it is a contiguous run of them (st_item), which
 * cut a row's sums over 1e6 particles and 3e6 pairs from 31 to 7 ms on two cores (bench/step).
 */

#include "pd_real.h"
#include "integrate.h"
#include "contact_history.h"

/* Item j of work-item g's share: contiguous runs of `span` items (a CPU), or every parts-th item
 * from g (span 0: a GPU). */
PD_FN int st_item(int g, int j, int parts, int span)
{
    return span > 0 ? g * span + j : g + j * parts;
}

/* Adds x to the compensated sum (*s, *comp) (Kahan). */
PD_FN void st_add(pd_real *s, pd_real *comp, pd_real x)
{
    pd_real y = x - *comp, t = *s + y;
    *comp = (t - *s) - y;
    *s = t;
}

/*
 * Kinetic energy, translational plus rotational (1/2 m v^2 + 1/2 L . omega, in J), summed into
 * sum[g]; emax[g] and imax[g]: the largest single particle's energy and its index (-1 for a part
 * with no particle), for the divergence message. A NaN, once met, stays the largest, so the
 * particle named is one whose state is not finite.
 */
__kernel void stats_energy(__global const pd_real *q, __global const pd_real *v,
                           __global const pd_real *L, __global const pd_real *inv_m,
                           __global const int *shape, __global const int *material,
                           __global const pd_real *size, __global const pd_real *unit_inertia,
                           __global const pd_real *density, int n, int parts, int span,
                           __global pd_real *sum, __global pd_real *emax, __global int *imax)
{
    int g = (int)get_global_id(0);
    if (g >= parts) return;
    pd_real s = PD_R(0), comp = PD_R(0), best = -PD_R(1);
    int worst = -1;
    int end = span > 0 ? min(n, (g + 1) * span) : n;
    for (int j = 0, i = st_item(g, 0, parts, span); i < end; i = st_item(g, ++j, parts, span)) {
        __global const pd_real *qi = q + 4 * i;
        pd_v3 vi = v3_load(v, i);
        /* the inverse inertia as integrate_drift computes it (integrate.h) */
        pd_v3 ii = int_inverse_inertia(unit_inertia, shape[i], density[material[i]], size[i]);
        pd_real e = PD_R(0.5) * v3_dot(vi, vi) / inv_m[i] +
                    int_rot_energy(q4(qi[0], qi[1], qi[2], qi[3]), v3_load(L, i), ii);
        st_add(&s, &comp, e);
        if (!(e <= best) && !isnan(best)) {
            best = e;
            worst = i;
        }
    }
    sum[g] = s;
    emax[g] = best;
    imax[g] = worst;
}

/*
 * The last step's pairs: count[g] touching pairs (info >= 0: depth / size), ratio[g] the largest
 * info (0 if none touches), and the force each wall takes from them, N: wall[(g * nwall + w) * 6
 * + k] for k < 3, compensated sums (the next three hold their compensations).
 */
__kernel void stats_contacts(__global const ch_key *keys, __global const float *info,
                             __global const pd_real *force, int npairs, int nwall, int parts,
                             int span, __global int *count, __global float *ratio,
                             __global pd_real *wall)
{
    int g = (int)get_global_id(0);
    if (g >= parts) return;
    __global pd_real *wf = wall + (size_t)g * 6 * (size_t)nwall;
    for (int k = 0; k < 6 * nwall; k++)
        wf[k] = PD_R(0);
    int m = 0;
    float r = 0.0f;
    int end = span > 0 ? min(npairs, (g + 1) * span) : npairs;
    for (int j = 0, c = st_item(g, 0, parts, span); c < end; c = st_item(g, ++j, parts, span)) {
        float x = info[c];
        m += x >= 0.0f;
        r = x > r ? x : r;
        unsigned b = ch_second(keys[c]);
        if (b < CH_WALL) continue;
        __global pd_real *f = wf + 6 * (size_t)(b - CH_WALL);
        for (int k = 0; k < 3; k++) {
            pd_real s = f[k], comp = f[3 + k];
            st_add(&s, &comp, force[3 * c + k]);
            f[k] = s;
            f[3 + k] = comp;
        }
    }
    count[g] = m;
    ratio[g] = r;
}
