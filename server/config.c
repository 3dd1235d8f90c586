/* config.c - polydemd's settings: defaults, config file, command line. */
#include "config.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void config_defaults(config *c)
{
    memset(c, 0, sizeof *c);
    snprintf(c->listen, sizeof c->listen, "127.0.0.1:8080");
    snprintf(c->data, sizeof c->data, "polydem-data");
    c->device = -1;
    snprintf(c->three_dir, sizeof c->three_dir, "/usr/share/javascript/three");
    c->selftest = 1;
    c->max_body = 64LL << 20;
    c->max_queued = 1000;
    c->max_particles = 1000000;
    c->max_steps = 1000000000LL;
    c->http_threads = 4;
    c->max_connections = 256;
    c->progress_interval = 0.5;
    c->keepalive = 15;
}

static int set_str(char *dst, size_t cap, const char *key, const char *v, char *msg, size_t ml)
{
    if (strlen(v) >= cap) {
        snprintf(msg, ml, "'%s': value longer than %zu bytes", key, cap - 1);
        return -1;
    }
    snprintf(dst, cap, "%s", v);
    return 0;
}

static int set_ll(long long *dst, long long lo, long long hi, const char *key, const char *v,
                  char *msg, size_t ml)
{
    char *end;
    errno = 0;
    long long x = strtoll(v, &end, 10);
    if (errno || end == v || *end || x < lo || x > hi) {
        snprintf(msg, ml, "'%s': '%s' is not an integer in [%lld, %lld]", key, v, lo, hi);
        return -1;
    }
    *dst = x;
    return 0;
}

static int set_double(double *dst, double lo, double hi, const char *key, const char *v, char *msg,
                      size_t ml)
{
    char *end;
    errno = 0;
    double x = strtod(v, &end);
    if (errno || end == v || *end || !(x >= lo && x <= hi)) {
        snprintf(msg, ml, "'%s': '%s' is not a number in [%g, %g]", key, v, lo, hi);
        return -1;
    }
    *dst = x;
    return 0;
}

static int set_bool(int *dst, const char *key, const char *v, char *msg, size_t ml)
{
    if (!strcmp(v, "true") || !strcmp(v, "yes") || !strcmp(v, "1") || !strcmp(v, "on")) {
        *dst = 1;
    } else if (!strcmp(v, "false") || !strcmp(v, "no") || !strcmp(v, "0") || !strcmp(v, "off")) {
        *dst = 0;
    } else {
        snprintf(msg, ml, "'%s': '%s' is not a boolean (true or false)", key, v);
        return -1;
    }
    return 0;
}

int config_set(config *c, const char *key, const char *v, char *msg, size_t ml)
{
    long long x;
    int rc;
    if (!strcmp(key, "listen")) return set_str(c->listen, sizeof c->listen, key, v, msg, ml);
    if (!strcmp(key, "data")) return set_str(c->data, sizeof c->data, key, v, msg, ml);
    if (!strcmp(key, "tokens")) return set_str(c->tokens, sizeof c->tokens, key, v, msg, ml);
    if (!strcmp(key, "dashboard"))
        return set_str(c->dashboard, sizeof c->dashboard, key, v, msg, ml);
    if (!strcmp(key, "examples")) return set_str(c->examples, sizeof c->examples, key, v, msg, ml);
    if (!strcmp(key, "three")) return set_str(c->three_dir, sizeof c->three_dir, key, v, msg, ml);
    if (!strcmp(key, "insecure")) return set_bool(&c->insecure, key, v, msg, ml);
    if (!strcmp(key, "selftest")) return set_bool(&c->selftest, key, v, msg, ml);
    if (!strcmp(key, "device")) {
        rc = set_ll(&x, -1, 1023, key, v, msg, ml);
        if (!rc) c->device = (int)x;
        return rc;
    }
    if (!strcmp(key, "max_body_bytes"))
        return set_ll(&c->max_body, 1024, 1LL << 40, key, v, msg, ml);
    if (!strcmp(key, "max_queued_jobs")) {
        rc = set_ll(&x, 1, 100000000, key, v, msg, ml);
        if (!rc) c->max_queued = (long)x;
        return rc;
    }
    if (!strcmp(key, "max_particles")) {
        rc = set_ll(&x, 1, 1000000000, key, v, msg, ml);
        if (!rc) c->max_particles = (long)x;
        return rc;
    }
    if (!strcmp(key, "max_steps")) return set_ll(&c->max_steps, 1, 1LL << 50, key, v, msg, ml);
    if (!strcmp(key, "http_threads")) {
        rc = set_ll(&x, 1, 256, key, v, msg, ml);
        if (!rc) c->http_threads = (int)x;
        return rc;
    }
    if (!strcmp(key, "max_connections")) {
        rc = set_ll(&x, 4, 100000, key, v, msg, ml);
        if (!rc) c->max_connections = (int)x;
        return rc;
    }
    if (!strcmp(key, "progress_interval"))
        return set_double(&c->progress_interval, 0.01, 3600, key, v, msg, ml);
    if (!strcmp(key, "keepalive_seconds"))
        return set_double(&c->keepalive, 0.1, 3600, key, v, msg, ml);
    snprintf(msg, ml, "unknown setting '%s'", key);
    return -1;
}

