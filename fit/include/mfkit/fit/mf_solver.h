/*
 * mf_solver.h -- bounded nonlinear least squares with C callbacks (a C bridge over Ceres 2.1).
 *
 * Minimises  cost(p) = 1/2 * sum_i r_i(p)^2  over the parameter vector p (n_params doubles)
 * subject to optional box bounds lower <= p <= upper.  The residual vector r and, when asked,
 * its Jacobian J = dr/dp come from a user callback: the Jacobian is analytic, never finite
 * differences.  The linear solver is dense QR and the trust region is Levenberg-Marquardt or
 * dogleg, so the solve is meant for small, dense problems (a handful to a few hundred
 * parameters), such as fitting a BRDF model to a table.
 *
 * Units: the solver adds none.  Parameters and bounds are in the caller's parameter units,
 * residuals in the caller's residual units, and costs in residual units squared (with Ceres's
 * factor 1/2).  The function and parameter tolerances are relative (dimensionless).
 *
 * Every function here is plain C; the C++ implementation catches every exception at the
 * boundary.  The solver prints nothing on stdout or stderr: Ceres logs failures through glog
 * at ERROR level regardless of its own options, so while a solve runs glog's minloglevel is
 * raised to FATAL (and restored afterwards; this affects other glog users in the process).
 * A solve is bitwise deterministic for a given input, callback, options and machine (same
 * binary, same CPU).
 *
 * Thread safety: independent calls may run concurrently if the callbacks allow it.  With
 * num_threads > 1 the callback may still be called from a thread other than the caller's.
 */
#ifndef MF_SOLVER_H
#define MF_SOLVER_H

#include <mfkit/mf_core.h>

