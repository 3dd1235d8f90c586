/*
 * contact_force.h - contact force laws, shared by OpenCL kernels and host C (see pd_real.h).
 *
 * Sign conventions: n is the unit contact normal from A into B; the relative velocity at the
 * contact point is v_rel = v_B - v_A, so the approach speed is vn = -(v_rel . n) (positive while
 * the bodies close in). Forces returned act on B; A receives the opposite.
 *
 * Models:
 *   - Hertz-Mindlin for arbitrary shapes from the overlap volume (thesis eqs. 4.16-4.18),
 *   - Hertz-Mindlin for analytic spheres (thesis eqs. 4.1, 4.5, 4.7, 4.10),
 *   - the linear spring-dashpot of seed 004 (eq. 2.1) with its friction (eqs. 2.2-2.4),
 *   - the tangential spring with history (thesis eqs. 4.8, 4.9) and the Coulomb limit
 *     (eqs. 4.12, 4.13),
 *   - a twisting spring with history and its Coulomb limit for volumetric contacts (not in the
 *     thesis; cf_twist below).
 */
#ifndef PD_CONTACT_FORCE_H
#define PD_CONTACT_FORCE_H

#include "pd_real.h"

#define CF_PI PD_R(3.14159265358979323846)

/* eq. 4.2: effective Young's modulus of two materials. */
PD_FN pd_real cf_effective_modulus(pd_real e1, pd_real nu1, pd_real e2, pd_real nu2)
{
    return PD_R(1) / ((PD_R(1) - nu1 * nu1) / e1 + (PD_R(1) - nu2 * nu2) / e2);
}

/*
 * Effective shear modulus. Eq. 4.11 as printed, 1/G* = (1 - nu1^2)/G1 + (1 - nu2^2)/G2, is not
 * Mindlin's; the standard form (Mindlin 1949; Di Renzo & Di Maio 2004) is used instead:
 * 1/G* = (2 - nu1)/G1 + (2 - nu2)/G2.
 */
PD_FN pd_real cf_effective_shear(pd_real g1, pd_real nu1, pd_real g2, pd_real nu2)
{
    return PD_R(1) / ((PD_R(2) - nu1) / g1 + (PD_R(2) - nu2) / g2);
}

/* eq. 4.6 (seed 004 eq. 2.12): effective mass; pass inv = 1/m, 0 for an immovable wall. */
PD_FN pd_real cf_effective_mass(pd_real inv_m1, pd_real inv_m2)
{
    return PD_R(1) / (inv_m1 + inv_m2);
}

/*
 * Normal force from the overlap volume V and depth delta (eqs. 4.16, 4.17):
 *   F_n = 4/(3 sqrt(pi)) E* sqrt(V delta) + 2 gamma sqrt(m* k_n) vn,  k_n = 2 E* sqrt(V/(pi
 * delta)). The damped force is not allowed to pull (F_n >= 0): a dashpot that glues separating
 * bodies together is an artefact of the linear damping term, not cohesion. *kn receives k_n.
 */
PD_FN pd_real cf_hertz_volume_normal(pd_real estar, pd_real vol, pd_real depth, pd_real mstar,
                                     pd_real gamma, pd_real vn, pd_real *kn)
{
    if (!(vol > PD_R(0)) || !(depth > PD_R(0))) {
        *kn = PD_R(0);
        return PD_R(0);
    }
    *kn = PD_R(2) * estar * PD_SQRT(vol / (CF_PI * depth));
    pd_real f = PD_R(4) / (PD_R(3) * PD_SQRT(CF_PI)) * estar * PD_SQRT(vol * depth) +
                PD_R(2) * gamma * PD_SQRT(mstar * *kn) * vn;
    return f > PD_R(0) ? f : PD_R(0);
}

/* eq. 4.18: tangential stiffness from the overlap volume. */
PD_FN pd_real cf_hertz_volume_kt(pd_real gstar, pd_real vol, pd_real depth)
{
    return depth > PD_R(0) ? PD_R(8) * gstar * PD_SQRT(vol / (CF_PI * depth)) : PD_R(0);
}

/*
 * Hertz normal force of two spheres (eqs. 4.1, 4.5, 4.7): F_n = 4/3 E* sqrt(R) delta^(3/2) +
 * 2 gamma sqrt(m* k_n) vn with k_n = 2 E* sqrt(R delta); R is the effective radius (eq. 4.3).
 */
PD_FN pd_real cf_hertz_sphere_normal(pd_real estar, pd_real rstar, pd_real delta, pd_real mstar,
                                     pd_real gamma, pd_real vn, pd_real *kn)
{
    if (!(delta > PD_R(0))) {
        *kn = PD_R(0);
        return PD_R(0);
    }
    pd_real srd = PD_SQRT(rstar * delta);
    *kn = PD_R(2) * estar * srd;
    pd_real f =
        PD_R(4) / PD_R(3) * estar * srd * delta + PD_R(2) * gamma * PD_SQRT(mstar * *kn) * vn;
    return f > PD_R(0) ? f : PD_R(0);
}

/* eq. 4.10: tangential stiffness of two spheres. */
PD_FN pd_real cf_hertz_sphere_kt(pd_real gstar, pd_real rstar, pd_real delta)
{
    return delta > PD_R(0) ? PD_R(8) * gstar * PD_SQRT(rstar * delta) : PD_R(0);
}

