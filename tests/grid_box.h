/*
 * grid_box.h - test helper: a closed box mesh whose six faces are n x n grids of squares (two
 * triangles each), outward counter-clockwise: the finely meshed flat wall that wall contacts are
 * tested on. Vertices along shared edges are computed by the same expression on both faces, so
 * they coincide exactly and weld.
 */
#ifndef PD_TEST_GRID_BOX_H
#define PD_TEST_GRID_BOX_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The box [c - h, c + h]: fills *v (3 per vertex, 6 (n+1)^2 of them, with duplicates on the
 * edges) and *t (12 n^2 triangles); free both. */
static inline void grid_box_arrays(const double c[3], const double h[3], int n, double **v_out,
                                   int **t_out, int *nv_out, int *nt_out)
{
    int nf = 6 * (n + 1) * (n + 1), nt = 12 * n * n;
    double *v = malloc(sizeof(double) * 3 * nf);
    int *t = malloc(sizeof(int) * 3 * nt), nv = 0, k = 0;
    for (int axis = 0; axis < 3; axis++)
        for (int side = -1; side <= 1; side += 2) {
            int u = (axis + 1) % 3, w = (axis + 2) % 3, base = nv;
            for (int i = 0; i <= n; i++)
                for (int j = 0; j <= n; j++) {
                    double *p = v + 3 * nv++;
                    /* (2i - n) / n is exactly +-1 at the ends: the faces' edges weld */
                    p[axis] = c[axis] + side * h[axis];
                    p[u] = c[u] + h[u] * ((2.0 * i - n) / n);
                    p[w] = c[w] + h[w] * ((2.0 * j - n) / n);
                }
            for (int i = 0; i < n; i++)
                for (int j = 0; j < n; j++) {
                    int a = base + i * (n + 1) + j, b = a + n + 1, cc = b + 1, d = a + 1;
                    /* (u, w, axis) is right-handed: counter-clockwise seen from +axis */
                    int q[6] = {a, b, cc, a, cc, d};
                    if (side < 0) {
                        q[1] = cc;
                        q[2] = b;
                        q[4] = d;
                        q[5] = cc;
                    }
                    memcpy(t + 3 * k, q, sizeof q);
                    k += 2;
                }
        }
    *v_out = v;
    *t_out = t;
    *nv_out = nv;
    *nt_out = nt;
}

/* Writes the box as a Wavefront OBJ file; 0 on success. */
static inline int grid_box_obj(const char *path, const double c[3], const double h[3], int n)
{
    double *v;
    int *t, nv, nt;
    grid_box_arrays(c, h, n, &v, &t, &nv, &nt);
    FILE *f = fopen(path, "w");
    if (f) {
        for (int i = 0; i < nv; i++)
            fprintf(f, "v %.17g %.17g %.17g\n", v[3 * i], v[3 * i + 1], v[3 * i + 2]);
        for (int i = 0; i < nt; i++)
            fprintf(f, "f %d %d %d\n", t[3 * i] + 1, t[3 * i + 1] + 1, t[3 * i + 2] + 1);
    }
    free(v);
    free(t);
    return f && fclose(f) == 0 ? 0 : -1;
}

#endif
