/*
 * mf_ltcfit.h -- fit isotropic LTC lookup tables (mf_ltc_table.h) to a BRDF model (mf_model.h).
 *
 * For every texel (alpha, cos theta_o) of an n_r x n_u table the fitter finds the isotropic LTC
 * M = [[a, 0, b], [0, c, 0], [d, 0, 1]] in the view frame [Heitz et al. 2016; Nahmias Eq. 2.26]
 * that best reproduces POLYGON-LIT shading, the only use renderers make of the table:
 *
 *   residual_k = (magnitude * E_LTC(P_k; M) - I_k) / (I_k + 0.2 magnitude),   k = 1..K
 *
 * (the floor 0.2: docs/tables.md, "Weight floor"; two low lights have residual weights that blend
 * with the lobe's side, so that the objective is continuous in the texel)
 *
 * over a fixed family of K test lights P_k placed around the BRDF lobe (quads, triangles and
 * cap-like 8-gons of angular radius 0.25 to 4 lobe widths on the lobe and beside it, lights
 * across the horizon and large caps; docs/tables.md).  E_LTC is the LTC integral of the polygon
 * (transform by M^-1, clip at z >= 0, Lambert's edge sum; mf_ltc_integrate_polygon); I_k the
 * integral of f(wo, wi) wi.z over P_k, estimated from ONE set of directions per texel: the first
 * `samples` points of the 2D Sobol sequence, XOR-scrambled with two words drawn from `seed`
 * (the same scramble for every texel, so neighbouring texels see the same point set mapped
 * through slightly different samplers and their errors are correlated: a smoother table), mapped
 * through the model's sampler (or the cosine hemisphere) with weights f cos / pdf, reused across
 * all lights; the weights are rescaled so that their mean equals the quadrature magnitude, and a
 * control variate (the previous texel's LTC, whose light integrals are exact, with a per-light
 * regression coefficient in [0, 1]) removes most of the noise of the light edges.  Views with
 * cos theta < 0.2 use 4 x `samples` directions.  A
 * direction is inside a convex spherical polygon when dot(w, v_i x v_i+1) > 0 for every edge.
 * The Jacobian is exact: forward-mode dual numbers (4 derivatives) through the transform, the
 * clip and the edge formula.  The least-squares problem is solved by mfkit's Ceres bridge
 * (mf_solver.h, Levenberg-Marquardt) in the LOBE frame: M = R M', R the rotation about y taking z
 * to the mean direction of f cos, M' = [[a', 0, b'], [0, c', 0], [d', 0, 1]] (the same family, but
 * well conditioned when the lobe nears the horizon, where the view-frame M22 -> 0), bounds
 * a', c' >= 1e-7 and a' - b' d' > 0 (positive det).
 *
 * Warm start and determinism.  Each roughness column ir is fitted sequentially along u (view
 * angle) from a closed-form start at u = 0 (the best isotropic scaling a' = c' = s, b' = d' = 0 of a
 * log grid of s, about the lobe's mean direction), each entry starting from the previous entry's
 * lobe-frame solution (when its cost is not above that of the closed-form start, which every
 * entry computes).  Four proximal residuals, 0.1 (b' - b'_prev), 0.1 (d' - d'_prev),
 * 0.1 (a' - a'_prev) / a'_prev, 0.1 (c' - c'_prev) / c'_prev, keep weakly determined directions
 * continuous along the column (docs/tables.md, "Proximal term"), and where the lobe's mean is within 0.1 of the
 * normal a forward-skewed fit (d' > 0) is replaced by its mirror image if that costs within 1 %
 * (docs/tables.md, "Mirror convention").  Columns are
 * independent and handed out to `threads` pthreads; so the result does not depend on the thread
 * count or the order, bit for bit (tests/test_ltcfit.c).
 *
 * Stored per texel (mf_ltc_table.h): the packed M^-1, the magnitude (the model's albedo by
 * deterministic quadrature: a product Gauss-Legendre rule, 8 panels x 8 points per axis, over the
 * sampler's map, graded towards grazing micro-normals; error estimate against 4 panels; see
 * mf_ltcfit.c for why not mf_brdf_microfacet_albedo), the
 * Fresnel term (the same quadrature of f cos (1 - wo.wh)^5), zero, and the sphere term:
 * mf_ltc_sphere_integral(len, z) / len on the reference's indexing z = 2 r - 1, len = u (the
 * "scale" a shader multiplies |F| by; max(z, 0) at len = 0); it does not depend on the BRDF.
 *
 * Interruption.  `cancel` (a flag set from a signal handler) and `stop_after_columns` make the
 * fit return early with result->interrupted = 1 after finishing the columns in progress; the
 * table is then not filled.  With `checkpoint` set, every completed column is written (atomically:
 * temporary file + rename) with the float64 bits of its entries; `resume` loads it, checks that
 * it belongs to the same model, size, seed and settings, and fits only the missing columns: the
 * result is bitwise the one of an uninterrupted run.
 */
