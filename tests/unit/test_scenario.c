/*
 * test_scenario.c - scenario parsing and validation (engine/scenario*.c): the issue's example,
 * defaults, every error reported with its JSON path, and the stable time step estimates against
 * the formulas computed here independently.
 */
#include <string.h>
#include <unistd.h>

#include "polydem.h"
#include "scenario.h"
#include "test.h"

static const double PI = 3.14159265358979323846;

/* Parses text; returns the scenario (or NULL) and leaves the diagnostics in *d. */
static pd_scenario *parse(const char *text, pd_diags *d)
{
    pd_scenario *s = NULL;
    pd_error err = {0};
    memset(d, 0, sizeof *d);
    pd_scenario_parse(text, NULL, &s, d, &err);
    return s;
}

/* Whether some diagnostic has this path and a message containing frag. */
static int has(const pd_diags *d, const char *path, const char *frag)
{
    for (int i = 0; i < d->n; i++)
        if (!strcmp(d->items[i].path, path) && strstr(d->items[i].msg, frag)) return 1;
    printf("  no diagnostic at %s containing \"%s\"; got:\n", path, frag);
    for (int i = 0; i < d->n; i++)
        printf("    %s: %s\n", d->items[i].path, d->items[i].msg);
    return 0;
}

/* A small valid scenario with room for one substitution (%s) inside the particle group. */
#define BASE_HEAD                                                                                  \
    "{\"time\": {\"dt\": 1e-6, \"duration\": 0.01},"                                               \
    "\"materials\": {\"rock\": {\"density\": 2600, \"youngs_modulus\": 2e7}},"                     \
    "\"interactions\": [{\"between\": [\"rock\", \"rock\"]}],"                                     \
    "\"shapes\": {\"s\": {\"builtin\": \"schonhardt\"}},"
#define BASE_GROUP                                                                                 \
    "\"particles\": [{\"shape\": \"s\", \"material\": \"rock\", \"count\": 10, \"size\": 0.01,"    \
    " \"region\": {\"min\": [0, 0, 0], \"max\": [0.1, 0.1, 0.1]}}]}"

TEST(issue_example_parses_with_defaults)
{
    char dir[] = "/tmp/pd_scenario_XXXXXX";
    CHECK(mkdtemp(dir) != NULL);
    char stl[512], scen[512];
    pd_mesh *cube = NULL;
    pd_error err = {0};
    pd_mesh_builtin("cube", 0, 0, &cube, &err);
    snprintf(stl, sizeof stl, "%s/rock.stl", dir);
    CHECK(pd_mesh_write_stl(cube, stl, &err) == PD_OK);
    /* the bin beside the particles' region: a wall around their centres is refused */
    for (int i = 0; i < cube->nverts; i++)
        cube->verts[3 * i] += 5;
    snprintf(stl, sizeof stl, "%s/bin.stl", dir);
    CHECK(pd_mesh_write_stl(cube, stl, &err) == PD_OK);
    pd_mesh_destroy(cube);
    /* the issue's example, with steel added to the materials and a closed "v" */
    const char *text =
        "{ \"name\": \"packing\", \"precision\": \"double\", \"seed\": 1,"
        "\"time\": {\"dt\": 1e-5, \"duration\": 0.5, \"output_interval\": 0.01, "
        "\"stats_interval\": 0.001},"
        "\"gravity\": [0, 0, -9.81],"
        "\"materials\": {\"rock\": {\"density\": 2600, \"youngs_modulus\": 2e7, "
        "\"poisson_ratio\": 0.25, \"shear_modulus\": 2e7},"
        " \"steel\": {\"density\": 7800, \"youngs_modulus\": 2e11, \"poisson_ratio\": 0.3}},"
        "\"interactions\": [{\"between\": [\"rock\", \"steel\"], \"friction\": 0.35, \"damping\": "
        "0.382097, \"model\": \"hertz_mindlin\", \"cohesion\": 0},"
        " {\"between\": [\"rock\", \"rock\"], \"friction\": 0.5}],"
        "\"shapes\": {\"s\": {\"builtin\": \"schonhardt\"}, \"r\": {\"builtin\": \"rock\", "
        "\"triangles\": 80}, \"m\": {\"mesh\": \"rock.stl\"}, \"v\": {\"vertices\": [[1,1,1],"
        "[1,-1,-1],[-1,1,-1],[-1,-1,1]], \"triangles\": [[0,1,2],[0,3,1],[0,2,3],[1,3,2]]}, "
        "\"ball\": {\"sphere\": {}}},"
        "\"particles\": ["
        " {\"shape\": \"s\", \"material\": \"rock\", \"count\": 1000, \"size\": {\"distribution\": "
        "\"normal\", \"mean\": 0.01, \"std\": 0.005, \"min\": 0.005, \"max\": 0.01}, "
        "\"region\": {\"min\": [0,0,0], \"max\": [0.2,0.2,0.4]}, \"arrangement\": \"lattice\", "
        "\"orientation\": \"random\", \"velocity\": [0,0,0]},"
        " {\"shape\": \"ball\", \"material\": \"rock\", \"list\": [{\"position\": [0,0,0.1], "
        "\"orientation\": [1,0,0,0], \"velocity\": [0,0,-1], \"angular_velocity\": [0,0,0], "
        "\"size\": 0.02}]}],"
        "\"walls\": [{\"name\": \"floor\", \"material\": \"steel\", \"box\": {\"min\": "
        "[-1,-1,-0.1], "
        "\"max\": [1,1,0]}},"
        " {\"name\": \"bin\", \"material\": \"steel\", \"mesh\": \"bin.stl\", \"velocity\": "
        "[0,0,0]}],"
        "\"fluid\": {\"viscosity\": 1.8e-5, \"velocity\": [0,0,0]},"
        "\"output\": {\"fields\": [\"position\", \"orientation\", \"velocity\", "
        "\"angular_velocity\"]} }";
    snprintf(scen, sizeof scen, "%s/packing.json", dir);
    FILE *f = fopen(scen, "w");
    CHECK(f != NULL);
    if (!f) return;
    fputs(text, f);
    fclose(f);
    pd_scenario *s = NULL;
    pd_diags d = {0, 0, NULL};
    int rc = pd_scenario_load(scen, &s, &d, &err);
    if (rc != PD_OK)
        for (int i = 0; i < d.n; i++)
            printf("    %s: %s\n", d.items[i].path, d.items[i].msg);
    CHECK_EQ_INT(PD_OK, rc);
    if (s) {
        pd_scenario_summary m;
        pd_scenario_summarize(s, &m);
        CHECK_EQ_INT(1001, m.particles);
        CHECK_EQ_INT(5, m.shapes);
        CHECK_EQ_INT(2, m.walls);
        CHECK_EQ_INT(50000, m.steps);
        CHECK(m.dt_stable >= 1e-5); /* the example's own dt is stable */
        CHECK(m.memory_bytes > 1001 * 100.0);
        /* shear modulus default E / (2 (1 + nu)) for steel, explicit for rock */
        CHECK_REL(2e11 / 2.6, s->mat[1].shear_modulus, 1e-15);
        CHECK_REL(2e7, s->mat[0].shear_modulus, 1e-15);
        /* meshes are rescaled to a volume-equivalent diameter of 1 m, in their body frame */
        pd_mass_props mp;
        pd_mesh_mass_props(s->shape[0].mesh, &mp);
        CHECK_REL(PI / 6, mp.volume, 1e-12);
        CHECK_NEAR(0, mp.centroid[0], 1e-12);
        CHECK(s->group[0].random_orientation);
        CHECK_EQ_INT(SC_SIZE_NORMAL, s->group[0].size.dist);
        CHECK(s->has_fluid);
    }
    pd_scenario_destroy(s);
    pd_diags_free(&d);
    unlink(scen);
    snprintf(stl, sizeof stl, "%s/rock.stl", dir);
    unlink(stl);
    snprintf(stl, sizeof stl, "%s/bin.stl", dir);
    unlink(stl);
    rmdir(dir);
}

