/* test_prefilter.c -- the effective BRDF of a normal-map footprint and its per-level LTC fits
 * (mf_prefilter.h) [Nahmias 2022, Eq. 2.34-2.36, Fig. 2.16].  Small maps (4 x 4) and few views
 * keep it to seconds. */
#include "mf_test.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mfkit/fit/mf_ltcfit_aniso.h"
#include "mfkit/fit/mf_prefilter.h"
#include "mfkit/mf_ltc.h"
#include "mfkit/mf_polygon.h"
#include "mfkit/mf_rng.h"

/* magnitude * the LTC integral of a quad light of half-width h about direction (theta_l, phi_l) */
static double shade(const float *m9, double mag, double theta_l, double phi_l, double h)
{
    mf_mat3 m;
    for (int i = 0; i < 9; ++i)
        m.m[i / 3][i % 3] = m9[i];
    mf_ltc ltc;
    if (mf_ltc_init(&ltc, m) != MF_OK)
        return NAN;
    mf_vec3 c = mf_vec3_make(sin(theta_l) * cos(phi_l), sin(theta_l) * sin(phi_l), cos(theta_l));
    mf_vec3 t1 = mf_vec3_normalize(mf_vec3_cross(mf_vec3_make(0, 0, 1), c));
    if (!(mf_vec3_length(t1) > 0.5))
        t1 = mf_vec3_make(1, 0, 0);
    mf_vec3 t2 = mf_vec3_cross(c, t1);
    mf_vec3 v[4];
    static const double sx[4] = {-1, 1, 1, -1}, sy[4] = {-1, -1, 1, 1};
    for (int k = 0; k < 4; ++k)
        v[k] = mf_vec3_add(c, mf_vec3_add(mf_vec3_scale(t1, h * sx[k]), mf_vec3_scale(t2, h * sy[k])));
    mf_polygon p = mf_polygon_make(4, v);
    return mag * mf_ltc_integrate_polygon(&ltc, &p, MF_POLYGON_ONE_SIDED);
}

/* count random unit normals, slopes uniform in [-spread / 2, spread / 2]^2 (fixed seed) */
static void random_normals(double *n, int count, double spread, uint64_t seed)
{
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, seed, 1);
    for (int t = 0; t < count; ++t) {
        double x = spread * (mf_pcg32_next_double(&rng) - 0.5), y = spread * (mf_pcg32_next_double(&rng) - 0.5);
        double l = sqrt(x * x + y * y + 1.0);
        n[3 * t] = x / l, n[3 * t + 1] = y / l, n[3 * t + 2] = 1.0 / l;
    }
}

static void fill(double *n, int w, int h, double tilt, int period)
{
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) {
            double sx = period ? ((i % period) < period / 2 ? sin(tilt) : -sin(tilt)) : sin(tilt);
            double *p = n + 3 * (j * w + i);
            p[0] = sx, p[1] = 0.0, p[2] = cos(tilt);
        }
}

/* A flat constant map: the mixture is GGX itself, so every level's lobes must shade like the
 * anisotropic fitter's fit of plain GGX at the same view (phi = 0: the aligned frame). */
static void test_constant(void)
{
    double n[4 * 4 * 3];
    fill(n, 4, 4, 0.0, 0);
    mf_prefilter_options o;
    mf_prefilter_options_default(&o);
    o.n_theta = 3, o.n_phi = 2;
    mf_prefilter_level *lv;
    int nl;
    char msg[256];
    CHECK(mf_prefilter_run(n, 4, 4, &o, &lv, &nl, msg, sizeof msg) == MF_OK);
    CHECK(nl == 2);
    mf_ltcfit_aniso_options fo;
    mf_ltcfit_aniso_options_default(&fo);
    const mf_brdf_model *ggx = mf_brdf_model_find("ggx");
    for (int a = 0; a < o.n_theta; ++a) {
        mf_ltcfit_aniso_entry e;
        double th = mf_prefilter_theta(&o, a);
        CHECK(mf_ltcfit_aniso_entry_fit(ggx, o.alpha, o.alpha, th, 0.0, NULL, &fo, &e) == MF_OK);
        float ref[9];
        for (int i = 0; i < 9; ++i)
            ref[i] = (float)e.m[i];
        for (int l = 0; l < nl; ++l)
            for (int t = 0; t < lv[l].width * lv[l].height; ++t)
                for (int b = 0; b < o.n_phi; ++b) {
                    size_t idx = ((size_t)t * o.n_theta + a) * o.n_phi + b;
                    /* the magnitudes: two quadratures of one albedo (128 vs 64 points per axis):
                     * 2e-3 relative is the fitter's albedo rule's own error at grazing views */
                    CHECK_REL(lv[l].albedo[idx], e.magnitude, 2e-3);
                    /* keep_albedo: the magnitude is the albedo over the lobe's mass above the
                     * horizon; the reference gets the same treatment */
                    double rn = sqrt(e.m[6] * e.m[6] + e.m[7] * e.m[7] + e.m[8] * e.m[8]);
                    double rmag = o.keep_albedo ? e.magnitude / fmax(0.5 * (1.0 + e.m[8] / rn), MF_PREFILTER_HORIZON_MIN)
                                                : e.magnitude;
                    /* lights about the reflection direction and about the normal, 3 sizes: the
                     * two fits minimise the same residuals (RMS ~1e-2 albedo at grazing views,
                     * worst_residual), so they agree to that order: 2e-2 albedo */
                    for (int s = 0; s < 3; ++s) {
                        double hw = 0.05 * pow(4.0, s);
                        double l1 = shade(lv[l].m + 9 * idx, lv[l].magnitude[idx], th, MF_PI, hw);
                        double r1 = shade(ref, rmag, th, MF_PI, hw);
                        double l2 = shade(lv[l].m + 9 * idx, lv[l].magnitude[idx], 0.0, 0.0, hw);
                        double r2 = shade(ref, rmag, 0.0, 0.0, hw);
                        /* every elevation, the grazing one (89.9 deg) included: the footprint is
                         * mirror symmetric, so the fit holds the phi = 0 zero pattern as the
                         * reference does, and the first azimuth's rows keep the better of the
                         * warm and the closed-form start (mf_prefilter.c, fit_row_entry) */
                        CHECK_ABS(l1, r1, 2e-2 * e.magnitude);
                        CHECK_ABS(l2, r2, 2e-2 * e.magnitude);
                    }
                }
    }
    mf_prefilter_levels_free(lv, nl);
}

