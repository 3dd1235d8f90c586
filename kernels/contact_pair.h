/*
 * contact_pair.h - one candidate pair of the simulation, from geometry to forces: the narrow phase
 * (thesis sections 4.2, 5.2-5.3, or the analytic sphere), the tangential history (eqs. 4.8-4.9)
 * and the force laws of contact_force.h. Shared by the contact kernel (kernels/contact.cl) and
 * host C, so tests run the code the device runs.
 *
 * Bodies are particles and walls alike: a body has a pose, a size (volume-equivalent diameter;
 * walls have size 1 and their mesh in metres about its centroid), a shape and a material. A pair
 * (a, b) always has a < b, walls last, so b may be a wall and a never is.
 *
 * Geometry by shape kinds:
 *   mesh-mesh     exact overlap volume V, centroid, normal (eq. 4.19) and depth (overlap.h);
 *   sphere-sphere the classic overlap of two spheres;
 *   sphere-mesh   the sphere against the mesh taken as locally flat: the closest point of the
 *                 mesh surface, inside or outside by the winding number, overlap delta = r - d
 *                 (outside) or r + d (inside).
 * Forces by model (per material pair, cp_params):
 *   hertz_mindlin volumetric Hertz (eqs. 4.16-4.18) for mesh-mesh, sphere Hertz (eqs. 4.1-4.10)
 *                 otherwise with R* = r_a r_b / (r_a + r_b), or r for a sphere on a mesh;
 *   linear        seed 004 eq. 2.1 with the friction of eqs. 2.2-2.4 (k_f spring, Coulomb cap).
 * Cohesion (seed 004 eq. 2.5) acts on pairs with a sphere: F_c = k_c delta_e, attractive, where
 * delta_e = L_e + delta is the overlap of the effect surfaces, L_e (cohesion_range) beyond the
 * bodies. Mesh-mesh pairs have no separation distance and get no cohesion.
 */
#ifndef PD_CONTACT_PAIR_H
#define PD_CONTACT_PAIR_H

#include "contact_force.h"
#include "contact_history.h"
#include "integrate.h"
#include "narrow_phase.h"

/* Per material pair parameters, CP_NPARAM reals at params[CP_NPARAM (ma * nmat + mb)]. */
enum {
    CP_MODEL = 0, /* 0 hertz_mindlin, 1 linear */
    CP_ESTAR,     /* eq. 4.2, Pa */
    CP_GSTAR,     /* Mindlin's effective shear modulus, Pa */
    CP_MU,        /* friction coefficient */
    CP_GAMMA,     /* damping of eqs. 4.5/4.16 */
    CP_KC,        /* cohesion stiffness, N/m */
    CP_LE,        /* cohesion range L_e, m */
    CP_KE,        /* linear normal stiffness, N/m */
    CP_KF,        /* linear tangential (friction) stiffness, N/m */
    CP_ETA,       /* linear damping coefficient, N s/m */
    CP_PLACES,    /* 1: "contact_places": "separate" (OVL_PLACES) */
    CP_GTWIST,    /* twisting shear modulus 1/(1/G1 + 1/G2), Pa; 0: no contact moments */
    CP_NPARAM
};

/* Everything the contact stage reads about bodies, shapes and materials. */
typedef struct cp_world {
    PD_GLOBAL const pd_real *x, *q, *v, *L, *size, *inv_m;
    PD_GLOBAL const int *shape, *material;
    PD_GLOBAL const pd_real *w_wall;       /* per wall: angular velocity, rad/s */
    PD_GLOBAL const pd_real *unit_inertia; /* per shape: principal moments for size and density 1 */
    PD_GLOBAL const pd_real *density;      /* per material, kg/m^3 */
    np_shapes sh;
    PD_GLOBAL const int *kind;             /* per shape: 0 mesh, 1 sphere */
    PD_GLOBAL const pd_real *radius_ratio; /* per shape: circumradius / size */
    PD_GLOBAL const pd_real *params;
    int nmat;
    int nparticles; /* bodies at and above are walls: body = nparticles + (key - CH_WALL) */
    pd_real dt;
    /* separated polyhedra: the gap cp_mesh_gap certifies at most, m (0: only np_hull_gap's) */
    pd_real gap_cap;
    pd_real list_life; /* steps pair lists have lasted lately: certificates die with theirs */
    /* the walls' triangle BVHs (wall_bvh.h): wall w's nodes from wnode_off[w]; the leaves'
     * triangle order of a wall of shape s at wtri_order[toff[s] ..]; wall_cap: most triangles of
     * one wall near one particle (np_wall_local's cap) */
    PD_GLOBAL const pd_real *wnode_box;
    PD_GLOBAL const int *wnode_kid, *wnode_off, *wtri_order;
    int wall_cap;
    /* status[2]: lowest particle * nwall + wall whose near wall triangles exceeded wall_cap */
    PD_GLOBAL int *status;
    int nwall;
} cp_world;

