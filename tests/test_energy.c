/* test_energy.c -- the accurate albedo against the independent reference, its bound, the DFG
 * terms' Schlick identity, the Kulla-Conty furnace gate.  Deterministic (no random numbers). */
#include "mf_test.h"

#include "mfkit/mfkit.h"

#include <stdio.h>

#define DEG (MF_PI / 180.0)
/* the reference's tolerance; its achieved error is below its own estimate, printed on failure */
#define REF_TOL 1e-10

static void albedo_vs_reference(void)
{
    const double alphas[] = {1e-4, 1e-3, 0.05, 0.3, 0.5, 1.0};
    const double thetas[] = {0.0, 60.0, 85.0, 89.0, 89.78, 89.99};
    double worst_ratio = 0.0, worst_err = 0.0;
    for (int n = 0; n < 2; ++n)
        for (int a = 0; a < 6; ++a)
            for (int t = 0; t < 6; ++t) {
                mf_microfacet m = {mf_ndf_make(n ? MF_NDF_BECKMANN : MF_NDF_GGX, alphas[a], alphas[a]), MF_G2_JOINT,
                                   {MF_FRESNEL_NONE, 0, 0, 0}};
                mf_vec3 wo = mf_vec3_spherical(thetas[t] * DEG, 0.0);
                mf_result q, r;
                CHECK(mf_albedo_microfacet(&m, wo, &q) == MF_OK);
                mf_status s = mf_albedo_microfacet_reference(&m, wo, REF_TOL, &r);
                CHECK(s == MF_OK);
                double d = fabs(q.val - r.val);
                /* the bound must cover the difference (plus the reference's own bound) and be <= 1e-9,
                 * the target, over the whole domain: alpha 1e-4..1, theta up to 89.99 deg */
                if (!(d <= q.err + r.err) || !(q.err <= 1e-9) || s != MF_OK)
                    printf("ndf %d alpha %g theta %g: %.15f err %.2e vs reference %.15f (err %.1e, status %d), diff "
                           "%.2e\n",
                           n, alphas[a], thetas[t], q.val, q.err, r.val, r.err, (int)s, d);
                CHECK(d <= q.err + r.err);
                CHECK(q.err <= 1e-9);
                worst_err = fmax(worst_err, q.err);
                worst_ratio = fmax(worst_ratio, d / (q.err + r.err));
            }
    printf("albedo vs reference: 72 points, worst bound %.2e, worst |diff| / (bound + reference bound) %.3f\n",
           worst_err, worst_ratio);
    /* the reference against the second, older one (spherical angles of wi) where that one converges:
     * two quadratures in different coordinates agree within both bounds */
    const double ca[][2] = {{0.05, 0.0}, {0.5, 60.0}, {1.0, 85.0}, {0.3, 30.0}};
    for (int n = 0; n < 2; ++n)
        for (int i = 0; i < 4; ++i) {
            mf_microfacet m = {mf_ndf_make(n ? MF_NDF_BECKMANN : MF_NDF_GGX, ca[i][0], ca[i][0]), MF_G2_JOINT,
                               {MF_FRESNEL_NONE, 0, 0, 0}};
            mf_vec3 wo = mf_vec3_spherical(ca[i][1] * DEG, 0.0);
            mf_result r, rw;
            CHECK(mf_albedo_microfacet_reference(&m, wo, REF_TOL, &r) == MF_OK);
            CHECK(mf_albedo_microfacet_reference_wi(&m, wo, REF_TOL, &rw) == MF_OK);
            if (!(fabs(r.val - rw.val) <= r.err + rw.err))
                printf("references disagree: ndf %d alpha %g theta %g: %.15f vs %.15f\n", n, ca[i][0], ca[i][1], r.val,
                       rw.val);
            CHECK(fabs(r.val - rw.val) <= r.err + rw.err);
        }
    /* the value of the issue: GGX alpha 0.5, normal view, 0.68784852 to 1e-8 */
    mf_microfacet g = {mf_ndf_make(MF_NDF_GGX, 0.5, 0.5), MF_G2_JOINT, {MF_FRESNEL_NONE, 0, 0, 0}};
    mf_result q;
    CHECK(mf_albedo_microfacet(&g, mf_vec3_make(0, 0, 1), &q) == MF_OK);
    CHECK(fabs(q.val - 0.68784852) < 1e-8);
}

/* the Charlie channel against its reference (other coordinates: wi instead of the micro-normal),
 * over the table's domain including the grazing, smallest-alpha corner where it exceeds 30 */
