/*
 * mf_moments.h -- linearly filterable slope moments (LEAN / LEADR), their covariances, bump
 * roughness (Hery), symmetric 2x2 eigen-decomposition and Toksvig's factor.
 *
 * What is stored.  For slopes (x, y) of the normals under a filter footprint, the five moments
 * E[x], E[y], E[x^2], E[xy], E[y^2] combine linearly, so MIP maps and any linear filter give
 * the moments of the filtered region [Olano 2010, Sec. 3.3; Dupuy 2013, Sec. 4.1].  The
 * covariance is reconstructed afterwards: Sigma = M - E E^T [Olano 2010, Eq. 5; Dupuy 2013, Eq. 9].
 *
 * Slopes and signs (docs/math.md, corrections C-N4, C-L6).  mfkit slopes are height gradients, (-n.x/n.z, -n.y/n.z)
 * [Dupuy 2013, Sec. 4.1], as everywhere in mfkit (docs/conventions.md).  LEAN stores
 * B = n.xy/n.z (+ sign, Sec. 3.3 and 3.5), so  E[slope] (mfkit, LEADR) = -B (LEAN).  Second
 * moments are products of two slopes and do not change sign.  mf_moments_from_lean converts.
 *
 * Measures and units.  Slopes are dimensionless (height per length); the moments are
 * expectations under the normalised filter weights (they are averages, not sums).  The
 * Beckmann roughness of a slope variance sigma^2 is alpha^2 = 2 sigma^2 (docs/conventions.md).
 *
 * Domain.  Every input must be finite; normals need n.z > 0; a NaN input or a value outside a
 * function's documented domain gives NaN outputs, never a silent clamp (the one documented
 * exception: covariances that are negative by rounding only, see mf_moments_to_gaussian).
 *
 * References
 *  [Olano 2010]  Olano, Baker. LEAN Mapping. I3D 2010, Eq. 3-9.
 *  [Dupuy 2013]  Dupuy, Heitz, Iehl, Poulin, Neyret, Ostromoukhov. LEADR Mapping. ACM TOG 32(6),
 *                2013, Sec. 4.1-4.2, Eq. 8-12.
 *  [Hery 2014]   Hery, Kass, Ling. Geometry into Shading. Pixar Tech. Memo 14-04, 2014,
 *                Eq. 3-12, with docs/math.md, corrections C-H1, C-H2, C-H5, C-H6.
 *  [Toksvig 2005] Toksvig. Mipmapping Normal Maps. Journal of Graphics Tools 10(3), 65-71.
 */
#ifndef MF_MOMENTS_H
#define MF_MOMENTS_H

#include "mfkit/mf_ndf.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A symmetric 2x2 matrix [[xx, xy], [xy, yy]] (covariances, second moments, roughness
 * matrices).  Units: those of its entries (slope^2 for slope covariances). */
typedef struct mf_sym2 {
    double xx, xy, yy;
} mf_sym2;

/* First and raw second moments of slopes (mfkit sign): mean_x = E[x], mean_y = E[y],
 * m_xx = E[x^2], m_xy = E[x y], m_yy = E[y^2].  Linear: weighted sums of moments are moments. */
typedef struct mf_slope_moments {
    double mean_x, mean_y;
    double m_xx, m_xy, m_yy;
} mf_slope_moments;

/* Cross moments of two layers f and g for mixing [Olano 2010, Eq. 7-9, the "red" terms]:
 * xx = E[fx gx], yy = E[fy gy], xy = E[fx gy], yx = E[fy gx]. */
typedef struct mf_slope_cross_moments {
    double xx, yy, xy, yx;
} mf_slope_cross_moments;

/* Eigen-decomposition of a symmetric 2x2 matrix: A v1 = l1 v1, A v2 = l2 v2, l1 >= l2,
 * v1 and v2 orthonormal, v2 = v1 rotated by +90 degrees. */
typedef struct mf_eigen2 {
    double l1, l2;
    double v1[2], v2[2];
} mf_eigen2;

/* Anisotropic Beckmann roughness along two orthonormal directions of the shading frame:
 * alpha1 along dir1, alpha2 along dir2, alpha1 >= alpha2. */
typedef struct mf_aniso_roughness {
    double alpha1, alpha2;
    double dir1[2], dir2[2];
} mf_aniso_roughness;

/* ---- LEAN / LEADR moments ----------------------------------------------------------------- */

/* Moments of one normal n (any length, n.z > 0): slope s = (-n.x/n.z, -n.y/n.z), mean = s,
 * second moments s s^T [Olano 2010, Eq. 3-4, with the sign of correction C-N4: mean = -B].
 * NaN in every field for n.z <= 0 or a non-finite n. */
mf_slope_moments mf_moments_from_normal(mf_vec3 n);
/* Moments of one slope (sx, sy) (mfkit sign): mean (sx, sy), second moments s s^T. */
mf_slope_moments mf_moments_from_slope(double sx, double sy);
/* From LEAN's stored values: B = (bx, by) in LEAN's +n.xy/n.z sign and M in the order of
 * Eq. 4, (M.x, M.y, M.z) = (E[x^2], E[xy], E[y^2]).  Returns mean = -B (correction C-N4) and the
 * second moments unchanged.  Note correction C-N5(a): LEAN's Fig. 15 code stores M as
 * (xx, yy, xy), not in the order of Eq. 4; reorder before calling. */
