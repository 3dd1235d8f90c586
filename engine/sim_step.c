/*
 * sim_step.c - the stages of one time step on the device (see sim.h): integration, broad phase,
 * narrow phase and forces, gather. Deterministic: no floating-point atomics anywhere, every
 * order fixed by keys, so a run repeats bit for bit on one device.
 */
#include <limits.h>
#include <string.h>
#include <time.h>

#include "sim.h"

static double clock_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Profiling: ends a stage (waits for the device) and books its time since *t0. */
static void stage_end(sim *m, int stage, double *t0)
{
    if (!m->profile) return;
    clFinish(m->dev->queue);
    double t = clock_now();
    m->stage_seconds[stage] += t - *t0;
    *t0 = t;
}

/* Sets a pd_real argument in the device's precision. */
static cl_int arg_real(sim *m, cl_kernel k, int i, double v)
{
    float f = (float)v;
    return m->dbl ? clSetKernelArg(k, (cl_uint)i, sizeof v, &v)
                  : clSetKernelArg(k, (cl_uint)i, sizeof f, &f);
}

cl_int sim_body_box_args(sim *m, cl_kernel k, int first)
{
    cl_int e = CL_ARG(k, first, m->x);
    e |= CL_ARG(k, first + 1, m->size);
    e |= CL_ARG(k, first + 2, m->shape);
    e |= CL_ARG(k, first + 3, m->radius_ratio);
    e |= arg_real(m, k, first + 4, m->margin + 0.5 * m->skin); /* the skin: see reuse_pairs */
    return e;
}

/*
 * Capacity for `need` pairs. Arrays grow only when a list is rebuilt, and their old contents are
 * not copied (the state was carried out first), so growing costs an allocation: 1/8 headroom
 * means a packing whose pairs triple reallocates about ten times. The 64 spare slots keep tiny
 * runs from reallocating every few pairs; 1 024 cost a 1e3-particle bed ~38 bytes a particle.
 */
static size_t pair_capacity(size_t need)
{
    return need + need / 8 + 64;
}

/* (Re)allocates a set of pair arrays for `need` pairs, discarding its contents. */
static int grow_pairs(sim *m, sim_pairs *p, size_t need, const char *what, pd_error *err)
{
    if (need <= p->cap && p->keys) return PD_OK;
    size_t cap = pair_capacity(need);
    cl_int e = CL_SUCCESS;
    cl_context ctx = m->dev->ctx;
    /* key, spring, kt; the twist with contact moments, the point in single precision */
    m->bytes += (double)(cap - p->cap) *
                (sizeof(cl_ulong) + (4 + (m->moments ? 1 : 0) + (m->dbl ? 0 : 3)) * m->rs);
    if (p->keys) clReleaseMemObject(p->keys);
    if (p->spring) clReleaseMemObject(p->spring);
    if (p->kt) clReleaseMemObject(p->kt);
    if (p->point) clReleaseMemObject(p->point);
    if (p->twist) clReleaseMemObject(p->twist);
    p->keys = p->spring = p->kt = p->point = p->twist = NULL;
    p->cap = 0;
    p->keys = clCreateBuffer(ctx, CL_MEM_READ_WRITE, sizeof(cl_ulong) * cap, NULL, &e);
    if (e == CL_SUCCESS)
        p->spring = clCreateBuffer(ctx, CL_MEM_READ_WRITE, m->rs * 3 * cap, NULL, &e);
    if (e == CL_SUCCESS) p->kt = clCreateBuffer(ctx, CL_MEM_READ_WRITE, m->rs * cap, NULL, &e);
    if (e == CL_SUCCESS && !m->dbl)
        p->point = clCreateBuffer(ctx, CL_MEM_READ_WRITE, m->rs * 3 * cap, NULL, &e);
    if (e == CL_SUCCESS && m->moments)
        p->twist = clCreateBuffer(ctx, CL_MEM_READ_WRITE, m->rs * cap, NULL, &e);
    if (e != CL_SUCCESS) return CL_FAIL(err, what, e);
    p->cap = cap;
    return PD_OK;
}

