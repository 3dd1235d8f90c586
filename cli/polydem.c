/*
 * polydem.c - the command-line front end of the engine.
 *
 *   polydem overlap A B --pose-a "x y z qw qx qy qz" --pose-b "..." [--opencl] [--single]
 *                       [--no-filter] [--device N]
 *   polydem mesh-info FILE|builtin:NAME[:TRIANGLES[:SEED]]
 *   polydem validate SCENARIO.json [--json]
 *   polydem run SCENARIO.json -o OUT.h5 [--device N] [--quiet] [--meshes]
 *   polydem devices [--json]
 *   polydem COMMAND --help
 *
 * Output is one JSON object on stdout, SI units, full double precision. Bad arguments or meshes
 * print a message on stderr and exit 2; output that cannot be written (a full disk, a closed
 * stdout) exits 1 with a message.
 */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <unistd.h>

#include "polydem.h"

#define EXIT_USAGE 2
#define EXIT_OUTPUT 1 /* stdout could not be written: as a run whose result write fails */

typedef struct command command;
struct command {
    const char *name;
    int (*run)(const command *cmd, int argc, char **argv);
    /* the synopsis after the name, a '\n' continuing it under the first argument */
    const char *args;
    const char *about; /* what it does and prints, in lines */
    int meshes;        /* takes mesh arguments: its help lists the builtin shapes */
};

static const char builtin_shapes[] =
    "builtin shapes: cube, tetrahedron, schonhardt, icosphere[:20|80|320|1280|5120],\n"
    "                rock[:TRIANGLES[:SEED]]\n";

/* cmd's synopsis after lead, its continuation lines lined up under its first argument */
static void print_synopsis(FILE *f, const char *lead, const command *cmd)
{
    int indent = (int)(strlen(lead) + strlen(cmd->name) + 1);
    fprintf(f, "%s%s ", lead, cmd->name);
    for (const char *p = cmd->args; *p; p++) {
        fputc(*p, f);
        if (*p == '\n') fprintf(f, "%*s", indent, "");
    }
    fputc('\n', f);
}

static void print_about(FILE *f, const command *cmd, int indent)
{
    for (const char *p = cmd->about; *p;) {
        size_t n = strcspn(p, "\n");
        fprintf(f, "%*s%.*s\n", indent, "", (int)n, p);
        p += n + (p[n] == '\n');
    }
}

/* `polydem COMMAND --help`: that command's usage on stdout, exit 0 */
static int print_help(const command *cmd)
{
    print_synopsis(stdout, "usage: polydem ", cmd);
    printf("\n");
    print_about(stdout, cmd, 2);
    if (cmd->meshes) printf("\n%s", builtin_shapes);
    return 0;
}

static int is_help(const char *a)
{
    return !strcmp(a, "-h") || !strcmp(a, "--help");
}

/*
 * Copies s[0..n) into out[len] as a message can show it: control characters as \t, \n, \r or
 * \xHH, so that a stray \r or terminal escape cannot redraw the line, and where quoted, backslash
 * and double quote escaped too, so that a quoted argument reads unambiguously; cut short with
 * "..." where out is too small. Returns out.
 */
static const char *shown_as(const char *s, size_t n, char *out, size_t len, int quoted)
{
    size_t k = 0;
    for (size_t i = 0; i < n; i++) {
        unsigned char c = (unsigned char)s[i];
        char e[8] = {(char)c, '\0'};
        if (quoted && (c == '\\' || c == '"'))
            snprintf(e, sizeof e, "\\%c", c);
        else if (c == '\t' || c == '\n' || c == '\r')
            snprintf(e, sizeof e, "\\%c", c == '\t' ? 't' : c == '\n' ? 'n' : 'r');
        else if (c < 0x20 || c == 0x7f)
            snprintf(e, sizeof e, "\\x%02x", c);
        size_t m = strlen(e);
        if (k + m + 4 > len) { /* room for "..." and the terminator */
            memcpy(out + k, "...", 3);
            k += 3;
            break;
        }
        memcpy(out + k, e, m);
        k += m;
    }
    out[k] = '\0';
    return out;
}

/* s[0..n) as a quoted argument (shown_as) */
static const char *shown(const char *s, size_t n, char *out, size_t len)
{
    return shown_as(s, n, out, len, 1);
}

