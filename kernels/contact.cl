/*
 * contact.cl - the narrow phase and contact forces of one step (kernels/contact_pair.h) over the
 * step's candidate pairs, sorted by key. Built with -DPD_DOUBLE=0 or 1.
 *
 * nwork work-items stride over the pairs, each with its own overlap scratch (ilen ints, rlen
 * reals), so scratch memory follows the device's parallelism, not the number of pairs. Each pair
 * finds its tangential history by binary search in last step's sorted keys (contact_history.h).
 * The search is confined to the pair's first body's segment of last step's keys (old_offset).
 * A particle meets a wall's triangles found in the wall's BVH (wall_bvh.h, np_wall_local); a
 * wall-pair work-item's scratch begins with np_wall_ilen/_rlen(wall_cap) for them.
 * Per pair out: force on the second body (3), the contact point (3), the new
 * tangential spring (3) and stiffness (1), and info (2): touching flag and depth / size.
 */
#include "pd_real.h"
#include "contact_pair.h"

__kernel void
contact_forces(__global const ch_key *keys, int npairs, __global const ch_key *old_keys,
               __global const int *old_offset, __global const pd_real *old_spring,
               __global const pd_real *old_kt, __global const pd_real *x, __global const pd_real *q,
               __global const pd_real *v, __global const pd_real *w, __global const pd_real *size,
               __global const pd_real *inv_m, __global const int *shape,
               __global const int *material, __global const pd_real *vert, __global const int *tri,
               __global const int *voff, __global const int *toff, __global const int *vt_off,
               __global const int *vt, __global const pd_real *unit_vol, __global const int *kind,
               __global const pd_real *radius_ratio, __global const pd_real *params, int nmat,
               int nparticles, pd_real dt, __global const pd_real *wnode_box,
               __global const int *wnode_kid, __global const int *wnode_off,
               __global const int *wtri_order, int wall_cap, int nwall, __global int *status,
               __global int *iscr, __global pd_real *rscr, int ilen, int rlen, int pts_cap,
               int nwork, __global pd_real *force, __global pd_real *point,
               __global pd_real *spring, __global pd_real *kt, __global pd_real *info)
{
    int g = (int)get_global_id(0);
    if (g >= nwork) return;
    cp_world wd;
    wd.x = x;
    wd.q = q;
    wd.v = v;
    wd.w = w;
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
    wd.sh.unit_vol = unit_vol;
    wd.kind = kind;
    wd.radius_ratio = radius_ratio;
    wd.params = params;
    wd.nmat = nmat;
    wd.nparticles = nparticles;
    wd.dt = dt;
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
        if (cp_apart(&wd, k)) {
            cp_none(&r); /* no force, and no history to look up */
        } else {
            /* last step's pairs of the same first body: a few entries to search, not all */
            int lo = old_offset[ch_first(k)],
                j = ch_find(old_keys + lo, old_offset[ch_first(k) + 1] - lo, k);
            j = j >= 0 ? lo + j : -1;
            pd_v3 s0 = j >= 0 ? v3_load(old_spring, j) : v3(0, 0, 0);
            pd_real kt0 = j >= 0 ? old_kt[j] : PD_R(0);
            cp_pair(&wd, k, s0, kt0, is, rs, pts_cap, &r);
        }
        v3_store(force, c, r.force);
        v3_store(point, c, r.point);
        v3_store(spring, c, r.spring);
        kt[c] = r.kt;
        info[2 * c] = (pd_real)r.touching;
        info[2 * c + 1] = r.ratio;
    }
}
