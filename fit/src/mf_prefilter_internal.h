/* mf_prefilter_internal.h -- functions of mf_prefilter.c that the gate (mf_prefilter_gate.c) shares
 * (not installed; not a public API). */
#ifndef MF_PREFILTER_INTERNAL_H
#define MF_PREFILTER_INTERNAL_H

#include "mfkit/mf_core.h"

/* The minimal rotation taking z to the unit normal n (n.z > -1), row-major 3x3 into r. */
void mf_prefilter_min_rotation(const double *n, double *r);
/* The view wo in the texel frame of rotation r, its elevation cosine clamped to
 * MF_PREFILTER_COS_MIN at the same azimuth [Nahmias 2022, Sec. 3, "Sampling the base BRDF"]. */
mf_vec3 mf_prefilter_texel_view(const double *r, mf_vec3 wo);
/* R^T v for the row-major rotation r. */
mf_vec3 mf_prefilter_rot_t(const double *r, mf_vec3 v);

/* The fits' per-view cache of mixture m (GGX, isotropic alpha): until the next call, eval_cos, pdf,
 * sample and sample_weights at this wo use the cached texel-frame views (for tests of the fused
 * paths against the per-direction ones; the fits set it themselves).  MF_ERR_ALLOC. */
struct mf_prefilter_mix;
struct mf_brdf_params;
mf_status mf_prefilter_mix_set_view(struct mf_prefilter_mix *m, const struct mf_brdf_params *p, mf_vec3 wo);

/* The mixture's 4-wide AVX2 evaluation (mf_prefilter.c, mix_eval_pdf_batch4): used where the CPU
 * has it while mf_prefilter_mix_wide is non-zero (the default); tests set it to 0 to run the 2-wide
 * path too.  mf_prefilter_mix_wide_available: 1 if this build and CPU have the 4-wide path. */
extern int mf_prefilter_mix_wide;
int mf_prefilter_mix_wide_available(void);

#endif
