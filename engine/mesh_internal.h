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
 * Welds exactly equal vertices, drops unreferenced ones, validates (closed, edge-manifold,
 * consistently oriented, no zero-area triangles, positive volume), flips an inward-oriented mesh
 * and wraps the result in a pd_mesh. Takes ownership of verts and tris (malloc'd) whatever the
 * outcome. label prefixes every error message.
 */
int mesh_finish(double *verts, int nverts, int *tris, int ntris, const char *label, pd_mesh **out,
                pd_error *err);

/* Signed volume enclosed by the triangles (positive when outward oriented). */
double mesh_signed_volume(const double *verts, int nverts, const int *tris, int ntris);

/*
 * Convex hull of n points (incremental, O(n^2)): on success *tris_out holds *ntris_out outward
 * counter-clockwise triangles indexing pts (malloc'd; interior points are left out). Returns
 * PD_OK, PD_ENOMEM, or PD_EMESH when the points are (nearly) coplanar or the hull fails.
 */
int mesh_convex_hull(const double *pts, int n, int **tris_out, int *ntris_out);

#endif
