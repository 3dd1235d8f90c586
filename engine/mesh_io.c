/*
 * mesh_io.c - reading binary/ASCII STL and Wavefront OBJ, writing binary STL, and the
 * "builtin:NAME[:TRIANGLES[:SEED]]" specs of pd_mesh_open.
 *
 * Files are read whole (they are small: particles have hundreds to thousands of triangles) and
 * the format is chosen by content first, extension second. Every parser hands its triangle soup
 * to mesh_finish, which welds and validates.
 */
#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "mesh_internal.h"

/* Largest file read: a binary STL at the triangle limit is 500 MB, an ASCII one a few times
 * more; anything bigger is not a particle. */
#define MESH_MAX_FILE ((size_t)1 << 31)

/* ---- reading files ------------------------------------------------------------------------- */

/*
 * Opens a file to read. A FIFO is opened without waiting for a writer (fopen would wait forever
 * for one that never comes: a scenario naming a FIFO as its mesh hung `polydem validate`), then
 * read as a pipe: what a writer sends, or nothing. A device (/dev/zero) is refused rather than
 * read up to the size limit.
 */
static FILE *open_read(const char *path, pd_error *err, int *rc)
{
    int fd = open(path, O_RDONLY | O_NONBLOCK);
    struct stat st;
    if (fd < 0 || fstat(fd, &st) != 0) {
        *rc = pd_error_set(err, PD_EIO, "%s: cannot open: %s", path, strerror(errno));
        if (fd >= 0) close(fd);
        return NULL;
    }
    if (S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode)) {
        close(fd);
        *rc = pd_error_set(err, PD_EIO, "%s: cannot read: a device, not a file", path);
        return NULL;
    }
    /* blocking again, so that a pipe's reads wait for its writer's data */
    int fl = fcntl(fd, F_GETFL);
    FILE *f = fl < 0 || fcntl(fd, F_SETFL, fl & ~O_NONBLOCK) < 0 ? NULL : fdopen(fd, "rb");
    if (!f) {
        *rc = pd_error_set(err, PD_EIO, "%s: cannot open: %s", path, strerror(errno));
        close(fd);
    }
    return f;
}

/* Reads the whole file (works for pipes too) into a NUL-terminated buffer. */
static int read_whole(const char *path, char **buf_out, size_t *len_out, pd_error *err)
{
    *buf_out = NULL;
    int rc = PD_OK;
    FILE *f = open_read(path, err, &rc);
    if (!f) return rc;
    size_t cap = 1 << 16, len = 0;
    char *buf = malloc(cap + 1);
    if (!buf) {
        rc = pd_error_set(err, PD_ENOMEM, "%s: out of memory", path);
        goto done;
    }
    for (;;) {
        if (len == cap) {
            if (cap >= MESH_MAX_FILE) {
                rc = pd_error_set(err, PD_EIO, "%s: file too large (the limit is %zu bytes)", path,
                                  MESH_MAX_FILE);
                goto done;
            }
            size_t ncap = cap * 2 > MESH_MAX_FILE ? MESH_MAX_FILE : cap * 2;
            char *nb = realloc(buf, ncap + 1);
            if (!nb) {
                rc = pd_error_set(err, PD_ENOMEM, "%s: out of memory reading the file", path);
                goto done;
            }
            buf = nb;
            cap = ncap;
        }
        size_t n = fread(buf + len, 1, cap - len, f);
        len += n;
        if (n == 0) {
            if (ferror(f)) {
                rc = pd_error_set(err, PD_EIO, "%s: cannot read: %s", path, strerror(errno));
                goto done;
            }
            break;
        }
    }
    buf[len] = '\0';
done:
    fclose(f);
    if (rc != PD_OK) {
        free(buf);
        return rc;
    }
    *buf_out = buf;
    *len_out = len;
    return PD_OK;
}

/* Grows *p (elements of size elem) so that it holds at least need elements. */
static int grow(void **p, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap) return 0;
    size_t ncap = *cap ? *cap : 256;
    while (ncap < need)
        ncap *= 2;
    void *np = realloc(*p, ncap * elem);
    if (!np) return -1;
    *p = np;
    *cap = ncap;
    return 0;
}

/* ---- binary STL ---------------------------------------------------------------------------- */

static uint32_t get_le32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static void put_le32(unsigned char *p, uint32_t u)
{
    for (int k = 0; k < 4; k++)
        p[k] = (unsigned char)(u >> (8 * k));
}

static double get_float(const unsigned char *p)
{
    uint32_t u = get_le32(p);
    float f;
    memcpy(&f, &u, sizeof f);
    return (double)f; /* exact: STL coordinates are float32 and stay those values */
}