/* Grows the pair arrays to hold npairs (their state has been carried out by keep_history). */
static int ensure_pairs(sim *m, int npairs, pd_error *err)
{
    size_t need = (size_t)npairs;
    cl_int e = CL_SUCCESS;
    cl_context ctx = m->dev->ctx;
    int rc = grow_pairs(m, &m->pairs, need, "clCreateBuffer(contact pairs)", err);
    if (rc != PD_OK) return rc;
    if (need > m->work_cap || !m->force) {
        size_t cap = pair_capacity(need);
        cl_mem *b[] = {&m->force, &m->torque, &m->info, &m->second_list};
        size_t sz[] = {m->rs * 3, m->rs * 3, sizeof(float), sizeof(int)}; /* info: floats */
        m->bytes += (double)(cap - m->work_cap) * (6 * m->rs + sizeof(float) + sizeof(int));
        m->work_cap = 0;
        for (size_t i = 0; i < sizeof b / sizeof b[0]; i++) {
            if (*b[i]) clReleaseMemObject(*b[i]);
            *b[i] = NULL;
        }
        for (size_t i = 0; i < sizeof b / sizeof b[0] && e == CL_SUCCESS; i++)
            *b[i] = clCreateBuffer(ctx, CL_MEM_READ_WRITE, sz[i] * cap, NULL, &e);
        if (e != CL_SUCCESS) return CL_FAIL(err, "clCreateBuffer(contact work)", e);
        m->work_cap = cap;
    }
    return PD_OK;
}

/* The divergence and wall flags the kernels set (status[1], status[2]): an error for the latter. */
static int check_status(sim *m, pd_error *err)
{
    if (m->status_host[2] != INT_MAX) { /* last step's contacts: a wall too fine near a particle */
        int code = m->status_host[2], wi = code % m->nwall;
        return pd_error_set(err, PD_EINVAL,
                            "run: step %lld: wall '%s' has more than %d triangles within the "
                            "bounding cube of particle %d, beyond the bound computed from its "
                            "mesh at the start (a particle far from the origin?)",
                            m->step, m->s->wall[wi].name, m->wall_cap, code / m->nwall);
    }
    return PD_OK;
}

/*
 * The last step's pair list again, when no particle has moved half the skin since it was built
 * (status[0], set by the drift): the same keys in the same order, each pair's state where the
 * last step left it. Returns 1 when reused, 0 when the list must be built, or an error.
 */
static int reuse_pairs(sim *m, pd_error *err)
{
    pd_device *dev = m->dev;
    if (!m->list_valid) return 0;
    /* walls' boxes carry skin / 2 too: the list holds while no wall has moved that far either
     * (a ten-millionth taken off for the rounding of the times) */
    if (m->walls_move &&
        m->wall_speed * (m->wall_time - m->built_wall_time) >= 0.5 * m->skin * (1 - 1e-7))
        return 0;
    cl_int e = clEnqueueReadBuffer(dev->queue, m->status, CL_TRUE, 0, sizeof m->status_host,
                                   m->status_host, 0, NULL, NULL);
    if (e != CL_SUCCESS) return CL_FAIL(err, "clEnqueueReadBuffer(status)", e);
    int rc = check_status(m, err);
    if (rc != PD_OK) return rc;
    return m->status_host[0] ? 0 : 1;
}

/*
 * Before the list is rebuilt: the old list's pairs that carry state (ch_has_state), copied in
 * key order into m->carry with per-particle offsets (carry_offset), where the new list's pairs
 * find theirs. Uses m->count, which the traversal overwrites next.
 */
