/*
 * test_walk_split.c -- the dielectric compensation's split closed by the random walk
 * (mf_energy_dielectric_walk_split, mf_walk_dielectric_split, mf_energy_walk_split_project).
 *
 * Tolerances.  Monte Carlo comparisons are |a - b| <= Z sqrt(se_a^2 + se_b^2) with Z = 4.5 (two
 * independent estimates; a two-sided normal tail of 7e-6 per check, about 30 such checks here); the
 * seeds are fixed, so the test is deterministic.  Identities of the construction (the balance, the
 * projection of a balanced pair, bitwise reproducibility) are checked to rounding (1e-12 relative: a
 * handful of operations on numbers <= 1).
 */
#include "mfkit/mfkit.h"
#include "mf_test.h"

#include <string.h>

#define Z 4.5
#define WALKS 65536L /* per side: se <= 0.01 for alpha >= 0.3 (measured: 0.0007 to 0.006) */

typedef struct {
    double eavg, eavg_inv, favg, favg_inv;
} avgs;

static avgs averages(mf_ndf_type ndf, double alpha, double eta)
{
    avgs a;
    mf_result r;
    CHECK(mf_energy_dielectric_eavg(ndf, MF_G2_JOINT, alpha, eta, &r) == MF_OK);
    a.eavg = r.val;
    CHECK(mf_energy_dielectric_eavg(ndf, MF_G2_JOINT, alpha, 1.0 / eta, &r) == MF_OK);
    a.eavg_inv = r.val;
    CHECK(mf_energy_favg_dielectric(eta, &r) == MF_OK);
    a.favg = r.val;
    CHECK(mf_energy_favg_dielectric(1.0 / eta, &r) == MF_OK);
    a.favg_inv = r.val;
    return a;
}

/* the closure's balance t (1 - E_avg) = eta^2 t' (1 - E_avg_inv), to rounding */
static void check_balance(const mf_energy_walk_split *w, double eta, const avgs *a, const char *what)
{
    double lhs = w->t[0] * (1.0 - a->eavg), rhs = eta * eta * w->t[1] * (1.0 - a->eavg_inv);
    if (!(fabs(lhs - rhs) <= 1e-12 * fmax(fabs(lhs), 1e-300) + 1e-300))
        MF_FAIL_AT("%s: balance %.17g vs %.17g", what, lhs, rhs);
    CHECK(w->t[0] >= 0.0 && w->t[0] <= 1.0 && w->t[1] >= 0.0 && w->t[1] <= 1.0);
}

static void projection_identities(void)
{
    /* a balanced pair is its own projection; an unbalanced one lands on the line, and the one with the
     * smaller se moves less */
    double a = 0.3, b = 0.6, tw[2] = {0.2, 0.4}, se[2] = {0.01, 0.05}, t[2], chi;
    mf_energy_walk_split_project(tw, se, a, b, t, &chi);
    CHECK_REL(t[0], 0.2, 1e-14);
    CHECK_REL(t[1], 0.4, 1e-14);
    CHECK(chi < 1e-12);
    double tu[2] = {0.25, 0.4};
    mf_energy_walk_split_project(tu, se, a, b, t, &chi);
    CHECK_REL(t[0] * b, t[1] * a, 1e-14);
    /* least squares in se units: the residuals satisfy the normal equation a r0 / se0^2 + b r1 / se1^2 = 0 */
    double r0 = tu[0] - t[0], r1 = tu[1] - t[1];
    CHECK_ABS(a * r0 / (se[0] * se[0]) + b * r1 / (se[1] * se[1]), 0.0, 1e-9);
    CHECK(fabs(r0) > 1e-6 && fabs(r1) > 1e-6); /* the unbalanced pair did move */
    /* a pair pushed above 1 is scaled back onto the line, max = 1 */
    double th[2] = {1.5, 3.0};
    mf_energy_walk_split_project(th, se, a, b, t, NULL);
    CHECK_REL(fmax(t[0], t[1]), 1.0, 1e-14);
    CHECK_REL(t[0] * b, t[1] * a, 1e-14);
}

/* held-out cells (not on the 16^3 table's texel centres): the closure's raw walk fractions against fresh
 * walks (another seed), and the closure's balance; GGX and Beckmann, both sides */
