/* test_prefilter_quad_mis.c -- the evaluations' Monte Carlo estimator over a square light
 * (mf_prefilter_quad_mis_sample, mf_prefilter_quad_mis_mean in mf_prefilter.h): half the points
 * uniform on the light's area, half from the footprint mixture's sampler, weighted by the balance
 * heuristic [Veach and Guibas 1995].  `mfkit prefilter-eval` and analysis/study_prefilter_cell take
 * their ground truth from it.
 *
 * Checks, each |estimate - reference| <= z SE + delta with z = 5 (about 200 checks: a false alarm
 * anywhere has probability about 200 x 5.7e-7 = 1e-4) and delta covering only the reference's
 * rounding, stated per check:
 *   1. Lambert mixtures (1 to 6 normals, tilts up to 80 deg) under lights from the zenith to 10 deg
 *      below the horizon (so the horizon cuts many): the estimate of the mixture's f cos against the
 *      exact footprint average of mf_prefilter_texel_lambert.  Exercises both strategies' densities:
 *      the Lambert sampler's directions are weighted by p_M, the light's by p_L.
 *      1b: the same with squares at distance 0.5 to 5 whose planes are tilted against the line of sight
 *      (the function takes any square light, as a scene's).
 *   2. g = 1 with GGX mixtures (alpha 1e-4 to 0.5, views up to 89.9 deg): the weights alone must sum
 *      to the light's solid angle, 4 asin(h^2 / (1 + h^2)) for a square of half side h at distance 1
 *      [the solid angle of a rectangle seen from its centre's normal], for lights wholly above the
 *      horizon.  A wrong p_L (the ray-to-light Jacobian of the BRDF strategy) or a p_M not the
 *      sampler's density biases this.
 *   3. GGX mixtures at alpha 0.1 and 0.5: the estimate of f cos against uniform points alone (the
 *      estimator before, 2^20 points), |a - b| <= z sqrt(se_a^2 + se_b^2).
 *   4. Efficiency, the reason for the estimator: a single normal at alpha 0.01 under a light of half
 *      side 0.8 about the mirror direction, 4096 points: the relative standard error must be below
 *      0.02 (measured 0.0032 to 0.0040 at 30, 60 and 70 deg); uniform points alone read 0.43 to 0.52
 *      there.  At alpha 1e-4 the whole lobe lies inside the light, so the estimate must equal the GGX
 *      albedo at that view (mf_prefilter_mix_albedo, its err added to delta).
 *   5. Degenerate input: a light wholly below the horizon, a view below it, h = 0: weight 0.
 *
 * How it fails (checked when the test was written): with p_M's factor 1/2 dropped (w = 1 / (p_L / 2
 * + p_M)) 106 of the 147 checks fail; with the BRDF strategy's p_L missing its t^2 (the squared
 * distance to the light's plane), 48 (solid angle worst |z| 7.7). */
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

/* A square light of half side h at distance 1, centred at elevation elev (negative: below the
 * horizon) and azimuth az, facing the origin: the quad and its corners. */
static mf_prefilter_quad light_quad(double elev, double az, double h, mf_vec3 *v)
{
    mf_prefilter_quad q;
    q.c = mf_vec3_make(cos(elev) * cos(az), cos(elev) * sin(az), sin(elev));
    q.e1 = mf_vec3_normalize(mf_vec3_cross(mf_vec3_make(0.0, 0.0, 1.0), q.c));
    q.e2 = mf_vec3_cross(q.c, q.e1);
    q.h = h;
    static const double sx[4] = {-1, 1, 1, -1}, sy[4] = {-1, -1, 1, 1};
    for (int k = 0; k < 4; ++k)
        v[k] = mf_vec3_add(q.c, mf_vec3_add(mf_vec3_scale(q.e1, h * sx[k]), mf_vec3_scale(q.e2, h * sy[k])));
    return q;
}

/* The estimator over n points (n even, strategies alternating): of the mixture's f cos (unit = 0) or
 * of g = 1 (unit = 1). */
static void mis_estimate(const mf_prefilter_mix *mix, const mf_brdf_params *p, mf_vec3 wo, const mf_prefilter_quad *q,
                         int n, int unit, mf_pcg32 *rng, double *mean, double *se)
{
    double cnt[2] = {0, 0}, s1[2] = {0, 0}, s2[2] = {0, 0};
    for (int i = 0; i < n; ++i) {
        double u[2] = {mf_pcg32_next_double(rng), mf_pcg32_next_double(rng)}, f;
        mf_vec3 wi;
        int k = i & 1;
        double w = mf_prefilter_quad_mis_sample(mix, p, wo, q, k, u, &wi, &f);
        double g = (unit ? 1.0 : f) * w;
        cnt[k] += 1.0, s1[k] += g, s2[k] += g * g;
    }
    mf_prefilter_quad_mis_mean(cnt, s1, s2, mean, se);
}

