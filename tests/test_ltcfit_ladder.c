/* test_ltcfit_ladder.c -- the ladder of base-lobe-sized lights of the prefilter's fits
 * (mf_ltcfit_aniso_options.ladder_alpha, mf_prefilter_options.fit_lights; mf_ltcfit_aniso.c, "The
 * ladder"): its squares are the stated ones, the default leaves every fit as it was (the table's random
 * family never reads the option), the structured family does read it, bad values are refused, and on a
 * V-groove seen along the groove it moves the stored lobe towards the truth under a light smaller than
 * the gap between the facets. */
#include "mf_test.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mfkit/fit/mf_ltcfit_aniso.h"
#include "mfkit/fit/mf_prefilter.h"
#include "mfkit/mf_ltc.h"
#include "mfkit/mf_polygon.h"

/* The squares: MF_LTCFIT_ANISO_LADDER of them, each centred on the view's mirror direction m about z
 * in the plane at distance 1 (vertices minus m orthogonal to m, their mean m), front-facing
 * (counter-clockwise about m), with half sides alpha / 4 .. 10 alpha in a geometric series; at a
 * grazing view (86 deg) the centre is the mirror direction too (prefilter revision 11: before, it was
 * clamped to 75 deg, which this check refuses). */
static void test_geometry(void)
{
  for (int g = 0; g < 2; ++g) {
    const double alpha = 0.1, th = g ? 1.5 : 0.7, tl = th;
    const double m[3] = {-sin(tl), 0.0, cos(tl)};
    double v[MF_LTCFIT_ANISO_LADDER * 12];
    CHECK(mf_ltcfit_aniso_ladder_lights(th, alpha, v) == MF_LTCFIT_ANISO_LADDER);
    double ratio = pow(40.0, 1.0 / (MF_LTCFIT_ANISO_LADDER - 1));
    for (int k = 0; k < MF_LTCFIT_ANISO_LADDER; ++k) {
        const double *q = v + 12 * k;
        double c[3] = {0, 0, 0};
        for (int i = 0; i < 4; ++i)
            for (int a = 0; a < 3; ++a)
                c[a] += 0.25 * q[3 * i + a];
        /* rounding of a few operations on O(1) numbers: 1e-14 */
        for (int a = 0; a < 3; ++a)
            CHECK_ABS(c[a], m[a], 1e-14);
        double h_expect = 0.25 * alpha * pow(ratio, k);
        for (int i = 0; i < 4; ++i) {
            const double *p = q + 3 * i, *p1 = q + 3 * ((i + 1) % 4);
            double d[3] = {p[0] - m[0], p[1] - m[1], p[2] - m[2]};
            CHECK_ABS(d[0] * m[0] + d[1] * m[1] + d[2] * m[2], 0.0, 1e-14);
            /* a square's vertex is sqrt(2) h from its centre */
            CHECK_REL(sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]), sqrt(2.0) * h_expect, 1e-12);
            /* front-facing: (p x p1) . m > 0 for every edge */
            double x[3] = {p[1] * p1[2] - p[2] * p1[1], p[2] * p1[0] - p[0] * p1[2], p[0] * p1[1] - p[1] * p1[0]};
            CHECK(x[0] * m[0] + x[1] * m[1] + x[2] * m[2] > 0.0);
        }
    }
    /* the ends of the ladder: alpha / 4 and 10 alpha */
    double d0 = hypot(hypot(v[0] - m[0], v[1] - m[1]), v[2] - m[2]) / sqrt(2.0);
    const double *l7 = v + 12 * (MF_LTCFIT_ANISO_LADDER - 1);
    double d7 = hypot(hypot(l7[0] - m[0], l7[1] - m[1]), l7[2] - m[2]) / sqrt(2.0);
    CHECK_REL(d0, 0.025, 1e-12);
    CHECK_REL(d7, 1.0, 1e-12);
    CHECK(mf_ltcfit_aniso_ladder_lights(th, 0.0, v) == -1);
    CHECK(mf_ltcfit_aniso_ladder_lights(th, NAN, v) == -1);
    CHECK(mf_ltcfit_aniso_ladder_lights(0.5 * MF_PI, alpha, v) == -1);
  }
}