static int keep_history(sim *m, pd_error *err)
{
    pd_device *dev = m->dev;
    int n = m->n, rc;
    cl_int e = CL_SUCCESS;
    if (m->npairs == 0) { /* nothing to carry: every particle's segment is empty */
        int zero = 0;
        e = clEnqueueFillBuffer(dev->queue, m->carry_offset, &zero, sizeof zero, 0,
                                sizeof(int) * ((size_t)n + 1), 0, NULL, NULL);
        if (e != CL_SUCCESS) return CL_FAIL(err, "clEnqueueFillBuffer(carry offsets)", e);
        return grow_pairs(m, &m->carry, 0, "clCreateBuffer(carried pairs)", err);
    }
    cl_kernel k = m->k_hist_count;
    e |= CL_ARG(k, 0, m->offset);
    e |= CL_ARG(k, 1, m->pairs.spring);
    e |= CL_ARG(k, 2, m->pairs.kt);
    e |= CL_ARG(k, 3, m->pairs.twist);
    e |= CL_ARG(k, 4, n);
    e |= CL_ARG(k, 5, m->count);
    if (e != CL_SUCCESS) return CL_ARG_FAIL(err, "history_count");
    if ((rc = cl_launch(dev, k, (size_t)n, "history_count", err)) != PD_OK) return rc;
    if ((rc = dsort_scan(&m->sort, m->count, n, m->carry_offset, err)) != PD_OK) return rc;
    cl_int total = 0;
    e = clEnqueueReadBuffer(dev->queue, m->carry_offset, CL_TRUE, sizeof(int) * (size_t)n,
                            sizeof total, &total, 0, NULL, NULL);
    if (e != CL_SUCCESS) return CL_FAIL(err, "clEnqueueReadBuffer(carried pair count)", e);
    rc = grow_pairs(m, &m->carry, (size_t)total, "clCreateBuffer(carried pairs)", err);
    if (rc != PD_OK) return rc;
    k = m->k_hist_keep;
    e |= CL_ARG(k, 0, m->offset);
    e |= CL_ARG(k, 1, m->pairs.keys);
    e |= CL_ARG(k, 2, m->pairs.spring);
    e |= CL_ARG(k, 3, m->pairs.kt);
    e |= CL_ARG(k, 4, m->pairs.point);
    e |= CL_ARG(k, 5, m->pairs.twist);
    e |= CL_ARG(k, 6, n);
    e |= CL_ARG(k, 7, m->carry_offset);
    e |= CL_ARG(k, 8, m->carry.keys);
    e |= CL_ARG(k, 9, m->carry.spring);
    e |= CL_ARG(k, 10, m->carry.kt);
    e |= CL_ARG(k, 11, m->carry.point);
    e |= CL_ARG(k, 12, m->carry.twist);
    if (e != CL_SUCCESS) return CL_ARG_FAIL(err, "history_keep");
    if ((rc = cl_launch(dev, k, (size_t)n, "history_keep", err)) != PD_OK) return rc;
    return PD_OK;
}

/* After a build: its positions are the reference the skin and the travel are measured from. */
static int list_built(sim *m, pd_error *err)
{
    int zero = 0;
    cl_int e = clEnqueueCopyBuffer(m->dev->queue, m->x, m->x_ref, 0, 0, m->rs * 3 * (size_t)m->n, 0,
                                   NULL, NULL);
    if (e == CL_SUCCESS)
        e = clEnqueueFillBuffer(m->dev->queue, m->status, &zero, sizeof zero, 0, sizeof zero, 0,
                                NULL, NULL);
    if (e == CL_SUCCESS) e = sim_zero_reals(m, m->travel, (size_t)m->n);
    if (e != CL_SUCCESS) return CL_FAIL(err, "clEnqueueCopyBuffer(reference positions)", e);
    m->list_valid = 1;
    m->builds++;
    /* how long lists last, smoothed: certificates (contact.cl) die with their list */
    if (m->builds > 1) m->list_life = 0.5 * m->list_life + 0.5 * (double)(m->step - m->built_at);
    m->built_at = m->step;
    m->built_wall_time = m->wall_time;
    return PD_OK;
}

/* The arguments broad_count and broad_write share: the tree, the bodies' boxes, the walls'. */
static cl_int traversal_args(sim *m, cl_kernel k)
{
    cl_int e = CL_ARG(k, 0, m->tbox);
    e |= CL_ARG(k, 1, m->left);
    e |= CL_ARG(k, 2, m->right);
    e |= CL_ARG(k, 3, m->idx);
    e |= CL_ARG(k, 4, m->n);
    e |= sim_body_box_args(m, k, 5);
    e |= CL_ARG(k, 10, m->wbox);
    e |= CL_ARG(k, 11, m->nwall);
    return e;
}

