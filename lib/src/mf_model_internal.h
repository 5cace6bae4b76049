/* mf_model_internal.h -- functions of the model files shared inside the core (not installed). */
#ifndef MF_MODEL_INTERNAL_H
#define MF_MODEL_INTERNAL_H

#include "mfkit/mf_model.h"

/* mf_model_sample_weights_polar's GGX branch (mf_model_ggx.c): the disk points pp of
 * mf_model_polar_points instead of the unit-square points. */
void mf_model_ggx_sample_weights_polar(const mf_brdf_params *p, mf_vec3 wo, int n, const double *pp, mf_vec3 *wi,
                                       double *pdf, double *w);

#endif
