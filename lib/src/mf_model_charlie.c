/*
 * mf_model_charlie.c -- the "Charlie" sheen lobe [Estevez & Kulla 2017, "Production Friendly
 * Microfacet Sheen BRDF", Sony Pictures Imageworks technical report] (mf_model.h, name "charlie").
 *
 *   D(wh) = (2 + 1/r) sin^(1/r)(theta_h) / (2 pi)                         [Estevez & Kulla 2017, Eq. 2]
 *   f     = D(wh) G2(wo, wi) / (4 wo.z wi.z),  G2 = 1 / (1 + Lambda(wo) + Lambda(wi))
 *   Lambda(cos t) = exp(L(cos t))                  for cos t < 1/2
 *                 = exp(2 L(1/2) - L(1 - cos t))   otherwise,
 *   L(x) = a / (1 + b x^c) + d x + e, with (a, b, c, d, e) interpolated by (1 - r)^2 between the
 *   fits at r = 1 (21.5473, 3.82987, 0.19823, -1.97760, -4.32054) and r = 0 (25.3245, 3.32435,
 *   0.16801, -1.27393, -4.85967)                                          [Estevez & Kulla 2017, Table 1]
 *
 * r = alpha (the roughness axis gives r = max(table r^2, alpha_min)).  Visibility choice: the
 * paper's physically based height-correlated Smith form with the Lambda fit above, WITHOUT the
 * "terminator softening" exponent 1 + 2 (1 - cos)^8 (a shading-normal artistic fix, not part of
 * the microfacet model) and not the approximate 1 / (4 (wi.z + wo.z - wi.z wo.z)) visibility of
 * Neubelt & Pettineo 2013 used by some real-time engines.  F = 1.
 * No sampler (cosine-hemisphere sampling; the lobe is wide).
 */
#include "mfkit/mf_model.h"

#include <stddef.h>

static double charlie_l(double r, double x)
{
    double t = (1.0 - r) * (1.0 - r);
    double a = 21.5473 + t * (25.3245 - 21.5473);
    double b = 3.82987 + t * (3.32435 - 3.82987);
    double c = 0.19823 + t * (0.16801 - 0.19823);
    double d = -1.97760 + t * (-1.27393 + 1.97760);
    double e = -4.32054 + t * (-4.85967 + 4.32054);
    return a / (1.0 + b * pow(x, c)) + d * x + e;
}

static double charlie_lambda(double r, double cos_t)
{
    return cos_t < 0.5 ? exp(charlie_l(r, cos_t)) : exp(2.0 * charlie_l(r, 0.5) - charlie_l(r, 1.0 - cos_t));
}

static double charlie_eval_cos(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, mf_vec3 wi)
{
    (void)m;
    double alpha, value;
    if (!mf_model_iso_domain(p, wo, wi, &alpha, &value))
        return value;
    double r = fmin(alpha, 1.0);
    mf_vec3 h = mf_vec3_add(wo, wi);
    double h_len_sq = mf_vec3_dot(h, h);
    if (!(h_len_sq > 0.0))
        return 0.0;
    double sin_h_sq = fmax(0.0, (h.x * h.x + h.y * h.y) / h_len_sq);
    double d = (2.0 + 1.0 / r) * pow(sin_h_sq, 0.5 / r) / (2.0 * MF_PI);
    double g2 = 1.0 / (1.0 + charlie_lambda(r, wo.z) + charlie_lambda(r, wi.z));
    return d * g2 / (4.0 * wo.z);
}

const mf_brdf_model mf_model_charlie = {
    "charlie", "Charlie sheen, Lambda fit, height-correlated G2, not energy conserving [Estevez & Kulla 2017]",
    MF_MODEL_RECIPROCAL,
    charlie_eval_cos, NULL, NULL, NULL};
