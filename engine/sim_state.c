/*
 * sim_state.c - setting up a run on a device: bodies, shape and material tables, the broad
 * phase's buffers and the kernels; host <-> device copies; the walls' prescribed motion.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PD_DOUBLE 1
#include "bvh.h"          /* BVH_CAND, float boxes */
#include "contact_pair.h" /* cp_* parameter layout, overlap scratch sizes, force-law helpers */
#include "overlap_run.h"
#include "sim.h"
#include "wall_tree.h"

static cl_mem mk(sim *m, size_t bytes, int *ok, cl_int *e)
{
    if (!*ok) return NULL;
    cl_mem b = clCreateBuffer(m->dev->ctx, CL_MEM_READ_WRITE, bytes ? bytes : 16, NULL, e);
    if (*e != CL_SUCCESS) *ok = 0;
    m->bytes += (double)bytes;
    return b;
}

int sim_write(sim *m, cl_mem b, size_t first, size_t cnt, const double *in, pd_error *err)
{
    if (cnt == 0) return PD_OK;
    void *h = malloc(m->rs * cnt);
    if (!h) return pd_error_set(err, PD_ENOMEM, "run: out of memory");
    for (size_t i = 0; i < cnt; i++) {
        if (m->dbl)
            ((double *)h)[i] = in[i];
        else
            ((float *)h)[i] = (float)in[i];
    }
    cl_int e = clEnqueueWriteBuffer(m->dev->queue, b, CL_TRUE, m->rs * first, m->rs * cnt, h, 0,
                                    NULL, NULL);
    free(h);
    return e == CL_SUCCESS ? PD_OK : CL_FAIL(err, "clEnqueueWriteBuffer", e);
}

/* Reads cnt doubles (dbl) or floats of b from element `first` into doubles. */
static int read_as_doubles(sim *m, cl_mem b, int dbl, size_t first, size_t cnt, double *out,
                           pd_error *err)
{
    if (cnt == 0) return PD_OK;
    cl_int e;
    if (dbl) { /* straight into out: a stats row of a large run is mostly these reads */
        e = clEnqueueReadBuffer(m->dev->queue, b, CL_TRUE, sizeof(double) * first,
                                sizeof(double) * cnt, out, 0, NULL, NULL);
        return e == CL_SUCCESS ? PD_OK : CL_FAIL(err, "clEnqueueReadBuffer", e);
    }
    float *h = malloc(sizeof(float) * cnt);
    if (!h) return pd_error_set(err, PD_ENOMEM, "run: out of memory");
    e = clEnqueueReadBuffer(m->dev->queue, b, CL_TRUE, sizeof(float) * first, sizeof(float) * cnt,
                            h, 0, NULL, NULL);
    if (e == CL_SUCCESS)
        for (size_t i = 0; i < cnt; i++)
            out[i] = h[i];
    free(h);
    return e == CL_SUCCESS ? PD_OK : CL_FAIL(err, "clEnqueueReadBuffer", e);
}

int sim_read(sim *m, cl_mem b, size_t first, size_t cnt, double *out, pd_error *err)
{
    return read_as_doubles(m, b, m->dbl, first, cnt, out, err);
}

int sim_read_info(sim *m, size_t cnt, double *out, pd_error *err)
{
    return read_as_doubles(m, m->info, 0, 0, cnt, out, err);
}

/* All zero bytes: a zero of either precision. */
cl_int sim_zero_reals(sim *m, cl_mem b, size_t cnt)
{
    double z = 0;
    return clEnqueueFillBuffer(m->dev->queue, b, &z, m->rs, 0, cnt * m->rs, 0, NULL, NULL);
}

static int write_ints(sim *m, cl_mem b, size_t cnt, const int *in, pd_error *err)
{
    if (cnt == 0) return PD_OK;
    cl_int e =
        clEnqueueWriteBuffer(m->dev->queue, b, CL_TRUE, 0, sizeof(int) * cnt, in, 0, NULL, NULL);
    return e == CL_SUCCESS ? PD_OK : CL_FAIL(err, "clEnqueueWriteBuffer", e);
}

/* v turned by the quaternion q. */
static void rotate(const double q[4], const double v[3], double out[3])
{
    double r[3][3];
    pd_quat_to_matrix(q, r);
    for (int i = 0; i < 3; i++)
        out[i] = r[i][0] * v[0] + r[i][1] * v[1] + r[i][2] * v[2];
}

/*
 * Writes the walls' bodies (x, q, v, w at body n + i) and boxes without blocking: converted into
 * m->wall_stage, which the writes read until they complete, so the last step's writes are waited
 * for first (long done by then: each step reads the device's status back).
 */
