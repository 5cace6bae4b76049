/*
 * mf_ltc_aniso_table.h -- the 4-D anisotropic LTC table (table kind "ltc_anisotropic").
 *
 * Axes [Kt, Heitz, Dupuy, Narayanan 2022, Sec. 5] (all MF_AXIS_IDENTITY):
 *   MF_LTC_ANISO_PARAM_ALPHA_XY:     "ax" (alpha_x, clamp 1e-4) in [0, 1], "ay" (alpha_y, clamp 1e-4) in [0, 1],
 *   MF_LTC_ANISO_PARAM_ALPHA_LAMBDA: "a" (alpha, clamp 1e-4) in [0, 1], "lambda" (alpha_y / alpha_x) in [0, 1]:
 *                                    alpha_x = max(a, 1e-4), alpha_y = max(a lambda, 1e-4),
 *   then "theta" (view elevation) in [0, 0.9999 pi/2] and "phi" (view azimuth) in [0, pi/2].
 * The view is wo = (sin theta cos phi, sin theta sin phi, cos theta) in the frame whose x axis is
 * the alpha_x direction (the shading tangent).
 *
 * Fields: m00 .. m22, the forward LTC matrix M (row-major, view frame, cosine directions to lobe
 * directions) divided by the norm of its last column (the published layout); minv00 .. minv22 its
 * inverse (what a shader applies to the polygon's vertices before the edge sum); magnitude (the
 * albedo), fresnel (the integral of f cos (1 - wo.wh)^5: a shader scales by
 * F0 magnitude + (1 - F0) fresnel), residual (the fit's RMS weighted light residual).
 *
 * Other azimuths.  GGX with axis-aligned roughness is symmetric under x -> -x and y -> -y, so for
 * a view at azimuth phi in [0, 2 pi): reduce phi to phi' in [0, pi/2] by
 *   phi in (pi/2, pi]:     phi' = pi - phi,   mirror S_x = diag(-1, 1, 1)
 *   phi in (pi, 3 pi/2]:   phi' = phi - pi,   mirror S_x S_y
 *   phi in (3 pi/2, 2 pi): phi' = 2 pi - phi, mirror S_y = diag(1, -1, 1)
 * and use M(phi) = S M(phi') S (M^-1 likewise; S = S^-1, det unchanged) (mf_ltc_aniso_lookup).
 *
 * Pure C11.
 */
#ifndef MF_LTC_ANISO_TABLE_H
#define MF_LTC_ANISO_TABLE_H

#include <stddef.h>
#include <stdint.h>

#include "mfkit/mf_check.h"
#include "mfkit/mf_core.h"
#include "mfkit/mf_model.h"
#include "mfkit/mf_table.h"

