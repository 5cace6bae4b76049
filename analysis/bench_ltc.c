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
 *     per entry (each one objective + Jacobian evaluation), worst residual, unconverged entries;
 *   - with --bake DIR: `mfkit fit ltc` as a whole (mf_ltc_bake into DIR: fit, gate, export), wall
 *     and CPU time of each stage and the gate's checks; with --hdrp also the opt-in fit of Unity
 *     HDRP's grid in the export (`mfkit fit ltc --hdrp`);
 *   - with --power N: the texel check's power on the first TABLE (a table fitted by mfkit with
 *     --seed S: the check refits its texels): N single-texel corruptions, the fraction flagged per
 *     band of the true difference (power_study below);
 *   - with --reference-fit: the reference fitter re-implemented below (Nelder-Mead, one thread;
 *     GGX), its wall and CPU time, and with --bake the speed-up of mf_ltc_bake over it (wall and
 *     CPU; the CPU ratio is the one that a loaded machine does not distort); its table joins the
 *     comparison.
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
#include "mfkit/fit/mf_ltc_bake.h"
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

/* ---- the reference fitter, re-implemented as a yardstick of speed ------------------------------
 * The algorithm of the public code of Heitz, Dupuy, Hill and Neubelt 2016 (fitLTC, isotropic GGX;
 * tests/data/reference/README.md), written here from its description: per texel, the magnitude,
 * Fresnel term and mean direction of f cos from 32 x 32 stratified samples of the BRDF's sampler
 * (GGX distribution of normals); the LTC M = [X Y Z] [[m11, 0, m13], [0, m22, 0], [0, 0, 1]] with Z
 * the mean direction, X = (Z.z, 0, -Z.x) (at normal view: the identity frame and m22 = m11,
 * m13 = 0); the error sum of |f cos - LTC|^3 / (pdf_LTC + pdf_BRDF) over 32 x 32 samples of each
 * of the two densities; Nelder-Mead over (m11, m22, m13) (start the previous texel's, step 0.05,
 * relative tolerance 1e-5, at most 100 iterations), texels in the order of that code (roughness
 * from 1 down, view angle from normal to grazing, each warm-started from the previous one).  One
 * thread, double precision.  It is not the original program: its speed is what it is compared for
 * (its table is printed for comparison too, not used by any test).  GGX only. */
typedef struct ref_ltc {
    double magnitude, fresnel, m11, m22, m13;
    mf_vec3 x, y, z;
    mf_mat3 m, inv;
    double det;
} ref_ltc;

static void ref_update(ref_ltc *l)
{
    mf_mat3 f = {{{l->x.x, l->y.x, l->z.x}, {l->x.y, l->y.y, l->z.y}, {l->x.z, l->y.z, l->z.z}}};
    mf_mat3 s = {{{l->m11, 0.0, l->m13}, {0.0, l->m22, 0.0}, {0.0, 0.0, 1.0}}};
    l->m = mf_mat3_mul(f, s);
    if (mf_mat3_inverse(l->m, &l->inv) != MF_OK)
        memset(&l->inv, 0, sizeof l->inv);
    l->det = fabs(mf_mat3_det(l->m));
}

static double ref_ltc_eval(const ref_ltc *l, mf_vec3 w)
{
    mf_vec3 lo = mf_vec3_normalize(mf_mat3_apply(l->inv, w));
    double len = mf_vec3_length(mf_mat3_apply(l->m, lo));
    double jac = l->det / (len * len * len);
    return l->magnitude * (lo.z > 0.0 ? lo.z / MF_PI : 0.0) / jac;
}

static mf_vec3 ref_ltc_sample(const ref_ltc *l, double u1, double u2)
{
    double th = acos(sqrt(u1)), ph = 2.0 * MF_PI * u2;
    return mf_vec3_normalize(mf_mat3_apply(l->m, mf_vec3_make(sin(th) * cos(ph), sin(th) * sin(ph), cos(th))));
}

static double ref_lambda(double alpha, double cz)
{
    if (cz >= 1.0)
        return 0.0;
    double a = 1.0 / (alpha * sqrt(1.0 - cz * cz) / cz); /* 1 / (alpha tan theta) */
    return (-1.0 + sqrt(1.0 + 1.0 / (a * a))) / 2.0;
}

