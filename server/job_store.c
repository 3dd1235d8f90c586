/* job_store.c - the job table in SQLite: schema, migrations, prepared statements. */
#include "job_store.h"

#include "util.h"

#include <pthread.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *const job_status_names[JOB_NSTATUS] = {"queued", "running", "succeeded", "failed",
                                                   "cancelled"};

int job_status_index(const char *name)
{
    for (int i = 0; i < JOB_NSTATUS; i++)
        if (!strcmp(name, job_status_names[i])) return i;
    return -1;
}

/* Each migration takes the schema from version i to i+1; append, never edit. */
static const char *const migrations[] = {
    /* 1: jobs and idempotency keys */
    "CREATE TABLE jobs ("
    "  seq INTEGER PRIMARY KEY AUTOINCREMENT,"
    "  id TEXT NOT NULL UNIQUE,"
    "  owner TEXT,"
    "  status TEXT NOT NULL CHECK (status IN "
    "    ('queued','running','succeeded','failed','cancelled')),"
    "  name TEXT NOT NULL,"
    "  tags TEXT NOT NULL DEFAULT '[]',"
    "  priority INTEGER NOT NULL DEFAULT 0,"
    "  scenario TEXT NOT NULL,"
    "  created_at TEXT NOT NULL,"
    "  started_at TEXT,"
    "  finished_at TEXT,"
    "  error TEXT,"
    "  progress TEXT,"
    "  result TEXT,"
    "  cancel_requested INTEGER NOT NULL DEFAULT 0,"
    "  attempts INTEGER NOT NULL DEFAULT 0);"
    "CREATE INDEX jobs_queue ON jobs (status, priority DESC, created_at, seq);"
    "CREATE TABLE idempotency ("
    "  owner TEXT NOT NULL,"
    "  key TEXT NOT NULL,"
    "  body_sha256 TEXT NOT NULL,"
    "  job_id TEXT NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,"
    "  created_at TEXT NOT NULL,"
    "  PRIMARY KEY (owner, key));"
    "CREATE INDEX idempotency_job ON idempotency (job_id);",
    /* 2: a deleted job's place in the list, so that a page cursor (?after=ID) naming it still
     * works: "list finished jobs, delete them, fetch the next page" is the usual clean-up loop */
    "CREATE TABLE deleted_jobs ("
    "  id TEXT PRIMARY KEY,"
    "  owner TEXT,"
    "  seq INTEGER NOT NULL);"
    "CREATE TRIGGER jobs_deleted AFTER DELETE ON jobs BEGIN"
    "  INSERT OR REPLACE INTO deleted_jobs (id, owner, seq) VALUES (old.id, old.owner, old.seq);"
    "  END;",
};
#define NMIGRATIONS ((int)(sizeof migrations / sizeof migrations[0]))

#define JOB_COLS                                                                                   \
    "id, status, owner, name, tags, priority, created_at, started_at, finished_at, error, "        \
    "progress, result, cancel_requested"
#define OWNER_OK "(?2 IS NULL OR owner = ?2)"

enum {
    S_GET,
    S_SCENARIO,
    S_LIST,
    S_SEQ_OF,
    S_CURSOR, /* S_SEQ_OF, or the seq a deleted job had */
    S_COUNT,
    S_CLAIM,
    S_PROGRESS,
    S_FINISH,
    S_REQUEUE,
    S_CANCEL_QUEUED,
    S_CANCEL_RUNNING,
    S_DELETE,
    S_IDEM_GET,
    S_IDEM_PUT,
    S_INSERT,
    S_EXISTS,
    S_NSTMT
};

