/*
 * mf_filter.h -- filtering NDFs over a pixel footprint in slope space (Kaplanyan et al. 2016).
 *
 * Pipeline [Kaplanyan 2016, Sec. 3-5]:
 *  1. the half vector of (wo, wi) in slope space, h (Eq. 3);
 *  2. its first-order variation over the pixel footprint: the Jacobian M = dh/dx (Eq. 4) maps
 *     the footprint vectors dx_u, dx_v (ray differentials on the tangent plane) to
 *     dh_u = M dx_u, dh_v = M dx_v (Eq. 5);
 *  3. a Gaussian pixel filter carried into slope space has covariance
 *     P = dh_u dh_u^T + dh_v dh_v^T (Eq. 13 corrected, docs/math.md, correction C-K4), and the parallelogram
 *     {h + a dh_u + b dh_v : |a|, |b| <= 1/2} has an axis-aligned bounding rectangle (Sec. 4.3);
 *     both are clamped as in Sec. 5.2;
 *  4. Beckmann: convolution = covariance sum B' = diag(alpha^2/2) + P (Eq. 14-15), also with LEAN
 *     statistics (Eq. 21); GGX: the mean of the slope density over the rectangle (Eq. 16,
 *     Appendix A corrected, correction C-K1), or a GGX "proxy" roughness alpha' matching its peak (Eq. 19).
 *
 * Slopes and signs (correction C-L6).  mfkit slopes are height gradients, (-m.x/m.z, -m.y/m.z)
 * (docs/conventions.md).  Kaplanyan writes h = (i + o).xy / |n . (i + o)| (+ sign).  So
 *   h (mfkit) = -h (Kaplanyan),  M (mfkit) = -M (Kaplanyan),  dh (mfkit) = -dh (Kaplanyan),
 * while P, the rectangle widths and every centred NDF value D(h) = D(-h) are the same in both;
 * only the rectangle's centre flips.  Statistics with a non-zero mean (LEAN) must be converted
 * with mf_moments_from_lean (correction C-N4) before they are combined with anything here.
 *
 * Measures.  "Slope density" is P22, per unit slope area (docs/conventions.md; docs/math.md, correction C-K2: the
 * D(s, t) of Kaplanyan Eq. 16 and Appendix A is P22, not D(m)).  Means over rectangles are in
 * the same units (per unit slope area).  To use a filtered P22 as an NDF per steradian divide by
 * wm.z^4 as for any P22 (mf_ndf.h).
 *
 * Units and domains.  alpha > 0 and finite (the tested range is [1e-4, 1]); slope positions and
 * rectangle widths are dimensionless slopes, widths >= 0 (0 = no filtering along that axis).
 * Pure functions return NaN (or NaN-filled outputs) outside their domain; none aborts or prints.
 *
 * References
 *  [Kaplanyan 2016] Kaplanyan, Hill, Patney, Lefohn. Filtering Distributions of Normals for
 *                   Shading Antialiasing. HPG 2016, Eq. 3-21, Appendix A, with docs/math.md,
 *                   corrections C-K1 to C-K6.
 *  [Olano 2010]     Olano, Baker. LEAN Mapping. I3D 2010, Eq. 5 (the covariance added by Eq. 21).
 *  Derivations: docs/math.md, section "NDF filtering and slope moments".
 */
#ifndef MF_FILTER_H
#define MF_FILTER_H

#include "mfkit/mf_moments.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The clamping constants used in all experiments of [Kaplanyan 2016, Sec. 5.2]. */
#define MF_FILTER_KAPLANYAN_LAMBDA 1.0    /* largest linear extent of the filtering region */
#define MF_FILTER_KAPLANYAN_EPSILON 1e-3  /* smallest side of the GGX rectangle */

/* ---- footprint to slope space ------------------------------------------------------------- */

/* Slope of the half vector of (wo, wi) in the shading frame [Kaplanyan 2016, Eq. 3 with
 * T = identity]:  h = -(wo + wi).xy / (wo + wi).z  (mfkit sign; Kaplanyan's h is -h, see the
 * header).  Equals mf_slope_from_normal(normalize(wo + wi)).  wo, wi: unit vectors pointing
 * away from the surface.  NaN for (wo + wi).z <= 0 (Kaplanyan's |n . (i + o)| serves
 * transmission; mfkit's reflection-only h is undefined there) or non-finite input. */
void mf_filter_half_slope(mf_vec3 wo, mf_vec3 wi, double h[2]);

