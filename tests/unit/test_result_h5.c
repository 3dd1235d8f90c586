/*
 * test_result_h5.c - unit tests of engine/result_h5.c: a small run written through the API and
 * read back with the plain HDF5 API, the XDMF file beside it, abort, and the error paths.
 *
 * Values are stored as double and read back bit for bit, so they are compared exactly (tolerance
 * 0); the world-space shape meshes pass through a rotation and are compared to 1e-15 (a few ulps
 * of coordinates of order 1).
 */
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <hdf5.h>

#include "polydem.h"
#include "result_h5.h"
#include "test.h"

/* ---- helpers ------------------------------------------------------------------------------- */

static char tmpdir[64];

/* Path of a file in the test's temporary directory (a few rotating buffers). */
static const char *tmp_path(const char *name)
{
    static char buf[8][160];
    static int next;
    char *p = buf[next++ % 8];
    snprintf(p, sizeof buf[0], "%s/%s", tmpdir, name);
    return p;
}

static int exists(const char *path)
{
    return access(path, F_OK) == 0;
}

/* Removes a result and everything that may lie beside it. */
static void remove_result(const char *path)
{
    static const char *const suffix[] = {"", ".partial", ".xmf", ".xmf.partial"};
    for (size_t i = 0; i < sizeof suffix / sizeof suffix[0]; i++) {
        char p[200];
        snprintf(p, sizeof p, "%s%s", path, suffix[i]);
        remove(p);
    }
}

static char *read_text(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *s = malloc((size_t)n + 1);
    if (s && fread(s, 1, (size_t)n, f) != (size_t)n) {
        free(s);
        s = NULL;
    }
    if (s) s[n] = '\0';
    fclose(f);
    return s;
}

static int count_of(const char *hay, const char *needle)
{
    int n = 0;
    for (const char *p = hay; (p = strstr(p, needle)); p += strlen(needle))
        n++;
    return n;
}

/* String attribute `name` of object `obj_path` (scalar, or element i of a list); malloc'd. */
static char *attr_str(hid_t file, const char *obj_path, const char *name, int i)
{
    char *out = NULL;
    hid_t a = H5Aopen_by_name(file, obj_path, name, H5P_DEFAULT, H5P_DEFAULT);
    if (a < 0) return NULL;
    hid_t t = H5Aget_type(a), sp = H5Aget_space(a);
    hssize_t n = H5Sget_simple_extent_npoints(sp);
    if (H5Tget_class(t) == H5T_STRING && H5Tis_variable_str(t) > 0 && i < n) {
        char **v = calloc((size_t)n, sizeof *v);
        hid_t mt = H5Tcopy(t); /* HDF5 does not convert between ASCII and UTF-8 */
        if (v && H5Aread(a, mt, v) >= 0) {
            size_t len = strlen(v[i]) + 1;
            out = malloc(len);
            if (out) memcpy(out, v[i], len);
            H5Dvlen_reclaim(mt, sp, H5P_DEFAULT, v);
        }
        H5Tclose(mt);
        free(v);
    }
    H5Sclose(sp);
    H5Tclose(t);
    H5Aclose(a);
    return out;
}

static int attr_strs_count(hid_t file, const char *obj_path, const char *name)
{
    hid_t a = H5Aopen_by_name(file, obj_path, name, H5P_DEFAULT, H5P_DEFAULT);
    if (a < 0) return -1;
    hid_t sp = H5Aget_space(a);
    int n = (int)H5Sget_simple_extent_npoints(sp);
    H5Sclose(sp);
    H5Aclose(a);
    return n;
}

static double attr_double(hid_t file, const char *obj_path, const char *name)
{
    double v = NAN;
    hid_t a = H5Aopen_by_name(file, obj_path, name, H5P_DEFAULT, H5P_DEFAULT);
    if (a >= 0) {
        if (H5Aread(a, H5T_NATIVE_DOUBLE, &v) < 0) v = NAN;
        H5Aclose(a);
    }
    return v;
}

static long long attr_int(hid_t file, const char *obj_path, const char *name)
{
    long long v = -999;
    hid_t a = H5Aopen_by_name(file, obj_path, name, H5P_DEFAULT, H5P_DEFAULT);
    if (a >= 0) {
        if (H5Aread(a, H5T_NATIVE_LLONG, &v) < 0) v = -999;
        H5Aclose(a);
    }
    return v;
}

/* Reads dataset `path` whole as mtype into buf (room for cap elements); returns its rank (or -1)
 * and its dimensions in dims. */
static int read_ds(hid_t file, const char *path, hid_t mtype, void *buf, size_t cap,
                   hsize_t dims[3])
{
    dims[0] = dims[1] = dims[2] = 0;
    hid_t d = H5Dopen2(file, path, H5P_DEFAULT);
    if (d < 0) return -1;
    hid_t sp = H5Dget_space(d);
    int rank = H5Sget_simple_extent_ndims(sp);
    if (rank < 0 || rank > 3 || H5Sget_simple_extent_dims(sp, dims, NULL) < 0 ||
        (size_t)H5Sget_simple_extent_npoints(sp) > cap ||
        (H5Sget_simple_extent_npoints(sp) > 0 &&
         H5Dread(d, mtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) < 0))
        rank = -1;
    H5Sclose(sp);
    H5Dclose(d);
    return rank;
}

/* H5Lvisit callback: counts datasets and those without a "units" attribute. */
typedef struct {
    int datasets, missing;
    char first_missing[128];
} units_count;

static herr_t check_units_cb(hid_t g, const char *name, const H5L_info_t *info, void *data)
{
    (void)info;
    units_count *u = data;
    hid_t d = H5Dopen2(g, name, H5P_DEFAULT);
    if (d < 0) return 0; /* a group */
    u->datasets++;
    if (H5Aexists(d, "units") <= 0 && !u->missing++)
        snprintf(u->first_missing, sizeof u->first_missing, "%s", name);
    H5Dclose(d);
    return 0;
}

/* ---- the run written by the tests ---------------------------------------------------------- */

#define N 3

static const char *const SCENARIO = "{\"name\": \"test \\u00e9\", \"dt\": 1e-5}";
static const double CUBE_V[8 * 3] = {-.5, -.5, -.5, .5, -.5, -.5, .5, .5, -.5, -.5, .5, -.5,
                                     -.5, -.5, .5,  .5, -.5, .5,  .5, .5, .5,  -.5, .5, .5};
