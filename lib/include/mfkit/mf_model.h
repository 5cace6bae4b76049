/*
 * mf_model.h -- the registry of BRDF models that LTC tables are fitted to (one source file each).
 *
 * A model evaluates the cosine-weighted BRDF f(wo, wi) wi.z (per steradian of wi; 0 for wo.z <= 0
 * or wi.z <= 0) for the roughness in an mf_brdf_params record, and optionally samples wi with a
 * known density (per steradian of wi) that covers the lobe well; models without a sampler are
 * sampled from the cosine hemisphere (mf_model_sample and friends below do that fallback).
 * Directions are unit vectors in the shading frame (z the normal, x the tangent along which
 * alpha_x acts).
 *
 * Each model declares what it claims in `flags` (MF_MODEL_*): anisotropic roughness, energy
 * conservation (directional albedo <= 1), reciprocity (f(wo, wi) = f(wi, wo)); "has its own
 * sampler" is `sample != NULL`.  tests/test_models.c loops over the registry and holds every model
 * to its claims (chi-square of the sampler against its pdf, batched against single evaluation,
 * zero below the horizon, reciprocity, albedo <= 1, finite values on the domain grid).
 *
 * Adding a model: one file lib/src/mf_model_<name>.c defining `const mf_brdf_model
 * mf_model_<name>` (name, description with its reference, flags, functions), one line
 * X(<name>) in MF_MODEL_LIST (lib/src/mf_model.c), and the file in lib/CMakeLists.txt.  The CLI's
 * --brdf list, `mfkit fit ltc --list` and its usage text come from the registry; docs/cli.md's
 * list is checked against `--list` by tests/test_cli.sh.
 *
 * Shipped models (names for `mfkit fit ltc --brdf NAME`; `mfkit fit ltc --list` prints them):
 *   ggx          Walter microfacet, GGX, height-correlated masking-shadowing, F = 1; anisotropic
 *   beckmann     the same with Beckmann; anisotropic
 *   lambert      1/pi (the identity LTC: a test of the pipeline)
 *   leadr-diffuse  LEADR's rough diffuse microfacet BRDF (Dupuy 2013, Eq. 21) for centred isotropic
 *                Beckmann slopes (alpha^2 = 2 sigma^2), by a quadrature with a measured error < 1e-8
 *   oren-nayar   Oren & Nayar 1994's qualitative model (Eq. 30), sigma = alpha / sqrt(2); NOT energy
 *                conserving (albedo up to 1.004 at grazing views, small sigma)
 *   eon          the energy-preserving Oren-Nayar of OpenPBR (Portsmouth et al. 2025), r = sqrt(alpha):
 *                albedo exactly 1
 *   disney       Disney / Burley 2012 diffuse; Burley's roughness R = sqrt(alpha) (his alpha = R^2, so
 *                the table axis r is R), no Fresnel of the specular; NOT energy conserving
 *   charlie      the Charlie sheen lobe (Estevez & Kulla 2017) with its Lambda fit, alpha as roughness;
 *                NOT energy conserving; samples its NDF truncated to micro-normals that reflect above
 *                the horizon
 */
#ifndef MF_MODEL_H
#define MF_MODEL_H

#include <stddef.h>

#include "mfkit/mf_core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The parameters of a model evaluation.  alpha_x, alpha_y: the roughness along the shading
 * frame's x and y axes (for the microfacet models the NDF's alpha_x, alpha_y [Heitz 2014,
 * Sec. 5.2]; each model's header comment says what its roughness means).  Isotropic models (no
 * MF_MODEL_ANISOTROPIC flag) read alpha_x only and ignore alpha_y.  An LTC table's roughness axis
 * gives alpha_x = alpha_y = max(r^2, MF_LTC_ALPHA_MIN).  New parameters are added at the end;
 * initialise records with mf_brdf_params_iso() or a designated initializer so that added members
 * are zero. */
typedef struct mf_brdf_params {
    double alpha_x, alpha_y;
} mf_brdf_params;

/* {alpha, alpha}: the isotropic record. */
static inline mf_brdf_params mf_brdf_params_iso(double alpha)
{
    mf_brdf_params p = {alpha, alpha};
    return p;
}