static int stage_walls(sim *m, int W, const double *x, const double *q, const double *v,
                       const double *w, const double *box, pd_error *err)
{
    size_t rs = m->rs, nr = 13 * (size_t)W; /* reals: x 3, q 4, v 3, w 3 per wall */
    if (m->wall_ev) {
        cl_int e = clWaitForEvents(1, &m->wall_ev);
        clReleaseEvent(m->wall_ev);
        m->wall_ev = NULL;
        if (e != CL_SUCCESS) return CL_FAIL(err, "clWaitForEvents(wall writes)", e);
    }
    if (!m->wall_stage && !(m->wall_stage = malloc(rs * nr + sizeof(float) * 6 * (size_t)W)))
        return pd_error_set(err, PD_ENOMEM, "run: out of memory");
    const double *part[4] = {x, q, v, w};
    const size_t len[4] = {3, 4, 3, 3};
    size_t off[4], at = 0;
    for (int a = 0; a < 4; a++) {
        off[a] = at;
        for (size_t i = 0; i < len[a] * (size_t)W; i++, at++) {
            if (m->dbl)
                ((double *)m->wall_stage)[at] = part[a][i];
            else
                ((float *)m->wall_stage)[at] = (float)part[a][i];
        }
    }
    float *fb = (float *)((char *)m->wall_stage + rs * nr);
    for (int i = 0; i < W; i++)
        for (int k = 0; k < 3; k++) {
            fb[6 * i + k] = bvh_down(box[6 * i + k]);
            fb[6 * i + 3 + k] = bvh_up(box[6 * i + 3 + k]);
        }
    size_t b0 = (size_t)m->n;
    cl_mem dst[4] = {m->x, m->q, m->v, m->w};
    /* the walls' angular velocities are the only bodies of w */
    size_t first[4] = {3 * b0, 4 * b0, 3 * b0, 0};
    cl_int e = CL_SUCCESS;
    for (int a = 0; a < 4 && e == CL_SUCCESS; a++)
        e = clEnqueueWriteBuffer(m->dev->queue, dst[a], CL_FALSE, rs * first[a],
                                 rs * len[a] * (size_t)W, (char *)m->wall_stage + rs * off[a], 0,
                                 NULL, NULL);
    if (e == CL_SUCCESS)
        e = clEnqueueWriteBuffer(m->dev->queue, m->wbox, CL_FALSE, 0, sizeof(float) * 6 * (size_t)W,
                                 fb, 0, NULL, &m->wall_ev);
    if (e != CL_SUCCESS) {
        clFinish(m->dev->queue); /* the writes enqueued may still read the stage */
        return CL_FAIL(err, "clEnqueueWriteBuffer(walls)", e);
    }
    return PD_OK;
}

/*
 * A wall translates with its velocity and turns at its angular velocity about its center, which
 * moves with it: at time t its centroid is center + v t + R(omega t) (c0 - center)
 * (pd_wall_rotation).
 */
int sim_walls_at(sim *m, double t, pd_error *err)
{
    int W = m->nwall;
    if (W == 0) return PD_OK;
    double *x = malloc(sizeof(double) * 3 * W), *q = malloc(sizeof(double) * 4 * W);
    double *v = malloc(sizeof(double) * 3 * W), *w = malloc(sizeof(double) * 3 * W);
    double *box = malloc(sizeof(double) * 6 * W);
    int rc = PD_OK;
    if (!x || !q || !v || !w || !box) {
        rc = pd_error_set(err, PD_ENOMEM, "run: out of memory");
        goto done;
    }
    for (int i = 0; i < W; i++) {
        const sc_wall *wl = &m->s->wall[i];
        double rel[3], rr[3];
        for (int k = 0; k < 3; k++)
            rel[k] = m->wall_c0[3 * i + k] - wl->center[k];
        pd_wall_rotation(wl->angular_velocity, t, q + 4 * i);
        rotate(q + 4 * i, rel, rr);
        for (int k = 0; k < 3; k++)
            x[3 * i + k] = wl->center[k] + wl->velocity[k] * t + rr[k];
        const double *om = wl->angular_velocity;
        double vr[3] = {om[1] * rr[2] - om[2] * rr[1], om[2] * rr[0] - om[0] * rr[2],
                        om[0] * rr[1] - om[1] * rr[0]};
        for (int k = 0; k < 3; k++) {
            v[3 * i + k] = wl->velocity[k] + vr[k];
            w[3 * i + k] = om[k];
            box[6 * i + k] = INFINITY;
            box[6 * i + 3 + k] = -INFINITY;
        }
        /* The box of the wall's box in its own frame, turned: it holds the turned mesh, and costs
         * 8 corners a step where the mesh's vertices (up to 1e5 and more for a CAD drum) cost
         * each a rotation; unturned (a translating wall, and every wall at t = 0) it is the
         * mesh's own box, to the same bits (rounding is monotonic). */
        const double *lb = m->wall_lbox + 6 * i;
        for (int c = 0; c < 8; c++) {
            double p[3] = {lb[(c & 1) ? 3 : 0], lb[(c & 2) ? 4 : 1], lb[(c & 4) ? 5 : 2]}, r[3];
            rotate(q + 4 * i, p, r);
            for (int k = 0; k < 3; k++) {
                double at = r[k] + x[3 * i + k];
                box[6 * i + k] = fmin(box[6 * i + k], at - m->margin - 0.5 * m->skin);
                box[6 * i + 3 + k] = fmax(box[6 * i + 3 + k], at + m->margin + 0.5 * m->skin);
            }
        }
    }
    rc = stage_walls(m, W, x, q, v, w, box, err);
    if (rc == PD_OK) m->wall_time = t;
done:
    free(x);
    free(q);
    free(v);
    free(w);
    free(box);
    return rc;
}

/*
 * The walls' triangle BVHs (thesis section 5.6), built in each wall's frame from the shape tables
 * (vert, tri; walls are shapes nshape ..), and wall_cap: the most triangles of one wall whose
 * boxes can meet the cube np_wall_local searches around any particle (wall_tree_max_near, for
 * the largest particle; allowing for the kernel's widening of the cube), which sizes the overlap
 * scratch independently of the walls' triangle counts.
 */
