/* test_smith.c -- Smith Lambda, G1, G2 (mf_smith.h), with docs/math.md, corrections C-L2, C-L3, C-L4 and the GGX
 * small-angle note. */
#include "mf_test.h"
#include "mfkit/mf_smith.h"

#include <float.h>

/* Lambda of the Beckmann family at nu, to 20 digits, from
 *   /usr/bin/python3 -c "import mpmath as mp; mp.mp.dps=40; n=mp.mpf(NU);
 *                        print(mp.exp(-n**2)/(2*n*mp.sqrt(mp.pi))-mp.erfc(n)/2)"   */
static const double k_lambda_ref[][2] = {
    {0.01, 27.712300078290694799},       {0.5, 0.19964122837424566589},
    {1.5, 0.0028742881082602587887},     {1.99, 0.00025775058122321695203},
    {2.0, 0.00024450567873787381317},    {2.01, 0.00023190673042019609913},
    {3, 5.5917249626960047115e-7},       {6, 1.4555347395581356344e-19},
    {12, 2.3385453759653965084e-67},     {25, 3.3147780416353551477e-277},
};

int main(void)
{
    /* Beckmann Lambda(nu) against 40-digit references: 16 eps everywhere.  Just below nu = 2 the
     * direct difference cancels about one digit (each term is ~10x Lambda): ~10 eps measured;
     * from nu = 2 on the continued fraction keeps every digit (the printed difference would lose
     * 1/(2 nu^2) of them and be 0 beyond nu ~ 26). */
    for (int i = 0; i < (int)(sizeof k_lambda_ref / sizeof k_lambda_ref[0]); ++i)
        CHECK_REL(mf_smith_lambda_beckmann_nu(k_lambda_ref[i][0]), k_lambda_ref[i][1], 16 * DBL_EPSILON);
    double below = mf_smith_lambda_beckmann_nu(nextafter(2.0, 0.0)), at = mf_smith_lambda_beckmann_nu(2.0);
    CHECK_REL(below, at, 1e-14);

    /* correction C-L3: nu <= 0 means below the (meso)surface: Lambda = +inf, G2 = 0.  The printed
     * formulas give finite negative values there (-1.1996 and -1.4142 at nu = -0.5). */
    CHECK(isinf(mf_smith_lambda_beckmann_nu(-0.5)) && mf_smith_lambda_beckmann_nu(-0.5) > 0);
    CHECK(isinf(mf_smith_lambda_beckmann_nu(0.0)));
    CHECK(isinf(mf_smith_lambda_beckmann_walter_nu(-0.5)));
    {
        double nu = -0.5; /* the printed closed form, evaluated literally, is negative */
        double printed = exp(-nu * nu) / (2 * nu * MF_SQRT_PI) - 0.5 * erfc(nu);
        CHECK_REL(printed, -1.1996, 1e-4);
    }
    CHECK(isnan(mf_smith_lambda_beckmann_nu(NAN)));

    /* correction C-L4: Walter's rational form is negative on (1.548, 1.6); mfkit clamps to 0 so G1 <= 1. */
    for (double nu = 1.549; nu < 1.6; nu += 0.001) {
        double printed = (1.0 - 1.259 * nu + 0.396 * nu * nu) / (3.535 * nu + 2.181 * nu * nu);
        CHECK(printed < 0.0);
        CHECK(mf_smith_lambda_beckmann_walter_nu(nu) == 0.0);
    }
    CHECK(mf_smith_lambda_beckmann_walter_nu(1.6) == 0.0);
    CHECK_REL(mf_smith_lambda_beckmann_walter_nu(0.5), (1 - 1.259 * 0.5 + 0.396 * 0.25) / (3.535 * 0.5 + 2.181 * 0.25),
              DBL_EPSILON);

    /* correction C-L2: for non-centred slopes the closed form is Smith's construction relative to the
     * mean plane.  Configuration of C-L2: mean (0, 0.3), S = [2, 0.5, -0.9], theta 85 deg,
     * phi 300 deg: closed form 1.031053385642978 (mpmath, 40 digits), the literal printed
     * definition tan(theta) (cot - mu) x closed = 4.0928846743111. 1e-13: nu's own rounding. */
    mf_gaussian_slopes g = {0.0, 0.3, 2.0, 0.5, -0.9};
    mf_vec3 w = mf_vec3_spherical(85.0 * MF_PI / 180.0, 300.0 * MF_PI / 180.0);
    double lam = mf_smith_lambda_gaussian(&g, w);
    CHECK_REL(lam, 1.031053385642978, 1e-13);
    CHECK(fabs(lam - 4.0928846743111) > 3.0);

    /* Centred Gaussian = Beckmann (var = alpha^2/2): same Lambda to 8 eps */
    mf_gaussian_slopes gb = mf_gaussian_from_beckmann(0.3, 0.05);
    for (double th = 5.0; th < 90.0; th += 7.0)
        for (double ph = 0.0; ph < 6.0; ph += 0.9) {
            mf_vec3 d = mf_vec3_spherical(th * MF_PI / 180.0, ph);
            /* nu agrees to a few ulp; Lambda's relative condition number in nu is ~ 1 + 2 nu^2 */
            double nu = d.z / hypot(0.3 * d.x, 0.05 * d.y);
            CHECK_REL(mf_smith_lambda_gaussian(&gb, d), mf_smith_lambda_beckmann(0.3, 0.05, d),
                      8 * DBL_EPSILON * (1.0 + 2.0 * nu * nu));
            /* nu agrees to a few ulp along both paths; Walter's form has |dL/dnu| <= 4 for nu >= 0.29
             * (this grid), but near its root L -> 0, so compare absolutely: 1e-14. */
            CHECK_ABS(mf_smith_lambda_gaussian_walter(&gb, d), mf_smith_lambda_beckmann_walter(0.3, 0.05, d), 1e-14);
        }
    /* A direction below the geometric horizon but above a tilted mesosurface has finite Lambda
     * (correction C-L3): mean slope (2, 0), theta 100 deg towards -x. */
    mf_gaussian_slopes tilt = {2.0, 0.0, 0.1, 0.1, 0.0};
    mf_vec3 under = mf_vec3_spherical(100.0 * MF_PI / 180.0, MF_PI);
    CHECK(isfinite(mf_smith_lambda_gaussian(&tilt, under)));
    CHECK(mf_smith_lambda_gaussian(&tilt, under) > 0.0);
    mf_vec3 under2 = mf_vec3_spherical(100.0 * MF_PI / 180.0, 0.0); /* away from the tilt: masked */
    CHECK(isinf(mf_smith_lambda_gaussian(&tilt, under2)));
    CHECK(mf_smith_g2_gaussian(&tilt, mf_vec3_make(0, 0, 1), under2) == 0.0);
    /* degenerate covariance: no NaN (Lambda 0 above the mesosurface, inf below) */
    mf_gaussian_slopes zero = {0.2, 0.0, 0.0, 0.0, 0.0};
    CHECK(mf_smith_lambda_gaussian(&zero, mf_vec3_spherical(1.0, 0.3)) == 0.0);
    CHECK(isinf(mf_smith_lambda_gaussian(&zero, mf_vec3_spherical(1.5, 0.0))));

    /* GGX near normal incidence (docs/math.md, correction C-X2): alpha 1e-3, theta 0.001 deg:
     * Lambda = (alpha tan)^2 / 4 to first order = 7.6e-17; the naive (-1 + sqrt(1 + t))/2 gives 0. */
    double th = 0.001 * MF_PI / 180.0;
    double t = 1e-3 * tan(th);
    double lg = mf_smith_lambda_ggx(1e-3, 1e-3, mf_vec3_spherical(th, 0.4));
    CHECK(lg > 0.0);
    CHECK_REL(lg, t * t / 4.0, 1e-12);
    CHECK(0.5 * (-1.0 + sqrt(1.0 + t * t)) == 0.0); /* the naive form underflows to 0 */
    /* GGX closed form at a large angle: (-1 + sqrt(1 + a^2 tan^2)) / 2 */
    mf_vec3 w60 = mf_vec3_spherical(60.0 * MF_PI / 180.0, 0.0);
    CHECK_REL(mf_smith_lambda_ggx(0.5, 0.1, w60), 0.5 * (-1.0 + sqrt(1.0 + 0.25 * 3.0)), 4 * DBL_EPSILON);

    /* below the horizon: centred NDFs give G1 = G2 = 0 (Lambda = inf); at the pole Lambda = 0 */
    mf_ndf types[2] = {mf_ndf_make(MF_NDF_GGX, 0.3, 0.3), mf_ndf_make(MF_NDF_BECKMANN, 1e-4, 1e-4)};
    for (int i = 0; i < 2; ++i) {
        mf_vec3 down = mf_vec3_make(0.6, 0.0, -0.8), flat = mf_vec3_make(1.0, 0.0, 0.0), up = mf_vec3_make(0, 0, 1);
        CHECK(mf_smith_g1(types[i], down) == 0.0);
        CHECK(mf_smith_g1(types[i], flat) == 0.0);
        CHECK(mf_smith_lambda(types[i], up) == 0.0);
        CHECK(mf_smith_g2(types[i], MF_G2_JOINT, up, down) == 0.0);
        CHECK(mf_smith_g2(types[i], MF_G2_SEPARABLE, down, up) == 0.0);
        CHECK(mf_smith_g2(types[i], MF_G2_JOINT, up, up) == 1.0);
        /* grazing 89.99 deg: finite, in (0, 1] */
        mf_vec3 gr = mf_vec3_spherical(89.99 * MF_PI / 180.0, 0.3);
        double g1 = mf_smith_g1(types[i], gr);
        CHECK(g1 > 0.0 && g1 <= 1.0);
        /* joint >= separable (height correlation only increases visibility) */
        mf_vec3 a = mf_vec3_spherical(1.2, 0.1), b = mf_vec3_spherical(1.4, 2.0);
        CHECK(mf_smith_g2(types[i], MF_G2_JOINT, a, b) >= mf_smith_g2(types[i], MF_G2_SEPARABLE, a, b));
    }
    CHECK(isnan(mf_smith_lambda_ggx(-1.0, 0.3, mf_vec3_make(0, 0, 1))));
    CHECK(isnan(mf_smith_lambda_beckmann(0.3, 0.3, mf_vec3_make(NAN, 0, 1))));
    MF_TEST_MAIN_END();
}