TEST(defaults)
{
    pd_diags d;
    pd_scenario *s = parse(BASE_HEAD BASE_GROUP, &d);
    CHECK(s != NULL);
    if (!s) return;
    CHECK(s->double_precision);
    CHECK_NEAR(-9.81, s->gravity[2], 0);
    CHECK_NEAR(0.25, s->mat[0].poisson_ratio, 0);
    CHECK_NEAR(0.5, s->inter[0].friction, 0);
    CHECK_EQ_INT(SC_MODEL_HERTZ_MINDLIN, s->inter[0].model);
    CHECK_EQ_INT(0, s->inter[0].separate_places); /* "merged", the thesis's model */
    CHECK_EQ_INT(1, s->inter[0].contact_moments); /* on by default for hertz_mindlin */
    CHECK_NEAR(0.01 / 100, s->output_interval, 1e-18);
    CHECK_NEAR(0.01 / 1000, s->stats_interval, 1e-18);
    CHECK_NEAR(1, s->group[0].orientation[0], 0);
    CHECK_EQ_INT(SC_OUT_POSITION | SC_OUT_ORIENTATION | SC_OUT_VELOCITY | SC_OUT_ANGULAR,
                 s->output_fields);
    pd_scenario_destroy(s);
    pd_diags_free(&d);
}

/* Each case: a scenario text, the JSON pointer of the problem, a fragment of the message. */
static void expect_error(const char *text, const char *path, const char *frag)
{
    pd_diags d;
    pd_scenario *s = parse(text, &d);
    CHECK(s == NULL);
    CHECK(has(&d, path, frag));
    pd_scenario_destroy(s);
    pd_diags_free(&d);
}

/* A material's own pair needs an interaction only where two of its particles can meet: one
 * rock dropped on a steel floor needs rock-steel alone; two rocks (two groups of one, or one
 * group of two) need rock-rock as well. */
TEST(own_pair_needed_only_for_two_particles)
{
#define ONE_ROCK(extra)                                                                            \
    "{\"time\": {\"dt\": 1e-6, \"duration\": 0.01},"                                               \
    "\"materials\": {\"rock\": {\"density\": 2600, \"youngs_modulus\": 2e7},"                      \
    " \"steel\": {\"density\": 7800, \"youngs_modulus\": 2e11}},"                                  \
    "\"interactions\": [{\"between\": [\"rock\", \"steel\"]}],"                                    \
    "\"shapes\": {\"s\": {\"builtin\": \"schonhardt\"}},"                                          \
    "\"walls\": [{\"name\": \"floor\", \"material\": \"steel\", \"box\": {\"min\": "               \
    "[-1,-1,-1], \"max\": [1,1,0]}}],"                                                             \
    "\"particles\": [{\"shape\": \"s\", \"material\": \"rock\", \"list\": [{\"position\": "        \
    "[0,0,0.1], \"size\": 0.01}]}" extra "]}"
    pd_diags d;
    pd_scenario *s = parse(ONE_ROCK(""), &d);
    CHECK(s != NULL);
    pd_scenario_destroy(s);
    pd_diags_free(&d);
    expect_error(ONE_ROCK(", {\"shape\": \"s\", \"material\": \"rock\", \"list\": "
                          "[{\"position\": [0,0,0.3], \"size\": 0.01}]}"),
                 "/interactions", "no interaction between 'rock' and 'rock'");
    expect_error(ONE_ROCK(", {\"shape\": \"s\", \"material\": \"rock\", \"count\": 2, \"size\": "
                          "0.01, \"region\": {\"min\": [0,0,0.2], \"max\": [0.1,0.1,0.3]}}"),
                 "/interactions", "no interaction between 'rock' and 'rock'");
#undef ONE_ROCK
}

