/*
 * test_ltc_gate.c -- the LTC gate (mf_ltc_gate.h): a table with the exact answer passes every
 * check; deliberately corrupted copies fail the check made for that defect; the reader of the
 * reference CSV (mf_ltc_reference.h, in mfkit_io) reads the 64 x 64 table.
 *
 * The exact table: Lambert (f cos = cos / pi) is the clamped cosine itself, so its LTC is the
 * identity (minv = [1, 0, 0, 1]) with magnitude 1 and fresnel = integral of cos/pi (1 - wo.wh)^5,
 * which we do not need: the gate only requires 0 <= fresnel <= magnitude, so we store 0.
 *
 * usage: test_ltc_gate [REFERENCE_DIR]   (default: the compile definition MFKIT_REFERENCE_DIR,
 * the vendored tests/data/reference of the source tree; a missing table is a failure)
 */
#include "mf_test.h"
#include "test_tables.h"

#include "mfkit/mfkit.h"
#ifdef MFKIT_HAVE_FIT
#include "mfkit/io/mf_ltc_reference.h"
#endif

#include <string.h>
#ifdef MFKIT_HAVE_LTCFIT
#include "mfkit/fit/mf_ltc_bake.h"

/* The gate's power (issue 14): single-texel corruptions of a fitted 16 x 16 GGX table (at 16 x 16
 * the smoothness checks miss them: neighbours are too far apart), each matrix field and the
 * magnitude, by amounts that cross the threshold and by amounts that do not; fixed seed.
 *   - matrix field v -> v + delta max(|v|, 0.1) (an additive floor so that fields near 0 move too),
 *     delta from +-{0.01, 0.03, 0.1, 0.2, 0.3, 1}; which side of the threshold a corruption is on is
 *     measured, not assumed: D = mf_ltc_gate_texel_difference of the corrupted texel against the
 *     fitted one on the texel's gate polygons, "above" when D > 0.1 (the 10 %), except
 *     within BAND of 0.1 (below);
 *   - magnitude m -> m (1 + delta), delta from +-{5e-4, 3e-3, 1e-2, 0.1}: "above" when
 *     |delta| m exceeds the albedo check's allowance (1e-3 max(albedo, 0.01) + 4 err).
 * The gate is the pipeline's (mf_ltc_bake): mf_ltc_gate_run in full mode (its Monte Carlo
 * checks with 4096 samples: they are not under test here) plus the texel check
 * mf_ltc_bake_texel_check.  Asserted: the good table passes (no false alarm), every
 * "above" corruption fails (power 1).  Reported: the false-alarm rate on the "below" set. */
static int full_gate_fails(const mf_table *t, const mf_brdf_model *m, const mf_ltcfit_options *fo, int *texel_failed,
                           int *albedo_failed, double *texel_worst)
{
    mf_check c[MF_LTC_GATE_MAX_CHECKS + 1];
    int n = 0;
    mf_ltc_gate_options o;
    mf_ltc_gate_options_default(&o);
    o.seed = fo->seed;
    o.mc_samples = 4096; /* the polygon checks are not under test here (512 is too few: a small polygon that no sample hits has a zero standard error) */
    mf_status st = mf_ltc_gate_run(t, m, &o, c, MF_LTC_GATE_MAX_CHECKS, &n);
    CHECK(st == MF_OK || st == MF_ERR_CHECK_FAILED);
    mf_status ts = mf_ltc_bake_texel_check(t, m, fo, fo->seed, 2, &c[n]);
    CHECK(ts == MF_OK);
    *texel_failed = !c[n].passed;
    *texel_worst = c[n].worst;
    *albedo_failed = mf_test_check_passed(c, n, "ltc_albedo_quad") == 0;
    ++n;
    int failed = 0;
    for (int k = 0; k < n; ++k)
        failed |= !c[k].passed;
    return failed;
}

/* The gate compares a texel with a refit of it, not with the original fit: the refit reproduces a
 * good texel's shading to within about 1 % (measured: 98.5 % of the default 64 x 64 table's texels
 * within 1 %, this 16 x 16 table within 3.4 %), so within +-0.005 of the threshold either verdict
 * is right (a corruption with D = 0.1002 read 0.0999).  Cases in that band are reported apart. */
#define BAND 0.005

