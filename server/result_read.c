/* result_read.c - a result file's stats, frames and shapes as JSON (see result_read.h). */
#include "result_read.h"

#include <hdf5.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Opens the file read-only with HDF5's error printing off for this thread. */
static hid_t open_file(const char *path, char *msg, size_t ml)
{
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    if (f < 0) snprintf(msg, ml, "cannot open the result file");
    return f;
}

/* Reads a whole dataset of rank <= 3 as mtype into a malloc'd buffer; dims receive its shape. */
static void *read_all(hid_t f, const char *path, hid_t mtype, size_t esize, hsize_t dims[3],
                      int *rank)
{
    void *buf = NULL;
    hid_t d = H5Dopen2(f, path, H5P_DEFAULT);
    hid_t sp = d >= 0 ? H5Dget_space(d) : -1;
    int r = sp >= 0 ? H5Sget_simple_extent_ndims(sp) : -1;
    dims[0] = dims[1] = dims[2] = 1;
    if (r >= 1 && r <= 3 && H5Sget_simple_extent_dims(sp, dims, NULL) >= 0) {
        size_t n = (size_t)dims[0] * (r > 1 ? dims[1] : 1) * (r > 2 ? dims[2] : 1);
        buf = malloc(n ? n * esize : 1);
        if (buf && n && H5Dread(d, mtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) < 0) {
            free(buf);
            buf = NULL;
        }
    }
    if (sp >= 0) H5Sclose(sp);
    if (d >= 0) H5Dclose(d);
    *rank = r;
    return buf;
}

/* A JSON array of n doubles, or of n rows of `cols` doubles when cols > 0. */
static json_t *doubles(const double *v, size_t n, int cols)
{
    json_t *a = json_array();
    for (size_t i = 0; a && i < n; i++) {
        if (cols <= 0) {
            json_array_append_new(a, json_real(v[i]));
            continue;
        }
        json_t *row = json_array();
        for (int c = 0; row && c < cols; c++)
            json_array_append_new(row, json_real(v[i * (size_t)cols + (size_t)c]));
        json_array_append_new(a, row);
    }
    return a;
}

static json_t *ints(const long long *v, size_t n, int cols)
{
    json_t *a = json_array();
    for (size_t i = 0; a && i < n; i++) {
        if (cols <= 0) {
            json_array_append_new(a, json_integer(v[i]));
            continue;
        }
        json_t *row = json_array();
        for (int c = 0; row && c < cols; c++)
            json_array_append_new(row, json_integer(v[i * (size_t)cols + (size_t)c]));
        json_array_append_new(a, row);
    }
    return a;
}

/* A 1-D dataset as a JSON array (of doubles, or integers when integer is set); NULL if absent. */
static json_t *column(hid_t f, const char *path, int integer, size_t *n)
{
    hsize_t dims[3];
    int rank;
    void *buf = integer ? read_all(f, path, H5T_NATIVE_LLONG, sizeof(long long), dims, &rank)
                        : read_all(f, path, H5T_NATIVE_DOUBLE, sizeof(double), dims, &rank);
    if (!buf || rank != 1) {
        free(buf);
        return NULL;
    }
    *n = (size_t)dims[0];
    json_t *a = integer ? ints(buf, *n, 0) : doubles(buf, *n, 0);
    free(buf);
    return a;
}

/* Names of a group's members in creation order; a NULL-terminated malloc'd list. */
static char **member_names(hid_t f, const char *group)
{
    hid_t g = H5Gopen2(f, group, H5P_DEFAULT);
    H5G_info_t info;
    if (g < 0) return NULL;
    char **names = NULL;
    if (H5Gget_info(g, &info) >= 0 && (names = calloc(info.nlinks + 1, sizeof *names))) {
        for (hsize_t i = 0; i < info.nlinks; i++) {
            ssize_t len = H5Lget_name_by_idx(g, ".", H5_INDEX_CRT_ORDER, H5_ITER_INC, i, NULL, 0,
                                             H5P_DEFAULT);
            if (len < 0 || !(names[i] = malloc((size_t)len + 1)) ||
                H5Lget_name_by_idx(g, ".", H5_INDEX_CRT_ORDER, H5_ITER_INC, i, names[i],
                                   (size_t)len + 1, H5P_DEFAULT) < 0) {
                for (hsize_t k = 0; k <= i; k++)
                    free(names[k]);
                free(names);
                names = NULL;
                break;
            }
        }
    }
    H5Gclose(g);
    return names;
}

