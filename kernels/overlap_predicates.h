/*
 * overlap_predicates.h - the geometric predicates of the polyhedral overlap (overlap.h): its
 * input and state, the robust orientation tests of Algorithm 1 (edge through triangle, point
 * against plane) and the point-in-solid test by ray parity. Compiles as OpenCL C and host C.
 *
 * Degenerate configurations (coplanar faces, a vertex on a face, an edge on an edge, coincident
 * shapes) are resolved by simulation of simplicity: every predicate is evaluated for B displaced by
 * eps * w with w = (1, d, d^2) and eps >> d infinitesimal, so each zero determinant takes the sign
 * of its first non-zero symbolic term. Volume and centroid are continuous in the displacement, so
 * the perturbed configuration's combinatorics evaluated at eps = 0 give the exact answer. The
 * normal of eq. 4.19 is not continuous where faces of A and B are coplanar (which of the two owns
 * the shared face flips with w), so when a degenerate predicate was met the pass is repeated with
 * -w and the two normals are averaged: shared faces then cancel, as they must.
 *
 * A determinant within the configuration's rounding resolution (OVL_SNAP times the coordinate
 * scale L to the power of its length dimension) is taken as exactly zero and resolved the same
 * way: nearly coplanar or nearly coincident faces, which rounding of the pose produces, then
 * behave like exactly coplanar ones instead of taking random signs from rounding noise. The
 * bound is one absolute resolution for the whole configuration (features closer than about
 * OVL_SNAP * L count as touching), not a per-determinant one: a determinant whose own factors are
 * noise-sized would otherwise see the noise while its neighbours snap.
 *
 * Every predicate shared between neighbouring triangles (edge-edge orientation, ray-edge
 * orientation, crossing points) is computed from the edge's canonical orientation (lower vertex
 * index first), so the two triangles of an edge always agree bit for bit on what crosses where.
 */
#ifndef PD_OVERLAP_PREDICATES_H
#define PD_OVERLAP_PREDICATES_H

#include "pd_real.h"
#include "wall_bvh.h"

#define OVL_NO_FILTER 2 /* same value as PD_OVERLAP_NO_FILTER */
/*
 * B is open: the part of a closed wall that meets a box around A (the wall's triangles whose boxes
 * meet the cube of A's circumradius about its centroid), with its vertices numbered in the whole
 * wall's order. Everything but one test needs only that part: a node of A n B lies on A, so in
 * the cube. The exception is whether a vertex of A lies inside the wall, a question about the
 * whole solid; it is answered by the parity of the segment from the vertex to A's centroid (the
 * origin of A's frame, inside the cube with the segment) through the local triangles, combined
 * with whether the centroid is inside, found once by a ray through the whole wall's BVH (in.wall).
 * Set by np_wall_local (narrow_phase.h).
 */
#define OVL_OPEN_B 4
/*
 * Find the overlap's separate places (thesis section 5.4): the connected parts of A n B, each
 * with its own volume, normal and depth, summed into what the force law needs (ovl_out.places,
 * vol_eff, depth_eff, point_eff; ovl_places in overlap.h). Needs ovl_places_ilen/_rlen(pts_cap)
 * more scratch after the usual (see ovl_compute).
 */
#define OVL_PLACES 8
/*
 * OVL_PLACES is compiled in unless the includer defines OVL_PLACES_BUILD to 0: the engine builds
 * its kernels so when no interaction of a scenario asks for separate places, and their overlap
 * then costs what it did before places existed (the bookkeeping otherwise adds about 4 % of
 * instructions to every overlap, bench/RESULTS.md). The flag is ignored in such a build.
 */
#ifndef OVL_PLACES_BUILD
#define OVL_PLACES_BUILD 1
#endif
/*
 * In single precision the places also rescue a pair touching in places far apart, whose cusps,
 * summed about one origin between them, are too large for its volume to stand out of their
 * rounding (ovl_rescue in overlap.h). It needs the places' bookkeeping and their scratch
 * (ovl_places_ilen/_rlen, whether or not OVL_PLACES is asked for), so the engine builds its
 * single-precision kernels with OVL_PLACES_BUILD (engine/cl_device.c) and sizes their scratch so.
 * Double precision has 2^29 times the room and goes without.
 */
#define OVL_RESCUE (OVL_PLACES_BUILD && !PD_DOUBLE)
/*
 * in->org (A's frame) lies near where the overlap is expected, e.g. the pair's contact point in
 * the last step: the cusps are summed about it first instead of about A's centroid. Each cusp is a
 * simplex from that origin to its node, so about a point inside the overlap they are of its size
 * and the volume stands out of their rounding in one pass; about A's centroid a small overlap
 * in single precision does not, and is summed again (ovl_compute). The result is the same in
 * exact arithmetic.
 */
#define OVL_ORIGIN 16
/* Reals cached per near triangle of B: raw normal, box (lo, hi), raw inward edge normals, the
 * snap bound of its plane (ovl_plane_tol). */
#define OVL_TRI_CACHE 19
/* Reals in a kernel's result record (ovl_out_store; OVL_RESULT_LEN on the host). */
#define OVL_OUT_LEN 19

/* Input of one overlap computation. Scratch sizes: see ovl_iscratch_len / ovl_rscratch_len. */
typedef struct ovl_in {
    PD_GLOBAL const pd_real *va; /* A's vertices, xyz, in A's frame, times sa */
    pd_real sa;                  /* scale of A's vertices (a particle's size; 1 for a mesh as is) */
    PD_GLOBAL const int *ta;     /* A's triangles, outward counter-clockwise */
    int nva, nta;
    PD_GLOBAL const pd_real *vb; /* B's vertices in B's own frame */
    PD_GLOBAL const int *tb;
    int nvb, ntb;
    /* optional vertex -> triangle tables (CSR: the triangles of vertex i are
     * vt[vt_off[i] .. vt_off[i+1]-1]); with them the filter visits only the triangles of the
     * vertices that reach into the other's half-plane; NULL: it classifies every triangle */
    PD_GLOBAL const int *vt_a_off, *vt_a, *vt_b_off, *vt_b;
    /*
     * optional vertex clusters (engine/vertex_clusters.c), with which the filter
     * projects only the vertices of the clusters that can reach an extreme or the other's
     * half-plane instead of every vertex: vc (2 nv ints) lists the vertices cluster by cluster
     * (OVL_CLUSTER a cluster, the last one shorter) and then each vertex's cluster; disc
     * (OVL_DISC reals a cluster) holds the disc that bounds it (ovl_cluster_bounds): centre m,
     * unit normal n, radius r in its plane, half-thickness h, and a bound on |v| and |m|, in the
     * frame of va (A) or vb (B). NULL: every vertex is projected. Used only with the vt tables.
     */
    PD_GLOBAL const int *vc_a, *vc_b;
    PD_GLOBAL const pd_real *disc_a, *disc_b;
    pd_real rot[9]; /* B's frame -> A's frame, row-major: p = rot * v + tr (B's scale in rot) */
    pd_real tr[3];
    pd_v3 ca, cb; /* centroids of A and B in A's frame (filter direction, eq. 5.3) */
    int flags;
    PD_GLOBAL int *iscr;     /* ovl_iscratch_len ints */
    PD_GLOBAL pd_real *rscr; /* ovl_rscratch_len reals */
    int pts_cap;             /* capacity for overlap nodes kept for the depth */
    wb_tree wall;            /* OVL_OPEN_B only: the whole wall, B's frame (B's size must be 1) */
    pd_v3 org;               /* OVL_ORIGIN only: the first sum's origin, A's frame */
} ovl_in;

