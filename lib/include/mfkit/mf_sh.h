/*
 * mf_sh.h -- real spherical harmonics up to order 2 (9 coefficients) and irradiance from them.
 *
 * Basis.  Real SH without the Condon-Shortley phase, as tabulated by Ramamoorthi & Hanrahan
 * [R&H 2001, Eq. 3] for a unit direction w = (x, y, z):
 *   Y(0, 0) = 1/(2 sqrt(pi))
 *   Y(1,-1) = sqrt(3/(4 pi)) y     Y(1, 0) = sqrt(3/(4 pi)) z     Y(1, 1) = sqrt(3/(4 pi)) x
 *   Y(2,-2) = sqrt(15/(4 pi)) x y  Y(2,-1) = sqrt(15/(4 pi)) y z  Y(2, 1) = sqrt(15/(4 pi)) x z
 *   Y(2, 0) = sqrt(5/(16 pi)) (3 z^2 - 1)                          Y(2, 2) = sqrt(15/(16 pi)) (x^2 - y^2)
 * orthonormal over the sphere (integral Y_i Y_j dw = delta_ij, dw solid angle).  Indices are (l, m),
 * flattened i = l (l + 1) + m: i = 0 (0,0); 1 (1,-1); 2 (1,0); 3 (1,1); 4 (2,-2); 5 (2,-1); 6 (2,0);
 * 7 (2,1); 8 (2,2).  The constants are the exact forms above at full double precision, not the
 * 6-digit values printed in R&H Eq. 3 / Eq. 13 and LEADR Algorithm 2 (0.282095, 0.488603, ...;
 * docs/math.md, correction C-L9: relative deviations up to 1.5e-6).
 *
 * Frames.  The coefficients live in whatever frame the directions were given in.  mfkit's
 * shading frame is z-up (docs/conventions.md); mf_sh_rotate / mf_sh_to_frame move coefficients
 * between frames exactly (order 2 rotates as a vector and a traceless symmetric matrix).
 *
 * Radiance and irradiance.  A radiance field L(w) (W m^-2 sr^-1) has coefficients
 * L_lm = integral L(w) Y_lm(w) dw  [R&H 2001, Eq. 10].  A directional light of irradiance P
 * (W m^-2 on a surface facing it), L(w) = P delta(w - d), has L_lm = P Y_lm(d).  The irradiance
 * E(n) = integral L(w) max(0, n.w) dw (W m^-2) has E_lm = A_l L_lm with the clamped-cosine
 * factors A_0 = pi, A_1 = 2 pi/3, A_2 = pi/4  [R&H 2001, Eq. 7-9] (the "A hat" of the paper).
 * Truncated at order 2 this is R&H's Eq. 13; it is exact for radiance with no l > 2 even part
 * (the odd A_l vanish for l >= 3), e.g. L = 1 + z and L = max(0, z)^2, and for a single directional
 * light its error is at most 3/32 of P, at n perpendicular to d (docs/math.md, tests/test_sh.c).
 * The order-2 irradiance of a sharp light can be negative (down to -0.0396 P at n.d = -8/15); it
 * is not clamped.  An optional window damps the ringing (mf_sh_apply_window; off by default).
 *
 * Errors.  Functions of a direction take unit vectors: |w.w - 1| <= 1e-6, else NaN.  Accumulating
 * functions propagate NaN into the coefficients for invalid input.  The projections iterate over
 * a quadrature or an image and return mf_status.
 *
 * References
 *  [R&H 2001]   Ramamoorthi, Hanrahan. An Efficient Representation for Irradiance Environment
 *               Maps. SIGGRAPH 2001 (Eq. 3 basis, Eq. 7-9 clamped-cosine convolution, Eq. 10
 *               projection, Eq. 13 order-2 irradiance).
 *  [Dupuy 2013] Dupuy, Heitz, Iehl, Poulin, Neyret, Ostromoukhov. LEADR Mapping. ACM TOG 32(6),
 *               2013, Algorithm 2 (with docs/math.md, corrections C-L1 and C-L9).
 *  [Sloan 2008] Sloan. Stupid Spherical Harmonics (SH) Tricks. GDC 2008 (windowing).
 */
#ifndef MF_SH_H
#define MF_SH_H

#include "mfkit/mf_core.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MF_SH_ORDER 2
#define MF_SH_COEFFS 9 /* (MF_SH_ORDER + 1)^2 */

