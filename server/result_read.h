/*
 * result_read.h - reads a finished job's HDF5 result (layout: engine/result_h5.h) into JSON for
 * the dashboard's plots and viewer. Read-only; the file must be closed by its writer (a
 * succeeded job's file, renamed from .partial). Each call returns NULL with a message on failure.
 */
#ifndef RESULT_READ_H
#define RESULT_READ_H

#include <jansson.h>
#include <stddef.h>

/* {"partial": false, "time", "step", "kinetic_energy", "contacts", "broad_pairs",
 *  "max_overlap_ratio", "wall_time" and "stage_time": {"<stage>": [...]} (when the file has them),
 *  "wall_force": {"<wall>": [[Fx, Fy, Fz], ...]}, "units": {...}} */
json_t *result_stats(const char *path, char *msg, size_t msglen);

/* {"count": F, "time": [...]} */
json_t *result_frames(const char *path, char *msg, size_t msglen);

/* {"frame": k, "count": F, "time", "step", "position": [[x, y, z], ...], "orientation":
 * [[w, x, y, z], ...]}; k < 0 counts from the end. *range set when k is out of range. */
json_t *result_frame(const char *path, long long k, int *range, char *msg, size_t msglen);

/* {"shapes": [{"name", "kind", "volume", "vertices", "triangles"}], "particles": {"shape",
 *  "size"}, "walls": [{"name", "vertices", "triangles"}]}: the viewer's geometry (shape vertices
 *  for size 1 in the body frame, wall vertices in metres at time 0) */
json_t *result_shapes(const char *path, char *msg, size_t msglen);

#endif