typedef struct ovl_out {
    int hit;        /* overlap volume above round-off */
    int degenerate; /* a zero predicate was resolved symbolically */
    int kept_a;     /* triangles of A that survived the filters */
    int kept_b;     /* triangles of B that survived the filters */
    pd_real volume; /* V */
    pd_v3 centroid; /* centre of mass of the overlap, A's frame */
    pd_v3 normal;   /* unit, from A into B (eq. 4.19), A's frame */
    pd_real depth;  /* extent of the overlap along normal */
    /*
     * OVL_PLACES: the number of separate places of the overlap (ovl_places), and the volume and
     * depth that give eqs. 4.16-4.18 the sums of each place's own force and stiffnesses. Without
     * the flag, or when more than pts_cap nodes leave the places unknown: 1, volume and depth.
     */
    int places;
    /* 0 where the places are not known and places is 1 for that reason: more nodes than pts_cap,
     * or a degenerate pair's nodes taken from its -w pass, whose per-node sums are not kept */
    int places_known;
    pd_real vol_eff, depth_eff;
    pd_v3 point_eff; /* where the places' summed force acts (their force-weighted centroids) */
    /* half the norm of eq. 4.19's vector (A's faces inside B minus B's inside A): the contact
     * area of a thin overlap; a host diagnostic (bench/contacts), not in the kernels' record */
    pd_real area;
} ovl_out;

/*
 * Vertices a cluster (ovl_in's vc_*, disc_*) and reals a cluster's disc. OVL_CLUSTER_MIN: the
 * vertices of both meshes together from which the filter uses the clusters. Below it, projecting
 * every vertex costs less than bounding the clusters and projecting those that reach an extreme
 * or the other's half-plane, about a third of a 1280-triangle icosphere's: with the clusters its
 * pair took 2 % longer and an 80-triangle pair 8 %, a 5120-triangle pair 10-13 % less
 * (bench/RESULTS.md, 2026-12-06).
 */
#define OVL_CLUSTER 16
#define OVL_DISC 9
#define OVL_CLUSTER_MIN 2048
PD_FN int ovl_nclusters(int nv)
{
    return (nv + OVL_CLUSTER - 1) / OVL_CLUSTER;
}

PD_FN int ovl_iscratch_len(int nta, int ntb, int nva, int nvb)
{
    /* kept, near, xa / xb, slot, strip ord: 5 per triangle; st, and ovl_resolve's list and
     * queue (one side at a time): 3 per vertex; hits and sweep_ord: 2 per triangle of B; the
     * clusters' projected flags: 1 per cluster */
    return 5 * (nta + ntb) + 3 * (nva + nvb) + 2 * ntb + ovl_nclusters(nva) + ovl_nclusters(nvb);
}
PD_FN int ovl_rscratch_len(int nta, int ntb, int nva, int nvb, int pts_cap)
{
    /* ... and the clusters' bounds of projection: 2 per cluster */
    return nva + nvb + 3 * nva + 3 * nvb + 3 * pts_cap + OVL_TRI_CACHE * ntb + nta + 2 * ntb +
           2 * (ovl_nclusters(nva) + ovl_nclusters(nvb));
}
/* The per-node arrays of OVL_PLACES (ovl_ctx, ovl_ndi, ovl_ndr): ints and reals. */
enum { OVL_ND_KEY, OVL_ND_END, OVL_ND_FL, OVL_ND_PAR, OVL_ND_ORD, OVL_ND_INTS };
enum {
    OVL_ND_VOL,
    OVL_ND_LAM,
    OVL_ND_LO,
    OVL_ND_HI,
    OVL_ND_AREA, /* 3 per node, as MOM and ORG */
    OVL_ND_MOM = OVL_ND_AREA + 3,
    OVL_ND_ORG = OVL_ND_MOM + 3, /* ovl_rescue: the origin its cusps are taken about */
    OVL_ND_REALS = OVL_ND_ORG + 3
};
/* Scratch that OVL_PLACES needs beyond the above, at the end of each (per node kept). */
PD_FN int ovl_places_ilen(int pts_cap)
{
    return OVL_ND_INTS * pts_cap;
}
PD_FN int ovl_places_rlen(int pts_cap)
{
    return OVL_ND_REALS * pts_cap;
}

/* Vertex state bits (per pass). */
#define OVL_V_READY 1   /* B only: transformed into A's frame */
#define OVL_V_TESTED 2  /* side of the other solid known in this pass (ovl_resolve) */
#define OVL_V_INSIDE 4  /* inside the other polyhedron */
#define OVL_V_EMITTED 8 /* its node emitted in this pass (ovl_vertex_emit) */
#define OVL_V_LISTED 16 /* on ovl_resolve's list of corners whose side is not yet known */
#define OVL_V_NODE 32   /* bits from here: 1 + the index of the vertex's node in this pass */

/*
 * One solid's kept triangles in order along eu, a direction across d, for the ray casts: every ray
 * of ovl_ray_parity runs along +-d, so only the triangles whose extent along eu holds the ray's
 * can be crossed, a strip of about the square root of them on a curved contact. The other tests
 * of a cast being O(kept triangles) each, a contact of many triangles was dominated by them (a
 * 5120-triangle rock pair at 1 % depth spent 63 % of its time there, bench/RESULTS.md). Built
 * on the solid's first cast of an overlap, when it has OVL_STRIP_MIN kept triangles or more;
 * below that, a cast tests every kept triangle (sorting would cost more than it saves). Not
 * against a wall (OVL_OPEN_B): the particle keeps all of its triangles there, unfiltered, and
 * sorting them all for the wall's few casts made 27 5120-triangle rocks on a 43 200-triangle
 * floor 18 % slower (bench/RESULTS.md).
 */
#define OVL_STRIP_MIN 64
typedef struct ovl_strip {
    PD_GLOBAL int *ord;     /* the kept triangles, by key */
    PD_GLOBAL pd_real *key; /* each one's lowest corner along eu */
    pd_real width;          /* the widest one's extent along eu */
    pd_v3 eu;
    int built;
} ovl_strip;