/* Uniform points of the light alone (prefilter-eval's estimator before). */
static void uniform_estimate(const mf_prefilter_mix *mix, const mf_brdf_params *p, mf_vec3 wo,
                             const mf_prefilter_quad *q, int n, mf_pcg32 *rng, double *mean, double *se)
{
    double s1 = 0.0, s2 = 0.0, area = 4.0 * q->h * q->h;
    for (int i = 0; i < n; ++i) {
        double a = (2.0 * mf_pcg32_next_double(rng) - 1.0) * q->h, b = (2.0 * mf_pcg32_next_double(rng) - 1.0) * q->h;
        mf_vec3 x = mf_vec3_add(q->c, mf_vec3_add(mf_vec3_scale(q->e1, a), mf_vec3_scale(q->e2, b)));
        double r2 = mf_vec3_dot(x, x);
        mf_vec3 wi = mf_vec3_scale(x, 1.0 / sqrt(r2));
        double f = wi.z > 0.0 ? mix->model.eval_cos(&mix->model, p, wo, wi) * area * fabs(mf_vec3_dot(wi, q->c)) / r2
                              : 0.0;
        s1 += f, s2 += f * f;
    }
    *mean = s1 / n;
    double var = (s2 / n - *mean * *mean) * n / (n - 1.0);
    *se = sqrt(var > 0.0 ? var / n : 0.0);
}

static void random_normals(mf_pcg32 *rng, int count, double max_tilt_deg, double *nrm)
{
    for (int q = 0; q < count; ++q) {
        double t = mf_pcg32_next_double(rng) * max_tilt_deg * MF_PI / 180.0;
        double ph = 2.0 * MF_PI * mf_pcg32_next_double(rng);
        nrm[3 * q] = sin(t) * cos(ph), nrm[3 * q + 1] = sin(t) * sin(ph), nrm[3 * q + 2] = cos(t);
    }
}

static void test_lambert_exact(void)
{
    const mf_brdf_model *lam = mf_brdf_model_find("lambert");
    CHECK(lam != NULL);
    if (!lam)
        return;
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, mf_test_seed(20261203), 0);
    int cut = 0, below = 0;
    double worst_z = 0.0;
    for (int cs = 0; cs < 80; ++cs) {
        int count = 1 + (int)(mf_pcg32_next_double(&rng) * 6.0);
        double nrm[3 * 6];
        random_normals(&rng, count, 80.0, nrm);
        double h = 0.05 + 1.45 * mf_pcg32_next_double(&rng);
        double elev = (-10.0 + 100.0 * mf_pcg32_next_double(&rng)) * MF_PI / 180.0;
        mf_vec3 v[4];
        mf_prefilter_quad q = light_quad(elev, 2.0 * MF_PI * mf_pcg32_next_double(&rng), h, v);
        double exact = 0.0;
        for (int k = 0; k < count; ++k)
            exact += mf_prefilter_texel_lambert(mf_vec3_make(nrm[3 * k], nrm[3 * k + 1], nrm[3 * k + 2]), v, 4);
        exact /= count;
        mf_prefilter_mix mix;
        if (mf_prefilter_mix_init(&mix, lam, nrm, count) != MF_OK) {
            CHECKF(0, "case %d: mf_prefilter_mix_init failed", cs);
            continue;
        }
        mf_vec3 wo = mf_vec3_make(0.3, 0.1, 0.9);
        mf_brdf_params p = mf_brdf_params_iso(1.0);
        double mean, se;
        mis_estimate(&mix, &p, mf_vec3_normalize(wo), &q, 20000, 0, &rng, &mean, &se);
        mf_prefilter_mix_free(&mix);
        int any_below = v[0].z <= 0.0 || v[1].z <= 0.0 || v[2].z <= 0.0 || v[3].z <= 0.0;
        int all_below = v[0].z <= 0.0 && v[1].z <= 0.0 && v[2].z <= 0.0 && v[3].z <= 0.0;
        if (all_below) {
            ++below;
            CHECKF(exact == 0.0 && mean == 0.0 && se == 0.0, "case %d: light below the horizon: exact %.17g, MC %.17g",
                   cs, exact, mean);
            continue;
        }
        cut += any_below;
        /* delta: Lambert's formula, a few ulps of its terms (test_prefilter_lambert_truth) */
        CHECK_MC(mean, se, exact, Z_MC, 1e-12 + 1e-9 * exact);
        if (se > 0.0 && fabs(mean - exact) / se > worst_z)
            worst_z = fabs(mean - exact) / se;
    }
    printf("lambert: 80 cases (%d cut by the horizon, %d wholly below), worst |z| %.2f\n", cut, below, worst_z);
    CHECKF(cut >= 5, "cases cut by the horizon %d (need >= 5)", cut);
}