TEST(errors_name_the_field)
{
    expect_error("{\"time\": ", "/", "not valid JSON at line 1");
    expect_error("[1, 2]", "/", "JSON object");
    expect_error(BASE_HEAD "\"precision\": \"quad\"," BASE_GROUP, "/precision", "\"single\"");
    expect_error("{\"time\": {\"dt\": 1e-6, \"duration\": 0.01, \"dtt\": 1},"
                 "\"materials\": {\"rock\": {\"density\": 2600, \"youngs_modulus\": 2e7}},"
                 "\"interactions\": [{\"between\": [\"rock\", \"rock\"]}],"
                 "\"shapes\": {\"s\": {\"builtin\": \"schonhardt\"}}," BASE_GROUP,
                 "/time/dtt", "unknown field");
    expect_error("{\"time\": {\"dt\": -1, \"duration\": 0.01},"
                 "\"materials\": {\"rock\": {\"density\": 2600, \"youngs_modulus\": 2e7}},"
                 "\"interactions\": [{\"between\": [\"rock\", \"rock\"]}],"
                 "\"shapes\": {\"s\": {\"builtin\": \"schonhardt\"}}," BASE_GROUP,
                 "/time/dt", "must be > 0");
    expect_error(BASE_HEAD "\"particles\": [{\"shape\": \"s\", \"material\": \"rock\", \"count\": "
                           "10, \"size\": {\"distribution\": \"normal\", \"mean\": 0.01, \"std\": "
                           "-0.005}, \"region\": {\"min\": [0,0,0], \"max\": [1,1,1]}}]}",
                 "/particles/0/size/std", "must be >= 0");
    expect_error(BASE_HEAD "\"particles\": [{\"shape\": \"s\", \"material\": \"granite\", "
                           "\"count\": 1, \"size\": 0.01, \"region\": {\"min\": [0,0,0], "
                           "\"max\": [1,1,1]}}]}",
                 "/particles/0/material", "no material named 'granite'");
    expect_error(BASE_HEAD "\"particles\": [{\"shape\": \"q\", \"material\": \"rock\", "
                           "\"count\": 1, \"size\": 0.01, \"region\": {\"min\": [0,0,0], "
                           "\"max\": [1,1,1]}}]}",
                 "/particles/0/shape", "no shape named 'q'");
    expect_error(BASE_HEAD "\"particles\": [{\"shape\": \"s\", \"material\": \"rock\", "
                           "\"count\": 1, \"size\": 0.01, \"region\": {\"min\": [0,0,0], "
                           "\"max\": [1,0,1]}}]}",
                 "/particles/0/region", "max must exceed min");
    expect_error(BASE_HEAD "\"particles\": [{\"shape\": \"s\", \"material\": \"rock\", "
                           "\"count\": 100000, \"size\": 0.01, \"region\": {\"min\": [0,0,0], "
                           "\"max\": [0.1,0.1,0.1]}}]}",
                 "/particles/0", "do not fit in the region");
    expect_error(BASE_HEAD "\"particles\": [{\"shape\": \"s\", \"material\": \"rock\", \"list\": "
                           "[{\"position\": [0,0,0], \"orientation\": [0,0,0,0], \"size\": "
                           "0.01}]}]}",
                 "/particles/0/list/0/orientation", "must not be zero");
    /* a used pair without an interaction */
    expect_error("{\"time\": {\"dt\": 1e-6, \"duration\": 0.01},"
                 "\"materials\": {\"rock\": {\"density\": 2600, \"youngs_modulus\": 2e7},"
                 " \"steel\": {\"density\": 7800, \"youngs_modulus\": 2e11}},"
                 "\"interactions\": [{\"between\": [\"rock\", \"rock\"]}],"
                 "\"shapes\": {\"s\": {\"builtin\": \"schonhardt\"}},"
                 "\"walls\": [{\"name\": \"floor\", \"material\": \"steel\", \"box\": {\"min\": "
                 "[-1,-1,-1], \"max\": [1,1,0]}}]," BASE_GROUP,
                 "/interactions", "no interaction between 'rock' and 'steel'");
    expect_error("{\"time\": {\"dt\": 1e-6, \"duration\": 0.01},"
                 "\"materials\": {\"rock\": {\"density\": 2600, \"youngs_modulus\": 2e7}},"
                 "\"interactions\": [{\"between\": [\"rock\", \"rock\"]}, {\"between\": "
                 "[\"rock\", \"rock\"]}],"
                 "\"shapes\": {\"s\": {\"builtin\": \"schonhardt\"}}," BASE_GROUP,
                 "/interactions/1", "a second interaction");
    expect_error("{\"time\": {\"dt\": 1e-6, \"duration\": 0.01},"
                 "\"materials\": {\"rock\": {\"density\": 2600, \"youngs_modulus\": 2e7}},"
                 "\"interactions\": [{\"between\": [\"rock\", \"rock\"], \"model\": \"linear\"}],"
                 "\"shapes\": {\"s\": {\"builtin\": \"schonhardt\"}}," BASE_GROUP,
                 "/interactions/0/normal_stiffness", "required");
    expect_error("{\"time\": {\"dt\": 1e-6, \"duration\": 0.01},"
                 "\"materials\": {\"rock\": {\"density\": 2600, \"youngs_modulus\": 2e7}},"
                 "\"interactions\": [{\"between\": [\"rock\", \"rock\"], \"contact_places\": "
                 "\"apart\"}],"
                 "\"shapes\": {\"s\": {\"builtin\": \"schonhardt\"}}," BASE_GROUP,
                 "/interactions/0/contact_places",
                 "must be \"merged\" or \"separate\", got \"apart\"");
    expect_error("{\"time\": {\"dt\": 1e-6, \"duration\": 0.01},"
                 "\"materials\": {\"rock\": {\"density\": 2600, \"youngs_modulus\": 2e7}},"
                 "\"interactions\": [{\"between\": [\"rock\", \"rock\"], \"model\": \"linear\", "
                 "\"normal_stiffness\": 1e4, \"contact_places\": \"separate\"}],"
                 "\"shapes\": {\"s\": {\"builtin\": \"schonhardt\"}}," BASE_GROUP,
                 "/interactions/0/contact_places", "is for \"model\": \"hertz_mindlin\"");
    expect_error("{\"time\": {\"dt\": 1e-6, \"duration\": 0.01},"
                 "\"materials\": {\"rock\": {\"density\": 2600, \"youngs_modulus\": 2e7}},"
                 "\"interactions\": [{\"between\": [\"rock\", \"rock\"], \"contact_moments\": "
                 "\"yes\"}],"
                 "\"shapes\": {\"s\": {\"builtin\": \"schonhardt\"}}," BASE_GROUP,
                 "/interactions/0/contact_moments", "must be true or false");
    expect_error("{\"time\": {\"dt\": 1e-6, \"duration\": 0.01},"
                 "\"materials\": {\"rock\": {\"density\": 2600, \"youngs_modulus\": 2e7}},"
                 "\"interactions\": [{\"between\": [\"rock\", \"rock\"], \"model\": \"linear\", "
                 "\"normal_stiffness\": 1e4, \"contact_moments\": true}],"
                 "\"shapes\": {\"s\": {\"builtin\": \"schonhardt\"}}," BASE_GROUP,
                 "/interactions/0/contact_moments", "is for \"model\": \"hertz_mindlin\"");
    expect_error("{\"time\": {\"dt\": 1e-6, \"duration\": 0.01},"
                 "\"materials\": {\"rock\": {\"density\": 2600, \"youngs_modulus\": 2e7}},"
                 "\"interactions\": [{\"between\": [\"rock\", \"rock\"]}],"
                 "\"shapes\": {\"s\": {\"mesh\": \"/nonexistent/rock.stl\"}}," BASE_GROUP,
                 "/shapes/s/mesh", "/nonexistent/rock.stl");
    expect_error("{\"time\": {\"dt\": 1e-6, \"duration\": 0.01},"
                 "\"materials\": {\"rock\": {\"density\": 2600, \"youngs_modulus\": 2e7}},"
                 "\"interactions\": [{\"between\": [\"rock\", \"rock\"]}],"
                 "\"shapes\": {\"s\": {\"vertices\": [[0,0,0],[1,0,0],[0,1,0]], \"triangles\": "
                 "[[0,1,2]]}}," BASE_GROUP,
                 "/shapes/s", "open edge");
    expect_error(BASE_HEAD "\"walls\": [{\"name\": \"w\", \"material\": \"rock\"}]," BASE_GROUP,
                 "/walls/0", "exactly one of \"box\" or \"mesh\"");
    expect_error(BASE_HEAD "\"output\": {\"fields\": [\"position\", \"pressure\"]}," BASE_GROUP,
                 "/output/fields/1", "must be one of");
    expect_error(BASE_HEAD "\"gravity\": [1e308, 0, 0]," BASE_GROUP, "/gravity", "beyond 1e6");
    expect_error("{\"time\": {\"dt\": 1e-6, \"duration\": 0.01},"
                 "\"materials\": {\"rock\": {\"density\": 2600, \"youngs_modulus\": 2e7}},"
                 "\"interactions\": [{\"between\": [\"rock\", \"rock\"], \"cohesion\": 10}],"
                 "\"shapes\": {\"s\": {\"builtin\": \"schonhardt\"}}," BASE_GROUP,
                 "/interactions/0/cohesion_range", "required");
}