typedef struct ovl_ctx {
    const ovl_in *in;
    pd_v3 d; /* filter direction, eq. 5.3 */
    pd_real e1, e2;
    int filter;
    int ka, kb; /* triangles kept by the half-plane filter: the ray casts' candidates */
    int na, nb; /* of those, the ones meeting the box where A n B can lie: the pair loop's */
    PD_GLOBAL int *kept_a, *kept_b, *near_a, *near_b, *st_a, *st_b;
    PD_GLOBAL int *hits; /* ovl_pass: the near triangles of B whose boxes meet the current T's */
    /*
     * ovl_pass's crossings, per near triangle of A (xa) and of B (xb): bit k is the parity of
     * the other solid's faces that the triangle's edge k (corner k to k + 1) crosses. With them a
     * vertex's side of the other solid follows from a neighbour's (ovl_resolve), where it took a
     * ray cast. slot_a / slot_b: a triangle's place in near_a / near_b (valid where near lists
     * it back), queue: ovl_resolve's list of unknown corners and its walk's queue.
     */
    PD_GLOBAL int *xa, *xb, *slot_a, *slot_b, *queue;
    pd_v3 box_lo, box_hi;     /* box of A's kept part n box of B's kept part, padded */
    pd_v3 alo, ahi, blo, bhi; /* boxes of A's and B's kept parts, padded */
    pd_v3 nblo, nbhi;         /* box of B's near triangles (the pair loop's), padded */
    int origin_in_b;          /* OVL_OPEN_B: A's centroid inside the wall; -1 not yet known */
    PD_GLOBAL pd_real *proj_a, *proj_b, *vat, *vbt, *pts, *ucache;
    /*
     * clustered: the filter projected only the vertices of the clusters flagged in done_a /
     * done_b (ovl_in's vc_*); any other vertex is known to lie short of the other's half-plane
     * (ovl_proj). bnd_a / bnd_b: each cluster's lowest and highest possible projection.
     */
    int clustered;
    PD_GLOBAL int *done_a, *done_b;
    PD_GLOBAL pd_real *bnd_a, *bnd_b;
    ovl_strip strip_a, strip_b; /* for casts from B's vertices through A, and from A's through B */
    /*
     * The pair loop's sweep, when B has OVL_STRIP_MIN near triangles or more: their boxes in
     * order of their low ends on the axis d is least aligned with (sweep_ord: positions in
     * near_b; sweep_key: the low ends; sweep_width: the widest box on that axis), so that each
     * triangle of A looks only at the boxes that can meet its own on that axis instead of at all.
     */
    int sweep, sweep_axis;
    pd_real sweep_width;
    PD_GLOBAL int *sweep_ord;
    PD_GLOBAL pd_real *sweep_key;
    int npts, pts_overflow, store_pts;
    int pts_flip; /* the nodes stored are the -w pass's (ovl_sum: the +w pass had none) */
    /*
     * OVL_PLACES. Every node gets an index in the order a pass emits them (inode counts; a pass
     * without flip emits the same nodes in the same order). Per stored node, in pts_cap-long
     * arrays at nd_i and nd_r (ovl_ndi, ovl_ndr): key (2 * vertex + side, or for a crossing
     * 2 * the edge's lower end + side, with the edge's higher end in end, else -1), fl (1: the
     * crossing heads into the other solid towards the higher end), lam (its position along the
     * edge from the lower end), par (union-find), and the sums of its cusps: vol, area (eq.
     * 4.19's vector) and mom (first moment about origin), 3 reals each; lo, hi and ord are
     * ovl_places's work. cur_node: the node whose
     * cusps are being added; -1 none.
     */
    int places, rec, inode, cur_node; /* rec: this pass records the nodes' volumes */
    int joined;                       /* ovl_places_join has joined the nodes into places */
    int node_org; /* OVL_RESCUE: each node's cusps are taken about its place's centre (ORG) */
    PD_GLOBAL int *nd_i;
    PD_GLOBAL pd_real *nd_r;
    pd_real pad; /* OVL_SNAP * L: the configuration's length resolution */
    int flip;    /* 0: B displaced by +eps w, 1: by -eps w */
    /*
     * ovl_compute's last resort (ovl_compute_try's one_side): one pass only, with w (wneg 0) or -w
     * (wneg 1) for the first pass's displacement
     */
    int one_pass, wneg;
    int degenerate; /* a predicate was exactly zero */
    /* cusp sums, about `origin` (A's frame origin, or the nodes' centre when re-summed) */
    pd_v3 origin;
    pd_real vol;
    pd_real vol_abs;  /* sum of the cusps' |volume|: what vol's rounding is relative to */
    pd_v3 moment;     /* first moment of volume */
    pd_real area_abs; /* sum of |area| over every cusp: the scale of area_a - area_b's terms */
    pd_v3 area_a;     /* sum of area * outward normal over A's faces inside B */
    pd_v3 area_b;     /* the same over B's faces inside A */
#if !PD_DOUBLE
    /* each solid's sum of nu (x) n (t . p) over its cusps, row-major, and the sum of |t . p|
     * (ovl_faces_close) */
    pd_real gap[2][9];
    pd_real gap_abs;
#endif
    /* depth mode: project nodes on n instead of storing them */
    int depth_mode;
    pd_v3 n;
    pd_real lo, hi;
} ovl_ctx;

PD_FN PD_GLOBAL int *ovl_ndi(const ovl_ctx *c, int k)
{
    return c->nd_i + k * c->in->pts_cap;
}
PD_FN PD_GLOBAL pd_real *ovl_ndr(const ovl_ctx *c, int k)
{
    return c->nd_r + k * c->in->pts_cap;
}

/* Relative size below which a determinant is rounding noise: its inputs carry a few ulps from the
 * pose transform and the determinant adds about ten more; 64 ulps leaves a margin. */
#define OVL_SNAP (PD_R(64) * PD_EPS)

/* Ratio of a sum of cusps to their magnitudes below which ovl_compute_try sums them again about
 * the overlap's own centre (see there): the sum's relative rounding is about eps over it. */
#if PD_DOUBLE
#define OVL_RESUM PD_R(1e-8)
#else
#define OVL_RESUM (PD_R(1e4) * PD_EPS)
#endif

/*
 * How many resolutions (pad) every culling test gives away: the half-planes of eq. 5.5, the box
 * where A n B lies, the pair loop's triangle boxes and the casts' ray boxes. A plane predicate
 * snaps a point within 2 pad of the plane to a tie, which the symbolic displacement then decides
 * (ovl_plane_tol), so the configuration the predicates describe may differ from the coordinates
 * by that much; a test that culls by less can drop a corner, a triangle or a crossing that the
 * predicates count, and the cusps no longer close a surface. With one pad, two equal cubes
 * stacked face on face with side faces coplanar to within 2e-14 lost a side face (box) or called
 * a corner outside that the displaced pass put inside: a centroid 394 m off for a 1 m cube, a
 * third of the volume lost, and in a simulation the cubes thrown apart
 * (tests/physics/test_overlap.c, stacked_cubes_with_coplanar_sides). Twice the band.
 */
