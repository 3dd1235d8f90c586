/*
 * contact_history.h - the per-pair state carried between steps (the tangential spring of thesis
 * eqs. 4.8-4.9, and the contact point, where single precision sums the next overlap: OVL_ORIGIN)
 * and the deterministic per-particle sum of contact forces, shared by OpenCL and host C (see
 * pd_real.h).
 *
 * A contact is named by a 64-bit key: first body in the high half, second in the low half, so the
 * contacts of one step sorted by key are grouped by first body. Walls are second bodies numbered
 * from CH_WALL up. A new contact finds its predecessor by binary search in the previous step's
 * sorted keys: no hashing, no atomics, the same answer on every device.
 *
 * A pair list is kept for many steps (the Verlet skin), and each pair's state is updated in place
 * while it is. When a new list is built, the pairs that carry state (ch_has_state; in a bed a
 * fifth of the candidates) are first copied out, sorted by key with per-particle offsets, and
 * the new list's pairs look themselves up there: memory for one list, not two.
 *
 * Forces are summed per particle in a fixed order (its contacts as first body in key order, then
 * those as second body in key order), never with floating-point atomics, so a run is
 * bit-identical from run to run on one device (issue 3, stage 6).
 */
#ifndef PD_CONTACT_HISTORY_H
#define PD_CONTACT_HISTORY_H

#include "pd_real.h"

#ifdef __OPENCL_VERSION__
typedef ulong ch_key;
#else
#include <stdint.h>
typedef uint64_t ch_key;
#endif

#define CH_WALL 0x80000000u /* second bodies from here up are walls */

PD_FN ch_key ch_make(unsigned a, unsigned b)
{
    return (ch_key)a << 32 | (ch_key)b;
}
PD_FN unsigned ch_first(ch_key k)
{
    return (unsigned)(k >> 32);
}
PD_FN unsigned ch_second(ch_key k)
{
    return (unsigned)(k & 0xffffffffu);
}

/* First position in sorted keys[0..n) whose key is >= k. */
PD_FN int ch_lower_bound(PD_GLOBAL const ch_key *keys, int n, ch_key k)
{
    int lo = 0, hi = n;
    while (lo < hi) {
        int mid = lo + (hi - lo) / 2;
        if (keys[mid] < k)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

/* Position of k in sorted keys[0..n), or -1: where a contact's last-step state is. */
PD_FN int ch_find(PD_GLOBAL const ch_key *keys, int n, ch_key k)
{
    int i = ch_lower_bound(keys, n, k);
    return i < n && keys[i] == k ? i : -1;
}

/*
 * Whether pair c's state is worth carrying to the next pair list: a pair with no tangential
 * spring, no twist and no stiffness starts as a new contact would (zero state), so it is not
 * kept; nor is a separated pair's certificate (a negative kt, contact.cl), which holds only while
 * its list does. twist is NULL in a run without contact moments (engine/sim.h).
 */
PD_FN int ch_has_state(PD_GLOBAL const pd_real *spring, PD_GLOBAL const pd_real *kt,
                       PD_GLOBAL const pd_real *twist, int c)
{
    return kt[c] > PD_R(0) || spring[3 * c] != PD_R(0) || spring[3 * c + 1] != PD_R(0) ||
           spring[3 * c + 2] != PD_R(0) || (twist && twist[c] != PD_R(0));
}

/*
 * Where pair k's carried state is in the arrays history_keep (contact.cl) fills when a pair list
 * is rebuilt: the carried pairs of each first body p are carry_keys[carry_offset[p] ..
 * carry_offset[p+1]), sorted, so the search covers a few entries, not all. Returns the index
 * into the carry arrays, or -1 for a pair that carried nothing (a new contact: zero state).
 */
PD_FN int ch_carried(PD_GLOBAL const ch_key *carry_keys, PD_GLOBAL const int *carry_offset,
                     ch_key k)
{
    int lo = carry_offset[ch_first(k)];
    int j = ch_find(carry_keys + lo, carry_offset[ch_first(k) + 1] - lo, k);
    return j >= 0 ? lo + j : -1;
}

/*
 * Torque on the first body of a contact about its centre xa: (c - xa) x (-F) - M, for the force
 * F on the second body at contact point c and the contact's own moment M on the second body
 * (contact_pair.h, cp_couple; zero without contact moments). What the contact stage stores per
 * pair, with F: the gather needs no contact point (ch_gather).
 */
PD_FN pd_v3 ch_first_torque(pd_v3 xa, pd_v3 c, pd_v3 f, pd_v3 m)
{
    return v3_sub(v3_cross(v3_sub(c, xa), v3_scale(f, -1)), m);
}

/*
 * Sum over particle p's contacts of the force and torque on p. Its contacts as first body are
 * first[p] .. first[p+1]-1 (the step's keys are sorted, so they are contiguous and in key
 * order). Its contacts as second body are listed, in any order, in second_list[second_off[p] ..
 * second_off[p+1]-1]; the list is sorted here (only p's gather touches it) so they are summed in
 * key order too. Contact c carries force[3c], acting on its second body (the first body gets
 * minus it), and torque[3c], the torque on its first body a about a's centre (ch_first_torque).
 * The second body b's torque about its own centre follows without the contact point:
 * (c - xb) x F + M = (xa - xb) x F - torque. (Storing one torque, not the point and a moment,
 * saves 3 reals per pair; the point is kept only where single precision needs it.)
 */
PD_FN void ch_gather(unsigned p, PD_GLOBAL const int *first, PD_GLOBAL const int *second_off,
                     PD_GLOBAL int *second_list, PD_GLOBAL const ch_key *keys,
                     PD_GLOBAL const pd_real *force, PD_GLOBAL const pd_real *torque,
                     PD_GLOBAL const pd_real *x, pd_v3 *f_out, pd_v3 *t_out)
{
    pd_v3 f = v3(0, 0, 0), t = v3(0, 0, 0), xp = v3_load(x, (int)p);
    for (int c = first[p]; c < first[p + 1]; c++) {
        f = v3_sub(f, v3_load(force, c));
        t = v3_add(t, v3_load(torque, c));
    }
    PD_GLOBAL int *l = second_list + second_off[p];
    int m = second_off[p + 1] - second_off[p];
    for (int a = 1; a < m; a++) { /* insertion sort: a particle has tens of contacts */
        int v = l[a], b = a - 1;
        while (b >= 0 && l[b] > v) {
            l[b + 1] = l[b];
            b--;
        }
        l[b + 1] = v;
    }
    for (int s = 0; s < m; s++) {
        int c = l[s];
        pd_v3 fc = v3_load(force, c), xa = v3_load(x, (int)ch_first(keys[c]));
        f = v3_add(f, fc);
        t = v3_add(t, v3_sub(v3_cross(v3_sub(xa, xp), fc), v3_load(torque, c)));
    }
    *f_out = f;
    *t_out = t;
}

#endif /* PD_CONTACT_HISTORY_H */
