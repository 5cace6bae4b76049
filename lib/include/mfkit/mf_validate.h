/*
 * mf_validate.h -- property checks of the core math over a grid of the whole domain.
 *
 * Each check integrates or evaluates the library's functions over a fixed, deterministic grid
 * (alpha from 1e-4 to 1, view angles up to 89.99 degrees, anisotropy ratios up to 1:100,
 * non-centred mean slopes up to 2) and reports its worst value against a stated bound.  The
 * checks, their grids and the reasons for their bounds are listed in docs/validation.md.
 * `mfkit validate` prints them; tests/ run them too.  Each check records its cases through
 * mf_check.h (one rule for NaN: a NaN case fails the check and is reported as worst = NaN,
 * "NaN at <where>").
 */
#ifndef MF_VALIDATE_H
#define MF_VALIDATE_H

#include "mfkit/mf_check.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Called after each check with its index and the total, for progress display; may be NULL. */
typedef void (*mf_validate_progress_fn)(void *user, int done, int total, const mf_check *last);

/* Number of checks mf_validate_core() writes. */
int mf_validate_core_count(void);

/* Runs all core checks into checks[0 .. mf_validate_core_count()-1] (cap must be large enough,
 * else MF_ERR_DOMAIN).  Returns MF_OK when every check passed, MF_ERR_CHECK_FAILED otherwise,
 * MF_ERR_ALLOC on allocation failure. */
mf_status mf_validate_core(mf_check *checks, int cap, mf_validate_progress_fn progress, void *user) MF_WARN_UNUSED;

#ifdef __cplusplus
}
#endif
#endif /* MF_VALIDATE_H */
