/*
 * scenario.h - the parsed form of a scenario (schemas/scenario.schema.json, docs/SCENARIO.md),
 * engine-internal: the CLI and the daemon see only pd_scenario_* in polydem.h.
 *
 * Every length is in m, time in s, mass in kg, stiffness in Pa or N/m, as in the JSON.
 */
#ifndef PD_SCENARIO_H
#define PD_SCENARIO_H

#include "polydem.h"

#define SC_NAME_CHARS 63                    /* the schema's maxLength, in characters */
#define SC_NAME_MAX (4 * SC_NAME_CHARS + 1) /* bytes: UTF-8 takes up to 4 a character */
#define SC_PATH_MAX 640 /* a JSON pointer into a scenario (pd_diag's path): two names, escaped */

typedef struct sc_material {
    char name[SC_NAME_MAX];
    double density, youngs_modulus, poisson_ratio, shear_modulus;
} sc_material;

enum { SC_MODEL_HERTZ_MINDLIN = 0, SC_MODEL_LINEAR = 1 };

typedef struct sc_interaction {
    int mat[2];
    int model;
    double friction, damping, cohesion, cohesion_range;
    double normal_stiffness, tangential_stiffness, damping_coefficient; /* linear model only */
    int separate_places; /* "contact_places": "separate" (thesis 5.4; kernels/overlap.h) */
    int contact_moments; /* "contact_moments" (kernels/contact_pair.h, cp_couple) */
} sc_interaction;

enum { SC_SHAPE_MESH = 0, SC_SHAPE_SPHERE = 1 };

typedef struct sc_shape {
    char name[SC_NAME_MAX];
    int kind;
    pd_mesh *mesh; /* body frame, scaled to volume-equivalent diameter 1 m; NULL for spheres */
    double radius_ratio; /* circumradius / volume-equivalent diameter (0.5 for a sphere) */
} sc_shape;

enum { SC_SIZE_FIXED = 0, SC_SIZE_UNIFORM = 1, SC_SIZE_NORMAL = 2 };

typedef struct sc_size {
    int dist;
    double mean, std, min, max; /* FIXED: mean = min = max */
} sc_size;

typedef struct sc_particle {
    double position[3], orientation[4], velocity[3], angular_velocity[3], size;
} sc_particle;

typedef struct sc_group {
    int shape, material;
    long count;        /* particles in the group */
    sc_particle *list; /* explicit particles (count of them), or NULL for a generated group */
    sc_size size;      /* generated groups */
    double region_min[3], region_max[3];
    int random_arrangement; /* 0: lattice */
    int random_orientation; /* 0: the quaternion in orientation */
    double orientation[4], velocity[3], angular_velocity[3];
} sc_group;

typedef struct sc_wall {
    char name[SC_NAME_MAX];
    int material;
    pd_mesh *mesh; /* world coordinates at t = 0 (a box is meshed) */
    double velocity[3], angular_velocity[3], center[3];
} sc_wall;

enum { SC_OUT_POSITION = 1, SC_OUT_ORIENTATION = 2, SC_OUT_VELOCITY = 4, SC_OUT_ANGULAR = 8 };

/* A file the scenario was read from (the scenario itself, a mesh), which a run must not write. */
typedef struct sc_input {
    char *path;
    unsigned long long dev, ino; /* stat(2)'s identity of the file, through symbolic links */
} sc_input;

struct pd_scenario {
    char name[SC_NAME_MAX];
    int double_precision;
    unsigned long long seed;
    double dt, duration, output_interval, stats_interval;
    double gravity[3];
    int allow_unstable_dt;
    int nmat, nint, nshape, ngroup, nwall;
    sc_material *mat;
    sc_interaction *inter;
    sc_shape *shape;
    sc_group *group;
    sc_wall *wall;
    int has_fluid;
    double fluid_viscosity, fluid_velocity[3];
    int output_fields; /* SC_OUT_* */
    char *json;        /* the scenario as submitted */
    sc_input *inputs;  /* files read (pd_scenario_load's file, mesh files) */
    int ninputs;
};

/* The interaction of materials a and b, or NULL. */
const sc_interaction *sc_interaction_of(const pd_scenario *s, int a, int b);

/* Smallest and largest diameters of a group, m (a listed group has at least one particle). */
void sc_group_sizes(const sc_group *g, double *dmin, double *dmax);

/* The steps a run of `duration` takes at dt (pd_run and pd_scenario_summarize agree on it). */
long long sc_steps(double duration, double dt);

/* How the result file draws a sphere (pd_run's shapes, pd_scenario_summarize's sizes): an
 * icosphere of this many triangles, with this many vertices. */
#define SC_SPHERE_VIEW_TRIANGLES 80
#define SC_SPHERE_VIEW_VERTICES 42
/* An interval in whole steps, at least one: the nearest, halves up even where the quotient
 * rounds below them (0.00015 / 1e-4 = 1.4999999999999998: every 2 steps, not every step). */
long long sc_steps_per(double interval, double dt);

/* Stable time step estimates (scenario_dt.c); see pd_scenario_summary in polydem.h. */
void sc_dt_estimates(const pd_scenario *s, double *rayleigh, double *hertz, double *stable);

#endif
