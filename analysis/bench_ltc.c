/*
 * bench_ltc.c -- speed and accuracy of LTC tables (issue 7, "Speed and accuracy"; a benchmark,
 * not a test).
 *
 * usage: bench_ltc [--fit] [--brdf NAME] [--threads N] [--size N] [--seed S] [--views V]
 *                  [--polygons P] [--samples N] [--csv PATH] [TABLE ...]
 *
 * For every TABLE (an mfkit table: .json/.exr/.dds/.npy; or the reference CSV layout, e.g.
 * tests/data/reference/ltc_code_ggx_64.csv) and, with --fit, for a table fitted now by
 * mf_ltcfit_table (fit/include/mfkit/fit/mf_ltcfit.h), it prints:
 *   - the polygon-shading error against Monte Carlo over V random views BETWEEN the texels
 *     ((r, u) uniform in [0, 1]^2), with the bilinear lookup a shader does (mf_table_lookup of
 *     the 4 minv fields and the magnitude, then mf_ltc_table_unpack), P random quads and
 *     triangles per view (mf_ltc_gate_random_polygons: a third towards the lobe, a third across
 *     the horizon), LTC = magnitude * mf_ltc_integrate_polygon (clipped after the transform,
 *     one-sided): mean and 95th percentile of |LTC - MC| and of |LTC - MC| / max(MC, 0.01 albedo);
 *   - the albedo error at the same views: |magnitude(lookup) - quadrature| / quadrature
 *     (mf_model_albedo, 128 x 128 Gauss-Legendre through the model's sampler);
 *   - the LTC gate (quick) on the table's own texels;
 *   - with --fit: wall time, CPU time, time per entry, peak memory (getrusage), solver iterations
 *     per entry (each one objective + Jacobian evaluation), worst residual, unconverged entries.
 * Every table sees the SAME views, polygons and Monte Carlo estimates (a paired comparison), for
 * the truth alpha = max(r^2, 1e-4) (mfkit's domain: the reference's 1e-5 clamp differs only for
 * r < 0.01) and cos theta = max(1 - u^2, cos 1.57).  Fixed seeds; the seed and the command line are
 * printed.  --csv PATH writes one row per (table, view, polygon) (use notebooks_data/...).
 */
#define _POSIX_C_SOURCE 200809L
#include "study_header.h"
#include "mfkit/mfkit.h"
#include "mfkit/io/mf_ltc_reference.h"
#include "mfkit/fit/mf_ltcfit.h"
#include "mfkit/io/mf_table_io.h"
#include "mfkit/fit/mf_image_oiio.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

#define MAX_TABLES 8

typedef struct view {
    double r, u, alpha, cos_theta, albedo, albedo_err;
} view;