/* The Jacobian jac[i][j] = d h_i / d x_j of the half-vector slope with respect to the shading
 * point x = (x_0, x_1, 0) moving on a locally flat surface z = 0, for a pinhole eye and a point
 * light at fixed positions [Kaplanyan 2016, Eq. 4; this is the term T h'_w of Eq. 6 with T' = 0,
 * i.e. no curvature].  eye, light, x: positions in the shading frame (any length unit L); the
 * result is in slope per L.  mfkit sign (= -M of Kaplanyan).  NaN if eye or light is not
 * strictly above the plane or coincides with x.  For curved surfaces add the T' h_w term
 * (Eq. 6, 17) or use finite differences of mf_filter_half_slope (Sec. 5.1). */
void mf_filter_half_slope_jacobian_planar(mf_vec3 eye, mf_vec3 light, mf_vec3 x, double jac[2][2]);

/* First-order footprint in slope space [Kaplanyan 2016, Eq. 5]: dh_u = jac dx_u, dh_v = jac dx_v
 * (column vectors, jac[i][j] = d h_i / d x_j as in Eq. 4).  Eq. 5 writes the row-vector product
 * dx M, which is the same thing only if its M is laid out as the transpose of Eq. 4's; with a
 * non-symmetric Jacobian the literal reading gives a different (wrong) footprint (tested).
 * dx_u, dx_v: the ray differentials of one pixel step in u and v on the tangent plane. */
void mf_filter_footprint_to_slope(const double jac[2][2], const double dx_u[2], const double dx_v[2],
                                  double dh_u[2], double dh_v[2]);

/* Covariance in slope space of a Gaussian pixel filter [Kaplanyan 2016, Eq. 13 corrected]:
 *   P = s^2 (dh_u dh_u^T + dh_v dh_v^T)   (= J^T J with J the matrix of rows dh_u, dh_v),
 * the covariance of s (a dh_u + b dh_v) with a, b ~ N(0, 1).  Differs from the printed paper
 * (correction C-K4): Eq. 13 read with row vectors is J J^T, the Gram matrix [dh_u.dh_u, dh_u.dh_v; ...],
 * which has the same eigenvalues but not the same eigenvectors.  s >= 0 is the filter's standard
 * deviation in pixel steps: Sec. 4.3 takes dh_u, dh_v themselves as the standard-deviation
 * vectors (s = 1) while naming sigma = 0.5 pixel -- pass s = 0.5 if dh_u, dh_v are one-pixel
 * differentials and the filter has sigma = 0.5 pixel.  Units: slope^2.  NaN outside the domain. */
mf_sym2 mf_filter_footprint_covariance(const double dh_u[2], const double dh_v[2], double s);

/* Full widths of the axis-aligned bounding rectangle of the parallelogram
 * {h + a dh_u + b dh_v : |a|, |b| <= 1/2} [Kaplanyan 2016, Sec. 4.3, Fig. 6a]:
 *   width[0] = |dh_u.x| + |dh_v.x|,  width[1] = |dh_u.y| + |dh_v.y|
 * (full widths: the rectangle is centre +- width/2, as in Eq. 16).  Scale dh_u, dh_v first for a
 * footprint of another size. */
void mf_filter_footprint_rect(const double dh_u[2], const double dh_v[2], double width[2]);

/* Clamping of large regions by rescaling the parallelogram [Kaplanyan 2016, Sec. 5.2]: if its
 * largest linear extent (the longer diagonal, max(|dh_u + dh_v|, |dh_u - dh_v|)) exceeds lambda,
 * dh_u and dh_v are scaled by lambda / extent.  lambda > 0 (+INFINITY: no clamp; the paper uses
 * MF_FILTER_KAPLANYAN_LAMBDA = 1).  Returns the scale applied (<= 1), NaN (and NaN vectors)
 * outside the domain. */
double mf_filter_clamp_parallelogram(double dh_u[2], double dh_v[2], double lambda);

/* Clamping of the rectangle's sides to [epsilon, lambda] [Kaplanyan 2016, Sec. 5.2]; the paper
 * uses lambda = 1, epsilon = 1e-3.  0 <= epsilon <= lambda.  The lower clamp exists in the paper
 * because its division by the area is unstable for small rectangles; mf_filter_ggx_rect_mean is
 * stable down to width 0, so epsilon = 0 is allowed (epsilon > 0 biases the result: with
 * alpha = 1e-4 and epsilon = 1e-3 the peak value drops by ~33x).  NaN widths outside the domain. */
void mf_filter_clamp_rect(double width[2], double lambda, double epsilon);

/* ---- Beckmann --------------------------------------------------------------------------- */

