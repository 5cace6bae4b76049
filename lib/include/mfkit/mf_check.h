/*
 * mf_check.h -- recording a property check: the one API behind the core validator
 * (mf_validate.h), the LTC gate (mf_ltc_gate.h) and the gates of the table kinds
 * (mf_table_kind.h).
 *
 * A check measures one value per case (a grid point, a texel, a polygon), keeps the worst value
 * and where it occurred, and passes when the worst value is <= its bound:
 *
 *     mf_check c;
 *     mf_check_begin(&c, "ndf_normalisation", "|integral of D cos - 1|", 1e-8);
 *     for (each case)
 *         mf_check_record(&c, value, "alpha 0.1, ratio 1");
 *     mf_check_finish(&c);
 *
 * Rules (tests/test_validate.c and tests/test_ltc_gate.c check them for both users):
 *   - worst starts at 0 and is the maximum of the recorded values and 0: a check measures an
 *     error or an excess, so values <= 0 mean "no error" (worst 0, worst_at the first case).
 *     Ties keep the earlier case.
 *   - A NaN value fails the check: worst becomes NaN and worst_at "NaN at <where>" for the first
 *     NaN recorded; later values (NaN or not) only count as cases.  A NaN never hides behind a
 *     larger value, and it is never turned into a number (mfkit's JSON writer prints it as the string "NaN", mf_json.h).
 *   - +infinity is an ordinary (failing) value: the users record it for a case that could not be
 *     evaluated at all (a singular matrix, a model that returned NaN inside a quadrature), with
 *     a worst_at that says so.
 *   - mf_check_fail marks a check failed without a value (e.g. an allocation failed midway).
 *   - passed = no mf_check_fail and worst <= bound (false for a NaN worst).
 *
 * Pure C11.
 */
#ifndef MF_CHECK_H
#define MF_CHECK_H

#include "mfkit/mf_core.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mf_check {
    char name[48];       /* stable identifier, e.g. "ndf_normalisation" */
    char what[160];      /* one line: what is measured */
    double worst;        /* the worst value found (same unit as bound); NaN if a NaN was recorded */
    double bound;        /* passes when worst <= bound */
    int passed;          /* worst <= bound and no evaluation failed */
    long cases;          /* number of cases checked */
    char worst_at[200];  /* the parameters of the worst case ("NaN at ..." for a NaN) */
} mf_check;

/* Starts a check: zero cases, worst 0, worst_at empty, passed. */
void mf_check_begin(mf_check *c, const char *name, const char *what, double bound);
/* Records the value v of one case at `where` (rules in the header comment). */
void mf_check_record(mf_check *c, double v, const char *where);
/* The same with a printf-style description of the case, formatted only when it is needed (the
 * first case, a new worst value or the first NaN). */
void mf_check_recordf(mf_check *c, double v, const char *where_fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
/* Marks the check failed whatever its values (worst_at gets `why` if no NaN is recorded). */
void mf_check_fail(mf_check *c, const char *why);
/* Decides passed (call once after the last case). */
void mf_check_finish(mf_check *c);

/* A check of a table of checks: its name, what it measures, its bound, whether it needs a BRDF
 * model, and the function that runs it on a context of the runner's type (the runner calls
 * mf_check_begin with name, what and bound before `run` and mf_check_finish after it; `run`
 * may refine `what`, e.g. with an option's value). */
typedef struct mf_check_def {
    const char *name;
    const char *what;
    double bound;
    int needs_model;
    void (*run)(void *ctx, mf_check *c);
} mf_check_def;

/* The number of checks in defs[0..n-1] that run with (has_model != 0) or without a model. */
int mf_check_defs_count(const mf_check_def *defs, int n, int has_model);

/* Runs defs[0..n-1] in order on ctx, skipping those that need a model when has_model is 0, into
 * checks[0..cap-1]; *count the number written.  MF_ERR_DOMAIN if cap is too small (nothing run),
 * MF_OK when every check passed, MF_ERR_CHECK_FAILED otherwise. */
mf_status mf_check_run_defs(const mf_check_def *defs, int n, void *ctx, int has_model, mf_check *checks, int cap,
                            int *count) MF_WARN_UNUSED;

#ifdef __cplusplus
}
#endif
#endif /* MF_CHECK_H */
