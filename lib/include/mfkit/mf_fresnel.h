/*
 * mf_fresnel.h -- Fresnel reflectance of a smooth interface, unpolarised light.
 *
 * cos_theta is the cosine between the incident direction and the (micro-)normal, in [-1, 1].
 * eta is the relative index n_transmitted / n_incident for light arriving from the side the
 * normal points to (cos_theta > 0); for cos_theta < 0 the dielectric formula swaps the sides
 * (eta -> 1/eta, cos_theta -> -cos_theta), so it is symmetric in the direction of travel.
 * |cos_theta| up to 1 + 1e-9 (rounding of a dot product of unit vectors) is clamped to 1.
 * Values outside the domain (NaN, |cos_theta| > 1 + 1e-9, eta <= 0, k < 0, f0 outside [0, 1]) give NaN.
 *
 * References
 *  [Schlick 1994]  An Inexpensive BRDF Model for Physically-based Rendering, CGF 13(3), Eq. 15.
 *  [Born & Wolf]   Principles of Optics, Sec. 1.5.2 (dielectric) and 14.2 (absorbing media).
 *  [pbrt-v3]       Pharr, Jakob, Humphreys, 3rd ed., Sec. 8.2.1 (FrConductor in real arithmetic).
 */
#ifndef MF_FRESNEL_H
#define MF_FRESNEL_H

#include "mfkit/mf_core.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum mf_fresnel_type {
    MF_FRESNEL_NONE = 0,       /* F = 1 */
    MF_FRESNEL_SCHLICK = 1,    /* uses f0 */
    MF_FRESNEL_DIELECTRIC = 2, /* uses eta */
    MF_FRESNEL_CONDUCTOR = 3   /* uses eta and k (complex index eta + i k) */
} mf_fresnel_type;

typedef struct mf_fresnel {
    mf_fresnel_type type;
    double f0;   /* reflectance at normal incidence, Schlick only */
    double eta;  /* real part of the relative index */
    double k;    /* extinction coefficient, conductor only */
} mf_fresnel;

/* F0 + (1 - F0)(1 - cos)^5 [Schlick 1994, Eq. 15]; |cos_theta| is used. */
double mf_fresnel_schlick(double f0, double cos_theta);
/* Exact unpolarised dielectric reflectance; 1 under total internal reflection. */
double mf_fresnel_dielectric(double eta, double cos_theta);
/* Exact unpolarised reflectance of a conductor of complex index eta + i k (cos_theta >= 0;
 * |cos_theta| is used).  With k = 0 and eta >= 1 it equals the dielectric formula. */
double mf_fresnel_conductor(double eta, double k, double cos_theta);
/* Normal-incidence reflectance ((eta - 1) / (eta + 1))^2 of a dielectric. */
double mf_fresnel_f0_from_eta(double eta);
/* Evaluates a descriptor; F = 1 for MF_FRESNEL_NONE. */
double mf_fresnel_eval(mf_fresnel f, double cos_theta);

#ifdef __cplusplus
}
#endif
#endif /* MF_FRESNEL_H */
