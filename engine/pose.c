/* pose.c - rigid-body orientation helpers. */
#include <math.h>

#include "polydem.h"

int pd_quat_normalize(const double q[4], double out[4])
{
    double a[4] = {q[0], q[1], q[2], q[3]};
    double n = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2] + a[3] * a[3]);
    if (!isfinite(n) || n < 1e-150) {
        /* the squares overflowed or underflowed: scale by the largest component first (only
         * here, so that ordinary quaternions keep the bits they always had) */
        double m = 0;
        for (int k = 0; k < 4; k++) {
            if (!isfinite(a[k])) return PD_EINVAL;
            m = fmax(m, fabs(a[k]));
        }
        if (!(m > 0)) return PD_EINVAL;
        for (int k = 0; k < 4; k++)
            a[k] /= m;
        n = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2] + a[3] * a[3]);
    }
    if (!(n > 0) || !isfinite(n)) return PD_EINVAL;
    for (int k = 0; k < 4; k++)
        out[k] = a[k] / n;
    return PD_OK;
}

void pd_wall_rotation(const double omega[3], double t, double q[4])
{
    double phi[3] = {omega[0] * t, omega[1] * t, omega[2] * t};
    double a = sqrt(phi[0] * phi[0] + phi[1] * phi[1] + phi[2] * phi[2]);
    double s = a > 0 ? sin(0.5 * a) / a : 0.5;
    q[0] = cos(0.5 * a);
    for (int k = 0; k < 3; k++)
        q[k + 1] = phi[k] * s;
}

int pd_quat_to_matrix(const double q[4], double r[3][3])
{
    double u[4];
    if (pd_quat_normalize(q, u) != PD_OK) return PD_EINVAL;
    double w = u[0], x = u[1], y = u[2], z = u[3];
    r[0][0] = 1 - 2 * (y * y + z * z);
    r[0][1] = 2 * (x * y - w * z);
    r[0][2] = 2 * (x * z + w * y);
    r[1][0] = 2 * (x * y + w * z);
    r[1][1] = 1 - 2 * (x * x + z * z);
    r[1][2] = 2 * (y * z - w * x);
    r[2][0] = 2 * (x * z - w * y);
    r[2][1] = 2 * (y * z + w * x);
    r[2][2] = 1 - 2 * (x * x + y * y);
    return PD_OK;
}
