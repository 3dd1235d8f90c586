/*
 * sim.c - running a scenario (pd_run): the time loop around sim_step, the result file, stats
 * rows, frames, progress reports, cancellation, and the divergence checks.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#define PD_DOUBLE 1
#include "integrate.h" /* rotational energy and omega on the host, as the kernels do */
#include "result_h5.h"
#include "sim.h"

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Host copies of what frames need (stats rows are summed on the device: sim_stats.c). */
typedef struct run_host {
    double *x, *q, *v, *L, *w;
    double *wall_force;
} run_host;

_Static_assert(SIM_NSTAGES == RH5_NSTAGES, "the result file names every stage of sim.h");

/* Times the next step stage by stage (on) or runs it unsynchronised (off). The earlier steps'
 * work still queued is waited for first, or the first stage would be booked for it. */
static int timed_steps(sim *m, int on, pd_error *err)
{
    m->profile = on;
    if (!on) return PD_OK;
    memset(m->stage_seconds, 0, sizeof m->stage_seconds);
    cl_int e = clFinish(m->dev->queue);
    return e == CL_SUCCESS ? PD_OK : CL_FAIL(err, "clFinish(before a timed step)", e);
}

static void host_free(run_host *h)
{
    free(h->x);
    free(h->q);
    free(h->v);
    free(h->L);
    free(h->w);
    free(h->wall_force);
}

/* Reads a frame's state, with omega from L on the host. */
static int read_frame(sim *m, run_host *h, pd_error *err)
{
    size_t n = (size_t)m->n;
    int rc = sim_read(m, m->q, 0, 4 * n, h->q, err);
    if (rc == PD_OK) rc = sim_read(m, m->v, 0, 3 * n, h->v, err);
    if (rc == PD_OK) rc = sim_read(m, m->L, 0, 3 * n, h->L, err);
    if (rc == PD_OK) rc = sim_read(m, m->x, 0, 3 * n, h->x, err);
    if (rc != PD_OK) return rc;
    for (size_t i = 0; i < n; i++) {
        const double *in = m->p->inertia + 3 * i;
        pd_q4 q = q4(h->q[4 * i], h->q[4 * i + 1], h->q[4 * i + 2], h->q[4 * i + 3]);
        pd_v3 wb = int_omega_body(q, v3_load(h->L, (int)i), v3(1 / in[0], 1 / in[1], 1 / in[2]));
        v3_store(h->w, (int)i, q4_rotate(q, wb));
    }
    return PD_OK;
}

/* Shapes, walls and particles into a new result file. */
static int open_result(sim *m, const pd_run_options *opt, rh5_writer **out, pd_error *err)
{
    const pd_scenario *s = m->s;
    int fields = 0;
    if (s->output_fields & SC_OUT_VELOCITY) fields |= RH5_VELOCITY;
    if (s->output_fields & SC_OUT_ANGULAR) fields |= RH5_ANGULAR_VELOCITY;
    int meshes = opt->shape_meshes;
    if (meshes == 0) {
        pd_scenario_summary sm;
        pd_scenario_summarize(s, &sm);
        meshes = sm.mesh_view_default;
    }
    if (meshes > 0) fields |= RH5_SHAPE_MESHES;
    rh5_writer *w;
    int rc = rh5_create(opt->output_path, s->json ? s->json : "{}", s->double_precision, s->dt,
                        fields, &w, err);
    if (rc != PD_OK) return rc;
    pd_mesh *ball = NULL;
    for (int i = 0; i < s->nshape && rc == PD_OK; i++) {
        const sc_shape *sh = &s->shape[i];
        if (sh->kind == SC_SHAPE_SPHERE) {
            /* display tessellation: an icosphere of diameter 1 (scenario.h) */
            if (!ball && (rc = pd_mesh_builtin("icosphere", SC_SPHERE_VIEW_TRIANGLES, 0, &ball,
                                               err)) != PD_OK)
                break;
            double *v = malloc(sizeof(double) * 3 * (size_t)ball->nverts);
            if (!v) {
                rc = pd_error_set(err, PD_ENOMEM, "run: out of memory");
                break;
            }
            for (int j = 0; j < 3 * ball->nverts; j++)
                v[j] = 0.5 * ball->verts[j];
            rc = rh5_add_shape(w, sh->name, "sphere", v, ball->nverts, ball->tris, ball->ntris,
                               3.14159265358979323846 / 6, err);
            free(v);
        } else {
            pd_mass_props mp;
            pd_mesh_mass_props(sh->mesh, &mp);
            rc = rh5_add_shape(w, sh->name, "mesh", sh->mesh->verts, sh->mesh->nverts,
                               sh->mesh->tris, sh->mesh->ntris, mp.volume, err);
        }
    }
    pd_mesh_destroy(ball);
    for (int i = 0; i < s->nwall && rc == PD_OK; i++) {
        const pd_mesh *me = s->wall[i].mesh;
        const sc_wall *wl = &s->wall[i];
        double motion[9];
        for (int k = 0; k < 3; k++) {
            motion[k] = wl->velocity[k];
            motion[3 + k] = wl->angular_velocity[k];
            motion[6 + k] = wl->center[k];
        }
        rc = rh5_add_wall(w, wl->name, me->verts, me->nverts, me->tris, me->ntris, motion, err);
    }
    if (rc == PD_OK)
        rc = rh5_set_particles(w, m->n, m->p->shape, m->p->material, m->p->size, m->p->mass, err);
    if (rc != PD_OK) {
        rh5_abort(w);
        return rc;
    }
    *out = w;
    return PD_OK;
}