#ifdef __cplusplus
extern "C" {
#endif

/*
 * The residual callback.
 *   user       the pointer given to mf_solver_least_squares, passed through unchanged.
 *   params     n_params values to evaluate at (read-only; always within the bounds).
 *   residuals  out: n_residuals values r_i(params).  Always non-NULL.
 *   jacobian   out, may be NULL: when non-NULL, the row-major n_residuals x n_params matrix
 *              jacobian[i * n_params + j] = d r_i / d params[j].  When NULL, do not compute it.
 * Return 0 on success.  A non-zero return means "cannot evaluate here" (e.g. a parameter
 * leaves the model's domain): the solver rejects the step and shrinks the trust region.  If
 * the evaluation fails at the starting point the solve stops with MF_ERR_NO_CONVERGENCE.
 * Non-finite residuals or Jacobian entries are treated as a failed evaluation too.
 */
typedef int (*mf_solver_residual_fn)(void *user, const double *params, double *residuals, double *jacobian);

/* Trust region strategies (mf_solver_options.trust_region). */
enum {
    MF_SOLVER_LEVENBERG_MARQUARDT = 0,
    MF_SOLVER_DOGLEG = 1
};

typedef struct mf_solver_options {
    int max_iterations;        /* maximum number of trust region steps (accepted or rejected) of one
                                * Ceres solve (a bounded problem may take several, see below); >= 0 */
    double function_tolerance; /* stop when |delta cost| / cost < this; >= 0, dimensionless */
    double gradient_tolerance; /* stop when max_j |projected gradient_j| < this (in cost / parameter units); >= 0 */
    double parameter_tolerance;/* stop when |delta p| < this * (|p| + this); >= 0, dimensionless */
    int num_threads;           /* threads for Jacobian evaluation and linear algebra; >= 1 */
    int trust_region;          /* MF_SOLVER_LEVENBERG_MARQUARDT or MF_SOLVER_DOGLEG */
} mf_solver_options;

/* Defaults: max_iterations 100, all three tolerances 1e-12, num_threads 1, Levenberg-Marquardt.
 * A NULL o is ignored. */
void mf_solver_options_default(mf_solver_options *o);

/* Why the solver stopped (mf_solver_summary.termination). */
enum {
    MF_SOLVER_NOT_RUN = -1,       /* invalid arguments or an internal error: the solver did not run */
    MF_SOLVER_CONVERGENCE = 0,    /* one of the three tolerances was met */
    MF_SOLVER_NO_CONVERGENCE = 1, /* max_iterations reached before any tolerance was met */
    MF_SOLVER_FAILURE = 2,        /* the solver failed: the callback failed at the start point or on
                                   * too many consecutive steps, or the linear solver failed */
    MF_SOLVER_USER_SUCCESS = 3,   /* reserved (Ceres USER_SUCCESS); not produced by this API today */
    MF_SOLVER_USER_FAILURE = 4    /* reserved (Ceres USER_FAILURE); not produced by this API today */
};

typedef struct mf_solver_summary {
    int iterations;      /* trust region steps taken (accepted + rejected, over all bound
                          * re-solves); 0 if not run or if every parameter is fixed */
    double initial_cost; /* 1/2 sum r^2 at the start point (NaN if not run or not evaluable) */
    double final_cost;   /* 1/2 sum r^2 at the returned parameters (NaN if not run) */
    int converged;       /* 1 if termination is MF_SOLVER_CONVERGENCE (or USER_SUCCESS), else 0 */
    int termination;     /* one of the MF_SOLVER_NOT_RUN ... MF_SOLVER_USER_FAILURE values */
    char message[256];   /* Ceres's one-line reason, or ours for invalid arguments; NUL-terminated,
                          * truncated to fit */
} mf_solver_summary;

/*
 * Solve  min_p 1/2 sum_i r_i(p)^2  subject to lower <= p <= upper.
 *   n_params     number of parameters, >= 1.
 *   n_residuals  number of residuals, >= 1 (n_params * n_residuals must fit in an int).
 *   fn, user     the residual callback and its pass-through pointer (user may be NULL).
 *   params       in: the start point (finite, within the bounds); out: the solution.
 *   lower, upper NULL, or n_params bounds each.  -INFINITY / +INFINITY mean unbounded on that
 *                side; lower[j] == upper[j] holds params[j] fixed; NaN bounds and
 *                lower[j] > upper[j] are invalid.  The start point must satisfy
 *                lower[j] <= params[j] <= upper[j] (it is not clamped).  Ceres enforces bounds by
 *                projecting steps onto the box, which tends to stop early (or crawl) once a
 *                parameter hits a bound; so after a bounded solve that converged or ran out of
 *                iterations, the parameters resting on a bound that the gradient pushes against
 *                are held fixed and the others re-solved, until that set is stable (at most
 *                n_params + 1 re-solves, each with its own max_iterations budget).
 *   opt          NULL for mf_solver_options_default().
 *   summary      NULL, or filled on every return (including errors: termination MF_SOLVER_NOT_RUN).
 * Returns
 *   MF_OK                  converged; params holds the solution.
 *   MF_ERR_DOMAIN          an invalid argument (see above, or an option out of range); params untouched.
 *   MF_ERR_NO_CONVERGENCE  the solver stopped without meeting a tolerance; summary says why.  After
 *                          MF_SOLVER_NO_CONVERGENCE (max_iterations reached) params holds the last
 *                          accepted point (the best found so far); after MF_SOLVER_FAILURE (e.g. the
 *                          callback failing at the start point) params is left at the start point.
 *   MF_ERR_ALLOC           memory allocation failed; params untouched.
 *   MF_ERR_INTERNAL        an unexpected exception inside Ceres; params untouched.
 */
mf_status mf_solver_least_squares(int n_params, int n_residuals, mf_solver_residual_fn fn, void *user,
                                  double *params, const double *lower, const double *upper,
                                  const mf_solver_options *opt, mf_solver_summary *summary) MF_WARN_UNUSED;

#ifdef __cplusplus
}
#endif
#endif /* MF_SOLVER_H */
