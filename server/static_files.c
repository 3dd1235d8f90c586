/* static_files.c - the dashboard and three.js from disk, and files with Range and ETag. */
#define _DEFAULT_SOURCE /* realpath, flock */
#include "api.h"

#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

/* A strong validator from the file's identity, size and modification time. */
static void etag_of(const struct stat *st, char *out, size_t cap)
{
    snprintf(out, cap, "\"%" PRIx64 "-%" PRIx64 "-%" PRIx64 "\"", (uint64_t)st->st_ino,
             (uint64_t)st->st_size,
             (uint64_t)st->st_mtim.tv_sec * 1000000000u + (uint64_t)st->st_mtim.tv_nsec);
}

/* Whether an If-None-Match list holds etag (or "*"). */
static int etag_matches(const char *list, const char *etag)
{
    size_t n = strlen(etag);
    for (const char *p = list; *p;) {
        while (*p == ' ' || *p == ',')
            p++;
        if (!*p) break;
        const char *e = p;
        while (*e && *e != ',')
            e++;
        const char *t = e;
        while (t > p && t[-1] == ' ')
            t--;
        const char *q = p;
        if (t - q > 2 && !strncmp(q, "W/", 2)) q += 2;
        if ((t - p == 1 && *p == '*') || ((size_t)(t - q) == n && !strncmp(q, etag, n))) return 1;
        p = e;
    }
    return 0;
}

/*
 * Parses a single "bytes=A-B", "bytes=A-" or "bytes=-N" range against size. 1 with [*lo, *hi]
 * when satisfiable, 0 when the header is to be ignored (malformed or several ranges: the whole
 * file goes out), -1 when unsatisfiable (416).
 */
static int parse_range(const char *h, uint64_t size, uint64_t *lo, uint64_t *hi)
{
    if (strncasecmp(h, "bytes=", 6)) return 0;
    h += 6;
    while (*h == ' ')
        h++;
    if (strchr(h, ',')) return 0;
    char *end;
    if (*h == '-') { /* suffix: the last N bytes */
        if (h[1] < '0' || h[1] > '9') return 0;
        errno = 0;
        unsigned long long nb = strtoull(h + 1, &end, 10);
        while (*end == ' ')
            end++;
        if (errno || *end) return 0;
        if (nb == 0 || size == 0) return -1;
        *lo = nb >= size ? 0 : size - nb;
        *hi = size - 1;
        return 1;
    }
    if (*h < '0' || *h > '9') return 0;
    errno = 0;
    unsigned long long a = strtoull(h, &end, 10);
    if (errno || *end != '-') return 0;
    const char *b = end + 1;
    unsigned long long z = UINT64_MAX;
    if (*b >= '0' && *b <= '9') {
        errno = 0;
        z = strtoull(b, &end, 10);
        if (errno) return 0;
        b = end;
    }
    while (*b == ' ')
        b++;
    if (*b || z < a) return 0;
    if (a >= size) return -1;
    *lo = a;
    *hi = z >= size ? size - 1 : z;
    return 1;
}

static int add_headers(struct MHD_Response *resp, const char *const *kv)
{
    for (; kv[0]; kv += 2)
        if (kv[1] && MHD_add_response_header(resp, kv[0], kv[1]) != MHD_YES) return -1;
    return 0;
}

