/*
 * test.h - the tiny unit-test harness shared by tests/unit and tests/physics.
 *
 * A test file defines TEST(name) functions and a main that calls RUN(name) for each, then
 * returns TEST_DONE(). Each assertion prints the expression with expected and actual values on
 * failure; each test prints one line "ok NAME" or "FAIL NAME"; the last line of a test program is
 * "N passed, N failed", which tests/run.sh sums into the suite's closing line.
 * TEST_ONLY="name1 name2" in the environment runs only the tests named (for working on one).
 */
#ifndef PD_TEST_H
#define PD_TEST_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int test_passed_, test_failed_, test_cur_failed_;

/* Whether TEST_ONLY leaves test `name` out (a whole word of the list). */
static inline int test_skipped_(const char *name)
{
    const char *only = getenv("TEST_ONLY");
    if (!only || !*only) return 0;
    size_t n = strlen(name);
    for (const char *p = strstr(only, name); p; p = strstr(p + 1, name))
        if ((p == only || p[-1] == ' ') && (p[n] == ' ' || p[n] == 0)) return 0;
    return 1;
}

#define TEST(name) static void name(void)

#define RUN(name)                                                                                  \
    do {                                                                                           \
        if (test_skipped_(#name)) break;                                                           \
        test_cur_failed_ = 0;                                                                      \
        name();                                                                                    \
        if (test_cur_failed_) {                                                                    \
            test_failed_++;                                                                        \
            printf("FAIL %s\n", #name);                                                            \
        } else {                                                                                   \
            test_passed_++;                                                                        \
            printf("ok   %s\n", #name);                                                            \
        }                                                                                          \
        fflush(stdout);                                                                            \
    } while (0)

#define TEST_DONE()                                                                                \
    (printf("%d passed, %d failed\n", test_passed_, test_failed_), test_failed_ ? 1 : 0)

#define TEST_FAILF(...)                                                                            \
    do {                                                                                           \
        printf("  %s:%d: ", __FILE__, __LINE__);                                                   \
        printf(__VA_ARGS__);                                                                       \
        printf("\n");                                                                              \
        test_cur_failed_ = 1;                                                                      \
    } while (0)

#define CHECK(cond)                                                                                \
    do {                                                                                           \
        if (!(cond)) TEST_FAILF("CHECK(%s) failed", #cond);                                        \
    } while (0)

#define CHECK_EQ_INT(expected, actual)                                                             \
    do {                                                                                           \
        long long e_ = (long long)(expected), a_ = (long long)(actual);                            \
        if (e_ != a_) TEST_FAILF("%s == %s: expected %lld, got %lld", #expected, #actual, e_, a_); \
    } while (0)

/* |actual - expected| <= tol (absolute). */
#define CHECK_NEAR(expected, actual, tol)                                                          \
    do {                                                                                           \
        double e_ = (expected), a_ = (actual), t_ = (tol);                                         \
        if (!(fabs(e_ - a_) <= t_))                                                                \
            TEST_FAILF("%s ~ %s: expected %.17g, got %.17g (diff %.3g, tol %.3g)", #expected,      \
                       #actual, e_, a_, fabs(e_ - a_), t_);                                        \
    } while (0)

/* |actual - expected| <= rtol * |expected| (relative). */
#define CHECK_REL(expected, actual, rtol)                                                          \
    do {                                                                                           \
        double e_ = (expected), a_ = (actual), t_ = (rtol);                                        \
        if (!(fabs(e_ - a_) <= t_ * fabs(e_)))                                                     \
            TEST_FAILF("%s ~ %s: expected %.17g, got %.17g (rel diff %.3g, rtol %.3g)", #expected, \
                       #actual, e_, a_, fabs(e_ - a_) / fabs(e_), t_);                             \
    } while (0)

#define CHECK_STR_CONTAINS(haystack, needle)                                                       \
    do {                                                                                           \
        const char *h_ = (haystack), *n_ = (needle);                                               \
        if (!h_ || !strstr(h_, n_))                                                                \
            TEST_FAILF("expected \"%s\" to contain \"%s\"", h_ ? h_ : "(null)", n_);               \
    } while (0)

#endif