/* Broad phase: boxes, tree, traversal; leaves the step's sorted pair keys in m->pairs.keys. */
static int broad_phase(sim *m, double *t0, pd_error *err)
{
    pd_device *dev = m->dev;
    int n = m->n, rc = reuse_pairs(m, err);
    m->list_fresh = rc == 0;
    if (rc != 0) { /* reused (1) or an error */
        stage_end(m, SIM_TRAVERSE, t0);
        return rc == 1 ? PD_OK : rc;
    }
    if ((rc = keep_history(m, err)) != PD_OK) return rc;
    cl_int e = CL_SUCCESS;
    /* the top 32 bits of the 63-bit Morton codes (10-11 bits per axis, 1/2048 of the scene
     * box): four radix passes instead of eight; equal codes are ordered by index (Karras) */
    int morton_drop = 31;

    /* small runs: the traversal kernels test every pair of boxes instead of building a tree */
    int brute = n <= SIM_BRUTE_MAX;
    if (!brute) {
        e |= CL_ARG(m->k_codes, 0, m->x);
        e |= CL_ARG(m->k_codes, 1, n);
        for (int k = 0; k < 3; k++) {
            e |= arg_real(m, m->k_codes, 2 + k, m->lo[k]);
            e |= arg_real(m, m->k_codes, 5 + k, m->inv_ext[k]);
        }
        e |= CL_ARG(m->k_codes, 8, m->codes);
        e |= CL_ARG(m->k_codes, 9, m->idx);
        e |= CL_ARG(m->k_codes, 10, morton_drop);
        if (e != CL_SUCCESS) return CL_ARG_FAIL(err, "bvh_codes");
        if ((rc = cl_launch(dev, m->k_codes, (size_t)n, "bvh_codes", err)) != PD_OK) return rc;
        static const int morton_shifts[4] = {0, 8, 16, 24}; /* codes of 32 bits (morton_drop) */
        /* an even number of passes leaves the results in codes and idx, and the scratch in the
         * arrays it borrows (sim_create: t and second_count) */
        _Static_assert(sizeof morton_shifts / sizeof morton_shifts[0] % 2 == 0,
                       "radix passes must be even");
        rc = dsort_radix(&m->sort, &m->codes, &m->idx, &m->codes_tmp, &m->idx_tmp, n, morton_shifts,
                         4, err);
        if (rc != PD_OK) return rc;

        e |= sim_body_box_args(m, m->k_leaves, 0);
        e |= CL_ARG(m->k_leaves, 5, m->idx);
        e |= CL_ARG(m->k_leaves, 6, n);
        e |= CL_ARG(m->k_leaves, 7, m->tbox);
        e |= CL_ARG(m->k_nodes, 0, m->codes);
        e |= CL_ARG(m->k_nodes, 1, n);
        e |= CL_ARG(m->k_nodes, 2, m->left);
        e |= CL_ARG(m->k_nodes, 3, m->right);
        e |= CL_ARG(m->k_nodes, 4, m->parent);
        e |= CL_ARG(m->k_refit, 0, m->tbox);
        e |= CL_ARG(m->k_refit, 1, m->left);
        e |= CL_ARG(m->k_refit, 2, m->right);
        e |= CL_ARG(m->k_refit, 3, m->parent);
        e |= CL_ARG(m->k_refit, 4, n);
        e |= CL_ARG(m->k_refit, 5, m->arrivals);
        if (e != CL_SUCCESS) return CL_ARG_FAIL(err, "bvh_leaves/bvh_nodes/bvh_refit");
        if ((rc = cl_launch(dev, m->k_leaves, (size_t)n, "bvh_leaves", err)) != PD_OK) return rc;
        if (n > 1) {
            if ((rc = cl_launch(dev, m->k_nodes, (size_t)n - 1, "bvh_nodes", err)) != PD_OK)
                return rc;
            int zero = 0;
            e = clEnqueueFillBuffer(dev->queue, m->arrivals, &zero, sizeof zero, 0,
                                    sizeof(int) * (size_t)(n - 1), 0, NULL, NULL);
            if (e != CL_SUCCESS) return CL_FAIL(err, "clEnqueueFillBuffer", e);
            if ((rc = cl_launch(dev, m->k_refit, (size_t)n, "bvh_refit", err)) != PD_OK) return rc;
        }
    }
    stage_end(m, SIM_BVH, t0);
    e |= traversal_args(m, m->k_count);
    e |= CL_ARG(m->k_count, 12, m->count);
    e |= CL_ARG(m->k_count, 13, m->cand);
    e |= CL_ARG(m->k_count, 14, brute);
    if (e != CL_SUCCESS) return CL_ARG_FAIL(err, "broad_count");
    if ((rc = cl_launch(dev, m->k_count, (size_t)n, "broad_count", err)) != PD_OK) return rc;
    if ((rc = dsort_scan(&m->sort, m->count, n, m->offset, err)) != PD_OK) return rc;
    /* the one value the host needs every step; the divergence flag comes with it */
    cl_int total = 0;
    e = clEnqueueReadBuffer(dev->queue, m->status, CL_FALSE, 0, sizeof m->status_host,
                            m->status_host, 0, NULL, NULL);
    if (e == CL_SUCCESS)
        e = clEnqueueReadBuffer(dev->queue, m->offset, CL_TRUE, sizeof(int) * (size_t)n,
                                sizeof total, &total, 0, NULL, NULL);
    if (e != CL_SUCCESS) return CL_FAIL(err, "clEnqueueReadBuffer(pair count)", e);
    if (total < 0) return pd_error_set(err, PD_ENOMEM, "run: more than 2^31 candidate pairs");
    if ((rc = check_status(m, err)) != PD_OK) return rc;
    if ((rc = ensure_pairs(m, total, err)) != PD_OK) return rc;
    m->npairs = total;

    e |= traversal_args(m, m->k_write);
    e |= CL_ARG(m->k_write, 12, m->offset);
    e |= CL_ARG(m->k_write, 13, m->cand);
    e |= CL_ARG(m->k_write, 14, m->second_list); /* scratch until the gather lists into it */
    e |= CL_ARG(m->k_write, 15, m->pairs.keys);
    e |= CL_ARG(m->k_write, 16, brute);
    if (e != CL_SUCCESS) return CL_ARG_FAIL(err, "broad_write");
    rc = cl_launch(dev, m->k_write, (size_t)n, "broad_write", err);
    if (rc == PD_OK) rc = list_built(m, err);
    stage_end(m, SIM_TRAVERSE, t0);
    return rc;
}

