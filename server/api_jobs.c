/* api_jobs.c - the job routes and the scenario dry run. */
#include "api.h"

#include "job_json.h"
#include "polydem.h"
#include "util.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* ---- submissions: the body of POST /v1/jobs and POST /v1/scenarios/validate ---------------- */

typedef struct submission {
    json_t *doc;         /* the parsed body */
    char *scenario_text; /* the scenario as stored: the body itself, or its "scenario" member */
    const char *prefix;  /* JSON pointer of the scenario in the body: "" or "/scenario" */
    json_t *tags;        /* an array of strings (owned) */
    long long priority;
    pd_scenario *s;
    pd_scenario_summary sum;
} submission;

static void submission_free(submission *sub)
{
    json_decref(sub->doc);
    json_decref(sub->tags);
    free(sub->scenario_text);
    pd_scenario_destroy(sub->s);
    memset(sub, 0, sizeof *sub);
}

static void detail(json_t *details, const char *prefix, const char *path, const char *msg)
{
    char full[768], m[512];
    snprintf(full, sizeof full, "%s%s", prefix, path);
    snprintf(m, sizeof m, "%s", msg);
    json_array_append_new(
        details, json_pack("{s:s, s:s}", "path", util_utf8_fix(full), "message", util_utf8_fix(m)));
}

static int valid_tag(const char *t)
{
    size_t n = strlen(t);
    if (n == 0 || n > 64) return 0;
    for (; *t; t++)
        if ((unsigned char)*t < 0x20 || *t == 0x7f) return 0;
    return 1;
}

/* The wrapper's own members: priority and tags. */
static void check_wrapper(submission *sub, json_t *details)
{
    const char *key;
    json_t *v;
    json_object_foreach(sub->doc, key, v)
    {
        char at[200], esc[160];
        http_pointer_escape(key, esc, sizeof esc);
        snprintf(at, sizeof at, "/%s", esc);
        if (!strcmp(key, "scenario")) {
            if (!json_is_object(v)) detail(details, "", at, "must be a scenario object");
        } else if (!strcmp(key, "priority")) {
            if (!json_is_integer(v) || json_integer_value(v) < -1000000 ||
                json_integer_value(v) > 1000000)
                detail(details, "", at, "must be an integer in [-1000000, 1000000]");
            else
                sub->priority = json_integer_value(v);
        } else if (!strcmp(key, "tags")) {
            if (!json_is_array(v) || json_array_size(v) > 32) {
                detail(details, "", at, "must be an array of at most 32 strings");
                continue;
            }
            size_t i;
            json_t *t;
            json_array_foreach(v, i, t)
            {
                char ti[240];
                snprintf(ti, sizeof ti, "%s/%zu", at, i);
                if (!json_is_string(t) || !valid_tag(json_string_value(t)))
                    detail(details, "", ti, "a tag is a string of 1 to 64 printable characters");
            }
            json_decref(sub->tags);
            sub->tags = json_incref(v);
        } else {
            detail(details, "", at,
                   "unknown member (a submission holds \"scenario\", \"priority\" and \"tags\")");
        }
    }
}

/* A mesh reference must name an uploaded mesh: "sha256:" and 64 hex digits, stored here. */
static void check_mesh_ref(http_req *r, json_t *obj, const char *at, const char *prefix,
                           json_t *details)
{
    json_t *m = json_is_object(obj) ? json_object_get(obj, "mesh") : NULL;
    if (!json_is_string(m)) return;
    const char *ref = json_string_value(m);
    char path[300], file[4400];
    snprintf(path, sizeof path, "%s/mesh", at);
    size_t n = strlen(ref);
    int ok = n == 71 && !strncmp(ref, "sha256:", 7);
    for (size_t i = 7; ok && i < n; i++)
        ok = (ref[i] >= '0' && ref[i] <= '9') || (ref[i] >= 'a' && ref[i] <= 'f');
    if (!ok) {
        detail(details, prefix, path,
               "the service takes meshes uploaded with POST /v1/meshes: use the \"sha256:...\" "
               "id it returns (file paths are not read)");
        return;
    }
    struct stat st;
    snprintf(file, sizeof file, "%s/%s", r->app->meshes_dir, ref);
    if (stat(file, &st) != 0) {
        char msg[200];
        snprintf(msg, sizeof msg, "mesh '%.80s' has not been uploaded (POST /v1/meshes)", ref);
        detail(details, prefix, path, msg);
    }
}

