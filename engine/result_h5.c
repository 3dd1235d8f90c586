/*
 * result_h5.c - the HDF5 result file of a run and its XDMF companion (layout in result_h5.h).
 *
 * Every HDF5 call is checked; a failure becomes a pd_error naming the file and the object, with
 * the innermost message of HDF5's error stack appended (HDF5's own printing is switched off).
 * Frames and stats rows are appended to chunked datasets whose first axis is unlimited, and the
 * file is flushed after each, so a crashed run leaves a readable "<path>.partial" up to its last
 * row; a run whose write fails leaves one too, cut back to its last whole frame and stats row
 * (finish_broken). The XDMF file is written at close, when the number of frames is known.
 */
#define _GNU_SOURCE /* flock(2), memfd_create(2) */
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <hdf5.h>

#include "result_h5.h"

#define NAME_MAX_LEN 255 /* bytes of a shape or wall name (scenario.h: 63 UTF-8 characters) */

/* One extendible dataset: rows of shape tail[0] x tail[1] (rank - 1 of them) appended along F. */
typedef struct rh5_ext {
    hid_t id;
    hid_t mtype; /* memory type of a row */
    int rank;
    hsize_t tail[2];
    char path[NAME_MAX_LEN + 32];
} rh5_ext;

typedef struct rh5_shape {
    char *name;
    double *verts; /* 3*nv, kept for the world-space meshes */
    int *tris;     /* 3*nt */
    int nv, nt;
} rh5_shape;

typedef struct rh5_wall {
    char *name;
    rh5_ext force;    /* /stats/wall_force/<name> */
    double motion[9]; /* velocity, angular_velocity, center (rh5_add_wall) */
    int moving, nv, nt;
    double *verts; /* 3*nv at t=0, kept for frame_vertices when it moves */
    rh5_ext frame; /* /walls/<name>/frame_vertices when it moves */
} rh5_wall;

enum { F_TIME, F_STEP, F_POS, F_QUAT, F_VEL, F_ANGVEL, F_MESH, NFRAME_DS };
enum { S_TIME, S_STEP, S_KE, S_CONTACTS, S_BROAD, S_RATIO, S_WALL_TIME, NSTATS_DS };

/* /stats/stage_time/<name>, in the order of rh5_write_stats' stage_time (sim.h's SIM_* stages) */
static const char *const stage_names[RH5_NSTAGES] = {"integrate", "bvh", "traverse", "contacts",
                                                     "gather"};

struct rh5_writer {
    char *path, *partial;
    int lock_fd;      /* the .partial, open and flock()ed while this writer owns it; -1 when not */
    const char *base; /* file name of path, how the XDMF file refers to it */
    hid_t file;
    int fields;
    rh5_shape *shapes;
    int nshapes, shapes_cap;
    rh5_wall *walls;
    int nwalls, walls_cap;
    int n;       /* particles; 0 until rh5_set_particles */
    int *pshape; /* copies of the particles' shapes and sizes, for the meshes */
    double *psize;
    int mesh_nv, mesh_nt; /* world-space mesh totals; 0 without RH5_SHAPE_MESHES */
    double *world;        /* 3*mesh_nv scratch */
    double *wall_world;   /* 3 * (the most vertices of a moving wall) scratch */
    int wall_size;        /* length of /xdmf/wall_size: the most vertices of a wall */
    rh5_ext fr[NFRAME_DS], st[NSTATS_DS], stage[RH5_NSTAGES];
    long long nframes, nstats;
    double *times; /* frame times, for the XDMF file */
    size_t times_cap;
    int broken;   /* a write failed: the file no longer follows the contract */
    pd_error why; /* the failure that broke it (rh5_finish restates it) */
};

/* ---- errors -------------------------------------------------------------------------------- */

/*
 * Keeps the innermost entry of HDF5's error stack, shortened: its descriptions run on with
 * timestamps and buffer addresses ("file write failed: time = ..., errno = 27, error message =
 * 'File too large', buf = 0x...") where the first phrase and the system's message tell the story.
 */
static herr_t first_desc(unsigned n, const H5E_error2_t *e, void *data)
{
    if (n != 0 || !e->desc) return 0;
    char *out = data;
    const char *colon = strchr(e->desc, ':'), *sys = strstr(e->desc, "error message = '");
    int len = colon ? (int)(colon - e->desc) : (int)strlen(e->desc);
    if (sys) {
        sys += strlen("error message = '");
        const char *end = strchr(sys, '\'');
        snprintf(out, 200, "%.*s: %.*s", len, e->desc, end ? (int)(end - sys) : 60, sys);
    } else {
        snprintf(out, 200, "%.*s", len, e->desc);
    }
    return 0;
}

static int vh5fail(const rh5_writer *w, pd_error *err, const char *fmt, va_list ap)
{
    char what[320], why[200] = "";
    vsnprintf(what, sizeof what, fmt, ap);
    H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, first_desc, why);
    if (why[0]) return pd_error_set(err, PD_EIO, "%s: %s (hdf5: %s)", w->path, what, why);
    return pd_error_set(err, PD_EIO, "%s: %s", w->path, what);
}

/* Reports a failed HDF5 call: "<path>: <what> (hdf5: <innermost error>)". */
#if defined(__GNUC__)
__attribute__((format(printf, 3, 4)))
#endif
static int
h5fail(const rh5_writer *w, pd_error *err, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int rc = vh5fail(w, err, fmt, ap);
    va_end(ap);
    return rc;
}

/* h5fail for a failed append: the writer is broken from then on, and keeps the message for
 * rh5_finish. */
#if defined(__GNUC__)
__attribute__((format(printf, 3, 4)))
#endif
static int
h5break(rh5_writer *w, pd_error *err, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int rc = vh5fail(w, &w->why, fmt, ap);
    va_end(ap);
    w->broken = 1;
    if (err) *err = w->why;
    return rc;
}

/* HDF5 prints its error stack by default, per thread in a thread-safe build; every entry point
 * silences it for its own thread since the writer may move between threads. */
static void quiet(void)
{
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
}

static char *dupstr(const char *s)
{
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    if (d) memcpy(d, s, n);
    return d;
}

/* Grows *p (elements of size elem) to hold at least need elements. */
static int grow(void **p, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap) return 0;
    size_t ncap = *cap ? *cap : 16;
    while (ncap < need)
        ncap *= 2;
    void *np = realloc(*p, ncap * elem);
    if (!np) return -1;
    *p = np;
    *cap = ncap;
    return 0;
}

/* ---- attributes and datasets --------------------------------------------------------------- */

static hid_t str_type(void)
{
    hid_t t = H5Tcopy(H5T_C_S1);
    if (t < 0) return t;
    if (H5Tset_size(t, H5T_VARIABLE) < 0 || H5Tset_cset(t, H5T_CSET_UTF8) < 0) {
        H5Tclose(t);
        return -1;
    }
    return t;
}

/* Writes attribute `name` on obj: a list of n strings, or one scalar string when n < 0. */
static int put_strs(hid_t obj, const char *name, const char *const *s, int n)
{
    hsize_t dim = n < 0 ? 1 : (hsize_t)n;
    hid_t t = str_type();
    hid_t sp = n < 0 ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &dim, NULL);
    hid_t a = t >= 0 && sp >= 0 ? H5Acreate2(obj, name, t, sp, H5P_DEFAULT, H5P_DEFAULT) : -1;
    int ok = a >= 0 && H5Awrite(a, t, s) >= 0;
    if (a >= 0 && H5Aclose(a) < 0) ok = 0;
    if (sp >= 0 && H5Sclose(sp) < 0) ok = 0;
    if (t >= 0 && H5Tclose(t) < 0) ok = 0;
    return ok ? 0 : -1;
}

