/*
 * mesh_internal.h - helpers shared by mesh.c, mesh_io.c and mesh_builtin.c (and the mesh unit
 * test). Not part of the public API: the CLI and the daemon use polydem.h only.
 */
#ifndef PD_MESH_INTERNAL_H
#define PD_MESH_INTERNAL_H

#include "polydem.h"

/* Largest triangle count any loader or generator accepts: bigger inputs are rejected with a
 * message rather than risking allocations of many gigabytes. */
#define MESH_MAX_TRIS 10000000

/*
 * Coordinates are metres, and a mesh must lie within MESH_MAX_COORD of the origin and span at
 * least MESH_MIN_SPAN (its bounding box's diagonal). Far beyond any granular material, both
 * keep every number the engine forms finite and normal: the inertia tensor is a sum of fifth
 * powers of coordinates (a cube of side 1e62 m gave an infinite and NaN tensor, one of 1e80 m
 * overlapped its own translate by nothing), and a mesh of 1e-100 m was refused for a "zero
 * area" triangle when its products underflowed.
 */
#define MESH_MAX_COORD 1e12
#define MESH_MIN_SPAN 1e-12

/*
 * Welds exactly equal vertices, drops unreferenced ones, validates (closed, edge-manifold,
 * consistently oriented, no zero-area triangles, positive volume, shells nested sensibly, no two
 * triangles crossing), flips an inward-oriented mesh or shell and wraps the result in a pd_mesh.
 * Takes ownership of verts and tris (malloc'd) whatever the outcome. label prefixes every error
 * message.
 */
int mesh_finish(double *verts, int nverts, int *tris, int ntris, const char *label, pd_mesh **out,
                pd_error *err);

/* Parts closer than this (m) touch rather than cross: MESH_TOUCH_TOL times the larger of the
 * bounding box's diagonal and the largest coordinate's magnitude (mesh_cross.c says why). */
#define MESH_TOUCH_TOL 1e-6
double mesh_touch_eps(const double *verts, int nverts);

/*
 * Refuses (PD_EMESH) a mesh two of whose triangles cross: an edge of one passes through the
 * other, or they overlap in one plane facing the same way, or a touch the surface goes on
 * through; touching (stacked solids, a corner on a face) is accepted. Call on a closed,
 * oriented mesh: nb[3 t + k] is the triangle across edge k of t (corners k to k + 1), shell[t]
 * its closed shell (for the message). About O(n log n) (mesh_cross.c).
 */
int mesh_check_crossings(const double *verts, int nverts, const int *tris, int ntris, const int *nb,
                         const int *shell, const char *label, pd_error *err);

/* Signed volume enclosed by the triangles (positive when outward oriented). */
double mesh_signed_volume(const double *verts, int nverts, const int *tris, int ntris);

/*
 * Convex hull of n points (incremental, O(n^2)): on success *tris_out holds *ntris_out outward
 * counter-clockwise triangles indexing pts (malloc'd; interior points are left out). Returns
 * PD_OK, PD_ENOMEM, or PD_EMESH when the points are (nearly) coplanar or the hull fails.
 */
int mesh_convex_hull(const double *pts, int n, int **tris_out, int *ntris_out);

/* Eigenvalues w and unit eigenvectors (columns of v) of the symmetric 3x3 in (Jacobi). */
void mesh_sym3_eigen(const double in[3][3], double w[3], double v[3][3]);

#endif