/* Narrow phase and contact forces with history over the step's pairs. */
static int contacts(sim *m, pd_error *err)
{
    cl_kernel k = m->k_contact;
    int a = 0, nwork = m->npairs < m->nwork ? m->npairs : m->nwork;
    cl_int e = CL_SUCCESS;
    e |= CL_ARG(k, a++, m->pairs.keys);
    e |= CL_ARG(k, a++, m->npairs);
    e |= CL_ARG(k, a++, m->list_fresh);
    e |= CL_ARG(k, a++, m->carry.keys);
    e |= CL_ARG(k, a++, m->carry_offset);
    e |= CL_ARG(k, a++, m->carry.spring);
    e |= CL_ARG(k, a++, m->carry.kt);
    e |= CL_ARG(k, a++, m->carry.point);
    e |= CL_ARG(k, a++, m->carry.twist);
    cl_mem bodies[] = {m->x,      m->q,     m->v,     m->L,        m->w,
                       m->size,   m->inv_m, m->shape, m->material, m->unit_inertia,
                       m->density};
    for (size_t i = 0; i < sizeof bodies / sizeof bodies[0]; i++)
        e |= CL_ARG(k, a++, bodies[i]);
    /* the shapes (vc, coff, disc: the filter's vertex clusters) and the materials' parameters */
    cl_mem shapes[] = {m->vert, m->tri,  m->voff, m->toff, m->vt_off,       m->vt,
                       m->vc,   m->coff, m->disc, m->kind, m->radius_ratio, m->params};
    for (size_t i = 0; i < sizeof shapes / sizeof shapes[0]; i++)
        e |= CL_ARG(k, a++, shapes[i]);
    e |= CL_ARG(k, a++, m->nmat);
    e |= CL_ARG(k, a++, m->n);
    e |= arg_real(m, k, a++, m->dt);
    cl_mem trees[] = {m->wnode_box, m->wnode_kid, m->wnode_off, m->wtri_order};
    for (size_t i = 0; i < sizeof trees / sizeof trees[0]; i++)
        e |= CL_ARG(k, a++, trees[i]);
    e |= CL_ARG(k, a++, m->wall_cap);
    e |= CL_ARG(k, a++, m->nwall);
    e |= CL_ARG(k, a++, m->status);
    e |= CL_ARG(k, a++, m->iscr);
    e |= CL_ARG(k, a++, m->rscr);
    e |= CL_ARG(k, a++, m->ilen);
    e |= CL_ARG(k, a++, m->rlen);
    e |= CL_ARG(k, a++, m->pts_cap);
    e |= CL_ARG(k, a++, nwork);
    e |= CL_ARG(k, a++, m->travel);
    /* surfaces' gaps (cp_mesh_gap) certified up to the skin, a list's reach */
    e |= arg_real(m, k, a++, m->skin);
    e |= arg_real(m, k, a++, m->list_life);
    cl_mem outs[] = {m->force,    m->pairs.point, m->torque, m->pairs.spring,
                     m->pairs.kt, m->pairs.twist, m->info};
    for (size_t i = 0; i < sizeof outs / sizeof outs[0]; i++)
        e |= CL_ARG(k, a++, outs[i]);
    if (e != CL_SUCCESS) return CL_ARG_FAIL(err, "contact_forces");
    return cl_launch(m->dev, k, (size_t)nwork, "contact_forces", err);
}

