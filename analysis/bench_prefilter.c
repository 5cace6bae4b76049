/*
 * bench_prefilter.c -- speed of the normal-map prefilter fits (mf_prefilter_run, the code path of
 * `mfkit prefilter`: the CLI runs it tile by tile through mf_prefilter_run_from); a benchmark, not
 * a test (issue 13, "Speed and scale").
 *
 *   build-dir/analysis/bench_prefilter [--size N] [--views T P] [--threads K] [--base ggx|lambert]
 *                                      [--samples S] [--levels L] [--gate-tile] [--no-reuse]
 *
 * The map: a deterministic synthetic height field on an N x N torus (N a power of two, default 32):
 * the sum of 24 Gaussian bumps and dents (centres, radii 0.03 N .. 0.15 N and heights from a fixed
 * PCG32 stream) plus two sine ripples, normals from its central differences, so that slopes range
 * over 0 .. about 0.8 and almost no two texels share a normal (the demo V-groove map has two
 * normals in all, so it measures the fits but not the per-texel albedo).  --levels L fits only the
 * top L levels (mf_prefilter_run_from), to time the large footprints of a big map without its
 * small ones.  Identical footprints are fitted once (options.reuse; this map has few), so the lobes
 * copied are printed; --no-reuse fits every footprint (the same bits).
 *
 * Prints the lobes fitted, wall and CPU (user + sys, getrusage) time in total and per lobe, the
 * peak resident set, solver iterations per lobe, unconverged lobes, the worst residual per level
 * and a checksum (FNV-1a of the float32 matrices and magnitudes of every level, for bitwise
 * comparisons across thread counts and code changes).  Where the time goes: run it under a
 * sampling profiler (docs/prefilter.md, "Measured: speed, memory and quality"; each revision's
 * profiles: docs/prefilter_log.md).
 *
 * --gate-tile: after the fits, the gate's cost on one thread (process CPU), the map taken as one
 * region tile of a map twice as wide and tall (`mfkit prefilter`'s tile workers: docs/prefilter.md,
 * "The gate across ranks"): the tile's reference (mf_prefilter_gate_reference) and its part of the
 * gate (mf_prefilter_gate_region: all but its border's texel checks), against the whole gate over
 * the same levels (mf_prefilter_gate_run_ref, what rank 0 ran for every lobe before), per lobe.
 */
#define _POSIX_C_SOURCE 200809L
#include "mfkit/mfkit.h"
#include "mfkit/fit/mf_prefilter.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

static double cpu_seconds(void)
{
    struct rusage r;
    getrusage(RUSAGE_SELF, &r);
    return r.ru_utime.tv_sec + 1e-6 * r.ru_utime.tv_usec + r.ru_stime.tv_sec + 1e-6 * r.ru_stime.tv_usec;
}

static long peak_rss_kb(void)
{
    struct rusage r;
    getrusage(RUSAGE_SELF, &r);
    return r.ru_maxrss;
}

/* The synthetic map: height h(x, y) on the n x n torus, normals (-dh/dx, -dh/dy, 1) normalised
 * (central differences, periodic). */
static double *make_map(int n)
{
    enum { NB = 24 };
    double cx[NB], cy[NB], rad[NB], amp[NB];
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, 13, 0x62656e6368707266ull);
    for (int b = 0; b < NB; ++b) {
        cx[b] = mf_pcg32_next_double(&rng) * n;
        cy[b] = mf_pcg32_next_double(&rng) * n;
        rad[b] = (0.03 + 0.12 * mf_pcg32_next_double(&rng)) * n;
        amp[b] = (mf_pcg32_next_double(&rng) - 0.4) * 0.6 * rad[b];
    }
    double *h = malloc(sizeof(double) * (size_t)n * n), *nrm = malloc(sizeof(double) * 3 * (size_t)n * n);
    if (!h || !nrm) {
        free(h), free(nrm);
        return NULL;
    }
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            double v = 0.15 * sin(2.0 * MF_PI * 3.0 * x / n) + 0.1 * sin(2.0 * MF_PI * (2.0 * x + 5.0 * y) / n);
            for (int b = 0; b < NB; ++b) {
                double dx = fabs(x - cx[b]), dy = fabs(y - cy[b]);
                dx = fmin(dx, n - dx), dy = fmin(dy, n - dy);
                v += amp[b] * exp(-0.5 * (dx * dx + dy * dy) / (rad[b] * rad[b]));
            }
            h[(size_t)y * n + x] = v;
        }
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            double gx = 0.5 * (h[(size_t)y * n + (x + 1) % n] - h[(size_t)y * n + (x + n - 1) % n]);
            double gy = 0.5 * (h[(size_t)((y + 1) % n) * n + x] - h[(size_t)((y + n - 1) % n) * n + x]);
            double l = sqrt(gx * gx + gy * gy + 1.0);
            double *o = nrm + 3 * ((size_t)y * n + x);
            o[0] = -gx / l, o[1] = -gy / l, o[2] = 1.0 / l;
        }
    free(h);
    return nrm;
}