/* The V-groove (Fig. 2.16): two opposite normals, 30 deg, in equal counts at level 2.  The
 * stored magnitude must equal the mixture's albedo estimated independently (Monte Carlo through
 * the mixture's own sampler, 2^16 random points), and the lobe must have the symmetry of the
 * groove: at phi = 0 (view across the groove) y -> -y, at phi = pi/2 (along it) x -> -x. */
static void test_vgroove(void)
{
    double n[4 * 4 * 3];
    fill(n, 4, 4, MF_PI / 6, 4);
    mf_prefilter_options o;
    mf_prefilter_options_default(&o);
    o.n_theta = 3, o.n_phi = 4;
    mf_prefilter_level *lv;
    int nl;
    char msg[256];
    CHECK(mf_prefilter_run(n, 4, 4, &o, &lv, &nl, msg, sizeof msg) == MF_OK);
    const mf_prefilter_level *top = &lv[1];
    CHECK(top->width == 1 && top->height == 1);
    mf_brdf_params p = mf_brdf_params_iso(o.alpha);
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, 7, 1);
    for (int a = 0; a < o.n_theta; ++a)
        for (int b = 0; b < o.n_phi; ++b) {
            double th = mf_prefilter_theta(&o, a), ph = mf_prefilter_phi(&o, b);
            double nr[16 * 3];
            for (int q = 0; q < 16; ++q) { /* the aligned frame */
                nr[3 * q] = cos(ph) * n[3 * q] + sin(ph) * n[3 * q + 1];
                nr[3 * q + 1] = -sin(ph) * n[3 * q] + cos(ph) * n[3 * q + 1];
                nr[3 * q + 2] = n[3 * q + 2];
            }
            mf_prefilter_mix mix;
            CHECK(mf_prefilter_mix_init(&mix, mf_brdf_model_find("ggx"), nr, 16) == MF_OK);
            CHECK(mix.n == 2);
            mf_vec3 wo = mf_vec3_make(sin(th), 0.0, cos(th));
            double s = 0.0, s2 = 0.0;
            const int N = 1 << 16;
            for (int i = 0; i < N; ++i) {
                double u[2] = {mf_pcg32_next_double(&rng), mf_pcg32_next_double(&rng)}, pdf;
                mf_vec3 wi = mix.model.sample(&mix.model, &p, wo, u, &pdf);
                double w = pdf > 0.0 ? mix.model.eval_cos(&mix.model, &p, wo, wi) / pdf : 0.0;
                s += w, s2 += w * w;
            }
            double mean = s / N, se = sqrt(fmax(s2 / N - mean * mean, 0.0) / N);
            size_t idx = (size_t)a * o.n_phi + b;
            /* 4 standard errors, plus the float storage of the magnitude */
            CHECK_MC(top->albedo[idx], se, mean, 4.0, 1e-6);
            const float *m = top->m + 9 * idx;
            /* the groove's mirror symmetry: at phi = 0 and pi (views across the groove) and pi/2,
             * 3 pi/2 (along it) the aligned-frame normals are symmetric under y -> -y, so the
             * off-pattern entries m01, m10, m12, m21 vanish; 1e-6: the float storage of entries
             * that are rounding-level (1e-16) after the theta = 0 rotation R_z(-phi) M_0 R_z(phi) */
            double off = fmax(fmax(fabs(m[1]), fabs(m[3])), fmax(fabs(m[5]), fabs(m[7])));
            CHECK_ABS(off, 0.0, 1e-6);
            /* phi and phi + pi see the same footprint (the groove is its own half-turn): the two
             * lobes agree to the float storage and the order of the mixture's sums (1e-5) */
            if (b < o.n_phi / 2) {
                const float *m2 = top->m + 9 * (idx + o.n_phi / 2);
                for (int i = 0; i < 9; ++i)
                    CHECK_ABS(m[i], m2[i], 1e-5);
            }
            mf_prefilter_mix_free(&mix);
        }
    mf_prefilter_levels_free(lv, nl);
}