/* f cos of GGX (height-correlated masking-shadowing) and the density of ref_ggx_sample at l. */
static double ref_ggx_eval(mf_vec3 v, mf_vec3 l, double alpha, double *pdf)
{
    if (v.z <= 0.0 || l.z <= 0.0) {
        *pdf = 0.0;
        return 0.0;
    }
    mf_vec3 h = mf_vec3_normalize(mf_vec3_add(v, l));
    double sx = h.x / h.z, sy = h.y / h.z, a2 = alpha * alpha;
    double d = 1.0 / (1.0 + (sx * sx + sy * sy) / a2);
    d = d * d / (MF_PI * a2 * h.z * h.z * h.z * h.z);
    *pdf = fabs(d * h.z / 4.0 / mf_vec3_dot(v, h));
    double g2 = 1.0 / (1.0 + ref_lambda(alpha, v.z) + ref_lambda(alpha, l.z));
    return d * g2 / 4.0 / v.z;
}

static mf_vec3 ref_ggx_sample(mf_vec3 v, double alpha, double u1, double u2)
{
    double ph = 2.0 * MF_PI * u1, r = alpha * sqrt(u2 / (1.0 - u2));
    mf_vec3 n = mf_vec3_normalize(mf_vec3_make(r * cos(ph), r * sin(ph), 1.0));
    return mf_vec3_sub(mf_vec3_scale(n, 2.0 * mf_vec3_dot(n, v)), v);
}

#define REF_NS 32

static double ref_error(const ref_ltc *l, mf_vec3 v, double alpha)
{
    double err = 0.0;
    for (int j = 0; j < REF_NS; ++j)
        for (int i = 0; i < REF_NS; ++i) {
            double u1 = (i + 0.5) / REF_NS, u2 = (j + 0.5) / REF_NS;
            for (int k = 0; k < 2; ++k) {
                mf_vec3 w = k == 0 ? ref_ltc_sample(l, u1, u2) : ref_ggx_sample(v, alpha, u1, u2);
                double pdf_b, fb = ref_ggx_eval(v, w, alpha, &pdf_b);
                double fl = ref_ltc_eval(l, w), pdf_l = fl / l->magnitude;
                double e = fabs(fb - fl);
                if (pdf_l + pdf_b > 0.0)
                    err += e * e * e / (pdf_l + pdf_b);
            }
        }
    return err / (REF_NS * REF_NS);
}

typedef struct ref_fitter {
    ref_ltc *l;
    mf_vec3 v;
    double alpha;
    int isotropic;
} ref_fitter;

static double ref_objective(ref_fitter *f, const double p[3])
{
    f->l->m11 = fmax(p[0], 1e-7);
    f->l->m22 = f->isotropic ? f->l->m11 : fmax(p[1], 1e-7);
    f->l->m13 = f->isotropic ? 0.0 : p[2];
    ref_update(f->l);
    return ref_error(f->l, f->v, f->alpha);
}

/* Nelder-Mead over 3 parameters (reflection 1, expansion 2, contraction 0.5, shrink 0.5). */
static void ref_nelder_mead(ref_fitter *fn, const double start[3], double delta, double tol, int max_iter,
                            double out[3])
{
    double s[4][3], f[4];
    for (int i = 0; i < 4; ++i) {
        memcpy(s[i], start, sizeof s[i]);
        if (i > 0)
            s[i][i - 1] += delta;
        f[i] = ref_objective(fn, s[i]);
    }
    int lo = 0;
    for (int it = 0; it < max_iter; ++it) {
        int hi = 0, nh = 0;
        lo = 0;
        for (int i = 1; i < 4; ++i) {
            if (f[i] < f[lo])
                lo = i;
            if (f[i] > f[hi]) {
                nh = hi;
                hi = i;
            } else if (f[i] > f[nh])
                nh = i;
        }
        double a = fabs(f[lo]), b = fabs(f[hi]);
        if (2.0 * fabs(a - b) < (a + b) * tol)
            break;
        double o[3] = {0, 0, 0}, r[3], e[3], c[3];
        for (int i = 0; i < 4; ++i)
            if (i != hi)
                for (int k = 0; k < 3; ++k)
                    o[k] += s[i][k] / 3.0;
        for (int k = 0; k < 3; ++k)
            r[k] = o[k] + (o[k] - s[hi][k]);
        double fr = ref_objective(fn, r);
        if (fr < f[lo]) {
            for (int k = 0; k < 3; ++k)
                e[k] = o[k] + 2.0 * (r[k] - o[k]);
            double fe = ref_objective(fn, e);
            memcpy(s[hi], fe < fr ? e : r, sizeof s[hi]);
            f[hi] = fe < fr ? fe : fr;
            continue;
        }
        if (fr < f[nh]) {
            memcpy(s[hi], r, sizeof s[hi]);
            f[hi] = fr;
            continue;
        }
        for (int k = 0; k < 3; ++k)
            c[k] = o[k] + 0.5 * (s[hi][k] - o[k]);
        double fc = ref_objective(fn, c);
        if (fc < f[hi]) {
            memcpy(s[hi], c, sizeof s[hi]);
            f[hi] = fc;
            continue;
        }
        for (int i = 0; i < 4; ++i)
            if (i != lo) {
                for (int k = 0; k < 3; ++k)
                    s[i][k] = s[lo][k] + 0.5 * (s[i][k] - s[lo][k]);
                f[i] = ref_objective(fn, s[i]);
            }
    }
    memcpy(out, s[lo], sizeof s[lo]);
}