/* Defaults, who reads the option, and refusals. */
static void test_options(void)
{
    mf_ltcfit_aniso_options o;
    mf_ltcfit_aniso_options_default(&o);
    CHECK(o.ladder_alpha == 0.0);
    mf_prefilter_options po;
    mf_prefilter_options_default(&po);
    CHECK(po.fit_lights == MF_PREFILTER_LIGHTS_LADDER);
    const mf_brdf_model *ggx = mf_brdf_model_find("ggx");
    CHECK(ggx != NULL);
    if (!ggx)
        return;
    o.samples = 1024;
    /* the table's fits (random family): the same bits with the option set */
    mf_ltcfit_aniso_entry a, b;
    CHECK(mf_ltcfit_aniso_entry_fit(ggx, 0.3, 0.5, 0.7, 0.4, NULL, &o, &a) == MF_OK);
    o.ladder_alpha = 0.1;
    CHECK(mf_ltcfit_aniso_entry_fit(ggx, 0.3, 0.5, 0.7, 0.4, NULL, &o, &b) == MF_OK);
    CHECK(memcmp(a.m, b.m, sizeof a.m) == 0 && a.residual == b.residual && a.iterations == b.iterations);
    /* the structured family reads it: other lights, another residual */
    mf_brdf_params p = {0.3, 0.5};
    o.ladder_alpha = 0.0;
    CHECK(mf_ltcfit_aniso_entry_fit_general(ggx, p, 0.7, 0.4, 0.8, 1e-6, NULL, &o, &a) == MF_OK);
    o.ladder_alpha = 0.3;
    CHECK(mf_ltcfit_aniso_entry_fit_general(ggx, p, 0.7, 0.4, 0.8, 1e-6, NULL, &o, &b) == MF_OK);
    CHECK(a.residual != b.residual);
    printf("structured family, residual without / with the ladder: %.6g / %.6g\n", a.residual, b.residual);
    o.ladder_alpha = -0.1;
    CHECK(mf_ltcfit_aniso_entry_fit_general(ggx, p, 0.7, 0.4, 0.8, 1e-6, NULL, &o, &b) == MF_ERR_DOMAIN);
    o.ladder_alpha = NAN;
    CHECK(mf_ltcfit_aniso_entry_fit(ggx, 0.3, 0.5, 0.7, 0.4, NULL, &o, &b) == MF_ERR_DOMAIN);
    double n[2 * 2 * 3] = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
    po.fit_lights = 7;
    mf_prefilter_level *lv = NULL;
    int nl = 0;
    char msg[256] = "";
    CHECK(mf_prefilter_run(n, 2, 2, &po, &lv, &nl, msg, sizeof msg) == MF_ERR_DOMAIN && lv == NULL);
    CHECK(strstr(msg, "fit_lights") != NULL);
}

/* magnitude x the LTC integral of the square (two-sided, as prefilter-eval) */
static double lobe_shade(const float *m9, double mag, const mf_vec3 v[4])
{
    mf_mat3 m;
    for (int i = 0; i < 9; ++i)
        m.m[i / 3][i % 3] = m9[i];
    mf_ltc ltc;
    if (mf_ltc_init(&ltc, m) != MF_OK)
        return NAN;
    mf_polygon p = mf_polygon_make(4, v);
    return mag * mf_ltc_integrate_polygon(&ltc, &p, MF_POLYGON_TWO_SIDED);
}

/* The effective BRDF's integral over the square c + a e1 + b e2, |a|, |b| <= h (plane at distance 1
 * facing the origin: d omega = dA / r^3), by the midpoint rule on n x n cells. */
static double truth_shade(const mf_prefilter_mix *mix, const mf_brdf_params *p, mf_vec3 wo, mf_vec3 c, mf_vec3 e1,
                          mf_vec3 e2, double h, int n)
{
    double s = 0.0, da = (2.0 * h / n) * (2.0 * h / n);
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            double a = -h + (i + 0.5) * 2.0 * h / n, b = -h + (j + 0.5) * 2.0 * h / n;
            mf_vec3 q = mf_vec3_add(c, mf_vec3_add(mf_vec3_scale(e1, a), mf_vec3_scale(e2, b)));
            double r = mf_vec3_length(q);
            mf_vec3 wi = mf_vec3_scale(q, 1.0 / r);
            if (wi.z > 0.0)
                s += mix->model.eval_cos(&mix->model, p, wo, wi) * da / (r * r * r);
        }
    return s;
}

/* The V-groove of tests/test_prefilter.c (30 deg facets, period 4, 4 x 4): its level-2 footprint holds
 * both facets.  Seen along the groove (phi = 90 deg) the two facet lobes lie on either side of the view
 * plane and the mirror direction sits in the gap between them; prefilter-eval's lights are squares
 * centred there.  Revision 5's family (fit_lights LOBE) had no light smaller than the gap and put the
 * symmetric lobe's peak in it.  The views are prefilter-eval's default grid (analysis/
 * prefilter_eval_data.sh: --views 4x4, elevations 0, 30, 60, 89.9 deg); its two inner rows are checked. */
