/*
 * job_store.h - the job table in SQLite (WAL mode, schema version and migrations, prepared
 * statements). One connection guarded by a mutex: every call is a short statement, so neither the
 * HTTP threads nor the worker wait long on each other.
 *
 * Calls return JS_OK or one of the other JS_* results; JS_ERROR means SQLite failed (the message
 * is logged on stderr with the statement it came from).
 */
#ifndef JOB_STORE_H
#define JOB_STORE_H

#include <stddef.h>

enum {
    JS_OK = 0,
    JS_NOTFOUND = 1, /* no such job (or not the caller's) */
    JS_CONFLICT = 2, /* the job's state does not allow it / idempotency key with another body */
    JS_EXISTS = 3,   /* idempotent retry: the job already exists */
    JS_RUNNING = 4,  /* cancel: the job runs; the worker must stop it */
    JS_ERROR = -1,
};

/* The job statuses, in the order job_store_count reports them. */
enum { JOB_QUEUED, JOB_RUNNING, JOB_SUCCEEDED, JOB_FAILED, JOB_CANCELLED, JOB_NSTATUS };
extern const char *const job_status_names[JOB_NSTATUS];

/* Index of a status name, or -1. */
int job_status_index(const char *name);

/* One job row (without its scenario). Strings are owned; "" stands for NULL in the fixed ones. */
typedef struct job_rec {
    char id[24];
    char status[12];
    char *owner; /* token name, NULL without authentication */
    char *name;
    char *tags; /* JSON array text */
    long long priority;
    char created_at[32], started_at[32], finished_at[32];
    char *error;    /* NULL unless failed or cancelled */
    char *progress; /* JSON object text, NULL before the job first ran */
    char *result;   /* result file relative to the data directory, NULL unless succeeded */
    int cancel_requested;
} job_rec;

void job_rec_free(job_rec *j);

typedef struct job_store job_store;

/* Opens (creating and migrating) the database at path; -1 with a message on failure. */
int job_store_open(const char *path, job_store **out, char *msg, size_t msglen);
void job_store_close(job_store *st);

/* After a crash: jobs left running go back to queued (or to cancelled when a cancel was asked,
 * or to failed when the daemon has now died in them JS_MAX_CRASHES times). */
#define JS_MAX_CRASHES 3
int job_store_recover(job_store *st, int *requeued, int *cancelled, int *failed);

/*
 * Inserts job j (id, owner, name, tags, priority, created_at) with its scenario text. With an
 * idempotency key: a key seen before with the same body hash gives JS_EXISTS and that job's id in
 * existing; with another body hash JS_CONFLICT.
 */
int job_store_insert(job_store *st, const job_rec *j, const char *scenario, const char *idem_key,
                     const char *body_hash, char existing[24]);

/* Looks an idempotency key up: JS_NOTFOUND, JS_EXISTS (same body hash; the job's id in
 * existing) or JS_CONFLICT (another body). */
int job_store_idempotent(job_store *st, const char *owner, const char *idem_key,
                         const char *body_hash, char existing[24]);

/* owner NULL: any job. */
int job_store_get(job_store *st, const char *id, const char *owner, job_rec *out);
int job_store_scenario(job_store *st, const char *id, const char *owner, char **text);

/*
 * Jobs newest first; status, tag, after (a job id: list older jobs) and owner filter when
 * non-NULL. *more tells whether further jobs follow. JS_NOTFOUND when after is unknown.
 */
int job_store_list(job_store *st, const char *status, const char *tag, const char *after,
                   const char *owner, int limit, job_rec **out, int *n, int *more);
void job_store_list_free(job_rec *jobs, int n);

/* Jobs per status (JOB_QUEUED...), all owners. */
int job_store_count(job_store *st, long counts[JOB_NSTATUS]);

/* The next queued job (priority desc, created asc) becomes running; JS_NOTFOUND when none. */
int job_store_claim_next(job_store *st, job_rec *out, char **scenario);

int job_store_set_progress(job_store *st, const char *id, const char *progress_json);

/* A running job ends: status succeeded, failed or cancelled; error and result may be NULL. */
int job_store_finish(job_store *st, const char *id, const char *status, const char *error,
                     const char *result, const char *progress_json);

/* A running job goes back to the queue (shutdown while it ran). */
int job_store_requeue(job_store *st, const char *id);

/*
 * Cancels: a queued job becomes cancelled (JS_OK); a running one is marked (JS_RUNNING, the
 * caller stops it); a finished one gives JS_CONFLICT. out (may be NULL) receives the row after.
 */
int job_store_cancel(job_store *st, const char *id, const char *owner, job_rec *out);

/* Removes a finished job; *result receives its result path (or NULL). JS_CONFLICT while it is
 * queued or running. */
int job_store_delete(job_store *st, const char *id, const char *owner, char **result);

/* Whether a job id exists (for sweeping stray result files); 1, 0, or JS_ERROR. */
int job_store_exists(job_store *st, const char *id);

/* SELECT 1: the database answers. */
int job_store_ping(job_store *st);

#endif
