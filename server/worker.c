/* worker.c - the device's worker thread: self-test, then one job at a time (see worker.h). */
#include "worker.h"

#include "job_json.h"
#include "polydem.h"
#include "util.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Live time series kept for the running job: samples of 4 values, halved when full. */
#define LIVE_MAX_SAMPLES 8192

struct worker {
    const config *cfg;
    job_store *st;
    sse_hub *hub;
    char results_dir[4200], meshes_dir[4200];
    pthread_t thread;
    int thread_started;

    pthread_mutex_t mu; /* guards everything below */
    pthread_cond_t cv;
    int stop;            /* shutdown */
    int pending;         /* there may be queued jobs */
    int busy;            /* the device runs a job or a self-test */
    volatile int cancel; /* pd_run's cancel flag */
    int user_cancel;     /* the cancel came from a client (not from shutdown) */
    char running[24];    /* id of the running job, "" when idle */

    pd_device *dev;
    pd_device_info info;
    int have_info;
    int state;           /* DEV_* */
    char state_msg[700]; /* why the device is not usable */
    char st_status[16];  /* self-test: "not run", "running", "passed", "failed", "skipped" */
    char st_report[600], st_at[32];
    double st_seconds;

    pd_progress live; /* the running job's last progress record */
    int have_live;
    double *series; /* LIVE_MAX_SAMPLES x (time, kinetic_energy, contacts, broad_pairs) */
    int nseries;
    int series_stride, series_skip; /* keep every stride-th record after halving */
};

static void live_reset(worker *w)
{
    w->have_live = 0;
    w->nseries = 0;
    w->series_stride = 1;
    w->series_skip = 0;
}

/* Records a progress sample; with w->mu held. */
static void live_add(worker *w, const pd_progress *p)
{
    w->live = *p;
    w->have_live = 1;
    if (!w->series) return;
    if (w->nseries > 0 && !(p->sim_time > w->series[4 * (w->nseries - 1)])) return;
    if (++w->series_skip < w->series_stride) return;
    w->series_skip = 0;
    if (w->nseries == LIVE_MAX_SAMPLES) { /* keep every other sample */
        for (int i = 0; i < LIVE_MAX_SAMPLES / 2; i++)
            memcpy(w->series + 4 * i, w->series + 8 * i, 4 * sizeof(double));
        w->nseries = LIVE_MAX_SAMPLES / 2;
        w->series_stride *= 2;
    }
    double *s = w->series + 4 * w->nseries++;
    s[0] = p->sim_time;
    s[1] = p->kinetic_energy;
    s[2] = (double)p->contacts;
    s[3] = (double)p->broad_pairs;
}

typedef struct run_ctx {
    worker *w;
    const job_rec *job;
} run_ctx;

static int on_progress(const pd_progress *p, void *user)
{
    run_ctx *rc = user;
    worker *w = rc->w;
    json_t *o = job_json_progress(p);
    char *t = o ? job_json_dump(o) : NULL;
    if (t) job_store_set_progress(w->st, rc->job->id, t);
    json_t *ev = o ? json_pack("{s:s, s:O}", "id", rc->job->id, "progress", o) : NULL;
    char *et = ev ? job_json_dump(ev) : NULL;
    if (et) sse_publish(w->hub, rc->job->id, rc->job->owner, "progress", et, 0);
    free(et);
    json_decref(ev);
    free(t);
    json_decref(o);
    pthread_mutex_lock(&w->mu);
    live_add(w, p);
    int cancel = w->cancel;
    pthread_mutex_unlock(&w->mu);
    return cancel;
}