/* The domain rule of an isotropic model's eval_cos (used by its first lines): returns 1 to evaluate,
 * with *alpha = p->alpha_x; else 0 with *value the result, NaN for a NaN wo.z or wi.z or an alpha
 * that is not > 0, and 0 for wo or wi on or below the horizon. */
static inline int mf_model_iso_domain(const mf_brdf_params *p, mf_vec3 wo, mf_vec3 wi, double *alpha, double *value)
{
    *alpha = p->alpha_x; /* isotropic: alpha_y is not read */
    if (isnan(wo.z) || isnan(wi.z) || !(*alpha > 0.0)) {
        *value = NAN;
        return 0;
    }
    if (!(wo.z > 0.0) || !(wi.z > 0.0)) {
        *value = 0.0;
        return 0;
    }
    return 1;
}

/* Claims of a model (mf_brdf_model.flags), each checked by tests/test_models.c. */
enum {
    MF_MODEL_ANISOTROPIC = 1 << 0,       /* reads alpha_y too (else alpha_x only) */
    MF_MODEL_ENERGY_CONSERVING = 1 << 1, /* directional albedo <= 1 for every wo and parameter */
    MF_MODEL_RECIPROCAL = 1 << 2         /* f(wo, wi) = f(wi, wo) (Helmholtz reciprocity) */
};

typedef struct mf_brdf_model mf_brdf_model;

struct mf_brdf_model {
    const char *name;        /* stable identifier, [a-z0-9-] */
    const char *description; /* one line, with its reference */
    unsigned flags;          /* MF_MODEL_* */
    /* f(wo, wi) wi.z; 0 for wo.z <= 0 or wi.z <= 0; NaN for NaN directions or a roughness that is
     * not > 0. */
    double (*eval_cos)(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, mf_vec3 wi);
    /* Optional (NULL: cosine hemisphere): wi from u in [0,1)^2 and its density per steradian
     * (*pdf is 0 for a sample to discard, e.g. below the horizon). */
    mf_vec3 (*sample)(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, const double u[2], double *pdf);
    /* Present iff sample is: the density of `sample` at wi (0 for wo.z <= 0 or wi.z <= 0). */
    double (*pdf)(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, mf_vec3 wi);
    /* Optional (may be NULL; only with sample): n samples at once.  For u = (u[2i], u[2i+1]):
     * wi[i] and pdf[i] as `sample` gives them, and w[i] = eval_cos(wi[i]) / pdf[i] where
     * pdf[i] > 0 and wi[i] is finite with wi[i].z > 0, else w[i] = 0 -- bit for bit the separate
     * calls, with the work that depends on wo alone done once (the fitter's hot loop). */
    void (*sample_weights)(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, int n, const double *u,
                           mf_vec3 *wi, double *pdf, double *w);
};

/* The registry: NULL-terminated array of the shipped models, in the order `--list` prints them,
 * and lookup by name (NULL if unknown). */
extern const mf_brdf_model *const mf_brdf_models[];
const mf_brdf_model *mf_brdf_model_find(const char *name);

/* ---- using a model: the cosine-hemisphere fallback for models without a sampler ---------------- */

/* The model's sampler, or the cosine hemisphere (pdf wi.z / pi; 0 for wo.z <= 0, as the models'
 * own samplers). */
mf_vec3 mf_model_sample(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, const double u[2], double *pdf);
/* The density of mf_model_sample at wi. */
double mf_model_pdf(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, mf_vec3 wi);
/* n samples of mf_model_sample with their weights f cos / pdf (0 unless pdf > 0 and wi is finite
 * with wi.z > 0): the model's sample_weights when it has one, which gives the same bits. */
void mf_model_sample_weights(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, int n, const double *u,
                             mf_vec3 *wi, double *pdf, double *w);

/* mf_model_sample_weights for a point set reused across calls (the LTC fitter's Sobol prefix, the
 * albedo rule's rows): mf_model_polar_points maps n points u to the disk points pp[2i], pp[2i+1] =
 * sqrt(u0) (cos, sin)(2 pi u1) of GGX's visible-normal sampler [Heitz 2018, Listing 1] once, and
 * mf_model_sample_weights_polar, given both u and those pp, is bit for bit
 * mf_model_sample_weights(m, p, wo, n, u, ...): the "ggx" model reads pp (no square root, sine and
 * cosine per point), every other model reads u. */
