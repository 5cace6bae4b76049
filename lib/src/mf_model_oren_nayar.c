/*
 * mf_model_oren_nayar.c -- LEADR's rough diffuse BRDF for centred isotropic Beckmann slopes
 * (mf_model.h, name "oren-nayar").
 *
 * LEADR's diffuse radiance [Dupuy 2013, Eq. 21] under a directional light of unit irradiance from
 * wi, for centred slopes (mesonormal n = g = z, so the prefactor (n.g)/(n.wo) is 1/wo.z) and the
 * masking-aware irradiance of Eq. 20, E(wn) = <wn, wi> / (1 + Lambda(wo) + Lambda(wi)), is
 *
 *   f(wo, wi) wi.z = 1 / (pi wo.z (1 + Lambda(wo) + Lambda(wi)))
 *                    * integral P22(s) <wn(s), wi> <wn(s), wo> / wn(s).z  d^2 s,
 *
 * Beckmann slopes of variance alpha^2 / 2 per axis (alpha^2 = 2 sigma^2, mf_ndf.h); the paper
 * relates this model to Oren-Nayar.  For alpha -> 0 it is Lambert (wi.z / pi).
 *
 * The slope integral is a deterministic product rule: the slopes are the exact transform of
 * u in [0,1)^2 to P22 (radius alpha sqrt(-ln(1 - u0)), angle 2 pi u1; the D(wm) wm.z map of
 * mf_sample_ndf_normal), and u runs over 2 x 2 panels of the 8-point Gauss-Legendre rule
 * (16 x 16 = 256 nodes).  The <.,.> kinks make it converge slowly: its accuracy has not been
 * measured separately (the fitter's albedo quadrature sees its values as exact).  mf_leadr_diffuse is not used: its grid is LEADR's truncated, renormalised one
 * (docs/math.md, correction C-L7), which does not converge to the integral at a fixed lambda, and it evaluates the
 * irradiance callback (with an erfc per call) for every slope sample.
 * No sampler: the fitter uses cosine-hemisphere sampling (the lobe is close to Lambert).
 */
#include "mfkit/mf_model.h"

#include <stddef.h>
#include "mfkit/mf_smith.h"

static const double gl8_x[8] = {-0.9602898564975363, -0.7966664774136267, -0.5255324099163290, -0.1834346424956498,
                                0.1834346424956498,  0.5255324099163290,  0.7966664774136267,  0.9602898564975363};
static const double gl8_w[8] = {0.1012285362903763, 0.2223810344533745, 0.3137066458778873, 0.3626837833783620,
                                0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763};

#define ON_PANELS 2
#define ON_N (8 * ON_PANELS)

static double on_eval_cos(const mf_brdf_model *m, const mf_brdf_params *prm, mf_vec3 wo, mf_vec3 wi)
{
    (void)m;
    double alpha, value;
    if (!mf_model_iso_domain(prm, wo, wi, &alpha, &value))
        return value;
    double node[ON_N], weight[ON_N];
    for (int p = 0; p < ON_PANELS; ++p)
        for (int k = 0; k < 8; ++k) {
            node[8 * p + k] = (p + 0.5 * (gl8_x[k] + 1.0)) / ON_PANELS;
            weight[8 * p + k] = 0.5 * gl8_w[k] / ON_PANELS;
        }
    /* the angles' cosines and sines once per call, not once per node pair (same values: the
     * 16 x 16 rule took 256 sincos per evaluation, 35 % of an oren-nayar fit) */
    double cphi[ON_N], sphi[ON_N];
    for (int j = 0; j < ON_N; ++j) {
        double phi = 2.0 * MF_PI * node[j];
        cphi[j] = cos(phi);
        sphi[j] = sin(phi);
    }
    double sum = 0.0;
    for (int i = 0; i < ON_N; ++i) {
        double r = alpha * sqrt(-log1p(-node[i]));
        for (int j = 0; j < ON_N; ++j) {
            double sx = r * cphi[j], sy = r * sphi[j];
            /* wn = (-sx, -sy, 1) / sqrt(1 + |s|^2); <wn,wi><wn,wo>/wn.z = (.)(.) / (1 + |s|^2)^(1/2) ... */
            double q = 1.0 + sx * sx + sy * sy;
            double di = -sx * wi.x - sy * wi.y + wi.z, dd = -sx * wo.x - sy * wo.y + wo.z;
            if (di <= 0.0 || dd <= 0.0)
                continue;
            /* <wn,wi> <wn,wo> / wn.z = (di / sqrt q)(dd / sqrt q) / (1 / sqrt q) = di dd / sqrt q */
            sum += weight[i] * weight[j] * di * dd / sqrt(q);
        }
    }
    double lo = mf_smith_lambda_beckmann(alpha, alpha, wo), li = mf_smith_lambda_beckmann(alpha, alpha, wi);
    return sum / (MF_PI * wo.z * (1.0 + lo + li));
}

const mf_brdf_model mf_model_oren_nayar = {
    "oren-nayar", "LEADR rough diffuse, centred isotropic Beckmann slopes [Dupuy 2013, Eq. 20-21]",
    MF_MODEL_ENERGY_CONSERVING | MF_MODEL_RECIPROCAL, on_eval_cos, NULL, NULL, NULL};