/*
 * What a run can supply, for the runaway check (a kinetic energy 10x beyond it stops the run):
 * fixed at the start, plus gravity's work, which grows with the time fallen.
 */
typedef struct energy_budget {
    double fixed;    /* J */
    double mg;       /* total weight, N */
    double h, v0, g; /* the scene's extent (m), fastest start (m/s), |g| (m/s^2) */
} energy_budget;

/*
 * The energy a scenario can supply: the initial kinetic energy; what moving walls and a flow can
 * give (every particle at twice their speed); when it starts with contacts or has cohesion
 * (stored), what overlaps and cohesion hold, bounded by 1/2 M c^2 with c = sqrt(E / rho) the
 * slowest material's wave speed (an overlap of a particle's size stores about E V, and DEM
 * particles never outrun their wave speed); and gravity's work over the scene's height
 * (particles, their sizes and the walls) or over the fall since the start, whichever is larger
 * (particles need not land). The wave-speed term is left out where nothing is stored at the
 * start, so that a contact that blows up (a dt far too large) is caught at once.
 */
static energy_budget energy_of(const sim *m, double ke0, int stored)
{
    const pd_scenario *s = m->s;
    energy_budget b = {0, 0, 0, 0, 0};
    b.g = sqrt(s->gravity[0] * s->gravity[0] + s->gravity[1] * s->gravity[1] +
               s->gravity[2] * s->gravity[2]);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    double mass = 0, c2 = INFINITY, vw = 0;
    for (long i = 0; i < m->n; i++) {
        const double *x = m->p->x + 3 * i, *v = m->p->v + 3 * i;
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], x[k] - m->p->size[i]);
            hi[k] = fmax(hi[k], x[k] + m->p->size[i]);
        }
        b.v0 = fmax(b.v0, sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]));
        mass += m->p->mass[i];
        const sc_material *mt = &s->mat[m->p->material[i]];
        c2 = fmin(c2, mt->youngs_modulus / mt->density);
    }
    for (int w = 0; w < s->nwall; w++) {
        const pd_mesh *me = s->wall[w].mesh;
        const double *v = s->wall[w].velocity, *om = s->wall[w].angular_velocity,
                     *c = s->wall[w].center;
        double r = 0;
        for (int j = 0; me && j < me->nverts; j++) {
            const double *p = me->verts + 3 * j;
            double d2 = 0;
            for (int k = 0; k < 3; k++) {
                lo[k] = fmin(lo[k], p[k]);
                hi[k] = fmax(hi[k], p[k]);
                d2 += (p[k] - c[k]) * (p[k] - c[k]);
            }
            r = fmax(r, sqrt(d2));
        }
        vw = fmax(vw, sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) +
                          sqrt(om[0] * om[0] + om[1] * om[1] + om[2] * om[2]) * r);
    }
    if (s->has_fluid && s->fluid_viscosity > 0) {
        const double *u = s->fluid_velocity;
        vw = fmax(vw, sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]));
    }
    for (int k = 0; k < 3 && isfinite(lo[k]); k++)
        b.h += (hi[k] - lo[k]) * (hi[k] - lo[k]);
    b.h = sqrt(b.h);
    b.mg = mass * b.g;
    b.fixed = ke0 + 2 * mass * vw * vw + (stored && isfinite(c2) ? 0.5 * mass * c2 : 0);
    return b;
}

/* Energy a run may reach at time t without something being wrong: 10x what it can supply. */
static double energy_bound(const energy_budget *b, double t)
{
    double fall = b->v0 * t + 0.5 * b->g * t * t;
    return 10 * (b->fixed + b->mg * fmax(b->h, fall)) + 1e-300;
}

const char *pd_run_status(int rc)
{
    return rc == PD_OK           ? "complete"
           : rc == PD_ECANCELLED ? "cancelled"
           : rc == PD_EDIVERGED  ? "diverged"
                                 : "failed";
}