/* a view at elevation th and azimuth 0, the light centred on its mirror direction about z (elevation
 * clamped as prefilter-eval clamps it, 75 deg from the zenith) */
static mf_prefilter_quad mirror_light(double th, double h, mf_vec3 *v)
{
    double tl = th < 75.0 * MF_PI / 180.0 ? th : 75.0 * MF_PI / 180.0;
    return light_quad(0.5 * MF_PI - tl, MF_PI, h, v);
}

/* 1b. The same for squares that do not face the shading point: centre at distance 0.5 to 5 in any
 * direction above -10 deg, edges of a random orientation (so the light's plane is tilted against the
 * line of sight, and the BRDF strategy's ray-plane distance t and |wi . n| differ from the facing
 * case), half side 0.1 to 2.  Same bound. */
static void test_lambert_tilted(void)
{
    const mf_brdf_model *lam = mf_brdf_model_find("lambert");
    if (!lam)
        return;
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, mf_test_seed(20261207), 0);
    double worst_z = 0.0;
    int used = 0;
    for (int cs = 0; cs < 60; ++cs) {
        int count = 1 + (int)(mf_pcg32_next_double(&rng) * 4.0);
        double nrm[3 * 4];
        random_normals(&rng, count, 60.0, nrm);
        double el = (-10.0 + 100.0 * mf_pcg32_next_double(&rng)) * MF_PI / 180.0;
        double az = 2.0 * MF_PI * mf_pcg32_next_double(&rng), dist = 0.5 + 4.5 * mf_pcg32_next_double(&rng);
        mf_prefilter_quad q;
        q.c = mf_vec3_scale(mf_vec3_make(cos(el) * cos(az), cos(el) * sin(az), sin(el)), dist);
        q.h = 0.1 + 1.9 * mf_pcg32_next_double(&rng);
        mf_vec3 a = mf_vec3_normalize(mf_vec3_make(mf_pcg32_next_normal(&rng), mf_pcg32_next_normal(&rng),
                                                   mf_pcg32_next_normal(&rng)));
        mf_vec3 b = mf_vec3_make(mf_pcg32_next_normal(&rng), mf_pcg32_next_normal(&rng), mf_pcg32_next_normal(&rng));
        q.e1 = a;
        q.e2 = mf_vec3_normalize(mf_vec3_sub(b, mf_vec3_scale(a, mf_vec3_dot(a, b))));
        mf_vec3 v[4];
        static const double sx[4] = {-1, 1, 1, -1}, sy[4] = {-1, -1, 1, 1};
        for (int k = 0; k < 4; ++k)
            v[k] = mf_vec3_add(q.c, mf_vec3_add(mf_vec3_scale(q.e1, q.h * sx[k]), mf_vec3_scale(q.e2, q.h * sy[k])));
        /* the square must not contain the shading point's line through it edge-on (|c . n| tiny) */
        if (fabs(mf_vec3_dot(q.c, mf_vec3_cross(q.e1, q.e2))) < 0.05 * dist)
            continue;
        double exact = 0.0;
        for (int k = 0; k < count; ++k)
            exact += mf_prefilter_texel_lambert(mf_vec3_make(nrm[3 * k], nrm[3 * k + 1], nrm[3 * k + 2]), v, 4);
        exact /= count;
        mf_prefilter_mix mix;
        if (mf_prefilter_mix_init(&mix, lam, nrm, count) != MF_OK) {
            CHECKF(0, "case %d: mf_prefilter_mix_init failed", cs);
            continue;
        }
        mf_brdf_params p = mf_brdf_params_iso(1.0);
        double mean, se;
        mis_estimate(&mix, &p, mf_vec3_make(0.0, 0.0, 1.0), &q, 20000, 0, &rng, &mean, &se);
        mf_prefilter_mix_free(&mix);
        CHECK_MC(mean, se, exact, Z_MC, 1e-12 + 1e-9 * exact);
        ++used;
        if (se > 0.0 && fabs(mean - exact) / se > worst_z)
            worst_z = fabs(mean - exact) / se;
    }
    printf("lambert, tilted squares: %d cases, worst |z| %.2f\n", used, worst_z);
    CHECKF(used >= 40, "tilted cases used %d (need >= 40)", used);
}