static const int CUBE_T[12 * 3] = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                   1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7};
static const double TET_V[4 * 3] = {1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1};
static const int TET_T[4 * 3] = {0, 1, 2, 0, 3, 1, 0, 2, 3, 1, 3, 2};
static const double WALL_V[4 * 3] = {-2, -2, 0, 2, -2, 0, 2, 2, 0, -2, 2, 0};
static const int WALL_T[2 * 3] = {0, 1, 2, 0, 2, 3};
/* Shapes are added "tet" first, so index order differs from alphabetical order. */
static const int P_SHAPE[N] = {0, 1, 0};
static const int P_MAT[N] = {0, 1, 1};
static const double P_SIZE[N] = {0.5, 1.0, 2.0};
static const double P_MASS[N] = {1.5, 2.5, 3.5};

/* Deterministic per-frame values. */
static double pos_v(int f, int i, int c)
{
    return f + 0.1 * i + 0.01 * c;
}
static double vel_v(int f, int i, int c)
{
    return -f - 0.2 * i - 0.03 * c;
}
static double angvel_v(int f, int i, int c)
{
    return 10 * f + i + 0.5 * c;
}
static void quat_v(int f, int i, double q[4])
{
    /* rotation by (f + i) * 0.3 rad about z */
    double h = 0.15 * (f + i);
    q[0] = cos(h);
    q[1] = 0;
    q[2] = 0;
    q[3] = sin(h);
}

/* A moving wall, named with XML's specials: it rises at 1 m/s and turns at pi rad/s about z
 * through the origin, a quarter turn by frame 2 (t = 0.5 s). */
#define LID "lid <&\">"
static const double LID_MOTION[9] = {0, 0, 1, 0, 0, 3.14159265358979323846, 0, 0, 0};

/* Writes the standard run to path: 2 shapes, 2 walls, N particles, 3 frames, 4 stats rows.
 * Returns 0 when every call succeeded, or stops at the first failure (writer aborted). */
static int write_run(const char *path, int fields, int close_it, pd_error *err)
{
    rh5_writer *w;
    if (rh5_create(path, SCENARIO, 1, 1e-5, fields, &w, err)) return -1;
    if (rh5_add_shape(w, "tet", "mesh", TET_V, 4, TET_T, 4, 8.0 / 3, err) ||
        rh5_add_shape(w, "cube", "mesh", CUBE_V, 8, CUBE_T, 12, 1.0, err) ||
        rh5_add_wall(w, "floor", WALL_V, 4, WALL_T, 2, NULL, err) ||
        rh5_add_wall(w, LID, WALL_V, 4, WALL_T, 2, LID_MOTION, err) ||
        rh5_set_particles(w, N, P_SHAPE, P_MAT, P_SIZE, P_MASS, err))
        goto fail;
    for (int f = 0; f < 3; f++) {
        double pos[3 * N], vel[3 * N], av[3 * N], q[4 * N];
        for (int i = 0; i < N; i++) {
            for (int c = 0; c < 3; c++) {
                pos[3 * i + c] = pos_v(f, i, c);
                vel[3 * i + c] = vel_v(f, i, c);
                av[3 * i + c] = angvel_v(f, i, c);
            }
            quat_v(f, i, &q[4 * i]);
        }
        if (rh5_write_frame(w, 0.25 * f, 100LL * f + 5000000000LL, pos, q, vel, av, err)) goto fail;
    }
    for (int s = 0; s < 4; s++) {
        double wf[6] = {s, -s, 9.81 * s, 0, 0, -s};
        double st[RH5_NSTAGES] = {0.01 * s, 0.02 * s, 0.03 * s, 0.04 * s, 0.05 * s};
        if (rh5_write_stats(w, 0.1 * s, 40LL * s, 0.5 * s, 7LL * s, 11LL * s, 0.001 * s, 2.5 * s,
                            wf, st, err))
            goto fail;
    }
    if (!close_it) {
        rh5_abort(w);
        return 0;
    }
    return rh5_close(w, err) ? -1 : 0;
fail:
    rh5_abort(w);
    return -1;
}

/* ---- tests --------------------------------------------------------------------------------- */