static int upload_wall_trees(sim *m, const double *vert, const int *tri, const int *voff,
                             const int *toff, pd_error *err)
{
    const pd_scenario *s = m->s;
    int W = s->nwall, rc = PD_OK;
    wall_tree *t = calloc((size_t)W + 1, sizeof *t);
    int *noff = calloc((size_t)W + 1, sizeof(int));
    if (!t || !noff) {
        free(t);
        free(noff);
        return pd_error_set(err, PD_ENOMEM, "run: out of memory for the walls' trees");
    }
    /* the cube's half-side: the largest circumradius, widened as wb_reach_box does, plus its
     * rounding allowance at ten times the scene's largest coordinate */
    double reach = 0, far = 0, eps = m->dbl ? 2.220446049250313e-16 : 1.1920929e-7;
    for (long i = 0; i < m->p->n; i++) {
        /* spheres reach their cohesion range beyond (margin: half the largest) */
        double r = s->shape[m->p->shape[i]].radius_ratio * m->p->size[i] + 2 * m->margin;
        reach = r > reach ? r : reach;
        for (int k = 0; k < 3; k++)
            far = fmax(far, fabs(m->p->x[3 * i + k]));
    }
    for (int j = voff[s->nshape]; j < voff[s->nshape + W]; j++)
        for (int k = 0; k < 3; k++)
            far = fmax(far, fabs(vert[3 * j + k]));
    double side = 2 * (reach * (1 + 2e-5) + 64 * eps * 10 * far);
    m->wall_cap = 0;
    for (int w = 0; w < W && rc == PD_OK; w++) {
        int sh = s->nshape + w;
        const double *v = vert + 3 * (size_t)voff[sh];
        const int *tr = tri + 3 * (size_t)toff[sh];
        int nt = toff[sh + 1] - toff[sh];
        rc = wall_tree_build(v, tr, nt, &t[w], s->wall[w].name, err);
        if (rc != PD_OK) break;
        noff[w + 1] = noff[w] + t[w].nnode;
        /* a particle that starts with its centre inside a wall would never be pushed out along
         * any sensible normal: refuse the scenario, naming both */
        long i = wall_tree_first_inside(&t[w], v, tr, m->p->x, m->p->n, m->wall_c0 + 3 * w);
        if (i >= 0) {
            const double *x = m->p->x + 3 * i;
            rc = pd_error_set(err, PD_EINVAL,
                              "/particles: particle %ld starts with its centre (%g, %g, %g) m "
                              "inside wall '%s': move the particles or the wall",
                              i, x[0], x[1], x[2], s->wall[w].name);
        }
        if (rc != PD_OK) break;
        int near = wall_tree_max_near(&t[w], v, tr, nt, side);
        if (near < 0) rc = pd_error_set(err, PD_ENOMEM, "run: out of memory for the walls' trees");
        m->wall_cap = near > m->wall_cap ? near : m->wall_cap;
    }
    int nn = noff[W];
    double *box = rc == PD_OK ? malloc(sizeof(double) * 6 * ((size_t)nn + 1)) : NULL;
    int *kid = rc == PD_OK ? malloc(sizeof(int) * 2 * ((size_t)nn + 1)) : NULL;
    int *order = rc == PD_OK ? calloc((size_t)toff[s->nshape + W] + 1, sizeof(int)) : NULL;
    if (rc == PD_OK && (!box || !kid || !order))
        rc = pd_error_set(err, PD_ENOMEM, "run: out of memory for the walls' trees");
    if (rc == PD_OK) {
        for (int w = 0; w < W; w++) {
            memcpy(box + 6 * (size_t)noff[w], t[w].box, sizeof(double) * 6 * (size_t)t[w].nnode);
            memcpy(kid + 2 * (size_t)noff[w], t[w].kid, sizeof(int) * 2 * (size_t)t[w].nnode);
            int sh = s->nshape + w;
            memcpy(order + toff[sh], t[w].order, sizeof(int) * (size_t)(toff[sh + 1] - toff[sh]));
        }
        cl_int e = CL_SUCCESS;
        int ok = 1;
        m->wnode_box = mk(m, m->rs * 6 * (size_t)nn, &ok, &e);
        m->wnode_kid = mk(m, sizeof(int) * 2 * (size_t)nn, &ok, &e);
        m->wnode_off = mk(m, sizeof(int) * ((size_t)W + 1), &ok, &e);
        m->wtri_order = mk(m, sizeof(int) * ((size_t)toff[s->nshape + W] + 1), &ok, &e);
        if (!ok) rc = CL_FAIL(err, "clCreateBuffer(wall trees)", e);
        if (rc == PD_OK) rc = sim_write(m, m->wnode_box, 0, 6 * (size_t)nn, box, err);
        if (rc == PD_OK) rc = write_ints(m, m->wnode_kid, 2 * (size_t)nn, kid, err);
        if (rc == PD_OK) rc = write_ints(m, m->wnode_off, (size_t)W + 1, noff, err);
        if (rc == PD_OK)
            rc = write_ints(m, m->wtri_order, (size_t)toff[s->nshape + W] + 1, order, err);
    }
    for (int w = 0; w < W; w++)
        wall_tree_free(&t[w]);
    free(t);
    free(noff);
    free(box);
    free(kid);
    free(order);
    return rc;
}

/* Shape tables: the scenario's shapes (size 1, body frame), then one per wall (metres, about
 * the wall's centroid). Also the largest triangle counts for the overlap scratch. */
