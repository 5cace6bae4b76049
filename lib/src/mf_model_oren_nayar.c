/*
 * mf_model_oren_nayar.c -- the qualitative Oren-Nayar model (QON) [Oren & Nayar 1994, "Generalization
 * of Lambert's Reflectance Model", SIGGRAPH, Eq. 30] (mf_model.h, name "oren-nayar"):
 *
 *   f(wo, wi) = (1/pi) (A + B max(0, cos(phi_i - phi_o)) sin(a) tan(b)),   a = max(theta_i, theta_o),
 *   A = 1 - 0.5 sigma^2 / (sigma^2 + 0.33),  B = 0.45 sigma^2 / (sigma^2 + 0.09),   b = min(theta_i, theta_o),
 *
 * white (albedo parameter rho = 1), without the paper's interreflection term (Eq. 30 is the
 * qualitative model as it is used).  The angular factor is evaluated without trigonometry as
 * max(0, s) / t with s = wi.wo - wi.z wo.z = sin theta_i sin theta_o cos(phi_i - phi_o) and
 * t = max(wi.z, wo.z) = cos b, which is the same number [Fujii 2012, "A tiny improvement of
 * Oren-Nayar reflectance model"]: sin a sin b / cos b = sin a tan b.
 *
 * Roughness: sigma, the standard deviation of the facet slope angle of Oren and Nayar's V-cavities
 * (radians), is sigma = alpha / sqrt(2): the per-axis RMS slope of the Beckmann surface of alpha
 * (alpha^2 = 2 sigma^2, the identification LEADR uses between its rough diffuse model and
 * Oren-Nayar [Dupuy 2013, Sec. 4.3]), slope and angle identified to first order.  So at the same
 * alpha "oren-nayar" and "leadr-diffuse" describe the same slope statistics; the table's r = 1
 * is sigma = 0.707 rad (40.5 deg).
 *
 * Energy: QON does NOT conserve energy, and does not claim to.  Its albedo is A + a B term >= A,
 * below 1 at most views, but above 1 at grazing views for small sigma (measured by adaptive
 * quadrature in tests/test_models.c: 1.0042 at alpha 0.1, theta_o 89 deg; 1 + 5e-9 at alpha 1e-4):
 * the B term's tan b grows faster than A falls.  EON ("eon") is the energy-preserving variant.
 * Reciprocal.  Sampler: the cosine hemisphere split at theta_i = theta_o (mf_model_sample_cosine_split), so
 * that the albedo rule's panels end on the kink of max(0, s) / t.
 */
#include "mfkit/mf_model.h"

#include <stddef.h>

static double qon_eval_cos(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, mf_vec3 wi)
{
    (void)m;
    double alpha, value;
    if (!mf_model_iso_domain(p, wo, wi, &alpha, &value))
        return value;
    double s2 = 0.5 * alpha * alpha; /* sigma^2 */
    double a = 1.0 - 0.5 * s2 / (s2 + 0.33), b = 0.45 * s2 / (s2 + 0.09);
    double s = mf_vec3_dot(wi, wo) - wi.z * wo.z;
    double st = s > 0.0 ? s / fmax(wi.z, wo.z) : 0.0;
    return MF_INV_PI * (a + b * st) * wi.z;
}

const mf_brdf_model mf_model_oren_nayar = {
    "oren-nayar", "Oren-Nayar qualitative model, sigma = alpha / sqrt(2), not energy conserving [Oren & Nayar 1994, Eq. 30]",
    MF_MODEL_RECIPROCAL, qon_eval_cos, mf_model_sample_cosine_split, mf_model_pdf_cosine_split, NULL};