TEST(roundtrip_hdf5)
{
    const char *path = tmp_path("out.h5");
    pd_error err = {0};
    int rc = write_run(path, RH5_VELOCITY | RH5_ANGULAR_VELOCITY | RH5_SHAPE_MESHES, 1, &err);
    CHECK_EQ_INT(0, rc);
    if (rc) printf("  error: %s\n", err.msg);
    CHECK(exists(path));
    CHECK(!exists(tmp_path("out.h5.partial")));
    CHECK(!exists(tmp_path("out.h5.xmf.partial")));
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    CHECK(f >= 0);
    if (f < 0) return;
    char *s;

    /* root attributes */
    CHECK_STR_CONTAINS(s = attr_str(f, "/", "format", 0), "polydem-result");
    CHECK(s && !strcmp(s, "polydem-result"));
    free(s);
    CHECK_EQ_INT(1, attr_int(f, "/", "format_version"));
    CHECK((s = attr_str(f, "/", "scenario", 0)) && !strcmp(s, SCENARIO));
    free(s);
    CHECK((s = attr_str(f, "/", "precision", 0)) && !strcmp(s, "double"));
    free(s);
    CHECK_NEAR(1e-5, attr_double(f, "/", "dt"), 0);

    /* shapes: order by the names list, index attribute and values */
    CHECK_EQ_INT(2, attr_strs_count(f, "/shapes", "names"));
    CHECK((s = attr_str(f, "/shapes", "names", 0)) && !strcmp(s, "tet"));
    free(s);
    CHECK((s = attr_str(f, "/shapes", "names", 1)) && !strcmp(s, "cube"));
    free(s);
    CHECK((s = attr_str(f, "/particles/shape", "names", 1)) && !strcmp(s, "cube"));
    free(s);
    CHECK_EQ_INT(0, attr_int(f, "/shapes/tet", "index"));
    CHECK_EQ_INT(1, attr_int(f, "/shapes/cube", "index"));
    CHECK((s = attr_str(f, "/shapes/cube", "kind", 0)) && !strcmp(s, "mesh"));
    free(s);
    CHECK_NEAR(8.0 / 3, attr_double(f, "/shapes/tet", "volume"), 0);
    CHECK_NEAR(1.0, attr_double(f, "/shapes/cube", "volume"), 0);
    double d[64];
    int ib[64];
    hsize_t dims[3];
    CHECK_EQ_INT(2, read_ds(f, "/shapes/cube/vertices", H5T_NATIVE_DOUBLE, d, 64, dims));
    CHECK_EQ_INT(8, dims[0]);
    CHECK_EQ_INT(3, dims[1]);
    for (int k = 0; k < 24; k++)
        CHECK_NEAR(CUBE_V[k], d[k], 0);
    CHECK_EQ_INT(2, read_ds(f, "/shapes/tet/triangles", H5T_NATIVE_INT, ib, 64, dims));
    CHECK_EQ_INT(4, dims[0]);
    for (int k = 0; k < 12; k++)
        CHECK_EQ_INT(TET_T[k], ib[k]);

    /* walls */
    CHECK_EQ_INT(2, read_ds(f, "/walls/floor/vertices", H5T_NATIVE_DOUBLE, d, 64, dims));
    CHECK_EQ_INT(4, dims[0]);
    CHECK_NEAR(-2, d[9], 0);
    CHECK_NEAR(2, d[10], 0);
    CHECK_EQ_INT(2, read_ds(f, "/walls/floor/triangles", H5T_NATIVE_INT, ib, 64, dims));
    CHECK_EQ_INT(2, dims[0]);
    CHECK_EQ_INT(3, ib[5]);
    /* the floor is fixed: zero motion, no frame_vertices */
    CHECK_EQ_INT(1, read_ds(f, "/walls/floor/angular_velocity", H5T_NATIVE_DOUBLE, d, 64, dims));
    CHECK(dims[0] == 3 && d[0] == 0 && d[1] == 0 && d[2] == 0);
    CHECK(H5Lexists(f, "/walls/floor/frame_vertices", H5P_DEFAULT) == 0);
    /* the lid: its motion, and its vertices at each frame's time t = 0.25 f, rotated by pi t
     * about z and raised by t: (2, -2, 0) at t = 0.5 is (2, 2, 0.5) */
    CHECK_EQ_INT(1, read_ds(f, "/walls/" LID "/angular_velocity", H5T_NATIVE_DOUBLE, d, 64, dims));
    CHECK_NEAR(3.14159265358979323846, d[2], 0);
    CHECK_EQ_INT(1, read_ds(f, "/walls/" LID "/velocity", H5T_NATIVE_DOUBLE, d, 64, dims));
    CHECK_NEAR(1, d[2], 0);
    CHECK_EQ_INT(3, read_ds(f, "/walls/" LID "/frame_vertices", H5T_NATIVE_DOUBLE, d, 64, dims));
    CHECK(dims[0] == 3 && dims[1] == 4 && dims[2] == 3);
    for (int fr = 0; fr < 3; fr++) {
        double t = 0.25 * fr, c = cos(3.14159265358979323846 * t),
               sn = sin(3.14159265358979323846 * t);
        for (int v = 0; v < 4; v++) {
            const double *p = WALL_V + 3 * v, *o = d + 12 * fr + 3 * v;
            CHECK_NEAR(c * p[0] - sn * p[1], o[0], 1e-15);
            CHECK_NEAR(sn * p[0] + c * p[1], o[1], 1e-15);
            CHECK_NEAR(t, o[2], 1e-15);
        }
    }
    CHECK_NEAR(2, d[24 + 3], 1e-15);
    CHECK_NEAR(2, d[24 + 4], 1e-15);

    /* particles */
    CHECK_EQ_INT(1, read_ds(f, "/particles/shape", H5T_NATIVE_INT, ib, 64, dims));
    CHECK_EQ_INT(N, dims[0]);
    for (int i = 0; i < N; i++)
        CHECK_EQ_INT(P_SHAPE[i], ib[i]);
    CHECK_EQ_INT(1, read_ds(f, "/particles/material", H5T_NATIVE_INT, ib, 64, dims));
    for (int i = 0; i < N; i++)
        CHECK_EQ_INT(P_MAT[i], ib[i]);
    CHECK_EQ_INT(1, read_ds(f, "/particles/size", H5T_NATIVE_DOUBLE, d, 64, dims));
    for (int i = 0; i < N; i++)
        CHECK_NEAR(P_SIZE[i], d[i], 0);
    CHECK_EQ_INT(1, read_ds(f, "/particles/mass", H5T_NATIVE_DOUBLE, d, 64, dims));
    for (int i = 0; i < N; i++)
        CHECK_NEAR(P_MASS[i], d[i], 0);

    /* frames: dims and the values of frame 2 */
    CHECK_EQ_INT(1, read_ds(f, "/frames/time", H5T_NATIVE_DOUBLE, d, 64, dims));
    CHECK_EQ_INT(3, dims[0]);
    CHECK_NEAR(0.5, d[2], 0);
    long long lb[16];
    CHECK_EQ_INT(1, read_ds(f, "/frames/step", H5T_NATIVE_LLONG, lb, 16, dims));
    CHECK_EQ_INT(5000000200LL, lb[2]); /* needs the 64 bits */
    static const struct {
        const char *path;
        int c;
    } fr[] = {{"/frames/position", 3},
              {"/frames/orientation", 4},
              {"/frames/velocity", 3},
              {"/frames/angular_velocity", 3}};
    for (size_t a = 0; a < sizeof fr / sizeof fr[0]; a++) {
        CHECK_EQ_INT(3, read_ds(f, fr[a].path, H5T_NATIVE_DOUBLE, d, 64, dims));
        CHECK_EQ_INT(3, dims[0]);
        CHECK_EQ_INT(N, dims[1]);
        CHECK_EQ_INT(fr[a].c, dims[2]);
        for (int i = 0; i < N; i++) {
            double q[4];
            quat_v(2, i, q);
            for (int c = 0; c < fr[a].c; c++) {
                double want = a == 0   ? pos_v(2, i, c)
                              : a == 1 ? q[c]
                              : a == 2 ? vel_v(2, i, c)
                                       : angvel_v(2, i, c);
                CHECK_NEAR(want, d[(2 * N + i) * fr[a].c + c], 0);
            }
        }
    }

    /* world-space meshes: particle 1 (the cube, size 1) starts at tet's 4 vertices */
    double *mv = malloc(3 * 16 * 3 * sizeof *mv);
    CHECK_EQ_INT(3, read_ds(f, "/xdmf/vertices", H5T_NATIVE_DOUBLE, mv, 3 * 16 * 3, dims));
    CHECK_EQ_INT(3, dims[0]);
    CHECK_EQ_INT(16, dims[1]); /* 4 + 8 + 4 */
    if (dims[1] == 16) {
        double q[4], r[3][3];
        quat_v(2, 1, q);
        pd_quat_to_matrix(q, r);
        for (int v = 0; v < 8; v++) {
            for (int k = 0; k < 3; k++) {
                const double *b = &CUBE_V[3 * v];
                double want = pos_v(2, 1, k) + r[k][0] * b[0] + r[k][1] * b[1] + r[k][2] * b[2];
                CHECK_NEAR(want, mv[(2 * 16 + 4 + v) * 3 + k], 1e-15);
            }
        }
        /* particle 2: the tet at size 2 */
        quat_v(2, 2, q);
        pd_quat_to_matrix(q, r);
        double want = pos_v(2, 2, 0) + 2 * (r[0][0] * 1 + r[0][1] * -1 + r[0][2] * -1);
        CHECK_NEAR(want, mv[(2 * 16 + 12 + 1) * 3 + 0], 1e-15);
    }
    free(mv);
    CHECK_EQ_INT(2, read_ds(f, "/xdmf/triangles", H5T_NATIVE_INT, ib, 64, dims));
    CHECK_EQ_INT(20, dims[0]);
    CHECK_EQ_INT(4 + CUBE_T[0], ib[3 * 4]);       /* the cube's first triangle, renumbered */
    CHECK_EQ_INT(12 + TET_T[11], ib[3 * 19 + 2]); /* the last tet's last index */
    CHECK_EQ_INT(1, read_ds(f, "/xdmf/particle", H5T_NATIVE_INT, ib, 64, dims));
    CHECK_EQ_INT(0, ib[3]);
    CHECK_EQ_INT(1, ib[4]);
    CHECK_EQ_INT(2, ib[19]);

    /* stats */
    CHECK_EQ_INT(1, read_ds(f, "/stats/kinetic_energy", H5T_NATIVE_DOUBLE, d, 64, dims));
    CHECK_EQ_INT(4, dims[0]);
    for (int s2 = 0; s2 < 4; s2++)
        CHECK_NEAR(0.5 * s2, d[s2], 0);
    CHECK_EQ_INT(1, read_ds(f, "/stats/time", H5T_NATIVE_DOUBLE, d, 64, dims));
    CHECK_NEAR(0.1 * 3, d[3], 0);
    CHECK_EQ_INT(1, read_ds(f, "/stats/max_overlap_ratio", H5T_NATIVE_DOUBLE, d, 64, dims));
    CHECK_NEAR(0.001 * 3, d[3], 0);
    CHECK_EQ_INT(1, read_ds(f, "/stats/wall_time", H5T_NATIVE_DOUBLE, d, 64, dims));
    CHECK_EQ_INT(4, dims[0]);
    CHECK_NEAR(2.5 * 3, d[3], 0);
    CHECK_EQ_INT(1, read_ds(f, "/stats/step", H5T_NATIVE_LLONG, lb, 16, dims));
    CHECK_EQ_INT(120, lb[3]);
    CHECK_EQ_INT(1, read_ds(f, "/stats/contacts", H5T_NATIVE_LLONG, lb, 16, dims));
    CHECK_EQ_INT(21, lb[3]);
    CHECK_EQ_INT(1, read_ds(f, "/stats/broad_pairs", H5T_NATIVE_LLONG, lb, 16, dims));
    CHECK_EQ_INT(33, lb[3]);
    CHECK_EQ_INT(2, read_ds(f, "/stats/wall_force/floor", H5T_NATIVE_DOUBLE, d, 64, dims));
    CHECK_EQ_INT(4, dims[0]);
    CHECK_EQ_INT(3, dims[1]);
    CHECK_NEAR(2, d[6], 0);
    CHECK_NEAR(-2, d[7], 0);
    CHECK_NEAR(9.81 * 2, d[8], 0);
    static const char *const stages[RH5_NSTAGES] = {"integrate", "bvh", "traverse", "contacts",
                                                    "gather"};
    for (int k = 0; k < RH5_NSTAGES; k++) {
        char p[64];
        snprintf(p, sizeof p, "/stats/stage_time/%s", stages[k]);
        CHECK_EQ_INT(1, read_ds(f, p, H5T_NATIVE_DOUBLE, d, 64, dims));
        CHECK_EQ_INT(4, dims[0]);
        CHECK_NEAR(0.01 * (k + 1) * 3, d[3], 0);
    }

    /* units: on every dataset, and the right ones where they matter */
    units_count u = {0};
    CHECK(H5Lvisit(f, H5_INDEX_NAME, H5_ITER_INC, check_units_cb, &u) >= 0);
    /* 4 shapes; the walls' 2 meshes and 3 motions each, and the lid's frame_vertices; 4 particles,
     * 5 xdmf (wall_size), 6 frames, 14 stats */
    CHECK_EQ_INT(44, u.datasets);
    CHECK_EQ_INT(0, u.missing);
    if (u.missing) printf("  first dataset without units: %s\n", u.first_missing);
    static const char *const units[][2] = {{"/frames/position", "m"},
                                           {"/frames/velocity", "m/s"},
                                           {"/frames/angular_velocity", "rad/s"},
                                           {"/frames/time", "s"},
                                           {"/frames/step", ""},
                                           {"/frames/orientation", "1"},
                                           {"/particles/mass", "kg"},
                                           {"/particles/size", "m"},
                                           {"/stats/kinetic_energy", "J"},
                                           {"/stats/wall_force/floor", "N"},
                                           {"/stats/stage_time/contacts", "s"},
                                           {"/shapes/cube/triangles", ""},
                                           {"/walls/floor/vertices", "m"},
                                           {"/walls/floor/velocity", "m/s"},
                                           {"/walls/floor/angular_velocity", "rad/s"},
                                           {"/walls/floor/center", "m"},
                                           {"/walls/" LID "/frame_vertices", "m"},
                                           {"/stats/max_overlap_ratio", "1"},
                                           {"/stats/wall_time", "s"}};
    for (size_t a = 0; a < sizeof units / sizeof units[0]; a++) {
        s = attr_str(f, units[a][0], "units", 0);
        if (!s || strcmp(s, units[a][1]))
            TEST_FAILF("%s: units \"%s\", expected \"%s\"", units[a][0], s ? s : "(none)",
                       units[a][1]);
        free(s);
    }
    H5Fclose(f);

    if (system("command -v h5dump >/dev/null 2>&1") == 0) {
        char cmd[300];
        snprintf(cmd, sizeof cmd, "h5dump -H '%s' >/dev/null 2>&1", path);
        CHECK_EQ_INT(0, system(cmd));
    }
}

