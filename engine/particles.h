/*
 * particles.h - the initial particle state a scenario describes (engine-internal).
 *
 * sc_particles_create turns each group of a parsed scenario into particles: listed ones as given,
 * generated ones placed on (lattice) or at random among (random) the cells of a grid whose cell is
 * the circumscribed diameter of the group's largest particle, so no two particles overlap at
 * t = 0; sizes drawn from the group's distribution, orientations identity, given or uniformly
 * random. Everything follows from the scenario's seed: the same scenario gives the same state.
 */
#ifndef PD_PARTICLES_H
#define PD_PARTICLES_H

#include "scenario.h"

typedef struct sc_particles {
    long n;
    double *x;       /* 3n: centre of mass, m */
    double *q;       /* 4n: orientation body -> world, [w, x, y, z] */
    double *v;       /* 3n: m/s */
    double *w;       /* 3n: angular velocity, rad/s (world) */
    double *size;    /* n: volume-equivalent diameter, m */
    double *mass;    /* n: kg */
    double *inertia; /* 3n: principal moments in the body frame, kg m^2 */
    int *shape;      /* n: index into the scenario's shapes */
    int *material;   /* n */
} sc_particles;

/* Builds the state; PD_ENOMEM, or PD_EINVAL when a group cannot be placed. */
int sc_particles_create(const pd_scenario *s, sc_particles **out, pd_error *err);
void sc_particles_destroy(sc_particles *p);

/* Principal moments of a shape per unit density at size 1 m (body frame), kg m^2 / (kg/m^3). */
void sc_shape_unit_inertia(const sc_shape *sh, double out[3]);

#endif