/* The reference fitter's n x n GGX table into an mfkit LTC table (minv packed from M / M22). */
static mf_status reference_fit(int n, mf_table *t)
{
    mf_status st = mf_ltc_table_create(t, n, n);
    if (st != MF_OK)
        return st;
    ref_ltc l;
    memset(&l, 0, sizeof l);
    double prev_m11 = 1.0, prev_m22 = 1.0; /* the t = 0 texel of the previous roughness */
    for (int a = n - 1; a >= 0; --a)
        for (int it = 0; it < n; ++it) {
            double x = (double)it / (n - 1), ct = 1.0 - x * x, th = fmin(1.57, acos(ct));
            mf_vec3 v = mf_vec3_make(sin(th), 0.0, cos(th));
            double rough = (double)a / (n - 1), alpha = fmax(rough * rough, 1e-5);
            /* magnitude, Fresnel, mean direction */
            double norm = 0.0, fres = 0.0;
            mf_vec3 avg = mf_vec3_make(0, 0, 0);
            for (int j = 0; j < REF_NS; ++j)
                for (int i = 0; i < REF_NS; ++i) {
                    mf_vec3 w = ref_ggx_sample(v, alpha, (i + 0.5) / REF_NS, (j + 0.5) / REF_NS);
                    double pdf, f = ref_ggx_eval(v, w, alpha, &pdf);
                    if (pdf > 0.0) {
                        double wt = f / pdf;
                        mf_vec3 h = mf_vec3_normalize(mf_vec3_add(v, w));
                        norm += wt;
                        fres += wt * pow(1.0 - fmax(mf_vec3_dot(v, h), 0.0), 5.0);
                        avg = mf_vec3_add(avg, mf_vec3_scale(w, wt));
                    }
                }
            l.magnitude = norm / (REF_NS * REF_NS);
            l.fresnel = fres / (REF_NS * REF_NS);
            avg.y = 0.0;
            avg = mf_vec3_normalize(avg);
            int iso = it == 0;
            if (iso) {
                l.x = mf_vec3_make(1, 0, 0);
                l.y = mf_vec3_make(0, 1, 0);
                l.z = mf_vec3_make(0, 0, 1);
                l.m11 = prev_m11;
                l.m22 = prev_m22;
                l.m13 = 0.0;
            } else {
                l.x = mf_vec3_make(avg.z, 0, -avg.x);
                l.y = mf_vec3_make(0, 1, 0);
                l.z = avg;
            }
            ref_update(&l);
            ref_fitter fn = {&l, v, alpha, iso};
            double start[3] = {l.m11, l.m22, l.m13}, res[3];
            ref_nelder_mead(&fn, start, 0.05, 1e-5, 100, res);
            ref_objective(&fn, res);
            if (iso) {
                prev_m11 = l.m11;
                prev_m22 = l.m22;
            }
            double *r = t->data + ((size_t)a + (size_t)n * (size_t)it) * (size_t)t->nfields;
            double m22 = l.m.m[2][2];
            if (mf_ltc_table_pack(l.m.m[0][0] / m22, l.m.m[0][2] / m22, l.m.m[1][1] / m22, l.m.m[2][0] / m22, r) !=
                MF_OK)
                r[0] = r[1] = r[2] = r[3] = NAN;
            r[MF_LTC_F_MAGNITUDE] = l.magnitude;
            r[MF_LTC_F_FRESNEL] = l.fresnel;
        }
    return MF_OK;
}

