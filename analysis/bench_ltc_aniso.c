/*
 * bench_ltc_aniso.c -- speed and renderer-level accuracy of the anisotropic GGX LTC table
 * (issue 12); a benchmark, not a test.
 *
 *   build-dir/analysis/bench_ltc_aniso [--points N] [--samples M] [--threads T]
 *                                      [--objective default|relative] [--table FILE]
 *                                      [--point-seed S] [--lights quads|triangles|small|large]
 *                                      PUBLISHED.npy
 *
 * 1. Fits the default 8^4 table (mf_ltcfit_aniso_table) with T threads (default 2) and reports
 *    the wall time; --objective relative: with mf_ltcfit_aniso_options.objective =
 *    MF_LTCFIT_ANISO_OBJECTIVE_RELATIVE (mf_ltcfit_aniso.h).  --table FILE: reads an 8^4 table
 *    (e.g. the .npy of `mfkit fit ltc-aniso --out DIR`) instead of fitting one.
 *    The checks that a change is not tuned to the benchmark's own cases: --point-seed S draws
 *    another set of points (default 12, the benchmark's), --lights another light distribution
 *    (default quads, the benchmark's; bench_ltc_aniso_common.h, ABENCH_LIGHTS_*).
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
 *    The points, quads, truth, published lookup and error measures are bench_ltc_aniso_common.h,
 *    shared with analysis/study_aniso_oracle.c.
 */
#define _POSIX_C_SOURCE 200809L
#include "mfkit/mfkit.h"
#include "mfkit/mf_ltc_aniso_table.h"
#include "mfkit/mf_ltc_gate.h"
#include "mfkit/fit/mf_ltcfit_aniso.h"
#include "mfkit/io/mf_table_io.h"

#include "bench_ltc_aniso_common.h"

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
    e->abs[e->n] = abench_abs_err(v, mc);
    e->rel[e->n] = abench_rel_err(v, mc, albedo);
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
    printf("%-28s abs mean %.6f p95 %.6f   rel mean %.5f p95 %.5f   (%d lights)\n", name, sa / e->n, e->abs[p],
           sr / e->n, e->rel[p], e->n);
}

/* Mean and 95th percentile of a's abs and rel errors over b's (b: the published table's). */
static void ratios(const char *name, const errs *a, const errs *b)
{
    double s[4] = {0.0, 0.0, 0.0, 0.0};
    for (int i = 0; i < a->n; ++i)
        s[0] += a->abs[i], s[1] += a->rel[i];
    for (int i = 0; i < b->n; ++i)
        s[2] += b->abs[i], s[3] += b->rel[i];
    double *sa = malloc(sizeof(double) * (size_t)(a->n + b->n) * 2);
    double *sr = sa + a->n, *pa = sr + a->n, *pr = pa + b->n;
    memcpy(sa, a->abs, sizeof(double) * a->n), memcpy(sr, a->rel, sizeof(double) * a->n);
    memcpy(pa, b->abs, sizeof(double) * b->n), memcpy(pr, b->rel, sizeof(double) * b->n);
    qsort(sa, (size_t)a->n, sizeof(double), cmpd), qsort(sr, (size_t)a->n, sizeof(double), cmpd);
    qsort(pa, (size_t)b->n, sizeof(double), cmpd), qsort(pr, (size_t)b->n, sizeof(double), cmpd);
    int qa = (int)(0.95 * (a->n - 1)), qb = (int)(0.95 * (b->n - 1));
    printf("%-28s x published: abs mean %.3f p95 %.3f   rel mean %.3f p95 %.3f\n", name, (s[0] / a->n) / (s[2] / b->n),
           sa[qa] / pa[qb], (s[1] / a->n) / (s[3] / b->n), sr[qa] / pr[qb]);
    free(sa);
}