static double now_wall(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static double now_cpu(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec + (double)ru.ru_stime.tv_sec +
           1e-6 * (double)ru.ru_stime.tv_usec;
}

static long peak_rss_kib(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return ru.ru_maxrss; /* KiB on Linux */
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double p95(double *v, long n)
{
    if (n <= 0)
        return NAN;
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    long k = (long)ceil(0.95 * (double)n) - 1;
    return v[k < 0 ? 0 : k];
}

static mf_status load(const char *path, mf_table *t, char *msg, size_t size)
{
    if (mf_table_format_from_path(path) == MF_TABLE_FORMAT_CSV)
        return mf_ltc_reference_read_csv(path, t, msg, size);
    return mf_table_read(path, t, NULL, msg, size);
}

static void usage(FILE *f)
{
    fprintf(f, "usage: bench_ltc [--fit] [--brdf NAME] [--threads N] [--size N] [--seed S] [--views V]\n"
               "                 [--polygons P] [--samples N] [--csv PATH] [TABLE ...]\n");
}

int main(int argc, char **argv)
{
    mf_image_set_backend(mf_image_oiio_backend()); /* EXR files */
    int do_fit = 0, threads = 2, size = 64, nviews = 512, npoly = 16, nsamples = 32768;
    uint64_t seed = 1;
    const char *brdf = "ggx", *csv_path = NULL;
    const char *paths[MAX_TABLES];
    int npaths = 0;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--fit"))
            do_fit = 1;
        else if (!strcmp(a, "--brdf") && v)
            brdf = v, ++i;
        else if (!strcmp(a, "--threads") && v)
            threads = atoi(v), ++i;
        else if (!strcmp(a, "--size") && v)
            size = atoi(v), ++i;
        else if (!strcmp(a, "--seed") && v)
            seed = strtoull(v, NULL, 10), ++i;
        else if (!strcmp(a, "--views") && v)
            nviews = atoi(v), ++i;
        else if (!strcmp(a, "--polygons") && v)
            npoly = atoi(v), ++i;
        else if (!strcmp(a, "--samples") && v)
            nsamples = atoi(v), ++i;
        else if (!strcmp(a, "--csv") && v)
            csv_path = v, ++i;
        else if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return 0;
        } else if (a[0] == '-') {
            usage(stderr);
            return 2;
        } else if (npaths < MAX_TABLES)
            paths[npaths++] = a;
    }
    if (threads < 1 || size < 2 || nviews < 1 || npoly < 1 || npoly > 256 || nsamples < 2 || (!do_fit && !npaths)) {
        usage(stderr);
        return 2;
    }
    const mf_brdf_model *model = mf_brdf_model_find(brdf);
    if (!model) {
        fprintf(stderr, "bench_ltc: unknown BRDF '%s'\n", brdf);
        return 2;
    }
    printf("command:");
    for (int i = 0; i < argc; ++i)
        printf(" %s", argv[i]);
    printf("\nseed %llu, brdf %s, %d views x %d polygons, %d Monte Carlo samples per view\n", (unsigned long long)seed,
           model->name, nviews, npoly, nsamples);

    mf_table tables[MAX_TABLES + 1];
    const char *names[MAX_TABLES + 1];
    int ntab = 0;
    char msg[1024];
    for (int i = 0; i < npaths; ++i) {
        mf_status st = load(paths[i], &tables[ntab], msg, sizeof msg);
        if (st != MF_OK) {
            fprintf(stderr, "bench_ltc: %s\n", msg[0] ? msg : mf_status_str(st));
            return 3;
        }
        names[ntab++] = paths[i];
    }

    if (do_fit) {
        mf_ltcfit_options fo;
        mf_ltcfit_options_default(&fo);
        fo.n_r = fo.n_u = size;
        fo.threads = threads;
        fo.seed = seed;
        mf_ltcfit_result fr;
        memset(&fr, 0, sizeof fr);
        double w0 = now_wall(), c0 = now_cpu();
        mf_status st = mf_ltcfit_table(model, &fo, &tables[ntab], &fr, msg, sizeof msg);
        double wall = now_wall() - w0, cpu = now_cpu() - c0;
        if (st != MF_OK) {
            fprintf(stderr, "bench_ltc: fit: %s\n", msg[0] ? msg : mf_status_str(st));
            return 1;
        }
        int entries = size * size;
        printf("\nfit %s %dx%d, %d threads: wall %.3f s, CPU %.3f s, %.3f ms wall/entry (%.3f ms CPU), peak RSS %.1f MiB\n",
               model->name, size, size, threads, wall, cpu, 1e3 * wall / entries, 1e3 * cpu / entries,
               peak_rss_kib() / 1024.0);
        printf("  solver iterations per entry: mean %.2f, max %d (each one objective + Jacobian evaluation); "
               "not converged %d; worst residual %.4g at entry %d\n",
               (double)fr.total_iterations / entries, fr.max_iterations, fr.not_converged, fr.worst_residual,
               fr.worst_index);
        mf_ltcfit_result_free(&fr);
        names[ntab++] = "mfkit fit (this run)";
    }

    /* The views, their quadrature albedo, polygons and Monte Carlo estimates: shared by every table. */
    view *views = calloc((size_t)nviews, sizeof *views);
    mf_polygon *polys = malloc(sizeof *polys * (size_t)nviews * (size_t)npoly);
    double *mc = malloc(sizeof *mc * (size_t)nviews * (size_t)npoly * 2);
    if (!views || !polys || !mc)
        return 4;
    double *se = mc + (size_t)nviews * (size_t)npoly;
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, seed, 0x62656e6368ULL);
    double t_mc0 = now_wall();
    for (int v = 0; v < nviews; ++v) {
        view *w = &views[v];
        w->r = mf_pcg32_next_double(&rng);
        w->u = mf_pcg32_next_double(&rng);
        w->alpha = w->r * w->r > MF_LTC_ALPHA_MIN ? w->r * w->r : MF_LTC_ALPHA_MIN;
        double c = 1.0 - w->u * w->u, cmin = cos(MF_LTC_THETA_MAX);
        w->cos_theta = c > cmin ? c : cmin;
        mf_vec3 wo = mf_ltc_gate_view(w->cos_theta);
        mf_result q;
        mf_brdf_params prm = mf_brdf_params_iso(w->alpha);
        if (mf_model_albedo(model, &prm, wo, 128, &q) != MF_OK)
            return 5;
        w->albedo = q.val;
        w->albedo_err = q.err;
        mf_ltc_gate_random_polygons(model, w->alpha, wo, seed, 2 * (uint64_t)v + 1, npoly, polys + (size_t)v * npoly);
        if (mf_ltc_gate_polygon_mc(model, w->alpha, wo, polys + (size_t)v * npoly, npoly, nsamples, seed,
                                   2 * (uint64_t)v + 2, mc + (size_t)v * npoly, se + (size_t)v * npoly, NULL) != MF_OK)
            return 5;
    }
    double mean_se = 0.0;
    for (long k = 0; k < (long)nviews * npoly; ++k)
        mean_se += se[k] / ((double)nviews * npoly);
    printf("\nreference integrals: %.2f s; mean Monte Carlo standard error %.3g (|error| below ~2x this is noise)\n",
           now_wall() - t_mc0, mean_se);

    FILE *csv = NULL;
    if (csv_path) {
        csv = fopen(csv_path, "w");
        if (!csv) {
            fprintf(stderr, "bench_ltc: cannot write %s\n", csv_path);
            return 3;
        }
        char seed_s[32];
        snprintf(seed_s, sizeof seed_s, "%llu", (unsigned long long)seed);
        study_write_header(csv, "bench_ltc", argc, argv, seed_s);
        fprintf(csv, "table,view,r,u,alpha,cos_theta,polygon,vertices,ltc,mc,mc_se,abs_error,rel_error,magnitude,"
                     "albedo_quadrature\n");
    }

    long nk = (long)nviews * npoly;
    double *eabs = malloc(sizeof *eabs * (size_t)nk), *erel = malloc(sizeof *erel * (size_t)nk);
    double *ealb = malloc(sizeof *ealb * (size_t)nviews);
    if (!eabs || !erel || !ealb)
        return 4;
    printf("\n%-44s %10s %10s %10s %10s %10s %10s %10s %8s\n", "table (polygon error: between texels, bilinear)",
           "mean|e|", "p95|e|", "mean rel", "p95 rel", "alb mean", "alb p95", "alb worst", "gate");
    for (int ti = 0; ti < ntab; ++ti) {
        const mf_table *t = &tables[ti];
        int f[5];
        for (int k = 0; k < 5; ++k)
            f[k] = mf_table_field(t, mf_ltc_table_fields[k]);
        if (t->naxes != 2 || f[0] < 0 || f[1] < 0 || f[2] < 0 || f[3] < 0 || f[4] < 0) {
            printf("%-44s not an LTC table\n", names[ti]);
            continue;
        }
        double sum_abs = 0.0, sum_rel = 0.0, sum_alb = 0.0, worst_alb = 0.0;
        long bad = 0;
        double *rec = malloc(sizeof *rec * (size_t)t->nfields);
        for (int v = 0; v < nviews; ++v) {
            const view *w = &views[v];
            double p[2] = {w->r, w->u};
            mf_ltc ltc;
            int ok = rec && mf_table_lookup(t, p, rec) == MF_OK;
            double m4[4] = {ok ? rec[f[0]] : NAN, ok ? rec[f[1]] : NAN, ok ? rec[f[2]] : NAN, ok ? rec[f[3]] : NAN};
            ok = ok && mf_ltc_table_unpack(m4, &ltc) == MF_OK;
            double mag = ok ? rec[f[4]] : NAN;
            ealb[v] = fabs(mag - w->albedo) / w->albedo;
            sum_alb += ealb[v];
            if (!(ealb[v] <= worst_alb))
                worst_alb = ealb[v];
            for (int k = 0; k < npoly; ++k) {
                long i = (long)v * npoly + k;
                double l = ok ? mag * mf_ltc_integrate_polygon(&ltc, &polys[i], MF_POLYGON_ONE_SIDED) : NAN;
                double d = fabs(l - mc[i]);
                double den = mc[i] > 0.01 * w->albedo ? mc[i] : 0.01 * w->albedo;
                if (!isfinite(d))
                    ++bad, d = INFINITY;
                eabs[i] = d;
                erel[i] = d / den;
                sum_abs += d;
                sum_rel += erel[i];
                if (csv)
                    fprintf(csv, "\"%s\",%d,%.17g,%.17g,%.17g,%.17g,%d,%d,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n",
                            names[ti], v, w->r, w->u, w->alpha, w->cos_theta, k, polys[i].n, l, mc[i], se[i], d, erel[i],
                            mag, w->albedo);
            }
        }
        free(rec);
        /* The gate (quick) on the table's own texels. */
        mf_ltc_gate_options go;
        mf_ltc_gate_options_default(&go);
        go.seed = seed;
        go.quick = 1;
        mf_check checks[MF_LTC_GATE_MAX_CHECKS];
        int nc = 0;
        mf_status gs = mf_ltc_gate_run(t, model, &go, checks, MF_LTC_GATE_MAX_CHECKS, &nc);
        double mean_abs = sum_abs / nk, mean_rel = sum_rel / nk, mean_alb = sum_alb / nviews;
        printf("%-44.44s %10.4g %10.4g %10.4g %10.4g %10.3g %10.3g %10.3g %8s\n", names[ti], mean_abs, p95(eabs, nk),
               mean_rel, p95(erel, nk), mean_alb, p95(ealb, nviews), worst_alb,
               gs == MF_OK ? "pass" : (gs == MF_ERR_CHECK_FAILED ? "FAIL" : "n/a"));
        if (bad)
            printf("  %ld polygon values not finite\n", bad);
        for (int c = 0; c < nc; ++c)
            if (!checks[c].passed)
                printf("  gate: %s failed: worst %.4g > bound %.4g at %s\n", checks[c].name, checks[c].worst,
                       checks[c].bound, checks[c].worst_at);
    }
    if (csv) {
        fclose(csv);
        printf("\nper-polygon errors written to %s\n", csv_path);
    }
    for (int ti = 0; ti < ntab; ++ti)
        mf_table_free(&tables[ti]);
    free(views);
    free(polys);
    free(mc);
    free(eabs);
    free(erel);
    free(ealb);
    return 0;
}
