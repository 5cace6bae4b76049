/*
 * study_leadr_grid.c -- accuracy of LEADR's N x N Gaussian sampling grid (Sec. 5.1) as a function
 * of N and lambda, against converged Monte Carlo over the slope distribution (issue 5).
 *
 *   build-dir/analysis/study_leadr_grid [--samples M] [--seed S] [--out FILE]
 *
 * Quantities (white microfacets, no Fresnel):
 *   spec  Eq. 19, 22 / Algorithm 1 (mf_leadr_specular_env) under a smooth analytic sky
 *         L(wi) = 1 + 0.5 wi.z + 2 exp(8 (wi.sun - 1)) over the whole sphere;
 *   diff  Eq. 21, 23 / Algorithm 3 (mf_leadr_diffuse) with the exact masking-aware irradiance of
 *         Eq. 20 of two directional lights (mf_leadr_irradiance_lights).
 * Both are expectations over the slope distribution s ~ N(mean, Sigma) of a summand h(s) (the
 * one mf_leadr.c sums); the grid replaces the expectation by sum_jk W_j W_k h(s_jk).  The
 * reference is the same expectation by stratified Monte Carlo: M samples (default 2^23) of
 * s = mean + L z, z ~ N(0, I) by Box-Muller from jittered K x K strata of the unit square
 * (K = sqrt(M/2), two points per stratum, mf_pcg32), with its standard error from the
 * within-stratum differences.  The
 * program first checks that its summand reproduces the library's grid sums (to 1e-12).
 *
 * Cases: 3 slope statistics (centred isotropic Beckmann alpha = 0.3; non-centred anisotropic
 * correlated; rough non-centred) x 2 views (theta 30 and 70 deg), N = 3, 5, ..., 31, lambda =
 * 0.8 .. 5.0 step 0.05, both layouts (end points, cell centres: docs/math.md, correction C-L7).  Error of a setting
 * = mean over the 12 cases (3 statistics x 2 views x 2 quantities) of |grid - ref| / ref.
 *
 * Writes notebooks_data/leadr_grid_convergence.csv (or --out): '#' header lines (command, mfkit
 * version, seed, samples, date), then one row per (layout, N, lambda, stats, view, quantity).
 * Prints the best lambda per N and layout on stdout.  The CSV is generated: not committed.
 */
#define _POSIX_C_SOURCE 200809L
#include <mfkit/mfkit.h>

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#ifndef MFKIT_VERSION
#define MFKIT_VERSION "unknown"
#endif

#define N_STATS 3
#define N_VIEWS 2
#define N_QUANT 2
#define N_CASES (N_STATS * N_VIEWS * N_QUANT)
#define N_MIN 3
#define N_MAX 31
#define N_COUNT ((N_MAX - N_MIN) / 2 + 1)
#define LAMBDA_LO 0.8
#define LAMBDA_STEP 0.05
#define LAMBDA_COUNT 85 /* 0.8 .. 5.0 */

static const mf_gaussian_slopes k_stats[N_STATS] = {
    {0.0, 0.0, 0.045, 0.045, 0.0},   /* centred isotropic, Beckmann alpha = 0.3 */
    {0.2, -0.1, 0.08, 0.02, 0.01},   /* non-centred, anisotropic, correlated */
    {0.3, 0.3, 0.25, 0.25, -0.1}};   /* rough, non-centred, correlated */
static const char *const k_stat_names[N_STATS] = {"centred_iso_a0.3", "noncentred_aniso", "rough_noncentred"};
static const double k_view_theta_deg[N_VIEWS] = {30.0, 70.0};
static const double k_view_phi[N_VIEWS] = {0.0, 2.0};
static const char *const k_quant_names[N_QUANT] = {"spec_eq19", "diff_eq21"};

typedef struct scene {
    mf_vec3 sun;
    mf_leadr_light lights[2];
} scene;

static double sky(mf_vec3 wi, double solid_angle, void *user)
{
    (void)solid_angle;
    const scene *s = user;
    return 1.0 + 0.5 * wi.z + 2.0 * exp(8.0 * (mf_vec3_dot(wi, s->sun) - 1.0));
}