int main(int argc, char **argv)
{
    int points = 100, samples = 1 << 18, threads = 2, objective = MF_LTCFIT_ANISO_OBJECTIVE_DEFAULT;
    int lights = ABENCH_LIGHTS_QUADS;
    uint64_t point_seed = ABENCH_POINT_SEED;
    const char *kt = NULL, *table_path = NULL;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--points") && i + 1 < argc)
            points = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--samples") && i + 1 < argc)
            samples = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--threads") && i + 1 < argc)
            threads = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--table") && i + 1 < argc)
            table_path = argv[++i];
        else if (!strcmp(argv[i], "--point-seed") && i + 1 < argc)
            point_seed = strtoull(argv[++i], NULL, 10);
        else if (!strcmp(argv[i], "--lights") && i + 1 < argc) {
            ++i;
            lights = -1;
            for (int k = 0; k < 4; ++k)
                if (!strcmp(argv[i], abench_lights_name(k)))
                    lights = k;
            if (lights < 0) {
                fprintf(stderr, "bench_ltc_aniso: --lights %s: expected quads, triangles, small or large\n", argv[i]);
                return 2;
            }
        } else if (!strcmp(argv[i], "--objective") && i + 1 < argc) {
            ++i;
            if (!strcmp(argv[i], "relative"))
                objective = MF_LTCFIT_ANISO_OBJECTIVE_RELATIVE;
            else if (strcmp(argv[i], "default")) {
                fprintf(stderr, "bench_ltc_aniso: --objective %s: expected default or relative\n", argv[i]);
                return 2;
            }
        }
        else
            kt = argv[i];
    }
    float *pub = kt ? abench_read_kt(kt) : NULL;
    if (!pub) {
        fprintf(stderr, "bench_ltc_aniso: %s: not an (8, 8, 8, 8, 3, 3) float32 .npy\n", kt ? kt : "(none)");
        return 2;
    }
    const mf_brdf_model *ggx = mf_brdf_model_find("ggx");
    mf_ltcfit_aniso_options o;
    mf_ltcfit_aniso_options_default(&o);
    o.threads = threads;
    o.objective = objective;
    mf_table t;
    mf_ltcfit_aniso_result r;
    double t0 = now();
    memset(&r, 0, sizeof r);
    double storage_u = 0.0;
    int fitted = abench_table_get_u("bench_ltc_aniso", table_path, &o, &t, &r, &storage_u);
    if (fitted < 0)
        return 1;
    if (fitted) {
        double t1 = now();
        printf("fit 8^4, %d threads: %.2f s wall; worst residual %.4g, not converged %d of %zu, max iterations %d, "
               "anchor fallbacks %d\n",
               threads, t1 - t0, r.worst_residual, r.not_converged, mf_table_texels(&t), r.max_iterations,
               r.anchor_fallbacks);
    }
    /* the full gate on the fitted table (the smoothness checks are reported here, not in ctest) */
    mf_check ch[MF_LTC_ANISO_GATE_MAX_CHECKS];
    int nch = 0;
    /* a table read from a file is gated with its storage's rounding (float32: ltca_inverse allows each
     * product term 2 u; a fitted table in memory keeps the strict float64 bound) */
    mf_ltc_aniso_gate_options go;
    mf_ltc_aniso_gate_options_default(&go);
    go.unit_roundoff = storage_u;
    mf_status gs = mf_ltc_aniso_gate_run(&t, ggx, &go, ch, MF_LTC_ANISO_GATE_MAX_CHECKS, &nch);
    printf("gate: %s\n", gs == MF_OK ? "PASS" : "FAIL");
    for (int i = 0; i < nch; ++i)
        printf("  %-20s %s worst %.4g bound %.4g at %s\n", ch[i].name, ch[i].passed ? "ok  " : "FAIL", ch[i].worst,
               ch[i].bound, ch[i].worst_at);
    enum { Q = ABENCH_Q };
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
    abench_points pts;
    abench_points_init_seed(&pts, point_seed);
    int flipped = 0;
    double se_sum = 0.0;
    for (int i = 0; i < points; ++i) {
        double p[4];
        abench_next_point(&pts, p);
        abench_case cs;
        if (!abench_case_make_lights(ggx, p, i, samples, lights, &cs))
            continue;
        const mf_polygon *quads = cs.quads;
        const double *mc = cs.mc, *se = cs.se;
        const mf_result alb = {cs.albedo, 0.0};
        double mm[9], mag, mp[9];
        if (mf_ltc_aniso_lookup(&t, p[0], p[1], p[2], p[3], mm, &mag, NULL) != MF_OK)
            continue;
        flipped += abench_published(pub, p, mp);
        mf_ltcfit_aniso_entry fe;
        int have_fit = mf_ltcfit_aniso_entry_fit(ggx, p[0], p[1], p[2], p[3], NULL, &o, &fe) == MF_OK;
        mf_ltc lm = abench_ltc_of(mm), lp = abench_ltc_of(mp), lf = abench_ltc_of(have_fit ? fe.m : mm);
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
    printf("%d points (seed %llu) x %d lights (%s), Monte Carlo %d samples (mean standard error %.2g); published "
           "matrices interpolated to det < 0: %d\n",
           points, (unsigned long long)point_seed, Q, abench_lights_name(lights), samples, se_sum / em.n, flipped);
    ratios("mfkit 8^4 shape", &em, &ep);
    ratios("mfkit fit at the point", &ef, &ep);
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