mf_slope_moments mf_moments_from_lean(double bx, double by, double mxx, double mxy, double myy);

/* acc += w * m, field by field: the linear filter (box, MIP, bilinear, ...) that makes the
 * moments filterable [Olano 2010, Sec. 3.3].  The weights of a filter should sum to 1. */
void mf_moments_accumulate(mf_slope_moments *acc, const mf_slope_moments *m, double w);

/* Mean slope and covariance Sigma = M - E E^T [Olano 2010, Eq. 5; Dupuy 2013, Eq. 9].
 * The subtraction cancels when the variance is small against the squared mean; a variance or
 * determinant that comes out negative by no more than 16 eps * (the second moments involved),
 * i.e. by rounding alone, is set to 0 (resp. |cov| to sqrt(var_x var_y)).  A larger negative
 * value means the input is not a set of moments: every field is NaN (mf_gaussian_valid fails). */
mf_gaussian_slopes mf_moments_to_gaussian(const mf_slope_moments *m);

/* Base roughness as an added covariance: M += c (E unchanged), so that Sigma += c
 * [Olano 2010, Eq. 6: c = (1/s) I for a Blinn-Phong exponent s].  Correction C-N5(c): if the moments
 * are stored scaled by 1/sc (LEAN Fig. 15), add c / sc^2 before unscaling (or c after): the
 * printed code adds 1/s to the scaled moments and gets sc^2/s back.  NaN for a non-finite c. */
mf_slope_moments mf_moments_add_covariance(const mf_slope_moments *m, mf_sym2 c);
/* Base Beckmann roughness: M += diag(alpha_x^2 / 2, alpha_y^2 / 2) (alpha^2 = 2 sigma^2; with
 * the Blinn-Phong exponent s, alpha^2 / 2 = 1/s [Olano 2010, Sec. 3.1 and Eq. 6]).
 * alpha >= 0 (0 = mirror facets); NaN outside. */
mf_slope_moments mf_moments_add_beckmann(const mf_slope_moments *m, double alpha_x, double alpha_y);

/* Height scaling by eta (any finite real): E *= eta, M *= eta^2 [Dupuy 2013, Sec. 4.2, "Height
 * Scaling"].  Also the scale factor sc of LEAN's Fig. 15/16 (eta = 1/sc to pack, sc to unpack). */
mf_slope_moments mf_moments_scale(const mf_slope_moments *m, double eta);

/* Texture-space slope moments (u, v) to world (tangent-plane) slope moments (x, y) under a
 * locally constant parameterisation [Dupuy 2013, Eq. 12]:  with A = [[du_dx, dv_dx],
 * [du_dy, dv_dy]] (the chain rule (h_x, h_y) = A (h_u, h_v)), E' = A E and M' = A M A^T
 * (Eq. 12 is printed for the covariance; the raw second moments transform the same way because
 * the map is linear, so Sigma' = A Sigma A^T follows).  Stretching, shearing and rotation of the
 * parameterisation; any finite A (singular A collapses the distribution, still valid). */
mf_slope_moments mf_moments_transform(const mf_slope_moments *m, double du_dx, double dv_dx, double du_dy,
                                      double dv_dy);

/* Cross moments of one pair of normals (f and g layers at the same texel), mfkit sign
 * (the sign cancels in the products).  NaN if either n.z <= 0. */
mf_slope_cross_moments mf_moments_cross_from_normals(mf_vec3 nf, mf_vec3 ng);
/* acc += w * c (cross moments filter linearly like the moments). */
void mf_moments_cross_accumulate(mf_slope_cross_moments *acc, const mf_slope_cross_moments *c, double w);
/* LEAN's "mixing approximation" [Olano 2010, Sec. 3.5]: cross moments from the means alone,
 * E[fx gx] ~ E[fx] E[gx] etc.  Exact for layers whose slopes are uncorrelated under the
 * filter; wrong for coherent layers (e.g. g = -f, LEAN Fig. 10). */
mf_slope_cross_moments mf_moments_cross_uncorrelated(const mf_slope_moments *f, const mf_slope_moments *g);
/* Moments of the mixed height field t f + u g [Olano 2010, Eq. 7-9]:
 *   E = t E_f + u E_g,
 *   M.xx = t^2 Mf.xx + u^2 Mg.xx + 2 t u c.xx,   M.yy likewise with c.yy,
 *   M.xy = t^2 Mf.xy + u^2 Mg.xy + t u (c.xy + c.yx).
 * t, u any finite reals (LEAN uses barycentric t + u = 1; the algebra does not need it).
 * Base roughness must be added after mixing, not to the layers (it would be scaled by t^2). */
mf_slope_moments mf_moments_mix(const mf_slope_moments *f, const mf_slope_moments *g,
                                const mf_slope_cross_moments *c, double t, double u);