typedef struct irr_ctx {
    const scene *sc;
    const mf_gaussian_slopes *g;
    mf_vec3 wo;
} irr_ctx;

static double irradiance(mf_vec3 wn, void *user)
{
    const irr_ctx *c = user;
    return mf_leadr_irradiance_lights(c->g, c->wo, c->sc->lights, 2, wn);
}

/* The summands of mf_leadr_specular_env and mf_leadr_diffuse at slope s (without the weight and
 * the prefactor n_bar.g / n_bar.wo, which multiply both estimates alike). */
static void summand(const scene *sc, const mf_gaussian_slopes *g, mf_vec3 wo, double lo, double sx, double sy,
                    double out[2])
{
    out[0] = out[1] = 0.0;
    mf_vec3 wn = mf_normal_from_slope(sx, sy);
    double cos_no = mf_vec3_dot(wn, wo);
    if (!(cos_no > 0.0))
        return;
    irr_ctx ic = {sc, g, wo};
    out[1] = irradiance(wn, &ic) * cos_no / wn.z * MF_INV_PI;
    mf_vec3 wi = mf_vec3_sub(mf_vec3_scale(wn, 2.0 * cos_no), wo);
    double li = mf_smith_lambda_gaussian(g, wi);
    if (isinf(li))
        return;
    out[0] = sky(wi, 0.0, (void *)sc) * (cos_no / wn.z) / (1.0 + lo + li);
}

static void cholesky(const mf_gaussian_slopes *g, double *l00, double *l10, double *l11)
{
    *l00 = sqrt(g->var_x);
    *l10 = g->cov_xy / *l00;
    *l11 = sqrt(g->var_y - *l10 * *l10);
}

static mf_vec3 view(int iv)
{
    return mf_vec3_spherical(k_view_theta_deg[iv] * MF_PI / 180.0, k_view_phi[iv]);
}

static double prefactor(const mf_gaussian_slopes *g, mf_vec3 wo)
{
    mf_vec3 n = mf_gaussian_mesonormal(g);
    return n.z / mf_vec3_dot(n, wo);
}

static int grid_estimate(const scene *sc, const mf_leadr_grid *grid, int is, int iv, double out[2])
{
    const mf_gaussian_slopes *g = &k_stats[is];
    mf_vec3 wo = view(iv);
    mf_fresnel none = {MF_FRESNEL_NONE, 0.0, 0.0, 0.0};
    irr_ctx ic = {sc, g, wo};
    if (mf_leadr_specular_env(grid, g, none, wo, sky, (void *)sc, &out[0]) != MF_OK ||
        mf_leadr_diffuse(grid, g, wo, irradiance, &ic, &out[1]) != MF_OK)
        return -1;
    return 0;
}

