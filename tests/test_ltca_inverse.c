/*
 * test_ltca_inverse.c -- the anisotropic LTC gate's ltca_inverse check (mf_ltc_aniso_table.c): minv is
 * m's inverse within what the table's storage allows.  A synthetic 2 x 2 x 3 x 3 table (no fit): every
 * entry a random matrix near the identity, two of them ill-conditioned (condition about 1e5 and 1e3),
 * minv their float64 inverse.
 *   - in memory (u = 0) the check passes, strictly: minv changed by 4 units of float64 rounding in
 *     one small entry (m01, about 1e-3) still passes, by 1e-8 relative (a sixth of float32 rounding) fails;
 *   - written as float32 .npy and .json and read back, it passes with the file's unit roundoff
 *     (2^-24) and fails with u = 0 (what bench_ltc_aniso used to do with --table);
 *   - a file entry corrupted by 1e-4 relative fails, whether the entry is a large one (a diagonal
 *     entry of minv) or a small one (m01, about 1e-3 of its matrix: the former measure over the
 *     Frobenius norms, |minv m - I| / (|minv|_F |m|_F) against 3 u, let that one pass; printed).
 * Fixed seed; the tolerances are the check's own bound (1), derived in mf_ltc_aniso_table.c.
 */
#define _POSIX_C_SOURCE 200809L

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <mfkit/io/mf_table_io.h>
#include <mfkit/mf_ltc_aniso_table.h>
#include <mfkit/mf_rng.h>
#include <mfkit/mf_table_kind.h>

#include "mf_test.h"
#include "test_files.h"

static char dir[] = "/tmp/mfkit_test_ltca_inverse_XXXXXX";

/* ltca_inverse's result on t with storage unit roundoff u; *worst gets its measure */
static int inverse_passes(const mf_table *t, double u, double *worst, char *at, size_t at_size)
{
    mf_ltc_aniso_gate_options o;
    mf_ltc_aniso_gate_options_default(&o);
    o.unit_roundoff = u;
    mf_check ch[MF_LTC_ANISO_GATE_MAX_CHECKS];
    int n = 0;
    mf_status st = mf_ltc_aniso_gate_run(t, NULL, &o, ch, MF_LTC_ANISO_GATE_MAX_CHECKS, &n);
    CHECK(st == MF_OK || st == MF_ERR_CHECK_FAILED);
    for (int i = 0; i < n; ++i)
        if (!strcmp(ch[i].name, "ltca_inverse")) {
            *worst = ch[i].worst;
            snprintf(at, at_size, "%s", ch[i].worst_at);
            CHECK(ch[i].bound == 1.0);
            return ch[i].passed;
        }
    CHECK(!"ltca_inverse not run");
    return -1;
}

/* the former measure: max |minv m - I| / (|minv|_F |m|_F) over the table */
static double frobenius_measure(const mf_table *t)
{
    double worst = 0.0;
    for (size_t e = 0; e < mf_table_texels(t); ++e) {
        const double *r = t->data + e * (size_t)t->nfields, *m = r + MF_LTCA_F_M00, *mi = r + MF_LTCA_F_MINV00;
        double na = 0.0, nb = 0.0, w = 0.0;
        for (int k = 0; k < 9; ++k)
            na += mi[k] * mi[k], nb += m[k] * m[k];
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) {
                double p = 0.0;
                for (int k = 0; k < 3; ++k)
                    p += mi[3 * a + k] * m[3 * k + b];
                w = fmax(w, fabs(p - (a == b)));
            }
        worst = fmax(worst, w / sqrt(na * nb));
    }
    return worst;
}

