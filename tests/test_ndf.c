/* test_ndf.c -- GGX, Beckmann, non-centred Gaussian NDFs (mf_ndf.h), with docs/math.md, corrections C-N1, C-N2, C-L6. */
#include "mf_test.h"
#include "mfkit/mf_ndf.h"
#include "mfkit/mf_quad.h"
#include "mfkit/mf_rng.h"

#include <float.h>

/* 2D Gauss-Legendre product rule of P22 over the box mean +- 12 sd (the Gaussian mass outside
 * is < 1e-30), 40 panels of 16 points per axis: converged to rounding (~1e-14). */
static double integrate_p22_box(const mf_gaussian_slopes *g)
{
    double x[16], w[16];
    if (mf_quad_gauss_legendre(16, x, w) != MF_OK)
        return NAN;
    double sx = sqrt(g->var_x), sy = sqrt(g->var_y), sum = 0.0;
    const int panels = 40;
    for (int pi = 0; pi < panels; ++pi)
        for (int i = 0; i < 16; ++i) {
            double hx = 24.0 * sx / panels;
            double px = g->mean_x - 12.0 * sx + hx * (pi + 0.5 * (x[i] + 1.0));
            for (int pj = 0; pj < panels; ++pj)
                for (int j = 0; j < 16; ++j) {
                    double hy = 24.0 * sy / panels;
                    double py = g->mean_y - 12.0 * sy + hy * (pj + 0.5 * (x[j] + 1.0));
                    sum += 0.25 * hx * hy * w[i] * w[j] * mf_gaussian_p22(g, px, py);
                }
        }
    return sum;
}

