/*
 * mf_proxy.h -- mfkit's fitted closed form of the GGX proxy roughness (shader-cheap).
 *
 * The exact proxy roughness alpha'(alpha, dh) of an isotropic GGX filtered over the square slope
 * footprint of full width dh centred on the peak solves 1/(pi alpha'^2) = mean of P22 over the
 * square [Kaplanyan 2016, Eq. 19; docs/math.md, correction C-K3]; mf_filter_ggx_proxy_alpha evaluates it with an atan.
 * The paper's approximation sqrt(alpha^2 + dh^2) (mf_filter_ggx_proxy_alpha_approx) is off by up
 * to sqrt(pi) - 1 = 77 %.  This module evaluates a fitted form of the same cost class (no
 * transcendental: one division, one square root, ~10 multiply-adds):
 *
 *   alpha'^2 = alpha^2 + dh^2 R(x),   x = dh^2 / (alpha^2 + dh^2)  in [0, 1],
 *   R(x)     = (1 - x)/3 + x/pi + x (1 - x) c / (1 + q x).
 *
 * The limits are built in, so no coefficients can break them: R(0) = 1/3 gives
 * alpha'^2 = alpha^2 + dh^2/3 + O(dh^4/alpha^2) for dh << alpha, and R(1) = 1/pi gives
 * alpha' -> dh / sqrt(pi) for dh >> alpha (docs/math.md, "GGX proxy: fitted form").  Because the
 * exact alpha'/alpha depends on dh/alpha only, the relative error depends on x only, so the
 * bound below holds for every alpha > 0, not just the fitted domain.
 *
 * Coefficients: fitted by `mfkit fit ggx-proxy` (fit/src/mf_proxyfit.c; Ceres least squares of
 * the relative error of alpha' on the default 64 x 64 log grid alpha in [1e-3, 1],
 * dh in [1e-3, 10]); tests/test_proxyfit.c checks that the command reproduces them.
 * Measured relative error of alpha' (over x in [0, 1], equivalently any alpha > 0, dh >= 0):
 * max 3.12e-6, mean 7.5e-7 over the 64 x 64 domain (MF_PROXY_FIT_MAX_REL_ERROR = 3.2e-6 bounds it
 * for all x), versus max 0.772, mean 0.444 for sqrt(alpha^2 + dh^2): ~2.5e5 times smaller.
 *
 * Pure C11, libm only.
 *
 * References
 *  [Kaplanyan 2016] Kaplanyan, Hill, Patney, Lefohn. Filtering Distributions of Normals for
 *                   Shading Antialiasing. HPG 2016, Eq. 18-20, with docs/math.md, correction C-K3.
 */
#ifndef MF_PROXY_H
#define MF_PROXY_H

#ifdef __cplusplus
extern "C" {
#endif

/* Number of fitted coefficients: coef[0] = c, coef[1] = q of R(x) above. */
#define MF_PROXY_NCOEF 2

/* The shipped coefficients, produced by `mfkit fit ggx-proxy` (default options: --size 64), %.17g. */
#define MF_PROXY_FIT_C 0.0093784086977565084
#define MF_PROXY_FIT_Q -0.64968460173987008
/* A bound on the relative error |fit/exact - 1| of alpha' with the shipped coefficients, for all
 * alpha > 0, dh >= 0 (the measured maximum, rounded up; tests/test_proxyfit.c). */
#define MF_PROXY_FIT_MAX_REL_ERROR 3.2e-6

/* The fitted proxy roughness with the shipped coefficients (see the header comment).
 * alpha > 0, dh >= 0 (full width of the square, Eq. 16's convention), both finite: returns
 * alpha' (dh = 0 gives alpha exactly); NaN outside the domain. */
double mf_proxy_alpha_fit(double alpha, double dh);

/* The same form with caller-given coefficients coef[0] = c, coef[1] = q (q > -1 keeps the
 * denominator positive).  NaN outside the domain or for q <= -1. */
double mf_proxy_alpha_fit_coef(const double coef[MF_PROXY_NCOEF], double alpha, double dh);

/* R(x) of the form above and, if grad is non-NULL, grad[k] = d R / d coef[k].  x in [0, 1]. */
double mf_proxy_fit_r(const double coef[MF_PROXY_NCOEF], double x, double grad[MF_PROXY_NCOEF]);

#ifdef __cplusplus
}
#endif
#endif /* MF_PROXY_H */
