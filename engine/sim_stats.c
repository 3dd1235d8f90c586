/*
 * sim_stats.c - a stats row (/stats in the result, the progress over HTTP) summed on the device by
 * kernels/stats.cl: each of up to m->stat_parts work-items sums a strided share of the particles
 * or pairs, and the host adds the shares in order. A row used to read every particle's state and
 * every pair back to the host (on an H200, 32 ms for 1e6 particles, where a step of them falling
 * takes 0.6 ms); it now reads a few kilobytes. Deterministic: the shares and their order depend
 * only on the device and the counts.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sim.h"

/* Reads the first `bytes` of buffer b as they are (the shares' ints and floats). */
static int read_raw(sim *m, cl_mem b, size_t bytes, void *out, pd_error *err)
{
    cl_int e = clEnqueueReadBuffer(m->dev->queue, b, CL_TRUE, 0, bytes, out, 0, NULL, NULL);
    return e == CL_SUCCESS ? PD_OK : CL_FAIL(err, "clEnqueueReadBuffer(stats)", e);
}

/* The number of shares for cnt items: one item per work-item below stat_parts. */
static int shares(const sim *m, long cnt)
{
    return cnt < m->stat_parts ? (int)cnt : m->stat_parts;
}

/* A share's contiguous run of items on a CPU (kernels/stats.cl, st_item); 0 on a GPU. */
static int span(const sim *m, long cnt, int parts)
{
    return m->dev->gpu ? 0 : (int)((cnt + parts - 1) / parts);
}

int sim_stats_energy(sim *m, double *ke, int *worst, pd_error *err)
{
    *ke = 0;
    *worst = 0;
    int parts = shares(m, m->n);
    cl_kernel k = m->k_stats_energy;
    cl_int e = CL_ARG(k, 0, m->q);
    e |= CL_ARG(k, 1, m->v);
    e |= CL_ARG(k, 2, m->L);
    e |= CL_ARG(k, 3, m->inv_m);
    e |= CL_ARG(k, 4, m->shape);
    e |= CL_ARG(k, 5, m->material);
    e |= CL_ARG(k, 6, m->size);
    e |= CL_ARG(k, 7, m->unit_inertia);
    e |= CL_ARG(k, 8, m->density);
    e |= CL_ARG(k, 9, m->n);
    int sp = span(m, m->n, parts);
    e |= CL_ARG(k, 10, parts);
    e |= CL_ARG(k, 11, sp);
    e |= CL_ARG(k, 12, m->st_sum);
    e |= CL_ARG(k, 13, m->st_emax);
    e |= CL_ARG(k, 14, m->st_imax);
    if (e != CL_SUCCESS) return CL_ARG_FAIL(err, "stats_energy");
    int rc = cl_launch(m->dev, k, (size_t)parts, "stats_energy", err);
    if (rc != PD_OK) return rc;
    double *sum = malloc(sizeof(double) * 2 * (size_t)parts);
    int *imax = malloc(sizeof(int) * (size_t)parts);
    if (!sum || !imax) {
        rc = pd_error_set(err, PD_ENOMEM, "run: out of memory for stats");
        goto done;
    }
    double *emax = sum + parts;
    if ((rc = sim_read(m, m->st_sum, 0, (size_t)parts, sum, err)) != PD_OK ||
        (rc = sim_read(m, m->st_emax, 0, (size_t)parts, emax, err)) != PD_OK ||
        (rc = read_raw(m, m->st_imax, sizeof(int) * (size_t)parts, imax, err)) != PD_OK)
        goto done;
    double best = -1;
    for (int g = 0; g < parts; g++) {
        *ke += sum[g];
        /* as within a share: the largest, and a NaN once met */
        if (imax[g] >= 0 && !(emax[g] <= best) && !isnan(best)) {
            best = emax[g];
            *worst = imax[g];
        }
    }
done:
    free(sum);
    free(imax);
    return rc;
}

int sim_stats_contacts(sim *m, long *contacts, double *max_ratio, double *wall_force, pd_error *err)
{
    *contacts = 0;
    *max_ratio = 0;
    size_t W = (size_t)m->nwall;
    if (W) memset(wall_force, 0, sizeof(double) * 3 * W);
    int parts = shares(m, m->npairs);
    if (parts == 0) return PD_OK;
    cl_kernel k = m->k_stats_contacts;
    cl_int e = CL_ARG(k, 0, m->pairs.keys);
    e |= CL_ARG(k, 1, m->info);
    e |= CL_ARG(k, 2, m->force);
    e |= CL_ARG(k, 3, m->npairs);
    e |= CL_ARG(k, 4, m->nwall);
    int sp = span(m, m->npairs, parts);
    e |= CL_ARG(k, 5, parts);
    e |= CL_ARG(k, 6, sp);
    e |= CL_ARG(k, 7, m->st_count);
    e |= CL_ARG(k, 8, m->st_ratio);
    e |= CL_ARG(k, 9, m->st_wall);
    if (e != CL_SUCCESS) return CL_ARG_FAIL(err, "stats_contacts");
    int rc = cl_launch(m->dev, k, (size_t)parts, "stats_contacts", err);
    if (rc != PD_OK) return rc;
    int *count = malloc(sizeof(int) * (size_t)parts);
    float *ratio = malloc(sizeof(float) * (size_t)parts);
    double *wall = malloc(sizeof(double) * (6 * W * (size_t)parts + 1));
    if (!count || !ratio || !wall) {
        rc = pd_error_set(err, PD_ENOMEM, "run: out of memory for stats");
        goto done;
    }
    if ((rc = read_raw(m, m->st_count, sizeof(int) * (size_t)parts, count, err)) != PD_OK ||
        (rc = read_raw(m, m->st_ratio, sizeof(float) * (size_t)parts, ratio, err)) != PD_OK ||
        (W && (rc = sim_read(m, m->st_wall, 0, 6 * W * (size_t)parts, wall, err)) != PD_OK))
        goto done;
    for (int g = 0; g < parts; g++) {
        *contacts += count[g];
        if (ratio[g] > *max_ratio) *max_ratio = ratio[g];
        for (size_t w = 0; w < W; w++) /* each share's sum less its compensation */
            for (int c = 0; c < 3; c++)
                wall_force[3 * w + c] += wall[(g * W + w) * 6 + c] - wall[(g * W + w) * 6 + 3 + c];
    }
done:
    free(count);
    free(ratio);
    free(wall);
    return rc;
}
