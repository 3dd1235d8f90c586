/* overlap.c - the overlap of two posed meshes on the host (pd_overlap_host) and its set-up. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "overlap_run.h"

int ovl_pts_cap(int nta, int ntb)
{
    /* An overlap's nodes number a few per triangle that reaches into it; beyond this the kernel
     * recomputes the depth in a second sweep instead of storing nodes. */
    return 256 + (nta + ntb) / 2;
}

/* Unit quaternion of q; 0 when q is zero or not finite. */
static int quat_normalised(const double q[4], double out[4])
{
    return pd_quat_normalize(q, out) == PD_OK;
}

int ovl_vertex_triangles(const pd_mesh *m, int **off_out, int **vt_out)
{
    int *off = calloc((size_t)m->nverts + 1, sizeof *off);
    int *vt = malloc(sizeof *vt * 3 * (size_t)m->ntris);
    if (!off || !vt) {
        free(off);
        free(vt);
        return PD_ENOMEM;
    }
    for (int i = 0; i < 3 * m->ntris; i++)
        off[m->tris[i] + 1]++;
    for (int v = 0; v < m->nverts; v++)
        off[v + 1] += off[v];
    for (int t = 0; t < m->ntris; t++) /* off[v] walks forward as v's triangles are placed */
        for (int q = 0; q < 3; q++)
            vt[off[m->tris[3 * t + q]]++] = t;
    for (int v = m->nverts; v > 0; v--)
        off[v] = off[v - 1]; /* and is shifted back */
    off[0] = 0;
    *off_out = off;
    *vt_out = vt;
    return PD_OK;
}

int ovl_setup_make(const pd_mesh *a, const pd_pose *pa, const pd_mesh *b, const pd_pose *pb,
                   int flags, ovl_setup *s, pd_error *err)
{
    pd_mass_props ma, mb;
    double qa[4], qb[4], qr[4];
    memset(s, 0, sizeof *s);
    if (!quat_normalised(pa->q, qa) || pd_quat_to_matrix(qa, s->ra) != PD_OK)
        return pd_error_set(err, PD_EINVAL, "pose of A: quaternion is zero or not finite");
    if (!quat_normalised(pb->q, qb))
        return pd_error_set(err, PD_EINVAL, "pose of B: quaternion is zero or not finite");
    /* B's orientation relative to A, conj(qa) * qb: for equal orientations its vector part is
     * exactly zero, so coincident or aligned shapes stay exactly degenerate in A's frame and
     * the symbolic perturbation resolves them (a product of two matrices would leave 1e-16s). */
    qr[0] = qa[0] * qb[0] + qa[1] * qb[1] + qa[2] * qb[2] + qa[3] * qb[3];
    /* terms paired so that each pair cancels exactly when qa == qb */
    qr[1] = (qa[0] * qb[1] - qa[1] * qb[0]) + (qa[3] * qb[2] - qa[2] * qb[3]);
    qr[2] = (qa[0] * qb[2] - qa[2] * qb[0]) + (qa[1] * qb[3] - qa[3] * qb[1]);
    qr[3] = (qa[0] * qb[3] - qa[3] * qb[0]) + (qa[2] * qb[1] - qa[1] * qb[2]);
    double rr[3][3];
    if (pd_quat_to_matrix(qr, rr) != PD_OK)
        return pd_error_set(err, PD_EINVAL, "pose of B: quaternion is zero or not finite");
    pd_mesh_mass_props(a, &ma);
    pd_mesh_mass_props(b, &mb);
    s->va = malloc(sizeof(double) * 3 * (size_t)a->nverts);
    if (!s->va || ovl_vertex_triangles(a, &s->vt_a_off, &s->vt_a) != PD_OK ||
        ovl_vertex_triangles(b, &s->vt_b_off, &s->vt_b) != PD_OK) {
        ovl_setup_free(s);
        return pd_error_set(err, PD_ENOMEM, "overlap: out of memory");
    }
    /* A's frame: A's mesh axes, origin at A's centroid (figure 5.4) */
    for (int i = 0; i < a->nverts; i++)
        for (int k = 0; k < 3; k++)
            s->va[3 * i + k] = a->verts[3 * i + k] - ma.centroid[k];
    /* the filter's clusters, in the frames the kernel reads the vertices in */
    if (ovl_vertex_clusters(s->va, a->nverts, &s->vc_a, &s->disc_a) != PD_OK ||
        ovl_vertex_clusters(b->verts, b->nverts, &s->vc_b, &s->disc_b) != PD_OK) {
        ovl_setup_free(s);
        return pd_error_set(err, PD_ENOMEM, "overlap: out of memory");
    }
    s->ta = a->tris;
    s->nva = a->nverts;
    s->nta = a->ntris;
    s->vb = b->verts;
    s->tb = b->tris;
    s->nvb = b->nverts;
    s->ntb = b->ntris;
    /* p_A = Ra^T (Rb v + xb - xa) - ca = R(conj(qa) qb) v + Ra^T (xb - xa) - ca */
    double dx[3];
    for (int k = 0; k < 3; k++)
        dx[k] = pb->x[k] - pa->x[k];
    for (int i = 0; i < 3; i++) {
        double acc = 0;
        for (int j = 0; j < 3; j++)
            s->rot[3 * i + j] = rr[i][j];
        for (int k = 0; k < 3; k++)
            acc += s->ra[k][i] * dx[k];
        s->tr[i] = acc - ma.centroid[i];
    }
    for (int i = 0; i < 3; i++) {
        s->ca[i] = 0;
        s->cb[i] = s->rot[3 * i] * mb.centroid[0] + s->rot[3 * i + 1] * mb.centroid[1] +
                   s->rot[3 * i + 2] * mb.centroid[2] + s->tr[i];
        s->ca_mesh[i] = ma.centroid[i];
        s->xa[i] = pa->x[i];
    }
    s->flags = flags;
    return PD_OK;
}