/* The same bits with 1 and 3 threads. */
static void test_threads(void)
{
    double n[4 * 4 * 3];
    random_normals(n, 16, 0.4, 3);
    mf_prefilter_options o;
    mf_prefilter_options_default(&o);
    o.n_theta = 2, o.n_phi = 2;
    o.samples = 1024;
    mf_prefilter_level *a, *b;
    int na, nb;
    char msg[256];
    CHECK(mf_prefilter_run(n, 4, 4, &o, &a, &na, msg, sizeof msg) == MF_OK);
    o.threads = 3;
    CHECK(mf_prefilter_run(n, 4, 4, &o, &b, &nb, msg, sizeof msg) == MF_OK);
    CHECK(na == nb);
    for (int l = 0; l < na; ++l) {
        size_t k = (size_t)a[l].width * a[l].height * o.n_theta * o.n_phi;
        CHECK(memcmp(a[l].m, b[l].m, 9 * k * sizeof(float)) == 0);
        CHECK(memcmp(a[l].magnitude, b[l].magnitude, k * sizeof(float)) == 0);
    }
    mf_prefilter_levels_free(a, na);
    mf_prefilter_levels_free(b, nb);
    /* bad maps: one message, no levels */
    n[5] = NAN;
    mf_prefilter_level *c = (mf_prefilter_level *)1;
    int nc = -1;
    CHECK(mf_prefilter_run(n, 4, 4, &o, &c, &nc, msg, sizeof msg) == MF_ERR_DOMAIN && c == NULL && nc == 0);
    CHECK(strstr(msg, "texel (1, 0)") != NULL);
    CHECK(mf_prefilter_run(n, 3, 4, &o, &c, &nc, msg, sizeof msg) == MF_ERR_DOMAIN);
}

/* The diffuse table: Lambert.  A flat map's mixture is Lambert itself, whose LTC is the identity
 * (the cosine), and its albedo 1; a V-groove of 30 deg tilts has albedo (1 + cos 30 deg) / 2
 * exactly at every view (the clamped cosine about n over the geometric hemisphere). */
