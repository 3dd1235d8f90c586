/*
 * studies/resolution_scaling/overlap_scaling.c - nanoseconds per polyhedral overlap of one
 * built-in shape at one resolution and one overlap depth, with the half-plane filter on and off
 * (thesis section 7.2.1, figure 7.6). A variant of bench/overlap.c (same placement and timing:
 * NCONF random pairs placed by bisection at the depth, ovl_compute on one host core in double
 * precision with preallocated scratch) that takes the shape, resolution and depth as arguments
 * and prints one CSV row:
 *
 *   shape,triangles,depth,pairs,kept_tris_filter_on,ns_filter_on,ns_filter_off
 *
 * usage: overlap_scaling SHAPE TRIANGLES DEPTH [SEED] [--min-time S] [--no-filter-off]
 *                        [--precision]
 *   DEPTH is the overlap depth as a fraction of the volume-equivalent diameter; SEED the shape's
 *   seed (rock). The thesis's stiffnesses become depths: a stiffer contact overlaps less.
 *   --no-filter-off skips the unfiltered timing (quadratic in the triangles: seconds per overlap
 *   beyond ~10 000) and prints nan for it.
 *   --precision adds a line comparing the single-precision overlap with the double one on the
 *   same pairs: the volume's relative difference (median, 90th percentile, max) and how many
 *   pairs single precision misses.
 */
#define PD_DOUBLE 1
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "overlap.h"
#include "overlap_run.h"
#include "polydem.h"