/* Beckmann (alpha_x, alpha_y) filtered by a Gaussian of covariance p [Kaplanyan 2016,
 * Eq. 14-15]: the centred Gaussian slope statistics with covariance B' = diag(alpha^2 / 2) + p
 * (exact: Gaussian * Gaussian).  Evaluate it with mf_gaussian_p22 / mf_gaussian_d (this is the
 * "Beckmann with the roughness matrix 2B'" of the paper; mf_roughness_from_covariance gives
 * anisotropic alphas and directions for storage).  alpha >= 0 (0 = a mirror filtered by p alone),
 * p positive semi-definite; otherwise NaN fields. */
mf_gaussian_slopes mf_filter_beckmann(double alpha_x, double alpha_y, mf_sym2 p);

/* Non-centred Gaussian statistics g (e.g. LEAN/LEADR moments with base roughness, from
 * mf_moments_to_gaussian, in the mfkit sign) filtered by a further covariance p [Kaplanyan 2016,
 * Eq. 21: K_L * K_P * D]: the mean stays, the covariances add.  Differs from the paper in the
 * frame only: Kaplanyan rotates the shading frame to the LEAN mean normal and filters a centred
 * lobe there; mfkit keeps the base frame and the non-centred Gaussian of LEAN Eq. 1 / LEADR Eq. 8.
 * NaN fields if g is invalid or p is not positive semi-definite. */
mf_gaussian_slopes mf_filter_gaussian_add(const mf_gaussian_slopes *g, mf_sym2 p);

/* ---- GGX over a slope rectangle ----------------------------------------------------------- */

/* Antiderivative of the anisotropic GGX slope density [Kaplanyan 2016, Appendix A]:
 *   F(s, t) = [phi(s, t, ax, ay) + phi(t, s, ay, ax)] / (2 pi),
 *   phi(x, y, g, d) = x atan(g y / (d sqrt(x^2 + g^2))) / sqrt(x^2 + g^2),
 * with d^2 F / ds dt = P22_GGX(s, t) and F(0, t) = F(s, 0) = 0, so F(s, t) is the probability
 * mass of the rectangle between (0, 0) and (s, t) (dimensionless).  Differs from the printed
 * paper (correction C-K1): with Appendix A's half-width limits h -+ dh the normalisation must be
 * 1/(8 pi dh_s dh_t), not 1/(2 pi dh_s dh_t) (4x too large); mfkit uses full widths.  Plain
 * evaluation (the differences of F cancel; use mf_filter_ggx_rect_mean for means). */
double mf_filter_ggx_rect_antiderivative(double alpha_x, double alpha_y, double s, double t);

/* Mean of the GGX slope density P22 over the axis-aligned rectangle of centre (cx, cy) and
 * full widths (wx, wy) [Kaplanyan 2016, Eq. 16 and Appendix A, corrections C-K1, C-K2]:
 *   (1 / (wx wy)) integral_{cx-wx/2}^{cx+wx/2} integral_{cy-wy/2}^{cy+wy/2} P22(s, t) dt ds,
 * per unit slope area.  Any position; widths >= 0 (width 0 along an axis: the mean along the
 * other axis; both 0: P22(cx, cy)).  Evaluation (docs/math.md):
 *  - in the stretched coordinates u = s/alpha_x, v = t/alpha_y (where P22 = (1+u^2+v^2)^-2 / pi);
 *  - the four differences of F are regrouped by edges, each a difference of two atans evaluated
 *    as one atan2 of the exact width (Lambert's edge formula of the projected solid angle of the
 *    rectangle seen from (0, 0, -1));
 *  - where the edges still cancel (rectangles small against their distance from the peak, or
 *    far in the tail: condition number above 16) it integrates one axis in closed form, written as
 *    a sum of non-negative terms ((dpsi - sin dpsi) + 2 cos^2(psi_mean) sin dpsi), and the other
 *    by 16-point Gauss-Legendre on panels graded geometrically away from the peak (error < 1e-16
 *    by the Bernstein-ellipse bound; no iteration: 16 (log2(L) + 2) evaluations for a side of
 *    stretched length L, ~400 for the tested range, ~5000 at the domain limit);
 *  - sides below 1e-9 alpha are replaced by their midpoint (relative error < 1e-18).
 * Measured relative error <= 3e-15 (docs/math.md, tests/test_filter.c).  Domain: alpha > 0,
 * widths >= 0, all finite, and the stretched ends and widths (position / alpha, width / alpha)
 * finite; NaN outside.  Beyond 1e100 in stretched units the edge form is evaluated with scaled
 * arguments (e.g. bounds +-1e300) and rectangles farther than 1e100 from the peak by the
 * degree -4 homogeneity of the far tail; the one case left NaN is a rectangle that reaches
 * beyond 1e100 and whose edges cancel (condition > 16) without being that far from the peak. */