static uint64_t fnv(uint64_t hsh, const void *p, size_t n)
{
    const unsigned char *c = p;
    for (size_t i = 0; i < n; ++i)
        hsh = (hsh ^ c[i]) * 0x100000001b3ull;
    return hsh;
}

/* --albedo-check K: the one-texel albedo of K texels (spread over the map) at every view, by
 * mf_prefilter_mix_albedo (the revision-2 rule, MF_PREFILTER_ALBEDO_N), by mf_model_albedo at
 * n = 32 and 128, by mf_prefilter_texel_albedo (the same rule fused, and its table: what the fits
 * of revision 3 use), against mf_model_albedo at n = 512. */
#define NMETH 5
static int check_albedo(const double *nrm, int size, const mf_prefilter_options *o, int k)
{
    const mf_brdf_model *base = mf_brdf_model_find(o->base == MF_PREFILTER_BASE_LAMBERT ? "lambert" : "ggx");
    mf_brdf_params p = mf_brdf_params_iso(o->base == MF_PREFILTER_BASE_LAMBERT ? 1.0 : o->alpha);
    static const int rule_n[2] = {32, 128};
    static const char *names[NMETH] = {"mix_albedo n = 64 (revision 2)", "mf_model_albedo n = 32",
                                       "mf_model_albedo n = 128", "texel_albedo fused n = 64",
                                       "texel_albedo table (revision 3)"};
    int nm = o->base == MF_PREFILTER_BASE_GGX ? NMETH : 3;
    double worst[NMETH] = {0}, sum[NMETH] = {0}, cpu[NMETH] = {0}, under[NMETH] = {0}, dtab = 0.0;
    long n = 0;
    long ntex = (long)size * size, step = ntex / k > 0 ? ntex / k : 1;
    /* the table's nodes are filled on first use: fill them before timing the lookups */
    for (long t = 0; nm == NMETH && t < ntex; t += step) {
        mf_result r;
        if (mf_prefilter_texel_albedo(o->alpha, nrm + 3 * t, mf_vec3_make(0.0, 0.0, 1.0), 0, &r) != MF_OK)
            return 1;
    }
    for (long t = 0; t < ntex; t += step) {
        mf_prefilter_mix one;
        if (mf_prefilter_mix_init(&one, base, nrm + 3 * t, 1) != MF_OK)
            return 1;
        for (int a = 0; a < o->n_theta; ++a)
            for (int b = 0; b < o->n_phi; ++b) {
                double th = mf_prefilter_theta(o, a), ph = mf_prefilter_phi(o, b);
                mf_vec3 wo = mf_vec3_make(sin(th) * cos(ph), sin(th) * sin(ph), cos(th));
                mf_result r[NMETH], ref;
                for (int q = 0; q < nm; ++q) {
                    double c0 = cpu_seconds();
                    mf_status st = q == 0   ? mf_prefilter_mix_albedo(&one, &p, wo, &r[0])
                                   : q < 3  ? mf_model_albedo(&one.model, &p, wo, rule_n[q - 1], &r[q])
                                            : mf_prefilter_texel_albedo(o->alpha, nrm + 3 * t, wo, q == 3, &r[q]);
                    if (st != MF_OK)
                        return 1;
                    cpu[q] += cpu_seconds() - c0;
                }
                if (mf_model_albedo(&one.model, &p, wo, 512, &ref) != MF_OK)
                    return 1;
                for (int q = 0; q < nm; ++q) {
                    double e = fabs(r[q].val - ref.val);
                    worst[q] = fmax(worst[q], e), sum[q] += e;
                    under[q] += e > r[q].err; /* the estimate |Q(n) - Q(n/2)| below the true error */
                }
                if (nm == NMETH)
                    dtab = fmax(dtab, fabs(r[4].val - r[3].val));
                ++n;
            }
        mf_prefilter_mix_free(&one);
    }
    printf("albedo check: %ld (texel, view) pairs, |Q - Q(512)|:\n", n);
    for (int q = 0; q < nm; ++q)
        printf("  %-32s: worst %.2e, mean %.2e, estimate below the error at %.0f %%, %.4f ms CPU each\n", names[q],
               worst[q], sum[q] / n, 100.0 * under[q] / n, 1e3 * cpu[q] / n);
    if (nm == NMETH)
        printf("  table vs fused rule: worst %.2e\n", dtab);
    return 0;
}