static void check_mesh_refs(http_req *r, json_t *scen, const char *prefix, json_t *details)
{
    json_t *shapes = json_object_get(scen, "shapes"), *walls = json_object_get(scen, "walls");
    const char *key;
    json_t *v;
    char at[200], esc[160];
    if (json_is_object(shapes)) {
        json_object_foreach(shapes, key, v)
        {
            http_pointer_escape(key, esc, sizeof esc);
            snprintf(at, sizeof at, "/shapes/%s", esc);
            check_mesh_ref(r, v, at, prefix, details);
        }
    }
    if (json_is_array(walls)) {
        size_t i;
        json_array_foreach(walls, i, v)
        {
            snprintf(at, sizeof at, "/walls/%zu", i);
            check_mesh_ref(r, v, at, prefix, details);
        }
    }
}

static enum MHD_Result invalid(http_req *r, json_t *details)
{
    size_t n = json_array_size(details);
    json_t *first = json_array_get(details, 0);
    char msg[900];
    snprintf(msg, sizeof msg, "the scenario has %zu problem%s; the first: %s: %s", n,
             n == 1 ? "" : "s", json_string_value(json_object_get(first, "path")),
             json_string_value(json_object_get(first, "message")));
    return http_error_details(r, 422, "invalid_scenario", msg, details);
}

/*
 * Parses and validates the request body as a submission. 0 with sub filled; 1 when an error
 * response was queued (its result in *ret).
 */
static int parse_submission(http_req *r, submission *sub, enum MHD_Result *ret)
{
    memset(sub, 0, sizeof *sub);
    sub->prefix = "";
    if (r->len == 0) {
        *ret = http_error(r, 400, "empty_body", "the request body is empty: send scenario JSON");
        return 1;
    }
    json_error_t je;
    /* any JSON value parses: a number, string or null is valid JSON that is not a scenario,
     * answered as an array is (422 at ""), not as unparseable (jansson's default refuses them
     * with "'[' or '{' expected") */
    sub->doc = json_loadb(r->body, r->len, JSON_DECODE_ANY, &je);
    if (!sub->doc) {
        *ret = http_error(r, 400, "invalid_json", "the body is not JSON: line %d, column %d: %s",
                          je.line, je.column, je.text);
        return 1;
    }
    json_t *details = json_array();
    sub->tags = json_array();
    if (!details || !sub->tags) {
        json_decref(details);
        submission_free(sub);
        *ret = http_error(r, 500, "internal", "out of memory");
        return 1;
    }
    json_t *scen = sub->doc;
    if (!json_is_object(sub->doc)) {
        detail(details, "", "", "a scenario is a JSON object");
        scen = NULL;
    } else if (json_object_get(sub->doc, "scenario")) {
        sub->prefix = "/scenario";
        check_wrapper(sub, details);
        scen = json_object_get(sub->doc, "scenario");
        if (!json_is_object(scen)) scen = NULL;
    }
    size_t before = json_array_size(details);
    if (scen) check_mesh_refs(r, scen, sub->prefix, details);
    /* a refused mesh reference must not reach the engine, which would open the file it names */
    if (json_array_size(details) > before) scen = NULL;
    if (scen == sub->doc)
        sub->scenario_text = strdup(r->body);
    else if (scen)
        sub->scenario_text = json_dumps(scen, JSON_INDENT(2) | JSON_REAL_PRECISION(17));
    if (scen && !sub->scenario_text) {
        json_decref(details);
        submission_free(sub);
        *ret = http_error(r, 500, "internal", "out of memory");
        return 1;
    }
    if (!scen) { /* not an object, or it names files: nothing more to check */
        submission_free(sub);
        *ret = invalid(r, details);
        return 1;
    }
    pd_diags diags = {0};
    pd_error err = {0};
    int rc = pd_scenario_parse(sub->scenario_text, r->app->meshes_dir, &sub->s, &diags, &err);
    /* diagnostics are the scenario's problems whatever the code (a scenario missing its
     * materials is reported with PD_ENOMEM by the engine today) */
    for (int i = 0; rc != PD_OK && i < diags.n; i++)
        detail(details, sub->prefix, diags.items[i].path, diags.items[i].msg);
    if (rc == PD_EINVAL && diags.n == 0) detail(details, sub->prefix, "", err.msg);
    int internal = rc != PD_OK && rc != PD_EINVAL && diags.n == 0;
    pd_diags_free(&diags);
    if (internal) {
        json_decref(details);
        submission_free(sub);
        *ret = http_error(r, 500, "internal", "scenario: %s", err.msg);
        return 1;
    }
    if (json_array_size(details) > 0) { /* the wrapper's, the mesh references' and the engine's */
        submission_free(sub);
        *ret = invalid(r, details);
        return 1;
    }
    pd_scenario_summarize(sub->s, &sub->sum);
    const config *cfg = r->app->cfg;
    char msg[300];
    if (sub->sum.particles > cfg->max_particles) {
        snprintf(msg, sizeof msg, "%ld particles exceed this server's limit of %ld (max_particles)",
                 sub->sum.particles, cfg->max_particles);
        detail(details, sub->prefix, "/particles", msg);
    }
    if (sub->sum.steps > cfg->max_steps) {
        snprintf(msg, sizeof msg, "%ld steps exceed this server's limit of %lld (max_steps)",
                 sub->sum.steps, cfg->max_steps);
        detail(details, sub->prefix, "/time/duration", msg);
    }
    if (json_array_size(details) > 0) {
        submission_free(sub);
        *ret = http_error_details(
            r, 422, "limit_exceeded",
            json_string_value(json_object_get(json_array_get(details, 0), "message")), details);
        return 1;
    }
    json_decref(details);
    return 0;
}

