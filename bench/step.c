/*
 * bench/step.c - the whole time step on a device: particle-steps per second, time per
 * contact-step and time per stage, for a gravity packing of Schonhardt particles (thesis Table
 * A.3 materials and time step) and for a bed of settled analytic spheres.
 *
 * Each case starts as a lattice just above a floor, falls and piles for --settle steps, then is
 * timed for --steps steps twice: once free-running (the figures that count), once with a device
 * barrier after every stage (the per-stage split; barriers add their own cost). Memory is what
 * the run allocated on the device (buffers), per particle.
 *
 * --wall-grid G replaces the 12-triangle box floor by the same slab meshed as G x G grids on
 * every face (12 G^2 triangles), to show what a finely meshed wall costs (its BVH, section 5.6).
 *
 * --traversal also times the broad phase's traversal alone on the settled state, twice: the
 * pipeline's per-particle depth-first query (broad_count) and a batched breadth-first traversal
 * with stream compaction (bfs_count/bfs_write in kernels/broad_phase.cl; the host reads each
 * level's frontier size), and checks that both find the same number of candidate pairs.
 *
 * --no-skin builds the pair list every step (the engine's default reuses it until a particle has
 * moved half the Verlet skin, a tenth of the smallest particle). --places presses each place of
 * a contact on its own ("contact_places": "separate", docs/SCENARIO.md).
 *
 * usage: build/bench/step [--quick] [--sizes N,N,...] [--spheres N] [--settle S] [--steps S]
 *                         [--device N] [--single] [--wall-grid G] [--traversal] [--no-skin]
 *                         [--places]
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "../tests/grid_box.h"
#include "sim.h"

static int traversal;      /* also time DFS against BFS traversal */
static int no_skin;        /* build the pair list every step (no Verlet skin) */
static int places;         /* "contact_places": "separate" */
static int no_moments;     /* "contact_moments": false (the thesis's point contact) */
static int wall_grid;      /* 0: a box floor */
static char wall_path[64]; /* the meshed floor, when wall_grid */

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* A flat-ish lattice (the thesis's 169 x 169 x 35 aspect) of n particles of `shape`. */
static void scenario(char *json, size_t len, long n, int spheres, int dbl)
{
    double size = 0.02,
           cell = spheres ? size * 1.001 : 1.9 * size; /* Schonhardt: circumradius 0.945 d */
    long nz = 1;
    while (nz * nz * nz * 23 < n) /* (169/35)^2 = 23 */
        nz++;
    long nxy = 1;
    while (nxy * nxy * nz < n)
        nxy++;
    double w = nxy * cell * 1.0001, h = nz * cell * 1.0001;
    char floor[200];
    if (wall_grid) {
        /* the box floor's slab, [-1, w + 1]^2 x [-0.1, 0] */
        double c[3] = {0.5 * w, 0.5 * w, -0.05}, hh[3] = {0.5 * w + 1, 0.5 * w + 1, 0.05};
        snprintf(wall_path, sizeof wall_path, "/tmp/polydem-bench-floor-%d.obj", (int)getpid());
        if (grid_box_obj(wall_path, c, hh, wall_grid))
            fprintf(stderr, "bench: cannot write %s\n", wall_path);
        snprintf(floor, sizeof floor, "\"mesh\": \"%s\"", wall_path);
    } else {
        snprintf(floor, sizeof floor,
                 "\"box\": {\"min\": [-1, -1, -0.1], \"max\": [%.9g, %.9g, 0]}", w + 1, w + 1);
    }
    snprintf(json, len,
             "{\"name\": \"bench\", \"precision\": \"%s\", \"allow_unstable_dt\": true,"
             " \"time\": {\"dt\": 1e-5, \"duration\": 1, \"output_interval\": 1},"
             " \"gravity\": [0, 0, -9.81],"
             " \"materials\": {\"p\": {\"density\": 2600, \"youngs_modulus\": 2e9, "
             "\"poisson_ratio\": 0.25, \"shear_modulus\": 1e9},"
             " \"w\": {\"density\": 7800, \"youngs_modulus\": 1e9, \"poisson_ratio\": 0.25, "
             "\"shear_modulus\": 1e9}},"
             " \"interactions\": [{\"between\": [\"p\", \"p\"], \"friction\": 0.39, \"damping\": "
             "0.453619, \"contact_places\": \"%s\", \"contact_moments\": %s}, {\"between\": "
             "[\"p\", \"w\"], \"friction\": 0.35, \"damping\": 0.382097, \"contact_places\": "
             "\"%s\", \"contact_moments\": %s}],"
             " \"shapes\": {\"s\": %s},"
             " \"particles\": [{\"shape\": \"s\", \"material\": \"p\", \"count\": %ld, \"size\": "
             "%g, \"region\": {\"min\": [0, 0, 0.001], \"max\": [%.9g, %.9g, %.9g]}, "
             "\"orientation\": \"random\", \"velocity\": [0, 0, -1]}],"
             " \"walls\": [{\"name\": \"floor\", \"material\": \"w\", %s}]}",
             dbl ? "double" : "single", places ? "separate" : "merged",
             no_moments ? "false" : "true", places ? "separate" : "merged",
             no_moments ? "false" : "true",
             spheres ? "{\"sphere\": {}}" : "{\"builtin\": \"schonhardt\"}", n, size, w, w,
             0.001 + h, floor);
}

static long certified; /* pairs the last step skipped as certified apart (info -2) */
static long waiting;   /* pairs apart, too close for a certificate, not searched (info <= -3) */

static long count_contacts(sim *m)
{
    long c = 0;
    size_t np = (size_t)m->npairs;
    double *info = malloc(sizeof(double) * (np + 1));
    pd_error err = {0};
    certified = waiting = 0;
    if (info && sim_read_info(m, np, info, &err) == PD_OK)
        for (size_t i = 0; i < np; i++) {
            c += info[i] >= 0; /* depth / size when touching, -1 when not, -2 certified apart */
            certified += info[i] == -2;
            waiting += info[i] <= -3;
        }
    free(info);
    return c;
}

/*
 * What a stats row costs on this state: its sums on the device (sim_stats.c: kinetic energy,
 * contacts, wall forces), against reading back the state and pairs they are sums of, which rows
 * did until 2026-12-01 (before their host loops). The fastest of 5 rounds of 10 rows each.
 */
static void stats_row_time(sim *m)
{
    size_t n = (size_t)m->n, np = (size_t)m->npairs;
    double *buf = malloc(sizeof(double) * (10 * n + 4 * np + 4)),
           *wf = calloc(3 * (size_t)m->nwall + 3, sizeof(double));
    pd_error err = {0};
    double dev_t = 1e30, read_t = 1e30, ke = 0, ratio = 0;
    long contacts = 0;
    int worst, rc = buf && wf ? PD_OK : PD_ENOMEM;
    for (int round = 0; round < 5 && rc == PD_OK; round++) {
        clFinish(m->dev->queue);
        double t0 = now();
        for (int r = 0; r < 10 && rc == PD_OK; r++) {
            rc = sim_stats_energy(m, &ke, &worst, &err);
            if (rc == PD_OK) rc = sim_stats_contacts(m, &contacts, &ratio, wf, &err);
        }
        double t1 = now();
        for (int r = 0; r < 10 && rc == PD_OK; r++) {
            rc = sim_read(m, m->q, 0, 4 * n, buf, &err);
            if (rc == PD_OK) rc = sim_read(m, m->v, 0, 3 * n, buf + 4 * n, &err);
            if (rc == PD_OK) rc = sim_read(m, m->L, 0, 3 * n, buf + 7 * n, &err);
            if (rc == PD_OK && np) rc = sim_read(m, m->force, 0, 3 * np, buf + 10 * n, &err);
            if (rc == PD_OK && np) rc = sim_read_info(m, np, buf + 10 * n + 3 * np, &err);
            if (rc == PD_OK && np &&
                clEnqueueReadBuffer(m->dev->queue, m->pairs.keys, CL_TRUE, 0, 8 * np, buf, 0, NULL,
                                    NULL) != CL_SUCCESS)
                rc = PD_ECL;
        }
        double t2 = now();
        dev_t = t1 - t0 < dev_t ? t1 - t0 : dev_t;
        read_t = t2 - t1 < read_t ? t2 - t1 : read_t;
    }
    if (rc == PD_OK)
        printf(
            "  a stats row: %.3g ms summed on the device (%.6g J, %ld contacts); reading back the "
            "state and pairs they sum: %.3g ms\n",
            100 * dev_t, ke, contacts, 100 * read_t);
    else
        fprintf(stderr, "bench: stats row: %s\n", err.msg[0] ? err.msg : "failed");
    free(buf);
    free(wf);
}

static cl_mem grow(pd_device *dev, cl_mem b, size_t *cap, size_t need, cl_int *e)
{
    if (need <= *cap && b) return b;
    if (b) clReleaseMemObject(b);
    *cap = need + need / 2 + 64;
    return clCreateBuffer(dev->ctx, CL_MEM_READ_WRITE, sizeof(int) * *cap, NULL, e);
}

/*
 * The traversal alone, depth first (the pipeline's broad_count, with the arguments its last step
 * set) against breadth first; prints ms per traversal and the pairs each found.
 */
static int traversal_compare(sim *m, int reps)
{
    pd_device *dev = m->dev;
    pd_error err = {0};
    int n = m->n, rc = PD_OK, levels = 0;
    cl_int e = CL_SUCCESS;
    if (n < 2 || n <= SIM_BRUTE_MAX) return 0;
    /* depth first */
    double t0 = now();
    for (int r = 0; r < reps && rc == PD_OK; r++)
        rc = cl_launch(dev, m->k_count, (size_t)n, "broad_count", &err);
    clFinish(dev->queue);
    double t_dfs = (now() - t0) / reps;
    int *cnt = malloc(sizeof(int) * (size_t)n);
    cl_ulong *keys = malloc(sizeof(cl_ulong) * ((size_t)m->npairs + 1));
    long dfs = 0, walls = 0, bfs = 0;
    if (rc == PD_OK && cnt && keys) {
        clEnqueueReadBuffer(dev->queue, m->count, CL_TRUE, 0, sizeof(int) * n, cnt, 0, NULL, NULL);
        clEnqueueReadBuffer(dev->queue, m->pairs.keys, CL_TRUE, 0, sizeof(cl_ulong) * m->npairs,
                            keys, 0, NULL, NULL);
        for (int i = 0; i < n; i++)
            dfs += cnt[i];
        for (int k = 0; k < m->npairs; k++)
            walls += (keys[k] & 0xffffffffu) >= 0x80000000u; /* CH_WALL: walls' ids */
    }
    /* breadth first */
    cl_program prog;
    cl_kernel kc = NULL, kw = NULL;
    if (rc == PD_OK) rc = cl_program_get(dev, "broad_phase", m->dbl, &prog, &err);
    if (rc == PD_OK) kc = clCreateKernel(prog, "bfs_count", &e);
    if (rc == PD_OK && e == CL_SUCCESS) kw = clCreateKernel(prog, "bfs_write", &e);
    /* frontier buffers: [f][0] particles, [f][1] nodes; f = cur, 1 - cur the next level */
    cl_mem fb[2][2] = {{NULL, NULL}, {NULL, NULL}}, emit = NULL, off = NULL, count = NULL;
    size_t fcap[2][2] = {{0, 0}, {0, 0}}, ecap = 0, ocap = 0, ccap = 0;
    double t_bfs = 0;
    for (int r = 0; r <= reps && rc == PD_OK && e == CL_SUCCESS; r++) { /* r = 0: warm-up */
        int nf = n, zero = 0, cur = 0;
        for (int k = 0; k < 2; k++)
            fb[0][k] = grow(dev, fb[0][k], &fcap[0][k], (size_t)nf, &e);
        count = grow(dev, count, &ccap, (size_t)n, &e);
        int *init = malloc(sizeof(int) * 2 * (size_t)n);
        if (e != CL_SUCCESS || !init) {
            free(init);
            break;
        }
        /* the frontier starts as (i, root) for every particle: set up outside the timing */
        for (int i = 0; i < n; i++) {
            init[i] = i;
            init[n + i] = 0;
        }
        clEnqueueWriteBuffer(dev->queue, fb[0][0], CL_TRUE, 0, sizeof(int) * n, init, 0, NULL,
                             NULL);
        clEnqueueWriteBuffer(dev->queue, fb[0][1], CL_TRUE, 0, sizeof(int) * n, init + n, 0, NULL,
                             NULL);
        free(init);
        clEnqueueFillBuffer(dev->queue, count, &zero, sizeof zero, 0, sizeof(int) * n, 0, NULL,
                            NULL);
        clFinish(dev->queue);
        t0 = now();
        levels = 0;
        while (nf > 0 && rc == PD_OK && e == CL_SUCCESS) {
            levels++;
            emit = grow(dev, emit, &ecap, (size_t)nf + 1, &e);
            off = grow(dev, off, &ocap, (size_t)nf + 1, &e);
            if (e != CL_SUCCESS) break;
            e |= CL_ARG(kc, 0, m->tbox);
            e |= CL_ARG(kc, 1, m->left);
            e |= CL_ARG(kc, 2, m->right);
            e |= CL_ARG(kc, 3, n);
            e |= sim_body_box_args(m, kc, 4);
            e |= CL_ARG(kc, 9, fb[cur][0]);
            e |= CL_ARG(kc, 10, fb[cur][1]);
            e |= CL_ARG(kc, 11, nf);
            e |= CL_ARG(kc, 12, emit);
            if (e != CL_SUCCESS) break;
            rc = cl_launch(dev, kc, (size_t)nf, "bfs_count", &err);
            if (rc == PD_OK) rc = dsort_scan(&m->sort, emit, nf, off, &err);
            int next = 0;
            if (rc == PD_OK)
                e = clEnqueueReadBuffer(dev->queue, off, CL_TRUE, sizeof(int) * (size_t)nf,
                                        sizeof next, &next, 0, NULL, NULL);
            for (int k = 0; k < 2 && e == CL_SUCCESS; k++)
                fb[1 - cur][k] = grow(dev, fb[1 - cur][k], &fcap[1 - cur][k], (size_t)next + 1, &e);
            if (e != CL_SUCCESS || rc != PD_OK) break;
            e |= CL_ARG(kw, 0, m->tbox);
            e |= CL_ARG(kw, 1, m->left);
            e |= CL_ARG(kw, 2, m->right);
            e |= CL_ARG(kw, 3, m->idx);
            e |= CL_ARG(kw, 4, n);
            e |= sim_body_box_args(m, kw, 5);
            e |= CL_ARG(kw, 10, fb[cur][0]);
            e |= CL_ARG(kw, 11, fb[cur][1]);
            e |= CL_ARG(kw, 12, nf);
            e |= CL_ARG(kw, 13, off);
            e |= CL_ARG(kw, 14, fb[1 - cur][0]);
            e |= CL_ARG(kw, 15, fb[1 - cur][1]);
            e |= CL_ARG(kw, 16, count);
            if (e != CL_SUCCESS) break;
            rc = cl_launch(dev, kw, (size_t)nf, "bfs_write", &err);
            cur = 1 - cur;
            nf = next;
        }
        clFinish(dev->queue);
        if (r > 0) t_bfs += now() - t0;
    }
    t_bfs /= reps;
    if (rc == PD_OK && e == CL_SUCCESS && cnt) {
        clEnqueueReadBuffer(dev->queue, count, CL_TRUE, 0, sizeof(int) * n, cnt, 0, NULL, NULL);
        for (int i = 0; i < n; i++)
            bfs += cnt[i];
    }
    if (rc != PD_OK || e != CL_SUCCESS)
        fprintf(stderr, "bench: traversal: %s (OpenCL %d)\n", err.msg, (int)e);
    else
        printf("  traversal of %d particles: depth first %.3g ms (%ld pairs), breadth first %.3g "
               "ms (%ld pairs, %d levels)%s\n",
               n, 1e3 * t_dfs, dfs - walls, 1e3 * t_bfs, bfs, levels,
               dfs - walls == bfs ? "" : "  MISMATCH");
    cl_mem bufs[] = {fb[0][0], fb[0][1], fb[1][0], fb[1][1], emit, off, count};
    for (size_t i = 0; i < sizeof bufs / sizeof bufs[0]; i++)
        if (bufs[i]) clReleaseMemObject(bufs[i]);
    if (kc) clReleaseKernel(kc);
    if (kw) clReleaseKernel(kw);
    free(cnt);
    free(keys);
    return rc != PD_OK || e != CL_SUCCESS || dfs - walls != bfs;
}

static int bench_case(pd_device *dev, long n, int spheres, int dbl, int settle, int steps)
{
    char json[4000];
    scenario(json, sizeof json, n, spheres, dbl);
    pd_scenario *s = NULL;
    pd_diags d = {0, 0, NULL};
    pd_error err = {0};
    int prc = pd_scenario_parse(json, NULL, &s, &d, &err);
    if (wall_grid) remove(wall_path);
    if (prc != PD_OK) {
        fprintf(stderr, "bench: scenario: %s %s\n", d.n ? d.items[0].path : "",
                d.n ? d.items[0].msg : err.msg);
        pd_diags_free(&d);
        return 1;
    }
    sim *m = NULL;
    int bad = -1, rc = sim_create(dev, s, &m, &err);
    if (rc == PD_OK && no_skin) m->skin = 0;
    if (rc == PD_OK) rc = sim_forces(m, &err);
    for (int i = 0; i < settle && rc == PD_OK; i++)
        rc = sim_step(m, &bad, &err);
    clFinish(dev->queue);
    double t0 = now();
    long long built0 = m ? m->builds : 0;
    for (int i = 0; i < steps && rc == PD_OK; i++)
        rc = sim_step(m, &bad, &err);
    clFinish(dev->queue);
    double t = now() - t0;
    long long built = m ? m->builds - built0 : 0;
    long contacts = rc == PD_OK ? count_contacts(m) : 0;
    if (m) m->profile = 1;
    for (int i = 0; i < steps && rc == PD_OK; i++)
        rc = sim_step(m, &bad, &err);
    if (rc != PD_OK || bad >= 0) {
        fprintf(stderr, "bench: %s (bad particle %d)\n", err.msg, bad);
        sim_destroy(m);
        pd_scenario_destroy(s);
        return 1;
    }
    double per_step = t / steps, total = 0;
    for (int k = 0; k < SIM_NSTAGES; k++)
        total += m->stage_seconds[k];
    printf("%-10s %8ld %9.3g %10.3g %9ld %9d %10.3g %8.0f |", spheres ? "spheres" : "schonhardt", n,
           1e3 * per_step, (double)n / per_step, contacts, m->npairs,
           contacts ? 1e6 * per_step / contacts : 0, m->bytes / n);
    for (int k = 0; k < SIM_NSTAGES; k++)
        printf(" %5.1f", 100 * m->stage_seconds[k] / total);
    /* the overlap scratch follows the device's parallelism (nwork work-items), not N */
    double scratch = (double)m->nwork * ((double)sizeof(int) * m->ilen + (double)m->rs * m->rlen);
    printf("\n  pair list built in %lld of the %d timed steps (skin %.3g m); %.3g candidate pairs "
           "per particle, %ld skipped as certified apart in the last (%ld too close for one, their "
           "gap search waiting); %.0f bytes per particle besides the %.2f MB of overlap scratch\n",
           built, steps, m->skin, (double)m->npairs / n, certified, waiting,
           (m->bytes - scratch) / n, scratch / 1048576);
    stats_row_time(m);
    if (getenv("BENCH_DUMP")) { /* positions, for comparing runs */
        double *x = malloc(sizeof(double) * 3 * (size_t)n);
        if (x && sim_read(m, m->x, 0, 3 * (size_t)n, x, &err) == PD_OK) {
            FILE *f = fopen(getenv("BENCH_DUMP"), "wb");
            if (f) {
                fwrite(x, sizeof(double), 3 * (size_t)n, f);
                fclose(f);
            }
        }
        free(x);
    }
    fflush(stdout);
    int bad_traversal = traversal ? traversal_compare(m, 5) : 0;
    sim_destroy(m);
    pd_scenario_destroy(s);
    return bad_traversal;
}

int main(int argc, char **argv)
{
    long sizes[8] = {1000, 10000, 100000};
    int nsizes = 3, settle = 2000, steps = 100, device = -1, dbl = 1;
    long spheres = 50000;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--quick")) {
            sizes[0] = 1000;
            nsizes = 1;
            spheres = 2000;
            settle = 300;
            steps = 30;
        } else if (!strcmp(argv[i], "--sizes") && i + 1 < argc) {
            nsizes = 0;
            for (char *p = argv[++i]; *p && nsizes < 8;) {
                sizes[nsizes++] = strtol(p, &p, 10);
                if (*p == ',') p++;
            }
        } else if (!strcmp(argv[i], "--spheres") && i + 1 < argc) {
            spheres = strtol(argv[++i], NULL, 10);
        } else if (!strcmp(argv[i], "--settle") && i + 1 < argc) {
            settle = atoi(argv[++i]);
        } else if (!strcmp(argv[i], "--steps") && i + 1 < argc) {
            steps = atoi(argv[++i]);
        } else if (!strcmp(argv[i], "--device") && i + 1 < argc) {
            device = atoi(argv[++i]);
        } else if (!strcmp(argv[i], "--single")) {
            dbl = 0;
        } else if (!strcmp(argv[i], "--places")) {
            places = 1;
        } else if (!strcmp(argv[i], "--no-moments")) {
            no_moments = 1;
        } else if (!strcmp(argv[i], "--no-skin")) {
            no_skin = 1;
        } else if (!strcmp(argv[i], "--traversal")) {
            traversal = 1;
        } else if (!strcmp(argv[i], "--wall-grid") && i + 1 < argc) {
            wall_grid = atoi(argv[++i]);
        } else {
            fprintf(stderr,
                    "usage: %s [--quick] [--sizes N,N] [--spheres N] [--settle S] "
                    "[--steps S] [--device N] [--single] [--wall-grid G] [--traversal] [--no-skin] "
                    "[--places] [--no-moments]\n",
                    argv[0]);
            return 2;
        }
    }
    if (steps < 1) steps = 1;
    pd_device *dev = NULL;
    pd_error err = {0};
    if (pd_device_open(device, &dev, &err) != PD_OK) {
        fprintf(stderr, "bench: %s\n", err.msg);
        return 1;
    }
    if (dbl && !pd_device_has_fp64(dev)) dbl = 0;
    printf("device: %s, %s precision, contact places %s, dt 1e-5 s, %d settling steps, %d timed, "
           "floor: ",
           pd_device_name(dev), dbl ? "double" : "single", places ? "separate" : "merged", settle,
           steps);
    if (wall_grid)
        printf("%d x %d grids (%d triangles)\n", wall_grid, wall_grid, 12 * wall_grid * wall_grid);
    else
        printf("a box (12 triangles)\n");
    printf("%-10s %8s %9s %10s %9s %9s %10s %8s | %% of step: integ bvh   trav  contacts gather\n",
           "case", "N", "ms/step", "p-steps/s", "contacts", "pairs", "us/c-step", "B/part");
    int rc = 0;
    for (int i = 0; i < nsizes; i++)
        rc |= bench_case(dev, sizes[i], 0, dbl, settle, steps);
    if (spheres > 0) rc |= bench_case(dev, spheres, 1, dbl, settle, steps);
    pd_device_close(dev);
    return rc;
}