#define OVL_CULL 4

/*
 * The filter's direction d is also the direction of every ray cast (ovl_ray_parity), so it is
 * rounded to a grid of OVL_DIR_GRID steps per unit before use: any direction serves both, but
 * the exact one between the centres carries the very offsets the predicates snap. Two cubes
 * stacked with side faces delta apart (delta within the tie band) have delta / |c_b - c_a| as
 * the component of d across those faces: a ray from a corner on one face then crosses the other
 * at an angle of about the resolution, at t = delta / sin(angle), a point that no snap of delta
 * to 0 can place (it moves to the ray's start), and the parities came out wrong (a 1 m cube
 * given 0.6 m^3 of overlap for 1.1e-4; tests/physics/test_overlap.c,
 * cube_sides_across_the_tie_band). On the grid such components are exactly 0, so the rays run
 * exactly along the faces, which ovl_parallel rejects; a face crossed at all is crossed at an
 * angle of at least about 1 / OVL_DIR_GRID unless it is tilted to d by chance.
 */
#define OVL_DIR_GRID 1024

PD_FN pd_v3 ovl_dir_grid(pd_v3 u)
{
    pd_real g = PD_R(OVL_DIR_GRID);
    return v3_unit(v3(PD_FLOOR(u.x * g + PD_R(0.5)) / g, PD_FLOOR(u.y * g + PD_R(0.5)) / g,
                      PD_FLOOR(u.z * g + PD_R(0.5)) / g));
}

PD_FN pd_real ovl_det(pd_v3 a, pd_v3 b, pd_v3 c)
{
    return v3_dot(a, v3_cross(b, c));
}

/*
 * Snap bounds. Every predicate below is a determinant whose value is a distance times the lengths
 * of the edges it is taken against: a point's side of a triangle's plane is its distance times
 * |n| = |(v1 - v0) x (v2 - v0)|, a line's side of an edge is their distance times the edge's
 * length. Each is snapped to a tie when that distance is within about the resolution pad, so its
 * bound scales with its own edges, not with the configuration's size L: bounds of pad L^2 and
 * pad L^3 snapped the predicates of a triangle of edge e at distances of pad (L / e)^2, which for
 * 20 000-triangle rocks in single precision reached ~5e-3 L, where the ties, each broken on its
 * own, no longer described one geometry: their overlaps' volumes came out wrong by up to 200
 * times (bench/RESULTS.md). The bounds still exceed each determinant's own rounding (a few ulps
 * of its operands' products, the operands within 2 sqrt(3) L of each other) by more than ten
 * times, so a decision outside them is the exact one for the coordinates given.
 *
 * A plane's bound is 2 pad |n|, the Euclidean length: it must not depend on the frame's axes,
 * or coplanar triangles of one wall would disagree about a point's side. Bounds from the edges'
 * max-norms, tried first, did: a prism resting on a floor meshed in squares had corners within
 * the resolution by one triangle of the floor and outside it by the next, and got a 4 200 N kick.
 */
PD_FN pd_real ovl_plane_tol(const ovl_ctx *c, pd_real nn)
{
    return PD_R(2) * c->pad * nn; /* nn: |n| */
}

/*
 * The bands of the determinants of two lines, det(da, q, db) = (the lines' distance) x |da x db|
 * (x = da x db, or db x r for a ray along unit r). A band of 2 pad |x| snaps a line within 2 pad
 * of another to a tie exactly when a point there would against a plane through it.
 *
 * Rays (ovl_ray_tol): 2 pad |db x r|. The edges' max-norm bound 2 pad amax(db) snapped rays up to
 * 2 pad / sin(angle) from an edge: a ray cast within 2.2 pad of a cube's edge tied while the
 * corner it was cast from, 2.05 pad from the face, did not, and a cube stacked on another with its
 * side face 4.3e-14 m from the other's was given 0.509 m^3 of overlap for 6.6e-5
 * (tests/physics/test_overlap.c, cube_sides_across_the_tie_band). Edges within 14 degrees of the
 * ray keep a floor of pad |db| / 2, twice the determinant's worst rounding (about 4 eps |q| |db|
 * with |q| <= 2 sqrt(3) L, pad = 64 eps L): a decision outside the bound must be the exact one.
 *
 * Edges (ovl_edge_tol): 2 pad max(|da x db|, amax(da) amax(db)), the larger of that band and the
 * max-norm bound, never below the latter. Nearly parallel edges, as those of cubes stacked in a
 * column and turned against each other by rounding, must keep snapping as generously as before:
 * with the rays' floor instead, a 4 x 4 x 4 lattice of 2 cm cubes dropped onto each other
 * (bench/RESULTS.md, 2026-12-05) got an overlap of 1.7 % of a size at the first impacts and kept
 * gaining kinetic energy (8e-4 J after 0.4 s against 2e-5 J), the columns toppled. That distance
 * is ill-conditioned, and with the edges' ends snapped onto each other's planes only a tie keeps
 * the two kinds of predicate describing one geometry.
 *
 * In single precision that floor is far too wide for the contacts it is meant for. A resolution
 * is ~2e-7 m there for 2 cm particles, and the cubes of a settled lattice are turned against each
 * other by ~2e-4 rad, so 2 pad / sin(angle) is ~2 mm. The facing side edges of two cubes of a
 * column shifted sideways by 0.2 mm, a thousand resolutions, tied; the side tests of the same
 * corners, decided by the coordinates, disagreed with the ties; no try closed; and 5 to 15 of the
 * 48 contacts of each settled frame were lost (bench/RESULTS.md, 2026-12-07;
 * tests/physics/test_overlap.c, single_precision_finds_shifted_column_contacts). The single
 * floor is what can move this determinant instead, never more than the double floor:
 * - each end displaced by up to the resolution changes it by up to pad |q| (amax(da) + amax(db)),
 *   q = b0 - a0, taken at an eighth (pad = 64 eps L is some 20 times the transforms' own rounding
 *   of a coordinate);
 * - its own rounding, below 32 eps amax(da) amax(db) amax(q) (three products of two terms each,
 *   summed).
 * Double precision keeps its floor: the lattice above keeps every contact in double, and its
 * columns are where the wide floor was needed.
 */
PD_FN pd_real ovl_ray_tol(const ovl_ctx *c, pd_v3 x, pd_real db2)
{
    /* db2: |db|^2; one square root for both terms */
    return PD_R(2) * c->pad * PD_SQRT(pd_max(v3_dot(x, x), db2 * PD_R(0.0625)));
}

