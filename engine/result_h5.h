/*
 * result_h5.h - the HDF5 result file of a run, and the XDMF file beside it for ParaView.
 * Engine-internal: the simulation driver writes results through this; the CLI and the daemon only
 * read the files.
 *
 * The file layout is a contract other tools read (format="polydem-result", format_version=1):
 *
 *   /               attrs format, format_version (int), scenario (JSON text), precision
 *                   ("single"|"double": what the run computed in; data are always stored as
 *                   double), dt (double, s), status ("complete"; "cancelled", "diverged" or
 *                   "failed" when the run stopped early and its frames so far were kept, with
 *                   status_message saying why; a file without status predates it: complete)
 *   /shapes/<name>/ vertices (nv,3) double [1], triangles (nt,3) int32; attrs volume (double,
 *                   [1]), kind ("mesh"|"sphere"), index (int, position in the shapes' order)
 *   /particles/     shape (N) int32, material (N) int32, size (N) double [m], mass (N) double
 *                   [kg]; the string list attribute "names" (the shape names in index order) is
 *                   on both /particles/shape and /shapes
 *   /frames/        time (F) [s], step (F) int64, position (F,N,3) [m], orientation (F,N,4) [1]
 *                   (w,x,y,z), velocity (F,N,3) [m/s], angular_velocity (F,N,3) [rad/s]
 *   /stats/         time (S) [s], step (S) int64, kinetic_energy (S) [J], contacts (S) int64,
 *                   broad_pairs (S) int64, max_overlap_ratio (S) [1], wall_time (S) [s]
 *                   (wall-clock time since the run started, when the row was written; the
 *                   differences between rows time the steps between them), wall_force/<wall>
 *                   (S,3) [N], stage_time/<stage> (S) [s] for the stages integrate, bvh
 *                   (building the particles' tree), traverse (the pair list), contacts (narrow
 *                   phase, overlaps and contact forces) and gather (forces per particle): the
 *                   wall time each took in the one step that ended at the row (the first row:
 *                   the initial force evaluation), timed with the device finishing after every
 *                   stage, so they sum to a little more than an unsynchronised step
 *   /walls/<name>/  vertices (nv,3) [m] at t=0, triangles (nt,3) int32, and its motion:
 *                   velocity (3) [m/s], angular_velocity (3) [rad/s], center (3) [m] at t=0
 *                   (pd_wall_rotation: zeros for a fixed wall); a wall that moves also has
 *                   frame_vertices (F,nv,3) [m], its vertices at each frame's time
 *   /xdmf/          additions for the XDMF file: particle_id (N) int32 = 0..N-1 (the Polyvertex
 *                   connectivity); with walls, wall_size (V) zeros [m], V the most vertices of a
 *                   wall (the walls' "size" in the XDMF file, so a Glyph by size skips them); with
 * RH5_SHAPE_MESHES also vertices (F,V,3) [m], every particle's mesh in world coordinates per frame,
 * triangles (T,3) int32 into those V vertices, and particle (T) int32, the particle of each
 * triangle
 *
 * Shape vertices are for size 1: a particle's body-frame mesh is its shape's vertices times its
 * size (m), so shape vertices and volumes are dimensionless ("1"). Every dataset has a "units"
 * string attribute ("" for indices, "1" for counts and other dimensionless values). Strings are
 * variable-length UTF-8 (a C reader reads them with a UTF-8 memory type, H5Aget_type's copy: HDF5
 * converts no ASCII to UTF-8). The /frames and /stats datasets are chunked, extendible along their
 * first axis, and the file is flushed after every frame and every stats row.
 *
 * Lifecycle: rh5_create -> rh5_add_shape / rh5_add_wall (any number, any order) ->
 * rh5_set_particles (once; ends the setup, creates /frames and /stats) -> rh5_write_frame /
 * rh5_write_stats (any number, interleaved) -> rh5_close (success), rh5_finish (a run stopped
 * early whose frames are kept, marked by the root attribute status) or rh5_abort (nothing worth
 * keeping). The file is written as "<path>.partial" and renamed to path by rh5_close or
 * rh5_finish, so a half-written file is never mistaken for a result; both also write
 * "<path>.xmf".
 *
 * After a failed write (a full disk, mostly) the writer refuses further writes, and rh5_close or
 * rh5_finish keep what was written when they can: every /frames and /stats dataset is cut back to
 * its last whole row (a frame whose position was written but not its velocity, or half a stats
 * row, is dropped: no reader sees datasets of unequal length or rows of fill values), the file is
 * read back to check it, and left as "<path>.partial", not renamed: it is no complete result (no
 * status attribute, no XDMF file). A file that fails the check is removed. Either way the error
 * restates the failure and says which ("...; the 36 frames up to t = 0.0144 s are kept in
 * 'out.h5.partial' (incomplete, so not renamed)" or "...; result discarded: <why>").
 *
 * A writer is used from one thread at a time; different writers may live in different threads
 * (Debian's HDF5 is built thread-safe and serialises its calls).
 */