/* fmt's two %s, a and b, are command-line text: shown() escapes them */
static int fail(const char *fmt, const char *a, const char *b)
{
    char ea[512], eb[512];
    fprintf(stderr, "polydem: ");
    fprintf(stderr, fmt, shown(a, strlen(a), ea, sizeof ea), shown(b, strlen(b), eb, sizeof eb));
    fprintf(stderr, "\n");
    return EXIT_USAGE;
}

/* Separates a pose's numbers. Whitespace of every kind: a value pasted from a file or a shell's
 * $(...) brings a trailing \n or \r\n, and strtod already skipped any before a number. */
static int is_sep(char c)
{
    return c && strchr(" \t\n\v\f\r,", c) != NULL;
}

/*
 * Parses exactly n finite numbers separated by whitespace or commas. Returns 0, or -1 with why in
 * why[len] ("number 3 of 7, \"nan\", is not finite"). A number too small to hold, like 1e-320,
 * is taken as the nearest representable one (strtod's ERANGE on underflow), not refused.
 */
static int parse_numbers(const char *s, double *out, int n, char *why, size_t len)
{
    const char *p = s;
    char tok[64];
    for (int i = 0; i < n; i++) {
        while (is_sep(*p))
            p++;
        if (!*p) {
            snprintf(why, len, "got %d", i);
            return -1;
        }
        char *end;
        errno = 0;
        out[i] = strtod(p, &end);
        if (end == p) {
            size_t k = 0;
            while (p[k] && !is_sep(p[k]))
                k++;
            snprintf(why, len, "number %d of %d, \"%s\", is not a number", i + 1, n,
                     shown(p, k, tok, sizeof tok));
            return -1;
        }
        if (!isfinite(out[i]) || (errno == ERANGE && fabs(out[i]) > 1)) {
            snprintf(why, len, "number %d of %d, \"%s\", is not finite", i + 1, n,
                     shown(p, (size_t)(end - p), tok, sizeof tok));
            return -1;
        }
        p = end;
    }
    while (is_sep(*p))
        p++;
    if (*p) {
        char *end;
        (void)strtod(p, &end);
        if (end != p)
            snprintf(why, len, "got more than %d", n);
        else
            snprintf(why, len, "\"%s\" after number %d is not a number",
                     shown(p, strlen(p), tok, sizeof tok), n);
        return -1;
    }
    return 0;
}

static int parse_pose(const char *flag, const char *s, pd_pose *pose)
{
    double v[7];
    char why[160], es[512];
    if (parse_numbers(s, v, 7, why, sizeof why) != 0) {
        fprintf(stderr, "polydem: %s: expected 7 numbers \"x y z qw qx qy qz\" (%s): \"%s\"\n",
                flag, why, shown(s, strlen(s), es, sizeof es));
        return EXIT_USAGE;
    }
    if (pd_quat_normalize(v + 3, pose->q) != PD_OK)
        return fail("%s: quaternion \"%s\" has zero length", flag, s);
    for (int k = 0; k < 3; k++)
        pose->x[k] = v[k];
    return 0;
}

/*
 * Length of the well-formed UTF-8 sequence at s (RFC 3629: no overlong forms, no surrogates,
 * nothing above U+10FFFF), or 0 where none starts there. Reads no further than a NUL.
 */
static int utf8_len(const unsigned char *s)
{
    unsigned char c = s[0], lo = 0x80, hi = 0xbf; /* the range of the second byte */
    int n;
    if (c < 0x80) return 1;
    if (c < 0xc2) return 0; /* a continuation byte, or the lead of an overlong pair */
    if (c < 0xe0) {
        n = 2;
    } else if (c < 0xf0) {
        n = 3;
        lo = c == 0xe0 ? 0xa0 : lo; /* overlong */
        hi = c == 0xed ? 0x9f : hi; /* U+D800-DFFF, the surrogates */
    } else if (c < 0xf5) {
        n = 4;
        lo = c == 0xf0 ? 0x90 : lo; /* overlong */
        hi = c == 0xf4 ? 0x8f : hi; /* above U+10FFFF */
    } else {
        return 0;
    }
    if (s[1] < lo || s[1] > hi) return 0;
    for (int k = 2; k < n; k++)
        if (s[k] < 0x80 || s[k] > 0xbf) return 0;
    return n;
}

/*
 * Writes s as a JSON string literal: quotes, backslashes and control characters escaped, and
 * each byte that is not part of well-formed UTF-8 (a file name is any bytes) written as U+FFFD,
 * since JSON text must be UTF-8 and a parser refuses the whole document over one stray byte.
 */
