/*
 * main.c - polydemd: the long-running job service. Reads its settings, opens the data directory
 * (jobs.sqlite, results/, meshes/), starts the worker and the HTTP front, and waits for SIGTERM or
 * SIGINT to shut down: stop accepting, stop the running job at a safe point and queue it again,
 * end the event streams, exit 0.
 */
#define _DEFAULT_SOURCE /* realpath, flock */
#include "api.h"
#include "polydem.h"
#include "config.h"
#include "http.h"
#include "util.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

/* Takes the data directory's lock file: one daemon per data directory. fd, or -1. */
static int lock_data(const char *data)
{
    char path[4400];
    snprintf(path, sizeof path, "%s/polydemd.lock", data);
    int fd = open(path, O_RDWR | O_CREAT | O_CLOEXEC, 0640);
    if (fd < 0) {
        fprintf(stderr, "polydemd: cannot open '%s': %s\n", path, strerror(errno));
        return -1;
    }
    if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
        fprintf(stderr, "polydemd: another polydemd uses '%s' (%s is locked)\n", data, path);
        close(fd);
        return -1;
    }
    return fd;
}

/* A 16-hex-digit job id at the start of name, followed by '.'. */
static int job_file(const char *name, char id[24])
{
    size_t i;
    for (i = 0; i < 16; i++)
        if (!((name[i] >= '0' && name[i] <= '9') || (name[i] >= 'a' && name[i] <= 'f'))) return 0;
    if (name[16] != '.') return 0;
    memcpy(id, name, 16);
    id[16] = 0;
    return 1;
}

static int ends_with(const char *s, const char *suffix)
{
    size_t n = strlen(s), k = strlen(suffix);
    return n >= k && !strcmp(s + n - k, suffix);
}

/* Whether name is the .partial a failed job's error says its frames were kept in (the run's
 * result write failed, a full disk: pd_run keeps what was written under that name). */
static int kept_partial(job_store *st, const char *id, const char *name)
{
    job_rec j;
    if (job_store_get(st, id, NULL, &j) != JS_OK) return 0;
    char quoted[300];
    snprintf(quoted, sizeof quoted, "/%s' ", name);
    int kept = !strcmp(j.status, "failed") && j.error && strstr(j.error, quoted);
    job_rec_free(&j);
    return kept;
}

/* After a crash: half-written results and files of deleted jobs go, but not the frames a failed
 * job's error says were kept; uploads left midway go too. */
static void sweep(job_store *st, const char *results, const char *meshes)
{
    char path[4700], id[24];
    DIR *d = opendir(results);
    struct dirent *e;
    while (d && (e = readdir(d))) {
        if (!job_file(e->d_name, id)) continue;
        if (!ends_with(e->d_name, ".partial") && job_store_exists(st, id) != 0) continue;
        if (ends_with(e->d_name, ".h5.partial") && kept_partial(st, id, e->d_name)) continue;
        snprintf(path, sizeof path, "%s/%s", results, e->d_name);
        if (unlink(path) == 0) fprintf(stderr, "polydemd: removed stray '%s'\n", path);
    }
    if (d) closedir(d);
    d = opendir(meshes);
    while (d && (e = readdir(d))) {
        if (strncmp(e->d_name, ".upload-", 8)) continue;
        snprintf(path, sizeof path, "%s/%s", meshes, e->d_name);
        unlink(path);
    }
    if (d) closedir(d);
}

static int is_dir(const char *p)
{
    struct stat st;
    return stat(p, &st) == 0 && S_ISDIR(st.st_mode);
}

/*
 * A directory of the repository (the dashboard, the examples): the configured one, else the
 * first of rel[] that exists beside the executable: <prefix>/share/polydem/... for an installed
 * <prefix>/bin/polydemd, then the source tree's for build/polydemd or build/san/polydemd. The
 * installed one comes first: from ~/.local/bin, "../../examples" is ~/examples.
 */
static void find_dir(const char *configured, const char *what, const char *const *rel, int nrel,
                     char *out, size_t cap)
{
    out[0] = 0;
    if (configured[0]) {
        if (is_dir(configured))
            snprintf(out, cap, "%s", configured);
        else
            fprintf(stderr, "polydemd: %s directory '%s' does not exist\n", what, configured);
        return;
    }
    char exe[PATH_MAX], cand[PATH_MAX + 64], real[PATH_MAX];
    ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (n <= 0) return;
    exe[n] = 0;
    char *slash = strrchr(exe, '/');
    if (!slash) return;
    *slash = 0;
    for (int i = 0; i < nrel; i++) {
        snprintf(cand, sizeof cand, "%s/%s", exe, rel[i]);
        if (is_dir(cand) && realpath(cand, real)) {
            snprintf(out, cap, "%s", real);
            return;
        }
    }
}

static int make_dirs(app *a, const config *cfg)
{
    if (util_fmt(a->results_dir, sizeof a->results_dir, "%s/results", cfg->data) ||
        util_fmt(a->meshes_dir, sizeof a->meshes_dir, "%s/meshes", cfg->data)) {
        fprintf(stderr, "polydemd: data directory name too long\n");
        return -1;
    }
    const char *dirs[] = {cfg->data, a->results_dir, a->meshes_dir};
    for (int i = 0; i < 3; i++) {
        if (util_mkdir_p(dirs[i]) != 0) {
            fprintf(stderr, "polydemd: cannot create '%s': %s\n", dirs[i], strerror(errno));
            return -1;
        }
    }
    return 0;
}