#ifdef __OPENCL_VERSION__
#define CP_FLAG_MIN(p, v) atomic_min(p, v)
#else
#define CP_FLAG_MIN(p, v) (*(p) = *(p) < (v) ? *(p) : (v))
#endif

/* What a pair yields: force on b (a gets minus it) at the contact point, and stats. */
typedef struct cp_result {
    pd_v3 force;  /* on b, at point */
    pd_v3 spring; /* tangential history carried to the next step */
    pd_real kt;
    pd_v3 couple;  /* moment on b (a gets minus it) besides the force's (cp_couple), N m */
    pd_real twist; /* twisting history carried to the next step (cf_twist), N m */
    int touching;  /* bodies overlap (a contact) */
    pd_real ratio; /* depth / smaller particle size */
    pd_v3 point;   /* contact point, m */
    pd_real gap;   /* two polyhedral particles apart: a certified lower bound on their distance
                      (np_hull_gap), m; 0 otherwise */
    int gave_up;   /* the surfaces' gap was searched (cp_mesh_gap) and found too small */
} cp_result;

/* Gilbert iterations np_hull_gap may take for a separated pair's gap. */
#define CP_GAP_ITERS 8
/* cp_mesh_gap is tried for pairs that would take this many steps to close gap_cap, and kept
 * only when its gap would last that long */
#define CP_GAP_STEPS 64
/* After cp_mesh_gap gave up on a pair (surfaces within CP_GAP_STEPS steps' motion), it is not
 * searched again for this many steps: such pairs stay close, and in a resting bed they were
 * hundreds of searches a step (bench/RESULTS.md) */
#define CP_GAP_RETRY 8
/*
 * World angular velocity of body i, rad/s: a wall's as prescribed; a particle's from its
 * orientation and angular momentum, by the same operations as integrate_drift turns it with
 * (integrate.h), so it is the omega of the step's new orientation bit for bit. Not stored per
 * particle: it is only needed for touching pairs, and cost 24 bytes a particle.
 */
PD_FN pd_v3 cp_omega(const cp_world *wd, int i)
{
    if (i >= wd->nparticles) return v3_load(wd->w_wall, i - wd->nparticles);
    PD_GLOBAL const pd_real *qi = wd->q + 4 * i;
    pd_q4 r = q4(qi[0], qi[1], qi[2], qi[3]);
    pd_v3 ii = int_inverse_inertia(wd->unit_inertia, wd->shape[i], wd->density[wd->material[i]],
                                   wd->size[i]);
    return q4_rotate(r, int_omega_body(r, v3_load(wd->L, i), ii));
}

/* The body index of the second half of a key (walls follow the particles). */
PD_FN int cp_body(const cp_world *wd, unsigned id)
{
    return id >= CH_WALL ? wd->nparticles + (int)(id - CH_WALL) : (int)id;
}

PD_FN void cp_load_body(const cp_world *wd, int i, np_body *b)
{
    b->x = v3_load(wd->x, i);
    for (int k = 0; k < 4; k++)
        b->q[k] = wd->q[4 * i + k];
    b->size = wd->size[i];
    b->shape = wd->shape[i];
}

/* The BVH of wall body ib (of shape sh). */
PD_FN void cp_wall_tree(const cp_world *wd, int ib, int sh, wb_tree *t)
{
    int n0 = wd->wnode_off[ib - wd->nparticles];
    t->box = wd->wnode_box + 6 * n0;
    t->kid = wd->wnode_kid + 2 * n0;
    t->order = wd->wtri_order + wd->sh.toff[sh];
    t->vert = wd->sh.vert + 3 * wd->sh.voff[sh];
    t->tri = wd->sh.tri + 3 * wd->sh.toff[sh];
}