TEST(xdmf_file)
{
    const char *path = tmp_path("out.h5"); /* written by roundtrip_hdf5 */
    char *x = read_text(tmp_path("out.h5.xmf"));
    CHECK(x != NULL);
    if (!x) return;
    CHECK_STR_CONTAINS(x, "CollectionType=\"Temporal\"");
    CHECK_EQ_INT(3, count_of(x, "<Time "));
    CHECK_STR_CONTAINS(x, "<Time Value=\"0.5\"/>");
    CHECK_EQ_INT(3, count_of(x, "TopologyType=\"Polyvertex\""));
    /* the connectivity DataItem inside every Polyvertex topology, by the h5 base name */
    int inside = 0;
    for (const char *t = x; (t = strstr(t, "TopologyType=\"Polyvertex\"")); t++) {
        const char *end = strstr(t, "</Topology>"), *item = strstr(t, "<DataItem");
        const char *ref = strstr(t, ">out.h5:/xdmf/particle_id</DataItem>");
        const char *ne = strstr(t, "NumberOfElements=\"3\" NodesPerElement=\"1\"");
        inside += end && item && ref && ne && ne < item && item < end && ref < end;
    }
    CHECK_EQ_INT(3, inside);
    CHECK(!strstr(x, tmpdir)); /* relative: the pair can move together */
    /* frame k's positions: a selection (start:stride:count:dataspace) of the (3, 3, 3) dataset */
    CHECK_EQ_INT(3, count_of(x, "<DataItem Dimensions=\"3 3\" NumberType=\"Float\" "
                                "Precision=\"8\" Format=\"HDF\">out.h5:/frames/position|"));
    CHECK_STR_CONTAINS(x, ">out.h5:/frames/position|2 0 0:1 1 1:1 3 3:3 3 3</DataItem>");
    CHECK_STR_CONTAINS(x, ">out.h5:/frames/velocity|1 0 0:1 1 1:1 3 3:3 3 3</DataItem>");
    CHECK_EQ_INT(3, count_of(x, "out.h5:/frames/velocity|"));
    CHECK_EQ_INT(3, count_of(x, "out.h5:/frames/angular_velocity|"));
    CHECK_EQ_INT(3, count_of(x, "Name=\"orientation\" AttributeType=\"Matrix\""));
    CHECK_STR_CONTAINS(x, "<DataItem Dimensions=\"3 4\" NumberType=\"Float\" Precision=\"8\" "
                          "Format=\"HDF\">out.h5:/frames/orientation|0 0 0:1 1 1:1 3 4:3 3 4<");
    /* the shape meshes: one triangle grid per frame over the 16 world vertices */
    CHECK_EQ_INT(3, count_of(x, "TopologyType=\"Triangle\" NumberOfElements=\"20\""));
    CHECK_STR_CONTAINS(x, ">out.h5:/xdmf/vertices|2 0 0:1 1 1:1 16 3:3 16 3</DataItem>");
    CHECK_STR_CONTAINS(x, ">out.h5:/xdmf/triangles</DataItem>");
    CHECK_EQ_INT(3, count_of(x, "CollectionType=\"Spatial\""));
    /* the walls in every frame, named, the XML specials escaped: the floor where it stands, the
     * lid where it is at that frame */
    CHECK_EQ_INT(3, count_of(x, "<Grid Name=\"floor\" GridType=\"Uniform\">"));
    CHECK_EQ_INT(3, count_of(x, "<Grid Name=\"lid &lt;&amp;&quot;&gt;\" GridType=\"Uniform\">"));
    CHECK_EQ_INT(6, count_of(x, "TopologyType=\"Triangle\" NumberOfElements=\"2\""));
    CHECK_EQ_INT(3, count_of(x, ">out.h5:/walls/floor/vertices</DataItem>"));
    CHECK_EQ_INT(3, count_of(x, ">out.h5:/walls/lid &lt;&amp;&quot;&gt;/triangles</DataItem>"));
    /* each wall's points carry a zero size (a Glyph by size over the frame skips them) */
    CHECK_EQ_INT(6, count_of(x, "<DataItem Dimensions=\"4\" NumberType=\"Float\" Precision=\"8\" "
                                "Format=\"HDF\">out.h5:/xdmf/wall_size|0:1:4:4</DataItem>"));
    CHECK_STR_CONTAINS(x, "<DataItem Dimensions=\"4 3\" NumberType=\"Float\" Precision=\"8\" "
                          "Format=\"HDF\">out.h5:/walls/lid &lt;&amp;&quot;&gt;/frame_vertices|1 0 "
                          "0:1 1 1:1 4 3:3 4 3</DataItem>");
    if (system("command -v xmllint >/dev/null 2>&1") == 0) {
        char cmd[300];
        snprintf(cmd, sizeof cmd, "xmllint --noout '%s.xmf' >/dev/null 2>&1", path);
        CHECK_EQ_INT(0, system(cmd));
    }
    free(x);
    remove_result(path);
}