/* Basis constants, exact forms of [R&H 2001, Eq. 3] (correction C-L9). */
#define MF_SH_Y00 0.282094791773878143474039725780386293 /* 1/(2 sqrt(pi))   (printed 0.282095) */
#define MF_SH_Y1  0.488602511902919921586384622838347005 /* sqrt(3/(4 pi))   (printed 0.488603) */
#define MF_SH_Y2  1.09254843059207907054338570580268840  /* sqrt(15/(4 pi))  (printed 1.092548) */
#define MF_SH_Y20 0.315391565252520006030893690295710493 /* sqrt(5/(16 pi))  (printed 0.315392) */
#define MF_SH_Y22 0.546274215296039535271692852901344201 /* sqrt(15/(16 pi)) (printed 0.546274) */

/* Flattened index of (l, m): l (l + 1) + m. */
static inline int mf_sh_index(int l, int m) { return l * (l + 1) + m; }

/* The 9 basis functions at the unit direction w [R&H 2001, Eq. 3].  NaNs if w is not finite
 * or not unit (|w.w - 1| > 1e-6). */
void mf_sh_eval(mf_vec3 w, double y[MF_SH_COEFFS]);

/* sum_i c_i Y_i(w): the order-2 function with coefficients c at the unit direction w. */
double mf_sh_reconstruct(const double c[MF_SH_COEFFS], mf_vec3 w);

/* Clamped-cosine convolution factor A_l ("A hat") for any l >= 0 [R&H 2001, Eq. 8]:
 *   A_0 = pi, A_1 = 2 pi/3, A_l = 0 for odd l >= 3, and for even l >= 2
 *   A_l = 2 pi (-1)^(l/2 - 1) / ((l + 2)(l - 1)) * l! / (2^l ((l/2)!)^2);
 * A_2 = pi/4, A_4 = -pi/24 [Eq. 9].  NaN for l < 0. */
double mf_sh_cosine_lobe(int l);

/* Irradiance coefficients E_lm = A_l L_lm from radiance coefficients [R&H 2001, Eq. 7].
 * out may alias radiance. */
void mf_sh_convolve_cosine(const double radiance[MF_SH_COEFFS], double irradiance[MF_SH_COEFFS]);

/* Irradiance E(n) (W m^-2) at the unit normal n from the 9 radiance coefficients:
 * sum_i A_l(i) L_i Y_i(n), algebraically R&H's Eq. 13 with c1 = (pi/4) sqrt(15/(16 pi)),
 * c2 = (pi/3) sqrt(3/(4 pi)), c3 = (3 pi/4) sqrt(5/(16 pi)), c4 = sqrt(pi)/2,
 * c5 = (pi/4) sqrt(5/(16 pi)) (printed 0.429043, 0.511664, 0.743125, 0.886227, 0.247708;
 * correction C-L9.  0.511664 and 0.743125 are not the roundings of these, 0.5116634 and 0.7431239, but
 * products of the rounded 0.488603 and 0.315392; relative deviation <= 1.53e-6).
 * Not clamped at 0 (see the header comment).  NaN for a non-unit n. */
double mf_sh_irradiance(const double radiance[MF_SH_COEFFS], mf_vec3 n);

/* Adds a directional light of irradiance `power` (W m^-2 normal to d) arriving from the unit
 * direction d: c_i += power Y_i(d)  [LEADR Algorithm 2, with correction C-L1: L00 += Y00 P, not the
 * printed L00 += L00 + 0.282095 P, which doubles the running sum for every light after the
 * first].  A non-finite power or a non-unit d turns every coefficient into NaN. */
void mf_sh_add_directional(double c[MF_SH_COEFFS], mf_vec3 d, double power);

/* Radiance (or any scalar) as a function of a unit direction. */
typedef double (*mf_sh_fn)(mf_vec3 w, void *user);

/* Projection c_i = integral f(w) Y_i(w) dw over the sphere [R&H 2001, Eq. 10] by a deterministic
 * product rule: n-point Gauss-Legendre in z = cos(theta) on each hemisphere [-1, 0] and [0, 1]
 * separately (a sky that is 0 below the horizon z = 0 has a kink there: split, the rule stays
 * spectrally convergent), times 4n equispaced azimuths phi_k = 2 pi (k + 1/2)/(4n).  Exact for
 * f a spherical polynomial of degree <= 2n - 3 (the products f Y_i of degree <= 2n - 1), so
 * exact for order-2 functions from n = 3.  8 n^2 evaluations of f (plus 8 ceil(n/2)^2 for err).
 * err (may be NULL) receives max_i |c_i(n) - c_i(ceil(n/2))|, an error estimate of the coarser
 * rule, hence conservative for the result.  n in [2, 1024].
 * MF_ERR_DOMAIN for a bad n or a non-finite value of f (coefficients NaN); MF_ERR_ALLOC. */
