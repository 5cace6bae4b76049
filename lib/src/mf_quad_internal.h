/* mf_quad_internal.h -- tables of mf_quad.c shared inside the core (not installed). */
#ifndef MF_QUAD_INTERNAL_H
#define MF_QUAD_INTERNAL_H

/* QUADPACK's 15-point Kronrod rule on [-1, 1] [Piessens et al. 1983, QK15]: the abscissae of its
 * positive half, descending (the last is 0), their weights, and the weights of the embedded
 * 7-point Gauss rule (nodes mf_quad_qk15_xgk[1], [3], [5], [7]). */
extern const double mf_quad_qk15_xgk[8];
extern const double mf_quad_qk15_wgk[8];
extern const double mf_quad_qk15_wg[4];

#endif