static void held_out(void)
{
    static const struct {
        mf_ndf_type ndf;
        double alpha, eta;
    } cells[] = {{MF_NDF_GGX, 0.4, 1.4}, {MF_NDF_GGX, 0.85, 1.7}, {MF_NDF_GGX, 0.6, 1.05},
                 {MF_NDF_BECKMANN, 0.45, 1.45}, {MF_NDF_BECKMANN, 0.9, 2.2}};
    for (size_t c = 0; c < sizeof cells / sizeof cells[0]; ++c) {
        avgs a = averages(cells[c].ndf, cells[c].alpha, cells[c].eta);
        mf_energy_walk_split w, w2;
        CHECK(mf_energy_dielectric_walk_split(cells[c].ndf, cells[c].alpha, cells[c].eta, a.eavg, a.eavg_inv, a.favg,
                                              a.favg_inv, WALKS, MF_ENERGY_WALK_SPLIT_SEED, 100 + 2 * c, &w) == MF_OK);
        check_balance(&w, cells[c].eta, &a, "held-out");
        /* bitwise reproducible: the same stream gives the same bits */
        CHECK(mf_energy_dielectric_walk_split(cells[c].ndf, cells[c].alpha, cells[c].eta, a.eavg, a.eavg_inv, a.favg,
                                              a.favg_inv, WALKS, MF_ENERGY_WALK_SPLIT_SEED, 100 + 2 * c, &w2) == MF_OK);
        CHECK(memcmp(&w, &w2, sizeof w) == 0);
        CHECK(w.stopped == 0);
        for (int side = 0; side < 2; ++side) {
            mf_walk_split f;
            double eta = side ? 1.0 / cells[c].eta : cells[c].eta;
            CHECK(mf_walk_dielectric_split(mf_ndf_make(cells[c].ndf, cells[c].alpha, cells[c].alpha), eta, WALKS, 100000,
                                           7, 1000 + c * 2 + side, &f) == MF_OK);
            double d = fabs(w.t_walk[side] - f.t), bound = Z * sqrt(w.se[side] * w.se[side] + f.t_se * f.t_se);
            if (getenv("MF_TEST_VERBOSE"))
                printf("%s alpha %.2f eta %.4f: t_walk %.4f +- %.4f fresh %.4f +- %.4f, t_split %.4f, chi %.1f\n",
                       mf_ndf_type_name(cells[c].ndf), cells[c].alpha, eta, w.t_walk[side], w.se[side], f.t, f.t_se,
                       w.t[side], w.chi);
            if (!(d <= bound))
                MF_FAIL_AT("%s alpha %g eta %g: t_walk %.6f vs fresh %.6f, |d| %.3g > %.3g", mf_ndf_type_name(cells[c].ndf),
                           cells[c].alpha, eta, w.t_walk[side], f.t, d, bound);
            /* the walk is lossless: every walk leaves on a side */
            CHECK(f.single + f.ms + f.stopped == f.walks && f.stopped == 0);
        }
    }
}

/* the walk's reciprocity with the closure's own estimator: the cosine-averaged transmitted energy of
 * the multiple scattering, t (1 - e1), obeys T(eta) = eta^2 T(1/eta) within Z se */
static void walk_balance(void)
{
    double alpha = 0.7, eta = 1.5;
    mf_walk_split o, i;
    mf_ndf n = mf_ndf_make(MF_NDF_GGX, alpha, alpha);
    CHECK(mf_walk_dielectric_split(n, eta, 4 * WALKS, 100000, 3, 0, &o) == MF_OK);
    CHECK(mf_walk_dielectric_split(n, 1.0 / eta, 4 * WALKS, 100000, 3, 1, &i) == MF_OK);
    double N = (double)o.walks;
    double To = (double)(o.ms_trans + o.single_trans) / N, Ti = (double)(i.ms_trans + i.single_trans) / N;
    double se = sqrt(To * (1.0 - To) / N + eta * eta * eta * eta * Ti * (1.0 - Ti) / N);
    if (!(fabs(To - eta * eta * Ti) <= Z * se))
        MF_FAIL_AT("T(eta) %.5f vs eta^2 T(1/eta) %.5f (se %.2g)", To, eta * eta * Ti, se);
}

/* extreme inputs: alpha 1e-4 (no multiple scattering: Kulla and Conty's pair, se 1/2), alpha 1, eta near
 * 1 (index-matched: nearly everything is transmitted), and walks from grazing views */