TEST(without_optional_fields)
{
    const char *path = tmp_path("plain.h5");
    pd_error err = {0};
    CHECK_EQ_INT(0, write_run(path, 0, 1, &err));
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    CHECK(f >= 0);
    if (f >= 0) {
        CHECK(H5Lexists(f, "/frames/position", H5P_DEFAULT) > 0);
        CHECK(H5Lexists(f, "/frames/orientation", H5P_DEFAULT) > 0);
        CHECK(H5Lexists(f, "/frames/velocity", H5P_DEFAULT) == 0);
        CHECK(H5Lexists(f, "/frames/angular_velocity", H5P_DEFAULT) == 0);
        CHECK(H5Lexists(f, "/xdmf/vertices", H5P_DEFAULT) == 0);
        H5Fclose(f);
    }
    char *x = read_text(tmp_path("plain.h5.xmf"));
    /* no velocities, no particle meshes; the walls, so every frame is a spatial collection */
    CHECK(x && !strstr(x, "velocity") && !strstr(x, "Name=\"shapes\"") &&
          count_of(x, "Triangle") == 6 && count_of(x, "Spatial") == 3);
    CHECK(x && count_of(x, "<Time ") == 3 && count_of(x, "Polyvertex") == 3);
    free(x);
    remove_result(path);
}