#ifndef MF_LTCFIT_H
#define MF_LTCFIT_H

#include <stddef.h>
#include <stdint.h>

#include <mfkit/mf_core.h>
#include <mfkit/mf_ltc_table.h>
#include <mfkit/mf_model.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mf_ltcfit_options {
    int n_r, n_u;              /* table size, >= 2 each (default 64 x 64) */
    int threads;               /* worker threads, 1..256 (default 1) */
    uint64_t seed;             /* scramble of the Sobol points (default 1) */
    int samples;               /* directions per texel, a power of two in [64, 1 << 20] (default 4096) */
    int max_iterations;        /* per solve (default 100) */
    const char *checkpoint;    /* NULL: no checkpoint file */
    int resume;                /* load `checkpoint` if it exists and skip its completed columns */
    int stop_after_columns;    /* > 0: fit at most this many columns in this run, then return
                                * interrupted (a test hook for resume); 0: no limit */
    const volatile int *cancel;/* may be NULL; non-zero: stop after the columns in progress */
    void (*progress)(void *user, int done, int total); /* may be NULL; called under a lock */
    void *progress_user;
    double r_lo, r_hi;         /* the roughness axis r (alpha = max(r^2, 1e-4)): default [0, 1] */
    double u_lo, u_hi;         /* the view axis u = sqrt(1 - cos theta_o): default [0, 1]; 0 <= lo < hi <= 1 */
    /* Optional, NULL by default (mf_ltcfit_table only): 3 doubles per texel, index 3 (ir + n_r iu):
     * the albedo, its error estimate and the Fresnel moment at the texel, as
     * mf_ltc_gate_texel_albedo_fresnel returns them for a table of this layout, computed beforehand
     * (mf_ltc_bake computes them once for the fit and the gate).  They are the values the fitter
     * computes (mf_model_albedo_fresnel, 64 points per axis, at the texel's alpha and view), so the
     * table is the same bits with or without them; a NaN albedo is computed by the fitter. */
    const double *albedo;
} mf_ltcfit_options;

void mf_ltcfit_options_default(mf_ltcfit_options *o);

/* The float64 fit of one texel. */
typedef struct mf_ltcfit_entry {
    double a, b, c, d;       /* M = [[a, 0, b], [0, c, 0], [d, 0, 1]]: M / M22 of m below (NaN when the
                              * fitted M22 <= 0, possible at grazing views of smooth BRDFs) */
    double m[9];             /* the fitted view-frame M, row-major, as solved (its scale is irrelevant) */
    double residual;         /* RMS of the K weighted residuals at the solution (dimensionless) */
    int iterations;          /* solver steps (accepted + rejected) */
    int converged;           /* the solver met a tolerance */
    double magnitude;        /* albedo */
    double magnitude_err;    /* its quadrature error estimate */
    double fresnel;          /* integral of f cos (1 - wo.wh)^5 */
} mf_ltcfit_entry;

