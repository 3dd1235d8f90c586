/*
 * contact.cl - the narrow phase and contact forces of one step (kernels/contact_pair.h) over the
 * step's candidate pairs, sorted by key. Built with -DPD_DOUBLE=0 or 1.
 *
 * nwork work-items stride over the pairs, each with its own overlap scratch (ilen ints, rlen
 * reals), so scratch memory follows the device's parallelism, not the number of pairs. While a
 * pair list is reused, each pair's tangential state is read and written in place (spring, kt).
 * On the step a list is built (fresh), each pair finds its state by binary search among the
 * pairs the old list carried (history_keep below; contact_history.h), within its first body's
 * segment (carry_offset).
 *
 * Temporal coherence: two polyhedra found apart get a certified gap (np_hull_gap), stored as
 * -(gap + their travel then) in kt, which no contact has negative. While the list is reused, the
 * pair is skipped (info -2) until the particles' travel (integrate.cl: a bound on how far any of
 * their points has moved since the list was built) reaches it: they cannot have met. In a
 * resting bed most candidates are such pairs, and their overlaps were half of the step.
 * A particle meets a wall's triangles found in the wall's BVH (wall_bvh.h, np_wall_local); a
 * wall-pair work-item's scratch begins with np_wall_ilen/_rlen(wall_cap) for them.
 * Per pair out: force on the second body (3), torque on the first (3; ch_first_torque), the
 * contact point (3; kept, as the spring, for the next step's overlap in single precision:
 * contact_pair.h, OVL_ORIGIN), the new tangential spring (3), stiffness (1) (or certificate) and
 * twist (1), and info (1 float in either precision, for statistics): depth / smaller size when
 * the bodies touch, -1 when they do not, -2 when skipped as certified apart, -(3 + k) when apart
 * but too close for a certificate, the surfaces' gap not to be searched for k more steps
 * (CP_GAP_RETRY). point (and carry_point) are NULL in double precision, twist (and carry_twist)
 * in a run without contact moments (engine/sim.h).
 */
#include "pd_real.h"
#include "contact_pair.h"

/* How far the points of pair k's particles have moved since the list was built, at most (a
 * wall's pair never holds a certificate): read only where a certificate is checked or made. */
PD_FN pd_real pair_travel(__global const pd_real *travel, ch_key k, int nparticles)
{
    unsigned ib = ch_second(k);
    return travel[ch_first(k)] + (ib < (unsigned)nparticles ? travel[ib] : PD_R(0));
}