static int put_str(hid_t obj, const char *name, const char *s)
{
    return put_strs(obj, name, &s, -1);
}

/* Writes a scalar numeric attribute. */
static int put_num(hid_t obj, const char *name, hid_t ftype, hid_t mtype, const void *v)
{
    hid_t sp = H5Screate(H5S_SCALAR);
    hid_t a = sp >= 0 ? H5Acreate2(obj, name, ftype, sp, H5P_DEFAULT, H5P_DEFAULT) : -1;
    int ok = a >= 0 && H5Awrite(a, mtype, v) >= 0;
    if (a >= 0 && H5Aclose(a) < 0) ok = 0;
    if (sp >= 0 && H5Sclose(sp) < 0) ok = 0;
    return ok ? 0 : -1;
}

static hid_t file_type(hid_t mtype)
{
    if (H5Tequal(mtype, H5T_NATIVE_INT) > 0) return H5T_STD_I32LE;
    if (H5Tequal(mtype, H5T_NATIVE_LLONG) > 0) return H5T_STD_I64LE;
    return H5T_IEEE_F64LE;
}

/* Creates group `path` (absolute); tracks creation order so readers list shapes and walls in the
 * order they were added. */
static int make_group(rh5_writer *w, const char *path, pd_error *err)
{
    hid_t pl = H5Pcreate(H5P_GROUP_CREATE);
    int ok = pl >= 0 && H5Pset_link_creation_order(pl, H5P_CRT_ORDER_TRACKED) >= 0;
    hid_t g = ok ? H5Gcreate2(w->file, path, H5P_DEFAULT, pl, H5P_DEFAULT) : -1;
    ok = g >= 0;
    if (g >= 0 && H5Gclose(g) < 0) ok = 0;
    if (pl >= 0 && H5Pclose(pl) < 0) ok = 0;
    return ok ? 0 : h5fail(w, err, "cannot create group %s", path);
}

/*
 * Creates dataset `path` of d0 (x d1 when d1 > 0) elements of mtype, writes data whole and its
 * units. When keep is non-NULL the open dataset is returned there for more attributes.
 */
static int put_data(rh5_writer *w, const char *path, hid_t mtype, hsize_t d0, hsize_t d1,
                    const void *data, const char *units, hid_t *keep, pd_error *err)
{
    hsize_t dims[2] = {d0, d1};
    hid_t sp = H5Screate_simple(d1 > 0 ? 2 : 1, dims, NULL);
    hid_t ds = sp >= 0 ? H5Dcreate2(w->file, path, file_type(mtype), sp, H5P_DEFAULT, H5P_DEFAULT,
                                    H5P_DEFAULT)
                       : -1;
    if (ds < 0) {
        int rc = h5fail(w, err, "cannot create dataset %s", path);
        if (sp >= 0) H5Sclose(sp);
        return rc;
    }
    /* An empty dataset (a shape without triangles) has nothing to write. */
    int ok = d0 * (d1 > 0 ? d1 : 1) == 0 ||
             H5Dwrite(ds, mtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) >= 0;
    ok = ok && put_str(ds, "units", units) == 0;
    int rc = ok ? PD_OK : h5fail(w, err, "cannot write dataset %s", path);
    if (keep && rc == PD_OK) {
        *keep = ds;
    } else if (H5Dclose(ds) < 0 && rc == PD_OK) {
        rc = h5fail(w, err, "cannot close dataset %s", path);
    }
    if (H5Sclose(sp) < 0 && rc == PD_OK) rc = h5fail(w, err, "cannot write dataset %s", path);
    return rc;
}

/*
 * Creates an empty extendible dataset: rank 1 (d1 = 0), 2 (d2 = 0) or 3. A chunk holds up to 256
 * rows and about 16 KiB (rows split along d1 past 32768 particles): a chunk per small frame would
 * cost an index entry per row, while big chunks are allocated whole and bloat short runs; a
 * frame of a large run is a few chunks of at most 1 MiB, HDF5's default chunk cache.
 */
static int make_ext(rh5_writer *w, rh5_ext *e, const char *path, hid_t mtype, hsize_t d1,
                    hsize_t d2, const char *units, pd_error *err)
{
    snprintf(e->path, sizeof e->path, "%s", path);
    e->mtype = mtype;
    e->rank = d1 == 0 ? 1 : d2 == 0 ? 2 : 3;
    e->tail[0] = d1;
    e->tail[1] = d2;
    hsize_t dims[3] = {0, d1, d2}, maxd[3] = {H5S_UNLIMITED, d1, d2};
    hsize_t chunk[3] = {1, d1 > 32768 ? 32768 : d1, d2};
    hsize_t row = 8;
    for (int k = 1; k < e->rank; k++)
        row *= chunk[k];
    chunk[0] = row >= 16384 ? 1 : 16384 / row > 256 ? 256 : 16384 / row;
    hid_t sp = H5Screate_simple(e->rank, dims, maxd);
    hid_t pl = H5Pcreate(H5P_DATASET_CREATE);
    int ok = sp >= 0 && pl >= 0 && H5Pset_chunk(pl, e->rank, chunk) >= 0;
    e->id = ok ? H5Dcreate2(w->file, path, file_type(mtype), sp, H5P_DEFAULT, pl, H5P_DEFAULT) : -1;
    int rc = e->id >= 0 ? PD_OK : h5fail(w, err, "cannot create dataset %s", path);
    if (rc == PD_OK && put_str(e->id, "units", units) < 0)
        rc = h5fail(w, err, "cannot write the units of %s", path);
    if (pl >= 0) H5Pclose(pl);
    if (sp >= 0) H5Sclose(sp);
    return rc;
}

/* Extends e to row + 1 rows and writes row `row` from data. */
static int append_row(const rh5_ext *e, hsize_t row, const void *data)
{
    hsize_t dims[3] = {row + 1, e->tail[0], e->tail[1]};
    hsize_t start[3] = {row, 0, 0}, count[3] = {1, e->tail[0], e->tail[1]};
    if (H5Dset_extent(e->id, dims) < 0) return -1;
    hid_t fs = H5Dget_space(e->id);
    hid_t ms = H5Screate_simple(e->rank, count, NULL);
    int ok = fs >= 0 && ms >= 0 &&
             H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, count, NULL) >= 0 &&
             H5Dwrite(e->id, e->mtype, ms, fs, H5P_DEFAULT, data) >= 0;
    if (ms >= 0 && H5Sclose(ms) < 0) ok = 0;
    if (fs >= 0 && H5Sclose(fs) < 0) ok = 0;
    return ok ? 0 : -1;
}

static int close_ext(rh5_ext *e)
{
    int ok = e->id < 0 || H5Dclose(e->id) >= 0;
    e->id = -1;
    return ok ? 0 : -1;
}

/* ---- setup --------------------------------------------------------------------------------- */

/* Checks a shape or wall name: an HDF5 link name of its own, unique among the `count` names
 * reached through `name_at`. */
static int check_name(const rh5_writer *w, const char *what, const char *name, int count,
                      const char *(*name_at)(const rh5_writer *, int), pd_error *err)
{
    if (!name || !name[0] || strlen(name) > NAME_MAX_LEN || strchr(name, '/') ||
        !strcmp(name, ".") || !strcmp(name, "..")) {
        return pd_error_set(err, PD_EINVAL,
                            "%s: bad %s name '%.*s' (1 to %d bytes, no '/', not '.' or '..')",
                            w->path, what, NAME_MAX_LEN, name ? name : "", NAME_MAX_LEN);
    }
    for (int i = 0; i < count; i++)
        if (!strcmp(name_at(w, i), name))
            return pd_error_set(err, PD_EINVAL, "%s: %s '%s' added twice", w->path, what, name);
    return PD_OK;
}