/* ---- symmetric 2x2 eigen-decomposition and roughness ---------------------------------------- */

/* Closed-form eigen-decomposition of [[a, b], [b, c]] that never divides by a small number
 * (correction C-H6: Hery's SymetricEigenVecVal2D uses v = (1, (l - a)/b), which fails for b = 0):
 *   m = (a + c)/2, d = (a - c)/2, r = hypot(d, b), l1 = m + r, l2 = det / l1 (or m - r),
 *   v1 = (r + d, b) / |.| if d >= 0, else (b, r - d) / |.|  (|.| >= r: no cancellation).
 * b = 0 returns the diagonal exactly with axis-aligned vectors (v1 = x if a >= c); r = 0
 * (isotropic) returns v1 = (1, 0).  NaN in every field for a non-finite input. */
mf_eigen2 mf_sym2_eigen(mf_sym2 a);

/* Anisotropic Beckmann roughness of a slope covariance: alpha_k = sqrt(2 lambda_k) along the
 * eigenvectors (alpha^2 = 2 sigma^2; Kaplanyan 2016, "evaluate Beckmann with 2B'").  NaN if
 * the covariance is not positive semi-definite (lambda_2 < -16 eps lambda_1; rounding-level
 * negative eigenvalues are set to 0). */
mf_aniso_roughness mf_roughness_from_covariance(mf_sym2 cov);

/* ---- Hery bump roughness ------------------------------------------------------------------ */

/* Covariance of the displacement slopes per unit arc length [Hery 2014, Eq. 6-8 and 10].
 * dw: filtered moments of the displacement derivatives (w_u, w_v) = (dw/du, dw/dv) -- i.e.
 * mean = (f(w_u), f(w_v)), m_xx = f(w_u^2), m_xy = f(w_u w_v), m_yy = f(w_v^2) in Hery's
 * notation; len_ru = |dR/du| > 0, len_rv = |dR/dv| > 0 (lengths of the undisplaced surface's
 * tangents).  Returns, in the frame (R_u/|R_u|, R_v/|R_v|):
 *   xx = var(w_u) / |R_u|^2, yy = var(w_v) / |R_v|^2, xy = cov(w_u, w_v) / (|R_u| |R_v|).
 * Differs from the printed paper: Eq. 4-5 print s_u = w_u |R_u|^(1/2); the slope per arc length
 * is w_u / |R_u| (correction C-H1; Eq. 6 and 8 agree with the corrected form).  This is *not* yet
 * multiplied by Hery's Eq. 10 factor (see mf_hery_bump_roughness, correction C-H2).  Assumes an
 * orthogonal parameterisation, R_u . R_v = 0 (correction C-H4); for a sheared one use
 * mf_moments_transform with the inverse metric instead.  NaN outside the domain. */
mf_sym2 mf_hery_slope_covariance(const mf_slope_moments *dw, double len_ru, double len_rv);

/* Effective anisotropic Beckmann roughness of a base roughness (m_orig_x, m_orig_y) along the
 * frame axes (>= 0) plus displacement slopes of covariance slope_cov [Hery 2014, Eq. 3, 11-12]:
 * the eigen-decomposition of  diag(m_orig_x^2, m_orig_y^2) + 2 slope_cov,  alpha_k = sqrt(l_k).
 * Differs from the printed paper: (correction C-H2) Eq. 10 scales the variances by 1/2; the roughness
 * matrix needs 2 Sigma (m^2 = 2 sigma^2, consistent with Eq. 3); (correction C-H5) Eq. 12 adds
 * m_orig,k^2 to the eigenvalues of the displacement term alone, which is right only if the base
 * is isotropic or aligned with the eigenvectors -- the sum is decomposed here.  (correction C-H6) the
 * eigen-solver is mf_sym2_eigen.  NaN outside the domain. */
mf_aniso_roughness mf_hery_bump_roughness(double m_orig_x, double m_orig_y, mf_sym2 slope_cov);

/* ---- Toksvig ------------------------------------------------------------------------------ */

/* Toksvig's variance from the length len = |average of unit normals| in (0, 1]
 * [Toksvig 2005]:  len = 1 / (1 + sigma^2),  sigma^2 = (1 - len) / len.  For small slopes
 * sigma^2 is the per-axis slope variance of an isotropic distribution (1 - len ~ E|s|^2 / 2).
 * NaN for len <= 0, len > 1 or NaN. */
double mf_toksvig_variance(double len);
/* Toksvig's factor ft = len / (len + s (1 - len)) for a Blinn-Phong exponent s > 0: the
 * filtered exponent is ft * s, i.e. 1/(ft s) = 1/s + sigma^2 [Toksvig 2005]. */
double mf_toksvig_factor(double len, double exponent);
/* The same for a Beckmann roughness alpha >= 0: alpha' = sqrt(alpha^2 + 2 sigma^2)
 * (slope variance 1/s = alpha^2 / 2, LEAN Sec. 3.1). */
double mf_toksvig_beckmann_alpha(double len, double alpha);

#ifdef __cplusplus
}
#endif
#endif /* MF_MOMENTS_H */
