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
 *
 * Sampler: a mixture, 1/4 the cosine hemisphere (polar map) for u1 < 1/4 and 3/4 the reflected
 * micro-normals of D below, u1 rescaled to [0, 1) in each part; density 1/4 wi.z / pi + 3/4 the
 * reflected density.  The split at u1 = 1/4 is an edge of mf_model_albedo's panels (n >= 32), so
 * the albedo rule sees two smooth parts.  The cosine part covers the views where few micro-normals
 * reflect above the horizon (near the normal at low roughness no node of the D part does).
 * The D part: the micro-normal wh with density D(wh) cos theta_h, reflected: wi = 2 (wo.wh) wh - wo.
 * D is normalised so that integral D cos theta_h dw = (2 + k) integral_0^{pi/2} sin^(k+1) cos
 * d theta = 1 (k = 1/r), and its CDF in theta_h is sin^(k+2) theta_h, inverted exactly:
 * sin^2 theta_h = u0^(2/(k+2)), cos^2 theta_h = -expm1(2 ln(u0) / (k+2)) (no cancellation when
 * the NDF's mass sits at grazing micro-normals, r -> 0), phi_h = 2 pi u1.  The density of wi is
 * D(wh) cos theta_h / (4 wo.wh) [Walter 2007, Eq. 14] with wh = normalize(wo + wi); a micro-normal
 * with wo.wh <= 0 reflects below the horizon and is discarded (pdf 0), and so is wi.z <= 0.  This
 * density is > 0 wherever f is (D > 0 off the normal), so the albedo quadrature of mf_model_albedo
 * and the fitter see the grazing peak of the sheen lobe instead of missing it through the cosine
 * hemisphere (which underestimated the albedo by a third at alpha 1e-4, 89.95 deg).
 */
#include "mfkit/mf_model.h"

#include <stddef.h>

#include "mfkit/mf_sample.h"

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

/* D(wh) of [Estevez & Kulla 2017, Eq. 2] at wh = normalize(h), h = wo + wi (r in (0, 1]). */
static double charlie_d(double r, mf_vec3 h)
{
    double h_len_sq = mf_vec3_dot(h, h);
    double sin_h_sq = fmax(0.0, (h.x * h.x + h.y * h.y) / h_len_sq);
    return (2.0 + 1.0 / r) * pow(sin_h_sq, 0.5 / r) / (2.0 * MF_PI);
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
    double d = charlie_d(r, h);
    double g2 = 1.0 / (1.0 + charlie_lambda(r, wo.z) + charlie_lambda(r, wi.z));
    return d * g2 / (4.0 * wo.z);
}

#define CHARLIE_MIX 0.25 /* the cosine hemisphere's share of the sampler */

static double charlie_pdf(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, mf_vec3 wi)
{
    (void)m;
    double alpha = p->alpha_x;
    if (!(alpha > 0.0) || !(wo.z > 0.0) || !(wi.z > 0.0))
        return 0.0;
    double r = fmin(alpha, 1.0), cosine = CHARLIE_MIX * wi.z * MF_INV_PI;
    mf_vec3 h = mf_vec3_add(wo, wi);
    double len = mf_vec3_length(h);
    if (!(len > 0.0))
        return cosine;
    double wo_h = mf_vec3_dot(wo, h) / len, cos_h = h.z / len;
    if (!(wo_h > 0.0))
        return cosine;
    return cosine + (1.0 - CHARLIE_MIX) * charlie_d(r, h) * cos_h / (4.0 * wo_h);
}

static mf_vec3 charlie_sample(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, const double u[2],
                              double *pdf)
{
    double alpha = p->alpha_x;
    *pdf = 0.0;
    if (!(alpha > 0.0) || !(wo.z > 0.0) || !mf_vec3_isfinite(wo))
        return mf_vec3_make(0.0, 0.0, 1.0);
    mf_vec3 wi;
    if (u[1] < CHARLIE_MIX) {
        double v[2] = {u[0], u[1] / CHARLIE_MIX};
        wi = mf_sample_cosine_hemisphere_polar(v);
    } else {
        double r = fmin(alpha, 1.0), k2 = 2.0 + 1.0 / r;
        double e = u[0] > 0.0 ? 2.0 * log(u[0]) / k2 : -INFINITY;
        double sin_sq = exp(e), cos_sq = -expm1(e); /* sin^2 theta_h = u0^(2/(k+2)) */
        double st = sqrt(sin_sq), ct = sqrt(cos_sq), phi = 2.0 * MF_PI * (u[1] - CHARLIE_MIX) / (1.0 - CHARLIE_MIX);
        mf_vec3 wh = mf_vec3_make(st * cos(phi), st * sin(phi), ct);
        double d = mf_vec3_dot(wo, wh);
        if (!(d > 0.0))
            return mf_vec3_make(0.0, 0.0, -1.0);
        wi = mf_vec3_normalize(mf_vec3_sub(mf_vec3_scale(wh, 2.0 * d), wo));
    }
    if (!(wi.z > 0.0))
        return wi;
    *pdf = charlie_pdf(m, p, wo, wi);
    return wi;
}

const mf_brdf_model mf_model_charlie = {
    "charlie", "Charlie sheen, Lambda fit, height-correlated G2, D cos + cosine sampling, not energy conserving [Estevez & Kulla 2017]",
    MF_MODEL_RECIPROCAL,
    charlie_eval_cos, charlie_sample, charlie_pdf, NULL};