static void test_solid_angle(void)
{
    const mf_brdf_model *ggx = mf_brdf_model_find("ggx");
    CHECK(ggx != NULL);
    if (!ggx)
        return;
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, mf_test_seed(20261204), 0);
    static const double alphas[] = {1e-4, 0.01, 0.1, 0.5};
    double worst_z = 0.0;
    int n_checks = 0;
    for (int ia = 0; ia < 4; ++ia)
        for (int cs = 0; cs < 12; ++cs) {
            int count = 1 + (int)(mf_pcg32_next_double(&rng) * 4.0);
            double nrm[3 * 4];
            random_normals(&rng, count, 40.0, nrm);
            double th = (cs % 4 == 3 ? 89.9 : 80.0 * mf_pcg32_next_double(&rng)) * MF_PI / 180.0;
            double h = 0.05 + 0.6 * mf_pcg32_next_double(&rng);
            mf_vec3 v[4];
            mf_prefilter_quad q = mirror_light(th, h, v);
            if (v[0].z <= 0.0 || v[1].z <= 0.0 || v[2].z <= 0.0 || v[3].z <= 0.0)
                continue; /* the closed form is for the whole square */
            mf_prefilter_mix mix;
            if (mf_prefilter_mix_init(&mix, ggx, nrm, count) != MF_OK) {
                CHECKF(0, "alpha %g case %d: mf_prefilter_mix_init failed", alphas[ia], cs);
                continue;
            }
            mf_brdf_params p = mf_brdf_params_iso(alphas[ia]);
            double mean, se, omega = 4.0 * asin(h * h / (1.0 + h * h));
            mis_estimate(&mix, &p, mf_vec3_make(sin(th), 0.0, cos(th)), &q, 20000, 1, &rng, &mean, &se);
            mf_prefilter_mix_free(&mix);
            /* delta: rounding of asin and of the sum of 20,000 weights */
            CHECK_MC(mean, se, omega, Z_MC, 1e-12 * omega);
            ++n_checks;
            if (se > 0.0 && fabs(mean - omega) / se > worst_z)
                worst_z = fabs(mean - omega) / se;
        }
    printf("solid angle: %d lights, worst |z| %.2f\n", n_checks, worst_z);
    CHECKF(n_checks >= 30, "lights wholly above the horizon %d (need >= 30)", n_checks);
}

static void test_against_uniform(void)
{
    const mf_brdf_model *ggx = mf_brdf_model_find("ggx");
    if (!ggx)
        return;
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, mf_test_seed(20261205), 0);
    double worst_z = 0.0;
    for (int cs = 0; cs < 16; ++cs) {
        double alpha = cs < 8 ? 0.1 : 0.5;
        int count = 1 + (int)(mf_pcg32_next_double(&rng) * 5.0);
        double nrm[3 * 5];
        random_normals(&rng, count, 50.0, nrm);
        double th = (cs % 4 == 3 ? 89.9 : 85.0 * mf_pcg32_next_double(&rng)) * MF_PI / 180.0;
        mf_vec3 v[4];
        mf_prefilter_quad q = mirror_light(th, 0.05 + 0.75 * mf_pcg32_next_double(&rng), v);
        mf_prefilter_mix mix;
        if (mf_prefilter_mix_init(&mix, ggx, nrm, count) != MF_OK) {
            CHECKF(0, "case %d: mf_prefilter_mix_init failed", cs);
            continue;
        }
        mf_brdf_params p = mf_brdf_params_iso(alpha);
        mf_vec3 wo = mf_vec3_make(sin(th), 0.0, cos(th));
        double a, sa, b, sb;
        mis_estimate(&mix, &p, wo, &q, 8192, 0, &rng, &a, &sa);
        uniform_estimate(&mix, &p, wo, &q, 1 << 20, &rng, &b, &sb);
        mf_prefilter_mix_free(&mix);
        double s = sqrt(sa * sa + sb * sb);
        CHECK_MC(a, s, b, Z_MC, 1e-12);
        if (s > 0.0 && fabs(a - b) / s > worst_z)
            worst_z = fabs(a - b) / s;
    }
    printf("against uniform points: 16 cases, worst |z| %.2f\n", worst_z);
}