static const char *const stmt_sql[S_NSTMT] = {
    [S_GET] = "SELECT " JOB_COLS " FROM jobs WHERE id = ?1 AND " OWNER_OK,
    [S_SCENARIO] = "SELECT scenario FROM jobs WHERE id = ?1 AND " OWNER_OK,
    [S_LIST] = "SELECT " JOB_COLS " FROM jobs WHERE " OWNER_OK " AND (?1 IS NULL OR status = ?1)"
               " AND (?3 IS NULL OR EXISTS (SELECT 1 FROM json_each(jobs.tags) WHERE value = ?3))"
               " AND (?4 IS NULL OR seq < ?4) ORDER BY seq DESC LIMIT ?5",
    [S_SEQ_OF] = "SELECT seq FROM jobs WHERE id = ?1 AND " OWNER_OK,
    [S_CURSOR] = "SELECT seq FROM jobs WHERE id = ?1 AND " OWNER_OK
                 " UNION ALL SELECT seq FROM deleted_jobs WHERE id = ?1 AND " OWNER_OK " LIMIT 1",
    [S_COUNT] = "SELECT status, COUNT(*) FROM jobs GROUP BY status",
    [S_CLAIM] = "UPDATE jobs SET status = 'running', started_at = ?1, progress = NULL, "
                "error = NULL, attempts = attempts + 1 WHERE seq = (SELECT seq FROM jobs WHERE "
                "status = 'queued' ORDER BY priority DESC, created_at, seq LIMIT 1) "
                "RETURNING " JOB_COLS ", scenario",
    [S_PROGRESS] = "UPDATE jobs SET progress = ?2 WHERE id = ?1 AND status = 'running'",
    [S_FINISH] = "UPDATE jobs SET status = ?2, finished_at = ?3, error = ?4, result = ?5, "
                 "progress = COALESCE(?6, progress) WHERE id = ?1 AND status = 'running'",
    /* a shutdown's requeue gives the try back: attempts counts the tries the daemon died in */
    [S_REQUEUE] = "UPDATE jobs SET status = 'queued', started_at = NULL, progress = NULL, "
                  "attempts = MAX(attempts - 1, 0) WHERE id = ?1 AND status = 'running'",
    [S_CANCEL_QUEUED] = "UPDATE jobs SET status = 'cancelled', finished_at = ?3, "
                        "cancel_requested = 1, error = 'cancelled before it ran' "
                        "WHERE id = ?1 AND " OWNER_OK " AND status = 'queued'",
    [S_CANCEL_RUNNING] = "UPDATE jobs SET cancel_requested = 1 WHERE id = ?1 AND " OWNER_OK
                         " AND status = 'running'",
    [S_DELETE] = "DELETE FROM jobs WHERE id = ?1 AND " OWNER_OK
                 " AND status IN ('succeeded', 'failed', 'cancelled') RETURNING result",
    [S_IDEM_GET] = "SELECT body_sha256, job_id FROM idempotency WHERE owner = ?1 AND key = ?2",
    [S_IDEM_PUT] = "INSERT INTO idempotency (owner, key, body_sha256, job_id, created_at) "
                   "VALUES (?1, ?2, ?3, ?4, ?5)",
    [S_INSERT] = "INSERT INTO jobs (id, owner, status, name, tags, priority, scenario, "
                 "created_at) VALUES (?1, ?2, 'queued', ?3, ?4, ?5, ?6, ?7)",
    [S_EXISTS] = "SELECT 1 FROM jobs WHERE id = ?1",
};

struct job_store {
    sqlite3 *db;
    pthread_mutex_t mu;
    sqlite3_stmt *st[S_NSTMT];
};

static void log_err(job_store *s, const char *what)
{
    fprintf(stderr, "polydemd: database: %s: %s\n", what, sqlite3_errmsg(s->db));
}

void job_rec_free(job_rec *j)
{
    if (!j) return;
    free(j->owner);
    free(j->name);
    free(j->tags);
    free(j->error);
    free(j->progress);
    free(j->result);
    memset(j, 0, sizeof *j);
}

void job_store_list_free(job_rec *jobs, int n)
{
    for (int i = 0; i < n; i++)
        job_rec_free(&jobs[i]);
    free(jobs);
}

