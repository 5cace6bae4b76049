/*
 * study_smith.c -- accuracy of the Smith Lambda forms mfkit ships (issue 6).
 *
 *   build-dir/analysis/study_smith [--nu-points N] [--grid G] [--out FILE]
 *
 * Two parts, one CSV (long format, a `part` column):
 *  walter    Beckmann Lambda: the exact erfc form (mf_smith_lambda_beckmann_nu) against Walter's
 *            rational approximation (mf_smith_lambda_beckmann_walter_nu, [Walter 2007, Eq. 27],
 *            clamped at 0, docs/math.md, correction C-L4) over nu in [1e-3, 10] (log spaced, N points): relative error
 *            of G1 = 1 / (1 + Lambda) and of Lambda (Lambda_walter = 0 for nu >= 1.6 while the
 *            exact Lambda is > 0, so its relative error is 1 there; G1's is what shading sees).
 *  gaussian  non-centred Gaussian slopes (isotropic, variance 0.125 = Beckmann alpha 0.5, mean
 *            slope (m, 0) with m in [-2, 2]): the closed form mf_smith_lambda_gaussian against
 *            Smith's construction relative to the mean plane (correction C-L2),
 *              Lambda = (1/a) integral_0^inf y p(a + y) dy,  a = (cot theta - mu(phi)) / sigma(phi),
 *            p the standard normal density, by adaptive Gauss-Kronrod (the integral of
 *            lib/src/mf_validate.c check_lambda, along the same independent path of angles), over
 *            a G x G grid of m and theta in [1, 89] deg, view azimuth phi = 0 (in the plane of the
 *            mean, where the mean tilts the mesosurface most).  Cells below the mesosurface
 *            (a <= 0: Lambda = +inf, correction C-L3), where cot theta - mu cancels (condition > 1e6) and far in the tail (a > 30: Lambda < 1e-198) have
 *            rel_err = nan.  The Walter form of the same nu is written beside it.
 *
 * Columns: part, nu, mean_slope, theta_deg, lambda_exact, lambda_ref, g1_exact, g1_ref,
 *          rel_err_g1, rel_err_lambda   (walter: ref = Walter; gaussian: ref = integral).
 * The first line is the provenance header (command, mfkit version, seed, UTC date); nothing here is
 * random (seed=none).  The CSV is generated: not committed.
 */
#define _POSIX_C_SOURCE 200809L
#include <mfkit/mfkit.h>

#include "study_header.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define DEG (MF_PI / 180.0)
#define GAUSS_VAR 0.125 /* Beckmann alpha 0.5: var = alpha^2 / 2 */

typedef struct {
    double a;
} smith_ctx;

static double smith_integrand(double y, void *user)
{
    const smith_ctx *s = user;
    double x = s->a + y;
    return y * exp(-0.5 * x * x) / sqrt(2.0 * MF_PI);
}

/* Smith's Lambda of the standard normal marginal at distance a (in units of sigma) from the mean. */
static double smith_lambda_integral(double a, int *failed)
{
    smith_ctx s = {a};
    mf_result r;
    static const double pts[3] = {1.0, 4.0, 16.0};
    double v = 0.0, lo = 0.0;
    for (int i = 0; i <= 3; ++i) {
        double hi = i < 3 ? pts[i] : INFINITY;
        if (mf_quad_adaptive(smith_integrand, &s, lo, hi, 0.0, 1e-13, MF_QUAD_MAX_INTERVALS, &r) != MF_OK)
            *failed = 1;
        v += r.val;
        lo = hi;
    }
    return v / a;
}

static void row(FILE *f, const char *part, double nu, double m, double theta_deg, double l_exact, double l_ref,
                double rel_lambda_override)
{
    double g_exact = 1.0 / (1.0 + l_exact), g_ref = 1.0 / (1.0 + l_ref);
    double rel_g = fabs(g_ref - g_exact) / g_exact;
    double rel_l = isnan(rel_lambda_override) ? fabs(l_ref - l_exact) / l_exact : rel_lambda_override;
    if (!isfinite(l_exact) || !isfinite(l_ref))
        rel_g = rel_l = NAN;
    fprintf(f, "%s,%.10g,%.10g,%.10g,%.17g,%.17g,%.17g,%.17g,%.6e,%.6e\n", part, nu, m, theta_deg, l_exact, l_ref,
            g_exact, g_ref, rel_g, rel_l);
}

