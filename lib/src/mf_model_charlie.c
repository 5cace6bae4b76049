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
 * Sampler: the micro-normal wh from the Charlie NDF's D(wh) cos theta_h, truncated to the
 * micro-normals that reflect wo above the horizon, and wi = 2 (wo.wh) wh - wo.  D is normalised so
 * that integral D cos theta_h dw = (2 + k) integral_0^{pi/2} sin^(k+1) cos d theta = 1 (k = 1/r),
 * and its CDF in theta_h is sin^(k+2) theta_h.  In the frame where wo = (sin t_o, 0, cos t_o),
 * wh = (sin t cos p, sin t sin p, cos t) reflects wo above the horizon iff
 * cos t_o cos 2t + sin t_o cos p sin 2t > 0, i.e. t < t_max(p) = (atan2(sin t_o cos p, cos t_o) +
 * pi/2) / 2 (and then wo.wh > 0 too).  So p = 2 pi u1 and sin^(k+2) t = u0 sin^(k+2) t_max(p): every
 * sample is valid and the map is smooth in u (no cut inside the albedo rule's panels), which the
 * unrestricted CDF was not: near the normal at low roughness no node of the rule reflected above
 * the horizon.  Computed in logarithms (sin^(k+2) t_max underflows at k = 1e4):
 * ln sin^2 t = 2 ln(u0) / (k+2) + 2 ln sin t_max, cos^2 t = -expm1(ln sin^2 t).
 * Density of wi: D(wh) cos theta_h / (sin^(k+2) t_max(p_h) 4 wo.wh) [Walter 2007, Eq. 14], with
 * wh = normalize(wo + wi) and p_h its azimuth from wo's.
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

/* ln sin t_max(p) for the view (sin_o, 0, cos_o) and cos p = cp (see the header). */
static double charlie_log_sin_tmax(double sin_o, double cos_o, double cp)
{
    double tmax = 0.5 * (atan2(sin_o * cp, cos_o) + 0.5 * MF_PI);
    return log(sin(tmax));
}

static double charlie_pdf(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, mf_vec3 wi)
{
    (void)m;
    double alpha = p->alpha_x;
    if (!(alpha > 0.0) || !(wo.z > 0.0) || !(wi.z > 0.0))
        return 0.0;
    double r = fmin(alpha, 1.0), k = 1.0 / r;
    mf_vec3 h = mf_vec3_add(wo, wi);
    double len = mf_vec3_length(h), hxy = hypot(h.x, h.y), oxy = hypot(wo.x, wo.y);
    if (!(len > 0.0) || !(hxy > 0.0))
        return 0.0; /* wh at the normal: D = 0 */
    double wo_h = mf_vec3_dot(wo, h) / len, cos_h = h.z / len, sin_h = hxy / len;
    if (!(wo_h > 0.0) || !(cos_h > 0.0))
        return 0.0;
    double cp = oxy > 0.0 ? (h.x * wo.x + h.y * wo.y) / (hxy * oxy) : 1.0;
    double log_s = charlie_log_sin_tmax(oxy, wo.z, fmax(-1.0, fmin(1.0, cp)));
    double pdf_h = (k + 2.0) / (2.0 * MF_PI) * cos_h * exp(k * log(sin_h) - (k + 2.0) * log_s);
    return pdf_h / (4.0 * wo_h);
}

static mf_vec3 charlie_sample(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, const double u[2],
                              double *pdf)
{
    double alpha = p->alpha_x;
    *pdf = 0.0;
    if (!(alpha > 0.0) || !(wo.z > 0.0) || !mf_vec3_isfinite(wo) || !(u[0] > 0.0))
        return mf_vec3_make(0.0, 0.0, 1.0); /* u0 = 0: wh at the normal, D = 0 (a null set) */
    double r = fmin(alpha, 1.0), k2 = 2.0 + 1.0 / r;
    double oxy = hypot(wo.x, wo.y), co = oxy > 0.0 ? wo.x / oxy : 1.0, so = oxy > 0.0 ? wo.y / oxy : 0.0;
    double phi = 2.0 * MF_PI * u[1], cp = cos(phi), sp = sin(phi);
    double e = 2.0 * log(u[0]) / k2 + 2.0 * charlie_log_sin_tmax(oxy, wo.z, cp); /* ln sin^2 theta_h */
    double st = sqrt(exp(e)), ct = sqrt(-expm1(e));
    double lx = st * cp, ly = st * sp; /* in wo's azimuthal frame, then rotated to wo's azimuth */
    mf_vec3 wh = mf_vec3_make(lx * co - ly * so, lx * so + ly * co, ct);
    double d = mf_vec3_dot(wo, wh);
    mf_vec3 wi = mf_vec3_normalize(mf_vec3_sub(mf_vec3_scale(wh, 2.0 * d), wo));
    if (!(d > 0.0) || !(wi.z > 0.0))
        return wi; /* only by rounding at t = t_max */
    *pdf = charlie_pdf(m, p, wo, wi);
    return wi;
}

const mf_brdf_model mf_model_charlie = {
    "charlie", "Charlie sheen, Lambda fit, height-correlated G2, truncated D cos sampling, not energy conserving [Estevez & Kulla 2017]",
    MF_MODEL_RECIPROCAL,
    charlie_eval_cos, charlie_sample, charlie_pdf, NULL};
