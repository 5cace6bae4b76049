/* test_leadr.c -- LEADR grid, environment specular, rough diffuse and masking-aware irradiance (mf_leadr.h). */
#include "mf_test.h"
#include "mfkit/mf_brdf.h"
#include "mfkit/mf_leadr.h"
#include "mfkit/mf_rng.h"
#include "mfkit/mf_smith.h"

#include <float.h>

/* ---- environments and irradiance callbacks ---------------------------------------------- */
static double env_one(mf_vec3 wi, double sa, void *u) { (void)wi; (void)sa; (void)u; return 1.0; }
static double env_below(mf_vec3 wi, double sa, void *u) { (void)sa; (void)u; return wi.z < 0.0 ? 1.0 : 0.0; }
static double env_nan(mf_vec3 wi, double sa, void *u) { (void)wi; (void)sa; (void)u; return NAN; }
static double env_sky(mf_vec3 wi, double sa, void *u)
{
    (void)sa;
    (void)u;
    return 0.5 + 0.4 * wi.z + 2.0 * exp(6.0 * (wi.x * 0.6 + wi.z * 0.8 - 1.0));
}

/* records the mirror case: the direction and solid angle it was called with */
typedef struct {
    int calls;
    mf_vec3 wi;
    double solid_angle;
} record_ctx;
static double env_record(mf_vec3 wi, double sa, void *u)
{
    record_ctx *r = u;
    r->calls++;
    r->wi = wi;
    r->solid_angle = sa;
    return env_sky(wi, sa, NULL);
}

/* checks the solid angle passed with every sample against J A recomputed from (wo, wi) */
typedef struct {
    mf_vec3 wo;
    double area;
    double worst;
} solid_angle_ctx;
static double env_check_solid_angle(mf_vec3 wi, double sa, void *u)
{
    solid_angle_ctx *c = u;
    mf_vec3 wn = mf_vec3_normalize(mf_vec3_add(wi, c->wo));
    double expect = 4.0 * mf_vec3_dot(wn, c->wo) * wn.z * wn.z * wn.z * c->area;
    c->worst = fmax(c->worst, fabs(sa - expect) / expect);
    return 1.0;
}

typedef struct {
    const mf_gaussian_slopes *g;
    mf_vec3 wo;
    const mf_leadr_light *lights;
    int n;
} lights_ctx;
static double irr_lights(mf_vec3 wn, void *u)
{
    const lights_ctx *c = u;
    return mf_leadr_irradiance_lights(c->g, c->wo, c->lights, c->n, wn);
}
static double irr_one(mf_vec3 wn, void *u) { (void)wn; (void)u; return 1.0; }

/* Oren-Nayar qualitative model [Oren & Nayar 1994, Eq. 30] for albedo 1, as a ratio to Lambert:
 * A + B max(0, cos(phi_i - phi_o)) sin(max theta) tan(min theta), sigma in radians. */
static double oren_nayar_ratio(double sigma, double th_i, double th_o, double dphi)
{
    double s2 = sigma * sigma;
    double a = 1.0 - 0.5 * s2 / (s2 + 0.33), b = 0.45 * s2 / (s2 + 0.09);
    return a + b * fmax(0.0, cos(dphi)) * sin(fmax(th_i, th_o)) * tan(fmin(th_i, th_o));
}

/* The normalisation identity after Eq. 16 (no Fresnel, no shadowing), on the grid:
 * (n.g)/(n.wo) sum W <wn, wo>/(wn.g) / (1 + Lambda(wo)) -> 1. */
static double grid_identity(const mf_leadr_grid *grid, const mf_gaussian_slopes *g, mf_vec3 wo)
{
    mf_vec3 nb = mf_gaussian_mesonormal(g);
    double lo = mf_smith_lambda_gaussian(g, wo), s = 0.0;
    for (int j = 0; j < grid->n; ++j)
        for (int k = 0; k < grid->n; ++k) {
            double slope[2];
            double w = mf_leadr_grid_warp(grid, g, j, k, slope);
            mf_vec3 wn = mf_normal_from_slope(slope[0], slope[1]);
            s += w * fmax(0.0, mf_vec3_dot(wn, wo)) / wn.z;
        }
    return nb.z / mf_vec3_dot(nb, wo) * s / (1.0 + lo);
}

static double spec_env(int n, double lambda, mf_leadr_grid_layout layout, const mf_gaussian_slopes *g, mf_vec3 wo,
                       mf_leadr_env_fn env)
{
    mf_leadr_grid grid;
    double v = NAN;
    mf_fresnel none = {MF_FRESNEL_NONE, 0, 0, 0};
    if (mf_leadr_grid_init(&grid, n, lambda, layout) != MF_OK || mf_leadr_specular_env(&grid, g, none, wo, env, NULL, &v) != MF_OK)
        return NAN;
    return v;
}

