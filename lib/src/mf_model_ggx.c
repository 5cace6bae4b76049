/*
 * mf_model_ggx.c -- GGX microfacet reflection for LTC fitting (mf_model.h).
 *
 * f = D(wh) G2(wo, wi) / (4 wo.z wi.z), F = 1 [Walter 2007, Eq. 20 and 33], with the
 * height-correlated masking-shadowing G2 = 1 / (1 + Lambda(wo) + Lambda(wi)) [Heitz 2014].
 * Sampler: visible normals [Heitz 2018, Listing 1], density of wm G1(wo) max(0, wo.wm) D(wm) / wo.z
 * per steradian of wm, reflected about wm; the density of wi is that / (4 |wo.wm|)
 * [Walter 2007, Eq. 14], per steradian of wi, i.e. G1(wo) D(wm) / (4 wo.z).
 *
 * The fitter and the gate evaluate f cos and the density millions of times per table, so both
 * are written here in closed form for the isotropic case (the generic mf_brdf_microfacet path
 * builds an NDF and a Fresnel record and normalises wh per call):
 *   D(h) = alpha^2 |h|^4 / (pi (alpha^2 h.z^2 + h.x^2 + h.y^2)^2)   for an unnormalised h,
 *   Lambda(w) = (sqrt(1 + t) - 1) / 2 = t / (2 (1 + sqrt(1 + t))),  t = alpha^2 (w.x^2 + w.y^2) / w.z^2,
 * which have no cancellation at alpha -> 0 or at grazing (no 1 - z^2, no sqrt(1 + t) - 1).
 * tests/test_ltcfit.c (test_ggx_model) holds them against the generic mf_brdf_microfacet path.
 */
#include "mfkit/mf_brdf.h"
#include "mfkit/mf_model.h"
#include "mfkit/mf_sample.h"

/* D of the direction of the unnormalised h (h.z > 0). */
static inline double ggx_d_unnorm(double a2, mf_vec3 h)
{
    double s2 = h.x * h.x + h.y * h.y, z2 = h.z * h.z;
    double den = a2 * z2 + s2, l2 = s2 + z2;
    return a2 * l2 * l2 / (MF_PI * den * den);
}

/* Smith Lambda of GGX for a unit (or unnormalised) w with w.z > 0. */
static inline double ggx_lambda(double a2, mf_vec3 w)
{
    double t = a2 * (w.x * w.x + w.y * w.y) / (w.z * w.z);
    return 0.5 * t / (1.0 + sqrt(1.0 + t));
}

static double ggx_eval_cos(const mf_brdf_model *m, double alpha, mf_vec3 wo, mf_vec3 wi)
{
    (void)m;
    if (!(wi.z > 0.0) || !(wo.z > 0.0) || !(alpha > 0.0) || !mf_vec3_isfinite(wo) || !mf_vec3_isfinite(wi))
        return (isnan(wi.z) || isnan(wo.z) || !(alpha > 0.0)) ? NAN : 0.0;
    double a2 = alpha * alpha;
    mf_vec3 h = mf_vec3_add(wo, wi);
    double g2 = 1.0 / (1.0 + ggx_lambda(a2, wo) + ggx_lambda(a2, wi));
    return ggx_d_unnorm(a2, h) * g2 / (4.0 * wo.z);
}

/* Density per steradian of wi = reflect(wo, wm): G1(wo) D(wm) / (4 wo.z) (0 if wo.wm <= 0). */
static double ggx_density(double a2, mf_vec3 wo, mf_vec3 wm)
{
    if (!(mf_vec3_dot(wo, wm) > 0.0) || !(wm.z > 0.0))
        return 0.0;
    return ggx_d_unnorm(a2, wm) / ((1.0 + ggx_lambda(a2, wo)) * 4.0 * wo.z);
}

static mf_vec3 ggx_sample(const mf_brdf_model *m, double alpha, mf_vec3 wo, const double u[2], double *pdf)
{
    (void)m;
    mf_vec3 wm = mf_sample_ggx_vndf(alpha, alpha, wo, u);
    mf_vec3 wi = mf_vec3_reflect(wo, wm);
    *pdf = wi.z > 0.0 && wo.z > 0.0 ? ggx_density(alpha * alpha, wo, wm) : 0.0;
    return wi;
}

static double ggx_pdf(const mf_brdf_model *m, double alpha, mf_vec3 wo, mf_vec3 wi)
{
    (void)m;
    if (!(wi.z > 0.0) || !(wo.z > 0.0))
        return 0.0;
    return ggx_density(alpha * alpha, wo, mf_vec3_add(wo, wi));
}

const mf_brdf_model mf_model_ggx = {
    "ggx", "GGX microfacet, height-correlated Smith G2, F = 1 [Walter 2007, Eq. 20, 33; Heitz 2014]",
    ggx_eval_cos, ggx_sample, ggx_pdf};