PD_FN pd_real ovl_edge_tol(const ovl_ctx *c, pd_v3 x, pd_v3 da, pd_v3 db, pd_v3 q)
{
#if PD_DOUBLE
    (void)q;
    return PD_R(2) * c->pad * pd_max(v3_norm(x), v3_amax(da) * v3_amax(db));
#else
    pd_real la = v3_amax(da), lb = v3_amax(db), lq = v3_amax(q);
    pd_real moved = PD_R(0.125) * c->pad * lq * (la + lb) + PD_R(32) * PD_EPS * la * lb * lq;
    return PD_R(2) * pd_max(c->pad * v3_norm(x), pd_min(c->pad * la * lb, moved));
#endif
}

/*
 * Sign of q0 + eps * (g . w) for w = (1, d, d^2): the sign of q0 when |q0| exceeds the snap bound
 * tol (ovl_sign), else of the first non-zero component of g (ovl_tie; negated for the -w pass).
 * Zero only when g vanishes, which the callers' geometry rules out (a parallel edge or ray, already
 * rejected by a plane test). g is computed by the caller only inside the band.
 */
PD_FN int ovl_sign(pd_real q0, pd_real tol)
{
    /* arithmetic, not branches: for a new pair the sign is unpredictable, and a mispredicted
     * branch per predicate was a tenth of a Schonhardt overlap's time (bench/overlap) */
    return (q0 > tol) - (q0 < -tol);
}

PD_FN int ovl_tie(ovl_ctx *c, pd_v3 g)
{
    c->degenerate = 1;
    /* components of g within rounding of its largest are zero too (near-aligned geometry) */
    pd_real gt = OVL_SNAP * v3_amax(g);
    int s = g.x > gt    ? 1
            : g.x < -gt ? -1
            : g.y > gt  ? 1
            : g.y < -gt ? -1
            : g.z > gt  ? 1
            : g.z < -gt ? -1
                        : 0;
    return c->flip != c->wneg ? -s : s;
}

PD_FN pd_v3 ovl_va(const ovl_ctx *c, int i)
{
    return v3_load(c->vat, i); /* scaled by sa once, for the kept triangles' corners */
}
PD_FN pd_v3 ovl_vb(const ovl_ctx *c, int j)
{
    return v3_load(c->vbt, j);
}
/* Vertex v of A (side 0) or B (side 1), in A's frame. */
PD_FN pd_v3 ovl_vx(const ovl_ctx *c, int side, int v)
{
    return v3_load(side ? c->vbt : c->vat, v);
}

/*
 * Orientation of A's edge a0->a1 against B's edge b0->b1, both canonical (lower index first):
 * sign of det(a1 - a0, b0 - a0, b1 - a0) = det(a1 - a0, b0 - a0, b1 - b0) (the lines' distance
 * times |da x db|; evaluated in the second form, whose rounding is relative to the edges' lengths)
 * with B displaced. The eps term is det(a1 - a0, w, b1 - b0) = w . ((b1 - b0) x (a1 - a0)).
 */
PD_FN int ovl_edge_edge(ovl_ctx *c, int ia0, int ia1, int ib0, int ib1)
{
    pd_v3 a0 = ovl_va(c, ia0), da = v3_sub(ovl_va(c, ia1), a0);
    pd_v3 b0 = ovl_vb(c, ib0), db = v3_sub(ovl_vb(c, ib1), b0);
    pd_v3 g = v3_cross(db, da);
    pd_v3 q = v3_sub(b0, a0);
    pd_real tol = ovl_edge_tol(c, g, da, db, q);
    int s = ovl_sign(ovl_det(da, q, db), tol);
    return s ? s : ovl_tie(c, g);
}

/* Directed edge-edge orientation from canonical evaluation: A edge i->j against B edge k->l. */
PD_FN int ovl_edge_edge_dir(ovl_ctx *c, int i, int j, int k, int l)
{
    int s = i < j ? 1 : -1;
    if (k > l) s = -s;
    return s * ovl_edge_edge(c, i < j ? i : j, i < j ? j : i, k < l ? k : l, k < l ? l : k);
}

/* Side of A's point p against B's triangle plane (u0, raw normal nu, snap bound tol from
 * ovl_plane_tol): eps term is -w . nu. */
PD_FN int ovl_side_a(ovl_ctx *c, pd_v3 p, pd_v3 u0, pd_v3 nu, pd_real tol, pd_real *q0)
{
    *q0 = v3_dot(v3_sub(p, u0), nu);
    int s = ovl_sign(*q0, tol);
    return s ? s : ovl_tie(c, v3_scale(nu, PD_R(-1)));
}

/* Side of B's point u against A's triangle plane (t0, raw normal nt, bound tol): eps term is
 * +w . nt. */
PD_FN int ovl_side_b(ovl_ctx *c, pd_v3 u, pd_v3 t0, pd_v3 nt, pd_real tol, pd_real *q0)
{
    *q0 = v3_dot(v3_sub(u, t0), nt);
    int s = ovl_sign(*q0, tol);
    return s ? s : ovl_tie(c, nt);
}

/*
 * Box of the ray p + t r (t >= 0) up to where it leaves the box [lo, hi]: the kept triangles it
 * can cross all lie inside [lo, hi], so a triangle whose box misses this one is not crossed.
 */
PD_FN void ovl_ray_box(pd_v3 p, pd_v3 r, pd_v3 lo, pd_v3 hi, pd_real pad, pd_v3 *rlo, pd_v3 *rhi)
{
    pd_real t = PD_REAL_MAX;
    if (r.x != PD_R(0)) t = pd_min(t, ((r.x > 0 ? hi.x : lo.x) - p.x) / r.x);
    if (r.y != PD_R(0)) t = pd_min(t, ((r.y > 0 ? hi.y : lo.y) - p.y) / r.y);
    if (r.z != PD_R(0)) t = pd_min(t, ((r.z > 0 ? hi.z : lo.z) - p.z) / r.z);
    t = pd_max(t, PD_R(0));
    pd_v3 q = v3_add(p, v3_scale(r, t));
    *rlo = v3(pd_min(p.x, q.x) - pad, pd_min(p.y, q.y) - pad, pd_min(p.z, q.z) - pad);
    *rhi = v3(pd_max(p.x, q.x) + pad, pd_max(p.y, q.y) + pad, pd_max(p.z, q.z) + pad);
}

/*
 * Whether boxes [alo, ahi] and [blo, bhi] meet: on each axis the larger low end lies at or below
 * the smaller high end. Written as max / min arithmetic with a single comparison, where the
 * obvious form (six comparisons joined by ||) compiles to up to six branches: whether a box test
 * passes is unpredictable, and on a 1280-triangle icosphere pair those branches were half of
 * the mispredicted ones (callgrind --branch-sim; bench/RESULTS.md). For boxes with lo <= hi the
 * answer is the comparisons' own: a difference is 0 only when its terms are equal (where a
 * device flushes subnormals, a gap below 1e-38 reads as touching, which only costs a test).
 */