/* Closest point to p on triangle (a, b, c) (Ericson, Real-Time Collision Detection 5.1.5). */
PD_FN pd_v3 cp_closest_on_triangle(pd_v3 p, pd_v3 a, pd_v3 b, pd_v3 c)
{
    pd_v3 ab = v3_sub(b, a), ac = v3_sub(c, a), ap = v3_sub(p, a);
    pd_real d1 = v3_dot(ab, ap), d2 = v3_dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) return a;
    pd_v3 bp = v3_sub(p, b);
    pd_real d3 = v3_dot(ab, bp), d4 = v3_dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) return b;
    pd_real vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return v3_add(a, v3_scale(ab, d1 / (d1 - d3)));
    pd_v3 cp = v3_sub(p, c);
    pd_real d5 = v3_dot(ab, cp), d6 = v3_dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) return c;
    pd_real vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return v3_add(a, v3_scale(ac, d2 / (d2 - d6)));
    pd_real va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
        return v3_add(b, v3_scale(v3_sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6))));
    pd_real den = PD_R(1) / (va + vb + vc);
    return v3_add(a, v3_add(v3_scale(ab, vb * den), v3_scale(ac, vc * den)));
}

/* Squared distance between segments p0-p1 and q0-q1 (Ericson 5.1.9). */
PD_FN pd_real cp_segment_dist2(pd_v3 p0, pd_v3 p1, pd_v3 q0, pd_v3 q1)
{
    pd_v3 d1 = v3_sub(p1, p0), d2 = v3_sub(q1, q0), r = v3_sub(p0, q0);
    pd_real a = v3_dot(d1, d1), e = v3_dot(d2, d2), f = v3_dot(d2, r);
    pd_real s = 0, t = 0;
    if (a <= PD_R(0) && e <= PD_R(0)) {
        s = t = 0;
    } else if (a <= PD_R(0)) {
        t = pd_min(pd_max(f / e, PD_R(0)), PD_R(1));
    } else {
        pd_real c = v3_dot(d1, r);
        if (e <= PD_R(0)) {
            s = pd_min(pd_max(-c / a, PD_R(0)), PD_R(1));
        } else {
            pd_real b = v3_dot(d1, d2), den = a * e - b * b;
            s = den > PD_R(0) ? pd_min(pd_max((b * f - c * e) / den, PD_R(0)), PD_R(1)) : PD_R(0);
            t = (b * s + f) / e;
            if (t < PD_R(0)) {
                t = 0;
                s = pd_min(pd_max(-c / a, PD_R(0)), PD_R(1));
            } else if (t > PD_R(1)) {
                t = 1;
                s = pd_min(pd_max((b - c) / a, PD_R(0)), PD_R(1));
            }
        }
    }
    pd_v3 dd = v3_sub(v3_add(p0, v3_scale(d1, s)), v3_add(q0, v3_scale(d2, t)));
    return v3_dot(dd, dd);
}

/*
 * Squared distance between triangles t[0..2] and u[0..2]: the least of the edge pairs', the
 * corners' to the other triangle, and, where an edge crosses the other's plane, the crossing's
 * to the other triangle (0 when the triangles cut each other).
 */
PD_FN pd_real cp_triangle_dist2(const pd_v3 *t, const pd_v3 *u)
{
    pd_real best = PD_REAL_MAX;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            best = pd_min(best, cp_segment_dist2(t[i], t[(i + 1) % 3], u[j], u[(j + 1) % 3]));
    for (int side = 0; side < 2; side++) {
        const pd_v3 *a = side ? u : t, *b = side ? t : u;
        pd_v3 nb = v3_cross(v3_sub(b[1], b[0]), v3_sub(b[2], b[0]));
        pd_real h[3];
        for (int i = 0; i < 3; i++) {
            pd_v3 cp = v3_sub(cp_closest_on_triangle(a[i], b[0], b[1], b[2]), a[i]);
            best = pd_min(best, v3_dot(cp, cp));
            h[i] = v3_dot(nb, v3_sub(a[i], b[0]));
        }
        for (int i = 0; i < 3; i++) {
            int k = (i + 1) % 3;
            if ((h[i] < PD_R(0)) == (h[k] < PD_R(0)) || h[i] == h[k]) continue;
            pd_v3 x = v3_add(a[i], v3_scale(v3_sub(a[k], a[i]), h[i] / (h[i] - h[k])));
            pd_v3 cp = v3_sub(cp_closest_on_triangle(x, b[0], b[1], b[2]), x);
            best = pd_min(best, v3_dot(cp, cp));
        }
    }
    return best;
}

/*
 * A lower bound on the distance between the surfaces of A and B of `in` (np_setup, A's frame),
 * capped at `cap` (m), for a pair whose overlap came out empty: the least distance between a
 * triangle of A and one of B whose boxes come within cap (any other pair is at least cap apart).
 * Works for non-convex shapes that nest in each other's pockets, where np_hull_gap finds
 * nothing. The distances are those of points found on the triangles, so rounding can only place
 * them slightly past the true closest points: 1 % and a few ulps of the scale are taken off.
 * Gives up (0) as soon as two triangles are found within `least` (m): a gap that small would
 * not repay the search. scr: 3 nvb reals (B's vertices in A's frame); iscr: ntb ints.
 */
