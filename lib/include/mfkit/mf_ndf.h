/*
 * mf_ndf.h -- normal distribution functions (NDFs) and their slope densities.
 *
 * Measures.  D(wm) is a density per steradian of micro-normal, normalised so that the
 * projected micro-area is one:  integral over the hemisphere of D(wm) wm.z dwm = 1.
 * P22(slope) is the density of micro-slopes per unit slope area; the two are related by
 * D(wm) = P22(slope(wm)) / wm.z^4  [Dupuy 2013, Eq. 10] (Jacobian 1/wm.z^3 times 1/wm.z).
 *
 * Slopes.  The slope of a micro-normal m is (-m.x/m.z, -m.y/m.z), the height gradient
 * [Dupuy 2013, Sec. 4.1] (docs/math.md, correction C-L6).  LEAN and Kaplanyan use +m.xy/m.z; for centred
 * (symmetric) distributions the sign does not matter, for non-centred ones it does.
 *
 * Roughness.  alpha_x, alpha_y are the GGX / Beckmann roughness parameters along x and y of
 * the shading frame.  Beckmann: alpha^2 = 2 sigma^2, sigma^2 the variance of one slope
 * component [Dupuy 2013; Kaplanyan 2016, Eq. 14; docs/math.md, "Checked and found correct"].
 * The documented domain is alpha in [1e-4, 1e3] (finite and > 0; values below 1e-4 still
 * evaluate but are outside what the tests cover).  A non-positive or NaN alpha gives NaN.
 *
 * References
 *  [Walter 2007]  Walter, Marschner, Li, Torrance. Microfacet Models for Refraction through
 *                 Rough Surfaces. EGSR 2007 (GGX, Eq. 33; Beckmann, Eq. 25).
 *  [Heitz 2014]   Heitz. Understanding the Masking-Shadowing Function in Microfacet-Based
 *                 BRDFs. JCGT 3(2) (anisotropic forms by stretching of the
 *                 isotropic ones; slope-space densities).
 *  [Dupuy 2013]   Dupuy, Heitz, Iehl, Poulin, Neyret, Ostromoukhov. LEADR Mapping. ACM TOG
 *                 32(6), 2013, Eq. 8-11.
 *  [Olano 2010]   Olano, Baker. LEAN Mapping. I3D 2010, Sec. 3.1 (Blinn-Phong / Beckmann
 *                 equivalence).
 */
#ifndef MF_NDF_H
#define MF_NDF_H

#include "mfkit/mf_core.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum mf_ndf_type {
    MF_NDF_GGX = 0,      /* GGX / Trowbridge-Reitz */
    MF_NDF_BECKMANN = 1  /* centred Beckmann (Gaussian slopes) */
} mf_ndf_type;

/* A centred, possibly anisotropic NDF aligned with the shading frame. */
typedef struct mf_ndf {
    mf_ndf_type type;
    double alpha_x, alpha_y;
} mf_ndf;

/* Non-centred anisotropic Gaussian slope statistics [Dupuy 2013, Eq. 8-9]:
 * mean slope (mean_x, mean_y) and covariance [[var_x, cov_xy], [cov_xy, var_y]].
 * Valid when var_x >= 0, var_y >= 0 and var_x var_y - cov_xy^2 >= 0. */
typedef struct mf_gaussian_slopes {
    double mean_x, mean_y;
    double var_x, var_y, cov_xy;
} mf_gaussian_slopes;

static inline mf_ndf mf_ndf_make(mf_ndf_type type, double alpha_x, double alpha_y)
{
    mf_ndf n = {type, alpha_x, alpha_y};
    return n;
}

/* Name ("ggx", "beckmann") and parser; parse returns 0 on success, -1 for an unknown name. */
const char *mf_ndf_type_name(mf_ndf_type t);
int mf_ndf_type_parse(const char *name, mf_ndf_type *out);

/* 1 if the NDF's parameters are inside the domain (finite, alpha > 0). */
int mf_ndf_valid(mf_ndf ndf);

/* D(wm), per steradian of micro-normal; 0 for wm.z <= 0.  wm must be a unit vector.
 * GGX [Walter 2007, Eq. 33], anisotropic [Heitz 2014, stretched form]:
 *   D = 1 / (pi ax ay (x^2/ax^2 + y^2/ay^2 + z^2)^2).
 * Beckmann [Walter 2007, Eq. 25], anisotropic [Heitz 2014, stretched form]:
 *   D = exp(-(x^2/ax^2 + y^2/ay^2) / z^2) / (pi ax ay z^4). */
double mf_ndf_d(mf_ndf ndf, mf_vec3 wm);

/* P22(slope), per unit slope area [Heitz 2014, slope form]:
 * GGX      1 / (pi ax ay (1 + sx^2/ax^2 + sy^2/ay^2)^2)
 * Beckmann exp(-(sx^2/ax^2 + sy^2/ay^2)) / (pi ax ay). */
double mf_ndf_p22(mf_ndf ndf, double slope_x, double slope_y);

/* Slope of a micro-normal, (-m.x/m.z, -m.y/m.z) [Dupuy 2013, Sec. 4.1]; NaN for m.z <= 0. */
void mf_slope_from_normal(mf_vec3 wm, double slope[2]);
/* Unit micro-normal of a slope: (-sx, -sy, 1) / sqrt(1 + sx^2 + sy^2). */
mf_vec3 mf_normal_from_slope(double slope_x, double slope_y);

/* 1 if the statistics are inside the domain: finite, var >= 0, det >= 0. */
int mf_gaussian_valid(const mf_gaussian_slopes *g);
/* The centred Gaussian equal to a Beckmann NDF: var = alpha^2 / 2, zero mean and covariance. */
mf_gaussian_slopes mf_gaussian_from_beckmann(double alpha_x, double alpha_y);

/* P22 of the non-centred Gaussian [Dupuy 2013, Eq. 8]:
 * exp(-d^T S^-1 d / 2) / (2 pi sqrt|S|), d = slope - mean.  A singular covariance (|S| = 0)
 * is a distribution without a density: returns +INFINITY on its support line, 0 off it.
 * NaN outside the domain. */
double mf_gaussian_p22(const mf_gaussian_slopes *g, double slope_x, double slope_y);
/* D(wm) = P22(slope(wm)) / wm.z^4 [Dupuy 2013, Eq. 10]; 0 for wm.z <= 0. */
double mf_gaussian_d(const mf_gaussian_slopes *g, mf_vec3 wm);
/* Mesonormal (-E[x], -E[y], 1) / sqrt(1 + E[x]^2 + E[y]^2) [Dupuy 2013, Eq. 11]. */
mf_vec3 mf_gaussian_mesonormal(const mf_gaussian_slopes *g);

/* Blinn-Phong exponent s <-> Beckmann roughness.  LEAN models cos^s as a Gaussian of
 * slope variance 1/s per axis [Olano 2010, Sec. 3.1]; with alpha^2 = 2 sigma^2 this is
 * alpha = sqrt(2 / s) and s = 2 / alpha^2.  NaN for s <= 0 or alpha <= 0. */
double mf_ndf_beckmann_alpha_from_blinn_phong(double exponent);
double mf_ndf_blinn_phong_from_beckmann_alpha(double alpha);

#ifdef __cplusplus
}
#endif
#endif /* MF_NDF_H */