static void power_test(void)
{
    const mf_brdf_model *ggx = mf_brdf_model_find("ggx");
    CHECK(ggx != NULL);
    if (!ggx)
        return;
    mf_ltcfit_options fo;
    mf_ltcfit_options_default(&fo);
    fo.n_r = fo.n_u = 16;
    fo.threads = 2;
    mf_table good;
    mf_ltcfit_result fr;
    char msg[512] = "";
    mf_status st = mf_ltcfit_table(ggx, &fo, &good, &fr, msg, sizeof msg);
    CHECK(st == MF_OK);
    if (st != MF_OK) {
        fprintf(stderr, "fit: %s\n", msg);
        return;
    }
    mf_ltcfit_result_free(&fr);
    int tf = 0, af = 0;
    double tw = 0.0;
    int good_fails = full_gate_fails(&good, ggx, &fo, &tf, &af, &tw);
    printf("power: the fitted 16 x 16 GGX table: gate %s, ltc_texel_refit worst %.4g\n", good_fails ? "FAILS" : "passes",
           tw);
    if (good_fails)
        MF_FAIL_AT("false alarm: the fitted 16 x 16 GGX table fails the gate (ltc_texel_refit worst %.4g)", tw);

    /* The issue's own example: one texel's minv_00 times 1.3 in a 16 x 16 table passed the old
     * gate, quick and full, while that texel shaded -20 % to +34 % wrong. */
    {
        mf_table bad13;
        CHECK(mf_table_copy(&bad13, &good) == MF_OK);
        int idx[2] = {5, 9};
        mf_table_record(&bad13, idx)[MF_LTC_F_MINV_00] *= 1.3;
        int failed = full_gate_fails(&bad13, ggx, &fo, &tf, &af, &tw);
        printf("power: texel (5, 9) minv_00 x 1.3: gate %s, ltc_texel_refit %.4g\n", failed ? "fails" : "passes", tw);
        CHECK(failed && tf);
        mf_table_free(&bad13);
    }

    const double dm[6] = {0.01, 0.03, 0.1, 0.2, 0.3, 1.0}, dg[4] = {5e-4, 3e-3, 1e-2, 0.1};
    const int fields[5] = {MF_LTC_F_MINV_00, MF_LTC_F_MINV_20, MF_LTC_F_MINV_02, MF_LTC_F_MINV_22, MF_LTC_F_MAGNITUDE};
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, 99, 14);
    const int ncases = 30;
    int above = 0, above_caught = 0, below = 0, below_flagged = 0, band = 0, band_flagged = 0;
    mf_table bad;
    for (int k = 0; k < ncases; ++k) {
        int ir = (int)(mf_pcg32_next_u32(&rng) % 16u), iu = (int)(mf_pcg32_next_u32(&rng) % 16u);
        int fi = fields[k % 5];
        double sign = mf_pcg32_next_u32(&rng) & 1u ? 1.0 : -1.0;
        int is_mag = fi == MF_LTC_F_MAGNITUDE;
        double delta = sign * (is_mag ? dg[mf_pcg32_next_u32(&rng) % 4u] : dm[mf_pcg32_next_u32(&rng) % 6u]);
        CHECK(mf_table_copy(&bad, &good) == MF_OK);
        int idx[2] = {ir, iu};
        double *r = mf_table_record(&bad, idx);
        double v0 = r[fi];
        r[fi] = is_mag ? v0 * (1.0 + delta) : v0 + delta * fmax(fabs(v0), 0.1);
        /* which side of the threshold: against the fitted texel (matrix), or the albedo allowance */
        int is_above;
        double D = 0.0;
        mf_ltc a, b;
        double ma, mb;
        mf_polygon polys[MF_LTC_GATE_TEXEL_POLYGONS];
        int ua = mf_ltc_gate_texel(&bad, ir, iu, &a, &ma) == MF_OK, ub = mf_ltc_gate_texel(&good, ir, iu, &b, &mb) == MF_OK;
        CHECK(ub);
        if (is_mag) {
            mf_result q;
            mf_brdf_params prm = mf_brdf_params_iso(mf_ltc_table_alpha(&good, ir));
            CHECK(mf_model_albedo(ggx, &prm, mf_ltc_gate_view(mf_ltc_table_cos_theta(&good, iu)), 64, &q) == MF_OK);
            D = fabs(r[fi] - q.val) / fmax(q.val, 0.01);
            is_above = fabs(r[fi] - q.val) > 1e-3 * fmax(q.val, 0.01) + 4.0 * q.err;
        } else if (!ua) {
            D = INFINITY; /* a matrix that cannot be unpacked: a defect by any measure */
            is_above = 1;
        } else {
            mf_ltc_gate_texel_polygons(&good, ggx, fo.seed, ir, iu, MF_LTC_GATE_TEXEL_POLYGONS, polys);
            D = mf_ltc_gate_texel_difference(&a, ma, &b, mb, polys, MF_LTC_GATE_TEXEL_POLYGONS, NULL);
            is_above = !(D <= MF_LTC_GATE_TEXEL_REL);
            /* the band within the gate's resolution of the threshold: neither asserted nor counted */
            if (fabs(D - MF_LTC_GATE_TEXEL_REL) < BAND)
                is_above = -1;
        }
        int failed = full_gate_fails(&bad, ggx, &fo, &tf, &af, &tw);
        printf("power: case %2d texel (%2d, %2d) %-9s %+7.4f: %s D %-9.4g -> gate %s (texel check %.4g%s%s)\n", k, ir, iu,
               bad.fields[fi], delta, is_above < 0 ? "band " : is_above ? "ABOVE" : "below", D, failed ? "fails" : "passes", tw,
               tf ? " FAIL" : "", af ? ", ltc_albedo_quad FAIL" : "");
        if (is_above < 0) {
            ++band;
            band_flagged += failed;
        } else if (is_above) {
            ++above;
            above_caught += failed;
            if (!failed)
                MF_FAIL_AT("power: corruption %d (texel %d %d, %s %+g, D %.4g above the threshold) passes the gate", k, ir,
                           iu, bad.fields[fi], delta, D);
        } else {
            ++below;
            below_flagged += failed;
        }
        mf_table_free(&bad);
    }
    printf("power: %d of %d corruptions above the threshold fail the gate (power %.3f); %d of %d below it fail "
           "(false-alarm rate %.3f)\n",
           above_caught, above, above ? (double)above_caught / above : NAN, below_flagged, below,
           below ? (double)below_flagged / below : NAN);
    printf("power: %d of %d within +-%g of the threshold fail\n", band_flagged, band, BAND);
    CHECK(above >= 10 && below >= 10); /* both sets are populated by the seed above */
    mf_table_free(&good);
}
#endif

