/* http.c - libmicrohttpd set-up, request bodies, limits, authentication and routing. */
#include "http.h"

#include "api.h"

#include <arpa/inet.h>
#include <errno.h>
#include <netdb.h>
#include <netinet/in.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

/* ---- responses ----------------------------------------------------------------------------- */

enum MHD_Result http_queue(http_req *r, unsigned status, struct MHD_Response *resp)
{
    if (!resp) {
        fprintf(stderr, "polydemd: %s %s: cannot build the response\n", r->method, r->url);
        return MHD_NO;
    }
    enum MHD_Result rc = MHD_queue_response(r->conn, status, resp);
    MHD_destroy_response(resp);
    if (rc == MHD_YES && status < 600) {
        atomic_fetch_add(&r->app->requests[status / 100], 1);
        atomic_fetch_add(&r->app->requests_by_code[status], 1);
    }
    return rc;
}

enum MHD_Result http_text(http_req *r, unsigned status, const char *type, const char *text,
                          size_t len)
{
    struct MHD_Response *resp =
        MHD_create_response_from_buffer(len, (void *)text, MHD_RESPMEM_MUST_COPY);
    if (!resp) return MHD_NO;
    if (MHD_add_response_header(resp, "Content-Type", type) != MHD_YES ||
        MHD_add_response_header(resp, "Cache-Control", "no-store") != MHD_YES) {
        MHD_destroy_response(resp);
        return MHD_NO;
    }
    return http_queue(r, status, resp);
}

enum MHD_Result http_json_hdr(http_req *r, unsigned status, json_t *body, const char *hname,
                              const char *hval)
{
    char *text = body ? json_dumps(body, JSON_COMPACT | JSON_REAL_PRECISION(17)) : NULL;
    json_decref(body);
    if (!text) {
        static const char oom[] =
            "{\"error\":{\"code\":\"internal\",\"message\":\"out of memory\"}}";
        return http_text(r, 500, "application/json", oom, sizeof oom - 1);
    }
    size_t n = strlen(text);
    struct MHD_Response *resp = MHD_create_response_from_buffer_with_free_callback(n, text, free);
    if (!resp) {
        free(text);
        return MHD_NO;
    }
    if (MHD_add_response_header(resp, "Content-Type", "application/json") != MHD_YES ||
        MHD_add_response_header(resp, "Cache-Control", "no-store") != MHD_YES ||
        (hname && MHD_add_response_header(resp, hname, hval) != MHD_YES)) {
        MHD_destroy_response(resp);
        return MHD_NO;
    }
    return http_queue(r, status, resp);
}

enum MHD_Result http_json(http_req *r, unsigned status, json_t *body)
{
    return http_json_hdr(r, status, body, NULL, NULL);
}

enum MHD_Result http_error_details(http_req *r, unsigned status, const char *code,
                                   const char *message, json_t *details)
{
    json_t *e = json_pack("{s:s, s:s}", "code", code, "message", message);
    if (e && details)
        json_object_set_new(e, "details", details);
    else
        json_decref(details);
    return http_json(r, status, e ? json_pack("{s:o}", "error", e) : NULL);
}