static void json_str(const char *s)
{
    putchar('"');
    for (const unsigned char *p = (const unsigned char *)s; *p;) {
        int n = utf8_len(p);
        if (n == 0) {
            fputs("\\ufffd", stdout);
            n = 1;
        } else if (n > 1) {
            fwrite(p, 1, (size_t)n, stdout);
        } else if (*p == '"' || *p == '\\') {
            printf("\\%c", *p);
        } else if (*p < 0x20 || *p == 0x7f) {
            printf("\\u%04x", *p);
        } else {
            putchar(*p);
        }
        p += n;
    }
    putchar('"');
}

/* Three numbers as a JSON array. Adding 0 turns -0 into 0: a cube's products of inertia and
 * other exact zeros came out as "-0", correct JSON that reads as a defect. */
static void print_row(const double *v)
{
    printf("[%.17g, %.17g, %.17g]", v[0] + 0.0, v[1] + 0.0, v[2] + 0.0);
}

static void print_vec(const char *key, const double *v, int last)
{
    printf("\"%s\": ", key);
    print_row(v);
    printf("%s", last ? "" : ", ");
}

/* A 3 x 3 matrix as a JSON array of its rows, followed by ", ". */
static void print_matrix(const char *key, const double m[3][3])
{
    printf("\"%s\": [", key);
    for (int i = 0; i < 3; i++) {
        print_row(m[i]);
        printf("%s", i < 2 ? ", " : "");
    }
    printf("], ");
}

/* Opens a mesh argument (a file, or builtin:NAME[:TRIANGLES[:SEED]]): 0, or a message and 2. */
static int open_mesh(const char *spec, pd_mesh **m)
{
    pd_error err = {0};
    if (pd_mesh_open(spec, m, &err) == PD_OK) return 0;
    char e[1024];
    /* the engine's message names the file, whose name may hold anything */
    fprintf(stderr, "polydem: %s\n", shown_as(err.msg, strlen(err.msg), e, sizeof e, 0));
    return EXIT_USAGE;
}

static int cmd_overlap(const command *cmd, int argc, char **argv)
{
    const char *files[2] = {NULL, NULL};
    int nfiles = 0, use_cl = 0, flags = 0, device = -1, posed[2] = {0, 0};
    pd_pose pose[2] = {{{0, 0, 0}, {1, 0, 0, 0}}, {{0, 0, 0}, {1, 0, 0, 0}}};
    for (int i = 2; i < argc; i++) {
        const char *a = argv[i];
        if (is_help(a)) {
            return print_help(cmd);
        } else if (!strcmp(a, "--pose-a") || !strcmp(a, "--pose-b")) {
            int b = a[7] == 'b';
            if (posed[b]++) return fail("overlap: %s given twice%s", a, "");
            if (i + 1 >= argc) return fail("%s: missing value%s", a, "");
            if (parse_pose(a, argv[++i], &pose[b])) return EXIT_USAGE;
        } else if (!strcmp(a, "--opencl")) {
            use_cl = 1;
        } else if (!strcmp(a, "--single")) {
            flags |= PD_OVERLAP_SINGLE;
        } else if (!strcmp(a, "--no-filter")) {
            flags |= PD_OVERLAP_NO_FILTER;
        } else if (!strcmp(a, "--device")) {
            char *end;
            if (device >= 0) return fail("overlap: %s given twice%s", a, "");
            if (i + 1 >= argc) return fail("%s: missing value%s", a, "");
            long d = strtol(argv[++i], &end, 10);
            if (*end || end == argv[i] || d < 0 || d > 1000)
                return fail("--device: expected a device index, got \"%s\"%s", argv[i], "");
            device = (int)d;
        } else if (a[0] == '-' && a[1]) {
            return fail("overlap: unknown option \"%s\"%s", a, "");
        } else if (nfiles < 2) {
            files[nfiles++] = a;
        } else {
            return fail("overlap: unexpected argument \"%s\" (two meshes expected)%s", a, "");
        }
    }
    if (nfiles != 2) return fail("overlap: two meshes expected, A and B%s%s", "", "");
    if (device >= 0 && !use_cl)
        return fail("overlap: --device picks the OpenCL device of --opencl; give both%s%s", "", "");

    pd_error err = {0};
    pd_mesh *m[2] = {NULL, NULL};
    pd_device *dev = NULL;
    pd_contact c;
    int rc = EXIT_USAGE;
    for (int k = 0; k < 2; k++)
        if (open_mesh(files[k], &m[k]) != 0) goto done;
    if (use_cl) {
        if (pd_device_open(device, &dev, &err) != PD_OK) {
            fprintf(stderr, "polydem: %s\n", err.msg);
            rc = err.code == PD_EINVAL ? EXIT_USAGE
                                       : 1; /* as run: no such device is a usage error */
            goto done;
        }
        if (pd_overlap_cl(dev, m[0], &pose[0], m[1], &pose[1], flags, &c, &err) != PD_OK) {
            fprintf(stderr, "polydem: %s\n", err.msg);
            rc = 1;
            goto done;
        }
    } else if (pd_overlap_host(m[0], &pose[0], m[1], &pose[1], flags, &c, &err) != PD_OK) {
        fprintf(stderr, "polydem: %s\n", err.msg);
        rc = 1;
        goto done;
    }
    if (!c.hit) {
        printf("{\"volume\": 0}\n");
    } else {
        printf("{\"volume\": %.17g, ", c.volume);
        print_vec("centroid", c.centroid, 0);
        print_vec("normal", c.normal, 0);
        printf("\"depth\": %.17g, \"places\": %d, \"places_known\": %s, ", c.depth, c.places,
               c.places_known ? "true" : "false");
        printf("\"effective_volume\": %.17g, \"effective_depth\": %.17g, ", c.effective_volume,
               c.effective_depth);
        print_vec("effective_point", c.effective_point, 1);
        printf("}\n");
    }
    rc = 0;
done:
    pd_device_close(dev);
    pd_mesh_destroy(m[0]);
    pd_mesh_destroy(m[1]);
    return rc;
}

