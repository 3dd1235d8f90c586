/*
 * overlap_run.h - engine-internal glue between meshes and poses (doubles) and the overlap kernel
 * of kernels/overlap.h, which is compiled once per precision (overlap_f32.c, overlap_f64.c) on the
 * host and once per precision on each OpenCL device (cl_device.c).
 */
#ifndef PD_OVERLAP_RUN_H
#define PD_OVERLAP_RUN_H

#include "polydem.h"

/* One overlap problem in A's frame, in doubles: what the kernel's ovl_in holds. */
typedef struct ovl_setup {
    double *va; /* A's vertices in A's frame (owned: ovl_setup_free) */
    const int *ta;
    int nva, nta;
    const double *vb; /* B's vertices in B's mesh frame */
    const int *tb;
    int nvb, ntb;
    int *vt_a_off, *vt_a, *vt_b_off, *vt_b; /* vertex -> triangle tables (owned) */
    int *vc_a, *vc_b;                       /* vertex clusters of va and vb (owned) */
    double *disc_a, *disc_b;                /* and their discs */
    double rot[9], tr[3];                   /* B's frame -> A's frame */
    double ca[3], cb[3];                    /* centroids in A's frame */
    int flags;
    double org[3]; /* OVL_ORIGIN in flags: the first sum's origin, A's frame */
    /* A's frame -> world: world = ra * (p + ca_mesh) + xa */
    double ra[3][3], ca_mesh[3], xa[3];
} ovl_setup;

typedef struct ovl_result {
    int hit, degenerate, kept_a, kept_b;
    double volume, centroid[3], normal[3], depth;
    int places;                /* OVL_PLACES (always asked for by ovl_run_*): separate places */
    int places_known;          /* 0: places is 1 because they could not be told (ovl_out) */
    double vol_eff, depth_eff; /* the force law's volume and depth over them (ovl_places) */
    double point_eff[3];       /* where their summed force acts, A's frame */
} ovl_result;

/* Reals in a kernel's result record (OVL_OUT_LEN in kernels/overlap_predicates.h). */
#define OVL_RESULT_LEN 19
/* Reals in a cluster's disc (OVL_DISC, ibid.). */
#define NP_DISC_LEN 9

/* Whether x and y are the same result to the bit (every field but degenerate): what the host
 * and a kernel built from the same source, or two filters that keep the same triangles, give. */
int ovl_result_equal(const ovl_result *x, const ovl_result *y);

/* Runs the host build of the kernel. Returns PD_OK or PD_ENOMEM. */
int ovl_run_f64(const ovl_setup *s, ovl_result *r);
int ovl_run_f32(const ovl_setup *s, ovl_result *r);

/* Scratch one overlap of s needs, OVL_PLACES's included: ints and reals (of the kernel's
 * precision). */
void ovl_scratch_len(const ovl_setup *s, size_t *ints, size_t *reals);

/* Capacity of the node buffer used for the depth; larger overlaps recompute instead. */
int ovl_pts_cap(int nta, int ntb);

/*
 * Sets up the overlap of A at pa with B at pb: A's frame is A's mesh frame shifted to A's centroid
 * (figure 5.4), B is mapped into it. Returns PD_OK, PD_EINVAL (bad quaternion) or PD_ENOMEM.
 */
int ovl_setup_make(const pd_mesh *a, const pd_pose *pa, const pd_mesh *b, const pd_pose *pb,
                   int flags, ovl_setup *s, pd_error *err);
void ovl_setup_free(ovl_setup *s);

/* Vertex -> triangle table of m in CSR form (see ovl_in in kernels/overlap.h): the triangles of
 * vertex i are (*vt)[(*off)[i] .. (*off)[i+1]-1]. Returns PD_OK or PD_ENOMEM; free both. */
int ovl_vertex_triangles(const pd_mesh *m, int **off, int **vt);

/*
 * Vertex clusters of the nv vertices v (xyz) for the filter (ovl_in's vc_* and disc_*, kernels/
 * overlap_predicates.h): *vc receives 2 nv ints, *disc OVL_DISC reals per cluster
 * (ovl_nclusters). Returns PD_OK or PD_ENOMEM; free both.
 */
int ovl_vertex_clusters(const double *v, int nv, int **vc, double **disc);
/* Reals in the discs of nv vertices' clusters. */
size_t ovl_discs_len(int nv);