/* Runs one claimed job to its end and records the outcome. */
static void run_job(worker *w, const job_rec *j, const char *scenario)
{
    job_json_publish_id(w->hub, w->st, j->id);
    pd_scenario *s = NULL;
    pd_diags diags = {0};
    pd_error err = {0};
    char out[4400], rel[64], *final_json = NULL;
    int rc = pd_scenario_parse(scenario, w->meshes_dir, &s, &diags, &err);
    pd_diags_free(&diags);
    if (rc != PD_OK) {
        char msg[700];
        snprintf(msg, sizeof msg, "scenario: %s", err.msg);
        job_store_finish(w->st, j->id, "failed", msg, NULL, NULL);
        fprintf(stderr, "polydemd: job %s failed: %s\n", j->id, msg);
        job_json_publish_id(w->hub, w->st, j->id);
        return;
    }
    snprintf(rel, sizeof rel, "results/%s.h5", j->id);
    snprintf(out, sizeof out, "%s/%s.h5", w->results_dir, j->id);
    run_ctx ctx = {w, j};
    pd_run_options opt = {0};
    opt.output_path = out;
    opt.progress = on_progress;
    opt.user = &ctx;
    opt.progress_interval = w->cfg->progress_interval;
    opt.cancel = &w->cancel;
    pd_progress fin = {0};
    fprintf(stderr, "polydemd: job %s (%s) started\n", j->id, j->name);
    double t0 = util_monotonic();
    rc = pd_run(w->dev, s, &opt, &fin, &err);
    double wall = util_monotonic() - t0;
    pd_scenario_destroy(s);
    if (fin.steps_total > 0) {
        json_t *o = job_json_progress(&fin);
        final_json = o ? job_json_dump(o) : NULL;
        json_decref(o);
    }
    pthread_mutex_lock(&w->mu);
    int user_cancel = w->user_cancel, stopping = w->stop;
    pthread_mutex_unlock(&w->mu);
    if (rc == PD_OK) {
        job_store_finish(w->st, j->id, "succeeded", NULL, rel, final_json);
        fprintf(stderr, "polydemd: job %s succeeded in %.1f s\n", j->id, wall);
    } else if (rc == PD_ECANCELLED && stopping && !user_cancel) {
        /* it runs again from the start: the frames kept from this try are not its result */
        if (fin.result_kept) util_remove_job_files(w->results_dir, j->id);
        job_store_requeue(w->st, j->id);
        fprintf(stderr, "polydemd: job %s stopped by shutdown, queued again\n", j->id);
    } else if (rc == PD_ECANCELLED) {
        job_store_finish(w->st, j->id, "cancelled", "cancelled while running",
                         fin.result_kept ? rel : NULL, final_json);
        fprintf(stderr, "polydemd: job %s cancelled after %.1f s\n", j->id, wall);
    } else {
        job_store_finish(w->st, j->id, "failed", err.msg[0] ? err.msg : "run failed",
                         fin.result_kept ? rel : NULL, final_json);
        fprintf(stderr, "polydemd: job %s failed: %s\n", j->id, err.msg);
    }
    free(final_json);
    job_json_publish_id(w->hub, w->st, j->id);
}

/* Runs the device self-test; the caller has set w->busy. */
static void selftest_run(worker *w)
{
    char report[512] = "";
    pd_error err = {0};
    double t0 = util_monotonic();
    int rc = pd_device_selftest(w->dev, report, sizeof report, &err);
    double dt = util_monotonic() - t0;
    pthread_mutex_lock(&w->mu);
    snprintf(w->st_status, sizeof w->st_status, "%s", rc == PD_OK ? "passed" : "failed");
    if (rc == PD_OK)
        snprintf(w->st_report, sizeof w->st_report, "%s", report);
    else
        snprintf(w->st_report, sizeof w->st_report, "%s%s%s", err.msg, report[0] ? "; " : "",
                 report);
    util_now_iso(w->st_at);
    w->st_seconds = dt;
    w->state = rc == PD_OK ? DEV_READY : DEV_FAILED;
    if (rc != PD_OK)
        snprintf(w->state_msg, sizeof w->state_msg, "device self-test failed: %s", w->st_report);
    else
        w->state_msg[0] = 0;
    w->busy = 0;
    pthread_cond_broadcast(&w->cv);
    pthread_mutex_unlock(&w->mu);
    fprintf(stderr, "polydemd: device self-test %s in %.1f s: %s\n",
            rc == PD_OK ? "passed" : "FAILED (jobs wait in the queue)", dt, w->st_report);
}

/* Opens the configured device; with w->mu not held. */
static void open_device(worker *w)
{
    pd_device_info infos[64];
    int n = 0, pick = w->cfg->device;
    pd_error err = {0};
    pd_device *dev = NULL;
    int rc = pd_device_list(infos, 64, &n, &err);
    if (rc == PD_OK && n > 64) n = 64;
    if (rc == PD_OK && pick < 0) {
        pick = n > 0 ? 0 : -1;
        for (int i = n - 1; i >= 0; i--)
            if (!strcmp(infos[i].type, "GPU")) pick = i;
    }
    if (rc == PD_OK && (pick < 0 || pick >= n))
        rc = pd_error_set(&err, PD_EINVAL, "opencl: device %d does not exist (%d found)", pick, n);
    if (rc == PD_OK) rc = pd_device_open(pick, &dev, &err);
    pthread_mutex_lock(&w->mu);
    if (rc == PD_OK) {
        w->dev = dev;
        w->info = infos[pick];
        w->have_info = 1;
    } else {
        w->state = DEV_UNAVAILABLE;
        snprintf(w->state_msg, sizeof w->state_msg, "%s", err.msg);
    }
    pthread_mutex_unlock(&w->mu);
    if (rc == PD_OK)
        fprintf(stderr, "polydemd: device %d: %s (%s)\n", pick, infos[pick].name,
                infos[pick].platform);
    else
        fprintf(stderr, "polydemd: no device, jobs wait in the queue: %s\n", err.msg);
}