/* A malloc'd copy of a text column, NULL for SQL NULL (or when out of memory: *oom set). */
static char *col_dup(sqlite3_stmt *q, int i, int *oom)
{
    const unsigned char *t = sqlite3_column_text(q, i);
    if (!t) return NULL;
    char *d = strdup((const char *)t);
    if (!d) *oom = 1;
    return d;
}

static void col_copy(sqlite3_stmt *q, int i, char *dst, size_t cap)
{
    const unsigned char *t = sqlite3_column_text(q, i);
    snprintf(dst, cap, "%s", t ? (const char *)t : "");
}

/* Fills j from the JOB_COLS of the current row; JS_ERROR when out of memory. */
static int row_to_job(sqlite3_stmt *q, job_rec *j)
{
    int oom = 0;
    memset(j, 0, sizeof *j);
    col_copy(q, 0, j->id, sizeof j->id);
    col_copy(q, 1, j->status, sizeof j->status);
    j->owner = col_dup(q, 2, &oom);
    j->name = col_dup(q, 3, &oom);
    j->tags = col_dup(q, 4, &oom);
    j->priority = sqlite3_column_int64(q, 5);
    col_copy(q, 6, j->created_at, sizeof j->created_at);
    col_copy(q, 7, j->started_at, sizeof j->started_at);
    col_copy(q, 8, j->finished_at, sizeof j->finished_at);
    j->error = col_dup(q, 9, &oom);
    j->progress = col_dup(q, 10, &oom);
    j->result = col_dup(q, 11, &oom);
    j->cancel_requested = sqlite3_column_int(q, 12);
    if (oom || !j->name || !j->tags) {
        job_rec_free(j);
        fprintf(stderr, "polydemd: database: out of memory reading a job\n");
        return JS_ERROR;
    }
    return JS_OK;
}

/* Binds text, or NULL for a NULL pointer. */
static int bind_text(sqlite3_stmt *q, int i, const char *t)
{
    return t ? sqlite3_bind_text(q, i, t, -1, SQLITE_TRANSIENT) : sqlite3_bind_null(q, i);
}

/* Resets and clears a statement for its next use. */
static sqlite3_stmt *stmt(job_store *s, int k)
{
    sqlite3_reset(s->st[k]);
    sqlite3_clear_bindings(s->st[k]);
    return s->st[k];
}

static int exec(job_store *s, const char *sql)
{
    char *e = NULL;
    if (sqlite3_exec(s->db, sql, NULL, NULL, &e) != SQLITE_OK) {
        fprintf(stderr, "polydemd: database: %s: %s\n", sql, e ? e : "failed");
        sqlite3_free(e);
        return JS_ERROR;
    }
    return JS_OK;
}

static int schema_version(job_store *s, int *v)
{
    sqlite3_stmt *q;
    if (sqlite3_prepare_v2(s->db, "SELECT version FROM schema_version", -1, &q, NULL) != SQLITE_OK)
        return JS_ERROR;
    int rc = sqlite3_step(q);
    *v = rc == SQLITE_ROW ? sqlite3_column_int(q, 0) : -1;
    sqlite3_finalize(q);
    return rc == SQLITE_ROW || rc == SQLITE_DONE ? JS_OK : JS_ERROR;
}

