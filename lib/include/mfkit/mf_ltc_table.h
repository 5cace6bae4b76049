/*
 * mf_ltc_table.h -- the layout of an isotropic LTC lookup table, as renderers load it.
 *
 * The table is an mf_table (mf_table.h) with two axes:
 *   axis 0 "r" (texture u / x): roughness r in [0, 1], alpha = max(r^2, alpha_min)   (MF_AXIS_SQUARE)
 *   axis 1 "u" (texture v / y): u = sqrt(1 - cos theta_o) in [0, 1], cos theta_o = 1 - u^2,
 *                               clamped to >= cos(1.57) like the reference fitter     (MF_AXIS_ONE_MINUS_SQUARE)
 * Texel (ir, iu) is record ir + n_r iu; texel centres on the grid points (mf_table.h), so a
 * shader samples at uv = (r, u) * (n - 1)/n + 0.5/n.  This is the parameterisation of the public
 * reference tables (Heitz et al. 2016, `ltc_code`; tests/data/reference/README.md).
 *
 * Fields (the common two-texture layout, "ltc_1" and "ltc_2"):
 *   MF_LTC_F_MINV_00, _20, _02, _22   ltc_1.rgba: the inverse matrix M^-1 of the isotropic LTC in the
 *                                     view frame (mf_ltc_view_frame), divided by its middle element
 *                                     (1,1); a shader rebuilds
 *                                     Minv = [[m00, 0, m02], [0, 1, 0], [m20, 0, m22]]
 *   MF_LTC_F_MAGNITUDE                ltc_2.r: the BRDF's directional albedo without Fresnel,
 *                                     integral of f(wo, wi) wi.z dwi
 *   MF_LTC_F_FRESNEL                  ltc_2.g: integral of f wi.z (1 - wo.wh)^5 dwi (the Schlick split:
 *                                     shading = F0 * magnitude + (1 - F0) * fresnel ... see docs/tables.md)
 *   MF_LTC_F_ZERO                     ltc_2.b: 0 (kept for the layout)
 *   MF_LTC_F_SPHERE                   ltc_2.a: the horizon-clipped sphere form factor term
 *                                     (mf_ltc_sphere_integral) tabulated on the reference's
 *                                     (2 r - 1, u) indexing (docs/tables.md)
 * A float64 sidecar keeps the fitted parameters (a, b, c, d of mf_ltc_matrix_isotropic) and the
 * residual of every entry.
 */
#ifndef MF_LTC_TABLE_H
#define MF_LTC_TABLE_H

#include "mfkit/mf_ltc.h"
#include "mfkit/mf_table.h"

#ifdef __cplusplus
extern "C" {
#endif

enum {
    MF_LTC_F_MINV_00 = 0,
    MF_LTC_F_MINV_20 = 1,
    MF_LTC_F_MINV_02 = 2,
    MF_LTC_F_MINV_22 = 3,
    MF_LTC_F_MAGNITUDE = 4,
    MF_LTC_F_FRESNEL = 5,
    MF_LTC_F_ZERO = 6,
    MF_LTC_F_SPHERE = 7,
    MF_LTC_NFIELDS = 8
};

/* Field names in the order above: "minv_00", "minv_20", "minv_02", "minv_22", "magnitude",
 * "fresnel", "zero", "sphere". */
extern const char *const mf_ltc_table_fields[MF_LTC_NFIELDS];

/* Smallest alpha of the roughness axis (alpha = max(r^2, MF_LTC_ALPHA_MIN)): the lower end of
 * mfkit's tested domain. */
#define MF_LTC_ALPHA_MIN 1e-4
/* Largest theta_o of the view axis (radians), as in the reference fitter: cos clamped >= cos(1.57). */
#define MF_LTC_THETA_MAX 1.57

/* Creates an empty n_r x n_u LTC table with the axes above (n_r, n_u >= 2), r and u over [0, 1].
 * MF_ERR_DOMAIN, MF_ERR_ALLOC. */
mf_status mf_ltc_table_create(mf_table *t, int n_r, int n_u) MF_WARN_UNUSED;
/* The same with r over [r_lo, r_hi] and u over [u_lo, u_hi] (0 <= lo < hi <= 1 each): texel i of
 * an axis of n texels holds lo + (hi - lo) i / (n - 1).  Only the default ranges give the common
 * drop-in layout (docs/tables.md).  MF_ERR_DOMAIN for bad sizes or ranges, MF_ERR_ALLOC. */
mf_status mf_ltc_table_create_range(mf_table *t, int n_r, double r_lo, double r_hi, int n_u, double u_lo,
                                    double u_hi) MF_WARN_UNUSED;

/* alpha and cos theta_o of texel (ir, iu). */
double mf_ltc_table_alpha(const mf_table *t, int ir);
double mf_ltc_table_cos_theta(const mf_table *t, int iu);

/* The inverse-matrix fields of an isotropic LTC M = [[a, 0, b], [0, c, 0], [d, 0, 1]]: M^-1 divided
 * by its (1, 1) element, as four values in field order.  MF_ERR_DOMAIN for a singular M. */
mf_status mf_ltc_table_pack(double a, double b, double c, double d, double out4[4]) MF_WARN_UNUSED;
/* The LTC a shader rebuilds from the four stored values (the inverse of mf_ltc_table_pack up to
 * the irrelevant scale of M).  MF_ERR_DOMAIN if the rebuilt matrix is singular. */
mf_status mf_ltc_table_unpack(const double in4[4], mf_ltc *ltc) MF_WARN_UNUSED;

#ifdef __cplusplus
}
#endif
#endif /* MF_LTC_TABLE_H */