/* The texel check's power on the table t (fitted with the default options and `seed`): n
 * single-texel corruptions (PCG32(seed, 0x706f776572)): a random texel, a random minv field
 * v -> v + delta max(|v|, 0.1), delta = +-{0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1} (log-uniform-ish,
 * so that many land near the threshold); D = d of the corrupted texel against the stored one on
 * its gate polygons (the truth), and the check's reading at that texel
 * (mf_ltc_bake_texel_value).  Prints the fraction flagged (reading > 0.1) per band of D. */
static void power_study(const mf_table *t0, const mf_brdf_model *model, uint64_t seed, int n)
{
    mf_ltcfit_options fo;
    mf_ltcfit_options_default(&fo);
    fo.seed = seed;
    const double deltas[7] = {0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0};
    const double edges[7] = {0.0, 0.05, 0.095, 0.105, 0.2, 0.5, INFINITY};
    long cnt[6] = {0}, flag[6] = {0};
    double worst_gap = 0.0;
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, seed, 0x706f776572ULL);
    mf_table t;
    if (mf_table_copy(&t, t0) != MF_OK)
        return;
    const int nr = (int)t.axes[0].size, nu = (int)t.axes[1].size;
    double w0 = now_wall(), c0 = now_cpu();
    for (int k = 0; k < n; ++k) {
        int ir = (int)(mf_pcg32_next_u32(&rng) % (uint32_t)nr), iu = (int)(mf_pcg32_next_u32(&rng) % (uint32_t)nu);
        int fi = mf_table_field(&t, mf_ltc_table_fields[mf_pcg32_next_u32(&rng) % 4u]);
        double delta = (mf_pcg32_next_u32(&rng) & 1u ? 1.0 : -1.0) * deltas[mf_pcg32_next_u32(&rng) % 7u];
        int idx[2] = {ir, iu};
        double *r = mf_table_record(&t, idx), v0 = r[fi];
        mf_ltc a, b;
        double ma, mb;
        if (mf_ltc_gate_texel(t0, ir, iu, &b, &mb) != MF_OK)
            continue;
        r[fi] = v0 + delta * fmax(fabs(v0), 0.1);
        double D = INFINITY;
        if (mf_ltc_gate_texel(&t, ir, iu, &a, &ma) == MF_OK) {
            mf_polygon polys[MF_LTC_GATE_TEXEL_POLYGONS];
            mf_ltc_gate_texel_polygons(&t, model, seed, ir, iu, MF_LTC_GATE_TEXEL_POLYGONS, polys);
            D = mf_ltc_gate_texel_difference(&a, ma, &b, mb, polys, MF_LTC_GATE_TEXEL_POLYGONS, NULL);
        }
        int refit;
        double v = mf_ltc_bake_texel_value(&t, model, &fo, seed, ir, iu, &refit);
        r[fi] = v0;
        int band = 0;
        while (band < 5 && !(D < edges[band + 1]))
            ++band;
        ++cnt[band];
        flag[band] += !(v <= MF_LTC_GATE_TEXEL_REL);
        if ((D > 0.105 && v <= MF_LTC_GATE_TEXEL_REL) || (D < 0.095 && !(v <= MF_LTC_GATE_TEXEL_REL)))
            printf("  %s: texel (%d, %d) %s %+g: D %.4g, reading %.4g (refit %d)\n",
                   D > 0.105 ? "missed" : "false alarm", ir, iu, t.fields[fi], delta, D, v, refit);
        if (isfinite(D) && isfinite(v) && fabs(v - D) > worst_gap)
            worst_gap = fabs(v - D);
    }
    printf("\ntexel check power, %d single-texel matrix corruptions of table '%s' (seed %llu): %.2f s wall, %.2f s CPU\n",
           n, mf_table_get_meta(&t, "brdf") ? mf_table_get_meta(&t, "brdf") : "?", (unsigned long long)seed,
           now_wall() - w0, now_cpu() - c0);
    printf("  %-22s %8s %8s %8s\n", "true difference D", "cases", "flagged", "rate");
    for (int b = 0; b < 6; ++b)
        printf("  [%6.3f, %6.3f)       %8ld %8ld %8.3f\n", edges[b], edges[b + 1], cnt[b], flag[b],
               cnt[b] ? (double)flag[b] / cnt[b] : NAN);
    printf("  worst |reading - D| (finite cases): %.4f\n", worst_gap);
    mf_table_free(&t);
}

static void usage(FILE *f)
{
    fprintf(f, "usage: bench_ltc [--fit] [--bake DIR] [--hdrp] [--reference-fit] [--power N] [--brdf NAME] [--threads N]\n"
               "                 [--size N] [--seed S] [--views V] [--polygons P] [--samples N] [--csv PATH] [TABLE ...]\n");
}