int main(int argc, char **argv)
{
    int size = 32, top_levels = 0, albedo_check = 0, gate_tile = 0;
    mf_prefilter_options o;
    mf_prefilter_options_default(&o);
    o.threads = 2;
    int lambert = 0, nt = -1, np = -1;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--size") && i + 1 < argc)
            size = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--views") && i + 2 < argc)
            nt = atoi(argv[i + 1]), np = atoi(argv[i + 2]), i += 2;
        else if (!strcmp(argv[i], "--threads") && i + 1 < argc)
            o.threads = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--samples") && i + 1 < argc)
            o.samples = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--albedo-check") && i + 1 < argc)
            albedo_check = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--levels") && i + 1 < argc)
            top_levels = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--gate-tile"))
            gate_tile = 1;
        else if (!strcmp(argv[i], "--no-reuse"))
            o.reuse = 0;
        else if (!strcmp(argv[i], "--base") && i + 1 < argc) {
            ++i;
            if (!strcmp(argv[i], "lambert"))
                lambert = 1;
            else if (strcmp(argv[i], "ggx")) {
                fprintf(stderr, "bench_prefilter: --base %s: need ggx or lambert\n", argv[i]);
                return 2;
            }
        } else {
            fprintf(stderr, "usage: bench_prefilter [--size N] [--views T P] [--threads K] [--base ggx|lambert] "
                            "[--samples S] [--levels L] [--gate-tile] [--no-reuse]\n");
            return 2;
        }
    }
    if (lambert) {
        int th = o.threads, sa = o.samples;
        mf_prefilter_options_default_diffuse(&o);
        o.threads = th, o.samples = sa;
    }
    if (nt > 0)
        o.n_theta = nt, o.n_phi = np;
    if (size < 2 || size > 4096 || (size & (size - 1))) {
        fprintf(stderr, "bench_prefilter: --size %d: need a power of two in 2..4096\n", size);
        return 2;
    }
    double *nrm = make_map(size);
    if (!nrm) {
        fprintf(stderr, "bench_prefilter: out of memory\n");
        return 1;
    }
    int nl_all = 0;
    while ((size >> nl_all) > 1)
        ++nl_all;
    int first = top_levels > 0 && top_levels < nl_all ? nl_all - top_levels + 1 : 1;
    printf("bench_prefilter: mfkit %s, map %d x %d (synthetic bumps), base %s, views %d x %d, samples %d, "
           "threads %d, levels %d..%d\n",
           MFKIT_VERSION, size, size, lambert ? "lambert" : "ggx", o.n_theta, o.n_phi, o.samples, o.threads, first,
           nl_all);
    if (albedo_check > 0)
        return check_albedo(nrm, size, &o, albedo_check);
    mf_prefilter_level *lv = NULL;
    int nl = 0;
    char msg[256];
    double w0 = now(), c0 = cpu_seconds();
    mf_status st = mf_prefilter_run_from(nrm, size, size, &o, first, &lv, &nl, msg, sizeof msg);
    double wall = now() - w0, cpu = cpu_seconds() - c0;
    if (st != MF_OK) {
        fprintf(stderr, "bench_prefilter: %s (%s)\n", mf_status_str(st), msg);
        free(nrm);
        return 1;
    }
    long lobes = 0, iters = 0, nconv = 0, copied = 0;
    uint64_t hsh = 0xcbf29ce484222325ull;
    for (int l = 0; l < nl; ++l) {
        if (!lv[l].width)
            continue;
        size_t n = (size_t)lv[l].width * lv[l].height * lv[l].n_theta * lv[l].n_phi;
        hsh = fnv(hsh, lv[l].m, sizeof(float) * 9 * n);
        hsh = fnv(hsh, lv[l].magnitude, sizeof(float) * n);
        lobes += lv[l].lobes;
        iters += lv[l].iterations;
        nconv += lv[l].not_converged;
        copied += lv[l].reused;
        printf("  level %d: %4d x %-4d  %8ld lobes  worst residual %.4f  worst albedo err %.2e  "
               "iterations/lobe %.1f\n",
               lv[l].level, lv[l].width, lv[l].height, lv[l].lobes, lv[l].worst_residual, lv[l].worst_albedo_err,
               lv[l].lobes ? (double)lv[l].iterations / lv[l].lobes : 0.0);
    }
    /* lobes counts the fits; the theta = 0 lobe is fitted once and rotated to every azimuth */
    long stored = 0;
    for (int l = 0; l < nl; ++l)
        stored += (long)lv[l].width * lv[l].height * lv[l].n_theta * lv[l].n_phi;
    printf("lobes stored %ld (fitted %ld, %ld of them copied from identical footprints), iterations/fit %.2f, "
           "unconverged %ld\n",
           stored, lobes, copied, lobes ? (double)iters / lobes : 0.0, nconv);
    printf("wall %.2f s, cpu %.2f s (user+sys), per stored lobe: wall %.3f ms, cpu %.3f ms; peak RSS %.1f MB\n", wall,
           cpu, 1e3 * wall / (double)stored, 1e3 * cpu / (double)stored, peak_rss_kb() / 1024.0);
    printf("checksum %016llx\n", (unsigned long long)hsh);
    if (gate_tile && first == 1) {
        mf_prefilter_options g1 = o;
        g1.threads = 1;
        double *R[16] = {NULL};
        int ok = nl <= 16;
        for (int l = 0; ok && l < nl; ++l)
            ok = (R[l] = malloc(sizeof(double) * MF_PREFILTER_GATE_NLIGHTS * (size_t)lv[l].width * lv[l].height *
                                o.n_theta * o.n_phi)) != NULL;
        double c1 = cpu_seconds();
        ok = ok && mf_prefilter_gate_reference(lv, nl, nrm, size, size, &g1, R) == MF_OK;
        double c2 = cpu_seconds();
        mf_prefilter_gate_part part;
        ok = ok && mf_prefilter_gate_region(lv, nl, R, 2 * size, 2 * size, 0, 0, size, size, &g1, &part) == MF_OK;
        double c3 = cpu_seconds();
        mf_prefilter_gate whole;
        mf_prefilter_gate_bounds_default(&whole);
        ok = ok && mf_prefilter_gate_run_ref(lv, nl, nrm, size, size, &g1, &whole) == MF_OK;
        double c4 = cpu_seconds();
        if (!ok)
            fprintf(stderr, "bench_prefilter: the gate failed to run\n");
        else
            printf("gate on one tile (1 thread, CPU per stored lobe): reference %.2f us, the tile's part %.2f us, "
                   "together %.2f us; the whole gate over the same levels %.2f us\n",
                   1e6 * (c2 - c1) / stored, 1e6 * (c3 - c2) / stored, 1e6 * (c3 - c1) / stored, 1e6 * (c4 - c3) / stored);
        for (int l = 0; l < nl; ++l)
            free(R[l]);
    }
    mf_prefilter_levels_free(lv, nl);
    free(nrm);
    return 0;
}
