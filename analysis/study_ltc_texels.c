/*
 * study_ltc_texels.c -- the LTC fit error of a table per texel, over its (theta_o, roughness) grid.
 *
 *   build-dir/analysis/study_ltc_texels [--brdf NAME] [--polygons P] [--samples N] [--seed S]
 *                                       [--stride K] [--out FILE] TABLE [SECOND_TABLE]
 *
 * TABLE (and SECOND_TABLE) is any LTC table mfkit reads: an mfkit table (.exr, .json, .npy written
 * by `mfkit fit ltc`, mf_table_read; a .dds holds only 4 fields, not a whole table) or the reference CSV layout
 * (tests/data/reference/ltc_code_ggx_64.csv, mf_ltc_reference_read_csv), with the layout of
 * mf_ltc_table.h.  The BRDF is --brdf, else the table's "brdf" metadata, else ggx.
 *
 * For every tested texel (ir, iu) (every K-th along each axis, and the last one of each axis),
 * at the texel's own alpha and cos theta_o (mf_ltc_table_alpha / _cos_theta: the table's clamps),
 * with the texel's stored values (no interpolation; bench_ltc measures between texels):
 *  - albedo: the stored magnitude, the quadrature albedo (mf_model_albedo, 128 x 128 graded
 *    Gauss-Legendre through the model's sampler, with its error estimate) and their difference;
 *  - polygon shading: P random convex polygons (mf_ltc_gate_random_polygons: a third towards the
 *    lobe, a third across the horizon), the truth by Monte Carlo with N samples of the model's
 *    sampler (mf_ltc_gate_polygon_mc), LTC = magnitude * mf_ltc_integrate_polygon of the unpacked
 *    matrix (mf_ltc_table_unpack; clipped after the transform, one-sided [Heitz et al. 2016;
 *    docs/math.md, corrections C-T3, C-T4]): mean and worst |LTC - MC|, mean |LTC - MC| /
 *    max(MC, 0.01 albedo) (the relative error of bench_ltc and the gate), mean Monte Carlo
 *    standard error;
 *  - the lobe's pointwise error, an L1 distance relative to the albedo:
 *        lobe_l1 = integral over the sphere of |magnitude D(w) - f(wo, w) max(w.z, 0)| dw / albedo
 *    (D the LTC's density, mf_ltc_eval [Nahmias Eq. 2.21 with the Jacobian of correction
 *    C-T2]), estimated with N/2 samples of the model's sampler (kept only above the horizon) and
 *    N/2 of the LTC's (mf_ltc_sample), combined by the balance heuristic [Veach 1997, PhD
 *    thesis, Sec. 9.2.2: the multi-sample estimator with w_i = n_i p_i / sum_k n_k p_k], so
 *    every direction where either lobe is positive is sampled, including the LTC's mass below
 *    the horizon.  It bounds every light's error: for any
 *    set A of directions, |LTC(A) - truth(A)| <= (lobe_l1 albedo + |magnitude - albedo|) / 2, with
 *    equality for the worst A (the standard identity sup_A |mu(A) - nu(A)| = (|mu - nu|(S) +
 *    |mu(S) - nu(S)|) / 2 for two finite measures; D integrates to 1 over the sphere);
 *  - with SECOND_TABLE (same size, else exit 2): second - first of minv_00, minv_20, minv_02,
 *    minv_22, magnitude, and the second table's polygon errors on the SAME polygons and Monte
 *    Carlo values, so the difference of the two tables' errors is paired (MC noise is common).
 *
 * Randomness: PCG32 streams keyed by (seed, texel, purpose), so each texel's polygons and samples
 * do not depend on --stride or on the other texels.  Single-threaded.
 *
 * Output: one CSV (default notebooks_data/ltc_texels.csv): the provenance header (study_header.h),
 * the column names, one row per tested texel.  Columns (docs/figures.md):
 *   ir, iu, r, u, alpha, theta_deg, cos_theta, magnitude, albedo_quad, albedo_quad_err,
 *   albedo_diff (magnitude - albedo_quad), albedo_rel_diff (albedo_diff / albedo_quad), polygons,
 *   poly_mean_abs, poly_worst_abs, poly_mean_rel, mc_mean_se, lobe_l1, lobe_l1_se
 *   and with SECOND_TABLE: d_minv_00, d_minv_20, d_minv_02, d_minv_22, d_magnitude (second -
 *   first), second_poly_mean_abs, second_poly_worst_abs, second_poly_mean_rel, d_poly_mean_abs
 *   (second - first, paired), d_poly_mean_abs_se (standard error of that mean over the polygons),
 *   d_poly_mean_rel.
 * The file is written to a temporary beside it and renamed at the end: no partial output.
 * Exit status: 0 done, 2 bad usage (unknown option or BRDF, tables of different sizes), 3 a table
 * cannot be read or is not an LTC table, 4 the output cannot be written, 5 a model evaluation
 * failed.
 */