PD_FN pd_real cp_mesh_gap(const ovl_in *in, pd_real cap, pd_real least, PD_GLOBAL pd_real *scr,
                          PD_GLOBAL int *iscr)
{
    pd_v3 blo = v3(PD_REAL_MAX, PD_REAL_MAX, PD_REAL_MAX), bhi = v3_scale(blo, PD_R(-1));
    for (int j = 0; j < in->nvb; j++) {
        pd_v3 y = ovl_b_to_a(in, v3_load(in->vb, j));
        v3_store(scr, j, y);
        blo = v3(pd_min(blo.x, y.x), pd_min(blo.y, y.y), pd_min(blo.z, y.z));
        bhi = v3(pd_max(bhi.x, y.x), pd_max(bhi.y, y.y), pd_max(bhi.z, y.z));
    }
    pd_v3 capv = v3(cap, cap, cap);
    /* A's extent within cap of B's box, and B's triangles within cap of it */
    pd_v3 alo = v3(PD_REAL_MAX, PD_REAL_MAX, PD_REAL_MAX), ahi = v3_scale(alo, PD_R(-1));
    for (int i = 0; i < in->nva; i++) {
        pd_v3 x = v3_scale(v3_load(in->va, i), in->sa);
        alo = v3(pd_min(alo.x, x.x), pd_min(alo.y, x.y), pd_min(alo.z, x.z));
        ahi = v3(pd_max(ahi.x, x.x), pd_max(ahi.y, x.y), pd_max(ahi.z, x.z));
    }
    pd_real scale = pd_max(pd_max(v3_amax(alo), v3_amax(ahi)), pd_max(v3_amax(blo), v3_amax(bhi)));
    pd_v3 qlo = v3_sub(v3(pd_max(alo.x, blo.x), pd_max(alo.y, blo.y), pd_max(alo.z, blo.z)), capv);
    pd_v3 qhi = v3_add(v3(pd_min(ahi.x, bhi.x), pd_min(ahi.y, bhi.y), pd_min(ahi.z, bhi.z)), capv);
    int nb = 0;
    for (int u = 0; u < in->ntb; u++) {
        PD_GLOBAL const int *v = in->tb + 3 * u;
        if (ovl_tri_meets(v3_load(scr, v[0]), v3_load(scr, v[1]), v3_load(scr, v[2]), qlo, qhi))
            iscr[nb++] = u;
    }
    pd_real best = cap * cap;
    for (int t = 0; t < in->nta && nb > 0; t++) {
        pd_v3 a[3];
        for (int q = 0; q < 3; q++)
            a[q] = v3_scale(v3_load(in->va, in->ta[3 * t + q]), in->sa);
        ovl_tri T; /* its box, grown by cap: B's triangles beyond it are at least cap away */
        ovl_tri_make(&T, a[0], a[1], a[2], cap);
        if (T.hi.x < qlo.x || T.lo.x > qhi.x || T.hi.y < qlo.y || T.lo.y > qhi.y ||
            T.hi.z < qlo.z || T.lo.z > qhi.z)
            continue;
        for (int l = 0; l < nb; l++) {
            pd_v3 b[3];
            for (int q = 0; q < 3; q++)
                b[q] = v3_load(scr, in->tb[3 * iscr[l] + q]);
            if (!ovl_tri_meets(b[0], b[1], b[2], T.lo, T.hi)) continue;
            best = pd_min(best, cp_triangle_dist2(a, b));
            if (!(best > least * least)) return 0;
        }
    }
    pd_real gap = PD_R(0.99) * PD_SQRT(best) - PD_R(1024) * PD_EPS * scale;
    return gap > PD_R(0) ? gap : PD_R(0);
}

/* Solid angle of triangle (a, b, c) seen from the origin (Van Oosterom & Strackee 1983). */
PD_FN pd_real cp_solid_angle(pd_v3 a, pd_v3 b, pd_v3 c)
{
    pd_real la = v3_norm(a), lb = v3_norm(b), lc = v3_norm(c);
    pd_real num = v3_dot(a, v3_cross(b, c));
    pd_real den = la * lb * lc + v3_dot(a, b) * lc + v3_dot(a, c) * lb + v3_dot(b, c) * la;
    return PD_R(2) * atan2(num, den);
}

/*
 * Whether point p (a wall's frame) lies inside the wall of tree w, by ray parity through the tree
 * with the overlap's robust predicates (overlap_predicates.h), at the resolution of coordinates
 * of p's and the wall's magnitude. The ray's direction is fixed and generic.
 */
