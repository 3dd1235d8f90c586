/*
 * config.h - polydemd's settings: embedded defaults, then the config file, then the command line.
 *
 * The config file holds "key = value" lines; '#' starts a comment. Keys are the long option names
 * of the command line plus the limits below (deploy/polydemd.conf.example lists them all).
 */
#ifndef CONFIG_H
#define CONFIG_H

#include <stddef.h>

typedef struct config {
    char listen[256];         /* "host:port"; port 0 picks a free port (printed at start) */
    char data[4096];          /* holds jobs.sqlite, results/, meshes/ */
    int device;               /* OpenCL device index; -1: the first GPU, else the first device */
    char tokens[4096];        /* token file ("TOKEN NAME" lines); empty: no authentication */
    char dashboard[4096];     /* dashboard directory; empty: found beside the executable */
    char examples[4096];      /* example scenarios; empty: found beside the executable */
    char three_dir[4096];     /* three.js (Debian libjs-three) */
    int insecure;             /* allow a non-loopback listen address without tokens */
    int selftest;             /* run the device self-test at start (--no-selftest clears it) */
    long long max_body;       /* request body limit, bytes (413 beyond) */
    long max_queued;          /* queued jobs limit (429 beyond) */
    long max_particles;       /* per job (422 beyond) */
    long long max_steps;      /* per job (422 beyond) */
    int http_threads;         /* libmicrohttpd thread pool size */
    int max_connections;      /* concurrent connections, SSE streams included */
    double progress_interval; /* s between progress records of a running job */
    double keepalive;         /* s between SSE keep-alive comments */
} config;

/* Fills c with the embedded defaults. */
void config_defaults(config *c);

/*
 * Applies the command line (argv[1..]) over c, reading the --config file first wherever it
 * appears so that flags override it. Returns 0, 1 when --help was asked (usage printed on
 * stdout), or -1 after printing a message on stderr.
 */
int config_from_args(config *c, int argc, char **argv);

/* Applies one "key = value" setting; -1 with a message in msg when the key or value is bad. */
int config_set(config *c, const char *key, const char *value, char *msg, size_t msglen);

/* Reads a config file; -1 with a message naming the file and line on failure. */
int config_load(config *c, const char *path, char *msg, size_t msglen);

#endif
