/*
 * test_proxyfit.c -- the fitted GGX proxy roughness (lib mf_proxy.h) and its fit (fit
 * mf_proxyfit.h): accuracy over the domain against the exact alpha' and against
 * sqrt(alpha^2 + dh^2), the built-in limits, the analytic gradient, determinism of the fit,
 * that the fit reproduces the shipped coefficients, and the exported files.
 */
#define _POSIX_C_SOURCE 200809L
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

#include <mfkit/mf_filter.h>
#include <mfkit/mf_proxy.h>
#include <mfkit/fit/mf_proxyfit.h>
#include <mfkit/io/mf_table_io.h>

#include "mf_test.h"

static const double k_shipped[MF_PROXY_NCOEF] = {MF_PROXY_FIT_C, MF_PROXY_FIT_Q};

/* Max relative error of mf_proxy_alpha_fit over a 200 x 200 log grid of the default domain
 * (another grid than the fitter's, so it is an independent measurement). */
static void domain_errors(double *fit_max, double *sqrt_max)
{
    *fit_max = 0.0;
    *sqrt_max = 0.0;
    for (int j = 0; j < 200; ++j) {
        double d = pow(10.0, -3.0 + 4.0 * j / 199.0);
        for (int i = 0; i < 200; ++i) {
            double a = pow(10.0, -3.0 + 3.0 * i / 199.0);
            double ex = mf_filter_ggx_proxy_alpha(a, d);
            double ef = fabs(mf_proxy_alpha_fit(a, d) / ex - 1.0);
            double es = fabs(mf_filter_ggx_proxy_alpha_approx(a, d) / ex - 1.0);
            if (!(ef <= *fit_max))
                *fit_max = ef;
            if (!(es <= *sqrt_max))
                *sqrt_max = es;
        }
    }
}

static void test_accuracy(void)
{
    double fit_max, sqrt_max;
    domain_errors(&fit_max, &sqrt_max);
    printf("domain 200x200: fit max rel %.4g, sqrt max rel %.4g (ratio %.4g)\n", fit_max, sqrt_max,
           sqrt_max / fit_max);
    CHECK(fit_max <= MF_PROXY_FIT_MAX_REL_ERROR);
    CHECK(sqrt_max >= 10.0 * fit_max); /* the goal of issue 4 */
    CHECK(sqrt_max >= 1e4 * fit_max);  /* what the shipped form achieves (~2.5e5) */
    /* alpha'/alpha depends on dh/alpha only: the bound holds far outside the fitted domain. */
    for (int k = -12; k <= 12; k += 3) {
        double a = 1e-4, d = a * pow(10.0, k / 3.0);
        CHECK_REL(mf_proxy_alpha_fit(a, d), mf_filter_ggx_proxy_alpha(a, d), MF_PROXY_FIT_MAX_REL_ERROR);
        CHECK_REL(mf_proxy_alpha_fit(1e3 * a, 1e3 * d), mf_filter_ggx_proxy_alpha(1e3 * a, 1e3 * d),
                  MF_PROXY_FIT_MAX_REL_ERROR);
    }
}

/* The limits are in the form for any coefficients (shipped and arbitrary ones). */
static void test_limits(void)
{
    const double others[3][MF_PROXY_NCOEF] = {{MF_PROXY_FIT_C, MF_PROXY_FIT_Q}, {5.0, 3.0}, {-0.2, -0.9}};
    for (int k = 0; k < 3; ++k) {
        const double *c = others[k];
        /* dh = 0: alpha exactly */
        CHECK(mf_proxy_alpha_fit_coef(c, 0.37, 0.0) == 0.37);
        /* dh << alpha: (alpha'^2 - alpha^2)/dh^2 = R(x) -> 1/3, |R(x) - 1/3| = O(x) (x = 1e-12) */
        double a = 0.5, d = 0.5e-6;
        double f = mf_proxy_alpha_fit_coef(c, a, d);
        double r_small = mf_proxy_fit_r(c, d * d / (a * a + d * d), NULL);
        CHECK_ABS(r_small, 1.0 / 3.0, 1e-10);
        CHECK_REL(f, sqrt(a * a + d * d / 3.0), 4 * DBL_EPSILON);
        /* dh >> alpha: alpha' -> dh/sqrt(pi); R(x) - 1/pi = O(1 - x) = O(alpha^2/dh^2) */
        CHECK_ABS(mf_proxy_fit_r(c, 1.0, NULL), 1.0 / MF_PI, 2 * DBL_EPSILON);
        CHECK_REL(mf_proxy_alpha_fit_coef(c, 1e-9, 2.0), 2.0 / sqrt(MF_PI), 1e-15);
        CHECK_REL(mf_proxy_alpha_fit_coef(c, 1e-200, 3e100), 3e100 / sqrt(MF_PI), 4 * DBL_EPSILON);
    }
    /* the exact function has the same limits */
    CHECK_REL(mf_filter_ggx_proxy_alpha(1e-9, 2.0), 2.0 / sqrt(MF_PI), 1e-15);
    /* domain */
    CHECK(isnan(mf_proxy_alpha_fit(0.0, 0.1)));
    CHECK(isnan(mf_proxy_alpha_fit(0.1, -1e-3)));
    CHECK(isnan(mf_proxy_alpha_fit(NAN, 0.1)));
    CHECK(isnan(mf_proxy_alpha_fit(0.1, INFINITY)));
    const double bad_q[MF_PROXY_NCOEF] = {0.0, -1.0};
    CHECK(isnan(mf_proxy_alpha_fit_coef(bad_q, 0.1, 0.1)));
}

