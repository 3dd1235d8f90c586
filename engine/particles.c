/* particles.c - the initial particle state of a scenario (see particles.h). */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "particles.h"

static const double PI = 3.14159265358979323846;

/* splitmix64: small, fast, and the same sequence on every platform */
typedef struct rng {
    uint64_t s;
} rng;

static uint64_t rng_u64(rng *r)
{
    uint64_t z = (r->s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

/* Uniform in [0, 1). */
static double rng_unit(rng *r)
{
    return (double)(rng_u64(r) >> 11) / 9007199254740992.0;
}

/* Standard normal (Box-Muller). */
static double rng_normal(rng *r)
{
    double u = 1 - rng_unit(r), v = rng_unit(r);
    return sqrt(-2 * log(u)) * cos(2 * PI * v);
}

/* Uniformly random rotation (Shoemake 1992). */
static void rng_quat(rng *r, double q[4])
{
    double u1 = rng_unit(r), u2 = 2 * PI * rng_unit(r), u3 = 2 * PI * rng_unit(r);
    double a = sqrt(1 - u1), b = sqrt(u1);
    q[0] = a * sin(u2);
    q[1] = a * cos(u2);
    q[2] = b * sin(u3);
    q[3] = b * cos(u3);
}

static double draw_size(rng *r, const sc_size *z)
{
    switch (z->dist) {
    case SC_SIZE_UNIFORM:
        return z->min + (z->max - z->min) * rng_unit(r);
    case SC_SIZE_NORMAL: {
        /* truncated to [min, max] by rejection: normal draws while [min, max] holds a fair share
         * of the normal's mass; otherwise (a std much wider than the interval, where the normal
         * draws almost never land and every particle used to get the mean) uniform draws over
         * [min, max] kept with the normal's density relative to its peak there, which is exact
         * and, for a wide std, accepts nearly all */
        /* the mean kept in [min, max]: the normal's peak there, and the answer of last resort */
        double peak = z->mean < z->min ? z->min : z->mean > z->max ? z->max : z->mean;
        if (!(z->std > 0)) return peak;
        double a = (z->min - z->mean) / z->std, b = (z->max - z->mean) / z->std;
        double mass = 0.5 * (erfc(-b / sqrt(2.0)) - erfc(-a / sqrt(2.0)));
        if (mass >= 0.05) {
            for (int tries = 0; tries < 1000; tries++) {
                double d = z->mean + z->std * rng_normal(r);
                if (d >= z->min && d <= z->max) return d;
            }
        } else {
            double hp = (peak - z->mean) / z->std;
            for (int tries = 0; tries < 100000; tries++) {
                double d = z->min + (z->max - z->min) * rng_unit(r), h = (d - z->mean) / z->std;
                if (rng_unit(r) < exp(-0.5 * (h * h - hp * hp))) return d;
            }
        }
        return peak;
    }
    default:
        return z->mean;
    }
}

void sc_shape_unit_inertia(const sc_shape *sh, double out[3])
{
    if (sh->kind == SC_SHAPE_SPHERE || !sh->mesh) {
        /* solid sphere of diameter 1: (2/5) m r^2 per unit density, m = pi/6, r = 1/2 */
        double i = 0.4 * (PI / 6) * 0.25;
        out[0] = out[1] = out[2] = i;
        return;
    }
    pd_mass_props mp;
    pd_mesh_mass_props(sh->mesh, &mp);
    /* the shape is stored in its body frame: the inertia tensor is diagonal there */
    for (int k = 0; k < 3; k++)
        out[k] = mp.inertia[k][k];
}

void sc_particles_destroy(sc_particles *p)
{
    if (!p) return;
    free(p->x);
    free(p->q);
    free(p->v);
    free(p->w);
    free(p->size);
    free(p->mass);
    free(p->inertia);
    free(p->shape);
    free(p->material);
    free(p);
}

/* The most cells a generated group's lattice lists (8 bytes each for a random arrangement). */
#define LATTICE_MAX 1e9

/* Places a generated group's particles; returns PD_OK or PD_EINVAL/PD_ENOMEM. */
static int place_group(const pd_scenario *s, int gi, rng *r, sc_particles *p, long first,
                       pd_error *err)
{
    const sc_group *g = &s->group[gi];
    double rr = s->shape[g->shape].radius_ratio, cell = 2 * rr * g->size.max;
    long dims[3];
    double room = 1, fit[3];
    for (int k = 0; k < 3; k++) {
        fit[k] = floor((g->region_max[k] - g->region_min[k]) / cell);
        room *= fit[k];
    }
    if (!(room >= (double)g->count)) /* NaN too */
        return pd_error_set(err, PD_EINVAL, "/particles/%d: %ld particles do not fit the region",
                            gi, g->count);
    if (room <= LATTICE_MAX) {
        for (int k = 0; k < 3; k++)
            dims[k] = (long)fit[k];
    } else {
        /*
         * A region far larger than its particles need (1e3 grains in a 2 m box, a 1e5 m floor)
         * holds more cells than can be listed: a lattice just large enough for the group,
         * centred in the region, takes its place. The axes are sized from the thinnest up, each
         * to the root of what is still needed, so a thin axis passes its share on.
         */
        int ax[3] = {0, 1, 2};
        for (int a = 0; a < 2; a++)
            for (int b = a + 1; b < 3; b++)
                if (fit[ax[b]] < fit[ax[a]]) {
                    int t = ax[a];
                    ax[a] = ax[b];
                    ax[b] = t;
                }
        double need = (double)g->count;
        for (int i = 0; i < 3; i++) {
            double d = fmin(fit[ax[i]], ceil(pow(need, 1.0 / (3 - i)) - 1e-9));
            dims[ax[i]] = (long)d;
            need = ceil(need / d);
        }
        if ((double)dims[0] * (double)dims[1] * (double)dims[2] < (double)g->count)
            return pd_error_set(err, PD_EINVAL, "/particles/%d: no lattice of %ld cells found", gi,
                                g->count);
    }
    long ncell = dims[0] * dims[1] * dims[2];
    /* lattice: the first count cells; random: count cells chosen by a partial Fisher-Yates */
    long *pick = NULL;
    if (g->random_arrangement) {
        pick = malloc(sizeof *pick * (size_t)ncell);
        if (!pick) return pd_error_set(err, PD_ENOMEM, "particles: out of memory");
        for (long i = 0; i < ncell; i++)
            pick[i] = i;
        for (long i = 0; i < g->count; i++) {
            long j = i + (long)(rng_unit(r) * (double)(ncell - i));
            long t = pick[i];
            pick[i] = pick[j];
            pick[j] = t;
        }
    }
    /* centre the used lattice in the region */
    double off[3];
    for (int k = 0; k < 3; k++)
        off[k] = g->region_min[k] + 0.5 * (g->region_max[k] - g->region_min[k] - dims[k] * cell);
    for (long i = 0; i < g->count; i++) {
        long c = pick ? pick[i] : i, idx = first + i;
        long cx = c % dims[0], cy = (c / dims[0]) % dims[1], cz = c / (dims[0] * dims[1]);
        double d = draw_size(r, &g->size), *x = p->x + 3 * idx;
        /* random arrangement: jitter within the slack the particle leaves in its cell */
        double slack = g->random_arrangement ? 0.5 * (cell - 2 * rr * d) : 0;
        x[0] = off[0] + (cx + 0.5) * cell + slack * (2 * rng_unit(r) - 1);
        x[1] = off[1] + (cy + 0.5) * cell + slack * (2 * rng_unit(r) - 1);
        x[2] = off[2] + (cz + 0.5) * cell + slack * (2 * rng_unit(r) - 1);
        if (g->random_orientation)
            rng_quat(r, p->q + 4 * idx);
        else
            memcpy(p->q + 4 * idx, g->orientation, sizeof(double) * 4);
        memcpy(p->v + 3 * idx, g->velocity, sizeof(double) * 3);
        memcpy(p->w + 3 * idx, g->angular_velocity, sizeof(double) * 3);
        p->size[idx] = d;
    }
    free(pick);
    return PD_OK;
}

int sc_particles_create(const pd_scenario *s, sc_particles **out, pd_error *err)
{
    *out = NULL;
    sc_particles *p = calloc(1, sizeof *p);
    if (!p) return pd_error_set(err, PD_ENOMEM, "particles: out of memory");
    for (int i = 0; i < s->ngroup; i++)
        p->n += s->group[i].count;
    size_t n = (size_t)p->n;
    p->x = malloc(sizeof(double) * 3 * n);
    p->q = malloc(sizeof(double) * 4 * n);
    p->v = malloc(sizeof(double) * 3 * n);
    p->w = malloc(sizeof(double) * 3 * n);
    p->size = malloc(sizeof(double) * n);
    p->mass = malloc(sizeof(double) * n);
    p->inertia = malloc(sizeof(double) * 3 * n);
    p->shape = malloc(sizeof(int) * n);
    p->material = malloc(sizeof(int) * n);
    if (!p->x || !p->q || !p->v || !p->w || !p->size || !p->mass || !p->inertia || !p->shape ||
        !p->material) {
        long n_want = p->n; /* p is freed below */
        sc_particles_destroy(p);
        return pd_error_set(err, PD_ENOMEM, "particles: out of memory for %ld particles", n_want);
    }
    rng r = {s->seed * 0x9e3779b97f4a7c15ull + 1};
    long first = 0;
    for (int gi = 0; gi < s->ngroup; gi++) {
        const sc_group *g = &s->group[gi];
        if (g->list) {
            for (long i = 0; i < g->count; i++) {
                const sc_particle *q = &g->list[i];
                long idx = first + i;
                memcpy(p->x + 3 * idx, q->position, sizeof(double) * 3);
                memcpy(p->q + 4 * idx, q->orientation, sizeof(double) * 4);
                memcpy(p->v + 3 * idx, q->velocity, sizeof(double) * 3);
                memcpy(p->w + 3 * idx, q->angular_velocity, sizeof(double) * 3);
                p->size[idx] = q->size;
            }
        } else {
            int rc = place_group(s, gi, &r, p, first, err);
            if (rc != PD_OK) {
                sc_particles_destroy(p);
                return rc;
            }
        }
        double unit_i[3];
        sc_shape_unit_inertia(&s->shape[g->shape], unit_i);
        double rho = s->mat[g->material].density;
        for (long i = 0; i < g->count; i++) {
            long idx = first + i;
            double d = p->size[idx], d3 = d * d * d;
            p->shape[idx] = g->shape;
            p->material[idx] = g->material;
            p->mass[idx] = rho * PI / 6 * d3; /* volume-equivalent diameter d */
            for (int k = 0; k < 3; k++)
                p->inertia[3 * idx + k] = rho * unit_i[k] * d3 * d * d;
        }
        first += g->count;
    }
    *out = p;
    return PD_OK;
}