static int migrate(job_store *s, char *msg, size_t ml)
{
    int v;
    if (exec(s, "CREATE TABLE IF NOT EXISTS schema_version (version INTEGER NOT NULL)") ||
        schema_version(s, &v)) {
        snprintf(msg, ml, "cannot read the schema version: %s", sqlite3_errmsg(s->db));
        return -1;
    }
    if (v < 0) {
        if (exec(s, "INSERT INTO schema_version (version) VALUES (0)")) {
            snprintf(msg, ml, "cannot initialise the schema: %s", sqlite3_errmsg(s->db));
            return -1;
        }
        v = 0;
    }
    if (v > NMIGRATIONS) {
        snprintf(msg, ml, "database schema version %d is newer than this polydemd's (%d)", v,
                 NMIGRATIONS);
        return -1;
    }
    for (; v < NMIGRATIONS; v++) {
        char up[96];
        snprintf(up, sizeof up, "UPDATE schema_version SET version = %d", v + 1);
        if (exec(s, "BEGIN IMMEDIATE")) {
            snprintf(msg, ml, "migration %d: %s", v + 1, sqlite3_errmsg(s->db));
            return -1;
        }
        if (exec(s, migrations[v]) || exec(s, up) || exec(s, "COMMIT")) {
            snprintf(msg, ml, "migration %d: %s", v + 1, sqlite3_errmsg(s->db));
            exec(s, "ROLLBACK");
            return -1;
        }
    }
    return 0;
}

int job_store_open(const char *path, job_store **out, char *msg, size_t ml)
{
    *out = NULL;
    job_store *s = calloc(1, sizeof *s);
    if (!s) {
        snprintf(msg, ml, "out of memory");
        return -1;
    }
    if (pthread_mutex_init(&s->mu, NULL) != 0) {
        free(s);
        snprintf(msg, ml, "cannot create a mutex");
        return -1;
    }
    int rc = sqlite3_open_v2(
        path, &s->db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX, NULL);
    if (rc != SQLITE_OK) {
        snprintf(msg, ml, "cannot open '%s': %s", path,
                 s->db ? sqlite3_errmsg(s->db) : sqlite3_errstr(rc));
        goto fail;
    }
    if (sqlite3_busy_timeout(s->db, 5000) != SQLITE_OK) {
        snprintf(msg, ml, "'%s': cannot set the busy timeout", path);
        goto fail;
    }
    /* WAL: readers never wait for the writer; NORMAL sync is durable across process crashes */
    sqlite3_stmt *q;
    if (sqlite3_prepare_v2(s->db, "PRAGMA journal_mode = WAL", -1, &q, NULL) != SQLITE_OK) {
        snprintf(msg, ml, "'%s': %s", path, sqlite3_errmsg(s->db));
        goto fail;
    }
    rc = sqlite3_step(q);
    int wal = rc == SQLITE_ROW && !strcmp((const char *)sqlite3_column_text(q, 0), "wal");
    sqlite3_finalize(q);
    if (!wal) {
        snprintf(msg, ml, "'%s': cannot switch to WAL mode: %s", path, sqlite3_errmsg(s->db));
        goto fail;
    }
    if (exec(s, "PRAGMA synchronous = NORMAL") || exec(s, "PRAGMA foreign_keys = ON")) {
        snprintf(msg, ml, "'%s': %s", path, sqlite3_errmsg(s->db));
        goto fail;
    }
    if (migrate(s, msg, ml) != 0) goto fail;
    for (int k = 0; k < S_NSTMT; k++) {
        if (sqlite3_prepare_v3(s->db, stmt_sql[k], -1, SQLITE_PREPARE_PERSISTENT, &s->st[k],
                               NULL) != SQLITE_OK) {
            snprintf(msg, ml, "'%s': preparing statement %d: %s", path, k, sqlite3_errmsg(s->db));
            goto fail;
        }
    }
    *out = s;
    return 0;
fail:
    job_store_close(s);
    return -1;
}

void job_store_close(job_store *s)
{
    if (!s) return;
    for (int k = 0; k < S_NSTMT; k++)
        sqlite3_finalize(s->st[k]);
    if (s->db && sqlite3_close(s->db) != SQLITE_OK)
        fprintf(stderr, "polydemd: database: close: %s\n", sqlite3_errmsg(s->db));
    pthread_mutex_destroy(&s->mu);
    free(s);
}

