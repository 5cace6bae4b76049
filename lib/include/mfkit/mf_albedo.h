/*
 * mf_albedo.h -- the directional albedo of the microfacet reflection BRDF to 1e-9, fast.
 *
 *   rho(wo) = integral over wi.z > 0 of f(wo, wi) wi.z dwi,   f = F D G2 / (4 wo.z wi.z)
 *   [Walter 2007, Eq. 20],
 *
 * for a centred GGX or Beckmann NDF (anisotropic allowed), joint or separable G2, and any
 * Fresnel descriptor whose value is an analytic function of wo.wm (none, Schlick, conductor, dielectric
 * with eta >= 1).  A dielectric with eta < 1 (total internal reflection: a kink in F) is computed
 * by mf_albedo_dielectric's rule, which ends its panels on the critical angle (isotropic NDFs only;
 * MF_ERR_DOMAIN for anisotropic ones).
 *
 * Method (docs/math.md, "BRDFs and albedo").  With dwi = 4 (wo.wm) dwm [Walter 2007, Eq. 14]
 * and D(wm) wm.z dwm = P22(s) ds (s the slope of wm, wm ~ (s, 1)):
 *   rho = integral F G2 P22(s) (wo.z + s . wo_xy) / wo.z ds,
 * over the slopes whose reflection wi = 2 (wo.wm) wm - wo is above the horizon.  That set is the
 * DISK |s - wo_xy / wo.z| < 1 / wo.z (wi.z > 0 <=> wo.z |s|^2 - 2 s.wo_xy - wo.z < 0), so the
 * horizon of wi, where the integrand has its kink, is a curve known in closed form.  In the
 * stretched slopes p = (s_x / alpha_x, s_y / alpha_y), polar (r, phi) around the lobe's centre,
 * the ray of direction phi leaves the disk at r_max(phi) = 1 / (sqrt(k^2 + q) - k) with
 * k = (S e) . wo_xy / wo.z, q = |S e|^2, S = diag(alpha_x, alpha_y); for GGX r = tan t
 * (t in [0, atan r_max], measure sin t cos t dt dphi / pi), for Beckmann r itself (measure
 * exp(-r^2) r dr dphi / pi, cut at r = 7).  Inside the disk the integrand is analytic up to the
 * boundary (G2 -> 0 linearly in wi.z there, and is analytic in wi.z), so Gauss-Legendre panels
 * converge exponentially.  Two near-singularities remain and are resolved by panels graded
 * geometrically (ratio 1/5) towards them: the layer of width ~alpha in wi.z where G1(wi) turns
 * over, at the end of each ray; and, for views beyond ~45 deg, the directions phi where k
 * changes sign (the ray's exit jumps between the near and the far side of the disk) over
 * |k| ~ sqrt(q), a width ~ cot(theta_o) in phi.  An isotropic NDF is integrated over half the
 * circle (symmetry about the view's azimuth); at normal incidence over one direction.
 *
 * The value is the rule with 12 points per panel and the error estimate is |Q12 - Q8| (the same
 * panels with 8 points), plus 64 ulp of the result for rounding: the panels make Q8 converge
 * exponentially, so Q12 is far more accurate than Q8 and |Q12 - Q8| bounds its error.
 * Verified against an independent nested adaptive Gauss-Kronrod quadrature in the spherical
 * coordinates of wi (tests/test_energy.c; the measured figures in docs/math.md).
 *
 * Pure C11; no allocation, no state: safe from any number of threads.
 */
#ifndef MF_ALBEDO_H
#define MF_ALBEDO_H

#include "mfkit/mf_brdf.h"
#include "mfkit/mf_fresnel.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The albedo of m (its NDF, G2 and Fresnel) for the view wo (unit, wo.z > 0).
 * MF_ERR_DOMAIN for an invalid NDF, a non-finite or non-unit wo, wo.z <= 0, or a Fresnel
 * descriptor outside its domain (out = NaN). */
mf_status mf_albedo_microfacet(const mf_microfacet *m, mf_vec3 wo, mf_result *out) MF_WARN_UNUSED;

/* The two Schlick moments of the albedo with F = 1 (the split-sum DFG terms, [Karis 2013]):
 *   scale = integral f1 (1 - (1 - wo.wm)^5) wi.z dwi,   bias = integral f1 (1 - wo.wm)^5 wi.z dwi,
 * so that F0 scale + bias is the albedo with Schlick's Fresnel of F0.  One pass computes both;
 * each has its own error bound.  Same domain as mf_albedo_microfacet (m->fresnel is ignored). */
