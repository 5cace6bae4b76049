/*
 * mf_model.h -- the BRDF models that LTC tables are fitted to (one small source file each).
 *
 * A model is an isotropic BRDF with one roughness parameter alpha (the table's roughness axis
 * gives alpha = max(r^2, MF_LTC_ALPHA_MIN)).  It evaluates the cosine-weighted BRDF
 * f(wo, wi) wi.z (per steradian of wi; 0 for wi.z <= 0), and optionally samples wi with a known
 * density (per steradian of wi) that covers the lobe well; models without a sampler get
 * cosine-hemisphere sampling.  Adding a BRDF is one file lib/src/mf_model_<name>.c defining an
 * `const mf_brdf_model mf_model_<name>` and one line in the registry (mf_model.c).
 *
 * Shipped models (names for `mfkit fit ltc --brdf NAME`):
 *   ggx          Walter microfacet, GGX, joint (height-correlated) masking-shadowing, F = 1
 *   beckmann     the same with Beckmann
 *   lambert      1/pi (the identity LTC: a test of the pipeline)
 *   oren-nayar   LEADR's rough diffuse microfacet BRDF (Dupuy 2013, Eq. 21) for centred isotropic
 *                Beckmann slopes (alpha^2 = 2 sigma^2), which the paper relates to Oren-Nayar
 *   disney       Disney / Burley 2012 diffuse; Burley's roughness R = sqrt(alpha) (his alpha = R^2, so
 *                the table axis r is R), no Fresnel of the specular
 *   charlie      the Charlie sheen lobe (Estevez & Kulla 2017) with its Lambda fit, alpha as roughness
 */
#ifndef MF_MODEL_H
#define MF_MODEL_H

#include <stddef.h>

#include "mfkit/mf_core.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mf_brdf_model mf_brdf_model;

struct mf_brdf_model {
    const char *name;        /* stable identifier, [a-z0-9-] */
    const char *description; /* one line, with its reference */
    /* f(wo, wi) wi.z for roughness alpha; unit directions in the shading frame; 0 for wo.z <= 0
     * or wi.z <= 0; NaN outside the domain. */
    double (*eval_cos)(const mf_brdf_model *m, double alpha, mf_vec3 wo, mf_vec3 wi);
    /* Optional (NULL: cosine hemisphere): wi from u in [0,1)^2 and its density per steradian
     * (*pdf may be 0 for a sample to discard). */
    mf_vec3 (*sample)(const mf_brdf_model *m, double alpha, mf_vec3 wo, const double u[2], double *pdf);
    /* Optional (NULL when sample is NULL): the density of `sample` at wi. */
    double (*pdf)(const mf_brdf_model *m, double alpha, mf_vec3 wo, mf_vec3 wi);
    /* Optional (may be NULL; only with sample): n samples at once.  For u = (u[2i], u[2i+1]):
     * wi[i] and pdf[i] as `sample` gives them, and w[i] = eval_cos(wi[i]) / pdf[i] where
     * pdf[i] > 0 and wi[i] is finite with wi[i].z > 0, else w[i] = 0 -- bit for bit the separate
     * calls, with the work that depends on wo alone done once (the fitter's hot loop). */
    void (*sample_weights)(const mf_brdf_model *m, double alpha, mf_vec3 wo, int n, const double *u, mf_vec3 *wi,
                           double *pdf, double *w);
};

/* The registry: NULL-terminated array of the shipped models, and lookup by name (NULL if unknown). */
extern const mf_brdf_model *const mf_brdf_models[];
const mf_brdf_model *mf_brdf_model_find(const char *name);

#ifdef __cplusplus
}
#endif
#endif /* MF_MODEL_H */