/* Runs a statement that returns no rows; JS_ERROR on failure. */
static int run_done(job_store *s, sqlite3_stmt *q, const char *what)
{
    int rc = sqlite3_step(q);
    sqlite3_reset(q);
    if (rc != SQLITE_DONE) {
        log_err(s, what);
        return JS_ERROR;
    }
    return JS_OK;
}

int job_store_recover(job_store *s, int *requeued, int *cancelled, int *failed)
{
    char now[32];
    util_now_iso(now);
    char sql[512];
    pthread_mutex_lock(&s->mu);
    /* A job the daemon died in JS_MAX_CRASHES times is likely what kills it (a driver fault,
     * memory): running it again on every restart would keep the service in a crash loop. */
    snprintf(sql, sizeof sql,
             "UPDATE jobs SET status = 'failed', finished_at = '%s', error = 'polydemd stopped "
             "unexpectedly (a crash or kill -9) while running this job %d times; not retried' "
             "WHERE status = 'running' AND cancel_requested = 0 AND attempts >= %d",
             now, JS_MAX_CRASHES, JS_MAX_CRASHES);
    int rc = exec(s, sql);
    *failed = rc ? 0 : sqlite3_changes(s->db);
    if (!rc)
        rc = exec(s, "UPDATE jobs SET status = 'queued', started_at = NULL, progress = NULL "
                     "WHERE status = 'running' AND cancel_requested = 0");
    *requeued = rc ? 0 : sqlite3_changes(s->db);
    snprintf(sql, sizeof sql,
             "UPDATE jobs SET status = 'cancelled', finished_at = '%s', error = 'cancelled' "
             "WHERE status = 'running'",
             now);
    if (!rc) rc = exec(s, sql);
    *cancelled = rc ? 0 : sqlite3_changes(s->db);
    pthread_mutex_unlock(&s->mu);
    return rc;
}

/* With s->mu held: JS_NOTFOUND, JS_EXISTS, JS_CONFLICT or JS_ERROR. */
static int idem_lookup(job_store *s, const char *owner, const char *key, const char *hash,
                       char existing[24])
{
    int rc = JS_NOTFOUND;
    sqlite3_stmt *q = stmt(s, S_IDEM_GET);
    bind_text(q, 1, owner);
    bind_text(q, 2, key);
    int r = sqlite3_step(q);
    if (r == SQLITE_ROW) {
        rc = strcmp((const char *)sqlite3_column_text(q, 0), hash) ? JS_CONFLICT : JS_EXISTS;
        col_copy(q, 1, existing, 24);
    } else if (r != SQLITE_DONE) {
        log_err(s, "idempotency lookup");
        rc = JS_ERROR;
    }
    sqlite3_reset(q);
    return rc;
}

int job_store_idempotent(job_store *s, const char *owner, const char *key, const char *hash,
                         char existing[24])
{
    pthread_mutex_lock(&s->mu);
    int rc = idem_lookup(s, owner ? owner : "", key, hash, existing);
    pthread_mutex_unlock(&s->mu);
    return rc;
}

int job_store_insert(job_store *s, const job_rec *j, const char *scenario, const char *idem_key,
                     const char *body_hash, char existing[24])
{
    int rc = JS_OK;
    const char *owner = j->owner ? j->owner : "";
    pthread_mutex_lock(&s->mu);
    if (exec(s, "BEGIN IMMEDIATE")) {
        pthread_mutex_unlock(&s->mu);
        return JS_ERROR;
    }
    if (idem_key) {
        rc = idem_lookup(s, owner, idem_key, body_hash, existing);
        if (rc == JS_NOTFOUND) rc = JS_OK;
    }
    if (rc == JS_OK) {
        sqlite3_stmt *q = stmt(s, S_INSERT);
        bind_text(q, 1, j->id);
        bind_text(q, 2, j->owner);
        bind_text(q, 3, j->name);
        bind_text(q, 4, j->tags);
        sqlite3_bind_int64(q, 5, j->priority);
        bind_text(q, 6, scenario);
        bind_text(q, 7, j->created_at);
        rc = run_done(s, q, "insert job");
    }
    if (rc == JS_OK && idem_key) {
        sqlite3_stmt *q = stmt(s, S_IDEM_PUT);
        bind_text(q, 1, owner);
        bind_text(q, 2, idem_key);
        bind_text(q, 3, body_hash);
        bind_text(q, 4, j->id);
        bind_text(q, 5, j->created_at);
        rc = run_done(s, q, "insert idempotency key");
    }
    if (rc == JS_OK) {
        if (exec(s, "COMMIT")) rc = JS_ERROR;
    }
    if (rc != JS_OK) exec(s, "ROLLBACK");
    pthread_mutex_unlock(&s->mu);
    return rc;
}