static json_t *summary_json(const pd_scenario_summary *m)
{
    return json_pack(
        "{s:I, s:i, s:i, s:i, s:o, s:o, s:I, s:o, s:o, s:o, s:o, s:o, s:I, s:o, s:b}", "particles",
        (json_int_t)m->particles, "shapes", m->shapes, "materials", m->materials, "walls", m->walls,
        "dt", job_json_real(m->dt), "duration", job_json_real(m->duration), "steps",
        (json_int_t)m->steps, "dt_rayleigh", job_json_real(m->dt_rayleigh), "dt_hertz",
        job_json_real(m->dt_hertz), "dt_stable", job_json_real(m->dt_stable), "memory_bytes",
        job_json_real(m->memory_bytes), "contact_resolution_m",
        job_json_real(m->contact_resolution), "frames", (json_int_t)m->frames, "mesh_view_bytes",
        job_json_real(m->mesh_view_bytes), "mesh_view_default", m->mesh_view_default);
}

enum MHD_Result api_validate(http_req *r)
{
    submission sub;
    enum MHD_Result ret;
    if (parse_submission(r, &sub, &ret)) return ret;
    json_t *o = json_pack("{s:b, s:s, s:o}", "valid", 1, "name", pd_scenario_name(sub.s), "summary",
                          summary_json(&sub.sum));
    submission_free(&sub);
    return http_json(r, 200, o);
}

/* ---- jobs ---------------------------------------------------------------------------------- */

static enum MHD_Result job_not_found(http_req *r, const char *id)
{
    return http_error(r, 404, "job_not_found", "no job '%.40s'", id);
}

static enum MHD_Result db_error(http_req *r)
{
    return http_error(r, 500, "database", "the job database failed (see the server log)");
}

