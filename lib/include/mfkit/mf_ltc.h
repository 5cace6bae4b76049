/*
 * mf_ltc.h -- linearly transformed cosines (LTCs): density, sampling, integral over polygons.
 *
 * An LTC is the distribution of w = M wo / |M wo| when wo has the normalised clamped-cosine
 * density D_o(wo) = max(0, wo.z) / pi [Heitz et al. 2016, "Real-Time Polygonal-Light Shading
 * with Linearly Transformed Cosines", SIGGRAPH; Nahmias Eq. 2.19, 2.24].  M is any
 * invertible 3x3 matrix (row-major, docs/conventions.md), including det M < 0 (a mirrored lobe)
 * and strong shear.  Its density per steradian of w (unit w) is
 *
 *   D(w) = D_o(M^-1 w / |M^-1 w|) |det M^-1| / |M^-1 w|^3                  [Nahmias Eq. 2.21]
 *
 * with the Jacobian d wo / d w = |det M^-1| / |M^-1 w|^3 [Heitz et al. 2016, appendix], which
 * the thesis does not print (docs/math.md, correction C-T2).  D integrates to 1 over the sphere [Nahmias Eq. 2.22]
 * and is positive exactly on the hemisphere (M^-1 w).z > 0, which need not be the upper one.
 *
 * Integral over a polygon P (mf_polygon.h) [Nahmias Eq. 2.23, 2.32-2.33]:
 *   integral over P of D(w) dw = integral over P_o = M^-1 P of D_o = E(P_o clipped to z_o >= 0),
 * where E is the integral of the NORMALISED clamped cosine max(0, z)/pi (correction C-T3: not the
 * irradiance, which is pi times larger), and the clipping is done AFTER the transform, at the
 * support z_o >= 0 of D_o (correction C-T4: clipping P at the shading horizon first is wrong: it
 * misses the lobe below the horizon and keeps parts outside the lobe's support).
 * One-sided: a polygon contributes only when it faces the shading point (mf_polygon.h); the
 * facing is that of P, so the sign of det M (a reflection reverses the winding of P_o) is
 * accounted for.
 *
 * Parameterisations.  Isotropic fits of a BRDF use the view frame in which wo lies in the +x half
 * of the xz plane (mf_ltc_view_frame): there M = [[a, 0, b], [0, c, 0], [d, 0, 1]]
 * [Heitz et al. 2016; Nahmias Eq. 2.26]; anisotropic fits use all 9 entries [Kt et al. 2022,
 * "Bringing Linearly Transformed Cosines to Anisotropic GGX", I3D; Nahmias Sec. 2.2.7].  The
 * overall scale of M does not matter (D is invariant under M -> k M, k > 0; k < 0 mirrors the
 * lobe through the origin).
 *
 * Sphere approximation.  Renderers that avoid clipping replace the polygon by a spherical cap with
 * the same vector form factor F and integrate the clamped cosine over that cap in closed form
 * with horizon clipping [Snyder 1996, "Area Light Sources for Real-Time Graphics", Microsoft
 * Research MSR-TR-96-11; Heitz & Hill 2017, "Real-Time Line- and Disk-Light Shading with
 * Linearly Transformed Cosines", SIGGRAPH course notes]: mf_ltc_sphere_integral.
 */
#ifndef MF_LTC_H
#define MF_LTC_H

#include "mfkit/mf_polygon.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mf_ltc {
    mf_mat3 m;          /* M: w = M wo / |M wo| */
    mf_mat3 inv;        /* M^-1 */
    double det;         /* det M (non-zero; negative for a mirrored lobe) */
    double abs_det_inv; /* |det M^-1| = 1 / |det M| */
} mf_ltc;

/* Sets up the LTC of matrix m (row-major).  MF_ERR_DOMAIN, leaving *ltc untouched, if m has a
 * non-finite entry, det m = 0, or its inverse or 1/|det m| is not finite (numerically singular).
 * Ill-conditioned matrices are accepted: D, the sampler and the polygon integral then lose about
 * log10(condition number) digits. */
mf_status mf_ltc_init(mf_ltc *ltc, mf_mat3 m) MF_WARN_UNUSED;

