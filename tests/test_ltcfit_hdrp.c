/*
 * test_ltcfit_hdrp.c -- the LTC fitted on Unity HDRP's grid (mf_ltcfit_hdrp.h) and its C# file
 * (mf_ltc_write_hdrp):
 *   - HDRP's layout: entries 1, 3, 5, 7 zero, entry 8 one, the (1, 1) entry 1 / minv_22 > 0;
 *   - the same bits for 1 and 3 threads (every texel is an independent fit);
 *   - each texel equals a direct fit at HDRP's (r, theta) from the same start, and at theta = 0 the
 *     lobe is symmetric (m00 = m11 and m02 = m20 = 0 within the fit's Monte Carlo noise, 5e-3
 *     relative as in test_ltcfit's normal-incidence test);
 *   - the C# file reads back to the same values (%.9g: 5e-9 relative) and the writer refuses a
 *     bad array name and non-finite values with a message.
 */
#define _POSIX_C_SOURCE 200809L
#include "mf_test.h"

#include "mfkit/mfkit.h"
#include "mfkit/fit/mf_ltcfit.h"
#include "mfkit/fit/mf_ltcfit_hdrp.h"
#include "mfkit/io/mf_ltc_export.h"

#include <string.h>
#include <unistd.h>

int main(void)
{
    const mf_brdf_model *m = mf_brdf_model_find("ggx");
    mf_ltcfit_options o;
    mf_ltcfit_options_default(&o);
    o.n_r = o.n_u = 8;
    o.threads = 2;
    o.samples = 1024;
    mf_table start;
    mf_ltcfit_result res;
    char msg[512];
    CHECK(mf_ltcfit_table(m, &o, &start, &res, msg, sizeof msg) == MF_OK);
    mf_ltcfit_result_free(&res);

    enum { N = 6 };
    static double rows1[N * N * 9], rows3[N * N * 9];
    mf_ltcfit_hdrp_report r1, r3;
    o.threads = 1;
    CHECK(mf_ltcfit_hdrp(m, &start, &o, N, rows1, &r1) == MF_OK);
    o.threads = 3;
    CHECK(mf_ltcfit_hdrp(m, &start, &o, N, rows3, &r3) == MF_OK);
    CHECK(memcmp(rows1, rows3, sizeof rows1) == 0);
    CHECK(r1.fallbacks == r3.fallbacks && r1.worst_residual == r3.worst_residual);
    printf("HDRP grid %d x %d: %d texels kept the start, worst residual %.3g (1 and 3 threads: same bits)\n", N, N,
           r1.fallbacks, r1.worst_residual);
    /* a texel keeps its start only where the fit fails: at most the r = 0 column (alpha 1e-4, a
     * near-mirror lobe) on this coarse start table */
    CHECK(r1.fallbacks <= N);
    for (int i = 0; i < N * N; ++i) {
        const double *row = rows1 + 9 * i;
        CHECK(row[1] == 0.0 && row[3] == 0.0 && row[5] == 0.0 && row[7] == 0.0 && row[8] == 1.0 && row[4] > 0.0);
    }
    /* texel (i_r, i_theta) = a direct fit at r = i_r / (N - 1), theta = i_theta / (N - 1) pi/2 */
    for (int it = 0; it < N; it += 2)
        for (int ir = 1; ir < N; ir += 2) {
            double r = (double)ir / (N - 1), alpha = r * r, theta = fmin(it * 0.5 * MF_PI / (N - 1), MF_LTC_THETA_MAX);
            double p[2] = {r, sqrt(1.0 - cos(theta))}, rec[MF_LTC_NFIELDS], m0[9], f4[4];
            mf_ltc ltc;
            CHECK(mf_table_lookup(&start, p, rec) == MF_OK && mf_ltc_table_unpack(rec, &ltc) == MF_OK);
            for (int k = 0; k < 9; ++k)
                m0[k] = ltc.m.m[k / 3][k % 3];
            mf_ltcfit_entry e;
            CHECK(mf_ltcfit_entry_fit(m, alpha, cos(theta), m0, &o, &e) == MF_OK);
            CHECK(mf_ltc_table_pack(e.a, e.b, e.c, e.d, f4) == MF_OK);
            const double *row = rows1 + 9 * (ir + N * it);
            const double sc = 1.0 / f4[3]; /* HDRP's normalisation (M^-1)_22 = 1, as mf_ltcfit_hdrp computes it */
            CHECK(row[0] == f4[0] * sc && row[2] == f4[1] * sc && row[6] == f4[2] * sc && row[4] == sc);
            if (it == 0) { /* normal incidence: a symmetric lobe */
                CHECK_REL(row[0], row[4], 5e-3);
                CHECK_ABS(row[2], 0.0, 5e-3 * row[4]);
                CHECK_ABS(row[6], 0.0, 5e-3 * row[4]);
            }
        }

    /* the C# file */
    char dir[] = "/tmp/mfkit_hdrpXXXXXX", path[600];
    CHECK(mkdtemp(dir) != NULL);
    snprintf(path, sizeof path, "%s/LtcData.GGX.cs", dir);
    CHECK(mf_ltc_write_hdrp(path, rows1, N, NULL, "a test", msg, sizeof msg) == MF_OK);
    FILE *f = fopen(path, "r");
    char line[1024];
    int nrows = 0, has_array = 0;
    double worst = 0.0;
    while (f && fgets(line, sizeof line, f)) {
        if (strstr(line, "public static double[,] s_LtcGGXMatrixData = new double[k_LtcLUTResolution"))
            has_array = 1;
        double v[9];
        if (sscanf(line, " {%lf, %lf, %lf, %lf, %lf, %lf, %lf, %lf, %lf}", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5],
                   &v[6], &v[7], &v[8]) == 9 && nrows < N * N) {
            for (int k = 0; k < 9; ++k)
                worst = fmax(worst, fabs(v[k] - rows1[9 * nrows + k]) / fmax(fabs(rows1[9 * nrows + k]), 1e-300));
            ++nrows;
        }
    }
    if (f)
        fclose(f);
    printf("C# file: %d rows read back, worst relative difference %.3g\n", nrows, worst);
    CHECK(has_array && nrows == N * N && worst <= 5e-9);
    CHECK(mf_ltc_write_hdrp(path, rows1, N, "bad-name", NULL, msg, sizeof msg) == MF_ERR_DOMAIN && strstr(msg, path));
    rows1[7] = NAN;
    CHECK(mf_ltc_write_hdrp(path, rows1, N, NULL, NULL, msg, sizeof msg) == MF_ERR_DOMAIN && msg[0]);
    unlink(path);
    rmdir(dir);
    mf_table_free(&start);
    MF_TEST_MAIN_END();
}