static int parse_stl_binary(const char *label, const unsigned char *buf, size_t len, pd_mesh **out,
                            pd_error *err)
{
    if (len < 84) {
        return pd_error_set(err, PD_EMESH,
                            "%s: not a binary STL: %zu bytes, shorter than the 84-byte header",
                            label, len);
    }
    uint32_t n = get_le32(buf + 80);
    if (n == 0) return pd_error_set(err, PD_EMESH, "%s: no triangles", label);
    if (n > MESH_MAX_TRIS) {
        return pd_error_set(err, PD_EMESH, "%s: too many triangles (%lu; the limit is %d)", label,
                            (unsigned long)n, MESH_MAX_TRIS);
    }
    size_t need = 84 + 50 * (size_t)n;
    if (len < need) {
        return pd_error_set(err, PD_EMESH,
                            "%s: truncated binary STL: %lu triangles need %zu bytes, file has %zu",
                            label, (unsigned long)n, need, len);
    }
    double *verts = malloc(9 * (size_t)n * sizeof *verts);
    int *tris = malloc(3 * (size_t)n * sizeof *tris);
    if (!verts || !tris) {
        free(verts);
        free(tris);
        return pd_error_set(err, PD_ENOMEM, "%s: out of memory", label);
    }
    for (size_t t = 0; t < n; t++) {
        const unsigned char *rec = buf + 84 + 50 * t + 12; /* skip the stored normal */
        for (int k = 0; k < 9; k++)
            verts[9 * t + k] = get_float(rec + 4 * k);
        for (int k = 0; k < 3; k++)
            tris[3 * t + k] = (int)(3 * t + k);
    }
    return mesh_finish(verts, (int)(3 * n), tris, (int)n, label, out, err);
}

/* ---- text parsing helpers ------------------------------------------------------------------ */

typedef struct {
    const char *p, *end; /* rest of the current line */
} line_toks;

/* Next whitespace-separated token of the line; returns 0 at the end of the line. */
static int next_tok(line_toks *lt, const char **tok, size_t *len)
{
    while (lt->p < lt->end && isspace((unsigned char)*lt->p))
        lt->p++;
    if (lt->p >= lt->end) return 0;
    const char *s = lt->p;
    while (lt->p < lt->end && !isspace((unsigned char)*lt->p))
        lt->p++;
    *tok = s;
    *len = (size_t)(lt->p - s);
    return 1;
}

static int tok_is(const char *tok, size_t len, const char *word)
{
    return strlen(word) == len && strncasecmp(tok, word, len) == 0;
}

/* Parses a whole token as a number. The token is followed by whitespace or the buffer's NUL, so
 * strtod cannot run past it. */
static int tok_double(const char *tok, size_t len, double *out)
{
    char *end;
    *out = strtod(tok, &end);
    return end == tok + len;
}

/* Reads the line's next three tokens as numbers; 0 when one is missing or not a number. */
static int tok_vec3(line_toks *lt, double x[3])
{
    const char *tok;
    size_t tl;
    for (int k = 0; k < 3; k++)
        if (!next_tok(lt, &tok, &tl) || !tok_double(tok, tl, &x[k])) return 0;
    return 1;
}

/* Copies a token for an error message, at most 40 bytes, with unprintable bytes as '?'. */
static const char *tok_show(const char *tok, size_t len, char buf[41])
{
    size_t n = len > 40 ? 40 : len;
    for (size_t i = 0; i < n; i++)
        buf[i] = isprint((unsigned char)tok[i]) ? tok[i] : '?';
    buf[n] = '\0';
    return buf;
}

/* Splits [*pos, end) at the next newline: the line runs [*pos, *line_end). */
static const char *next_line(const char **pos, const char *end, const char **line_end)
{
    /* a line ends at \n, \r\n or a lone \r (classic Mac OS files, which otherwise read as one
     * line), as ASCII STL's do (stl_tok) */
    const char *s = *pos, *p = s;
    while (p < end && *p != '\n' && *p != '\r')
        p++;
    *line_end = p;
    if (p < end && *p == '\r' && p + 1 < end && p[1] == '\n') p++;
    *pos = p < end ? p + 1 : end;
    return s;
}

/* True when the first bytes hold no control characters other than whitespace. */
static int looks_like_text(const char *buf, size_t len)
{
    size_t n = len < 4096 ? len : 4096;
    for (size_t i = 0; i < n; i++) {
        unsigned char c = (unsigned char)buf[i];
        if (c < 0x20 && c != '\t' && c != '\n' && c != '\r' && c != '\f' && c != '\v') return 0;
    }
    return 1;
}

/* ---- ASCII STL ----------------------------------------------------------------------------- */

/*
 * ASCII STL is whitespace-separated tokens but for the solid's name, which is the rest of the
 * `solid` (and `endsolid`) line. So the reader takes the file as one stream of tokens across line
 * ends, not line by line: exporters and hand edits split facets anyhow (`outer` and `loop` on two
 * lines were refused). Each token keeps its line for messages. A line ends at \n, at \r\n (one
 * end, not two) and at a lone \r (classic Mac OS files, which read as one line whose solid's name
 * ate every facet).
 */