/* Steps a statement expected to give at most one JOB_COLS row. */
static int one_job(job_store *s, sqlite3_stmt *q, job_rec *out, const char *what)
{
    int r = sqlite3_step(q), rc;
    if (r == SQLITE_ROW)
        rc = row_to_job(q, out);
    else if (r == SQLITE_DONE)
        rc = JS_NOTFOUND;
    else {
        log_err(s, what);
        rc = JS_ERROR;
    }
    sqlite3_reset(q);
    return rc;
}

int job_store_get(job_store *s, const char *id, const char *owner, job_rec *out)
{
    pthread_mutex_lock(&s->mu);
    sqlite3_stmt *q = stmt(s, S_GET);
    bind_text(q, 1, id);
    bind_text(q, 2, owner);
    int rc = one_job(s, q, out, "get job");
    pthread_mutex_unlock(&s->mu);
    return rc;
}

int job_store_scenario(job_store *s, const char *id, const char *owner, char **text)
{
    int rc = JS_NOTFOUND, oom = 0;
    *text = NULL;
    pthread_mutex_lock(&s->mu);
    sqlite3_stmt *q = stmt(s, S_SCENARIO);
    bind_text(q, 1, id);
    bind_text(q, 2, owner);
    int r = sqlite3_step(q);
    if (r == SQLITE_ROW) {
        *text = col_dup(q, 0, &oom);
        rc = *text ? JS_OK : JS_ERROR;
    } else if (r != SQLITE_DONE) {
        log_err(s, "get scenario");
        rc = JS_ERROR;
    }
    sqlite3_reset(q);
    pthread_mutex_unlock(&s->mu);
    return rc;
}

int job_store_list(job_store *s, const char *status, const char *tag, const char *after,
                   const char *owner, int limit, job_rec **out, int *n, int *more)
{
    *out = NULL;
    *n = 0;
    *more = 0;
    int rc = JS_OK, cap = 0;
    sqlite3_int64 after_seq = 0;
    pthread_mutex_lock(&s->mu);
    if (after) {
        sqlite3_stmt *q = stmt(s, S_CURSOR);
        bind_text(q, 1, after);
        bind_text(q, 2, owner);
        int r = sqlite3_step(q);
        if (r == SQLITE_ROW)
            after_seq = sqlite3_column_int64(q, 0);
        else if (r == SQLITE_DONE)
            rc = JS_NOTFOUND;
        else {
            log_err(s, "list jobs: cursor");
            rc = JS_ERROR;
        }
        sqlite3_reset(q);
    }
    if (rc == JS_OK) {
        sqlite3_stmt *q = stmt(s, S_LIST);
        bind_text(q, 1, status);
        bind_text(q, 2, owner);
        bind_text(q, 3, tag);
        if (after)
            sqlite3_bind_int64(q, 4, after_seq);
        else
            sqlite3_bind_null(q, 4);
        sqlite3_bind_int(q, 5, limit + 1);
        int r;
        while ((r = sqlite3_step(q)) == SQLITE_ROW) {
            if (*n == limit) {
                *more = 1;
                break;
            }
            if (*n == cap) {
                int nc = cap ? 2 * cap : 16;
                job_rec *nj = realloc(*out, (size_t)nc * sizeof *nj);
                if (!nj) {
                    rc = JS_ERROR;
                    break;
                }
                *out = nj;
                cap = nc;
            }
            if (row_to_job(q, &(*out)[*n]) != JS_OK) {
                rc = JS_ERROR;
                break;
            }
            (*n)++;
        }
        if (rc == JS_OK && r != SQLITE_ROW && r != SQLITE_DONE) {
            log_err(s, "list jobs");
            rc = JS_ERROR;
        }
        sqlite3_reset(q);
    }
    pthread_mutex_unlock(&s->mu);
    if (rc != JS_OK) {
        job_store_list_free(*out, *n);
        *out = NULL;
        *n = 0;
    }
    return rc;
}