/* The analytic gradient of R used by the fit's Jacobian, against central differences. */
static void test_gradient(void)
{
    for (int ix = 0; ix <= 10; ++ix) {
        double x = ix / 10.0, g[MF_PROXY_NCOEF];
        mf_proxy_fit_r(k_shipped, x, g);
        for (int k = 0; k < MF_PROXY_NCOEF; ++k) {
            double p[MF_PROXY_NCOEF], m[MF_PROXY_NCOEF], h = 1e-6;
            memcpy(p, k_shipped, sizeof p);
            memcpy(m, k_shipped, sizeof m);
            p[k] += h;
            m[k] -= h;
            double fd = (mf_proxy_fit_r(p, x, NULL) - mf_proxy_fit_r(m, x, NULL)) / (2 * h);
            /* central difference: truncation O(h^2 R''') and rounding ~eps/h ~ 1e-10 */
            CHECK_ABS(g[k], fd, 1e-9);
        }
    }
}

static void test_fit(void)
{
    mf_proxyfit_result r1, r2;
    mf_table t;
    mf_status st = mf_proxyfit_run(NULL, &r1, &t);
    CHECK(st == MF_OK);
    CHECK(r1.solver.converged);
    printf("fit: c = %.17g, q = %.17g; max rel %.4g (all x %.4g), mean %.4g; sqrt max %.4g mean %.4g\n", r1.coef[0],
           r1.coef[1], r1.fit.max_rel, r1.fit.max_rel_all, r1.fit.mean_rel, r1.sqrt_approx.max_rel,
           r1.sqrt_approx.mean_rel);
    /* The command reproduces the shipped constants.  Ceres stops at the gradient tolerance 1e-12;
     * with the cost's curvature (J^T J >= ~1e-4 here) that moves the parameters by < 1e-8, so a
     * relative 1e-7 covers other machines and Ceres builds; the same binary gives them bitwise. */
    CHECK_REL(r1.coef[0], MF_PROXY_FIT_C, 1e-7);
    CHECK_REL(r1.coef[1], MF_PROXY_FIT_Q, 1e-7);
    /* the reported bound and the 10x goal */
    CHECK(r1.fit.max_rel_all <= MF_PROXY_FIT_MAX_REL_ERROR);
    CHECK(r1.fit.max_rel <= r1.fit.max_rel_all * (1 + 1e-9) + 1e-15);
    CHECK(r1.sqrt_approx.max_rel >= 10.0 * r1.fit.max_rel);
    CHECK(r1.sqrt_approx.mean_rel >= 10.0 * r1.fit.mean_rel);
    CHECK_REL(r1.sqrt_approx.max_rel_all, sqrt(MF_PI) - 1.0, 1e-6); /* sqrt: sqrt(pi) - 1 at dh >> alpha */
    /* determinism */
    st = mf_proxyfit_run(NULL, &r2, NULL);
    CHECK(st == MF_OK);
    CHECK(memcmp(r1.coef, r2.coef, sizeof r1.coef) == 0);
    CHECK(r1.fit.max_rel == r2.fit.max_rel && r1.fit.mean_rel == r2.fit.mean_rel);

    /* table content and export */
    CHECK(t.naxes == 2 && t.nfields == 5 && t.axes[0].size == 64 && t.axes[1].size == 64);
    int fe = mf_table_field(&t, "alpha_eff"), ff = mf_table_field(&t, "alpha_eff_fit");
    CHECK(fe >= 0 && ff >= 0);
    const char *dir = "test_proxyfit_out";
    mkdir(dir, 0777);
    char msg[1024];
    st = mf_proxyfit_write(dir, NULL, &r1, &t, "test_proxyfit", msg, sizeof msg);
    CHECK(st == MF_OK);
    if (st != MF_OK)
        fprintf(stderr, "%s\n", msg);
    mf_table back;
    st = mf_table_read("test_proxyfit_out/ggx_proxy_table.json", &back, NULL, msg, sizeof msg);
    CHECK(st == MF_OK);
    if (st == MF_OK) {
        int idx[2] = {17, 40};
        const double *a = mf_table_record(&t, idx), *b = mf_table_record(&back, idx);
        for (int f = 0; f < 5; ++f)
            CHECK(b[f] == (double)(float)a[f]);
        mf_table_free(&back);
    }
    const char *names[] = {"ggx_proxy_table.h", "ggx_proxy_fit.h", "ggx_proxy_fit.glsl", "ggx_proxy_fit.json"};
    for (int i = 0; i < 4; ++i) {
        char path[256];
        snprintf(path, sizeof path, "%s/%s", dir, names[i]);
        FILE *fp = fopen(path, "r");
        CHECK(fp != NULL);
        if (fp)
            fclose(fp);
    }
    /* bad options and a missing directory */
    mf_proxyfit_options o;
    mf_proxyfit_options_default(&o);
    o.size = 1;
    CHECK(mf_proxyfit_run(&o, &r2, NULL) == MF_ERR_DOMAIN);
    CHECK(mf_proxyfit_write("test_proxyfit_out/no/such/dir", NULL, &r1, &t, NULL, msg, sizeof msg) == MF_ERR_IO);
    mf_table_free(&t);
}

int main(void)
{
    test_accuracy();
    test_limits();
    test_gradient();
    test_fit();
    MF_TEST_MAIN_END();
}
