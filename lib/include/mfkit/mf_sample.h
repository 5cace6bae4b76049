/*
 * mf_sample.h -- warps from [0,1)^2 to directions, each with its pdf and the pdf's measure.
 *
 * All samplers are deterministic functions of u = (u0, u1) in [0, 1)^2, so the same maps
 * serve Monte Carlo (u from PCG32) and quadrature (u from Gauss-Legendre nodes or Sobol).
 *
 *  sampler                       density of the result              measure
 *  uniform_sphere                1 / (4 pi)                         solid angle
 *  uniform_hemisphere            1 / (2 pi)  (z >= 0)               solid angle
 *  cosine_hemisphere(_polar)     cos(theta) / pi                    solid angle
 *  ndf_normal (GGX, Beckmann)    D(wm) wm.z                         solid angle of micro-normal
 *  ggx_vndf                      G1(wo) max(0, wo.wm) D(wm) / wo.z  solid angle of micro-normal
 *
 * A micro-normal density p(wm) becomes a density of the reflected wi = reflect(wo, wm) by the
 * Jacobian 1 / (4 |wo.wm|) [Walter 2007, Eq. 14]: mf_pdf_reflected().
 *
 * References
 *  [Shirley & Chiu 1997] A Low Distortion Map Between Disk and Square, JGT 2(3) (concentric map).
 *  [Heitz 2018] Sampling the GGX Distribution of Visible Normals, JCGT 7(4), Listing 1.
 *  [Walter 2007] Eq. 28-29 (Beckmann) and 35-36 (GGX) sample D(wm) wm.z; here in slope form,
 *               with anisotropy by stretching the slopes.
 */
#ifndef MF_SAMPLE_H
#define MF_SAMPLE_H

#include "mfkit/mf_ndf.h"

#ifdef __cplusplus
extern "C" {
#endif

mf_vec3 mf_sample_uniform_sphere(const double u[2]);
double mf_pdf_uniform_sphere(void);
mf_vec3 mf_sample_uniform_hemisphere(const double u[2]);
double mf_pdf_uniform_hemisphere(mf_vec3 w); /* 0 for w.z < 0 */
/* Concentric disk [Shirley & Chiu 1997] lifted to the hemisphere (Malley's method). */
mf_vec3 mf_sample_cosine_hemisphere(const double u[2]);
double mf_pdf_cosine_hemisphere(mf_vec3 w); /* max(0, w.z) / pi */
/* The same density by the polar map sin^2 theta = u0, phi = 2 pi u1 (z = sqrt(1 - u0)): smooth in
 * u, with the horizon at u0 -> 1 (where mf_model_albedo grades its nodes), which the concentric
 * map spreads over the square's boundary.  The diffuse models' sampler. */
mf_vec3 mf_sample_cosine_hemisphere_polar(const double u[2]);

/* Micro-normal with density D(wm) wm.z; for Beckmann the slope radius is sqrt(-ln(1 - u0)),
 * for GGX sqrt(u0 / (1 - u0)), in the space stretched by 1/alpha.  NaN for an invalid NDF. */
mf_vec3 mf_sample_ndf_normal(mf_ndf ndf, const double u[2]);
double mf_pdf_ndf_normal(mf_ndf ndf, mf_vec3 wm);

/* GGX visible normals [Heitz 2018, Listing 1]: wm with density G1(wo) max(0, wo.wm) D(wm) / wo.z.
 * wo must be a unit vector with wo.z > 0; otherwise NaNs. */
mf_vec3 mf_sample_ggx_vndf(double alpha_x, double alpha_y, mf_vec3 wo, const double u[2]);
double mf_pdf_ggx_vndf(double alpha_x, double alpha_y, mf_vec3 wo, mf_vec3 wm);

/* Density of wi = reflect(wo, wm) given the density pdf_wm of wm: pdf_wm / (4 |wo.wm|). */
double mf_pdf_reflected(double pdf_wm, mf_vec3 wo, mf_vec3 wm);

#ifdef __cplusplus
}
#endif
#endif /* MF_SAMPLE_H */