static void free_names(char **names)
{
    for (char **p = names; p && *p; p++)
        free(*p);
    free(names);
}

json_t *result_stats(const char *path, char *msg, size_t ml)
{
    hid_t f = open_file(path, msg, ml);
    if (f < 0) return NULL;
    static const struct {
        const char *name, *unit;
        int integer;
    } cols[] = {{"time", "s", 0},     {"step", "1", 1},        {"kinetic_energy", "J", 0},
                {"contacts", "1", 1}, {"broad_pairs", "1", 1}, {"max_overlap_ratio", "1", 0}};
    json_t *o = json_pack("{s:b}", "partial", 0), *units = json_object();
    size_t rows = 0;
    int ok = o && units;
    for (size_t i = 0; ok && i < sizeof cols / sizeof cols[0]; i++) {
        char p[64];
        size_t n = 0;
        snprintf(p, sizeof p, "/stats/%s", cols[i].name);
        json_t *c = column(f, p, cols[i].integer, &n);
        ok = c && (i == 0 || n == rows);
        rows = n;
        if (c) json_object_set_new(o, cols[i].name, c);
        json_object_set_new(units, cols[i].name, json_string(cols[i].unit));
    }
    size_t nw = 0; /* wall-clock time per row: in results written since it was added */
    json_t *wall = ok ? column(f, "/stats/wall_time", 0, &nw) : NULL;
    if (wall && nw == rows) {
        json_object_set_new(o, "wall_time", wall);
        json_object_set_new(units, "wall_time", json_string("s"));
    } else {
        json_decref(wall);
    }
    json_t *walls = ok ? json_object() : NULL;
    char **names = ok ? member_names(f, "/stats/wall_force") : NULL;
    ok = ok && walls && names;
    for (char **w = names; ok && *w; w++) {
        char p[300];
        hsize_t dims[3];
        int rank;
        snprintf(p, sizeof p, "/stats/wall_force/%s", *w);
        double *v = read_all(f, p, H5T_NATIVE_DOUBLE, sizeof(double), dims, &rank);
        ok = v && rank == 2 && dims[1] == 3 && dims[0] == rows;
        if (ok) json_object_set_new(walls, *w, doubles(v, rows, 3));
        free(v);
    }
    free_names(names);
    /* seconds per stage of the step ending at each row: in results written since it was added */
    json_t *stages = NULL;
    char **snames = ok ? member_names(f, "/stats/stage_time") : NULL;
    if (snames && snames[0]) stages = json_object();
    for (char **st = snames; stages && *st; st++) {
        char p[300];
        size_t n = 0;
        snprintf(p, sizeof p, "/stats/stage_time/%s", *st);
        json_t *c = column(f, p, 0, &n);
        if (c && n == rows) {
            json_object_set_new(stages, *st, c);
        } else {
            json_decref(c);
            json_decref(stages);
            stages = NULL;
        }
    }
    free_names(snames);
    if (ok && stages) {
        json_object_set_new(o, "stage_time", stages);
        json_object_set_new(units, "stage_time", json_string("s"));
    } else {
        json_decref(stages);
    }
    if (ok) {
        json_object_set_new(o, "wall_force", walls);
        json_object_set_new(units, "wall_force", json_string("N"));
        json_object_set_new(o, "units", units);
    } else {
        json_decref(walls);
        json_decref(units);
        json_decref(o);
        o = NULL;
        snprintf(msg, ml, "cannot read /stats from the result file");
    }
    H5Fclose(f);
    return o;
}

json_t *result_frames(const char *path, char *msg, size_t ml)
{
    hid_t f = open_file(path, msg, ml);
    if (f < 0) return NULL;
    size_t n = 0;
    json_t *t = column(f, "/frames/time", 0, &n);
    json_t *o = t ? json_pack("{s:I, s:o}", "count", (json_int_t)n, "time", t) : NULL;
    if (!o) snprintf(msg, ml, "cannot read /frames/time from the result file");
    H5Fclose(f);
    return o;
}

