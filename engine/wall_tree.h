/*
 * wall_tree.h - building a wall's static triangle BVH on the host (engine-internal), in the
 * layout the kernels search (kernels/wall_bvh.h), and bounding how many of its triangles one
 * particle can meet, which sizes the narrow phase's scratch.
 */
#ifndef PD_WALL_TREE_H
#define PD_WALL_TREE_H

#include "polydem.h"

typedef struct wall_tree {
    int nnode;
    double *box; /* 6 per node: lo xyz, hi xyz */
    int *kid;    /* 2 per node: children, or (-1 - first, count) for a leaf */
    int *order;  /* the triangles in leaf order */
} wall_tree;

/*
 * Builds the tree over nt triangles (tri, 3 vertex indices each) of vertices vert (xyz): median
 * splits along the longest axis of the triangles' centroids down to leaves of WB_LEAF. Returns
 * PD_OK or PD_ENOMEM (err names `what`, e.g. the wall). Free with wall_tree_free.
 */
int wall_tree_build(const double *vert, const int *tri, int nt, wall_tree *t, const char *what,
                    pd_error *err);
void wall_tree_free(wall_tree *t);

/*
 * An upper bound on the number of triangles whose boxes meet any axis-aligned cube of side
 * `side` (m): such a cube lies within 2 x 2 x 2 cells of a grid of that spacing, so the largest
 * sum of eight neighbouring cells' counts (triangles whose boxes meet the cell) bounds it, at
 * most nt. Falls back to nt when counting would take more than 128 MB (a wall far larger than
 * the cube with few, huge triangles). Returns -1 when out of memory.
 */
int wall_tree_max_near(const wall_tree *t, const double *vert, const int *tri, int nt, double side);

/* The first of n points (xyz, taken relative to origin: the tree's frame) inside the closed mesh
 * the tree was built on (vert, tri), by the kernels' own ray parity (cp_inside_tree); -1 when
 * none is. */
long wall_tree_first_inside(const wall_tree *t, const double *vert, const int *tri,
                            const double *pts, long n, const double origin[3]);

#endif