TEST(abort_leaves_nothing)
{
    const char *path = tmp_path("aborted.h5");
    pd_error err = {0};
    CHECK_EQ_INT(0, write_run(path, RH5_VELOCITY | RH5_SHAPE_MESHES, 0, &err));
    CHECK(!exists(path));
    CHECK(!exists(tmp_path("aborted.h5.partial")));
    CHECK(!exists(tmp_path("aborted.h5.xmf")));
    rh5_abort(NULL); /* accepted */
}

TEST(error_missing_directory)
{
    const char *path = tmp_path("no/such/dir/out.h5");
    pd_error err = {0};
    rh5_writer *w = (rh5_writer *)&err; /* must be reset to NULL */
    int rc = rh5_create(path, "{}", 0, 1e-3, 0, &w, &err);
    CHECK_EQ_INT(PD_EIO, rc);
    CHECK(w == NULL);
    CHECK_STR_CONTAINS(err.msg, path);
    CHECK_STR_CONTAINS(err.msg, "No such file or directory");
}

TEST(error_bad_file_name)
{
    pd_error err = {0};
    rh5_writer *w = NULL;
    const char *path = tmp_path("a:b.h5");
    CHECK_EQ_INT(PD_EINVAL, rh5_create(path, "{}", 0, 1e-3, 0, &w, &err));
    CHECK(w == NULL);
    CHECK_STR_CONTAINS(err.msg, "a:b.h5: bad result file name");
    CHECK(!exists(tmp_path("a:b.h5.partial")));
    CHECK_EQ_INT(PD_EINVAL, rh5_create("dir/", "{}", 0, 1e-3, 0, &w, &err));
    CHECK_STR_CONTAINS(err.msg, "dir/: bad result file name");
}

TEST(error_frame_before_particles)
{
    const char *path = tmp_path("early.h5");
    pd_error err = {0};
    rh5_writer *w = NULL;
    CHECK_EQ_INT(0, rh5_create(path, "{}", 0, 1e-3, RH5_VELOCITY, &w, &err));
    if (!w) return;
    double pos[3] = {0}, q[4] = {1, 0, 0, 0};
    CHECK_EQ_INT(PD_EINVAL, rh5_write_frame(w, 0, 0, pos, q, pos, NULL, &err));
    CHECK_STR_CONTAINS(err.msg, path);
    CHECK_STR_CONTAINS(err.msg, "particle count unknown");
    CHECK_EQ_INT(PD_EINVAL, rh5_write_stats(w, 0, 0, 0, 0, 0, 0, 0, NULL, NULL, &err));
    CHECK_STR_CONTAINS(err.msg, "rh5_set_particles first");
    /* closing a result without particles discards it */
    CHECK_EQ_INT(PD_EINVAL, rh5_close(w, &err));
    CHECK_STR_CONTAINS(err.msg, "no particles");
    CHECK(!exists(path));
    CHECK(!exists(tmp_path("early.h5.partial")));
}

TEST(error_bad_input_keeps_writer_usable)
{
    const char *path = tmp_path("bad.h5");
    pd_error err = {0};
    rh5_writer *w = NULL;
    CHECK_EQ_INT(0, rh5_create(path, "{}", 0, 1e-3, RH5_VELOCITY, &w, &err));
    if (!w) return;
    CHECK_EQ_INT(0, rh5_add_shape(w, "cube", "mesh", CUBE_V, 8, CUBE_T, 12, 1, &err));
    CHECK_EQ_INT(PD_EINVAL, rh5_add_shape(w, "cube", "mesh", CUBE_V, 8, CUBE_T, 12, 1, &err));
    CHECK_STR_CONTAINS(err.msg, "shape 'cube' added twice");
    CHECK_EQ_INT(PD_EINVAL, rh5_add_shape(w, "ball", "blob", CUBE_V, 8, CUBE_T, 12, 1, &err));
    CHECK_STR_CONTAINS(err.msg, "kind 'blob'");
    CHECK_EQ_INT(PD_EINVAL, rh5_add_shape(w, "a/b", "mesh", CUBE_V, 8, CUBE_T, 12, 1, &err));
    CHECK_STR_CONTAINS(err.msg, "bad shape name 'a/b'");
    CHECK_EQ_INT(PD_EINVAL, rh5_add_shape(w, "tet", "mesh", TET_V, 3, TET_T, 4, 1, &err));
    CHECK_STR_CONTAINS(err.msg, "uses vertex 3 of 3");
    int shape[2] = {0, 1}, mat[2] = {0, 0};
    double size[2] = {1, 1}, mass[2] = {1, 1};
    CHECK_EQ_INT(PD_EINVAL, rh5_set_particles(w, 2, shape, mat, size, mass, &err));
    CHECK_STR_CONTAINS(err.msg, "particle 1: shape index 1 out of range (1 shapes)");
    shape[1] = 0;
    CHECK_EQ_INT(0, rh5_set_particles(w, 2, shape, mat, size, mass, &err));
    CHECK_EQ_INT(PD_EINVAL, rh5_set_particles(w, 2, shape, mat, size, mass, &err));
    CHECK_EQ_INT(PD_EINVAL, rh5_add_wall(w, "late", WALL_V, 4, WALL_T, 2, NULL, &err));
    CHECK_STR_CONTAINS(err.msg, "rh5_add_wall after rh5_set_particles");
    double pos[6] = {0}, q[8] = {1, 0, 0, 0, 1, 0, 0, 0};
    CHECK_EQ_INT(PD_EINVAL, rh5_write_frame(w, 0, 0, pos, q, NULL, NULL, &err));
    CHECK_STR_CONTAINS(err.msg, "velocity yes");
    CHECK_EQ_INT(0, rh5_write_frame(w, 0, 0, pos, q, pos, NULL, &err));
    CHECK_EQ_INT(PD_EINVAL, rh5_write_stats(w, 0, 0, 0, 0, 0, 0, 0, NULL, NULL, &err));
    CHECK_STR_CONTAINS(err.msg, "stats row 0: stage times missing");
    CHECK_EQ_INT(0, rh5_close(w, &err));
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    hsize_t dims[3];
    double d[16];
    CHECK_EQ_INT(3, read_ds(f, "/frames/velocity", H5T_NATIVE_DOUBLE, d, 16, dims));
    CHECK_EQ_INT(1, dims[0]);
    if (f >= 0) H5Fclose(f);
    remove_result(path);
}

