/*
 * mf_quad.h -- deterministic quadrature with error estimates.
 *
 *  - Gauss-Legendre nodes and weights of any order, by Newton iteration on the three-term
 *    recurrence (Golub & Welsch would also do; Newton is simpler and exact to a few ulp here).
 *  - Adaptive Gauss-Kronrod (7-point Gauss, 15-point Kronrod; the constants of QUADPACK's
 *    qk15) on finite and semi-infinite intervals, bisecting the interval with the largest
 *    error first.  The error estimate is QUADPACK's |K15 - G7| per interval, summed.
 *
 * Nothing here allocates on the heap or keeps state: safe from any number of threads.
 */
#ifndef MF_QUAD_H
#define MF_QUAD_H

#include "mfkit/mf_core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Largest interval count mf_quad_adaptive will use. */
#define MF_QUAD_MAX_INTERVALS 2048

typedef double (*mf_fn1)(double x, void *user);

/* Nodes and weights of the n-point Gauss-Legendre rule on [-1, 1], nodes ascending.
 * n in [1, 1024]; otherwise MF_ERR_DOMAIN. */
mf_status mf_quad_gauss_legendre(int n, double *nodes, double *weights) MF_WARN_UNUSED;

/* Integral of f over [a, b] (b may be +INFINITY: then x = a + t / (1 - t), t in [0, 1)).
 * Stops when the summed error estimate is <= max(abs_tol, rel_tol * |value|).
 * Returns MF_OK, MF_ERR_NO_CONVERGENCE (out still holds the best value and its error
 * estimate) when max_intervals (<= MF_QUAD_MAX_INTERVALS) is reached, or MF_ERR_DOMAIN
 * for a bad interval or a non-finite integrand value (out->val is then NaN). */
mf_status mf_quad_adaptive(mf_fn1 f, void *user, double a, double b, double abs_tol, double rel_tol,
                           int max_intervals, mf_result *out) MF_WARN_UNUSED;

#ifdef __cplusplus
}
#endif
#endif /* MF_QUAD_H */
