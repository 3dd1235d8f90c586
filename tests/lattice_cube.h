/*
 * lattice_cube.h - test helper: the engine's cube as examples/cube_lattice.json's particles hold
 * it (builtin:cube at a volume-equivalent diameter of 1 m, its vertex order and triangles), the
 * single-precision resolution and face area of two of them stacked at size 0.02 m, and the angle
 * between two unit vectors, for the tests that compare single precision's contacts of that
 * lattice with double's (tests/physics/test_overlap.c, test_single_narrow.c).
 */
#ifndef PD_TEST_LATTICE_CUBE_H
#define PD_TEST_LATTICE_CUBE_H

#include <math.h>
#include <stdio.h>

#include "polydem.h"

/* Half side of the cube at size 1, the lattice's size (m), and its half side there (m). */
#define LATTICE_UNIT_H 0.40299798850411739
#define LATTICE_SIZE 0.02
#define LATTICE_H (LATTICE_UNIT_H * LATTICE_SIZE)
/* Single precision's resolution between two of them stacked (64 ulps of the largest coordinate
 * in A's frame, B's far corners at ~0.0161 m + sqrt(3) h), and the area of a face. */
#define LATTICE_RES (64 * 1.1920929e-7 * (0.0161 + sqrt(3) * LATTICE_H))
#define LATTICE_AREA (4 * LATTICE_H * LATTICE_H)

static const int lattice_cube_tris[36] = {0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4,
                                          2, 6, 7, 2, 7, 3, 0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5};

/* The cube at `size` (m), corner i at (+-h, +-h, +-h) by the bits of i; NULL (said) on failure. */
static inline pd_mesh *lattice_cube_mesh(double size)
{
    const double h = LATTICE_UNIT_H * size;
    double v[24];
    for (int i = 0; i < 8; i++)
        for (int k = 0; k < 3; k++)
            v[3 * i + k] = (i >> k) & 1 ? h : -h;
    pd_mesh *m = NULL;
    pd_error err = {0};
    if (pd_mesh_from_arrays(v, 8, lattice_cube_tris, 12, "cube", &m, &err) != PD_OK)
        printf("  lattice cube: %s\n", err.msg);
    return m;
}

/* The angle between unit vectors u and v (rad), from both products: exact near 0 as well. */
static inline double angle_between(const double *u, const double *v)
{
    double cx = u[1] * v[2] - u[2] * v[1], cy = u[2] * v[0] - u[0] * v[2],
           cz = u[0] * v[1] - u[1] * v[0];
    return atan2(sqrt(cx * cx + cy * cy + cz * cz), u[0] * v[0] + u[1] * v[1] + u[2] * v[2]);
}

#endif