static const char *shape_name(const rh5_writer *w, int i)
{
    return w->shapes[i].name;
}
static const char *wall_name(const rh5_writer *w, int i)
{
    return w->walls[i].name;
}

/* Checks a triangle mesh's arrays: counts, pointers and indices. */
static int check_mesh(const rh5_writer *w, const char *what, const char *name, const double *verts,
                      int nv, const int *tris, int nt, pd_error *err)
{
    if (nv < 0 || nt < 0 || (nv > 0 && !verts) || (nt > 0 && !tris)) {
        return pd_error_set(err, PD_EINVAL,
                            "%s: %s '%s': bad mesh arrays (%d vertices, %d triangles)", w->path,
                            what, name, nv, nt);
    }
    for (long long k = 0; k < 3LL * nt; k++) {
        if (tris[k] < 0 || tris[k] >= nv) {
            return pd_error_set(err, PD_EINVAL, "%s: %s '%s': triangle %lld uses vertex %d of %d",
                                w->path, what, name, k / 3, tris[k], nv);
        }
    }
    return PD_OK;
}

/* Common refusals of the setup calls. */
static int check_setup(const rh5_writer *w, const char *call, pd_error *err)
{
    if (w->broken)
        return pd_error_set(err, PD_EIO, "%s: %s: an earlier write failed", w->path, call);
    if (w->n > 0)
        return pd_error_set(err, PD_EINVAL, "%s: %s after rh5_set_particles", w->path, call);
    return PD_OK;
}

/* Writes /<group>/<name>/{vertices,triangles} with the given vertex units. */
static int put_mesh(rh5_writer *w, const char *group, const char *name, const double *verts, int nv,
                    const int *tris, int nt, const char *vunits, hid_t *gout, pd_error *err)
{
    char p[NAME_MAX_LEN + 32];
    snprintf(p, sizeof p, "/%s/%s", group, name);
    int rc = make_group(w, p, err);
    if (rc != PD_OK) return rc;
    snprintf(p, sizeof p, "/%s/%s/vertices", group, name);
    rc = put_data(w, p, H5T_NATIVE_DOUBLE, (hsize_t)nv, 3, verts, vunits, NULL, err);
    snprintf(p, sizeof p, "/%s/%s/triangles", group, name);
    if (rc == PD_OK) rc = put_data(w, p, H5T_NATIVE_INT, (hsize_t)nt, 3, tris, "", NULL, err);
    if (rc == PD_OK && gout) {
        snprintf(p, sizeof p, "/%s/%s", group, name);
        *gout = H5Gopen2(w->file, p, H5P_DEFAULT);
        if (*gout < 0) rc = h5fail(w, err, "cannot open group %s", p);
    }
    return rc;
}

int rh5_add_shape(rh5_writer *w, const char *name, const char *kind, const double *verts, int nv,
                  const int *tris, int nt, double volume, pd_error *err)
{
    quiet();
    int rc = check_setup(w, "rh5_add_shape", err);
    if (rc == PD_OK) rc = check_name(w, "shape", name, w->nshapes, shape_name, err);
    if (rc == PD_OK && (!kind || (strcmp(kind, "mesh") && strcmp(kind, "sphere")))) {
        rc = pd_error_set(err, PD_EINVAL, "%s: shape '%s': kind '%s' is not \"mesh\" or \"sphere\"",
                          w->path, name, kind ? kind : "");
    }
    if (rc == PD_OK) rc = check_mesh(w, "shape", name, verts, nv, tris, nt, err);
    if (rc != PD_OK) return rc;

    size_t cap = (size_t)w->shapes_cap;
    if (grow((void **)&w->shapes, &cap, (size_t)w->nshapes + 1, sizeof *w->shapes))
        return pd_error_set(err, PD_ENOMEM, "%s: out of memory", w->path);
    w->shapes_cap = (int)cap;
    rh5_shape *s = &w->shapes[w->nshapes];
    s->name = dupstr(name);
    s->verts = malloc(3 * (size_t)nv * sizeof *s->verts + 1);
    s->tris = malloc(3 * (size_t)nt * sizeof *s->tris + 1);
    s->nv = nv;
    s->nt = nt;
    if (!s->name || !s->verts || !s->tris) {
        free(s->name);
        free(s->verts);
        free(s->tris);
        return pd_error_set(err, PD_ENOMEM, "%s: out of memory", w->path);
    }
    if (nv > 0) memcpy(s->verts, verts, 3 * (size_t)nv * sizeof *verts);
    if (nt > 0) memcpy(s->tris, tris, 3 * (size_t)nt * sizeof *tris);
    int index = w->nshapes++;

    hid_t g = -1;
    rc = put_mesh(w, "shapes", name, verts, nv, tris, nt, "1", &g, err);
    if (rc == PD_OK && (put_num(g, "volume", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &volume) < 0 ||
                        put_str(g, "kind", kind) < 0 ||
                        put_num(g, "index", H5T_STD_I32LE, H5T_NATIVE_INT, &index) < 0))
        rc = h5fail(w, err, "cannot write the attributes of /shapes/%s", name);
    if (g >= 0 && H5Gclose(g) < 0 && rc == PD_OK)
        rc = h5fail(w, err, "cannot close /shapes/%s", name);
    if (rc != PD_OK) w->broken = 1;
    return rc;
}

int rh5_add_wall(rh5_writer *w, const char *name, const double *verts, int nv, const int *tris,
                 int nt, const double *motion, pd_error *err)
{
    quiet();
    int rc = check_setup(w, "rh5_add_wall", err);
    if (rc == PD_OK) rc = check_name(w, "wall", name, w->nwalls, wall_name, err);
    if (rc == PD_OK) rc = check_mesh(w, "wall", name, verts, nv, tris, nt, err);
    if (rc != PD_OK) return rc;
    size_t cap = (size_t)w->walls_cap;
    if (grow((void **)&w->walls, &cap, (size_t)w->nwalls + 1, sizeof *w->walls))
        return pd_error_set(err, PD_ENOMEM, "%s: out of memory", w->path);
    w->walls_cap = (int)cap;
    rh5_wall *wl = &w->walls[w->nwalls];
    memset(wl, 0, sizeof *wl);
    if (!(wl->name = dupstr(name)))
        return pd_error_set(err, PD_ENOMEM, "%s: out of memory", w->path);
    wl->force.id = wl->frame.id = -1;
    wl->nv = nv;
    wl->nt = nt;
    for (int k = 0; k < 9 && motion; k++) {
        if (!isfinite(motion[k])) {
            free(wl->name);
            return pd_error_set(err, PD_EINVAL, "%s: wall '%s': motion value %d is not finite",
                                w->path, name, k);
        }
        wl->motion[k] = motion[k];
        wl->moving |= k < 6 && motion[k] != 0;
    }
    if (wl->moving && !(wl->verts = malloc(3 * (size_t)nv * sizeof *wl->verts))) {
        free(wl->name);
        return pd_error_set(err, PD_ENOMEM, "%s: out of memory", w->path);
    }
    if (wl->moving) memcpy(wl->verts, verts, 3 * (size_t)nv * sizeof *verts);
    w->nwalls++;
    rc = put_mesh(w, "walls", name, verts, nv, tris, nt, "m", NULL, err);
    static const char *const part[3] = {"velocity", "angular_velocity", "center"};
    static const char *const units[3] = {"m/s", "rad/s", "m"};
    for (int k = 0; k < 3 && rc == PD_OK; k++) {
        char p[NAME_MAX_LEN + 32];
        snprintf(p, sizeof p, "/walls/%s/%s", name, part[k]);
        rc = put_data(w, p, H5T_NATIVE_DOUBLE, 3, 0, wl->motion + 3 * k, units[k], NULL, err);
    }
    if (rc != PD_OK) w->broken = 1;
    return rc;
}

