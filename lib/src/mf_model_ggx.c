/*
 * mf_model_ggx.c -- GGX microfacet reflection for LTC fitting (mf_model.h, name "ggx"),
 * isotropic or anisotropic (alpha_x along the shading frame's x, alpha_y along y).
 *
 * f = D(wh) G2(wo, wi) / (4 wo.z wi.z), F = 1 [Walter 2007, Eq. 20 and 33], with the
 * height-correlated masking-shadowing G2 = 1 / (1 + Lambda(wo) + Lambda(wi)) and the anisotropic
 * GGX D and Lambda [Heitz 2014, height correlation; anisotropy by stretching] (the same forms as
 * mf_ndf_d and mf_smith_lambda_ggx; tests/test_models.c compares them).
 * Sampler: visible normals [Heitz 2018, Listing 1] (anisotropic by stretching), density of wm
 * G1(wo) max(0, wo.wm) D(wm) / wo.z per steradian of wm [Heitz 2018, the visible-normal density],
 * reflected about wm; the density of wi is that / (4 |wo.wm|) [Walter 2007, Eq. 14], per
 * steradian of wi, i.e. G1(wo) D(wm) / (4 wo.z).
 *
 * The fitter and the gate evaluate f cos and the density millions of times per table, so both
 * are written here in closed form (the generic mf_brdf_microfacet path builds an NDF and a
 * Fresnel record and normalises wh per call), for an unnormalised h:
 *   isotropic (alpha_x == alpha_y == a):
 *     D(h) = a^2 |h|^4 / (pi (a^2 h.z^2 + h.x^2 + h.y^2)^2),
 *     Lambda(w) = (sqrt(1 + t) - 1) / 2 = t / (2 (1 + sqrt(1 + t))),  t = a^2 (w.x^2 + w.y^2) / w.z^2;
 *   anisotropic:
 *     D(h) = |h|^4 / (pi ax ay (h.x^2 / ax^2 + h.y^2 / ay^2 + h.z^2)^2),
 *     Lambda(w) as above with t = ((ax w.x)^2 + (ay w.y)^2) / w.z^2,
 * which have no cancellation at alpha -> 0 or at grazing (no 1 - z^2, no sqrt(1 + t) - 1).  The
 * isotropic branch is kept apart so that alpha_x == alpha_y gives the bits of the isotropic model
 * (the default LTC table depends on them); the sampler needs no branch (stretching by
 * (ax, ay) is stretching by a).  tests/test_ltcfit.c (test_ggx_model) holds them against the
 * generic mf_brdf_microfacet path, tests/test_models.c against the model's claims.
 */
#include "mfkit/mf_brdf.h"
#include "mfkit/mf_model.h"
#include "mfkit/mf_sample.h"
#include "mf_model_internal.h"

typedef struct ggx_rough {
    double ax, ay, a2; /* a2 = ax^2, used by the isotropic branch */
    int iso;
} ggx_rough;

static inline ggx_rough ggx_rough_make(const mf_brdf_params *p)
{
    ggx_rough r = {p->alpha_x, p->alpha_y, p->alpha_x * p->alpha_x, p->alpha_x == p->alpha_y};
    return r;
}

static inline int ggx_rough_valid(const ggx_rough *r) { return r->ax > 0.0 && r->ay > 0.0 && isfinite(r->ax) && isfinite(r->ay); }

/* D of the direction of the unnormalised h (h.z > 0). */
static inline double ggx_d_unnorm(const ggx_rough *r, mf_vec3 h)
{
    if (r->iso) {
        double s2 = h.x * h.x + h.y * h.y, z2 = h.z * h.z;
        double den = r->a2 * z2 + s2, l2 = s2 + z2;
        return r->a2 * l2 * l2 / (MF_PI * den * den);
    }
    double x2 = h.x * h.x, y2 = h.y * h.y, z2 = h.z * h.z;
    double den = x2 / (r->ax * r->ax) + y2 / (r->ay * r->ay) + z2, l2 = x2 + y2 + z2;
    return l2 * l2 / (MF_PI * r->ax * r->ay * den * den);
}