PD_FN int ovl_boxes_meet(pd_v3 alo, pd_v3 ahi, pd_v3 blo, pd_v3 bhi)
{
    pd_real gx = pd_max(alo.x, blo.x) - pd_min(ahi.x, bhi.x);
    pd_real gy = pd_max(alo.y, blo.y) - pd_min(ahi.y, bhi.y);
    pd_real gz = pd_max(alo.z, blo.z) - pd_min(ahi.z, bhi.z);
    return pd_max(pd_max(gx, gy), gz) <= PD_R(0);
}

/* Whether triangle (u0, u1, u2) can meet the box [lo, hi]. */
PD_FN int ovl_tri_meets(pd_v3 u0, pd_v3 u1, pd_v3 u2, pd_v3 lo, pd_v3 hi)
{
    pd_v3 tlo = v3(pd_min(pd_min(u0.x, u1.x), u2.x), pd_min(pd_min(u0.y, u1.y), u2.y),
                   pd_min(pd_min(u0.z, u1.z), u2.z));
    pd_v3 thi = v3(pd_max(pd_max(u0.x, u1.x), u2.x), pd_max(pd_max(u0.y, u1.y), u2.y),
                   pd_max(pd_max(u0.z, u1.z), u2.z));
    return ovl_boxes_meet(tlo, thi, lo, hi);
}

PD_FN int ovl_in_box(const ovl_ctx *c, pd_v3 p)
{
    return p.x >= c->box_lo.x && p.x <= c->box_hi.x && p.y >= c->box_lo.y && p.y <= c->box_hi.y &&
           p.z >= c->box_lo.z && p.z <= c->box_hi.z;
}

/*
 * Whether the line through p along unit r passes through the triangle with corners v[] and vertex
 * indices id[]: the line turns the same way about all three edges. Each edge is evaluated in its
 * canonical orientation (lower index first), so the two triangles of an edge agree exactly. p is
 * a point of the solid displaced by sp eps w relative to the triangle's (see ovl_ray_parity).
 */
PD_FN int ovl_line_through(ovl_ctx *c, pd_v3 p, pd_v3 r, pd_real sp, const pd_v3 v[3],
                           const int id[3])
{
    int sg[3] = {0, 0, 0};
    for (int e = 0; e < 3; e++) {
        if (e > 0 && sg[e - 1] != sg[0]) return 0; /* turns differ: the line misses */
        int e1 = (e + 1) % 3;
        int k0 = id[e], k1 = id[e1];
        pd_v3 b0 = k0 < k1 ? v[e] : v[e1], db = v3_sub(k0 < k1 ? v[e1] : v[e], b0);
        /* det(r, b0 - q, b1 - q) = det(r, b0 - q, b1 - b0) for q = p + sp eps w: the line's
         * distance from the edge times the edge's length across r; eps term
         * -sp w . ((b1 - b0) x r) */
        pd_v3 g = v3_cross(db, r);
        int sv = ovl_sign(ovl_det(r, v3_sub(b0, p), db), ovl_ray_tol(c, g, v3_dot(db, db)));
        if (!sv) sv = ovl_tie(c, v3_scale(g, -sp));
        sg[e] = k0 < k1 ? sv : -sv;
    }
    return sg[0] != 0 && sg[0] == sg[1] && sg[1] == sg[2];
}

/* Side of point p (displaced by sp eps w) against the plane through v0 with raw normal n, snap
 * bound tol (ovl_plane_tol). */
PD_FN int ovl_point_side(ovl_ctx *c, pd_v3 p, pd_v3 v0, pd_v3 n, pd_real tol, pd_real sp)
{
    /* (p - v0) . n with p displaced by sp eps w: eps term sp w . n */
    int s = ovl_sign(v3_dot(v3_sub(p, v0), n), tol);
    return s ? s : ovl_tie(c, v3_scale(n, sp));
}

/*
 * Whether a line along unit r is parallel to the plane of a triangle (raw normal n of length nn)
 * to within the resolution: r . n = |n| sin(angle), and the plane's direction is known to about
 * pad over the triangle's size sqrt(|n|) (so that coplanar triangles of equal size agree).
 */
PD_FN int ovl_parallel(const ovl_ctx *c, pd_real rn, pd_real nn)
{
    return rn * rn <= c->pad * c->pad * nn;
}

/* Whether the ray from p along unit r crosses the triangle v[] (ids id[]); sp as above. */
PD_FN int ovl_ray_crosses(ovl_ctx *c, pd_v3 p, pd_v3 r, pd_real sp, const pd_v3 v[3],
                          const int id[3])
{
    pd_v3 n = v3_cross(v3_sub(v[1], v[0]), v3_sub(v[2], v[0]));
    pd_real rn = v3_dot(r, n), nn = v3_norm(n);
    /* a ray parallel to the plane, to within rounding, never crosses it (exactly parallel it
     * would cross only if it lay in the plane, which the perturbation rules out) */
    if (ovl_parallel(c, rn, nn)) return 0;
    int s = ovl_point_side(c, p, v[0], n, ovl_plane_tol(c, nn), sp);
    if ((s > 0) != (rn < PD_R(0))) return 0; /* plane behind the ray's start */
    return ovl_line_through(c, p, r, sp, v, id);
}

/*
 * Sorts an index list ascending in place: insertion sort for the short, nearly sorted lists of a
 * DEM contact, Shell sort beyond (no recursion, no extra memory).
 */
PD_FN void ovl_sort(PD_GLOBAL int *a, int n)
{
    for (int gap = n > 64 ? n / 2 : 1; gap > 0; gap = gap == 2 ? 1 : gap * 5 / 11) {
        for (int i = gap; i < n; i++) {
            int x = a[i], j = i;
            for (; j >= gap && a[j - gap] > x; j -= gap)
                a[j] = a[j - gap];
            a[j] = x;
        }
    }
}

/* Sorts key[0..n) ascending, carrying ord along (Shell sort: no recursion, no extra memory). */
PD_FN void ovl_sort_keyed(PD_GLOBAL pd_real *key, PD_GLOBAL int *ord, int n)
{
    for (int gap = n / 2; gap > 0; gap = gap == 2 ? 1 : gap * 5 / 11) {
        for (int i = gap; i < n; i++) {
            pd_real x = key[i];
            int t = ord[i], j = i;
            for (; j >= gap && key[j - gap] > x; j -= gap) {
                key[j] = key[j - gap];
                ord[j] = ord[j - gap];
            }
            key[j] = x;
            ord[j] = t;
        }
    }
}