typedef struct {
    const char *p, *end;
    int line; /* line of p */
} stl_toks;

static int stl_line_end(const stl_toks *st)
{
    return *st->p == '\n' || (*st->p == '\r' && (st->p + 1 == st->end || st->p[1] != '\n'));
}

/* Next token, across line ends; *line gets its line. Returns 0 at the end of the buffer. */
static int stl_tok(stl_toks *st, const char **tok, size_t *len, int *line)
{
    for (; st->p < st->end && isspace((unsigned char)*st->p); st->p++)
        st->line += stl_line_end(st);
    if (st->p >= st->end) return 0;
    const char *s = st->p;
    while (st->p < st->end && !isspace((unsigned char)*st->p))
        st->p++;
    *tok = s;
    *len = (size_t)(st->p - s);
    *line = st->line;
    return 1;
}

/*
 * Skips a solid's name, the rest of the line, and says whether it holds 'facet' and after it
 * 'vertex': a whole solid written on one line is all name, and reading it as facets would be a
 * guess (a solid may be named "facet normal ..."), so the caller reports it when the solid ends
 * with no facet.
 */
static int stl_skip_name(stl_toks *st)
{
    const char *s = st->p;
    while (st->p < st->end && *st->p != '\n' && *st->p != '\r')
        st->p++;
    line_toks lt = {s, st->p};
    const char *tok;
    size_t tl;
    int facet = 0;
    while (next_tok(&lt, &tok, &tl)) {
        if (tok_is(tok, tl, "facet")) facet = 1;
        if (facet && tok_is(tok, tl, "vertex")) return 1;
    }
    return 0;
}

/* The message for a solid that ended with no facet, its name line holding 'facet ... vertex'. */
static int stl_facets_in_name(const char *label, int line, pd_error *err)
{
    return pd_error_set(err, PD_EMESH,
                        "%s:%d: the solid's name line holds 'facet ... vertex': the name runs to "
                        "the end of its line, so the first facet must start on the next line",
                        label, line);
}

static int stl_keyword(const char *tok, size_t len)
{
    static const char *const kw[] = {"solid", "endsolid", "facet",   "normal",  "outer",
                                     "loop",  "vertex",   "endloop", "endfacet"};
    for (size_t i = 0; i < sizeof kw / sizeof kw[0]; i++)
        if (tok_is(tok, len, kw[i])) return 1;
    return 0;
}