/* A writer of path with the standard shapes, wall and N particles set; NULL (a failed check)
 * when a call failed. */
static rh5_writer *begin_writer(const char *path, int fields, pd_error *err)
{
    rh5_writer *w = NULL;
    CHECK_EQ_INT(0, rh5_create(path, SCENARIO, 1, 1e-5, fields, &w, err));
    if (!w) return NULL;
    int rc = rh5_add_shape(w, "tet", "mesh", TET_V, 4, TET_T, 4, 8.0 / 3, err);
    if (!rc) rc = rh5_add_shape(w, "cube", "mesh", CUBE_V, 8, CUBE_T, 12, 1.0, err);
    if (!rc) rc = rh5_set_particles(w, N, P_SHAPE, P_MAT, P_SIZE, P_MASS, err);
    CHECK_EQ_INT(0, rc);
    if (rc) {
        rh5_abort(w);
        return NULL;
    }
    return w;
}

/* The file-size limit before limit_file_size. */
static struct rlimit saved_limit;

static void lift_limit(int sig)
{
    (void)sig;
    setrlimit(RLIMIT_FSIZE, &saved_limit);
}

/*
 * Limits files to `bytes`: the first write past it fails with EFBIG, as on a full disk, and the
 * limit is then lifted at once (SIGXFSZ's handler), as when space comes free: HDF5's further
 * writes succeed, whatever state the failed one left the file in. unlimit_file_size restores.
 */
static void limit_file_size(rlim_t bytes)
{
    getrlimit(RLIMIT_FSIZE, &saved_limit);
    struct rlimit lim = saved_limit;
    lim.rlim_cur = bytes;
    signal(SIGXFSZ, lift_limit);
    setrlimit(RLIMIT_FSIZE, &lim);
}

static void unlimit_file_size(void)
{
    setrlimit(RLIMIT_FSIZE, &saved_limit);
    signal(SIGXFSZ, SIG_DFL);
}

/* Rows of dataset path in file (-1 when it cannot be read). */
static long long rows_of(hid_t f, const char *path)
{
    hid_t d = H5Dopen2(f, path, H5P_DEFAULT);
    hid_t sp = d >= 0 ? H5Dget_space(d) : -1;
    hsize_t dims[3] = {0, 0, 0};
    long long n =
        sp >= 0 && H5Sget_simple_extent_dims(sp, dims, NULL) > 0 ? (long long)dims[0] : -1;
    if (sp >= 0) H5Sclose(sp);
    if (d >= 0) H5Dclose(d);
    return n;
}

/* Reads dataset path of a kept .partial whole (n doubles) and checks that nothing in it is the
 * fill value 0 where a write put 1 + row; 0 when every row holds its values. */
static int rows_written(hid_t f, const char *path, long long rows, int per_row)
{
    size_t n = (size_t)rows * (size_t)per_row;
    double *v = malloc(n * sizeof *v + 1);
    hid_t d = H5Dopen2(f, path, H5P_DEFAULT);
    int ok = v && d >= 0 && H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v) >= 0;
    for (size_t k = 0; ok && k < n; k++)
        ok = v[k] == 1 + (double)(k / (size_t)per_row);
    if (d >= 0) H5Dclose(d);
    free(v);
    return ok ? 0 : -1;
}

/*
 * A write that fails inside HDF5 (the file-size limit is hit mid-run, as a full disk would) is
 * reported with the file and the dataset, and the writer refuses to go on. Closing it, with the
 * limit still there, keeps the .partial: every series cut back to its last whole row (a frame
 * whose position was written but not its orientation is gone), readable, the count and last time
 * in the message, and no file left open inside HDF5.
 */
TEST(error_disk_full_keeps_frames_so_far)
{
    enum { NP = 2000 }; /* a frame is ~112 KB: the limit is hit within a few frames */
    const char *path = tmp_path("full.h5"), *partial = tmp_path("full.h5.partial");
    pd_error err = {0};
    rh5_writer *w = NULL;
    int *shape = calloc(NP, sizeof *shape), *mat = calloc(NP, sizeof *mat);
    double *size = calloc(NP, sizeof *size), *mass = calloc(NP, sizeof *mass);
    double *pos = calloc(3 * NP, sizeof *pos), *q = calloc(4 * NP, sizeof *q);
    int unclosed = pd_results_unclosed();
    CHECK_EQ_INT(0, rh5_create(path, "{}", 0, 1e-3, 0, &w, &err));
    if (!w || !shape || !mat || !size || !mass || !pos || !q) goto out;
    CHECK_EQ_INT(0, rh5_add_shape(w, "cube", "mesh", CUBE_V, 8, CUBE_T, 12, 1, &err));
    CHECK_EQ_INT(0, rh5_add_wall(w, LID, WALL_V, 4, WALL_T, 2, LID_MOTION, &err)); /* moving */
    CHECK_EQ_INT(0, rh5_set_particles(w, NP, shape, mat, size, mass, &err));

    limit_file_size(512 * 1024);
    double wf[3] = {0, 0, 1};
    int rc = 0, frames = 0, stats = 0;
    double stage[RH5_NSTAGES] = {1, 1, 1, 1, 1};
    while (frames < 20 && rc == 0) {
        for (int k = 0; k < 3 * NP; k++)
            pos[k] = 1 + frames;
        for (int k = 0; k < 4 * NP; k++)
            q[k] = 1 + frames;
        rc = rh5_write_stats(w, 0.5 * stats, stats, 1 + stats, 0, 0, 0, 0, wf, stage, &err);
        if (rc == 0) stats++;
        if (rc == 0) rc = rh5_write_frame(w, 0.5 * frames, frames, pos, q, NULL, NULL, &err);
        if (rc == 0) frames++;
    }
    CHECK_EQ_INT(PD_EIO, rc);
    CHECK(frames >= 2 && frames < 20);
    CHECK_STR_CONTAINS(err.msg, path);
    CHECK_STR_CONTAINS(err.msg, "(hdf5: ");
    CHECK_STR_CONTAINS(err.msg, "File too large)"); /* the system's reason, from the stack */
    char first[sizeof err.msg];
    snprintf(first, sizeof first, "%s", err.msg);
    CHECK(rh5_broken(w));
    CHECK_EQ_INT(PD_EIO, rh5_write_frame(w, 99, 99, pos, q, NULL, NULL, &err));
    CHECK_STR_CONTAINS(err.msg, "an earlier write failed");

    unlimit_file_size();
    CHECK_EQ_INT(PD_EIO, rh5_close(w, &err));
    w = NULL;
    char kept[600];
    snprintf(kept, sizeof kept, "; the %d frames up to t = %.6g s are kept in '%s'", frames,
             0.5 * (frames - 1), partial);
    CHECK_STR_CONTAINS(err.msg, first); /* the failure restated, then what was kept */
    CHECK_STR_CONTAINS(err.msg, kept);
    CHECK(!exists(path));
    CHECK(!exists(tmp_path("full.h5.xmf")));
    CHECK_EQ_INT(unclosed, pd_results_unclosed());

    hid_t f = H5Fopen(partial, H5F_ACC_RDONLY, H5P_DEFAULT);
    CHECK(f >= 0);
    if (f >= 0) {
        CHECK_EQ_INT(frames, rows_of(f, "/frames/time"));
        CHECK_EQ_INT(frames, rows_of(f, "/frames/step"));
        CHECK_EQ_INT(frames, rows_of(f, "/frames/position"));
        CHECK_EQ_INT(frames, rows_of(f, "/frames/orientation"));
        CHECK_EQ_INT(stats, rows_of(f, "/stats/time"));
        CHECK_EQ_INT(stats, rows_of(f, "/stats/kinetic_energy"));
        CHECK_EQ_INT(stats, rows_of(f, "/stats/stage_time/gather"));
        CHECK_EQ_INT(stats, rows_of(f, "/stats/wall_force/" LID));
        CHECK_EQ_INT(frames, rows_of(f, "/walls/" LID "/frame_vertices"));
        CHECK_EQ_INT(0, rows_written(f, "/frames/position", frames, 3 * NP));
        CHECK_EQ_INT(0, rows_written(f, "/frames/orientation", frames, 4 * NP));
        CHECK_EQ_INT(0, rows_written(f, "/stats/kinetic_energy", stats, 1));
        char *fmt = attr_str(f, "/", "format", 0);
        CHECK_STR_CONTAINS(fmt, RH5_FORMAT);
        free(fmt);
        H5Fclose(f);
    }
out:
    rh5_abort(w);
    remove_result(path);
    free(shape);
    free(mat);
    free(size);
    free(mass);
    free(pos);
    free(q);
}

