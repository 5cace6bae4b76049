/* mf_ndf.c -- GGX, Beckmann and non-centred Gaussian NDFs (see mf_ndf.h). */
#include "mfkit/mf_ndf.h"

#include <string.h>

const char *mf_ndf_type_name(mf_ndf_type t)
{
    switch (t) {
    case MF_NDF_GGX: return "ggx";
    case MF_NDF_BECKMANN: return "beckmann";
    }
    return "unknown";
}

int mf_ndf_type_parse(const char *name, mf_ndf_type *out)
{
    if (name && strcmp(name, "ggx") == 0) { *out = MF_NDF_GGX; return 0; }
    if (name && strcmp(name, "beckmann") == 0) { *out = MF_NDF_BECKMANN; return 0; }
    return -1;
}

int mf_ndf_valid(mf_ndf ndf)
{
    return (ndf.type == MF_NDF_GGX || ndf.type == MF_NDF_BECKMANN) && isfinite(ndf.alpha_x)
        && isfinite(ndf.alpha_y) && ndf.alpha_x > 0.0 && ndf.alpha_y > 0.0;
}

double mf_ndf_d(mf_ndf ndf, mf_vec3 wm)
{
    if (!mf_ndf_valid(ndf) || !mf_vec3_isfinite(wm))
        return NAN;
    if (wm.z <= 0.0)
        return 0.0;
    double ax = ndf.alpha_x, ay = ndf.alpha_y;
    double ex = wm.x / ax, ey = wm.y / ay;
    double z_sq = wm.z * wm.z;
    if (ndf.type == MF_NDF_GGX) {
        /* [Walter 2007, Eq. 33] with pi ax ay cos^4 (1 + tan^2 stretched)^2 written as
         * pi ax ay (x^2/ax^2 + y^2/ay^2 + z^2)^2: no tan, finite at z -> 0. */
        double s = ex * ex + ey * ey + z_sq;
        return 1.0 / (MF_PI * ax * ay * s * s);
    }
    /* [Walter 2007, Eq. 25] anisotropic: exp(-stretched tan^2) / (pi ax ay cos^4). */
    double t = (ex * ex + ey * ey) / z_sq;
    if (t > 800.0) /* exp(-t) underflows to 0 while z^4 may too: avoid 0/0 */
        return 0.0;
    return exp(-t) / (MF_PI * ax * ay * z_sq * z_sq);
}

double mf_ndf_p22(mf_ndf ndf, double slope_x, double slope_y)
{
    if (!mf_ndf_valid(ndf) || !isfinite(slope_x) || !isfinite(slope_y))
        return NAN;
    double ex = slope_x / ndf.alpha_x, ey = slope_y / ndf.alpha_y;
    double r_sq = ex * ex + ey * ey;
    double norm = 1.0 / (MF_PI * ndf.alpha_x * ndf.alpha_y);
    if (ndf.type == MF_NDF_GGX) {
        double s = 1.0 + r_sq;
        return norm / (s * s);
    }
    return norm * exp(-r_sq);
}

void mf_slope_from_normal(mf_vec3 wm, double slope[2])
{
    if (!(wm.z > 0.0)) {
        slope[0] = slope[1] = NAN;
        return;
    }
    slope[0] = -wm.x / wm.z;
    slope[1] = -wm.y / wm.z;
}

mf_vec3 mf_normal_from_slope(double slope_x, double slope_y)
{
    return mf_vec3_normalize(mf_vec3_make(-slope_x, -slope_y, 1.0));
}

int mf_gaussian_valid(const mf_gaussian_slopes *g)
{
    if (!g || !isfinite(g->mean_x) || !isfinite(g->mean_y) || !isfinite(g->var_x) || !isfinite(g->var_y)
        || !isfinite(g->cov_xy))
        return 0;
    return g->var_x >= 0.0 && g->var_y >= 0.0 && g->var_x * g->var_y - g->cov_xy * g->cov_xy >= 0.0;
}

mf_gaussian_slopes mf_gaussian_from_beckmann(double alpha_x, double alpha_y)
{
    mf_gaussian_slopes g = {0.0, 0.0, 0.5 * alpha_x * alpha_x, 0.5 * alpha_y * alpha_y, 0.0};
    return g;
}

double mf_gaussian_p22(const mf_gaussian_slopes *g, double slope_x, double slope_y)
{
    if (!mf_gaussian_valid(g) || !isfinite(slope_x) || !isfinite(slope_y))
        return NAN;
    double dx = slope_x - g->mean_x, dy = slope_y - g->mean_y;
    double det = g->var_x * g->var_y - g->cov_xy * g->cov_xy;
    if (det > 0.0) {
        /* [Dupuy 2013, Eq. 8]; S^-1 = [[var_y, -cov], [-cov, var_x]] / det. */
        double q = (g->var_y * dx * dx - 2.0 * g->cov_xy * dx * dy + g->var_x * dy * dy) / det;
        return exp(-0.5 * q) / (2.0 * MF_PI * sqrt(det));
    }
    /* Degenerate covariance: all mass on a line (or a point); no density in the plane. */
    double on_support;
    if (g->var_x == 0.0 && g->var_y == 0.0)
        on_support = (dx == 0.0 && dy == 0.0);
    else /* direction of zero variance: (var_y, -cov) or (-cov, var_x), whichever is non-zero */
        on_support = (g->var_x >= g->var_y) ? (-g->cov_xy * dx + g->var_x * dy == 0.0)
                                            : (g->var_y * dx - g->cov_xy * dy == 0.0);
    return on_support ? INFINITY : 0.0;
}

double mf_gaussian_d(const mf_gaussian_slopes *g, mf_vec3 wm)
{
    if (!mf_gaussian_valid(g) || !mf_vec3_isfinite(wm))
        return NAN;
    if (wm.z <= 0.0)
        return 0.0;
    double z_sq = wm.z * wm.z;
    return mf_gaussian_p22(g, -wm.x / wm.z, -wm.y / wm.z) / (z_sq * z_sq);
}

mf_vec3 mf_gaussian_mesonormal(const mf_gaussian_slopes *g)
{
    return mf_normal_from_slope(g->mean_x, g->mean_y);
}

double mf_ndf_beckmann_alpha_from_blinn_phong(double exponent)
{
    if (!(exponent > 0.0) || !isfinite(exponent))
        return NAN;
    return sqrt(2.0 / exponent);
}

double mf_ndf_blinn_phong_from_beckmann_alpha(double alpha)
{
    if (!(alpha > 0.0) || !isfinite(alpha))
        return NAN;
    return 2.0 / (alpha * alpha);
}