#ifndef RESULT_H5_H
#define RESULT_H5_H

#include "polydem.h"

/* Optional contents chosen at rh5_create (position and orientation are always written). */
enum {
    RH5_VELOCITY = 1,         /* /frames/velocity */
    RH5_ANGULAR_VELOCITY = 2, /* /frames/angular_velocity */
    RH5_SHAPE_MESHES = 4,     /* /xdmf/vertices etc.: world-space meshes, shown by the XDMF file */
};

#define RH5_FORMAT "polydem-result"
#define RH5_FORMAT_VERSION 1

typedef struct rh5_writer rh5_writer;

/*
 * Creates "<path>.partial" (replacing a stale one) and writes the root attributes. fields is a
 * mask of RH5_* flags. scenario_json is stored verbatim. Silences HDF5's own error printing for
 * the calling thread; failures are reported through err, naming the file and the object.
 */
int rh5_create(const char *path, const char *scenario_json, int double_precision, double dt,
               int fields, rh5_writer **out, pd_error *err);

/*
 * Adds /shapes/<name>: verts (3*nv, body frame, size 1), tris (3*nt, indices into verts), the
 * volume at size 1, kind "mesh" or "sphere" (a sphere's vertices are its display tessellation).
 * Shapes are indexed in the order they are added. Names must be unique and contain no '/'.
 */
int rh5_add_shape(rh5_writer *w, const char *name, const char *kind, const double *verts, int nv,
                  const int *tris, int nt, double volume, pd_error *err);

/*
 * Adds /walls/<name> (vertices at t=0, m); its force is the stats column wall_force/<name>.
 * motion: velocity (m/s), angular_velocity (rad/s) and center (m) at t = 0, 9 values, or NULL for
 * a fixed wall. A wall that moves gets its vertices at every frame's time (frame_vertices).
 */
int rh5_add_wall(rh5_writer *w, const char *name, const double *verts, int nv, const int *tris,
                 int nt, const double *motion, pd_error *err);

/*
 * Writes /particles (n >= 1 particles; shape[i] indexes the shapes in add order) and creates the
 * empty /frames and /stats datasets. Call once, after every rh5_add_shape and rh5_add_wall.
 */
int rh5_set_particles(rh5_writer *w, int n, const int *shape, const int *material,
                      const double *size, const double *mass, pd_error *err);

/*
 * Appends one frame of the n particles: pos (3n, m), quat (4n, w,x,y,z), vel (3n, m/s) and
 * angvel (3n, rad/s). vel and angvel are required when their field was chosen at rh5_create and
 * ignored (may be NULL) otherwise. Flushes the file.
 */
int rh5_write_frame(rh5_writer *w, double time, long long step, const double *pos,
                    const double *quat, const double *vel, const double *angvel, pd_error *err);

