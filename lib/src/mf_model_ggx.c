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

/* ggx_sample + ggx_eval_cos for n points, with the same operations in the same order (so the same
 * bits), the view-dependent parts hoisted: the visible-normal frame of mf_sample_ggx_vndf
 * [Heitz 2018, Listing 1] and Lambda(wo).  tests/test_ltcfit.c (test_ggx_model) compares them. */
static void ggx_sample_weights(const mf_brdf_model *m, double alpha, mf_vec3 wo, int n, const double *u, mf_vec3 *wi,
                               double *pdf, double *w)
{
    (void)m;
    if (!(alpha > 0.0) || !(wo.z > 0.0) || !mf_vec3_isfinite(wo)) {
        for (int i = 0; i < n; ++i) {
            wi[i] = mf_vec3_make(NAN, NAN, NAN);
            pdf[i] = w[i] = 0.0;
        }
        return;
    }
    const double a2 = alpha * alpha, lo = ggx_lambda(a2, wo);
    mf_vec3 vh = mf_vec3_normalize(mf_vec3_make(alpha * wo.x, alpha * wo.y, wo.z));
    double lensq = vh.x * vh.x + vh.y * vh.y;
    mf_vec3 t1 = lensq > 0.0 ? mf_vec3_scale(mf_vec3_make(-vh.y, vh.x, 0.0), 1.0 / sqrt(lensq))
                             : mf_vec3_make(1.0, 0.0, 0.0);
    mf_vec3 t2 = mf_vec3_cross(vh, t1);
    double s = 0.5 * (1.0 + vh.z);
    for (int i = 0; i < n; ++i) {
        double r = sqrt(u[2 * i]);
        double phi = 2.0 * MF_PI * u[2 * i + 1];
        double p1 = r * cos(phi), p2 = r * sin(phi);
        p2 = (1.0 - s) * sqrt(fmax(0.0, 1.0 - p1 * p1)) + s * p2;
        double pz = sqrt(fmax(0.0, 1.0 - p1 * p1 - p2 * p2));
        mf_vec3 nh = mf_vec3_add(mf_vec3_add(mf_vec3_scale(t1, p1), mf_vec3_scale(t2, p2)), mf_vec3_scale(vh, pz));
        mf_vec3 wm = mf_vec3_normalize(mf_vec3_make(alpha * nh.x, alpha * nh.y, fmax(0.0, nh.z)));
        mf_vec3 v = mf_vec3_reflect(wo, wm);
        double p = 0.0;
        if (v.z > 0.0 && mf_vec3_dot(wo, wm) > 0.0 && wm.z > 0.0)
            p = ggx_d_unnorm(a2, wm) / ((1.0 + lo) * 4.0 * wo.z);
        double wt = 0.0;
        if (p > 0.0 && v.z > 0.0 && mf_vec3_isfinite(v)) {
            mf_vec3 h = mf_vec3_add(wo, v);
            double g2 = 1.0 / (1.0 + lo + ggx_lambda(a2, v));
            wt = ggx_d_unnorm(a2, h) * g2 / (4.0 * wo.z) / p;
        }
        wi[i] = v;
        pdf[i] = p;
        w[i] = wt;
    }
}

const mf_brdf_model mf_model_ggx = {
    "ggx", "GGX microfacet, height-correlated Smith G2, F = 1 [Walter 2007, Eq. 20, 33; Heitz 2014]",
    ggx_eval_cos, ggx_sample, ggx_pdf, ggx_sample_weights};