static int cmd_mesh_info(const command *cmd, int argc, char **argv)
{
    /* no options but help: a file named -h is ./-h */
    for (int i = 2; i < argc; i++)
        if (is_help(argv[i])) return print_help(cmd);
    if (argc != 3)
        return fail("mesh-info: exactly one mesh expected (FILE or builtin:NAME)%s%s", "", "");
    pd_mesh *m = NULL;
    if (open_mesh(argv[2], &m) != 0) return EXIT_USAGE;
    pd_mass_props mp;
    pd_mesh_mass_props(m, &mp);
    double lo[3], hi[3];
    for (int k = 0; k < 3; k++)
        lo[k] = hi[k] = m->verts[k];
    for (int i = 0; i < m->nverts; i++)
        for (int k = 0; k < 3; k++) {
            double v = m->verts[3 * i + k];
            lo[k] = v < lo[k] ? v : lo[k];
            hi[k] = v > hi[k] ? v : hi[k];
        }
    printf("{\"mesh\": ");
    json_str(argv[2]);
    printf(", \"triangles\": %d, \"vertices\": %d, \"closed\": true, ", m->ntris, m->nverts);
    printf("\"volume\": %.17g, ", mp.volume);
    printf("\"equivalent_diameter\": %.17g, ", cbrt(6.0 * mp.volume / 3.14159265358979323846));
    print_vec("centroid", mp.centroid, 0);
    print_matrix("inertia", mp.inertia);
    print_vec("principal_moments", mp.principal, 0);
    print_matrix("principal_axes", mp.axes);
    print_vec("bbox_min", lo, 0);
    print_vec("bbox_max", hi, 0);
    printf("\"units\": {\"volume\": \"m^3\", \"centroid\": \"m\", \"equivalent_diameter\": \"m\", "
           "\"inertia\": \"kg m^2 at density 1 kg/m^3\"}}\n");
    pd_mesh_destroy(m);
    return 0;
}