static int parse_stl_ascii(const char *label, const char *buf, size_t len, pd_mesh **out,
                           pd_error *err)
{
    double *verts = NULL;
    int *tris = NULL;
    size_t vcap = 0, tcap = 0, nv = 0, nt = 0, solid_nt = 0;
    /* what comes next; AFTER_LOOP: the loop has ended, 'endfacet' must follow */
    enum { OUTSIDE, IN_SOLID, IN_FACET, AFTER_OUTER, IN_LOOP, AFTER_LOOP } state = OUTSIDE;
    static const char *const expected[] = {"'solid'", "'facet' or 'endsolid'", "'outer loop'",
                                           "'loop'",  "'vertex' or 'endloop'", "'endfacet'"};
    int loop_verts = 0, line = 1, rc = PD_OK;
    int normal_kw = 0, normal = 0;      /* the facet's 'normal' read; how many of its values */
    int name_line = 0, name_facets = 0; /* the solid's `solid` line; it holds 'facet ... vertex' */
    int vertex_line = 0;                /* line of the last token when it ended a vertex, else 0 */
    char show[41];
    const char *tok;
    size_t tl;
    stl_toks st = {buf, buf + len, 1};
    while (stl_tok(&st, &tok, &tl, &line)) {
        int after_vertex = vertex_line;
        vertex_line = 0;
        if (state == OUTSIDE && tok_is(tok, tl, "solid")) {
            name_line = line;
            name_facets = stl_skip_name(&st);
            solid_nt = nt;
            state = IN_SOLID;
        } else if (state == IN_SOLID && tok_is(tok, tl, "facet")) {
            state = IN_FACET;
            normal = normal_kw = 0;
        } else if (state == IN_SOLID && tok_is(tok, tl, "endsolid")) {
            if (nt == solid_nt && name_facets) {
                rc = stl_facets_in_name(label, name_line, err);
                goto fail;
            }
            stl_skip_name(&st);
            state = OUTSIDE;
        } else if (state == IN_FACET && tok_is(tok, tl, "outer")) {
            state = AFTER_OUTER;
        } else if (state == IN_FACET && !normal_kw && !normal && tok_is(tok, tl, "normal")) {
            normal_kw = 1;
        } else if (state == IN_FACET && !stl_keyword(tok, tl)) {
            /* The stored normal is ignored (orientation comes from the vertices' order), so its
             * tokens need not be numbers: exporters write NaN as "-nan", "nan" or MSVC's
             * "1.#QNAN0" for degenerate facets, and some write no normal at all. */
            if (++normal > 3) {
                rc = pd_error_set(err, PD_EMESH,
                                  "%s:%d: facet normal takes 3 numbers, found more ('%s')", label,
                                  line, tok_show(tok, tl, show));
                goto fail;
            }
        } else if (state == AFTER_OUTER && tok_is(tok, tl, "loop")) {
            state = IN_LOOP;
            loop_verts = 0;
        } else if (state == IN_LOOP && tok_is(tok, tl, "vertex")) {
            double x[3];
            for (int k = 0; k < 3; k++) {
                if (!stl_tok(&st, &tok, &tl, &line)) {
                    rc = pd_error_set(
                        err, PD_EMESH,
                        "%s:%d: vertex needs 3 numbers, found %d before the end of the file", label,
                        line, k);
                    goto fail;
                }
                if (!tok_double(tok, tl, &x[k])) {
                    rc = pd_error_set(err, PD_EMESH, "%s:%d: vertex needs 3 numbers, found '%s'",
                                      label, line, tok_show(tok, tl, show));
                    goto fail;
                }
            }
            vertex_line = line;
            if (++loop_verts > 3) {
                rc = pd_error_set(err, PD_EMESH, "%s:%d: facet with more than 3 vertices", label,
                                  line);
                goto fail;
            }
            if (nv >= 3 * (size_t)MESH_MAX_TRIS) {
                rc = pd_error_set(err, PD_EMESH, "%s:%d: too many triangles (the limit is %d)",
                                  label, line, MESH_MAX_TRIS);
                goto fail;
            }
            if (grow((void **)&verts, &vcap, 3 * (nv + 1), sizeof *verts)) goto oom;
            memcpy(&verts[3 * nv], x, sizeof x);
            nv++;
        } else if (state == IN_LOOP && tok_is(tok, tl, "endloop")) {
            if (loop_verts != 3) {
                rc = pd_error_set(err, PD_EMESH, "%s:%d: facet with %d vertices (expected 3)",
                                  label, line, loop_verts);
                goto fail;
            }
            if (grow((void **)&tris, &tcap, 3 * (nt + 1), sizeof *tris)) goto oom;
            for (int k = 0; k < 3; k++)
                tris[3 * nt + k] = (int)(nv - 3 + (size_t)k);
            nt++;
            state = AFTER_LOOP;
        } else if (state == AFTER_LOOP && tok_is(tok, tl, "endfacet")) {
            state = IN_SOLID;
        } else {
            double x;
            /* a fourth number, or a word other than a keyword on the vertex's line, reads as one
             * more coordinate: say so rather than that the word is out of place */
            if (after_vertex && !stl_keyword(tok, tl) &&
                (line == after_vertex || tok_double(tok, tl, &x))) {
                rc = pd_error_set(err, PD_EMESH, "%s:%d: vertex takes 3 numbers, found more ('%s')",
                                  label, line, tok_show(tok, tl, show));
            } else {
                rc =
                    pd_error_set(err, PD_EMESH, "%s:%d: unexpected '%s' in ASCII STL (expected %s)",
                                 label, line, tok_show(tok, tl, show), expected[state]);
            }
            goto fail;
        }
    }
    if (state != OUTSIDE && state != IN_SOLID) {
        rc = pd_error_set(err, PD_EMESH, "%s:%d: file ends inside a facet", label, line);
        goto fail;
    }
    if (state == IN_SOLID && nt == solid_nt && name_facets) {
        rc = stl_facets_in_name(label, name_line, err);
        goto fail;
    }
    return mesh_finish(verts, (int)nv, tris, (int)nt, label, out, err);
oom:
    rc = pd_error_set(err, PD_ENOMEM, "%s: out of memory", label);
fail:
    free(verts);
    free(tris);
    return rc;
}

/* ---- Wavefront OBJ ------------------------------------------------------------------------- */

/* Statements that carry no surface geometry (normals, texture, grouping, materials, lines). */
static int obj_keyword(const char *tok, size_t len)
{
    static const char *const kw[] = {"v", "vt", "vn",     "vp",     "f", "g",
                                     "o", "s",  "usemtl", "mtllib", "l", "p"};
    for (size_t i = 0; i < sizeof kw / sizeof kw[0]; i++)
        if (tok_is(tok, len, kw[i])) return 1;
    return 0;
}

/* Resolves one face corner "i", "i/t", "i//n" or "i/t/n"; negative i counts back from the last
 * vertex read so far. Returns 0 and sets *idx, or fills err. */