static void test_groove(void)
{
    enum { W = 4 };
    double n[W * W * 3];
    const double t = MF_PI / 6;
    for (int j = 0; j < W; ++j)
        for (int i = 0; i < W; ++i) {
            double *q = n + 3 * (j * W + i);
            q[0] = (i % 4) < 2 ? sin(t) : -sin(t), q[1] = 0.0, q[2] = cos(t);
        }
    mf_prefilter_options o;
    mf_prefilter_options_default(&o);
    o.n_theta = 4, o.n_phi = 4;
    mf_prefilter_level *lad = NULL, *lob = NULL;
    int nla = 0, nlo = 0;
    char msg[256];
    CHECK(mf_prefilter_run(n, W, W, &o, &lad, &nla, msg, sizeof msg) == MF_OK);
    o.fit_lights = MF_PREFILTER_LIGHTS_LOBE;
    CHECK(mf_prefilter_run(n, W, W, &o, &lob, &nlo, msg, sizeof msg) == MF_OK);
    CHECK(nla == 2 && nlo == 2);
    if (nla != 2 || nlo != 2)
        return;
    /* the view-azimuth-aligned frame at phi = 90 deg: the normals rotated by -90 deg about z */
    double rn[W * W * 3];
    for (int k = 0; k < W * W; ++k)
        rn[3 * k] = n[3 * k + 1], rn[3 * k + 1] = -n[3 * k], rn[3 * k + 2] = n[3 * k + 2];
    mf_prefilter_mix mix;
    const mf_brdf_model *ggx = mf_brdf_model_find("ggx");
    CHECK(ggx && mf_prefilter_mix_init(&mix, ggx, rn, W * W) == MF_OK);
    if (!ggx)
        return;
    mf_brdf_params p = mf_brdf_params_iso(o.alpha);
    const int ip = 1; /* 90 deg */
    static const double hs[3] = {0.05, 0.2, 0.5};
    for (int it = 1; it <= 2; ++it) { /* 30 and 60 deg */
        double th = mf_prefilter_theta(&o, it);
        mf_vec3 wo = mf_vec3_make(sin(th), 0.0, cos(th));
        mf_vec3 c = mf_vec3_make(-sin(th), 0.0, cos(th)), e1 = mf_vec3_make(cos(th), 0.0, sin(th)),
                e2 = mf_vec3_make(0.0, 1.0, 0.0);
        size_t idx = (size_t)it * o.n_phi + ip; /* level 2: one texel */
        double err_lad[3], err_lob[3], albedo = lad[1].albedo[idx];
        for (int s = 0; s < 3; ++s) {
            double h = hs[s];
            mf_vec3 v[4];
            for (int k = 0; k < 4; ++k) {
                double a = (k == 0 || k == 3) ? -h : h, b = k < 2 ? -h : h;
                v[k] = mf_vec3_add(c, mf_vec3_add(mf_vec3_scale(e1, a), mf_vec3_scale(e2, b)));
            }
            double tr = truth_shade(&mix, &p, wo, c, e1, e2, h, 400);
            double sa = lobe_shade(lad[1].m + 9 * idx, lad[1].magnitude[idx], v);
            double so = lobe_shade(lob[1].m + 9 * idx, lob[1].magnitude[idx], v);
            err_lad[s] = fabs(sa - tr), err_lob[s] = fabs(so - tr);
            printf("groove along, %.0f deg, h = %.2f: truth %.5f, ladder %.5f, lobe family %.5f (albedo %.4f)\n",
                   th * 180.0 / MF_PI, h, tr, sa, so, albedo);
        }
        /* Measured (revision 6 as merged): 30 deg, errors 0.0010 / 0.017 / 0.13 with the ladder against
         * 0.0033 / 0.050 / 0.23 with the lobe family alone (ratios 0.31, 0.34, 0.56); 60 deg, 0.0023 /
         * 0.045 / 0.026 against 0.0037 / 0.068 / 0.033 (0.61, 0.66, 0.80).  Bounds: under the lights
         * smaller than the gap (h = 0.05, 0.2) the ladder must take off at least 15 % of the error (it is
         * there for them); under h = 0.5 it must not add any.
         * Not every elevation gains this much: at 45 deg (a 3-elevation grid) the merged fitter's ladder
         * is 4 and 7 % better under h = 0.05 and 0.2 and 2 % worse under 0.5 (docs/prefilter_log.md,
         * "Revision 6 as merged"). */
        CHECK(err_lad[0] < 0.85 * err_lob[0]);
        CHECK(err_lad[1] < 0.85 * err_lob[1]);
        CHECK(err_lad[2] <= err_lob[2]);
    }
    mf_prefilter_mix_free(&mix);
    mf_prefilter_levels_free(lad, nla);
    mf_prefilter_levels_free(lob, nlo);
}

int main(void)
{
    test_geometry();
    test_options();
    test_groove();
    MF_TEST_MAIN_END();
}
