/* api_service.c - health, metrics, the device, mesh uploads. */
#include "api.h"

#include "polydem.h"
#include "util.h"

#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

enum MHD_Result api_healthz(http_req *r)
{
    int db = job_store_ping(r->app->st) == JS_OK;
    json_t *dev = worker_device_json(r->app->w);
    int state = worker_device_state(r->app->w);
    int ok = db && state == DEV_READY;
    json_t *msg = json_object_get(dev, "message");
    json_t *o = json_pack("{s:s, s:s, s:s, s:O*}", "status", ok ? "ok" : "unavailable", "database",
                          db ? "ok" : "failed", "device", worker_state_name(state), "message",
                          json_is_string(msg) ? msg : NULL);
    if (o && !db) json_object_set_new(o, "message", json_string("the job database fails"));
    json_decref(dev);
    return http_json(r, ok ? 200 : 503, o);
}

/* Appends printf-style text to a growing buffer; -1 when out of memory. */
static int put(char **buf, size_t *len, size_t *cap, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

static int put(char **buf, size_t *len, size_t *cap, const char *fmt, ...)
{
    for (;;) {
        va_list ap;
        va_start(ap, fmt);
        int n = vsnprintf(*buf + *len, *cap - *len, fmt, ap);
        va_end(ap);
        if (n < 0) return -1;
        if ((size_t)n < *cap - *len) {
            *len += (size_t)n;
            return 0;
        }
        char *nb = realloc(*buf, *cap * 2 + (size_t)n);
        if (!nb) return -1;
        *buf = nb;
        *cap = *cap * 2 + (size_t)n;
    }
}

enum MHD_Result api_metrics(http_req *r)
{
    app *a = r->app;
    long counts[JOB_NSTATUS];
    int db = job_store_count(a->st, counts) == JS_OK;
    size_t len = 0, cap = 4096;
    char *b = malloc(cap);
    int bad = !b;
    if (!bad) b[0] = 0;
    bad = bad || put(&b, &len, &cap,
                     "# HELP polydem_jobs Jobs in the database by status.\n"
                     "# TYPE polydem_jobs gauge\n");
    for (int i = 0; db && !bad && i < JOB_NSTATUS; i++)
        bad = put(&b, &len, &cap, "polydem_jobs{status=\"%s\"} %ld\n", job_status_names[i],
                  counts[i]);
    bad = bad ||
          put(&b, &len, &cap,
              "# HELP polydem_queue_length Jobs waiting for the device.\n"
              "# TYPE polydem_queue_length gauge\npolydem_queue_length %ld\n"
              "# HELP polydem_steps_per_second Time steps per wall-clock second of the running "
              "job (0 when idle).\n"
              "# TYPE polydem_steps_per_second gauge\npolydem_steps_per_second %.6g\n"
              "# HELP polydem_device_ready 1 when the device passed its self-test and takes "
              "jobs.\n"
              "# TYPE polydem_device_ready gauge\npolydem_device_ready %d\n"
              "# HELP polydem_database_up 1 when the job database answers.\n"
              "# TYPE polydem_database_up gauge\npolydem_database_up %d\n"
              "# HELP polydem_sse_streams Open event streams.\n"
              "# TYPE polydem_sse_streams gauge\npolydem_sse_streams %d\n"
              "# HELP polydem_http_requests_total HTTP requests answered, by status code.\n"
              "# TYPE polydem_http_requests_total counter\n",
              db ? counts[JOB_QUEUED] : 0L, worker_steps_per_second(a->w),
              worker_device_state(a->w) == DEV_READY, db, sse_count(a->hub));
    for (int c = 100; !bad && c < 600; c++) {
        long n = atomic_load(&a->requests_by_code[c]);
        if (n) bad = put(&b, &len, &cap, "polydem_http_requests_total{code=\"%d\"} %ld\n", c, n);
    }
    enum MHD_Result ret =
        bad ? http_error(r, 500, "internal", "out of memory")
            : http_text(r, 200, "text/plain; version=0.0.4; charset=utf-8", b, len);
    free(b);
    return ret;
}

enum MHD_Result api_device(http_req *r)
{
    static const char *const known[] = {"selftest", NULL};
    enum MHD_Result ret;
    if (http_args_only(r, known, &ret)) return ret;
    const char *t = http_arg(r, "selftest");
    if (t && strcmp(t, "0") && strcmp(t, "1") && strcmp(t, "true") && strcmp(t, "false"))
        return http_error(r, 400, "invalid_parameter", "selftest: '%.20s' is not 1 or 0", t);
    if (t && (!strcmp(t, "1") || !strcmp(t, "true")) && worker_selftest(r->app->w) != 0)
        return http_error(r, 409, "device_busy",
                          "the device is running a job or a self-test, or did not open; ask "
                          "again when it is idle");
    return http_json(r, 200, worker_device_json(r->app->w));
}

/* Replaces every occurrence of from in s (in place, to fits in from's length) with to. */
static void replace_all(char *s, const char *from, const char *to)
{
    size_t fl = strlen(from), tl = strlen(to);
    char *p;
    if (!fl || tl > fl) return;
    while ((p = strstr(s, from))) {
        memcpy(p, to, tl);
        memmove(p + tl, p + fl, strlen(p + fl) + 1);
    }
}

/* Writes data to a new file; 0 or -1 with errno. */
static int write_new(const char *path, const char *data, size_t n)
{
    int fd = open(path, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0640);
    if (fd < 0) return -1;
    size_t off = 0;
    while (off < n) {
        ssize_t w = write(fd, data + off, n - off);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) {
            int e = errno;
            close(fd);
            unlink(path);
            errno = e;
            return -1;
        }
        off += (size_t)w;
    }
    if (close(fd) != 0) {
        int e = errno;
        unlink(path);
        errno = e;
        return -1;
    }
    return 0;
}

