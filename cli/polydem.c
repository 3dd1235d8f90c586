/*
 * polydem.c - the command-line front end of the engine.
 *
 *   polydem overlap A B --pose-a "x y z qw qx qy qz" --pose-b "..." [--opencl] [--single]
 *                       [--no-filter] [--device N]
 *   polydem mesh-info FILE|builtin:NAME[:TRIANGLES[:SEED]]
 *   polydem validate SCENARIO.json [--json]
 *   polydem run SCENARIO.json -o OUT.h5 [--device N] [--quiet] [--meshes]
 *   polydem devices [--json]
 *
 * Output is one JSON object on stdout, SI units, full double precision. Bad arguments or meshes
 * print a message on stderr and exit 2.
 */
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <unistd.h>

#include "polydem.h"

#define EXIT_USAGE 2

static const char *usage_text =
    "usage: polydem <command> [options]\n"
    "\n"
    "commands:\n"
    "  overlap A B [--pose-a \"x y z qw qx qy qz\"] [--pose-b \"...\"] [--opencl] [--single]\n"
    "              [--no-filter] [--device N]\n"
    "      exact overlap of two closed meshes (STL, OBJ or builtin:NAME); prints\n"
    "      {\"volume\": m^3, \"centroid\": [m], \"normal\": [unit, A into B], \"depth\": m,\n"
    "       \"places\": n, \"effective_volume\": m^3, \"effective_depth\": m,\n"
    "       \"effective_point\": [m]}\n"
    "      or {\"volume\": 0} when they do not overlap. Poses default to \"0 0 0 1 0 0 0\".\n"
    "      places: the overlap's separate parts; effective_*: what \"contact_places\":\n"
    "      \"separate\" gives the force law, and where its force acts (docs/SCENARIO.md).\n"
    "  mesh-info FILE|builtin:NAME[:TRIANGLES[:SEED]]\n"
    "      triangles, vertices, volume, centroid, inertia and principal moments\n"
    "      (inertia per unit density, m^5 = kg m^2 at 1 kg/m^3)\n"
    "\n"
    "  validate SCENARIO.json [--json]\n"
    "      checks a scenario: every error with its JSON path (exit 1), or the particle count,\n"
    "      memory estimate and stable time step\n"
    "  run SCENARIO.json -o OUT.h5 [--device N] [--quiet] [--meshes | --no-meshes]\n"
    "      runs a scenario on an OpenCL device (default: the first GPU, else the first\n"
    "      device); writes the HDF5 result and OUT.h5.xmf for ParaView, with every\n"
    "      particle's surface per frame when there are polyhedra and that adds at most\n"
    "      256 MiB (--meshes: always, --no-meshes: never); a progress bar on a terminal;\n"
    "      Ctrl-C cancels, keeping the frames so far (root attribute status = \"cancelled\")\n"
    "  devices [--json]\n"
    "      the OpenCL devices; N is what --device N takes\n"
    "\n"
    "builtin shapes: cube, tetrahedron, schonhardt, icosphere[:20|80|320|1280|5120],\n"
    "                rock[:TRIANGLES[:SEED]]\n";

static int fail(const char *fmt, const char *a, const char *b)
{
    fprintf(stderr, "polydem: ");
    fprintf(stderr, fmt, a, b);
    fprintf(stderr, "\n");
    return EXIT_USAGE;
}

/*
 * Parses exactly n finite numbers separated by blanks or commas. Returns 0, or -1 with why in
 * why[len] ("number 3 of 7, \"nan\", is not finite"). A number too small to hold, like 1e-320,
 * is taken as the nearest representable one (strtod's ERANGE on underflow), not refused.
 */
static int parse_numbers(const char *s, double *out, int n, char *why, size_t len)
{
    const char *p = s;
    for (int i = 0; i < n; i++) {
        while (*p == ' ' || *p == '\t' || *p == ',')
            p++;
        if (!*p) {
            snprintf(why, len, "got %d", i);
            return -1;
        }
        char *end;
        errno = 0;
        out[i] = strtod(p, &end);
        if (end == p) {
            snprintf(why, len, "number %d of %d, \"%.*s\", is not a number", i + 1, n,
                     (int)strcspn(p, " \t,"), p);
            return -1;
        }
        if (!isfinite(out[i]) || (errno == ERANGE && fabs(out[i]) > 1)) {
            snprintf(why, len, "number %d of %d, \"%.*s\", is not finite", i + 1, n, (int)(end - p),
                     p);
            return -1;
        }
        p = end;
    }
    while (*p == ' ' || *p == '\t' || *p == ',')
        p++;
    if (*p) {
        char *end;
        (void)strtod(p, &end);
        if (end != p)
            snprintf(why, len, "got more than %d", n);
        else
            snprintf(why, len, "\"%s\" after number %d is not a number", p, n);
        return -1;
    }
    return 0;
}

static int parse_pose(const char *flag, const char *s, pd_pose *pose)
{
    double v[7];
    char why[160];
    if (parse_numbers(s, v, 7, why, sizeof why) != 0) {
        fprintf(stderr, "polydem: %s: expected 7 numbers \"x y z qw qx qy qz\" (%s): \"%s\"\n",
                flag, why, s);
        return EXIT_USAGE;
    }
    if (pd_quat_normalize(v + 3, pose->q) != PD_OK)
        return fail("%s: quaternion \"%s\" has zero length", flag, s);
    for (int k = 0; k < 3; k++)
        pose->x[k] = v[k];
    return 0;
}