/* Each particle's contacts as second body, counted and listed (after a list is built). */
static int second_lists(sim *m, pd_error *err)
{
    int rc, np = m->npairs, n = m->n;
    int zero = 0;
    cl_int e = clEnqueueFillBuffer(m->dev->queue, m->second_count, &zero, sizeof zero, 0,
                                   sizeof(int) * (size_t)n, 0, NULL, NULL);
    if (e != CL_SUCCESS) return CL_FAIL(err, "clEnqueueFillBuffer", e);
    e |= CL_ARG(m->k_second_count, 0, m->pairs.keys);
    e |= CL_ARG(m->k_second_count, 1, np);
    e |= CL_ARG(m->k_second_count, 2, n);
    e |= CL_ARG(m->k_second_count, 3, m->second_count);
    e |= CL_ARG(m->k_second_fill, 0, m->pairs.keys);
    e |= CL_ARG(m->k_second_fill, 1, np);
    e |= CL_ARG(m->k_second_fill, 2, n);
    e |= CL_ARG(m->k_second_fill, 3, m->second_off);
    e |= CL_ARG(m->k_second_fill, 4, m->second_count);
    e |= CL_ARG(m->k_second_fill, 5, m->second_list);
    if (e != CL_SUCCESS) return CL_ARG_FAIL(err, "second_count/second_fill");
    rc = cl_launch(m->dev, m->k_second_count, (size_t)np, "second_count", err);
    if (rc == PD_OK) rc = dsort_scan(&m->sort, m->second_count, n, m->second_off, err);
    if (rc != PD_OK) return rc;
    /* the counts become the fill cursors */
    e = clEnqueueFillBuffer(m->dev->queue, m->second_count, &zero, sizeof zero, 0,
                            sizeof(int) * (size_t)n, 0, NULL, NULL);
    if (e != CL_SUCCESS) return CL_FAIL(err, "clEnqueueFillBuffer", e);
    return cl_launch(m->dev, m->k_second_fill, (size_t)np, "second_fill", err);
}