enum MHD_Result api_meshes_upload(http_req *r)
{
    app *a = r->app;
    char hash[65], final_path[4400], tmp[4400], rnd[17];
    if (r->len == 0)
        return http_error(r, 400, "empty_body",
                          "the request body is empty: send an STL or OBJ file");
    util_sha256_hex(r->body, r->len, hash);
    snprintf(final_path, sizeof final_path, "%s/sha256:%s", a->meshes_dir, hash);
    struct stat st;
    int existed = stat(final_path, &st) == 0;
    const char *load = final_path;
    if (!existed) {
        if (util_random_hex(rnd, 8) != 0)
            return http_error(r, 500, "internal", "no random source for a temporary name");
        snprintf(tmp, sizeof tmp, "%s/.upload-%s", a->meshes_dir, rnd);
        if (write_new(tmp, r->body, r->len) != 0)
            return http_error(r, 500, "storage", "cannot store the mesh: %s", strerror(errno));
        load = tmp;
    }
    pd_mesh *m = NULL;
    pd_error err = {0};
    if (pd_mesh_load(load, &m, &err) != PD_OK) {
        if (!existed) unlink(tmp);
        replace_all(err.msg, load, "mesh");
        return http_error(r, 422, "invalid_mesh", "%s", err.msg);
    }
    if (!existed && rename(tmp, final_path) != 0) {
        int e = errno;
        unlink(tmp);
        pd_mesh_destroy(m);
        return http_error(r, 500, "storage", "cannot store the mesh: %s", strerror(e));
    }
    pd_mass_props mp;
    pd_mesh_mass_props(m, &mp);
    double lo[3], hi[3];
    for (int k = 0; k < 3; k++)
        lo[k] = hi[k] = m->nverts ? m->verts[k] : 0;
    for (int i = 0; i < m->nverts; i++)
        for (int k = 0; k < 3; k++) {
            double v = m->verts[3 * i + k];
            if (v < lo[k]) lo[k] = v;
            if (v > hi[k]) hi[k] = v;
        }
    char id[80];
    snprintf(id, sizeof id, "sha256:%s", hash);
    json_t *o =
        json_pack("{s:s, s:I, s:i, s:i, s:f, s:[f,f,f], s:{s:[f,f,f], s:[f,f,f]}}", "id", id,
                  "bytes", (json_int_t)r->len, "vertices", m->nverts, "triangles", m->ntris,
                  "volume", mp.volume, "centroid", mp.centroid[0], mp.centroid[1], mp.centroid[2],
                  "bounds", "min", lo[0], lo[1], lo[2], "max", hi[0], hi[1], hi[2]);
    pd_mesh_destroy(m);
    if (!existed) fprintf(stderr, "polydemd: mesh %s stored (%zu bytes)\n", id, r->len);
    return http_json(r, existed ? 200 : 201, o);
}