int main(void)
{
    if (!mkdtemp(dir)) {
        printf("cannot create %s\n", dir);
        return 1;
    }
    const int n[4] = {2, 2, 3, 3};
    mf_table t;
    CHECK(mf_ltc_aniso_table_create(&t, n, 0) == MF_OK);
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, 2026, 14);
    size_t ne = mf_table_texels(&t);
    for (size_t e = 0; e < ne; ++e) {
        double *r = t.data + e * (size_t)t.nfields;
        mf_mat3 m, mi;
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b)
                m.m[a][b] = (a == b) + 0.3 * (2.0 * mf_pcg32_next_double(&rng) - 1.0);
        m.m[0][1] = 1e-3 * (1.0 + mf_pcg32_next_double(&rng)); /* a small entry */
        if (e == 5 || e == 17) { /* ill-conditioned: rows scaled by 300 and 1/300 (or 30, 1/30) */
            double s = e == 5 ? 300.0 : 30.0;
            for (int b = 0; b < 3; ++b)
                m.m[0][b] *= s, m.m[2][b] /= s;
        }
        CHECK(mf_mat3_inverse(m, &mi) == MF_OK);
        for (int k = 0; k < 9; ++k) {
            r[MF_LTCA_F_M00 + k] = m.m[k / 3][k % 3];
            r[MF_LTCA_F_MINV00 + k] = mi.m[k / 3][k % 3];
        }
        r[MF_LTCA_F_MAGNITUDE] = 0.5;
        r[MF_LTCA_F_FRESNEL] = 0.1;
        r[MF_LTCA_F_RESIDUAL] = 0.0;
    }
    double w;
    char at[200];
    /* in memory: strict */
    CHECK(inverse_passes(&t, 0.0, &w, at, sizeof at) == 1);
    printf("in memory, u = 0: ltca_inverse %.3g of its bound at %s\n", w, at);
    size_t small = 3 * (size_t)t.nfields + MF_LTCA_F_M00 + 1; /* entry 3's m01, 1e-3 to 2e-3 */
    double keep = t.data[small];
    t.data[small] = keep * (1.0 + 4.0 * DBL_EPSILON);
    CHECK(inverse_passes(&t, 0.0, &w, at, sizeof at) == 1);
    printf("in memory, m01 of entry 3 (%.3g) x (1 + 4 eps): %.3g, passes\n", keep, w);
    t.data[small] = keep * (1.0 + 1e-8);
    CHECK(inverse_passes(&t, 0.0, &w, at, sizeof at) == 0);
    printf("in memory, the same x (1 + 1e-8, a sixth of float32 rounding): %.3g, fails\n", w);
    t.data[small] = keep;
    /* read back from float32 files */
    const char *ext[2] = {"npy", "json"};
    for (int f = 0; f < 2; ++f) {
        char path[128], msg[256];
        snprintf(path, sizeof path, "%s/ltca.%s", dir, ext[f]);
        CHECK(mf_table_write(path, &t, NULL, NULL, msg, sizeof msg) == MF_OK);
        mf_table b;
        mf_table_file_info info;
        CHECK(mf_table_read(path, &b, &info, msg, sizeof msg) == MF_OK);
        double u = mf_table_storage_roundoff(info.half_float);
        CHECK(u == 0x1p-24);
        CHECK(inverse_passes(&b, u, &w, at, sizeof at) == 1);
        printf("%s read back, u = 2^-24: %.3g of the bound at %s; the former measure %.3g against 3 u = %.3g\n", ext[f], w,
               at, frobenius_measure(&b), 3.0 * u);
        CHECK(inverse_passes(&b, 0.0, &w, at, sizeof at) == 0);
        printf("%s read back, u = 0 (the strict bound of a table in memory): %.3g, fails\n", ext[f], w);
        /* corrupted entries: a small one and a large one */
        size_t which[2] = {small, 7 * (size_t)b.nfields + MF_LTCA_F_MINV00 + 4};
        for (int c = 0; c < 2; ++c) {
            double v = b.data[which[c]];
            b.data[which[c]] = (double)(float)(v * (1.0 + 1e-4));
            double fro = frobenius_measure(&b);
            int pass = inverse_passes(&b, u, &w, at, sizeof at);
            printf("%s, %s entry %.3g x (1 + 1e-4): ltca_inverse %.3g, %s (the former measure %.3g: %s)\n", ext[f],
                   c ? "a large" : "a small", v, w, pass ? "passes" : "fails", fro, fro <= 3.0 * u ? "would pass" : "fails");
            CHECK(pass == 0);
            b.data[which[c]] = v;
        }
        mf_table_free(&b);
        remove(path);
    }
    mf_table_free(&t);
    rmdir(dir);
    MF_TEST_MAIN_END();
}