int main(int argc, char **argv)
{
    int nu_points = 2000, grid = 81;
    const char *out_path = "notebooks_data/smith_lambda.csv";
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--nu-points") && i + 1 < argc)
            nu_points = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--grid") && i + 1 < argc)
            grid = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--out") && i + 1 < argc)
            out_path = argv[++i];
        else {
            fprintf(stderr, "usage: study_smith [--nu-points N] [--grid G] [--out FILE]\n");
            return 2;
        }
    }
    if (nu_points < 2 || grid < 2) {
        fprintf(stderr, "study_smith: --nu-points and --grid must be >= 2\n");
        return 2;
    }
    FILE *f = fopen(out_path, "w");
    if (!f) {
        fprintf(stderr, "study_smith: %s: %s\n", out_path, strerror(errno));
        return 3;
    }
    study_write_header(f, "study_smith", argc, argv, "none");
    fprintf(f, "part,nu,mean_slope,theta_deg,lambda_exact,lambda_ref,g1_exact,g1_ref,rel_err_g1,rel_err_lambda\n");

    /* 1. Walter's approximation over nu */
    double worst_w = 0.0, worst_nu = 0.0;
    for (int i = 0; i < nu_points; ++i) {
        double nu = 1e-3 * pow(1e4, (double)i / (nu_points - 1));
        double le = mf_smith_lambda_beckmann_nu(nu), lw = mf_smith_lambda_beckmann_walter_nu(nu);
        row(f, "walter", nu, NAN, NAN, le, lw, NAN);
        double rel = fabs(1.0 / (1.0 + lw) - 1.0 / (1.0 + le)) * (1.0 + le);
        if (rel > worst_w)
            worst_w = rel, worst_nu = nu;
    }

    /* 2. non-centred Gaussian closed form vs Smith's integral */
    double worst_g = 0.0, worst_m = 0.0, worst_t = 0.0;
    int failures = 0;
    for (int im = 0; im < grid; ++im)
        for (int it = 0; it < grid; ++it) {
            double m = -2.0 + 4.0 * im / (grid - 1);
            double theta_deg = 1.0 + 88.0 * it / (grid - 1);
            mf_gaussian_slopes g = {m, 0.0, GAUSS_VAR, GAUSS_VAR, 0.0};
            mf_vec3 w = mf_vec3_spherical(theta_deg * DEG, 0.0);
            double closed = mf_smith_lambda_gaussian(&g, w);
            /* independent path: angles, mu(phi = 0) = m, sigma(phi = 0) = sqrt(var) [Dupuy 2013, Eq. 14-15] */
            double a = (cos(theta_deg * DEG) / sin(theta_deg * DEG) - m) / sqrt(GAUSS_VAR);
            double nu = a / MF_SQRT2;
            /* skip cells below the mesosurface, where cot - mu cancels (condition > 1e6, as in
             * mf_validate.c check_lambda), and the far tail */
            double cot = cos(theta_deg * DEG) / sin(theta_deg * DEG);
            if (!(cot - m > 1e-6 * (fabs(cot) + fabs(m))) || a > 30.0) {
                fprintf(f, "gaussian,%.10g,%.10g,%.10g,%.17g,nan,nan,nan,nan,nan\n", nu, m, theta_deg, closed);
                continue;
            }
            int failed = 0;
            double ref = smith_lambda_integral(a, &failed);
            if (failed) {
                ++failures;
                ref = NAN;
            }
            row(f, "gaussian", nu, m, theta_deg, closed, ref, NAN);
            double rel = fabs(closed - ref) / ref;
            if (rel > worst_g)
                worst_g = rel, worst_m = m, worst_t = theta_deg;
        }
    if (fclose(f) != 0) {
        fprintf(stderr, "study_smith: %s: write failed\n", out_path);
        return 3;
    }
    printf("walter: max relative G1 error %.4e at nu = %.4g\n", worst_w, worst_nu);
    printf("gaussian: max relative Lambda error (closed form vs integral) %.3e at mean slope %.3g, theta %.3g deg"
           " (%d integrals did not converge)\n",
           worst_g, worst_m, worst_t, failures);
    printf("wrote %s\n", out_path);
    return failures ? 1 : 0;
}