static int upload_shapes(sim *m, pd_error *err)
{
    const pd_scenario *s = m->s;
    int ns = s->nshape + s->nwall;
    const pd_mesh **mesh = calloc((size_t)ns, sizeof *mesh);
    int *voff = calloc((size_t)ns + 1, sizeof(int)), *toff = calloc((size_t)ns + 1, sizeof(int));
    int *kind = calloc((size_t)ns, sizeof(int));
    double *rr = calloc((size_t)ns, sizeof(double));
    double *ui = calloc(3 * (size_t)ns, sizeof(double)); /* walls' stay 0: never integrated */
    double *vert = NULL;
    int *tri = NULL, *vt_off = NULL, *vt = NULL, *vc = NULL, *coff = NULL, rc = PD_OK;
    double *disc = NULL;
    if (!mesh || !voff || !toff || !kind || !rr || !ui) goto oom;
    int max_ta = 0, max_va = 0, max_tb = 0, max_vb = 0;
    for (int i = 0; i < ns; i++) {
        if (i < s->nshape) {
            const sc_shape *sh = &s->shape[i];
            mesh[i] = sh->mesh;
            kind[i] = sh->kind == SC_SHAPE_SPHERE;
            rr[i] = sh->radius_ratio;
            sc_shape_unit_inertia(sh, ui + 3 * i);
        } else {
            mesh[i] = s->wall[i - s->nshape].mesh;
        }
        int nv = mesh[i] && !kind[i] ? mesh[i]->nverts : 0;
        int nt = mesh[i] && !kind[i] ? mesh[i]->ntris : 0;
        voff[i + 1] = voff[i] + nv;
        toff[i + 1] = toff[i] + nt;
        if (i < s->nshape) { /* walls are met through their BVH: see upload_wall_trees */
            max_ta = nt > max_ta ? nt : max_ta;
            max_va = nv > max_va ? nv : max_va;
            max_tb = nt > max_tb ? nt : max_tb;
            max_vb = nv > max_vb ? nv : max_vb;
        }
    }
    vert = malloc(sizeof(double) * 3 * ((size_t)voff[ns] + 1));
    tri = malloc(sizeof(int) * 3 * ((size_t)toff[ns] + 1));
    vt_off = malloc(sizeof(int) * ((size_t)voff[ns] + ns + 1));
    vt = malloc(sizeof(int) * 3 * ((size_t)toff[ns] + 1));
    m->wall_local = malloc(sizeof(double) * 3 * ((size_t)voff[ns] - voff[s->nshape] + 1));
    m->wall_voff = calloc((size_t)s->nwall + 1, sizeof(int));
    m->wall_c0 = calloc(3 * (size_t)s->nwall + 1, sizeof(double));
    m->wall_lbox = malloc(sizeof(double) * (6 * (size_t)s->nwall + 1));
    if (!vert || !tri || !vt_off || !vt || !m->wall_local || !m->wall_voff || !m->wall_c0 ||
        !m->wall_lbox)
        goto oom;
    for (int i = 0; i < ns; i++) {
        const pd_mesh *me = mesh[i];
        if (kind[i]) {
            vt_off[voff[i] + i] = 0;
            continue;
        }
        double c[3] = {0, 0, 0};
        if (i >= s->nshape) { /* walls: about the centroid */
            int wi = i - s->nshape;
            pd_mass_props mp;
            pd_mesh_mass_props(me, &mp);
            memcpy(c, mp.centroid, sizeof c);
            memcpy(m->wall_c0 + 3 * wi, c, sizeof c);
            m->wall_voff[wi + 1] = m->wall_voff[wi] + me->nverts;
            for (int k = 0; k < 3; k++) {
                m->wall_lbox[6 * wi + k] = INFINITY;
                m->wall_lbox[6 * wi + 3 + k] = -INFINITY;
            }
        }
        for (int j = 0; j < me->nverts; j++)
            for (int k = 0; k < 3; k++) {
                double p = me->verts[3 * j + k] - c[k];
                vert[3 * (voff[i] + j) + k] = p;
                if (i < s->nshape) continue;
                double *lb = m->wall_lbox + 6 * (i - s->nshape);
                m->wall_local[3 * (m->wall_voff[i - s->nshape] + j) + k] = p;
                lb[k] = fmin(lb[k], p);
                lb[3 + k] = fmax(lb[3 + k], p);
            }
        memcpy(tri + 3 * toff[i], me->tris, sizeof(int) * 3 * me->ntris);
        int *off, *list;
        if (ovl_vertex_triangles(me, &off, &list) != PD_OK) goto oom;
        memcpy(vt_off + voff[i] + i, off, sizeof(int) * ((size_t)me->nverts + 1));
        memcpy(vt + 3 * toff[i], list, sizeof(int) * 3 * me->ntris);
        free(off);
        free(list);
    }
    m->nshape = ns;
    if ((rc = upload_wall_trees(m, vert, tri, voff, toff, err)) != PD_OK) goto done;
    /* the filter's vertex clusters, for the particles' shapes (walls are met through their BVH) */
    if (np_cluster_tables(vert, voff, ns, s->nshape, &vc, &coff, &disc) != PD_OK) goto oom;
    /* overlap scratch: particle pairs, or a particle and a wall's part near it (wall_cap) */
    int cap = m->wall_cap, cap_v = 3 * cap;
    m->pts_cap = ovl_pts_cap(max_ta, max_tb > cap ? max_tb : cap);
    m->ilen = ovl_iscratch_len(max_ta, max_tb, max_va, max_vb);
    m->rlen = ovl_rscratch_len(max_ta, max_tb, max_va, max_vb, m->pts_cap);
    if (cap > 0) {
        int il = np_wall_ilen(cap) + ovl_iscratch_len(max_ta, cap, max_va, cap_v);
        int rl = np_wall_rlen(cap) + ovl_rscratch_len(max_ta, cap, max_va, cap_v, m->pts_cap);
        m->ilen = il > m->ilen ? il : m->ilen;
        m->rlen = rl > m->rlen ? rl : m->rlen;
    }
    if (m->places) { /* the places' scratch follows the overlap's */
        m->ilen += ovl_places_ilen(m->pts_cap);
        m->rlen += ovl_places_rlen(m->pts_cap);
    }
    cl_int e = CL_SUCCESS;
    int ok = 1;
    m->vert = mk(m, m->rs * 3 * (size_t)voff[ns], &ok, &e);
    m->tri = mk(m, sizeof(int) * 3 * (size_t)toff[ns], &ok, &e);
    m->voff = mk(m, sizeof(int) * ((size_t)ns + 1), &ok, &e);
    m->toff = mk(m, sizeof(int) * ((size_t)ns + 1), &ok, &e);
    m->vt_off = mk(m, sizeof(int) * ((size_t)voff[ns] + ns), &ok, &e);
    m->vt = mk(m, sizeof(int) * 3 * (size_t)toff[ns], &ok, &e);
    size_t nvc = 2 * (size_t)voff[s->nshape] + 1, ndisc = NP_DISC_LEN * (size_t)coff[ns] + 1;
    m->vc = mk(m, sizeof(int) * nvc, &ok, &e);
    m->coff = mk(m, sizeof(int) * ((size_t)ns + 1), &ok, &e);
    m->disc = mk(m, m->rs * ndisc, &ok, &e);
    m->kind = mk(m, sizeof(int) * (size_t)ns, &ok, &e);
    m->radius_ratio = mk(m, m->rs * (size_t)ns, &ok, &e);
    m->unit_inertia = mk(m, m->rs * 3 * (size_t)ns, &ok, &e);
    if (!ok) {
        rc = CL_FAIL(err, "clCreateBuffer(shapes)", e);
        goto done;
    }
    rc = sim_write(m, m->vert, 0, 3 * (size_t)voff[ns], vert, err);
    if (rc == PD_OK) rc = write_ints(m, m->tri, 3 * (size_t)toff[ns], tri, err);
    if (rc == PD_OK) rc = write_ints(m, m->voff, (size_t)ns + 1, voff, err);
    if (rc == PD_OK) rc = write_ints(m, m->toff, (size_t)ns + 1, toff, err);
    if (rc == PD_OK) rc = write_ints(m, m->vt_off, (size_t)voff[ns] + ns, vt_off, err);
    if (rc == PD_OK) rc = write_ints(m, m->vt, 3 * (size_t)toff[ns], vt, err);
    if (rc == PD_OK) rc = write_ints(m, m->vc, nvc, vc, err);
    if (rc == PD_OK) rc = write_ints(m, m->coff, (size_t)ns + 1, coff, err);
    if (rc == PD_OK) rc = sim_write(m, m->disc, 0, ndisc, disc, err);
    if (rc == PD_OK) rc = write_ints(m, m->kind, (size_t)ns, kind, err);
    if (rc == PD_OK) rc = sim_write(m, m->radius_ratio, 0, (size_t)ns, rr, err);
    if (rc == PD_OK) rc = sim_write(m, m->unit_inertia, 0, 3 * (size_t)ns, ui, err);
    goto done;
oom:
    rc = pd_error_set(err, PD_ENOMEM, "run: out of memory for the shape tables");
done:
    free(mesh);
    free(voff);
    free(toff);
    free(kind);
    free(ui);
    free(rr);
    free(vert);
    free(tri);
    free(vt_off);
    free(vt);
    free(vc);
    free(coff);
    free(disc);
    return rc;
}