/* The GGX mixture of one flat texel (normal z); 0 (a failed check) if it cannot be built. */
static int flat_ggx(mf_prefilter_mix *mix)
{
    const mf_brdf_model *ggx = mf_brdf_model_find("ggx");
    double nrm[3] = {0.0, 0.0, 1.0};
    int ok = ggx && mf_prefilter_mix_init(mix, ggx, nrm, 1) == MF_OK;
    CHECKF(ok, "the flat GGX mixture could not be built");
    return ok;
}

static void test_sharp(void)
{
    mf_prefilter_mix mix;
    if (!flat_ggx(&mix))
        return;
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, mf_test_seed(20261206), 0);
    for (int it = 0; it < 3; ++it) {
        double th = (it == 0 ? 30.0 : it == 1 ? 60.0 : 70.0) * MF_PI / 180.0;
        mf_vec3 v[4], wo = mf_vec3_make(sin(th), 0.0, cos(th));
        mf_prefilter_quad q = mirror_light(th, 0.8, v);
        /* alpha 0.01: the relative standard error at 4096 points (bound 0.02; measured above) */
        mf_brdf_params p = mf_brdf_params_iso(0.01);
        double mean, se, um, use;
        mis_estimate(&mix, &p, wo, &q, 4096, 0, &rng, &mean, &se);
        uniform_estimate(&mix, &p, wo, &q, 4096, &rng, &um, &use);
        printf("alpha 0.01, view %.0f deg, light 0.8: MIS %.5f (rel. se %.4f), uniform %.5f (rel. se %.4f)\n",
               th * 180.0 / MF_PI, mean, se / mean, um, use / um);
        CHECKF(mean > 0.0 && se / mean < 0.02, "relative standard error %.4g (bound 0.02)",
               mean > 0.0 ? se / mean : 1.0);
        /* alpha 1e-4: the lobe lies wholly inside the light, so the integral is the albedo (delta: its
         * error estimate plus 1e-6 for the lobe's tail outside the light: GGX's D puts alpha^2 / (alpha^2
         * + tan^2 t) of its mass beyond a half-vector angle t, below 1e-7 at the light's edge, t >= 0.3) */
        mf_brdf_params p4 = mf_brdf_params_iso(1e-4);
        mf_result alb;
        CHECK(mf_prefilter_mix_albedo(&mix, &p4, wo, &alb) == MF_OK);
        mis_estimate(&mix, &p4, wo, &q, 4096, 0, &rng, &mean, &se);
        CHECK_MC(mean, se, alb.val, Z_MC, alb.err + 1e-6);
    }
    mf_prefilter_mix_free(&mix);
}

static void test_degenerate(void)
{
    mf_prefilter_mix mix;
    if (!flat_ggx(&mix))
        return;
    mf_brdf_params p = mf_brdf_params_iso(0.3);
    mf_vec3 v[4], wi, wo = mf_vec3_make(0.5, 0.0, sqrt(0.75));
    mf_prefilter_quad below = light_quad(-30.0 * MF_PI / 180.0, 0.0, 0.3, v), above = light_quad(1.0, MF_PI, 0.3, v);
    mf_prefilter_quad flat = above;
    flat.h = 0.0;
    int bad = 0;
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, 7, 0);
    for (int i = 0; i < 2000; ++i) {
        double u[2] = {mf_pcg32_next_double(&rng), mf_pcg32_next_double(&rng)}, f;
        bad += mf_prefilter_quad_mis_sample(&mix, &p, wo, &below, i & 1, u, &wi, &f) != 0.0 || f != 0.0;
        bad += mf_prefilter_quad_mis_sample(&mix, &p, mf_vec3_make(1.0, 0.0, -0.1), &above, i & 1, u, &wi, &f) != 0.0;
        bad += mf_prefilter_quad_mis_sample(&mix, &p, wo, &flat, i & 1, u, &wi, &f) != 0.0;
    }
    CHECKF(bad == 0, "%d samples with a nonzero weight (a light below the horizon, a view below it, h = 0)", bad);
    double n[2] = {0, 0}, s[2] = {0, 0}, mean = 1.0, se = 1.0;
    mf_prefilter_quad_mis_mean(n, s, s, &mean, &se);
    CHECK(mean == 0.0 && se == 0.0);
    mf_prefilter_mix_free(&mix);
}

int main(void)
{
    test_lambert_exact();
    test_lambert_tilted();
    test_solid_angle();
    test_against_uniform();
    test_sharp();
    test_degenerate();
    MF_TEST_MAIN_END();
}