enum MHD_Result files_send(http_req *r, const char *path, const char *type, const char *download)
{
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    struct stat st;
    if (fd < 0 || fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        int e = errno;
        if (fd >= 0) close(fd);
        if (fd < 0 && e == ENOENT) return http_error(r, 404, "not_found", "no such file");
        if (fd >= 0) /* a directory or other non-file: nothing to serve, not a storage fault */
            return http_error(r, 404, "not_found", "%.200s is not a file", r->url);
        return http_error(r, 500, "storage", "cannot read the file");
    }
    char etag[96], crange[96], disp[160];
    etag_of(&st, etag, sizeof etag);
    if (download) snprintf(disp, sizeof disp, "attachment; filename=\"%s\"", download);
    uint64_t size = (uint64_t)st.st_size, lo = 0, hi = size ? size - 1 : 0;
    const char *inm = MHD_lookup_connection_value(r->conn, MHD_HEADER_KIND, "If-None-Match");
    const char *range = MHD_lookup_connection_value(r->conn, MHD_HEADER_KIND, "Range");
    const char *ifr = MHD_lookup_connection_value(r->conn, MHD_HEADER_KIND, "If-Range");
    unsigned status = 200;
    struct MHD_Response *resp;
    if (inm && etag_matches(inm, etag)) {
        close(fd);
        status = 304;
        resp = MHD_create_response_from_buffer(0, NULL, MHD_RESPMEM_PERSISTENT);
    } else {
        int pr = range && (!ifr || !strcmp(ifr, etag)) ? parse_range(range, size, &lo, &hi) : 0;
        if (pr < 0) {
            close(fd);
            snprintf(crange, sizeof crange, "bytes */%" PRIu64, size);
            json_t *e = json_pack("{s:{s:s, s:s}}", "error", "code", "range_not_satisfiable",
                                  "message", "the range lies beyond the end of the file");
            return http_json_hdr(r, 416, e, "Content-Range", crange);
        }
        if (pr > 0) {
            status = 206;
            snprintf(crange, sizeof crange, "bytes %" PRIu64 "-%" PRIu64 "/%" PRIu64, lo, hi, size);
        }
        uint64_t len = size ? hi - lo + 1 : 0;
        resp = MHD_create_response_from_fd_at_offset64(len, fd, lo); /* owns fd */
        if (!resp) close(fd);
    }
    if (!resp) return MHD_NO;
    const char *const headers[] = {"ETag",
                                   etag,
                                   "Accept-Ranges",
                                   "bytes",
                                   "Cache-Control",
                                   "no-cache",
                                   "Content-Type",
                                   status == 304 ? NULL : type,
                                   "Content-Disposition",
                                   download && status != 304 ? disp : NULL,
                                   "Content-Range",
                                   status == 206 ? crange : NULL,
                                   "X-Content-Type-Options",
                                   "nosniff",
                                   NULL};
    if (add_headers(resp, headers) != 0) {
        MHD_destroy_response(resp);
        return MHD_NO;
    }
    return http_queue(r, status, resp);
}

/* ---- the dashboard and vendored libraries -------------------------------------------------- */

static const struct {
    const char *ext, *type;
} types[] = {
    {".html", "text/html; charset=utf-8"},
    {".js", "text/javascript; charset=utf-8"},
    {".mjs", "text/javascript; charset=utf-8"},
    {".css", "text/css; charset=utf-8"},
    {".json", "application/json"},
    {".map", "application/json"},
    {".svg", "image/svg+xml"},
    {".png", "image/png"},
    {".jpg", "image/jpeg"},
    {".ico", "image/x-icon"},
    {".txt", "text/plain; charset=utf-8"},
    {".wasm", "application/wasm"},
    {".woff2", "font/woff2"},
};

static const char *type_of(const char *path)
{
    const char *dot = strrchr(path, '.'), *slash = strrchr(path, '/');
    if (dot && (!slash || dot > slash))
        for (size_t i = 0; i < sizeof types / sizeof types[0]; i++)
            if (!strcasecmp(dot, types[i].ext)) return types[i].type;
    return "application/octet-stream";
}

/* A relative path is safe when none of its segments is empty, "." or ".." and it holds no
 * backslash or control character. */
static int safe_rel(const char *rel)
{
    if (!*rel) return 0;
    for (const char *p = rel; *p; p++)
        if (*p == '\\' || (unsigned char)*p < 0x20 || *p == 0x7f) return 0;
    for (const char *seg = rel; seg;) {
        const char *end = strchr(seg, '/');
        size_t n = end ? (size_t)(end - seg) : strlen(seg);
        if (n == 0 || (n == 1 && seg[0] == '.') || (n == 2 && seg[0] == '.' && seg[1] == '.'))
            return 0;
        seg = end ? end + 1 : NULL;
    }
    return 1;
}

/* Serves root/rel when it resolves to a regular file inside root. */
static enum MHD_Result serve_under(http_req *r, const char *root, const char *rel)
{
    char want[PATH_MAX + 8], real_root[PATH_MAX], real[PATH_MAX];
    if (!root[0] || !safe_rel(rel) ||
        snprintf(want, sizeof want, "%s/%s", root, rel) >= (int)sizeof want ||
        !realpath(root, real_root) || !realpath(want, real))
        return http_error(r, 404, "not_found", "no file %.200s", r->url);
    size_t n = strlen(real_root);
    if (strncmp(real, real_root, n) || real[n] != '/')
        return http_error(r, 404, "not_found", "no file %.200s", r->url);
    return files_send(r, real, type_of(real), NULL);
}

enum MHD_Result static_serve(http_req *r, const char *path)
{
    app *a = r->app;
    if (!strcmp(path, "/")) {
        if (!a->dashboard[0])
            return http_error(r, 404, "no_dashboard",
                              "the dashboard is not installed (give --dashboard DIR)");
        return serve_under(r, a->dashboard, "index.html");
    }
    if (!strncmp(path, "/vendor/three/", 14)) return serve_under(r, a->cfg->three_dir, path + 14);
    if (!strncmp(path, "/examples/", 10)) return serve_under(r, a->examples, path + 10);
    if (!strncmp(path, "/static/", 8)) return serve_under(r, a->dashboard, path + 8);
    return serve_under(r, a->dashboard, path + 1);
}