static void test_diffuse(void)
{
    double n[4 * 4 * 3];
    for (int g = 0; g < 2; ++g) {
        fill(n, 4, 4, g ? MF_PI / 6 : 0.0, g ? 4 : 0);
        mf_prefilter_options o;
        mf_prefilter_options_default_diffuse(&o);
        CHECK(o.base == MF_PREFILTER_BASE_LAMBERT && o.n_theta == 2 && o.n_phi == 4);
        o.keep_albedo = 1;
        mf_prefilter_level *lv;
        int nl;
        char msg[256];
        CHECK(mf_prefilter_run(n, 4, 4, &o, &lv, &nl, msg, sizeof msg) == MF_OK);
        double want = g ? 0.5 * (1.0 + cos(MF_PI / 6)) : 1.0;
        for (int l = 0; l < nl; ++l)
            for (size_t e = 0; e < (size_t)lv[l].width * lv[l].height * o.n_theta * o.n_phi; ++e) {
                CHECK_REL(lv[l].albedo[e], want, 1e-6); /* closed form, float storage */
                if (!g) { /* the identity, up to the fit's residual: the shading of 3 lights about the
                           * normal within 1e-2 of the albedo (the fitter's light sums are
                           * quasi-Monte Carlo estimates with ~1e-3 relative error) */
                    static const float id[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
                    for (int s = 0; s < 3; ++s) {
                        double hw = 0.05 * pow(4.0, s);
                        CHECK_ABS(shade(lv[l].m + 9 * e, lv[l].magnitude[e], 0.0, 0.0, hw), shade(id, 1.0, 0.0, 0.0, hw), 1e-2);
                        CHECK_ABS(shade(lv[l].m + 9 * e, lv[l].magnitude[e], 1.0, MF_PI, hw), shade(id, 1.0, 1.0, MF_PI, hw), 1e-2);
                    }
                }
            }
        mf_prefilter_gate gt;
        mf_prefilter_gate_bounds_default(&gt);
        CHECK(mf_prefilter_gate_run(lv, nl, &gt) == MF_OK);
        printf("diffuse %s: gate energy %.3g, level %.3g, view %.3g, texel %.3g\n", g ? "V-groove" : "flat",
               gt.worst_energy, gt.worst_level, gt.worst_view_spike, gt.worst_texel_spike);
        CHECK(gt.pass);
        mf_prefilter_levels_free(lv, nl);
    }
}

/* The gate passes on the V-groove and fails each check on a copy broken for it. */
static void test_gate(void)
{
    double n[4 * 4 * 3];
    fill(n, 4, 4, MF_PI / 6, 4);
    mf_prefilter_options o;
    mf_prefilter_options_default(&o);
    o.n_theta = 3, o.n_phi = 4;
    mf_prefilter_level *lv;
    int nl;
    char msg[256];
    /* without keep_albedo the grazing lobes lose their mass below the horizon: energy fails */
    CHECK(mf_prefilter_run(n, 4, 4, &o, &lv, &nl, msg, sizeof msg) == MF_OK);
    mf_prefilter_gate g;
    mf_prefilter_gate_bounds_default(&g);
    CHECK(mf_prefilter_gate_run(lv, nl, &g) == MF_OK && !g.pass_energy);
    printf("V-groove, magnitude = albedo: energy lost up to %.3g (%s)\n", g.worst_energy, g.where_energy);
    mf_prefilter_levels_free(lv, nl);
    o.keep_albedo = 1;
    CHECK(mf_prefilter_run(n, 4, 4, &o, &lv, &nl, msg, sizeof msg) == MF_OK);
    mf_prefilter_gate_bounds_default(&g);
    CHECK(mf_prefilter_gate_run(lv, nl, &g) == MF_OK);
    printf("V-groove gate: energy %.3g (%s), level %.3g (%s), view %.3g (%s), texel %.3g\n", g.worst_energy,
           g.where_energy, g.worst_level, g.where_level, g.worst_view_spike, g.where_view, g.worst_texel_spike);
    CHECK(g.pass && g.pass_energy && g.pass_nan && g.pass_level);
    size_t e = (size_t)(1 * o.n_phi + 1); /* level 1, texel 0, view (1, 1) */
    float keep = lv[0].m[9 * e];
    lv[0].m[9 * e] = NAN;
    CHECK(mf_prefilter_gate_run(lv, nl, &g) == MF_OK && !g.pass && !g.pass_nan && g.nan_entries == 1);
    lv[0].m[9 * e] = keep;
    /* the four level-1 lobes under the level-2 texel mirrored into the other half of the view
     * plane (x -> -x: the highlights on the wrong side) at one view: the level check (one
     * mirrored child alone moves the mean by a quarter, within the bound: 0.19 -> 0.21).  At view
     * (2, 1): at (1, 1) the lobes of revision 6 are nearer to x-symmetric and the mirrored
     * children read 0.494 (revision 5: 0.542), just inside the bound 0.5; at (2, 1) 0.821. */
    int nvv = o.n_theta * o.n_phi;
    size_t em = (size_t)(2 * o.n_phi + 1);
    float keep9[4][9];
    for (int t = 0; t < 4; ++t) {
        float *m = lv[0].m + 9 * ((size_t)t * nvv + em);
        memcpy(keep9[t], m, sizeof keep9[t]);
        m[1] = -m[1], m[2] = -m[2], m[3] = -m[3], m[6] = -m[6];
    }
    CHECK(mf_prefilter_gate_run(lv, nl, &g) == MF_OK && !g.pass && !g.pass_level);
    printf("mirrored children: level %.3g (%s)\n", g.worst_level, g.where_level);
    for (int t = 0; t < 4; ++t)
        memcpy(lv[0].m + 9 * ((size_t)t * nvv + em), keep9[t], sizeof keep9[t]);
    /* a magnitude off by 30 %: the energy check */
    lv[0].magnitude[e] *= 1.3f;
    CHECK(mf_prefilter_gate_run(lv, nl, &g) == MF_OK && !g.pass && !g.pass_energy);
    CHECK_REL(g.worst_energy, 0.3, 1e-6);
    mf_prefilter_levels_free(lv, nl);
}

/* Clustered footprints (>= MF_PREFILTER_CLUSTER_MIN texels): the lobes of an 8 x 8 map of random
 * normals (slopes up to 0.3) at every level (the top one, 64 texels, clustered; the others started from it) against the
 * unclustered fit: the shading of 6 lights within 3e-2 of the albedo (printed; the size of the clusters'
 * perturbation, cells of alpha / 4 in slope, plus two fits' residuals). */
static void test_clusters(void)
{
    double n[8 * 8 * 3];
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, 5, 1);
    for (int t = 0; t < 64; ++t) {
        double x = 0.6 * (mf_pcg32_next_double(&rng) - 0.5), y = 0.6 * (mf_pcg32_next_double(&rng) - 0.5);
        double l = sqrt(x * x + y * y + 1.0);
        n[3 * t] = x / l, n[3 * t + 1] = y / l, n[3 * t + 2] = 1.0 / l;
    }
    mf_prefilter_options o;
    mf_prefilter_options_default(&o);
    o.n_theta = 2, o.n_phi = 2;
    mf_prefilter_level *a, *b;
    int na, nb;
    char msg[256];
    CHECK(mf_prefilter_run(n, 8, 8, &o, &a, &na, msg, sizeof msg) == MF_OK);
    o.cluster_cell = 0.0;
    CHECK(mf_prefilter_run(n, 8, 8, &o, &b, &nb, msg, sizeof msg) == MF_OK);
    double worst = 0.0;
    for (int l = 0; l < na; ++l)
        for (size_t e = 0; e < (size_t)a[l].width * a[l].height * o.n_theta * o.n_phi; ++e) {
            double th = mf_prefilter_theta(&o, (int)(e / o.n_phi % o.n_theta));
            CHECK(a[l].albedo[e] == b[l].albedo[e]); /* the exact texel albedos either way */
            for (int s = 0; s < 6; ++s) {
                double hw = 0.05 * pow(4.0, s % 3), tl = s < 3 ? th : 0.0;
                double x = shade(a[l].m + 9 * e, a[l].magnitude[e], tl, MF_PI, hw);
                double y = shade(b[l].m + 9 * e, b[l].magnitude[e], tl, MF_PI, hw);
                /* levels 1, 2 (4, 16 texels) are not clustered, but start from their parents */
                worst = fmax(worst, fabs(x - y) / a[l].albedo[e]);
            }
        }
    printf("clusters: 64-texel footprint, worst shading difference %.4g of the albedo\n", worst);
    CHECK(worst <= 3e-2);
    mf_prefilter_levels_free(a, na);
    mf_prefilter_levels_free(b, nb);
}

