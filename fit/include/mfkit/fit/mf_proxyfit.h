/*
 * mf_proxyfit.h -- fitting the closed form of the GGX proxy roughness (mf_proxy.h) with Ceres.
 *
 * What it does.  Tabulates the exact proxy roughness alpha'(alpha, dh) of [Kaplanyan 2016,
 * Eq. 19] (mf_filter_ggx_proxy_alpha, docs/math.md, correction C-K3) on a grid log-spaced in both alpha and dh,
 * then fits the coefficients (c, q) of
 *   alpha'^2 = alpha^2 + dh^2 R(x),  x = dh^2/(alpha^2 + dh^2),
 *   R(x) = (1 - x)/3 + x/pi + x (1 - x) c / (1 + q x)
 * by least squares of the relative error of alpha' (residual fit/exact - 1 per grid point) with
 * mf_solver_least_squares and the analytic Jacobian, q bounded to [-0.95, 10] so that 1 + q x > 0.
 * The limits R(0) = 1/3 (dh << alpha) and R(1) = 1/pi (dh >> alpha) hold for any coefficients.
 * Start point c = 0, q = 0 (the plain blend of the two limits); the fit is deterministic.
 *
 * Errors are then measured on a check grid 4x finer than the table along each axis (it contains
 * the table's points and three points between each pair), for the fitted form and for the paper's
 * sqrt(alpha^2 + dh^2).  Since alpha'/alpha depends on dh/alpha only, the relative error is a
 * function of x alone; the report also gives its maximum over a dense sweep of x in [0, 1]
 * (max_rel_all), which bounds the error for every alpha > 0, dh >= 0.
 *
 * Outputs (mf_proxyfit_write, each file replaced atomically: temporary file + rename):
 *   <dir>/ggx_proxy_table.json, <dir>/ggx_proxy_table.h   the table (mf_table_write): axes
 *       log10_alpha, log10_dh (identity mapping: alpha = 10^p); fields alpha, dh, alpha_eff
 *       (exact), alpha_eff_sqrt, alpha_eff_fit;
 *   <dir>/ggx_proxy_fit.h      C header: the coefficients (%.17g) and an inline evaluator;
 *   <dir>/ggx_proxy_fit.glsl   GLSL function mf_ggx_proxy_alpha(alpha, dh);
 *   <dir>/ggx_proxy_fit.json   the form, coefficients, domain, grid, error report, solver summary.
 *
 * References: [Kaplanyan 2016] Kaplanyan, Hill, Patney, Lefohn. Filtering Distributions of Normals
 * for Shading Antialiasing. HPG 2016, Eq. 18-20; docs/math.md "GGX proxy: fitted form".
 */
#ifndef MF_PROXYFIT_H
#define MF_PROXYFIT_H

#include <stddef.h>

#include <mfkit/mf_core.h>
#include <mfkit/mf_proxy.h>
#include <mfkit/fit/mf_solver.h>
#include <mfkit/mf_table.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mf_proxyfit_options {
    int size;                  /* grid points per axis of the table, >= 2 (default 64) */
    double alpha_lo, alpha_hi; /* alpha domain, 0 < lo < hi (default 1e-3, 1) */
    double dh_lo, dh_hi;       /* dh domain, 0 < lo < hi (default 1e-3, 10) */
} mf_proxyfit_options;

void mf_proxyfit_options_default(mf_proxyfit_options *o);

/* Relative-error statistics of one approximation against the exact alpha'. */
typedef struct mf_proxyfit_error {
    double max_rel;           /* max |approx/exact - 1| over the check grid */
    double mean_rel;          /* mean of the same over the check grid */
    double worst_alpha, worst_dh;
    double max_rel_all;       /* max over a dense sweep of x in [0, 1] (all alpha > 0, dh >= 0) */
} mf_proxyfit_error;

typedef struct mf_proxyfit_result {
    double coef[MF_PROXY_NCOEF]; /* c, q */
    mf_proxyfit_error fit;       /* the fitted form */
    mf_proxyfit_error sqrt_approx; /* sqrt(alpha^2 + dh^2) */
    double table_fit_max_rel;    /* max relative error of the fit on the table's own points */
    long check_points;           /* points of the check grid */
    mf_solver_summary solver;
} mf_proxyfit_result;

/* Error statistics of the form with coefficients coef (and of sqrt(alpha^2 + dh^2) if sq is
 * non-NULL) over the check grid of o (see above). */
void mf_proxyfit_measure(const mf_proxyfit_options *o, const double coef[MF_PROXY_NCOEF], mf_proxyfit_error *fit,
                         mf_proxyfit_error *sq, long *points);

/*
 * Tabulate and fit.
 *   o      NULL for the defaults.
 *   table  NULL, or out: the table described above (owned by the caller: mf_table_free); zeroed
 *          on failure.
 * Returns MF_OK; MF_ERR_DOMAIN (bad options); MF_ERR_ALLOC; MF_ERR_NO_CONVERGENCE (the solver
 * stopped early: result->solver says why, result holds the last point); MF_ERR_INTERNAL.
 */
mf_status mf_proxyfit_run(const mf_proxyfit_options *o, mf_proxyfit_result *result, mf_table *table) MF_WARN_UNUSED;

/* Write the table and the coefficient files into the existing directory dir (names above).
 * tool: the producing command and version for the provenance fields (e.g. "mfkit fit ggx-proxy
 * 0.1.0"), may be NULL.  Returns MF_OK or MF_ERR_IO / MF_ERR_DOMAIN / MF_ERR_ALLOC with
 * "path: reason" in msg. */
mf_status mf_proxyfit_write(const char *dir, const mf_proxyfit_options *o, const mf_proxyfit_result *r,
                            const mf_table *table, const char *tool, char *msg, size_t msg_size) MF_WARN_UNUSED;

#ifdef __cplusplus
}
#endif
#endif /* MF_PROXYFIT_H */