/* What `validate` used to pass and `run` then refused or ran into NaN (a QA pass, 2026-12-02). */
TEST(validate_refuses_what_run_cannot_do)
{
    /* shape and wall names name HDF5 groups of the result */
    expect_error(BASE_HEAD "\"walls\": [{\"name\": \".\", \"material\": \"rock\", \"box\": "
                           "{\"min\": [-1,-1,-1], \"max\": [1,1,-0.5]}}]," BASE_GROUP,
                 "/walls/0/name", "cannot name a group");
    expect_error(BASE_HEAD "\"walls\": [{\"name\": \"\", \"material\": \"rock\", \"box\": "
                           "{\"min\": [-1,-1,-1], \"max\": [1,1,-0.5]}}]," BASE_GROUP,
                 "/walls/0/name", "must not be empty");
    expect_error("{\"time\": {\"dt\": 1e-6, \"duration\": 0.01},"
                 "\"materials\": {\"rock\": {\"density\": 2600, \"youngs_modulus\": 2e7}},"
                 "\"interactions\": [{\"between\": [\"rock\", \"rock\"]}],"
                 "\"shapes\": {\"a/b\": {\"builtin\": \"schonhardt\"}},"
                 "\"particles\": [{\"shape\": \"a/b\", \"material\": \"rock\", \"count\": 1,"
                 " \"size\": 0.01, \"region\": {\"min\": [0,0,0], \"max\": [1,1,1]}}]}",
                 "/shapes/a~1b", "no '/'");
    /* 63 characters is the limit in characters, as the schema's maxLength counts: 60 two-byte
     * ones pass (120 bytes), 64 one-byte ones do not */
    {
        char text[2048], name[256] = "", *q = name;
        for (int i = 0; i < 60; i++)
            q += sprintf(q, "\xc3\xa9"); /* e acute */
        snprintf(text, sizeof text,
                 BASE_HEAD "\"walls\": [{\"name\": \"%s\", \"material\": \"rock\", \"box\": "
                           "{\"min\": [-1,-1,-1], \"max\": [1,1,-0.5]}}]," BASE_GROUP,
                 name);
        pd_diags d;
        pd_scenario *sc = parse(text, &d);
        CHECK(sc != NULL);
        pd_scenario_destroy(sc);
        pd_diags_free(&d);
        memset(name, 'w', 64);
        name[64] = 0;
        snprintf(text, sizeof text,
                 BASE_HEAD "\"walls\": [{\"name\": \"%s\", \"material\": \"rock\", \"box\": "
                           "{\"min\": [-1,-1,-1], \"max\": [1,1,-0.5]}}]," BASE_GROUP,
                 name);
        expect_error(text, "/walls/0/name", "longer than 63 characters");
    }
    /* the schema's types: a sphere is {}, builtin counts and seeds are integers, a seed is a
     * rock's */
    expect_error("{\"time\": {\"dt\": 1e-6, \"duration\": 0.01},"
                 "\"materials\": {\"rock\": {\"density\": 2600, \"youngs_modulus\": 2e7}},"
                 "\"interactions\": [{\"between\": [\"rock\", \"rock\"]}],"
                 "\"shapes\": {\"s\": {\"sphere\": {\"r\": 1}}}," BASE_GROUP,
                 "/shapes/s/sphere", "must be {}");
    expect_error("{\"time\": {\"dt\": 1e-6, \"duration\": 0.01},"
                 "\"materials\": {\"rock\": {\"density\": 2600, \"youngs_modulus\": 2e7}},"
                 "\"interactions\": [{\"between\": [\"rock\", \"rock\"]}],"
                 "\"shapes\": {\"s\": {\"builtin\": \"rock\", \"triangles\": 40.5}}," BASE_GROUP,
                 "/shapes/s/triangles", "must be an integer");
    expect_error("{\"time\": {\"dt\": 1e-6, \"duration\": 0.01},"
                 "\"materials\": {\"rock\": {\"density\": 2600, \"youngs_modulus\": 2e7}},"
                 "\"interactions\": [{\"between\": [\"rock\", \"rock\"]}],"
                 "\"shapes\": {\"s\": {\"builtin\": \"rock\", \"seed\": 1e30}}," BASE_GROUP,
                 "/shapes/s/seed", "must be an integer");
    expect_error("{\"time\": {\"dt\": 1e-6, \"duration\": 0.01},"
                 "\"materials\": {\"rock\": {\"density\": 2600, \"youngs_modulus\": 2e7}},"
                 "\"interactions\": [{\"between\": [\"rock\", \"rock\"]}],"
                 "\"shapes\": {\"s\": {\"builtin\": \"cube\", \"seed\": 3}}," BASE_GROUP,
                 "/shapes/s/seed", "only a \"rock\"");
    /* a builtin's parameters on a mesh file, and an empty scenario name (schema: minLength 1) */
    expect_error("{\"time\": {\"dt\": 1e-6, \"duration\": 0.01},"
                 "\"materials\": {\"rock\": {\"density\": 2600, \"youngs_modulus\": 2e7}},"
                 "\"interactions\": [{\"between\": [\"rock\", \"rock\"]}],"
                 "\"shapes\": {\"s\": {\"mesh\": \"/nonexistent.stl\", \"seed\": 3}}," BASE_GROUP,
                 "/shapes/s", "belong to a \"builtin\"");
    expect_error("{\"name\": \"\", \"time\": {\"dt\": 1e-6, \"duration\": 0.01},"
                 "\"materials\": {\"rock\": {\"density\": 2600, \"youngs_modulus\": 2e7}},"
                 "\"interactions\": [{\"between\": [\"rock\", \"rock\"]}],"
                 "\"shapes\": {\"s\": {\"builtin\": \"schonhardt\"}}," BASE_GROUP,
                 "/name", "must not be empty");
    /* a run shorter than one step */
    expect_error("{\"time\": {\"dt\": 1e-6, \"duration\": 1e-7},"
                 "\"materials\": {\"rock\": {\"density\": 2600, \"youngs_modulus\": 2e7}},"
                 "\"interactions\": [{\"between\": [\"rock\", \"rock\"]}],"
                 "\"shapes\": {\"s\": {\"builtin\": \"schonhardt\"}}," BASE_GROUP,
                 "/time/duration", "shorter than one time step");
    /* a region whose extent overflows */
    expect_error(BASE_HEAD "\"particles\": [{\"shape\": \"s\", \"material\": \"rock\", "
                           "\"count\": 1, \"size\": 0.01, \"region\": {\"min\": [-1e308,0,0], "
                           "\"max\": [1e308,1,1]}}]}",
                 "/particles/0/region", "overflows");
    /* masses beyond double precision, cohesion wider than the particles, drag faster than dt */
    expect_error("{\"time\": {\"dt\": 1e-6, \"duration\": 0.01, \"output_interval\": 0.01},"
                 "\"materials\": {\"rock\": {\"density\": 1e308, \"youngs_modulus\": 2e7}},"
                 "\"interactions\": [{\"between\": [\"rock\", \"rock\"]}],"
                 "\"shapes\": {\"s\": {\"builtin\": \"schonhardt\"}}," BASE_GROUP,
                 "/particles/0", "beyond what double precision holds");
    expect_error("{\"time\": {\"dt\": 1e-6, \"duration\": 0.01},"
                 "\"materials\": {\"rock\": {\"density\": 2600, \"youngs_modulus\": 2e7}},"
                 "\"interactions\": [{\"between\": [\"rock\", \"rock\"], \"cohesion\": 10, "
                 "\"cohesion_range\": 1e308}],"
                 "\"shapes\": {\"s\": {\"builtin\": \"schonhardt\"}}," BASE_GROUP,
                 "/interactions/0/cohesion_range", "wider than the largest particle");
    /* tau = rho d^2 / (18 mu) = 2600 * 1e-4 / (18 * 1e3) = 1.4e-5 s at mu = 1e3 Pa s (pitch),
     * below dt = 1e-4 s, which the contact estimate allows for these soft particles (E = 2e3) */
    expect_error("{\"time\": {\"dt\": 1e-4, \"duration\": 0.01},"
                 "\"materials\": {\"rock\": {\"density\": 2600, \"youngs_modulus\": 2e3}},"
                 "\"interactions\": [{\"between\": [\"rock\", \"rock\"]}],"
                 "\"fluid\": {\"viscosity\": 1e3},"
                 "\"shapes\": {\"s\": {\"builtin\": \"schonhardt\"}}," BASE_GROUP,
                 "/time/dt", "Stokes relaxation time");
    /* a particle starting with its centre inside a wall: run refuses it, so validate does */
    expect_error(BASE_HEAD
                 "\"walls\": [{\"name\": \"floor\", \"material\": \"rock\", \"box\": "
                 "{\"min\": [-1,-1,-1], \"max\": [1,1,0]}}],"
                 "\"particles\": [{\"shape\": \"s\", \"material\": \"rock\", \"list\": "
                 "[{\"position\": [0,0,0.5], \"size\": 0.01}, {\"position\": [0.2,0,-0.3], "
                 "\"size\": 0.01}]}]}",
                 "/particles/0/list/1/position", "inside wall 'floor'");
    expect_error(BASE_HEAD "\"walls\": [{\"name\": \"floor\", \"material\": \"rock\", \"box\": "
                           "{\"min\": [-1,-1,-1], \"max\": [1,1,0.05]}}]," BASE_GROUP,
                 "/particles/0", "inside wall 'floor'");
    /* a flow of 1e300 m/s carries the particles to it: the contact estimate says so */
    expect_error("{\"time\": {\"dt\": 1e-6, \"duration\": 0.01},"
                 "\"materials\": {\"rock\": {\"density\": 2600, \"youngs_modulus\": 2e7}},"
                 "\"interactions\": [{\"between\": [\"rock\", \"rock\"]}],"
                 "\"fluid\": {\"viscosity\": 1e-3, \"velocity\": [1e300, 0, 0]},"
                 "\"shapes\": {\"s\": {\"builtin\": \"schonhardt\"}}," BASE_GROUP,
                 "/time/dt", "stable time step estimate");
}