double mf_filter_ggx_rect_mean(double alpha_x, double alpha_y, double cx, double cy, double wx, double wy);
/* The same over [x0, x1] x [y0, y1] (x0 <= x1, y0 <= y1); prefer the centre/width form for
 * tiny rectangles, whose width is then exact. */
double mf_filter_ggx_rect_mean_bounds(double alpha_x, double alpha_y, double x0, double x1, double y0,
                                      double y1);

/* ---- GGX proxy roughness ------------------------------------------------------------------ */

/* Effective roughness alpha' of an isotropic GGX filtered over the square of full width dh
 * centred on the peak, by the peak condition 1/(pi alpha'^2) = mean of P22 over the square
 * [Kaplanyan 2016, Eq. 18-19].  Exact solution (correction C-K3; the printed Eq. 20 is garbled):
 *   alpha'^2 = dh sqrt(4 alpha^2 + dh^2) / (4 atan(dh / sqrt(4 alpha^2 + dh^2)))
 * evaluated as the equal but cancellation-free
 *   alpha'^2 = (alpha^2 + dh^2/4) t / atan(t),  t = dh / sqrt(4 alpha^2 + dh^2)
 * (t / atan t -> 1 with full relative accuracy, so no series is needed for small dh).
 * Asymptotics: alpha'^2 = alpha^2 + dh^2/3 + O(dh^4/alpha^2) (dh << alpha), alpha' -> dh/sqrt(pi)
 * (dh >> alpha).  alpha > 0, dh >= 0 (dh = 0 gives alpha); NaN outside. */
double mf_filter_ggx_proxy_alpha(double alpha, double dh);
/* The paper's simpler fit alpha' ~ sqrt(alpha^2 + dh^2) [Kaplanyan 2016, Eq. 20, right], for
 * comparison: it always overestimates the exact alpha' (by 0.33 % at dh = 0.1 alpha, 22.7 % at
 * dh = alpha, -> sqrt(pi) - 1 = 77.2 % for dh >> alpha; correction C-K3, measured in the tests).
 * Note (correction C-K5) it is not the Beckmann covariance sum either: a box of width dh adds dh^2/6. */
double mf_filter_ggx_proxy_alpha_approx(double alpha, double dh);
/* Per-axis proxy as in the paper [Kaplanyan 2016, after Eq. 20]: out[0] = alpha'(alpha_x, wx),
 * out[1] = alpha'(alpha_y, wy) with the isotropic formula on each axis.  It satisfies the peak
 * equation (19) only for alpha_x = alpha_y and wx = wy. */
void mf_filter_ggx_proxy_alpha_per_axis(double alpha_x, double alpha_y, double wx, double wy, double out[2]);
/* Joint solve of both axes.  Unknowns alpha'_x, alpha'_y; equations:
 *   (19)  1 / (pi alpha'_x alpha'_y) = C = mf_filter_ggx_rect_mean(alpha_x, alpha_y, 0, 0, wx, wy)
 *   (M)   alpha'_x / alpha'_y = sqrt(4 alpha_x^2 + wx^2) / sqrt(4 alpha_y^2 + wy^2),
 * where (M) matches the ratio of the peaks of the two 1D marginal densities: the x-marginal of
 * the box-filtered GGX is the box-filtered marginal alpha^2 / (2 (alpha^2 + s^2)^(3/2)), whose mean
 * over the box is 1 / sqrt(4 alpha_x^2 + wx^2), and a GGX of roughness alpha' has marginal peak
 * 1/(2 alpha').  Why: the peak alone is under-determined (the paper's remark after Eq. 19); second
 * moments cannot be matched because GGX's are infinite; the marginal peaks are the finite,
 * exact width measures of each axis.  Solution (closed form, no iteration):
 *   alpha'_x = sqrt(rho / (pi C)),  alpha'_y = sqrt(1 / (pi C rho)),  rho = ratio (M).
 * It satisfies the peak equation exactly and reduces to mf_filter_ggx_proxy_alpha for
 * alpha_x = alpha_y, wx = wy.  Domain: alpha > 0, widths >= 0, finite; otherwise MF_ERR_DOMAIN
 * and NaN outputs. */
mf_status mf_filter_ggx_proxy_alpha_joint(double alpha_x, double alpha_y, double wx, double wy,
                                          double out[2]) MF_WARN_UNUSED;

#ifdef __cplusplus
}
#endif
#endif /* MF_FILTER_H */