void mf_model_polar_points(int n, const double *u, double *pp);
void mf_model_sample_weights_polar(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, int n, const double *u,
                                   const double *pp, mf_vec3 *wi, double *pdf, double *w);

/* The diffuse models' sampler (their `sample` and `pdf`): the cosine hemisphere by the polar map
 * (mf_sample_cosine_hemisphere_polar), density wi.z / pi (0 for wo.z <= 0 or wi.z <= 0).  Unlike
 * the fallback's concentric map, it is smooth in u and puts the horizon at u0 -> 1, where
 * mf_model_albedo grades its nodes: the grazing features of the rough diffuse models (QON's and
 * EON's s / max(wi.z, wo.z) at grazing views) converge there. */
mf_vec3 mf_model_sample_cosine_polar(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, const double u[2],
                                     double *pdf);
double mf_model_pdf_cosine(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, mf_vec3 wi);
/* The sampler of the models with a kink at theta_i = theta_o (QON's and EON's s / max(wi.z, wo.z)):
 * theta_i piecewise uniform in u0, [0, u_b) onto [0, theta_o) and [u_b, 1) onto [theta_o, pi/2),
 * phi = 2 pi u1, u_b an edge of mf_model_albedo's panels (37/64, 7/8 or 63/64, the one nearest
 * sin^2 theta_o), so that the kink falls on a panel edge and every trigonometric function of wi is
 * smooth in u; density per steradian p(theta) / (2 pi sin theta_i), p(theta) = u_b / theta_o below
 * the kink and (1 - u_b) / (pi/2 - theta_o) above it (0 at the pole, a null set).  Views within
 * 8 deg of the normal use mf_model_sample_cosine_polar. */
mf_vec3 mf_model_sample_cosine_split(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, const double u[2],
                                     double *pdf);
double mf_model_pdf_cosine_split(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, mf_vec3 wi);

/* ---- directional albedo ------------------------------------------------------------------------ */

/* The default number of points per axis of mf_model_albedo: the rule of the LTC fitter's
 * magnitude and of the LTC gate's albedo check. */
#define MF_MODEL_ALBEDO_N 64

/* Directional albedo rho(wo) = integral over wi.z > 0 of f(wo, wi) wi.z dwi of the model at wo
 * (wo.z > 0), by a product rule over the unit square of mf_model_sample: n x n points, n / 8
 * composite 8-point Gauss-Legendre panels per axis, the first coordinate graded towards 1 by
 * u0 = 1 - (1 - t)^3 (Jacobian 3 (1 - t)^2; u0 -> 1 is where the micro-normal maps reach grazing
 * normals and the integrand drops to 0 as wi crosses the horizon), integrand f cos / pdf.
 * out->err = |Q(n) - Q(n/2)|.  n a multiple of 16 in [16, 1024] (MF_MODEL_ALBEDO_N by default).
 * Measured against converged references in lib/src/mf_model_albedo.c.
 * MF_ERR_DOMAIN for a bad argument or a non-finite integrand. */
mf_status mf_model_albedo(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, int n,
                          mf_result *out) MF_WARN_UNUSED;
/* The same, and (fresnel may be NULL) the Schlick moment: the integral of f(wo, wi) wi.z
 * (1 - wo.wh)^5 dwi, wh = normalize(wo + wi), from the same points with its own |Q(n) - Q(n/2)|
 * error.  With Schlick's F = F0 + (1 - F0)(1 - wo.wh)^5 [Schlick 1994, Eq. 15] the albedo with
 * Fresnel is F0 albedo + (1 - F0) moment: the LTC table's magnitude and Fresnel fields. */
mf_status mf_model_albedo_fresnel(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, int n,
                                  mf_result *albedo, mf_result *fresnel) MF_WARN_UNUSED;

#ifdef __cplusplus
}
#endif
#endif /* MF_MODEL_H */
