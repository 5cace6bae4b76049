/*
 * study_proxy.c -- the GGX rectangle integral and the GGX proxy roughnesses over (alpha, dh) (issue 6).
 *
 *   build-dir/analysis/study_proxy [--grid G] [--out FILE]
 *
 * For an isotropic GGX of roughness alpha filtered over the square of full width dh centred on the
 * peak [Kaplanyan 2016, Eq. 16-20]:
 *  rect   the mean of P22 over the square: mf_filter_ggx_rect_mean (cancellation-free, docs/math.md, correction C-K1,
 *         K2) and the plain four-term difference of the antiderivative
 *         (mf_filter_ggx_rect_antiderivative, App. A) against nested adaptive Gauss-Kronrod of P22
 *         itself (one quadrant, by symmetry; split at alpha 10^k), at relative 1e-13 per level;
 *  proxy  alpha' from the exact peak condition (mf_filter_ggx_proxy_alpha, correction C-K3) against the
 *         paper's sqrt(alpha^2 + dh^2) (mf_filter_ggx_proxy_alpha_approx) and mfkit's fitted form
 *         (mf_proxy_alpha_fit): relative error of alpha'.
 * Grid: G x G, alpha in [1e-3, 1] and dh in [1e-3, 10], both log spaced.
 *
 * Columns: alpha, dh, x (= dh^2 / (alpha^2 + dh^2)), rect_mean, rect_naive, rect_ref, rect_ref_err,
 *          rel_err_rect, rel_err_rect_naive, alpha_exact, alpha_approx, alpha_fit, rel_err_approx,
 *          rel_err_fit.  First line: provenance header.  The CSV is generated: not committed.
 */
#define _POSIX_C_SOURCE 200809L
#include <mfkit/mfkit.h>

#include "study_header.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

typedef struct {
    mf_ndf ndf;
    double s, hi;
    int failed;
    double err;
} rect_ctx;

static double p22_inner(double t, void *user)
{
    const rect_ctx *c = user;
    return mf_ndf_p22(c->ndf, c->s, t);
}

/* integral over [0, hi] of fn, split at alpha 10^k (k = -2..2) inside the interval */
static double integrate_split(mf_fn1 fn, void *user, double hi, double alpha, int *failed, double *err)
{
    static const double k_scales[] = {0.01, 0.1, 1.0, 10.0, 100.0};
    double lo = 0.0, v = 0.0;
    for (int i = 0; i <= 5; ++i) {
        double b = i < 5 ? k_scales[i] * alpha : hi;
        if (b > hi)
            b = hi;
        if (b <= lo)
            continue;
        mf_result r;
        if (mf_quad_adaptive(fn, user, lo, b, 0.0, 1e-13, MF_QUAD_MAX_INTERVALS, &r) != MF_OK)
            *failed = 1;
        v += r.val;
        *err += r.err;
        lo = b;
    }
    return v;
}

static double p22_outer(double s, void *user)
{
    rect_ctx *c = user;
    c->s = s;
    double inner_err = 0.0;
    return integrate_split(p22_inner, c, c->hi, c->ndf.alpha_y, &c->failed, &inner_err);
}

int main(int argc, char **argv)
{
    int grid = 61;
    const char *out_path = "notebooks_data/ggx_proxy.csv";
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--grid") && i + 1 < argc)
            grid = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--out") && i + 1 < argc)
            out_path = argv[++i];
        else {
            fprintf(stderr, "usage: study_proxy [--grid G] [--out FILE]\n");
            return 2;
        }
    }
    if (grid < 2) {
        fprintf(stderr, "study_proxy: --grid must be >= 2\n");
        return 2;
    }
    FILE *f = fopen(out_path, "w");
    if (!f) {
        fprintf(stderr, "study_proxy: %s: %s\n", out_path, strerror(errno));
        return 3;
    }
    study_write_header(f, "study_proxy", argc, argv, "none");
    fprintf(f, "alpha,dh,x,rect_mean,rect_naive,rect_ref,rect_ref_err,rel_err_rect,rel_err_rect_naive,alpha_exact,"
               "alpha_approx,alpha_fit,rel_err_approx,rel_err_fit\n");
    double worst[4] = {0, 0, 0, 0};
    int failures = 0;
    for (int ia = 0; ia < grid; ++ia)
        for (int id = 0; id < grid; ++id) {
            double alpha = 1e-3 * pow(1e3, (double)ia / (grid - 1));
            double dh = 1e-3 * pow(1e4, (double)id / (grid - 1));
            double h = 0.5 * dh;
            /* reference: 4 x the quadrant [0, h]^2, divided by the area dh^2 */
            rect_ctx c = {mf_ndf_make(MF_NDF_GGX, alpha, alpha), 0.0, h, 0, 0.0};
            double outer_err = 0.0;
            double quadrant = integrate_split(p22_outer, &c, h, alpha, &c.failed, &outer_err);
            double ref = quadrant / (h * h), ref_err = outer_err / (h * h);
            if (c.failed)
                ++failures;
            double mean = mf_filter_ggx_rect_mean(alpha, alpha, 0.0, 0.0, dh, dh);
            double naive = (mf_filter_ggx_rect_antiderivative(alpha, alpha, h, h) -
                            mf_filter_ggx_rect_antiderivative(alpha, alpha, -h, h) -
                            mf_filter_ggx_rect_antiderivative(alpha, alpha, h, -h) +
                            mf_filter_ggx_rect_antiderivative(alpha, alpha, -h, -h)) /
                           (dh * dh);
            double ex = mf_filter_ggx_proxy_alpha(alpha, dh);
            double ap = mf_filter_ggx_proxy_alpha_approx(alpha, dh);
            double fi = mf_proxy_alpha_fit(alpha, dh);
            double rel[4] = {fabs(mean - ref) / ref, fabs(naive - ref) / ref, fabs(ap - ex) / ex, fabs(fi - ex) / ex};
            if (c.failed)
                rel[0] = rel[1] = NAN;
            for (int k = 0; k < 4; ++k)
                if (rel[k] > worst[k])
                    worst[k] = rel[k];
            fprintf(f, "%.10g,%.10g,%.17g,%.17g,%.17g,%.17g,%.3e,%.6e,%.6e,%.17g,%.17g,%.17g,%.6e,%.6e\n", alpha, dh,
                    dh * dh / (alpha * alpha + dh * dh), mean, naive, ref, ref_err, rel[0], rel[1], ex, ap, fi, rel[2],
                    rel[3]);
        }
    if (fclose(f) != 0) {
        fprintf(stderr, "study_proxy: %s: write failed\n", out_path);
        return 3;
    }
    printf("rect mean vs quadrature: max rel %.3e (plain antiderivative difference: %.3e)\n", worst[0], worst[1]);
    printf("proxy alpha': sqrt(alpha^2 + dh^2) max rel %.4f, fitted form max rel %.3e\n", worst[2], worst[3]);
    printf("wrote %s (%d reference integrals did not converge)\n", out_path, failures);
    return failures ? 1 : 0;
}