/* Sends job id with status and a Location header; 404 when it is gone. */
static enum MHD_Result send_job(http_req *r, unsigned status, const char *id, int location)
{
    job_rec j;
    int rc = job_store_get(r->app->st, id, r->owner, &j);
    if (rc == JS_NOTFOUND) return job_not_found(r, id);
    if (rc != JS_OK) return db_error(r);
    json_t *o = job_json(&j);
    job_rec_free(&j);
    char loc[64];
    snprintf(loc, sizeof loc, "/v1/jobs/%s", id);
    return http_json_hdr(r, status, o, location ? "Location" : NULL, loc);
}

typedef struct insert_ctx {
    http_req *r;
    job_rec job;
    const char *scenario, *key, *hash;
    char existing[24];
    int rc;
    int full; /* the queue holds max_queued_jobs: nothing inserted */
} insert_ctx;

/* Whether the queue holds max_queued_jobs jobs; -1 when the database fails. */
static int queue_full(app *a)
{
    long counts[JOB_NSTATUS];
    if (job_store_count(a->st, counts) != JS_OK) return -1;
    return counts[JOB_QUEUED] >= a->cfg->max_queued;
}

static enum MHD_Result queue_full_answer(http_req *r)
{
    json_t *e = json_pack("{s:{s:s, s:s}}", "error", "code", "queue_full", "message",
                          "the queue is full (max_queued_jobs); retry later");
    return http_json_hdr(r, 429, e, "Retry-After", "30");
}

/*
 * Inserts the job and announces it, before the worker may claim it (worker_enqueue). The queue
 * limit is checked here too: every insert runs under the worker's lock, one at a time, whereas
 * submissions parsed side by side all passed the early check before any of them was inserted
 * (30 parallel POSTs against max_queued_jobs = 5 queued 7). A known idempotency key still gets
 * its job when the queue is full.
 */
static int insert_job(void *ctx)
{
    insert_ctx *c = ctx;
    app *a = c->r->app;
    if (c->key) {
        c->rc = job_store_idempotent(a->st, c->r->owner, c->key, c->hash, c->existing);
        if (c->rc != JS_NOTFOUND) return -1;
    }
    int full = queue_full(a);
    if (full) {
        c->full = full > 0;
        c->rc = JS_ERROR;
        return -1;
    }
    c->rc = job_store_insert(a->st, &c->job, c->scenario, c->key, c->hash, c->existing);
    if (c->rc != JS_OK) return -1;
    job_json_publish(c->r->app->hub, &c->job);
    return 0;
}

/* The answer to a known idempotency key (rc JS_EXISTS or JS_CONFLICT; anything else is a
 * database failure). */
static enum MHD_Result seen_key(http_req *r, int rc, const char *key, const char *existing)
{
    if (rc == JS_EXISTS) return send_job(r, 200, existing, 1);
    if (rc == JS_CONFLICT)
        return http_error(r, 422, "idempotency_key_reused",
                          "Idempotency-Key '%.100s' was used for another request body (job %s)",
                          key, existing);
    return db_error(r);
}

static int valid_key(const char *k)
{
    size_t n = strlen(k);
    if (n == 0 || n > 255) return 0;
    for (; *k; k++)
        if ((unsigned char)*k < 0x21 || (unsigned char)*k > 0x7e) return 0;
    return 1;
}

enum MHD_Result api_jobs_create(http_req *r)
{
    app *a = r->app;
    const char *key = MHD_lookup_connection_value(r->conn, MHD_HEADER_KIND, "Idempotency-Key");
    char hash[65], existing[24] = "";
    if (key && !valid_key(key))
        return http_error(r, 400, "invalid_header",
                          "Idempotency-Key must be 1 to 255 visible ASCII characters");
    util_sha256_hex(r->body, r->len, hash);
    if (key) {
        int rc = job_store_idempotent(a->st, r->owner, key, hash, existing);
        if (rc != JS_NOTFOUND) return seen_key(r, rc, key, existing);
    }
    /* refused before parsing the body; insert_job decides for submissions side by side */
    int full = queue_full(a);
    if (full < 0) return db_error(r);
    if (full) return queue_full_answer(r);
    submission sub;
    enum MHD_Result ret;
    if (parse_submission(r, &sub, &ret)) return ret;