#define NCONF 64

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static uint64_t rng = 12345;
static double rnd(void)
{
    uint64_t z = (rng += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return (double)((z ^ (z >> 31)) >> 11) / 9007199254740992.0;
}
static void rnd_unit(double *v, int n)
{
    double s;
    do {
        s = 0;
        for (int k = 0; k < n; k++) {
            v[k] = 2 * rnd() - 1;
            s += v[k] * v[k];
        }
    } while (s < 0.01 || s > 1);
    for (int k = 0; k < n; k++)
        v[k] /= sqrt(s);
}

/* Places up to NCONF pairs of m at depth frac x D. Returns the number placed. */
static int make_configs(const pd_mesh *m, double frac, ovl_setup *s)
{
    pd_mass_props mp;
    pd_mesh_mass_props(m, &mp);
    double D = cbrt(6 * mp.volume / 3.14159265358979323846), target = frac * D;
    int n = 0;
    for (int tries = 0; n < NCONF && tries < 10 * NCONF; tries++) {
        pd_pose pa = {{0, 0, 0}, {1, 0, 0, 0}}, pb;
        double u[3];
        rnd_unit(pa.q, 4);
        rnd_unit(pb.q, 4);
        rnd_unit(u, 3);
        double lo = 0, hi = 4 * D; /* depth(lo) > target >= depth(hi) */
        pd_contact c;
        for (int it = 0; it < 50; it++) {
            double mid = 0.5 * (lo + hi);
            for (int k = 0; k < 3; k++)
                pb.x[k] = mid * u[k];
            pd_overlap_host(m, &pa, m, &pb, 0, &c, NULL);
            if (c.hit && c.depth > target)
                lo = mid;
            else
                hi = mid;
        }
        for (int k = 0; k < 3; k++)
            pb.x[k] = lo * u[k];
        pd_overlap_host(m, &pa, m, &pb, 0, &c, NULL);
        if (!c.hit || fabs(c.depth - target) > 0.1 * target) continue;
        if (ovl_setup_make(m, &pa, m, &pb, 0, &s[n], NULL) != PD_OK) continue;
        n++;
    }
    return n;
}

/* ns per overlap over the n configs, repeated for at least min_time seconds. */
static double time_host(ovl_setup *cf, int n, int flags, double min_time, double *kept)
{
    int cap = ovl_pts_cap(cf[0].nta, cf[0].ntb);
    int *iscr = malloc(sizeof(int) * ovl_iscratch_len(cf[0].nta, cf[0].ntb, cf[0].nva, cf[0].nvb));
    double *rscr = malloc(sizeof(double) * ovl_rscratch_len(cf[0].nta, cf[0].ntb, cf[0].nva, cf[0].nvb, cap));
    static ovl_in in[NCONF];
    if (!iscr || !rscr) {
        fprintf(stderr, "overlap_scaling: out of memory\n");
        exit(1);
    }
    for (int i = 0; i < n; i++) {
        ovl_in_from_setup(&in[i], &cf[i], cf[i].va, cf[i].vb, flags, iscr, rscr, cap);
    }
    long reps = 0;
    double t0 = now(), t, sink = 0, kept_sum = 0;
    do {
        for (int i = 0; i < n; i++) {
            ovl_out o;
            ovl_compute(&in[i], &o);
            sink += o.volume;
            kept_sum += o.kept_a + o.kept_b;
        }
        reps++;
        t = now() - t0;
    } while (t < min_time);
    if (sink < 0) printf(" ");
    *kept = kept_sum / (reps * n);
    free(iscr);
    free(rscr);
    return 1e9 * t / (reps * (double)n);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Single against double precision on the placed pairs (--precision). Returns 0 or 1 (memory). */
static int precision_check(const char *shape, int tris, double depth, ovl_setup *cf, int n)
{
    double err[NCONF];
    int ne = 0, missed = 0;
    for (int i = 0; i < n; i++) {
        ovl_result d, f;
        if (ovl_run_f64(&cf[i], &d) != PD_OK || ovl_run_f32(&cf[i], &f) != PD_OK) return 1;
        if (!d.hit) continue;
        if (!f.hit) {
            missed++;
            continue;
        }
        err[ne++] = fabs(f.volume / d.volume - 1);
    }
    qsort(err, ne, sizeof err[0], cmp_double);
    printf("%s %d at depth %g: single against double, volume: median %.2e, 90th %.2e, max "
           "%.2e relative (%d pairs); %d missed by single\n",
           shape, tris, depth, ne ? err[ne / 2] : NAN, ne ? err[ne * 9 / 10] : NAN,
           ne ? err[ne - 1] : NAN, ne, missed);
    return 0;
}

int main(int argc, char **argv)
{
    const char *pos[4] = {0};
    int np = 0;
    double min_time = 0.5;
    int filter_off = 1, precision = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--min-time") && i + 1 < argc)
            min_time = atof(argv[++i]);
        else if (!strcmp(argv[i], "--no-filter-off"))
            filter_off = 0;
        else if (!strcmp(argv[i], "--precision"))
            precision = 1;
        else if (argv[i][0] != '-' && np < 4)
            pos[np++] = argv[i];
        else {
            fprintf(stderr, "usage: %s SHAPE TRIANGLES DEPTH [SEED] [--min-time S] [--no-filter-off] [--precision]\n", argv[0]);
            return 2;
        }
    }
    if (np < 3) {
        fprintf(stderr, "usage: %s SHAPE TRIANGLES DEPTH [SEED] [--min-time S] [--no-filter-off] [--precision]\n", argv[0]);
        return 2;
    }
    int tris = atoi(pos[1]);
    double depth = atof(pos[2]);
    unsigned seed = np > 3 ? (unsigned)atoi(pos[3]) : 1;
    if (!(depth > 0 && depth < 0.5)) {
        fprintf(stderr, "overlap_scaling: depth must be in (0, 0.5), got '%s'\n", pos[2]);
        return 2;
    }
    pd_error err;
    pd_mesh *m = NULL;
    if (pd_mesh_builtin(pos[0], tris, seed, &m, &err) != PD_OK) {
        fprintf(stderr, "overlap_scaling: %s\n", err.msg);
        return 1;
    }
    static ovl_setup cf[NCONF];
    int n = make_configs(m, depth, cf);
    if (n == 0) {
        fprintf(stderr, "overlap_scaling: could not place %s:%d pairs at depth %g\n", pos[0],
                tris, depth);
        return 1;
    }
    double kept_on, kept_off;
    double on = time_host(cf, n, 0, min_time, &kept_on);
    double off = filter_off ? time_host(cf, n, OVL_NO_FILTER, min_time, &kept_off) : NAN;
    printf("%s,%d,%g,%d,%.1f,%.0f,%.0f\n", pos[0], m->ntris, depth, n, kept_on, on, off);
    int rc = 0;
    if (precision && precision_check(pos[0], m->ntris, depth, cf, n)) {
        fprintf(stderr, "overlap_scaling: out of memory\n");
        rc = 1;
    }
    for (int i = 0; i < n; i++)
        ovl_setup_free(&cf[i]);
    pd_mesh_destroy(m);
    return rc;
}