#ifdef __cplusplus
extern "C" {
#endif

enum { MF_LTC_ANISO_PARAM_ALPHA_XY = 0, MF_LTC_ANISO_PARAM_ALPHA_LAMBDA = 1 };

enum {
    MF_LTCA_F_M00 = 0,     /* m00 .. m22: fields 0..8 */
    MF_LTCA_F_MINV00 = 9,  /* minv00 .. minv22: fields 9..17 */
    MF_LTCA_F_MAGNITUDE = 18,
    MF_LTCA_F_FRESNEL = 19,
    MF_LTCA_F_RESIDUAL = 20,
    MF_LTCA_NFIELDS = 21
};
extern const char *const mf_ltc_aniso_table_fields[MF_LTCA_NFIELDS];

#define MF_LTC_ANISO_ALPHA_MIN 1e-4
#define MF_LTC_ANISO_THETA_MAX (0.9999 * 0.5 * MF_PI)

/* Creates a zeroed table of sizes n[0..3] (>= 2 each) in the given parameterisation, tagged with
 * its kind.  MF_ERR_DOMAIN, MF_ERR_ALLOC. */
mf_status mf_ltc_aniso_table_create(mf_table *t, const int n[4], int param) MF_WARN_UNUSED;

/* The parameterisation of t (from its first two axes' names), or -1 if t is not such a table. */
int mf_ltc_aniso_table_param(const mf_table *t);

/* (alpha_x, alpha_y) of the first two axis parameters p0, p1 in parameterisation param. */
void mf_ltc_aniso_alphas(int param, double p0, double p1, double *alpha_x, double *alpha_y);

/* The physical values of entry idx[0..3]. */
void mf_ltc_aniso_entry_values(const mf_table *t, const int idx[4], double *alpha_x, double *alpha_y,
                               double *theta, double *phi);

/* The shader's lookup: quadrilinear interpolation (mf_table_lookup, clamp to edge) at
 * (alpha_x, alpha_y, theta, phi) for any phi (the mirrors above; alpha-lambda tables use
 * a = alpha_x, lambda = alpha_y / alpha_x), the forward M (9, row-major, as interpolated, then
 * mirrored) and, if not NULL, magnitude and fresnel.  MF_ERR_DOMAIN for NaN or a table of
 * another layout. */
mf_status mf_ltc_aniso_lookup(const mf_table *t, double alpha_x, double alpha_y, double theta, double phi,
                              double m[9], double *magnitude, double *fresnel) MF_WARN_UNUSED;

/* 1 if t has the layout; else 0 with a one-line reason. */
int mf_ltc_aniso_layout_ok(const mf_table *t, char *why, size_t why_size);

/* ---- the gate -------------------------------------------------------------------------------
 *   ltca_finite         no NaN or infinity in any field                              (model-free)
 *   ltca_energy         magnitude <= 1 + 1e-5, 0 <= fresnel <= magnitude + 1e-5       (model-free)
 *   ltca_normalisation  |integral of the LTC of minv over the sphere - 1| <= 1e-6: the sum of its
 *                       exact integrals over the 8 octant triangles of a rotated frame (model-free)
 *   ltca_inverse        minv is m's inverse: per element, |(minv m - I)_ab| <= 1e-12 |minv|_F |m|_F
 *                       + (s + 8 eps) (|minv| |m|)_ab, s = (2 u + u^2) / (1 - u)^2 the storage rounding
 *                       of the product's terms (u = unit_roundoff below; 0 in memory); the measure is
 *                       the worst ratio, bound 1                                       (model-free)
 *   ltca_smooth_jump    |difference| of m00..m22 and magnitude between neighbours along each of
 *                       the 4 axes, and across phi = 0 and phi = pi/2 to the mirrored neighbour
 *                       (S M S of the entry beside the boundary), <= 16 h (h = 1/(n - 1): the
 *                       isotropic gate's rule)                                        (model-free)
 *   ltca_smooth_spike   no entry outside the range of its two neighbours along an axis (mirrored
 *                       neighbours at the phi boundaries) by more than 80 h^2 (with a model, a
 *                       magnitude spike is measured on magnitude - albedo, as in mf_ltc_gate.h:
 *                       the true albedo has sharp features at grazing)                (model-free)
 *   ltca_albedo         |magnitude - albedo| / max(albedo, 0.01) <= 1e-3 + 4 err / albedo, the
 *                       albedo by mf_model_albedo (64 x 64), at the tested entries    (model)
 *   ltca_polygon_mean   at `entries` entries drawn by the seed: random quads and triangles
 *                       (mf_ltc_gate_random_polygons_params), Monte Carlo of f cos
 *                       (mf_ltc_gate_polygon_mc_params): mean of max(0, |LTC - MC| - 5.5 se) /
 *                       albedo <= 0.01                                                (model)
 *   ltca_polygon_entry  the same mean per entry, worst <= 0.05                        (model)
 * The bounds are the isotropic gate's (mf_ltc_gate.h, docs/validation.md). */
typedef struct mf_ltc_aniso_gate_options {
    uint64_t seed;          /* default 1 */
    int entries;            /* entries with albedo and polygon tests (default 64; 0 or more than
                             * the table: every entry) */
    int polygons_per_entry; /* default 24 */
    int mc_samples;         /* default 32768 */
    /* outputs (may be NULL): polygon error aggregates in units of the albedo */
    double *mean_abs_out, *mean_rel_out;
    double unit_roundoff;   /* storage rounding of the table's values (mf_table_storage_roundoff: 2^-24
                             * for a float32 file, 2^-11 for halves; default 0, a table in memory):
                             * ltca_inverse allows each term of minv m its storage rounding, 2 u + u^2
                             * relative (see above) */
} mf_ltc_aniso_gate_options;

#define MF_LTC_ANISO_GATE_MAX_CHECKS 9
void mf_ltc_aniso_gate_options_default(mf_ltc_aniso_gate_options *o);
extern const mf_check_def mf_ltc_aniso_gate_check_table[MF_LTC_ANISO_GATE_MAX_CHECKS];
/* Runs the gate (model may be NULL: model-free checks only).  MF_OK, MF_ERR_CHECK_FAILED,
 * MF_ERR_DOMAIN (layout, cap), MF_ERR_ALLOC. */
mf_status mf_ltc_aniso_gate_run(const mf_table *t, const mf_brdf_model *model, const mf_ltc_aniso_gate_options *o,
                                mf_check *checks, int cap, int *count) MF_WARN_UNUSED;

#ifdef __cplusplus
}
#endif
#endif /* MF_LTC_ANISO_TABLE_H */
