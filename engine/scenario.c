/*
 * scenario.c - parsing and validating a scenario (the contract: schemas/scenario.schema.json;
 * every field, unit and default: docs/SCENARIO.md).
 *
 * Parsing is strict: unknown fields are errors (a misspelt "frction" must not silently become the
 * default), and every problem is collected with its JSON pointer rather than stopping at the
 * first, so a user fixes a scenario in one round.
 */
#include <errno.h>
#include <jansson.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "particles.h"
#include "scenario.h"
#include "wall_tree.h"

static const double PI = 3.14159265358979323846;

typedef struct sc_parse {
    pd_scenario *s;
    pd_diags *d;
    const char *base_dir;
    int failed;
    int ints_as_reals; /* read with JSON_DECODE_INT_AS_REAL: integers beyond 2^53 are not exact */
} sc_parse;

void pd_diags_free(pd_diags *d)
{
    if (!d) return;
    free(d->items);
    d->items = NULL;
    d->n = d->cap = 0;
}

/* snprintf for labels and paths, where truncation is harmless (they only name things). */
static void put(char *out, size_t n, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static void put(char *out, size_t n, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(out, n, fmt, ap);
    va_end(ap);
}

/* Records one problem at a JSON pointer. */
static void diag(sc_parse *p, const char *at, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static void diag(sc_parse *p, const char *at, const char *fmt, ...)
{
    p->failed = 1;
    pd_diags *d = p->d;
    if (!d) return;
    if (d->n == d->cap) {
        int cap = d->cap ? 2 * d->cap : 16;
        pd_diag *it = realloc(d->items, sizeof *it * (size_t)cap);
        if (!it) return; /* out of memory: the failure is still recorded in p->failed */
        d->items = it;
        d->cap = cap;
    }
    pd_diag *g = &d->items[d->n++];
    put(g->path, sizeof g->path, "%s", at[0] ? at : "/");
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(g->msg, sizeof g->msg, fmt, ap);
    va_end(ap);
}

/* Child pointer: at + "/" + key (JSON pointer escaping of '~' and '/' in keys). */
static void child(char *out, size_t n, const char *at, const char *key)
{
    size_t k = (size_t)snprintf(out, n, "%s/", at);
    for (const char *c = key; *c && k + 3 < n; c++) {
        if (*c == '~' || *c == '/') {
            out[k++] = '~';
            out[k++] = *c == '~' ? '0' : '1';
        } else {
            out[k++] = *c;
        }
    }
    out[k < n ? k : n - 1] = 0;
}

static void child_i(char *out, size_t n, const char *at, size_t i)
{
    put(out, n, "%s/%zu", at, i);
}

/*
 * The JSON pointer of the value being read at byte `stop` of text, which a JSON parser gave up on
 * (jansson reports a line and column, not a field). A light scan: strings skipped, containers
 * stacked, object keys and array indices noted; keys are copied with their escapes undone only
 * for \" \\ and \/ (a key with other escapes names no field anyway).
 */
static void path_at(const char *text, size_t stop, char *out, size_t n)
{
    enum { DEPTH = 16 };
    struct {
        char kind; /* '{' or '[' */
        int in_value;
        size_t index;
        char key[SC_NAME_MAX];
    } st[DEPTH];
    int depth = 0; /* frames, counting those beyond DEPTH that are not kept */
    for (size_t i = 0; i < stop && text[i]; i++) {
        char c = text[i];
        if (c == '"') {
            int is_key =
                depth > 0 && depth <= DEPTH && st[depth - 1].kind == '{' && !st[depth - 1].in_value;
            size_t k = 0;
            for (i++; i < stop && text[i] && text[i] != '"'; i++) {
                if (text[i] == '\\' && text[i + 1]) i++;
                if (is_key && k + 1 < SC_NAME_MAX) st[depth - 1].key[k++] = text[i];
            }
            if (is_key) st[depth - 1].key[k] = 0;
            if (i >= stop || !text[i]) break;
        } else if (c == '{' || c == '[') {
            if (depth < DEPTH) {
                st[depth].kind = c;
                st[depth].in_value = c == '[';
                st[depth].index = 0;
                st[depth].key[0] = 0;
            }
            depth++;
        } else if (c == '}' || c == ']') {
            depth -= depth > 0;
        } else if (depth > 0 && depth <= DEPTH && c == ':') {
            st[depth - 1].in_value = 1;
        } else if (depth > 0 && depth <= DEPTH && c == ',') {
            if (st[depth - 1].kind == '[')
                st[depth - 1].index++;
            else
                st[depth - 1].in_value = 0;
        }
    }
    char a[SC_PATH_MAX], b[SC_PATH_MAX];
    a[0] = 0;
    for (int k = 0; k < depth && k < DEPTH && st[k].in_value; k++) {
        if (st[k].kind == '[')
            child_i(b, sizeof b, a, st[k].index);
        else
            child(b, sizeof b, a, st[k].key);
        put(a, sizeof a, "%s", b);
    }
    put(out, n, "%s", a);
}

/* Unknown keys of an object are errors; allowed is NULL-terminated. */
static void only(sc_parse *p, json_t *o, const char *at, const char *const *allowed)
{
    const char *key;
    json_t *v;
    json_object_foreach(o, key, v)
    {
        int ok = 0;
        for (const char *const *a = allowed; *a && !ok; a++)
            ok = !strcmp(*a, key);
        if (!ok) {
            char c[SC_PATH_MAX];
            child(c, sizeof c, at, key);
            diag(p, c, "unknown field");
        }
    }
}

enum { ANY = 0, POSITIVE = 1, NONNEG = 2 };

/* A number field; absent: def (an error when required). */
static double num(sc_parse *p, json_t *o, const char *at, const char *key, int required, double def,
                  int rule, const char *unit)
{
    char c[SC_PATH_MAX];
    child(c, sizeof c, at, key);
    json_t *v = json_object_get(o, key);
    if (!v) {
        if (required) diag(p, c, "required%s%s", unit[0] ? ", in " : "", unit);
        return def;
    }
    if (!json_is_number(v)) {
        diag(p, c, "must be a number%s%s", unit[0] ? " in " : "", unit);
        return def;
    }
    double x = json_number_value(v);
    if (!isfinite(x)) {
        diag(p, c, "must be finite");
        return def;
    }
    if (rule == POSITIVE && !(x > 0)) {
        diag(p, c, "must be > 0, got %g", x);
        return def;
    }
    if (rule == NONNEG && !(x >= 0)) {
        diag(p, c, "must be >= 0, got %g", x);
        return def;
    }
    return x;
}

/*
 * Whether v is an integer in [lo, hi], stored in *out: a JSON number with no fraction, 80 or 80.0,
 * as the schema's "integer" counts them (JSON Schema 2020-12 section 6.1.1 takes 80.0 as 80).
 */
static int int_value(const sc_parse *p, json_t *v, long long lo, long long hi, long long *out)
{
    if (json_is_integer(v)) {
        if (json_integer_value(v) < lo || json_integer_value(v) > hi) return 0;
        *out = json_integer_value(v);
        return 1;
    }
    if (!json_is_real(v)) return 0;
    double x = json_real_value(v);
    /* (double)hi rounds up for hi near 2^63: such a real must not reach the cast */
    if (!(x >= (double)lo && x <= (double)hi) || x != floor(x) || !(fabs(x) < 0x1p63)) return 0;
    if (p->ints_as_reals && fabs(x) >= 0x1p53) return 0; /* which integer it was is lost */
    if ((long long)x < lo || (long long)x > hi) return 0;
    *out = (long long)x;
    return 1;
}

/* An integer field in [lo, hi]; absent: def. */
static long long integer(sc_parse *p, json_t *o, const char *at, const char *key, long long def,
                         long long lo, long long hi)
{
    char c[SC_PATH_MAX];
    child(c, sizeof c, at, key);
    json_t *v = json_object_get(o, key);
    long long x;
    if (!v) return def;
    if (!int_value(p, v, lo, hi, &x)) {
        diag(p, c, "must be an integer from %lld to %lld", lo, hi);
        return def;
    }
    return x;
}

/* A fixed-length numeric array field; absent: def (when def is NULL the field is required). */
static int numvec(sc_parse *p, json_t *o, const char *at, const char *key, int n, const double *def,
                  double *out)
{
    char c[SC_PATH_MAX];
    child(c, sizeof c, at, key);
    json_t *v = json_object_get(o, key);
    if (!v) {
        if (!def) {
            diag(p, c, "required: an array of %d numbers", n);
            return 0;
        }
        memcpy(out, def, sizeof(double) * (size_t)n);
        return 1;
    }
    if (!json_is_array(v) || (int)json_array_size(v) != n) {
        diag(p, c, "must be an array of %d numbers", n);
        return 0;
    }
    for (int i = 0; i < n; i++) {
        json_t *x = json_array_get(v, (size_t)i);
        if (!json_is_number(x) || !isfinite(json_number_value(x))) {
            char ci[SC_PATH_MAX];
            child_i(ci, sizeof ci, c, (size_t)i);
            diag(p, ci, "must be a finite number");
            return 0;
        }
        out[i] = json_number_value(x);
    }
    return 1;
}

/* A string field, or NULL (an error when required). */
static const char *str(sc_parse *p, json_t *o, const char *at, const char *key, int required)
{
    char c[SC_PATH_MAX];
    child(c, sizeof c, at, key);
    json_t *v = json_object_get(o, key);
    if (!v) {
        if (required) diag(p, c, "required: a string");
        return NULL;
    }
    if (!json_is_string(v)) {
        diag(p, c, "must be a string");
        return NULL;
    }
    return json_string_value(v);
}

/* An object member that must be a JSON object when present. */
static json_t *obj(sc_parse *p, json_t *o, const char *at, const char *key, int required)
{
    char c[SC_PATH_MAX];
    child(c, sizeof c, at, key);
    json_t *v = json_object_get(o, key);
    if (!v) {
        if (required) diag(p, c, "required: an object");
        return NULL;
    }
    if (!json_is_object(v)) {
        diag(p, c, "must be an object");
        return NULL;
    }
    return v;
}

/* An object member that must be a JSON array when present. */
static json_t *arr(sc_parse *p, json_t *o, const char *at, const char *key)
{
    char c[SC_PATH_MAX];
    child(c, sizeof c, at, key);
    json_t *v = json_object_get(o, key);
    if (v && !json_is_array(v)) {
        diag(p, c, "must be an array");
        return NULL;
    }
    return v;
}

static int find_material(const pd_scenario *s, const char *name)
{
    for (int i = 0; i < s->nmat; i++)
        if (!strcmp(s->mat[i].name, name)) return i;
    return -1;
}

static int find_shape(const pd_scenario *s, const char *name)
{
    for (int i = 0; i < s->nshape; i++)
        if (!strcmp(s->shape[i].name, name)) return i;
    return -1;
}

const sc_interaction *sc_interaction_of(const pd_scenario *s, int a, int b)
{
    for (int i = 0; i < s->nint; i++) {
        const sc_interaction *x = &s->inter[i];
        if ((x->mat[0] == a && x->mat[1] == b) || (x->mat[0] == b && x->mat[1] == a)) return x;
    }
    return NULL;
}

/* A material reference: the index, or -1 after a diagnostic. */
static int material_ref(sc_parse *p, json_t *o, const char *at, const char *key)
{
    const char *name = str(p, o, at, key, 1);
    if (!name) return -1;
    int m = find_material(p->s, name);
    if (m < 0) {
        char c[SC_PATH_MAX];
        child(c, sizeof c, at, key);
        diag(p, c, "no material named '%s' in /materials", name);
    }
    return m;
}

/*
 * Copies a name of at most SC_NAME_CHARS characters (code points, as the schema's maxLength
 * counts them). A shape's or wall's name (group = 1) also names an HDF5 group in the result
 * (/shapes/<name>, /walls/<name>), so it must be a plain link name: not empty, no '/', not "."
 * or "..".
 */
static void copy_name(char *dst, const char *src, sc_parse *p, const char *at, int group)
{
    size_t chars = 0;
    for (const unsigned char *c = (const unsigned char *)src; *c; c++)
        chars += (*c & 0xC0) != 0x80; /* UTF-8: count the bytes that start a character */
    if (chars > SC_NAME_CHARS)
        diag(p, at, "name longer than %d characters", SC_NAME_CHARS);
    else if (group && !src[0])
        diag(p, at, "name must not be empty");
    else if (group && (strchr(src, '/') || !strcmp(src, ".") || !strcmp(src, "..")))
        diag(p, at, "name '%s' cannot name a group in the result: no '/', not '.' or '..'", src);
    put(dst, SC_NAME_MAX, "%s", src);
}

static void parse_time(sc_parse *p, json_t *root)
{
    static const char *const keys[] = {"dt", "duration", "output_interval", "stats_interval", NULL};
    pd_scenario *s = p->s;
    json_t *t = obj(p, root, "", "time", 1);
    if (!t) return;
    only(p, t, "/time", keys);
    s->dt = num(p, t, "/time", "dt", 1, 1e-5, POSITIVE, "s");
    s->duration = num(p, t, "/time", "duration", 1, 1, POSITIVE, "s");
    /* defaults: 100 frames and 10 stats rows per frame, never finer than one step */
    double out_def = s->duration / 100 > s->dt ? s->duration / 100 : s->dt;
    s->output_interval = num(p, t, "/time", "output_interval", 0, out_def, POSITIVE, "s");
    double stats_def = s->output_interval / 10 > s->dt ? s->output_interval / 10 : s->dt;
    s->stats_interval = num(p, t, "/time", "stats_interval", 0, stats_def, POSITIVE, "s");
    if (s->duration < s->dt)
        diag(p, "/time/duration", "%g s is shorter than one time step dt (%g s)", s->duration,
             s->dt);
    else if (s->output_interval < s->dt)
        diag(p, "/time/output_interval", "%g s is shorter than dt (%g s)", s->output_interval,
             s->dt);
    if (s->stats_interval < s->dt)
        diag(p, "/time/stats_interval", "%g s is shorter than dt (%g s)", s->stats_interval, s->dt);
    if (s->duration / s->dt > 1e12)
        diag(p, "/time/duration", "%g s at dt %g s is more than 1e12 steps", s->duration, s->dt);
}

static void parse_materials(sc_parse *p, json_t *root)
{
    static const char *const keys[] = {"density", "youngs_modulus", "poisson_ratio",
                                       "shear_modulus", NULL};
    pd_scenario *s = p->s;
    json_t *m = obj(p, root, "", "materials", 1);
    if (!m) return;
    if (json_object_size(m) == 0) diag(p, "/materials", "at least one material is required");
    s->mat = calloc(json_object_size(m) + 1, sizeof *s->mat);
    if (!s->mat) return;
    const char *name;
    json_t *v;
    json_object_foreach(m, name, v)
    {
        char at[SC_PATH_MAX];
        child(at, sizeof at, "/materials", name);
        if (!json_is_object(v)) {
            diag(p, at, "must be an object");
            continue;
        }
        only(p, v, at, keys);
        sc_material *x = &s->mat[s->nmat++];
        copy_name(x->name, name, p, at, 0);
        x->density = num(p, v, at, "density", 1, 1000, POSITIVE, "kg/m^3");
        x->youngs_modulus = num(p, v, at, "youngs_modulus", 1, 1e7, POSITIVE, "Pa");
        x->poisson_ratio = num(p, v, at, "poisson_ratio", 0, 0.25, ANY, "");
        if (!(x->poisson_ratio > -1 && x->poisson_ratio < 0.5)) {
            char c[SC_PATH_MAX];
            child(c, sizeof c, at, "poisson_ratio");
            diag(p, c, "must lie in (-1, 0.5), got %g", x->poisson_ratio);
            x->poisson_ratio = 0.25;
        }
        x->shear_modulus = num(p, v, at, "shear_modulus", 0,
                               x->youngs_modulus / (2 * (1 + x->poisson_ratio)), POSITIVE, "Pa");
    }
}

static void parse_interactions(sc_parse *p, json_t *root)
{
    static const char *const keys[] = {"between",
                                       "friction",
                                       "damping",
                                       "model",
                                       "cohesion",
                                       "cohesion_range",
                                       "normal_stiffness",
                                       "tangential_stiffness",
                                       "damping_coefficient",
                                       "contact_places",
                                       "contact_moments",
                                       NULL};
    pd_scenario *s = p->s;
    json_t *a = arr(p, root, "", "interactions");
    if (!a) return; /* missing pairs are reported where materials are used */
    s->inter = calloc(json_array_size(a) + 1, sizeof *s->inter);
    if (!s->inter) return;
    size_t i;
    json_t *v;
    json_array_foreach(a, i, v)
    {
        char at[SC_PATH_MAX], c[SC_PATH_MAX];
        child_i(at, sizeof at, "/interactions", i);
        if (!json_is_object(v)) {
            diag(p, at, "must be an object");
            continue;
        }
        only(p, v, at, keys);
        sc_interaction x;
        memset(&x, 0, sizeof x);
        json_t *b = json_object_get(v, "between");
        child(c, sizeof c, at, "between");
        if (!json_is_array(b) || json_array_size(b) != 2 || !json_is_string(json_array_get(b, 0)) ||
            !json_is_string(json_array_get(b, 1))) {
            diag(p, c, "required: two material names");
            continue;
        }
        int ok = 1;
        for (int k = 0; k < 2; k++) {
            const char *mn = json_string_value(json_array_get(b, (size_t)k));
            x.mat[k] = find_material(s, mn);
            if (x.mat[k] < 0) {
                char ck[SC_PATH_MAX];
                child_i(ck, sizeof ck, c, (size_t)k);
                diag(p, ck, "no material named '%s' in /materials", mn);
                ok = 0;
            }
        }
        const char *model = str(p, v, at, "model", 0);
        x.model = SC_MODEL_HERTZ_MINDLIN;
        if (model && !strcmp(model, "linear"))
            x.model = SC_MODEL_LINEAR;
        else if (model && strcmp(model, "hertz_mindlin")) {
            child(c, sizeof c, at, "model");
            diag(p, c, "must be \"hertz_mindlin\" or \"linear\", got \"%s\"", model);
        }
        const char *places = str(p, v, at, "contact_places", 0);
        x.separate_places = places && !strcmp(places, "separate");
        if (places && !x.separate_places && strcmp(places, "merged")) {
            child(c, sizeof c, at, "contact_places");
            diag(p, c, "must be \"merged\" or \"separate\", got \"%s\"", places);
        } else if (x.separate_places && x.model == SC_MODEL_LINEAR) {
            child(c, sizeof c, at, "contact_places");
            diag(p, c,
                 "\"separate\" is for \"model\": \"hertz_mindlin\" (the linear model's "
                 "force is not a function of volume and depth)");
        }
        json_t *tw = json_object_get(v, "contact_moments");
        child(c, sizeof c, at, "contact_moments");
        if (tw && !json_is_boolean(tw))
            diag(p, c, "must be true or false");
        else if (json_is_true(tw) && x.model == SC_MODEL_LINEAR)
            diag(p, c, "is for \"model\": \"hertz_mindlin\" (polyhedra's volumetric contacts)");
        x.contact_moments = x.model == SC_MODEL_HERTZ_MINDLIN && !json_is_false(tw);
        x.friction = num(p, v, at, "friction", 0, 0.5, NONNEG, "");
        x.damping = num(p, v, at, "damping", 0, 0, NONNEG, "");
        x.cohesion = num(p, v, at, "cohesion", 0, 0, NONNEG, "N/m");
        x.cohesion_range = num(p, v, at, "cohesion_range", 0, 0, NONNEG, "m");
        if (x.cohesion > 0 && !(x.cohesion_range > 0)) {
            child(c, sizeof c, at, "cohesion_range");
            diag(p, c,
                 "required (> 0 m) when cohesion is set: how far beyond the surfaces the "
                 "cohesive effect surface lies (seed 004 L_e = d_e - d_b)");
        }
        if (x.model == SC_MODEL_LINEAR) {
            x.normal_stiffness = num(p, v, at, "normal_stiffness", 1, 1e4, POSITIVE, "N/m");
            x.tangential_stiffness = num(p, v, at, "tangential_stiffness", 0,
                                         2.0 / 7.0 * x.normal_stiffness, NONNEG, "N/m");
            x.damping_coefficient = num(p, v, at, "damping_coefficient", 0, 0, NONNEG, "N s/m");
        } else {
            static const char *const lin[] = {"normal_stiffness", "tangential_stiffness",
                                              "damping_coefficient"};
            for (int k = 0; k < 3; k++)
                if (json_object_get(v, lin[k])) {
                    child(c, sizeof c, at, lin[k]);
                    diag(p, c, "only for \"model\": \"linear\"");
                }
        }
        if (!ok) continue;
        if (sc_interaction_of(s, x.mat[0], x.mat[1])) {
            diag(p, at, "a second interaction between '%s' and '%s'", s->mat[x.mat[0]].name,
                 s->mat[x.mat[1]].name);
            continue;
        }
        s->inter[s->nint++] = x;
    }
}

/* Records a file the scenario was read from; PD_ENOMEM or PD_OK (a file that cannot be stat'ed
 * is not recorded: its reader reports it). */
static int add_input(pd_scenario *s, const char *path)
{
    struct stat st;
    if (stat(path, &st) != 0) return PD_OK;
    sc_input *in = realloc(s->inputs, sizeof *in * ((size_t)s->ninputs + 1));
    if (!in) return PD_ENOMEM;
    s->inputs = in;
    in += s->ninputs;
    if (!(in->path = strdup(path))) return PD_ENOMEM;
    in->dev = (unsigned long long)st.st_dev;
    in->ino = (unsigned long long)st.st_ino;
    s->ninputs++;
    return PD_OK;
}

/* Loads the mesh file named by the "mesh" field of the object at `at`, relative to the scenario's
 * directory; NULL after a diagnostic that quotes the loader's message (file and defect). */
static pd_mesh *load_mesh_file(sc_parse *p, const char *file, const char *at)
{
    char path[4096], c[SC_PATH_MAX];
    pd_mesh *m = NULL;
    pd_error err = {0};
    if (file[0] == '/' || !p->base_dir)
        put(path, sizeof path, "%s", file);
    else
        put(path, sizeof path, "%s/%s", p->base_dir, file);
    if (pd_mesh_load(path, &m, &err) != PD_OK) {
        child(c, sizeof c, at, "mesh");
        diag(p, c, "%s", err.msg);
    } else if (add_input(p->s, path) != PD_OK) {
        diag(p, at, "out of memory");
    }
    return m;
}

/* Loads the mesh of one shape object (not a sphere); NULL after a diagnostic. */
static pd_mesh *shape_mesh(sc_parse *p, json_t *v, const char *at)
{
    pd_error err = {0};
    pd_mesh *m = NULL;
    char c[SC_PATH_MAX];
    const char *builtin = str(p, v, at, "builtin", 0);
    const char *file = str(p, v, at, "mesh", 0);
    json_t *verts = json_object_get(v, "vertices");
    int kinds = (builtin != NULL) + (file != NULL) + (verts != NULL);
    if (kinds != 1) {
        diag(p, at, "needs exactly one of \"builtin\", \"mesh\", \"vertices\" or \"sphere\"");
        return NULL;
    }
    if (builtin) {
        /* "triangles" picks a level of the refinable shapes (and is checked against the fixed
         * ones' own count); "seed" draws a rock and means nothing to the others */
        long long tri = integer(p, v, at, "triangles", 0, 1, 1000000);
        long long seed = integer(p, v, at, "seed", 1, 0, 4294967295LL);
        if (json_object_get(v, "seed") && strcmp(builtin, "rock")) {
            child(c, sizeof c, at, "seed");
            diag(p, c, "only a \"rock\" takes a seed");
        }
        if (pd_mesh_builtin(builtin, (int)tri, (unsigned)seed, &m, &err) != PD_OK) {
            /* a count the shape does not come in is the count's fault, not the name's */
            static const char *const known[] = {"cube", "tetrahedron", "schonhardt", "icosphere",
                                                "rock"};
            int named = 0;
            for (int k = 0; k < 5; k++)
                named |= !strcmp(builtin, known[k]);
            child(c, sizeof c, at,
                  named && json_object_get(v, "triangles") ? "triangles" : "builtin");
            diag(p, c, "%s", err.msg);
        }
    } else if (file) {
        /* a builtin's parameters mean nothing to a file: an error, not silently ignored */
        if (json_object_get(v, "seed") || json_object_get(v, "triangles"))
            diag(p, at, "\"seed\" and \"triangles\" belong to a \"builtin\" shape, not a \"mesh\"");
        m = load_mesh_file(p, file, at);
    } else {
        if (json_object_get(v, "seed")) { /* was silently ignored */
            child(c, sizeof c, at, "seed");
            diag(p, c, "only a \"builtin\": \"rock\" takes a seed");
        }
        json_t *tris = json_object_get(v, "triangles");
        size_t nv = json_is_array(verts) ? json_array_size(verts) : 0;
        size_t nt = json_is_array(tris) ? json_array_size(tris) : 0;
        if (!nv || !nt) {
            diag(p, at, "\"vertices\" and \"triangles\" must be non-empty arrays");
            return NULL;
        }
        double *vx = malloc(sizeof(double) * 3 * nv);
        int *tx = malloc(sizeof(int) * 3 * nt);
        int bad = !vx || !tx;
        for (size_t i = 0; i < nv && !bad; i++) {
            json_t *r = json_array_get(verts, i);
            for (int k = 0; k < 3 && !bad; k++) {
                json_t *x = json_array_get(r, (size_t)k);
                if (!json_is_array(r) || json_array_size(r) != 3 || !json_is_number(x)) {
                    put(c, sizeof c, "%s/vertices/%zu", at, i);
                    diag(p, c, "must be [x, y, z] in m");
                    bad = 1;
                } else {
                    vx[3 * i + k] = json_number_value(x);
                }
            }
        }
        for (size_t i = 0; i < nt && !bad; i++) {
            json_t *r = json_array_get(tris, i);
            for (int k = 0; k < 3 && !bad; k++) {
                json_t *x = json_array_get(r, (size_t)k);
                long long ix;
                if (!json_is_array(r) || json_array_size(r) != 3 || !json_is_number(x)) {
                    put(c, sizeof c, "%s/triangles/%zu", at, i);
                    diag(p, c, "must be [i, j, k] vertex indices");
                    bad = 1;
                } else if (!int_value(p, x, 0, (long long)nv - 1, &ix)) {
                    /* checked here, before the cast to int, which wrapped 4294967296 to 0 */
                    put(c, sizeof c, "%s/triangles/%zu/%d", at, i, k);
                    diag(p, c, "must be a vertex index, an integer from 0 to %zu", nv - 1);
                    bad = 1;
                } else {
                    tx[3 * i + k] = (int)ix;
                }
            }
        }
        if (!bad && pd_mesh_from_arrays(vx, (int)nv, tx, (int)nt, at, &m, &err) != PD_OK)
            diag(p, at, "%s", err.msg);
        free(vx);
        free(tx);
    }
    return m;
}

static void parse_shapes(sc_parse *p, json_t *root)
{
    static const char *const keys[] = {"builtin",  "triangles", "seed", "mesh",
                                       "vertices", "sphere",    NULL};
    pd_scenario *s = p->s;
    json_t *o = obj(p, root, "", "shapes", 1);
    if (!o) return;
    s->shape = calloc(json_object_size(o) + 1, sizeof *s->shape);
    if (!s->shape) return;
    const char *name;
    json_t *v;
    json_object_foreach(o, name, v)
    {
        char at[SC_PATH_MAX];
        child(at, sizeof at, "/shapes", name);
        if (!json_is_object(v)) {
            diag(p, at, "must be an object");
            continue;
        }
        only(p, v, at, keys);
        sc_shape *x = &s->shape[s->nshape++];
        copy_name(x->name, name, p, at, 1);
        json_t *sph = json_object_get(v, "sphere");
        if (sph) {
            if (json_object_size(v) != 1) diag(p, at, "a \"sphere\" takes no other field");
            if (!json_is_object(sph) || json_object_size(sph) != 0) {
                char c[SC_PATH_MAX];
                child(c, sizeof c, at, "sphere");
                diag(p, c, "must be {} (a sphere's size is the particle's size)");
            }
            x->kind = SC_SHAPE_SPHERE;
            x->radius_ratio = 0.5;
            continue;
        }
        x->kind = SC_SHAPE_MESH;
        x->mesh = shape_mesh(p, v, at);
        if (!x->mesh) continue;
        /* body frame, scaled to a volume-equivalent diameter of 1 m: a particle's size scales it */
        pd_mass_props mp;
        double rot[3][3];
        pd_mesh_to_body_frame(x->mesh, &mp, rot);
        double k = cbrt(PI / 6 / mp.volume), r2 = 0;
        for (int i = 0; i < 3 * x->mesh->nverts; i++)
            x->mesh->verts[i] *= k;
        for (int i = 0; i < x->mesh->nverts; i++) {
            const double *q = x->mesh->verts + 3 * i;
            double d = q[0] * q[0] + q[1] * q[1] + q[2] * q[2];
            r2 = d > r2 ? d : r2;
        }
        x->radius_ratio = sqrt(r2);
    }
}

/* Normalises a quaternion field; 0 after a diagnostic. */
static int quat(sc_parse *p, const char *at, double q[4])
{
    if (pd_quat_normalize(q, q) != PD_OK) {
        diag(p, at, "quaternion [w, x, y, z] must not be zero");
        return 0;
    }
    return 1;
}

static void parse_size(sc_parse *p, json_t *g, const char *at, sc_size *z)
{
    static const char *const keys[] = {"distribution", "mean", "std", "min", "max", NULL};
    char c[SC_PATH_MAX];
    child(c, sizeof c, at, "size");
    json_t *v = json_object_get(g, "size");
    memset(z, 0, sizeof *z);
    z->mean = z->min = z->max = 0.01;
    if (!v) {
        diag(p, c, "required: a diameter in m, or a distribution");
        return;
    }
    if (json_is_number(v)) {
        double d = json_number_value(v);
        if (!(d > 0) || !isfinite(d))
            diag(p, c, "must be > 0 m, got %g", d);
        else
            z->mean = z->min = z->max = d;
        return;
    }
    if (!json_is_object(v)) {
        diag(p, c, "must be a number (m) or a distribution object");
        return;
    }
    only(p, v, c, keys);
    const char *dist = str(p, v, c, "distribution", 1);
    if (dist && !strcmp(dist, "uniform")) {
        z->dist = SC_SIZE_UNIFORM;
        /* a uniform distribution has no mean or std: given, they were silently ignored */
        static const char *const normal_only[] = {"mean", "std"};
        for (int k = 0; k < 2; k++)
            if (json_object_get(v, normal_only[k])) {
                char ck[SC_PATH_MAX];
                child(ck, sizeof ck, c, normal_only[k]);
                diag(p, ck, "only for \"distribution\": \"normal\" (uniform takes min and max)");
            }
        z->min = num(p, v, c, "min", 1, 0.01, POSITIVE, "m");
        z->max = num(p, v, c, "max", 1, z->min, POSITIVE, "m");
        z->mean = 0.5 * (z->min + z->max);
    } else if (dist && !strcmp(dist, "normal")) {
        z->dist = SC_SIZE_NORMAL;
        z->mean = num(p, v, c, "mean", 1, 0.01, POSITIVE, "m");
        z->std = num(p, v, c, "std", 1, 0, NONNEG, "m");
        z->min = num(p, v, c, "min", 0, z->mean - 3 * z->std, ANY, "m");
        z->max = num(p, v, c, "max", 0, z->mean + 3 * z->std, POSITIVE, "m");
        if (!(z->min > 0)) {
            char cm[SC_PATH_MAX];
            child(cm, sizeof cm, c, "min");
            diag(p, cm, "must be > 0 m (mean - 3 std is %g m when min is not given)", z->min);
            z->min = z->mean;
        }
    } else if (dist) {
        char cd[SC_PATH_MAX];
        child(cd, sizeof cd, c, "distribution");
        diag(p, cd, "must be \"normal\" or \"uniform\", got \"%s\"", dist);
        return;
    }
    if (z->min > z->max) diag(p, c, "min (%g m) is larger than max (%g m)", z->min, z->max);
}

static void parse_list(sc_parse *p, json_t *list, const char *at, sc_group *g)
{
    static const char *const keys[] = {"position",         "orientation", "velocity",
                                       "angular_velocity", "size",        NULL};
    static const double zero[3] = {0, 0, 0}, ident[4] = {1, 0, 0, 0};
    size_t n = json_array_size(list);
    if (n == 0) {
        diag(p, at, "must list at least one particle");
        return;
    }
    g->list = calloc(n, sizeof *g->list);
    if (!g->list) return;
    g->count = (long)n;
    size_t i;
    json_t *v;
    json_array_foreach(list, i, v)
    {
        char c[SC_PATH_MAX];
        child_i(c, sizeof c, at, i);
        sc_particle *x = &g->list[i];
        if (!json_is_object(v)) {
            diag(p, c, "must be an object");
            continue;
        }
        only(p, v, c, keys);
        numvec(p, v, c, "position", 3, NULL, x->position);
        if (numvec(p, v, c, "orientation", 4, ident, x->orientation)) {
            char co[SC_PATH_MAX];
            child(co, sizeof co, c, "orientation");
            quat(p, co, x->orientation);
        }
        numvec(p, v, c, "velocity", 3, zero, x->velocity);
        numvec(p, v, c, "angular_velocity", 3, zero, x->angular_velocity);
        x->size = num(p, v, c, "size", 1, 0.01, POSITIVE, "m");
    }
}

static void parse_particles(sc_parse *p, json_t *root)
{
    static const char *const keys[] = {
        "shape",    "material",         "count", "size", "region", "arrangement", "orientation",
        "velocity", "angular_velocity", "list",  NULL};
    static const double zero[3] = {0, 0, 0};
    pd_scenario *s = p->s;
    json_t *a = json_object_get(root, "particles");
    if (!json_is_array(a) || json_array_size(a) == 0) {
        diag(p, "/particles", "required: an array of particle groups");
        return;
    }
    s->group = calloc(json_array_size(a), sizeof *s->group);
    if (!s->group) return;
    size_t i;
    json_t *v;
    json_array_foreach(a, i, v)
    {
        char at[SC_PATH_MAX], c[SC_PATH_MAX];
        child_i(at, sizeof at, "/particles", i);
        if (!json_is_object(v)) {
            diag(p, at, "must be an object");
            continue;
        }
        only(p, v, at, keys);
        sc_group *g = &s->group[s->ngroup++];
        g->orientation[0] = 1;
        const char *sh = str(p, v, at, "shape", 1);
        g->shape = sh ? find_shape(s, sh) : -1;
        if (sh && g->shape < 0) {
            child(c, sizeof c, at, "shape");
            diag(p, c, "no shape named '%s' in /shapes", sh);
        }
        g->material = material_ref(p, v, at, "material");
        json_t *list = json_object_get(v, "list");
        if (list) {
            child(c, sizeof c, at, "list");
            if (!json_is_array(list)) {
                diag(p, c, "must be an array of particles");
                continue;
            }
            static const char *const gen[] = {"count",           "size",        "region",
                                              "arrangement",     "orientation", "velocity",
                                              "angular_velocity"};
            for (int k = 0; k < 7; k++)
                if (json_object_get(v, gen[k])) {
                    char ck[SC_PATH_MAX];
                    child(ck, sizeof ck, at, gen[k]);
                    diag(p, ck, "not allowed with \"list\" (give it per particle)");
                }
            parse_list(p, list, c, g);
            continue;
        }
        child(c, sizeof c, at, "count");
        if (!json_object_get(v, "count"))
            diag(p, c, "required: an integer from 1 to 1e8 (or give \"list\")");
        else
            g->count = (long)integer(p, v, at, "count", 0, 1, 100000000);
        parse_size(p, v, at, &g->size);
        json_t *reg = obj(p, v, at, "region", 1);
        if (reg) {
            static const char *const rk[] = {"min", "max", NULL};
            child(c, sizeof c, at, "region");
            only(p, reg, c, rk);
            if (numvec(p, reg, c, "min", 3, NULL, g->region_min) &&
                numvec(p, reg, c, "max", 3, NULL, g->region_max)) {
                for (int k = 0; k < 3; k++) {
                    if (!(g->region_max[k] > g->region_min[k])) {
                        diag(p, c, "max must exceed min on every axis (axis %d: %g <= %g m)", k,
                             g->region_max[k], g->region_min[k]);
                        break;
                    }
                    if (!isfinite(g->region_max[k] - g->region_min[k])) {
                        diag(p, c, "too large: max - min overflows on axis %d", k);
                        break;
                    }
                }
            }
        }
        const char *arr = str(p, v, at, "arrangement", 0);
        if (arr && !strcmp(arr, "random"))
            g->random_arrangement = 1;
        else if (arr && strcmp(arr, "lattice")) {
            child(c, sizeof c, at, "arrangement");
            diag(p, c, "must be \"lattice\" or \"random\", got \"%s\"", arr);
        }
        json_t *o = json_object_get(v, "orientation");
        child(c, sizeof c, at, "orientation");
        if (json_is_string(o) && !strcmp(json_string_value(o), "random"))
            g->random_orientation = 1;
        else if (o && !json_is_array(o))
            diag(p, c, "must be \"random\" or a quaternion [w, x, y, z]");
        else if (o && numvec(p, v, at, "orientation", 4, NULL, g->orientation))
            quat(p, c, g->orientation);
        numvec(p, v, at, "velocity", 3, zero, g->velocity);
        numvec(p, v, at, "angular_velocity", 3, zero, g->angular_velocity);
    }
}

static void parse_walls(sc_parse *p, json_t *root)
{
    static const char *const keys[] = {"name",     "material",         "box",    "mesh",
                                       "velocity", "angular_velocity", "center", NULL};
    static const double zero[3] = {0, 0, 0};
    pd_scenario *s = p->s;
    json_t *a = arr(p, root, "", "walls");
    if (!a) return;
    s->wall = calloc(json_array_size(a) + 1, sizeof *s->wall);
    if (!s->wall) return;
    size_t i;
    json_t *v;
    json_array_foreach(a, i, v)
    {
        char at[SC_PATH_MAX], c[SC_PATH_MAX];
        child_i(at, sizeof at, "/walls", i);
        if (!json_is_object(v)) {
            diag(p, at, "must be an object");
            continue;
        }
        only(p, v, at, keys);
        sc_wall *w = &s->wall[s->nwall++];
        const char *name = str(p, v, at, "name", 1);
        if (name) {
            child(c, sizeof c, at, "name");
            copy_name(w->name, name, p, c, 1);
            for (int k = 0; k + 1 < s->nwall; k++)
                if (!strcmp(s->wall[k].name, w->name)) diag(p, c, "a second wall named '%s'", name);
        }
        w->material = material_ref(p, v, at, "material");
        json_t *box = json_object_get(v, "box");
        const char *file = str(p, v, at, "mesh", 0);
        pd_error err = {0};
        if ((box != NULL) == (file != NULL)) {
            diag(p, at, "needs exactly one of \"box\" or \"mesh\"");
        } else if (box) {
            static const char *const bk[] = {"min", "max", NULL};
            double lo[3], hi[3];
            child(c, sizeof c, at, "box");
            if (!json_is_object(box)) {
                diag(p, c, "must be an object {\"min\": [..], \"max\": [..]}");
            } else {
                only(p, box, c, bk);
                if (numvec(p, box, c, "min", 3, NULL, lo) &&
                    numvec(p, box, c, "max", 3, NULL, hi)) {
                    if (!(hi[0] > lo[0] && hi[1] > lo[1] && hi[2] > lo[2]))
                        diag(p, c, "max must exceed min on every axis");
                    else if (pd_mesh_box(lo, hi, &w->mesh, &err) != PD_OK)
                        diag(p, c, "%s", err.msg);
                }
            }
        } else {
            w->mesh = load_mesh_file(p, file, at);
        }
        numvec(p, v, at, "velocity", 3, zero, w->velocity);
        numvec(p, v, at, "angular_velocity", 3, zero, w->angular_velocity);
        numvec(p, v, at, "center", 3, zero, w->center);
    }
}

static void parse_rest(sc_parse *p, json_t *root)
{
    static const double g0[3] = {0, 0, -9.81}, zero[3] = {0, 0, 0};
    pd_scenario *s = p->s;
    const char *name = str(p, root, "", "name", 0);
    if (name && !name[0]) diag(p, "/name", "must not be empty (omit it for \"scenario\")");
    copy_name(s->name, name ? name : "scenario", p, "/name", 0);
    const char *prec = str(p, root, "", "precision", 0);
    s->double_precision = 1;
    if (prec && !strcmp(prec, "single"))
        s->double_precision = 0;
    else if (prec && strcmp(prec, "double"))
        diag(p, "/precision", "must be \"double\" or \"single\", got \"%s\"", prec);
    /* up to the largest integer a JSON parser of 64-bit integers reads (the schema's maximum) */
    s->seed = (unsigned long long)integer(p, root, "", "seed", 1, 0, LLONG_MAX);
    if (numvec(p, root, "", "gravity", 3, g0, s->gravity)) {
        double g = hypot(hypot(s->gravity[0], s->gravity[1]), s->gravity[2]);
        if (!(g <= 1e6)) /* beyond any centrifuge; overflows the time step estimates */
            diag(p, "/gravity", "magnitude %g m/s^2 is beyond 1e6 m/s^2", g);
    }
    json_t *au = json_object_get(root, "allow_unstable_dt");
    if (au && !json_is_boolean(au)) diag(p, "/allow_unstable_dt", "must be true or false");
    s->allow_unstable_dt = json_is_true(au);
    json_t *f = obj(p, root, "", "fluid", 0);
    if (f) {
        static const char *const fk[] = {"viscosity", "velocity", NULL};
        only(p, f, "/fluid", fk);
        s->has_fluid = 1;
        s->fluid_viscosity = num(p, f, "/fluid", "viscosity", 1, 0, NONNEG, "Pa s");
        numvec(p, f, "/fluid", "velocity", 3, zero, s->fluid_velocity);
    }
    s->output_fields = SC_OUT_POSITION | SC_OUT_ORIENTATION | SC_OUT_VELOCITY | SC_OUT_ANGULAR;
    json_t *out = obj(p, root, "", "output", 0);
    if (out) {
        static const char *const ok[] = {"fields", NULL};
        static const char *const names[] = {"position", "orientation", "velocity",
                                            "angular_velocity"};
        only(p, out, "/output", ok);
        json_t *fl = json_object_get(out, "fields");
        if (fl) {
            s->output_fields = SC_OUT_POSITION | SC_OUT_ORIENTATION; /* always: viewers need them */
            if (!json_is_array(fl)) diag(p, "/output/fields", "must be an array of field names");
            size_t i;
            json_t *v;
            int listed = 0;
            json_array_foreach(fl, i, v)
            {
                int bit = 0;
                for (int k = 0; k < 4; k++)
                    if (json_is_string(v) && !strcmp(json_string_value(v), names[k])) bit = 1 << k;
                char c[SC_PATH_MAX];
                child_i(c, sizeof c, "/output/fields", i);
                if (!bit)
                    diag(p, c, "must be one of position, orientation, velocity, angular_velocity");
                else if (listed & bit) /* the schema's uniqueItems */
                    diag(p, c, "'%s' is listed twice", json_string_value(v));
                listed |= bit;
                s->output_fields |= bit;
            }
        }
    }
}

/* Every pair of materials that can touch needs an interaction (a material's own pair only where
 * it has two particles, or a wall of it). */
static void check_pairs(sc_parse *p)
{
    pd_scenario *s = p->s;
    long used_p[64] = {0}; /* particles of each material */
    int used_w[64] = {0};
    for (int g = 0; g < s->ngroup; g++)
        if (s->group[g].material >= 0 && s->group[g].material < 64 && s->group[g].count > 0)
            used_p[s->group[g].material] += s->group[g].count;
    for (int w = 0; w < s->nwall; w++)
        if (s->wall[w].material >= 0 && s->wall[w].material < 64) used_w[s->wall[w].material] = 1;
    for (int a = 0; a < s->nmat && a < 64; a++) {
        if (!used_p[a]) continue;
        for (int b = a; b < s->nmat && b < 64; b++)
            if ((b == a ? used_p[a] > 1 || used_w[a] : used_p[b] || used_w[b]) &&
                !sc_interaction_of(s, a, b))
                diag(p, "/interactions",
                     "no interaction between '%s' and '%s', which can touch: add "
                     "{\"between\": [\"%s\", \"%s\"], ...}",
                     s->mat[a].name, s->mat[b].name, s->mat[a].name, s->mat[b].name);
        for (int b = 0; b < a; b++)
            if (used_w[b] && !used_p[b] && !sc_interaction_of(s, a, b))
                diag(p, "/interactions",
                     "no interaction between '%s' and '%s', which can touch: add "
                     "{\"between\": [\"%s\", \"%s\"], ...}",
                     s->mat[a].name, s->mat[b].name, s->mat[a].name, s->mat[b].name);
    }
    if (s->nmat > 64) diag(p, "/materials", "at most 64 materials");
}

/*
 * What no time step can rescue, caught before a run fails at its first step with advice to
 * reduce dt: particle masses and moments of inertia beyond the precision's range, a cohesion
 * range wider than the particles (every particle would pair with every other, and the broad
 * phase's margins overflow), and Stokes drag relaxing a particle's velocity faster than a step
 * (explicit drag is stable only for dt below ~2 tau, tau = rho d^2 / (18 mu)).
 */
static void check_extremes(sc_parse *p)
{
    pd_scenario *s = p->s;
    double big = s->double_precision ? 1e300 : 1e36, tiny = 1 / big, dall = 0;
    for (int i = 0; i < s->ngroup; i++) {
        const sc_group *g = &s->group[i];
        double dmin, dmax;
        sc_group_sizes(g, &dmin, &dmax);
        if (g->material < 0 || !(dmax > 0)) continue;
        dall = fmax(dall, dmax);
        double rho = s->mat[g->material].density, k = rho * PI / 6; /* mass = k d^3 */
        char c[SC_PATH_MAX];
        child_i(c, sizeof c, "/particles", (size_t)i);
        if (!(k * dmax * dmax * dmax * dmax * dmax < big) || !(k * dmin * dmin * dmin > tiny))
            diag(p, c,
                 "particles of %g to %g m at %g kg/m^3 have masses or moments of inertia beyond "
                 "what %s precision holds",
                 dmin, dmax, rho, s->double_precision ? "double" : "single");
        else if (s->has_fluid && s->fluid_viscosity > 0 && !s->allow_unstable_dt) {
            double tau = rho * dmin * dmin / (18 * s->fluid_viscosity);
            if (s->dt > tau)
                diag(p, "/time/dt",
                     "%g s exceeds the Stokes relaxation time %.3g s of %s's smallest particles "
                     "(%g m) in /fluid: drag would be unstable; set \"allow_unstable_dt\": true "
                     "to run anyway",
                     s->dt, tau, c, dmin);
        }
    }
    for (int i = 0; i < s->nint; i++) {
        const sc_interaction *x = &s->inter[i];
        if (x->cohesion > 0 && dall > 0 && x->cohesion_range > dall) {
            char c[SC_PATH_MAX];
            put(c, sizeof c, "/interactions/%d/cohesion_range", i);
            diag(p, c,
                 "%g m is wider than the largest particle (%g m): cohesion reaches across such "
                 "gaps only between touching effect surfaces, a fraction of a particle",
                 x->cohesion_range, dall);
        }
    }
}

/*
 * A particle whose centre starts inside a wall would never be pushed out along a sensible normal,
 * and a run refuses it (sim_state.c); validation says so first, naming the particle. The places
 * are drawn as a run draws them, for scenarios of up to SC_CHECK_PLACES particles (beyond that
 * only a run checks, so that validating a huge scenario stays cheap).
 */
#define SC_CHECK_PLACES 200000
static void check_walls_clear(sc_parse *p)
{
    pd_scenario *s = p->s;
    long total = 0;
    for (int i = 0; i < s->ngroup; i++)
        total += s->group[i].count;
    if (!s->nwall || total > SC_CHECK_PLACES) return;
    sc_particles *pa = NULL;
    pd_error err = {0};
    if (sc_particles_create(s, &pa, &err) != PD_OK) {
        diag(p, "/particles", "%s", err.msg);
        return;
    }
    for (int w = 0; w < s->nwall; w++) {
        const pd_mesh *me = s->wall[w].mesh;
        wall_tree t;
        if (!me ||
            wall_tree_build(me->verts, me->tris, me->ntris, &t, s->wall[w].name, &err) != PD_OK)
            continue;                             /* out of memory: the run will say so */
        static const double world[3] = {0, 0, 0}; /* the tree is built in world coordinates */
        long i = wall_tree_first_inside(&t, me->verts, me->tris, pa->x, pa->n, world);
        wall_tree_free(&t);
        if (i < 0) continue;
        long first = 0;
        int g = 0;
        while (g + 1 < s->ngroup && i >= first + s->group[g].count)
            first += s->group[g++].count;
        char c[SC_PATH_MAX];
        if (s->group[g].list)
            put(c, sizeof c, "/particles/%d/list/%ld/position", g, i - first);
        else
            put(c, sizeof c, "/particles/%d", g);
        const double *x = pa->x + 3 * i;
        diag(p, c,
             "particle %ld of the group starts with its centre (%g, %g, %g) m inside wall '%s': "
             "move the particles or the wall",
             i - first, x[0], x[1], x[2], s->wall[w].name);
    }
    sc_particles_destroy(pa);
}

/* A generated group must fit its region on a lattice of circumscribed spheres of the largest. */
static void check_fit(sc_parse *p)
{
    pd_scenario *s = p->s;
    for (int i = 0; i < s->ngroup; i++) {
        sc_group *g = &s->group[i];
        if (g->list || g->shape < 0 || g->count <= 0) continue;
        double cell = 2 * s->shape[g->shape].radius_ratio * g->size.max;
        double room = 1;
        for (int k = 0; k < 3; k++)
            room *= floor((g->region_max[k] - g->region_min[k]) / cell);
        if (room < (double)g->count) {
            char c[SC_PATH_MAX];
            child_i(c, sizeof c, "/particles", (size_t)i);
            diag(p, c,
                 "%ld particles of size up to %g m do not fit in the region: it holds %.0f "
                 "without initial overlaps (cell %g m)",
                 g->count, g->size.max, room, cell);
        }
    }
}

void pd_scenario_destroy(pd_scenario *s)
{
    if (!s) return;
    for (int i = 0; i < s->nshape; i++)
        pd_mesh_destroy(s->shape[i].mesh);
    for (int i = 0; i < s->ngroup; i++)
        free(s->group[i].list);
    for (int i = 0; i < s->nwall; i++)
        pd_mesh_destroy(s->wall[i].mesh);
    free(s->mat);
    free(s->inter);
    free(s->shape);
    free(s->group);
    free(s->wall);
    free(s->json);
    for (int i = 0; i < s->ninputs; i++)
        free(s->inputs[i].path);
    free(s->inputs);
    free(s);
}

int pd_scenario_parse(const char *json_text, const char *base_dir, pd_scenario **out,
                      pd_diags *diags, pd_error *err)
{
    static const char *const keys[] = {
        "name",   "precision", "seed",  "time",  "gravity", "materials",         "interactions",
        "shapes", "particles", "walls", "fluid", "output",  "allow_unstable_dt", NULL};
    *out = NULL;
    json_error_t je;
    json_t *root = json_loads(json_text, JSON_REJECT_DUPLICATES, &je);
    sc_parse p = {NULL, diags, base_dir, 0, 0};
    if (!root && !strncmp(je.text, "too big", 7)) { /* "too big [negative] integer" */
        /* An integer beyond 64 bits is still a JSON number: the schema takes 1e23 written out in
         * full where a number is meant, and refuses it by range where an integer is. Read as
         * doubles, it reaches the field that judges it. */
        root = json_loads(json_text, JSON_REJECT_DUPLICATES | JSON_DECODE_INT_AS_REAL, &je);
        p.ints_as_reals = root != NULL;
    }
    if (!root) {
        char at[64], where[SC_PATH_MAX];
        put(at, sizeof at, "line %d, column %d", je.line, je.column);
        /* a number beyond a double's range (1e999), or a string holding \u0000 (no name or path
         * can), is valid JSON syntax: name its field */
        int overflow = !strncmp(je.text, "real number overflow", 20),
            nul = !strncmp(je.text, "\\u0000", 6);
        if (overflow || nul) {
            const char *what = overflow ? "beyond the range of a double (1.8e308)"
                                        : "a string must not contain \\u0000";
            path_at(json_text, je.position > 0 ? (size_t)je.position - 1 : 0, where, sizeof where);
            diag(&p, where, "%s, at %s: %s", what, at, je.text);
            return pd_error_set(err, PD_EINVAL, "%s: %s, at %s: %s", where[0] ? where : "/", what,
                                at, je.text);
        }
        diag(&p, "", "not valid JSON at %s: %s", at, je.text);
        return pd_error_set(err, PD_EINVAL, "scenario is not valid JSON at %s: %s", at, je.text);
    }
    if (!json_is_object(root)) {
        json_decref(root);
        diag(&p, "", "a scenario is a JSON object");
        return pd_error_set(err, PD_EINVAL, "scenario: a scenario is a JSON object");
    }
    pd_scenario *s = calloc(1, sizeof *s);
    if (!s || !(s->json = strdup(json_text))) {
        free(s);
        json_decref(root);
        return pd_error_set(err, PD_ENOMEM, "scenario: out of memory");
    }
    p.s = s;
    only(&p, root, "", keys);
    parse_rest(&p, root);
    parse_time(&p, root);
    parse_materials(&p, root);
    parse_interactions(&p, root);
    parse_shapes(&p, root);
    parse_particles(&p, root);
    parse_walls(&p, root);
    json_decref(root);
    /* missing arrays without a recorded problem can only be failed allocations (an absent or
     * empty "materials" is a problem already reported at its path) */
    if (!p.failed && (!s->mat || (!s->shape && s->nshape) || (!s->group && s->ngroup))) {
        pd_scenario_destroy(s);
        return pd_error_set(err, PD_ENOMEM, "scenario: out of memory");
    }
    if (!p.failed) {
        check_pairs(&p);
        check_fit(&p);
        check_extremes(&p);
    }
    if (!p.failed) {
        check_walls_clear(&p);
    }
    if (!p.failed) {
        double rayleigh, hertz, stable;
        sc_dt_estimates(s, &rayleigh, &hertz, &stable);
        if (!isfinite(stable) || !(stable > 0))
            diag(&p, "/time/dt",
                 "the stable time step estimate is %g s: check the materials, sizes, velocities "
                 "and gravity for extreme values",
                 stable);
        else if (s->dt > stable && !s->allow_unstable_dt)
            diag(&p, "/time/dt",
                 "%g s exceeds the stable estimate %.3g s (0.3 x Rayleigh time %.3g s of the "
                 "smallest particle, 1/20 of the shortest Hertz contact time %.3g s); set "
                 "\"allow_unstable_dt\": true to run anyway",
                 s->dt, stable, rayleigh, hertz);
    }
    if (p.failed) {
        if (diags && diags->n)
            pd_error_set(err, PD_EINVAL, "%s: %s", diags->items[0].path, diags->items[0].msg);
        else
            pd_error_set(err, PD_EINVAL, "scenario is invalid");
        pd_scenario_destroy(s);
        return PD_EINVAL;
    }
    *out = s;
    return PD_OK;
}

int pd_scenario_load(const char *path, pd_scenario **out, pd_diags *diags, pd_error *err)
{
    *out = NULL;
    FILE *f = fopen(path, "rb");
    if (!f) return pd_error_set(err, PD_EIO, "%s: cannot open: %s", path, strerror(errno));
    char *buf = NULL;
    size_t len = 0, cap = 0;
    for (;;) {
        if (len + 65536 + 1 > cap) {
            cap = cap ? 2 * cap : 131072;
            if (cap > ((size_t)256 << 20)) {
                free(buf);
                fclose(f);
                return pd_error_set(err, PD_EINVAL, "%s: larger than 256 MiB", path);
            }
            char *nb = realloc(buf, cap);
            if (!nb) {
                free(buf);
                fclose(f);
                return pd_error_set(err, PD_ENOMEM, "%s: out of memory", path);
            }
            buf = nb;
        }
        size_t n = fread(buf + len, 1, 65536, f);
        len += n;
        if (n < 65536) break;
    }
    int rd_err = ferror(f);
    fclose(f);
    if (rd_err) {
        free(buf);
        return pd_error_set(err, PD_EIO, "%s: read error", path);
    }
    buf[len] = 0;
    char dir[4096];
    put(dir, sizeof dir, "%s", path);
    char *slash = strrchr(dir, '/');
    const char *base = NULL;
    if (slash) {
        *slash = 0;
        base = dir[0] ? dir : "/";
    }
    int rc = pd_scenario_parse(buf, base, out, diags, err);
    free(buf);
    if (rc == PD_OK && add_input(*out, path) != PD_OK) {
        pd_scenario_destroy(*out);
        *out = NULL;
        return pd_error_set(err, PD_ENOMEM, "%s: out of memory", path);
    }
    if (rc == PD_EINVAL && err) {
        char first[sizeof err->msg];
        put(first, sizeof first, "%s", err->msg);
        pd_error_set(err, PD_EINVAL, "%s: %s", path, first);
    }
    return rc;
}

const char *pd_scenario_name(const pd_scenario *s)
{
    return s->name;
}

const char *pd_scenario_json(const pd_scenario *s)
{
    return s->json ? s->json : "";
}