/*
 * Linear spring-dashpot (seed 004 eq. 2.1): F_n = k_e delta + eta vn. Unlike the Hertz laws this
 * one is left exactly as the seed's analytic solutions (A.1-A.3) assume, tension included.
 */
PD_FN pd_real cf_linear_normal(pd_real ke, pd_real eta, pd_real delta, pd_real vn)
{
    return delta > PD_R(0) ? ke * delta + eta * vn : PD_R(0);
}

/*
 * Tangential force with history (eqs. 4.8-4.9, 4.12-4.13), in vector form.
 *   spring   in/out: the elastic tangential force F_t,e carried from the last step
 *   n        the current unit normal (the stored spring is first turned into its plane)
 *   kt, kt0  the tangential stiffness now and at the last step
 *   loading  1 when the normal force grew this step (eq. 4.8), else it is rescaled (eq. 4.9)
 *   dt_disp  the tangential displacement increment this step (v_t dt)
 *   vt       the tangential relative velocity (B relative to A), for the dashpot
 *   damp     2 gamma sqrt(m* kt): the tangential dashpot coefficient
 *   mu, fn   friction coefficient and the current normal force
 * Returns the tangential force on B. When the Coulomb limit binds, the stored spring is reset to
 * the limit so that it does not keep growing while the contact slides.
 */
PD_FN pd_v3 cf_tangential(pd_v3 *spring, pd_v3 n, pd_real kt, pd_real kt0, int loading,
                          pd_v3 dt_disp, pd_v3 vt, pd_real damp, pd_real mu, pd_real fn)
{
    pd_v3 s = *spring;
    /* keep the history in the current tangent plane, preserving its magnitude */
    pd_real mag = v3_norm(s);
    s = v3_sub(s, v3_scale(n, v3_dot(s, n)));
    pd_real m2 = v3_norm(s);
    if (m2 > PD_R(0)) s = v3_scale(s, mag / m2);
    if (!loading && kt0 > PD_R(0)) s = v3_scale(s, kt / kt0); /* eq. 4.9 */
    /* the spring resists the displacement of B relative to A: force on B is -kt d */
    s = v3_sub(s, v3_scale(dt_disp, kt));    /* eqs. 4.8, 4.9 */
    pd_v3 f = v3_sub(s, v3_scale(vt, damp)); /* eq. 4.12 */
    pd_real fl = mu * fn, fm = v3_norm(f);
    if (fm > fl) { /* eq. 4.13: slide at the Coulomb limit */
        f = fm > PD_R(0) ? v3_scale(f, fl / fm) : f;
        s = f;
    }
    *spring = s;
    return f;
}

/*
 * Twisting resistance of a volumetric contact. The thesis's contact is a point: a force at the
 * overlap's centroid, so a relative spin about the normal through it meets no resistance, and a
 * cube resting on a face keeps turning at whatever rate an impact left it (2 rad/s for seconds
 * in examples/cube_lattice.json before this). A real face contact resists it by friction over
 * its area. Modelled as the tangential spring is (eqs. 4.8-4.13), about n instead of along the
 * plane, on the circular contact of radius a = sqrt(V / (pi delta)) that eqs. 4.17-4.18 use:
 *   stiffness  k_tw = 16/3 a^3 G_tw, 1/G_tw = 1/G1 + 1/G2: a disc bonded to two half-spaces and
 *              turned (Reissner and Sagoci 1944; Lubkin 1951 for spheres in contact),
 *   limit      M_max = 3 pi / 16 mu F_n a: Coulomb friction under Hertz's pressure, fully sliding
 *              (integrate mu p(r) r over the disc with p = 3 F_n / (2 pi a^2) sqrt(1 - r^2/a^2)),
 *   dashpot    eq. 4.12's tangential dashpot spread over the disc (contact_pair.h, cp_couple).
 *   twist      in/out: the elastic moment carried from the last step, N m (about n, on B)
 *   ktw, ktw0  the stiffness now and at the last step (the moment shrinks with it on unloading,
 *              as eq. 4.9 rescales the tangential spring)
 *   spin       (w_B - w_A) . n, rad/s; dt the step, s; damp the dashpot, N m s
 *   mlim       M_max, N m
 * Returns the moment about n on B (A receives minus it).
 */
PD_FN pd_real cf_twist(pd_real *twist, pd_real ktw, pd_real ktw0, int loading, pd_real spin,
                       pd_real dt, pd_real damp, pd_real mlim)
{
    pd_real s = *twist;
    if (!loading && ktw0 > PD_R(0)) s *= ktw / ktw0;
    s -= ktw * spin * dt;
    pd_real m = s - damp * spin;
    if (PD_FABS(m) > mlim) { /* slides at the limit, and the spring with it */
        m = m > PD_R(0) ? mlim : -mlim;
        s = m;
    }
    *twist = s;
    return m;
}

/* k_tw of cf_twist for contact radius a, N m / rad. */
PD_FN pd_real cf_twist_stiffness(pd_real gtw, pd_real a)
{
    return PD_R(16) / PD_R(3) * gtw * a * a * a;
}

#endif /* PD_CONTACT_FORCE_H */
