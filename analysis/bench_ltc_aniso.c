/*
 * bench_ltc_aniso.c -- speed and renderer-level accuracy of the anisotropic GGX LTC table
 * (issue 12); a benchmark, not a test.
 *
 *   build-dir/analysis/bench_ltc_aniso [--points N] [--samples M] [--threads T] PUBLISHED.npy
 *
 * 1. Fits the default 8^4 table (mf_ltcfit_aniso_table) with T threads (default 2) and reports
 *    the wall time.
 * 2. At N random off-grid (alpha_x, alpha_y, theta, phi) (alpha in [0.02, 1], theta in
 *    [0, 0.9999 pi/2], phi in [0, pi/2]; fixed seed), for 12 random quads per point
 *    (mf_ltc_gate_random_polygons_params, even indices), compares magnitude * E_LTC against a
 *    Monte Carlo integral of f cos over the quad (M samples, default 2^18; its mean standard error
 *    is printed) for: mfkit's table with quadrilinear interpolation (mf_ltc_aniso_lookup), the
 *    published table (Kt et al. 2022) with the same interpolation, and a fit made exactly at
 *    the point (mf_ltcfit_aniso_entry_fit: the fit's own error, without interpolation).
 *    Shape error: magnitude = the exact albedo for all three (the published table stores none);
 *    total error (mfkit only): the table's interpolated magnitude.  Absolute errors are in units
 *    of the reflected radiance of a unit-radiance light; relative errors against
 *    max(MC, 0.01 albedo).  Mean and 95th percentile.
 *    A published matrix interpolated to det < 0 (its entries mix flipped gauges) is evaluated as
 *    M diag(-1, 1, 1) (the same lobe density with positive orientation); the count is printed.
 */
#define _POSIX_C_SOURCE 200809L
#include "mfkit/mfkit.h"
#include "mfkit/mf_ltc_aniso_table.h"
#include "mfkit/mf_ltc_gate.h"
#include "mfkit/fit/mf_ltcfit_aniso.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

static float *read_kt(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    unsigned char h[10];
    if (fread(h, 1, 10, f) != 10 || memcmp(h, "\x93NUMPY", 6)) {
        fclose(f);
        return NULL;
    }
    int hl = h[8] | h[9] << 8;
    char hdr[512] = {0};
    if (hl >= 512 || fread(hdr, 1, (size_t)hl, f) != (size_t)hl || !strstr(hdr, "(8, 8, 8, 8, 3, 3)") ||
        !strstr(hdr, "<f4")) {
        fclose(f);
        return NULL;
    }
    size_t n = 8 * 8 * 8 * 8 * 9;
    float *d = malloc(n * sizeof *d);
    if (d && fread(d, sizeof *d, n, f) != n) {
        free(d);
        d = NULL;
    }
    fclose(f);
    return d;
}

/* Quadrilinear interpolation of the published table at (alpha_x, alpha_y, theta, phi). */
static void kt_lookup(const float *d, const double p[4], double m[9])
{
    const double hi[4] = {1.0, 1.0, 0.9999 * 0.5 * MF_PI, 0.5 * MF_PI};
    int i[4];
    double w[4];
    for (int k = 0; k < 4; ++k) {
        double x = fmin(fmax(p[k] / hi[k], 0.0), 1.0) * 7.0;
        i[k] = (int)fmin(floor(x), 6.0);
        w[k] = x - i[k];
    }
    memset(m, 0, 9 * sizeof *m);
    for (int c = 0; c < 16; ++c) {
        double wt = 1.0;
        int j[4];
        for (int k = 0; k < 4; ++k) {
            int b = (c >> k) & 1;
            j[k] = i[k] + b;
            wt *= b ? w[k] : 1.0 - w[k];
        }
        const float *e = d + ((((size_t)j[0] * 8 + j[1]) * 8 + j[2]) * 8 + j[3]) * 9;
        for (int a = 0; a < 9; ++a)
            m[a] += wt * e[a];
    }
}

static double det9(const double *m)
{
    return m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) + m[2] * (m[3] * m[7] - m[4] * m[6]);
}

