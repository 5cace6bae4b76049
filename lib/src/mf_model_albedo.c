/*
 * mf_model_albedo.c -- the directional albedo of a BRDF model (mf_model.h), the one quadrature
 * behind the LTC fitter's magnitude and Fresnel fields, the LTC gate's albedo check, bench_ltc and
 * study_ltc_texels.
 *
 * Rule: the integral over the unit square of the model's sampler (mf_model_sample: its own, or the
 * cosine hemisphere) of f cos / pdf, as a product of composite 8-point Gauss-Legendre panels,
 * the first coordinate graded towards 1 by u0 = 1 - (1 - t)^3 (Jacobian 3 (1 - t)^2).  This is
 * bit for bit the rule the LTC fitter used for its magnitude before this file existed (same
 * nodes, weights, operations and summation order), so the default LTC table did not change.
 *
 * Accuracy at the default n = 64, measured by analysis/study_albedo_rules (alpha 1e-4 .. 1 x
 * theta_o 0 .. 89.95 deg, 77 points per model) against this rule at n = 1024, which for GGX and
 * Beckmann agrees with the quartic-graded rule of mf_brdf_microfacet_albedo at n = 1024 within
 * 2.9e-6:  worst |error| GGX 3.5e-4 (alpha 0.07, normal view), Beckmann 1.6e-4, disney 2.5e-4,
 * lambert 3e-13 (exact up to rounding); mf_brdf_microfacet_albedo at n = 64 is no better (GGX
 * 2.6e-4, Beckmann 4.2e-4).  The error estimate |Q(64) - Q(32)| covers the true error at only
 * 56 / 77 GGX points and 40 / 77 Beckmann points (the integrand's kink where wi crosses the
 * horizon makes the convergence algebraic and not monotone): read err as a scale, not a bound.
 * (Those figures predate charlie's own sampler (D cos theta_h of its NDF): through the cosine
 * hemisphere charlie was not converged at low roughness and grazing views.)  The diffuse models
 * leadr-diffuse, oren-nayar and eon have samplers made for this rule (smooth in u, kinks on panel
 * edges): against adaptive references it is within 1.8e-8 for them (tests/test_models.c, "albedo").
 */
#include "mfkit/mf_model.h"

static const double gl8_x[8] = {-0.9602898564975363, -0.7966664774136267, -0.5255324099163290, -0.1834346424956498,
                                0.1834346424956498,  0.5255324099163290,  0.7966664774136267,  0.9602898564975363};
static const double gl8_w[8] = {0.1012285362903763, 0.2223810344533745, 0.3137066458778873, 0.3626837833783620,
                                0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763};

#define CHUNK 64 /* points per batch of mf_model_sample_weights_polar (stack buffers) */

/* Q(panels): the albedo and (fres not NULL) the Schlick moment, summed in the order (panel i,
 * node i, panel j, node j) with one accumulator each.  0 on success, -1 for a non-finite sum.
 * Without fres the moment is not computed (the albedo's bits are the same either way). */
static int rule(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, int panels, double *alb, double *fres)
{
    double u[2 * CHUNK], pp[2 * CHUNK], qw[CHUNK], pdf[CHUNK], w[CHUNK];
    mf_vec3 dir[CHUNK];
    double sa = 0.0, sf = 0.0;
    const int row = 8 * panels;
    /* the columns' (cos, sin)(2 pi u1), the same in every row: the disk points of
     * mf_model_polar_points (sqrt(u0) times these, the same expressions) for
     * mf_model_sample_weights_polar */
    double csn[2 * 1024];
    for (int c = 0; c < row; ++c) {
        double phi = 2.0 * MF_PI * ((c / 8 + 0.5 * (gl8_x[c % 8] + 1.0)) / panels);
        csn[2 * c] = cos(phi);
        csn[2 * c + 1] = sin(phi);
    }
    for (int pi = 0; pi < panels; ++pi)
        for (int i = 0; i < 8; ++i) {
            double tt = (pi + 0.5 * (gl8_x[i] + 1.0)) / panels, om = 1.0 - tt;
            double u0 = 1.0 - om * om * om, rr = sqrt(u0);
            for (int start = 0; start < row; start += CHUNK) {
                int k = row - start < CHUNK ? row - start : CHUNK;
                for (int q = 0; q < k; ++q) {
                    int pj = (start + q) / 8, j = (start + q) % 8;
                    u[2 * q] = u0;
                    u[2 * q + 1] = (pj + 0.5 * (gl8_x[j] + 1.0)) / panels;
                    pp[2 * q] = rr * csn[2 * (start + q)];
                    pp[2 * q + 1] = rr * csn[2 * (start + q) + 1];
                    qw[q] = 0.25 * gl8_w[i] * gl8_w[j] / ((double)panels * panels) * 3.0 * om * om;
                }
                mf_model_sample_weights_polar(m, p, wo, k, u, pp, dir, pdf, w);
                for (int q = 0; q < k; ++q) {
                    if (!(pdf[q] > 0.0) || !(dir[q].z > 0.0))
                        continue;
                    double v = w[q];
                    sa += qw[q] * v;
                    if (!fres)
                        continue;
                    mf_vec3 h = mf_vec3_normalize(mf_vec3_add(wo, dir[q]));
                    double x = 1.0 - fmin(1.0, fmax(0.0, mf_vec3_dot(wo, h)));
                    double x5 = x * x * x * x * x;
                    sf += qw[q] * v * x5;
                }
            }
        }
    *alb = sa;
    if (fres)
        *fres = sf;
    return isfinite(sa) && isfinite(sf) ? 0 : -1;
}

mf_status mf_model_albedo_fresnel(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, int n,
                                  mf_result *albedo, mf_result *fresnel)
{
    if (albedo)
        albedo->val = albedo->err = NAN;
    if (fresnel)
        fresnel->val = fresnel->err = NAN;
    if (!m || !m->eval_cos || !p || !albedo || n < 16 || n > 1024 || n % 16 != 0 || !mf_vec3_isfinite(wo) ||
        !(wo.z > 0.0))
        return MF_ERR_DOMAIN;
    double a1, f1 = 0.0, a2, f2 = 0.0;
    if (rule(m, p, wo, n / 8, &a1, fresnel ? &f1 : NULL) != 0 || rule(m, p, wo, n / 16, &a2, fresnel ? &f2 : NULL) != 0)
        return MF_ERR_DOMAIN;
    albedo->val = a1;
    albedo->err = fabs(a1 - a2);
    if (fresnel) {
        fresnel->val = f1;
        fresnel->err = fabs(f1 - f2);
    }
    return MF_OK;
}

mf_status mf_model_albedo(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, int n, mf_result *out)
{
    return mf_model_albedo_fresnel(m, p, wo, n, out, NULL);
}
