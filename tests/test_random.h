/*
 * test_random.h - test helper: a deterministic generator (splitmix64) for random poses, so every
 * run of a test draws the same cases. A test file defines TEST_RANDOM_SEED before including it
 * to draw its own sequence.
 */
#ifndef PD_TEST_RANDOM_H
#define PD_TEST_RANDOM_H

#include <math.h>
#include <stdint.h>

#ifndef TEST_RANDOM_SEED
#define TEST_RANDOM_SEED 1
#endif

static uint64_t test_random_state = TEST_RANDOM_SEED;

static inline uint64_t rnd64(void)
{
    uint64_t z = (test_random_state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

/* Uniform in [0, 1). */
static inline double rnd(void)
{
    return (double)(rnd64() >> 11) / 9007199254740992.0;
}

/*
 * Three draws into v, in order. The arguments of one call and the operands of one expression are
 * evaluated in an unspecified order, and gcc and clang take a call's in opposite orders:
 * v3(rnd(), rnd(), rnd()) drew a different case under each compiler. Draw into variables first.
 */
static inline void rnd3(double v[3])
{
    for (int k = 0; k < 3; k++)
        v[k] = rnd();
}

/* A random unit quaternion [w, x, y, z] (normalised from a random point of the 4-cube). */
static inline void rnd_quat(double q[4])
{
    double n = 0;
    for (int c = 0; c < 4; c++) {
        q[c] = rnd() - 0.5;
        n += q[c] * q[c];
    }
    for (int c = 0; c < 4; c++)
        q[c] /= sqrt(n);
}

#endif
