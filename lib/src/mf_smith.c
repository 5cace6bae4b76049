/* mf_smith.c -- Smith Lambda, G1, G2 (see mf_smith.h for the formulas and references). */
#include "mfkit/mf_smith.h"

double mf_smith_lambda_beckmann_nu(double nu)
{
    if (isnan(nu))
        return NAN;
    if (nu <= 0.0) /* at or below the (meso)surface: fully masked (docs/math.md, correction C-L3) */
        return INFINITY;
    if (nu < 2.0) /* [Dupuy 2013, after Eq. 15] directly; cancellation costs < 1 digit here */
        return exp(-nu * nu) / (2.0 * nu * MF_SQRT_PI) - 0.5 * erfc(nu);
    /* erfc(nu) = exp(-nu^2)/sqrt(pi) * 1/(nu + r), r = (1/2)/(nu + 1/(nu + (3/2)/(nu + ...)))
     * (Laplace's continued fraction).  Then Lambda = exp(-nu^2)/(2 sqrt(pi)) (1/nu - 1/(nu + r))
     * = exp(-nu^2)/(2 sqrt(pi)) * r / (nu (nu + r)): the difference is formed exactly.
     * 80 terms converge to < 1e-16 relative for nu >= 2 (checked against mpmath, tests/).  Fewer
     * suffice as nu grows (58 at nu = 2, 25 at 3.9, 13 at 7.6, 9 at 15, against 400 terms), so
     * K = min(80, 12 + 160 / nu) terms: over nu = 2..28 in steps of 1e-4 (250791 values; beyond,
     * exp(-nu^2) underflows) the result is bit for bit the 80-term one.  Beckmann LTC fits spent
     * 58 % of their time here. */
    int terms = nu < 160.0 / 68.0 ? 80 : 12 + (int)(160.0 / nu);
    double t = nu;
    for (int k = terms; k >= 2; --k)
        t = nu + 0.5 * k / t;
    double r = 0.5 / t;
    return exp(-nu * nu) * (0.5 * MF_INV_SQRT_PI) * r / (nu * (nu + r));
}

double mf_smith_lambda_beckmann_walter_nu(double nu)
{
    if (isnan(nu))
        return NAN;
    if (nu <= 0.0)
        return INFINITY;
    if (nu >= 1.6)
        return 0.0;
    /* [Walter 2007, Eq. 27] as 1/G1 - 1, printed in [Dupuy 2013, after Eq. 15]; clamped at 0
     * because the numerator is negative on (1.5497, 1.6) (correction C-L4). */
    double l = (1.0 - 1.259 * nu + 0.396 * nu * nu) / (3.535 * nu + 2.181 * nu * nu);
    return l > 0.0 ? l : 0.0;
}

/* sqrt(ax^2 x^2 + ay^2 y^2): the stretched sin(theta), computed with hypot against overflow. */
static double stretched_sin(double alpha_x, double alpha_y, mf_vec3 w)
{
    return hypot(alpha_x * w.x, alpha_y * w.y);
}

static int alphas_valid(double ax, double ay)
{
    return isfinite(ax) && isfinite(ay) && ax > 0.0 && ay > 0.0;
}

double mf_smith_lambda_ggx(double alpha_x, double alpha_y, mf_vec3 w)
{
    if (!alphas_valid(alpha_x, alpha_y) || !mf_vec3_isfinite(w))
        return NAN;
    if (w.z <= 0.0)
        return INFINITY;
    double r = stretched_sin(alpha_x, alpha_y, w) / w.z; /* alpha tan(theta), stretched */
    if (isinf(r))
        return INFINITY;
    double t = r * r;
    /* (-1 + sqrt(1 + t)) / 2 rewritten as t / (2 (1 + sqrt(1 + t))): no cancellation. */
    return t / (2.0 * (1.0 + sqrt(1.0 + t)));
}

/* Lambda of a centred Beckmann NDF through a Lambda(nu) form: nu = cot(theta) / alpha(phi)
 * = z / sqrt(ax^2 x^2 + ay^2 y^2), +inf at the pole (-> Lambda 0). */
static double beckmann_lambda_via(double alpha_x, double alpha_y, mf_vec3 w, double (*lambda_of_nu)(double))
{
    if (!alphas_valid(alpha_x, alpha_y) || !mf_vec3_isfinite(w))
        return NAN;
    if (w.z <= 0.0)
        return INFINITY;
    return lambda_of_nu(w.z / stretched_sin(alpha_x, alpha_y, w));
}

double mf_smith_lambda_beckmann(double alpha_x, double alpha_y, mf_vec3 w)
{
    return beckmann_lambda_via(alpha_x, alpha_y, w, mf_smith_lambda_beckmann_nu);
}

double mf_smith_lambda_beckmann_walter(double alpha_x, double alpha_y, mf_vec3 w)
{
    return beckmann_lambda_via(alpha_x, alpha_y, w, mf_smith_lambda_beckmann_walter_nu);
}

double mf_smith_lambda(mf_ndf ndf, mf_vec3 w)
{
    switch (ndf.type) {
    case MF_NDF_GGX: return mf_smith_lambda_ggx(ndf.alpha_x, ndf.alpha_y, w);
    case MF_NDF_BECKMANN: return mf_smith_lambda_beckmann(ndf.alpha_x, ndf.alpha_y, w);
    }
    return NAN;
}

double mf_smith_gaussian_nu(const mf_gaussian_slopes *g, mf_vec3 w)
{
    if (!mf_gaussian_valid(g) || !mf_vec3_isfinite(w))
        return NAN;
    /* [Dupuy 2013, Eq. 14-15]: multiply numerator and denominator of
     * (cot theta - mu(phi)) / (sigma(phi) sqrt 2) by sin(theta). */
    double num = w.z - w.x * g->mean_x - w.y * g->mean_y;
    double q = w.x * w.x * g->var_x + w.y * w.y * g->var_y + 2.0 * w.x * w.y * g->cov_xy;
    if (q < 0.0) /* only by rounding for a valid covariance */
        q = 0.0;
    double den = sqrt(2.0 * q);
    if (den == 0.0)
        return num > 0.0 ? INFINITY : -INFINITY;
    return num / den;
}

double mf_smith_lambda_gaussian(const mf_gaussian_slopes *g, mf_vec3 w)
{
    return mf_smith_lambda_beckmann_nu(mf_smith_gaussian_nu(g, w));
}

double mf_smith_lambda_gaussian_walter(const mf_gaussian_slopes *g, mf_vec3 w)
{
    return mf_smith_lambda_beckmann_walter_nu(mf_smith_gaussian_nu(g, w));
}

double mf_smith_g1(mf_ndf ndf, mf_vec3 w)
{
    return 1.0 / (1.0 + mf_smith_lambda(ndf, w));
}

double mf_smith_g2(mf_ndf ndf, mf_g2_form form, mf_vec3 wo, mf_vec3 wi)
{
    double lo = mf_smith_lambda(ndf, wo), li = mf_smith_lambda(ndf, wi);
    if (form == MF_G2_SEPARABLE)
        return 1.0 / ((1.0 + lo) * (1.0 + li));
    if (form == MF_G2_JOINT)
        return 1.0 / (1.0 + lo + li);
    return NAN;
}

double mf_smith_g2_gaussian(const mf_gaussian_slopes *g, mf_vec3 wo, mf_vec3 wi)
{
    return 1.0 / (1.0 + mf_smith_lambda_gaussian(g, wo) + mf_smith_lambda_gaussian(g, wi));
}