static int cmd_validate(const command *cmd, int argc, char **argv)
{
    const char *file = NULL;
    int json = 0;
    for (int i = 2; i < argc; i++) {
        if (is_help(argv[i]))
            return print_help(cmd);
        else if (!strcmp(argv[i], "--json"))
            json = 1;
        else if (argv[i][0] == '-' && argv[i][1])
            return fail("validate: unknown option \"%s\"%s", argv[i], "");
        else if (!file)
            file = argv[i];
        else
            return fail("validate: one scenario file expected, got \"%s\" too%s", argv[i], "");
    }
    if (!file) return fail("validate: a scenario file is required%s%s", "", "");
    pd_scenario *sc = NULL;
    pd_diags d = {0, 0, NULL};
    pd_error err = {0};
    int rc = pd_scenario_load(file, &sc, &d, &err);
    if (rc != PD_OK) {
        if (json) {
            printf("{\"valid\": false, \"errors\": [");
            if (d.n == 0) {
                printf("{\"path\": \"\", \"message\": ");
                json_str(err.msg);
                printf("}");
            }
            for (int i = 0; i < d.n; i++) {
                printf("%s{\"path\": ", i ? ", " : "");
                json_str(d.items[i].path);
                printf(", \"message\": ");
                json_str(d.items[i].msg);
                printf("}");
            }
            printf("]}\n");
        } else if (d.n == 0) {
            fprintf(stderr, "polydem: %s\n", err.msg);
        } else {
            for (int i = 0; i < d.n; i++)
                fprintf(stderr, "%s: %s: %s\n", file, d.items[i].path, d.items[i].msg);
            fprintf(stderr, "%s: %d error%s\n", file, d.n, d.n == 1 ? "" : "s");
        }
        pd_diags_free(&d);
        return 1;
    }
    pd_scenario_summary m;
    pd_scenario_summarize(sc, &m);
    if (json) {
        printf("{\"valid\": true, \"particles\": %ld, \"shapes\": %d, \"materials\": %d, "
               "\"walls\": %d, \"dt_s\": %.17g, \"duration_s\": %.17g, \"steps\": %ld, "
               "\"dt_stable_s\": %.17g, \"dt_rayleigh_s\": %.17g, \"hertz_contact_time_s\": ",
               m.particles, m.shapes, m.materials, m.walls, m.dt, m.duration, m.steps, m.dt_stable,
               m.dt_rayleigh);
        /* null when no pair has a Hertz contact (as the daemon's dt_hertz) */
        if (isfinite(m.dt_hertz))
            printf("%.17g", m.dt_hertz);
        else
            printf("null");
        printf(", \"memory_bytes\": %.0f, \"contact_resolution_m\": %.17g, \"frames\": %ld, "
               "\"mesh_view_bytes\": %.0f, \"mesh_view_default\": %s}\n",
               m.memory_bytes, m.contact_resolution, m.frames, m.mesh_view_bytes,
               m.mesh_view_default ? "true" : "false");
    } else {
        printf("%s: valid\n", file);
        printf("  particles: %ld (%d shapes, %d materials, %d walls)\n", m.particles, m.shapes,
               m.materials, m.walls);
        printf("  time: dt %g s, duration %g s, %ld steps\n", m.dt, m.duration, m.steps);
        printf("  stable dt estimate: %.3g s (0.3 x Rayleigh time %.3g s", m.dt_stable,
               m.dt_rayleigh);
        if (isfinite(m.dt_hertz))
            printf("; Hertz contact time %.3g s / 20)\n", m.dt_hertz);
        else
            printf("; no contact speed)\n");
        if (m.memory_bytes < 1048576)
            printf("  memory estimate: %.1f KiB\n", m.memory_bytes / 1024.0);
        else
            printf("  memory estimate: %.1f MiB\n", m.memory_bytes / 1048576.0);
        printf("  result: %ld frames", m.frames);
        if (m.mesh_view_bytes > 0)
            printf("; the particles' surfaces for ParaView add %.1f MiB%s",
                   m.mesh_view_bytes / 1048576.0,
                   m.mesh_view_default ? "" : " (written only with run --meshes)");
        printf("\n");
        if (m.contact_resolution > 0)
            printf("  polyhedral contacts resolved to about %.2g m (64 ulps of the largest "
                   "coordinate in play)\n",
                   m.contact_resolution);
        if (m.contact_resolution > 1e-8) /* single precision, or walls a million metres long */
            printf("  warning: contact depths below %.2g m are not resolved, and particles "
                   "resting on walls or on each other can gain energy: use \"precision\": "
                   "\"double\" (docs/SCENARIO.md)\n",
                   m.contact_resolution);
    }
    pd_scenario_destroy(sc);
    return 0;
}

/* ---- run ---- */

static volatile int run_cancel;

static void on_interrupt(int sig)
{
    (void)sig;
    run_cancel = 1;
}

typedef struct run_view {
    int tty;
} run_view;

static void fmt_seconds(double s, char *out, size_t len)
{
    if (s < 0)
        snprintf(out, len, "?");
    else if (s < 120)
        snprintf(out, len, "%.0f s", s);
    else if (s < 7200)
        snprintf(out, len, "%.0f min", s / 60);
    else
        snprintf(out, len, "%.1f h", s / 3600);
}

