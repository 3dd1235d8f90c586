/*
 * scenario_dt.c - what a scenario amounts to: particle count, memory, and the stable time step.
 *
 * DEM practice (as issue 3 states it): dt must not exceed 0.3 x the Rayleigh time step of the
 * smallest particle, nor 1/20 of the shortest Hertz contact time at the scenario's initial speeds
 * plus the free-fall speed across its extent. The contact speed used is 2 v_max + sqrt(2 g h):
 * two of the fastest particles closing head-on after falling the scene's height h, v_max
 * counting a fluid's flow speed, which drag carries particles towards.
 */
#include <math.h>
#include <string.h>

#include "scenario.h"

static const double PI = 3.14159265358979323846;

void sc_group_sizes(const sc_group *g, double *dmin, double *dmax)
{
    if (!g->list) {
        *dmin = g->size.min;
        *dmax = g->size.max;
        return;
    }
    *dmin = *dmax = g->list[0].size;
    for (long i = 1; i < g->count; i++) {
        *dmin = g->list[i].size < *dmin ? g->list[i].size : *dmin;
        *dmax = g->list[i].size > *dmax ? g->list[i].size : *dmax;
    }
}

/* Largest initial speed of any point of a group's particles, m/s (|v| + |w| r_circumscribed). */
static double group_speed(const pd_scenario *s, const sc_group *g)
{
    double rr = g->shape >= 0 ? s->shape[g->shape].radius_ratio : 0.5, vmax = 0;
    if (!g->list) {
        double dmin, dmax;
        sc_group_sizes(g, &dmin, &dmax);
        return sqrt(g->velocity[0] * g->velocity[0] + g->velocity[1] * g->velocity[1] +
                    g->velocity[2] * g->velocity[2]) +
               sqrt(g->angular_velocity[0] * g->angular_velocity[0] +
                    g->angular_velocity[1] * g->angular_velocity[1] +
                    g->angular_velocity[2] * g->angular_velocity[2]) *
                   rr * dmax;
    }
    for (long i = 0; i < g->count; i++) {
        const sc_particle *q = &g->list[i];
        double v = sqrt(q->velocity[0] * q->velocity[0] + q->velocity[1] * q->velocity[1] +
                        q->velocity[2] * q->velocity[2]) +
                   sqrt(q->angular_velocity[0] * q->angular_velocity[0] +
                        q->angular_velocity[1] * q->angular_velocity[1] +
                        q->angular_velocity[2] * q->angular_velocity[2]) *
                       rr * q->size;
        vmax = v > vmax ? v : vmax;
    }
    return vmax;
}

static void grow_box(double lo[3], double hi[3], const double p[3])
{
    for (int k = 0; k < 3; k++) {
        lo[k] = p[k] < lo[k] ? p[k] : lo[k];
        hi[k] = p[k] > hi[k] ? p[k] : hi[k];
    }
}

/* Hertz contact time of two spheres (Johnson, Contact Mechanics 11.4):
 * t_c = 2.868 (m*^2 / (R* E*^2 v))^(1/5); for the linear model pi sqrt(m* / k). */
static double contact_time(const sc_interaction *x, const sc_material *a, const sc_material *b,
                           double mstar, double rstar, double v)
{
    if (x->model == SC_MODEL_LINEAR) return PI * sqrt(mstar / x->normal_stiffness);
    if (!(v > 0)) return INFINITY;
    double estar = 1 / ((1 - a->poisson_ratio * a->poisson_ratio) / a->youngs_modulus +
                        (1 - b->poisson_ratio * b->poisson_ratio) / b->youngs_modulus);
    return 2.868 * pow(mstar * mstar / (rstar * estar * estar * v), 0.2);
}