mf_status mf_albedo_microfacet_schlick(const mf_microfacet *m, mf_vec3 wo, mf_result *scale,
                                       mf_result *bias) MF_WARN_UNUSED;

/* The independent reference of the tests and gates: nested adaptive Gauss-Kronrod (mf_quad_adaptive)
 * in the polar angles (theta, phi) of the micro-normal about the normal, of
 * D(h) G2(wo, wi) F(wo.h) (wo.h) / wo.z sin(theta) [Walter 2007, Eq. 14, 20], the inner integral
 * ending exactly on the horizon of wi (theta_k(phi) = atan2(wo.z, -wo.x cos phi) / 2), with
 * breakpoints at alpha 2^j from the pole and towards theta_k.  The lobe's peak is the pole, so it
 * converges for every alpha >= 1e-4 and view up to 89.99 deg (the whole table domain).  tol is the
 * absolute tolerance; out->err = the outer rule's estimate + tol / 4 (the inner rules' share) +
 * 1e-13 |val| (their relative guard).  About 0.01 to 0.5 s: for tests, gates and studies.
 * Isotropic NDFs and wo.y = 0, wo.x >= 0 only; MF_ERR_DOMAIN otherwise; MF_ERR_NO_CONVERGENCE if an
 * adaptive rule ran out of intervals (out keeps its estimate). */
mf_status mf_albedo_microfacet_reference(const mf_microfacet *m, mf_vec3 wo, double tol, mf_result *out) MF_WARN_UNUSED;

/* A second, older reference (for cross-checking the first): nested adaptive Gauss-Kronrod over the
 * spherical angles of wi (theta_i broken at the mirror direction and graded around it, phi_i over
 * [0, pi]).  Converges only for alpha >= ~0.01 and views below ~89 deg (measured: at alpha 1e-4
 * off the normal it runs out of intervals after ~45 s).  Same domain and statuses. */
mf_status mf_albedo_microfacet_reference_wi(const mf_microfacet *m, mf_vec3 wo, double tol, mf_result *out) MF_WARN_UNUSED;

/* The directional albedo of the Charlie sheen lobe as engines tabulate it (Filament's DFG LUT, third
 * channel): f = D V with D = (2 + 1/a) sin(theta_h)^(1/a) / (2 pi) [Estevez and Kulla 2017, Eq. 2]
 * and V = 1 / (4 (wi.z + wo.z - wi.z wo.z)) [Neubelt and Pettineo 2013], F = 1, a = alpha in (0, 1],
 * mu = wo.z in (0, 1].  Same method as mf_albedo_microfacet (adaptive K15 in the micro-normal's polar
 * angles, split at the horizon of wi), same bound target.  Note: this is NOT the `charlie` model of
 * the registry (whose G2 is the paper's Lambda fit); it is the sheen term engines ship. */
mf_status mf_albedo_charlie(double alpha, double mu, mf_result *out) MF_WARN_UNUSED;
/* Its independent reference: nested adaptive Gauss-Kronrod in the spherical angles of wi (no kink in
 * those coordinates), graded towards the horizon and the view's azimuth; err as for
 * mf_albedo_microfacet_reference.  About 0.05 to 1 s. */
mf_status mf_albedo_charlie_reference(double alpha, double mu, double tol, mf_result *out) MF_WARN_UNUSED;

/* The reflection and transmission albedo of a rough dielectric interface (isotropic ndf, joint or
 * separable G2, exact dielectric Fresnel), for the view mu = wo.z in (0, 1] and the relative index
 * eta = eta_beyond / eta_view (eta < 1: seen from the denser side, with total internal
 * reflection):
 *   E_R = int f_r |wi.z| dwi over the upper hemisphere, E_T = int f_t |wi.z| dwi over the lower one,
 * with Walter 2007's BSDFs (Eq. 20, 21), E_T the transmitted energy (without the 1 / eta^2 radiance
 * scaling), G2 of the transmission 1 / (1 + Lambda_o + Lambda_t) (pbrt-v4's and Cycles' form).
 * Same method and bound target as mf_albedo_microfacet, panels also ending on the critical angle and
 * the transmission's horizon.  eta = 1 gives E_R = 0 and E_T = G2(wo, -wo mirrored) exactly. */
mf_status mf_albedo_dielectric(mf_ndf ndf, mf_g2_form g2, double mu, double eta, mf_result *refl,
                               mf_result *trans) MF_WARN_UNUSED;

#ifdef __cplusplus
}
#endif
#endif /* MF_ALBEDO_H */
