/*
 * selftest.c - pd_device_selftest: does this device compute what the host computes, and what the
 * physics says? Seed 004 section 5.3.3 recommends checking heterogeneous devices before trusting
 * them; the daemon runs this at start and on GET /v1/device?selftest=1.
 *
 *  1. every embedded program builds (single, and double where the device has cl_khr_fp64);
 *  2. the overlap kernel on non-convex pairs (Schonhardt, rock) at several poses agrees with the
 *     host build of the same code: 1e-9 relative in double (the two compile one source with
 *     contraction off; only libm differences remain), 1e-3 in single;
 *  3. two analytic spheres (Hertz, no damping) collide head-on through the whole device
 *     pipeline; the contact time and peak overlap agree with Hertz theory (Johnson 1985,
 *     section 11.4): t_c = 2.8683 (m*^2 / (R* E*^2 v))^(1/5), delta_max = (15 m* v^2 /
 *     (16 E* sqrt(R*)))^(2/5), to 2% and 1% (dt = t_c / 200 resolves both to ~0.5%).
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "sim.h"

static int overlap_check(pd_device *dev, int dbl, double *worst, pd_error *err)
{
    static const char *const shapes[2][2] = {{"builtin:schonhardt", "builtin:schonhardt"},
                                             {"builtin:rock:80:3", "builtin:schonhardt"}};
    static const double poses[3][7] = {{0.6, 0.2, 0.1, 0.9, 0.1, 0.3, 0.2},
                                       {0.3, -0.5, 0.4, 0.5, 0.5, -0.5, 0.5},
                                       {0.1, 0.1, 0.9, 0.2, 0.9, 0.1, -0.3}};
    *worst = 0;
    for (int s = 0; s < 2; s++) {
        pd_mesh *a = NULL, *b = NULL;
        int rc = pd_mesh_open(shapes[s][0], &a, err);
        if (rc == PD_OK) rc = pd_mesh_open(shapes[s][1], &b, err);
        for (int p = 0; p < 3 && rc == PD_OK; p++) {
            pd_pose pa = {{0, 0, 0}, {1, 0, 0, 0}}, pb;
            memcpy(pb.x, poses[p], sizeof pb.x);
            memcpy(pb.q, poses[p] + 3, sizeof pb.q);
            int flags = dbl ? 0 : PD_OVERLAP_SINGLE;
            pd_contact h, d;
            rc = pd_overlap_host(a, &pa, b, &pb, flags, &h, err);
            if (rc == PD_OK) rc = pd_overlap_cl(dev, a, &pa, b, &pb, flags, &d, err);
            if (rc != PD_OK) break;
            double scale = h.volume > 0 ? h.volume : 1e-30;
            double rel = fabs(h.volume - d.volume) / scale;
            if (h.hit != d.hit) rel = 1;
            if (rel > *worst) *worst = rel;
        }
        pd_mesh_destroy(a);
        pd_mesh_destroy(b);
        if (rc != PD_OK) return rc;
    }
    return PD_OK;
}

/* Two spheres of radius R, E, nu, density rho approaching at v each: contact time and peak
 * overlap measured on the device. */
static int hertz_check(pd_device *dev, int dbl, double *tc_err, double *dmax_err, pd_error *err)
{
    const double R = 0.01, E = 1e7, nu = 0.25, rho = 2500, v = 0.5;
    const double PI = 3.14159265358979323846;
    double m = rho * 4.0 / 3.0 * PI * R * R * R, mstar = m / 2, rstar = R / 2;
    double estar = E / (2 * (1 - nu * nu)), vrel = 2 * v;
    double tc = 2.8683 * pow(mstar * mstar / (rstar * estar * estar * vrel), 0.2);
    double dmax = pow(15 * mstar * vrel * vrel / (16 * estar * sqrt(rstar)), 0.4);
    double dt = tc / 200;
    char json[1400];
    snprintf(json, sizeof json,
             "{\"name\": \"selftest\", \"precision\": \"%s\", \"allow_unstable_dt\": true,"
             " \"time\": {\"dt\": %.17g, \"duration\": %.17g, \"output_interval\": 1},"
             " \"gravity\": [0, 0, 0],"
             " \"materials\": {\"m\": {\"density\": %g, \"youngs_modulus\": %g,"
             " \"poisson_ratio\": %g}},"
             " \"interactions\": [{\"between\": [\"m\", \"m\"], \"friction\": 0}],"
             " \"shapes\": {\"ball\": {\"sphere\": {}}},"
             " \"particles\": [{\"shape\": \"ball\", \"material\": \"m\", \"list\": ["
             " {\"position\": [0, 0, 0], \"velocity\": [%g, 0, 0], \"size\": %g},"
             " {\"position\": [%.17g, 0, 0], \"velocity\": [%g, 0, 0], \"size\": %g}]}]}",
             dbl ? "double" : "single", dt, 3 * tc, rho, E, nu, v, 2 * R, 2 * R + 2 * v * dt * 10,
             -v, 2 * R);
    pd_scenario *s = NULL;
    pd_diags diags = {0, 0, NULL};
    int rc = pd_scenario_parse(json, NULL, &s, &diags, err);
    pd_diags_free(&diags);
    if (rc != PD_OK) return rc;
    sim *sm = NULL;
    rc = sim_create(dev, s, &sm, err);
    int touching_steps = 0, nsteps = (int)(3 * tc / dt);
    double peak = 0, x[6];
    if (rc == PD_OK) rc = sim_forces(sm, err);
    for (int i = 0; i < nsteps && rc == PD_OK; i++) {
        int bad;
        rc = sim_step(sm, &bad, err);
        if (rc == PD_OK) rc = sim_read(sm, sm->x, 0, 6, x, err);
        if (rc != PD_OK) break;
        double d = 2 * R - fabs(x[3] - x[0]);
        if (d > 0) touching_steps++;
        if (d > peak) peak = d;
    }
    sim_destroy(sm);
    pd_scenario_destroy(s);
    if (rc != PD_OK) return rc;
    *tc_err = fabs(touching_steps * dt - tc) / tc;
    *dmax_err = fabs(peak - dmax) / dmax;
    return PD_OK;
}

int pd_device_selftest(pd_device *dev, char *report, size_t report_len, pd_error *err)
{
    char local[2];
    if (!report) {
        report = local;
        report_len = sizeof local;
    }
    report[0] = 0;
    int rc = pd_device_compile_all(dev, err);
    if (rc != PD_OK) {
        snprintf(report, report_len, "FAIL %s: %s", dev->name, err ? err->msg : "build failed");
        return rc;
    }
    int dbl = dev->fp64;
    double ovl, tce, dme;
    const double ovl_tol = dbl ? 1e-9 : 1e-3;
    rc = overlap_check(dev, dbl, &ovl, err);
    if (rc == PD_OK) rc = hertz_check(dev, dbl, &tce, &dme, err);
    if (rc != PD_OK) {
        snprintf(report, report_len, "FAIL %s: %s", dev->name, err ? err->msg : "error");
        return rc;
    }
    int pass = ovl <= ovl_tol && tce <= 0.02 && dme <= 0.01;
    snprintf(report, report_len,
             "%s %s (%s): programs build; overlap kernel vs host %.2g relative (limit %.0g); "
             "Hertz sphere collision: contact time off by %.2g%%, peak overlap by %.2g%% "
             "(limits 2%%, 1%%)",
             pass ? "PASS" : "FAIL", dev->name, dbl ? "double" : "single", ovl, ovl_tol, 100 * tce,
             100 * dme);
    if (!pass) return pd_error_set(err, PD_ECL, "device self-test failed: %s", report);
    return PD_OK;
}