/* Writes /xdmf/triangles and /xdmf/particle (every particle's shape triangles, renumbered into
 * the world vertex array) and creates /xdmf/vertices. */
static int setup_meshes(rh5_writer *w, pd_error *err)
{
    long long nv = 0, nt = 0;
    for (int i = 0; i < w->n; i++) {
        nv += w->shapes[w->pshape[i]].nv;
        nt += w->shapes[w->pshape[i]].nt;
    }
    if (nv == 0 || nt == 0) return PD_OK; /* nothing to draw */
    if (3 * nv > INT_MAX || 3 * nt > INT_MAX) {
        return pd_error_set(err, PD_EINVAL,
                            "%s: shape meshes too large for the XDMF view (%lld vertices, %lld "
                            "triangles in all)",
                            w->path, nv, nt);
    }
    int *tris = malloc(3 * (size_t)nt * sizeof *tris), *owner = malloc((size_t)nt * sizeof *owner);
    w->world = malloc(3 * (size_t)nv * sizeof *w->world);
    int rc = PD_OK;
    if (!tris || !owner || !w->world) {
        rc = pd_error_set(err, PD_ENOMEM, "%s: out of memory for the shape meshes", w->path);
        goto done;
    }
    for (int i = 0, vb = 0, tb = 0; i < w->n; i++) {
        const rh5_shape *s = &w->shapes[w->pshape[i]];
        for (int t = 0; t < s->nt; t++, tb++) {
            for (int k = 0; k < 3; k++)
                tris[3 * tb + k] = vb + s->tris[3 * t + k];
            owner[tb] = i;
        }
        vb += s->nv;
    }
    w->mesh_nv = (int)nv;
    w->mesh_nt = (int)nt;
    rc = put_data(w, "/xdmf/triangles", H5T_NATIVE_INT, (hsize_t)nt, 3, tris, "", NULL, err);
    if (rc == PD_OK)
        rc = put_data(w, "/xdmf/particle", H5T_NATIVE_INT, (hsize_t)nt, 0, owner, "", NULL, err);
    if (rc == PD_OK)
        rc = make_ext(w, &w->fr[F_MESH], "/xdmf/vertices", H5T_NATIVE_DOUBLE, (hsize_t)nv, 3, "m",
                      err);
done:
    free(tris);
    free(owner);
    return rc;
}

/*
 * /xdmf/wall_size: zeros, as many as the largest wall has vertices. The XDMF file gives every
 * wall's points the particles' "size" attribute from it, so that ParaView's Glyph scaled by size
 * over a whole frame (a multiblock of particles and walls) draws nothing at the walls' corners
 * (without it, glyphs of the default scale sat on every corner).
 */
static int setup_wall_size(rh5_writer *w, pd_error *err)
{
    int most = 0;
    for (int i = 0; i < w->nwalls; i++)
        most = w->walls[i].nv > most ? w->walls[i].nv : most;
    if (most == 0) return PD_OK;
    double *z = calloc((size_t)most, sizeof *z);
    if (!z) return pd_error_set(err, PD_ENOMEM, "%s: out of memory", w->path);
    int rc = put_data(w, "/xdmf/wall_size", H5T_NATIVE_DOUBLE, (hsize_t)most, 0, z, "m", NULL, err);
    free(z);
    w->wall_size = most;
    return rc;
}

/* Creates the empty /frames and /stats datasets. */
static int setup_series(rh5_writer *w, pd_error *err)
{
    hsize_t n = (hsize_t)w->n;
    hid_t D = H5T_NATIVE_DOUBLE, L = H5T_NATIVE_LLONG;
    int rc = make_group(w, "/frames", err);
    if (!rc) rc = make_ext(w, &w->fr[F_TIME], "/frames/time", D, 0, 0, "s", err);
    if (!rc) rc = make_ext(w, &w->fr[F_STEP], "/frames/step", L, 0, 0, "", err);
    if (!rc) rc = make_ext(w, &w->fr[F_POS], "/frames/position", D, n, 3, "m", err);
    if (!rc) rc = make_ext(w, &w->fr[F_QUAT], "/frames/orientation", D, n, 4, "1", err);
    if (!rc && (w->fields & RH5_VELOCITY))
        rc = make_ext(w, &w->fr[F_VEL], "/frames/velocity", D, n, 3, "m/s", err);
    if (!rc && (w->fields & RH5_ANGULAR_VELOCITY))
        rc = make_ext(w, &w->fr[F_ANGVEL], "/frames/angular_velocity", D, n, 3, "rad/s", err);
    if (!rc) rc = make_group(w, "/stats", err);
    if (!rc) rc = make_ext(w, &w->st[S_TIME], "/stats/time", D, 0, 0, "s", err);
    if (!rc) rc = make_ext(w, &w->st[S_STEP], "/stats/step", L, 0, 0, "", err);
    if (!rc) rc = make_ext(w, &w->st[S_KE], "/stats/kinetic_energy", D, 0, 0, "J", err);
    if (!rc) rc = make_ext(w, &w->st[S_CONTACTS], "/stats/contacts", L, 0, 0, "1", err);
    if (!rc) rc = make_ext(w, &w->st[S_BROAD], "/stats/broad_pairs", L, 0, 0, "1", err);
    if (!rc) rc = make_ext(w, &w->st[S_RATIO], "/stats/max_overlap_ratio", D, 0, 0, "1", err);
    if (!rc) rc = make_ext(w, &w->st[S_WALL_TIME], "/stats/wall_time", D, 0, 0, "s", err);
    if (!rc) rc = make_group(w, "/stats/wall_force", err);
    for (int i = 0; i < w->nwalls && !rc; i++) {
        char p[NAME_MAX_LEN + 32];
        snprintf(p, sizeof p, "/stats/wall_force/%s", w->walls[i].name);
        rc = make_ext(w, &w->walls[i].force, p, D, 3, 0, "N", err);
    }
    int most = 0; /* vertices of the largest moving wall */
    for (int i = 0; i < w->nwalls && !rc; i++) {
        rh5_wall *wl = &w->walls[i];
        if (!wl->moving) continue;
        char p[NAME_MAX_LEN + 32];
        snprintf(p, sizeof p, "/walls/%s/frame_vertices", wl->name);
        rc = make_ext(w, &wl->frame, p, D, (hsize_t)wl->nv, 3, "m", err);
        most = wl->nv > most ? wl->nv : most;
    }
    if (!rc && most > 0 && !(w->wall_world = malloc(3 * (size_t)most * sizeof *w->wall_world)))
        rc = pd_error_set(err, PD_ENOMEM, "%s: out of memory for the moving walls", w->path);
    if (!rc) rc = make_group(w, "/stats/stage_time", err);
    for (int k = 0; k < RH5_NSTAGES && !rc; k++) {
        char p[64];
        snprintf(p, sizeof p, "/stats/stage_time/%s", stage_names[k]);
        rc = make_ext(w, &w->stage[k], p, D, 0, 0, "s", err);
    }
    return rc;
}