#define _POSIX_C_SOURCE 200809L
#include "mfkit/mfkit.h"
#include "mfkit/io/mf_ltc_reference.h"
#include "mfkit/io/mf_io.h"
#include "mfkit/io/mf_table_io.h"
#include "mfkit/fit/mf_image_oiio.h"

#include "study_header.h"

#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define PROG "study_ltc_texels"
#define REL_FLOOR 0.01 /* relative polygon errors against max(MC, 0.01 albedo), as bench_ltc and the gate */
#define QUAD_N 128     /* albedo quadrature points per axis, as bench_ltc */
#define MAX_POLYGONS 256

/* Stream purposes: each (texel, purpose) has its own PCG32 stream. */
enum { STREAM_POLY = 1, STREAM_MC = 2, STREAM_LOBE = 3 };

static uint64_t stream_of(int purpose, size_t texel) { return ((uint64_t)texel << 2) | (uint64_t)purpose; }

static void usage(FILE *f)
{
    fprintf(f,
            "usage: " PROG " [--brdf NAME] [--polygons P] [--samples N] [--seed S] [--stride K]\n"
            "                        [--out FILE] TABLE [SECOND_TABLE]\n\n"
            "The LTC fit error of TABLE per texel over its (theta_o, roughness) grid, one CSV row per\n"
            "tested texel: polygon shading against Monte Carlo, the lobe's pointwise L1 error, the\n"
            "albedo; with SECOND_TABLE (same size) the field differences and the second table's polygon\n"
            "errors on the same polygons (paired).  TABLE: .exr/.dds/.json/.npy (mfkit fit ltc) or the\n"
            "reference CSV layout (ltc_code_ggx_64.csv).\n\n"
            "  --brdf NAME     the BRDF the table approximates (default: the table's \"brdf\" metadata, else ggx)\n"
            "  --polygons P    random polygons per texel, 1..%d (default 32)\n"
            "  --samples N     Monte Carlo samples per texel for the polygons, and for the lobe error (default 65536)\n"
            "  --seed S        seed of every random number (default 1)\n"
            "  --stride K      test every K-th texel along each axis, and the last one (default 1: all)\n"
            "  --out FILE      output CSV (default notebooks_data/ltc_texels.csv)\n"
            "Columns and figures: docs/figures.md; plot with /usr/bin/python3 analysis/plot.py DIR OUT.\n",
            MAX_POLYGONS);
}

/* Reads an LTC table: the reference CSV layout, or a file mf_table_read reads (as bench_ltc and
 * `mfkit validate` do).  Returns 0, or the exit status after printing "path: reason". */
static int load_table(const char *path, mf_table *t, int field[5])
{
    char msg[1024] = "";
    mf_table_format fmt = mf_table_format_from_path(path);
    mf_status st;
    if (fmt == MF_TABLE_FORMAT_CSV)
        st = mf_ltc_reference_read_csv(path, t, msg, sizeof msg);
    else if (mf_table_format_readable(fmt))
        st = mf_table_read(path, t, NULL, msg, sizeof msg);
    else {
        fprintf(stderr, PROG ": %s: not a readable table format (.exr, .dds, .json, .npy, or a reference .csv)\n",
                path);
        return 3;
    }
    if (st != MF_OK) {
        fprintf(stderr, PROG ": %s\n", msg[0] ? msg : mf_status_str(st));
        return 3;
    }
    int ok = t->naxes == 2 && t->axes[0].mapping == MF_AXIS_SQUARE && t->axes[1].mapping == MF_AXIS_ONE_MINUS_SQUARE &&
             t->axes[0].size >= 2 && t->axes[1].size >= 2;
    for (int k = 0; k < 5; ++k) {
        field[k] = mf_table_field(t, mf_ltc_table_fields[k]);
        ok = ok && field[k] >= 0;
    }
    if (!ok) {
        fprintf(stderr,
                PROG ": %s: not an LTC table layout (two axes r: alpha = r^2 and u: cos = 1 - u^2, fields "
                     "minv_00, minv_20, minv_02, minv_22, magnitude)%s\n",
                path, fmt == MF_TABLE_FORMAT_DDS ? "; a .dds holds 4 of them: read the .exr, .json or .npy" : "");
        mf_table_free(t);
        return 3;
    }
    return 0;
}

