/*
 * result_read.h - what the bench tools read back from a polydem result file (HDF5): whole
 * datasets, one frame of /frames, the shapes under /shapes, string attributes. Header-only
 * (static functions), for bench/contacts.c and bench/replay.c.
 */
#ifndef PD_BENCH_RESULT_READ_H
#define PD_BENCH_RESULT_READ_H

#include <hdf5.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Opens result file `path` for reading, HDF5's own error printing off; prints why not (naming
 * the tool) and returns a negative id where it cannot. */
static hid_t result_open(const char *tool, const char *path)
{
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    if (f < 0) fprintf(stderr, "%s: %s: not an HDF5 file that can be opened\n", tool, path);
    return f;
}

/* Reads string attribute `name` of the object at `path` into buf (size bytes, NUL-terminated);
 * buf is left empty where there is none. */
static void read_string_attr(hid_t f, const char *path, const char *name, char *buf, size_t size)
{
    buf[0] = 0;
    hid_t a = H5Aopen_by_name(f, path, name, H5P_DEFAULT, H5P_DEFAULT);
    if (a < 0) return;
    hid_t ft = H5Aget_type(a);
    hid_t mt = H5Tcopy(H5T_C_S1);
    H5Tset_cset(mt, H5Tget_cset(ft)); /* polydem writes UTF-8; HDF5 does not convert sets */
    if (H5Tis_variable_str(ft) > 0) {
        char *str = NULL;
        H5Tset_size(mt, H5T_VARIABLE);
        if (H5Aread(a, mt, &str) >= 0 && str) {
            snprintf(buf, size, "%s", str);
            H5free_memory(str);
        }
    } else {
        H5Tset_size(mt, size - 1);
        if (H5Aread(a, mt, buf) < 0) buf[0] = 0;
        buf[size - 1] = 0;
    }
    H5Tclose(mt);
    H5Tclose(ft);
    H5Aclose(a);
}

/* Reads dataset `path` as doubles or ints (mtype) into a new buffer; dims[] gets its extent. */
static void *read_all(hid_t f, const char *path, hid_t mtype, size_t esize, hsize_t dims[3],
                      int *rank)
{
    hid_t d = H5Dopen2(f, path, H5P_DEFAULT);
    if (d < 0) return NULL;
    hid_t sp = H5Dget_space(d);
    *rank = sp >= 0 ? H5Sget_simple_extent_ndims(sp) : -1;
    void *buf = NULL;
    if (*rank >= 1 && *rank <= 3 && H5Sget_simple_extent_dims(sp, dims, NULL) >= 0) {
        size_t n = 1;
        for (int k = 0; k < *rank; k++)
            n *= dims[k];
        buf = malloc(esize * (n ? n : 1));
        if (buf && H5Dread(d, mtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) < 0) {
            free(buf);
            buf = NULL;
        }
    }
    if (sp >= 0) H5Sclose(sp);
    H5Dclose(d);
    return buf;
}

/* Reads row `frame` (negative: the last) of /frames/<name>, width w, into out (n x w doubles). */
static int read_frame(hid_t f, const char *name, int *frame, int n, int w, double *out)
{
    char path[64];
    snprintf(path, sizeof path, "/frames/%s", name);
    hid_t d = H5Dopen2(f, path, H5P_DEFAULT);
    if (d < 0) return -1;
    hid_t sp = H5Dget_space(d);
    hsize_t dims[3];
    int ok = sp >= 0 && H5Sget_simple_extent_ndims(sp) == 3 &&
             H5Sget_simple_extent_dims(sp, dims, NULL) >= 0 && dims[1] == (hsize_t)n &&
             dims[2] == (hsize_t)w && dims[0] > 0;
    if (ok && *frame < 0) *frame = (int)dims[0] - 1;
    ok = ok && (hsize_t)*frame < dims[0];
    hsize_t start[3] = {(hsize_t)(ok ? *frame : 0), 0, 0}, count[3] = {1, (hsize_t)n, (hsize_t)w};
    hid_t mem = ok ? H5Screate_simple(3, count, NULL) : -1;
    ok = ok && mem >= 0 && H5Sselect_hyperslab(sp, H5S_SELECT_SET, start, NULL, count, NULL) >= 0 &&
         H5Dread(d, H5T_NATIVE_DOUBLE, mem, sp, H5P_DEFAULT, out) >= 0;
    if (mem >= 0) H5Sclose(mem);
    if (sp >= 0) H5Sclose(sp);
    H5Dclose(d);
    return ok ? 0 : -1;
}

/* A shape of the file: its mesh at size 1, or NULL for an analytic sphere. */
#define NAME_MAX_LEN 127 /* a shape's name, read_shape rejects longer (a bound GCC can see) */
typedef struct {
    char name[NAME_MAX_LEN + 1];
    double *v;
    int *t, nv, nt, sphere;
    double radius; /* circumradius about the body origin at size 1 */
} shape;

static int read_shape(hid_t f, int i, shape *s)
{
    hid_t g = H5Gopen2(f, "/shapes", H5P_DEFAULT);
    if (g < 0) return -1;
    ssize_t len = H5Lget_name_by_idx(g, ".", H5_INDEX_CRT_ORDER, H5_ITER_INC, (hsize_t)i, s->name,
                                     sizeof s->name, H5P_DEFAULT);
    H5Gclose(g);
    if (len <= 0 || len >= (ssize_t)sizeof s->name) return -1;
    char path[200];
    hsize_t dims[3];
    int rank;
    snprintf(path, sizeof path, "/shapes/%.*s/vertices", NAME_MAX_LEN, s->name);
    s->v = read_all(f, path, H5T_NATIVE_DOUBLE, sizeof(double), dims, &rank);
    if (!s->v || rank != 2 || dims[1] != 3) return -1;
    s->nv = (int)dims[0];
    snprintf(path, sizeof path, "/shapes/%.*s/triangles", NAME_MAX_LEN, s->name);
    s->t = read_all(f, path, H5T_NATIVE_INT, sizeof(int), dims, &rank);
    if (!s->t || rank != 2 || dims[1] != 3) return -1;
    s->nt = (int)dims[0];
    /* the kind attribute names analytic spheres (their mesh is for viewing only) */
    char kind[32] = "";
    snprintf(path, sizeof path, "/shapes/%.*s", NAME_MAX_LEN, s->name);
    read_string_attr(f, path, "kind", kind, sizeof kind);
    s->sphere = strcmp(kind, "sphere") == 0;
    s->radius = 0;
    for (int k = 0; k < s->nv; k++) {
        const double *x = s->v + 3 * k;
        s->radius = fmax(s->radius, sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]));
    }
    return 0;
}

#endif /* PD_BENCH_RESULT_READ_H */
