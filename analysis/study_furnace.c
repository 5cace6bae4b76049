/*
 * study_furnace.c -- white furnace: directional albedo of every BRDF over (theta_o, alpha) (issue 6).
 *
 *   build-dir/analysis/study_furnace [--thetas T] [--alphas A] [--quad N] [--strata K] [--seed S]
 *                                    [--out FILE]
 *
 * Directional albedo rho(wo) = integral over the hemisphere of f(wo, wi) wi.z dwi (single
 * scattering; a white furnace, radiance 1 from every direction, returns rho):
 *  - source "microfacet": GGX and Beckmann Walter microfacet BRDFs, height-correlated G2
 *    [Walter 2007, Eq. 20; Heitz 2014], without Fresnel (F = 1: the energy lost to single
 *    scattering is 1 - rho) and with Schlick F0 = 0.04 [Schlick 1994, Eq. 15], by the deterministic
 *    product quadrature mf_brdf_microfacet_albedo (N x N points; err is its own error estimate);
 *  - source "model": each LTC target model of mf_model.h (ggx, beckmann, lambert, leadr-diffuse, oren-nayar, eon,
 *    disney, charlie; F = 1), by stratified Monte Carlo (K x K jittered strata of the unit square,
 *    two points per stratum, pcg32 with the given seed) with a one-sample mixture of the model's
 *    own sampler (probability 7/8) and the cosine hemisphere (1/8): pdf = (7 p_model + p_cos) / 8,
 *    unbiased wherever f > 0); err is the standard error from the within-stratum differences.
 * Grid: theta_o = 0 .. 89 deg (T points), alpha = 0.01 .. 1 (A points, linear); alpha is the GGX /
 * Beckmann roughness, and each model's own roughness parameter (mf_model.h).
 *
 * Columns: source, brdf, fresnel, theta_deg, alpha, albedo, err.  First line: provenance header.
 * The CSV is generated: not committed.
 */
#define _POSIX_C_SOURCE 200809L
#include <mfkit/mfkit.h>

#include "study_header.h"

#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define DEG (MF_PI / 180.0)
/* probability of the model's own sampler in the mixture (the rest: cosine hemisphere) */
#define MODEL_WEIGHT 0.875

/* One sample of the mixture estimator f cos / pdf. */
static double mixture_sample(const mf_brdf_model *m, double alpha, mf_vec3 wo, const double u[2], double pick)
{
    mf_vec3 wi;
    double pdf_model = 0.0;
    mf_brdf_params p = mf_brdf_params_iso(alpha);
    if (m->sample && pick < MODEL_WEIGHT)
        wi = m->sample(m, &p, wo, u, &pdf_model);
    else
        wi = mf_sample_cosine_hemisphere(u);
    if (!mf_vec3_isfinite(wi) || !(wi.z > 0.0))
        return 0.0;
    double pdf;
    if (m->sample) {
        pdf_model = m->pdf(m, &p, wo, wi);
        pdf = MODEL_WEIGHT * pdf_model + (1.0 - MODEL_WEIGHT) * mf_pdf_cosine_hemisphere(wi);
    } else {
        pdf = mf_pdf_cosine_hemisphere(wi);
    }
    if (!(pdf > 0.0))
        return 0.0;
    return m->eval_cos(m, &p, wo, wi) / pdf;
}