static int obj_corner(const char *label, int lineno, const char *tok, size_t tl, size_t nv,
                      int *idx, pd_error *err)
{
    char *end;
    errno = 0;
    long i = strtol(tok, &end, 10);
    if (end == tok || (end < tok + tl && *end != '/') || errno == ERANGE) {
        char show[41];
        return pd_error_set(err, PD_EMESH, "%s:%d: bad face vertex '%s'", label, lineno,
                            tok_show(tok, tl, show));
    }
    long long r = i > 0 ? (long long)i - 1 : (long long)nv + i;
    if (i == 0 || r < 0 || r >= (long long)nv) {
        return pd_error_set(err, PD_EMESH, "%s:%d: face index %ld out of range (%zu vert%s)", label,
                            lineno, i, nv, nv == 1 ? "ex" : "ices");
    }
    *idx = (int)r;
    return PD_OK;
}

/*
 * Triangulates an OBJ face of np > 3 corners (vertex indices into verts) into np - 2 triangles at
 * out, keeping its orientation. A strictly convex face is fanned from its first corner, as it
 * always was; any other (an L-shaped cap, a corner on a straight edge) is cut into ears in the
 * plane it faces most, since a fan would fold it over itself or leave a zero-area triangle.
 * Returns -1 when no ear can be cut (a self-crossing or degenerate face). scratch holds 3 np.
 */
static int obj_polygon(const double *verts, const int *poly, size_t np, int *out, double *scratch)
{
    double n[3] = {0, 0, 0}; /* Newell's normal */
    for (size_t k = 0; k < np; k++) {
        const double *a = &verts[3 * (size_t)poly[k]], *b = &verts[3 * (size_t)poly[(k + 1) % np]];
        n[0] += (a[1] - b[1]) * (a[2] + b[2]);
        n[1] += (a[2] - b[2]) * (a[0] + b[0]);
        n[2] += (a[0] - b[0]) * (a[1] + b[1]);
    }
    int ax = fabs(n[0]) > fabs(n[1]) ? (fabs(n[0]) > fabs(n[2]) ? 0 : 2)
                                     : (fabs(n[1]) > fabs(n[2]) ? 1 : 2);
    int u = (ax + 1) % 3, v = (ax + 2) % 3; /* counter-clockwise seen along +n[ax] */
    double sgn = n[ax] < 0 ? -1 : 1;
    double *x = scratch, *y = scratch + np;
    int *idx = (int *)(void *)(scratch + 2 * np); /* np ints fit in np doubles */
    for (size_t k = 0; k < np; k++) {
        x[k] = verts[3 * (size_t)poly[k] + u];
        y[k] = sgn * verts[3 * (size_t)poly[k] + v];
        idx[k] = (int)k;
    }
#define TURN(i, j, k) ((x[j] - x[i]) * (y[k] - y[i]) - (y[j] - y[i]) * (x[k] - x[i]))
    int convex = 1;
    for (size_t k = 0; k < np && convex; k++)
        convex = TURN(k, (k + 1) % np, (k + 2) % np) > 0;
    size_t nt = 0;
    if (convex) {
        for (size_t k = 1; k + 1 < np; k++, nt++) {
            out[3 * nt] = poly[0];
            out[3 * nt + 1] = poly[k];
            out[3 * nt + 2] = poly[k + 1];
        }
        return 0;
    }
    size_t m = np;
    while (m > 3) {
        size_t cut = m;
        for (size_t e = 0; e < m && cut == m; e++) {
            int a = idx[(e + m - 1) % m], b = idx[e], c = idx[(e + 1) % m];
            if (!(TURN(a, b, c) > 0)) continue; /* reflex or straight: not an ear */
            int clear = 1;                      /* no other corner in or on the ear */
            for (size_t q = 0; q < m && clear; q++) {
                int d = idx[q];
                if (d == a || d == b || d == c) continue;
                clear = !(TURN(a, b, d) >= 0 && TURN(b, c, d) >= 0 && TURN(c, a, d) >= 0);
            }
            if (clear) cut = e;
        }
        if (cut == m) return -1;
        out[3 * nt] = poly[idx[(cut + m - 1) % m]];
        out[3 * nt + 1] = poly[idx[cut]];
        out[3 * nt + 2] = poly[idx[(cut + 1) % m]];
        nt++;
        memmove(&idx[cut], &idx[cut + 1], sizeof *idx * (m - cut - 1));
        m--;
    }
    if (!(TURN(idx[0], idx[1], idx[2]) > 0)) return -1;
    out[3 * nt] = poly[idx[0]];
    out[3 * nt + 1] = poly[idx[1]];
    out[3 * nt + 2] = poly[idx[2]];
#undef TURN
    return 0;
}

/*
 * Where line [ls, le), whose comment starts at hash (NULL: none), continues on the next (OBJ's
 * trailing backslash, as exporters write long faces): at its last character when that is a
 * backslash followed only by blanks, and the line has no comment; else NULL.
 */
static const char *obj_continues(const char *ls, const char *le, const char *hash)
{
    if (hash) return NULL;
    while (le > ls && isspace((unsigned char)le[-1]))
        le--;
    return le > ls && le[-1] == '\\' ? le - 1 : NULL;
}

