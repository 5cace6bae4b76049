/*
 * mf_leadr.h -- LEADR shading of a pixel with non-centred anisotropic Beckmann (Gaussian slope)
 * statistics under environment and directional lighting [Dupuy 2013, Sec. 4.4-5.3].
 *
 * A pixel's microsurface is described by mf_gaussian_slopes (mean slope and covariance, slopes
 * as height gradients, docs/math.md, correction C-L6) in the z-up shading frame g = (0, 0, 1); n_bar is its
 * mesonormal [Eq. 11].  wo is the view (unit, pointing away).  The outputs are radiances I
 * (W m^-2 sr^-1) for white microfacets: multiply by the specular colour / diffuse albedo.
 *
 *  specular, directional light   mf_leadr_specular in mf_brdf.h  [Eq. 17]
 *  specular, environment          mf_leadr_specular_env           [Eq. 19, 22; Algorithm 1]
 *  diffuse                        mf_leadr_diffuse(_sh)            [Eq. 21, 23; Algorithm 3]
 *  masking-aware irradiance       mf_leadr_irradiance_lights (exact for directional lights),
 *                                 mf_leadr_irradiance_sh           [Eq. 20; Algorithm 2]
 *
 * Slope integrals  integral h(slope) P22(slope) d^2slope  are estimated on LEADR's grid
 * [Sec. 5.1]: N x N points p_j of a standard normal on [-lambda, lambda], normalised Gaussian
 * weights W_j = exp(-p_j^2/2) / sum_k exp(-p_k^2/2), warped by the Cholesky factor of the slope
 * covariance and shifted by the mean.  Where the spacing of the points is not said (correction C-L7)
 * both readings are offered; the normalised grid does not reproduce the unit variance
 * (N = 5, lambda = 1.8: 0.8656 end points, 0.6981 cell centres).  The estimate converges to the
 * integral only if lambda grows with N (for fixed lambda it converges to the Gaussian truncated
 * to [-lambda, lambda]^2 and renormalised); the paper uses N = 5, lambda = 1.8.
 *
 * Below the surface.  Lambda(w) = +inf for w on or below the mesosurface (nu <= 0, correction C-L3);
 * such incident directions contribute nothing, whether or not they are below the geometric
 * horizon: every integral over wi runs over the whole sphere (correction C-L5).  A view on or below
 * the mesosurface (n_bar . wo <= 0; the paper culls such faces) gives I = 0 and MF_OK.
 * Invalid arguments (NULL, invalid statistics, a non-unit wo, an invalid Fresnel descriptor or a
 * non-finite callback value) give MF_ERR_DOMAIN and *out = NaN.
 *
 * References: [Dupuy 2013] Dupuy, Heitz, Iehl, Poulin, Neyret, Ostromoukhov. Linear Efficient
 * Antialiased Displacement and Reflectance Mapping (LEADR). ACM TOG 32(6), 2013, with docs/math.md,
 * corrections C-L1, C-L3, C-L5, C-L7, C-L8; [R&H 2001] (see mf_sh.h).
 */
#ifndef MF_LEADR_H
#define MF_LEADR_H

#include "mfkit/mf_fresnel.h"
#include "mfkit/mf_ndf.h"
#include "mfkit/mf_sh.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A directional light: radiance irradiance * delta(w - wi), i.e. `irradiance` (W m^-2) on a
 * surface facing it; wi a unit vector in the shading frame (pointing towards the light). */
typedef struct mf_leadr_light {
    mf_vec3 wi;
    double irradiance;
} mf_leadr_light;

/* Masking-aware irradiance of Eq. 20 for directional lights, exactly:
 *   E(wn) = sum_k P_k max(0, wn . wi_k) / (1 + Lambda(wo) + Lambda(wi_k))   [Dupuy 2013, Eq. 20]
 * wn a unit micro-normal.  0 if wo is on or below the mesosurface.  NaN outside the domain
 * (invalid statistics, non-unit wo, wn or wi_k, negative or non-finite P_k, n_lights < 0,
 * lights NULL with n_lights > 0). */
