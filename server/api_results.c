/* api_results.c - a finished job's result file, its XDMF, and data read from it. */
#include "api.h"

#include "result_read.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/*
 * Finds job id; when it has a result (it succeeded, or stopped early with its frames so far kept:
 * the file's root attribute status says which), 0 with its result file in path. Otherwise queues
 * 404 or 409 (and *ret) and returns 1; *running tells whether the job is running (may be NULL).
 */
static int result_of(http_req *r, const char *id, char *path, size_t cap, int *running,
                     enum MHD_Result *ret)
{
    job_rec j;
    int rc = job_store_get(r->app->st, id, r->owner, &j);
    if (running) *running = 0;
    if (rc == JS_NOTFOUND) {
        *ret = http_error(r, 404, "job_not_found", "no job '%.40s'", id);
        return 1;
    }
    if (rc != JS_OK) {
        *ret = http_error(r, 500, "database", "the job database failed (see the server log)");
        return 1;
    }
    int queued = !strcmp(j.status, "queued"), run = !strcmp(j.status, "running");
    int ok = !queued && !run && j.result; /* a requeued job's old path is not kept */
    if (ok) {
        snprintf(path, cap, "%s/%s", r->app->cfg->data, j.result);
    } else {
        if (running) *running = run;
        if (!running || !run)
            *ret = http_error(r, 409, "result_not_ready",
                              queued || run ? "job '%s' is %s: its result is served once it has "
                                              "succeeded"
                                            : "job '%s' %s: it has no result",
                              id, j.status);
    }
    job_rec_free(&j);
    return !ok;
}

enum MHD_Result api_job_result(http_req *r, const char *id, int xmf)
{
    char path[4400], name[64];
    enum MHD_Result ret;
    if (result_of(r, id, path, sizeof path - 8, NULL, &ret)) return ret;
    if (xmf) {
        strcat(path, ".xmf");
        snprintf(name, sizeof name, "%s.h5.xmf", id);
        return files_send(r, path, "application/xml", name);
    }
    snprintf(name, sizeof name, "%s.h5", id);
    return files_send(r, path, "application/x-hdf5", name);
}

static enum MHD_Result read_failed(http_req *r, const char *msg)
{
    return http_error(r, 500, "result_unreadable", "%s", msg);
}

enum MHD_Result api_job_stats(http_req *r, const char *id)
{
    char path[4400], msg[256];
    int running;
    enum MHD_Result ret;
    if (result_of(r, id, path, sizeof path, &running, &ret)) {
        if (!running) return ret;
        /* while it runs: the samples of its progress records, kept by the worker */
        json_t *live = worker_live_stats(r->app->w, id);
        if (live) return http_json(r, 200, live);
        /* it has just ended: answer from its new state */
        if (result_of(r, id, path, sizeof path, NULL, &ret)) return ret;
    }
    json_t *o = result_stats(path, msg, sizeof msg);
    return o ? http_json(r, 200, o) : read_failed(r, msg);
}

enum MHD_Result api_job_frames(http_req *r, const char *id, const char *k)
{
    char path[4400], msg[256];
    enum MHD_Result ret;
    long long frame = 0;
    if (k) {
        char *end;
        errno = 0;
        frame = strtoll(k, &end, 10);
        if (errno || end == k || *end)
            return http_error(r, 400, "invalid_parameter",
                              "frame: '%.40s' is not an integer (0 is the first frame, -1 the "
                              "last)",
                              k);
    }
    if (result_of(r, id, path, sizeof path, NULL, &ret)) return ret;
    if (!k) {
        json_t *o = result_frames(path, msg, sizeof msg);
        return o ? http_json(r, 200, o) : read_failed(r, msg);
    }
    int range;
    json_t *o = result_frame(path, frame, &range, msg, sizeof msg);
    if (o) return http_json(r, 200, o);
    if (range) return http_error(r, 404, "frame_not_found", "no frame %lld: %s", frame, msg);
    return read_failed(r, msg);
}

enum MHD_Result api_job_shapes(http_req *r, const char *id)
{
    char path[4400], msg[256];
    enum MHD_Result ret;
    if (result_of(r, id, path, sizeof path, NULL, &ret)) return ret;
    json_t *o = result_shapes(path, msg, sizeof msg);
    return o ? http_json(r, 200, o) : read_failed(r, msg);
}
