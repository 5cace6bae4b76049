/*
 * mf_brdf.h -- BRDFs and their directional albedo.
 *
 * A BRDF f(wo, wi) here is per steradian of wi (no cosine): the reflected radiance is
 * the integral of f(wo, wi) L(wi) wi.z dwi.  Directions are unit vectors in the shading frame.
 *
 *  microfacet   f = F(wh.wi) D(wh) G2(wo, wi) / (4 wo.z wi.z),  wh = normalize(wo + wi)
 *               [Walter 2007, Eq. 20], reflection only: 0 unless wo.z > 0 and wi.z > 0.
 *  LEADR        non-centred Gaussian slopes, [Dupuy 2013, Eq. 17]:
 *               I / L = (n.g)/(n.wo) F(wh.wi) D(wh) / (4 (1 + L(wo) + L(wi))),  n the mesonormal.
 *  Lambert      f = rho / pi.
 *
 * Directional albedo  rho(wo) = integral over the hemisphere of f(wo, wi) wi.z dwi,
 * by deterministic quadrature with an error bound (mf_albedo.h; mf_brdf_microfacet_albedo).
 */
#ifndef MF_BRDF_H
#define MF_BRDF_H

#include "mfkit/mf_fresnel.h"
#include "mfkit/mf_smith.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mf_microfacet {
    mf_ndf ndf;
    mf_g2_form g2;
    mf_fresnel fresnel;
} mf_microfacet;

/* Microfacet reflection BRDF [Walter 2007, Eq. 20]; 0 if wo or wi is at or below the horizon;
 * NaN for invalid parameters or non-finite directions. */
double mf_brdf_microfacet(const mf_microfacet *m, mf_vec3 wo, mf_vec3 wi);

/* LEADR specular under a directional light, the ratio I / L of [Dupuy 2013, Eq. 17]: this is
 * f(wo, wi) wi.z, defined for wi on the whole sphere (the normalisation identity after Eq. 16
 * needs the full sphere, docs/math.md, correction C-L5).  0 when wo or wi is on or below the mesosurface (nu <= 0,
 * correction C-L3).  The geometric normal g is +z and n the mesonormal of Eq. 11.
 * Reciprocity: because of the mesosurface normalisation (n.g)/(n.wo), f itself is reciprocal
 * only for centred slopes; f(wo, wi) (n.wo) wi.z is symmetric in general (tests/). */
double mf_leadr_specular(const mf_gaussian_slopes *g, mf_fresnel fresnel, mf_vec3 wo, mf_vec3 wi);
/* The same as a BRDF: mf_leadr_specular / wi.z for wi.z > 0, else 0. */
double mf_brdf_leadr_specular(const mf_gaussian_slopes *g, mf_fresnel fresnel, mf_vec3 wo, mf_vec3 wi);

/* Lambert: rho / pi for wo.z > 0 and wi.z > 0, else 0; NaN for rho outside [0, 1]. */
double mf_brdf_lambert(double rho, mf_vec3 wo, mf_vec3 wi);

/* Directional albedo of the microfacet BRDF for view wo (wo.z > 0), by a product rule of
 * n x n points (n a multiple of 8 in [8, 2048]: composite 8-point Gauss-Legendre panels) over
 * the sampler's unit square: GGX through the visible-normal map (integrand F G2 / G1(wo), in
 * [0, 1]), Beckmann through the D(wm) wm.z map, with u0 = 1 - (1 - s)^4 so that the lobe's tail
 * (a layer of width ~alpha^2 in u0) is resolved.  err is max(|Q(n) - Q(n/2)|, |Q(n/2) - Q(n/4)|):
 * the integrand has kinks where wi crosses the horizon, so convergence is algebraic and not
 * monotone and a single difference can underestimate; the two-level estimate is an estimate of the
 * error of the coarser rules, so conservative for Q(n) (checked against Monte Carlo in tests/).
 * n = 0 selects the accurate rule of mf_albedo.h instead (panels split at the horizon of wi,
 * |error| <= err, err <= 1e-8 over alpha 1e-4..1, theta_o <= 89.99 deg; docs/math.md): new
 * code should call mf_albedo_microfacet.  The n x n rule stays for the callers whose results
 * must not change (mf_validate's checks).
 * MF_ERR_DOMAIN for invalid parameters or wo.z <= 0. */
mf_status mf_brdf_microfacet_albedo(const mf_microfacet *m, mf_vec3 wo, int n, mf_result *out) MF_WARN_UNUSED;
/* Directional albedo of the LEADR specular model (integral over wi.z > 0 of
 * mf_leadr_specular(g, fresnel, wo, wi) dwi, i.e. with shadowing), by the same product rule over
 * the exact sampling map of the Gaussian slopes (Box-Muller radius and the Cholesky factor of
 * the covariance, [Dupuy 2013, Sec. 5.1]), so the integrand is (n.g)/(n.wo) F (wo.wh) /
 * (wh.z (1 + L(wo) + L(wi))).  wo must be above the mesosurface (nu > 0); the covariance must be
 * positive definite.  MF_ERR_DOMAIN otherwise. */
mf_status mf_leadr_specular_albedo(const mf_gaussian_slopes *g, mf_fresnel fresnel, mf_vec3 wo, int n,
                                   mf_result *out) MF_WARN_UNUSED;
/* Lambert albedo by the same quadrature over the cosine map (exactly rho: a pipeline check). */
mf_status mf_brdf_lambert_albedo(double rho, mf_vec3 wo, int n, mf_result *out) MF_WARN_UNUSED;

#ifdef __cplusplus
}
#endif
#endif /* MF_BRDF_H */