/* The contact parameters of every material pair (kernels/contact_pair.h, CP_*). */
static int upload_params(sim *m, pd_error *err)
{
    const pd_scenario *s = m->s;
    int M = s->nmat;
    double *par = calloc((size_t)M * M * CP_NPARAM, sizeof(double));
    if (!par) return pd_error_set(err, PD_ENOMEM, "run: out of memory");
    for (int a = 0; a < M; a++)
        for (int b = 0; b < M; b++) {
            const sc_interaction *in = sc_interaction_of(s, a, b);
            double *p = par + CP_NPARAM * (a * M + b);
            const sc_material *ma = &s->mat[a], *mb = &s->mat[b];
            p[CP_ESTAR] = cf_effective_modulus(ma->youngs_modulus, ma->poisson_ratio,
                                               mb->youngs_modulus, mb->poisson_ratio);
            p[CP_GSTAR] = cf_effective_shear(ma->shear_modulus, ma->poisson_ratio,
                                             mb->shear_modulus, mb->poisson_ratio);
            if (!in) continue; /* a pair no particles use (the parser checks used pairs) */
            p[CP_MODEL] = in->model == SC_MODEL_LINEAR;
            p[CP_MU] = in->friction;
            p[CP_GAMMA] = in->damping;
            p[CP_KC] = in->cohesion;
            p[CP_LE] = in->cohesion_range;
            p[CP_KE] = in->normal_stiffness;
            p[CP_KF] = in->tangential_stiffness;
            p[CP_ETA] = in->damping_coefficient;
            p[CP_PLACES] = in->separate_places;
            /* the contact's moments (contact_pair.h, cp_couple); the twisting spring's
             * modulus: the two bodies' shear compliances in series */
            if (in->contact_moments) {
                p[CP_GTWIST] = 1 / (1 / ma->shear_modulus + 1 / mb->shear_modulus);
                for (int k = 0; k < s->nshape; k++)
                    m->moments |= s->shape[k].kind == SC_SHAPE_MESH;
            }
            if (in->cohesion > 0 && 0.5 * in->cohesion_range > m->margin)
                m->margin = 0.5 * in->cohesion_range;
        }
    cl_int e = CL_SUCCESS;
    int ok = 1;
    m->params = mk(m, m->rs * (size_t)M * M * CP_NPARAM, &ok, &e);
    m->density = mk(m, m->rs * (size_t)M, &ok, &e);
    int rc = ok ? sim_write(m, m->params, 0, (size_t)M * M * CP_NPARAM, par, err)
                : CL_FAIL(err, "clCreateBuffer(params)", e);
    for (int a = 0; a < M && rc == PD_OK; a++) /* the integrator's inertia: see sim.h */
        par[a] = s->mat[a].density;
    if (rc == PD_OK) rc = sim_write(m, m->density, 0, (size_t)M, par, err);
    free(par);
    return rc;
}

/*
 * m->wall_speed: a bound on how fast any point of any wall moves. A wall's point p moves by
 * v t + (R(omega t) - 1)(p - center), at most (|v| + |omega| |p - center|) t.
 */
static void wall_speeds(sim *m)
{
    m->wall_speed = 0;
    for (int i = 0; i < m->nwall; i++) {
        const sc_wall *wl = &m->s->wall[i];
        const double *v = wl->velocity, *om = wl->angular_velocity;
        double r = 0;
        for (int j = m->wall_voff[i]; j < m->wall_voff[i + 1]; j++) {
            double d2 = 0;
            for (int k = 0; k < 3; k++) {
                double d = m->wall_c0[3 * i + k] + m->wall_local[3 * j + k] - wl->center[k];
                d2 += d * d;
            }
            r = fmax(r, sqrt(d2));
        }
        double speed = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) +
                       sqrt(om[0] * om[0] + om[1] * om[1] + om[2] * om[2]) * r;
        m->wall_speed = fmax(m->wall_speed, speed);
    }
}

