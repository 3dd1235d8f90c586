/*
 * u_shape.h - test helper: a U-shaped solid, the simplest non-convex particle that touches a flat
 * surface in two separate places (thesis section 5.4; OVL_PLACES in kernels/overlap.h).
 *
 * An 8-cornered U in the x-z plane, prongs pointing down (-z) with their tips on z = 0, extruded
 * along y by U_LY (m, at size 1 of the mesh as written):
 *
 *     z = 2  +-----------+
 *            |           |
 *     z = 1  |   +---+   |
 *            |   |   |   |
 *     z = 0  +---+   +---+
 *            0   1   2   3  x
 *
 * Volume 5 U_LY, centroid (1.5, U_LY / 2, 1.1), each prong tip a 1 x U_LY rectangle. U_LY = 2.5
 * makes the mesh's own axes its principal axes in ascending order (moments 10.55, 15.08, 17.55
 * per unit density), so the body frame is the mesh shifted to its centroid, unrotated.
 */
#ifndef PD_TEST_U_SHAPE_H
#define PD_TEST_U_SHAPE_H

#include <stdio.h>

#include "polydem.h"

#define U_LY 2.5
#define U_NV 16
#define U_NT 28
#define U_VOLUME (5 * U_LY)
#define U_CENTROID_Z 1.1

/* The U's vertices (U_NV x 3) and outward counter-clockwise triangles (U_NT x 3). */
static inline void u_shape_arrays(double *v, int *t)
{
    static const double poly[8][2] = {{0, 2}, {3, 2}, {3, 0}, {2, 0},
                                      {2, 1}, {1, 1}, {1, 0}, {0, 0}};
    static const int cap[6][3] = {{0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {0, 4, 5}, {0, 5, 7}, {5, 6, 7}};
    for (int i = 0; i < 8; i++)
        for (int s = 0; s < 2; s++) {
            double *p = v + 3 * (i + 8 * s);
            p[0] = poly[i][0];
            p[1] = s * U_LY;
            p[2] = poly[i][1];
        }
    int n = 0;
    for (int k = 0; k < 6; k++) { /* y = 0 and y = U_LY caps */
        int *a = t + 3 * n++, *b = t + 3 * n++;
        a[0] = cap[k][0];
        a[1] = cap[k][2];
        a[2] = cap[k][1];
        b[0] = cap[k][0] + 8;
        b[1] = cap[k][1] + 8;
        b[2] = cap[k][2] + 8;
    }
    for (int i = 0; i < 8; i++) { /* the sides, one quad per polygon edge */
        int j = (i + 1) % 8, *a = t + 3 * n++, *b = t + 3 * n++;
        a[0] = i;
        a[1] = j + 8;
        a[2] = i + 8;
        b[0] = i;
        b[1] = j;
        b[2] = j + 8;
    }
}

/* The U as a mesh (orientation fixed by the loader if need be); NULL on failure. */
static inline pd_mesh *u_shape_mesh(void)
{
    double v[3 * U_NV];
    int t[3 * U_NT];
    u_shape_arrays(v, t);
    pd_mesh *m = NULL;
    pd_error err = {0};
    if (pd_mesh_from_arrays(v, U_NV, t, U_NT, "u", &m, &err) != PD_OK) {
        printf("  u shape: %s\n", err.msg);
        return NULL;
    }
    return m;
}

/* The U as a scenario shape: {"vertices": [...], "triangles": [...]}. */
static inline void u_shape_json(char *out, size_t len)
{
    double v[3 * U_NV];
    int t[3 * U_NT];
    u_shape_arrays(v, t);
    size_t n = (size_t)snprintf(out, len, "{\"vertices\": [");
    for (int i = 0; i < U_NV && n < len; i++)
        n += (size_t)snprintf(out + n, len - n, "%s[%g, %g, %g]", i ? ", " : "", v[3 * i],
                              v[3 * i + 1], v[3 * i + 2]);
    if (n < len) n += (size_t)snprintf(out + n, len - n, "], \"triangles\": [");
    for (int i = 0; i < U_NT && n < len; i++)
        n += (size_t)snprintf(out + n, len - n, "%s[%d, %d, %d]", i ? ", " : "", t[3 * i],
                              t[3 * i + 1], t[3 * i + 2]);
    if (n < len) snprintf(out + n, len - n, "]}");
}

#endif
