/* test_brdf.c -- microfacet, LEADR and Lambert BRDFs and their albedo (mf_brdf.h). */
#include "mf_test.h"
#include "mfkit/mf_brdf.h"
#include "mfkit/mf_rng.h"
#include "mfkit/mf_sample.h"

#include <float.h>

/* Monte Carlo albedo with uniform hemisphere sampling: independent of the quadrature's maps. */
static void mc_albedo(const mf_microfacet *m, mf_vec3 wo, int n, mf_pcg32 *rng, double *mean, double *se)
{
    double s = 0.0, s2 = 0.0;
    for (int i = 0; i < n; ++i) {
        double u[2] = {mf_pcg32_next_double(rng), mf_pcg32_next_double(rng)};
        mf_vec3 wi = mf_sample_uniform_hemisphere(u);
        double v = mf_brdf_microfacet(m, wo, wi) * wi.z / mf_pdf_uniform_hemisphere(wi);
        s += v;
        s2 += v * v;
    }
    *mean = s / n;
    *se = sqrt(fmax(0.0, s2 / n - *mean * *mean) / (n - 1));
}

int main(void)
{
    mf_pcg32 rng;
    uint64_t seed = mf_test_seed(99);
    mf_pcg32_seed(&rng, seed, 5);
    mf_fresnel none = {MF_FRESNEL_NONE, 0, 0, 0};

    /* Albedo by quadrature against Monte Carlo.  z = 4.5: 18 comparisons, two-sided
     * P(|Z| > 4.5) = 6.8e-6 each, family-wise < 1.3e-4.  delta = the quadrature's own error
     * estimate plus 1e-12 (rounding). 400k samples: se ~ 1e-3 at alpha 0.3. */
    const double alphas[3] = {0.3, 0.6, 1.0}, thetas[3] = {0.0, 60.0, 85.0};
    for (int t = 0; t < 2; ++t)
        for (int ia = 0; ia < 3; ++ia)
            for (int it = 0; it < 3; ++it) {
                mf_microfacet m = {mf_ndf_make(t ? MF_NDF_BECKMANN : MF_NDF_GGX, alphas[ia], alphas[ia]), MF_G2_JOINT, none};
                mf_vec3 wo = mf_vec3_spherical(thetas[it] * MF_PI / 180.0, 0.3);
                mf_result q;
                CHECK(mf_brdf_microfacet_albedo(&m, wo, 256, &q) == MF_OK);
                double mean, se;
                mc_albedo(&m, wo, 400000, &rng, &mean, &se);
                CHECK_MC(mean, se, q.val, 4.5, q.err + 1e-12);
                CHECK(q.val <= 1.0 + q.err);
            }
    /* Low roughness: the lobe's tail lives in a layer of width ~alpha^2 of the sampler's unit
     * square; a quadrature that misses it gets Q(n) = Q(n/2) and a falsely tiny error estimate
     * (before the u0 substitution in mf_brdf.c: alpha 0.02, normal view gave 0.9999959 +- 2.5e-6
     * against Monte Carlo 0.99959 +- 1.4e-5).  Monte Carlo here uses the VNDF sampler with its
     * exact weight G2/G1: unbiased; z = 4.5 (4 cases), delta = the quadrature's error estimate. */
    {
        const double la[2] = {0.02, 0.05}, lt[2] = {0.0, 60.0};
        for (int ia = 0; ia < 2; ++ia)
            for (int it = 0; it < 2; ++it) {
                mf_microfacet m = {mf_ndf_make(MF_NDF_GGX, la[ia], la[ia]), MF_G2_JOINT, none};
                mf_vec3 wo = mf_vec3_spherical(lt[it] * MF_PI / 180.0, 0.0);
                mf_result q;
                CHECK(mf_brdf_microfacet_albedo(&m, wo, 256, &q) == MF_OK);
                double g1 = mf_smith_g1(m.ndf, wo), s1 = 0.0, s2 = 0.0;
                const int nmc = 1000000;
                for (int k = 0; k < nmc; ++k) {
                    double u[2] = {mf_pcg32_next_double(&rng), mf_pcg32_next_double(&rng)};
                    mf_vec3 wi = mf_vec3_reflect(wo, mf_sample_ggx_vndf(la[ia], la[ia], wo, u));
                    double v = wi.z > 0.0 ? mf_smith_g2(m.ndf, MF_G2_JOINT, wo, wi) / g1 : 0.0;
                    s1 += v;
                    s2 += v * v;
                }
                double mean = s1 / nmc, se = sqrt((s2 / nmc - mean * mean) / (nmc - 1));
                CHECK_MC(mean, se, q.val, 4.5, q.err + 1e-12);
            }
    }
    /* Quadrature convergence: the error estimate shrinks with n and brackets the next level. */
    {
        mf_microfacet m = {mf_ndf_make(MF_NDF_GGX, 0.05, 0.05), MF_G2_JOINT, none};
        mf_vec3 wo = mf_vec3_spherical(80.0 * MF_PI / 180.0, 0.0);
        mf_result r64, r512;
        CHECK(mf_brdf_microfacet_albedo(&m, wo, 64, &r64) == MF_OK);
        CHECK(mf_brdf_microfacet_albedo(&m, wo, 512, &r512) == MF_OK);
        CHECK(fabs(r64.val - r512.val) <= r64.err + 1e-15);
        CHECK(r512.err <= r64.err);
    }
    /* Extremes: alpha 1e-4 is a mirror: albedo -> 1 for joint masking at moderate angles
     * (Lambda ~ 1e-8), and stays <= 1 at 89.99 deg. */
    for (int t = 0; t < 2; ++t) {
        mf_microfacet m = {mf_ndf_make(t ? MF_NDF_BECKMANN : MF_NDF_GGX, 1e-4, 1e-4), MF_G2_JOINT, none};
        mf_result r;
        CHECK(mf_brdf_microfacet_albedo(&m, mf_vec3_spherical(0.5, 0.0), 64, &r) == MF_OK);
        CHECK_ABS(r.val, 1.0, 1e-6);
        CHECK(mf_brdf_microfacet_albedo(&m, mf_vec3_spherical(89.99 * MF_PI / 180.0, 0.0), 64, &r) == MF_OK);
        CHECK(r.val <= 1.0 + r.err && r.val > 0.0);
    }
    mf_result bad;
    mf_microfacet mg = {mf_ndf_make(MF_NDF_GGX, 0.3, 0.3), MF_G2_JOINT, none};
    CHECK(mf_brdf_microfacet_albedo(&mg, mf_vec3_make(0, 0.6, -0.8), 64, &bad) == MF_ERR_DOMAIN);
    CHECK(mf_brdf_microfacet_albedo(&mg, mf_vec3_make(0, 0, 1), 60, &bad) == MF_ERR_DOMAIN);
    CHECK(isnan(bad.val));

    /* Lambert: albedo rho exactly (to rounding of the weights' sum: 1e-13). */
    mf_result lr;
    CHECK(mf_brdf_lambert_albedo(0.7, mf_vec3_spherical(1.0, 0.0), 64, &lr) == MF_OK);
    CHECK_REL(lr.val, 0.7, 1e-13);
    CHECK(mf_brdf_lambert(0.7, mf_vec3_make(0, 0, 1), mf_vec3_make(0, 0, -1)) == 0.0);
    CHECK(isnan(mf_brdf_lambert(1.5, mf_vec3_make(0, 0, 1), mf_vec3_make(0, 0, 1))));

    /* BRDF value against the formula written out: GGX isotropic, wo = wi mirror pair. */
    {
        mf_vec3 wo = mf_vec3_spherical(0.4, 0.0), wi = mf_vec3_spherical(0.4, MF_PI); /* wh = z */
        double a = 0.2, lam = 0.5 * (-1.0 + sqrt(1.0 + a * a * tan(0.4) * tan(0.4)));
        double expect = (1.0 / (MF_PI * a * a)) / (1.0 + 2.0 * lam) / (4.0 * cos(0.4) * cos(0.4));
        mf_microfacet m = {mf_ndf_make(MF_NDF_GGX, a, a), MF_G2_JOINT, none};
        CHECK_REL(mf_brdf_microfacet(&m, wo, wi), expect, 1e-14);
        CHECK(mf_brdf_microfacet(&m, wo, mf_vec3_make(0, 0.6, -0.8)) == 0.0);
    }

    /* LEADR Eq. 17 with centred slopes is the Walter BRDF with Beckmann D and joint G2 (Eq. 17
     * "is equivalent to previous work" for a centred mesonormal); 32 eps: different paths. */
    {
        mf_gaussian_slopes g = mf_gaussian_from_beckmann(0.3, 0.1);
        mf_fresnel sch = {MF_FRESNEL_SCHLICK, 0.04, 0, 0};
        mf_microfacet m = {mf_ndf_make(MF_NDF_BECKMANN, 0.3, 0.1), MF_G2_JOINT, sch};
        for (int k = 0; k < 1000; ++k) {
            double u1[2] = {mf_pcg32_next_double(&rng), mf_pcg32_next_double(&rng)};
            double u2[2] = {mf_pcg32_next_double(&rng), mf_pcg32_next_double(&rng)};
            mf_vec3 wo = mf_sample_uniform_hemisphere(u1), wi = mf_sample_uniform_hemisphere(u2);
            double a = mf_brdf_leadr_specular(&g, sch, wo, wi), b = mf_brdf_microfacet(&m, wo, wi);
            /* exp(-t) of the Beckmann D turns the relative rounding of its argument t (the
             * stretched tan^2 of wh, computed along two paths) into t times that error. */
            mf_vec3 wh = mf_vec3_normalize(mf_vec3_add(wo, wi));
            double t = (wh.x * wh.x / 0.09 + wh.y * wh.y / 0.01) / (wh.z * wh.z);
            if (b > 1e-290)
                CHECK_REL(a, b, 32 * DBL_EPSILON * (1.0 + t));
            else
                CHECK(a < 1e-290);
        }
        /* LEADR albedo, centred: equals the microfacet albedo (Beckmann, joint G2); the two
         * quadratures use different maps, so they agree to their error estimates. */
        for (double th = 0.0; th < 1.5; th += 0.35) {
            mf_vec3 wo = mf_vec3_spherical(th, 0.6);
            mf_result la, ma;
            CHECK(mf_leadr_specular_albedo(&g, sch, wo, 256, &la) == MF_OK);
            CHECK(mf_brdf_microfacet_albedo(&m, wo, 256, &ma) == MF_OK);
            CHECK_ABS(la.val, ma.val, la.err + ma.err + 1e-12);
        }
        /* non-centred: against Monte Carlo over the full hemisphere with uniform directions
         * (z = 4.5, delta = the quadrature's error estimate) and <= 1 */
        {
            mf_gaussian_slopes gt = {0.4, -0.2, 0.08, 0.03, 0.01};
            mf_vec3 wo = mf_vec3_spherical(0.9, 0.3);
            mf_result la;
            CHECK(mf_leadr_specular_albedo(&gt, sch, wo, 256, &la) == MF_OK);
            double s1 = 0.0, s2 = 0.0;
            const int nmc = 400000;
            for (int k = 0; k < nmc; ++k) {
                double u[2] = {mf_pcg32_next_double(&rng), mf_pcg32_next_double(&rng)};
                mf_vec3 wi = mf_sample_uniform_hemisphere(u);
                double v = mf_leadr_specular(&gt, sch, wo, wi) / mf_pdf_uniform_hemisphere(wi);
                s1 += v;
                s2 += v * v;
            }
            double mean = s1 / nmc, se = sqrt((s2 / nmc - mean * mean) / (nmc - 1));
            CHECK_MC(mean, se, la.val, 4.5, la.err + 1e-12);
            CHECK(la.val <= 1.0 + la.err);
            mf_gaussian_slopes singular = {0.0, 0.0, 0.1, 0.0, 0.0};
            CHECK(mf_leadr_specular_albedo(&singular, sch, wo, 64, &la) == MF_ERR_DOMAIN);
        }
        /* a view below the mesosurface gives 0, not NaN or a negative value */
        mf_gaussian_slopes tilt = {1.0, 0.0, 0.01, 0.01, 0.0};
        double v = mf_leadr_specular(&tilt, sch, mf_vec3_spherical(1.2, 0.0), mf_vec3_make(0, 0, 1));
        CHECK(v == 0.0);
        CHECK(mf_leadr_specular(&tilt, sch, mf_vec3_make(0, 0, 1), mf_vec3_make(0, 0, -1)) == 0.0);
    }
    MF_TEST_MAIN_END();
}
