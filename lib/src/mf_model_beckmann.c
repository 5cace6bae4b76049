/*
 * mf_model_beckmann.c -- Beckmann microfacet reflection for LTC fitting (mf_model.h).
 *
 * f = D(wh) G2(wo, wi) / (4 wo.z wi.z), F = 1 [Walter 2007, Eq. 20 and 25], with the
 * height-correlated G2 = 1 / (1 + Lambda(wo) + Lambda(wi)) and the exact (erfc) Lambda [Heitz 2014];
 * anisotropic (alpha_x, alpha_y) by stretching [Heitz 2014], through the generic microfacet path
 * (mf_brdf_microfacet, mf_ndf.h).
 * Sampler: micro-normals with density D(wm) wm.z per steradian of wm [Walter 2007, Eq. 28-29],
 * reflected about wm; the density of wi is D(wm) wm.z / (4 |wo.wm|) [Walter 2007, Eq. 14], per
 * steradian of wi (samples below the horizon get density 0 and are discarded by the caller).
 */
#include "mfkit/mf_brdf.h"
#include "mfkit/mf_model.h"
#include "mfkit/mf_sample.h"

static double beckmann_eval_cos(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, mf_vec3 wi)
{
    (void)m;
    mf_microfacet mf = {mf_ndf_make(MF_NDF_BECKMANN, p->alpha_x, p->alpha_y), MF_G2_JOINT,
                        {MF_FRESNEL_NONE, 0.0, 1.0, 0.0}};
    if (!(wi.z > 0.0) || !(wo.z > 0.0))
        return (isnan(wi.z) || isnan(wo.z) || !(p->alpha_x > 0.0) || !(p->alpha_y > 0.0)) ? NAN : 0.0;
    return mf_brdf_microfacet(&mf, wo, wi) * wi.z;
}

static double beckmann_pdf(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, mf_vec3 wi)
{
    (void)m;
    if (!(wi.z > 0.0) || !(wo.z > 0.0))
        return 0.0;
    mf_vec3 wm = mf_vec3_normalize(mf_vec3_add(wo, wi));
    return mf_pdf_reflected(mf_pdf_ndf_normal(mf_ndf_make(MF_NDF_BECKMANN, p->alpha_x, p->alpha_y), wm), wo, wm);
}

static mf_vec3 beckmann_sample(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, const double u[2],
                               double *pdf)
{
    mf_vec3 wm = mf_sample_ndf_normal(mf_ndf_make(MF_NDF_BECKMANN, p->alpha_x, p->alpha_y), u);
    mf_vec3 wi = mf_vec3_reflect(wo, wm);
    *pdf = (wi.z > 0.0 && mf_vec3_dot(wo, wm) > 0.0) ? beckmann_pdf(m, p, wo, wi) : 0.0;
    return wi;
}

const mf_brdf_model mf_model_beckmann = {
    "beckmann",
    "Beckmann microfacet, anisotropic, height-correlated Smith G2, F = 1, D(wm) wm.z sampling "
    "[Walter 2007, Eq. 20, 25, 28-29; Heitz 2014]",
    MF_MODEL_ANISOTROPIC | MF_MODEL_ENERGY_CONSERVING | MF_MODEL_RECIPROCAL,
    beckmann_eval_cos,
    beckmann_sample,
    beckmann_pdf,
    NULL};