int rh5_set_particles(rh5_writer *w, int n, const int *shape, const int *material,
                      const double *size, const double *mass, pd_error *err)
{
    quiet();
    int rc = check_setup(w, "rh5_set_particles", err);
    if (rc != PD_OK) return rc;
    if (n < 1 || !shape || !material || !size || !mass) {
        return pd_error_set(err, PD_EINVAL, "%s: rh5_set_particles: bad arguments (%d particles)",
                            w->path, n);
    }
    for (int i = 0; i < n; i++) {
        if (shape[i] < 0 || shape[i] >= w->nshapes) {
            return pd_error_set(err, PD_EINVAL,
                                "%s: particle %d: shape index %d out of range (%d shapes)", w->path,
                                i, shape[i], w->nshapes);
        }
    }
    int *ids = malloc((size_t)n * sizeof *ids);
    const char **names = malloc((size_t)w->nshapes * sizeof *names);
    w->pshape = malloc((size_t)n * sizeof *w->pshape);
    w->psize = malloc((size_t)n * sizeof *w->psize);
    if (!ids || !names || !w->pshape || !w->psize) {
        free(w->pshape);
        free(w->psize);
        w->pshape = NULL;
        w->psize = NULL;
        rc = pd_error_set(err, PD_ENOMEM, "%s: out of memory for %d particles", w->path, n);
        goto done;
    }
    memcpy(w->pshape, shape, (size_t)n * sizeof *shape);
    memcpy(w->psize, size, (size_t)n * sizeof *size);
    for (int i = 0; i < n; i++)
        ids[i] = i;
    for (int i = 0; i < w->nshapes; i++)
        names[i] = w->shapes[i].name;
    w->n = n;

    hid_t ds = -1, g = -1;
    rc = make_group(w, "/particles", err);
    if (!rc)
        rc = put_data(w, "/particles/shape", H5T_NATIVE_INT, (hsize_t)n, 0, shape, "", &ds, err);
    if (!rc && put_strs(ds, "names", names, w->nshapes) < 0)
        rc = h5fail(w, err, "cannot write the shape names of /particles/shape");
    if (ds >= 0 && H5Dclose(ds) < 0 && !rc) rc = h5fail(w, err, "cannot close /particles/shape");
    if (!rc && ((g = H5Gopen2(w->file, "/shapes", H5P_DEFAULT)) < 0 ||
                put_strs(g, "names", names, w->nshapes) < 0))
        rc = h5fail(w, err, "cannot write the shape names of /shapes");
    if (g >= 0 && H5Gclose(g) < 0 && !rc) rc = h5fail(w, err, "cannot close /shapes");
    if (!rc)
        rc = put_data(w, "/particles/material", H5T_NATIVE_INT, (hsize_t)n, 0, material, "", NULL,
                      err);
    if (!rc)
        rc = put_data(w, "/particles/size", H5T_NATIVE_DOUBLE, (hsize_t)n, 0, size, "m", NULL, err);
    if (!rc)
        rc =
            put_data(w, "/particles/mass", H5T_NATIVE_DOUBLE, (hsize_t)n, 0, mass, "kg", NULL, err);
    if (!rc) rc = make_group(w, "/xdmf", err);
    if (!rc)
        rc = put_data(w, "/xdmf/particle_id", H5T_NATIVE_INT, (hsize_t)n, 0, ids, "", NULL, err);
    if (!rc && (w->fields & RH5_SHAPE_MESHES)) rc = setup_meshes(w, err);
    if (!rc) rc = setup_wall_size(w, err);
    if (!rc) rc = setup_series(w, err);
    if (!rc && H5Fflush(w->file, H5F_SCOPE_LOCAL) < 0) rc = h5fail(w, err, "cannot flush");
    if (rc != PD_OK) w->broken = 1;
done:
    free(ids);
    free(names);
    return rc;
}

/* ---- appending ----------------------------------------------------------------------------- */

/* Refusals of the append calls. */
static int check_append(const rh5_writer *w, const char *what, pd_error *err)
{
    if (w->broken)
        return pd_error_set(err, PD_EIO, "%s: cannot write %s: an earlier write failed", w->path,
                            what);
    if (w->n == 0) {
        return pd_error_set(err, PD_EINVAL,
                            "%s: cannot write %s: particle count unknown (rh5_set_particles first)",
                            w->path, what);
    }
    return PD_OK;
}

/* Every particle's shape mesh in world coordinates: R(q) (size v) + x. */
static int world_meshes(rh5_writer *w, const double *pos, const double *quat, pd_error *err)
{
    double *o = w->world;
    for (int i = 0; i < w->n; i++) {
        const rh5_shape *s = &w->shapes[w->pshape[i]];
        double r[3][3], sz = w->psize[i];
        const double *x = &pos[3 * i];
        if (pd_quat_to_matrix(&quat[4 * i], r) != PD_OK) {
            return pd_error_set(err, PD_EINVAL,
                                "%s: frame %lld: particle %d: zero orientation quaternion", w->path,
                                w->nframes, i);
        }
        for (int v = 0; v < s->nv; v++, o += 3) {
            const double *b = &s->verts[3 * v];
            for (int k = 0; k < 3; k++)
                o[k] = x[k] + sz * (r[k][0] * b[0] + r[k][1] * b[1] + r[k][2] * b[2]);
        }
    }
    return PD_OK;
}

