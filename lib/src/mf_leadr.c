/* mf_leadr.c -- LEADR environment, diffuse and irradiance shading on the slope grid (see mf_leadr.h). */
#include "mfkit/mf_leadr.h"
#include "mfkit/mf_smith.h"

static int is_unit(mf_vec3 w)
{
    return mf_vec3_isfinite(w) && fabs(mf_vec3_dot(w, w) - 1.0) <= 1e-6;
}

static int lights_valid(const mf_leadr_light *lights, int n_lights)
{
    if (n_lights < 0 || (n_lights > 0 && !lights))
        return 0;
    for (int k = 0; k < n_lights; ++k)
        if (!is_unit(lights[k].wi) || !isfinite(lights[k].irradiance) || !(lights[k].irradiance >= 0.0))
            return 0;
    return 1;
}

/* Lambda(wo), +inf when wo is on or below the mesosurface (docs/math.md, correction C-L3). */
static double lambda_view(const mf_gaussian_slopes *g, mf_vec3 wo)
{
    return mf_smith_lambda_gaussian(g, wo);
}

double mf_leadr_irradiance_lights(const mf_gaussian_slopes *g, mf_vec3 wo, const mf_leadr_light *lights,
                                  int n_lights, mf_vec3 wn)
{
    if (!mf_gaussian_valid(g) || !is_unit(wo) || !is_unit(wn) || !lights_valid(lights, n_lights))
        return NAN;
    double lo = lambda_view(g, wo);
    if (isinf(lo))
        return 0.0;
    double e = 0.0;
    for (int k = 0; k < n_lights; ++k) {
        double cos_ni = mf_vec3_dot(wn, lights[k].wi);
        if (!(cos_ni > 0.0))
            continue;
        double li = mf_smith_lambda_gaussian(g, lights[k].wi);
        if (isinf(li))
            continue;
        /* [Dupuy 2013, Eq. 20] with L = P delta(w - wi) */
        e += lights[k].irradiance * cos_ni / (1.0 + lo + li);
    }
    return e;
}

mf_status mf_leadr_irradiance_sh(const mf_gaussian_slopes *g, mf_vec3 wo, const mf_leadr_light *lights,
                                 int n_lights, const double env[MF_SH_COEFFS], double out[MF_SH_COEFFS])
{
    for (int i = 0; i < MF_SH_COEFFS; ++i)
        out[i] = NAN;
    if (!mf_gaussian_valid(g) || !is_unit(wo) || !lights_valid(lights, n_lights))
        return MF_ERR_DOMAIN;
    if (env)
        for (int i = 0; i < MF_SH_COEFFS; ++i)
            if (!isfinite(env[i]))
                return MF_ERR_DOMAIN;
    for (int i = 0; i < MF_SH_COEFFS; ++i)
        out[i] = 0.0;
    double lo = lambda_view(g, wo);
    if (isinf(lo))
        return MF_OK;
    /* [Dupuy 2013, Algorithm 2], correction C-L1 fixed inside mf_sh_add_directional */
    for (int k = 0; k < n_lights; ++k) {
        double li = mf_smith_lambda_gaussian(g, lights[k].wi);
        if (isinf(li))
            continue;
        mf_sh_add_directional(out, lights[k].wi, lights[k].irradiance / (1.0 + lo + li));
    }
    if (env)
        for (int i = 0; i < MF_SH_COEFFS; ++i)
            out[i] += env[i] / (1.0 + lo);
    return MF_OK;
}

/* ---- grid ----------------------------------------------------------------------------- */

static int grid_valid(const mf_leadr_grid *grid)
{
    return grid && grid->n >= 1 && grid->n <= MF_LEADR_GRID_MAX && isfinite(grid->lambda) && grid->lambda > 0.0;
}