/* A progress bar on stderr when it is a terminal. */
static int run_progress(const pd_progress *p, void *user)
{
    run_view *v = user;
    if (!v->tty) return 0;
    int width = 24, fill = (int)(p->fraction * width + 0.5);
    char bar[32], eta[32];
    for (int i = 0; i < width; i++)
        bar[i] = i < fill ? '#' : '.';
    bar[width] = 0;
    fmt_seconds(p->eta_seconds, eta, sizeof eta);
    fprintf(stderr,
            "\r[%s] %3.0f%%  t %.4g/%.4g s  %.0f steps/s  ETA %s  %ld contacts  KE %.3g J   ", bar,
            100 * p->fraction, p->sim_time, p->sim_duration, p->steps_per_second, eta, p->contacts,
            p->kinetic_energy);
    fflush(stderr);
    return 0;
}

static void print_diags(const char *file, const pd_diags *d, const pd_error *err)
{
    if (d->n == 0) fprintf(stderr, "polydem: %s\n", err->msg);
    for (int i = 0; i < d->n; i++)
        fprintf(stderr, "%s: %s: %s\n", file, d->items[i].path, d->items[i].msg);
    if (d->n) fprintf(stderr, "%s: %d error%s\n", file, d->n, d->n == 1 ? "" : "s");
}

