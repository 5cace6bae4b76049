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
 * Method (docs/math.md, "BRDFs and albedo").  With dwi = 4 (wo.wm) dwm [Walter 2007, Eq. 14] and
 * D(wm) wm.z dwm = P22(s) ds (s the slope of wm), rho = integral F G2 P22(s) (wo.z + s . wo_xy) /
 * wo.z ds over the slopes whose reflection is above the horizon: the DISK |s - wo_xy / wo.z| <
 * 1 / wo.z, so the kink of the integrand (the horizon of wi) is a circle known in closed form.  In
 * the stretched slopes, polar rays around the lobe's centre leave the disk at r_max(phi) = 1 /
 * (sqrt(k^2 + q) - k) (k = (S e) . wo_xy / wo.z, q = |S e|^2, S = diag(alpha_x, alpha_y)); for GGX
 * r = tan t, for Beckmann r itself (cut at r = 7).  The integral along each ray and the one over phi
 * are global-adaptive QK15 rules (bound |K15 - G7| per segment; the phi segments add the rays'
 * bounds through the K15 weights), first graded towards the layer where G1(wi) turns over and
 * towards the azimuths where the exit jumps; the worst segment is bisected until the total bound is
 * <= 5e-10 (plus 64 ulp of the result).  An isotropic NDF is integrated over half the circle.
 * Verified against the independent references below (tests/test_energy.c; figures in docs/math.md).
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
 * Same bound target as mf_albedo_microfacet (<= 5e-10 each); the micro-normal in angles (b, p) about
 * wo, b outer: every kink (the critical angle, the horizons of wi, wt and h, and the angles b where
 * they reach p = 0 or pi) is a panel end in closed form (docs/math.md, "The rough dielectric rule").
 * About 3 ms of CPU.  eta = 1 gives E_R = 0 and E_T = G2(wo, -wo mirrored) exactly. */
mf_status mf_albedo_dielectric(mf_ndf ndf, mf_g2_form g2, double mu, double eta, mf_result *refl,
                               mf_result *trans) MF_WARN_UNUSED;

#ifdef __cplusplus
}
#endif
#endif /* MF_ALBEDO_H */