int job_store_count(job_store *s, long counts[JOB_NSTATUS])
{
    int rc = JS_OK, r;
    memset(counts, 0, JOB_NSTATUS * sizeof counts[0]);
    pthread_mutex_lock(&s->mu);
    sqlite3_stmt *q = stmt(s, S_COUNT);
    while ((r = sqlite3_step(q)) == SQLITE_ROW) {
        int k = job_status_index((const char *)sqlite3_column_text(q, 0));
        if (k >= 0) counts[k] = (long)sqlite3_column_int64(q, 1);
    }
    if (r != SQLITE_DONE) {
        log_err(s, "count jobs");
        rc = JS_ERROR;
    }
    sqlite3_reset(q);
    pthread_mutex_unlock(&s->mu);
    return rc;
}

int job_store_claim_next(job_store *s, job_rec *out, char **scenario)
{
    char now[32];
    int oom = 0;
    util_now_iso(now);
    *scenario = NULL;
    pthread_mutex_lock(&s->mu);
    sqlite3_stmt *q = stmt(s, S_CLAIM);
    bind_text(q, 1, now);
    int r = sqlite3_step(q), rc;
    if (r == SQLITE_ROW) {
        rc = row_to_job(q, out);
        if (rc == JS_OK) {
            *scenario = col_dup(q, 13, &oom);
            if (!*scenario) {
                job_rec_free(out);
                rc = JS_ERROR;
            }
        }
        /* RETURNING: the update completes when the statement runs to its end */
        while ((r = sqlite3_step(q)) == SQLITE_ROW) {
        }
        if (r != SQLITE_DONE) {
            log_err(s, "claim job");
            if (rc == JS_OK) {
                job_rec_free(out);
                free(*scenario);
                *scenario = NULL;
            }
            rc = JS_ERROR;
        }
    } else if (r == SQLITE_DONE) {
        rc = JS_NOTFOUND;
    } else {
        log_err(s, "claim job");
        rc = JS_ERROR;
    }
    sqlite3_reset(q);
    pthread_mutex_unlock(&s->mu);
    return rc;
}

int job_store_set_progress(job_store *s, const char *id, const char *progress)
{
    pthread_mutex_lock(&s->mu);
    sqlite3_stmt *q = stmt(s, S_PROGRESS);
    bind_text(q, 1, id);
    bind_text(q, 2, progress);
    int rc = run_done(s, q, "set progress");
    pthread_mutex_unlock(&s->mu);
    return rc;
}

int job_store_finish(job_store *s, const char *id, const char *status, const char *error,
                     const char *result, const char *progress)
{
    char now[32];
    util_now_iso(now);
    pthread_mutex_lock(&s->mu);
    sqlite3_stmt *q = stmt(s, S_FINISH);
    bind_text(q, 1, id);
    bind_text(q, 2, status);
    bind_text(q, 3, now);
    bind_text(q, 4, error);
    bind_text(q, 5, result);
    bind_text(q, 6, progress);
    int rc = run_done(s, q, "finish job");
    pthread_mutex_unlock(&s->mu);
    return rc;
}