/* Per-particle sums: the gather kernel, over second-body lists kept while the list is. */
static int gather(sim *m, pd_error *err)
{
    int rc;
    if (m->list_fresh && (rc = second_lists(m, err)) != PD_OK) return rc;
    const pd_scenario *s = m->s;
    cl_kernel k = m->k_body;
    cl_int e = CL_SUCCESS;
    int a = 0;
    e |= CL_ARG(k, a++, m->offset);
    e |= CL_ARG(k, a++, m->second_off);
    e |= CL_ARG(k, a++, m->second_list);
    e |= CL_ARG(k, a++, m->pairs.keys);
    e |= CL_ARG(k, a++, m->force);
    e |= CL_ARG(k, a++, m->torque);
    e |= CL_ARG(k, a++, m->x);
    e |= CL_ARG(k, a++, m->n);
    e |= CL_ARG(k, a++, m->inv_m);
    e |= CL_ARG(k, a++, m->size);
    e |= CL_ARG(k, a++, m->v);
    for (int c = 0; c < 3; c++)
        e |= arg_real(m, k, a++, s->gravity[c]);
    e |= arg_real(m, k, a++, s->has_fluid ? s->fluid_viscosity : 0);
    for (int c = 0; c < 3; c++)
        e |= arg_real(m, k, a++, s->has_fluid ? s->fluid_velocity[c] : 0);
    e |= CL_ARG(k, a++, m->f);
    e |= CL_ARG(k, a++, m->t);
    if (e != CL_SUCCESS) return CL_ARG_FAIL(err, "body_forces");
    return cl_launch(m->dev, k, (size_t)m->n, "body_forces", err);
}

int sim_forces(sim *m, pd_error *err)
{
    double t0 = m->profile ? clock_now() : 0;
    int rc = broad_phase(m, &t0, err);
    if (rc == PD_OK && m->npairs > 0) rc = contacts(m, err);
    stage_end(m, SIM_CONTACTS, &t0);
    if (rc == PD_OK) rc = gather(m, err);
    stage_end(m, SIM_GATHER, &t0);
    return rc;
}

static int kick(sim *m, pd_error *err)
{
    cl_kernel k = m->k_kick;
    cl_int e = CL_SUCCESS;
    e |= CL_ARG(k, 0, m->v);
    e |= CL_ARG(k, 1, m->L);
    e |= CL_ARG(k, 2, m->f);
    e |= CL_ARG(k, 3, m->t);
    e |= CL_ARG(k, 4, m->inv_m);
    e |= CL_ARG(k, 5, m->n);
    e |= arg_real(m, k, 6, 0.5 * m->dt);
    if (e != CL_SUCCESS) return CL_ARG_FAIL(err, "integrate_kick");
    return cl_launch(m->dev, k, (size_t)m->n, "integrate_kick", err);
}

int sim_step(sim *m, int *bad_particle, pd_error *err)
{
    cl_kernel k = m->k_drift;
    cl_int e = CL_SUCCESS;
    double t0 = m->profile ? clock_now() : 0;
    int rc = kick(m, err);
    if (rc != PD_OK) return rc;
    e |= CL_ARG(k, 0, m->x);
    e |= CL_ARG(k, 1, m->v);
    e |= CL_ARG(k, 2, m->q);
    e |= CL_ARG(k, 3, m->L);
    e |= CL_ARG(k, 4, m->material);
    e |= CL_ARG(k, 5, m->n);
    e |= arg_real(m, k, 6, m->dt);
    e |= CL_ARG(k, 7, m->status);
    e |= CL_ARG(k, 8, m->x_ref);
    e |= arg_real(m, k, 9, 0.25 * m->skin * m->skin);
    e |= CL_ARG(k, 10, m->size);
    e |= CL_ARG(k, 11, m->shape);
    e |= CL_ARG(k, 12, m->radius_ratio);
    e |= CL_ARG(k, 13, m->travel);
    e |= CL_ARG(k, 14, m->unit_inertia);
    e |= CL_ARG(k, 15, m->density);
    if (e != CL_SUCCESS) return CL_ARG_FAIL(err, "integrate_drift");
    if ((rc = cl_launch(m->dev, k, (size_t)m->n, "integrate_drift", err)) != PD_OK) return rc;
    if (m->walls_move && (rc = sim_walls_at(m, (double)(m->step + 1) * m->dt, err)) != PD_OK)
        return rc;
    stage_end(m, SIM_INTEGRATE, &t0);
    if ((rc = sim_forces(m, err)) != PD_OK) return rc;
    t0 = m->profile ? clock_now() : 0;
    if ((rc = kick(m, err)) != PD_OK) return rc;
    stage_end(m, SIM_INTEGRATE, &t0);
    m->step++;
    *bad_particle = m->status_host[1] != INT_MAX ? m->status_host[1] : -1;
    return PD_OK;
}