/* A moving wall's vertices at time t (pd_wall_rotation): center + v t + R (p0 - center). */
static void wall_at(const rh5_wall *wl, double t, double *out)
{
    double q[4], r[3][3];
    const double *v = wl->motion, *c = wl->motion + 6;
    pd_wall_rotation(wl->motion + 3, t, q);
    pd_quat_to_matrix(q, r); /* a unit quaternion: cannot fail */
    for (int j = 0; j < wl->nv; j++) {
        const double *p = wl->verts + 3 * j;
        double d[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
        for (int k = 0; k < 3; k++)
            out[3 * j + k] = c[k] + v[k] * t + r[k][0] * d[0] + r[k][1] * d[1] + r[k][2] * d[2];
    }
}

int rh5_write_frame(rh5_writer *w, double time, long long step, const double *pos,
                    const double *quat, const double *vel, const double *angvel, pd_error *err)
{
    quiet();
    int rc = check_append(w, "a frame", err);
    if (rc != PD_OK) return rc;
    if (!pos || !quat || (!vel && (w->fields & RH5_VELOCITY)) ||
        (!angvel && (w->fields & RH5_ANGULAR_VELOCITY))) {
        return pd_error_set(err, PD_EINVAL,
                            "%s: frame %lld: position, orientation and the chosen fields "
                            "(velocity %s, angular_velocity %s) are required",
                            w->path, w->nframes, w->fields & RH5_VELOCITY ? "yes" : "no",
                            w->fields & RH5_ANGULAR_VELOCITY ? "yes" : "no");
    }
    if (w->fr[F_MESH].id >= 0 && (rc = world_meshes(w, pos, quat, err)) != PD_OK) return rc;
    if (grow((void **)&w->times, &w->times_cap, (size_t)w->nframes + 1, sizeof *w->times))
        return pd_error_set(err, PD_ENOMEM, "%s: out of memory", w->path);

    const void *data[NFRAME_DS] = {&time, &step, pos, quat, vel, angvel, w->world};
    for (int k = 0; k < NFRAME_DS; k++) {
        if (w->fr[k].id >= 0 && append_row(&w->fr[k], (hsize_t)w->nframes, data[k]) < 0)
            return h5break(w, err, "cannot append frame %lld to %s", w->nframes, w->fr[k].path);
    }
    for (int i = 0; i < w->nwalls; i++) {
        rh5_wall *wl = &w->walls[i];
        if (!wl->moving) continue;
        wall_at(wl, time, w->wall_world);
        if (append_row(&wl->frame, (hsize_t)w->nframes, w->wall_world) < 0)
            return h5break(w, err, "cannot append frame %lld to %s", w->nframes, wl->frame.path);
    }
    if (H5Fflush(w->file, H5F_SCOPE_LOCAL) < 0)
        return h5break(w, err, "cannot flush frame %lld", w->nframes);
    w->times[w->nframes++] = time;
    return PD_OK;
}

int rh5_write_stats(rh5_writer *w, double time, long long step, double kinetic_energy,
                    long long contacts, long long broad_pairs, double max_overlap_ratio,
                    double wall_time, const double *wall_forces, const double *stage_time,
                    pd_error *err)
{
    quiet();
    int rc = check_append(w, "stats", err);
    if (rc != PD_OK) return rc;
    if (w->nwalls > 0 && !wall_forces) {
        return pd_error_set(err, PD_EINVAL, "%s: stats row %lld: wall forces missing (%d walls)",
                            w->path, w->nstats, w->nwalls);
    }
    if (!stage_time) {
        return pd_error_set(err, PD_EINVAL, "%s: stats row %lld: stage times missing", w->path,
                            w->nstats);
    }
    const void *data[NSTATS_DS] = {
        &time, &step, &kinetic_energy, &contacts, &broad_pairs, &max_overlap_ratio, &wall_time};
    for (int k = 0; k < NSTATS_DS + w->nwalls; k++) {
        const rh5_ext *e = k < NSTATS_DS ? &w->st[k] : &w->walls[k - NSTATS_DS].force;
        const void *d = k < NSTATS_DS ? data[k] : &wall_forces[3 * (k - NSTATS_DS)];
        if (append_row(e, (hsize_t)w->nstats, d) < 0)
            return h5break(w, err, "cannot append stats row %lld to %s", w->nstats, e->path);
    }
    for (int k = 0; k < RH5_NSTAGES; k++) {
        if (append_row(&w->stage[k], (hsize_t)w->nstats, &stage_time[k]) < 0)
            return h5break(w, err, "cannot append stats row %lld to %s", w->nstats,
                           w->stage[k].path);
    }
    if (H5Fflush(w->file, H5F_SCOPE_LOCAL) < 0)
        return h5break(w, err, "cannot flush stats row %lld", w->nstats);
    w->nstats++;
    return PD_OK;
}

/* ---- lifecycle ----------------------------------------------------------------------------- */

/* Closes every HDF5 object and the file; 0 when all closed cleanly. */
/* Files whose H5Fclose failed (a full disk): HDF5 keeps them open, and its own exit-time
 * cleanup then crashes or loops on them (pd_results_unclosed). */
static int unclosed_files;

int pd_results_unclosed(void)
{
    return unclosed_files;
}

static int close_file(rh5_writer *w)
{
    int ok = 1;
    for (int k = 0; k < NFRAME_DS; k++)
        if (close_ext(&w->fr[k]) < 0) ok = 0;
    for (int k = 0; k < NSTATS_DS; k++)
        if (close_ext(&w->st[k]) < 0) ok = 0;
    for (int i = 0; i < w->nwalls; i++) {
        /* both, whatever the first gives */
        if (close_ext(&w->walls[i].force) < 0) ok = 0;
        if (close_ext(&w->walls[i].frame) < 0) ok = 0;
    }
    for (int k = 0; k < RH5_NSTAGES; k++)
        if (close_ext(&w->stage[k]) < 0) ok = 0;
    if (w->file >= 0 && H5Fclose(w->file) < 0) {
        ok = 0;
        unclosed_files++;
    }
    w->file = -1;
    return ok ? 0 : -1;
}

static void free_writer(rh5_writer *w)
{
    for (int i = 0; i < w->nshapes; i++) {
        free(w->shapes[i].name);
        free(w->shapes[i].verts);
        free(w->shapes[i].tris);
    }
    for (int i = 0; i < w->nwalls; i++) {
        free(w->walls[i].name);
        free(w->walls[i].verts);
    }
    free(w->wall_world);
    free(w->shapes);
    free(w->walls);
    free(w->pshape);
    free(w->psize);
    free(w->world);
    free(w->times);
    free(w->path);
    free(w->partial);
    if (w->lock_fd >= 0) close(w->lock_fd); /* releases the lock */
    free(w);
}

/* ---- keeping what a failed write leaves ---------------------------------------------------- */

/*
 * After a failed write (a full disk, mostly) the file on disk holds every frame and stats row up
 * to the last flushed, and perhaps part of the one being written: the datasets already extended
 * for it one row longer than the others, that row's chunks missing (read as zeros) or written.
 * rh5_finish (finish_broken) then:
 *  1. closes HDF5's session without writing anything more (close_detached): a close would retry
 *     the writes that failed, and cutting the datasets back in that session corrupts their chunk
 *     index (HDF5 1.10 dropped an earlier, flushed chunk);
 *  2. opens the file anew and cuts every series back to its last complete row (H5Dset_extent:
 *     nframes and nstats count only rows written to every dataset of their series and flushed);
 *     this rewrites object headers in place, which a full disk allows;
 *  3. opens it read-only, as a reader will, and checks it (check_kept): root attributes readable,
 *     every series exactly those rows with every chunk holding them stored, /frames/time the
 *     times written.
 * Only then is the file kept, under its .partial name: it is no complete result (it has no status
 * attribute and no XDMF file, which need the space that ran out). Otherwise it is removed.
 */

/* What a series dataset does with the rows it should have: cut to them, or check them. */
typedef int (*series_fn)(hid_t f, const rh5_ext *e, long long rows);

/* Applies fn to every /frames and /stats dataset; 0 when every call returned 0. */
static int each_series(const rh5_writer *w, hid_t f, series_fn fn)
{
    int rc = 0;
    for (int k = 0; k < NFRAME_DS && !rc; k++)
        if (w->fr[k].rank > 0) rc = fn(f, &w->fr[k], w->nframes);
    for (int i = 0; i < w->nwalls && !rc; i++) /* a moving wall's frame_vertices */
        if (w->walls[i].frame.rank > 0) rc = fn(f, &w->walls[i].frame, w->nframes);
    for (int k = 0; k < NSTATS_DS && !rc; k++)
        rc = fn(f, &w->st[k], w->nstats);
    for (int i = 0; i < w->nwalls && !rc; i++)
        rc = fn(f, &w->walls[i].force, w->nstats);
    for (int k = 0; k < RH5_NSTAGES && !rc; k++)
        rc = fn(f, &w->stage[k], w->nstats);
    return rc;
}

/* The shape of series dataset ds: 0 when it has e's rank and row shape and at least `rows` rows;
 * dims and, when chunk is not NULL, its chunk shape are filled in. */
static int series_shape(hid_t ds, const rh5_ext *e, long long rows, hsize_t dims[3],
                        hsize_t chunk[3])
{
    hid_t sp = H5Dget_space(ds), pl = chunk ? H5Dget_create_plist(ds) : -1;
    int ok = sp >= 0 && H5Sget_simple_extent_ndims(sp) == e->rank &&
             H5Sget_simple_extent_dims(sp, dims, NULL) == e->rank && dims[0] >= (hsize_t)rows &&
             (!chunk || (pl >= 0 && H5Pget_chunk(pl, e->rank, chunk) == e->rank));
    for (int k = 1; k < e->rank; k++)
        ok = ok && dims[k] == e->tail[k - 1];
    if (pl >= 0) H5Pclose(pl);
    if (sp >= 0) H5Sclose(sp);
    return ok ? 0 : -1;
}

static int cut_series(hid_t f, const rh5_ext *e, long long rows)
{
    hsize_t dims[3] = {0, 0, 0};
    hid_t ds = H5Dopen2(f, e->path, H5P_DEFAULT);
    int ok = ds >= 0 && series_shape(ds, e, rows, dims, NULL) == 0;
    dims[0] = (hsize_t)rows;
    ok = ok && H5Dset_extent(ds, dims) >= 0;
    if (ds >= 0 && H5Dclose(ds) < 0) ok = 0;
    return ok ? 0 : -1;
}

/* Exactly `rows` rows, and every chunk holding them stored: a chunk missing from the index reads
 * as zeros, it does not fail. The chunks are counted (one walk of the index; those past the rows
 * were cut); make_ext's chunks split rows along axis 1 only. */
static int check_series(hid_t f, const rh5_ext *e, long long rows)
{
    hsize_t dims[3] = {0, 0, 0}, chunk[3] = {1, 1, 1}, stored = 0;
    hid_t ds = H5Dopen2(f, e->path, H5P_DEFAULT), sp = ds >= 0 ? H5Dget_space(ds) : -1;
    int ok = sp >= 0 && series_shape(ds, e, rows, dims, chunk) == 0 && dims[0] == (hsize_t)rows &&
             H5Dget_num_chunks(ds, sp, &stored) >= 0;
    hsize_t cols = e->rank > 1 ? dims[1] : 1, step = e->rank > 1 ? chunk[1] : 1;
    ok = ok && stored == (dims[0] + chunk[0] - 1) / chunk[0] * ((cols + step - 1) / step);
    if (sp >= 0) H5Sclose(sp);
    if (ds >= 0 && H5Dclose(ds) < 0) ok = 0;
    return ok ? 0 : -1;
}

/* Opens the .partial in a new HDF5 session. The stdio driver: a session of the default (sec2)
 * driver would share the writer's when close_detached left that one open, while one of another
 * driver is its own. HDF5's file locking is off: our flock holds the file. */
static hid_t reopen(const rh5_writer *w, unsigned flags)
{
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS), f = -1;
    if (fapl >= 0 && H5Pset_fapl_stdio(fapl) >= 0 && H5Pset_file_locking(fapl, 0, 1) >= 0)
        f = H5Fopen(w->partial, flags, fapl);
    if (fapl >= 0) H5Pclose(fapl);
    return f;
}