int job_store_requeue(job_store *s, const char *id)
{
    pthread_mutex_lock(&s->mu);
    sqlite3_stmt *q = stmt(s, S_REQUEUE);
    bind_text(q, 1, id);
    int rc = run_done(s, q, "requeue job");
    pthread_mutex_unlock(&s->mu);
    return rc;
}

int job_store_cancel(job_store *s, const char *id, const char *owner, job_rec *out)
{
    char now[32];
    util_now_iso(now);
    int rc;
    pthread_mutex_lock(&s->mu);
    sqlite3_stmt *q = stmt(s, S_CANCEL_QUEUED);
    bind_text(q, 1, id);
    bind_text(q, 2, owner);
    bind_text(q, 3, now);
    rc = run_done(s, q, "cancel queued job");
    if (rc == JS_OK && sqlite3_changes(s->db) == 0) {
        q = stmt(s, S_CANCEL_RUNNING);
        bind_text(q, 1, id);
        bind_text(q, 2, owner);
        rc = run_done(s, q, "cancel running job");
        if (rc == JS_OK) rc = sqlite3_changes(s->db) ? JS_RUNNING : JS_CONFLICT;
    }
    if (rc != JS_ERROR) {
        job_rec tmp;
        q = stmt(s, S_GET);
        bind_text(q, 1, id);
        bind_text(q, 2, owner);
        int g = one_job(s, q, out ? out : &tmp, "get job");
        if (g == JS_NOTFOUND || g == JS_ERROR) rc = g;
        if (g == JS_OK && !out) job_rec_free(&tmp);
    }
    pthread_mutex_unlock(&s->mu);
    return rc;
}

int job_store_delete(job_store *s, const char *id, const char *owner, char **result)
{
    int oom = 0, rc;
    *result = NULL;
    pthread_mutex_lock(&s->mu);
    sqlite3_stmt *q = stmt(s, S_DELETE);
    bind_text(q, 1, id);
    bind_text(q, 2, owner);
    int r = sqlite3_step(q);
    if (r == SQLITE_ROW) {
        *result = col_dup(q, 0, &oom);
        rc = oom ? JS_ERROR : JS_OK;
        while ((r = sqlite3_step(q)) == SQLITE_ROW) {
        }
        if (r != SQLITE_DONE) {
            log_err(s, "delete job");
            rc = JS_ERROR;
        }
    } else if (r == SQLITE_DONE) {
        sqlite3_reset(q);
        q = stmt(s, S_SEQ_OF);
        bind_text(q, 1, id);
        bind_text(q, 2, owner);
        r = sqlite3_step(q);
        rc = r == SQLITE_ROW ? JS_CONFLICT : r == SQLITE_DONE ? JS_NOTFOUND : JS_ERROR;
        if (rc == JS_ERROR) log_err(s, "delete job");
    } else {
        log_err(s, "delete job");
        rc = JS_ERROR;
    }
    sqlite3_reset(q);
    pthread_mutex_unlock(&s->mu);
    if (rc != JS_OK) {
        free(*result);
        *result = NULL;
    }
    return rc;
}

int job_store_exists(job_store *s, const char *id)
{
    pthread_mutex_lock(&s->mu);
    sqlite3_stmt *q = stmt(s, S_EXISTS);
    bind_text(q, 1, id);
    int r = sqlite3_step(q);
    int rc = r == SQLITE_ROW ? 1 : r == SQLITE_DONE ? 0 : JS_ERROR;
    if (rc == JS_ERROR) log_err(s, "job exists");
    sqlite3_reset(q);
    pthread_mutex_unlock(&s->mu);
    return rc;
}

int job_store_ping(job_store *s)
{
    pthread_mutex_lock(&s->mu);
    int rc = exec(s, "SELECT 1");
    pthread_mutex_unlock(&s->mu);
    return rc;
}