static int lambert_table(mf_table *t, int n)
{
    if (mf_ltc_table_create(t, n, n) != MF_OK)
        return 0;
    for (size_t i = 0; i < mf_table_texels(t); ++i) {
        double *r = t->data + i * (size_t)t->nfields;
        r[MF_LTC_F_MINV_00] = 1.0;
        r[MF_LTC_F_MINV_22] = 1.0;
        r[MF_LTC_F_MAGNITUDE] = 1.0;
        /* sphere: the form-factor term is not checked beyond smoothness; a smooth stand-in. */
        r[MF_LTC_F_SPHERE] = 0.5;
    }
    return 1;
}

/* Runs the gate on t (quick, seed) and checks which checks fail: exactly those in `fail` (comma list). */
static void expect(const char *title, const mf_table *t, const mf_brdf_model *model, uint64_t seed, int quick,
                   const char *const *must_fail, int nfail)
{
    mf_check c[MF_LTC_GATE_MAX_CHECKS];
    int n = 0;
    mf_ltc_gate_options o;
    mf_ltc_gate_options_default(&o);
    o.seed = seed;
    o.quick = quick;
    mf_status st = mf_ltc_gate_run(t, model, &o, c, MF_LTC_GATE_MAX_CHECKS, &n);
    mf_test_print_checks(title, c, n);
    CHECK(n == (model ? 9 : 5));
    CHECK(st == (nfail ? MF_ERR_CHECK_FAILED : MF_OK));
    for (int k = 0; k < nfail; ++k) {
        const mf_check *x = mf_test_find_check(c, n, must_fail[k]);
        CHECK(x != NULL);
        if (x && x->passed)
            MF_FAIL_AT("%s: check %s passed but must fail", title, must_fail[k]);
    }
}