/* Reads one root attribute whole (all of ours are scalars); for H5Aiterate2. */
static herr_t read_root_attr(hid_t obj, const char *name, const H5A_info_t *info, void *data)
{
    (void)info;
    (void)data;
    hid_t a = H5Aopen(obj, name, H5P_DEFAULT);
    hid_t t = a >= 0 ? H5Aget_type(a) : -1, sp = a >= 0 ? H5Aget_space(a) : -1;
    int ok = t >= 0 && sp >= 0 && H5Sget_simple_extent_npoints(sp) == 1;
    if (ok && H5Tis_variable_str(t) > 0) {
        char *s = NULL;
        ok = H5Aread(a, t, &s) >= 0 && s;
        if (s) H5free_memory(s);
    } else {
        unsigned char buf[64];
        ok = ok && H5Tget_size(t) <= sizeof buf && H5Aread(a, t, buf) >= 0;
    }
    if (sp >= 0) H5Sclose(sp);
    if (t >= 0) H5Tclose(t);
    if (a >= 0) H5Aclose(a);
    return ok ? 0 : -1;
}

/* What a reader finds in the closed .partial: its root attributes readable, every series as
 * counted (check_series), /frames/time the times written. 0 when all holds. */
static int check_kept(const rh5_writer *w)
{
    hid_t f = reopen(w, H5F_ACC_RDONLY);
    double *t = malloc((size_t)w->nframes * sizeof *t);
    hsize_t at = 0;
    int ok = f >= 0 && t &&
             H5Aiterate2(f, H5_INDEX_NAME, H5_ITER_NATIVE, &at, read_root_attr, NULL) >= 0 &&
             each_series(w, f, check_series) == 0;
    hid_t ds = ok ? H5Dopen2(f, "/frames/time", H5P_DEFAULT) : -1;
    ok = ds >= 0 && H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, t) >= 0 &&
         memcmp(t, w->times, (size_t)w->nframes * sizeof *t) == 0;
    if (ds >= 0) H5Dclose(ds);
    if (f >= 0 && H5Fclose(f) < 0) ok = 0;
    free(t);
    return ok ? 0 : -1;
}

/*
 * Ends the writer's HDF5 session without writing to the file: the file descriptor HDF5 holds is
 * first pointed at an anonymous memory file (dup2 over the one H5Fget_vfd_handle gives), where
 * the close writes what it still has. 0 when HDF5 no longer writes to the file: the session
 * closed, or failed to close (a file-size limit applies to the memory file too) but holds only
 * the memory file (counted by pd_results_unclosed); -1 when the descriptor could not be moved.
 */
static int close_detached(rh5_writer *w)
{
    int *fdp = NULL;
    int mem = w->file >= 0 ? memfd_create("rh5-detached", MFD_CLOEXEC) : -1;
    int moved =
        w->file < 0 || (mem >= 0 && H5Fget_vfd_handle(w->file, H5P_DEFAULT, (void **)&fdp) >= 0 &&
                        fdp && dup2(mem, *fdp) >= 0);
    if (mem >= 0) close(mem);
    close_file(w);
    return moved ? 0 : -1;
}

/* Steps 1-3 above: NULL when the file is kept, else why it is not. */
static const char *salvage(rh5_writer *w)
{
    /* The superblock may already give the file's new end while the writes that reach it failed:
     * HDF5 then refuses to open the file ("truncated file"). It is lengthened to that end with a
     * hole, which takes no space; what the failed writes left there is cut away or found missing
     * below. */
    hsize_t end = 0;
    if (w->file < 0 || H5Fget_filesize(w->file, &end) < 0) end = 0;
    if (close_detached(w) < 0) return "its HDF5 session could not be detached from it";
    if (w->nframes == 0) return "no frame had been written";
    struct stat st;
    if (fstat(w->lock_fd, &st) == 0 && (hsize_t)st.st_size < end &&
        ftruncate(w->lock_fd, (off_t)end) != 0)
        return "it could not be lengthened to the end its superblock gives";
    hid_t f = reopen(w, H5F_ACC_RDWR);
    int cut = f >= 0 && each_series(w, f, cut_series) == 0;
    if (f >= 0 && H5Fclose(f) < 0) {
        unclosed_files++; /* that session would write no more than the cut */
        cut = 0;
    }
    if (!cut) return "its datasets could not be cut back to the last whole row";
    if (check_kept(w) < 0) return "it could not be read back whole";
    return NULL;
}

/* rh5_finish after a failed write: keeps what it can, restating the failure and saying what
 * became of the frames. */
static int finish_broken(rh5_writer *w, pd_error *err)
{
    const char *why = w->why.msg[0] ? w->why.msg : "an earlier write failed";
    const char *lost = salvage(w);
    int rc;
    if (lost) {
        remove(w->partial);
        rc = pd_error_set(err, PD_EIO, "%s; result discarded: %s", why, lost);
    } else if (w->nframes == 1) {
        rc = pd_error_set(err, PD_EIO,
                          "%s; the 1 frame at t = %.6g s is kept in '%s' (incomplete, so not "
                          "renamed)",
                          why, w->times[0], w->partial);
    } else {
        rc = pd_error_set(err, PD_EIO,
                          "%s; the %lld frames up to t = %.6g s are kept in '%s' (incomplete, so "
                          "not renamed)",
                          why, w->nframes, w->times[w->nframes - 1], w->partial);
    }
    free_writer(w);
    return rc;
}

void rh5_abort(rh5_writer *w)
{
    if (!w) return;
    quiet();
    if (w->broken)
        close_detached(w); /* without retrying the writes that failed */
    else
        close_file(w);
    remove(w->partial);
    free_writer(w);
}