PD_FN int cp_inside_tree(const wb_tree *w, pd_v3 p)
{
    ovl_ctx c;
    PD_GLOBAL const pd_real *b = w->box;
    pd_real l =
        pd_max(v3_amax(p), pd_max(v3_amax(v3(b[0], b[1], b[2])), v3_amax(v3(b[3], b[4], b[5]))));
    c.pad = OVL_SNAP * l;
    c.flip = c.wneg = c.degenerate = 0;
    pd_v3 r = v3_unit(v3(PD_R(0.5772156649), PD_R(0.6180339887), PD_R(0.5336)));
    return ovl_tree_parity(&c, w, 0, p, r, p, r);
}

/*
 * Sphere (centre s, radius r, world) against mesh body m. Returns the overlap delta (negative:
 * the gap), the unit normal from the sphere into the mesh and the closest surface point (world).
 * With tree (m a wall, size 1), only the wall's triangles within `reach` of the centre are
 * searched (their ids into iscr, up to cap; *overflow set when more), inside or outside by a ray
 * through the tree; none within reach: no contact (-PD_REAL_MAX).
 */
PD_FN pd_real cp_sphere_mesh(const cp_world *wd, pd_v3 s, pd_real r, const np_body *m,
                             const wb_tree *tree, pd_real reach, PD_GLOBAL int *iscr, int cap,
                             int *overflow, pd_v3 *n, pd_v3 *surf)
{
    pd_real R[9];
    np_quat_matrix(m->q, R);
    pd_v3 d = v3_sub(s, m->x);
    /* the sphere's centre in the mesh's body frame at size 1 */
    pd_real inv = PD_R(1) / m->size;
    pd_v3 p = v3((R[0] * d.x + R[3] * d.y + R[6] * d.z) * inv,
                 (R[1] * d.x + R[4] * d.y + R[7] * d.z) * inv,
                 (R[2] * d.x + R[5] * d.y + R[8] * d.z) * inv);
    int sh = m->shape;
    PD_GLOBAL const pd_real *vert = wd->sh.vert + 3 * wd->sh.voff[sh];
    PD_GLOBAL const int *tri = wd->sh.tri + 3 * wd->sh.toff[sh];
    int nt = wd->sh.toff[sh + 1] - wd->sh.toff[sh];
    if (tree) {
        pd_v3 lo, hi;
        wb_reach_box(p, reach, &lo, &hi);
        nt = wb_query_box(tree, lo, hi, iscr, cap);
        if (nt < 0 || nt > cap) *overflow = 1;
        if (nt <= 0 || nt > cap) return -PD_REAL_MAX;
    }
    pd_real best = PD_REAL_MAX, omega = 0;
    pd_v3 cbest = p, fnormal = v3(0, 0, 1);
    for (int k = 0; k < nt; k++) {
        int t = tree ? iscr[k] : k;
        pd_v3 a = v3_load(vert, tri[3 * t]), b = v3_load(vert, tri[3 * t + 1]),
              c = v3_load(vert, tri[3 * t + 2]);
        pd_v3 cp = cp_closest_on_triangle(p, a, b, c), dd = v3_sub(cp, p);
        pd_real d2 = v3_dot(dd, dd);
        if (d2 < best) {
            best = d2;
            cbest = cp;
            fnormal = v3_cross(v3_sub(b, a), v3_sub(c, a));
        }
        if (!tree) omega += cp_solid_angle(v3_sub(a, p), v3_sub(b, p), v3_sub(c, p));
    }
    /* winding number 1 vs 0 over a particle's few triangles; a wall's by its tree */
    int inside = tree ? cp_inside_tree(tree, p) : PD_FABS(omega) > PD_R(6.283185307179586);
    pd_v3 dv = v3_sub(cbest, p);
    pd_real dist = v3_norm(dv) * m->size;
    pd_v3 nb; /* body frame, from the sphere into the mesh */
    if (dist > PD_R(0))
        nb = v3_unit(inside ? v3_scale(dv, -1) : dv);
    else
        nb = v3_unit(v3_scale(fnormal, -1));
    /* back to world */
    *n = v3(R[0] * nb.x + R[1] * nb.y + R[2] * nb.z, R[3] * nb.x + R[4] * nb.y + R[5] * nb.z,
            R[6] * nb.x + R[7] * nb.y + R[8] * nb.z);
    pd_v3 cw = v3_scale(cbest, m->size);
    *surf = v3_add(m->x, v3(R[0] * cw.x + R[1] * cw.y + R[2] * cw.z,
                            R[3] * cw.x + R[4] * cw.y + R[5] * cw.z,
                            R[6] * cw.x + R[7] * cw.y + R[8] * cw.z));
    return inside ? r + dist : r - dist;
}

