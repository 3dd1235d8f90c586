/*
 * box_pairs.h - pairs of axis-aligned boxes whose faces lie within rounding of each other's, and
 * the exact overlap to judge a result by: the contact geometry of particles stacked in a lattice,
 * resting in a corner, or flush against a wall. bench/degenerate counts the wrong results over
 * many such pairs; tests/physics/test_overlap.c samples the same generator.
 *
 * A spans 0..a; B spans lo..hi, with sides 0.5 to 1.5 m each. Along each axis B lies at a generic
 * overlap, with its lower or its upper face offset from A's by a random delta within +-scale (0 a
 * third of the time), or shallow (1 mm at most) with such an offset. The overlap of two boxes is
 * a box: its volume and centroid are exact up to one rounding each.
 */
#ifndef PD_TEST_BOX_PAIRS_H
#define PD_TEST_BOX_PAIRS_H

#include <math.h>

#include "polydem.h"

typedef struct {
    double a[3];                /* A: 0..a (m) */
    double lo[3], hi[3];        /* B (m) */
    double volume, centroid[3]; /* of A n B, in the boxes' frame (m^3, m) */
} box_pair;

/* Fills a pair's volume and centroid from its boxes. */
static void box_pair_exact(box_pair *bp)
{
    bp->volume = 1;
    for (int k = 0; k < 3; k++) {
        double l = fmax(0, bp->lo[k]), h = fmin(bp->a[k], bp->hi[k]);
        bp->volume *= fmax(0, h - l);
        bp->centroid[k] = (l + h) / 2;
    }
}

/* Draws a pair with faces offset by up to +-scale (m); rnd: uniform on [0, 1). */
static void box_pair_draw(box_pair *bp, double scale, double (*rnd)(void))
{
    double b[3];
    for (int k = 0; k < 3; k++) {
        bp->a[k] = 0.5 + rnd();
        b[k] = 0.5 + rnd();
    }
    for (int k = 0; k < 3; k++) { /* generic, lower faces near, upper faces near, shallow */
        int mode = (int)(rnd() * 4);
        double e = rnd() < 1.0 / 3 ? 0 : scale * (2 * rnd() - 1);
        double a = bp->a[k];
        /* the shallow mode's two draws in order (operands' order is unspecified) */
        double u = mode == 3 ? rnd() : 0;
        bp->lo[k] = mode == 0   ? a - 0.3 * rnd() * fmin(a, b[k])
                    : mode == 1 ? e
                    : mode == 2 ? a - b[k] + e
                                : a - 1e-3 * u + (rnd() < 0.2 ? e : 0);
        bp->hi[k] = bp->lo[k] + b[k];
    }
    box_pair_exact(bp);
}

/*
 * Whether o, the overlap of the pair with both boxes placed by pose p, is wrong: bit 0 when its
 * volume is off by more than 1e-9 relative plus 1e-12 m^3 (a miss counts as volume 0), bit 1 when,
 * for an overlap above 1e-9 m^3, its centroid is off by more than 1e-9 m plus 1e-14 m^4 / V. The
 * centroid's allowance grows as the overlap shrinks because the cusp sums' rounding is of the order
 * of the cusps' moments (about 1e-16 of a 1 m box's 1 m^4), divided by V. *rel gets the relative
 * volume error (1 where one of the two volumes is 0 and the other is not).
 */
static int box_pair_wrong(const box_pair *bp, const pd_pose *p, const pd_contact *o, double *rel)
{
    double v = bp->volume, vo = o->hit ? o->volume : 0;
    int bad = !(fabs(vo - v) <= 1e-9 * v + 1e-12), off = 0;
    *rel = v > 0 && vo > 0 ? fabs(vo - v) / v : v == vo ? 0 : 1;
    double R[3][3];
    pd_quat_to_matrix(p->q, R);
    for (int i = 0; i < 3 && v > 1e-9; i++) {
        const double *c = bp->centroid;
        double cw = R[i][0] * c[0] + R[i][1] * c[1] + R[i][2] * c[2] + p->x[i];
        off |= !(fabs(o->centroid[i] - cw) <= 1e-9 + 1e-14 / v);
    }
    return bad | off << 1;
}

#endif