/* A write that fails before any frame leaves nothing to keep: the file is removed and the error
 * says so; no file is left open inside HDF5. */
TEST(error_disk_full_before_a_frame_discards)
{
    const char *path = tmp_path("none.h5");
    pd_error err = {0};
    struct stat st;
    int unclosed = pd_results_unclosed();
    rh5_writer *w = begin_writer(path, RH5_VELOCITY, &err);
    if (!w) return;
    CHECK_EQ_INT(0, stat(tmp_path("none.h5.partial"), &st));
    limit_file_size((rlim_t)st.st_size);
    double pos[3 * N] = {0}, q[4 * N] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};
    int rc = rh5_write_frame(w, 0, 0, pos, q, pos, NULL, &err); /* its chunks need new space */
    unlimit_file_size();
    CHECK_EQ_INT(PD_EIO, rc);
    CHECK_EQ_INT(PD_EIO, rh5_close(w, &err));
    CHECK_STR_CONTAINS(err.msg, "; result discarded: no frame had been written");
    CHECK(!exists(path));
    CHECK(!exists(tmp_path("none.h5.partial")));
    CHECK_EQ_INT(unclosed, pd_results_unclosed());
}

/* Every frame written, but the status attribute does not fit (a long status_message on a full
 * disk): the frames are kept in the .partial, and the error says why it has no status. */
TEST(error_disk_full_at_status_keeps_frames)
{
    const char *path = tmp_path("status.h5"), *partial = tmp_path("status.h5.partial");
    pd_error err = {0};
    rh5_writer *w = begin_writer(path, RH5_VELOCITY, &err);
    if (!w) return;
    double pos[3 * N] = {0}, q[4 * N] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};
    for (int f = 0; f < 3; f++)
        CHECK_EQ_INT(0, rh5_write_frame(w, 0.25 * f, f, pos, q, pos, NULL, &err));
    struct stat st;
    CHECK_EQ_INT(0, stat(partial, &st));
    char *why = malloc(20000);
    if (!why) {
        rh5_abort(w);
        return;
    }
    memset(why, 'x', 19999);
    why[19999] = 0;
    limit_file_size((rlim_t)st.st_size);
    CHECK_EQ_INT(PD_EIO, rh5_finish(w, "failed", why, &err));
    unlimit_file_size();
    free(why);
    CHECK_STR_CONTAINS(err.msg, "cannot write the root attribute 'status'");
    char kept[300];
    snprintf(kept, sizeof kept, "; the 3 frames up to t = 0.5 s are kept in '%s'", partial);
    CHECK_STR_CONTAINS(err.msg, kept);
    CHECK(!exists(path));
    hid_t f = H5Fopen(partial, H5F_ACC_RDONLY, H5P_DEFAULT);
    CHECK(f >= 0);
    if (f >= 0) {
        CHECK_EQ_INT(3, rows_of(f, "/frames/time"));
        CHECK_EQ_INT(3, rows_of(f, "/frames/velocity"));
        H5Fclose(f);
    }
    remove_result(path);
}

int main(void)
{
    snprintf(tmpdir, sizeof tmpdir, "/tmp/test_result_h5.XXXXXX");
    if (!mkdtemp(tmpdir)) {
        perror("mkdtemp");
        return 1;
    }
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL); /* the checks print the failures */
    RUN(roundtrip_hdf5);
    RUN(xdmf_file);
    RUN(without_optional_fields);
    RUN(abort_leaves_nothing);
    RUN(error_missing_directory);
    RUN(error_bad_file_name);
    RUN(error_frame_before_particles);
    RUN(error_bad_input_keeps_writer_usable);
    RUN(error_disk_full_keeps_frames_so_far);
    RUN(error_disk_full_before_a_frame_discards);
    RUN(error_disk_full_at_status_keeps_frames);
    if (rmdir(tmpdir) != 0) printf("  warning: %s not empty\n", tmpdir);
    return TEST_DONE();
}