/* The albedo pyramid (mf_prefilter_albedo_level, mf_prefilter_run_tile) on an 8 x 8 map of random
 * normals, 2 x 2 views: (a) each level's albedo is the mean of its texels' one-texel albedos
 * (mf_prefilter_texel_albedo, the same table lookups) summed in row order, to 1e-13 relative: the
 * pyramid sums in another order, and 64 terms of about 1 differ by at most 64 rounding errors
 * (64 x 1.1e-16 = 7e-15); (b) the stored float albedo is that value rounded; (c) the top level fitted
 * from the level-1 or level-2 albedos alone gives the same bits as from level 0; (d) a base level not
 * below the first level is refused. */
static void test_albedo_pyramid(void)
{
    enum { W = 8 };
    double n[W * W * 3];
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, 7, 3);
    for (int t = 0; t < W * W; ++t) {
        double x = 1.2 * (mf_pcg32_next_double(&rng) - 0.5), y = 1.2 * (mf_pcg32_next_double(&rng) - 0.5);
        double l = sqrt(x * x + y * y + 1.0);
        n[3 * t] = x / l, n[3 * t + 1] = y / l, n[3 * t + 2] = 1.0 / l;
    }
    mf_prefilter_options o;
    mf_prefilter_options_default(&o);
    o.n_theta = 2, o.n_phi = 2;
    const int nv = 4;
    char msg[256];
    double lev[3][2 * 16 * 4];
    double worst = 0.0;
    for (int k = 1; k <= 3; ++k) {
        CHECK(mf_prefilter_albedo_level(n, W, W, &o, k, lev[k - 1], msg, sizeof msg) == MF_OK);
        int lw = W >> k, f = 1 << k;
        for (int r = 0; r < lw; ++r)
            for (int c = 0; c < lw; ++c)
                for (int v = 0; v < nv; ++v) {
                    double th = mf_prefilter_theta(&o, v / o.n_phi), ph = mf_prefilter_phi(&o, v % o.n_phi);
                    mf_vec3 wo = mf_vec3_make(sin(th) * cos(ph), sin(th) * sin(ph), cos(th));
                    double sum = 0.0;
                    for (int y = r * f; y < (r + 1) * f; ++y)
                        for (int x = c * f; x < (c + 1) * f; ++x) {
                            mf_result a;
                            CHECK(mf_prefilter_texel_albedo(o.alpha, n + 3 * (y * W + x), wo, 0, &a) == MF_OK);
                            sum += a.val;
                        }
                    double want = sum / (f * f), got = lev[k - 1][2 * ((r * lw + c) * nv + v)];
                    worst = fmax(worst, fabs(got - want) / want);
                }
    }
    printf("albedo pyramid: worst relative difference from the row-order mean %.3g\n", worst);
    CHECK(worst <= 1e-13);
    mf_prefilter_level *a, *b, *c;
    int na, nb, nc;
    CHECK(mf_prefilter_run_from(n, W, W, &o, 3, &a, &na, msg, sizeof msg) == MF_OK);
    CHECK(mf_prefilter_run_tile(n, W, W, &o, 3, lev[0], 1, &b, &nb, msg, sizeof msg) == MF_OK);
    CHECK(mf_prefilter_run_tile(n, W, W, &o, 3, lev[1], 2, &c, &nc, msg, sizeof msg) == MF_OK);
    CHECK(na == 3 && nb == 3 && nc == 3);
    for (int v = 0; v < nv; ++v)
        CHECK(a[2].albedo[v] == (float)lev[2][2 * v]);
    CHECK(memcmp(a[2].m, b[2].m, 9 * nv * sizeof(float)) == 0 && memcmp(a[2].m, c[2].m, 9 * nv * sizeof(float)) == 0);
    CHECK(memcmp(a[2].magnitude, b[2].magnitude, nv * sizeof(float)) == 0 &&
          memcmp(a[2].magnitude, c[2].magnitude, nv * sizeof(float)) == 0);
    CHECK(memcmp(a[2].albedo, b[2].albedo, nv * sizeof(float)) == 0 &&
          memcmp(a[2].albedo, c[2].albedo, nv * sizeof(float)) == 0);
    CHECK(a[2].worst_albedo_err == b[2].worst_albedo_err && a[2].worst_albedo_err == c[2].worst_albedo_err);
    mf_prefilter_levels_free(a, na);
    mf_prefilter_levels_free(b, nb);
    mf_prefilter_levels_free(c, nc);
    CHECK(mf_prefilter_run_tile(n, W, W, &o, 2, lev[1], 2, &c, &nc, msg, sizeof msg) == MF_ERR_DOMAIN && c == NULL);
    CHECK(strstr(msg, "albedo base level 2") != NULL);
}

