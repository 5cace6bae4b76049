/*
 * mf_model_ggx.c -- GGX microfacet reflection for LTC fitting (mf_model.h).
 *
 * f = D(wh) G2(wo, wi) / (4 wo.z wi.z), F = 1 [Walter 2007, Eq. 20 and 33], with the
 * height-correlated masking-shadowing G2 = 1 / (1 + Lambda(wo) + Lambda(wi)) [Heitz 2014].
 * Sampler: visible normals [Heitz 2018, Listing 1], density of wm G1(wo) max(0, wo.wm) D(wm) / wo.z
 * per steradian of wm, reflected about wm; the density of wi is that / (4 |wo.wm|)
 * [Walter 2007, Eq. 14], per steradian of wi.
 */
#include "mfkit/mf_brdf.h"
#include "mfkit/mf_model.h"
#include "mfkit/mf_sample.h"

static double ggx_eval_cos(const mf_brdf_model *m, double alpha, mf_vec3 wo, mf_vec3 wi)
{
    (void)m;
    mf_microfacet mf = {mf_ndf_make(MF_NDF_GGX, alpha, alpha), MF_G2_JOINT, {MF_FRESNEL_NONE, 0.0, 1.0, 0.0}};
    if (!(wi.z > 0.0) || !(wo.z > 0.0))
        return (isnan(wi.z) || isnan(wo.z) || !(alpha > 0.0)) ? NAN : 0.0;
    return mf_brdf_microfacet(&mf, wo, wi) * wi.z;
}

static mf_vec3 ggx_sample(const mf_brdf_model *m, double alpha, mf_vec3 wo, const double u[2], double *pdf)
{
    (void)m;
    mf_vec3 wm = mf_sample_ggx_vndf(alpha, alpha, wo, u);
    mf_vec3 wi = mf_vec3_reflect(wo, wm);
    *pdf = wi.z > 0.0 ? mf_pdf_reflected(mf_pdf_ggx_vndf(alpha, alpha, wo, wm), wo, wm) : 0.0;
    return wi;
}

static double ggx_pdf(const mf_brdf_model *m, double alpha, mf_vec3 wo, mf_vec3 wi)
{
    (void)m;
    if (!(wi.z > 0.0) || !(wo.z > 0.0))
        return 0.0;
    mf_vec3 wm = mf_vec3_normalize(mf_vec3_add(wo, wi));
    return mf_pdf_reflected(mf_pdf_ggx_vndf(alpha, alpha, wo, wm), wo, wm);
}

const mf_brdf_model mf_model_ggx = {
    "ggx", "GGX microfacet, height-correlated Smith G2, F = 1 [Walter 2007, Eq. 20, 33; Heitz 2014]",
    ggx_eval_cos, ggx_sample, ggx_pdf};