mf_status mf_leadr_grid_init(mf_leadr_grid *grid, int n, double lambda, mf_leadr_grid_layout layout)
{
    if (!grid)
        return MF_ERR_DOMAIN;
    grid->n = 0;
    if (n < 1 || n > MF_LEADR_GRID_MAX || !isfinite(lambda) || !(lambda > 0.0)
        || (layout != MF_LEADR_GRID_END_POINTS && layout != MF_LEADR_GRID_CELL_CENTRES))
        return MF_ERR_DOMAIN;
    grid->lambda = lambda;
    grid->layout = layout;
    if (n == 1) {
        grid->spacing = 2.0 * lambda;
        grid->p[0] = 0.0;
    } else {
        /* [Dupuy 2013, Sec. 5.1], the two readings of correction C-L7; p_{N-1-j} = -p_j exactly */
        grid->spacing = (layout == MF_LEADR_GRID_END_POINTS) ? 2.0 * lambda / (n - 1) : 2.0 * lambda / n;
        for (int j = 0; j < n; ++j) {
            double t = (layout == MF_LEADR_GRID_END_POINTS) ? (2.0 * j - (n - 1)) / (n - 1)
                                                            : (2.0 * j + 1.0 - n) / n;
            grid->p[j] = lambda * t;
        }
    }
    double sum = 0.0;
    for (int j = 0; j < n; ++j) {
        grid->w[j] = exp(-0.5 * grid->p[j] * grid->p[j]);
        sum += grid->w[j];
    }
    for (int j = 0; j < n; ++j)
        grid->w[j] /= sum;
    grid->n = n;
    return MF_OK;
}

double mf_leadr_grid_variance(const mf_leadr_grid *grid)
{
    if (!grid_valid(grid))
        return NAN;
    double v = 0.0;
    for (int j = 0; j < grid->n; ++j)
        v += grid->w[j] * grid->p[j] * grid->p[j];
    return v;
}

/* Cholesky factor [[l00, 0], [l10, l11]] of the covariance, without 0/0 for degenerate ones. */
static void cholesky(const mf_gaussian_slopes *g, double *l00, double *l10, double *l11)
{
    if (g->var_x > 0.0) {
        double det = fmax(0.0, g->var_x * g->var_y - g->cov_xy * g->cov_xy);
        *l00 = sqrt(g->var_x);
        *l10 = g->cov_xy / *l00;
        *l11 = sqrt(det / g->var_x);
    } else { /* var_x = 0 forces cov_xy = 0 (det >= 0) */
        *l00 = 0.0;
        *l10 = 0.0;
        *l11 = sqrt(g->var_y);
    }
}

/* Node (j, k) of the grid warped to the slopes of g, whose Cholesky factor is l[3] = (l00, l10,
 * l11) [Dupuy 2013, Sec. 5.1]; returns the node's weight. */
static double warp_node(const mf_leadr_grid *grid, const mf_gaussian_slopes *g, const double l[3], int j, int k,
                        double slope[2])
{
    slope[0] = l[0] * grid->p[j] + g->mean_x;
    slope[1] = l[1] * grid->p[j] + l[2] * grid->p[k] + g->mean_y;
    return grid->w[j] * grid->w[k];
}

double mf_leadr_grid_warp(const mf_leadr_grid *grid, const mf_gaussian_slopes *g, int j, int k, double slope[2])
{
    slope[0] = slope[1] = NAN;
    if (!grid_valid(grid) || !mf_gaussian_valid(g) || j < 0 || k < 0 || j >= grid->n || k >= grid->n)
        return NAN;
    double l[3];
    cholesky(g, &l[0], &l[1], &l[2]);
    return warp_node(grid, g, l, j, k, slope);
}

double mf_leadr_grid_sample_area(const mf_leadr_grid *grid, const mf_gaussian_slopes *g)
{
    if (!grid_valid(grid) || !mf_gaussian_valid(g))
        return NAN;
    double s = grid->spacing * sqrt(fmax(g->var_x, g->var_y));
    return s * s; /* [Dupuy 2013, Sec. 5.2], spacing per correction C-L7 */
}

/* ---- shading -------------------------------------------------------------------------- */

/* The shared set-up: validity (usable: the caller's own arguments are valid), *out = NaN, the
 * prefactor (n_bar.g)/(n_bar.wo) and Lambda(wo).  Returns 0 for invalid input, 1 to shade, 2 for a
 * view on or below the mesosurface (*out = 0). */
static int shading_setup(int usable, const mf_leadr_grid *grid, const mf_gaussian_slopes *g, mf_vec3 wo,
                         double *prefactor, double *lo, double *out)
{
    if (!out)
        return 0;
    *out = NAN;
    if (!usable || !grid_valid(grid) || !mf_gaussian_valid(g) || !is_unit(wo))
        return 0;
    mf_vec3 n = mf_gaussian_mesonormal(g);
    double n_wo = mf_vec3_dot(n, wo);
    *lo = lambda_view(g, wo);
    if (!(n_wo > 0.0) || isinf(*lo)) {
        *out = 0.0;
        return 2;
    }
    *prefactor = n.z / n_wo; /* [Dupuy 2013, Eq. 16, 19, 21]: n_bar.g / n_bar.wo */
    return 1;
}