static void *worker_main(void *arg)
{
    worker *w = arg;
    pthread_mutex_lock(&w->mu);
    int test = w->dev && w->cfg->selftest && !w->stop;
    if (w->dev && !w->cfg->selftest) {
        w->state = DEV_READY;
        snprintf(w->st_status, sizeof w->st_status, "skipped");
    }
    if (test) {
        w->busy = 1;
        snprintf(w->st_status, sizeof w->st_status, "running");
    }
    pthread_mutex_unlock(&w->mu);
    if (test) selftest_run(w);

    pthread_mutex_lock(&w->mu);
    for (;;) {
        while (!w->stop && (w->state != DEV_READY || w->busy || !w->pending))
            pthread_cond_wait(&w->cv, &w->mu);
        if (w->stop) break;
        job_rec j;
        char *scenario = NULL;
        int rc = job_store_claim_next(w->st, &j, &scenario);
        if (rc != JS_OK) {
            w->pending = 0; /* none queued (or the database failed: retry on the next wake) */
            continue;
        }
        snprintf(w->running, sizeof w->running, "%s", j.id);
        w->busy = 1;
        w->cancel = 0;
        w->user_cancel = 0;
        live_reset(w);
        pthread_mutex_unlock(&w->mu);

        run_job(w, &j, scenario);
        free(scenario);
        job_rec_free(&j);

        pthread_mutex_lock(&w->mu);
        w->running[0] = 0;
        w->busy = 0;
        w->cancel = 0;
        w->user_cancel = 0;
        live_reset(w);
    }
    pthread_mutex_unlock(&w->mu);
    return NULL;
}

int worker_start(const config *cfg, job_store *st, sse_hub *hub, worker **out, char *msg, size_t ml)
{
    *out = NULL;
    worker *w = calloc(1, sizeof *w);
    if (!w || !(w->series = malloc(4 * LIVE_MAX_SAMPLES * sizeof(double)))) {
        free(w);
        snprintf(msg, ml, "out of memory");
        return -1;
    }
    w->cfg = cfg;
    w->st = st;
    w->hub = hub;
    w->pending = 1;
    w->state = DEV_STARTING;
    snprintf(w->st_status, sizeof w->st_status, "not run");
    snprintf(w->state_msg, sizeof w->state_msg, "the device is starting");
    live_reset(w);
    if (util_fmt(w->results_dir, sizeof w->results_dir, "%s/results", cfg->data) ||
        util_fmt(w->meshes_dir, sizeof w->meshes_dir, "%s/meshes", cfg->data)) {
        snprintf(msg, ml, "data directory name too long");
        free(w->series);
        free(w);
        return -1;
    }
    if (pthread_mutex_init(&w->mu, NULL) != 0 || pthread_cond_init(&w->cv, NULL) != 0) {
        snprintf(msg, ml, "cannot create the worker's mutex");
        free(w->series);
        free(w);
        return -1;
    }
    /* The OpenCL platform loads here, in the main thread: PoCL's LLVM installs an alternate
     * signal stack in the thread that first loads it, which a worker thread could not free at
     * its exit (AddressSanitizer aborts there). */
    open_device(w);
    if (pthread_create(&w->thread, NULL, worker_main, w) != 0) {
        snprintf(msg, ml, "cannot start the worker thread");
        free(w->series);
        free(w);
        return -1;
    }
    w->thread_started = 1;
    *out = w;
    return 0;
}

int worker_enqueue(worker *w, int (*insert)(void *ctx), void *ctx)
{
    pthread_mutex_lock(&w->mu); /* the worker claims jobs with this held */
    int rc = insert(ctx);
    if (rc == 0) {
        w->pending = 1;
        pthread_cond_broadcast(&w->cv);
    }
    pthread_mutex_unlock(&w->mu);
    return rc;
}

int worker_cancel(worker *w, const char *id)
{
    pthread_mutex_lock(&w->mu);
    int hit = w->running[0] && !strcmp(w->running, id);
    if (hit) {
        w->user_cancel = 1;
        w->cancel = 1;
    }
    pthread_mutex_unlock(&w->mu);
    return hit;
}

void worker_stop(worker *w)
{
    if (!w) return;
    pthread_mutex_lock(&w->mu);
    w->stop = 1;
    w->cancel = 1;
    pthread_cond_broadcast(&w->cv);
    pthread_mutex_unlock(&w->mu);
    if (w->thread_started) pthread_join(w->thread, NULL);
    w->thread_started = 0;
    pthread_mutex_lock(&w->mu);
    /* A self-test asked for with GET /v1/device?selftest=1 runs in that request's thread, not
     * the worker's: closing the device under it crashed the daemon at SIGTERM. It cannot be
     * interrupted, so wait for it (selftest_run clears busy and broadcasts). */
    while (w->busy)
        pthread_cond_wait(&w->cv, &w->mu);
    pd_device_close(w->dev);
    w->dev = NULL;
    pthread_mutex_unlock(&w->mu);
}