/* options.lobe (two lobes per entry).  A map of two normals in alternating columns: every footprint
 * holds both at equal counts, its 2-means halves are the two normals, so half a's table (the larger
 * n.x) must be the constant map of that normal at every level and view, with half its albedo and
 * magnitude, and half b's the other normal's.  Tolerances: the fits' albedo inputs differ by rounding
 * (the pyramid sums 4^l equal values, the half its texels' mean), so M is compared to 2e-6 (float
 * storage 6e-8, the fit's response to an ulp of its magnitude target well below that) and the
 * magnitudes and albedos to 1e-6 relative. */
static void test_two_lobes(void)
{
    /* the split itself */
    {
        const double t = 0.3, c = cos(t), s = sin(t);
        double nrm[5 * 3] = {-s, 0, c, s, 0, c, -s, 0, c, s, 0, c, -s, 0, c};
        int side[5];
        CHECK(mf_prefilter_split_two(nrm, 5, side) == 3); /* half b: the three -x normals */
        CHECK(side[0] == 1 && side[1] == 0 && side[2] == 1 && side[3] == 0 && side[4] == 1);
        double one[3 * 3] = {0, s, c, 0, s, c, 0, s, c};
        CHECK(mf_prefilter_split_two(one, 3, side) == 0 && side[0] == 0 && side[1] == 0 && side[2] == 0);
        double ys[4 * 3] = {0, -s, c, 0, s, c, 0, -s, c, 0, s, c}; /* equal x: the larger y is half a */
        CHECK(mf_prefilter_split_two(ys, 4, side) == 2 && side[0] == 1 && side[1] == 0);
    }
    double n[4 * 4 * 3], na[4 * 4 * 3], nb[4 * 4 * 3];
    const double tilt = 0.35;
    fill(n, 4, 4, tilt, 2);
    fill(na, 4, 4, tilt, 0);
    fill(nb, 4, 4, -tilt, 0);
    mf_prefilter_options o;
    mf_prefilter_options_default(&o);
    o.n_theta = 3, o.n_phi = 4, o.keep_albedo = 1;
    char msg[256];
    mf_prefilter_level *h[2], *c[2];
    int nh[2], ncst[2];
    for (int k = 0; k < 2; ++k) {
        o.lobe = k + 1;
        CHECK(mf_prefilter_run(n, 4, 4, &o, &h[k], &nh[k], msg, sizeof msg) == MF_OK);
        o.lobe = 0;
        CHECK(mf_prefilter_run(k ? nb : na, 4, 4, &o, &c[k], &ncst[k], msg, sizeof msg) == MF_OK);
        CHECK(nh[k] == 2 && ncst[k] == 2);
        double dm = 0.0, dmag = 0.0, dalb = 0.0;
        for (int l = 0; l < 2; ++l) {
            long ne = (long)h[k][l].width * h[k][l].height * o.n_theta * o.n_phi;
            for (long e = 0; e < ne; ++e) {
                for (int i = 0; i < 9; ++i)
                    dm = fmax(dm, fabs(h[k][l].m[9 * e + i] - c[k][l].m[9 * e + i]));
                dmag = fmax(dmag, fabs(h[k][l].magnitude[e] / (0.5 * c[k][l].magnitude[e]) - 1.0));
                dalb = fmax(dalb, fabs(h[k][l].albedo[e] / (0.5 * c[k][l].albedo[e]) - 1.0));
            }
        }
        if (!(dm <= 2e-6 && dmag <= 1e-6 && dalb <= 1e-6))
            printf("two lobes, half %c: |M - M_const| %.3g, magnitude %.3g, albedo %.3g\n", "ab"[k], dm, dmag, dalb);
        CHECK(dm <= 2e-6 && dmag <= 1e-6 && dalb <= 1e-6);
        mf_prefilter_gate g; /* with the options: a half table's gate (energy and nan) */
        mf_prefilter_gate_bounds_default(&g);
        o.lobe = k + 1;
        CHECK(mf_prefilter_gate_run_ref(h[k], nh[k], n, 4, 4, &o, &g) == MF_OK);
        o.lobe = 0;
        if (!(g.pass && g.half_table == 1))
            printf("half %c gate: pass %d energy %.3g (%s) nan %ld half_table %d\n", "ab"[k], g.pass, g.worst_energy, g.where_energy, g.nan_entries, g.half_table);
        CHECK(g.pass && g.pass_energy && g.pass_nan && g.half_table == 1);
    }
    /* the two halves gated as one table (mf_prefilter_gate_run_pair): every check on the sum of the lobes.
     * Each half is exactly one normal's lobe, so the sum follows the footprint and passes; the level check,
     * which one lobe per entry cannot pass tightly on this map, reads near 0 (bound: a tenth of the one-lobe
     * table's).  A half's magnitude zeroed at one entry must fail the energy check there. */
    {
        mf_prefilter_level *w1;
        int nw1;
        CHECK(mf_prefilter_run(n, 4, 4, &o, &w1, &nw1, msg, sizeof msg) == MF_OK);
        mf_prefilter_gate g1, g2;
        mf_prefilter_gate_bounds_default(&g1);
        mf_prefilter_gate_bounds_default(&g2);
        CHECK(mf_prefilter_gate_run_ref(w1, nw1, n, 4, 4, &o, &g1) == MF_OK);
        CHECK(mf_prefilter_gate_run_pair(h[0], h[1], nh[0], n, 4, 4, &o, &g2) == MF_OK);
        printf("two lobes, pair gate: pass %d, energy %.3g, level %.3g (one lobe: %.3g), own fit %.3g, excess %.3g, "
               "largest error %.3g (one lobe: %.3g)\n",
               g2.pass, g2.worst_energy, g2.worst_level, g1.worst_level, g2.worst_cont_owner, g2.worst_cont_excess,
               g2.worst_ref_error, g1.worst_ref_error);
        CHECK(g2.pass && g2.half_table == 0 && g2.worst_energy <= 1e-5);
        CHECK(g2.worst_level <= 0.1 * g1.worst_level && g2.worst_ref_error < g1.worst_ref_error);
        float keep = h[1][0].magnitude[5];
        h[1][0].magnitude[5] = 0.0f;
        mf_prefilter_gate_bounds_default(&g2);
        CHECK(mf_prefilter_gate_run_pair(h[0], h[1], nh[0], n, 4, 4, &o, &g2) == MF_OK);
        CHECK(!g2.pass && !g2.pass_energy && g2.worst_energy > 0.3);
        h[1][0].magnitude[5] = keep;
        o.lobe = 1;
        CHECK(mf_prefilter_gate_run_pair(h[0], h[1], nh[0], n, 4, 4, &o, &g2) == MF_ERR_DOMAIN);
        o.lobe = 0;
        mf_prefilter_levels_free(w1, nw1);
    }
    /* a constant map has no split: half b is empty (identity, magnitude and albedo 0) */
    mf_prefilter_level *e;
    int ne;
    o.lobe = 2;
    CHECK(mf_prefilter_run(na, 4, 4, &o, &e, &ne, msg, sizeof msg) == MF_OK);
    int empty = 1;
    for (int l = 0; l < ne; ++l)
        for (long q = 0; q < (long)e[l].width * e[l].height * o.n_theta * o.n_phi; ++q)
            empty &= e[l].magnitude[q] == 0.0f && e[l].albedo[q] == 0.0f && e[l].m[9 * q] == 1.0f &&
                     e[l].m[9 * q + 4] == 1.0f && e[l].m[9 * q + 8] == 1.0f && e[l].m[9 * q + 1] == 0.0f;
    CHECK(empty);
    mf_prefilter_gate g;
    mf_prefilter_gate_bounds_default(&g);
    CHECK(mf_prefilter_gate_run_ref(e, ne, na, 4, 4, &o, &g) == MF_OK && g.pass && g.half_table == 1);
    mf_prefilter_levels_free(e, ne);
    o.lobe = 3;
    CHECK(mf_prefilter_run(na, 4, 4, &o, &e, &ne, msg, sizeof msg) == MF_ERR_DOMAIN && strstr(msg, "lobe 3"));
    /* a random map: the halves' albedos sum to the whole footprint's (to float rounding) */
    double r[8 * 8 * 3];
    random_normals(r, 64, 0.6, 7);
    o.n_theta = 2, o.n_phi = 2, o.samples = 256;
    mf_prefilter_level *w[3];
    int nw[3];
    for (int k = 0; k < 3; ++k) {
        o.lobe = k;
        CHECK(mf_prefilter_run(r, 8, 8, &o, &w[k], &nw[k], msg, sizeof msg) == MF_OK && nw[k] == 3);
    }
    double worst = 0.0;
    for (int l = 0; l < 3; ++l)
        for (long q = 0; q < (long)w[0][l].width * w[0][l].height * 4; ++q)
            worst = fmax(worst, fabs((w[1][l].albedo[q] + w[2][l].albedo[q]) / w[0][l].albedo[q] - 1.0));
    if (!(worst <= 1e-6))
        printf("two lobes: halves' albedo sum vs the footprint's: %.3g\n", worst);
    CHECK(worst <= 1e-6);
    for (int k = 0; k < 3; ++k)
        mf_prefilter_levels_free(w[k], nw[k]);
    for (int k = 0; k < 2; ++k)
        mf_prefilter_levels_free(h[k], nh[k]), mf_prefilter_levels_free(c[k], ncst[k]);
}

