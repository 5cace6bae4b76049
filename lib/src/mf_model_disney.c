/*
 * mf_model_disney.c -- the Disney diffuse BRDF [Burley 2012, "Physically-Based Shading at Disney",
 * SIGGRAPH course notes, Sec. 5.3] (mf_model.h, name "disney"):
 *
 *   f = (1/pi) (1 + (F_D90 - 1)(1 - wi.z)^5) (1 + (F_D90 - 1)(1 - wo.z)^5),
 *   F_D90 = 0.5 + 2 R cos^2(theta_d),   cos theta_d = wi.wh,  wh = normalize(wo + wi),
 *
 * base colour 1, no Fresnel of the specular layer.  R is Burley's (perceptual) roughness, whose
 * square is the specular alpha [Burley 2012, Sec. 5.4]; so the model's alpha argument maps to
 * R = sqrt(alpha), and the table's roughness axis r (alpha = r^2) is R itself.
 * No sampler (cosine-hemisphere sampling: f is within a factor ~2.5 of Lambert).
 */
#include "mfkit/mf_model.h"

#include <stddef.h>

static double pow5(double x)
{
    double x2 = x * x;
    return x2 * x2 * x;
}

static double disney_eval_cos(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, mf_vec3 wi)
{
    (void)m;
    double alpha, value;
    if (!mf_model_iso_domain(p, wo, wi, &alpha, &value))
        return value;
    double rough = sqrt(alpha);
    /* cos^2 theta_d = (wi.wh)^2 = (1 + wo.wi) / 2 (half-angle identity, no normalisation needed) */
    double cos_d_sq = 0.5 * (1.0 + mf_vec3_dot(wo, wi));
    double fd90 = 0.5 + 2.0 * rough * cos_d_sq;
    double fl = 1.0 + (fd90 - 1.0) * pow5(1.0 - wi.z), fv = 1.0 + (fd90 - 1.0) * pow5(1.0 - wo.z);
    return MF_INV_PI * fl * fv * wi.z;
}

const mf_brdf_model mf_model_disney = {"disney",
                                       "Disney diffuse, roughness sqrt(alpha), not energy conserving "
                                       "[Burley 2012, Sec. 5.3]",
                                       MF_MODEL_RECIPROCAL, disney_eval_cos, NULL, NULL, NULL};
