/* test_prefilter_mix_fast.c -- the fused evaluation of the prefilter mixture (mf_prefilter.c,
 * mix_sample_weights at a cached view: directions sampled in chunks, the mixture evaluated over a
 * chunk two directions at a time) against the per-direction calls it replaces (sample, eval_cos and
 * pdf at the same cached view).  The fused path promises the same bits, so every comparison is
 * exact (memcmp): any reordering or contraction of its operations fails here.  The calls change the
 * points u and their count between cases, so the thread's cache of the angles 2 pi u[1] (their
 * cosines and sines, mix_angles_get) is filled, grown and partly replaced: a stale entry fails here.
 * Both evaluation paths are checked: the 4-wide AVX2 one (where the CPU has it) and the 2-wide one. */
#include "mf_test.h"

#include <string.h>

#include "mfkit/fit/mf_prefilter.h"
#include "mfkit/mf_model.h"
#include "mfkit/mf_rng.h"

#include "../fit/src/mf_prefilter_internal.h"

static int same(double a, double b) { return memcmp(&a, &b, sizeof a) == 0; }

/* ncomp random normals (slopes up to about 1.2, some below the views' horizon at grazing views),
 * n directions (n odd and above the chunk of 64: the vector pairs, their scalar tail and a
 * partial chunk are all exercised), views from the zenith to 89.9 deg. */
static void check_mix(int ncomp, int n, uint64_t seed)
{
    const mf_brdf_model *ggx = mf_brdf_model_find("ggx");
    double nrm[3 * 16];
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, seed, 7);
    for (int j = 0; j < ncomp; ++j) {
        double x = 2.4 * (mf_pcg32_next_double(&rng) - 0.5), y = 2.4 * (mf_pcg32_next_double(&rng) - 0.5);
        double l = sqrt(x * x + y * y + 1.0);
        nrm[3 * j] = x / l, nrm[3 * j + 1] = y / l, nrm[3 * j + 2] = 1.0 / l;
    }
    mf_prefilter_mix mix;
    CHECK(mf_prefilter_mix_init(&mix, ggx, nrm, ncomp) == MF_OK);
    static const double thetas[4] = {0.0, 0.7, 1.35, 1.569};
    static const double alphas[2] = {0.1, 0.5};
    double *u = malloc(sizeof(double) * 2 * (size_t)n), *pdf = malloc(sizeof(double) * (size_t)n),
           *w = malloc(sizeof(double) * (size_t)n);
    mf_vec3 *wi = malloc(sizeof(mf_vec3) * (size_t)n);
    for (int i = 0; i < 2 * n; ++i)
        u[i] = mf_pcg32_next_double(&rng);
    long checked = 0, live = 0;
    int bad = 0;
    for (int a = 0; a < 2; ++a)
        for (int t = 0; t < 4; ++t) {
            mf_brdf_params p = mf_brdf_params_iso(alphas[a]);
            double ph = 0.9 * t;
            mf_vec3 wo = mf_vec3_make(sin(thetas[t]) * cos(ph), sin(thetas[t]) * sin(ph), cos(thetas[t]));
            CHECK(mf_prefilter_mix_set_view(&mix, &p, wo) == MF_OK);
            mix.model.sample_weights(&mix.model, &p, wo, n, u, wi, pdf, w);
            for (int i = 0; i < n; ++i) {
                double pr;
                mf_vec3 r = mix.model.sample(&mix.model, &p, wo, u + 2 * i, &pr);
                double f = pr > 0.0 ? mix.model.eval_cos(&mix.model, &p, wo, r) : 0.0;
                double wr = pr > 0.0 ? f / pr : 0.0;
                int ok = same(wi[i].x, r.x) && same(wi[i].y, r.y) && same(wi[i].z, r.z) && same(pdf[i], pr) &&
                         same(w[i], wr);
                if (!ok && bad++ < 5)
                    fprintf(stderr, "components %d, alpha %g, theta %g, direction %d: fused pdf %.17g w %.17g, "
                                    "per direction pdf %.17g w %.17g\n",
                            ncomp, alphas[a], thetas[t], i, pdf[i], w[i], pr, wr);
                ++checked;
                live += pr > 0.0;
            }
        }
    CHECK(bad == 0);
    CHECK(live > checked / 4); /* the comparison is not only of zeros */
    printf("components %d: %ld directions compared bit for bit (%ld with a positive density), %d differ\n", ncomp,
           checked, live, bad);
    free(u), free(pdf), free(w), free(wi);
    mf_prefilter_mix_free(&mix);
}

int main(void)
{
    uint64_t seed = mf_test_seed(13);
    /* both evaluation paths: 4-wide (AVX2, where this CPU has it) and 2-wide */
    printf("4-wide AVX2 evaluation %s\n", mf_prefilter_mix_wide_available() ? "available: both paths checked"
                                                                            : "not available: the 2-wide path twice");
    for (int wide = 1; wide >= 0; --wide) {
        mf_prefilter_mix_wide = wide;
        check_mix(1, 131, seed);
        check_mix(2, 131, seed + 1);
        check_mix(4, 201, seed + 2);
        check_mix(13, 131, seed + 3);
    }
    mf_prefilter_mix_wide = 1;
    MF_TEST_MAIN_END();
}