int main(void)
{
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, mf_test_seed(2026), 3);
    const mf_ndf_type types[2] = {MF_NDF_GGX, MF_NDF_BECKMANN};
    /* D(m) = P22(slope(m)) / m.z^4 [Dupuy 2013, Eq. 10]: two code paths (direction form and
     * slope form) agree to 32 eps (a dozen roundings each, exp amplifies by its argument <~ 10). */
    for (int t = 0; t < 2; ++t)
        for (int k = 0; k < 2000; ++k) {
            double ax = exp(-9.0 * mf_pcg32_next_double(&rng)), ay = exp(-9.0 * mf_pcg32_next_double(&rng));
            mf_ndf ndf = mf_ndf_make(types[t], ax, ay);
            double u = mf_pcg32_next_double(&rng), phi = 2 * MF_PI * mf_pcg32_next_double(&rng);
            double tan_t = 3.0 * fmax(ax, ay) * u; /* within a few alphas of the peak */
            double slope[2] = {tan_t * cos(phi), tan_t * sin(phi)};
            mf_vec3 m = mf_normal_from_slope(slope[0], slope[1]);
            double z4 = m.z * m.z * m.z * m.z;
            double d = mf_ndf_d(ndf, m), p = mf_ndf_p22(ndf, slope[0], slope[1]);
            if (p < 1e-290)
                continue; /* subnormal results carry no relative precision */
            /* Beckmann's exp(-t) multiplies the relative rounding of t by t */
            double t_exp = slope[0] * slope[0] / (ax * ax) + slope[1] * slope[1] / (ay * ay);
            CHECK_REL(d * z4, p, 64 * DBL_EPSILON * (1.0 + t_exp));
            if (types[t] == MF_NDF_BECKMANN) { /* Beckmann = centred Gaussian with var = alpha^2 / 2 */
                mf_gaussian_slopes g = mf_gaussian_from_beckmann(ax, ay);
                CHECK_REL(mf_gaussian_d(&g, m), d, 64 * DBL_EPSILON * (1.0 + t_exp));
            }
        }
    /* peak values: GGX and Beckmann 1 / (pi ax ay) at m = z, for alpha down to 1e-4 */
    CHECK_REL(mf_ndf_d(mf_ndf_make(MF_NDF_GGX, 1e-4, 1e-4), mf_vec3_make(0, 0, 1)), 1.0 / (MF_PI * 1e-8), 4 * DBL_EPSILON);
    CHECK_REL(mf_ndf_d(mf_ndf_make(MF_NDF_BECKMANN, 1e-4, 2e-4), mf_vec3_make(0, 0, 1)), 1.0 / (MF_PI * 2e-8),
              4 * DBL_EPSILON);
    /* grazing and below-horizon micro-normals: finite, 0 below */
    mf_vec3 graze = mf_vec3_make(sqrt(1 - 1e-16), 0, 1e-8);
    CHECK(mf_ndf_d(mf_ndf_make(MF_NDF_GGX, 1e-4, 1e-4), graze) >= 0.0);
    CHECK(isfinite(mf_ndf_d(mf_ndf_make(MF_NDF_GGX, 1e-4, 1e-4), graze)));
    CHECK(mf_ndf_d(mf_ndf_make(MF_NDF_BECKMANN, 1e-4, 1e-4), graze) == 0.0);
    CHECK(mf_ndf_d(mf_ndf_make(MF_NDF_BECKMANN, 1.0, 1.0), mf_vec3_make(1.0, 0, 1e-200)) == 0.0); /* z^4 underflows */
    CHECK(mf_ndf_d(mf_ndf_make(MF_NDF_GGX, 0.3, 0.3), mf_vec3_make(0, 0.6, -0.8)) == 0.0);
    /* outside the domain: NaN, not a silent clamp */
    CHECK(isnan(mf_ndf_d(mf_ndf_make(MF_NDF_GGX, 0.0, 0.3), mf_vec3_make(0, 0, 1))));
    CHECK(isnan(mf_ndf_d(mf_ndf_make(MF_NDF_GGX, -0.1, 0.3), mf_vec3_make(0, 0, 1))));
    CHECK(isnan(mf_ndf_p22(mf_ndf_make(MF_NDF_BECKMANN, NAN, 0.3), 0, 0)));
    CHECK(isnan(mf_ndf_d(mf_ndf_make(MF_NDF_GGX, 0.3, 0.3), mf_vec3_make(NAN, 0, 1))));

    /* correction C-N1: LEAN Eq. 1 prints the normalisation 1/(sqrt(2 pi)|S|); the 2D Gaussian needs
     * 1/(2 pi sqrt|S|).  Our P22 integrates to 1 (box quadrature, 1e-12: converged rule) and its
     * peak is 1/(2 pi sqrt|S|); the printed peak would integrate to 125.33 for S = 0.02 I. */
    mf_gaussian_slopes g = {0.3, -0.2, 0.02, 0.02, 0.0};
    CHECK_REL(integrate_p22_box(&g), 1.0, 1e-12);
    CHECK_REL(mf_gaussian_p22(&g, 0.3, -0.2), 1.0 / (2 * MF_PI * 0.02), 4 * DBL_EPSILON);
    double printed_peak = 1.0 / (sqrt(2 * MF_PI) * 0.02 * 0.02);
    CHECK(fabs(printed_peak * 2 * MF_PI * 0.02 - 1.0) > 100.0); /* the printed form is off by ~125x */
    mf_gaussian_slopes gc = {-1.5, 1.3, 2.0, 0.5, -0.9}; /* correlated, the correction C-L2 covariance */
    CHECK_REL(integrate_p22_box(&gc), 1.0, 1e-12);

    /* correction C-N2: cos^s ~ exp(-(s/2) tan^2) is normalised by s / (2 pi), not s / sqrt(2 pi):
     * the Beckmann P22 with alpha = sqrt(2/s) equals (s / 2 pi) exp(-(s/2)|h|^2). */
    double s_exp = 64.0, alpha = mf_ndf_beckmann_alpha_from_blinn_phong(s_exp);
    CHECK_REL(alpha, sqrt(2.0 / 64.0), DBL_EPSILON);
    CHECK_REL(mf_ndf_blinn_phong_from_beckmann_alpha(alpha), s_exp, 4 * DBL_EPSILON);
    for (double h = 0.0; h < 0.5; h += 0.05)
        CHECK_REL(mf_ndf_p22(mf_ndf_make(MF_NDF_BECKMANN, alpha, alpha), h, 0.5 * h),
                  s_exp / (2 * MF_PI) * exp(-0.5 * s_exp * 1.25 * h * h), 16 * DBL_EPSILON);
    CHECK(isnan(mf_ndf_beckmann_alpha_from_blinn_phong(0.0)));
    CHECK(isnan(mf_ndf_blinn_phong_from_beckmann_alpha(-1.0)));

    /* correction C-L6: slopes are the height gradient (-m.x/m.z, -m.y/m.z); a mean slope of +0.3 in x
     * tilts the mesonormal towards -x [Dupuy 2013, Eq. 11]. */
    double sl[2];
    mf_slope_from_normal(mf_vec3_make(0.6, 0.0, 0.8), sl);
    CHECK_REL(sl[0], -0.75, DBL_EPSILON);
    CHECK(sl[1] == 0.0);
    mf_slope_from_normal(mf_vec3_make(0.6, 0.0, -0.8), sl);
    CHECK(isnan(sl[0]));
    mf_gaussian_slopes tilted = {0.3, 0.0, 0.01, 0.01, 0.0};
    CHECK(mf_gaussian_mesonormal(&tilted).x < 0.0);
    /* the NDF of a tilted distribution peaks at the mesonormal, not at its mirror */
    mf_vec3 mn = mf_gaussian_mesonormal(&tilted), mirror = mf_vec3_make(-mn.x, mn.y, mn.z);
    CHECK(mf_gaussian_d(&tilted, mn) > 1e6 * mf_gaussian_d(&tilted, mirror));

    /* degenerate covariances: mass on a line or a point, no NaN */
    mf_gaussian_slopes line = {0.0, 0.0, 0.04, 0.0, 0.0}, point = {0.1, 0.2, 0.0, 0.0, 0.0};
    CHECK(isinf(mf_gaussian_p22(&line, 0.3, 0.0)));
    CHECK(mf_gaussian_p22(&line, 0.3, 0.1) == 0.0);
    CHECK(isinf(mf_gaussian_p22(&point, 0.1, 0.2)));
    CHECK(mf_gaussian_p22(&point, 0.1, 0.2001) == 0.0);
    mf_gaussian_slopes corr_line = {0.0, 0.0, 1.0, 1.0, 1.0}; /* all mass on sy = sx */
    CHECK(isinf(mf_gaussian_p22(&corr_line, 0.5, 0.5)));
    CHECK(mf_gaussian_p22(&corr_line, 0.5, -0.5) == 0.0);
    mf_gaussian_slopes not_psd = {0.0, 0.0, 1.0, 1.0, 1.5};
    CHECK(!mf_gaussian_valid(&not_psd));
    CHECK(isnan(mf_gaussian_p22(&not_psd, 0.0, 0.0)));

    mf_ndf_type parsed;
    CHECK(mf_ndf_type_parse("ggx", &parsed) == 0 && parsed == MF_NDF_GGX);
    CHECK(mf_ndf_type_parse("beckmann", &parsed) == 0 && parsed == MF_NDF_BECKMANN);
    CHECK(mf_ndf_type_parse("GGX ", &parsed) != 0);
    MF_TEST_MAIN_END();
}
