/*
 * mf_smith.h -- Smith masking: Lambda, G1 and the two masking-shadowing forms.
 *
 * Lambda(w) is Smith's auxiliary function: the fraction of micro-area facing away from w
 * (and hidden) relative to the visible fraction, so that G1(w) = 1 / (1 + Lambda(w)) satisfies
 * the projected-area identity  integral of G1(w) max(0, w.wm) D(wm) dwm = w . (mesonormal) /
 * (mesonormal . z)  (= cos theta for a centred NDF) [Heitz 2014, the projected-area constraint].
 *
 * Masking-shadowing:
 *   joint (height-correlated)  G2 = 1 / (1 + Lambda(wo) + Lambda(wi))   [Dupuy 2013, Eq. 13;
 *                                                                         Heitz 2014]
 *   separable                   G2 = G1(wo) G1(wi)                        [Walter 2007, Eq. 23]
 *
 * Directions below the surface.  For a centred NDF, Lambda(w) = +INFINITY for w.z <= 0, so
 * G1 = G2 = 0.  For non-centred Gaussian slopes the criterion is LEADR's: nu <= 0, i.e. w is
 * on or below the *mesosurface* (w . mesonormal <= 0), not w.z <= 0 (docs/math.md, correction C-L3): a direction
 * slightly below the geometric horizon but above a tilted mesosurface has a finite Lambda.
 * Every function here takes unit vectors; a NaN input or invalid NDF gives NaN.
 *
 * References: [Walter 2007] (Eq. 27 Beckmann rational approximation; Eq. 34 GGX G1),
 * [Heitz 2014] (GGX and Beckmann Lambda, anisotropy by stretching, height correlation),
 * [Dupuy 2013] Dupuy, Heitz, Iehl, Poulin, Neyret, Ostromoukhov. LEADR Mapping. ACM TOG 32(6), 2013,
 * Eq. 13-15 and the closed form after them, with docs/math.md, corrections C-L2 to C-L4.
 */
#ifndef MF_SMITH_H
#define MF_SMITH_H

#include "mfkit/mf_ndf.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum mf_g2_form {
    MF_G2_JOINT = 0,     /* height-correlated 1 / (1 + L(wo) + L(wi)) */
    MF_G2_SEPARABLE = 1  /* G1(wo) G1(wi) */
} mf_g2_form;

/* Lambda of the Beckmann / Gaussian family as a function of
 * nu = cot(theta) / (sigma(phi) sqrt(2)) (the "a" of Walter 2007):
 *   Lambda(nu) = exp(-nu^2) / (2 nu sqrt(pi)) - erfc(nu) / 2      [Dupuy 2013, after Eq. 15]
 * For nu > 2 this is evaluated through the Laplace continued fraction of erfc so that the
 * difference does not cancel (relative error ~1e-15 instead of losing 1/(2 nu^2) of the digits).
 * +INFINITY for nu <= 0 (correction C-L3: the printed forms give finite negative values there). */
double mf_smith_lambda_beckmann_nu(double nu);

/* Walter's rational approximation [Walter 2007, Eq. 27; Dupuy 2013, after Eq. 15]:
 *   (1 - 1.259 nu + 0.396 nu^2) / (3.535 nu + 2.181 nu^2) for nu < 1.6, else 0.
 * Differs from the printed form: the numerator has roots at nu = 1.5497 and 1.6295, so the
 * printed form is negative (down to -6.1e-5, G1 > 1) on 1.548 < nu < 1.6 (correction C-L4); mfkit
 * clamps it at 0.  +INFINITY for nu <= 0 (correction C-L3). */
double mf_smith_lambda_beckmann_walter_nu(double nu);

/* GGX: Lambda = (-1 + sqrt(1 + a^2 tan^2)) / 2 with a^2 tan^2 = (ax^2 x^2 + ay^2 y^2) / z^2
 * [Heitz 2014; Walter 2007, Eq. 34 as 1/G1 - 1], evaluated as t / (2 (1 + sqrt(1 + t))) so it does not
 * cancel to 0 near normal incidence (docs/math.md, correction C-X2). */
double mf_smith_lambda_ggx(double alpha_x, double alpha_y, mf_vec3 w);
/* Beckmann, exact (erfc form) and Walter's approximation; nu = z / sqrt(ax^2 x^2 + ay^2 y^2). */
double mf_smith_lambda_beckmann(double alpha_x, double alpha_y, mf_vec3 w);
double mf_smith_lambda_beckmann_walter(double alpha_x, double alpha_y, mf_vec3 w);
/* Dispatch on the NDF type (exact forms). */
double mf_smith_lambda(mf_ndf ndf, mf_vec3 w);

/* nu of non-centred Gaussian slopes for direction w [Dupuy 2013, Eq. 14-15 and after]:
 *   nu = (cot theta - mu(phi)) / (sigma(phi) sqrt 2)
 *      = (w.z - w.x mean_x - w.y mean_y) / sqrt(2 (w.x^2 var_x + w.y^2 var_y + 2 w.x w.y cov_xy))
 * (the second form multiplies through by sin theta: no trigonometry, defined at the pole).
 * A zero denominator gives +INFINITY (or -INFINITY) by the sign of the numerator. */
double mf_smith_gaussian_nu(const mf_gaussian_slopes *g, mf_vec3 w);
/* Lambda of non-centred Gaussian slopes: exact closed form and Walter's approximation.
 * The closed form equals Smith's construction relative to the mean plane,
 *   Lambda = 1/(cot theta - mu) * integral_{cot theta}^inf (x - cot theta) P2(x) dx,
 * not the definition printed after Eq. 13 (which has tan theta in front; correction C-L2). */
double mf_smith_lambda_gaussian(const mf_gaussian_slopes *g, mf_vec3 w);
double mf_smith_lambda_gaussian_walter(const mf_gaussian_slopes *g, mf_vec3 w);

/* G1 = 1 / (1 + Lambda); 0 below the horizon. */
double mf_smith_g1(mf_ndf ndf, mf_vec3 w);
/* G2 of (wo, wi) in the given form; 0 when either direction is below the horizon. */
double mf_smith_g2(mf_ndf ndf, mf_g2_form form, mf_vec3 wo, mf_vec3 wi);
/* Joint G2 of non-centred Gaussian slopes [Dupuy 2013, Eq. 13]. */
double mf_smith_g2_gaussian(const mf_gaussian_slopes *g, mf_vec3 wo, mf_vec3 wi);

#ifdef __cplusplus
}
#endif
#endif /* MF_SMITH_H */