int rh5_create(const char *path, const char *scenario_json, int double_precision, double dt,
               int fields, rh5_writer **out, pd_error *err)
{
    quiet();
    if (out) *out = NULL;
    if (!path || !path[0] || !scenario_json || !out)
        return pd_error_set(err, PD_EINVAL, "rh5_create: missing path, scenario or result pointer");
    rh5_writer *w = calloc(1, sizeof *w);
    size_t len = strlen(path);
    if (w) {
        w->lock_fd = -1;
        w->path = dupstr(path);
        w->partial = malloc(len + sizeof ".partial");
    }
    if (!w || !w->path || !w->partial) {
        if (w) free_writer(w);
        return pd_error_set(err, PD_ENOMEM, "%s: out of memory", path);
    }
    memcpy(w->partial, path, len);
    memcpy(w->partial + len, ".partial", sizeof ".partial");
    const char *slash = strrchr(w->path, '/');
    w->base = slash ? slash + 1 : w->path;
    w->fields = fields;
    w->file = -1;
    for (int k = 0; k < NFRAME_DS; k++)
        w->fr[k].id = -1;
    for (int k = 0; k < NSTATS_DS; k++)
        w->st[k].id = -1;
    for (int k = 0; k < RH5_NSTAGES; k++)
        w->stage[k].id = -1;
    /* The XDMF file names the .h5 as "<base>:<dataset>|<selection>": an empty base or one with
     * ':' or '|' could not be referred to. */
    if (!w->base[0] || strpbrk(w->base, ":|")) {
        free_writer(w);
        return pd_error_set(err, PD_EINVAL,
                            "%s: bad result file name (not empty, no ':' or '|': the XDMF file "
                            "could not refer to it)",
                            path);
    }

    /*
     * Own the .partial before truncating it: another run writing the same result holds an
     * exclusive flock on it, and must keep its file (a second run used to truncate it, then
     * remove it on its own failure). The lock is taken on our own descriptor, kept until the
     * writer is freed; HDF5's own locking is switched off so that it does not trip over ours.
     * open(2) first also names the real cause of a failure (missing directory, permissions),
     * which HDF5's message buries.
     */
    w->lock_fd = open(w->partial, O_RDWR | O_CREAT | O_CLOEXEC, 0666);
    if (w->lock_fd < 0) {
        int rc = pd_error_set(err, PD_EIO, "%s: cannot create '%s': %s", path, w->partial,
                              strerror(errno));
        free_writer(w);
        return rc;
    }
    if (flock(w->lock_fd, LOCK_EX | LOCK_NB) != 0) {
        int busy = errno == EWOULDBLOCK;
        int rc = pd_error_set(err, PD_EIO, "%s: cannot lock '%s': %s", path, w->partial,
                              busy ? "another run is writing this result; choose another path"
                                   : strerror(errno));
        free_writer(w); /* not ours: left as it is */
        return rc;
    }
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
    if (fapl >= 0 && H5Pset_file_locking(fapl, 0, 1) >= 0)
        w->file = H5Fcreate(w->partial, H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
    if (fapl >= 0) H5Pclose(fapl);
    if (w->file < 0) {
        int rc = h5fail(w, err, "cannot create '%s'", w->partial);
        rh5_abort(w);
        return rc;
    }
    const char *prec = double_precision ? "double" : "single";
    int version = RH5_FORMAT_VERSION;
    int rc = PD_OK;
    if (put_str(w->file, "format", RH5_FORMAT) < 0 ||
        put_num(w->file, "format_version", H5T_STD_I32LE, H5T_NATIVE_INT, &version) < 0 ||
        put_str(w->file, "scenario", scenario_json) < 0 ||
        put_str(w->file, "precision", prec) < 0 ||
        put_num(w->file, "dt", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &dt) < 0)
        rc = h5fail(w, err, "cannot write the root attributes");
    if (!rc) rc = make_group(w, "/shapes", err);
    if (!rc) rc = make_group(w, "/walls", err);
    if (rc != PD_OK) {
        rh5_abort(w);
        return rc;
    }
    *out = w;
    return PD_OK;
}

long long rh5_frames(const rh5_writer *w)
{
    return w ? w->nframes : 0;
}

int rh5_broken(const rh5_writer *w)
{
    return w ? w->broken : 0;
}

int rh5_close(rh5_writer *w, pd_error *err)
{
    return rh5_finish(w, "complete", NULL, err);
}

int rh5_finish(rh5_writer *w, const char *status, const char *message, pd_error *err)
{
    if (!w) return pd_error_set(err, PD_EINVAL, "rh5_finish: no writer");
    quiet();
    if (w->broken) return finish_broken(w, err);
    int rc = PD_OK;
    if (w->n == 0)
        rc = pd_error_set(err, PD_EINVAL, "%s: result discarded: no particles were set", w->path);
    else if (!status || !status[0])
        rc = pd_error_set(err, PD_EINVAL, "%s: result discarded: no status given", w->path);
    else if (put_str(w->file, "status", status) < 0 ||
             (message && put_str(w->file, "status_message", message) < 0) ||
             H5Fflush(w->file, H5F_SCOPE_LOCAL) < 0) {
        /* every frame is written: a full disk here costs only the status */
        h5break(w, NULL, "cannot write the root attribute 'status'");
        return finish_broken(w, err);
    }
    if (close_file(w) < 0 && rc == PD_OK) rc = h5fail(w, err, "cannot close '%s'", w->partial);

    size_t len = strlen(w->path);
    char *xmf = malloc(len + sizeof ".xmf"), *xtmp = malloc(len + sizeof ".xmf.partial");
    if ((!xmf || !xtmp) && rc == PD_OK)
        rc = pd_error_set(err, PD_ENOMEM, "%s: out of memory", w->path);
    /* The XDMF file is derived from the result: failing to write it (a full disk: it is larger
     * than the result) must not cost the result itself, which is still renamed into place. */
    pd_error xerr = {0};
    int xrc = PD_OK;
    if (rc == PD_OK) {
        snprintf(xmf, len + sizeof ".xmf", "%s.xmf", w->path);
        snprintf(xtmp, len + sizeof ".xmf.partial", "%s.xmf.partial", w->path);
        rh5_xdmf_wall *xw = calloc((size_t)w->nwalls + 1, sizeof *xw);
        for (int i = 0; xw && i < w->nwalls; i++)
            xw[i] = (rh5_xdmf_wall){w->walls[i].name, w->walls[i].nv, w->walls[i].nt,
                                    w->walls[i].moving};
        rh5_xdmf x = {w->base,    w->path,    w->n,      w->fields, w->nframes,  w->times,
                      w->mesh_nv, w->mesh_nt, w->nwalls, xw,        w->wall_size};
        xrc = xw ? rh5_write_xdmf(xtmp, &x, &xerr)
                 : pd_error_set(&xerr, PD_ENOMEM, "%s: out of memory", w->path);
        free(xw);
    }
    int kept = 0; /* the result is whole, only its final name could not be given */
    if (rc == PD_OK && rename(w->partial, w->path) != 0) {
        kept = 1;
        rc = pd_error_set(err, PD_EIO,
                          "%s: cannot rename '%s' to it: %s; the whole result is kept as '%s'",
                          w->path, w->partial, strerror(errno), w->partial);
    }
    if (rc == PD_OK && xrc != PD_OK) {
        rc = pd_error_set(err, PD_EIO,
                          "%s: the result is complete and kept, but its XDMF file for ParaView "
                          "could not be written: %s",
                          w->path, xerr.msg);
    } else if (rc == PD_OK && rename(xtmp, xmf) != 0) {
        rc = pd_error_set(err, PD_EIO, "%s: cannot rename '%s' to '%s': %s", w->path, xtmp, xmf,
                          strerror(errno));
    }
    if (rc != PD_OK) {
        if (!kept) remove(w->partial);
        if (xtmp) remove(xtmp);
    }
    free(xmf);
    free(xtmp);
    free_writer(w);
    return rc;
}