/* The first of the ascending key[0..n) that is >= x (n when none is). */
PD_FN int ovl_first_key(PD_GLOBAL const pd_real *key, int n, pd_real x)
{
    int a = 0, b = n;
    while (a < b) {
        int mid = (a + b) / 2;
        if (key[mid] < x)
            a = mid + 1;
        else
            b = mid;
    }
    return a;
}

/* The coordinate axis (0, 1, 2) that d is least aligned with: the strip's eu and the pair
 * loop's sweep run across d, the direction the contact is pressed along. */
PD_FN int ovl_least_axis(pd_v3 d)
{
    pd_v3 ad = v3(PD_FABS(d.x), PD_FABS(d.y), PD_FABS(d.z));
    return ad.x <= ad.y && ad.x <= ad.z ? 0 : ad.y <= ad.z ? 1 : 2;
}

PD_FN void ovl_strip_build(const ovl_ctx *c, ovl_strip *s, PD_GLOBAL const int *tri,
                           PD_GLOBAL const int *kept, int nk, PD_GLOBAL const pd_real *vx)
{
    /* eu: d crossed with the axis it is least aligned with */
    int a = ovl_least_axis(c->d);
    s->eu = v3_unit(v3_cross(c->d, v3(a == 0, a == 1, a == 2)));
    pd_real width = PD_R(0);
    for (int k = 0; k < nk; k++) {
        int t = kept[k];
        pd_real u0 = v3_dot(v3_load(vx, tri[3 * t]), s->eu);
        pd_real u1 = v3_dot(v3_load(vx, tri[3 * t + 1]), s->eu);
        pd_real u2 = v3_dot(v3_load(vx, tri[3 * t + 2]), s->eu);
        pd_real lo = pd_min(pd_min(u0, u1), u2);
        width = pd_max(width, pd_max(pd_max(u0, u1), u2) - lo);
        s->key[k] = lo;
        s->ord[k] = t;
    }
    s->width = width;
    ovl_sort_keyed(s->key, s->ord, nk); /* kept lists come in index order, unrelated to eu */
    s->built = 1;
}

/*
 * Point-in-solid test by ray parity: whether p lies inside the solid whose kept triangles are
 * tri[kept[0..nk)] over vertices vx (A's frame) and whose kept part lies in the box [lo, hi],
 * counting crossings of the ray from p along sp d (all it can meet are kept, by the half-plane
 * filter). B is the body displaced by +eps w, so relative to the tested solid p moves by
 * sp eps w: sp = -1 for A's points tested against B, +1 for B's against A; sp fixes every
 * tie-break below as in ovl_side_a/_b.
 */
PD_FN int ovl_ray_parity(ovl_ctx *c, pd_v3 p, PD_GLOBAL const int *tri, PD_GLOBAL const int *kept,
                         int nk, PD_GLOBAL const pd_real *vx, pd_real sp, pd_v3 lo, pd_v3 hi,
                         ovl_strip *s)
{
    pd_v3 r = v3_scale(c->d, sp);
    pd_v3 rlo, rhi;
    ovl_ray_box(p, r, lo, hi, OVL_CULL * c->pad, &rlo, &rhi);
    int odd = 0, k0 = 0, k1 = nk;
    if (c->filter && nk >= OVL_STRIP_MIN && !(c->in->flags & OVL_OPEN_B)) {
        if (!s->built) ovl_strip_build(c, s, tri, kept, nk, vx);
        /* the triangles whose extent along eu, widened by 4 resolutions (as the boxes are by
         * one; the coordinates along eu carry a few ulps of L), holds the ray's: keys from
         * u - width - m to u + m. ovl_line_through snaps within 2 pad of an edge (ovl_ray_tol),
         * and within 2 pad / (4 sin(angle)) of one within 14 degrees of the ray: beyond this
         * margin only for edges within 7 degrees, where a tie could fall to a skipped triangle
         * (never seen: with and without the strip and boxes, 1 920 single-precision pairs of
         * up to 20 000 triangles agree; bench/RESULTS.md) */
        pd_real u = v3_dot(p, s->eu), m = PD_R(4) * c->pad;
        k0 = ovl_first_key(s->key, nk, u - s->width - m);
        for (k1 = k0; k1 < nk && s->key[k1] <= u + m; k1++)
            ;
        kept = s->ord;
    }
    for (int k = k0; k < k1; k++) {
        int t = kept[k];
        int id[3] = {tri[3 * t], tri[3 * t + 1], tri[3 * t + 2]};
        pd_v3 v[3] = {v3_load(vx, id[0]), v3_load(vx, id[1]), v3_load(vx, id[2])};
        if (c->filter && !ovl_tri_meets(v[0], v[1], v[2], rlo, rhi)) continue;
        odd ^= ovl_ray_crosses(c, p, r, sp, v, id);
    }
    return odd;
}

/* B's vertex x (B's frame) in A's frame. */
PD_FN pd_v3 ovl_b_to_a(const ovl_in *in, pd_v3 x)
{
    return v3(in->rot[0] * x.x + in->rot[1] * x.y + in->rot[2] * x.z + in->tr[0],
              in->rot[3] * x.x + in->rot[4] * x.y + in->rot[5] * x.z + in->tr[1],
              in->rot[6] * x.x + in->rot[7] * x.y + in->rot[8] * x.z + in->tr[2]);
}

/*
 * Parity of the ray from p along unit r (a point of the solid displaced by -eps w, as A's) through
 * the triangles of tree w: whether p lies inside the tree's closed mesh. The tree is searched in
 * its own frame, where the ray is (pw, rw) (the same ray to rounding; the boxes are widened well
 * beyond that rounding), and each triangle it may cross is mapped into p's frame by map's rot and
 * tr exactly as ovl_compute maps B's vertices (map NULL: the frames are the same), then decided
 * by the same predicates as any other crossing.
 */
PD_FN int ovl_tree_parity(ovl_ctx *c, const wb_tree *w, const ovl_in *map, pd_v3 p, pd_v3 r,
                          pd_v3 pw, pd_v3 rw)
{
    PD_GLOBAL const pd_real *root = w->box;
    pd_v3 o = pw;
    pd_real ext = pd_max(v3_amax(o), pd_max(v3_amax(v3(root[0], root[1], root[2])),
                                            v3_amax(v3(root[3], root[4], root[5]))));
    pd_real pad = PD_R(1024) * PD_EPS * ext + OVL_CULL * c->pad;
    int stack[WB_STACK], sp = 0, odd = 0;
    if (wb_ray_meets(root, o, rw, pad)) stack[sp++] = 0;
    while (sp > 0) {
        int k = stack[--sp];
        int k0 = w->kid[2 * k], k1 = w->kid[2 * k + 1];
        if (k0 >= 0) {
            if (sp + 2 > WB_STACK) break; /* the builder bounds the depth; never taken */
            if (wb_ray_meets(w->box + 6 * k1, o, rw, pad)) stack[sp++] = k1;
            if (wb_ray_meets(w->box + 6 * k0, o, rw, pad)) stack[sp++] = k0;
            continue;
        }
        for (int i = -1 - k0; i < -1 - k0 + k1; i++) {
            int t = w->order[i];
            int id[3] = {w->tri[3 * t], w->tri[3 * t + 1], w->tri[3 * t + 2]};
            pd_v3 v[3];
            for (int q = 0; q < 3; q++) {
                v[q] = v3_load(w->vert, id[q]);
                if (map) v[q] = ovl_b_to_a(map, v[q]);
            }
            odd ^= ovl_ray_crosses(c, p, r, PD_R(-1), v, id);
        }
    }
    return odd;
}