/* The stages of a step timed in /stats/stage_time: integrate, bvh, traverse, contacts, gather. */
#define RH5_NSTAGES 5

/* Appends one stats row; wall_time is the wall-clock time (s) since the run started; wall_forces
 * holds 3 values (N) per wall in add order (NULL when there are no walls); stage_time holds
 * RH5_NSTAGES wall times (s) of the step that ends at this row. Flushes the file. */
int rh5_write_stats(rh5_writer *w, double time, long long step, double kinetic_energy,
                    long long contacts, long long broad_pairs, double max_overlap_ratio,
                    double wall_time, const double *wall_forces, const double *stage_time,
                    pd_error *err);

/*
 * Closes the file, writes "<path>.xmf" (through a temporary name), renames "<path>.partial" to
 * path, and frees the writer. On failure the partial file is removed, except where a write failed
 * (rh5_broken, or the status attribute did not fit): the frames so far are then kept in it when
 * they read back whole (above), and the error says so. The writer is freed whatever the outcome;
 * w may not be used afterwards. The root attribute status is "complete".
 */
int rh5_close(rh5_writer *w, pd_error *err);

/*
 * rh5_close for a run that stopped before its end (cancelled, diverged, or failed on the device)
 * but whose frames so far are sound: the root attributes status (e.g. "cancelled") and, when
 * message is not NULL, status_message (why it stopped) tell a reader that the frames end early.
 * After a failed write neither is written (the error restates that failure instead).
 */
int rh5_finish(rh5_writer *w, const char *status, const char *message, pd_error *err);

/* Frames written so far (0 for NULL). */
long long rh5_frames(const rh5_writer *w);

/* 1 when a write failed and the writer refuses further writes (0 for NULL). */
int rh5_broken(const rh5_writer *w);

/* Closes and removes the partial file and frees the writer (failed or cancelled jobs). Accepts
 * NULL. */
void rh5_abort(rh5_writer *w);

/* ---- the XDMF file (engine/result_xdmf.c) ------------------------------------------------- */

/* A wall as the XDMF file shows it: /walls/<name>/triangles on its vertices (frame_vertices
 * frame k when it moves). */
typedef struct rh5_xdmf_wall {
    const char *name;
    int nv, nt, moving;
} rh5_xdmf_wall;

/* What the XDMF file describes: the datasets of a closed result file. */
typedef struct rh5_xdmf {
    const char *h5_name;  /* base name of the .h5 file, how every DataItem refers to it */
    const char *label;    /* names the result in error messages */
    int n;                /* particles */
    int fields;           /* RH5_* mask chosen at rh5_create */
    long long nframes;    /* frames written */
    const double *times;  /* nframes frame times, s */
    int mesh_nv, mesh_nt; /* /xdmf/vertices and /xdmf/triangles sizes; 0 when not stored */
    int nwalls;
    const rh5_xdmf_wall *walls;
    int wall_size; /* length of /xdmf/wall_size (zeros: the walls' "size" attribute) */
} rh5_xdmf;

/*
 * Writes xpath: a temporal collection with one grid per frame. Each frame's particles are a
 * Polyvertex grid (explicit connectivity /xdmf/particle_id) with geometry frame k of
 * /frames/position and point attributes orientation, velocity and angular_velocity (where
 * written), particle_id, shape, material, size and mass. With shape meshes or walls, each frame
 * is a spatial collection of that grid, a Triangle grid "shapes" of /xdmf/vertices frame k with
 * the cell attribute particle_id, and a Triangle grid per wall, named after it, where it is at
 * that frame, with a point attribute size of zeros (/xdmf/wall_size). Frames are selected with Xdmf
 * 3's "file:dataset|start:stride:count: dataspace" syntax: read by ParaView's Xdmf3 readers, not by
 * the legacy "XDMF Reader".
 */
int rh5_write_xdmf(const char *xpath, const rh5_xdmf *x, pd_error *err);

#endif