typedef struct mf_ltcfit_result {
    int n_r, n_u;
    mf_ltcfit_entry *entries; /* n_r * n_u, texel ir + n_r iu (owned; mf_ltcfit_result_free) */
    int interrupted;          /* stopped by cancel or stop_after_columns: table not filled */
    int columns_done;         /* completed columns (including those loaded by resume) */
    int columns_resumed;      /* loaded from the checkpoint */
    double worst_residual;    /* over the table */
    int worst_index;
    int max_iterations;       /* largest per-entry iteration count */
    long total_iterations;
    int not_converged;        /* entries whose solve did not meet a tolerance */
} mf_ltcfit_result;

/* Fits every texel of a new table *table (mf_ltc_table_create(o->n_r, o->n_u)) to the model and
 * fills its fields and metadata ("tool", "brdf", "seed", "samples").  On MF_OK with
 * result->interrupted the table is freed (zeroed).  MF_ERR_DOMAIN (bad options or model),
 * MF_ERR_ALLOC, MF_ERR_IO / MF_ERR_FORMAT (checkpoint; msg says which), MF_ERR_INTERNAL. */
mf_status mf_ltcfit_table(const mf_brdf_model *model, const mf_ltcfit_options *o, mf_table *table,
                          mf_ltcfit_result *result, char *msg, size_t msg_size) MF_WARN_UNUSED;
void mf_ltcfit_result_free(mf_ltcfit_result *r);

/* Fits one texel (alpha > 0, cos_theta in (0, 1]) from `start` (a view-frame M, 9 doubles
 * row-major; NULL: the closed-form start) with the options' seed, samples and max_iterations. */
mf_status mf_ltcfit_entry_fit(const mf_brdf_model *model, double alpha, double cos_theta, const double *start,
                              const mf_ltcfit_options *o, mf_ltcfit_entry *out) MF_WARN_UNUSED;

/* mf_ltcfit_entry_fit with the texel's albedo given instead of computed (albedo NULL: computed):
 * the fitter computes it by mf_model_albedo_fresnel with 64 points per axis, the rule and points of
 * mf_ltc_gate_texel_albedo, so a caller holding that value (the texel check of mf_ltc_bake) gets
 * the same fit, bit for bit, without the quadrature.  out->fresnel is NaN (not computed); a
 * non-finite albedo->val is MF_ERR_DOMAIN. */
mf_status mf_ltcfit_entry_fit_albedo(const mf_brdf_model *model, double alpha, double cos_theta, const double *start,
                                     const mf_ltcfit_options *o, const mf_result *albedo,
                                     mf_ltcfit_entry *out) MF_WARN_UNUSED;

/* The fitter's objective for one texel at parameters p = (a, b, c, d): fills res[0..K-1] (K =
 * mf_ltcfit_light_count()) and, if jac != NULL, the K x 4 Jacobian.  For tests. */
int mf_ltcfit_light_count(void);
mf_status mf_ltcfit_objective(const mf_brdf_model *model, double alpha, double cos_theta, const mf_ltcfit_options *o,
                              const double p[4], double *res, double *jac) MF_WARN_UNUSED;

/* Writes the float64 fit as JSON ({"brdf", "n_r", "n_u", "seed", "samples", "entries": [{"ir",
 * "iu", "alpha", "cos_theta", "a", "b", "c", "d", "residual", "iterations", "converged",
 * "magnitude", "magnitude_err", "fresnel"}, ...]}, numbers %.17g: they read back bitwise),
 * atomically.  MF_ERR_IO with msg. */
mf_status mf_ltcfit_write_sidecar(const char *path, const mf_brdf_model *model, const mf_ltcfit_options *o,
                                  const mf_table *table, const mf_ltcfit_result *r, char *msg,
                                  size_t msg_size) MF_WARN_UNUSED;

#ifdef __cplusplus
}
#endif
#endif /* MF_LTCFIT_H */