int main(int argc, char **argv)
{
    int n_theta = 30, n_alpha = 30, quad = 32, strata = 32;
    unsigned long long seed = 1;
    const char *out_path = "notebooks_data/furnace.csv";
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--thetas") && i + 1 < argc)
            n_theta = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--alphas") && i + 1 < argc)
            n_alpha = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--quad") && i + 1 < argc)
            quad = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--strata") && i + 1 < argc)
            strata = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--seed") && i + 1 < argc)
            seed = strtoull(argv[++i], NULL, 0);
        else if (!strcmp(argv[i], "--out") && i + 1 < argc)
            out_path = argv[++i];
        else {
            fprintf(stderr, "usage: study_furnace [--thetas T] [--alphas A] [--quad N] [--strata K] [--seed S] "
                            "[--out FILE]\n");
            return 2;
        }
    }
    if (n_theta < 2 || n_alpha < 2 || strata < 1 || quad < 8 || quad % 8 != 0) {
        fprintf(stderr, "study_furnace: need --thetas, --alphas >= 2, --strata >= 1, --quad a multiple of 8\n");
        return 2;
    }
    FILE *f = fopen(out_path, "w");
    if (!f) {
        fprintf(stderr, "study_furnace: %s: %s\n", out_path, strerror(errno));
        return 3;
    }
    char seed_text[32];
    snprintf(seed_text, sizeof seed_text, "%llu", seed);
    study_write_header(f, "study_furnace", argc, argv, seed_text);
    fprintf(f, "source,brdf,fresnel,theta_deg,alpha,albedo,err\n");

    /* 1. microfacet BRDFs by deterministic quadrature */
    static const mf_ndf_type k_ndfs[2] = {MF_NDF_GGX, MF_NDF_BECKMANN};
    const mf_fresnel fresnels[2] = {{MF_FRESNEL_NONE, 0.0, 0.0, 0.0}, {MF_FRESNEL_SCHLICK, 0.04, 0.0, 0.0}};
    static const char *const k_fresnel_names[2] = {"none", "schlick_0.04"};
    double min_white[2] = {1.0, 1.0};
    for (int in = 0; in < 2; ++in)
        for (int ifr = 0; ifr < 2; ++ifr)
            for (int ia = 0; ia < n_alpha; ++ia)
                for (int it = 0; it < n_theta; ++it) {
                    double alpha = 0.01 + 0.99 * ia / (n_alpha - 1);
                    double theta_deg = 89.0 * it / (n_theta - 1);
                    mf_microfacet m = {mf_ndf_make(k_ndfs[in], alpha, alpha), MF_G2_JOINT, fresnels[ifr]};
                    mf_result r;
                    mf_status st = mf_brdf_microfacet_albedo(&m, mf_vec3_spherical(theta_deg * DEG, 0.0), quad, &r);
                    if (st != MF_OK) {
                        fprintf(stderr, "study_furnace: albedo %s alpha %g theta %g: %s\n", mf_ndf_type_name(k_ndfs[in]),
                                alpha, theta_deg, mf_status_str(st));
                        fclose(f);
                        return 1;
                    }
                    fprintf(f, "microfacet,%s,%s,%.10g,%.10g,%.17g,%.3e\n", mf_ndf_type_name(k_ndfs[in]),
                            k_fresnel_names[ifr], theta_deg, alpha, r.val, r.err);
                    if (ifr == 0 && r.val < min_white[in])
                        min_white[in] = r.val;
                }

    /* 2. the LTC target models by stratified Monte Carlo */
    int model_index = 0;
    for (const mf_brdf_model *const *pm = mf_brdf_models; *pm; ++pm, ++model_index) {
        const mf_brdf_model *m = *pm;
        double lo = INFINITY, hi = -INFINITY;
        for (int ia = 0; ia < n_alpha; ++ia)
            for (int it = 0; it < n_theta; ++it) {
                double alpha = 0.01 + 0.99 * ia / (n_alpha - 1);
                double theta_deg = 89.0 * it / (n_theta - 1);
                mf_vec3 wo = mf_vec3_spherical(theta_deg * DEG, 0.0);
                mf_pcg32 rng;
                mf_pcg32_seed(&rng, seed, (uint64_t)((model_index * n_alpha + ia) * n_theta + it));
                double sum = 0.0, dev = 0.0;
                for (int a = 0; a < strata; ++a)
                    for (int b = 0; b < strata; ++b) {
                        double h[2];
                        for (int t = 0; t < 2; ++t) {
                            double u[2] = {(a + mf_pcg32_next_double(&rng)) / strata,
                                           (b + mf_pcg32_next_double(&rng)) / strata};
                            h[t] = mixture_sample(m, alpha, wo, u, mf_pcg32_next_double(&rng));
                        }
                        sum += 0.5 * (h[0] + h[1]);
                        dev += 0.25 * (h[0] - h[1]) * (h[0] - h[1]);
                    }
                double k2 = (double)strata * strata;
                double val = sum / k2, se = sqrt(dev) / k2;
                fprintf(f, "model,%s,none,%.10g,%.10g,%.17g,%.3e\n", m->name, theta_deg, alpha, val, se);
                lo = val < lo ? val : lo;
                hi = val > hi ? val : hi;
            }
        printf("model %-10s albedo range [%.4f, %.4f]\n", m->name, lo, hi);
    }
    if (fclose(f) != 0) {
        fprintf(stderr, "study_furnace: %s: write failed\n", out_path);
        return 3;
    }
    printf("microfacet (F = 1): min albedo ggx %.4f, beckmann %.4f\n", min_white[0], min_white[1]);
    printf("wrote %s\n", out_path);
    return 0;
}