/* D(w), per steradian of w [Nahmias Eq. 2.21 with the Jacobian of correction C-T2]; 0 where
 * (M^-1 w).z <= 0.  w is a direction (normalised here, so its length does not matter); a zero or
 * non-finite w gives NaN. */
double mf_ltc_eval(const mf_ltc *ltc, mf_vec3 w);

/* Sample w = M wo / |M wo|, wo from mf_sample_cosine_hemisphere(u), u in [0, 1)^2
 * [Nahmias Eq. 2.19].  Its density per steradian is mf_ltc_pdf(w) = mf_ltc_eval(w). */
mf_vec3 mf_ltc_sample(const mf_ltc *ltc, const double u[2]);
double mf_ltc_pdf(const mf_ltc *ltc, mf_vec3 w);

/* Integral over the polygon p of D(w) dw, dimensionless in [0, 1]: the cosine integral of
 * M^-1 p clipped to z_o >= 0 after the transform (corrections C-T3, C-T4; see above).  ONE_SIDED: 0 when p
 * faces away from the shading point.  NaN outside the domain of mf_polygon_valid. */
double mf_ltc_integrate_polygon(const mf_ltc *ltc, const mf_polygon *p, mf_polygon_sided sided);

/* The isotropic form [[a, 0, b], [0, c, 0], [d, 0, 1]] [Heitz et al. 2016; Nahmias Eq. 2.26],
 * in the view frame of mf_ltc_view_frame. */
mf_mat3 mf_ltc_matrix_isotropic(double a, double b, double c, double d);
/* The general form: m[0..8] = m00, m01, m02, m10, ..., m22 (row-major). */
mf_mat3 mf_ltc_matrix_general(const double m[9]);

/* The view frame of an isotropic fit: n = z (up), s = normalize(wo - wo.z z) (wo in the +x half
 * of the local xz plane), t = n x s.  At normal incidence (wo.x = wo.y = 0) s = x.  A frame of
 * NaNs for non-finite wo.  Local coordinates of a world direction: mf_frame_to_local(f, w). */
mf_frame mf_ltc_view_frame(mf_vec3 wo);
/* The matrix of the same lobe in world coordinates: R M with R = [s t n] (columns).  Because
 * n = z and D_o is invariant under rotations about z, the world LTC of R M equals the local LTC
 * of M evaluated at mf_frame_to_local(f, w). */
mf_mat3 mf_ltc_matrix_to_world(mf_frame f, mf_mat3 m_local);

/* Integral of max(0, z)/pi over the spherical cap whose unclipped vector form factor is F
 * (sin^2(sigma) = |F|, sigma the cap's angular radius; centre at cos(theta) = F.z/|F| from the
 * normal), clipped at the horizon:
 *   cap above the horizon (cos^2 theta >= sin^2 sigma, cos theta > 0):  |F| cos theta = F.z;
 *   cap below it:                                                      0;
 *   otherwise [Snyder 1996, as in Heitz & Hill 2017]:
 *     (1/pi) [ (cos theta acos y - x sin theta sqrt(1 - y^2)) sin^2 sigma
 *              + atan(sin theta sqrt(1 - y^2) / x) ],  x = cot sigma,  y = -x cot theta,
 *   evaluated in a rearranged form without the cancellation of the printed one for small caps
 *   (docs/math.md).  Exact for caps; for a polygon it is the "clipless" approximation of
 *   renderers, exact whenever the equivalent cap lies above the horizon.
 * f_len = |F| in [0, 1], f_cos = F.z/|F| in [-1, 1] (values within 1e-12 outside, from rounding,
 * are clamped); otherwise NaN. */
double mf_ltc_sphere_integral(double f_len, double f_cos);

/* The clipless approximation of mf_ltc_integrate_polygon: F of the unclipped M^-1 p, oriented by
 * the facing of p (one-sided: 0 when p faces away), passed to mf_ltc_sphere_integral. */
double mf_ltc_integrate_polygon_sphere(const mf_ltc *ltc, const mf_polygon *p, mf_polygon_sided sided);

#ifdef __cplusplus
}
#endif
#endif /* MF_LTC_H */
