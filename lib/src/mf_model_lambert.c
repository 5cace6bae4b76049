/*
 * mf_model_lambert.c -- the Lambertian BRDF 1/pi (mf_model.h): its LTC is the identity matrix,
 * for every alpha and view (alpha is ignored), which makes it a test of the fitting pipeline.
 * No sampler: the fitter's default cosine-hemisphere sampling is exactly proportional to f cos.
 */
#include "mfkit/mf_model.h"

#include <stddef.h>

static double lambert_eval_cos(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, mf_vec3 wi)
{
    (void)m;
    double alpha = p->alpha_x; /* isotropic: alpha_y is not read */
    if (isnan(alpha) || isnan(wo.z) || isnan(wi.z))
        return NAN;
    return (wo.z > 0.0 && wi.z > 0.0) ? wi.z * MF_INV_PI : 0.0;
}

const mf_brdf_model mf_model_lambert = {"lambert", "Lambert 1/pi (the identity LTC; alpha is not read) [Lambert 1760]",
                                        MF_MODEL_ENERGY_CONSERVING | MF_MODEL_RECIPROCAL,
                                        lambert_eval_cos, NULL, NULL, NULL};
