/*
 * polydem.h - the public engine API: everything the CLI and the daemon may touch.
 *
 * Conventions (see ../shared/STYLE.md): every call that can fail returns 0 on success or a negative
 * PD_E* code and fills a pd_error whose message names the thing and what is wrong. Library code
 * never exits. Objects follow create -> use -> destroy; destroy accepts NULL.
 *
 * Units are SI throughout: metres, kilograms, seconds.
 */
#ifndef POLYDEM_H
#define POLYDEM_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ---- errors ------------------------------------------------------------------------------ */

enum {
    PD_OK = 0,
    PD_EINVAL = -1,     /* bad argument or bad input data */
    PD_EIO = -2,        /* file could not be read or written */
    PD_EMESH = -3,      /* mesh failed validation */
    PD_ENOMEM = -4,     /* allocation failed */
    PD_ECL = -5,        /* OpenCL failure */
    PD_ECANCELLED = -6, /* a run was stopped through its cancel flag */
    PD_EDIVERGED = -7, /* a run produced NaN or runaway energy (the message names step, particle) */
};

typedef struct pd_error {
    int code;
    char msg[512];
} pd_error;

/* Fills err (when non-NULL) with code and a printf-style message; returns code. */
int pd_error_set(pd_error *err, int code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* ---- meshes (engine/mesh.c, engine/mesh_io.c, engine/mesh_builtin.c) ------------------------- */

/*
 * A closed, edge-manifold, consistently outward-oriented triangle mesh. Triangles are
 * counter-clockwise seen from outside, so (v1-v0)x(v2-v0) is the outward normal.
 */
typedef struct pd_mesh {
    int nverts;
    int ntris;
    double *verts; /* 3*nverts coordinates, m */
    int *tris;     /* 3*ntris vertex indices */
} pd_mesh;

/* Mass properties of the solid bounded by a mesh, for unit density. */
typedef struct pd_mass_props {
    double volume;        /* m^3 */
    double centroid[3];   /* m */
    double inertia[3][3]; /* about the centroid, per unit density, m^5 */
    double principal[3];  /* principal moments, ascending, m^5 */
    double axes[3][3];    /* axes[i] is the unit principal axis of principal[i]; right-handed */
} pd_mass_props;

/*
 * Loads "builtin:NAME[:TRIANGLES[:SEED]]" or a file (binary or ASCII STL, Wavefront OBJ). Welds
 * coincident vertices, validates (closed, edge-manifold, consistently oriented, no zero-area
 * triangles, positive volume, no two triangles crossing: parts may touch, not cut through each
 * other) and silently flips an inward-oriented mesh or part. Errors name the file and the defect.
 */
int pd_mesh_open(const char *spec, pd_mesh **out, pd_error *err);

/* Loads a mesh file only (no builtin: prefix). */
int pd_mesh_load(const char *path, pd_mesh **out, pd_error *err);

/*
 * Built-in shapes generated in code:
 *   "cube"        unit cube centred at the origin, axis-aligned (12 triangles)
 *   "tetrahedron" regular, vertices (1,1,1),(1,-1,-1),(-1,1,-1),(-1,-1,1) (4 triangles)
 *   "schonhardt"  the non-convex twisted triangular prism of thesis figure 7.2 (8 triangles)
 *   "icosphere"   unit-circumradius subdivided icosahedron; triangles 20, 80, 320, 1280, 5120
 *   "rock"        seeded, non-convex, star-shaped irregular particle; any even triangle count >= 20
 * triangles <= 0 picks the default (icosphere 80, rock 80); seed is used by "rock" only.
 */
int pd_mesh_builtin(const char *name, int triangles, unsigned seed, pd_mesh **out, pd_error *err);

/*
 * Builds a mesh from arrays (copied), welds and validates it as pd_mesh_load does; label names
 * the source in error messages.
 */
int pd_mesh_from_arrays(const double *verts, int nverts, const int *tris, int ntris,
                        const char *label, pd_mesh **out, pd_error *err);

/* The solid box [lo, hi] (every lo[k] < hi[k]) as a closed mesh of 12 triangles, as walls'
 * "box" are meshed. */
int pd_mesh_box(const double lo[3], const double hi[3], pd_mesh **out, pd_error *err);

void pd_mesh_destroy(pd_mesh *m);

/* Writes binary STL. */
int pd_mesh_write_stl(const pd_mesh *m, const char *path, pd_error *err);

/* Exact mass properties (divergence theorem over the triangles). */
void pd_mesh_mass_props(const pd_mesh *m, pd_mass_props *mp);

/*
 * Moves the mesh into its body frame: centroid at the origin, principal axes along x, y, z.
 * Where principal moments coincide (relative difference < 1e-9) the mesh's own axes are kept
 * in that eigenspace, so a cube stays axis-aligned. On return rot[i][j] is the rotation with
 * v_body = rot * (v - centroid); mp (if non-NULL) is updated to the body-frame properties.
 */
void pd_mesh_to_body_frame(pd_mesh *m, pd_mass_props *mp, double rot[3][3]);

/* ---- rigid poses ---------------------------------------------------------------------------- */

/* world = R(q) v + x; q = (w, x, y, z), normalised by the functions that take it. */
typedef struct pd_pose {
    double x[3];
    double q[4];
} pd_pose;

/*
 * The number of result files HDF5 could not close (a disk that filled up under a run). HDF5 keeps
 * them open, and its own clean-up at exit then crashes on them; a program for which this is not
 * 0 should end with _exit (after flushing its streams) instead of returning from main.
 */
int pd_results_unclosed(void);

/* q / |q| into out (which may be q), exact in range for any finite q (no overflow of the squares).
 * Returns PD_EINVAL for a zero or non-finite quaternion. */
int pd_quat_normalize(const double q[4], double out[4]);

/* Rotation matrix of a quaternion (normalised first). Returns PD_EINVAL for a zero quaternion. */
int pd_quat_to_matrix(const double q[4], double r[3][3]);

/*
 * Where a moving wall is at time t (s). A wall translates at velocity v (m/s) and turns at the
 * constant angular velocity omega (rad/s) about its center, which moves with it: a point p0 of
 * the wall at t = 0 is at center + v t + R(q) (p0 - center), q the rotation by omega t, which this
 * returns (w, x, y, z). The engine places its walls with it, and the result file's per-frame wall
 * vertices come from it.
 */
void pd_wall_rotation(const double omega[3], double t, double q[4]);

/* ---- overlap of two polyhedra (kernels/overlap.h, thesis sections 4.2, 5.2, 5.3) ------------- */

enum {
    PD_OVERLAP_SINGLE = 1,    /* compute in single precision */
    PD_OVERLAP_NO_FILTER = 2, /* skip the half-plane triangle filter (eqs. 5.3-5.5) */
    PD_OVERLAP_PLACES = 8,    /* separate places (thesis 5.4); pd_overlap_host/_cl set it */
};

/* One contact between A and B, in world coordinates. */
typedef struct pd_contact {
    int hit;            /* 1 when the solids overlap with positive volume */
    double volume;      /* overlap volume V, m^3 */
    double centroid[3]; /* centre of mass of the overlap (contact point), m */
    double normal[3];   /* unit normal from A into B (eq. 4.19) */
    double depth;       /* extent of the overlap along normal, m */
    int degenerate;     /* 1 when a coplanar or touching configuration was resolved */
    int tris_a, tris_b; /* triangles that survived the filter */
    /*
     * The overlap's separate places (thesis section 5.4: connected parts of the overlap), and the
     * volume (m^3) and depth (m) that make eqs. 4.16-4.18 the sum of each place's own force and
     * stiffnesses; equal to volume and depth for one place. What "contact_places": "separate"
     * gives the force law (docs/SCENARIO.md).
     */
    int places;
    /* 0 where places is 1 only because the places could not be told apart: more nodes than the
     * kernel's scratch holds (256 + half the triangles), or a degenerate pair whose nodes came from
     * its second pass; the effective values are then the whole overlap's */
    int places_known;
    double effective_volume, effective_depth;
    double effective_point[3]; /* where the places' summed force acts (force-weighted), m */
} pd_contact;

/* Overlap of A at pose pa with B at pose pb, computed on the host by the kernel's own code. */
int pd_overlap_host(const pd_mesh *a, const pd_pose *pa, const pd_mesh *b, const pd_pose *pb,
                    int flags, pd_contact *out, pd_error *err);

/* ---- scenarios (engine/scenario*.c; contract: schemas/scenario.schema.json) -------------------
 */

typedef struct pd_scenario pd_scenario;

/* One problem in a scenario: where (a JSON pointer, e.g. "/particles/0/size/std") and what. */
typedef struct pd_diag {
    char path[640]; /* a JSON pointer: names of up to 63 UTF-8 characters, escaped */
    char msg[352];
} pd_diag;

/* Every problem found in a scenario, in document order. */
typedef struct pd_diags {
    int n, cap;
    pd_diag *items;
} pd_diags;

void pd_diags_free(pd_diags *d);

/*
 * Parses and validates a scenario given as JSON text; relative mesh paths resolve against
 * base_dir (NULL: the current directory). On PD_EINVAL diags lists every problem (err holds the
 * first); other codes are I/O or memory failures in err. *out is NULL unless PD_OK.
 */
int pd_scenario_parse(const char *json_text, const char *base_dir, pd_scenario **out,
                      pd_diags *diags, pd_error *err);

/* Reads a scenario file and parses it; meshes resolve against the file's directory. */
int pd_scenario_load(const char *path, pd_scenario **out, pd_diags *diags, pd_error *err);

void pd_scenario_destroy(pd_scenario *s);

/* What a scenario amounts to, for `polydem validate` and POST /v1/scenarios/validate. */
typedef struct pd_scenario_summary {
    long particles;
    int shapes, materials, walls;
    double dt, duration; /* s */
    long steps;
    double dt_rayleigh;  /* Rayleigh time step of the smallest particle, s */
    double dt_hertz;     /* shortest Hertz contact time at the scenario's speeds, s */
    double dt_stable;    /* min(0.3 dt_rayleigh, dt_hertz / 20), s */
    double memory_bytes; /* device memory estimate, bytes */
    /* Polyhedral contacts resolve lengths to 64 ulps of the largest coordinate in play (a pair of
     * the largest particles, or a wall about its centroid): this many metres at the scenario's
     * precision; 0 without polyhedra. Contact depths below it are not resolved. */
    double contact_resolution;
    long frames; /* frames the result holds: t = 0, every output_interval, and the end */
    /* Every particle's mesh in world coordinates at every frame (/xdmf/vertices), which lets
     * ParaView show the particles' shapes: the bytes it adds to the result file, and whether a run
     * writes it unless told (pd_run_options.shape_meshes = 0): when some particle is a polyhedron
     * and it adds at most PD_MESH_VIEW_AUTO_BYTES. */
    double mesh_view_bytes;
    int mesh_view_default;
} pd_scenario_summary;

/* The most bytes of per-frame particle meshes a run writes without being asked (256 MiB). */
#define PD_MESH_VIEW_AUTO_BYTES (256.0 * 1048576.0)

void pd_scenario_summarize(const pd_scenario *s, pd_scenario_summary *out);

/* ---- OpenCL devices (engine/cl_device.c) ---------------------------------------------------- */

typedef struct pd_device pd_device;

/* One OpenCL device as pd_device_list reports it. */
typedef struct pd_device_info {
    int index; /* the N of --device N: devices of all platforms, in order */
    char name[128];
    char platform[128];
    char type[8]; /* "GPU", "CPU" or "other" */
    int compute_units;
    double global_mem_bytes;
    int fp64;
    /* single-precision / and sqrt rounded as on the host (CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT;
     * programs are then built so): its single-precision overlaps are the host's to the bit */
    int fp32_rounded;
} pd_device_info;

/* Lists up to max devices into out; *n receives how many exist. */
int pd_device_list(pd_device_info *out, int max, int *n, pd_error *err);

/*
 * Opens OpenCL device `index` over all platforms (-1: first GPU, else first device). A device is
 * used by one thread at a time: its kernels' arguments and the overlap's scratch buffers are its
 * own (the daemon's worker thread holds its device).
 */
int pd_device_open(int index, pd_device **out, pd_error *err);
void pd_device_close(pd_device *dev);
const char *pd_device_name(const pd_device *dev);
int pd_device_has_fp64(const pd_device *dev);
/* whether its single-precision / and sqrt are the host's (pd_device_info.fp32_rounded) */
int pd_device_fp32_rounded(const pd_device *dev);
/*
 * What fills dev: *work_items, the work-items the engine's contact stage launches on it (256 per
 * compute unit), and *scratch_bytes, what per-work-item scratch may take of a GPU (a quarter of
 * its memory, at most its largest allocation), bytes. A CPU device shares the host's memory, so
 * its callers keep bounds of their own (the contact stage 128 MiB, bench/overlap 256 MiB).
 */
void pd_device_capacity(const pd_device *dev, int *work_items, double *scratch_bytes);
int pd_device_is_gpu(const pd_device *dev);

/*
 * Compiles every embedded OpenCL program for dev, in single precision and, where the device has
 * cl_khr_fp64, in double: a self-test that the shared kernel headers build as OpenCL C there.
 * The error names the program and precision and quotes the build log.
 */
int pd_device_compile_all(pd_device *dev, pd_error *err);

/*
 * Volumetric Hertz normal forces (thesis eq. 4.16) for n contacts on dev: in holds 6 doubles per
 * contact (V m^3, delta m, E* Pa, m* kg, gamma, vn m/s), out receives 2 (F_n N, k_n N/m).
 */
int pd_forces_cl(pd_device *dev, const double *in, int n, int dbl, double *out, pd_error *err);

/* The same overlap as pd_overlap_host, run by the OpenCL kernel on dev. */
int pd_overlap_cl(pd_device *dev, const pd_mesh *a, const pd_pose *pa, const pd_mesh *b,
                  const pd_pose *pb, int flags, pd_contact *out, pd_error *err);

/* ---- running a scenario (engine/sim*.c) ----------------------------------------------------- */

/* Where a run stands; passed to the progress callback and returned at the end. */
typedef struct pd_progress {
    long long step, steps_total;
    double sim_time;         /* s */
    double sim_duration;     /* s */
    double fraction;         /* step / steps_total */
    double steps_per_second; /* wall-clock rate over the recent past */
    double eta_seconds;      /* wall-clock seconds left at that rate (-1 while unknown) */
    long particles;
    long contacts;         /* contacts with positive overlap at the last stats step */
    long broad_pairs;      /* candidate pairs of the broad phase at the last stats step */
    double kinetic_energy; /* J, translational + rotational, at the last stats step */
    double wall_seconds;   /* since the run started */
    long long frames;      /* output frames written so far */
    /* At the end of a run that stopped early (cancelled, diverged, a device error): 1 when its
     * frames so far were kept in the output file, whose root attribute status then says why
     * ("cancelled", "diverged" or "failed"); 0 when there was nothing to keep, or when writing
     * the result failed (a full disk): what was written is then at best in "<output>.partial",
     * and the error says so. */
    int result_kept;
} pd_progress;

/*
 * Called from the running thread about every progress_interval wall seconds and once at the end.
 * Return non-zero to cancel the run (as the cancel flag does).
 */
typedef int (*pd_progress_fn)(const pd_progress *p, void *user);

typedef struct pd_run_options {
    const char *output_path;  /* HDF5 result; written as "<path>.partial", renamed when done,
                                 with "<path>.xmf" beside it. Required. */
    pd_progress_fn progress;  /* may be NULL */
    void *user;               /* passed to progress */
    double progress_interval; /* wall seconds between callbacks; <= 0 means 0.5 */
    /* Set non-zero from any thread to stop the run at the end of the current step; pd_run then
     * returns PD_ECANCELLED and keeps the frames written so far (pd_progress.result_kept). May
     * be NULL. */
    volatile int *cancel;
    /* Every particle's world-space mesh per frame for ParaView: > 0 always, < 0 never, 0 as
     * pd_scenario_summary.mesh_view_default says (polyhedra present and at most
     * PD_MESH_VIEW_AUTO_BYTES). */
    int shape_meshes;
} pd_run_options;

/*
 * Runs scenario s on dev to its duration, writing the result file. Returns PD_OK, PD_ECANCELLED,
 * PD_EDIVERGED (NaN or runaway energy: the message names the step and particle), PD_EINVAL (a
 * scenario the device cannot run, e.g. double precision without cl_khr_fp64, or dt above the
 * stable estimate without allow_unstable_dt), PD_EIO, PD_ENOMEM or PD_ECL. final (may be NULL)
 * receives the last progress record whatever the outcome. A run that stops after its first frame
 * keeps the frames so far in output_path, marked by the root attribute status (final's
 * result_kept); before that, no file is left. A run whose result write fails (PD_EIO: a full
 * disk) keeps its whole frames and stats rows so far in "<output_path>.partial" when they read
 * back whole, and its error ends "; the N frames up to t = T s are kept in '<output_path>.partial'
 * (incomplete, so not renamed)", else "; result discarded: <why>". A device runs one scenario at a
 * time.
 */
int pd_run(pd_device *dev, const pd_scenario *s, const pd_run_options *opt, pd_progress *final,
           pd_error *err);

/* The result file's root attribute status for pd_run's return code: "complete" (PD_OK),
 * "cancelled", "diverged", or "failed" (any other error). */
const char *pd_run_status(int rc);

/* The scenario's name and its JSON text as submitted. */
const char *pd_scenario_name(const pd_scenario *s);
const char *pd_scenario_json(const pd_scenario *s);

/*
 * Device self-test (seed 004 section 5.3.3): builds every program, runs the overlap kernel on a
 * few poses of non-convex shapes against the host build, and runs a short two-sphere Hertz
 * collision scenario on the device against the analytic contact time and peak overlap.
 * report (may be NULL) receives a one-line human-readable summary. PD_OK when the device passed.
 */
int pd_device_selftest(pd_device *dev, char *report, size_t report_len, pd_error *err);

#ifdef __cplusplus
}
#endif

#endif /* POLYDEM_H */
