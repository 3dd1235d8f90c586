/*
 * test_narrow_phase.c - the pipeline's narrow phase (kernels/narrow_phase.h): particles of
 * several shapes, sizes and poses, every pair against pd_overlap_host on explicitly scaled and
 * posed meshes. The two paths compute the same overlap in the same frame but reach B's transform
 * through different roundings, so they agree to round-off: 1e-10 relative on V, 1e-10 of the size
 * on the centroid, 1e-9 on the normal.
 */
#define PD_DOUBLE 1
#include <stdint.h>
#include <string.h>

#include "narrow_phase.h"
#include "overlap_run.h"
#include "polydem.h"
#include "test.h"
#include "unit_shape.h"

static uint64_t rs = 7;
static double rnd(void)
{
    uint64_t z = (rs += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return (double)((z ^ (z >> 31)) >> 11) / 9007199254740992.0;
}

enum { NSHAPE = 3, NBODY = 24 };

TEST(pairs_match_overlap_of_posed_scaled_meshes)
{
    const char *names[NSHAPE] = {"schonhardt", "rock", "cube"};
    pd_mesh *m[NSHAPE];
    int voff[NSHAPE + 1] = {0}, toff[NSHAPE + 1] = {0};
    for (int s = 0; s < NSHAPE; s++) {
        m[s] = unit_shape(names[s], s == 1 ? 80 : 0);
        if (!m[s]) {
            TEST_FAILF("builtin %s", names[s]);
            return;
        }
        voff[s + 1] = voff[s] + m[s]->nverts;
        toff[s + 1] = toff[s] + m[s]->ntris;
    }
    double *vert = malloc(sizeof(double) * 3 * voff[NSHAPE]), unit_vol[NSHAPE];
    int *tri = malloc(sizeof(int) * 3 * toff[NSHAPE]);
    int *vt_off = calloc((size_t)(voff[NSHAPE] + NSHAPE), sizeof(int));
    int *vt = malloc(sizeof(int) * 3 * toff[NSHAPE]);
    for (int s = 0; s < NSHAPE; s++) {
        memcpy(vert + 3 * voff[s], m[s]->verts, sizeof(double) * 3 * m[s]->nverts);
        memcpy(tri + 3 * toff[s], m[s]->tris, sizeof(int) * 3 * m[s]->ntris);
        pd_mass_props mp;
        pd_mesh_mass_props(m[s], &mp);
        unit_vol[s] = mp.volume;
        /* CSR vertex -> triangle table, local to the shape */
        int *off = vt_off + voff[s] + s, *list = vt + 3 * toff[s], nv = m[s]->nverts;
        for (int i = 0; i < 3 * m[s]->ntris; i++)
            off[m[s]->tris[i] + 1]++;
        for (int v = 0; v < nv; v++)
            off[v + 1] += off[v];
        int *fill = calloc(nv > 0 ? (size_t)nv : 1, sizeof(int));
        for (int t = 0; t < m[s]->ntris; t++)
            for (int c = 0; c < 3; c++) {
                int v = m[s]->tris[3 * t + c];
                list[off[v] + fill[v]++] = t;
            }
        free(fill);
    }
    np_shapes sh = {vert, tri, voff, toff, vt_off, vt, unit_vol};
    np_body b[NBODY];
    for (int i = 0; i < NBODY; i++) {
        b[i].x = v3(0.9 * rnd(), 0.9 * rnd(), 0.9 * rnd());
        double n = 0;
        for (int c = 0; c < 4; c++) {
            b[i].q[c] = rnd() - 0.5;
            n += b[i].q[c] * b[i].q[c];
        }
        for (int c = 0; c < 4; c++)
            b[i].q[c] /= sqrt(n);
        if (i % 6 == 5) memcpy(b[i].q, b[i - 1].q, sizeof b[i].q); /* some exactly aligned */
        b[i].size = 0.2 + 0.3 * rnd();
        b[i].shape = i % NSHAPE;
    }
    int ilen = ovl_iscratch_len(toff[NSHAPE], toff[NSHAPE], voff[NSHAPE], voff[NSHAPE]);
    int cap = 1024, rlen = ovl_rscratch_len(voff[NSHAPE], voff[NSHAPE], toff[NSHAPE], cap);
    int *iscr = malloc(sizeof(int) * ilen);
    double *rscr = malloc(sizeof(double) * rlen);
    int hits = 0, checked = 0, npairs = 0;
    int pairs[2 * NBODY * NBODY];
    double host[12 * NBODY * NBODY];
    for (int i = 0; i < NBODY; i++)
        for (int j = i + 1; j < NBODY; j++) {
            ovl_in in;
            double ra[9];
            np_setup(&sh, &b[i], &b[j], 0, &in, ra);
            in.iscr = iscr;
            in.rscr = rscr;
            in.pts_cap = cap;
            ovl_out o;
            ovl_compute(&in, &o);
            np_to_world(&b[i], ra, &o);
            pairs[2 * npairs] = i;
            pairs[2 * npairs + 1] = j;
            double h[12] = {o.hit,      o.degenerate, o.kept_a,     o.kept_b,
                            o.volume,   o.centroid.x, o.centroid.y, o.centroid.z,
                            o.normal.x, o.normal.y,   o.normal.z,   o.depth};
            memcpy(host + 12 * npairs++, h, sizeof h);
            /* reference: the meshes scaled by size, posed by (x, q) */
            pd_mesh *ma = NULL, *mb = NULL;
            pd_error err = {0};
            pd_mesh_from_arrays(m[b[i].shape]->verts, m[b[i].shape]->nverts, m[b[i].shape]->tris,
                                m[b[i].shape]->ntris, "a", &ma, &err);
            pd_mesh_from_arrays(m[b[j].shape]->verts, m[b[j].shape]->nverts, m[b[j].shape]->tris,
                                m[b[j].shape]->ntris, "b", &mb, &err);
            for (int k = 0; k < 3 * ma->nverts; k++)
                ma->verts[k] *= b[i].size;
            for (int k = 0; k < 3 * mb->nverts; k++)
                mb->verts[k] *= b[j].size;
            pd_pose pa = {{b[i].x.x, b[i].x.y, b[i].x.z},
                          {b[i].q[0], b[i].q[1], b[i].q[2], b[i].q[3]}};
            pd_pose pb = {{b[j].x.x, b[j].x.y, b[j].x.z},
                          {b[j].q[0], b[j].q[1], b[j].q[2], b[j].q[3]}};
            pd_contact r;
            pd_overlap_host(ma, &pa, mb, &pb, 0, &r, &err);
            checked++;
            CHECK_EQ_INT(r.hit, o.hit);
            if (r.hit && o.hit) {
                hits++;
                double sz = b[i].size;
                CHECK_REL(r.volume, o.volume, 1e-10);
                CHECK_NEAR(r.centroid[0], o.centroid.x, 1e-10 * sz);
                CHECK_NEAR(r.centroid[1], o.centroid.y, 1e-10 * sz);
                CHECK_NEAR(r.centroid[2], o.centroid.z, 1e-10 * sz);
                CHECK_NEAR(r.normal[0], o.normal.x, 1e-9);
                CHECK_NEAR(r.normal[1], o.normal.y, 1e-9);
                CHECK_NEAR(r.normal[2], o.normal.z, 1e-9);
                CHECK_NEAR(r.depth, o.depth, 1e-9 * sz);
            }
            pd_mesh_destroy(ma);
            pd_mesh_destroy(mb);
        }
    printf("  %d pairs, %d overlapping\n", checked, hits);
    CHECK(hits >= 15); /* the test must exercise real contacts */

    /* the same pairs through the OpenCL kernel: the host build's numbers to 1e-12 (double) */
    pd_device *dev = NULL;
    pd_error err = {0};
    double x[3 * NBODY], q[4 * NBODY], size[NBODY], *dout = malloc(sizeof(double) * 12 * npairs);
    int shape[NBODY];
    for (int i = 0; i < NBODY; i++) {
        x[3 * i] = b[i].x.x;
        x[3 * i + 1] = b[i].x.y;
        x[3 * i + 2] = b[i].x.z;
        memcpy(q + 4 * i, b[i].q, sizeof b[i].q);
        size[i] = b[i].size;
        shape[i] = b[i].shape;
    }
    np_tables tabs = {NSHAPE, vert, unit_vol, tri, voff, toff, vt_off, vt};
    if (pd_device_open(-1, &dev, &err) != PD_OK ||
        np_run_cl(dev, &tabs, x, q, size, shape, NBODY, pairs, npairs, 1, dout, &err) != PD_OK) {
        TEST_FAILF("opencl narrow phase: %s", err.msg);
    } else {
        int agree = 1;
        for (int k = 0; k < npairs; k++) {
            const double *h = host + 12 * k, *d = dout + 12 * k;
            agree &= h[0] == d[0];
            for (int c = 4; c < 12; c++)
                agree &= fabs(h[c] - d[c]) <= 1e-12 * (fabs(h[c]) + (c == 4 ? 0 : b[0].size));
        }
        CHECK(agree);
    }
    pd_device_close(dev);
    free(dout);
    free(iscr);
    free(rscr);
    free(vert);
    free(tri);
    free(vt_off);
    free(vt);
    for (int s = 0; s < NSHAPE; s++)
        pd_mesh_destroy(m[s]);
}

int main(void)
{
    RUN(pairs_match_overlap_of_posed_scaled_meshes);
    return TEST_DONE();
}