mf_status mf_leadr_specular_env(const mf_leadr_grid *grid, const mf_gaussian_slopes *g, mf_fresnel fresnel,
                                mf_vec3 wo, mf_leadr_env_fn env, void *user, double *out)
{
    double pref = 0.0, lo = 0.0;
    int s = shading_setup(env && !isnan(mf_fresnel_eval(fresnel, 1.0)), grid, g, wo, &pref, &lo, out);
    if (s != 1)
        return s == 2 ? MF_OK : MF_ERR_DOMAIN;
    const double area = mf_leadr_grid_sample_area(grid, g);
    double l[3], slope[2];
    cholesky(g, &l[0], &l[1], &l[2]);
    double sum = 0.0;
    for (int j = 0; j < grid->n; ++j)
        for (int k = 0; k < grid->n; ++k) {
            double w = warp_node(grid, g, l, j, k, slope);
            mf_vec3 wn = mf_normal_from_slope(slope[0], slope[1]);
            double cos_no = mf_vec3_dot(wn, wo);
            if (!(cos_no > 0.0)) /* <wn, wo> = 0: a back-facing micro-normal */
                continue;
            mf_vec3 wi = mf_vec3_sub(mf_vec3_scale(wn, 2.0 * cos_no), wo); /* [Eq. 18] */
            double li = mf_smith_lambda_gaussian(g, wi);
            if (isinf(li)) /* wi on or below the mesosurface: shadowed (correction C-L3) */
                continue;
            double cos_ng = wn.z;
            /* [Dupuy 2013, Sec. 5.2]: alpha = 4 |wn.wo| |wn.g|^3 A */
            double solid_angle = 4.0 * cos_no * cos_ng * cos_ng * cos_ng * area;
            double radiance = env(wi, solid_angle, user);
            if (!isfinite(radiance))
                return MF_ERR_DOMAIN;
            /* [Dupuy 2013, Eq. 22 / Algorithm 1], correction C-L8: wn per sample; F(wn.wi) = F(wn.wo) */
            double f = mf_fresnel_eval(fresnel, cos_no);
            sum += w * radiance * f * (cos_no / cos_ng) / (1.0 + lo + li);
        }
    *out = pref * sum;
    return MF_OK;
}

mf_status mf_leadr_diffuse(const mf_leadr_grid *grid, const mf_gaussian_slopes *g, mf_vec3 wo,
                           mf_leadr_irradiance_fn irradiance, void *user, double *out)
{
    double pref = 0.0, lo = 0.0;
    int s = shading_setup(irradiance != 0, grid, g, wo, &pref, &lo, out);
    if (s != 1)
        return s == 2 ? MF_OK : MF_ERR_DOMAIN;
    double l[3], slope[2];
    cholesky(g, &l[0], &l[1], &l[2]);
    double sum = 0.0;
    for (int j = 0; j < grid->n; ++j)
        for (int k = 0; k < grid->n; ++k) {
            double w = warp_node(grid, g, l, j, k, slope);
            mf_vec3 wn = mf_normal_from_slope(slope[0], slope[1]);
            double cos_no = mf_vec3_dot(wn, wo);
            if (!(cos_no > 0.0))
                continue;
            double e = irradiance(wn, user);
            if (!isfinite(e))
                return MF_ERR_DOMAIN;
            /* [Dupuy 2013, Eq. 23 / Algorithm 3] */
            sum += w * e * cos_no / wn.z;
        }
    *out = pref * MF_INV_PI * sum;
    return MF_OK;
}

static double sh_irradiance_cb(mf_vec3 wn, void *user)
{
    return mf_sh_irradiance((const double *)user, wn);
}

mf_status mf_leadr_diffuse_sh(const mf_leadr_grid *grid, const mf_gaussian_slopes *g, mf_vec3 wo,
                              const double radiance_sh[MF_SH_COEFFS], double *out)
{
    if (!radiance_sh) {
        if (out)
            *out = NAN;
        return MF_ERR_DOMAIN;
    }
    /* the callback reads the coefficients only; the cast drops const for the void* channel */
    return mf_leadr_diffuse(grid, g, wo, sh_irradiance_cb, (void *)radiance_sh, out);
}