/* The stored record of texel (ir, iu): the 4 minv fields and the magnitude, and its LTC
 * (mf_ltc_table_unpack, the shader's rebuild).  Returns 0 for an unusable record. */
static int texel_ltc(const mf_table *t, const int field[5], int ir, int iu, double v[5], mf_ltc *ltc)
{
    int idx[2] = {ir, iu};
    const double *rec = mf_table_record(t, idx);
    for (int k = 0; k < 5; ++k)
        v[k] = rec ? rec[field[k]] : NAN;
    return rec && isfinite(v[4]) && mf_ltc_table_unpack(v, ltc) == MF_OK;
}

/* The density of the model's sampler at wi as a sub-density of its KEPT samples: 0 below the
 * horizon, where the estimators discard its samples (cosine hemisphere without a sampler). */
static double model_pdf(const mf_brdf_model *m, double alpha, mf_vec3 wo, mf_vec3 wi)
{
    if (!(wi.z > 0.0))
        return 0.0;
    mf_brdf_params p = mf_brdf_params_iso(alpha);
    return mf_model_pdf(m, &p, wo, wi);
}

/* lobe_l1 (see the header) with its standard error.  n samples, half from each sampler; the
 * estimate is 0.5 (mean_1 + mean_2) of h = |magnitude D - f cos| / (0.5 p_model + 0.5 D), which is
 * the balance-heuristic multi-sample estimator with n_1 = n_2 [Veach 1997, Sec. 9.2.2].
 * Returns MF_ERR_DOMAIN for a non-finite model value. */
static mf_status lobe_l1(const mf_brdf_model *m, double alpha, mf_vec3 wo, const mf_ltc *ltc, double magnitude,
                         double albedo, int n, uint64_t seed, uint64_t stream, mf_result *out)
{
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, seed, stream);
    mf_brdf_params prm = mf_brdf_params_iso(alpha);
    int half = n / 2;
    double s1[2] = {0.0, 0.0}, s2[2] = {0.0, 0.0};
    for (int which = 0; which < 2; ++which)
        for (int s = 0; s < half; ++s) {
            double u[2];
            u[0] = mf_pcg32_next_double(&rng);
            u[1] = mf_pcg32_next_double(&rng);
            mf_vec3 wi;
            double h = 0.0;
            if (which == 0) { /* the model's sampler: kept above the horizon only (model_pdf) */
                double pdf = 0.0;
                wi = mf_model_sample(m, &prm, wo, u, &pdf);
                if (pdf > 0.0 && mf_vec3_isfinite(wi) && wi.z > 0.0) {
                    double d = mf_ltc_eval(ltc, wi), fc = m->eval_cos(m, &prm, wo, wi);
                    h = fabs(magnitude * d - fc) / (0.5 * model_pdf(m, alpha, wo, wi) + 0.5 * d);
                }
            } else { /* the LTC's sampler: its density is D itself (mf_ltc_pdf) */
                wi = mf_ltc_sample(ltc, u);
                double d = mf_ltc_eval(ltc, wi);
                if (mf_vec3_isfinite(wi) && d > 0.0) {
                    double fc = wi.z > 0.0 ? m->eval_cos(m, &prm, wo, wi) : 0.0;
                    h = fabs(magnitude * d - fc) / (0.5 * model_pdf(m, alpha, wo, wi) + 0.5 * d);
                }
            }
            if (!isfinite(h))
                return MF_ERR_DOMAIN;
            s1[which] += h;
            s2[which] += h * h;
        }
    double mean = 0.0, var = 0.0;
    for (int which = 0; which < 2; ++which) {
        double mu = s1[which] / half, v = s2[which] / half - mu * mu;
        mean += 0.5 * mu;
        var += 0.25 * (v > 0.0 ? v : 0.0) / (half - 1);
    }
    out->val = mean / albedo;
    out->err = sqrt(var) / albedo;
    return MF_OK;
}

/* Per-texel polygon errors of one table against the shared Monte Carlo values. */
typedef struct poly_err {
    double mean_abs, worst_abs, mean_rel;
} poly_err;