/*
 * The clusters of the first nclust of nshape concatenated shapes (vertices vert[3 voff[s] ..],
 * as kernels/narrow_phase.h stores them), as np_shapes reads them: shape s's vc at
 * (*vc)[2 voff[s] ..], its discs at (*disc)[OVL_DISC (*coff)[s] ..]; the later shapes (walls,
 * met through their BVH) get none, coff[s + 1] == coff[s]. *coff has nshape + 1 entries. Returns
 * PD_OK or PD_ENOMEM; free all three.
 */
int np_cluster_tables(const double *vert, const int *voff, int nshape, int nclust, int **vc,
                      int **coff, double **disc);

/* Converts a result in A's frame into a world-frame pd_contact. */
void ovl_result_to_world(const ovl_setup *s, const ovl_result *r, pd_contact *out);

/*
 * Runs the OpenCL kernel for npairs placements of B against A (cl_device.c), with the overlap's
 * places when s->flags has PD_OVERLAP_PLACES (pd_overlap_cl sets it): xf holds 18 doubles
 * per pair (rot, tr, ca, cb as in ovl_setup; see ovl_setup_pack), out receives OVL_RESULT_LEN
 * per pair (see ovl_result_unpack). dbl selects the double-precision program.
 */
int ovl_run_cl(pd_device *dev, const ovl_setup *s, const double *xf, int npairs, int dbl,
               double *out, pd_error *err);
void ovl_setup_pack(const ovl_setup *s, double xf[18]);

/*
 * Shapes for the narrow phase (kernels/narrow_phase.h), in doubles: nshape shapes concatenated,
 * vertex and triangle offsets voff/toff (nshape + 1), vertex -> triangle tables vt_off/vt, and
 * optionally the filter's vertex clusters (np_cluster_tables; vc NULL: none).
 */
typedef struct np_tables {
    int nshape;
    const double *vert;
    const int *tri, *voff, *toff, *vt_off, *vt;
    const int *vc, *coff;
    const double *disc;
} np_tables;

/*
 * Runs the narrow-phase kernel (kernels/narrow.cl) for npairs pairs of nbody particles (x 3n,
 * q 4n, size n, shape n) on dev; out receives OVL_RESULT_LEN doubles per pair as the kernel writes
 * them.
 */
int np_run_cl(pd_device *dev, const np_tables *t, const double *x, const double *q,
              const double *size, const int *shape, int nbody, const int *pairs, int npairs,
              int dbl, double *out, pd_error *err);
void ovl_result_unpack(const double r[OVL_RESULT_LEN], ovl_result *o);

#ifdef PD_OVERLAP_H
/*
 * The kernel's input for s in a host build of either precision: A's and B's vertices va, vb as
 * the kernel's reals (s->va and s->vb themselves in double precision), the caller's scratch
 * (ovl_scratch_len). For ovl_run_f32/_f64 and the benchmarks that call ovl_compute themselves.
 */
static inline void ovl_in_from_setup(ovl_in *in, const ovl_setup *s, const pd_real *va,
                                     const pd_real *vb, int flags, int *iscr, pd_real *rscr,
                                     int pts_cap)
{
    /* the clusters, whose discs must be the kernel's reals: in single precision the caller
     * sets them from its own copies of the discs (overlap_precision.inc), or goes without */
    in->vc_a = in->vc_b = NULL;
    in->disc_a = in->disc_b = NULL;
#if PD_DOUBLE
    in->vc_a = s->vc_a;
    in->vc_b = s->vc_b;
    in->disc_a = s->disc_a;
    in->disc_b = s->disc_b;
#endif
    in->va = va;
    in->sa = 1;
    in->ta = s->ta;
    in->nva = s->nva;
    in->nta = s->nta;
    in->vb = vb;
    in->tb = s->tb;
    in->nvb = s->nvb;
    in->ntb = s->ntb;
    in->vt_a_off = s->vt_a_off;
    in->vt_a = s->vt_a;
    in->vt_b_off = s->vt_b_off;
    in->vt_b = s->vt_b;
    for (int k = 0; k < 9; k++)
        in->rot[k] = (pd_real)s->rot[k];
    for (int k = 0; k < 3; k++)
        in->tr[k] = (pd_real)s->tr[k];
    in->ca = v3((pd_real)s->ca[0], (pd_real)s->ca[1], (pd_real)s->ca[2]);
    in->cb = v3((pd_real)s->cb[0], (pd_real)s->cb[1], (pd_real)s->cb[2]);
    in->flags = flags;
    in->org = v3((pd_real)s->org[0], (pd_real)s->org[1], (pd_real)s->org[2]);
    wb_tree_none(&in->wall);
    in->iscr = iscr;
    in->rscr = rscr;
    in->pts_cap = pts_cap;
}
#endif

#endif
