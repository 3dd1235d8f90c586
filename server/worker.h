/*
 * worker.h - the device and its worker thread: opens the OpenCL device, runs the self-test, then
 * takes queued jobs one at a time (priority desc, created asc) and runs them with pd_run, keeping
 * the job table, the SSE streams and a live copy of the running job's numbers up to date.
 *
 * The HTTP side never waits for a run: it reads the job table, asks the worker for its live
 * numbers (a mutex held for a copy), or sets the running job's cancel flag.
 */
#ifndef WORKER_H
#define WORKER_H

#include "config.h"
#include "job_store.h"
#include "sse.h"

#include <jansson.h>

typedef struct worker worker;

/* Device states as /healthz and /v1/device report them. */
enum { DEV_STARTING, DEV_READY, DEV_FAILED, DEV_UNAVAILABLE };

/*
 * Opens cfg->device (in the calling thread; a device that does not open leaves the worker
 * DEV_UNAVAILABLE, jobs waiting) and starts the worker thread: it runs the self-test (unless
 * cfg->selftest is 0), then the queued jobs. Results go to <data>/results, meshes resolve in
 * <data>/meshes.
 */
int worker_start(const config *cfg, job_store *st, sse_hub *hub, worker **out, char *msg,
                 size_t msglen);

/*
 * Queues a job: runs insert(ctx) (which inserts the job and publishes its "queued" event) with the
 * queue locked, so that the worker cannot claim the job before that event has gone out, then
 * wakes the worker when insert returned 0. Returns insert's result.
 */
int worker_enqueue(worker *w, int (*insert)(void *ctx), void *ctx);

/* Stops job id if it is the one running (its status becomes cancelled); 1 if it was running. */
int worker_cancel(worker *w, const char *id);

/*
 * Shutdown: the running job stops at the end of its current step and goes back to the queue (it
 * re-runs on the next start); the thread ends and the device closes. The other calls stay safe
 * until worker_free (jobs queued meanwhile run on the next start).
 */
void worker_stop(worker *w);
void worker_free(worker *w);

/* "starting", "ready", "failed" or "unavailable". */
const char *worker_state_name(int state);

/* The device: DEV_* state, and the JSON for /v1/device (info, self-test, queue). */
int worker_device_state(worker *w);
json_t *worker_device_json(worker *w);

/* Runs the self-test now; 0 when it ran (passed or not), -1 when the device is busy or absent. */
int worker_selftest(worker *w);

/*
 * The running job's numbers: for job id, its time series so far (time s, kinetic_energy J,
 * contacts, broad_pairs, sampled at progress records) as the /stats object; NULL when id is
 * not running.
 */
json_t *worker_live_stats(worker *w, const char *id);

/* steps/s of the running job (0 when idle), for /metrics. */
double worker_steps_per_second(worker *w);

#endif