/* Smith Lambda of GGX for a unit (or unnormalised) w with w.z > 0. */
static inline double ggx_lambda(const ggx_rough *r, mf_vec3 w)
{
    double t;
    if (r->iso) {
        t = r->a2 * (w.x * w.x + w.y * w.y) / (w.z * w.z);
    } else {
        double sx = r->ax * w.x, sy = r->ay * w.y;
        t = (sx * sx + sy * sy) / (w.z * w.z);
    }
    return 0.5 * t / (1.0 + sqrt(1.0 + t));
}

static double ggx_eval_cos(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, mf_vec3 wi)
{
    (void)m;
    ggx_rough r = ggx_rough_make(p);
    if (!(wi.z > 0.0) || !(wo.z > 0.0) || !ggx_rough_valid(&r) || !mf_vec3_isfinite(wo) || !mf_vec3_isfinite(wi))
        return (isnan(wi.z) || isnan(wo.z) || !ggx_rough_valid(&r)) ? NAN : 0.0;
    mf_vec3 h = mf_vec3_add(wo, wi);
    double g2 = 1.0 / (1.0 + ggx_lambda(&r, wo) + ggx_lambda(&r, wi));
    return ggx_d_unnorm(&r, h) * g2 / (4.0 * wo.z);
}

/* Density per steradian of wi = reflect(wo, wm): G1(wo) D(wm) / (4 wo.z) (0 if wo.wm <= 0). */
static double ggx_density(const ggx_rough *r, mf_vec3 wo, mf_vec3 wm)
{
    if (!(mf_vec3_dot(wo, wm) > 0.0) || !(wm.z > 0.0))
        return 0.0;
    return ggx_d_unnorm(r, wm) / ((1.0 + ggx_lambda(r, wo)) * 4.0 * wo.z);
}

static mf_vec3 ggx_sample(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, const double u[2], double *pdf)
{
    (void)m;
    ggx_rough r = ggx_rough_make(p);
    mf_vec3 wm = mf_sample_ggx_vndf(r.ax, r.ay, wo, u);
    mf_vec3 wi = mf_vec3_reflect(wo, wm);
    *pdf = wi.z > 0.0 && wo.z > 0.0 ? ggx_density(&r, wo, wm) : 0.0;
    return wi;
}

static double ggx_pdf(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, mf_vec3 wi)
{
    (void)m;
    if (!(wi.z > 0.0) || !(wo.z > 0.0))
        return 0.0;
    ggx_rough r = ggx_rough_make(p);
    return ggx_density(&r, wo, mf_vec3_add(wo, wi));
}

/* ggx_sample + ggx_eval_cos for n points, with the same operations in the same order (so the same
 * bits), the view-dependent parts hoisted: the visible-normal frame of mf_sample_ggx_vndf
 * [Heitz 2018, Listing 1] and Lambda(wo).  The disk point (p1, p2) = sqrt(u0) (cos, sin)(2 pi u1)
 * of point i comes from u, or (pp not NULL) is given in pp[2i], pp[2i+1] by a caller that reuses
 * one point set (mf_model_polar_points: the same expressions, so the same bits).  tests/test_models.c
 * compares them bit for bit. */