static void charlie_vs_reference(void)
{
    const double alphas[] = {1e-4, 1e-2, 0.3, 1.0};
    const double mus[] = {1.0, 0.5, 0.05, 0.0039, 1.745e-4};
    double worst = 0.0;
    for (int a = 0; a < 4; ++a)
        for (int t = 0; t < 5; ++t) {
            mf_result q, r;
            CHECK(mf_albedo_charlie(alphas[a], mus[t], &q) == MF_OK);
            CHECK(mf_albedo_charlie_reference(alphas[a], mus[t], REF_TOL, &r) == MF_OK);
            double d = fabs(q.val - r.val);
            if (!(d <= q.err + r.err) || !(q.err <= 1e-9))
                printf("charlie alpha %g mu %g: %.15g err %.2e vs reference %.15g err %.2e\n", alphas[a], mus[t], q.val,
                       q.err, r.val, r.err);
            CHECK(d <= q.err + r.err);
            CHECK(q.err <= 1e-9);
            worst = fmax(worst, d / (q.err + r.err));
        }
    /* closed form at normal incidence, alpha 1: D = 3 sin(t) / (2 pi), V = 1/4, wi.z = cos 2t,
     * wo.h = cos t, so the albedo is 3 int_0^{pi/4} sin^2 t cos t cos 2t dt = 3 (u^3/3 - 2 u^5/5) at
     * u = 1/sqrt(2), = 1 / (5 sqrt(2)); within the bound */
    mf_result q;
    CHECK(mf_albedo_charlie(1.0, 1.0, &q) == MF_OK);
    CHECK(fabs(q.val - 1.0 / (5.0 * sqrt(2.0))) <= q.err);
    printf("charlie vs reference: 20 points, worst |diff| / bounds %.3f; alpha 1 normal %.15f\n", worst, q.val);
}

/* 2 int_0^1 E_T(mu) mu dmu = 4 int_0^1 E_T(s^2) s^3 ds on [0, s_c], [s_c, 1] with an n-point rule
 * (s_c^2 = the cosine of the critical angle on the dense side, where E_T turns over; 0.5 if none);
 * *b gets the propagated bounds */
static double transmit_avg(double alpha, double eta, int n, double *b)
{
    double x[32], w[32], sum = 0.0, sc = eta < 1.0 ? sqrt(sqrt(1.0 - eta * eta)) : 0.5;
    CHECK(mf_quad_gauss_legendre(n, x, w) == MF_OK);
    *b = 0.0;
    for (int p = 0; p < 2; ++p) {
        double a = p ? sc : 0.0, h = 0.5 * (p ? 1.0 - sc : sc);
        for (int j = 0; j < n; ++j) {
            double t = a + h * (1.0 + x[j]), wt = h * w[j] * 4.0 * t * t * t;
            mf_result r, tr;
            CHECK(mf_albedo_dielectric(mf_ndf_make(MF_NDF_GGX, alpha, alpha), MF_G2_JOINT, t * t, eta, &r, &tr) == MF_OK);
            sum += wt * tr.val;
            *b += wt * tr.err;
        }
    }
    return sum;
}

/* the rough dielectric: three checks that share no code with its rule */
static void dielectric(void)
{
    const double alphas[] = {1e-4, 0.01, 0.3, 1.0};
    const double mus[] = {1.0, 0.5, 0.05, 1.745e-4};
    for (int n = 0; n < 2; ++n)
        for (int a = 0; a < 4; ++a)
            for (int t = 0; t < 4; ++t)
                for (int g = 0; g < 2; ++g) {
                    /* eta = 1: no refraction (wt = -wo), F = 0, so E_R = 0 and E_T = (1 + Lambda_o) G2(wo, wo)
                     * (int D (wo.h)_+ dh = wo.z (1 + Lambda_o)): 1 / (1 + 2 L) joint (times 1 + L), 1 / (1 + L)
                     * separable */
                    mf_ndf ndf = mf_ndf_make(n ? MF_NDF_BECKMANN : MF_NDF_GGX, alphas[a], alphas[a]);
                    mf_g2_form g2 = g ? MF_G2_SEPARABLE : MF_G2_JOINT;
                    double mu = mus[t];
                    mf_result r, tr;
                    CHECK(mf_albedo_dielectric(ndf, g2, mu, 1.0, &r, &tr) == MF_OK);
                    double l = mf_smith_lambda(ndf, mf_vec3_make(sqrt(1.0 - mu * mu), 0.0, mu));
                    double exact = g ? 1.0 / (1.0 + l) : (1.0 + l) / (1.0 + 2.0 * l);
                    if (!(fabs(tr.val - exact) <= tr.err) || !(fabs(r.val) <= 1e-15) || !(tr.err <= 1e-9))
                        printf("dielectric eta 1: ndf %d g2 %d alpha %g mu %g: E_T %.15f err %.1e vs %.15f, E_R %g\n", n, g,
                               alphas[a], mu, tr.val, tr.err, exact, r.val);
                    CHECK(fabs(tr.val - exact) <= tr.err);
                    CHECK(tr.err <= 1e-9);
                    CHECK(fabs(r.val) <= 1e-15); /* F(eta = 1) is 0 up to the rounding of its formula */
                    /* eta 1.5 and 3 (no total internal reflection): E_R against mf_albedo_microfacet with the
                     * dielectric Fresnel (the slope-space rule) within both bounds */
                    for (int e = 0; e < 2; ++e) {
                        double eta = e ? 3.0 : 1.5;
                        mf_microfacet m = {ndf, g2, {MF_FRESNEL_DIELECTRIC, 0.0, eta, 0.0}};
                        mf_result q;
                        CHECK(mf_albedo_dielectric(ndf, g2, mu, eta, &r, &tr) == MF_OK);
                        CHECK(mf_albedo_microfacet(&m, mf_vec3_make(sqrt(1.0 - mu * mu), 0.0, mu), &q) == MF_OK);
                        if (!(fabs(r.val - q.val) <= r.err + q.err) || !(r.err <= 1e-9) || !(tr.err <= 1e-9))
                            printf("dielectric eta %g: ndf %d g2 %d alpha %g mu %g: E_R %.15f (%.1e) vs albedo %.15f (%.1e), "
                                   "E_T err %.1e\n",
                                   eta, n, g, alphas[a], mu, r.val, r.err, q.val, q.err, tr.err);
                        CHECK(fabs(r.val - q.val) <= r.err + q.err);
                        CHECK(r.err <= 1e-9 && tr.err <= 1e-9);
                    }
                }
    /* reciprocity: a uniform radiance L outside sends pi L T_avg(eta) into the dense side; in
     * equilibrium the radiance inside is eta^2 L and sends pi eta^2 L T_avg(1/eta) back, so
     * T_avg(eta) = eta^2 T_avg(1/eta) (the single-scattering BTDF is reciprocal and this G2 is symmetric).
     * The two sides' integrals have different kinks (total internal reflection only inside).  Tolerance:
     * each average's |Q24 - Q16| plus the propagated bounds. */
    for (int a = 0; a < 2; ++a) {
        double alpha = a ? 1.0 : 0.3, eta = 1.5, b1, b2, b3, b4;
        double out = transmit_avg(alpha, eta, 24, &b1), out16 = transmit_avg(alpha, eta, 16, &b2);
        double in = transmit_avg(alpha, 1.0 / eta, 24, &b3), in16 = transmit_avg(alpha, 1.0 / eta, 16, &b4);
        double tol = fabs(out - out16) + b1 + b2 + eta * eta * (fabs(in - in16) + b3 + b4);
        printf("dielectric reciprocity alpha %g: T_avg(1.5) %.12f, 1.5^2 T_avg(1/1.5) %.12f, diff %.2e, tolerance %.2e\n",
               alpha, out, eta * eta * in, out - eta * eta * in, tol);
        CHECK(fabs(out - eta * eta * in) <= tol);
    }
}

