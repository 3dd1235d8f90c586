/*
 * bench/contacts.c - the contacts of a saved state, pair by pair, on the host: what a real bed's
 * overlaps cost, how single precision sees them, and how far each pair's depth is from the
 * thickness of its overlap.
 *
 * Reads one frame of a polydem result (HDF5: /shapes, /particles, /frames), takes every pair of
 * polyhedral particles whose circumspheres meet, and runs the overlap (kernels/overlap.h) of each
 * in double precision (timed over --reps passes, touching pairs and misses apart) and in single
 * (the engine's host single-precision path, ovl_run_f32, which allocates its scratch per pair:
 * timed the same way, for before/after comparisons of that path), then again with the pairs that
 * touch in single precision summed first about their contact point (OVL_ORIGIN, as the engine
 * sums a pair that touched in the last step). Walls and analytic spheres are left out.
 *
 * The depth of section 4.2 is the extent of the whole overlap along the normal. When a pair of
 * non-convex particles touches in several separate places (thesis section 5.4: they are one
 * contact), that extent spans the places, not the thickness of any. rho = depth * area / volume,
 * with area half the norm of eq. 4.19's vector, tells them apart: a thin slab has rho = 1, a
 * wedge 2, a cone or a cap about 3; far above that, the depth is mostly distance between places.
 * The force of eq. 4.16 goes as sqrt(V depth), so the report gives the share of sum sqrt(V depth)
 * carried by pairs with rho > 5.
 *
 * The overlap's separate places (OVL_PLACES, "contact_places": "separate") count them: the report
 * gives how many pairs touch in several places, what finding them costs, and sum sqrt(V depth)
 * with each pair's places merged (the thesis) and separate (sum sqrt(V_eff depth_eff), which is
 * the sum over the places of sqrt(V_k d_k)).
 *
 * --list prints each touching pair: particles, volume (m^3), depth (m), area (m^2), rho, the
 * single-precision volume (0: missed), places, the effective depth (m), the normal and the
 * centroid in the first particle's frame (its centroid at the origin), and single precision's
 * effective depth (m; 0: missed), plain and summed about its contact point.
 *
 * usage: build/bench/contacts RESULT.h5 [--frame K] [--reps N] [--list]   (K: default the last)
 */
#include <hdf5.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define PD_DOUBLE 1
#include "overlap.h"
#include "overlap_run.h"
#include "polydem.h"
#include "result_read.h"

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The q-quantile of sorted v[0..n). */
static double quantile(const double *v, int n, double q)
{
    return n ? v[(int)(q * (n - 1) + 0.5)] : 0;
}

static int usage(const char *prog)
{
    fprintf(stderr, "usage: %s RESULT.h5 [--frame K] [--reps N] [--list]\n", prog);
    return 2;
}

/* Seconds for reps passes of the host single-precision overlap over the np pairs su (ovl_run_f32,
 * which allocates its scratch per pair, as the engine's host path), or -1 out of memory. */
static double time_single(const ovl_setup *su, int np, int reps, double *sink)
{
    double t0 = now();
    for (int r = 0; r < reps; r++)
        for (int p = 0; p < np; p++) {
            ovl_result s32;
            if (ovl_run_f32(&su[p], &s32) != PD_OK) {
                fprintf(stderr, "contacts: out of memory\n");
                return -1;
            }
            *sink += s32.volume;
        }
    return now() - t0;
}

