/*
 * mf_walk.h -- true multiple scattering on the Smith microsurface: the random walk of Heitz, Hanika,
 * d'Eon and Dachsbacher 2016 ("Multiple-scattering microfacet BSDFs with the Smith model", ACM TOG
 * 35(4)), for a conductor and a rough dielectric interface, GGX or Beckmann (isotropic or anisotropic).
 *
 * The model (their uncorrelated-height Smith microsurface read as a volume of microflakes):
 *  - a ray at height h in direction w is free up to height h' with probability given by the height
 *    CDF C1 and Smith's Lambda: upwards (w.z > 0) it leaves the surface with probability
 *    G1(w, h) = C1(h)^Lambda(w) [Heitz 2014, the masking at a given height], else it meets it at
 *    C1(h') = C1(h) / (1 - U)^(1 / Lambda(w)); downwards it always meets it, at
 *    C1(h') = C1(h) (1 - U)^(1 / (1 + Lambda(-w))) (Heitz et al. 2016, the free-path / height
 *    distribution; their code writes the exponent as 1 / Lambda(w) with Lambda(w) = -1 - Lambda(-w)
 *    for w.z < 0).  Only C1(h) enters, so the result does not depend on the height distribution;
 *    mfkit walks in u = C1(h) directly (u = 1 above the surface).
 *  - at a hit the micro-normal is drawn from the visible normals of -w, D_{-w}(m) proportional to
 *    max(0, -w.m) D(m), also for -w below the horizon (a ray going up that hits the surface sees
 *    back-facing slopes): GGX by the spherical-cap construction [Dupuy and Benyoub 2023, "Sampling
 *    visible GGX normals with spherical caps"], valid for every view direction; Beckmann by inverting
 *    the CDF of the slope along the view [Heitz and d'Eon 2014], and for views more than 45 degrees
 *    below the horizon (in the stretched space) by rejection from a Gamma(2) density (mf_walk.c);
 *  - a conductor reflects and multiplies its weight by F(-w.m); a dielectric reflects with
 *    probability F(-w.m) (exact Fresnel, total internal reflection included) and otherwise refracts
 *    and continues on the other side, where the microsurface is the same one seen upside down
 *    (h -> -h, so u -> 1 - u; w -> -w; eta -> 1 / eta) (Heitz et al. 2016, the dielectric walk).
 * A walk that leaves on the side it entered is reflected; on the other side, transmitted.
 *
 * Single scattering of this model (the first bounce, then leaving): reflection carries the
 * height-correlated G2 = 1 / (1 + Lambda_o + Lambda_i), the same as mfkit's joint G2; transmission
 * carries G2 = B(1 + Lambda_o, 1 + Lambda_t), the Beta function [Heitz 2014, height-correlated
 * masking and shadowing for transmission], NOT the 1 / (1 + Lambda_o + Lambda_t) of pbrt-v4, Cycles
 * and mf_albedo_dielectric (docs/math.md, "The random walk against the compensation").
 *
 * Pure C11 + libm.
 */
#ifndef MF_WALK_H
#define MF_WALK_H

#include "mfkit/mf_fresnel.h"
#include "mfkit/mf_ndf.h"
#include "mfkit/mf_rng.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MF_WALK_MAX_CHANNELS 8

typedef struct mf_walk_path {
    int bounces; /* scattering events (>= 1 for a walk that ends) */
    int side;    /* +1 left on the view's side (reflected), -1 on the other side (transmitted), 0 stopped
                    at max_bounces */
    mf_vec3 w;   /* the exit direction in the view's frame (z up on the view's side) */
} mf_walk_path;

/* Visible normals of the direction v (any unit v with |v.z| < 1 or v.z = 1; v.z = -1 has no
 * visible normal): m with density max(0, v.m) D(m) / A(v), A(v) = integral max(0, v.m) D(m) dm
 * (= v.z (1 + Lambda(v)) for v.z > 0, -v.z Lambda(-v) for v.z < 0).  GGX [Dupuy and Benyoub 2023: in
 * the space stretched to alpha = 1, m = normalize(v + c) with c uniform on the spherical cap
 * c.z >= -v.z]; Beckmann [Heitz and d'Eon 2014: the slope along the view by inverting its CDF, the
 * other Gaussian], only where the stretched view is at most 45 degrees below the horizon (NaNs
 * beyond: use mf_walk_sample_vndf_rng).  u in [0, 1)^2.  NaNs for invalid arguments. */
