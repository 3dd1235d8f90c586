/*
 * overlap.cl - the polyhedral overlap of kernels/overlap.h, one work-item per pair.
 * Built with -DPD_DOUBLE=0 or 1. Each pair places B by its own transform (18 reals: rot[9],
 * tr[3], ca[3], cb[3]) and writes OVL_OUT_LEN reals (ovl_out_store). Scratch per pair: the
 * overlap's own and OVL_PLACES's (ovl_places_ilen/_rlen), whether flags ask for places or not.
 */
#include "pd_real.h"
#include "overlap.h"

__kernel void overlap_pairs(__global const pd_real *va, __global const int *ta, int nva, int nta,
                            __global const pd_real *vb, __global const int *tb, int nvb, int ntb,
                            __global const int *vt_a_off, __global const int *vt_a,
                            __global const int *vt_b_off, __global const int *vt_b,
                            __global const int *vc_a, __global const pd_real *disc_a,
                            __global const int *vc_b, __global const pd_real *disc_b,
                            __global const pd_real *xf, int npairs, int flags, __global int *iscr,
                            __global pd_real *rscr, int pts_cap, __global pd_real *out)
{
    int g = (int)get_global_id(0);
    if (g >= npairs) return;
    __global const pd_real *x = xf + 18 * g;
    ovl_in in;
    in.va = va;
    in.sa = PD_R(1);
    in.ta = ta;
    in.nva = nva;
    in.nta = nta;
    in.vb = vb;
    in.tb = tb;
    in.vt_a_off = vt_a_off;
    in.vt_a = vt_a;
    in.vt_b_off = vt_b_off;
    in.vt_b = vt_b;
    in.vc_a = vc_a;
    in.disc_a = disc_a;
    in.vc_b = vc_b;
    in.disc_b = disc_b;
    in.nvb = nvb;
    in.ntb = ntb;
    for (int i = 0; i < 9; i++)
        in.rot[i] = x[i];
    for (int i = 0; i < 3; i++)
        in.tr[i] = x[9 + i];
    in.ca = v3(x[12], x[13], x[14]);
    in.cb = v3(x[15], x[16], x[17]);
    in.flags = flags;
    wb_tree_none(&in.wall);
    in.iscr = iscr +
              (size_t)g * (size_t)(ovl_iscratch_len(nta, ntb, nva, nvb) + ovl_places_ilen(pts_cap));
    in.rscr = rscr + (size_t)g * (size_t)(ovl_rscratch_len(nta, ntb, nva, nvb, pts_cap) +
                                          ovl_places_rlen(pts_cap));
    in.pts_cap = pts_cap;
    ovl_out o;
    ovl_compute(&in, &o);
    ovl_out_store(out + OVL_OUT_LEN * g, &o);
}