int main(int argc, char **argv)
{
    const char *path = NULL;
    int frame = -1, reps = 20, list = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--frame") && i + 1 < argc)
            frame = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--reps") && i + 1 < argc)
            reps = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--list"))
            list = 1;
        else if (argv[i][0] != '-' && !path)
            path = argv[i];
        else
            return usage(argv[0]);
    }
    if (!path || reps < 1) return usage(argv[0]);
    hid_t f = result_open("contacts", path);
    if (f < 0) return 1;
    hsize_t dims[3];
    int rank, ns = 0;
    int *pshape = read_all(f, "/particles/shape", H5T_NATIVE_INT, sizeof(int), dims, &rank);
    int n = pshape && rank == 1 ? (int)dims[0] : 0;
    double *psize = read_all(f, "/particles/size", H5T_NATIVE_DOUBLE, sizeof(double), dims, &rank);
    if (!pshape || !psize || rank != 1 || (int)dims[0] != n || n < 2) {
        fprintf(stderr, "contacts: %s: no /particles/shape and /particles/size of 2 or more\n",
                path);
        return 1;
    }
    shape sh[64];
    memset(sh, 0, sizeof sh);
    for (int i = 0; i < n; i++)
        ns = pshape[i] + 1 > ns ? pshape[i] + 1 : ns;
    if (ns > 64) {
        fprintf(stderr, "contacts: %s: more than 64 shapes\n", path);
        return 1;
    }
    for (int s = 0; s < ns; s++)
        if (read_shape(f, s, &sh[s]) < 0) {
            fprintf(stderr, "contacts: %s: cannot read shape %d under /shapes\n", path, s);
            return 1;
        }
    double *x = malloc(sizeof(double) * 3 * n), *q = malloc(sizeof(double) * 4 * n);
    int fr = frame;
    if (!x || !q || read_frame(f, "position", &fr, n, 3, x) < 0 ||
        read_frame(f, "orientation", &fr, n, 4, q) < 0) {
        fprintf(stderr,
                "contacts: %s: frame %d of /frames/position and /frames/orientation not found "
                "(both fields must be in the output)\n",
                path, frame);
        return 1;
    }
    H5Fclose(f);

    /* each particle's mesh at its size, in its body frame */
    pd_mesh **m = calloc((size_t)n, sizeof *m);
    pd_error err = {0};
    if (!m) {
        fprintf(stderr, "contacts: out of memory\n");
        return 1;
    }
    for (int i = 0; i < n; i++) {
        const shape *s = &sh[pshape[i]];
        if (s->sphere) continue;
        double *v = malloc(sizeof(double) * 3 * s->nv);
        for (int k = 0; v && k < 3 * s->nv; k++)
            v[k] = s->v[k] * psize[i];
        if (!v || pd_mesh_from_arrays(v, s->nv, s->t, s->nt, s->name, &m[i], &err) != PD_OK) {
            fprintf(stderr, "contacts: %s\n", v ? err.msg : "out of memory");
            return 1;
        }
        free(v);
    }

    /* candidate pairs: circumspheres meet */
    int cap = 1024, np = 0;
    ovl_setup *su = malloc(sizeof *su * cap);
    int *pair = malloc(sizeof(int) * 2 * cap); /* the particles of each */
    for (int i = 0; i < n; i++)
        for (int j = i + 1; j < n && m[i]; j++) {
            if (!m[j]) continue;
            double d2 = 0, r = sh[pshape[i]].radius * psize[i] + sh[pshape[j]].radius * psize[j];
            for (int k = 0; k < 3; k++)
                d2 += (x[3 * i + k] - x[3 * j + k]) * (x[3 * i + k] - x[3 * j + k]);
            if (d2 > r * r) continue;
            if (np == cap) {
                cap *= 2;
                su = realloc(su, sizeof *su * cap);
                pair = realloc(pair, sizeof(int) * 2 * cap);
            }
            pd_pose pa, pb;
            memcpy(pa.x, x + 3 * i, sizeof pa.x);
            memcpy(pa.q, q + 4 * i, sizeof pa.q);
            memcpy(pb.x, x + 3 * j, sizeof pb.x);
            memcpy(pb.q, q + 4 * j, sizeof pb.q);
            if (!su || !pair || ovl_setup_make(m[i], &pa, m[j], &pb, 0, &su[np], &err) != PD_OK) {
                fprintf(stderr, "contacts: pair %d %d: %s\n", i, j,
                        su && pair ? err.msg : "out of memory");
                return 1;
            }
            pair[2 * np] = i;
            pair[2 * np + 1] = j;
            np++;
        }
    if (np == 0) {
        printf("contacts: no two polyhedral particles within reach in frame %d\n", fr);
        return 0;
    }

    /* double precision: the kernel's code with preallocated scratch, as bench/overlap */
    int mv = 0, mt = 0;
    for (int s = 0; s < ns; s++) {
        mv = sh[s].nv > mv ? sh[s].nv : mv;
        mt = sh[s].nt > mt ? sh[s].nt : mt;
    }
    int pc = ovl_pts_cap(mt, mt);
    int *iscr = malloc(sizeof(int) * (ovl_iscratch_len(mt, mt, mv, mv) + ovl_places_ilen(pc)));
    double *rscr =
        malloc(sizeof(double) * (ovl_rscratch_len(mt, mt, mv, mv, pc) + ovl_places_rlen(pc)));
    ovl_in *in = calloc((size_t)np, sizeof *in);
    ovl_out *out = calloc((size_t)np, sizeof *out), *pl = calloc((size_t)np, sizeof *pl);
    double *rho = malloc(sizeof(double) * np), *rho_eff = malloc(sizeof(double) * np),
           *verr = malloc(sizeof(double) * np), *nerr = malloc(sizeof(double) * np),
           *missed = malloc(sizeof(double) * np);
    if (!iscr || !rscr || !in || !out || !pl || !rho || !rho_eff || !verr || !nerr || !missed) {
        fprintf(stderr, "contacts: out of memory\n");
        return 1;
    }
    for (int p = 0; p < np; p++) {
        ovl_in_from_setup(&in[p], &su[p], su[p].va, su[p].vb, 0, iscr, rscr, pc);
        ovl_compute(&in[p], &out[p]);
    }
    double t_hit = 0, t_miss = 0, sink = 0;
    int nh = 0, ndeg = 0;
    for (int p = 0; p < np; p++) {
        nh += out[p].hit;
        ndeg += out[p].hit && out[p].degenerate;
    }
    for (int cls = 1; cls >= 0; cls--) { /* touching pairs first, then misses */
        double t0 = now();
        for (int r = 0; r < reps; r++)
            for (int p = 0; p < np; p++) {
                if (out[p].hit != cls) continue;
                ovl_out o;
                ovl_compute(&in[p], &o);
                sink += o.volume;
            }
        if (cls)
            t_hit = now() - t0;
        else
            t_miss = now() - t0;
    }
    /* the same touching pairs with their places found */
    double t_places = now();
    for (int r = 0; r < reps; r++)
        for (int p = 0; p < np; p++) {
            if (!out[p].hit) continue;
            in[p].flags = OVL_PLACES;
            ovl_compute(&in[p], &pl[p]);
            in[p].flags = 0;
        }
    t_places = now() - t_places;
    /* single precision, every touching pair (in double) and every miss: the rescue of pairs in far
     * places (OVL_RESCUE) runs on pairs that single precision would otherwise call misses */
    double t_single = time_single(su, np, reps, &sink);
    if (t_single < 0) return 1;
    /* ... and as the engine runs a pair that touched in the last step: the cusps summed first
     * about its contact point then (OVL_ORIGIN), here the point single precision finds now (a
     * settled bed's contacts move by micrometres a step) */
    ovl_result *s32a = malloc(sizeof *s32a * (size_t)np);
    if (!s32a) {
        fprintf(stderr, "contacts: out of memory\n");
        return 1;
    }
    int nhint = 0;
    for (int p = 0; p < np; p++) { /* the plain pass's results, also for the report below */
        if (ovl_run_f32(&su[p], &s32a[p]) != PD_OK) {
            fprintf(stderr, "contacts: out of memory\n");
            return 1;
        }
        if (!s32a[p].hit) continue;
        su[p].flags |= OVL_ORIGIN;
        memcpy(su[p].org, s32a[p].point_eff, sizeof su[p].org);
        nhint++;
    }
    double t_hinted = time_single(su, np, reps, &sink);
    if (t_hinted < 0) return 1;
    int hint_found = 0, nherr = 0;
    double *herr = malloc(sizeof(double) * np); /* against double, volume */
    if (!herr) {
        fprintf(stderr, "contacts: out of memory\n");
        return 1;
    }
    ovl_result *s32o = calloc((size_t)np, sizeof *s32o); /* about the contact point (hit 0: none) */
    if (!s32o) {
        fprintf(stderr, "contacts: out of memory\n");
        return 1;
    }
    for (int p = 0; p < np; p++) {
        ovl_result s32;
        if (!(su[p].flags & OVL_ORIGIN)) continue;
        if (ovl_run_f32(&su[p], &s32) != PD_OK) {
            fprintf(stderr, "contacts: out of memory\n");
            return 1;
        }
        su[p].flags &= ~OVL_ORIGIN;
        s32o[p] = s32;
        if (!s32.hit) continue;
        hint_found++;
        if (out[p].hit) herr[nherr++] = fabs(s32.volume - out[p].volume) / out[p].volume;
    }
    qsort(herr, nherr, sizeof *herr, cmp_double);

    /* depth against the overlap's thickness, and single precision against double */
    int nr = 0, nbig = 0, nboth = 0, nmiss = 0, nextra = 0, nplaces[5] = {0}, nbig_multi = 0;
    int ndeep = 0, ndeep_o = 0; /* single's effective depth above twice double's */
    double force = 0, force_big = 0, force_sep = 0, multi_merged = 0, multi_sep = 0;
    for (int p = 0; p < np; p++) {
        const ovl_result s32 = s32a[p]; /* the plain single-precision pass */
        const ovl_out *o = &out[p];
        if (!o->hit) {
            nextra += s32.hit;
            continue;
        }
        double r = o->depth * o->area / o->volume, fv = sqrt(o->volume * o->depth);
        if (list)
            printf("pair %d %d: volume %.6g m^3, depth %.6g m, area %.6g m^2, rho %.4g, single "
                   "volume %.6g m^3, places %d, effective depth %.6g m, normal (%.6g, %.6g, %.6g) "
                   "and centroid (%.6g, %.6g, %.6g) m in the first's frame; single effective "
                   "depth %.6g m, summed about its contact point %.6g m%s\n",
                   pair[2 * p], pair[2 * p + 1], o->volume, o->depth, o->area, r,
                   s32.hit ? s32.volume : 0, pl[p].places, pl[p].depth_eff, o->normal.x,
                   o->normal.y, o->normal.z, o->centroid.x, o->centroid.y, o->centroid.z,
                   s32.hit ? s32.depth_eff : 0, s32o[p].hit ? s32o[p].depth_eff : 0,
                   o->degenerate ? ", degenerate" : "");
        /* a force spike's signature: single's depth far beyond double's (a stray node, a turned
         * normal), the volume being right */
        ndeep += s32.hit && s32.depth_eff > 2 * pl[p].depth_eff;
        ndeep_o += s32o[p].hit && s32o[p].depth_eff > 2 * pl[p].depth_eff;
        rho_eff[nr] = pl[p].depth_eff * o->area / o->volume;
        rho[nr++] = r;
        force += fv;
        double fs = sqrt(pl[p].vol_eff * pl[p].depth_eff);
        force_sep += fs;
        nplaces[pl[p].places < 4 ? pl[p].places : 4]++;
        if (pl[p].places > 1) {
            multi_merged += fv;
            multi_sep += fs;
        }
        if (r > 5) {
            nbig++;
            force_big += fv;
            nbig_multi += pl[p].places > 1;
        }
        if (!s32.hit) {
            missed[nmiss++] = o->volume;
            continue;
        }
        verr[nboth] = fabs(s32.volume - o->volume) / o->volume;
        double c =
            s32.normal[0] * o->normal.x + s32.normal[1] * o->normal.y + s32.normal[2] * o->normal.z;
        nerr[nboth++] = acos(fmin(1, c)) * 180 / 3.14159265358979323846;
    }
    qsort(rho, nr, sizeof *rho, cmp_double);
    qsort(rho_eff, nr, sizeof *rho_eff, cmp_double);
    qsort(verr, nboth, sizeof *verr, cmp_double);
    qsort(nerr, nboth, sizeof *nerr, cmp_double);
    qsort(missed, nmiss, sizeof *missed, cmp_double);

    printf("# %s, frame %d: %d particles, %d pairs of polyhedra whose circumspheres meet\n", path,
           fr, n, np);
    printf("touching (double precision): %d (%d degenerate, taking two passes)\n", nh, ndeg);
    printf("host, one core, double: %.0f ns per touching pair, %.0f ns per miss (%d passes)%s\n",
           nh ? 1e9 * t_hit / ((double)reps * nh) : 0,
           np > nh ? 1e9 * t_miss / ((double)reps * (np - nh)) : 0, reps, sink < 0 ? " " : "");
    printf("rho = depth x area / volume (1 slab, 2 wedge, ~3 cap): median %.3g, 90th %.3g, 99th "
           "%.3g, max %.3g\n",
           quantile(rho, nr, 0.5), quantile(rho, nr, 0.9), quantile(rho, nr, 0.99),
           nr ? rho[nr - 1] : 0);
    printf("pairs with rho > 5: %d of %d, carrying %.1f %% of sum sqrt(V depth) (eq. 4.16's force "
           "goes as sqrt(V depth))\n",
           nbig, nr, force > 0 ? 100 * force_big / force : 0);
    printf(
        "places (thesis 5.4): one %d, two %d, three %d, four or more %d; %d of the %d pairs with "
        "rho > 5 touch in several\n",
        nplaces[1], nplaces[2], nplaces[3], nplaces[4], nbig_multi, nbig);
    printf("rho with the places' effective depth: median %.3g, 90th %.3g, 99th %.3g, max %.3g\n",
           quantile(rho_eff, nr, 0.5), quantile(rho_eff, nr, 0.9), quantile(rho_eff, nr, 0.99),
           nr ? rho_eff[nr - 1] : 0);
    printf("sum sqrt(V depth): merged %.4g, separate %.4g (%.3f); over the pairs in several "
           "places: merged %.4g, separate %.4g (%.3f)\n",
           force, force_sep, force > 0 ? force_sep / force : 0, multi_merged, multi_sep,
           multi_merged > 0 ? multi_sep / multi_merged : 0);
    printf("host, one core, double, places found: %.0f ns per touching pair (%+.1f %%)\n",
           nh ? 1e9 * t_places / ((double)reps * nh) : 0,
           t_hit > 0 ? 100 * (t_places / t_hit - 1) : 0);
    printf("host, one core, single (ovl_run_f32, scratch allocated per pair): %.0f ns per pair of "
           "the %d\n",
           np ? 1e9 * t_single / ((double)reps * np) : 0, np);
    printf("host, one core, single, the %d touching in single summed first about their contact "
           "point (OVL_ORIGIN, as the engine does for a pair that touched in the last step): "
           "%.0f ns per pair of the %d (%+.1f %%); %d still touch, against double in volume: "
           "median %.2g, 90th %.2g, 99th %.2g, max %.2g relative\n",
           nhint, np ? 1e9 * t_hinted / ((double)reps * np) : 0, np,
           t_single > 0 ? 100 * (t_hinted / t_single - 1) : 0, hint_found,
           quantile(herr, nherr, 0.5), quantile(herr, nherr, 0.9), quantile(herr, nherr, 0.99),
           nherr ? herr[nherr - 1] : 0);
    printf("single precision: %d of the %d touching pairs found, %d missed", nboth, nh, nmiss);
    if (nmiss)
        printf(" (volumes %.2g to %.2g m^3, median %.2g)", missed[0], missed[nmiss - 1],
               quantile(missed, nmiss, 0.5));
    printf(", %d touching in single only\n", nextra);
    printf("single against double, volume: median %.2g, 90th %.2g, 99th %.2g, max %.2g relative; "
           "normal: median %.2g, 99th %.2g, max %.2g deg\n",
           quantile(verr, nboth, 0.5), quantile(verr, nboth, 0.9), quantile(verr, nboth, 0.99),
           nboth ? verr[nboth - 1] : 0, quantile(nerr, nboth, 0.5), quantile(nerr, nboth, 0.99),
           nboth ? nerr[nboth - 1] : 0);
    printf("single precision's effective depth above twice double's (a stray node or a turned "
           "normal): %d of the %d touching pairs, %d summed about their contact point\n",
           ndeep, nh, ndeep_o);

    for (int p = 0; p < np; p++)
        ovl_setup_free(&su[p]);
    for (int i = 0; i < n; i++)
        if (m[i]) pd_mesh_destroy(m[i]);
    for (int s = 0; s < ns; s++) {
        free(sh[s].v);
        free(sh[s].t);
    }
    free(m);
    free(su);
    free(pair);
    free(in);
    free(out);
    free(iscr);
    free(rscr);
    free(pl);
    free(rho);
    free(rho_eff);
    free(verr);
    free(nerr);
    free(missed);
    free(herr);
    free(s32a);
    free(s32o);
    free(x);
    free(q);
    free(pshape);
    free(psize);
    return 0;
}