/*
 * Refuses, before any work, an output path that names a directory (the finished run could not be
 * renamed to it), whose result, XDMF file or their .partial files exist as anything but a regular
 * file (a device such as /dev/null, a pipe), or would be one of the files
 * the scenario was read from: writing them would destroy the input (compared by device and inode,
 * so symbolic links and other spellings of the same file are caught).
 */
static int check_output(const pd_scenario *s, const char *path, pd_error *err)
{
    static const char *const suffix[] = {"", ".partial", ".xmf", ".xmf.partial"};
    struct stat st;
    if (stat(path, &st) == 0 && S_ISDIR(st.st_mode))
        return pd_error_set(err, PD_EINVAL,
                            "output '%s' is a directory: give the result file's name, e.g. "
                            "'%s/result.h5'",
                            path, path);
    size_t len = strlen(path) + sizeof ".xmf.partial";
    char *name = malloc(len);
    if (!name) return pd_error_set(err, PD_ENOMEM, "run: out of memory");
    int rc = PD_OK;
    for (int k = 0; k < 4 && rc == PD_OK; k++) {
        snprintf(name, len, "%s%s", path, suffix[k]);
        if (stat(name, &st) != 0) continue;
        /* the finished files are renamed onto these names: that would replace a device (root
         * running `-o /dev/null` replaced the system's /dev/null with a file), a pipe or a socket
         */
        if (!S_ISREG(st.st_mode)) {
            rc = pd_error_set(err, PD_EINVAL,
                              "output '%s': '%s' is a %s, not a regular file, and the result "
                              "would replace it: give a file path (a temporary file, to discard "
                              "the result)",
                              path, name,
                              S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode) ? "device"
                              : S_ISFIFO(st.st_mode)                     ? "pipe"
                              : S_ISSOCK(st.st_mode)                     ? "socket"
                              : S_ISDIR(st.st_mode)                      ? "directory"
                                                                         : "special file");
            break;
        }
        for (int i = 0; i < s->ninputs && rc == PD_OK; i++)
            if ((unsigned long long)st.st_dev == s->inputs[i].dev &&
                (unsigned long long)st.st_ino == s->inputs[i].ino)
                rc = pd_error_set(err, PD_EINVAL,
                                  "output '%s' would overwrite '%s', which the scenario was read "
                                  "from: choose another output path",
                                  path, s->inputs[i].path);
    }
    free(name);
    return rc;
}