static double diffuse_cb(int n, double lambda, mf_leadr_grid_layout layout, const mf_gaussian_slopes *g, mf_vec3 wo,
                         mf_leadr_irradiance_fn f, void *user)
{
    mf_leadr_grid grid;
    double v = NAN;
    if (mf_leadr_grid_init(&grid, n, lambda, layout) != MF_OK || mf_leadr_diffuse(&grid, g, wo, f, user, &v) != MF_OK)
        return NAN;
    return v;
}

/* Truncation bias of the grid on [-lambda, lambda]^2 with renormalised weights: for an integrand h,
 * |E_T[h] - E[h]| <= (P(T^c) E[h] + E[h 1_{T^c}]) / P(T), P(T^c) <= 2 erfc(lambda/sqrt 2).  The
 * integrands here are <= (n.g)/(n.wo) sqrt(1 + |slope|^2) <= 10 over the tail's bulk, hence the
 * factor 2 * 10 * 2 (generous: the observed bias at lambda = 6 is 4e-10). */
static double trunc_delta(double lambda) { return 40.0 * erfc(lambda / MF_SQRT2); }

int main(void)
{
    mf_pcg32 rng;
    uint64_t seed = mf_test_seed(2013);
    mf_pcg32_seed(&rng, seed, 3);
    mf_fresnel none = {MF_FRESNEL_NONE, 0, 0, 0};
    const mf_leadr_grid_layout layouts[2] = {MF_LEADR_GRID_END_POINTS, MF_LEADR_GRID_CELL_CENTRES};
    const char *lname[2] = {"end points", "cell centres"};

    /* ================= grid [Sec. 5.1] ================= */
    for (int l = 0; l < 2; ++l)
        for (int n = 1; n <= 257; n += (n < 9 ? 1 : 31)) {
            mf_leadr_grid grid;
            CHECK(mf_leadr_grid_init(&grid, n, 1.8, layouts[l]) == MF_OK);
            double s = 0.0;
            for (int j = 0; j < n; ++j) {
                s += grid.w[j];
                CHECK(grid.p[n - 1 - j] == -grid.p[j]);
                CHECK(grid.w[n - 1 - j] == grid.w[j]);
            }
            CHECK_ABS(s, 1.0, 2 * n * DBL_EPSILON);
            if (n > 1) {
                CHECK_ABS(grid.p[1] - grid.p[0], grid.spacing, 4 * DBL_EPSILON * 1.8); /* p ~ lambda rounds */
                CHECK_REL(layouts[l] == MF_LEADR_GRID_END_POINTS ? grid.p[n - 1] : grid.p[n - 1] + 0.5 * grid.spacing, 1.8,
                          4 * DBL_EPSILON);
            }
        }
    /* docs/math.md, correction C-L7: discrete variance 0.8656 (end points) / 0.6981 (cell centres), N = 5, lambda = 1.8;
     * closed forms: points (0, +-0.9, +-1.8) and (0, +-0.72, +-1.44) */
    {
        mf_leadr_grid ge, gc;
        CHECK(mf_leadr_grid_init(&ge, 5, 1.8, MF_LEADR_GRID_END_POINTS) == MF_OK);
        CHECK(mf_leadr_grid_init(&gc, 5, 1.8, MF_LEADR_GRID_CELL_CENTRES) == MF_OK);
        double a = exp(-0.5 * 0.81), b = exp(-0.5 * 3.24);
        double ve = 2.0 * (0.81 * a + 3.24 * b) / (1.0 + 2.0 * a + 2.0 * b);
        a = exp(-0.5 * 0.5184);
        b = exp(-0.5 * 2.0736);
        double vc = 2.0 * (0.5184 * a + 2.0736 * b) / (1.0 + 2.0 * a + 2.0 * b);
        CHECK_REL(mf_leadr_grid_variance(&ge), ve, 8 * DBL_EPSILON);
        CHECK_REL(mf_leadr_grid_variance(&gc), vc, 8 * DBL_EPSILON);
        CHECK_ABS(mf_leadr_grid_variance(&ge), 0.8656, 5e-5);
        CHECK_ABS(mf_leadr_grid_variance(&gc), 0.6981, 5e-5);
        printf("correction C-L7: grid variance N=5 lambda=1.8: end points %.5f, cell centres %.5f\n", mf_leadr_grid_variance(&ge),
               mf_leadr_grid_variance(&gc));
        /* sample area [Sec. 5.2]: cell centres = the printed (2 lambda max(sigma)/N)^2 */
        mf_gaussian_slopes g = {0.1, 0.0, 0.02, 0.05, 0.01};
        CHECK_REL(mf_leadr_grid_sample_area(&gc, &g), pow(2.0 * 1.8 * sqrt(0.05) / 5.0, 2.0), 4 * DBL_EPSILON);
        CHECK_REL(mf_leadr_grid_sample_area(&ge, &g), pow(2.0 * 1.8 * sqrt(0.05) / 4.0, 2.0), 4 * DBL_EPSILON);
    }
    {
        mf_leadr_grid grid;
        CHECK(mf_leadr_grid_init(&grid, 0, 1.8, MF_LEADR_GRID_END_POINTS) == MF_ERR_DOMAIN);
        CHECK(mf_leadr_grid_init(&grid, MF_LEADR_GRID_MAX + 1, 1.8, MF_LEADR_GRID_END_POINTS) == MF_ERR_DOMAIN);
        CHECK(mf_leadr_grid_init(&grid, 5, 0.0, MF_LEADR_GRID_END_POINTS) == MF_ERR_DOMAIN);
        CHECK(mf_leadr_grid_init(&grid, 5, NAN, MF_LEADR_GRID_END_POINTS) == MF_ERR_DOMAIN);
        CHECK(mf_leadr_grid_init(&grid, 5, 1.8, (mf_leadr_grid_layout)9) == MF_ERR_DOMAIN);
        CHECK(isnan(mf_leadr_grid_variance(&grid)));
        CHECK(mf_leadr_grid_init(&grid, 1, 1.8, MF_LEADR_GRID_CELL_CENTRES) == MF_OK);
        CHECK(grid.p[0] == 0.0 && grid.w[0] == 1.0);
    }
    /* Warp: on the symmetric grid E[p_j] = 0, E[p_j p_k] = v1 delta_jk (v1 the 1D variance), so the
     * weighted samples have mean exactly the mean slope and covariance exactly v1 * Sigma
     * (L diag(v1, v1) L^T).  32 eps of the scale.  Degenerate covariances give finite samples. */
    {
        const mf_gaussian_slopes gs[4] = {
            {0.3, -0.2, 0.08, 0.03, 0.01},  /* general */
            {0.1, 0.4, 0.0, 0.05, 0.0},     /* var_x = 0 */
            {-0.2, 0.1, 0.04, 0.01, 0.02},  /* det = 0: perfectly correlated */
            {0.25, 0.5, 0.0, 0.0, 0.0}};    /* a single slope */
        mf_leadr_grid grid;
        CHECK(mf_leadr_grid_init(&grid, 7, 1.8, MF_LEADR_GRID_CELL_CENTRES) == MF_OK);
        double v1 = mf_leadr_grid_variance(&grid);
        for (int c = 0; c < 4; ++c) {
            const mf_gaussian_slopes *g = &gs[c];
            double m[2] = {0, 0}, cxx = 0, cyy = 0, cxy = 0, wsum = 0;
            int finite = 1;
            for (int j = 0; j < grid.n; ++j)
                for (int k = 0; k < grid.n; ++k) {
                    double s[2];
                    double w = mf_leadr_grid_warp(&grid, g, j, k, s);
                    finite &= isfinite(w) && isfinite(s[0]) && isfinite(s[1]);
                    wsum += w;
                    m[0] += w * s[0];
                    m[1] += w * s[1];
                    cxx += w * (s[0] - g->mean_x) * (s[0] - g->mean_x);
                    cyy += w * (s[1] - g->mean_y) * (s[1] - g->mean_y);
                    cxy += w * (s[0] - g->mean_x) * (s[1] - g->mean_y);
                }
            CHECK(finite);
            CHECK_ABS(wsum, 1.0, 64 * DBL_EPSILON);
            CHECK_ABS(m[0], g->mean_x, 32 * DBL_EPSILON);
            CHECK_ABS(m[1], g->mean_y, 32 * DBL_EPSILON);
            CHECK_ABS(cxx, v1 * g->var_x, 32 * DBL_EPSILON);
            CHECK_ABS(cyy, v1 * g->var_y, 32 * DBL_EPSILON);
            CHECK_ABS(cxy, v1 * g->cov_xy, 32 * DBL_EPSILON);
        }
        double s[2];
        mf_gaussian_slopes bad = {0, 0, 0.01, 0.01, 0.02};
        CHECK(isnan(mf_leadr_grid_warp(&grid, &bad, 0, 0, s)) && isnan(s[0]));
        CHECK(isnan(mf_leadr_grid_warp(&grid, &gs[0], 7, 0, s)));
    }

    /* ================= masking-aware irradiance [Eq. 20, Algorithm 2] ================= */
    {
        /* Zero variance: Lambda = 0 above the mesosurface, so Algorithm 2 is the plain projection:
         * correction C-L1's lights P = 1, 2.5, 0.7 give L00 = Y00 * 4.2 = 1.184798 (printed form: 2.736321). */
        mf_gaussian_slopes flat = {0, 0, 0, 0, 0};
        mf_leadr_light l1[3] = {{{0, 0, 1}, 1.0}, {{0.6, 0, 0.8}, 2.5}, {{0, -0.28, 0.96}, 0.7}};
        double c[MF_SH_COEFFS];
        CHECK(mf_leadr_irradiance_sh(&flat, mf_vec3_make(0, 0, 1), l1, 3, NULL, c) == MF_OK);
        CHECK_REL(c[0], MF_SH_Y00 * 4.2, 4 * DBL_EPSILON);
        CHECK_ABS(c[0], 1.184798, 5e-7);

        /* General statistics: weights P / (1 + L(wo) + L(wi)) per light, env / (1 + L(wo)). */
        mf_gaussian_slopes g = {0.3, -0.1, 0.09, 0.05, 0.02};
        mf_vec3 wo = mf_vec3_spherical(1.1, 0.4);
        mf_vec3 nb = mf_gaussian_mesonormal(&g);
        mf_leadr_light lights[4] = {
            {mf_vec3_spherical(0.5, 2.0), 1.5},
            {mf_vec3_spherical(1.3, -0.7), 0.8},
            {mf_vec3_spherical(1.62, MF_PI), 2.0}, /* below the horizon, above the tilted mesosurface */
            {mf_vec3_spherical(2.5, 0.0), 4.0}};   /* below the mesosurface: no contribution */
        CHECK(mf_vec3_dot(lights[2].wi, nb) > 0.0 && lights[2].wi.z < 0.0);
        CHECK(mf_vec3_dot(lights[3].wi, nb) < 0.0);
        double env[MF_SH_COEFFS], out[MF_SH_COEFFS], ref[MF_SH_COEFFS] = {0};
        for (int i = 0; i < MF_SH_COEFFS; ++i)
            env[i] = 0.1 * (i + 1) * (i % 2 ? -1.0 : 1.0);
        CHECK(mf_leadr_irradiance_sh(&g, wo, lights, 4, env, out) == MF_OK);
        double lo = mf_smith_lambda_gaussian(&g, wo), wsum = 0.0;
        for (int k = 0; k < 3; ++k) {
            double w = lights[k].irradiance / (1.0 + lo + mf_smith_lambda_gaussian(&g, lights[k].wi));
            mf_sh_add_directional(ref, lights[k].wi, w);
            wsum += w;
        }
        for (int i = 0; i < MF_SH_COEFFS; ++i) {
            ref[i] += env[i] / (1.0 + lo);
            CHECK_ABS(out[i], ref[i], 16 * DBL_EPSILON);
        }
        /* SH irradiance vs the exact Eq. 20 for the lights: |difference| <= 3/32 sum_k weights */
        double lights_only[MF_SH_COEFFS];
        CHECK(mf_leadr_irradiance_sh(&g, wo, lights, 4, NULL, lights_only) == MF_OK);
        double worst = 0.0;
        for (int k = 0; k < 500; ++k) {
            double u[2] = {mf_pcg32_next_double(&rng), mf_pcg32_next_double(&rng)};
            double z = u[0], r = sqrt(1.0 - z * z);
            mf_vec3 wn = mf_vec3_make(r * cos(2.0 * MF_PI * u[1]), r * sin(2.0 * MF_PI * u[1]), z);
            double e = mf_leadr_irradiance_lights(&g, wo, lights, 4, wn);
            worst = fmax(worst, fabs(mf_sh_irradiance(lights_only, wn) - e));
        }
        CHECK(worst <= 3.0 / 32.0 * wsum + 1e-14);
        printf("Algorithm 2: max |E_SH - E_exact| over normals = %.4f (bound 3/32 * sum of weights = %.4f)\n", worst,
               3.0 / 32.0 * wsum);
        /* a light below the mesosurface contributes nothing */
        CHECK(mf_leadr_irradiance_lights(&g, wo, lights + 3, 1, mf_vec3_make(0, 0, 1)) == 0.0);
        /* a view below the mesosurface: everything 0, MF_OK */
        mf_vec3 wo_below = mf_vec3_spherical(1.45, 0.0); /* nb tilts towards -x */
        CHECK(mf_vec3_dot(wo_below, nb) < 0.0);
        CHECK(mf_leadr_irradiance_sh(&g, wo_below, lights, 4, env, out) == MF_OK && out[0] == 0.0 && out[8] == 0.0);
        /* domain */
        mf_leadr_light neg = {{0, 0, 1}, -1.0}, nonunit = {{0, 0, 2}, 1.0};
        CHECK(mf_leadr_irradiance_sh(&g, wo, &neg, 1, NULL, out) == MF_ERR_DOMAIN && isnan(out[0]));
        CHECK(mf_leadr_irradiance_sh(&g, wo, &nonunit, 1, NULL, out) == MF_ERR_DOMAIN);
        CHECK(mf_leadr_irradiance_sh(&g, wo, NULL, 1, NULL, out) == MF_ERR_DOMAIN);
        CHECK(isnan(mf_leadr_irradiance_lights(&g, mf_vec3_make(0, 0, 0.5), lights, 1, mf_vec3_make(0, 0, 1))));
    }

    /* ================= specular under an environment [Eq. 19, 22; Algorithm 1] ================= */
    {
        /* Zero covariance = a mirror oriented by the mesonormal: I = F(n.wo) L(reflect(wo, n)), one
         * environment lookup per sample (all N^2 on the mean), solid angle 0.  8 eps. */
        mf_gaussian_slopes mirror = {0.2, -0.3, 0.0, 0.0, 0.0};
        mf_vec3 wo = mf_vec3_spherical(0.7, 2.5);
        mf_vec3 nb = mf_gaussian_mesonormal(&mirror);
        mf_fresnel sch = {MF_FRESNEL_SCHLICK, 0.04, 0, 0};
        mf_leadr_grid grid;
        CHECK(mf_leadr_grid_init(&grid, 5, 1.8, MF_LEADR_GRID_END_POINTS) == MF_OK);
        record_ctx rec = {0, {0, 0, 0}, -1.0};
        double v;
        CHECK(mf_leadr_specular_env(&grid, &mirror, sch, wo, env_record, &rec, &v) == MF_OK);
        mf_vec3 wr = mf_vec3_reflect(wo, nb);
        double expect = mf_fresnel_eval(sch, mf_vec3_dot(nb, wo)) * env_sky(wr, 0, NULL);
        CHECK_REL(v, expect, 8 * DBL_EPSILON);
        CHECK(rec.calls == 25 && rec.solid_angle == 0.0);
        CHECK_ABS(mf_vec3_dot(rec.wi, wr), 1.0, 4 * DBL_EPSILON);

        /* solid angle handed to the environment: 4 |wn.wo| (wn.z)^3 A for every sample */
        mf_gaussian_slopes g = {0.2, -0.1, 0.08, 0.03, 0.01};
        solid_angle_ctx sac = {mf_vec3_spherical(0.9, 0.3), mf_leadr_grid_sample_area(&grid, &g), 0.0};
        CHECK(mf_leadr_specular_env(&grid, &g, none, sac.wo, env_check_solid_angle, &sac, &v) == MF_OK);
        CHECK_ABS(sac.worst, 0.0, 1e-12);

        /* correction C-L5: the integral runs over the whole sphere: with a tilted mesosurface,
         * directions below the geometric horizon (but above the mesosurface) reflect light. */
        mf_gaussian_slopes tilt = {0.6, 0.0, 0.05, 0.05, 0.0};
        /* wi = (-0.95, 0, -0.1) is above the mesosurface (n ~ (-0.6, 0, 1)); its mirror wo is at 34 deg, phi = 0 */
        double below = spec_env(16, 3.0, MF_LEADR_GRID_CELL_CENTRES, &tilt, mf_vec3_spherical(0.6, 0.0), env_below);
        CHECK(below > 0.01);
        printf("tilted mean 0.6, wo at 34 deg: light from below the geometric horizon reflects %.4f of a unit environment\n",
               below);

        /* a view below the mesosurface: 0; domain errors */
        CHECK(mf_vec3_dot(mf_vec3_spherical(1.5, 0.0), mf_gaussian_mesonormal(&tilt)) < 0.0);
        CHECK(mf_leadr_specular_env(&grid, &tilt, none, mf_vec3_spherical(1.5, 0.0), env_one, NULL, &v) == MF_OK && v == 0.0);
        CHECK(mf_leadr_specular_env(&grid, &g, none, wo, env_nan, NULL, &v) == MF_ERR_DOMAIN && isnan(v));
        CHECK(mf_leadr_specular_env(&grid, &g, none, wo, NULL, NULL, &v) == MF_ERR_DOMAIN);
        CHECK(mf_leadr_specular_env(&grid, &g, none, mf_vec3_make(0, 0, 0.9), env_one, NULL, &v) == MF_ERR_DOMAIN);
        mf_fresnel badf = {MF_FRESNEL_SCHLICK, 2.0, 0, 0};
        CHECK(mf_leadr_specular_env(&grid, &g, badf, wo, env_one, NULL, &v) == MF_ERR_DOMAIN);
    }

    /* Convergence, centred anisotropic statistics, L = 1, no Fresnel: Eq. 19 is then the directional
     * albedo of the LEADR specular model (Lambda(wi) = inf exactly below the horizon), computed
     * independently by mf_leadr_specular_albedo (Gauss-Legendre over the Box-Muller map, its own
     * error estimate).  Check at N = 256, lambda = 6:
     *   |Q - ref| <= ref.err + |Q(256) - Q(128)| + TRUNC:
     * the grid's error estimate is that of the coarser grid, so conservative if the error decreases
     * monotonically (printed); TRUNC bounds the bias of the renormalised truncation (below). */
    {
        mf_gaussian_slopes g = mf_gaussian_from_beckmann(0.4, 0.25);
        mf_vec3 wo = mf_vec3_spherical(1.05, 0.5);
        mf_result ref;
        CHECK(mf_leadr_specular_albedo(&g, none, wo, 512, &ref) == MF_OK);
        printf("centred Beckmann (0.4, 0.25), wo 60 deg: albedo reference %.10f (err %.1g)\n", ref.val, ref.err);
        for (int l = 0; l < 2; ++l) {
            double prev = NAN, q = NAN;
            printf("  %-12s lambda=1.8 N=5: %.6f (error %+.2e)\n", lname[l],
                   spec_env(5, 1.8, layouts[l], &g, wo, env_one), spec_env(5, 1.8, layouts[l], &g, wo, env_one) - ref.val);
            for (int n = 4; n <= 256; n *= 2) {
                prev = q;
                q = spec_env(n, 6.0, layouts[l], &g, wo, env_one);
                printf("  %-12s lambda=6 N=%3d: %.8f (error %+.2e)\n", lname[l], n, q, q - ref.val);
            }
            CHECK_ABS(q, ref.val, ref.err + fabs(q - prev) + trunc_delta(6.0));
        }
    }

    /* Convergence, non-centred correlated statistics, L = 1 on the whole sphere, no Fresnel.
     * (1) The grid estimate of the normalisation identity after Eq. 16 (no shadowing) -> 1 exactly.
     * (2) Eq. 19 with shadowing against Monte Carlo over P22 (fixed seed) with the identity as
     *     control variate: ref = 1 - mean(g - f), g the unshadowed and f the shadowed integrand,
     *     whose mean is exactly 1 - Eq. 19.  z = 4 (two-sided P = 6.3e-5 per comparison, two
     *     comparisons); delta = the grid's own error estimate |Q(256) - Q(128)| + TRUNC.
     * Also, sample by sample, Eq. 19 <= the identity on the same grid. */
    {
        mf_gaussian_slopes g = {0.25, -0.15, 0.08, 0.03, 0.012};
        mf_vec3 wo = mf_vec3_spherical(1.1, 2.4);
        mf_vec3 nb = mf_gaussian_mesonormal(&g);
        double lo = mf_smith_lambda_gaussian(&g, wo), pref = nb.z / mf_vec3_dot(nb, wo);
        double l00 = sqrt(g.var_x), l10 = g.cov_xy / l00, l11 = sqrt((g.var_x * g.var_y - g.cov_xy * g.cov_xy) / g.var_x);
        const int nmc = 2000000;
        double s1 = 0.0, s2 = 0.0;
        for (int k = 0; k < nmc; ++k) {
            double a = mf_pcg32_next_normal(&rng), b = mf_pcg32_next_normal(&rng);
            mf_vec3 wn = mf_normal_from_slope(g.mean_x + l00 * a, g.mean_y + l10 * a + l11 * b);
            double c = mf_vec3_dot(wn, wo), d = 0.0;
            if (c > 0.0) {
                double li = mf_smith_lambda_gaussian(&g, mf_vec3_reflect(wo, wn));
                double gg = pref * c / (wn.z * (1.0 + lo));
                d = isinf(li) ? gg : gg * li / (1.0 + lo + li); /* g - f */
            }
            s1 += d;
            s2 += d * d;
        }
        double mean = s1 / nmc, se = sqrt(fmax(0.0, s2 / nmc - mean * mean) / (nmc - 1));
        double ref = 1.0 - mean;
        printf("non-centred (0.25,-0.15; 0.08,0.03,0.012), wo 63 deg: MC reference %.6f (se %.1g)\n", ref, se);
        for (int l = 0; l < 2; ++l) {
            mf_leadr_grid grid;
            CHECK(mf_leadr_grid_init(&grid, 5, 1.8, layouts[l]) == MF_OK);
            printf("  %-12s lambda=1.8 N=5: identity %.6f, Eq. 19 %.6f (error %+.2e)\n", lname[l], grid_identity(&grid, &g, wo),
                   spec_env(5, 1.8, layouts[l], &g, wo, env_one), spec_env(5, 1.8, layouts[l], &g, wo, env_one) - ref);
            double prev = NAN, q = NAN, id = NAN, id_prev = NAN;
            for (int n = 4; n <= 256; n *= 2) {
                CHECK(mf_leadr_grid_init(&grid, n, 6.0, layouts[l]) == MF_OK);
                id_prev = id;
                id = grid_identity(&grid, &g, wo);
                prev = q;
                q = spec_env(n, 6.0, layouts[l], &g, wo, env_one);
                printf("  %-12s lambda=6 N=%3d: identity error %+.2e, Eq. 19 %.6f (error %+.2e)\n", lname[l], n, id - 1.0, q,
                       q - ref);
                CHECK(q <= id * (1.0 + 1e-14));
            }
            CHECK_ABS(id, 1.0, fabs(id - id_prev) + trunc_delta(6.0));
            CHECK_MC(q, se, ref, 4.0, fabs(q - prev) + trunc_delta(6.0));
        }
    }

    /* ================= rough diffuse [Eq. 21, 23; Algorithm 3] ================= */
    {
        /* Zero covariance: Lambert on the mesosurface, I = E(n) / pi = P (n.wi) / pi (8 eps). */
        mf_gaussian_slopes flat = {0.3, 0.1, 0.0, 0.0, 0.0};
        mf_leadr_light light = {mf_vec3_spherical(0.6, 1.0), 2.0};
        mf_vec3 wo = mf_vec3_spherical(0.8, 3.0);
        lights_ctx lc = {&flat, wo, &light, 1};
        double v = diffuse_cb(5, 1.8, MF_LEADR_GRID_END_POINTS, &flat, wo, irr_lights, &lc);
        mf_vec3 nb = mf_gaussian_mesonormal(&flat);
        CHECK_REL(v, 2.0 * mf_vec3_dot(nb, light.wi) / MF_PI, 8 * DBL_EPSILON);
    }
    {
        /* Reciprocity: I(wo <- wi)(n.wo) = I(wi <- wo)(n.wi): the summand is symmetric (16 eps). */
        mf_gaussian_slopes g = {0.2, -0.3, 0.1, 0.06, -0.02};
        for (int k = 0; k < 20; ++k) {
            mf_vec3 a = mf_vec3_spherical(1.2 * mf_pcg32_next_double(&rng), 2.0 * MF_PI * mf_pcg32_next_double(&rng));
            mf_vec3 b = mf_vec3_spherical(1.2 * mf_pcg32_next_double(&rng), 2.0 * MF_PI * mf_pcg32_next_double(&rng));
            mf_vec3 nb = mf_gaussian_mesonormal(&g);
            if (mf_vec3_dot(a, nb) <= 0.0 || mf_vec3_dot(b, nb) <= 0.0)
                continue;
            mf_leadr_light la = {b, 1.0}, lb = {a, 1.0};
            lights_ctx ca = {&g, a, &la, 1}, cb = {&g, b, &lb, 1};
            double iab = diffuse_cb(9, 2.2, MF_LEADR_GRID_CELL_CENTRES, &g, a, irr_lights, &ca);
            double iba = diffuse_cb(9, 2.2, MF_LEADR_GRID_CELL_CENTRES, &g, b, irr_lights, &cb);
            CHECK_REL(iab * mf_vec3_dot(nb, a), iba * mf_vec3_dot(nb, b), 16 * DBL_EPSILON);
        }
    }
    {
        /* White surface under a uniform unit environment (env only, masking weight 1/(1 + L(wo))):
         * E(wn) = pi / (1 + L(wo)) and I = the normalisation identity -> 1 exactly.  Through the SH
         * pipeline (Algorithm 2 then 3).  Check at N = 256, lambda = 6 with the grid's estimate. */
        mf_gaussian_slopes g = {0.25, -0.15, 0.08, 0.03, 0.012};
        mf_vec3 wo = mf_vec3_spherical(1.1, 2.4);
        double env[MF_SH_COEFFS] = {2.0 * sqrt(MF_PI), 0, 0, 0, 0, 0, 0, 0, 0}, sh[MF_SH_COEFFS];
        CHECK(mf_leadr_irradiance_sh(&g, wo, NULL, 0, env, sh) == MF_OK);
        double prev = NAN, q = NAN;
        mf_leadr_grid grid;
        for (int n = 64; n <= 256; n *= 2) {
            CHECK(mf_leadr_grid_init(&grid, n, 6.0, MF_LEADR_GRID_CELL_CENTRES) == MF_OK);
            prev = q;
            CHECK(mf_leadr_diffuse_sh(&grid, &g, wo, sh, &q) == MF_OK);
        }
        CHECK_ABS(q, 1.0, fabs(q - prev) + trunc_delta(6.0));
        CHECK(mf_leadr_grid_init(&grid, 5, 1.8, MF_LEADR_GRID_END_POINTS) == MF_OK);
        double q5;
        CHECK(mf_leadr_diffuse_sh(&grid, &g, wo, sh, &q5) == MF_OK);
        printf("diffuse, uniform unit environment (exact 1): N=256 %.8f, N=5 lambda=1.8 end points %.6f\n", q, q5);
    }
    {
        /* SH pipeline vs the exact Eq. 20 for directional lights: |I_SH - I| <= (3/32) sum_k P_k w_k
         * times the grid's diffuse response to E = 1 (same grid, same weights). */
        mf_gaussian_slopes g = {0.1, 0.2, 0.15, 0.1, 0.03};
        mf_vec3 wo = mf_vec3_spherical(0.9, -1.0);
        mf_leadr_light lights[2] = {{mf_vec3_spherical(0.4, 0.5), 1.0}, {mf_vec3_spherical(1.2, 2.0), 3.0}};
        lights_ctx lc = {&g, wo, lights, 2};
        double sh[MF_SH_COEFFS], wsum = 0.0, lo = mf_smith_lambda_gaussian(&g, wo);
        for (int k = 0; k < 2; ++k)
            wsum += lights[k].irradiance / (1.0 + lo + mf_smith_lambda_gaussian(&g, lights[k].wi));
        CHECK(mf_leadr_irradiance_sh(&g, wo, lights, 2, NULL, sh) == MF_OK);
        mf_leadr_grid grid;
        CHECK(mf_leadr_grid_init(&grid, 5, 1.8, MF_LEADR_GRID_END_POINTS) == MF_OK);
        double i_sh, i_ex, i_one;
        CHECK(mf_leadr_diffuse_sh(&grid, &g, wo, sh, &i_sh) == MF_OK);
        CHECK(mf_leadr_diffuse(&grid, &g, wo, irr_lights, &lc, &i_ex) == MF_OK);
        CHECK(mf_leadr_diffuse(&grid, &g, wo, irr_one, NULL, &i_one) == MF_OK);
        CHECK(fabs(i_sh - i_ex) <= 3.0 / 32.0 * wsum * i_one + 1e-14);
        printf("diffuse, 2 lights, N=5: SH irradiance %.6f vs exact irradiance %.6f (relative %+.3f)\n", i_sh, i_ex,
               (i_sh - i_ex) / i_ex);
        double v;
        CHECK(mf_leadr_diffuse(&grid, &g, wo, NULL, NULL, &v) == MF_ERR_DOMAIN && isnan(v));
        CHECK(mf_leadr_diffuse_sh(&grid, &g, wo, NULL, &v) == MF_ERR_DOMAIN);
    }
    {
        /* Centred isotropic Beckmann vs Oren-Nayar, in trend.  Printed: the ratio to Lambert.
         * Asserted only what follows from the model on this grid:
         *  - alpha -> 0: Lambert (alpha = 1e-3: |ratio - 1| <= 1e-5; the deviation is O(sigma^2 tan^2)).
         *  - normal view and light: ratio = sum W wn.z < 1 (Lambda(z) = 0 for centred slopes).
         *  - backscatter (wi = wo) >= forward (wi = wo turned by pi about z) at equal angles:
         *    Cauchy-Schwarz on the grid, whose point reflection p -> -p maps one to the other.
         * ON's sigma (facet angle, radians) is taken as atan(alpha/sqrt 2), an approximate match. */
        const double alphas[4] = {1e-3, 0.2, 0.5, 1.0};
        printf("rough diffuse / Lambert, centred isotropic, N=33 lambda=4 cell centres:\n");
        printf("  alpha   th_i=th_o=0      60/60 back      60/60 forward    30/70 back\n");
        for (int a = 0; a < 4; ++a) {
            mf_gaussian_slopes g = mf_gaussian_from_beckmann(alphas[a], alphas[a]);
            double sig = atan(alphas[a] / MF_SQRT2);
            const double cfg[4][3] = {{0.0, 0.0, 0.0}, {60.0, 60.0, 0.0}, {60.0, 60.0, 180.0}, {30.0, 70.0, 0.0}};
            double ratio[4], on[4];
            for (int c = 0; c < 4; ++c) {
                double ti = cfg[c][0] * MF_PI / 180.0, to = cfg[c][1] * MF_PI / 180.0, dphi = cfg[c][2] * MF_PI / 180.0;
                mf_vec3 wo = mf_vec3_spherical(to, 0.3), wi = mf_vec3_spherical(ti, 0.3 + dphi);
                mf_leadr_light light = {wi, 1.0};
                lights_ctx lc = {&g, wo, &light, 1};
                double v = diffuse_cb(33, 4.0, MF_LEADR_GRID_CELL_CENTRES, &g, wo, irr_lights, &lc);
                ratio[c] = v / (cos(ti) / MF_PI);
                on[c] = oren_nayar_ratio(sig, ti, to, dphi);
            }
            printf("  %5.3f   %.4f (ON %.4f)  %.4f (ON %.4f)  %.4f (ON %.4f)  %.4f (ON %.4f)\n", alphas[a], ratio[0], on[0],
                   ratio[1], on[1], ratio[2], on[2], ratio[3], on[3]);
            if (a == 0)
                for (int c = 0; c < 4; ++c)
                    CHECK_ABS(ratio[c], 1.0, 1e-5);
            else {
                CHECK(ratio[0] < 1.0);
                CHECK(ratio[1] >= ratio[2]);
            }
        }
    }
    MF_TEST_MAIN_END();
}