static void ggx_weights(const mf_brdf_params *p, mf_vec3 wo, int n, const double *u, const double *pp, mf_vec3 *wi,
                        double *pdf, double *w)
{
    ggx_rough r = ggx_rough_make(p);
    if (!ggx_rough_valid(&r) || !(wo.z > 0.0) || !mf_vec3_isfinite(wo)) {
        for (int i = 0; i < n; ++i) {
            wi[i] = mf_vec3_make(NAN, NAN, NAN);
            pdf[i] = w[i] = 0.0;
        }
        return;
    }
    const double ax = r.ax, ay = r.ay, lo = ggx_lambda(&r, wo);
    mf_vec3 vh = mf_vec3_normalize(mf_vec3_make(ax * wo.x, ay * wo.y, wo.z));
    double lensq = vh.x * vh.x + vh.y * vh.y;
    mf_vec3 t1 = lensq > 0.0 ? mf_vec3_scale(mf_vec3_make(-vh.y, vh.x, 0.0), 1.0 / sqrt(lensq))
                             : mf_vec3_make(1.0, 0.0, 0.0);
    mf_vec3 t2 = mf_vec3_cross(vh, t1);
    double s = 0.5 * (1.0 + vh.z);
    for (int i = 0; i < n; ++i) {
        double p1, p2;
        if (pp) {
            p1 = pp[2 * i];
            p2 = pp[2 * i + 1];
        } else {
            double rr = sqrt(u[2 * i]);
            double phi = 2.0 * MF_PI * u[2 * i + 1];
            p1 = rr * cos(phi);
            p2 = rr * sin(phi);
        }
        p2 = (1.0 - s) * sqrt(fmax(0.0, 1.0 - p1 * p1)) + s * p2;
        double pz = sqrt(fmax(0.0, 1.0 - p1 * p1 - p2 * p2));
        mf_vec3 nh = mf_vec3_add(mf_vec3_add(mf_vec3_scale(t1, p1), mf_vec3_scale(t2, p2)), mf_vec3_scale(vh, pz));
        mf_vec3 wm = mf_vec3_normalize(mf_vec3_make(ax * nh.x, ay * nh.y, fmax(0.0, nh.z)));
        mf_vec3 v = mf_vec3_reflect(wo, wm);
        double pd = 0.0;
        if (v.z > 0.0 && mf_vec3_dot(wo, wm) > 0.0 && wm.z > 0.0)
            pd = ggx_d_unnorm(&r, wm) / ((1.0 + lo) * 4.0 * wo.z);
        double wt = 0.0;
        if (pd > 0.0 && v.z > 0.0 && mf_vec3_isfinite(v)) {
            mf_vec3 h = mf_vec3_add(wo, v);
            double g2 = 1.0 / (1.0 + lo + ggx_lambda(&r, v));
            wt = ggx_d_unnorm(&r, h) * g2 / (4.0 * wo.z) / pd;
        }
        wi[i] = v;
        pdf[i] = pd;
        w[i] = wt;
    }
}

static void ggx_sample_weights(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, int n, const double *u,
                               mf_vec3 *wi, double *pdf, double *w)
{
    (void)m;
    ggx_weights(p, wo, n, u, NULL, wi, pdf, w);
}

/* mf_model_internal.h */
void mf_model_ggx_sample_weights_polar(const mf_brdf_params *p, mf_vec3 wo, int n, const double *pp, mf_vec3 *wi,
                                       double *pdf, double *w)
{
    ggx_weights(p, wo, n, NULL, pp, wi, pdf, w);
}

void mf_model_polar_points(int n, const double *u, double *pp)
{
    for (int i = 0; i < n; ++i) {
        double rr = sqrt(u[2 * i]);
        double phi = 2.0 * MF_PI * u[2 * i + 1];
        pp[2 * i] = rr * cos(phi);
        pp[2 * i + 1] = rr * sin(phi);
    }
}

const mf_brdf_model mf_model_ggx = {
    "ggx",
    "GGX microfacet, anisotropic, height-correlated Smith G2, F = 1, visible-normal sampling "
    "[Walter 2007, Eq. 20, 33; Heitz 2014; Heitz 2018]",
    MF_MODEL_ANISOTROPIC | MF_MODEL_ENERGY_CONSERVING | MF_MODEL_RECIPROCAL,
    ggx_eval_cos,
    ggx_sample,
    ggx_pdf,
    ggx_sample_weights};
