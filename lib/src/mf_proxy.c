/*
 * mf_proxy.c -- the fitted GGX proxy roughness (see mf_proxy.h, docs/math.md).
 */
#include "mfkit/mf_proxy.h"
#include "mfkit/mf_core.h"

#include <math.h>

double mf_proxy_fit_r(const double coef[MF_PROXY_NCOEF], double x, double grad[MF_PROXY_NCOEF])
{
    double c = coef[0], q = coef[1];
    double den = 1.0 + q * x;
    double b = x * (1.0 - x) / den;
    if (grad) {
        grad[0] = b;
        grad[1] = -b * c * x / den;
    }
    return (1.0 - x) / 3.0 + x / MF_PI + b * c;
}

double mf_proxy_alpha_fit_coef(const double coef[MF_PROXY_NCOEF], double alpha, double dh)
{
    if (!(alpha > 0.0) || !(dh >= 0.0) || !isfinite(alpha) || !isfinite(dh) || !(coef[1] > -1.0) ||
        !isfinite(coef[0]) || !isfinite(coef[1]))
        return NAN;
    /* Scale by the larger input so that the squares neither overflow nor underflow. */
    double m = fmax(alpha, dh);
    double a = alpha / m, d = dh / m;
    double u = a * a, v = d * d, s = u + v;
    /* R = (1-x)/3 + x/pi + x(1-x) c/(1+qx) with x = v/s and 1 - x = u/s (no cancellation):
     * R = [(u/3 + v/pi)(s + q v) + c u v] / (s (s + q v)), one division. */
    double den = s + coef[1] * v;
    double r = ((u / 3.0 + v / MF_PI) * den + coef[0] * u * v) / (s * den);
    return m * sqrt(u + v * r);
}

double mf_proxy_alpha_fit(double alpha, double dh)
{
    static const double coef[MF_PROXY_NCOEF] = {MF_PROXY_FIT_C, MF_PROXY_FIT_Q};
    return mf_proxy_alpha_fit_coef(coef, alpha, dh);
}