static int cmpd(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

typedef struct {
    double *abs, *rel;
    int n;
} errs;

static void add(errs *e, double v, double mc, double albedo)
{
    e->abs[e->n] = fabs(v - mc);
    e->rel[e->n] = fabs(v - mc) / fmax(mc, 0.01 * albedo);
    ++e->n;
}

static void report(const char *name, errs *e)
{
    double sa = 0.0, sr = 0.0;
    for (int i = 0; i < e->n; ++i) {
        sa += e->abs[i];
        sr += e->rel[i];
    }
    qsort(e->abs, (size_t)e->n, sizeof(double), cmpd);
    qsort(e->rel, (size_t)e->n, sizeof(double), cmpd);
    int p = (int)(0.95 * (e->n - 1));
    printf("%-28s abs mean %.6f p95 %.6f   rel mean %.5f p95 %.5f   (%d quads)\n", name, sa / e->n, e->abs[p],
           sr / e->n, e->rel[p], e->n);
}

static mf_ltc ltc_of(const double *m9)
{
    mf_ltc l;
    if (mf_ltc_init(&l, mf_ltc_matrix_general(m9)) != MF_OK)
        memset(&l, 0, sizeof l);
    return l;
}

int main(int argc, char **argv)
{
    int points = 100, samples = 1 << 18, threads = 2;
    const char *kt = NULL;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--points") && i + 1 < argc)
            points = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--samples") && i + 1 < argc)
            samples = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--threads") && i + 1 < argc)
            threads = atoi(argv[++i]);
        else
            kt = argv[i];
    }
    float *pub = kt ? read_kt(kt) : NULL;
    if (!pub) {
        fprintf(stderr, "bench_ltc_aniso: %s: not an (8, 8, 8, 8, 3, 3) float32 .npy\n", kt ? kt : "(none)");
        return 2;
    }
    const mf_brdf_model *ggx = mf_brdf_model_find("ggx");
    mf_ltcfit_aniso_options o;
    mf_ltcfit_aniso_options_default(&o);
    o.threads = threads;
    mf_table t;
    mf_ltcfit_aniso_result r;
    char msg[256];
    double t0 = now();
    if (mf_ltcfit_aniso_table(ggx, &o, &t, &r, msg, sizeof msg) != MF_OK) {
        fprintf(stderr, "bench_ltc_aniso: fit failed: %s\n", msg);
        return 1;
    }
    double t1 = now();
    printf("fit 8^4, %d threads: %.2f s wall; worst residual %.4g, not converged %d of %zu, max iterations %d, "
           "anchor fallbacks %d\n",
           threads, t1 - t0, r.worst_residual, r.not_converged, mf_table_texels(&t), r.max_iterations,
           r.anchor_fallbacks);
    /* the full gate on the fitted table (the smoothness checks are reported here, not in ctest) */
    mf_check ch[MF_LTC_ANISO_GATE_MAX_CHECKS];
    int nch = 0;
    mf_status gs = mf_ltc_aniso_gate_run(&t, ggx, NULL, ch, MF_LTC_ANISO_GATE_MAX_CHECKS, &nch);
    printf("gate: %s\n", gs == MF_OK ? "PASS" : "FAIL");
    for (int i = 0; i < nch; ++i)
        printf("  %-20s %s worst %.4g bound %.4g at %s\n", ch[i].name, ch[i].passed ? "ok  " : "FAIL", ch[i].worst,
               ch[i].bound, ch[i].worst_at);
    enum { Q = 12 };
    errs em = {malloc(sizeof(double) * points * Q), malloc(sizeof(double) * points * Q), 0};
    errs et = {malloc(sizeof(double) * points * Q), malloc(sizeof(double) * points * Q), 0};
    errs ep = {malloc(sizeof(double) * points * Q), malloc(sizeof(double) * points * Q), 0};
    errs ef = {malloc(sizeof(double) * points * Q), malloc(sizeof(double) * points * Q), 0};
    /* the same, split by where the point lies: min(alpha_x, alpha_y) below the second grid
     * alpha (1/7: interpolating towards the alpha = 1e-4 anchors) or not */
    errs gm[2], gp[2];
    for (int g = 0; g < 2; ++g) {
        gm[g] = (errs){malloc(sizeof(double) * points * Q), malloc(sizeof(double) * points * Q), 0};
        gp[g] = (errs){malloc(sizeof(double) * points * Q), malloc(sizeof(double) * points * Q), 0};
    }
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, 12, 0x62656e6368ull);
    int flipped = 0;
    double se_sum = 0.0;
    for (int i = 0; i < points; ++i) {
        double p[4] = {0.02 + 0.98 * mf_pcg32_next_double(&rng), 0.02 + 0.98 * mf_pcg32_next_double(&rng),
                       0.9999 * 0.5 * MF_PI * mf_pcg32_next_double(&rng), 0.5 * MF_PI * mf_pcg32_next_double(&rng)};
        mf_brdf_params prm = {p[0], p[1]};
        mf_vec3 wo = mf_vec3_make(sin(p[2]) * cos(p[3]), sin(p[2]) * sin(p[3]), cos(p[2]));
        mf_polygon polys[2 * Q], quads[Q];
        mf_ltc_gate_random_polygons_params(ggx, &prm, wo, 5, (uint64_t)i, 2 * Q, polys);
        for (int k = 0; k < Q; ++k)
            quads[k] = polys[2 * k];
        double mc[Q], se[Q];
        mf_result alb;
        if (mf_ltc_gate_polygon_mc_params(ggx, &prm, wo, quads, Q, samples, 9, (uint64_t)i, mc, se, NULL) != MF_OK ||
            mf_model_albedo(ggx, &prm, wo, MF_MODEL_ALBEDO_N, &alb) != MF_OK)
            continue;
        double mm[9], mag, mp[9];
        if (mf_ltc_aniso_lookup(&t, p[0], p[1], p[2], p[3], mm, &mag, NULL) != MF_OK)
            continue;
        kt_lookup(pub, p, mp);
        if (det9(mp) < 0.0) {
            ++flipped;
            mp[0] = -mp[0], mp[3] = -mp[3], mp[6] = -mp[6];
        }
        mf_ltcfit_aniso_entry fe;
        int have_fit = mf_ltcfit_aniso_entry_fit(ggx, p[0], p[1], p[2], p[3], NULL, &o, &fe) == MF_OK;
        mf_ltc lm = ltc_of(mm), lp = ltc_of(mp), lf = ltc_of(have_fit ? fe.m : mm);
        for (int k = 0; k < Q; ++k) {
            double em_ = mf_ltc_integrate_polygon(&lm, &quads[k], MF_POLYGON_ONE_SIDED);
            add(&em, alb.val * em_, mc[k], alb.val);
            int g = fmin(p[0], p[1]) < 1.0 / 7.0;
            add(&gm[g], alb.val * em_, mc[k], alb.val);
            add(&gp[g], alb.val * mf_ltc_integrate_polygon(&lp, &quads[k], MF_POLYGON_ONE_SIDED), mc[k], alb.val);
            add(&et, mag * em_, mc[k], alb.val);
            add(&ep, alb.val * mf_ltc_integrate_polygon(&lp, &quads[k], MF_POLYGON_ONE_SIDED), mc[k], alb.val);
            if (have_fit)
                add(&ef, alb.val * mf_ltc_integrate_polygon(&lf, &quads[k], MF_POLYGON_ONE_SIDED), mc[k], alb.val);
            se_sum += se[k];
        }
    }
    printf("%d points x %d quads, Monte Carlo %d samples (mean standard error %.2g); published matrices "
           "interpolated to det < 0: %d\n",
           points, Q, samples, se_sum / em.n, flipped);
    report("mfkit 8^4 shape", &em);
    report("published 8^4 shape", &ep);
    report("mfkit 8^4 total", &et);
    report("mfkit fit at the point", &ef);
    report("mfkit shape, min alpha<1/7", &gm[1]);
    report("published,   min alpha<1/7", &gp[1]);
    report("mfkit shape, min alpha>1/7", &gm[0]);
    report("published,   min alpha>1/7", &gp[0]);
    mf_table_free(&t);
    mf_ltcfit_aniso_result_free(&r);
    free(pub);
    return 0;
}