/*
 * Where `validate` disagreed with the schema (a QA pass, 2026-12-02, mutating scenarios one field
 * at a time): each problem is reported at its own field, and integers are counted as JSON Schema
 * counts them (10.0 is the integer 10).
 */
TEST(validate_agrees_with_the_schema)
{
#define SHAPE_HEAD(shape)                                                                          \
    "{\"time\": {\"dt\": 1e-6, \"duration\": 0.01},"                                               \
    "\"materials\": {\"rock\": {\"density\": 2600, \"youngs_modulus\": 2e7}},"                     \
    "\"interactions\": [{\"between\": [\"rock\", \"rock\"]}],"                                     \
    "\"shapes\": {\"s\": " shape "},"
#define TET_VERTS "\"vertices\": [[1,1,1],[1,-1,-1],[-1,1,-1],[-1,-1,1]]"
    /* an index of 2^32 was cast to int, wrapped to 0 and accepted */
    expect_error(SHAPE_HEAD("{" TET_VERTS ", \"triangles\": [[4294967296,1,2],[0,3,1],[0,2,3],"
                            "[1,3,2]]}") BASE_GROUP,
                 "/shapes/s/triangles/0/0", "must be a vertex index, an integer from 0 to 3");
    expect_error(SHAPE_HEAD("{" TET_VERTS ", \"triangles\": [[0,1,2],[0,3,1],[0,2,3],[1,3,4]]}")
                     BASE_GROUP,
                 "/shapes/s/triangles/3/2", "must be a vertex index");
    /* a seed beside an inline mesh was silently ignored */
    expect_error(SHAPE_HEAD("{" TET_VERTS ", \"triangles\": [[0,1,2],[0,3,1],[0,2,3],[1,3,2]], "
                            "\"seed\": 3}") BASE_GROUP,
                 "/shapes/s/seed", "only a \"builtin\": \"rock\" takes a seed");
    /* a count the shape does not come in was reported at /shapes/s/builtin */
    expect_error(SHAPE_HEAD("{\"builtin\": \"rock\", \"triangles\": 81}") BASE_GROUP,
                 "/shapes/s/triangles", "bad triangle count 81");
    /* a uniform size's mean was silently ignored */
    expect_error(BASE_HEAD "\"particles\": [{\"shape\": \"s\", \"material\": \"rock\", \"count\": "
                           "10, \"size\": {\"distribution\": \"uniform\", \"min\": 0.005, \"max\": "
                           "0.01, \"mean\": 0.05}, \"region\": {\"min\": [0,0,0], \"max\": "
                           "[1,1,1]}}]}",
                 "/particles/0/size/mean", "only for \"distribution\": \"normal\"");
    /* the schema's uniqueItems */
    expect_error(BASE_HEAD "\"output\": {\"fields\": [\"velocity\", \"velocity\"]}," BASE_GROUP,
                 "/output/fields/1", "'velocity' is listed twice");
    expect_error(BASE_HEAD "\"seed\": 2e19," BASE_GROUP, "/seed",
                 "must be an integer from 0 to 9223372036854775807");
    expect_error(BASE_HEAD "\"seed\": -1," BASE_GROUP, "/seed", "must be an integer from 0");
    expect_error(BASE_HEAD "\"particles\": [{\"shape\": \"s\", \"material\": \"rock\", \"count\": "
                           "10.5, \"size\": 0.01, \"region\": {\"min\": [0,0,0], \"max\": "
                           "[0.1,0.1,0.1]}}]}",
                 "/particles/0/count", "must be an integer from 1 to 100000000");
    /* numbers beyond a double's range or 64 bits were 'not valid JSON at line 1, column N' */
    expect_error(BASE_HEAD "\"gravity\": [0, 0, -1e999]," BASE_GROUP, "/gravity/2",
                 "beyond the range of a double");
    expect_error(BASE_HEAD "\"walls\": [{\"name\": \"a\\\"b\", \"material\": \"rock\", \"box\": "
                           "{\"min\": [-1,-1,-1], \"max\": [1,1e400,-0.5]}}]," BASE_GROUP,
                 "/walls/0/box/max/1", "beyond the range of a double");
    expect_error(BASE_HEAD "\"seed\": 100000000000000000000000," BASE_GROUP, "/seed",
                 "must be an integer from 0");
    expect_error(BASE_HEAD "\"name\": \"a\\u0000b\"," BASE_GROUP, "/name",
                 "a string must not contain \\u0000");
    /* a seed past 2^53 cannot be told apart from its neighbours once read as a double */
    expect_error(BASE_HEAD "\"seed\": 9007199254740993, \"gravity\": [0, 0, "
                           "-10000000000000000000000000]," BASE_GROUP,
                 "/seed", "must be an integer from 0");
    /* integers written as reals without a fraction are integers */
    pd_diags d;
    pd_scenario *s = parse(SHAPE_HEAD("{" TET_VERTS ", \"triangles\": [[0.0,1,2],[0,3,1],[0,2,3],"
                                      "[1,3,2.0]]}") "\"seed\": 3.0, \"particles\": [{\"shape\": "
                                                     "\"s\", \"material\": \"rock\", \"count\": "
                                                     "10.0, \"size\": 0.01, \"region\": {\"min\": "
                                                     "[0,0,0], \"max\": [0.1,0.1,0.1]}}]}",
                           &d);
    CHECK(s != NULL);
    if (s) {
        CHECK_EQ_INT(10, (int)s->group[0].count);
        CHECK_EQ_INT(3, (int)s->seed);
    }
    pd_scenario_destroy(s);
    pd_diags_free(&d);
#undef TET_VERTS
#undef SHAPE_HEAD
}