/*
 * Joins a statement continued over lines (obj_continues) into *joined, NUL-terminated, with a
 * blank for each backslash; its first line [ls, cut) is the caller's, which has found where it
 * continues (cut), and *phys counts the lines taken after it. Returns its length, or -1 out of
 * memory.
 */
static long obj_join(const char *ls, const char *cut, const char **pos, const char *end, int *phys,
                     char **joined, size_t *cap)
{
    size_t n = 0;
    const char *stop = cut;
    for (;;) {
        size_t add = (size_t)(stop - ls);
        if (grow((void **)joined, cap, n + add + 2, 1)) return -1;
        memcpy(*joined + n, ls, add);
        n += add;
        (*joined)[n++] = ' ';
        if (!cut || *pos >= end) break;
        const char *le;
        ls = next_line(pos, end, &le);
        (*phys)++;
        const char *hash = memchr(ls, '#', (size_t)(le - ls));
        cut = obj_continues(ls, le, hash);
        stop = cut ? cut : hash ? hash : le;
    }
    (*joined)[n] = '\0';
    return (long)n;
}

static int parse_obj(const char *label, const char *buf, size_t len, pd_mesh **out, pd_error *err)
{
    double *verts = NULL, *pscratch = NULL;
    int *tris = NULL, *poly = NULL;
    char *joined = NULL;
    size_t vcap = 0, tcap = 0, pcap = 0, scap = 0, jcap = 0, nv = 0, nt = 0;
    int lineno = 0, phys = 0, rc = PD_OK; /* lineno: where the statement starts, for messages */
    const char *pos = buf, *end = buf + len;
    while (pos < end) {
        const char *le, *ls = next_line(&pos, end, &le), *tok;
        size_t tl;
        const char *hash = memchr(ls, '#', (size_t)(le - ls));
        line_toks lt = {ls, hash ? hash : le};
        lineno = ++phys;
        const char *cut = obj_continues(ls, le, hash);
        if (cut) {
            long jn = obj_join(ls, cut, &pos, end, &phys, &joined, &jcap);
            if (jn < 0) goto oom;
            lt.p = joined;
            lt.end = joined + jn;
        }
        if (!next_tok(&lt, &tok, &tl)) continue;
        if (tok_is(tok, tl, "v")) {
            double x[3];
            if (!tok_vec3(&lt, x)) {
                rc = pd_error_set(err, PD_EMESH, "%s:%d: vertex needs 3 numbers", label, lineno);
                goto fail;
            }
            if (nv >= 3 * (size_t)MESH_MAX_TRIS) {
                rc = pd_error_set(err, PD_EMESH, "%s:%d: too many vertices (the limit is %d)",
                                  label, lineno, 3 * MESH_MAX_TRIS);
                goto fail;
            }
            if (grow((void **)&verts, &vcap, 3 * (nv + 1), sizeof *verts)) goto oom;
            memcpy(&verts[3 * nv], x, sizeof x);
            nv++;
        } else if (tok_is(tok, tl, "f")) {
            size_t np = 0;
            while (next_tok(&lt, &tok, &tl)) {
                if (grow((void **)&poly, &pcap, np + 1, sizeof *poly)) goto oom;
                if ((rc = obj_corner(label, lineno, tok, tl, nv, &poly[np], err)) != PD_OK)
                    goto fail;
                np++;
            }
            if (np < 3) {
                rc = pd_error_set(err, PD_EMESH, "%s:%d: face with %zu vertices (needs 3)", label,
                                  lineno, np);
                goto fail;
            }
            if (nt + (np - 2) > (size_t)MESH_MAX_TRIS) {
                rc = pd_error_set(err, PD_EMESH, "%s:%d: too many triangles (the limit is %d)",
                                  label, lineno, MESH_MAX_TRIS);
                goto fail;
            }
            if (grow((void **)&tris, &tcap, 3 * (nt + np - 2), sizeof *tris)) goto oom;
            if (np == 3) {
                memcpy(&tris[3 * nt], poly, 3 * sizeof *poly);
            } else {
                if (grow((void **)&pscratch, &scap, 3 * np, sizeof *pscratch)) goto oom;
                if (obj_polygon(verts, poly, np, &tris[3 * nt], pscratch) != 0) {
                    rc = pd_error_set(err, PD_EMESH,
                                      "%s:%d: face of %zu corners is not a simple polygon (its "
                                      "edges cross, or its corners are in a line)",
                                      label, lineno, np);
                    goto fail;
                }
            }
            nt += np - 2;
        } else if (!isalpha((unsigned char)tok[0])) {
            char show[41];
            rc = pd_error_set(err, PD_EMESH, "%s:%d: not an OBJ statement: '%s'", label, lineno,
                              tok_show(tok, tl, show));
            goto fail;
        }
        /* other statements (vn, vt, g, o, s, usemtl, mtllib, l, ...) carry no solid geometry */
    }
    free(poly);
    free(pscratch);
    free(joined);
    return mesh_finish(verts, (int)nv, tris, (int)nt, label, out, err);
oom:
    rc = pd_error_set(err, PD_ENOMEM, "%s: out of memory", label);
fail:
    free(verts);
    free(tris);
    free(poly);
    free(pscratch);
    free(joined);
    return rc;
}