/* Bodies: particle state from the scenario, walls placed by sim_walls_at(0). */
static int upload_bodies(sim *m, pd_error *err)
{
    const sc_particles *p = m->p;
    int n = m->n, B = m->nbody;
    double *L = malloc(sizeof(double) * 3 * n);
    double *inv_m = calloc((size_t)B, sizeof(double)), *size = calloc((size_t)B, sizeof(double));
    int *shape = calloc((size_t)B, sizeof(int)), *mat = calloc((size_t)B, sizeof(int));
    int rc = PD_OK;
    if (!L || !inv_m || !size || !shape || !mat) {
        rc = pd_error_set(err, PD_ENOMEM, "run: out of memory for %d particles", n);
        goto done;
    }
    for (int i = 0; i < n; i++) {
        double r[3][3], wb[3];
        pd_quat_to_matrix(p->q + 4 * i, r);
        /* L = R I R^T omega with I the principal (body) inertia */
        for (int k = 0; k < 3; k++)
            wb[k] = r[0][k] * p->w[3 * i] + r[1][k] * p->w[3 * i + 1] + r[2][k] * p->w[3 * i + 2];
        for (int k = 0; k < 3; k++) {
            L[3 * i + k] = r[k][0] * p->inertia[3 * i] * wb[0] +
                           r[k][1] * p->inertia[3 * i + 1] * wb[1] +
                           r[k][2] * p->inertia[3 * i + 2] * wb[2];
        }
        inv_m[i] = 1 / p->mass[i];
        size[i] = p->size[i];
        shape[i] = p->shape[i];
        mat[i] = p->material[i];
    }
    for (int wi = 0; wi < m->nwall; wi++) {
        size[n + wi] = 1;
        shape[n + wi] = m->s->nshape + wi;
        mat[n + wi] = m->s->wall[wi].material;
    }
    rc = sim_write(m, m->x, 0, 3 * (size_t)n, p->x, err);
    if (rc == PD_OK) rc = sim_write(m, m->q, 0, 4 * (size_t)n, p->q, err);
    if (rc == PD_OK) rc = sim_write(m, m->v, 0, 3 * (size_t)n, p->v, err);
    if (rc == PD_OK) rc = sim_write(m, m->L, 0, 3 * (size_t)n, L, err);
    if (rc == PD_OK) rc = sim_write(m, m->inv_m, 0, (size_t)B, inv_m, err);
    if (rc == PD_OK) rc = sim_write(m, m->size, 0, (size_t)B, size, err);
    if (rc == PD_OK) rc = write_ints(m, m->shape, (size_t)B, shape, err);
    if (rc == PD_OK) rc = write_ints(m, m->material, (size_t)B, mat, err);
    if (rc == PD_OK) rc = sim_walls_at(m, 0, err);
done:
    free(L);
    free(inv_m);
    free(size);
    free(shape);
    free(mat);
    return rc;
}

/* The Morton codes' scene box: the particles' and walls' extent at t = 0, padded by half its
 * size; particles that leave it still work (their codes clamp), the tree is only less tight. */
static void scene_box(sim *m)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int i = 0; i < m->n; i++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], m->p->x[3 * i + k]);
            hi[k] = fmax(hi[k], m->p->x[3 * i + k]);
        }
    for (int k = 0; k < 3; k++) {
        double ext = hi[k] - lo[k], pad = 0.5 * ext + 1e-3;
        m->lo[k] = lo[k] - pad;
        m->inv_ext[k] = 1 / (ext + 2 * pad);
    }
}

static const char *const kernel_names[][2] = {
    {"bvh", "bvh_codes"},
    {"broad_phase", "bvh_leaves"},
    {"bvh", "bvh_nodes"},
    {"bvh", "bvh_refit"},
    {"broad_phase", "broad_count"},
    {"broad_phase", "broad_write"},
    {"contact", "contact_forces"},
    {"contact", "history_count"},
    {"contact", "history_keep"},
    {"forces", "second_count"},
    {"forces", "second_fill"},
    {"forces", "body_forces"},
    {"integrate", "integrate_kick"},
    {"integrate", "integrate_drift"},
    {"stats", "stats_energy"},
    {"stats", "stats_contacts"},
};

static cl_kernel *kernel_slot(sim *m, int i)
{
    cl_kernel *slots[] = {
        &m->k_codes,     &m->k_leaves,       &m->k_nodes,        &m->k_refit,
        &m->k_count,     &m->k_write,        &m->k_contact,      &m->k_hist_count,
        &m->k_hist_keep, &m->k_second_count, &m->k_second_fill,  &m->k_body,
        &m->k_kick,      &m->k_drift,        &m->k_stats_energy, &m->k_stats_contacts};
    return slots[i];
}

#define NKERNELS ((int)(sizeof kernel_names / sizeof kernel_names[0]))