static char *trim(char *s)
{
    while (*s == ' ' || *s == '\t')
        s++;
    size_t n = strlen(s);
    while (n && (s[n - 1] == ' ' || s[n - 1] == '\t' || s[n - 1] == '\n' || s[n - 1] == '\r'))
        s[--n] = 0;
    return s;
}

int config_load(config *c, const char *path, char *msg, size_t ml)
{
    FILE *f = fopen(path, "r");
    if (!f) {
        snprintf(msg, ml, "cannot open config '%s': %s", path, strerror(errno));
        return -1;
    }
    char line[8192], sub[512];
    int lineno = 0, rc = 0;
    while (fgets(line, sizeof line, f)) {
        lineno++;
        char *hash = strchr(line, '#');
        if (hash) *hash = 0;
        char *s = trim(line);
        if (!*s) continue;
        char *eq = strchr(s, '=');
        if (!eq) {
            snprintf(msg, ml, "%s:%d: expected 'key = value'", path, lineno);
            rc = -1;
            break;
        }
        *eq = 0;
        char *key = trim(s), *val = trim(eq + 1);
        if (config_set(c, key, val, sub, sizeof sub) != 0) {
            snprintf(msg, ml, "%s:%d: %s", path, lineno, sub);
            rc = -1;
            break;
        }
    }
    if (!rc && ferror(f)) {
        snprintf(msg, ml, "cannot read config '%s': %s", path, strerror(errno));
        rc = -1;
    }
    fclose(f);
    return rc;
}

static const char usage[] =
    "usage: polydemd [--listen HOST:PORT] [--data DIR] [--device N] [--config FILE]\n"
    "                [--tokens FILE] [--insecure] [--dashboard DIR] [--no-selftest]\n"
    "\n"
    "  --listen HOST:PORT  address to serve (default 127.0.0.1:8080; port 0 picks a free one)\n"
    "  --data DIR          jobs.sqlite, results/ and meshes/ (default ./polydem-data)\n"
    "  --device N          OpenCL device as `polydem devices` numbers them (default: the first\n"
    "                      GPU, else the first device)\n"
    "  --config FILE       settings file, 'key = value' lines (command-line flags win)\n"
    "  --tokens FILE       'TOKEN NAME' lines: every /v1 route then needs a bearer token\n"
    "  --insecure          allow a non-loopback address without tokens\n"
    "  --dashboard DIR     the web dashboard's files (default: <prefix>/share/polydem/dashboard\n"
    "                      for an installed <prefix>/bin/polydemd, else clients/dashboard\n"
    "                      beside the build)\n"
    "  --no-selftest       use the device without the start-up self-test (development)\n";

/* Flags taking a value, and the config key each sets. */
static const struct {
    const char *flag, *key;
} value_flags[] = {
    {"--listen", "listen"}, {"--data", "data"},         {"--device", "device"},
    {"--tokens", "tokens"}, {"--token-file", "tokens"}, {"--dashboard", "dashboard"},
    {"--config", NULL},
};

int config_from_args(config *c, int argc, char **argv)
{
    char msg[1024];
    /* pass 1: the config file, so that flags override it */
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            fputs(usage, stdout);
            return 1;
        }
        if (!strcmp(argv[i], "--config")) {
            if (i + 1 >= argc) {
                fprintf(stderr, "polydemd: --config needs a value\n%s", usage);
                return -1;
            }
            if (config_load(c, argv[++i], msg, sizeof msg) != 0) {
                fprintf(stderr, "polydemd: %s\n", msg);
                return -1;
            }
        }
    }
    /* pass 2: every other flag */
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--insecure")) {
            c->insecure = 1;
            continue;
        }
        if (!strcmp(a, "--no-selftest")) {
            c->selftest = 0;
            continue;
        }
        size_t k, nflags = sizeof value_flags / sizeof value_flags[0];
        for (k = 0; k < nflags; k++)
            if (!strcmp(a, value_flags[k].flag)) break;
        if (k == nflags) {
            fprintf(stderr, "polydemd: unknown argument '%s'\n%s", a, usage);
            return -1;
        }
        if (i + 1 >= argc) {
            fprintf(stderr, "polydemd: %s needs a value\n%s", a, usage);
            return -1;
        }
        i++;
        if (!value_flags[k].key) continue; /* --config, read in pass 1 */
        if (config_set(c, value_flags[k].key, argv[i], msg, sizeof msg) != 0) {
            fprintf(stderr, "polydemd: %s: %s\n", a, msg);
            return -1;
        }
    }
    return 0;
}