enum MHD_Result http_error(http_req *r, unsigned status, const char *code, const char *fmt, ...)
{
    char msg[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return http_error_details(r, status, code, msg, NULL);
}

const char *http_arg(http_req *r, const char *key)
{
    return MHD_lookup_connection_value(r->conn, MHD_GET_ARGUMENT_KIND, key);
}

typedef struct args_check {
    const char *const *allowed;
    const char *bad;
} args_check;

static enum MHD_Result check_arg(void *cls, enum MHD_ValueKind kind, const char *key,
                                 const char *value)
{
    args_check *c = cls;
    (void)kind;
    (void)value;
    for (const char *const *a = c->allowed; *a; a++)
        if (!strcmp(*a, key)) return MHD_YES;
    c->bad = key;
    return MHD_NO;
}

int http_args_only(http_req *r, const char *const *allowed, enum MHD_Result *ret)
{
    args_check c = {allowed, NULL};
    MHD_get_connection_values(r->conn, MHD_GET_ARGUMENT_KIND, check_arg, &c);
    if (!c.bad) return 0;
    char list[256] = "";
    for (const char *const *a = allowed; *a; a++) {
        size_t n = strlen(list);
        snprintf(list + n, sizeof list - n, "%s%s", n ? ", " : "", *a);
    }
    *ret = http_error(r, 400, "invalid_parameter", "unknown query parameter '%.100s' (known: %s)",
                      c.bad, list[0] ? list : "none");
    return 1;
}

void http_pointer_escape(const char *in, char *out, size_t cap)
{
    size_t o = 0;
    for (; *in && o + 3 < cap; in++) {
        if (*in == '~' || *in == '/') {
            out[o++] = '~';
            out[o++] = *in == '~' ? '0' : '1';
        } else {
            out[o++] = *in;
        }
    }
    out[o] = 0;
}

/* ---- routing ------------------------------------------------------------------------------- */

#define MAX_SEGS 6

static int is(const char *a, const char *b)
{
    return !strcmp(a, b);
}

static enum MHD_Result not_allowed(http_req *r, const char *allow)
{
    json_t *e = json_pack("{s:{s:s, s:s++}}", "error", "code", "method_not_allowed", "message",
                          r->method, " is not allowed here; allowed: ", allow);
    return http_json_hdr(r, 405, e, "Allow", allow);
}

static enum MHD_Result unauthorized(http_req *r, const char *why)
{
    json_t *e = json_pack("{s:{s:s, s:s}}", "error", "code", "unauthorized", "message", why);
    return http_json_hdr(r, 401, e, "WWW-Authenticate", "Bearer realm=\"polydemd\"");
}

static enum MHD_Result not_found(http_req *r)
{
    return http_error(r, 404, "not_found", "no route %s %.200s", r->method, r->url);
}

/* GET and HEAD read; everything else changes state. */
static int reading(http_req *r)
{
    return is(r->method, "GET") || is(r->method, "HEAD");
}

/* /v1/jobs/{id}/...: s[0] = "jobs", s[1] = id. */
static enum MHD_Result route_job(http_req *r, char **s, int n)
{
    const char *id = s[1];
    if (strlen(id) >= 24) return http_error(r, 404, "job_not_found", "no job '%.40s'", id);
    if (n == 2) {
        if (reading(r)) return api_job_get(r, id);
        if (is(r->method, "DELETE")) return api_job_delete(r, id);
        return not_allowed(r, "GET, HEAD, DELETE");
    }
    const char *sub = s[2];
    if (n == 3 && is(sub, "cancel")) {
        if (is(r->method, "POST")) return api_job_cancel(r, id);
        return not_allowed(r, "POST");
    }
    if (!reading(r)) {
        if (n <= 4) return not_allowed(r, "GET, HEAD");
        return not_found(r);
    }
    if (n == 3 && is(sub, "events")) return api_job_events(r, id);
    if (n == 3 && is(sub, "scenario")) return api_job_scenario(r, id);
    if (n == 3 && is(sub, "result")) return api_job_result(r, id, 0);
    if (n == 3 && is(sub, "result.xmf")) return api_job_result(r, id, 1);
    if (n == 3 && is(sub, "stats")) return api_job_stats(r, id);
    if (n == 3 && is(sub, "shapes")) return api_job_shapes(r, id);
    if (n == 3 && is(sub, "frames")) return api_job_frames(r, id, NULL);
    if (n == 4 && is(sub, "frames")) return api_job_frames(r, id, s[3]);
    return not_found(r);
}

static enum MHD_Result route_v1(http_req *r, char **s, int n)
{
    app *a = r->app;
    if (a->auth) {
        const char *tok = auth_bearer(
            MHD_lookup_connection_value(r->conn, MHD_HEADER_KIND, MHD_HTTP_HEADER_AUTHORIZATION));
        /* EventSource cannot set headers: the event streams also take ?token= */
        int events = n >= 1 && is(s[n - 1], "events");
        if (!tok && events) tok = http_arg(r, "token");
        if (!tok) return unauthorized(r, "this server needs 'Authorization: Bearer TOKEN'");
        r->owner = auth_lookup(a->auth, tok);
        if (!r->owner) return unauthorized(r, "unknown token");
    }
    if (n == 0) return not_found(r);
    if (is(s[0], "jobs")) {
        if (n == 1) {
            if (is(r->method, "POST")) return api_jobs_create(r);
            if (reading(r)) return api_jobs_list(r);
            return not_allowed(r, "GET, HEAD, POST");
        }
        return route_job(r, s, n);
    }
    if (n == 2 && is(s[0], "scenarios") && is(s[1], "validate")) {
        if (is(r->method, "POST")) return api_validate(r);
        return not_allowed(r, "POST");
    }
    if (n == 1 && is(s[0], "meshes")) {
        if (is(r->method, "POST")) return api_meshes_upload(r);
        return not_allowed(r, "POST");
    }
    if (n == 1 && is(s[0], "device")) {
        if (reading(r)) return api_device(r);
        return not_allowed(r, "GET, HEAD");
    }
    if (n == 1 && is(s[0], "events")) {
        if (reading(r)) return api_job_events(r, NULL);
        return not_allowed(r, "GET, HEAD");
    }
    return not_found(r);
}

static enum MHD_Result route(http_req *r)
{
    char path[1024], *s[MAX_SEGS];
    int n = 0;
    if (strlen(r->url) >= sizeof path)
        return http_error(r, 414, "uri_too_long", "the path is longer than %zu bytes",
                          sizeof path - 1);
    if (is(r->url, "/healthz")) {
        if (reading(r)) return api_healthz(r);
        return not_allowed(r, "GET, HEAD");
    }
    if (is(r->url, "/metrics")) {
        if (reading(r)) return api_metrics(r);
        return not_allowed(r, "GET, HEAD");
    }
    if (strncmp(r->url, "/v1/", 4) && !is(r->url, "/v1")) {
        if (reading(r)) return static_serve(r, r->url);
        return not_allowed(r, "GET, HEAD");
    }
    snprintf(path, sizeof path, "%s", r->url + 3);
    char *save = NULL;
    for (char *t = strtok_r(path, "/", &save); t; t = strtok_r(NULL, "/", &save)) {
        if (n == MAX_SEGS) return not_found(r);
        s[n++] = t;
    }
    return route_v1(r, s, n);
}

/* ---- libmicrohttpd callbacks --------------------------------------------------------------- */

static enum MHD_Result on_request(void *cls, struct MHD_Connection *c, const char *url,
                                  const char *method, const char *version, const char *upload,
                                  size_t *upload_size, void **con_cls)
{
    app *a = cls;
    http_req *r = *con_cls;
    (void)version;
    if (!r) {
        r = calloc(1, sizeof *r);
        if (!r) return MHD_NO;
        r->app = a;
        r->conn = c;
        r->method = method;
        r->url = url;
        *con_cls = r;
        /* a 413 can only go out from this first call: decide on Content-Length here */
        const char *cl = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Content-Length");
        if (cl) {
            char *end;
            errno = 0;
            unsigned long long n = strtoull(cl, &end, 10);
            if (errno || end == cl || *end || n > (unsigned long long)a->cfg->max_body) {
                r->too_large = 2; /* answered */
                return http_error(r, 413, "body_too_large",
                                  "request body of %s bytes exceeds this server's limit of %lld "
                                  "bytes (max_body_bytes)",
                                  cl, a->cfg->max_body);
            }
        }
        return MHD_YES;
    }
    if (*upload_size) {
        size_t n = *upload_size;
        *upload_size = 0;
        if (r->too_large) return MHD_YES;
        if (r->len + n > (size_t)a->cfg->max_body) { /* chunked: answer once it has all come */
            r->too_large = 1;
            free(r->body);
            r->body = NULL;
            r->len = r->cap = 0;
            return MHD_YES;
        }
        if (r->len + n + 1 > r->cap) {
            size_t nc = r->cap ? r->cap : 4096;
            while (nc < r->len + n + 1)
                nc *= 2;
            char *nb = realloc(r->body, nc);
            if (!nb) return MHD_NO;
            r->body = nb;
            r->cap = nc;
        }
        memcpy(r->body + r->len, upload, n);
        r->len += n;
        r->body[r->len] = 0;
        return MHD_YES;
    }
    if (r->too_large == 2) return MHD_YES;
    if (r->too_large)
        return http_error(r, 413, "body_too_large",
                          "request body exceeds this server's limit of %lld bytes "
                          "(max_body_bytes)",
                          a->cfg->max_body);
    if (!r->body) {
        r->body = calloc(1, 1);
        if (!r->body) return MHD_NO;
    }
    return route(r);
}

static void on_completed(void *cls, struct MHD_Connection *c, void **con_cls,
                         enum MHD_RequestTerminationCode toe)
{
    (void)cls;
    (void)c;
    (void)toe;
    http_req *r = *con_cls;
    if (!r) return;
    free(r->body);
    free(r);
    *con_cls = NULL;
}

static void on_log(void *cls, const char *fmt, va_list ap)
{
    (void)cls;
    char line[512];
    vsnprintf(line, sizeof line, fmt, ap);
    size_t n = strlen(line);
    while (n && line[n - 1] == '\n')
        line[--n] = 0;
    fprintf(stderr, "polydemd: http: %s\n", line);
}

static void on_panic(void *cls, const char *file, unsigned line, const char *reason)
{
    (void)cls;
    fprintf(stderr, "polydemd: libmicrohttpd failure at %s:%u: %s\n", file, line,
            reason ? reason : "unknown");
    abort();
}

/* ---- start --------------------------------------------------------------------------------- */

/* Parses "HOST:PORT" or "[V6]:PORT" into an address; loopback tells whether it is one. */
static int parse_listen(const char *spec, struct sockaddr_storage *ss, int *v6, int *loopback,
                        char *msg, size_t ml)
{
    char host[256], port[16];
    const char *colon;
    if (spec[0] == '[') {
        const char *close = strchr(spec, ']');
        if (!close || close[1] != ':' || (size_t)(close - spec - 1) >= sizeof host) goto bad;
        memcpy(host, spec + 1, (size_t)(close - spec - 1));
        host[close - spec - 1] = 0;
        colon = close + 1;
    } else {
        colon = strrchr(spec, ':');
        if (!colon || (size_t)(colon - spec) >= sizeof host) goto bad;
        memcpy(host, spec, (size_t)(colon - spec));
        host[colon - spec] = 0;
    }
    if (snprintf(port, sizeof port, "%s", colon + 1) >= (int)sizeof port || !port[0]) goto bad;
    for (const char *p = port; *p; p++)
        if (*p < '0' || *p > '9') goto bad;
    if (atol(port) > 65535) goto bad;
    struct addrinfo hints = {0}, *res = NULL;
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    hints.ai_flags = AI_NUMERICSERV | AI_PASSIVE;
    int e = getaddrinfo(host[0] ? host : NULL, port, &hints, &res);
    if (e != 0) {
        snprintf(msg, ml, "--listen '%s': %s", spec, gai_strerror(e));
        return -1;
    }
    memcpy(ss, res->ai_addr, res->ai_addrlen);
    *v6 = res->ai_family == AF_INET6;
    if (*v6)
        *loopback = IN6_IS_ADDR_LOOPBACK(&((struct sockaddr_in6 *)res->ai_addr)->sin6_addr);
    else
        *loopback = (ntohl(((struct sockaddr_in *)res->ai_addr)->sin_addr.s_addr) >> 24) == 127;
    freeaddrinfo(res);
    return 0;
bad:
    snprintf(msg, ml, "--listen '%s': expected HOST:PORT or [IPV6]:PORT", spec);
    return -1;
}

int http_start(app *a, struct MHD_Daemon **out, unsigned *port, char *msg, size_t ml)
{
    struct sockaddr_storage ss;
    int v6 = 0, loopback = 0;
    *out = NULL;
    if (parse_listen(a->cfg->listen, &ss, &v6, &loopback, msg, ml) != 0) return -1;
    if (!loopback && !a->auth && !a->cfg->insecure) {
        snprintf(msg, ml,
                 "refusing to listen on non-loopback address '%s' without --tokens "
                 "(give --insecure to do it anyway)",
                 a->cfg->listen);
        return -1;
    }
    MHD_set_panic_func(on_panic, NULL);
    unsigned flags = MHD_USE_AUTO_INTERNAL_THREAD | MHD_ALLOW_SUSPEND_RESUME | MHD_USE_ERROR_LOG;
    if (v6) flags |= MHD_USE_IPv6;
    struct MHD_Daemon *d = MHD_start_daemon(
        flags, 0, NULL, NULL, on_request, a, MHD_OPTION_SOCK_ADDR, (struct sockaddr *)&ss,
        MHD_OPTION_THREAD_POOL_SIZE, (unsigned)a->cfg->http_threads, MHD_OPTION_CONNECTION_LIMIT,
        (unsigned)a->cfg->max_connections, MHD_OPTION_CONNECTION_TIMEOUT, (unsigned)120,
        MHD_OPTION_NOTIFY_COMPLETED, on_completed, a, MHD_OPTION_EXTERNAL_LOGGER, on_log, NULL,
        MHD_OPTION_END);
    if (!d) {
        snprintf(msg, ml, "cannot listen on '%s' (address in use, or not allowed)", a->cfg->listen);
        return -1;
    }
    const union MHD_DaemonInfo *info = MHD_get_daemon_info(d, MHD_DAEMON_INFO_BIND_PORT);
    *port = info ? info->port : 0;
    *out = d;
    return 0;
}

void http_quiesce(struct MHD_Daemon *d)
{
    MHD_socket s = MHD_quiesce_daemon(d);
    if (s != MHD_INVALID_SOCKET) close(s);
}