/* options.reuse: a footprint whose fit inputs equal, bit for bit, those of a footprint fitted before in
 * the same call gets a copy of its lobes.  The copies must be the bits its own fits give: on a 16 x 16 map
 * made of one 8 x 8 patch of random normals repeated 2 x 2 (its first 2 x 2 block one normal: a uniform
 * footprint; the level-3 footprints, 64 texels, are clustered), every level's matrices, magnitudes,
 * albedos and fit statistics equal those of a run without reuse, for the one-lobe table, both halves and
 * the Lambert table, with 1 and 2 threads.  With one thread the copies are exactly the repeats: per
 * level the footprints less the patch's own (64 - 16, 16 - 4, 4 - 1, 1 - 1), times the views. */
static void test_reuse(void)
{
    double patch[8 * 8 * 3], n[16 * 16 * 3];
    random_normals(patch, 64, 0.6, 11);
    for (int t = 1; t < 4; ++t) { /* the 2 x 2 block at the patch's corner: texels 0, 1, 8, 9 */
        int q = t == 1 ? 1 : t == 2 ? 8 : 9;
        memcpy(patch + 3 * q, patch, sizeof(double) * 3);
    }
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x)
            memcpy(n + 3 * (y * 16 + x), patch + 3 * ((y % 8) * 8 + x % 8), sizeof(double) * 3);
    char msg[256];
    for (int run = 0; run < 4; ++run) {
        mf_prefilter_options o;
        if (run == 3)
            mf_prefilter_options_default_diffuse(&o);
        else
            mf_prefilter_options_default(&o), o.lobe = run;
        CHECK(o.reuse == 1);
        o.n_theta = 2, o.n_phi = 2, o.samples = 256, o.keep_albedo = 1;
        int nv = o.n_theta * o.n_phi;
        mf_prefilter_level *r[3];
        int nr[3];
        for (int k = 0; k < 3; ++k) { /* 0: no reuse; 1: reuse, 1 thread; 2: reuse, 2 threads */
            o.reuse = k > 0;
            o.threads = k == 2 ? 2 : 1;
            CHECK(mf_prefilter_run(n, 16, 16, &o, &r[k], &nr[k], msg, sizeof msg) == MF_OK && nr[k] == 4);
        }
        long copies = 0;
        for (int l = 0; l < 4; ++l) {
            const mf_prefilter_level *a = &r[0][l];
            size_t cnt = (size_t)a->width * a->height * nv;
            CHECK(a->reused == 0);
            for (int k = 1; k < 3; ++k) {
                const mf_prefilter_level *b = &r[k][l];
                int same = !memcmp(a->m, b->m, 9 * cnt * sizeof(float)) &&
                           !memcmp(a->magnitude, b->magnitude, cnt * sizeof(float)) &&
                           !memcmp(a->albedo, b->albedo, cnt * sizeof(float)) && a->iterations == b->iterations &&
                           a->not_converged == b->not_converged && a->lobes == b->lobes &&
                           !memcmp(&a->worst_residual, &b->worst_residual, sizeof(double)) &&
                           !memcmp(&a->worst_albedo_err, &b->worst_albedo_err, sizeof(double));
                if (!same)
                    printf("reuse: run %d (lobe %d, %s), level %d, %d thread(s): not the bits of the run without reuse\n",
                           run, o.lobe, run == 3 ? "lambert" : "ggx", l + 1, k);
                CHECK(same);
            }
            long want = ((long)a->width * a->height - (long)(a->width / 2 > 0 ? a->width / 2 : 1) *
                                                         (a->height / 2 > 0 ? a->height / 2 : 1)) * nv;
            if (run == 0 && r[1][l].reused != want)
                printf("reuse: level %d: %ld lobes copied with one thread, expected %ld\n", l + 1, r[1][l].reused, want);
            if (run == 0)
                CHECK(r[1][l].reused == want);
            copies += r[1][l].reused;
        }
        if (!(copies > 0))
            printf("reuse: run %d copied no lobe\n", run);
        CHECK(copies > 0);
        for (int k = 0; k < 3; ++k)
            mf_prefilter_levels_free(r[k], nr[k]);
    }
    mf_prefilter_options o;
    mf_prefilter_options_default(&o);
    o.reuse = 2;
    mf_prefilter_level *e;
    int ne;
    CHECK(mf_prefilter_run(n, 16, 16, &o, &e, &ne, msg, sizeof msg) == MF_ERR_DOMAIN && strstr(msg, "reuse 2"));
}

int main(void)
{
    test_constant();
    test_vgroove();
    test_threads();
    test_diffuse();
    test_gate();
    test_clusters();
    test_albedo_pyramid();
    test_two_lobes();
    test_reuse();
    MF_TEST_MAIN_END();
}