/* Frame k of a (F, N, cols) dataset as N rows; NULL on failure. */
static json_t *frame_rows(hid_t f, const char *path, hsize_t k, int cols)
{
    json_t *out = NULL;
    hid_t d = H5Dopen2(f, path, H5P_DEFAULT);
    hid_t sp = d >= 0 ? H5Dget_space(d) : -1;
    hsize_t dims[3];
    if (sp >= 0 && H5Sget_simple_extent_ndims(sp) == 3 &&
        H5Sget_simple_extent_dims(sp, dims, NULL) >= 0 && k < dims[0] && dims[2] == (hsize_t)cols) {
        hsize_t start[3] = {k, 0, 0}, count[3] = {1, dims[1], dims[2]};
        hsize_t mdims[1] = {dims[1] * dims[2]};
        double *buf = malloc(mdims[0] ? mdims[0] * sizeof(double) : 1);
        hid_t ms = H5Screate_simple(1, mdims, NULL);
        if (buf && ms >= 0 &&
            H5Sselect_hyperslab(sp, H5S_SELECT_SET, start, NULL, count, NULL) >= 0 &&
            H5Dread(d, H5T_NATIVE_DOUBLE, ms, sp, H5P_DEFAULT, buf) >= 0)
            out = doubles(buf, (size_t)dims[1], cols);
        if (ms >= 0) H5Sclose(ms);
        free(buf);
    }
    if (sp >= 0) H5Sclose(sp);
    if (d >= 0) H5Dclose(d);
    return out;
}

/* {"<wall>": its vertices at frame k} for every wall that moves (frame_vertices); fixed walls
 * are in result_shapes. NULL on failure. */
static json_t *moving_walls(hid_t f, hsize_t k)
{
    char **names = member_names(f, "/walls");
    json_t *o = names ? json_object() : NULL;
    for (char **n = names; o && *n; n++) {
        char p[300];
        snprintf(p, sizeof p, "/walls/%s/frame_vertices", *n);
        if (H5Lexists(f, p, H5P_DEFAULT) <= 0) continue;
        json_t *v = frame_rows(f, p, k, 3);
        if (!v || json_object_set_new(o, *n, v) != 0) {
            json_decref(o);
            o = NULL;
        }
    }
    free_names(names);
    return o;
}

json_t *result_frame(const char *path, long long k, int *range, char *msg, size_t ml)
{
    *range = 0;
    hid_t f = open_file(path, msg, ml);
    if (f < 0) return NULL;
    hsize_t dims[3];
    int rank;
    json_t *o = NULL;
    double *t = read_all(f, "/frames/time", H5T_NATIVE_DOUBLE, sizeof(double), dims, &rank);
    long long *s = read_all(f, "/frames/step", H5T_NATIVE_LLONG, sizeof(long long), dims, &rank);
    long long nf = t && s && rank == 1 ? (long long)dims[0] : -1;
    if (nf >= 0 && k < 0) k += nf;
    if (nf >= 0 && (k < 0 || k >= nf)) {
        *range = 1;
        snprintf(msg, ml, "the result has %lld frames (0 to %lld, or -1 for the last)", nf, nf - 1);
    } else if (nf >= 0) {
        json_t *pos = frame_rows(f, "/frames/position", (hsize_t)k, 3);
        json_t *quat = frame_rows(f, "/frames/orientation", (hsize_t)k, 4);
        json_t *walls = moving_walls(f, (hsize_t)k);
        if (pos && quat && walls)
            o = json_pack("{s:I, s:I, s:f, s:I, s:o, s:o, s:o, s:{s:s, s:s, s:s, s:s}}", "frame",
                          (json_int_t)k, "count", (json_int_t)nf, "time", t[k], "step",
                          (json_int_t)s[k], "position", pos, "orientation", quat, "walls", walls,
                          "units", "time", "s", "position", "m", "orientation", "1 (w, x, y, z)",
                          "walls", "m (vertices of each moving wall at this frame)");
        else {
            json_decref(pos);
            json_decref(quat);
            json_decref(walls);
        }
    }
    if (!o && !*range) snprintf(msg, ml, "cannot read /frames from the result file");
    free(t);
    free(s);
    H5Fclose(f);
    return o;
}