/* Writes s as a JSON string literal (quotes and control characters escaped). */
static void json_str(const char *s)
{
    putchar('"');
    for (; *s; s++) {
        if (*s == '"' || *s == '\\')
            printf("\\%c", *s);
        else if ((unsigned char)*s < 0x20)
            printf("\\u%04x", *s);
        else
            putchar(*s);
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

static int cmd_overlap(int argc, char **argv)
{
    const char *files[2] = {NULL, NULL};
    int nfiles = 0, use_cl = 0, flags = 0, device = -1;
    pd_pose pose[2] = {{{0, 0, 0}, {1, 0, 0, 0}}, {{0, 0, 0}, {1, 0, 0, 0}}};
    for (int i = 2; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--pose-a") || !strcmp(a, "--pose-b")) {
            if (i + 1 >= argc) return fail("%s: missing value%s", a, "");
            if (parse_pose(a, argv[++i], &pose[a[7] == 'b'])) return EXIT_USAGE;
        } else if (!strcmp(a, "--opencl")) {
            use_cl = 1;
        } else if (!strcmp(a, "--single")) {
            flags |= PD_OVERLAP_SINGLE;
        } else if (!strcmp(a, "--no-filter")) {
            flags |= PD_OVERLAP_NO_FILTER;
        } else if (!strcmp(a, "--device")) {
            char *end;
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
        if (pd_mesh_open(files[k], &m[k], &err) != PD_OK) {
            fprintf(stderr, "polydem: %s\n", err.msg);
            goto done;
        }
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
        printf("\"depth\": %.17g, \"places\": %d, ", c.depth, c.places);
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

static int cmd_mesh_info(int argc, char **argv)
{
    if (argc != 3)
        return fail("mesh-info: exactly one mesh expected (FILE or builtin:NAME)%s%s", "", "");
    pd_error err = {0};
    pd_mesh *m = NULL;
    if (pd_mesh_open(argv[2], &m, &err) != PD_OK) {
        fprintf(stderr, "polydem: %s\n", err.msg);
        return EXIT_USAGE;
    }
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

static int cmd_validate(int argc, char **argv)
{
    const char *file = NULL;
    int json = 0;
    for (int i = 2; i < argc; i++) {
        if (!strcmp(argv[i], "--json"))
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

static int cmd_run(int argc, char **argv)
{
    const char *file = NULL, *out = NULL;
    int device = -1, quiet = 0, meshes = 0;
    for (int i = 2; i < argc; i++) {
        if (!strcmp(argv[i], "-o") || !strcmp(argv[i], "--output")) {
            if (++i >= argc) return fail("run: %s needs a file name%s", argv[i - 1], "");
            out = argv[i];
        } else if (!strcmp(argv[i], "--device")) {
            char *end;
            if (++i >= argc) return fail("run: --device needs a number%s%s", "", "");
            long d = strtol(argv[i], &end, 10);
            if (*end || end == argv[i] || d < 0 || d > 1000)
                return fail("run: --device: expected a device number, got \"%s\"%s", argv[i], "");
            device = (int)d;
        } else if (!strcmp(argv[i], "--quiet")) {
            quiet = 1;
        } else if (!strcmp(argv[i], "--meshes")) {
            meshes = 1;
        } else if (!strcmp(argv[i], "--no-meshes")) {
            meshes = -1;
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

static int cmd_devices(int argc, char **argv)
{
    int json = argc == 3 && !strcmp(argv[2], "--json");
    if (argc > 3 || (argc == 3 && !json))
        return fail("devices: unexpected argument \"%s\" (only --json)%s", argv[argc - 1], "");
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
        if (json)
            printf("%s{\"index\": %d, \"name\": \"%s\", \"platform\": \"%s\", \"type\": \"%s\", "
                   "\"compute_units\": %d, \"global_mem_bytes\": %.0f, \"fp64\": %s, "
                   "\"fp32_rounded\": %s}",
                   i ? ", " : "", d->index, d->name, d->platform, d->type, d->compute_units,
                   d->global_mem_bytes, d->fp64 ? "true" : "false",
                   d->fp32_rounded ? "true" : "false");
        else
            printf("%d: %s [%s, %s], %d compute units, %.1f GiB, %s%s\n", d->index, d->name,
                   d->platform, d->type, d->compute_units, d->global_mem_bytes / 1073741824.0,
                   d->fp64 ? "double and single precision" : "single precision only",
                   d->fp32_rounded ? ""
                                   : " (single precision's / and sqrt not correctly rounded: "
                                     "its overlaps may differ from the host's in the last bits)");
    }
    if (json) printf("]\n");
    return 0;
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        fputs(usage_text, stderr);
        return EXIT_USAGE;
    }
    if (!strcmp(argv[1], "-h") || !strcmp(argv[1], "--help") || !strcmp(argv[1], "help")) {
        fputs(usage_text, stdout);
        return 0;
    }
    if (!strcmp(argv[1], "overlap")) return cmd_overlap(argc, argv);
    if (!strcmp(argv[1], "mesh-info")) return cmd_mesh_info(argc, argv);
    if (!strcmp(argv[1], "devices")) return cmd_devices(argc, argv);
    if (!strcmp(argv[1], "validate")) return cmd_validate(argc, argv);
    if (!strcmp(argv[1], "run")) {
        int rc = cmd_run(argc, argv);
        if (pd_results_unclosed()) { /* a full disk: HDF5's exit-time clean-up would crash */
            fflush(NULL);
            _exit(rc);
        }
        return rc;
    }
    fprintf(stderr, "polydem: unknown command \"%s\"\n\n%s", argv[1], usage_text);
    return EXIT_USAGE;
}
