/*
 * study_albedo_rules.c -- the directional-albedo quadratures of mfkit against converged references
 * (issue 11: one albedo routine for models).
 *
 *   build-dir/analysis/study_albedo_rules [--n N] [--models a,b,...] [--out FILE]
 *
 * For every registered model (or --models) on a grid of alpha x theta_o (alpha 1e-4 .. 1, theta
 * 0 .. 89.95 deg), with N points per axis (default 64, the fitter's and the gate's):
 *   rule "model"  mf_model_albedo: the model's sampler, cubic grading u0 = 1 - (1 - t)^3, err =
 *                 |Q(N) - Q(N/2)| (the LTC fitter's magnitude and the gate's albedo check);
 *   rule "micro"  mf_brdf_microfacet_albedo (GGX and Beckmann only: same integrand, quartic grading
 *                 u0 = 1 - (1 - t)^4, err = max(|Q(N) - Q(N/2)|, |Q(N/2) - Q(N/4)|)), the rule of
 *                 `mfkit eval albedo`, study_furnace and the core validator.
 * Reference: mf_model_albedo at 1024 points per axis; for GGX and Beckmann also
 * mf_brdf_microfacet_albedo at 1024, and ref_spread = the difference of the two (an independent
 * check of the reference).  Columns: model, alpha, theta_deg, reference, ref_spread, rule, value,
 * error (value - reference), err_estimate, covered (|error| <= err_estimate).  Summary on stdout:
 * per model and rule the worst |error|, and how often the estimate covered it.
 */
#define _POSIX_C_SOURCE 200809L
#include <mfkit/mfkit.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DEG (MF_PI / 180.0)

static int selected(const char *list, const char *name)
{
    if (!list)
        return 1;
    size_t n = strlen(name);
    for (const char *p = list; (p = strstr(p, name)) != NULL; p += n)
        if ((p == list || p[-1] == ',') && (p[n] == ',' || p[n] == '\0'))
            return 1;
    return 0;
}

int main(int argc, char **argv)
{
    int n = 64;
    const char *models = NULL, *out_path = "notebooks_data/albedo_rules.csv";
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--n") && i + 1 < argc)
            n = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--models") && i + 1 < argc)
            models = argv[++i];
        else if (!strcmp(argv[i], "--out") && i + 1 < argc)
            out_path = argv[++i];
        else {
            fprintf(stderr, "usage: study_albedo_rules [--n N] [--models a,b,...] [--out FILE]\n");
            return 2;
        }
    }
    if (n < 32 || n > 512 || n % 32 != 0) {
        fprintf(stderr, "study_albedo_rules: --n must be a multiple of 32 in [32, 512]\n");
        return 2;
    }
    FILE *f = fopen(out_path, "w");
    if (!f) {
        perror(out_path);
        return 3;
    }
    fprintf(f, "model,alpha,theta_deg,reference,ref_spread,rule,value,error,err_estimate,covered\n");
    static const double alphas[] = {1e-4, 1e-3, 0.01, 0.04, 0.07, 0.11, 0.18, 0.3, 0.5, 0.75, 1.0};
    static const double thetas[] = {0.0, 30.0, 60.0, 75.0, 85.0, 89.0, 89.95};
    const int na = (int)(sizeof alphas / sizeof alphas[0]), nt = (int)(sizeof thetas / sizeof thetas[0]);
    for (const mf_brdf_model *const *pm = mf_brdf_models; *pm; ++pm) {
        const mf_brdf_model *m = *pm;
        if (!selected(models, m->name))
            continue;
        int micro = !strcmp(m->name, "ggx") || !strcmp(m->name, "beckmann");
        double worst[2] = {0.0, 0.0}, worst_spread = 0.0;
        int covered[2] = {0, 0}, cases = 0;
        for (int ia = 0; ia < na; ++ia)
            for (int it = 0; it < nt; ++it) {
                mf_brdf_params p = mf_brdf_params_iso(alphas[ia]);
                mf_vec3 wo = mf_vec3_make(sin(thetas[it] * DEG), 0.0, cos(thetas[it] * DEG));
                mf_result ref, q, r2, qm;
                if (mf_model_albedo(m, &p, wo, 1024, &ref) != MF_OK || mf_model_albedo(m, &p, wo, n, &q) != MF_OK) {
                    fprintf(stderr, "study_albedo_rules: %s alpha %g theta %g: quadrature failed\n", m->name,
                            alphas[ia], thetas[it]);
                    fclose(f);
                    return 1;
                }
                double spread = NAN;
                mf_microfacet mf = {mf_ndf_make(!strcmp(m->name, "ggx") ? MF_NDF_GGX : MF_NDF_BECKMANN, alphas[ia],
                                                alphas[ia]),
                                    MF_G2_JOINT,
                                    {MF_FRESNEL_NONE, 0.0, 1.0, 0.0}};
                if (micro) {
                    if (mf_brdf_microfacet_albedo(&mf, wo, 1024, &r2) != MF_OK ||
                        mf_brdf_microfacet_albedo(&mf, wo, n, &qm) != MF_OK) {
                        fclose(f);
                        return 1;
                    }
                    spread = r2.val - ref.val;
                    if (fabs(spread) > worst_spread)
                        worst_spread = fabs(spread);
                }
                ++cases;
                for (int rule = 0; rule < 1 + micro; ++rule) {
                    const mf_result *v = rule == 0 ? &q : &qm;
                    double e = v->val - ref.val;
                    int cov = fabs(e) <= v->err;
                    covered[rule] += cov;
                    if (fabs(e) > worst[rule])
                        worst[rule] = fabs(e);
                    fprintf(f, "%s,%.6g,%.6g,%.17g,%.3e,%s,%.17g,%.3e,%.3e,%d\n", m->name, alphas[ia], thetas[it],
                            ref.val, spread, rule == 0 ? "model" : "micro", v->val, e, v->err, cov);
                }
            }
        printf("%-10s n=%d  model rule: worst |error| %.2e, estimate covers %d/%d", m->name, n, worst[0], covered[0],
               cases);
        if (micro)
            printf(";  micro rule: worst %.2e, covers %d/%d;  reference spread %.1e", worst[1], covered[1], cases,
                   worst_spread);
        printf("\n");
    }
    if (fclose(f) != 0)
        return 3;
    return 0;
}
