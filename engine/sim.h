/*
 * sim.h - the state of one run on a device and its stages (engine-internal; the public face is
 * pd_run in polydem.h).
 *
 * Bodies are the n particles followed by the walls: every per-body array (x, q, v, w, size,
 * inv_m, shape, material) has n + nwall entries, so a wall is a body of infinite mass whose
 * shape is its own mesh (in metres about its centroid, size 1) and whose pose the host sets
 * from the wall's prescribed motion. Per-particle arrays (L, f, t) have n entries; a particle's
 * inertia is its shape's (unit_inertia, per unit density and size) times its material's density
 * times size^5, not stored per particle.
 *
 * A step (sim_step.c), all on the device:
 *   kick (dt/2) -> drift -> [walls moved] -> forces -> kick (dt/2)
 * where forces = [history kept -> boxes -> Morton codes -> radix sort -> LBVH nodes -> refit ->
 * traversal (count, scan, write: sorted keys)] -> contact forces with history -> gather by
 * particle ([contacts as second body counted and listed], then summed in key order). The
 * bracketed parts run only when the pair list is stale: boxes carry a Verlet skin, and the last
 * list is reused until a particle has moved half of it (see `skin` below).
 * On a rebuild the host reads the number of carried and of candidate pairs (to size arrays);
 * on every step the divergence and wall flags. Everything else stays on the device until a
 * stats row or frame is due.
 */
#ifndef PD_SIM_H
#define PD_SIM_H

#include "cl_internal.h"
#include "device_sort.h"
#include "particles.h"
#include "scenario.h"

/* The stages of a step, as profiling books them. */
enum { SIM_INTEGRATE, SIM_BVH, SIM_TRAVERSE, SIM_CONTACTS, SIM_GATHER, SIM_NSTAGES };

/* Pairs sorted by key with their tangential state (kernels/contact_history.h). */

typedef struct sim_pairs {
    cl_mem keys, spring, kt;
    cl_mem point; /* last step's contact point (world): the next overlap's origin in single
                     precision (OVL_ORIGIN); NULL in double precision, which does not use it */
    cl_mem twist; /* the twisting spring's moment, N m (kernels/contact_force.h, cf_twist) */
    size_t cap;   /* capacity in pairs */
} sim_pairs;