mf_vec3 mf_walk_sample_vndf(mf_ndf ndf, mf_vec3 v, const double u[2]);
/* The same for every v, drawing from rng: two numbers, then (Beckmann, views beyond 45 degrees below)
 * three per rejection trial.  GGX: the same normal as mf_walk_sample_vndf with the two numbers. */
mf_vec3 mf_walk_sample_vndf_rng(mf_ndf ndf, mf_vec3 v, mf_pcg32 *rng);

/* One walk on a conductor: ray -wo (wo.z > 0, unit) from above the surface; weight[c] receives the
 * product over the bounces of mf_fresnel_eval(f[c], -w.m), c < nf (nf <= MF_WALK_MAX_CHANNELS;
 * F = 1 for MF_FRESNEL_NONE).  The path does not depend on f.  GGX or Beckmann (MF_ERR_DOMAIN otherwise);
 * max_bounces >= 1. */
mf_status mf_walk_conductor(mf_ndf ndf, mf_vec3 wo, const mf_fresnel *f, int nf, int max_bounces, mf_pcg32 *rng,
                            mf_walk_path *out, double *weight) MF_WARN_UNUSED;

/* One walk on a dielectric interface: ray -wo from the view's side, where the relative index is
 * eta = n_other / n_view (eta < 1: seen from the denser side).  Lossless: every walk that ends
 * leaves on one side. */
mf_status mf_walk_dielectric(mf_ndf ndf, double eta, mf_vec3 wo, int max_bounces, mf_pcg32 *rng,
                             mf_walk_path *out) MF_WARN_UNUSED;

/* The walk's single-scattering albedos at mu = wo.z, by quadrature over the visible normals of wo
 * (the spherical-cap map of mf_walk_sample_vndf; n x n panels of a 20-point Gauss-Legendre rule;
 * err = |Q(n) - Q(n / 2)|, n even >= 2):
 *   r1 = integral D_wo(m) F(wo.m) (1 + Lambda_o) / (1 + Lambda_o + Lambda_i) dm   (wi reflected, up)
 *   t1 = integral D_wo(m) (1 - F) (1 + Lambda_o) B(1 + Lambda_o, 1 + Lambda(-wt)) dm  (wt refracted, down)
 * eta as in mf_walk_dielectric; eta = 0 means a conductor with F = 1 (t1 = 0).  GGX or Beckmann,
 * isotropic or not (wo in the x-z plane). */
mf_status mf_walk_single(mf_ndf ndf, double mu, double eta, int n, mf_result *r1, mf_result *t1) MF_WARN_UNUSED;


/* The walk's split of its multiple scattering on one side, cosine-averaged over the view: `walks`
 * walks from views drawn with density 2 mu (mu = sqrt(1 - U)) on the side where the relative index is
 * eta, each with at most max_bounces bounces, from the generator stream (seed, stream) (so the result
 * depends only on those, not on threads or order).  Counts: single / single_trans the walks that leave
 * after one bounce (all / transmitted), ms / ms_trans those with two or more, stopped those cut at
 * max_bounces.  t = ms_trans / ms, the transmitted fraction of the multiple scattering, with its
 * binomial standard error t_se = sqrt(p (1 - p) / ms) at p = (ms_trans + 1/2) / (ms + 1) (never 0 for
 * ms > 0: a side that transmits all of its ms walks still carries an uncertainty); e1 = single / walks
 * the walk's own single-scattering albedo (cosine average).  ms = 0: t and t_se NaN. */
typedef struct mf_walk_split {
    long walks, single, single_trans, ms, ms_trans, stopped;
    double t, t_se, e1;
} mf_walk_split;

mf_status mf_walk_dielectric_split(mf_ndf ndf, double eta, long walks, int max_bounces, uint64_t seed, uint64_t stream,
                                   mf_walk_split *out) MF_WARN_UNUSED;

#ifdef __cplusplus
}
#endif

#endif /* MF_WALK_H */
