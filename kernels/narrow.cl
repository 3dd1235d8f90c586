/*
 * narrow.cl - the narrow phase over candidate pairs (kernels/narrow_phase.h), one work-item per
 * pair. Built with -DPD_DOUBLE=0 or 1. Particles: x (3n), q (4n, [w, x, y, z]), size (n),
 * shape (n); shapes as in narrow_phase.h (vc, coff and disc NULL: no vertex clusters). Each pair
 * gets ilen ints and rlen reals of scratch and writes OVL_OUT_LEN reals (ovl_out_store), in world
 * coordinates (the normal from the pair's first particle into its second).
 */
#include "pd_real.h"
#include "narrow_phase.h"

__kernel void narrow_phase(__global const int *pairs, int npairs, __global const pd_real *x,
                           __global const pd_real *q, __global const pd_real *size,
                           __global const int *shape, __global const pd_real *vert,
                           __global const int *tri, __global const int *voff,
                           __global const int *toff, __global const int *vt_off,
                           __global const int *vt, __global const int *vc, __global const int *coff,
                           __global const pd_real *disc, int flags, __global int *iscr,
                           __global pd_real *rscr, int ilen, int rlen, int pts_cap,
                           __global pd_real *out)
{
    int g = (int)get_global_id(0);
    if (g >= npairs) return;
    np_shapes sh;
    sh.vert = vert;
    sh.tri = tri;
    sh.voff = voff;
    sh.toff = toff;
    sh.vt_off = vt_off;
    sh.vt = vt;
    sh.vc = vc;
    sh.coff = coff;
    sh.disc = disc;
    np_body b[2];
    for (int k = 0; k < 2; k++) {
        int i = pairs[2 * g + k];
        b[k].x = v3_load(x, i);
        for (int c = 0; c < 4; c++)
            b[k].q[c] = q[4 * i + c];
        b[k].size = size[i];
        b[k].shape = shape[i];
    }
    ovl_in in;
    pd_real ra[9];
    np_setup(&sh, &b[0], &b[1], flags, &in, ra);
    in.iscr = iscr + (size_t)g * (size_t)ilen;
    in.rscr = rscr + (size_t)g * (size_t)rlen;
    in.pts_cap = pts_cap;
    ovl_out o;
    ovl_compute(&in, &o);
    np_to_world(&b[0], ra, &o);
    ovl_out_store(out + OVL_OUT_LEN * g, &o);
}
