/* http.c - libmicrohttpd set-up, request bodies, limits, authentication and routing. */
#include "http.h"

#include "api.h"
#include "util.h"

#include <arpa/inet.h>
#include <sys/resource.h>
#include <ctype.h>
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
    char msg[1200];
    snprintf(msg, sizeof msg, "%s", message);
    json_t *e = json_pack("{s:s, s:s}", "code", code, "message", util_utf8_fix(msg));
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
    const char *why; /* what is wrong with bad */
    unsigned seen;   /* bit i: allowed[i] was given */
} args_check;

static enum MHD_Result check_arg(void *cls, enum MHD_ValueKind kind, const char *key,
                                 const char *value)
{
    args_check *c = cls;
    (void)kind;
    for (unsigned i = 0; c->allowed[i]; i++) {
        if (strcmp(c->allowed[i], key)) continue;
        /* "?limit" has no value and "?limit=5&limit=abc" two: http_arg would see none, or the
         * first only, and the request went on as if the parameter were absent or valid */
        if (!value) c->why = "has no value (write NAME=VALUE)";
        if (i < 8 * sizeof c->seen && (c->seen & 1u << i)) c->why = "is given more than once";
        if (i < 8 * sizeof c->seen) c->seen |= 1u << i;
        if (!c->why) return MHD_YES;
        c->bad = key;
        return MHD_NO;
    }
    c->bad = key;
    return MHD_NO;
}