__kernel void contact_forces(
    __global const ch_key *keys, int npairs, int fresh, __global const ch_key *carry_keys,
    __global const int *carry_offset, __global const pd_real *carry_spring,
    __global const pd_real *carry_kt, __global const pd_real *carry_point,
    __global const pd_real *carry_twist, __global const pd_real *x, __global const pd_real *q,
    __global const pd_real *v, __global const pd_real *L, __global const pd_real *w_wall,
    __global const pd_real *size, __global const pd_real *inv_m, __global const int *shape,
    __global const int *material, __global const pd_real *unit_inertia,
    __global const pd_real *density, __global const pd_real *vert, __global const int *tri,
    __global const int *voff, __global const int *toff, __global const int *vt_off,
    __global const int *vt, __global const int *vc, __global const int *coff,
    __global const pd_real *disc, __global const int *kind, __global const pd_real *radius_ratio,
    __global const pd_real *params, int nmat, int nparticles, pd_real dt,
    __global const pd_real *wnode_box, __global const int *wnode_kid, __global const int *wnode_off,
    __global const int *wtri_order, int wall_cap, int nwall, __global int *status,
    __global int *iscr, __global pd_real *rscr, int ilen, int rlen, int pts_cap, int nwork,
    __global const pd_real *travel, pd_real gap_cap, pd_real list_life, __global pd_real *force,
    __global pd_real *point, __global pd_real *torque, __global pd_real *spring,
    __global pd_real *kt, __global pd_real *twist, __global float *info)
{
    int g = (int)get_global_id(0);
    if (g >= nwork) return;
    cp_world wd;
    wd.x = x;
    wd.q = q;
    wd.v = v;
    wd.L = L;
    wd.w_wall = w_wall;
    wd.unit_inertia = unit_inertia;
    wd.density = density;
    wd.size = size;
    wd.inv_m = inv_m;
    wd.shape = shape;
    wd.material = material;
    wd.sh.vert = vert;
    wd.sh.tri = tri;
    wd.sh.voff = voff;
    wd.sh.toff = toff;
    wd.sh.vt_off = vt_off;
    wd.sh.vt = vt;
    wd.sh.vc = vc;
    wd.sh.coff = coff;
    wd.sh.disc = disc;
    wd.kind = kind;
    wd.radius_ratio = radius_ratio;
    wd.params = params;
    wd.nmat = nmat;
    wd.nparticles = nparticles;
    wd.dt = dt;
    wd.gap_cap = gap_cap;
    wd.list_life = list_life;
    wd.wnode_box = wnode_box;
    wd.wnode_kid = wnode_kid;
    wd.wnode_off = wnode_off;
    wd.wtri_order = wtri_order;
    wd.wall_cap = wall_cap;
    wd.nwall = nwall;
    wd.status = status;
    __global int *is = iscr + (size_t)g * (size_t)ilen;
    __global pd_real *rs = rscr + (size_t)g * (size_t)rlen;
    for (int c = g; c < npairs; c += nwork) {
        ch_key k = keys[c];
        cp_result r;
        /* steps before a pair whose surfaces' gap search gave up may search again (last step's
         * info, -(3 + steps); a new list has no such memory) */
        float last = fresh ? -1.0f : info[c];
        int wait = last <= -3.0f ? (int)(-last) - 3 : 0;
        if (cp_apart(&wd, k)) {
            cp_none(&r); /* no force, and no history to look up */
        } else if (!fresh && kt[c] < PD_R(0) && pair_travel(travel, k, nparticles) < -kt[c]) {
            /* certified apart: kt holds -(gap + travel then); they have not moved that far */
            force[3 * c] = force[3 * c + 1] = force[3 * c + 2] = PD_R(0);
            torque[3 * c] = torque[3 * c + 1] = torque[3 * c + 2] = PD_R(0);
            if (point) point[3 * c] = point[3 * c + 1] = point[3 * c + 2] = PD_R(0);
            info[c] = -2.0f;
            continue;
        } else if (fresh) {
            int j = ch_carried(carry_keys, carry_offset, k);
            pd_v3 s0 = j >= 0 ? v3_load(carry_spring, j) : v3(0, 0, 0),
                  p0 = j >= 0 && carry_point ? v3_load(carry_point, j) : v3(0, 0, 0);
            pd_real kt0 = j >= 0 ? carry_kt[j] : PD_R(0),
                    tw0 = j >= 0 && carry_twist ? carry_twist[j] : PD_R(0);
            cp_pair(&wd, k, s0, kt0, tw0, is, rs, pts_cap, 1, p0, &r);
        } else { /* kt > 0: it touched in the last step, at point (as carried on a new list) */
            cp_pair(&wd, k, v3_load(spring, c), pd_max(kt[c], PD_R(0)), twist ? twist[c] : PD_R(0),
                    is, rs, pts_cap, wait == 0, point ? v3_load(point, c) : v3(0, 0, 0), &r);
        }
        v3_store(force, c, r.force);
        v3_store(torque, c,
                 ch_first_torque(v3_load(x, (int)ch_first(k)), r.point, r.force, r.couple));
        if (point) v3_store(point, c, r.point);
        v3_store(spring, c, r.spring);
        if (twist) twist[c] = r.twist; /* a run with contact moments (engine/sim.h) */
        /* a separated pair keeps its certificate where a touching one keeps its stiffness:
         * -(gap + travel so far), rounded down, valid while the list is (never carried) */
        kt[c] = r.gap > PD_R(0)
                    ? -(r.gap + pair_travel(travel, k, nparticles)) * (PD_R(1) - PD_R(4) * PD_EPS)
                    : r.kt;
        info[c] = r.touching  ? (float)r.ratio
                  : r.gave_up ? -(float)(3 + CP_GAP_RETRY)
                  : wait > 1  ? -(float)(3 + wait - 1)
                              : -1.0f;
    }
}

/* Before a new pair list is built: how many of particle p's pairs in the old list carry state. */
__kernel void history_count(__global const int *offset, __global const pd_real *spring,
                            __global const pd_real *kt, __global const pd_real *twist, int n,
                            __global int *count)
{
    int p = (int)get_global_id(0);
    if (p >= n) return;
    int m = 0;
    for (int c = offset[p]; c < offset[p + 1]; c++)
        m += ch_has_state(spring, kt, twist, c);
    count[p] = m;
}

/* ... and copies them, in key order, to particle p's segment of the carried pairs. */
__kernel void history_keep(__global const int *offset, __global const ch_key *keys,
                           __global const pd_real *spring, __global const pd_real *kt,
                           __global const pd_real *point, __global const pd_real *twist, int n,
                           __global const int *carry_offset, __global ch_key *carry_keys,
                           __global pd_real *carry_spring, __global pd_real *carry_kt,
                           __global pd_real *carry_point, __global pd_real *carry_twist)
{
    int p = (int)get_global_id(0);
    if (p >= n) return;
    int j = carry_offset[p];
    for (int c = offset[p]; c < offset[p + 1]; c++) {
        if (!ch_has_state(spring, kt, twist, c)) continue;
        carry_keys[j] = keys[c];
        v3_store(carry_spring, j, v3_load(spring, c));
        carry_kt[j] = kt[c];
        if (point) v3_store(carry_point, j, v3_load(point, c));
        if (twist) carry_twist[j] = twist[c];
        j++;
    }
}