double mf_leadr_irradiance_lights(const mf_gaussian_slopes *g, mf_vec3 wo, const mf_leadr_light *lights,
                                  int n_lights, mf_vec3 wn);

/* LEADR's irradiance map as 9 SH radiance coefficients, [Dupuy 2013, Algorithm 2] with
 * correction C-L1 (L00 += Y00 P, not L00 += L00 + 0.282095 P) and exact constants (correction C-L9):
 *   out = sum_k P_k / (1 + Lambda(wo) + Lambda(wi_k)) Y(wi_k)  +  env / (1 + Lambda(wo)).
 * Directional lights get the joint masking-shadowing weight; the environment (env, may be NULL:
 * no environment) gets the masking weight only, as in the paper: its shadowing 1/(1 + Lambda(wo)
 * + Lambda(wi)) would have to be projected per pixel.  env and the lights are in the shading
 * frame (mf_sh_to_frame converts world-frame coefficients).  The irradiance is then
 * E(wn) = mf_sh_irradiance(out, wn) [R&H 2001, Eq. 13].  All zero if wo is on or below the
 * mesosurface.  MF_ERR_DOMAIN (out NaN) for the invalid inputs of mf_leadr_irradiance_lights or
 * a non-finite env coefficient. */
mf_status mf_leadr_irradiance_sh(const mf_gaussian_slopes *g, mf_vec3 wo, const mf_leadr_light *lights,
                                 int n_lights, const double env[MF_SH_COEFFS], double out[MF_SH_COEFFS]) MF_WARN_UNUSED;

/* ---- the sampling grid [Dupuy 2013, Sec. 5.1] ------------------------------------------ */

#define MF_LEADR_GRID_MAX 512

/* correction C-L7: how the N points cover [-lambda, lambda] (j = 0 .. N-1). */
typedef enum mf_leadr_grid_layout {
    MF_LEADR_GRID_END_POINTS = 0,   /* p_j = -lambda + 2 lambda j/(N - 1), spacing 2 lambda/(N - 1) */
    MF_LEADR_GRID_CELL_CENTRES = 1  /* p_j = -lambda + (2 j + 1) lambda/N,  spacing 2 lambda/N,
                                       consistent with the sample area of Sec. 5.2 */
} mf_leadr_grid_layout;

/* N points and their normalised weights; N = 1 is the single point 0 (weight 1, spacing 2 lambda)
 * in both layouts. */
typedef struct mf_leadr_grid {
    int n;
    double lambda;
    mf_leadr_grid_layout layout;
    double spacing;                /* distance between neighbouring p_j */
    double p[MF_LEADR_GRID_MAX];   /* ascending, symmetric about 0 */
    double w[MF_LEADR_GRID_MAX];   /* W_j = exp(-p_j^2/2) / sum_k exp(-p_k^2/2), sum 1 */
} mf_leadr_grid;

/* Fills the grid.  n in [1, MF_LEADR_GRID_MAX], lambda finite and > 0, a known layout;
 * otherwise MF_ERR_DOMAIN (grid->n = 0). */
mf_status mf_leadr_grid_init(mf_leadr_grid *grid, int n, double lambda, mf_leadr_grid_layout layout) MF_WARN_UNUSED;

/* Variance sum_j W_j p_j^2 of the normalised 1D grid (1 for the standard normal it stands for;
 * correction C-L7: 0.8656 / 0.6981 for N = 5, lambda = 1.8).  NaN for an uninitialised grid. */
double mf_leadr_grid_variance(const mf_leadr_grid *grid);

/* Sample (j, k), 0 <= j, k < N, warped to the slope statistics [Dupuy 2013, Sec. 5.1]:
 *   slope_x = l00 p_j + mean_x,   slope_y = l10 p_j + l11 p_k + mean_y,
 * with the Cholesky factor  l00 = sigma_x, l10 = cov_xy/sigma_x, l11 = sqrt(det/var_x)  (the
 * paper's r_xy sigma_y and sqrt(1 - r_xy^2) sigma_y).  Degenerate covariances are handled
 * without 0/0: var_x = 0 gives l00 = l10 = 0, l11 = sqrt(var_y); det = 0 gives l11 = 0; zero
 * covariance puts every sample on the mean.  Returns the weight W_j W_k; NaN (and NaN slopes)
 * for an invalid grid, statistics or index. */