int main(int argc, char **argv)
{
    mf_image_set_backend(mf_image_oiio_backend()); /* EXR files */
    int do_fit = 0, do_ref = 0, do_hdrp = 0, power_n = 0, threads = 2, size = 64, nviews = 512, npoly = 16, nsamples = 32768;
    uint64_t seed = 1;
    const char *brdf = "ggx", *csv_path = NULL, *bake_dir = NULL;
    const char *paths[MAX_TABLES];
    int npaths = 0;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--fit"))
            do_fit = 1;
        else if (!strcmp(a, "--reference-fit"))
            do_ref = 1;
        else if (!strcmp(a, "--hdrp"))
            do_hdrp = 1;
        else if (!strcmp(a, "--power") && v)
            power_n = atoi(v), ++i;
        else if (!strcmp(a, "--bake") && v)
            bake_dir = v, ++i;
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
    if (threads < 1 || size < 2 || nviews < 1 || npoly < 1 || npoly > 256 || nsamples < 2 || (!do_fit && !do_ref && !bake_dir && !npaths)) {
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

    mf_table tables[MAX_TABLES + 2];
    const char *names[MAX_TABLES + 2];
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

    /* mfkit fit ltc as a whole (mf_ltc_bake: fit, gate, export), then the reference fitter: the
     * speed-up of the first over the second in this run, on this machine. */
    double bake_wall = NAN, bake_cpu = NAN;
    if (bake_dir) {
        mf_ltc_bake_options bo;
        mf_ltc_bake_options_default(&bo);
        bo.model = model;
        bo.fit.n_r = bo.fit.n_u = size;
        bo.fit.threads = threads;
        bo.fit.seed = seed;
        bo.out_dir = bake_dir;
        bo.tool = "bench_ltc";
        bo.hdrp = do_hdrp;
        mf_ltc_bake_report br;
        double w0 = now_wall(), c0 = now_cpu();
        mf_status st = mf_ltc_bake(&bo, &br);
        bake_wall = now_wall() - w0;
        bake_cpu = now_cpu() - c0;
        printf("\nmfkit fit ltc%s (mf_ltc_bake) %s %dx%d, %d threads: %s%s\n", do_hdrp ? " --hdrp" : "", model->name, size, size, threads,
               st == MF_OK ? "exported" : mf_status_str(st), br.gate_passed ? ", gate passed" : ", GATE FAILED");
        printf("  fit    wall %7.3f s  CPU %7.3f s\n  gate   wall %7.3f s  CPU %7.3f s\n  export wall %7.3f s  CPU %7.3f s\n"
               "  total  wall %7.3f s  CPU %7.3f s\n",
               br.fit_seconds, br.fit_cpu_seconds, br.gate_seconds, br.gate_cpu_seconds, br.export_seconds,
               br.export_cpu_seconds, bake_wall, bake_cpu);
        for (int c = 0; c < br.nchecks; ++c)
            printf("  %-20s worst %-10.4g bound %-10.4g %s  %s; worst at %s\n", br.checks[c].name, br.checks[c].worst,
                   br.checks[c].bound, br.checks[c].passed ? "pass" : "FAIL", br.checks[c].what, br.checks[c].worst_at);
        mf_ltc_bake_report_free(&br);
        if (st != MF_OK)
            return 1;
    }
    if (do_ref) {
        if (strcmp(model->name, "ggx")) {
            fprintf(stderr, "bench_ltc: --reference-fit: the reference fitter is for ggx only, not '%s'\n", model->name);
            return 2;
        }
        double w0 = now_wall(), c0 = now_cpu();
        mf_status st = reference_fit(size, &tables[ntab]);
        double wall = now_wall() - w0, cpu = now_cpu() - c0;
        if (st != MF_OK) {
            fprintf(stderr, "bench_ltc: reference fit: %s\n", mf_status_str(st));
            return 1;
        }
        printf("\nreference fitter (Nelder-Mead, 1 thread) %dx%d: wall %.3f s, CPU %.3f s\n", size, size, wall, cpu);
        if (bake_dir)
            printf("speed-up of mfkit fit ltc (fit, gate, export) over the reference fitter: %.2fx wall, %.2fx CPU\n",
                   wall / bake_wall, cpu / bake_cpu);
        names[ntab++] = "reference fitter (this run)";
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

    if (power_n > 0 && ntab > 0)
        power_study(&tables[0], model, seed, power_n);

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
