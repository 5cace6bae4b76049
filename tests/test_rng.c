/* test_rng.c -- PCG32 against its reference outputs, low-discrepancy sets (mf_rng.h). */
#include "mf_test.h"
#include "mfkit/mf_rng.h"

int main(void)
{
    /* The reference pcg32-demo (pcg-c-basic) with pcg32_srandom_r(&rng, 42, 54) prints
     * 0xa15c02b7 0x7b47f409 0xba1d3330 0x83d2f293 0xbfa4784b 0xcbed606e. */
    static const uint32_t expect[6] = {0xa15c02b7u, 0x7b47f409u, 0xba1d3330u, 0x83d2f293u, 0xbfa4784bu, 0xcbed606eu};
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, 42u, 54u);
    for (int i = 0; i < 6; ++i)
        CHECK(mf_pcg32_next_u32(&rng) == expect[i]);

    /* doubles in [0, 1), mean 1/2 within 5 standard errors (sd of U(0,1) = 1/sqrt(12)) */
    mf_pcg32_seed(&rng, mf_test_seed(1234), 0);
    const int n = 1000000;
    double sum = 0.0, sum_n = 0.0, sum_n2 = 0.0;
    int in_range = 1;
    for (int i = 0; i < n; ++i) {
        double u = mf_pcg32_next_double(&rng);
        in_range &= (u >= 0.0 && u < 1.0);
        sum += u;
    }
    CHECK(in_range);
    CHECK_MC(sum / n, 1.0 / sqrt(12.0 * n), 0.5, 5.0, 0.0);
    for (int i = 0; i < n; ++i) {
        double g = mf_pcg32_next_normal(&rng);
        sum_n += g;
        sum_n2 += g * g;
    }
    /* normal: mean 0 (se 1/sqrt(n)), variance 1 (se sqrt(2/n)) */
    CHECK_MC(sum_n / n, 1.0 / sqrt((double)n), 0.0, 5.0, 0.0);
    CHECK_MC(sum_n2 / n, sqrt(2.0 / n), 1.0, 5.0, 0.0);

    /* radical inverse: exact binary fractions */
    CHECK(mf_radical_inverse2(1) == 0.5);
    CHECK(mf_radical_inverse2(2) == 0.25);
    CHECK(mf_radical_inverse2(3) == 0.75);
    CHECK(mf_radical_inverse2(6) == 0.375);

    /* Sobol 2D: every power-of-two prefix of 2^m points is a (0, m, 2)-net: each of the 2^m
     * elementary intervals [a 2^-k, (a+1) 2^-k) x [b 2^-(m-k), ...) holds exactly one point.
     * Checked for m = 1..10 and every split k, with and without a scramble. */
    for (int scr = 0; scr < 2; ++scr)
        for (int m = 1; m <= 10; ++m) {
            int npts = 1 << m;
            for (int k = 0; k <= m; ++k) {
                static int count[1 << 10];
                for (int c = 0; c < npts; ++c)
                    count[c] = 0;
                for (int i = 0; i < npts; ++i) {
                    double p[2];
                    mf_sobol2((uint32_t)i, scr ? 0x9e3779b9u : 0u, scr ? 0x7f4a7c15u : 0u, p);
                    int a = (int)(p[0] * (1 << k)), b = (int)(p[1] * (1 << (m - k)));
                    count[a * (1 << (m - k)) + b]++;
                }
                int ok = 1;
                for (int c = 0; c < npts; ++c)
                    ok &= (count[c] == 1);
                CHECK(ok);
            }
        }
    double h[2];
    mf_hammersley(3, 8, h);
    CHECK(h[0] == 3.5 / 8.0 && h[1] == 0.75);
    MF_TEST_MAIN_END();
}