static int cmd_run(const command *cmd, int argc, char **argv)
{
    const char *file = NULL, *out = NULL;
    int device = -1, quiet = 0, meshes = 0;
    for (int i = 2; i < argc; i++) {
        if (is_help(argv[i])) {
            return print_help(cmd);
        } else if (!strcmp(argv[i], "-o") || !strcmp(argv[i], "--output")) {
            if (out)
                return fail("run: %s given twice (-o and --output are one option)%s", argv[i], "");
            if (++i >= argc) return fail("run: %s needs a file name%s", argv[i - 1], "");
            out = argv[i];
        } else if (!strcmp(argv[i], "--device")) {
            char *end;
            if (device >= 0) return fail("run: --device given twice%s%s", "", "");
            if (++i >= argc) return fail("run: --device needs a number%s%s", "", "");
            long d = strtol(argv[i], &end, 10);
            if (*end || end == argv[i] || d < 0 || d > 1000)
                return fail("run: --device: expected a device number, got \"%s\"%s", argv[i], "");
            device = (int)d;
        } else if (!strcmp(argv[i], "--quiet")) {
            quiet = 1;
        } else if (!strcmp(argv[i], "--meshes") || !strcmp(argv[i], "--no-meshes")) {
            int want = argv[i][2] == 'm' ? 1 : -1;
            if (meshes == -want) /* the later one used to win, unsaid */
                return fail("run: --meshes and --no-meshes contradict each other%s%s", "", "");
            meshes = want;
        } else if (argv[i][0] == '-' && argv[i][1]) {
            return fail("run: unknown option \"%s\"%s", argv[i], "");
        } else if (!file) {
            file = argv[i];
        } else {
            return fail("run: one scenario file expected, got \"%s\" too%s", argv[i], "");
        }
    }
    if (!file) return fail("run: a scenario file is required%s%s", "", "");
    if (!out) return fail("run: -o OUT.h5 is required (the result file)%s%s", "", "");
    pd_scenario *sc = NULL;
    pd_diags d = {0, 0, NULL};
    pd_error err = {0};
    if (pd_scenario_load(file, &sc, &d, &err) != PD_OK) {
        print_diags(file, &d, &err);
        pd_diags_free(&d);
        return 1;
    }
    pd_device *dev = NULL;
    if (pd_device_open(device, &dev, &err) != PD_OK) {
        fprintf(stderr, "polydem: %s\n", err.msg);
        pd_scenario_destroy(sc);
        return err.code == PD_EINVAL ? EXIT_USAGE : 1;
    }
    if (meshes == 0 && !quiet) {
        pd_scenario_summary m;
        pd_scenario_summarize(sc, &m);
        if (!m.mesh_view_default && m.mesh_view_bytes > PD_MESH_VIEW_AUTO_BYTES)
            fprintf(stderr,
                    "polydem: note: the particles' surfaces for ParaView are not written (they "
                    "would add %.0f MiB over %ld frames; --meshes writes them); ParaView shows "
                    "points\n",
                    m.mesh_view_bytes / 1048576.0, m.frames);
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_interrupt;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    run_view view = {!quiet && isatty(2)};
    pd_run_options opt = {0};
    opt.output_path = out;
    opt.progress = run_progress;
    opt.user = &view;
    opt.progress_interval = 0.25;
    opt.cancel = &run_cancel;
    opt.shape_meshes = meshes;
    pd_progress fin;
    int rc = pd_run(dev, sc, &opt, &fin, &err);
    if (view.tty) fputc('\n', stderr);
    if (rc == PD_OK) {
        if (!quiet)
            printf("%s: %lld steps (%.4g s simulated) of %ld particles on %s in %.3g s "
                   "(%.3g steps/s); %lld frames; at the end %ld contacts, kinetic energy %.6g "
                   "J\n",
                   out, fin.steps_total, fin.sim_duration, fin.particles, pd_device_name(dev),
                   fin.wall_seconds,
                   fin.wall_seconds > 0 ? (double)fin.steps_total / fin.wall_seconds : 0,
                   fin.frames, fin.contacts, fin.kinetic_energy);
    } else {
        fprintf(stderr, "polydem: %s: %s\n", file, err.msg);
        if (fin.result_kept)
            fprintf(stderr,
                    "polydem: %s: kept the %lld frame%s written before the stop (the run reached "
                    "t = %.6g s of %.6g s); its root attribute status says \"%s\"\n",
                    out, fin.frames, fin.frames == 1 ? "" : "s", fin.sim_time, fin.sim_duration,
                    pd_run_status(rc));
    }
    pd_device_close(dev);
    pd_scenario_destroy(sc);
    if (rc == PD_ECANCELLED) return 130;
    return rc == PD_OK ? 0 : 1;
}

static int cmd_devices(const command *cmd, int argc, char **argv)
{
    int json = 0;
    for (int i = 2; i < argc; i++) {
        if (is_help(argv[i]))
            return print_help(cmd);
        else if (!strcmp(argv[i], "--json"))
            json = 1;
        else
            return fail("devices: unexpected argument \"%s\" (only --json)%s", argv[i], "");
    }
    pd_device_info info[64];
    int n = 0;
    pd_error err = {0};
    if (pd_device_list(info, 64, &n, &err) != PD_OK) {
        fprintf(stderr, "polydem: %s\n", err.msg);
        return 1;
    }
    if (n > 64) n = 64;
    if (json) printf("[");
    for (int i = 0; i < n; i++) {
        const pd_device_info *d = &info[i];
        if (json) {
            /* the names are the driver's: escaped as any other string */
            printf("%s{\"index\": %d, \"name\": ", i ? ", " : "", d->index);
            json_str(d->name);
            printf(", \"platform\": ");
            json_str(d->platform);
            printf(", \"type\": ");
            json_str(d->type);
            printf(", \"compute_units\": %d, \"global_mem_bytes\": %.0f, \"fp64\": %s, "
                   "\"fp32_rounded\": %s}",
                   d->compute_units, d->global_mem_bytes, d->fp64 ? "true" : "false",
                   d->fp32_rounded ? "true" : "false");
        } else {
            printf("%d: %s [%s, %s], %d compute units, %.1f GiB, %s%s\n", d->index, d->name,
                   d->platform, d->type, d->compute_units, d->global_mem_bytes / 1073741824.0,
                   d->fp64 ? "double and single precision" : "single precision only",
                   d->fp32_rounded ? ""
                                   : " (single precision's / and sqrt not correctly rounded: "
                                     "its overlaps may differ from the host's in the last bits)");
        }
    }
    if (json) printf("]\n");
    return 0;
}

static const command commands[] = {
    {"overlap", cmd_overlap,
     "A B [--pose-a \"x y z qw qx qy qz\"] [--pose-b \"...\"]\n"
     "[--opencl] [--single] [--no-filter] [--device N]",
     "exact overlap of two closed meshes (STL, OBJ or builtin:NAME); prints\n"
     "{\"volume\": m^3, \"centroid\": [m], \"normal\": [unit, A into B], \"depth\": m,\n"
     " \"places\": n, \"places_known\": bool, \"effective_volume\": m^3, \"effective_depth\": m,\n"
     " \"effective_point\": [m]}\n"
     "or {\"volume\": 0} when they do not overlap. Poses default to \"0 0 0 1 0 0 0\".\n"
     "places: the overlap's separate parts; effective_*: what \"contact_places\":\n"
     "\"separate\" gives the force law, and where its force acts (docs/SCENARIO.md).",
     1},
    {"mesh-info", cmd_mesh_info, "FILE|builtin:NAME[:TRIANGLES[:SEED]]",
     "triangles, vertices, volume, centroid, inertia and principal moments\n"
     "(inertia per unit density, m^5 = kg m^2 at 1 kg/m^3)",
     1},
    {"validate", cmd_validate, "SCENARIO.json [--json]",
     "checks a scenario: every error with its JSON path (exit 1), or the particle count,\n"
     "memory estimate and stable time step",
     0},
    {"run", cmd_run, "SCENARIO.json -o OUT.h5 [--device N] [--quiet] [--meshes | --no-meshes]",
     "runs a scenario on an OpenCL device (default: the first GPU, else the first\n"
     "device); writes the HDF5 result and OUT.h5.xmf for ParaView, with every\n"
     "particle's surface per frame when there are polyhedra and that adds at most\n"
     "256 MiB (--meshes: always, --no-meshes: never); a progress bar on a terminal;\n"
     "Ctrl-C cancels, keeping the frames so far (root attribute status = \"cancelled\")",
     0},
    {"devices", cmd_devices, "[--json]", "the OpenCL devices; N is what --device N takes", 0},
};
#define NCOMMANDS (int)(sizeof commands / sizeof commands[0])

/* Every command's synopsis and what it does: on stdout for --help, with an error on stderr */
static void print_usage(FILE *f)
{
    fputs("usage: polydem <command> [options]\n\ncommands:\n", f);
    for (int k = 0; k < NCOMMANDS; k++) {
        print_synopsis(f, "  ", &commands[k]);
        print_about(f, &commands[k], 6);
    }
    fprintf(f, "  <command> --help\n      that command's usage\n\n%s", builtin_shapes);
}

/*
 * Holds descriptors 0-2 open. Started with stdout closed (>&-), the first file opened after (a
 * mesh, the result file, one of the OpenCL driver's) would become descriptor 1 and take what is
 * printed for stdout. /dev/null opened read-only keeps the place: writes to it fail, and are
 * reported as any failed write is (finish_stdout).
 */
static void hold_std_fds(void)
{
    for (int fd = 0; fd < 3; fd++)
        if (fcntl(fd, F_GETFD) == -1 && errno == EBADF) {
            int got = open("/dev/null", O_RDONLY); /* the lowest free descriptor: fd */
            if (got < 0) return;
            if (got != fd) { /* cannot happen: the lower ones are open */
                close(got);
                return;
            }
        }
}

/*
 * Whether what was printed reached stdout: a full disk or a closed stdout must not pass for
 * success, as scripts take the JSON from there. fclose as well as fflush, since a deferred write
 * error (NFS) comes back only from close. Returns rc, or EXIT_OUTPUT after a message where rc
 * was 0.
 */
static int finish_stdout(int rc)
{
    errno = 0;
    int failed = fflush(stdout) != 0 || ferror(stdout), e = errno;
    if (fclose(stdout) != 0 && !failed) {
        failed = 1;
        e = errno;
    }
    if (!failed) return rc;
    fprintf(stderr, "polydem: writing the output failed%s%s\n", e ? ": " : "",
            e ? strerror(e) : "");
    return rc ? rc : EXIT_OUTPUT;
}

static int dispatch(int argc, char **argv)
{
    if (argc < 2) {
        print_usage(stderr);
        return EXIT_USAGE;
    }
    if (!strcmp(argv[1], "-h") || !strcmp(argv[1], "--help") || !strcmp(argv[1], "help")) {
        print_usage(stdout);
        return 0;
    }
    for (int k = 0; k < NCOMMANDS; k++)
        if (!strcmp(argv[1], commands[k].name)) return commands[k].run(&commands[k], argc, argv);
    char e[512];
    fprintf(stderr, "polydem: unknown command \"%s\"\n\n",
            shown(argv[1], strlen(argv[1]), e, sizeof e));
    print_usage(stderr);
    return EXIT_USAGE;
}

int main(int argc, char **argv)
{
    hold_std_fds();
    int rc = finish_stdout(dispatch(argc, argv));
    if (argc >= 2 && !strcmp(argv[1], "run") && pd_results_unclosed()) {
        /* a full disk: HDF5's exit-time clean-up would crash */
        fflush(NULL);
        _exit(rc);
    }
    return rc;
}