int sim_create(pd_device *dev, const pd_scenario *s, sim **out, pd_error *err)
{
    *out = NULL;
    if (s->double_precision && !dev->fp64)
        return pd_error_set(err, PD_EINVAL,
                            "/precision: device '%s' has no cl_khr_fp64 (double precision); use "
                            "\"precision\": \"single\" or another device",
                            dev->name);
    sim *m = calloc(1, sizeof *m);
    if (!m) return pd_error_set(err, PD_ENOMEM, "run: out of memory");
    m->dev = dev;
    m->s = s;
    m->dbl = s->double_precision;
    for (int k = 0; k < s->nint; k++) /* "contact_places": "separate" (kernels/overlap.h) */
        m->places |= s->inter[k].separate_places;
    /* single precision rescues contacts through the places (OVL_RESCUE, overlap_predicates.h) */
    m->places |= !m->dbl;
    m->rs = m->dbl ? sizeof(double) : sizeof(float);
    m->dt = s->dt;
    m->nwall = s->nwall;
    m->nmat = s->nmat;
    int rc = sc_particles_create(s, &m->p, err);
    if (rc != PD_OK) goto fail;
    if (m->p->n > 0x7fffffff / 2) {
        rc = pd_error_set(err, PD_EINVAL, "/particles: %ld particles are more than a run holds",
                          m->p->n);
        goto fail;
    }
    m->n = (int)m->p->n;
    if (m->n < 1) {
        rc = pd_error_set(err, PD_EINVAL, "/particles: the scenario has no particles");
        goto fail;
    }
    m->nbody = m->n + m->nwall;
    for (int i = 0; i < s->nwall; i++) {
        const double *v = s->wall[i].velocity, *w = s->wall[i].angular_velocity;
        if (v[0] || v[1] || v[2] || w[0] || w[1] || w[2]) m->walls_move = 1;
    }
    for (int i = 0; i < NKERNELS; i++) {
        cl_program prog;
        rc = cl_program_get(dev, kernel_names[i][0], m->dbl | (m->places ? CL_PLACES : 0), &prog,
                            err);
        if (rc != PD_OK) goto fail;
        cl_int e;
        *kernel_slot(m, i) = clCreateKernel(prog, kernel_names[i][1], &e);
        if (e != CL_SUCCESS) {
            rc = CL_FAIL(err, kernel_names[i][1], e);
            goto fail;
        }
    }
    rc = dsort_init(&m->sort, dev, m->dbl, err);
    if (rc != PD_OK) goto fail;
    size_t n = (size_t)m->n, B = (size_t)m->nbody, rs = m->rs, W = (size_t)m->nwall;
    cl_int e = CL_SUCCESS;
    int ok = 1;
    m->x = mk(m, rs * 3 * B, &ok, &e);
    m->q = mk(m, rs * 4 * B, &ok, &e);
    m->v = mk(m, rs * 3 * B, &ok, &e);
    /* angular velocities of the walls only: a particle's follows from its L and q (cp_omega) */
    m->w = mk(m, rs * 3 * W, &ok, &e);
    m->size = mk(m, rs * B, &ok, &e);
    m->inv_m = mk(m, rs * B, &ok, &e);
    m->shape = mk(m, sizeof(int) * B, &ok, &e);
    m->material = mk(m, sizeof(int) * B, &ok, &e);
    m->L = mk(m, rs * 3 * n, &ok, &e);
    /* f holds the traversal's candidates too (m->cand below): BVH_CAND ints a particle, more
     * than its 3 reals in single precision */
    size_t f_per = rs * 3 > sizeof(int) * BVH_CAND ? rs * 3 : sizeof(int) * BVH_CAND;
    m->f = mk(m, f_per * n, &ok, &e);
    m->t = mk(m, rs * 3 * n, &ok, &e);
    m->wbox = mk(m, sizeof(float) * 6 * W, &ok, &e);
    m->tbox = mk(m, sizeof(float) * 6 * (2 * n - 1), &ok, &e); /* boxes are floats (bvh.h) */
    m->left = mk(m, sizeof(int) * n, &ok, &e);
    m->right = mk(m, sizeof(int) * n, &ok, &e);
    m->parent = mk(m, sizeof(int) * 2 * n, &ok, &e);
    m->codes = mk(m, sizeof(cl_ulong) * n, &ok, &e);
    m->idx = mk(m, sizeof(int) * n, &ok, &e);
    m->count = mk(m, sizeof(int) * n, &ok, &e);
    /* the refit's arrival counters share count's memory: count is free from keep_history's end
     * until broad_count, which runs after the refit (one in-order queue) */
    if (ok && (e = clRetainMemObject(m->count)) == CL_SUCCESS)
        m->arrivals = m->count;
    else
        ok = 0;
    m->offset = mk(m, sizeof(int) * (n + 1), &ok, &e);
    m->carry_offset = mk(m, sizeof(int) * (n + 1), &ok, &e);
    m->status = mk(m, sizeof(int) * 3, &ok, &e);
    m->x_ref = mk(m, rs * 3 * n, &ok, &e);
    m->travel = mk(m, rs * n, &ok, &e);
    m->second_count = mk(m, sizeof(int) * n, &ok, &e);
    m->second_off = mk(m, sizeof(int) * (n + 1), &ok, &e);
    /*
     * Scratch of the broad phase in arrays it leaves free (as arrivals in count above), 44 bytes
     * a particle in double precision: the forces f and torques t are dead from a step's first
     * kick to its gather, the broad phase included (sim_step), and second_count outside the
     * gather's second_lists. The traversal's candidates live in f, the radix sort's key scratch
     * in t (8 bytes a particle, within its 3 reals) and its value scratch in second_count.
     */
    cl_mem *alias[3][2] = {
        {&m->cand, &m->f}, {&m->codes_tmp, &m->t}, {&m->idx_tmp, &m->second_count}};
    for (int i = 0; i < 3 && ok; i++) {
        if ((e = clRetainMemObject(*alias[i][1])) == CL_SUCCESS)
            *alias[i][0] = *alias[i][1];
        else
            ok = 0;
    }
    /* stats rows: a few work-items per compute unit, fewer where the walls' partial sums (six
     * reals per wall and work-item) would pass 16 MiB */
    long parts = 64L * (dev->compute_units > 0 ? dev->compute_units : 1);
    long wall_parts = 16L * 1048576 / (long)(6 * rs * (W > 0 ? W : 1));
    if (parts > wall_parts) parts = wall_parts > 1 ? wall_parts : 1;
    m->stat_parts = (int)parts;
    m->st_sum = mk(m, rs * (size_t)parts, &ok, &e);
    m->st_emax = mk(m, rs * (size_t)parts, &ok, &e);
    m->st_imax = mk(m, sizeof(int) * (size_t)parts, &ok, &e);
    m->st_count = mk(m, sizeof(int) * (size_t)parts, &ok, &e);
    m->st_ratio = mk(m, sizeof(float) * (size_t)parts, &ok, &e);
    m->st_wall = mk(m, rs * 6 * W * (size_t)parts, &ok, &e);
    if (!ok) {
        rc = CL_FAIL(err, "clCreateBuffer(particles)", e);
        goto fail;
    }
    /* the contact stage's scratch: one overlap per work-item at a time */
    if ((rc = upload_params(m, err)) != PD_OK || (rc = upload_shapes(m, err)) != PD_OK) goto fail;
    wall_speeds(m);
    /* Contact work-items: enough work-groups of 64 (cl_launch) to fill every compute unit
     * several times over, within a scratch budget (an overlap of 1280-triangle shapes needs
     * ~250 KB of scratch per work-item). A GPU's is a quarter of its memory: a fixed 1 GiB held
     * an H200 to 4 096 of the 33 792 work-items it keeps resident for such shapes. */
    double per_item = sizeof(int) * (double)m->ilen + (double)rs * m->rlen;
    int items;
    double budget;
    pd_device_capacity(dev, &items, &budget);
    if (!dev->gpu) budget = 128.0 * 1048576;
    long nwork = items;
    if (nwork * per_item > budget) nwork = (long)(budget / per_item);
    nwork = nwork / 64 * 64;
    m->nwork = nwork < 64 ? 64 : (int)nwork;
    m->iscr = mk(m, sizeof(int) * (size_t)m->nwork * (size_t)m->ilen, &ok, &e);
    m->rscr = mk(m, rs * (size_t)m->nwork * (size_t)m->rlen, &ok, &e);
    if (!ok) {
        rc = CL_FAIL(err, "clCreateBuffer(overlap scratch)", e);
        goto fail;
    }
    /* the Verlet skin, a tenth of the smallest particle: 0.02 m particles falling at 1 m/s with
     * dt = 1e-5 s rebuild the pair list every 100 steps, a resting bed almost never */
    double dmin = INFINITY;
    for (long i = 0; i < m->p->n; i++)
        dmin = fmin(dmin, m->p->size[i]);
    m->skin = 0.1 * dmin;
    if ((rc = upload_bodies(m, err)) != PD_OK) goto fail;
    cl_int status0[3] = {0, 0x7fffffff, 0x7fffffff}; /* INT_MAX: nothing found */
    e = sim_zero_reals(m, m->travel, n);             /* no travel yet */
    if (e == CL_SUCCESS)
        e = clEnqueueWriteBuffer(dev->queue, m->status, CL_TRUE, 0, sizeof status0, status0, 0,
                                 NULL, NULL);
    if (e != CL_SUCCESS) {
        rc = CL_FAIL(err, "clEnqueueWriteBuffer(status)", e);
        goto fail;
    }
    scene_box(m);
    *out = m;
    return PD_OK;
fail:
    sim_destroy(m);
    return rc;
}