void worker_free(worker *w)
{
    if (!w) return;
    worker_stop(w);
    pthread_cond_destroy(&w->cv);
    pthread_mutex_destroy(&w->mu);
    free(w->series);
    free(w);
}

int worker_device_state(worker *w)
{
    pthread_mutex_lock(&w->mu);
    int s = w->state;
    pthread_mutex_unlock(&w->mu);
    return s;
}

const char *worker_state_name(int state)
{
    static const char *const names[] = {"starting", "ready", "failed", "unavailable"};
    return state >= 0 && state <= DEV_UNAVAILABLE ? names[state] : "unknown";
}

json_t *worker_device_json(worker *w)
{
    long counts[JOB_NSTATUS];
    int db_ok = job_store_count(w->st, counts) == JS_OK;
    pthread_mutex_lock(&w->mu);
    json_t *o = json_pack("{s:s, s:o, s:{s:s, s:s, s:o, s:o}, s:o, s:o, s:o}", "state",
                          worker_state_name(w->state), "message",
                          w->state_msg[0] ? json_string(w->state_msg) : json_null(), "selftest",
                          "status", w->st_status, "report", w->st_report, "finished_at",
                          w->st_at[0] ? json_string(w->st_at) : json_null(), "seconds",
                          w->st_at[0] ? json_real(w->st_seconds) : json_null(), "queue_length",
                          db_ok ? json_integer(counts[JOB_QUEUED]) : json_null(), "running_job",
                          w->running[0] ? json_string(w->running) : json_null(), "steps_per_second",
                          json_real(w->have_live ? w->live.steps_per_second : 0));
    if (o && w->have_info) {
        const pd_device_info *d = &w->info;
        json_t *prec =
            d->fp64 ? json_pack("[s, s]", "single", "double") : json_pack("[s]", "single");
        json_object_set_new(o, "index", json_integer(d->index));
        json_object_set_new(o, "name", json_string(d->name));
        json_object_set_new(o, "platform", json_string(d->platform));
        json_object_set_new(o, "type", json_string(d->type));
        json_object_set_new(o, "compute_units", json_integer(d->compute_units));
        json_object_set_new(o, "global_mem_bytes", json_real(d->global_mem_bytes));
        json_object_set_new(o, "fp64", json_boolean(d->fp64));
        json_object_set_new(o, "fp32_rounded", json_boolean(d->fp32_rounded));
        json_object_set_new(o, "precisions", prec ? prec : json_array());
    }
    pthread_mutex_unlock(&w->mu);
    return o;
}

int worker_selftest(worker *w)
{
    pthread_mutex_lock(&w->mu);
    if (!w->dev || w->busy || w->stop) {
        pthread_mutex_unlock(&w->mu);
        return -1;
    }
    w->busy = 1;
    snprintf(w->st_status, sizeof w->st_status, "running");
    pthread_mutex_unlock(&w->mu);
    selftest_run(w);
    return 0;
}

json_t *worker_live_stats(worker *w, const char *id)
{
    pthread_mutex_lock(&w->mu);
    if (!w->running[0] || strcmp(w->running, id)) {
        pthread_mutex_unlock(&w->mu);
        return NULL;
    }
    json_t *cols[4] = {json_array(), json_array(), json_array(), json_array()};
    for (int i = 0; i < w->nseries; i++) {
        const double *s = w->series + 4 * i;
        json_array_append_new(cols[0], json_real(s[0]));
        json_array_append_new(cols[1], json_real(s[1]));
        json_array_append_new(cols[2], json_integer((json_int_t)s[2]));
        json_array_append_new(cols[3], json_integer((json_int_t)s[3]));
    }
    pthread_mutex_unlock(&w->mu);
    return json_pack("{s:b, s:o, s:o, s:o, s:o, s:{s:s, s:s, s:s, s:s}}", "partial", 1, "time",
                     cols[0], "kinetic_energy", cols[1], "contacts", cols[2], "broad_pairs",
                     cols[3], "units", "time", "s", "kinetic_energy", "J", "contacts", "1",
                     "broad_pairs", "1");
}

double worker_steps_per_second(worker *w)
{
    pthread_mutex_lock(&w->mu);
    double r = w->have_live ? w->live.steps_per_second : 0;
    pthread_mutex_unlock(&w->mu);
    return r;
}
