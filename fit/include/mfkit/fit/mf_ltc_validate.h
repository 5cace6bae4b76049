/*
 * mf_ltc_validate.h -- `mfkit validate` on an isotropic LTC table with the fitter at hand: the
 * neighbour check's candidate texels refitted (mf_ltc_gate.h, "The refit of candidate texels";
 * docs/validation.md, "The refit of candidate texels").
 */
#ifndef MFKIT_FIT_MF_LTC_VALIDATE_H
#define MFKIT_FIT_MF_LTC_VALIDATE_H

#include "mfkit/fit/mf_ltcfit.h"
#include "mfkit/mf_ltc_gate.h"

#ifdef __cplusplus
extern "C" {
#endif

/* 1 if the table's metadata says mfkit's fitter made it for `model` ("tool" "mfkit fit ltc", "brdf"
 * the model's name, "seed" and "samples" readable): then *fit gets those options (the others at
 * their defaults), the fitter a refit of one of its texels reproduces. */
int mf_ltc_validate_fit_options(const mf_table *t, const mf_brdf_model *model, mf_ltcfit_options *fit);

/* mf_ltc_gate_validate, with the neighbour check's candidate texels refitted when
 * mf_ltc_validate_fit_options recognises the table (else exactly mf_ltc_gate_validate).  A refit
 * compares shapes (as the neighbour check does): the texel's magnitude is set to the model's
 * albedo (mf_ltc_gate_texel_albedo, the refit's own magnitude) in a scratch copy of the table,
 * since the stored magnitude is the albedo checks' business, and a float32 file rounds albedos of
 * 1e-300 (charlie at alpha 1e-4) to 0, which a refit would read as a texel that shades nothing.
 * *refit_used (may be NULL): 1 if the refits ran.  Returns as mf_ltc_gate_validate. */
mf_status mf_ltc_validate_fitted(const mf_table *t, const mf_brdf_model *model, const mf_ltc_gate_options *o,
                                 mf_check *checks, int cap, int *count, int *refit_used) MF_WARN_UNUSED;

/* The neighbour check alone, the same way (mf_ltc_gate_neighbour_check_refit with that refit, or
 * mf_ltc_gate_neighbour_check for a table not recognised). */
mf_status mf_ltc_validate_neighbour_check(const mf_table *t, const mf_brdf_model *model, uint64_t seed, mf_check *c,
                                          int *refit_used);

#ifdef __cplusplus
}
#endif
#endif