void ovl_setup_free(ovl_setup *s)
{
    free(s->va);
    free(s->vt_a_off);
    free(s->vt_a);
    free(s->vt_b_off);
    free(s->vt_b);
    free(s->vc_a);
    free(s->vc_b);
    free(s->disc_a);
    free(s->disc_b);
    s->va = NULL;
    s->vt_a_off = s->vt_a = s->vt_b_off = s->vt_b = NULL;
    s->vc_a = s->vc_b = NULL;
    s->disc_a = s->disc_b = NULL;
}

int ovl_result_equal(const ovl_result *x, const ovl_result *y)
{
    int eq = x->hit == y->hit && x->kept_a == y->kept_a && x->kept_b == y->kept_b &&
             x->volume == y->volume && x->depth == y->depth && x->places == y->places &&
             x->places_known == y->places_known && x->vol_eff == y->vol_eff &&
             x->depth_eff == y->depth_eff;
    for (int k = 0; k < 3; k++)
        eq = eq && x->centroid[k] == y->centroid[k] && x->normal[k] == y->normal[k] &&
             x->point_eff[k] == y->point_eff[k];
    return eq;
}

void ovl_result_to_world(const ovl_setup *s, const ovl_result *r, pd_contact *out)
{
    memset(out, 0, sizeof *out);
    out->hit = r->hit;
    out->degenerate = r->degenerate;
    out->tris_a = r->kept_a;
    out->tris_b = r->kept_b;
    out->places_known = r->places_known;
    if (!r->hit) return;
    out->volume = r->volume;
    out->depth = r->depth;
    out->places = r->places;
    out->effective_volume = r->vol_eff;
    out->effective_depth = r->depth_eff;
    for (int i = 0; i < 3; i++) {
        double c = s->xa[i], n = 0, pe = s->xa[i];
        for (int k = 0; k < 3; k++) {
            c += s->ra[i][k] * (r->centroid[k] + s->ca_mesh[k]);
            n += s->ra[i][k] * r->normal[k];
            pe += s->ra[i][k] * (r->point_eff[k] + s->ca_mesh[k]);
        }
        out->centroid[i] = c;
        out->normal[i] = n;
        out->effective_point[i] = pe;
    }
}

int pd_overlap_host(const pd_mesh *a, const pd_pose *pa, const pd_mesh *b, const pd_pose *pb,
                    int flags, pd_contact *out, pd_error *err)
{
    ovl_setup s;
    ovl_result r;
    int rc = ovl_setup_make(a, pa, b, pb, flags, &s, err);
    if (rc != PD_OK) return rc;
    rc = (flags & PD_OVERLAP_SINGLE) ? ovl_run_f32(&s, &r) : ovl_run_f64(&s, &r);
    if (rc != PD_OK) {
        ovl_setup_free(&s);
        return pd_error_set(err, rc, "overlap: out of memory");
    }
    ovl_result_to_world(&s, &r, out);
    ovl_setup_free(&s);
    return PD_OK;
}