void sc_dt_estimates(const pd_scenario *s, double *rayleigh, double *hertz, double *stable)
{
    double tr = INFINITY, th = INFINITY, vmax = 0;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int i = 0; i < s->ngroup; i++) {
        const sc_group *g = &s->group[i];
        if (g->material < 0) continue;
        const sc_material *m = &s->mat[g->material];
        double dmin, dmax;
        sc_group_sizes(g, &dmin, &dmax);
        /* Rayleigh wave time across the smallest particle (radius of the volume-equivalent
         * sphere): pi R sqrt(rho / G) / (0.1631 nu + 0.8766) */
        double t = PI * 0.5 * dmin * sqrt(m->density / m->shear_modulus) /
                   (0.1631 * m->poisson_ratio + 0.8766);
        tr = t < tr ? t : tr;
        double v = group_speed(s, g);
        vmax = v > vmax ? v : vmax;
        if (g->list)
            for (long k = 0; k < g->count; k++)
                grow_box(lo, hi, g->list[k].position);
        else {
            grow_box(lo, hi, g->region_min);
            grow_box(lo, hi, g->region_max);
        }
    }
    /* Stokes drag carries particles towards the flow's speed: they may meet one another, or a
     * wall, at it (a flow of 1e300 m/s used to pass and diverge at the first step) */
    if (s->has_fluid && s->fluid_viscosity > 0) {
        const double *u = s->fluid_velocity;
        double uf = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
        vmax = uf > vmax ? uf : vmax;
    }
    for (int w = 0; w < s->nwall; w++)
        if (s->wall[w].mesh)
            for (int i = 0; i < s->wall[w].mesh->nverts; i++)
                grow_box(lo, hi, s->wall[w].mesh->verts + 3 * i);
    /* free fall across the scene's extent along gravity */
    double gn = sqrt(s->gravity[0] * s->gravity[0] + s->gravity[1] * s->gravity[1] +
                     s->gravity[2] * s->gravity[2]),
           h = 0;
    if (gn > 0 && isfinite(lo[0]))
        for (int k = 0; k < 3; k++)
            h += (hi[k] - lo[k]) * fabs(s->gravity[k]) / gn;
    /* two particles may close in head-on: twice the fastest, plus what a fall gains */
    double v = 2 * vmax + sqrt(2 * gn * h);
    /* the shortest contact: the two smallest particles of each pair of groups, and each group's
     * smallest against a wall (R* = R, m* = m) */
    for (int i = 0; i < s->ngroup; i++) {
        const sc_group *a = &s->group[i];
        if (a->material < 0) continue;
        double da, dx;
        sc_group_sizes(a, &da, &dx);
        double ma = s->mat[a->material].density * PI / 6 * da * da * da, ra = 0.5 * da;
        for (int j = i; j < s->ngroup; j++) {
            const sc_group *b = &s->group[j];
            if (b->material < 0) continue;
            double db;
            sc_group_sizes(b, &db, &dx);
            double mb = s->mat[b->material].density * PI / 6 * db * db * db, rb = 0.5 * db;
            const sc_interaction *x = sc_interaction_of(s, a->material, b->material);
            if (!x) continue;
            double t = contact_time(x, &s->mat[a->material], &s->mat[b->material],
                                    ma * mb / (ma + mb), ra * rb / (ra + rb), v);
            th = t < th ? t : th;
        }
        for (int w = 0; w < s->nwall; w++) {
            const sc_wall *wl = &s->wall[w];
            if (wl->material < 0) continue;
            const sc_interaction *x = sc_interaction_of(s, a->material, wl->material);
            if (!x) continue;
            double t = contact_time(x, &s->mat[a->material], &s->mat[wl->material], ma, ra, v);
            th = t < th ? t : th;
        }
    }
    *rayleigh = tr;
    *hertz = th;
    double a = 0.3 * tr, b = th / 20;
    *stable = a < b ? a : b;
}

long long sc_steps(double duration, double dt)
{
    /* a whole number of steps to rounding (0.5 s at 1e-5 s is 49999.99.. or 50000.00..1): that
     * number; otherwise enough steps to cover the duration */
    double x = duration / dt;
    double n = nearbyint(x);
    return (long long)(fabs(x - n) <= 1e-9 * fmax(1, x) ? n : ceil(x));
}

long long sc_steps_per(double interval, double dt)
{
    long long n = (long long)floor(interval / dt * (1 + 1e-12) + 0.5);
    return n < 1 ? 1 : n;
}