/*
 * Whether the two particles of `key` are too far apart to touch or to cohere: their bounding
 * spheres (circumradius; a sphere's radius), widened by the pair's cohesion range, do not meet.
 * Most candidates of a reused pair list (the Verlet skin) end here, before their history is
 * looked up. Walls: 0 (their pairs are decided by the wall's triangles).
 */
PD_FN int cp_apart(const cp_world *wd, ch_key key)
{
    int ia = (int)ch_first(key), ib = cp_body(wd, ch_second(key));
    if (ib >= wd->nparticles) return 0;
    PD_GLOBAL const pd_real *pr =
        wd->params + CP_NPARAM * (wd->material[ia] * wd->nmat + wd->material[ib]);
    pd_real reach = wd->radius_ratio[wd->shape[ia]] * wd->size[ia] +
                    wd->radius_ratio[wd->shape[ib]] * wd->size[ib] + pr[CP_LE];
    pd_v3 d = v3_sub(v3_load(wd->x, ib), v3_load(wd->x, ia));
    return v3_dot(d, d) > reach * reach;
}

/*
 * The moment on b of a volumetric contact besides its force's (not in the thesis; see
 * contact_force.h, cf_twist): the normal and tangential dashpots of eqs. 4.16 and 4.12 (eta_n,
 * eta_t: their coefficients, N s/m) spread evenly over the contact's disc of radius
 * a = sqrt(V / (pi delta)) (eqs. 4.17-4.18), less their resultants at the contact point, resist
 * a relative rocking w_perp with -eta_n a^2/4 w_perp and a relative twist about n with
 * -eta_t a^2/2 (the disc's second moments of area over its area); and the twisting spring with
 * its Coulomb limit. The thesis's point contact has neither: a cube resting on a face kept any
 * turn about the normal an impact gave it (2 rad/s for seconds in examples/cube_lattice.json),
 * and its rocking was damped only through the shift of its contact point, quadratic in the
 * amplitude (docs/VERIFICATION.md, known limits).
 *   wrel    w_b - w_a, rad/s;  fn the normal force, N;  kt, kt0 this and last step's k_t
 *           (eq. 4.18, k_t = 8 G* a: the radii are k_t / (8 G*));  *twist in/out: the twisting
 *           spring, N m.
 */
PD_FN pd_v3 cp_couple(const cp_world *wd, PD_GLOBAL const pd_real *pr, pd_v3 n, pd_v3 wrel,
                      pd_real kt, pd_real eta_n, pd_real eta_t, pd_real fn, pd_real kt0,
                      int loading, pd_real *twist)
{
    pd_real rad = kt / (PD_R(8) * pr[CP_GSTAR]), r2 = rad * rad; /* eq. 4.18: k_t = 8 G* a */
    pd_real spin = v3_dot(wrel, n);
    pd_v3 m = v3_scale(v3_sub(wrel, v3_scale(n, spin)), -eta_n * r2 / PD_R(4));
    pd_real ktw = cf_twist_stiffness(pr[CP_GTWIST], rad);
    pd_real a0 = kt0 > PD_R(0) ? kt0 / (PD_R(8) * pr[CP_GSTAR]) : PD_R(0);
    pd_real ktw0 = cf_twist_stiffness(pr[CP_GTWIST], a0);
    pd_real mlim = PD_R(3) * CF_PI / PD_R(16) * pr[CP_MU] * fn * rad;
    return v3_add(m, v3_scale(n, cf_twist(twist, ktw, ktw0, loading, spin, wd->dt,
                                          eta_t * r2 / PD_R(2), mlim)));
}

/* A pair that does not touch: no force, no history. */
PD_FN void cp_none(cp_result *res)
{
    res->force = res->spring = res->point = res->couple = v3(0, 0, 0);
    res->kt = res->twist = 0;
    res->touching = 0;
    res->ratio = 0;
    res->gap = 0;
    res->gave_up = 0;
}

/*
 * Evaluates pair `key` with last step's tangential and twisting state (spring0, kt0, twist0;
 * zero for a new pair).
 * Callers drop the pairs cp_apart rejects first (without their overlap, about half of a
 * polyhedral bed's candidates, and most of a reused list's).
 * in/rscr: the overlap scratch of this work-item (ovl_in's iscr, rscr, pts_cap). surfaces: the
 * surfaces' gap (cp_mesh_gap) may be searched for a separated pair (see CP_GAP_RETRY). last: the
 * pair's contact point in the last step (world, m) when it touched then (kt0 > 0, on a reused
 * list and a new one alike, so that reusing a list changes nothing), else unused.
 */
