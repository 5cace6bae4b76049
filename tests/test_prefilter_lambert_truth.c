/* test_prefilter_lambert_truth.c -- the diffuse table's ground truth (mf_prefilter_texel_lambert,
 * mf_prefilter_lookup.h; `mfkit prefilter-eval` on a Lambert table) against a Monte Carlo integral of
 * the prefilter's own effective BRDF (mf_prefilter_mix with the "lambert" base, the mixture the
 * diffuse lobes are fitted to) over the light's area.
 *
 * For random footprints (1 to 6 unit normals, tilts up to 80 deg, so the texel horizons cut the
 * lights) and square lights of the eval's kind (half side 0.05 to 1.5 at distance 1, centred
 * anywhere from the zenith to 10 deg below the horizon, so the geometric horizon cuts many of them
 * too, and some lie entirely below it):
 *   exact  (1/N) sum_q mf_prefilter_texel_lambert(n_q, light);
 *   MC     (1/S) sum over S uniform points x on the light of f_mix(wo, wi) |wi.c| A / |x|^2,
 *          wi = x / |x|, A the light's area, c its normal (the Jacobian from area to solid angle);
 *          f_mix = mix.model.eval_cos (0 below the geometric horizon, the texels' max(0, n.wi)/pi
 *          above it), at a random view (the mixture does not depend on it).
 * Check |MC - exact| <= z SE + delta with z = 5 (120 cases: a false alarm anywhere has probability
 * about 120 x 5.7e-7 = 7e-5) and delta = 1e-12 + 1e-9 exact: the exact value is a sum of at most 8
 * atan2-weighted edge terms per texel, correct to a few ulps of its terms (mf_polygon.h: 1e-10
 * relative at worst for polygons of 1e-12 sr; these subtend at least 2e-3 sr), and the MC mean is
 * unbiased, so delta only absorbs rounding.  A light wholly below the horizon must give exactly 0
 * in both.  Also: the view does not enter (two views, the same exact value, bit for bit is not
 * claimed for MC), and a polygon of too many vertices gives NaN.
 *
 * How it fails (checked when the test was written, seed 20261202): without the clip at the
 * geometric horizon (the texel's horizon only) 40 of the 132 checks fail (worst |z| 121); with the
 * clip's crossing point taken at t = b.z / (a.z - b.z) instead of a.z / (a.z - b.z), 29 fail.
 * Measured as written: 52 of the 120 lights cut by the horizon, worst |z| 3.05. */
#include "mf_test.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mfkit/fit/mf_prefilter.h"
#include "mfkit/fit/mf_prefilter_lookup.h"
#include "mfkit/mf_brdf.h"
#include "mfkit/mf_polygon.h"
#include "mfkit/mf_rng.h"

#define Z_MC 5.0
#define CASES 120
#define SAMPLES 40000

static void light_quad(double elev, double az, double h, mf_vec3 *v, mf_vec3 *c)
{
    /* centre at distance 1, elevation elev above the horizon (negative: below), facing the origin */
    *c = mf_vec3_make(cos(elev) * cos(az), cos(elev) * sin(az), sin(elev));
    mf_vec3 e1 = mf_vec3_normalize(mf_vec3_cross(mf_vec3_make(0.0, 0.0, 1.0), *c));
    mf_vec3 e2 = mf_vec3_cross(*c, e1);
    static const double sx[4] = {-1, 1, 1, -1}, sy[4] = {-1, -1, 1, 1};
    for (int k = 0; k < 4; ++k)
        v[k] = mf_vec3_add(*c, mf_vec3_add(mf_vec3_scale(e1, h * sx[k]), mf_vec3_scale(e2, h * sy[k])));
}