typedef struct sim {
    pd_device *dev;
    const pd_scenario *s;
    int dbl;    /* double precision on the device */
    int places; /* an interaction asks for separate places: the CL_PLACES build, its scratch */
    /* some polyhedral pair has "contact_moments": the pair arrays carry the twist (a NULL
     * buffer otherwise, which the kernels test for) */
    int moments;
    size_t rs; /* sizeof(pd_real) on the device */
    int n, nwall, nbody, nmat, nshape;
    double dt;
    long long step;
    sc_particles *p;    /* initial state; mass, inertia, size on the host */
    double *wall_c0;    /* 3 per wall: the wall mesh's centroid at t = 0 */
    double *wall_local; /* the wall meshes about their centroids (concatenated) */
    double *wall_lbox;  /* 6 per wall: the box of its wall_local (lo, hi), for its boxes */
    int *wall_voff;
    int walls_move;
    /* the fastest any point of a moving wall moves, m/s: |v| + |omega| times its farthest vertex
     * from the rotation centre (walls move at constant velocities) */
    double wall_speed;
    double wall_time; /* the time the walls were last placed at (sim_walls_at) */
    /* sim_walls_at's host copy of what it writes to the device, and the event of its last write:
     * the writes do not block (a blocking write each step stalled the queue five times) */
    void *wall_stage;
    cl_event wall_ev;
    double margin;            /* added to every box: half the largest cohesion range, m */
    double lo[3], inv_ext[3]; /* Morton scene box */

    /* bodies (w: the walls' angular velocities only, from index 0) */
    cl_mem x, q, v, w, size, inv_m, shape, material;
    /* particles */
    cl_mem L, f, t;
    /* shapes and materials */
    cl_mem vert, tri, voff, toff, vt_off, vt, kind, radius_ratio, params;
    cl_mem vc, coff, disc;        /* the particle shapes' vertex clusters (np_cluster_tables) */
    cl_mem unit_inertia, density; /* per shape: principal moments for size 1 and density 1;
                                     per material: kg/m^3 */
    /* walls' triangle BVHs (kernels/wall_bvh.h, engine/wall_tree.c) */
    cl_mem wnode_box, wnode_kid, wnode_off, wtri_order;
    int wall_cap; /* most triangles of one wall that can be near one particle */
    /* broad phase */
    /* arrivals, codes_tmp, idx_tmp and cand share the memory of count, t, second_count and f,
     * free while the broad phase uses them (sim_create) */
    cl_mem wbox, tbox, left, right, parent, arrivals, codes, idx, codes_tmp, idx_tmp;
    cl_mem count, offset, status;
    cl_mem cand; /* broad phase: the first BVH_CAND partners of each particle, while counting */
    cl_mem carry_offset; /* where each particle's carried pairs begin in carry.keys */
    /* [1]: lowest particle found not finite, [2]: lowest particle * nwall + wall with more
     * wall triangles near it than wall_cap (kernels/contact_pair.h); INT_MAX when none */
    cl_int status_host[3];
    /*
     * Verlet skin: particle and wall boxes are grown by skin / 2, so the pair list built at
     * positions x_ref holds every pair that can touch until some particle has moved skin / 2
     * (the drift kernel flags status[0]) or some wall has (wall_speed times the time since);
     * until then a step reuses the list instead of building the tree and traversing it.
     */
    double skin;
    cl_mem x_ref;
    cl_mem travel;    /* per particle: how far any of its points has moved since the list was built,
                         at most (integrate.cl); separated pairs are skipped until it adds up to
                         their certified gap (contact.cl) */
    int list_valid;   /* a list was built and nothing since invalidates it */
    int list_fresh;   /* this step built the list (not reused): state comes from `carry` */
    long long builds; /* pair lists built so far (bench) */
    long long built_at;     /* the step the list was built at */
    double built_wall_time; /* the walls' time then */
    double list_life;       /* steps lists have lasted, smoothed over the last few */
    /*
     * The pair list, its state updated in place while the list is reused; and, on the step a
     * new list is built, the old list's pairs that carry state (ch_has_state), which the new
     * pairs look themselves up in: one list's memory plus the touching pairs', not two lists'.
     */
    sim_pairs pairs, carry;
    int npairs;
    cl_mem force, torque, info, second_list; /* torque: on the first body (ch_first_torque) */
    cl_mem second_count, second_off; /* per particle: contacts as second body, their offsets */
    size_t work_cap;                 /* capacity of the per-pair work arrays above */
    /* overlap scratch, per contact work-item */
    cl_mem iscr, rscr;
    int ilen, rlen, pts_cap, nwork;
    /* kernels */
    cl_kernel k_codes, k_leaves, k_nodes, k_refit, k_count, k_write, k_contact, k_hist_count,
        k_hist_keep, k_second_count, k_second_fill, k_body, k_kick, k_drift, k_stats_energy,
        k_stats_contacts;
    /* a stats row's partial sums (kernels/stats.cl, sim_stats.c): up to stat_parts work-items,
     * each summing every stat_parts-th particle or pair */
    int stat_parts;
    cl_mem st_sum, st_emax, st_imax, st_count, st_ratio, st_wall;
    dsort sort;
    /* profiling (bench/step, and pd_run for the steps that end at stats rows): when set, every
     * stage ends with clFinish and its wall time is added to stage_seconds[SIM_*] */
    int profile;
    double bytes; /* device memory this run has allocated (buffers only), bytes */
    double stage_seconds[SIM_NSTAGES];
} sim;

/* Up to this many particles the broad phase tests all pairs of boxes (no tree: fewer launches). */
#define SIM_BRUTE_MAX 16

/* sim_state.c: set-up, host <-> device copies, wall motion */
int sim_create(pd_device *dev, const pd_scenario *s, sim **out, pd_error *err);
void sim_destroy(sim *m);
/* Reads cnt reals of buffer b from offset `first` (in reals) into doubles. */
int sim_read(sim *m, cl_mem b, size_t first, size_t cnt, double *out, pd_error *err);
int sim_write(sim *m, cl_mem b, size_t first, size_t cnt, const double *in, pd_error *err);
/* Reads the first cnt pairs' info into doubles (floats on the device in either precision: depth
 * / smaller size when touching, negative when not: -2 certified apart, see contact.cl). */
int sim_read_info(sim *m, size_t cnt, double *out, pd_error *err);
/* Enqueues zeros into the first cnt reals of b. */
cl_int sim_zero_reals(sim *m, cl_mem b, size_t cnt);
/* Sets the walls' poses, velocities and boxes for time t (when they move). */
int sim_walls_at(sim *m, double t, pd_error *err);

/* sim_stats.c: a stats row, summed on the device (kernels/stats.cl) */
/* The particles' kinetic energy, J (translational + rotational), and the particle with the most
 * (one whose state is not finite, if any). */
int sim_stats_energy(sim *m, double *ke, int *worst, pd_error *err);
/* The last step's touching pairs, largest depth / size, and the force on each wall, N
 * (wall_force: 3 per wall). */
int sim_stats_contacts(sim *m, long *contacts, double *max_ratio, double *wall_force,
                       pd_error *err);

/* sim_step.c: the stages */
int sim_forces(sim *m, pd_error *err);
int sim_step(sim *m, int *bad_particle, pd_error *err);
/* Sets kernel k's arguments first .. first + 4 to the bodies' arrays its particle boxes are
 * computed from (kernels/broad_phase.cl): x, size, shape, radius_ratio, margin. */
cl_int sim_body_box_args(sim *m, cl_kernel k, int first);

#endif