int main(int argc, char **argv)
{
    long long samples = 1LL << 23;
    unsigned long long seed = 1;
    const char *out_path = "notebooks_data/leadr_grid_convergence.csv";
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--samples") && i + 1 < argc)
            samples = strtoll(argv[++i], NULL, 0);
        else if (!strcmp(argv[i], "--seed") && i + 1 < argc)
            seed = strtoull(argv[++i], NULL, 0);
        else if (!strcmp(argv[i], "--out") && i + 1 < argc)
            out_path = argv[++i];
        else {
            fprintf(stderr, "usage: study_leadr_grid [--samples M] [--seed S] [--out FILE]\n");
            return 2;
        }
    }
    if (samples < 2)
        samples = 2;
    scene sc;
    sc.sun = mf_vec3_normalize(mf_vec3_make(0.3, 0.2, 0.9));
    sc.lights[0].wi = mf_vec3_normalize(mf_vec3_make(0.5, 0.3, 0.81));
    sc.lights[0].irradiance = 1.0;
    sc.lights[1].wi = mf_vec3_normalize(mf_vec3_make(-0.6, 0.1, 0.5));
    sc.lights[1].irradiance = 0.5;

    /* 0. the summand above is the library's: a 9 x 9 grid summed both ways */
    {
        mf_leadr_grid gr;
        if (mf_leadr_grid_init(&gr, 9, 2.0, MF_LEADR_GRID_CELL_CENTRES) != MF_OK)
            return 1;
        for (int is = 0; is < N_STATS; ++is)
            for (int iv = 0; iv < N_VIEWS; ++iv) {
                const mf_gaussian_slopes *g = &k_stats[is];
                mf_vec3 wo = view(iv);
                double lo = mf_smith_lambda_gaussian(g, wo), lib[2], mine[2] = {0.0, 0.0}, h[2];
                if (grid_estimate(&sc, &gr, is, iv, lib) != 0)
                    return 1;
                double l00, l10, l11;
                cholesky(g, &l00, &l10, &l11);
                for (int j = 0; j < gr.n; ++j)
                    for (int k = 0; k < gr.n; ++k) {
                        summand(&sc, g, wo, lo, l00 * gr.p[j] + g->mean_x, l10 * gr.p[j] + l11 * gr.p[k] + g->mean_y,
                                h);
                        mine[0] += gr.w[j] * gr.w[k] * h[0];
                        mine[1] += gr.w[j] * gr.w[k] * h[1];
                    }
                for (int q = 0; q < 2; ++q) {
                    double v = prefactor(g, wo) * mine[q];
                    if (!(fabs(v - lib[q]) <= 1e-12 * fabs(lib[q]))) {
                        fprintf(stderr, "study_leadr_grid: summand mismatch (%s, view %d, %s): %.17g vs %.17g\n",
                                k_stat_names[is], iv, k_quant_names[q], v, lib[q]);
                        return 1;
                    }
                }
            }
    }

    /* 1. converged Monte Carlo references */
    double ref[N_STATS][N_VIEWS][N_QUANT], se[N_STATS][N_VIEWS][N_QUANT];
    for (int is = 0; is < N_STATS; ++is)
        for (int iv = 0; iv < N_VIEWS; ++iv) {
            const mf_gaussian_slopes *g = &k_stats[is];
            mf_vec3 wo = view(iv);
            double lo = mf_smith_lambda_gaussian(g, wo);
            double l00, l10, l11;
            cholesky(g, &l00, &l10, &l11);
            mf_pcg32 rng;
            mf_pcg32_seed(&rng, seed, (uint64_t)(is * N_VIEWS + iv));
            /* Stratified (jittered) Monte Carlo: Box-Muller maps the unit square onto the
             * standard normal plane preserving measure, so K x K strata of (u1, u2) are
             * equal-probability strata of z; two independent points per stratum give the
             * variance estimate var(I) = K^-4 sum_s (h1 - h2)^2 / 4. */
            long long kk = (long long)floor(sqrt((double)samples / 2.0));
            if (kk < 1)
                kk = 1;
            double sum[2] = {0, 0}, dev[2] = {0, 0};
            for (long long a = 0; a < kk; ++a)
                for (long long b = 0; b < kk; ++b) {
                    double hs[2][2];
                    for (int t = 0; t < 2; ++t) {
                        double u1 = ((double)a + mf_pcg32_next_double(&rng)) / (double)kk;
                        double u2 = ((double)b + mf_pcg32_next_double(&rng)) / (double)kk;
                        if (!(u1 > 0.0))
                            u1 = 0.5 / (double)kk;
                        double r = sqrt(-2.0 * log(u1)), ph = 2.0 * MF_PI * u2;
                        double z0 = r * cos(ph), z1 = r * sin(ph);
                        summand(&sc, g, wo, lo, l00 * z0 + g->mean_x, l10 * z0 + l11 * z1 + g->mean_y, hs[t]);
                    }
                    for (int q = 0; q < 2; ++q) {
                        sum[q] += 0.5 * (hs[0][q] + hs[1][q]);
                        dev[q] += 0.25 * (hs[0][q] - hs[1][q]) * (hs[0][q] - hs[1][q]);
                    }
                }
            double strata = (double)kk * (double)kk;
            double pf = prefactor(g, wo);
            for (int q = 0; q < 2; ++q) {
                ref[is][iv][q] = pf * sum[q] / strata;
                se[is][iv][q] = pf * sqrt(dev[q]) / strata;
            }
        }

    /* 2. the grid sweep */
    FILE *f = fopen(out_path, "w");
    if (!f) {
        fprintf(stderr, "study_leadr_grid: %s: %s\n", out_path, strerror(errno));
        return 3;
    }
    time_t now = time(NULL);
    char date[64];
    strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%SZ", gmtime(&now));
    fprintf(f, "# command: study_leadr_grid --samples %lld --seed %llu --out %s\n", samples, seed, out_path);
    fprintf(f, "# mfkit %s; seed %llu; stratified Monte Carlo samples per case %lld (2 per stratum); date %s\n", MFKIT_VERSION,
            seed, samples, date);
    fprintf(f, "# generated by analysis/study_leadr_grid.c (not committed); rel_err = |grid - ref| / ref\n");
    fprintf(f, "layout,N,lambda,stats,theta_o_deg,quantity,grid,ref,ref_se,rel_err\n");
    static const char *const layout_names[2] = {"end_points", "cell_centres"};
    double best_err[2][N_COUNT], best_lambda[2][N_COUNT], err_at_18[2][N_COUNT], best_worst[2][N_COUNT];
    for (int lay = 0; lay < 2; ++lay)
        for (int in = 0; in < N_COUNT; ++in) {
            int n = N_MIN + 2 * in;
            best_err[lay][in] = INFINITY;
            for (int il = 0; il < LAMBDA_COUNT; ++il) {
                double lambda = LAMBDA_LO + LAMBDA_STEP * il;
                mf_leadr_grid gr;
                if (mf_leadr_grid_init(&gr, n, lambda, (mf_leadr_grid_layout)lay) != MF_OK) {
                    fclose(f);
                    return 1;
                }
                double mean_err = 0.0, worst = 0.0;
                for (int is = 0; is < N_STATS; ++is)
                    for (int iv = 0; iv < N_VIEWS; ++iv) {
                        double est[2];
                        if (grid_estimate(&sc, &gr, is, iv, est) != 0) {
                            fclose(f);
                            return 1;
                        }
                        for (int q = 0; q < 2; ++q) {
                            double e = fabs(est[q] - ref[is][iv][q]) / ref[is][iv][q];
                            mean_err += e / N_CASES;
                            worst = fmax(worst, e);
                            fprintf(f, "%s,%d,%.2f,%s,%g,%s,%.17g,%.17g,%.6g,%.6g\n", layout_names[lay], n, lambda,
                                    k_stat_names[is], k_view_theta_deg[iv], k_quant_names[q], est[q],
                                    ref[is][iv][q], se[is][iv][q], e);
                        }
                    }
                if (mean_err < best_err[lay][in]) {
                    best_err[lay][in] = mean_err;
                    best_lambda[lay][in] = lambda;
                    best_worst[lay][in] = worst;
                }
                if (fabs(lambda - 1.8) < 1e-9)
                    err_at_18[lay][in] = mean_err;
            }
        }
    if (fclose(f) != 0) {
        fprintf(stderr, "study_leadr_grid: %s: write failed\n", out_path);
        return 3;
    }
    double max_rel_se = 0.0;
    for (int is = 0; is < N_STATS; ++is)
        for (int iv = 0; iv < N_VIEWS; ++iv)
            for (int q = 0; q < 2; ++q)
                max_rel_se = fmax(max_rel_se, se[is][iv][q] / ref[is][iv][q]);
    printf("Monte Carlo reference: %lld samples per case, seed %llu; largest relative standard error %.3g\n",
           samples, seed, max_rel_se);
    printf("error = mean over 12 cases of |grid - ref|/ref; errors below ~2x that are not resolved\n");
    for (int lay = 0; lay < 2; ++lay) {
        printf("\nlayout %s\n%4s %8s %12s %12s %14s\n", layout_names[lay], "N", "best_lam", "mean_err", "worst_err",
               "mean_err@1.8");
        for (int in = 0; in < N_COUNT; ++in)
            printf("%4d %8.2f %12.3e %12.3e %14.3e\n", N_MIN + 2 * in, best_lambda[lay][in], best_err[lay][in],
                   best_worst[lay][in], err_at_18[lay][in]);
    }
    printf("\nwrote %s\n", out_path);
    return 0;
}
