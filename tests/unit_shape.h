/*
 * unit_shape.h - test helper: a built-in shape as scenarios store it, in its body frame scaled
 * to a volume-equivalent diameter of 1 m (a particle's size then scales it).
 */
#ifndef PD_TEST_UNIT_SHAPE_H
#define PD_TEST_UNIT_SHAPE_H

#include <math.h>

#include "polydem.h"

static inline pd_mesh *unit_shape(const char *name, int tris)
{
    pd_mesh *m = NULL;
    pd_error err = {0};
    if (pd_mesh_builtin(name, tris, 1, &m, &err) != PD_OK) return NULL;
    pd_mass_props mp;
    double rot[3][3];
    pd_mesh_to_body_frame(m, &mp, rot);
    double k = cbrt(3.14159265358979323846 / 6 / mp.volume);
    for (int i = 0; i < 3 * m->nverts; i++)
        m->verts[i] *= k;
    return m;
}

#endif