/* An empty object is invalid input, reported field by field, not an allocation failure. */
TEST(empty_scenario_is_invalid_not_out_of_memory)
{
    pd_diags d = {0, 0, NULL};
    pd_scenario *s = NULL;
    pd_error err = {0};
    int rc = pd_scenario_parse("{}", NULL, &s, &d, &err);
    CHECK_EQ_INT(PD_EINVAL, rc);
    CHECK(has(&d, "/materials", "required"));
    CHECK(has(&d, "/particles", "required"));
    pd_diags_free(&d);
}

TEST(every_error_is_reported)
{
    /* three independent problems in one scenario: all three come back */
    pd_diags d;
    pd_scenario *s = parse("{\"time\": {\"dt\": 0, \"duration\": 0.01}, \"colour\": \"red\","
                           "\"materials\": {\"rock\": {\"density\": -1, \"youngs_modulus\": 2e7}},"
                           "\"interactions\": [{\"between\": [\"rock\", \"rock\"]}],"
                           "\"shapes\": {\"s\": {\"builtin\": \"schonhardt\"}}," BASE_GROUP,
                           &d);
    CHECK(s == NULL);
    CHECK(has(&d, "/time/dt", "must be > 0"));
    CHECK(has(&d, "/colour", "unknown field"));
    CHECK(has(&d, "/materials/rock/density", "must be > 0"));
    pd_diags_free(&d);
}