static void polygon_errors(const mf_ltc *ltc, int ok, double magnitude, double albedo, const mf_polygon *p, int n,
                           const double *mc, double *eabs, poly_err *out)
{
    out->mean_abs = out->worst_abs = out->mean_rel = 0.0;
    for (int i = 0; i < n; ++i) {
        double l = ok ? magnitude * mf_ltc_integrate_polygon(ltc, &p[i], MF_POLYGON_ONE_SIDED) : NAN;
        double d = fabs(l - mc[i]);
        if (!isfinite(d))
            d = INFINITY;
        double den = mc[i] > REL_FLOOR * albedo ? mc[i] : REL_FLOOR * albedo;
        eabs[i] = d;
        out->mean_abs += d / n;
        out->mean_rel += d / den / n;
        if (!(d <= out->worst_abs))
            out->worst_abs = d;
    }
}

/* Tested indices of an axis of n texels: 0, K, 2K, ... and n - 1.  Returns their count. */
static int tested_indices(int n, int stride, int *idx)
{
    int c = 0;
    for (int i = 0; i < n; i += stride)
        idx[c++] = i;
    if (idx[c - 1] != n - 1)
        idx[c++] = n - 1;
    return c;
}

int main(int argc, char **argv)
{
    mf_image_set_backend(mf_image_oiio_backend()); /* EXR files */
    int npoly = 32, nsamples = 65536, stride = 1;
    unsigned long long seed = 1;
    const char *brdf = NULL, *out_path = "notebooks_data/ltc_texels.csv";
    const char *paths[2] = {NULL, NULL};
    int npaths = 0;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        char *end = NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(a, "--brdf") && v) {
            brdf = v, ++i;
        } else if (!strcmp(a, "--out") && v) {
            out_path = v, ++i;
        } else if ((!strcmp(a, "--polygons") || !strcmp(a, "--samples") || !strcmp(a, "--stride") ||
                    !strcmp(a, "--seed")) && v) {
            errno = 0;
            unsigned long long x = strtoull(v, &end, 10);
            if (errno || end == v || *end || v[0] == '-' || (strcmp(a, "--seed") && x > 100000000ULL)) {
                fprintf(stderr, PROG ": %s: bad value '%s'\n", a, v);
                return 2;
            }
            if (!strcmp(a, "--polygons"))
                npoly = (int)x;
            else if (!strcmp(a, "--samples"))
                nsamples = (int)x;
            else if (!strcmp(a, "--stride"))
                stride = (int)x;
            else
                seed = x;
            ++i;
        } else if (a[0] == '-' && a[1]) {
            fprintf(stderr, PROG ": unknown option or missing value: %s\n", a);
            usage(stderr);
            return 2;
        } else if (npaths < 2) {
            paths[npaths++] = a;
        } else {
            fprintf(stderr, PROG ": at most two tables (TABLE [SECOND_TABLE]), got '%s' too\n", a);
            return 2;
        }
    }
    if (!npaths) {
        usage(stderr);
        return 2;
    }
    if (npoly < 1 || npoly > MAX_POLYGONS || nsamples < 4 || stride < 1) {
        fprintf(stderr, PROG ": need --polygons in 1..%d, --samples >= 4, --stride >= 1\n", MAX_POLYGONS);
        return 2;
    }

    mf_table tab[2];
    int field[2][5];
    int rc = load_table(paths[0], &tab[0], field[0]);
    if (rc)
        return rc;
    if (npaths == 2) {
        rc = load_table(paths[1], &tab[1], field[1]);
        if (rc) {
            mf_table_free(&tab[0]);
            return rc;
        }
        if (tab[1].axes[0].size != tab[0].axes[0].size || tab[1].axes[1].size != tab[0].axes[1].size) {
            fprintf(stderr, PROG ": %s: %d x %d texels, but %s has %d x %d: the tables must have the same size\n",
                    paths[1], tab[1].axes[0].size, tab[1].axes[1].size, paths[0], tab[0].axes[0].size,
                    tab[0].axes[1].size);
            mf_table_free(&tab[0]);
            mf_table_free(&tab[1]);
            return 2;
        }
    }
    const char *name = brdf ? brdf : mf_table_get_meta(&tab[0], "brdf");
    if (!name)
        name = "ggx";
    const mf_brdf_model *model = mf_brdf_model_find(name);
    if (!model) {
        fprintf(stderr, PROG ": unknown BRDF '%s' (see 'mfkit fit ltc --help' for the names)\n", name);
        for (int k = 0; k < npaths; ++k)
            mf_table_free(&tab[k]);
        return 2;
    }
    if (npaths == 2) {
        const char *b2 = mf_table_get_meta(&tab[1], "brdf");
        if (b2 && strcmp(b2, model->name))
            fprintf(stderr, PROG ": warning: %s was fitted to '%s', measured against '%s'\n", paths[1], b2,
                    model->name);
        /* The truth is computed at the FIRST table's alpha and theta; say where the second's differ
         * (the reference clamps alpha >= 1e-5, mfkit >= 1e-4: the r = 0 column). */
        for (int ax = 0; ax < 2; ++ax)
            for (int i = 0; i < tab[0].axes[ax].size; ++i) {
                double x0 = ax ? mf_ltc_table_cos_theta(&tab[0], i) : mf_ltc_table_alpha(&tab[0], i);
                double x1 = ax ? mf_ltc_table_cos_theta(&tab[1], i) : mf_ltc_table_alpha(&tab[1], i);
                if (fabs(x1 - x0) > 1e-9 * fabs(x0)) {
                    fprintf(stderr,
                            PROG ": warning: %s has %s %.6g at texel %d, %s has %.6g; both are measured at "
                                 "the first table's value\n",
                            paths[1], ax ? "cos theta" : "alpha", x1, i, paths[0], x0);
                    break;
                }
            }
    }

    /* The output goes to a temporary file beside it, renamed at the end (mf_io_atomic). */
    mf_io_atomic out;
    char msg[1024];
    if (mf_io_atomic_begin(&out, out_path, msg, sizeof msg) != MF_OK) {
        fprintf(stderr, PROG ": %s\n", msg);
        for (int k = 0; k < npaths; ++k)
            mf_table_free(&tab[k]);
        return 4;
    }
    FILE *f = out.file;
    char seed_text[32];
    snprintf(seed_text, sizeof seed_text, "%llu", seed);
    study_write_header(f, PROG, argc, argv, seed_text);
    fprintf(f, "ir,iu,r,u,alpha,theta_deg,cos_theta,magnitude,albedo_quad,albedo_quad_err,albedo_diff,albedo_rel_diff,"
               "polygons,poly_mean_abs,poly_worst_abs,poly_mean_rel,mc_mean_se,lobe_l1,lobe_l1_se");
    if (npaths == 2)
        fprintf(f, ",d_minv_00,d_minv_20,d_minv_02,d_minv_22,d_magnitude,second_poly_mean_abs,second_poly_worst_abs,"
                   "second_poly_mean_rel,d_poly_mean_abs,d_poly_mean_abs_se,d_poly_mean_rel");
    fputc('\n', f);

    const mf_table *t = &tab[0];
    int nr = t->axes[0].size, nu = t->axes[1].size;
    int *ir_idx = malloc(sizeof(int) * (size_t)(nr + nu + 2)), *iu_idx = ir_idx ? ir_idx + nr + 1 : NULL;
    mf_polygon *polys = malloc(sizeof *polys * (size_t)npoly);
    double *buf = malloc(sizeof(double) * (size_t)npoly * 4);
    int status = 0;
    if (!ir_idx || !polys || !buf) {
        fprintf(stderr, PROG ": out of memory\n");
        status = 4;
        goto done;
    }
    double *mc = buf, *se = buf + npoly, *eabs1 = buf + 2 * npoly, *eabs2 = buf + 3 * npoly;
    int mr = tested_indices(nr, stride, ir_idx), mu = tested_indices(nu, stride, iu_idx);
    int progress = isatty(fileno(stderr));
    double sum_rel = 0.0, sum_l1 = 0.0, worst_rel = 0.0, worst_alb = 0.0;
    for (int b = 0; b < mu && !status; ++b) {
        if (progress)
            fprintf(stderr, "\r" PROG ": row %d/%d (%d texels each)", b + 1, mu, mr);
        for (int a = 0; a < mr; ++a) {
            int ir = ir_idx[a], iu = iu_idx[b];
            size_t texel = (size_t)ir + (size_t)nr * (size_t)iu;
            double alpha = mf_ltc_table_alpha(t, ir), ct = mf_ltc_table_cos_theta(t, iu);
            mf_vec3 wo = mf_ltc_gate_view(ct);
            double v1[5], v2[5];
            mf_ltc ltc1, ltc2;
            int ok1 = texel_ltc(&tab[0], field[0], ir, iu, v1, &ltc1);
            int ok2 = npaths == 2 && texel_ltc(&tab[1], field[1], ir, iu, v2, &ltc2);
            mf_result q, l1 = {NAN, NAN};
            mf_ltc_gate_random_polygons(model, alpha, wo, seed, stream_of(STREAM_POLY, texel), npoly, polys);
            mf_brdf_params prm = mf_brdf_params_iso(alpha);
            if (mf_model_albedo(model, &prm, wo, QUAD_N, &q) != MF_OK ||
                mf_ltc_gate_polygon_mc(model, alpha, wo, polys, npoly, nsamples, seed, stream_of(STREAM_MC, texel), mc,
                                       se, NULL) != MF_OK ||
                (ok1 && lobe_l1(model, alpha, wo, &ltc1, v1[4], q.val, nsamples, seed, stream_of(STREAM_LOBE, texel),
                                &l1) != MF_OK)) {
                fprintf(stderr, "%s" PROG ": %s at alpha %.6g, cos theta %.6g (texel %d, %d): not finite\n",
                        progress ? "\n" : "", model->name, alpha, ct, ir, iu);
                status = 5;
                break;
            }
            poly_err e1, e2;
            polygon_errors(&ltc1, ok1, v1[4], q.val, polys, npoly, mc, eabs1, &e1);
            double mean_se = 0.0;
            for (int i = 0; i < npoly; ++i)
                mean_se += se[i] / npoly;
            double adiff = v1[4] - q.val;
            fprintf(f, "%d,%d,%.17g,%.17g,%.17g,%.17g,%.17g,%.9g,%.17g,%.3e,%.9g,%.9g,%d,%.9g,%.9g,%.9g,%.3e,%.9g,%.3e", ir,
                    iu, mf_table_axis_param(&t->axes[0], ir), mf_table_axis_param(&t->axes[1], iu), alpha,
                    acos(ct) * (180.0 / MF_PI), ct, v1[4], q.val, q.err, adiff, adiff / q.val, npoly, e1.mean_abs,
                    e1.worst_abs, e1.mean_rel, mean_se, l1.val, l1.err);
            if (npaths == 2) {
                polygon_errors(&ltc2, ok2, v2[4], q.val, polys, npoly, mc, eabs2, &e2);
                /* the paired difference and its standard error over the polygons */
                double dm = 0.0, dv = 0.0;
                for (int i = 0; i < npoly; ++i)
                    dm += (eabs2[i] - eabs1[i]) / npoly;
                for (int i = 0; i < npoly; ++i)
                    dv += (eabs2[i] - eabs1[i] - dm) * (eabs2[i] - eabs1[i] - dm);
                double dse = npoly > 1 ? sqrt(dv / (npoly - 1) / npoly) : NAN;
                fprintf(f, ",%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.3e,%.9g", v2[0] - v1[0], v2[1] - v1[1],
                        v2[2] - v1[2], v2[3] - v1[3], v2[4] - v1[4], e2.mean_abs, e2.worst_abs, e2.mean_rel,
                        e2.mean_abs - e1.mean_abs, dse, e2.mean_rel - e1.mean_rel);
            }
            fputc('\n', f);
            sum_rel += e1.mean_rel;
            sum_l1 += l1.val;
            if (!(e1.mean_rel <= worst_rel))
                worst_rel = e1.mean_rel;
            if (!(fabs(adiff / q.val) <= worst_alb))
                worst_alb = fabs(adiff / q.val);
        }
    }
    if (progress)
        fputc('\n', stderr);
    if (!status) {
        int n = mr * mu;
        printf(PROG ": %s, brdf %s, %d x %d texels tested (stride %d), %d polygons, %d samples: mean relative polygon "
               "error %.4g (worst texel %.4g), mean lobe L1 %.4g, worst |albedo error| %.3g\n",
               paths[0], model->name, mr, mu, stride, npoly, nsamples, sum_rel / n, worst_rel, sum_l1 / n, worst_alb);
    }
done:
    if (status)
        mf_io_atomic_abort(&out);
    else if (mf_io_atomic_commit(&out, msg, sizeof msg) != MF_OK) {
        fprintf(stderr, PROG ": %s\n", msg);
        status = 4;
    } else
        printf(PROG ": wrote %s\n", out_path);
    free(ir_idx);
    free(polys);
    free(buf);
    for (int k = 0; k < npaths; ++k)
        mf_table_free(&tab[k]);
    return status;
}
