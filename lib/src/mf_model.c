/* mf_model.c -- the registry of the BRDF models that LTC tables are fitted to, and the
 * cosine-hemisphere fallback for models without a sampler (mf_model.h). */
#include "mfkit/mf_model.h"

#include "mfkit/mf_sample.h"
#include "mf_model_internal.h"

#include <stddef.h>
#include <string.h>

/* The registry, in the order `mfkit fit ltc --list` prints it: one X(name) per model, where
 * lib/src/mf_model_<name>.c defines `const mf_brdf_model mf_model_<name>`. */
#define MF_MODEL_LIST(X)                                                                                          \
    X(ggx)                                                                                                        \
    X(beckmann)                                                                                                   \
    X(lambert)                                                                                                    \
    X(leadr_diffuse)                                                                                              \
    X(oren_nayar)                                                                                                 \
    X(eon)                                                                                                        \
    X(disney)                                                                                                     \
    X(charlie)

#define MF_MODEL_DECLARE(id) extern const mf_brdf_model mf_model_##id;
#define MF_MODEL_ENTRY(id) &mf_model_##id,
MF_MODEL_LIST(MF_MODEL_DECLARE)
const mf_brdf_model *const mf_brdf_models[] = {MF_MODEL_LIST(MF_MODEL_ENTRY) NULL};

const mf_brdf_model *mf_brdf_model_find(const char *name)
{
    if (!name)
        return NULL;
    for (int i = 0; mf_brdf_models[i]; ++i)
        if (!strcmp(mf_brdf_models[i]->name, name))
            return mf_brdf_models[i];
    return NULL;
}

mf_vec3 mf_model_sample(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, const double u[2], double *pdf)
{
    if (m->sample)
        return m->sample(m, p, wo, u, pdf);
    mf_vec3 wi = mf_sample_cosine_hemisphere(u);
    *pdf = wo.z > 0.0 ? mf_pdf_cosine_hemisphere(wi) : 0.0; /* nothing to sample for a view below the horizon */
    return wi;
}

double mf_model_pdf(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, mf_vec3 wi)
{
    if (m->sample)
        return m->pdf(m, p, wo, wi);
    return wo.z > 0.0 ? mf_pdf_cosine_hemisphere(wi) : 0.0;
}

void mf_model_sample_weights(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, int n, const double *u,
                             mf_vec3 *wi, double *pdf, double *w)
{
    if (m->sample && m->sample_weights) {
        m->sample_weights(m, p, wo, n, u, wi, pdf, w);
        return;
    }
    for (int i = 0; i < n; ++i) {
        wi[i] = mf_model_sample(m, p, wo, u + 2 * i, &pdf[i]);
        w[i] = pdf[i] > 0.0 && wi[i].z > 0.0 && mf_vec3_isfinite(wi[i]) ? m->eval_cos(m, p, wo, wi[i]) / pdf[i] : 0.0;
    }
}

void mf_model_sample_weights_polar(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, int n, const double *u,
                                   const double *pp, mf_vec3 *wi, double *pdf, double *w)
{
    if (m == &mf_model_ggx)
        mf_model_ggx_sample_weights_polar(p, wo, n, pp, wi, pdf, w);
    else
        mf_model_sample_weights(m, p, wo, n, u, wi, pdf, w);
}

mf_vec3 mf_model_sample_cosine_polar(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, const double u[2],
                                     double *pdf)
{
    (void)m;
    (void)p;
    mf_vec3 wi = mf_sample_cosine_hemisphere_polar(u);
    *pdf = wo.z > 0.0 && wi.z > 0.0 ? wi.z * MF_INV_PI : 0.0;
    return wi;
}

double mf_model_pdf_cosine(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, mf_vec3 wi)
{
    (void)m;
    (void)p;
    return wo.z > 0.0 && wi.z > 0.0 ? wi.z * MF_INV_PI : 0.0;
}

/* The break u_b of mf_model_sample_cosine_split: an edge of both albedo rules' panels in t
 * (u0 = 1 - (1 - t)^3 at t = 1/4, 1/2, 3/4), the one nearest the kink s_o^2 = sin^2 theta_o; 0 (no
 * split) for views within 8 deg of the normal, where the kink is weak (s is proportional to
 * sin theta_o) and the split would weigh the hemisphere unevenly. */
static double split_break(double so2)
{
    if (so2 < 0.02)
        return 0.0;
    return so2 <= 0.75 ? 37.0 / 64.0 : (so2 <= 0.95 ? 7.0 / 8.0 : 63.0 / 64.0);
}

mf_vec3 mf_model_sample_cosine_split(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, const double u[2],
                                     double *pdf)
{
    if (!(wo.z > 0.0) || !mf_vec3_isfinite(wo)) {
        *pdf = 0.0;
        return mf_vec3_make(0.0, 0.0, 1.0);
    }
    double so2 = wo.x * wo.x + wo.y * wo.y, ub = split_break(so2);
    if (ub == 0.0)
        return mf_model_sample_cosine_polar(m, p, wo, u, pdf);
    double theta_o = atan2(sqrt(so2), wo.z), theta;
    if (u[0] < ub)
        theta = theta_o * (u[0] / ub);
    else
        theta = theta_o + (0.5 * MF_PI - theta_o) * ((u[0] - ub) / (1.0 - ub));
    double r = sin(theta), z = cos(theta), phi = 2.0 * MF_PI * u[1];
    mf_vec3 wi = mf_vec3_make(r * cos(phi), r * sin(phi), z);
    *pdf = mf_model_pdf_cosine_split(m, p, wo, wi);
    return wi;
}

double mf_model_pdf_cosine_split(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, mf_vec3 wi)
{
    if (!(wo.z > 0.0) || !(wi.z > 0.0))
        return 0.0;
    double so2 = wo.x * wo.x + wo.y * wo.y, ub = split_break(so2);
    if (ub == 0.0)
        return mf_model_pdf_cosine(m, p, wo, wi);
    /* theta uniform on each piece: density per steradian p(theta) / (2 pi sin theta) */
    double theta_o = atan2(sqrt(so2), wo.z), si = sqrt(wi.x * wi.x + wi.y * wi.y), theta_i = atan2(si, wi.z);
    if (!(si > 0.0))
        return 0.0; /* the pole: the density per steradian is singular there (measure 0: discarded) */
    double p_theta = theta_i < theta_o ? ub / theta_o : (1.0 - ub) / (0.5 * MF_PI - theta_o);
    return p_theta / (2.0 * MF_PI * si);
}
