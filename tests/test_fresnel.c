/* test_fresnel.c -- Schlick, dielectric, conductor Fresnel (mf_fresnel.h). */
#include "mf_test.h"
#include "mfkit/mf_fresnel.h"

#include <float.h>

int main(void)
{
    /* normal incidence: ((eta - 1)/(eta + 1))^2 for the dielectric; Schlick returns f0 */
    CHECK_REL(mf_fresnel_dielectric(1.5, 1.0), 0.04, 8 * DBL_EPSILON);
    CHECK_REL(mf_fresnel_f0_from_eta(1.5), 0.04, 4 * DBL_EPSILON);
    CHECK_REL(mf_fresnel_schlick(0.04, 1.0), 0.04, DBL_EPSILON);
    /* grazing: 1 for all three */
    CHECK_ABS(mf_fresnel_dielectric(1.5, 0.0), 1.0, 4 * DBL_EPSILON);
    CHECK_ABS(mf_fresnel_conductor(0.2, 3.9, 0.0), 1.0, 4 * DBL_EPSILON);
    CHECK_ABS(mf_fresnel_schlick(0.04, 0.0), 1.0, DBL_EPSILON);
    /* Brewster angle tan(theta_B) = eta: the parallel reflectance vanishes, so
     * F = r_perp^2 / 2 with r_perp = (cos_i - eta cos_t)/(cos_i + eta cos_t), cos_t = sin_i. */
    double eta = 1.5, tb = atan(eta), ci = cos(tb), st = sin(tb);
    double ct = cos(asin(st / eta));
    double rperp = (ci - eta * ct) / (ci + eta * ct);
    CHECK_ABS(ct, st, 1e-15); /* theta_i + theta_t = 90 deg at Brewster's angle */
    CHECK_REL(mf_fresnel_dielectric(eta, ci), 0.5 * rperp * rperp, 1e-14);
    /* total internal reflection from the dense side: eta = 1/1.5, beyond the critical angle */
    CHECK(mf_fresnel_dielectric(1.0 / 1.5, cos(asin(1.0 / 1.5) + 0.01)) == 1.0);
    /* arriving from below swaps the media: F(eta, -c) = F(1/eta, c) */
    for (double c = 0.05; c <= 1.0; c += 0.05)
        CHECK_REL(mf_fresnel_dielectric(1.5, -c), mf_fresnel_dielectric(1.0 / 1.5, c), 4 * DBL_EPSILON);
    /* a conductor with k = 0 is a dielectric (eta > 1): 64 eps, the two formulas round differently */
    for (double c = 0.0; c <= 1.0; c += 0.01)
        CHECK_ABS(mf_fresnel_conductor(1.7, 0.0, c), mf_fresnel_dielectric(1.7, c), 64 * DBL_EPSILON);
    /* conductor at normal incidence: ((eta-1)^2 + k^2) / ((eta+1)^2 + k^2) [Born & Wolf 14.2] */
    CHECK_REL(mf_fresnel_conductor(0.2, 3.9, 1.0), (0.64 + 15.21) / (1.44 + 15.21), 16 * DBL_EPSILON);
    /* all in [0, 1] */
    for (double c = -1.0; c <= 1.0; c += 0.01) {
        double f1 = mf_fresnel_dielectric(1.33, c), f2 = mf_fresnel_conductor(1.1, 2.3, c), f3 = mf_fresnel_schlick(0.5, c);
        CHECK(f1 >= 0 && f1 <= 1 && f2 >= 0 && f2 <= 1 && f3 >= 0 && f3 <= 1);
    }
    /* rounding slack of dot products: |cos| up to 1 + 1e-9 accepted, beyond that NaN */
    CHECK(mf_fresnel_dielectric(1.5, 1.0 + 4 * DBL_EPSILON) == mf_fresnel_dielectric(1.5, 1.0));
    CHECK(isnan(mf_fresnel_dielectric(1.5, 1.001)));
    CHECK(isnan(mf_fresnel_schlick(1.5, 0.5)));
    CHECK(isnan(mf_fresnel_conductor(1.0, -1.0, 0.5)));
    CHECK(isnan(mf_fresnel_dielectric(0.0, 0.5)));
    mf_fresnel none = {MF_FRESNEL_NONE, 0, 0, 0};
    CHECK(mf_fresnel_eval(none, 0.3) == 1.0);
    MF_TEST_MAIN_END();
}