/* A variable-length string attribute of an object; "" when absent. */
static void str_attr(hid_t obj, const char *name, char *out, size_t cap)
{
    out[0] = 0;
    hid_t a = H5Aopen(obj, name, H5P_DEFAULT);
    if (a < 0) return;
    hid_t t = H5Aget_type(a), sp = H5Aget_space(a);
    if (t >= 0 && sp >= 0 && H5Tget_class(t) == H5T_STRING && H5Tis_variable_str(t) > 0) {
        char *v = NULL;
        hid_t mt = H5Tcopy(t);
        if (mt >= 0 && H5Aread(a, mt, &v) >= 0 && v) {
            snprintf(out, cap, "%s", v);
#if H5_VERSION_GE(1, 12, 0)
            H5Treclaim(mt, sp, H5P_DEFAULT, &v);
#else
            H5Dvlen_reclaim(mt, sp, H5P_DEFAULT, &v);
#endif
        }
        if (mt >= 0) H5Tclose(mt);
    }
    if (sp >= 0) H5Sclose(sp);
    if (t >= 0) H5Tclose(t);
    H5Aclose(a);
}

/* {"name", "vertices", "triangles"} of the group base/name; NULL on failure. */
static json_t *mesh_json(hid_t f, const char *base, const char *name)
{
    char p[300];
    hsize_t vd[3], td[3];
    int vr, tr;
    snprintf(p, sizeof p, "%s/%s/vertices", base, name);
    double *v = read_all(f, p, H5T_NATIVE_DOUBLE, sizeof(double), vd, &vr);
    snprintf(p, sizeof p, "%s/%s/triangles", base, name);
    long long *t = read_all(f, p, H5T_NATIVE_LLONG, sizeof(long long), td, &tr);
    json_t *o = NULL;
    if (v && t && vr == 2 && vd[1] == 3 && tr == 2 && td[1] == 3)
        o = json_pack("{s:s, s:o, s:o}", "name", name, "vertices", doubles(v, (size_t)vd[0], 3),
                      "triangles", ints(t, (size_t)td[0], 3));
    free(v);
    free(t);
    return o;
}

/* A shape: its mesh (size 1, body frame), kind and volume. */
static json_t *one_shape(hid_t f, const char *name)
{
    char p[300], kind[32];
    double volume = 0;
    json_t *o = mesh_json(f, "/shapes", name);
    snprintf(p, sizeof p, "/shapes/%s", name);
    hid_t g = o ? H5Gopen2(f, p, H5P_DEFAULT) : -1;
    if (g < 0) {
        json_decref(o);
        return NULL;
    }
    hid_t a = H5Aopen(g, "volume", H5P_DEFAULT);
    if (a >= 0) {
        if (H5Aread(a, H5T_NATIVE_DOUBLE, &volume) < 0) volume = 0;
        H5Aclose(a);
    }
    str_attr(g, "kind", kind, sizeof kind);
    H5Gclose(g);
    json_object_set_new(o, "kind", json_string(kind));
    json_object_set_new(o, "volume", json_real(volume));
    return o;
}

/* The meshes of a group's members (shapes or walls), in creation order; NULL on failure. */
static json_t *meshes(hid_t f, const char *group, int shapes)
{
    char **names = member_names(f, group);
    json_t *arr = names ? json_array() : NULL;
    int ok = arr != NULL;
    for (char **n = names; ok && *n; n++) {
        json_t *m = shapes ? one_shape(f, *n) : mesh_json(f, group, *n);
        ok = m != NULL;
        json_array_append_new(arr, m);
    }
    free_names(names);
    if (!ok) {
        json_decref(arr);
        arr = NULL;
    }
    return arr;
}

json_t *result_shapes(const char *path, char *msg, size_t ml)
{
    hid_t f = open_file(path, msg, ml);
    if (f < 0) return NULL;
    json_t *shapes = meshes(f, "/shapes", 1), *walls = meshes(f, "/walls", 0);
    size_t np = 0, ns = 0;
    json_t *pshape = column(f, "/particles/shape", 1, &np);
    json_t *psize = column(f, "/particles/size", 0, &ns);
    json_t *o = NULL;
    if (shapes && walls && pshape && psize && np == ns)
        o = json_pack("{s:o, s:{s:o, s:o}, s:o, s:{s:s, s:s, s:s}}", "shapes", shapes, "particles",
                      "shape", pshape, "size", psize, "walls", walls, "units", "shapes",
                      "1 (vertices times the particle size, body frame)", "size", "m", "walls",
                      "m (at time 0)");
    else {
        json_decref(shapes);
        json_decref(walls);
        json_decref(pshape);
        json_decref(psize);
        snprintf(msg, ml, "cannot read /shapes, /walls and /particles from the result file");
    }
    H5Fclose(f);
    return o;
}