/* ---- format detection ---------------------------------------------------------------------- */

enum { FMT_UNKNOWN, FMT_STL_BINARY, FMT_STL_ASCII, FMT_OBJ };

static int has_ext(const char *path, const char *ext)
{
    const char *dot = strrchr(path, '.');
    return dot && strcasecmp(dot, ext) == 0;
}

/* A binary STL's size is exactly determined by its triangle count. */
static int binary_stl_size(const char *buf, size_t len)
{
    return len >= 84 && 84 + 50 * (size_t)get_le32((const unsigned char *)buf + 80) == len;
}

static int detect_format(const char *path, const char *buf, size_t len)
{
    /* some binary files start with "solid" in their header, so the size decides first */
    if (binary_stl_size(buf, len)) return FMT_STL_BINARY;
    if (looks_like_text(buf, len)) {
        const char *pos = buf, *end = buf + len;
        while (pos < end) {
            const char *le, *ls = next_line(&pos, end, &le), *tok;
            size_t tl;
            line_toks lt = {ls, le};
            if (!next_tok(&lt, &tok, &tl) || tok[0] == '#') continue;
            if (tok_is(tok, tl, "solid")) return FMT_STL_ASCII;
            if (obj_keyword(tok, tl)) return FMT_OBJ;
            break;
        }
    }
    if (has_ext(path, ".obj")) return FMT_OBJ;
    if (has_ext(path, ".stl")) return FMT_STL_BINARY; /* reports why it is not one */
    return FMT_UNKNOWN;
}

int pd_mesh_load(const char *path, pd_mesh **out, pd_error *err)
{
    if (!out) return pd_error_set(err, PD_EINVAL, "pd_mesh_load: no output pointer");
    *out = NULL;
    if (!path || !*path) return pd_error_set(err, PD_EINVAL, "empty mesh path");
    char *buf = NULL;
    size_t len = 0;
    int rc = read_whole(path, &buf, &len, err);
    if (rc != PD_OK) return rc;
    if (len == 0) {
        free(buf);
        return pd_error_set(err, PD_EMESH, "%s: empty file, no triangles", path);
    }
    /* a text file may start with a UTF-8 byte order mark (Windows editors write one); a binary
     * STL is recognised by its size first, so its header's bytes are never taken for one */
    size_t bom = len >= 3 && !memcmp(buf, "\xEF\xBB\xBF", 3) ? 3 : 0;
    int fmt = detect_format(path, buf, len);
    if (bom && !binary_stl_size(buf, len))
        fmt = detect_format(path, buf + bom, len - bom);
    else
        bom = 0;
    switch (fmt) {
    case FMT_STL_BINARY:
        rc = parse_stl_binary(path, (const unsigned char *)buf, len, out, err);
        break;
    case FMT_STL_ASCII:
        rc = parse_stl_ascii(path, buf + bom, len - bom, out, err);
        break;
    case FMT_OBJ:
        rc = parse_obj(path, buf + bom, len - bom, out, err);
        break;
    default:
        rc = pd_error_set(err, PD_EMESH,
                          "%s: unrecognised mesh format (expected binary or ASCII STL, or "
                          "Wavefront OBJ)",
                          path);
    }
    free(buf);
    return rc;
}

/* ---- specs --------------------------------------------------------------------------------- */

/*
 * A builtin spec's TRIANGLES or SEED field f (what: its name in messages): digits only, from min
 * to max. A field that is there must say something: an empty one, or a count of 0, used to mean
 * the default, unsaid.
 */
static int spec_number(const char *spec, const char *what, const char *f, unsigned long min,
                       unsigned long max, unsigned long *out, pd_error *err)
{
    if (!*f) return pd_error_set(err, PD_EINVAL, "'%s': %s is empty", spec, what);
    if (strspn(f, "0123456789") != strlen(f))
        return pd_error_set(err, PD_EINVAL, "'%s': %s '%s' is not a whole number", spec, what, f);
    errno = 0;
    *out = strtoul(f, NULL, 10);
    if (errno == ERANGE || *out > max)
        return pd_error_set(err, PD_EINVAL, "'%s': %s '%s' is too large", spec, what, f);
    if (*out < min)
        return pd_error_set(err, PD_EINVAL,
                            "'%s': %s '%s' must be at least %lu (leave the field out for the "
                            "default)",
                            spec, what, f, min);
    return PD_OK;
}