static void dfg_identity(void)
{
    const double f0s[] = {0.0, 0.04, 0.5, 1.0};
    for (int a = 0; a < 3; ++a)
        for (int t = 0; t < 3; ++t) {
            double alpha = (double[]){1e-3, 0.2, 0.9}[a], mu = (double[]){1.0, 0.5, 0.05}[t];
            mf_result s, b;
            CHECK(mf_energy_dfg(MF_NDF_GGX, MF_G2_JOINT, alpha, mu, &s, &b) == MF_OK);
            for (int k = 0; k < 4; ++k) {
                mf_microfacet m = {mf_ndf_make(MF_NDF_GGX, alpha, alpha), MF_G2_JOINT, {MF_FRESNEL_SCHLICK, f0s[k], 0, 0}};
                mf_result q;
                CHECK(mf_albedo_microfacet(&m, mf_vec3_make(sqrt(1 - mu * mu), 0, mu), &q) == MF_OK);
                double d = fabs(f0s[k] * s.val + b.val - q.val);
                /* the same quadrature nodes, different summation: within both bounds */
                if (!(d <= s.err + b.err + q.err))
                    printf("alpha %g mu %g F0 %g: %.15g vs %.15g\n", alpha, mu, f0s[k], f0s[k] * s.val + b.val, q.val);
                CHECK(d <= s.err + b.err + q.err);
            }
        }
    CHECK(fabs(mf_energy_favg_schlick(0.04) - (20 * 0.04 + 1) / 21) == 0.0);
    mf_result fc;
    CHECK(mf_energy_favg_conductor(1.5, 0.0, &fc) == MF_OK); /* k = 0: a dielectric, F_avg(1.5) = 0.0918 */
    CHECK(fc.val > 0.09 && fc.val < 0.094);
}

static void furnace(void)
{
    mf_table t;
    CHECK(mf_energy_kulla_conty_table(&t, MF_NDF_GGX, MF_G2_JOINT, 8, 8, NULL, NULL) == MF_OK);
    mf_check ch[8];
    int n = 0;
    mf_status st = mf_table_kind_gate(&t, NULL, NULL, ch, 8, &n);
    for (int i = 0; i < n; ++i)
        if (!ch[i].passed)
            printf("%s: worst %g at %s\n", ch[i].name, ch[i].worst, ch[i].worst_at);
    CHECK(st == MF_OK);
    /* a corrupted E_avg must fail the furnace */
    t.data[2] *= 1.001;
    CHECK(mf_table_kind_gate(&t, NULL, NULL, ch, 8, &n) == MF_ERR_CHECK_FAILED);
    mf_table_free(&t);
}

int main(void)
{
    albedo_vs_reference();
    charlie_vs_reference();
    dielectric();
    dfg_identity();
    furnace();
    MF_TEST_MAIN_END();
}