int main(int argc, char **argv)
{
    static config cfg;
    static app a;
    char msg[1024], dbpath[4400];
    if (argc == 2 && !strcmp(argv[1], "--routes")) { /* for the OpenAPI test */
        http_print_routes(stdout);
        return 0;
    }
    config_defaults(&cfg);
    int rc = config_from_args(&cfg, argc, argv);
    if (rc != 0) return rc > 0 ? 0 : 2;
    a.cfg = &cfg;

    /* SIGTERM/SIGINT are taken by sigwait below, so every thread started later blocks them */
    sigset_t stop;
    sigemptyset(&stop);
    sigaddset(&stop, SIGTERM);
    sigaddset(&stop, SIGINT);
    sigaddset(&stop, SIGHUP); /* a closed terminal: shut down cleanly rather than die mid-job */
    if (pthread_sigmask(SIG_BLOCK, &stop, NULL) != 0 || signal(SIGPIPE, SIG_IGN) == SIG_ERR) {
        fprintf(stderr, "polydemd: cannot set up signal handling\n");
        return 1;
    }
    if (cfg.tokens[0] && auth_load(cfg.tokens, &a.auth, msg, sizeof msg) != 0) {
        fprintf(stderr, "polydemd: %s\n", msg);
        return 2;
    }
    int lock = -1;
    rc = 1;
    if (make_dirs(&a, &cfg) != 0 || (lock = lock_data(cfg.data)) < 0) goto out;
    snprintf(dbpath, sizeof dbpath, "%s/jobs.sqlite", cfg.data);
    if (job_store_open(dbpath, &a.st, msg, sizeof msg) != 0) {
        fprintf(stderr, "polydemd: database: %s\n", msg);
        goto out;
    }
    int requeued = 0, cancelled = 0, failed = 0;
    if (job_store_recover(a.st, &requeued, &cancelled, &failed) != JS_OK) goto out;
    if (requeued || cancelled)
        fprintf(stderr, "polydemd: recovered after a crash: %d job(s) queued again, %d cancelled\n",
                requeued, cancelled);
    if (failed)
        fprintf(stderr,
                "polydemd: recovered after a crash: %d job(s) failed, the daemon having died "
                "while running each of them %d times\n",
                failed, JS_MAX_CRASHES);
    sweep(a.st, a.results_dir, a.meshes_dir);
    static const char *const dash[] = {"../share/polydem/dashboard", "../clients/dashboard",
                                       "../../clients/dashboard"};
    static const char *const ex[] = {"../share/polydem/examples", "../examples", "../../examples"};
    find_dir(cfg.dashboard, "dashboard", dash, 3, a.dashboard, sizeof a.dashboard);
    find_dir(cfg.examples, "examples", ex, 3, a.examples, sizeof a.examples);
    if (sse_hub_create(cfg.keepalive, &a.hub) != 0) {
        fprintf(stderr, "polydemd: cannot start the event streams\n");
        goto out;
    }
    if (worker_start(&cfg, a.st, a.hub, &a.w, msg, sizeof msg) != 0) {
        fprintf(stderr, "polydemd: %s\n", msg);
        goto out;
    }
    struct MHD_Daemon *d = NULL;
    unsigned port = 0;
    if (http_start(&a, &d, &port, msg, sizeof msg) != 0) {
        fprintf(stderr, "polydemd: %s\n", msg);
        goto out;
    }
    char host[256];
    snprintf(host, sizeof host, "%s", cfg.listen);
    char *colon = strrchr(host, ':');
    if (colon) *colon = 0;
    fprintf(stderr, "polydemd: listening on http://%s:%u (data in '%s'%s%s)\n", host, port,
            cfg.data, a.auth ? ", tokens required" : "",
            a.dashboard[0] ? ", dashboard at /" : ", no dashboard");
    fflush(stderr);

    int sig = 0;
    while (sigwait(&stop, &sig) != 0) {
    }
    fprintf(stderr, "polydemd: %s: shutting down\n",
            sig == SIGTERM  ? "SIGTERM"
            : sig == SIGHUP ? "SIGHUP"
                            : "SIGINT");
    http_quiesce(d);
    worker_stop(a.w); /* the running job stops at a safe point and is queued again */
    sse_close_all(a.hub);
    /* Let the ended event streams send what they hold (the final status events) and close
     * cleanly before MHD drops every connection; a client that reads nothing costs 2 s at most. */
    for (int i = 0; i < 200 && sse_count(a.hub) > 0; i++)
        nanosleep(&(struct timespec){0, 10000000}, NULL);
    MHD_stop_daemon(d);
    rc = 0;
    fprintf(stderr, "polydemd: stopped\n");
out:
    worker_free(a.w);
    sse_hub_destroy(a.hub);
    job_store_close(a.st);
    auth_free(a.auth);
    if (lock >= 0) close(lock);
    if (pd_results_unclosed()) { /* a disk filled up under a job: HDF5's exit clean-up would crash
                                  */
        fflush(NULL);
        _exit(rc);
    }
    return rc;
}
