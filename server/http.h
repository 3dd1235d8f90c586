/*
 * http.h - the HTTP front: libmicrohttpd set-up, request bodies and limits, authentication,
 * routing, and the JSON response helpers the route handlers (api_*.c, static_files.c) share.
 *
 * Threading: libmicrohttpd's internal thread pool (MHD_USE_AUTO_INTERNAL_THREAD with
 * MHD_OPTION_THREAD_POOL_SIZE) and MHD_ALLOW_SUSPEND_RESUME. A handful of threads serve any
 * number of connections; SSE streams suspend their connection while they wait for events, so
 * they hold no thread, and no request waits for a running job.
 */
#ifndef HTTP_H
#define HTTP_H

#include "auth.h"
#include "config.h"
#include "job_store.h"
#include "sse.h"
#include "worker.h"

#include <jansson.h>
#include <microhttpd.h>
#include <stdatomic.h>
#include <stdio.h>

/* What every handler can reach. */
typedef struct app {
    const config *cfg;
    job_store *st;
    worker *w;
    sse_hub *hub;
    auth *auth;              /* NULL: no authentication */
    char dashboard[4096];    /* the dashboard directory, "" when none was found */
    char examples[4096];     /* the example scenarios, "" when none were found */
    char results_dir[4200];  /* <data>/results */
    char meshes_dir[4200];   /* <data>/meshes */
    atomic_long requests[6]; /* answered requests by status class: [2] = 2xx ... [5] = 5xx */
    atomic_long requests_by_code[600];
} app;

/* One request in progress. */
typedef struct http_req {
    app *app;
    struct MHD_Connection *conn;
    const char *method;
    const char *url;
    char *body; /* NUL-terminated */
    size_t len, cap;
    int too_large;
    const char *owner; /* the token's name; NULL without authentication */
} http_req;

/* Starts serving cfg->listen; the bound port goes to *port. -1 with a message on failure. */
int http_start(app *a, struct MHD_Daemon **out, unsigned *port, char *msg, size_t msglen);

/* Prints every route as "METHOD PATH" lines (`polydemd --routes`). */
void http_print_routes(FILE *out);

/* Stop accepting new connections (the listening socket closes); requests in flight go on. */
void http_quiesce(struct MHD_Daemon *d);

/* Queues resp with status (counted for /metrics) and releases it. */
enum MHD_Result http_queue(http_req *r, unsigned status, struct MHD_Response *resp);

/* Sends body (reference stolen; NULL means out of memory: 500) as application/json. */
enum MHD_Result http_json(http_req *r, unsigned status, json_t *body);

/* The same with one more header (hname NULL: none). */
enum MHD_Result http_json_hdr(http_req *r, unsigned status, json_t *body, const char *hname,
                              const char *hval);

/* Sends {"error": {"code", "message"}}; message is printf-style. */
enum MHD_Result http_error(http_req *r, unsigned status, const char *code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

/* Sends {"error": {"code", "message", "details": details}} (details stolen). */
enum MHD_Result http_error_details(http_req *r, unsigned status, const char *code,
                                   const char *message, json_t *details);

/* Sends text with a content type. */
enum MHD_Result http_text(http_req *r, unsigned status, const char *type, const char *text,
                          size_t len);

/* A query argument, or NULL. */
const char *http_arg(http_req *r, const char *key);

/* 400 for any query argument not in allowed (NULL-terminated); 1 when the reply was queued. */
int http_args_only(http_req *r, const char *const *allowed, enum MHD_Result *ret);

/* Escapes a name for use in a JSON pointer ("~" -> "~0", "/" -> "~1"). */
void http_pointer_escape(const char *in, char *out, size_t cap);

#endif