int pd_mesh_open(const char *spec, pd_mesh **out, pd_error *err)
{
    static const char prefix[] = "builtin:";
    if (!out) return pd_error_set(err, PD_EINVAL, "pd_mesh_open: no output pointer");
    *out = NULL;
    if (!spec) return pd_error_set(err, PD_EINVAL, "empty mesh spec");
    if (strncmp(spec, prefix, sizeof prefix - 1) != 0) return pd_mesh_load(spec, out, err);

    /* builtin:NAME[:TRIANGLES[:SEED]]; a field that changes nothing (a seed on any shape but the
     * rock, which alone is random) is a mistake to report, as the scenario's "seed" on a cube */
    char name[64], field[2][32];
    const char *s = spec + sizeof prefix - 1, *colon = strchr(s, ':');
    size_t n = colon ? (size_t)(colon - s) : strlen(s);
    if (n >= sizeof name) return pd_error_set(err, PD_EINVAL, "'%s': builtin name too long", spec);
    memcpy(name, s, n);
    name[n] = '\0';
    int nfields = 0;
    while (colon) {
        s = colon + 1;
        colon = strchr(s, ':');
        n = colon ? (size_t)(colon - s) : strlen(s);
        if (nfields == 2)
            return pd_error_set(err, PD_EINVAL,
                                "'%s': too many fields (expected builtin:NAME[:TRIANGLES[:SEED]])",
                                spec);
        if (n >= sizeof field[0])
            return pd_error_set(err, PD_EINVAL, "'%s': field '%s' too long", spec, s);
        memcpy(field[nfields], s, n);
        field[nfields++][n] = '\0';
    }
    unsigned long tris = 0, seed = 1; /* pd_mesh_builtin's defaults */
    int rc = PD_OK;
    if (nfields >= 1) rc = spec_number(spec, "triangle count", field[0], 1, INT_MAX, &tris, err);
    if (rc == PD_OK && nfields >= 2 && strcmp(name, "rock") != 0)
        rc = pd_error_set(err, PD_EINVAL, "'%s': only builtin:rock takes a seed", spec);
    if (rc == PD_OK && nfields >= 2)
        rc = spec_number(spec, "seed", field[1], 0, UINT_MAX, &seed, err);
    if (rc != PD_OK) return rc;
    return pd_mesh_builtin(name, (int)tris, (unsigned)seed, out, err);
}

/* ---- writing ------------------------------------------------------------------------------- */

static void put_float(unsigned char *p, double x)
{
    float f = (float)x;
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    put_le32(p, u);
}

int pd_mesh_write_stl(const pd_mesh *m, const char *path, pd_error *err)
{
    if (!m || !path) return pd_error_set(err, PD_EINVAL, "pd_mesh_write_stl: null argument");
    for (int i = 0; i < 3 * m->nverts; i++) {
        if (!(fabs(m->verts[i]) <= FLT_MAX)) {
            return pd_error_set(err, PD_EINVAL,
                                "%s: coordinate %g does not fit binary STL's float32", path,
                                m->verts[i]);
        }
    }
    FILE *f = fopen(path, "wb");
    if (!f)
        return pd_error_set(err, PD_EIO, "%s: cannot open for writing: %s", path, strerror(errno));

    /* The header must not start with "solid", or readers would take the file for ASCII. */
    unsigned char head[84];
    memset(head, ' ', 80);
    memcpy(head, "polydem binary STL", 18);
    put_le32(head + 80, (uint32_t)m->ntris);
    int ok = fwrite(head, 1, sizeof head, f) == sizeof head;
    unsigned char rec[50];
    for (int t = 0; ok && t < m->ntris; t++) {
        const double *a = &m->verts[3 * m->tris[3 * t]], *b = &m->verts[3 * m->tris[3 * t + 1]],
                     *c = &m->verts[3 * m->tris[3 * t + 2]];
        double u[3], v[3], nrm[3];
        for (int k = 0; k < 3; k++) {
            u[k] = b[k] - a[k];
            v[k] = c[k] - a[k];
        }
        nrm[0] = u[1] * v[2] - u[2] * v[1];
        nrm[1] = u[2] * v[0] - u[0] * v[2];
        nrm[2] = u[0] * v[1] - u[1] * v[0];
        double len = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
        for (int k = 0; k < 3; k++) {
            put_float(rec + 4 * k, len > 0 ? nrm[k] / len : 0);
            put_float(rec + 12 + 4 * k, a[k]);
            put_float(rec + 24 + 4 * k, b[k]);
            put_float(rec + 36 + 4 * k, c[k]);
        }
        rec[48] = rec[49] = 0;
        ok = fwrite(rec, 1, sizeof rec, f) == sizeof rec;
    }
    int saved = errno;
    if (fclose(f) != 0 && ok) {
        ok = 0;
        saved = errno;
    }
    if (!ok) {
        remove(path); /* do not leave a half-written file that looks like a mesh */
        return pd_error_set(err, PD_EIO, "%s: cannot write: %s", path, strerror(saved));
    }
    return PD_OK;
}