static void extremes(void)
{
    {
        avgs a = averages(MF_NDF_GGX, 1e-4, 1.5);
        mf_energy_walk_split w;
        double kc[2];
        CHECK(mf_energy_dielectric_walk_split(MF_NDF_GGX, 1e-4, 1.5, a.eavg, a.eavg_inv, a.favg, a.favg_inv, 20000,
                                              MF_ENERGY_WALK_SPLIT_SEED, 0, &w) == MF_OK);
        CHECK(mf_energy_dielectric_ms_split(1.5, a.eavg, a.eavg_inv, a.favg, a.favg_inv, &kc[0]) == MF_OK);
        CHECK(mf_energy_dielectric_ms_split(1.0 / 1.5, a.eavg_inv, a.eavg, a.favg_inv, a.favg, &kc[1]) == MF_OK);
        CHECK(w.ms[0] == 0 && w.ms[1] == 0);
        CHECK(w.se[0] == 0.5 && w.se[1] == 0.5);
        /* Kulla and Conty's pair is balanced, so its projection is itself (to rounding) */
        CHECK_ABS(w.t[0], kc[0], 1e-12);
        CHECK_ABS(w.t[1], kc[1], 1e-12);
    }
    {
        avgs a = averages(MF_NDF_GGX, 1.0, 1.001);
        mf_energy_walk_split w;
        CHECK(mf_energy_dielectric_walk_split(MF_NDF_GGX, 1.0, 1.001, a.eavg, a.eavg_inv, a.favg, a.favg_inv, WALKS,
                                              MF_ENERGY_WALK_SPLIT_SEED, 2, &w) == MF_OK);
        check_balance(&w, 1.001, &a, "eta 1.001");
        /* index-matched: a ray meeting the surface again is transmitted with probability 1 - F >= 0.99999 at
         * normal incidence, so nearly all multiple scattering ends on the other side */
        CHECK(w.t_walk[0] > 0.99 && w.t_walk[1] > 0.99);
        CHECK(w.t[0] > 0.98 && w.t[1] > 0.98);
    }
    {
        avgs a = averages(MF_NDF_BECKMANN, 1.0, 2.88);
        mf_energy_walk_split w;
        CHECK(mf_energy_dielectric_walk_split(MF_NDF_BECKMANN, 1.0, 2.88, a.eavg, a.eavg_inv, a.favg, a.favg_inv, WALKS,
                                              MF_ENERGY_WALK_SPLIT_SEED, 4, &w) == MF_OK);
        check_balance(&w, 2.88, &a, "Beckmann alpha 1, eta 2.88");
    }
    /* grazing views: every walk ends, on a side, at mu 1e-4 */
    for (int s = 0; s < 2; ++s) {
        mf_pcg32 rng;
        mf_pcg32_seed(&rng, 5, (uint64_t)s);
        double mu = 1e-4;
        long ends = 0;
        for (int i = 0; i < 20000; ++i) {
            mf_walk_path p;
            CHECK(mf_walk_dielectric(mf_ndf_make(MF_NDF_GGX, 0.5, 0.5), s ? 1.0 / 1.5 : 1.5,
                                     mf_vec3_make(sqrt(1.0 - mu * mu), 0.0, mu), 100000, &rng, &p) == MF_OK);
            ends += p.side != 0;
        }
        CHECK(ends == 20000);
    }
    /* bad arguments */
    mf_energy_walk_split w;
    CHECK(mf_energy_dielectric_walk_split(MF_NDF_GGX, 0.5, -1.0, 0.9, 0.9, 0.1, 0.5, WALKS, 1, 0, &w) == MF_ERR_DOMAIN);
    CHECK(mf_energy_dielectric_walk_split(MF_NDF_GGX, 0.5, 1.5, 0.9, 0.9, 0.1, 0.5, 0, 1, 0, &w) == MF_ERR_DOMAIN);
    mf_walk_split f;
    CHECK(mf_walk_dielectric_split(mf_ndf_make(MF_NDF_GGX, 0.5, 0.5), 0.0, 10, 10, 1, 0, &f) == MF_ERR_DOMAIN);
}

int main(void)
{
    mf_test_seed(14);
    projection_identities();
    held_out();
    walk_balance();
    extremes();
    MF_TEST_MAIN_END();
}