int main(int argc, char **argv)
{
    uint64_t seed = mf_test_seed(20240607);
    const mf_brdf_model *lambert = mf_brdf_model_find("lambert");
    CHECK(lambert != NULL);
    if (!lambert)
        MF_TEST_MAIN_END();
    const int N = 16;
    mf_table good;
    CHECK(lambert_table(&good, N));

    /* The exact table passes, with and without the model, quick and full. */
    expect("lambert identity, model-free", &good, NULL, seed, 1, NULL, 0);
    expect("lambert identity, quick", &good, lambert, seed, 1, NULL, 0);
    expect("lambert identity, full", &good, lambert, seed, 0, NULL, 0);

    /* Same seed, same report (determinism), and threads does not matter. */
    {
        mf_check a[MF_LTC_GATE_MAX_CHECKS], b[MF_LTC_GATE_MAX_CHECKS];
        int na = 0, nb = 0;
        mf_ltc_gate_options o;
        mf_ltc_gate_options_default(&o);
        o.seed = seed;
        o.quick = 1;
        mf_status s1 = mf_ltc_gate_run(&good, lambert, &o, a, MF_LTC_GATE_MAX_CHECKS, &na);
        o.threads = 7;
        mf_status s2 = mf_ltc_gate_run(&good, lambert, &o, b, MF_LTC_GATE_MAX_CHECKS, &nb);
        CHECK(s1 == s2 && na == nb);
        CHECK(memcmp(a, b, sizeof a) == 0);
    }

    /* One wrong entry, on a 32 x 32 table (16 h = 0.52), at texel (13, 18), which is on the quick
     * 8 x 8 grid (round(3 * 31 / 7) = 13, round(4 * 31 / 7) = 18).  A moderate error (the lobe
     * leaning by ~56 deg, or 3 times narrower along x) is caught by the smoothness checks; the
     * polygon check's per-texel budget is loose enough to pass the reference table at 89.95 deg
     * (docs/validation.md), so it catches only gross errors at one texel: the lobe 10 times
     * narrower and leaning.  Every case must fail the checks listed. */
    {
        mf_table big, bad;
        CHECK(lambert_table(&big, 32));
        const int idx[2] = {13, 18};
        const struct {
            const char *title;
            double m00, m02;
            int nfail;
            const char *fail[3];
        } cases[] = {
            {"one leaning matrix", 1.0, 1.5, 2, {"ltc_smooth_jump", "ltc_smooth_spike"}},
            {"one narrowed matrix", 3.0, 0.0, 2, {"ltc_smooth_jump", "ltc_smooth_spike"}},
            {"one grossly wrong matrix", 0.1, -3.0, 3, {"ltc_polygon_entry", "ltc_smooth_jump", "ltc_smooth_spike"}},
        };
        for (int k = 0; k < 3; ++k) {
            CHECK(mf_table_copy(&bad, &big) == MF_OK);
            double *r = mf_table_record(&bad, idx);
            r[MF_LTC_F_MINV_00] = cases[k].m00;
            r[MF_LTC_F_MINV_02] = cases[k].m02;
            expect(cases[k].title, &bad, lambert, seed, 1, cases[k].fail, cases[k].nfail);
            mf_table_free(&bad);
        }
        mf_table_free(&big);
    }
    /* The smoothness checks read the matrix scaled by its largest entry (docs/validation.md,
     * "Smoothness of the shape").  A ring lobe at the horizon, minv = diag(1, 1, s) with
     * s = 1 / (2 alpha) as a charlie table holds near the normal view (s up to 5000 at alpha 1e-4),
     * is smooth in the shape it defines (scaled: diag(1/s, 1/s, 1), steps <= 4 h), though its
     * stored minv_22 steps by thousands: model-free it must pass every check on a 32 x 32 table
     * (the stored values would read 1.3e4 x the jump bound).  The same table with one texel
     * leaning (minv_02 = s: scaled 1 against 0 at its neighbours, 1.94 x the jump bound at
     * 32 x 32) must fail both smoothness checks; with every magnitude 1e-7 (below the 1e-5 at
     * which a shape starts to count fully) it reads 1e-2 of that and passes. */
    {
        mf_table ring, bad;
        CHECK(lambert_table(&ring, 32));
        for (int iu = 0; iu < 32; ++iu)
            for (int ir = 0; ir < 32; ++ir) {
                const int id[2] = {ir, iu};
                double *r = mf_table_record(&ring, id);
                r[MF_LTC_F_MINV_22] = 1.0 / (2.0 * mf_ltc_table_alpha(&ring, ir));
                r[MF_LTC_F_MAGNITUDE] = 0.5;
            }
        expect("ring lobes, diag(1, 1, 1 / (2 alpha)), model-free", &ring, NULL, seed, 1, NULL, 0);
        const int id[2] = {13, 18};
        CHECK(mf_table_copy(&bad, &ring) == MF_OK);
        double *r = mf_table_record(&bad, id);
        r[MF_LTC_F_MINV_02] = r[MF_LTC_F_MINV_22];
        const char *const f[] = {"ltc_smooth_jump", "ltc_smooth_spike"};
        expect("ring lobes, one leaning texel", &bad, NULL, seed, 1, f, 2);
        for (size_t i = 0; i < mf_table_texels(&bad); ++i)
            bad.data[i * (size_t)bad.nfields + MF_LTC_F_MAGNITUDE] = 1e-7;
        expect("ring lobes, one leaning texel, magnitude 1e-7", &bad, NULL, seed, 1, NULL, 0);
        mf_table_free(&bad);
        mf_table_free(&ring);
    }
    /* An albedo > 1. */
    {
        mf_table bad;
        CHECK(mf_table_copy(&bad, &good) == MF_OK);
        int idx[2] = {2, 13};
        mf_table_record(&bad, idx)[MF_LTC_F_MAGNITUDE] = 1.02;
        const char *const f[] = {"ltc_energy"};
        expect("albedo 1.02, model-free", &bad, NULL, seed, 1, f, 1);
        mf_table_free(&bad);
    }
    /* The spike check of the magnitude.  (1) One magnitude 0.03 low (1.5 x 80 h^2 at 64 x 64) at a
     * texel off the quick grid: with the model the spike is measured on magnitude - albedo and
     * still fails, as it does model-free.  (2) The magnitude equal to the true GGX albedo (64 x 64
     * quadrature, identity matrices): model-free, the spike check fails on the albedo's own dip at
     * the grazing rows of low roughness (alpha 0.016: 0.962, 0.912, 0.990 at 86.4, 88.2, 89.95 deg;
     * docs/validation.md); with the GGX model it passes, as the error field is smooth. */
    {
        mf_table big;
        CHECK(lambert_table(&big, 64));
        const int idx[2] = {20, 37};
        mf_table_record(&big, idx)[MF_LTC_F_MAGNITUDE] = 0.97;
        const char *const f[] = {"ltc_smooth_spike"};
        expect("one magnitude 0.03 low, lambert", &big, lambert, seed, 1, f, 1);
        expect("one magnitude 0.03 low, model-free", &big, NULL, seed, 1, f, 1);
        mf_table_free(&big);
        const mf_brdf_model *ggx = mf_brdf_model_find("ggx");
        CHECK(ggx != NULL);
        if (ggx && lambert_table(&big, 64)) {
            int ok = 1;
            for (int iu = 0; iu < 64 && ok; ++iu)
                for (int ir = 0; ir < 64 && ok; ++ir) {
                    mf_result q;
                    const int id[2] = {ir, iu};
                    mf_brdf_params prm = mf_brdf_params_iso(mf_ltc_table_alpha(&big, ir));
                    ok = mf_model_albedo(ggx, &prm, mf_ltc_gate_view(mf_ltc_table_cos_theta(&big, iu)), 64, &q) == MF_OK;
                    mf_table_record(&big, id)[MF_LTC_F_MAGNITUDE] = q.val;
                }
            CHECK(ok);
            mf_check c[MF_LTC_GATE_MAX_CHECKS];
            int n = 0;
            CHECK(mf_ltc_gate_run(&big, NULL, NULL, c, MF_LTC_GATE_MAX_CHECKS, &n) == MF_ERR_CHECK_FAILED);
            mf_test_print_checks("true GGX albedo, model-free", c, n);
            const mf_check *sp = mf_test_find_check(c, n, "ltc_smooth_spike");
            CHECK(sp && !sp->passed && strstr(sp->worst_at, "magnitude along u"));
            mf_ltc_gate_options o;
            mf_ltc_gate_options_default(&o);
            o.quick = 1;
            o.seed = seed;
            mf_status gs = mf_ltc_gate_run(&big, ggx, &o, c, MF_LTC_GATE_MAX_CHECKS, &n);
            CHECK(gs == MF_OK || gs == MF_ERR_CHECK_FAILED);
            mf_test_print_checks("true GGX albedo, ggx, quick", c, n);
            sp = mf_test_find_check(c, n, "ltc_smooth_spike");
            CHECK(sp && sp->passed);
            mf_table_free(&big);
        }
    }
    /* An albedo uniformly 2 % low (the reference's weakness): the albedo checks fail. */
    {
        mf_table bad;
        CHECK(mf_table_copy(&bad, &good) == MF_OK);
        for (size_t i = 0; i < mf_table_texels(&bad); ++i)
            bad.data[i * (size_t)bad.nfields + MF_LTC_F_MAGNITUDE] = 0.98;
        const char *const f[] = {"ltc_albedo_quad", "ltc_albedo_mc"};
        expect("albedo 2% low", &bad, lambert, seed, 1, f, 2);
        mf_table_free(&bad);
    }
    /* A NaN. */
    {
        mf_table bad;
        CHECK(mf_table_copy(&bad, &good) == MF_OK);
        int idx[2] = {5, 5};
        mf_table_record(&bad, idx)[MF_LTC_F_MINV_20] = NAN;
        const char *const f[] = {"ltc_finite", "ltc_normalisation"};
        expect("a NaN", &bad, NULL, seed, 1, f, 2);
        mf_table_free(&bad);
    }
    /* The NaN rule of mf_check.h in the gate: a NaN magnitude is a NaN case of ltc_energy, which
     * fails with worst = NaN and "NaN at <texel>" (the first NaN, even though the texels after it
     * are fine); a NaN in a matrix field cannot be unpacked, which ltc_normalisation counts as
     * +infinity with the reason. */
    {
        mf_table bad;
        CHECK(mf_table_copy(&bad, &good) == MF_OK);
        int idx[2] = {5, 7};
        mf_table_record(&bad, idx)[MF_LTC_F_MAGNITUDE] = NAN;
        int idx2[2] = {2, 9};
        mf_table_record(&bad, idx2)[MF_LTC_F_MINV_20] = NAN;
        mf_check c[MF_LTC_GATE_MAX_CHECKS];
        int n = 0;
        CHECK(mf_ltc_gate_run(&bad, NULL, NULL, c, MF_LTC_GATE_MAX_CHECKS, &n) == MF_ERR_CHECK_FAILED);
        mf_test_print_checks("NaN rule", c, n);
        const mf_check *en = mf_test_find_check(c, n, "ltc_energy");
        const mf_check *no = mf_test_find_check(c, n, "ltc_normalisation");
        CHECK(en && !en->passed && isnan(en->worst));
        CHECK(en && strstr(en->worst_at, "NaN at ") == en->worst_at && strstr(en->worst_at, "ir 5, iu 7"));
        CHECK(en && en->cases == (long)mf_table_texels(&bad));
        CHECK(no && !no->passed && isinf(no->worst) && strstr(no->worst_at, "singular or non-finite matrix (ir 2, iu 9"));
        mf_table_free(&bad);
    }
    /* The table of checks: the run writes them in its order, model checks only with a model. */
    {
        int nd = 0;
        const mf_check_def *d = mf_ltc_gate_checks(&nd);
        CHECK(nd == MF_LTC_GATE_MAX_CHECKS);
        CHECK(mf_check_defs_count(d, nd, 0) == 5 && mf_check_defs_count(d, nd, 1) == 9);
        mf_check c[MF_LTC_GATE_MAX_CHECKS];
        int n = 0;
        CHECK(mf_ltc_gate_run(&good, NULL, NULL, c, MF_LTC_GATE_MAX_CHECKS, &n) == MF_OK);
        for (int i = 0, k = 0; i < nd; ++i) {
            if (d[i].needs_model)
                continue;
            CHECK(k < n && !strcmp(c[k].name, d[i].name) && c[k].bound == d[i].bound);
            ++k;
        }
        /* energy values are <= 0 on the exact table (magnitude 1, fresnel 0: max(0, -1, -1, -0)), and
         * the check reports worst = 0 (mf_check.h: worst is the maximum of the values and 0) */
        const mf_check *en = mf_test_find_check(c, n, "ltc_energy");
        CHECK(en && en->worst == 0.0 && en->passed);
        char why[160];
        CHECK(mf_ltc_gate_layout_ok(&good, why, sizeof why) == 1);
        mf_table bad;
        CHECK(mf_table_copy(&bad, &good) == MF_OK);
        snprintf(bad.fields[MF_LTC_F_MINV_02], sizeof bad.fields[0], "other");
        CHECK(mf_ltc_gate_layout_ok(&bad, why, sizeof why) == 0);
        printf("layout reason: %s\n", why);
        CHECK(strstr(why, "minv_02") != NULL);
        mf_table_free(&bad);
    }
    /* A singular matrix. */
    {
        mf_table bad;
        CHECK(mf_table_copy(&bad, &good) == MF_OK);
        int idx[2] = {9, 3};
        double *r = mf_table_record(&bad, idx);
        r[MF_LTC_F_MINV_00] = 0.0;
        const char *const f[] = {"ltc_normalisation"};
        expect("singular matrix", &bad, NULL, seed, 1, f, 1);
        mf_table_free(&bad);
    }
    /* Not an LTC layout. */
    {
        mf_check c[MF_LTC_GATE_MAX_CHECKS];
        int n = -1;
        mf_table bad;
        CHECK(mf_table_copy(&bad, &good) == MF_OK);
        bad.axes[1].mapping = MF_AXIS_IDENTITY;
        CHECK(mf_ltc_gate_run(&bad, NULL, NULL, c, MF_LTC_GATE_MAX_CHECKS, &n) == MF_ERR_DOMAIN);
        CHECK(n == 0);
        CHECK(mf_ltc_gate_run(&good, NULL, NULL, c, 3, &n) == MF_ERR_DOMAIN);
        mf_table_free(&bad);
    }

    /* The building blocks: quadrature albedo of GGX against its own error estimate and MC. */
    {
        const mf_brdf_model *ggx = mf_brdf_model_find("ggx");
        CHECK(ggx != NULL);
        if (ggx) {
            mf_result q, mc;
            mf_vec3 wo = mf_ltc_gate_view(0.3);
            mf_brdf_params prm = mf_brdf_params_iso(0.5);
            CHECK(mf_model_albedo(ggx, &prm, wo, 256, &q) == MF_OK);
            CHECK(q.err < 5e-5 && q.val > 0.5 && q.val < 1.0);
            CHECK(mf_ltc_gate_polygon_mc(ggx, 0.5, wo, NULL, 0, 100000, seed, 3, NULL, NULL, &mc) == MF_OK);
            /* z = 4.5 (two-sided 7e-6), delta = the quadrature's error estimate. */
            CHECK_MC(mc.val, mc.err, q.val, 4.5, q.err);
        }
    }

    mf_table_free(&good);

#ifdef MFKIT_HAVE_LTCFIT
    power_test();
#else
    printf("SKIP: the gate's power test (built without the fitters)\n");
#endif

#ifdef MFKIT_HAVE_FIT
    /* The reference CSV reader. */
    {
#ifdef MFKIT_REFERENCE_DIR
        const char *dir = argc > 1 ? argv[1] : MFKIT_REFERENCE_DIR;
#else
        const char *dir = argc > 1 ? argv[1] : NULL;
#endif
        char path[4096];
        snprintf(path, sizeof path, "%s/ltc_code_ggx_64.csv", dir ? dir : ".");
        FILE *f = dir ? fopen(path, "rb") : NULL;
        if (!f) {
            MF_FAIL_AT("reference table %s cannot be opened: it is vendored in tests/data/reference "
                       "(or pass the directory as the argument)", path);
        } else {
            fclose(f);
            mf_table ref;
            char msg[512];
            mf_status st = mf_ltc_reference_read_csv(path, &ref, msg, sizeof msg);
            CHECK(st == MF_OK);
            if (st != MF_OK) {
                fprintf(stderr, "%s\n", msg);
            } else {
                CHECK(mf_ltc_reference_is_csv(path));
                CHECK(ref.axes[0].size == 64 && ref.axes[1].size == 64);
                CHECK(mf_table_texels(&ref) == 4096);
                /* Rows of the CSV: (i_theta 0, i_alpha 1): invMn_r2c2 0.000503905, magnitude 1;
                 * alpha of texel 0 is the 1e-5 clamp; theta of the last row is the 1.57 cap. */
                int i01[2] = {1, 0};
                CHECK_ABS(mf_table_record(&ref, i01)[MF_LTC_F_MINV_22], 0.000503905, 0.0);
                CHECK_ABS(mf_table_record(&ref, i01)[MF_LTC_F_MAGNITUDE], 1.0, 0.0);
                CHECK_REL(mf_ltc_table_alpha(&ref, 0), 1e-5, 1e-15);
                CHECK_REL(mf_ltc_table_cos_theta(&ref, 63), cos(1.57), 1e-15);
                CHECK_REL(mf_ltc_table_alpha(&ref, 63), 1.0, 1e-15);
                /* Every value equals its CSV cell: re-read the file column by column. */
                FILE *g = fopen(path, "rb");
                char line[16384];
                int ok = g && fgets(line, sizeof line, g);
                int ci[9] = {-1, -1, -1, -1, -1, -1, -1, -1, -1};
                const char *names[9] = {"i_theta", "i_alpha", "invMn_r0c0", "invMn_r2c0", "invMn_r0c2",
                                        "invMn_r2c2", "magnitude", "fresnel", "sphere"};
                const int fields[7] = {MF_LTC_F_MINV_00, MF_LTC_F_MINV_20, MF_LTC_F_MINV_02, MF_LTC_F_MINV_22,
                                       MF_LTC_F_MAGNITUDE, MF_LTC_F_FRESNEL, MF_LTC_F_SPHERE};
                if (ok) {
                    int col = 0;
                    for (char *tok = strtok(line, ",\r\n"); tok; tok = strtok(NULL, ",\r\n"), ++col)
                        for (int k = 0; k < 9; ++k)
                            if (!strcmp(tok, names[k]))
                                ci[k] = col;
                }
                long rows = 0, mismatches = 0;
                while (ok && fgets(line, sizeof line, g)) {
                    double v[64];
                    int col = 0;
                    char *p = line;
                    for (; col < 64; ++col) {
                        v[col] = strtod(p, NULL);
                        p = strchr(p, ',');
                        if (!p)
                            break;
                        ++p;
                    }
                    int idx[2] = {(int)v[ci[1]], (int)v[ci[0]]};
                    const double *r = mf_table_record(&ref, idx);
                    for (int k = 0; k < 7; ++k)
                        if (!r || r[fields[k]] != v[ci[2 + k]])
                            ++mismatches;
                    ++rows;
                }
                if (g)
                    fclose(g);
                CHECK(rows == 4096);
                CHECK(mismatches == 0);
                /* The model-free gate on the reference runs (its verdict is reported by
                 * `mfkit validate`, docs/validation.md). */
                mf_check c[MF_LTC_GATE_MAX_CHECKS];
                int n = 0;
                mf_status gs = mf_ltc_gate_run(&ref, NULL, NULL, c, MF_LTC_GATE_MAX_CHECKS, &n);
                CHECK(gs == MF_OK || gs == MF_ERR_CHECK_FAILED);
                mf_test_print_checks("reference table, model-free", c, n);
                /* With the GGX model (quick): the reference's matrices pass the polygon budget, its
                 * albedo (32 x 32 MC, up to 6.5 % low at grazing) fails the albedo checks.  A
                 * wrong convention (minv_02 and minv_20 swapped: the transposed matrix) fails the
                 * polygon budget. */
                const mf_brdf_model *ggx = mf_brdf_model_find("ggx");
                if (ggx) {
                    const char *const fa[] = {"ltc_albedo_quad", "ltc_albedo_mc", "ltc_smooth_spike"};
                    mf_check cg[MF_LTC_GATE_MAX_CHECKS];
                    int ng = 0;
                    mf_ltc_gate_options o;
                    mf_ltc_gate_options_default(&o);
                    o.quick = 1;
                    o.seed = seed;
                    CHECK(mf_ltc_gate_run(&ref, ggx, &o, cg, MF_LTC_GATE_MAX_CHECKS, &ng) == MF_ERR_CHECK_FAILED);
                    mf_test_print_checks("reference table, ggx, quick", cg, ng);
                    for (int k = 0; k < 3; ++k)
                        CHECK(mf_test_check_passed(cg, ng, fa[k]) == 0);
                    CHECK(mf_test_check_passed(cg, ng, "ltc_polygon_mean") == 1);
                    CHECK(mf_test_check_passed(cg, ng, "ltc_polygon_entry") == 1);
                    for (size_t i = 0; i < mf_table_texels(&ref); ++i) {
                        double *r = ref.data + i * (size_t)ref.nfields, tmp = r[MF_LTC_F_MINV_02];
                        r[MF_LTC_F_MINV_02] = r[MF_LTC_F_MINV_20];
                        r[MF_LTC_F_MINV_20] = tmp;
                    }
                    CHECK(mf_ltc_gate_run(&ref, ggx, &o, cg, MF_LTC_GATE_MAX_CHECKS, &ng) == MF_ERR_CHECK_FAILED);
                    mf_test_print_checks("reference table transposed, ggx, quick", cg, ng);
                    CHECK(mf_test_check_passed(cg, ng, "ltc_polygon_mean") == 0);
                }
                mf_table_free(&ref);
            }
        }
        /* Malformed input is refused with a message. */
        {
            const char *bad = "test_ltc_gate_bad.csv"; /* in the test's working directory */
            FILE *h = fopen(bad, "wb");
            if (h) {
                fputs("i_theta,i_alpha,roughness,x_theta,invMn_r0c0,invMn_r2c0,invMn_r0c2,invMn_r2c2,magnitude,fresnel,sphere\n"
                      "0,0,0,0,1,0,0,1,1,0,0\n0,1,1,0,1,0,0,1,1,0,x\n",
                      h);
                fclose(h);
                mf_table t;
                char msg[512];
                CHECK(mf_ltc_reference_read_csv(bad, &t, msg, sizeof msg) == MF_ERR_FORMAT);
                CHECK(strstr(msg, "bad number") != NULL);
                remove(bad);
            }
        }
    }
#else
    (void)argc;
    (void)argv;
    printf("SKIP: reference CSV reader (built without the C++ dependencies)\n");
#endif
    MF_TEST_MAIN_END();
}