int pd_run(pd_device *dev, const pd_scenario *s, const pd_run_options *opt, pd_progress *final,
           pd_error *err)
{
    pd_progress pr;
    memset(&pr, 0, sizeof pr);
    pr.eta_seconds = -1;
    if (final) *final = pr;
    if (!dev || !s || !opt || !opt->output_path || !opt->output_path[0])
        return pd_error_set(err, PD_EINVAL,
                            "run: a device, a scenario and an output path are "
                            "required");
    sim *m = NULL;
    rh5_writer *w = NULL;
    run_host h;
    memset(&h, 0, sizeof h);
    double t_start = now_seconds();
    int rc = check_output(s, opt->output_path, err);
    if (rc != PD_OK) return rc;
    rc = sim_create(dev, s, &m, err);
    if (rc != PD_OK) return rc;
    size_t n = (size_t)m->n;
    h.x = malloc(sizeof(double) * 3 * n);
    h.q = malloc(sizeof(double) * 4 * n);
    h.v = malloc(sizeof(double) * 3 * n);
    h.L = malloc(sizeof(double) * 3 * n);
    h.w = malloc(sizeof(double) * 3 * n);
    h.wall_force = calloc(3 * ((size_t)m->nwall + 1), sizeof(double));
    if (!h.x || !h.q || !h.v || !h.L || !h.w || !h.wall_force) {
        rc = pd_error_set(err, PD_ENOMEM, "run: out of memory for %zu particles", n);
        goto done;
    }
    if ((rc = open_result(m, opt, &w, err)) != PD_OK) goto done;

    long long steps = sc_steps(s->duration, s->dt);
    long long stats_every = sc_steps_per(s->stats_interval, s->dt);
    long long frame_every = sc_steps_per(s->output_interval, s->dt);
    pr.steps_total = steps;
    pr.sim_duration = (double)steps * s->dt;
    pr.particles = m->n;
    double interval = opt->progress_interval > 0 ? opt->progress_interval : 0.5;
    double last_report = now_seconds(), rate_t0 = last_report;
    energy_budget budget = {0, 0, 0, 0, 0};
    double ke0 = 0;
    int cohesive = 0;
    for (int i = 0; i < s->nint; i++)
        cohesive |= s->inter[i].cohesion > 0;
    long long rate_s0 = 0;

    /* The steps that end at a stats row are timed stage by stage (the device finishing after
     * each) for /stats/stage_time; the others run unsynchronised. */
    if ((rc = timed_steps(m, 1, err)) != PD_OK || (rc = sim_forces(m, err)) != PD_OK) goto done;
    for (long long step = 0;; step++) {
        int stats_due = step % stats_every == 0 || step == steps;
        int frame_due = step % frame_every == 0 || step == steps;
        double t = (double)step * s->dt;
        if (stats_due || frame_due) {
            int worst = 0;
            double ke;
            if ((rc = sim_stats_energy(m, &ke, &worst, err)) != PD_OK) goto done;
            if (step == 0) ke0 = ke; /* the budget needs the contacts, counted below */
            if (!isfinite(ke) || (step > 0 && ke > energy_bound(&budget, t))) {
                rc = pd_error_set(err, PD_EDIVERGED,
                                  "run diverged at step %lld (t = %.6g s): %s; particle %d has "
                                  "the largest kinetic energy. Reduce dt (now %g s) or check "
                                  "stiffness and damping",
                                  step, t,
                                  isfinite(ke) ? "kinetic energy ran away past 10x what the "
                                                 "scenario can supply"
                                               : "kinetic energy is not finite",
                                  worst, s->dt);
                goto done;
            }
            pr.kinetic_energy = ke;
        }
        if (stats_due) {
            long contacts;
            double ratio;
            rc = sim_stats_contacts(m, &contacts, &ratio, h.wall_force, err);
            if (rc != PD_OK) goto done;
            if (step == 0) budget = energy_of(m, ke0, contacts > 0 || cohesive);
            pr.contacts = contacts;
            pr.broad_pairs = m->npairs;
            rc = rh5_write_stats(w, t, step, pr.kinetic_energy, contacts, m->npairs, ratio,
                                 now_seconds() - t_start, m->nwall ? h.wall_force : NULL,
                                 m->stage_seconds, err);
            if (rc != PD_OK) goto done;
        }
        if (frame_due) {
            if ((rc = read_frame(m, &h, err)) != PD_OK) goto done;
            rc = rh5_write_frame(w, t, step, h.x, h.q, h.v, h.w, err);
            if (rc != PD_OK) goto done;
            pr.frames++;
        }
        pr.step = step;
        pr.sim_time = t;
        pr.fraction = steps > 0 ? (double)step / (double)steps : 1;
        double tn = now_seconds();
        pr.wall_seconds = tn - t_start;
        int cancel = opt->cancel && *opt->cancel;
        if (tn - last_report >= interval || step == steps) {
            if (tn > rate_t0 && step > rate_s0) {
                pr.steps_per_second = (double)(step - rate_s0) / (tn - rate_t0);
                pr.eta_seconds = (double)(steps - step) / pr.steps_per_second;
            }
            rate_t0 = tn;
            rate_s0 = step;
            last_report = tn;
            if (opt->progress && opt->progress(&pr, opt->user)) cancel = 1;
        }
        if (step == steps) break;
        if (cancel) {
            rc =
                pd_error_set(err, PD_ECANCELLED, "run cancelled at step %lld of %lld", step, steps);
            goto done;
        }
        int bad = -1;
        rc = timed_steps(m, (step + 1) % stats_every == 0 || step + 1 == steps, err);
        if (rc != PD_OK || (rc = sim_step(m, &bad, err)) != PD_OK) goto done;
        if (bad >= 0) {
            rc = pd_error_set(err, PD_EDIVERGED,
                              "run diverged at step %lld (t = %.6g s): particle %d has a "
                              "position, velocity or angular momentum that is not finite. Reduce "
                              "dt (now %g s) or check the material parameters",
                              step + 1, (double)(step + 1) * s->dt, bad, s->dt);
            goto done;
        }
    }
    rc = rh5_close(w, err);
    w = NULL;
done:
    if (w && rc != PD_OK && rh5_frames(w) > 0) {
        /* Stopped early (cancelled, diverged, a device error): the frames written so far are
         * sound (a divergence is caught before its frame is written), and a user who stops a
         * long run wants them. The file says so in its root attribute status. After a failed
         * write the writer keeps them in the .partial if it can (result_kept stays 0: output
         * path holds nothing), and its error replaces ours: it restates ours and says where. */
        pd_error ferr = {0};
        int broken = rh5_broken(w);
        pr.result_kept = rh5_finish(w, pd_run_status(rc), err ? err->msg : NULL, &ferr) == PD_OK;
        w = NULL;
        if (!pr.result_kept && err) {
            if (broken) { /* ferr restates the failed write and says what became of its frames */
                snprintf(err->msg, sizeof err->msg, "%s", ferr.msg);
            } else {
                size_t len = strlen(err->msg);
                snprintf(err->msg + len, sizeof err->msg - len, "; %s", ferr.msg);
            }
        }
    }
    if (w) rh5_abort(w);
    pr.wall_seconds = now_seconds() - t_start;
    if (final) *final = pr;
    host_free(&h);
    sim_destroy(m);
    return rc;
}
