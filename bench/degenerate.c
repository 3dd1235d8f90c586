/*
 * bench/degenerate.c - how often the overlap is wrong for boxes whose faces lie within rounding
 * of each other's: the contact geometry of particles stacked in a lattice, resting in a corner,
 * or flush against a wall.
 *
 * Each trial takes two axis-aligned boxes with faces offset by up to +-scale along each axis
 * (tests/box_pairs.h, which tests/physics/test_overlap.c samples too). The exact overlap is a
 * box: its volume and centroid are the reference. A result counts as wrong when its volume is
 * off by more than 1e-9 relative (plus 1e-12 m^3) or its centroid by more than 1e-9 m plus
 * 1e-14 m^4 / V (the cusp sums' rounding, which grows as the overlap shrinks).
 * The predicates snap a distance within 2 resolutions (about 4e-14 m for these sizes) to a tie
 * (kernels/overlap_predicates.h), so scales near that band are the ones that find trouble.
 * Every pair runs with the half-plane filter on and off, as given and turned by one random
 * rotation moved up to 3 m away (both boxes, so their relative configuration stays).
 *
 * After the table, the wrong trials by how far off the volume is (relative; a miss counts as 1),
 * or "centroid only" where the volume is right.
 *
 * usage: build/bench/degenerate [--trials N]   (default 3000 per scale and frame)
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../tests/box_pairs.h"
#include "polydem.h"

static uint64_t rng = 0x12345678abcdefull;

static double rnd(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (double)(rng >> 11) * (1.0 / 9007199254740992.0);
}

static pd_mesh *box(const double lo[3], const double hi[3])
{
    pd_mesh *m = NULL;
    pd_error err = {0};
    if (pd_mesh_box(lo, hi, &m, &err) != PD_OK) fprintf(stderr, "degenerate: box: %s\n", err.msg);
    return m;
}

/* How wrong the wrong results are: the largest relative volume error of each trial's worse
 * result (a miss, or a hit where there is no overlap, counts as 1), in decades. */
enum { NBAND = 5 };
static const char *const band_name[NBAND] = {"< 1e-6", "1e-6 - 1e-3", "1e-3 - 0.1", ">= 0.1",
                                             "centroid only"};
static long band_count[NBAND];

static int band_of(double rel)
{
    return rel < 1e-6 ? 0 : rel < 1e-3 ? 1 : rel < 0.1 ? 2 : 3;
}

/* One trial: returns which results are wrong (bit 0: filter on, bit 1: off), -1 on an error. */
static int trial(double scale, int turned)
{
    box_pair bp;
    box_pair_draw(&bp, scale, rnd);
    double zero[3] = {0, 0, 0};
    pd_mesh *ma = box(zero, bp.a), *mb = box(bp.lo, bp.hi);
    pd_pose p = {{0, 0, 0}, {1, 0, 0, 0}};
    if (turned) {
        double q[4], n = 0; /* drawn in order: an initializer's order is unspecified */
        for (int k = 0; k < 4; k++)
            q[k] = rnd() + (k ? -0.5 : 1);
        for (int k = 0; k < 4; k++)
            n += q[k] * q[k];
        for (int k = 0; k < 4; k++)
            p.q[k] = q[k] / sqrt(n);
        p.x[0] = 3 * rnd();
        p.x[1] = -2 * rnd();
        p.x[2] = rnd();
    }
    int wrong = 0, vol_wrong = 0;
    double worst = 0;
    for (int f = 0; f < 2 && ma && mb; f++) {
        pd_contact o;
        pd_error err = {0};
        if (pd_overlap_host(ma, &p, mb, &p, f ? PD_OVERLAP_NO_FILTER : 0, &o, &err) != PD_OK) {
            fprintf(stderr, "degenerate: overlap: %s\n", err.msg);
            wrong = -1;
            break;
        }
        double rel;
        int bad = box_pair_wrong(&bp, &p, &o, &rel);
        if (bad & 1) {
            worst = rel > worst ? rel : worst;
            vol_wrong = 1;
        }
        wrong |= (bad != 0) << f;
    }
    if (wrong > 0) band_count[vol_wrong ? band_of(worst) : NBAND - 1]++;
    if (!ma || !mb) wrong = -1;
    pd_mesh_destroy(ma);
    pd_mesh_destroy(mb);
    return wrong;
}

int main(int argc, char **argv)
{
    int n = 3000;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--trials") && i + 1 < argc) {
            char *end;
            long t = strtol(argv[++i], &end, 10);
            if (*end || t < 1 || t > 10000000) {
                fprintf(stderr, "degenerate: --trials: expected 1 to 1e7, got \"%s\"\n", argv[i]);
                return 2;
            }
            n = (int)t;
        } else {
            fprintf(stderr, "usage: %s [--trials N]\n", argv[0]);
            return 2;
        }
    }
    static const double scales[] = {1e-15, 1e-14, 2e-14, 4e-14, 6e-14, 1e-13, 3e-13, 1e-12};
    printf("| offsets within (m) | frame | box pairs | wrong, filter on | wrong, filter off |\n");
    printf("|---|---|---|---|---|\n");
    for (int s = 0; s < (int)(sizeof scales / sizeof scales[0]); s++) {
        for (int turned = 0; turned < 2; turned++) {
            int won = 0, woff = 0;
            rng = 0x12345678abcdefull + (uint64_t)(2 * s + turned);
            for (int t = 0; t < n; t++) {
                int w = trial(scales[s], turned);
                if (w < 0) return 1;
                won += w & 1;
                woff += w >> 1;
            }
            printf("| %g | %s | %d | %d | %d |\n", scales[s], turned ? "turned" : "as given", n,
                   won, woff);
            fflush(stdout);
        }
    }
    printf("\nwrong trials by the worse result's relative volume error (all rows):\n\n");
    printf("| volume error | trials |\n|---|---|\n");
    for (int b = 0; b < NBAND; b++)
        printf("| %s | %ld |\n", band_name[b], band_count[b]);
    return 0;
}