int http_args_only(http_req *r, const char *const *allowed, enum MHD_Result *ret)
{
    args_check c = {allowed, NULL, NULL, 0};
    MHD_get_connection_values(r->conn, MHD_GET_ARGUMENT_KIND, check_arg, &c);
    if (!c.bad) return 0;
    if (c.why) {
        *ret = http_error(r, 400, "invalid_parameter", "query parameter '%.100s' %s", c.bad, c.why);
        return 1;
    }
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

static int is(const char *a, const char *b)
{
    return !strcmp(a, b);
}

static enum MHD_Result not_allowed(http_req *r, const char *allow)
{
    char method[64]; /* the client's bytes: made valid UTF-8 for the JSON string */
    snprintf(method, sizeof method, "%s", r->method);
    util_utf8_fix(method);
    json_t *e = json_pack("{s:{s:s, s:s++}}", "error", "code", "method_not_allowed", "message",
                          method, " is not allowed here; allowed: ", allow);
    return http_json_hdr(r, 405, e, "Allow", allow);
}

/* The host of an Origin ("scheme://host[:port]") or Host ("host[:port]") value, without the
 * port, into out; 0 when there is none. */
static int host_of(const char *v, char *out, size_t n)
{
    const char *sep = strstr(v, "://");
    const char *h = sep ? sep + 3 : v;
    size_t len = h[0] == '[' ? strcspn(h, "]") + 1 : strcspn(h, ":/"); /* [::1]:8080 */
    if (!len || len >= n) return 0;
    for (size_t i = 0; i < len; i++)
        out[i] = (char)tolower((unsigned char)h[i]);
    out[len] = 0;
    return 1;
}

/*
 * Whether a request that changes something (POST, DELETE) comes from a web page of another
 * site. Browsers send Origin with such requests; curl, sweep.sh and the Python client send none,
 * and the dashboard's own requests carry the daemon's host. Without this, any page a user visits
 * could queue, cancel or delete jobs on the daemon at localhost through the user's browser (a
 * text/plain POST needs no CORS preflight). Hosts are compared without ports: behind the
 * documented nginx, Host is nginx's $host, which has none.
 */
static int foreign_origin(http_req *r)
{
    const char *o = MHD_lookup_connection_value(r->conn, MHD_HEADER_KIND, "Origin");
    if (!o) return 0;
    const char *h = MHD_lookup_connection_value(r->conn, MHD_HEADER_KIND, MHD_HTTP_HEADER_HOST);
    char oh[256], hh[256];
    return !h || !host_of(o, oh, sizeof oh) || !host_of(h, hh, sizeof hh) || strcmp(oh, hh);
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

/* Adapters from the route table's signature (p: the path's {parameters}) to the handlers. */
typedef enum MHD_Result (*route_fn)(http_req *r, char **p);
static enum MHD_Result h_healthz(http_req *r, char **p)
{
    return (void)p, api_healthz(r);
}
static enum MHD_Result h_metrics(http_req *r, char **p)
{
    return (void)p, api_metrics(r);
}
static enum MHD_Result h_device(http_req *r, char **p)
{
    return (void)p, api_device(r);
}
static enum MHD_Result h_events(http_req *r, char **p)
{
    return (void)p, api_job_events(r, NULL);
}
static enum MHD_Result h_create(http_req *r, char **p)
{
    return (void)p, api_jobs_create(r);
}
static enum MHD_Result h_list(http_req *r, char **p)
{
    return (void)p, api_jobs_list(r);
}
static enum MHD_Result h_get(http_req *r, char **p)
{
    return api_job_get(r, p[0]);
}
static enum MHD_Result h_delete(http_req *r, char **p)
{
    return api_job_delete(r, p[0]);
}
static enum MHD_Result h_cancel(http_req *r, char **p)
{
    return api_job_cancel(r, p[0]);
}
static enum MHD_Result h_job_events(http_req *r, char **p)
{
    return api_job_events(r, p[0]);
}
static enum MHD_Result h_scenario(http_req *r, char **p)
{
    return api_job_scenario(r, p[0]);
}
static enum MHD_Result h_result(http_req *r, char **p)
{
    return api_job_result(r, p[0], 0);
}
static enum MHD_Result h_xmf(http_req *r, char **p)
{
    return api_job_result(r, p[0], 1);
}
static enum MHD_Result h_stats(http_req *r, char **p)
{
    return api_job_stats(r, p[0]);
}
static enum MHD_Result h_frames(http_req *r, char **p)
{
    return api_job_frames(r, p[0], NULL);
}
static enum MHD_Result h_frame(http_req *r, char **p)
{
    return api_job_frames(r, p[0], p[1]);
}
static enum MHD_Result h_shapes(http_req *r, char **p)
{
    return api_job_shapes(r, p[0]);
}
static enum MHD_Result h_validate(http_req *r, char **p)
{
    return (void)p, api_validate(r);
}
static enum MHD_Result h_meshes(http_req *r, char **p)
{
    return (void)p, api_meshes_upload(r);
}

/* Every route the daemon serves; schemas/openapi.yaml describes each (`polydemd --routes`). GET
 * routes answer HEAD too. Paths under /v1/ need the bearer token when tokens are configured. */
static const struct route {
    const char *method, *path;
    route_fn fn;
} routes[] = {
    {"GET", "/healthz", h_healthz},
    {"GET", "/metrics", h_metrics},
    {"GET", "/v1/device", h_device},
    {"GET", "/v1/events", h_events},
    {"POST", "/v1/jobs", h_create},
    {"GET", "/v1/jobs", h_list},
    {"GET", "/v1/jobs/{id}", h_get},
    {"DELETE", "/v1/jobs/{id}", h_delete},
    {"POST", "/v1/jobs/{id}/cancel", h_cancel},
    {"GET", "/v1/jobs/{id}/events", h_job_events},
    {"GET", "/v1/jobs/{id}/scenario", h_scenario},
    {"GET", "/v1/jobs/{id}/result", h_result},
    {"GET", "/v1/jobs/{id}/result.xmf", h_xmf},
    {"GET", "/v1/jobs/{id}/stats", h_stats},
    {"GET", "/v1/jobs/{id}/frames", h_frames},
    {"GET", "/v1/jobs/{id}/frames/{k}", h_frame},
    {"GET", "/v1/jobs/{id}/shapes", h_shapes},
    {"POST", "/v1/scenarios/validate", h_validate},
    {"POST", "/v1/meshes", h_meshes},
};
#define NROUTES (sizeof routes / sizeof routes[0])

void http_print_routes(FILE *out)
{
    for (size_t i = 0; i < NROUTES; i++)
        fprintf(out, "%s %s\n", routes[i].method, routes[i].path);
    fprintf(out, "GET /\nGET /{file}\nGET /static/{file}\nGET /examples/{file}\n"
                 "GET /vendor/three/{file}\n");
}

#define MAX_SEGS 8

/* Splits a path into its segments (in place); -1 when there are too many. */
static int split(char *path, char **seg)
{
    int n = 0;
    char *save = NULL;
    for (char *t = strtok_r(path, "/", &save); t; t = strtok_r(NULL, "/", &save)) {
        if (n == MAX_SEGS) return -1;
        seg[n++] = t;
    }
    return n;
}

/* Whether a route's template matches the request's segments; its {parameters} go to p. */
static int match(const char *tmpl, char **seg, int n, char **p)
{
    char buf[128], *t[MAX_SEGS];
    snprintf(buf, sizeof buf, "%s", tmpl);
    int m = split(buf, t), np = 0;
    if (m != n) return 0;
    for (int i = 0; i < n; i++) {
        if (t[i][0] == '{')
            p[np++] = seg[i];
        else if (!is(t[i], seg[i]))
            return 0;
    }
    return 1;
}

/* The bearer token's owner into r->owner; 0, or 1 when a 401 was queued (in *ret). */
static int authenticate(http_req *r, int events, enum MHD_Result *ret)
{
    const char *tok = auth_bearer(
        MHD_lookup_connection_value(r->conn, MHD_HEADER_KIND, MHD_HTTP_HEADER_AUTHORIZATION));
    /* EventSource cannot set headers: the event streams also take ?token= */
    if (!tok && events) tok = http_arg(r, "token");
    if (!tok) {
        *ret = unauthorized(r, "this server needs 'Authorization: Bearer TOKEN'");
        return 1;
    }
    r->owner = auth_lookup(r->app->auth, tok);
    if (!r->owner) {
        *ret = unauthorized(r, "unknown token");
        return 1;
    }
    return 0;
}

static enum MHD_Result route(http_req *r)
{
    char path[1024], *seg[MAX_SEGS], *p[2] = {NULL, NULL}, allow[64] = "";
    if (strlen(r->url) >= sizeof path)
        return http_error(r, 414, "uri_too_long", "the path is longer than %zu bytes",
                          sizeof path - 1);
    snprintf(path, sizeof path, "%s", r->url);
    int n = split(path, seg);
    const char *method = is(r->method, "HEAD") ? "GET" : r->method;
    const struct route *hit = NULL;
    for (size_t i = 0; n >= 0 && i < NROUTES && !hit; i++) {
        if (!match(routes[i].path, seg, n, p)) continue;
        if (is(routes[i].method, method)) {
            hit = &routes[i];
        } else if (!strstr(allow, routes[i].method)) {
            size_t k = strlen(allow);
            snprintf(allow + k, sizeof allow - k, "%s%s%s", k ? ", " : "", routes[i].method,
                     is(routes[i].method, "GET") ? ", HEAD" : "");
        }
    }
    /* Decided on the first segment as the routes see it, not on the URL's spelling: "//v1/jobs"
     * (and "/%2Fv1/jobs", which arrives decoded) reach the same routes as "/v1/jobs", so they
     * must need the same token. */
    const char *first = r->url;
    while (*first == '/')
        first++;
    int v1 = !strncmp(first, "v1", 2) && (first[2] == '/' || !first[2]);
    if (v1 && r->app->auth) {
        enum MHD_Result ret;
        if (authenticate(r, n > 0 && is(seg[n - 1], "events"), &ret)) return ret;
    }
    if (hit && !is(method, "GET") && foreign_origin(r))
        return http_error(r, 403, "cross_origin",
                          "%s from another site's page refused (its Origin is not this server)",
                          method);
    if (hit) return hit->fn(r, p);
    if (allow[0]) return not_allowed(r, allow);
    if (v1 || is(r->url, "/healthz") || is(r->url, "/metrics")) return not_found(r);
    if (is(method, "GET")) return static_serve(r, r->url);
    return not_allowed(r, "GET, HEAD");
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
    /* a client that left (an event stream closed by its browser tab) or sent no HTTP is no
     * fault of ours to report */
    if (strstr(line, "closed by remote peer") || strstr(line, "no longer available for sending") ||
        strstr(line, "Request malformed"))
        return;
    /* the address is handed over whole (MHD_OPTION_SOCK_ADDR), so MHD's own bind error names
     * "port 0"; the caller reports the address and why ("cannot listen on ...") */
    if (strstr(line, "Failed to bind to port")) return;
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
    /* Each connection holds a descriptor: more connections than the process may open left MHD
     * spinning on accept (a 100 % core and gigabytes of "busy waiting" log at `ulimit -n 20`).
     * Keep 64 for the database, results, meshes and OpenCL. */
    unsigned max_conn = (unsigned)a->cfg->max_connections;
    struct rlimit nofile;
    if (getrlimit(RLIMIT_NOFILE, &nofile) == 0 && nofile.rlim_cur != RLIM_INFINITY) {
        rlim_t room = nofile.rlim_cur > 80 ? nofile.rlim_cur - 64 : 16;
        if ((rlim_t)max_conn > room) {
            fprintf(stderr,
                    "polydemd: max_connections %u lowered to %u: the process may open %llu "
                    "files (ulimit -n)\n",
                    max_conn, (unsigned)room, (unsigned long long)nofile.rlim_cur);
            max_conn = (unsigned)room;
        }
    }
    MHD_set_panic_func(on_panic, NULL);
    unsigned flags = MHD_USE_AUTO_INTERNAL_THREAD | MHD_ALLOW_SUSPEND_RESUME | MHD_USE_ERROR_LOG;
    if (v6) flags |= MHD_USE_IPv6;
    struct MHD_Daemon *d = MHD_start_daemon(
        flags, 0, NULL, NULL, on_request, a, MHD_OPTION_EXTERNAL_LOGGER, on_log, NULL,
        MHD_OPTION_SOCK_ADDR, (struct sockaddr *)&ss, MHD_OPTION_THREAD_POOL_SIZE,
        (unsigned)a->cfg->http_threads, MHD_OPTION_CONNECTION_LIMIT, max_conn,
        MHD_OPTION_CONNECTION_TIMEOUT, (unsigned)120, MHD_OPTION_NOTIFY_COMPLETED, on_completed, a,
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
