/*
 * mf_model_eon.c -- the energy-preserving Oren-Nayar model (EON) [Portsmouth, Kutz & Hill 2025,
 * "EON: A Practical Energy-Preserving Rough Diffuse BRDF", JCGT 14(1), Sec. 3-4 and Listing 1]
 * (mf_model.h, name "eon"), white (single-scattering albedo rho = 1), the diffuse lobe of OpenPBR:
 *
 *   f = f_ss + f_ms,
 *   f_ss = (1/pi) (A_F + B_F s/t),  s = wi.wo - wi.z wo.z,  t = max(wi.z, wo.z) if s > 0 else 1,
 *          A_F = 1 / (1 + c1 r),  B_F = r A_F,  c1 = 1/2 - 2 / (3 pi)        (Fujii's FON [Fujii 2012])
 *   E_FON(mu) = A_F + (B_F / pi) G(mu),  the exact directional albedo of f_ss,
 *          G(mu) = S (acos(mu) - S mu) + (2/3) (S / mu) (1 - S^3) - (2/3) S,  S = sqrt(1 - mu^2)
 *   E_avg = 2 integral_0^1 E_FON(mu) mu dmu = A_F (1 + c2 r),  c2 = 2/3 - 28 / (15 pi)
 *   f_ms = (rho_ms / pi) (1 - E_FON(wo.z)) (1 - E_FON(wi.z)) / (1 - E_avg),
 *          rho_ms = rho^2 E_avg / (1 - rho (1 - E_avg)) = 1 for rho = 1.
 *
 * The compensation lobe f_ms is the Kelemen-Szirmay-Kalos form [Kelemen & Szirmay-Kalos 2001]: its
 * albedo is (1 - E_FON(wo.z)) exactly, so the albedo of EON is 1 for every view and roughness
 * (rho = 1); tests/test_models.c checks that by quadrature.  This file uses the exact E_FON
 * (the paper's Listing 1 also offers a polynomial fit of G, which breaks the exactness by up to
 * ~1e-3), and evaluates the small differences 1 - E_FON(mu) = r (c1 - G(mu)/pi) / (1 + c1 r) and
 * 1 - E_avg = r (c1 - c2) / (1 + c1 r) in these forms, so that f_ms has no 0/0 as r -> 0 and
 * needs none of the listing's epsilon clamps; (S / mu)(1 - S^3) = S mu (1 + S + S^2) / (1 + S)
 * avoids the cancellation of 1 - S^3 at normal incidence.
 *
 * Roughness: EON's r in [0, 1] is sqrt(alpha), so the table's roughness axis r (alpha = r^2) is
 * OpenPBR's base_diffuse_roughness itself (the same convention as "disney").  Reciprocal, energy
 * conserving (albedo 1).  Sampler: the cosine hemisphere split at theta_i = theta_o
 * (mf_model_sample_cosine_split: the albedo rule's panels end on the kink of s / max(wi.z, wo.z),
 * which left the fitted magnitude 7.6e-5 above 1 at alpha 1, 79 deg with the plain cosine map),
 * not the paper's clipped-LTC sampler (Sec. 5).
 */
#include "mfkit/mf_model.h"

#include <stddef.h>

#define EON_C1 (0.5 - 2.0 / (3.0 * MF_PI))
#define EON_C2 (2.0 / 3.0 - 28.0 / (15.0 * MF_PI))

/* G(mu) of E_FON [Portsmouth et al. 2025, Listing 1, E_FON_exact], mu in (0, 1]. */
static double eon_g(double mu)
{
    double s = sqrt(fmax(0.0, 1.0 - mu * mu));
    return s * (acos(fmin(1.0, mu)) - s * mu) + (2.0 / 3.0) * (s * mu * (1.0 + s + s * s) / (1.0 + s) - s);
}

static double eon_eval_cos(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, mf_vec3 wi)
{
    (void)m;
    double alpha, value;
    if (!mf_model_iso_domain(p, wo, wi, &alpha, &value))
        return value;
    double r = fmin(1.0, sqrt(alpha));
    double af = 1.0 / (1.0 + EON_C1 * r), bf = r * af;
    double s = mf_vec3_dot(wi, wo) - wi.z * wo.z;
    double sovert = s > 0.0 ? s / fmax(wi.z, wo.z) : s;
    double f_ss = af + bf * sovert;
    /* 1 - E_FON(mu) and 1 - E_avg over the common factor r / (1 + c1 r) */
    double eo = EON_C1 - eon_g(wo.z) * MF_INV_PI, ei = EON_C1 - eon_g(wi.z) * MF_INV_PI;
    double f_ms = r * af * eo * ei / (EON_C1 - EON_C2);
    return MF_INV_PI * (f_ss + f_ms) * wi.z;
}

const mf_brdf_model mf_model_eon = {
    "eon", "Energy-preserving Oren-Nayar (OpenPBR diffuse), r = sqrt(alpha), albedo 1 [Portsmouth et al. 2025]",
    MF_MODEL_ENERGY_CONSERVING | MF_MODEL_RECIPROCAL, eon_eval_cos, mf_model_sample_cosine_split, mf_model_pdf_cosine_split, NULL};