PD_FN void cp_pair(const cp_world *wd, ch_key key, pd_v3 spring0, pd_real kt0, pd_real twist0,
                   PD_GLOBAL int *iscr, PD_GLOBAL pd_real *rscr, int pts_cap, int surfaces,
                   pd_v3 last, cp_result *res)
{
    int ia = (int)ch_first(key), ib = cp_body(wd, ch_second(key));
    np_body a, b;
    cp_load_body(wd, ia, &a);
    cp_load_body(wd, ib, &b);
    int ka = wd->kind[a.shape], kb = wd->kind[b.shape];
    PD_GLOBAL const pd_real *pr =
        wd->params + CP_NPARAM * (wd->material[ia] * wd->nmat + wd->material[ib]);
    int linear = pr[CP_MODEL] != PD_R(0);
    int wall_b = ib >= wd->nparticles;
    pd_real smin = wall_b ? a.size : pd_min(a.size, b.size);

    cp_none(res);

    /* geometry: normal n from a into b, overlap delta (negative: gap), contact point c */
    pd_v3 n, c;
    pd_real delta, vol = 0, rstar = 0;
    int volumetric = 0, cohesive = 0;
    if (ka == 1 && kb == 1) {
        pd_real ra = PD_R(0.5) * a.size, rb = PD_R(0.5) * b.size;
        pd_v3 d = v3_sub(b.x, a.x);
        pd_real dist = v3_norm(d);
        n = dist > PD_R(0) ? v3_scale(d, PD_R(1) / dist) : v3(0, 0, 1);
        delta = ra + rb - dist;
        c = v3_add(a.x, v3_scale(n, ra - PD_R(0.5) * delta));
        rstar = ra * rb / (ra + rb);
        cohesive = 1;
    } else if (ka == 1 || kb == 1) {
        int sa = ka == 1;
        const np_body *sp = sa ? &a : &b, *me = sa ? &b : &a;
        pd_real r = PD_R(0.5) * sp->size;
        pd_v3 ns, surf;
        wb_tree t;
        int overflow = 0;
        if (wall_b) cp_wall_tree(wd, ib, b.shape, &t);
        delta = cp_sphere_mesh(wd, sp->x, r, me, wall_b ? &t : 0, r + pr[CP_LE], iscr, wd->wall_cap,
                               &overflow, &ns, &surf);
        if (overflow) CP_FLAG_MIN(wd->status + 2, ia * wd->nwall + (ib - wd->nparticles));
        n = sa ? ns : v3_scale(ns, -1);
        c = v3_add(sp->x, v3_scale(ns, r - PD_R(0.5) * delta));
        rstar = r;
        cohesive = 1;
    } else {
        ovl_in in;
        pd_real ra[9];
        np_setup(&wd->sh, &a, &b, pr[CP_PLACES] != PD_R(0) ? OVL_PLACES : 0, &in, ra);
        /* single precision: the cusps summed about last step's contact point are of the
         * overlap's size, so its volume stands out of their rounding in one pass, where about
         * a's centroid most touching pairs need a second (OVL_ORIGIN). Double precision has the
         * room and keeps a's centroid, so its results do not depend on the last step. */
        if (!PD_DOUBLE && kt0 > PD_R(0)) {
            in.flags |= OVL_ORIGIN;
            in.org = np_to_body(&a, ra, last);
        }
        if (wall_b) { /* the wall's triangles near a, from its BVH (thesis section 5.6) */
            int wi = ib - wd->nparticles;
            wb_tree t;
            cp_wall_tree(wd, ib, b.shape, &t);
            int nt = np_wall_local(&t, wd->radius_ratio[a.shape] * a.size, wd->wall_cap, iscr, rscr,
                                   &in);
            if (nt < 0) CP_FLAG_MIN(wd->status + 2, ia * wd->nwall + wi);
            if (nt <= 0) return;
            iscr += np_wall_ilen(wd->wall_cap);
            rscr += np_wall_rlen(wd->wall_cap);
        }
        in.iscr = iscr;
        in.rscr = rscr;
        in.pts_cap = pts_cap;
        ovl_out o;
        ovl_compute(&in, &o);
        if (!o.hit) {
            if (!wall_b) { /* hulls apart (cheap), or else the surfaces (nested shapes) */
                pd_real rad_a = wd->radius_ratio[a.shape] * a.size,
                        rad_b = wd->radius_ratio[b.shape] * b.size;
                res->gap = np_hull_gap(&in, rad_a, rad_b, CP_GAP_ITERS);
                /* the surfaces' gap costs several overlaps: only for pairs slow enough that a
                 * gap of up to gap_cap could last CP_GAP_STEPS steps, and while lists last
                 * that long (a resting bed; in a flow, some particle moves half the skin
                 * every few steps, the list is rebuilt and every certificate with it) */
                pd_real step =
                    (v3_norm(v3_sub(v3_load(wd->v, ib), v3_load(wd->v, ia))) +
                     v3_norm(cp_omega(wd, ia)) * rad_a + v3_norm(cp_omega(wd, ib)) * rad_b) *
                    wd->dt;
                if (res->gap <= PD_R(0) && surfaces && wd->gap_cap > CP_GAP_STEPS * step &&
                    wd->list_life >= CP_GAP_STEPS) {
                    res->gap = cp_mesh_gap(&in, wd->gap_cap, CP_GAP_STEPS * step, rscr, iscr);
                    res->gave_up = !(res->gap > PD_R(0));
                }
            }
            return;
        }
        np_to_world(&a, ra, &o);
        n = o.normal;
        /* one place: centroid, depth and volume; several (OVL_PLACES): where their summed force
         * acts, and the volume and depth that give that sum and their stiffnesses' */
        c = o.point_eff;
        delta = o.depth_eff;
        vol = o.vol_eff;
        volumetric = 1;
    }
    pd_real le = pr[CP_LE], kc = pr[CP_KC];
    int in_cohesion = cohesive && kc > PD_R(0) && delta + le > PD_R(0);
    if (!(delta > PD_R(0)) && !in_cohesion) return;

    /* relative velocity of b with respect to a at the contact point */
    pd_v3 wa = cp_omega(wd, ia), wb = cp_omega(wd, ib);
    pd_v3 va = v3_add(v3_load(wd->v, ia), v3_cross(wa, v3_sub(c, a.x)));
    pd_v3 vb = v3_add(v3_load(wd->v, ib), v3_cross(wb, v3_sub(c, b.x)));
    pd_v3 vrel = v3_sub(vb, va);
    pd_real vn = -v3_dot(vrel, n); /* approach speed */
    pd_v3 vt = v3_add(vrel, v3_scale(n, vn));
    pd_real mstar = cf_effective_mass(wd->inv_m[ia], wd->inv_m[ib]);

    pd_v3 f = v3(0, 0, 0);
    if (delta > PD_R(0)) {
        pd_real fn, kn, kt, damp;
        if (linear) {
            fn = cf_linear_normal(pr[CP_KE], pr[CP_ETA], delta, vn);
            kt = pr[CP_KF];
            damp = 0;
        } else if (volumetric) {
            fn = cf_hertz_volume_normal(pr[CP_ESTAR], vol, delta, mstar, pr[CP_GAMMA], vn, &kn);
            kt = cf_hertz_volume_kt(pr[CP_GSTAR], vol, delta);
            damp = PD_R(2) * pr[CP_GAMMA] * PD_SQRT(mstar * kt);
        } else {
            fn = cf_hertz_sphere_normal(pr[CP_ESTAR], rstar, delta, mstar, pr[CP_GAMMA], vn, &kn);
            kt = cf_hertz_sphere_kt(pr[CP_GSTAR], rstar, delta);
            damp = PD_R(2) * pr[CP_GAMMA] * PD_SQRT(mstar * kt);
        }
        pd_v3 s = spring0;
        int loading = kt >= kt0;
        pd_v3 ft = cf_tangential(&s, n, kt, kt0, loading, v3_scale(vt, wd->dt), vt, damp, pr[CP_MU],
                                 fn > PD_R(0) ? fn : PD_R(0));
        f = v3_add(v3_scale(n, fn), ft);
        if (volumetric && !linear && pr[CP_GTWIST] > PD_R(0)) { /* "contact_moments" */
            pd_real tw = twist0;
            res->couple = cp_couple(wd, pr, n, v3_sub(wb, wa), kt,
                                    PD_R(2) * pr[CP_GAMMA] * PD_SQRT(mstar * kn), damp,
                                    fn > PD_R(0) ? fn : PD_R(0), kt0, loading, &tw);
            res->twist = tw;
        }
        res->spring = s;
        res->kt = kt;
        res->touching = 1;
        res->ratio = delta / smin;
    }
    if (in_cohesion) /* seed 004 eq. 2.5: the effect surfaces pull b towards a */
        f = v3_sub(f, v3_scale(n, kc * (delta + le)));
    res->force = f;
    res->point = c;
}

#endif /* PD_CONTACT_PAIR_H */