/*
 * The contact resolution validate reports: 64 ulps (kernels/overlap.h, OVL_SNAP) of the largest
 * coordinate in play, here the 2 m floor (a pair of 2 cm cubes spans 4 circumradii, 0.069 m);
 * spheres alone have none.
 */
TEST(contact_resolution_follows_precision_and_walls)
{
    const char *fmt =
        "{\"precision\": \"%s\", \"time\": {\"dt\": 1e-6, \"duration\": 0.01},"
        "\"materials\": {\"rock\": {\"density\": 2600, \"youngs_modulus\": 2e7}},"
        "\"interactions\": [{\"between\": [\"rock\", \"rock\"]}],"
        "\"shapes\": {\"c\": %s},"
        "\"particles\": [{\"shape\": \"c\", \"material\": \"rock\", \"count\": 1, \"size\": 0.02,"
        " \"region\": {\"min\": [0,0,0.05], \"max\": [0.1,0.1,0.1]}}],"
        "\"walls\": [{\"name\": \"floor\", \"material\": \"rock\","
        " \"box\": {\"min\": [-1, -1, -0.1], \"max\": [1, 1, 0]}}]}";
    const char *prec[2] = {"double", "single"},
               *shape[2] = {"{\"builtin\": \"cube\"}", "{\"sphere\": {}}"};
    double eps[2] = {2.220446049250313e-16, 1.1920929e-7};
    for (int k = 0; k < 4; k++) {
        char text[2048];
        pd_diags d;
        snprintf(text, sizeof text, fmt, prec[k % 2], shape[k / 2]);
        pd_scenario *s = parse(text, &d);
        CHECK(s != NULL);
        if (!s) continue;
        pd_scenario_summary sum;
        pd_scenario_summarize(s, &sum);
        CHECK_REL(k < 2 ? 64 * eps[k % 2] * 2.0 : 0, sum.contact_resolution, 1e-12);
        pd_scenario_destroy(s);
    }
}