/* A's centroid (the origin of A's frame) in B's frame, rot^T (0 - tr): exact to rounding when B
 * has size 1 (rot a rotation), as walls have. */
PD_FN pd_v3 ovl_a_centroid_in_b(const ovl_in *in)
{
    const pd_real *R = in->rot, *t = in->tr;
    return v3(-(R[0] * t[0] + R[3] * t[1] + R[6] * t[2]),
              -(R[1] * t[0] + R[4] * t[1] + R[7] * t[2]),
              -(R[2] * t[0] + R[5] * t[1] + R[8] * t[2]));
}

/* OVL_OPEN_B: whether A's centroid (the origin) lies inside the whole wall: the parity of the
 * ray along -d through the wall's tree (mapped back by rot^T: a wall has size 1). */
PD_FN int ovl_origin_in_b(ovl_ctx *c)
{
    if (c->origin_in_b >= 0) return c->origin_in_b;
    const ovl_in *in = c->in;
    const pd_real *R = in->rot;
    pd_v3 r = v3_scale(c->d, PD_R(-1)), o = ovl_a_centroid_in_b(in);
    pd_v3 rw = v3(R[0] * r.x + R[3] * r.y + R[6] * r.z, R[1] * r.x + R[4] * r.y + R[7] * r.z,
                  R[2] * r.x + R[5] * r.y + R[8] * r.z);
    c->origin_in_b = ovl_tree_parity(c, &in->wall, in, v3(0, 0, 0), r, o, rw);
    return c->origin_in_b;
}

/*
 * OVL_OPEN_B: whether A's point p lies inside the wall: the centroid's answer, flipped by every
 * local triangle the segment from p to the centroid crosses (all such triangles are local: the
 * segment lies in A's circumsphere, so in the cube the local part was taken from).
 */
PD_FN int ovl_open_inside_b(ovl_ctx *c, pd_v3 p)
{
    int odd = ovl_origin_in_b(c);
    pd_real len = v3_norm(p);
    if (!(len > PD_R(0))) return odd;
    pd_v3 r = v3_scale(p, PD_R(-1) / len), o = v3(0, 0, 0);
    pd_real m = OVL_CULL * c->pad;
    pd_v3 slo = v3(pd_min(p.x, 0) - m, pd_min(p.y, 0) - m, pd_min(p.z, 0) - m);
    pd_v3 shi = v3(pd_max(p.x, 0) + m, pd_max(p.y, 0) + m, pd_max(p.z, 0) + m);
    PD_GLOBAL const int *tri = c->in->tb;
    for (int k = 0; k < c->kb; k++) {
        int t = c->kept_b[k];
        int id[3] = {tri[3 * t], tri[3 * t + 1], tri[3 * t + 2]};
        pd_v3 v[3] = {ovl_vb(c, id[0]), ovl_vb(c, id[1]), ovl_vb(c, id[2])};
        if (!ovl_tri_meets(v[0], v[1], v[2], slo, shi)) continue;
        pd_v3 n = v3_cross(v3_sub(v[1], v[0]), v3_sub(v[2], v[0]));
        pd_real nn = v3_norm(n);
        if (ovl_parallel(c, v3_dot(r, n), nn)) continue; /* as in ovl_ray_crosses */
        /* both ends are A's points: the segment crosses the plane when they lie on either side */
        pd_real tol = ovl_plane_tol(c, nn);
        if (ovl_point_side(c, p, v[0], n, tol, PD_R(-1)) ==
            ovl_point_side(c, o, v[0], n, tol, PD_R(-1)))
            continue;
        odd ^= ovl_line_through(c, p, r, PD_R(-1), v, id);
    }
    return odd;
}

/*
 * Vertex v's projection on the filter's direction (side 0: A's, 1: B's). Where the filter left
 * its cluster unprojected, the cluster lies wholly short of the other's half-plane (ovl_in's
 * vc_*), and the value stands for that: the lowest real for A, the highest for B.
 */
PD_FN pd_real ovl_proj(const ovl_ctx *c, int side, int v)
{
    if (side) {
        if (c->clustered && !c->done_b[c->in->vc_b[c->in->nvb + v]]) return PD_REAL_MAX;
        return c->proj_b[v];
    }
    if (c->clustered && !c->done_a[c->in->vc_a[c->in->nva + v]]) return -PD_REAL_MAX;
    return c->proj_a[v];
}

/* Whether vertex v of side (0: A, 1: B) is outside the other solid by the filter alone: beyond
 * the other's half-plane or outside the box where A n B lies (both widened by OVL_CULL pads). */
PD_FN int ovl_outside_known(const ovl_ctx *c, int side, int v)
{
    if (!c->filter) return 0;
    if (side) return ovl_proj(c, 1, v) > c->e1 || !ovl_in_box(c, ovl_vb(c, v));
    if (c->in->flags & OVL_OPEN_B) return 0; /* A is not filtered against a wall */
    return ovl_proj(c, 0, v) < c->e2 || !ovl_in_box(c, ovl_va(c, v));
}

/* Point-in-B test for A's vertex i, one that ovl_outside_known did not place. */
PD_FN int ovl_inside_b(ovl_ctx *c, int i)
{
    pd_v3 p = ovl_va(c, i);
    if (c->in->flags & OVL_OPEN_B) return ovl_open_inside_b(c, p);
    return ovl_ray_parity(c, p, c->in->tb, c->kept_b, c->kb, c->vbt, PD_R(-1), c->blo, c->bhi,
                          &c->strip_b);
}

/* Point-in-A test for B's vertex j, one that ovl_outside_known did not place. */
PD_FN int ovl_inside_a(ovl_ctx *c, int j)
{
    return ovl_ray_parity(c, ovl_vb(c, j), c->in->ta, c->kept_a, c->ka, c->vat, PD_R(1), c->alo,
                          c->ahi, &c->strip_a);
}

#endif /* PD_OVERLAP_PREDICATES_H */