mf_status mf_sh_project_fn(mf_sh_fn f, void *user, int n, double c[MF_SH_COEFFS], double *err) MF_WARN_UNUSED;

/* Projection of a latitude-longitude (equirectangular) float image of radiance.
 * Mapping (z-up, the shading-frame convention; docs/conventions.md):
 *   pixel (col i, row j), 0 <= i < width, 0 <= j < height, row 0 at the top, covers
 *   phi in [2 pi i/width, 2 pi (i + 1)/width], theta in [pi j/height, pi (j + 1)/height],
 *   so row 0 touches the zenith +z, the last row the nadir -z, column 0 starts at +x and phi
 *   grows with i towards +y; its direction is w = (sin theta cos phi, sin theta sin phi, cos theta)
 *   at the pixel centre (theta, phi at i + 1/2, j + 1/2) = mf_vec3_spherical.
 * A map with another up axis (e.g. +y) gives coefficients in its own frame: mf_sh_rotate them.
 * Each pixel is weighted by its exact solid angle (phi1 - phi0)(cos theta0 - cos theta1), computed
 * as (2 pi/width) 2 sin(theta_c) sin(pi/(2 height)) (no cancellation near the poles); these sum to
 * 4 pi to rounding, so a constant image gives L00 = 2 sqrt(pi) L exactly.  The value of each pixel
 * is taken as the radiance at its centre (midpoint rule): for a smooth radiance field the error is
 * O(height^-2) (tests/test_sh.c measures the order).
 * Pixel (i, j) is pixels[j * row_stride + i * pixel_stride] (strides in floats: for interleaved
 * RGB pass pixels + channel, pixel_stride 3, row_stride 3 width).
 * MF_ERR_DOMAIN for a NULL image, width or height < 1, pixel_stride < 1, row_stride <
 * width * pixel_stride, or a non-finite pixel (coefficients NaN). */
mf_status mf_sh_project_latlong(const float *pixels, int width, int height, int pixel_stride, int row_stride,
                                double c[MF_SH_COEFFS]) MF_WARN_UNUSED;

/* Rotation: out holds the coefficients of g(w) = f(R^T w), f the function of `in` (f rotated by R).
 * R must be orthogonal (max |R R^T - I| <= 1e-9; det -1 allowed), else out is NaN.  Exact: band 1
 * rotates as the vector (c(1,1), c(1,-1), c(1,0)), band 2 as the traceless symmetric matrix Q
 * with f_2(w) = w^T Q w (Q' = R Q R^T).  out may alias in. */
void mf_sh_rotate(const double in[MF_SH_COEFFS], mf_mat3 r, double out[MF_SH_COEFFS]);
/* World-frame coefficients to the local frame f (f.s, f.t, f.n the local x, y, z in world
 * coordinates): mf_sh_rotate with R = rows (s, t, n).  Then reconstruct(local, w_local) =
 * reconstruct(world, mf_frame_to_world(f, w_local)). */
void mf_sh_to_frame(const double world[MF_SH_COEFFS], mf_frame f, double local[MF_SH_COEFFS]);

/* Windows against ringing [Sloan 2008]: band l is multiplied by
 *   Hanning  (1 + cos(pi l/w)) / 2,   Lanczos  sin(pi l/w) / (pi l/w)   for l < w, and 0 for l >= w;
 * w > 0 is the window width (w = MF_SH_ORDER + 1 = 3 keeps bands 0..2: Hanning 1, 3/4, 1/4;
 * Lanczos 1, 0.827, 0.413).  Band 0 is never changed (the mean is kept).  Windowing is an option,
 * off unless the caller applies it; it trades ringing for blur. */
typedef enum mf_sh_window {
    MF_SH_WINDOW_NONE = 0,
    MF_SH_WINDOW_HANNING = 1,
    MF_SH_WINDOW_LANCZOS = 2
} mf_sh_window;
/* The factor of band l; NaN for l < 0, a non-finite or non-positive width, or an unknown window. */
double mf_sh_window_factor(mf_sh_window window, int l, double width);
/* Multiplies each band of c by its factor (NaNs on invalid arguments). */
void mf_sh_apply_window(double c[MF_SH_COEFFS], mf_sh_window window, double width);

#ifdef __cplusplus
}
#endif
#endif /* MF_SH_H */