/* The result's frame count (t = 0, every output_interval, the end) and the per-frame particle
 * surfaces for ParaView: written by default for polyhedra up to PD_MESH_VIEW_AUTO_BYTES. */
TEST(mesh_view_follows_frames_and_shapes)
{
    const char *fmt =
        "{\"time\": {\"dt\": 1e-6, \"duration\": %s, \"output_interval\": %s},"
        "\"materials\": {\"rock\": {\"density\": 2600, \"youngs_modulus\": 2e7}},"
        "\"interactions\": [{\"between\": [\"rock\", \"rock\"]}],"
        "\"shapes\": {\"c\": %s},"
        "\"particles\": [{\"shape\": \"c\", \"material\": \"rock\", \"count\": 10, \"size\": 0.01,"
        " \"region\": {\"min\": [0,0,0], \"max\": [0.1,0.1,0.1]}}]}";
    struct {
        const char *duration, *interval, *shape;
        long frames;
        double vertices; /* per particle */
        int written;
    } cases[] = {
        {"0.01", "0.001", "{\"builtin\": \"schonhardt\"}", 11, 6, 1},
        {"0.0105", "0.001", "{\"builtin\": \"schonhardt\"}", 12, 6, 1}, /* the end's frame */
        {"0.01", "0.001", "{\"sphere\": {}}", 11, 42, 0},               /* points suffice */
        /* 10 x 642 vertices x 24 bytes x 10 001 frames = 1.5 GB, over the 256 MiB default */
        {"0.01", "1e-6", "{\"builtin\": \"icosphere\", \"triangles\": 1280}", 10001, 642, 0},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        char text[2048];
        pd_diags d;
        snprintf(text, sizeof text, fmt, cases[k].duration, cases[k].interval, cases[k].shape);
        pd_scenario *s = parse(text, &d);
        CHECK(s != NULL);
        if (!s) {
            pd_diags_free(&d);
            continue;
        }
        pd_scenario_summary sum;
        pd_scenario_summarize(s, &sum);
        CHECK_EQ_INT(cases[k].frames, sum.frames);
        CHECK_REL(10 * cases[k].vertices * 3 * 8 * (double)cases[k].frames, sum.mesh_view_bytes,
                  1e-15);
        CHECK_EQ_INT(cases[k].written, sum.mesh_view_default);
        pd_scenario_destroy(s);
        pd_diags_free(&d);
    }
}

TEST(unstable_dt_is_refused_with_the_estimate)
{
    /* spheres of 1 cm, E = 2e7 Pa, nu = 0.25 (G = 8e6 Pa), rho = 2600, moving at 1 m/s without
     * gravity: Rayleigh pi R sqrt(rho/G) / (0.1631 nu + 0.8766); Hertz 2.868 (m*^2/(R* E*^2 v))^0.2
     * with m* = m/2, R* = R/2, E* = E / (2 (1 - nu^2)), v = 2 x 1 m/s (head-on) */
    const char *fmt =
        "{\"time\": {\"dt\": %g, \"duration\": 0.01}, \"gravity\": [0, 0, 0], %s"
        "\"materials\": {\"rock\": {\"density\": 2600, \"youngs_modulus\": 2e7}},"
        "\"interactions\": [{\"between\": [\"rock\", \"rock\"]}],"
        "\"shapes\": {\"b\": {\"sphere\": {}}},"
        "\"particles\": [{\"shape\": \"b\", \"material\": \"rock\", \"count\": 8, \"size\": 0.01,"
        " \"velocity\": [1, 0, 0], \"region\": {\"min\": [0,0,0], \"max\": [0.1,0.1,0.1]}}]}";
    double R = 0.005, G = 2e7 / 2.5, rho = 2600, nu = 0.25;
    double tr = PI * R * sqrt(rho / G) / (0.1631 * nu + 0.8766);
    double m = rho * 4.0 / 3.0 * PI * R * R * R, es = 2e7 / (2 * (1 - nu * nu));
    double th = 2.868 * pow((m / 2) * (m / 2) / (R / 2 * es * es * 2.0), 0.2);
    double stable = fmin(0.3 * tr, th / 20);
    char text[2048];
    pd_diags d;
    snprintf(text, sizeof text, fmt, 1e-6, "");
    pd_scenario *s = parse(text, &d);
    CHECK(s != NULL);
    if (s) {
        pd_scenario_summary sum;
        pd_scenario_summarize(s, &sum);
        CHECK_REL(tr, sum.dt_rayleigh, 1e-12);
        CHECK_REL(th, sum.dt_hertz, 1e-12);
        CHECK_REL(stable, sum.dt_stable, 1e-12);
    }
    pd_scenario_destroy(s);
    pd_diags_free(&d);
    snprintf(text, sizeof text, fmt, 2 * stable, "");
    s = parse(text, &d);
    CHECK(s == NULL);
    CHECK(has(&d, "/time/dt", "exceeds the stable estimate"));
    pd_diags_free(&d);
    snprintf(text, sizeof text, fmt, 2 * stable, "\"allow_unstable_dt\": true,");
    s = parse(text, &d);
    CHECK(s != NULL);
    pd_scenario_destroy(s);
    pd_diags_free(&d);
}

int main(void)
{
    RUN(issue_example_parses_with_defaults);
    RUN(defaults);
    RUN(own_pair_needed_only_for_two_particles);
    RUN(errors_name_the_field);
    RUN(validate_refuses_what_run_cannot_do);
    RUN(validate_agrees_with_the_schema);
    RUN(every_error_is_reported);
    RUN(empty_scenario_is_invalid_not_out_of_memory);
    RUN(unstable_dt_is_refused_with_the_estimate);
    RUN(contact_resolution_follows_precision_and_walls);
    RUN(mesh_view_follows_frames_and_shapes);
    return TEST_DONE();
}
