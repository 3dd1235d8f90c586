/*
 * repose_fit.c - the repose angle of a pile from its height map (thesis section 6.3, eq. 6.1).
 *
 *   repose_fit [FILE]    reads "x h" pairs (m), one bin a line, from FILE or stdin; '#' starts
 *                        a comment
 *
 * Fits h(x) = c / (1 + exp(a (x - b))) by nonlinear least squares (GSL's multifit_nlinear,
 * trust region with Levenberg-Marquardt steps, analytic Jacobian) and prints one line of JSON:
 * {"a": 1/m, "b": m, "c": m, "angle_deg": the repose angle, "rms_m": the fit's residual,
 * "bins": n, "status": GSL's message}. The angle is the steepest slope of the fitted sigmoid,
 * |h'(b)| = |a| c / 4, as atan in degrees. Exits 1 when the fit does not converge or the input
 * has fewer than 4 bins.
 */
#include <gsl/gsl_blas.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_multifit_nlinear.h>
#include <gsl/gsl_vector.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_BINS 4096

typedef struct {
    size_t n;
    const double *x, *h;
} hmap;

static int sig_f(const gsl_vector *p, void *data, gsl_vector *r)
{
    const hmap *d = data;
    double a = gsl_vector_get(p, 0), b = gsl_vector_get(p, 1), c = gsl_vector_get(p, 2);
    for (size_t i = 0; i < d->n; i++)
        gsl_vector_set(r, i, c / (1 + exp(a * (d->x[i] - b))) - d->h[i]);
    return GSL_SUCCESS;
}

static int sig_df(const gsl_vector *p, void *data, gsl_matrix *J)
{
    const hmap *d = data;
    double a = gsl_vector_get(p, 0), b = gsl_vector_get(p, 1), c = gsl_vector_get(p, 2);
    for (size_t i = 0; i < d->n; i++) {
        double e = exp(a * (d->x[i] - b)), s = 1 / (1 + e), ds = -e * s * s; /* d s / d(a(x-b)) */
        gsl_matrix_set(J, i, 0, c * ds * (d->x[i] - b));
        gsl_matrix_set(J, i, 1, -c * ds * a);
        gsl_matrix_set(J, i, 2, s);
    }
    return GSL_SUCCESS;
}

int main(int argc, char **argv)
{
    FILE *in = argc > 1 ? fopen(argv[1], "r") : stdin;
    if (!in) {
        fprintf(stderr, "repose_fit: cannot open %s\n", argv[1]);
        return 1;
    }
    static double x[MAX_BINS], h[MAX_BINS];
    size_t n = 0;
    char line[512];
    while (fgets(line, sizeof line, in)) {
        char *hash = strchr(line, '#');
        if (hash) *hash = 0;
        double xv, hv;
        if (sscanf(line, "%lf %lf", &xv, &hv) != 2) continue;
        if (n == MAX_BINS) {
            fprintf(stderr, "repose_fit: more than %d bins\n", MAX_BINS);
            return 1;
        }
        x[n] = xv;
        h[n++] = hv;
    }
    if (in != stdin) fclose(in);
    if (n < 4) {
        fprintf(stderr, "repose_fit: %zu bins read, need at least 4\n", n);
        return 1;
    }
    /* start: c the highest bin, b the middle of the range, a from a 45-degree slope; the sign
     * of a from which end is higher (a > 0: the pile falls towards +x) */
    double hmax = h[0], xmin = x[0], xmax = x[0], left = 0, right = 0;
    for (size_t i = 0; i < n; i++) {
        hmax = h[i] > hmax ? h[i] : hmax;
        xmin = x[i] < xmin ? x[i] : xmin;
        xmax = x[i] > xmax ? x[i] : xmax;
        if (i < n / 2) left += h[i];
        else right += h[i];
    }
    if (!(hmax > 0) || !(xmax > xmin)) {
        fprintf(stderr, "repose_fit: no pile (highest bin %g m, x range %g m)\n", hmax,
                xmax - xmin);
        return 1;
    }
    double p0[3] = {(left >= right ? 1 : -1) * 4 / hmax, 0.5 * (xmin + xmax), hmax};
    hmap d = {n, x, h};
    gsl_multifit_nlinear_fdf fdf = {.f = sig_f, .df = sig_df, .n = n, .p = 3, .params = &d};
    gsl_multifit_nlinear_parameters par = gsl_multifit_nlinear_default_parameters();
    gsl_multifit_nlinear_workspace *w =
        gsl_multifit_nlinear_alloc(gsl_multifit_nlinear_trust, &par, n, 3);
    gsl_vector_view p0v = gsl_vector_view_array(p0, 3);
    gsl_set_error_handler_off();
    gsl_multifit_nlinear_init(&p0v.vector, &fdf, w);
    int info = 0;
    int st = gsl_multifit_nlinear_driver(500, 1e-10, 1e-10, 1e-12, NULL, NULL, &info, w);
    const gsl_vector *p = gsl_multifit_nlinear_position(w);
    double a = gsl_vector_get(p, 0), b = gsl_vector_get(p, 1), c = gsl_vector_get(p, 2);
    double rms = gsl_blas_dnrm2(gsl_multifit_nlinear_residual(w)) / sqrt((double)n);
    double angle = atan(fabs(a * c) / 4) * 180 / M_PI;
    printf("{\"a\": %.9g, \"b\": %.9g, \"c\": %.9g, \"angle_deg\": %.6g, \"rms_m\": %.6g, "
           "\"bins\": %zu, \"iterations\": %zu, \"status\": \"%s\"}\n",
           a, b, c, angle, rms, n, gsl_multifit_nlinear_niter(w), gsl_strerror(st));
    gsl_multifit_nlinear_free(w);
    if (st != GSL_SUCCESS || !isfinite(angle)) {
        fprintf(stderr, "repose_fit: the fit did not converge (%s)\n", gsl_strerror(st));
        return 1;
    }
    return 0;
}