void pd_scenario_summarize(const pd_scenario *s, pd_scenario_summary *out)
{
    memset(out, 0, sizeof *out);
    for (int i = 0; i < s->ngroup; i++)
        out->particles += s->group[i].count;
    out->shapes = s->nshape;
    out->materials = s->nmat;
    out->walls = s->nwall;
    out->dt = s->dt;
    out->duration = s->duration;
    out->steps = (long)sc_steps(s->duration, s->dt);
    sc_dt_estimates(s, &out->dt_rayleigh, &out->dt_hertz, &out->dt_stable);
    /*
     * Device memory, a planning estimate: per particle its state (position, orientation, velocity,
     * angular momentum, force, torque, inverse mass and inertia: 24 reals) and BVH leaf and node
     * (two boxes, 14 reals); per contact (8 per particle in a dense bed) the pair (2 ints), the
     * tangential history (3 reals) and the overlap result (8 reals); plus every shape's and wall's
     * mesh (3 reals per vertex, 3 ints per triangle).
     */
    double r = s->double_precision ? 8 : 4, bytes = 0;
    bytes += (double)out->particles * (38 * r + 8 * (2 * 4 + 11 * r));
    for (int i = 0; i < s->nshape; i++)
        if (s->shape[i].mesh)
            bytes += s->shape[i].mesh->nverts * 3 * r + s->shape[i].mesh->ntris * 12.0;
    for (int w = 0; w < s->nwall; w++)
        if (s->wall[w].mesh)
            bytes += s->wall[w].mesh->nverts * 3 * r + s->wall[w].mesh->ntris * (12.0 + 14 * r);
    out->memory_bytes = bytes;
    /* The frames pd_run writes, and the world-space meshes of them all (a sphere drawn as an
     * icosphere, SC_SPHERE_VIEW_*; result_h5.c stores vertices in double precision). */
    long long steps = sc_steps(s->duration, s->dt), every = sc_steps_per(s->output_interval, s->dt);
    out->frames = (long)(steps / every + 1 + (steps % every != 0));
    double nv = 0;
    int polyhedra = 0;
    for (int i = 0; i < s->ngroup; i++) {
        const sc_shape *sh = &s->shape[s->group[i].shape];
        nv += (double)s->group[i].count * (sh->mesh ? sh->mesh->nverts : SC_SPHERE_VIEW_VERTICES);
        polyhedra |= sh->mesh != NULL && s->group[i].count > 0;
    }
    out->mesh_view_bytes = nv * 3 * sizeof(double) * (double)out->frames;
    out->mesh_view_default = polyhedra && out->mesh_view_bytes <= PD_MESH_VIEW_AUTO_BYTES;
    /*
     * The overlap's snapping resolution (kernels/overlap.h: OVL_SNAP = 64 ulps of the largest
     * coordinate in play, in a particle's frame): two of the largest polyhedra side by side, or a
     * wall's extent, the longest side of its box (the wall's triangles near a particle are used
     * whole, so their far corners count).
     */
    double span = 0;
    int poly = 0;
    for (int i = 0; i < s->ngroup; i++) {
        const sc_group *g = &s->group[i];
        const sc_shape *sh = &s->shape[g->shape];
        if (!sh->mesh) continue;
        poly = 1;
        double big = g->size.max;
        for (long k = 0; g->list && k < g->count; k++)
            big = fmax(big, g->list[k].size);
        span = fmax(span, 4 * sh->radius_ratio * big);
    }
    for (int w = 0; poly && w < s->nwall; w++) {
        const pd_mesh *m = s->wall[w].mesh;
        double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (int j = 0; m && j < m->nverts; j++)
            for (int k = 0; k < 3; k++) {
                lo[k] = fmin(lo[k], m->verts[3 * j + k]);
                hi[k] = fmax(hi[k], m->verts[3 * j + k]);
            }
        for (int k = 0; m && m->nverts > 0 && k < 3; k++)
            span = fmax(span, hi[k] - lo[k]);
    }
    double eps = s->double_precision ? 2.220446049250313e-16 : 1.1920929e-7;
    out->contact_resolution = poly ? 64 * eps * span : 0;
}