static void test_truth_vs_mc(void)
{
    const mf_brdf_model *lam = mf_brdf_model_find("lambert");
    CHECK(lam != NULL);
    if (!lam)
        return;
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, mf_test_seed(20261202), 0);
    int below = 0, cut = 0;
    double worst_z = 0.0;
    for (int cs = 0; cs < CASES; ++cs) {
        int count = 1 + (int)(mf_pcg32_next_double(&rng) * 6.0);
        double nrm[3 * 6];
        for (int q = 0; q < count; ++q) {
            double t = mf_pcg32_next_double(&rng) * 80.0 * MF_PI / 180.0, p = 2.0 * MF_PI * mf_pcg32_next_double(&rng);
            nrm[3 * q] = sin(t) * cos(p), nrm[3 * q + 1] = sin(t) * sin(p), nrm[3 * q + 2] = cos(t);
        }
        double h = 0.05 + 1.45 * mf_pcg32_next_double(&rng);
        double elev = (-10.0 + 100.0 * mf_pcg32_next_double(&rng)) * MF_PI / 180.0;
        double az = 2.0 * MF_PI * mf_pcg32_next_double(&rng);
        mf_vec3 v[4], c;
        light_quad(elev, az, h, v, &c);
        double exact = 0.0;
        for (int q = 0; q < count; ++q)
            exact += mf_prefilter_texel_lambert(mf_vec3_make(nrm[3 * q], nrm[3 * q + 1], nrm[3 * q + 2]), v, 4);
        exact /= count;
        mf_prefilter_mix mix;
        if (mf_prefilter_mix_init(&mix, lam, nrm, count) != MF_OK) {
            CHECKF(0, "case %d: mf_prefilter_mix_init failed", cs);
            continue;
        }
        double tv = mf_pcg32_next_double(&rng) * 1.5, pv = 2.0 * MF_PI * mf_pcg32_next_double(&rng);
        mf_vec3 wo = mf_vec3_make(sin(tv) * cos(pv), sin(tv) * sin(pv), cos(tv));
        mf_brdf_params p = mf_brdf_params_iso(1.0);
        mf_vec3 e1 = mf_vec3_scale(mf_vec3_sub(v[1], v[0]), 0.5), e2 = mf_vec3_scale(mf_vec3_sub(v[3], v[0]), 0.5);
        double area = 4.0 * h * h, s1 = 0.0, s2 = 0.0;
        int hit_below = 0, hit_above = 0;
        for (int i = 0; i < SAMPLES; ++i) {
            double a = 2.0 * mf_pcg32_next_double(&rng) - 1.0, b = 2.0 * mf_pcg32_next_double(&rng) - 1.0;
            mf_vec3 x = mf_vec3_add(c, mf_vec3_add(mf_vec3_scale(e1, a), mf_vec3_scale(e2, b)));
            double r2 = mf_vec3_dot(x, x);
            mf_vec3 wi = mf_vec3_scale(x, 1.0 / sqrt(r2));
            hit_below |= wi.z <= 0.0, hit_above |= wi.z > 0.0;
            double f = mix.model.eval_cos(&mix.model, &p, wo, wi) * area * fabs(mf_vec3_dot(wi, c)) / r2;
            s1 += f, s2 += f * f;
        }
        mf_prefilter_mix_free(&mix);
        double mean = s1 / SAMPLES, var = (s2 / SAMPLES - mean * mean) * SAMPLES / (SAMPLES - 1.0);
        double se = sqrt(var > 0.0 ? var / SAMPLES : 0.0);
        if (!hit_above) {
            ++below;
            CHECKF(exact == 0.0 && mean == 0.0, "case %d: light below the horizon: exact %.17g, MC %.17g", cs, exact,
                   mean);
            continue;
        }
        cut += hit_below;
        CHECK_MC(mean, se, exact, Z_MC, 1e-12 + 1e-9 * exact);
        if (se > 0.0 && fabs(mean - exact) / se > worst_z)
            worst_z = fabs(mean - exact) / se;
        /* the view does not enter the truth (it has none) nor the mixture: a second view, the same MC */
        if (cs % 20 == 0) {
            mf_prefilter_mix m2;
            if (mf_prefilter_mix_init(&m2, lam, nrm, count) == MF_OK) {
                mf_vec3 wo2 = mf_vec3_make(0.0, 0.0, 1.0), wi = mf_vec3_normalize(c);
                CHECK(m2.model.eval_cos(&m2.model, &p, wo, wi) == m2.model.eval_cos(&m2.model, &p, wo2, wi));
                mf_prefilter_mix_free(&m2);
            }
        }
    }
    printf("lambert truth vs MC: %d cases (%d cut by the geometric horizon, %d wholly below), worst |z| %.2f\n",
           CASES, cut, below, worst_z);
    /* the draw must exercise the clip: lights cut by the horizon, and some wholly below it */
    CHECKF(cut >= 10, "cases cut by the horizon %d (need >= 10)", cut);
    mf_vec3 many[MF_POLYGON_MAX_VERTICES];
    for (int k = 0; k < MF_POLYGON_MAX_VERTICES; ++k)
        many[k] = mf_vec3_make(cos(k), sin(k), 1.0);
    CHECK(isnan(mf_prefilter_texel_lambert(mf_vec3_make(0, 0, 1), many, MF_POLYGON_MAX_VERTICES)));
    CHECK(isnan(mf_prefilter_texel_lambert(mf_vec3_make(0, 0, 1), many, 2)));
}

/* A flat texel and a light above the horizon: Lambert's formula itself (mf_polygon_integrate_cosine). */
static void test_flat(void)
{
    mf_vec3 v[4], c;
    light_quad(1.0, 0.3, 0.4, v, &c);
    mf_polygon p = mf_polygon_make(4, v);
    CHECK_REL(mf_prefilter_texel_lambert(mf_vec3_make(0, 0, 1), v, 4),
              mf_polygon_integrate_cosine(&p, MF_POLYGON_TWO_SIDED), 1e-15);
    /* wholly below the geometric horizon: 0 even for a texel tilted towards it (whose own horizon
     * would let part of it through) */
    light_quad(-0.3, 0.0, 0.1, v, &c);
    double n = sin(1.2);
    CHECK(mf_prefilter_texel_lambert(mf_vec3_make(n, 0.0, cos(1.2)), v, 4) == 0.0);
}

int main(void)
{
    test_flat();
    test_truth_vs_mc();
    MF_TEST_MAIN_END();
}
