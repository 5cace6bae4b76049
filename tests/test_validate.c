/* test_validate.c -- the check-recording rules (mf_check.h) that every core check uses, and every
 * core property check passes (mf_validate.h). */
#include "mf_test.h"
#include "mfkit/mf_validate.h"

#include <string.h>

/* The rules of mf_check.h, exactly (no tolerance: they are comparisons, not arithmetic). */
static void test_check_api(void)
{
    mf_check c;
    mf_check_begin(&c, "x", "what", 1.0);
    CHECK(c.cases == 0 && c.worst == 0.0 && c.passed && !c.worst_at[0]);
    mf_check_finish(&c);
    CHECK(c.passed); /* no cases: nothing exceeded the bound */

    /* negative values: worst stays 0, worst_at the first case */
    mf_check_begin(&c, "x", "what", 1.0);
    mf_check_record(&c, -3.0, "a");
    mf_check_record(&c, -1.0, "b");
    CHECK(c.worst == 0.0 && !strcmp(c.worst_at, "a") && c.cases == 2);
    /* a larger value moves the worst; a tie keeps the earlier case */
    mf_check_record(&c, 0.5, "c");
    mf_check_record(&c, 0.5, "d");
    mf_check_recordf(&c, 0.25, "e %d", 5);
    CHECK(c.worst == 0.5 && !strcmp(c.worst_at, "c"));
    mf_check_recordf(&c, 0.75, "f %d", 6);
    CHECK(c.worst == 0.75 && !strcmp(c.worst_at, "f 6"));
    mf_check_finish(&c);
    CHECK(c.passed && c.cases == 6);

    /* NaN: fails, worst = NaN, "NaN at <where>" of the first NaN; later values only count */
    mf_check_begin(&c, "x", "what", 1.0);
    mf_check_record(&c, 0.5, "a");
    mf_check_record(&c, NAN, "b");
    mf_check_record(&c, 10.0, "c");
    mf_check_recordf(&c, NAN, "d %s", "second");
    mf_check_finish(&c);
    printf("NaN rule: worst %g at \"%s\", passed %d\n", c.worst, c.worst_at, c.passed);
    CHECK(isnan(c.worst) && !strcmp(c.worst_at, "NaN at b") && !c.passed && c.cases == 4);
    /* a NaN as the very first case, and a NaN after a value above the bound */
    mf_check_begin(&c, "x", "what", 1.0);
    mf_check_record(&c, 5.0, "a");
    mf_check_record(&c, NAN, "b");
    mf_check_finish(&c);
    CHECK(isnan(c.worst) && !strcmp(c.worst_at, "NaN at b") && !c.passed);

    /* +inf is an ordinary failing value; a bound that is exactly met passes */
    mf_check_begin(&c, "x", "what", 1.0);
    mf_check_record(&c, 1.0, "a");
    mf_check_finish(&c);
    CHECK(c.passed && c.worst == 1.0);
    mf_check_begin(&c, "x", "what", 1.0);
    mf_check_record(&c, INFINITY, "a");
    mf_check_record(&c, 2.0, "b");
    mf_check_finish(&c);
    CHECK(!c.passed && isinf(c.worst) && !strcmp(c.worst_at, "a"));

    /* mf_check_fail: fails whatever the values, keeps a NaN's report */
    mf_check_begin(&c, "x", "what", 1.0);
    mf_check_record(&c, 0.1, "a");
    mf_check_fail(&c, "out of memory");
    mf_check_finish(&c);
    CHECK(!c.passed && c.worst == 0.1 && !strcmp(c.worst_at, "out of memory"));
}

/* A table of two checks run by mf_check_run_defs: order, the model filter, the status. */
static void pass_fn(void *ctx, mf_check *c)
{
    ++*(int *)ctx;
    mf_check_record(c, 0.5, "p");
}
static void nan_fn(void *ctx, mf_check *c)
{
    ++*(int *)ctx;
    mf_check_record(c, NAN, "q");
}

static void test_check_defs(void)
{
    const mf_check_def defs[] = {{"one", "w1", 1.0, 0, pass_fn}, {"two", "w2", 1.0, 1, nan_fn}};
    mf_check c[2];
    int n = -1, calls = 0;
    CHECK(mf_check_defs_count(defs, 2, 0) == 1 && mf_check_defs_count(defs, 2, 1) == 2);
    CHECK(mf_check_run_defs(defs, 2, &calls, 1, c, 1, &n) == MF_ERR_DOMAIN && n == 0 && calls == 0);
    CHECK(mf_check_run_defs(defs, 2, &calls, 0, c, 1, &n) == MF_OK && n == 1 && calls == 1);
    CHECK(!strcmp(c[0].name, "one") && !strcmp(c[0].what, "w1") && c[0].passed && c[0].worst == 0.5);
    CHECK(mf_check_run_defs(defs, 2, &calls, 1, c, 2, &n) == MF_ERR_CHECK_FAILED && n == 2 && calls == 3);
    CHECK(!strcmp(c[1].name, "two") && !c[1].passed && isnan(c[1].worst) && !strcmp(c[1].worst_at, "NaN at q"));
}

int main(void)
{
    test_check_api();
    test_check_defs();
    int n = mf_validate_core_count();
    CHECK(n >= 8);
    mf_check checks[32];
    CHECK(mf_validate_core(checks, 2, NULL, NULL) == MF_ERR_DOMAIN);
    mf_status st = mf_validate_core(checks, 32, NULL, NULL);
    CHECK(st == MF_OK);
    for (int i = 0; i < n; ++i) {
        printf("%-22s worst %-12.4g bound %-12.4g cases %-7ld %s\n", checks[i].name, checks[i].worst, checks[i].bound,
               checks[i].cases, checks[i].worst_at);
        CHECK(checks[i].passed);
        CHECK(checks[i].cases > 0);
        CHECK(checks[i].worst <= checks[i].bound);
        CHECK(strlen(checks[i].name) > 0 && strlen(checks[i].worst_at) > 0);
    }
    MF_TEST_MAIN_END();
}
