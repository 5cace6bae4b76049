/* mf_fresnel.c -- Fresnel reflectance (see mf_fresnel.h). */
#include "mfkit/mf_fresnel.h"

/* |cos| may exceed 1 by a few ulp when it is the dot product of two normalised vectors;
 * such values are accepted (and clamped by the callers' use of 1 - c^2 >= 0).  Anything
 * beyond 1 + 1e-9 is a caller error. */
static int cos_valid(double c) { return c >= -1.0 - 1e-9 && c <= 1.0 + 1e-9; }
static double clamp_cos(double c) { return c > 1.0 ? 1.0 : (c < -1.0 ? -1.0 : c); }

double mf_fresnel_schlick(double f0, double cos_theta)
{
    if (!(f0 >= 0.0 && f0 <= 1.0) || !cos_valid(cos_theta))
        return NAN;
    double m = 1.0 - fabs(clamp_cos(cos_theta));
    double m2 = m * m;
    return f0 + (1.0 - f0) * (m2 * m2 * m); /* [Schlick 1994, Eq. 15] */
}

double mf_fresnel_dielectric(double eta, double cos_theta)
{
    if (!(eta > 0.0) || !isfinite(eta) || !cos_valid(cos_theta))
        return NAN;
    double ci = clamp_cos(cos_theta);
    if (ci < 0.0) { /* arriving from the other side */
        eta = 1.0 / eta;
        ci = -ci;
    }
    /* Snell: sin_t = sin_i / eta [Born & Wolf, Sec. 1.5.2] */
    double sin_t_sq = (1.0 - ci * ci) / (eta * eta);
    if (sin_t_sq >= 1.0)
        return 1.0; /* total internal reflection */
    double ct = sqrt(1.0 - sin_t_sq);
    double r_par = (eta * ci - ct) / (eta * ci + ct);
    double r_perp = (ci - eta * ct) / (ci + eta * ct);
    return 0.5 * (r_par * r_par + r_perp * r_perp);
}

double mf_fresnel_conductor(double eta, double k, double cos_theta)
{
    if (!(eta > 0.0) || !isfinite(eta) || !(k >= 0.0) || !isfinite(k) || !cos_valid(cos_theta))
        return NAN;
    /* [pbrt-v3, Sec. 8.2.1] real-arithmetic form of the complex Fresnel equations
     * [Born & Wolf, Sec. 14.2]: a^2 + b^2 = sqrt((eta^2 - k^2 - sin^2)^2 + 4 eta^2 k^2). */
    double c = fabs(clamp_cos(cos_theta));
    double c2 = c * c, s2 = 1.0 - c2;
    double eta2 = eta * eta, k2 = k * k;
    double t0 = eta2 - k2 - s2;
    double a2pb2 = sqrt(t0 * t0 + 4.0 * eta2 * k2);
    double t1 = a2pb2 + c2;
    double a = sqrt(fmax(0.0, 0.5 * (a2pb2 + t0)));
    double t2 = 2.0 * c * a;
    double rs = (t1 - t2) / (t1 + t2);
    double t3 = c2 * a2pb2 + s2 * s2;
    double t4 = t2 * s2;
    double rp = rs * (t3 - t4) / (t3 + t4);
    return 0.5 * (rp + rs);
}

double mf_fresnel_f0_from_eta(double eta)
{
    if (!(eta > 0.0) || !isfinite(eta))
        return NAN;
    double r = (eta - 1.0) / (eta + 1.0);
    return r * r;
}

double mf_fresnel_eval(mf_fresnel f, double cos_theta)
{
    switch (f.type) {
    case MF_FRESNEL_NONE: return cos_valid(cos_theta) ? 1.0 : NAN;
    case MF_FRESNEL_SCHLICK: return mf_fresnel_schlick(f.f0, cos_theta);
    case MF_FRESNEL_DIELECTRIC: return mf_fresnel_dielectric(f.eta, cos_theta);
    case MF_FRESNEL_CONDUCTOR: return mf_fresnel_conductor(f.eta, f.k, cos_theta);
    }
    return NAN;
}