    insert_ctx c = {
        .r = r, .scenario = sub.scenario_text, .key = key, .hash = hash, .rc = JS_ERROR};
    char *tags = json_dumps(sub.tags, JSON_COMPACT);
    if (util_random_hex(c.job.id, 8) != 0 || !tags) {
        free(tags);
        submission_free(&sub);
        return http_error(r, 500, "internal", "cannot make a job id");
    }
    snprintf(c.job.status, sizeof c.job.status, "queued");
    c.job.owner = (char *)r->owner;
    c.job.name = (char *)pd_scenario_name(sub.s);
    c.job.tags = tags;
    c.job.priority = sub.priority;
    util_now_iso(c.job.created_at);
    worker_enqueue(a->w, insert_job, &c);
    free(tags);
    if (c.rc == JS_OK)
        fprintf(stderr, "polydemd: job %s (%s) queued: %ld particles, %ld steps\n", c.job.id,
                pd_scenario_name(sub.s), sub.sum.particles, sub.sum.steps);
    submission_free(&sub);
    if (c.full) return queue_full_answer(r);
    if (c.rc != JS_OK) return seen_key(r, c.rc, key, c.existing);
    return send_job(r, 201, c.job.id, 1);
}

enum MHD_Result api_jobs_list(http_req *r)
{
    static const char *const known[] = {"status", "tag", "limit", "after", NULL};
    enum MHD_Result ret;
    if (http_args_only(r, known, &ret)) return ret;
    const char *status = http_arg(r, "status"), *tag = http_arg(r, "tag");
    const char *after = http_arg(r, "after"), *lim = http_arg(r, "limit");
    long limit = 50;
    if (status && job_status_index(status) < 0)
        return http_error(r, 400, "invalid_parameter",
                          "status: '%.40s' is none of queued, running, succeeded, failed, "
                          "cancelled",
                          status);
    if (tag && (!*tag || strlen(tag) > 64))
        return http_error(r, 400, "invalid_parameter", "tag: 1 to 64 characters");
    if (lim) {
        char *end;
        errno = 0;
        limit = strtol(lim, &end, 10);
        if (errno || end == lim || *end || limit < 1 || limit > 1000)
            return http_error(r, 400, "invalid_parameter",
                              "limit: '%.40s' is not an integer in [1, 1000]", lim);
    }
    if (after && (!*after || strlen(after) >= 24))
        return http_error(r, 400, "invalid_parameter", "after: no job '%.40s'", after);
    job_rec *jobs;
    int n, more;
    int rc = job_store_list(r->app->st, status, tag, after, r->owner, (int)limit, &jobs, &n, &more);
    if (rc == JS_NOTFOUND)
        return http_error(r, 400, "invalid_parameter", "after: no job '%.40s'", after);
    if (rc != JS_OK) return db_error(r);
    json_t *arr = json_array();
    for (int i = 0; arr && i < n; i++)
        json_array_append_new(arr, job_json(&jobs[i]));
    json_t *o = json_pack("{s:o, s:o}", "jobs", arr ? arr : json_array(), "next",
                          more && n > 0 ? json_string(jobs[n - 1].id) : json_null());
    job_store_list_free(jobs, n);
    return http_json(r, 200, o);
}

enum MHD_Result api_job_get(http_req *r, const char *id)
{
    return send_job(r, 200, id, 0);
}

enum MHD_Result api_job_scenario(http_req *r, const char *id)
{
    char *text;
    int rc = job_store_scenario(r->app->st, id, r->owner, &text);
    if (rc == JS_NOTFOUND) return job_not_found(r, id);
    if (rc != JS_OK) return db_error(r);
    enum MHD_Result ret = http_text(r, 200, "application/json", text, strlen(text));
    free(text);
    return ret;
}

