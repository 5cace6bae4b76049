/* test_quad.c -- Gauss-Legendre rules and adaptive Gauss-Kronrod (mf_quad.h). */
#include "mf_test.h"
#include "mfkit/mf_quad.h"

#include <float.h>

static double f_exp_neg(double x, void *u) { (void)u; return exp(-x); }
static double f_sqrt(double x, void *u) { (void)u; return sqrt(x); }
static double f_lorentz(double x, void *u) { double a = *(double *)u; return a / (MF_PI * (x * x + a * a)); }
static double f_nan(double x, void *u) { (void)u; (void)x; return NAN; }

int main(void)
{
    /* n-point Gauss-Legendre integrates x^k exactly for k <= 2n - 1 (to rounding: 64 eps
     * for n up to 64, the weights' and nodes' own rounding summed over n terms). */
    static double x[1024], w[1024];
    int orders[] = {1, 2, 3, 4, 5, 8, 16, 33, 64};
    for (int oi = 0; oi < 9; ++oi) {
        int n = orders[oi];
        CHECK(mf_quad_gauss_legendre(n, x, w) == MF_OK);
        for (int k = 0; k <= 2 * n - 1 && k <= 40; ++k) {
            double s = 0.0;
            for (int i = 0; i < n; ++i)
                s += w[i] * pow(x[i], k);
            double exact = (k % 2) ? 0.0 : 2.0 / (k + 1);
            CHECK_ABS(s, exact, 64 * DBL_EPSILON);
        }
        for (int i = 1; i < n; ++i)
            CHECK(x[i] > x[i - 1]);
    }
    CHECK(mf_quad_gauss_legendre(1024, x, w) == MF_OK);
    double s = 0.0;
    for (int i = 0; i < 1024; ++i)
        s += w[i];
    CHECK_ABS(s, 2.0, 1e-13); /* 1024 weights summed: ~1024 eps */
    CHECK(mf_quad_gauss_legendre(0, x, w) == MF_ERR_DOMAIN);
    CHECK(mf_quad_gauss_legendre(1025, x, w) == MF_ERR_DOMAIN);

    /* adaptive: semi-infinite, endpoint singularity in the derivative, narrow peak */
    mf_result r;
    CHECK(mf_quad_adaptive(f_exp_neg, NULL, 0.0, INFINITY, 0.0, 1e-12, 200, &r) == MF_OK);
    CHECK_REL(r.val, 1.0, 1e-12);
    CHECK(mf_quad_adaptive(f_sqrt, NULL, 0.0, 1.0, 0.0, 1e-10, 200, &r) == MF_OK);
    CHECK_REL(r.val, 2.0 / 3.0, 1e-10);
    double a = 1e-4; /* Lorentzian of width 1e-4 on [-1, 1]: (2/pi) atan(1/a) */
    CHECK(mf_quad_adaptive(f_lorentz, &a, -1.0, 1.0, 0.0, 1e-10, 500, &r) == MF_OK);
    CHECK_REL(r.val, 2.0 / MF_PI * atan(1.0 / a), 1e-10);
    /* the error estimate is honest: the true error is below it */
    CHECK(fabs(r.val - 2.0 / MF_PI * atan(1.0 / a)) <= r.err + 1e-15);
    /* too few intervals -> NO_CONVERGENCE with the best value still returned */
    CHECK(mf_quad_adaptive(f_lorentz, &a, -1.0, 1.0, 0.0, 1e-14, 2, &r) == MF_ERR_NO_CONVERGENCE);
    CHECK(isfinite(r.val));
    /* bad input */
    CHECK(mf_quad_adaptive(f_nan, NULL, 0.0, 1.0, 0.0, 1e-10, 10, &r) == MF_ERR_DOMAIN);
    CHECK(isnan(r.val));
    CHECK(mf_quad_adaptive(f_sqrt, NULL, 1.0, 0.0, 0.0, 1e-10, 10, &r) == MF_ERR_DOMAIN);
    CHECK(mf_quad_adaptive(f_sqrt, NULL, 0.0, 1.0, 0.0, 1e-10, MF_QUAD_MAX_INTERVALS + 1, &r) == MF_ERR_DOMAIN);
    MF_TEST_MAIN_END();
}