double mf_leadr_grid_warp(const mf_leadr_grid *grid, const mf_gaussian_slopes *g, int j, int k, double slope[2]);

/* Slope-space area of one sample [Dupuy 2013, Sec. 5.2]: A = (spacing * max(sigma_x, sigma_y))^2.
 * The printed A = (2 lambda max(sigma)/N)^2 is the cell-centre spacing; for end points mfkit
 * uses their own spacing 2 lambda/(N - 1) (correction C-L7).  NaN for invalid arguments. */
double mf_leadr_grid_sample_area(const mf_leadr_grid *grid, const mf_gaussian_slopes *g);

/* ---- shading ---------------------------------------------------------------------------- */

/* Environment radiance L(wi) (W m^-2 sr^-1) for the unit direction wi (shading frame, whole
 * sphere).  solid_angle (sr) is the footprint of the sample for a filtered (mip-mapped) lookup,
 * alpha = J A with J = 4 |wn . wo| |wn . g|^3 the Jacobian of slope -> reflected direction
 * [Dupuy 2013, Sec. 5.2, Algorithm 1]; a caller without a filtered map ignores it. */
typedef double (*mf_leadr_env_fn)(mf_vec3 wi, double solid_angle, void *user);

/* Specular radiance under an environment by the grid [Dupuy 2013, Eq. 19, 22; Algorithm 1]:
 *   I = (n_bar.g)/(n_bar.wo) sum_{j,k} W L(wi) F(wn.wi) <wn, wo>/(wn.g) / (1 + Lambda(wo) + Lambda(wi)),
 * wn the micro-normal of the sample's slope, wi = 2 (wn.wo) wn - wo [Eq. 18], <a, b> = max(0, a.b).
 * correction C-L8: the summand uses the per-sample normal wn, the prefactor the mesonormal n_bar.
 * The environment is called only for samples that contribute (wn.wo > 0, wi above the
 * mesosurface).  With L = 1 and F = 1 the exact integral is at most 1 (= 1 without the
 * shadowing Lambda(wi), the normalisation identity after Eq. 16 over the whole sphere). */
mf_status mf_leadr_specular_env(const mf_leadr_grid *grid, const mf_gaussian_slopes *g, mf_fresnel fresnel,
                                mf_vec3 wo, mf_leadr_env_fn env, void *user, double *out) MF_WARN_UNUSED;

/* Irradiance E(wn) (W m^-2) of Eq. 20 at the unit micro-normal wn (shading frame). */
typedef double (*mf_leadr_irradiance_fn)(mf_vec3 wn, void *user);

/* Rough diffuse radiance by the grid [Dupuy 2013, Eq. 21, 23; Algorithm 3]:
 *   I = (n_bar.g)/(n_bar.wo) (1/pi) sum_{j,k} W E(wn) <wn, wo>/(wn.g),
 * with E the masking-aware irradiance of Eq. 20 (e.g. mf_leadr_irradiance_lights, or the SH
 * form below).  The irradiance is not pre-filtered (the paper's choice, Sec. 5.3). */
mf_status mf_leadr_diffuse(const mf_leadr_grid *grid, const mf_gaussian_slopes *g, mf_vec3 wo,
                           mf_leadr_irradiance_fn irradiance, void *user, double *out) MF_WARN_UNUSED;
/* The same with E(wn) = mf_sh_irradiance(radiance_sh, wn), radiance_sh from
 * mf_leadr_irradiance_sh (LEADR's pipeline: Algorithm 2 then 3).  The order-2 irradiance is not
 * clamped: it may be slightly negative for sharp lights (mf_sh.h). */
mf_status mf_leadr_diffuse_sh(const mf_leadr_grid *grid, const mf_gaussian_slopes *g, mf_vec3 wo,
                              const double radiance_sh[MF_SH_COEFFS], double *out) MF_WARN_UNUSED;

#ifdef __cplusplus
}
#endif
#endif /* MF_LEADR_H */