enum MHD_Result api_job_cancel(http_req *r, const char *id)
{
    job_rec j;
    int rc = job_store_cancel(r->app->st, id, r->owner, &j);
    if (rc == JS_NOTFOUND) return job_not_found(r, id);
    if (rc == JS_ERROR) return db_error(r);
    enum MHD_Result ret;
    if (rc == JS_CONFLICT) {
        ret = http_error(r, 409, "job_finished", "job '%s' has already ended (%s)", id, j.status);
    } else {
        if (rc == JS_RUNNING) {
            worker_cancel(r->app->w, id);
            fprintf(stderr, "polydemd: job %s: cancel requested\n", id);
        } else {
            fprintf(stderr, "polydemd: job %s cancelled before it ran\n", id);
            job_json_publish_id(r->app->hub, r->app->st, id);
        }
        /* 202: a running job stops at the end of its current step; its status follows */
        ret = http_json(r, rc == JS_RUNNING ? 202 : 200, job_json(&j));
    }
    job_rec_free(&j);
    return ret;
}

enum MHD_Result api_job_delete(http_req *r, const char *id)
{
    char *result = NULL;
    int rc = job_store_delete(r->app->st, id, r->owner, &result);
    free(result);
    if (rc == JS_NOTFOUND) return job_not_found(r, id);
    if (rc == JS_CONFLICT)
        return http_error(r, 409, "job_active",
                          "job '%s' is queued or running: cancel it before deleting it", id);
    if (rc != JS_OK) return db_error(r);
    util_remove_job_files(r->app->results_dir, id);
    fprintf(stderr, "polydemd: job %s deleted\n", id);
    char data[64];
    snprintf(data, sizeof data, "{\"id\":\"%s\"}", id);
    sse_publish(r->app->hub, id, r->owner, "deleted", data, 1);
    struct MHD_Response *resp = MHD_create_response_from_buffer(0, NULL, MHD_RESPMEM_PERSISTENT);
    return http_queue(r, 204, resp);
}

/* ---- events -------------------------------------------------------------------------------- */

typedef struct snap_ctx {
    http_req *r;
    const char *id;
} snap_ctx;

static int job_snapshot(void *ctx, char **text, int *final)
{
    snap_ctx *c = ctx;
    *final = 0;
    if (!c->id) { /* all jobs: events from now on */
        *text = strdup(": polydemd job events\n\n");
        return *text ? 0 : -1;
    }
    job_rec j;
    if (job_store_get(c->r->app->st, c->id, c->r->owner, &j) != JS_OK) return -1;
    json_t *o = job_json(&j);
    json_t *p = json_object_get(o, "progress");
    json_t *ev = json_is_object(p) && !strcmp(j.status, "running")
                     ? json_pack("{s:s, s:O}", "id", j.id, "progress", p)
                     : NULL;
    char *st = o ? job_json_dump(o) : NULL, *pt = ev ? job_json_dump(ev) : NULL;
    *final = strcmp(j.status, "queued") && strcmp(j.status, "running");
    job_rec_free(&j);
    json_decref(o);
    json_decref(ev);
    size_t n = (st ? strlen(st) : 0) + (pt ? strlen(pt) : 0) + 64;
    *text = st ? malloc(n) : NULL;
    if (*text) {
        int k = snprintf(*text, n, "event: status\ndata: %s\n\n", st);
        if (pt) snprintf(*text + k, n - (size_t)k, "event: progress\ndata: %s\n\n", pt);
    }
    free(st);
    free(pt);
    return *text ? 0 : -1;
}

enum MHD_Result api_job_events(http_req *r, const char *id)
{
    static const char *const known[] = {"token", NULL};
    enum MHD_Result ret;
    if (http_args_only(r, known, &ret)) return ret;
    if (id) {
        job_rec j;
        int rc = job_store_get(r->app->st, id, r->owner, &j);
        if (rc == JS_NOTFOUND) return job_not_found(r, id);
        if (rc != JS_OK) return db_error(r);
        job_rec_free(&j);
    }
    snap_ctx c = {r, id};
    struct MHD_Response *resp = sse_open(r->app->hub, r->conn, id, r->owner, job_snapshot, &c);
    if (!resp) return id ? job_not_found(r, id) : http_error(r, 500, "internal", "out of memory");
    return http_queue(r, 200, resp);
}