static void release(cl_mem *b)
{
    if (*b) clReleaseMemObject(*b);
    *b = NULL;
}

void sim_destroy(sim *m)
{
    if (!m) return;
    cl_mem *bufs[] = {&m->x,
                      &m->q,
                      &m->v,
                      &m->w,
                      &m->size,
                      &m->inv_m,
                      &m->shape,
                      &m->material,
                      &m->L,
                      &m->unit_inertia,
                      &m->density,
                      &m->f,
                      &m->t,
                      &m->vert,
                      &m->tri,
                      &m->voff,
                      &m->toff,
                      &m->vt_off,
                      &m->vt,
                      &m->vc,
                      &m->coff,
                      &m->disc,
                      &m->kind,
                      &m->radius_ratio,
                      &m->params,
                      &m->wnode_box,
                      &m->wnode_kid,
                      &m->wnode_off,
                      &m->wtri_order,
                      &m->wbox,
                      &m->tbox,
                      &m->left,
                      &m->right,
                      &m->parent,
                      &m->arrivals,
                      &m->codes,
                      &m->idx,
                      &m->codes_tmp,
                      &m->idx_tmp,
                      &m->count,
                      &m->offset,
                      &m->carry_offset,
                      &m->status,
                      &m->x_ref,
                      &m->travel,
                      &m->pairs.keys,
                      &m->pairs.spring,
                      &m->pairs.kt,
                      &m->pairs.point,
                      &m->pairs.twist,
                      &m->carry.keys,
                      &m->carry.spring,
                      &m->carry.kt,
                      &m->carry.point,
                      &m->carry.twist,
                      &m->force,
                      &m->torque,
                      &m->info,
                      &m->second_list,
                      &m->second_count,
                      &m->second_off,
                      &m->cand,
                      &m->st_sum,
                      &m->st_emax,
                      &m->st_imax,
                      &m->st_count,
                      &m->st_ratio,
                      &m->st_wall,
                      &m->iscr,
                      &m->rscr};
    for (size_t i = 0; i < sizeof bufs / sizeof bufs[0]; i++)
        release(bufs[i]);
    for (int i = 0; i < NKERNELS; i++)
        if (*kernel_slot(m, i)) clReleaseKernel(*kernel_slot(m, i));
    if (m->sort.dev) dsort_free(&m->sort);
    sc_particles_destroy(m->p);
    if (m->wall_ev) {
        clWaitForEvents(1, &m->wall_ev); /* the write reads wall_stage until it completes */
        clReleaseEvent(m->wall_ev);
    }
    free(m->wall_stage);
    free(m->wall_lbox);
    free(m->wall_c0);
    free(m->wall_local);
    free(m->wall_voff);
    free(m);
}
