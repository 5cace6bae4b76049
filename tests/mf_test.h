/*
 * mf_test.h -- the tiny test harness of mfkit's C tests.
 *
 * CHECK(cond), CHECK_REL(a, b, tol), CHECK_ABS(a, b, tol) print the expression, both values,
 * the tolerance and the test's seed on failure, and count failures; MF_TEST_MAIN() returns
 * non-zero if any check failed.  Random tests take their seed from mf_test_seed(default):
 * the environment variable MF_TEST_SEED overrides it, so a failure can be replayed.
 */
#ifndef MF_TEST_H
#define MF_TEST_H

#include <inttypes.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

static int mf_test_failures = 0;
static int mf_test_checks = 0;
static uint64_t mf_test_current_seed = 0;

static inline uint64_t mf_test_seed(uint64_t dflt)
{
    const char *s = getenv("MF_TEST_SEED");
    mf_test_current_seed = s ? strtoull(s, NULL, 0) : dflt;
    return mf_test_current_seed;
}

#define MF_FAIL_AT(...)                                                                                         \
    do {                                                                                                        \
        ++mf_test_failures;                                                                                     \
        fprintf(stderr, "%s:%d: FAIL: ", __FILE__, __LINE__);                                                  \
        fprintf(stderr, __VA_ARGS__);                                                                           \
        fprintf(stderr, " [seed %" PRIu64 "]\n", mf_test_current_seed);                                         \
    } while (0)

#define CHECK(cond)                                                                                             \
    do {                                                                                                        \
        ++mf_test_checks;                                                                                       \
        if (!(cond))                                                                                            \
            MF_FAIL_AT("%s", #cond);                                                                            \
    } while (0)

/* CHECK with a printf-style failure message (the values that failed). */
#define CHECKF(cond, ...)                                                                                       \
    do {                                                                                                        \
        ++mf_test_checks;                                                                                       \
        if (!(cond))                                                                                            \
            MF_FAIL_AT(__VA_ARGS__);                                                                            \
    } while (0)

/* |a - b| <= tol * |b| (b the reference); NaN fails. */
#define CHECK_REL(a, b, tol)                                                                                    \
    do {                                                                                                        \
        double a_ = (a), b_ = (b), t_ = (tol);                                                                  \
        ++mf_test_checks;                                                                                       \
        if (!(fabs(a_ - b_) <= t_ * fabs(b_)))                                                                  \
            MF_FAIL_AT("%s = %.17g vs %s = %.17g: relative error %.3g > %.3g", #a, a_, #b, b_,                   \
                       fabs(a_ - b_) / fabs(b_), t_);                                                           \
    } while (0)

/* |a - b| <= tol; NaN fails. */
#define CHECK_ABS(a, b, tol)                                                                                    \
    do {                                                                                                        \
        double a_ = (a), b_ = (b), t_ = (tol);                                                                  \
        ++mf_test_checks;                                                                                       \
        if (!(fabs(a_ - b_) <= t_))                                                                             \
            MF_FAIL_AT("%s = %.17g vs %s = %.17g: |difference| %.3g > %.3g", #a, a_, #b, b_, fabs(a_ - b_), t_); \
    } while (0)

/* Monte Carlo: |estimate - reference| <= z * std_error + delta. */
#define CHECK_MC(est, se, ref, z, delta)                                                                        \
    do {                                                                                                        \
        double e_ = (est), s_ = (se), r_ = (ref), z_ = (z), d_ = (delta);                                       \
        ++mf_test_checks;                                                                                       \
        if (!(fabs(e_ - r_) <= z_ * s_ + d_))                                                                   \
            MF_FAIL_AT("%s = %.10g (se %.3g) vs %s = %.10g: |diff| %.3g > %g * se + %.3g", #est, e_, s_, #ref, r_, \
                       fabs(e_ - r_), z_, d_);                                                                  \
    } while (0)

#define MF_TEST_MAIN_END()                                                                                      \
    do {                                                                                                        \
        printf("%s: %d checks, %d failed\n", __FILE__, mf_test_checks, mf_test_failures);                       \
        return mf_test_failures ? 1 : 0;                                                                        \
    } while (0)

#endif /* MF_TEST_H */
