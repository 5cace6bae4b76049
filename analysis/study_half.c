/*
 * study_half.c -- what exporting a table as IEEE binary16 ("half", `--half`) does to it, per texel
 * and field, and to LTC polygon shading (issue 6; docs/tables.md "Half floats and their error").
 *
 *   build-dir/analysis/study_half [--brdf NAME] [--seed S] [--polygons P] [--out FILE] TABLE...
 *
 * TABLE: an mfkit table file (.json, .exr, .dds, .npy: mf_table_read) or the reference CSV layout
 * (e.g. tests/data/reference/ltc_code_ggx_64.csv: mf_ltc_reference_read_csv), chosen by extension
 * as bench_ltc and `mfkit validate` do.  The table's values as read (doubles: the float32 of an
 * mfkit file, the 6-digit decimals of the reference CSV) are the reference.
 *
 * Rounding.  Every value x becomes h = mf_half_to_double(mf_half_from_double(x)): the half nearest
 * to x, ties to even, exactly the conversion of mfkit's half-float writers (lib/io/src/fmt_exr.c, fmt_dds.c,
 * public in mf_table_io.h).  Per texel and field: abs_err = |h - x| (inf on overflow), rel_err =
 * abs_err / |x| (nan for x = 0 or non-finite x).  In half's normal range (|x| >= 2^-14) rounding to
 * nearest gives rel_err <= 2^-11 = 4.88e-4 [IEEE 754-2008, Sec. 3.6: p = 11]; below it the spacing
 * is fixed at 2^-24, so rel_err <= 2^-25 / |x| (subnormals).  The per-table maxima are checked
 * against mf_half_error_of, the report the writers store in the file.
 *
 * Shading (LTC tables only: two axes r (alpha = r^2, clamped) and u (cos theta_o = 1 - u^2) with
 * the fields minv_00, minv_20, minv_02, minv_22, magnitude; mf_ltc_table.h).  At every texel
 * (alpha, theta_o) the same P random convex polygons (mf_ltc_gate_random_polygons with the model
 * --brdf, seed S and stream = texel index: quads and triangles, some across the horizon) are shaded
 * as a renderer does, magnitude * E_LTC(P) with E_LTC = mf_ltc_integrate_polygon (one-sided,
 * clipped after the transform) of the LTC rebuilt from the four minv fields by
 * mf_ltc_table_unpack [Heitz et al. 2016, Sec. 3-4], once from the table's doubles and once from
 * their halves:
 *   shade_abs_worst = max over the polygons of |m_h E(M_h, P) - m E(M, P)|,
 *   shade_rel_worst, shade_rel_mean = the max and the mean of the same divided by the albedo m
 *   (the texel's float64 magnitude): the shading change in units of the brightest reflection.
 * The BRDF only places the polygons (towards its lobe); it does not enter the difference.
 *
 * Columns: table, kind, i0, i1, p0, p1, theta_o_deg, field, value, half, abs_err, rel_err,
 * shade_abs_worst, shade_rel_worst, shade_rel_mean.  kind "value": one row per texel and field
 * (shade_* nan); kind "shading": one row per texel of an LTC table (field "shading", value the
 * magnitude, half its half; abs_err, rel_err nan).  p0, p1: the axis parameters of the texel (r, u
 * for LTC tables; p1 nan for a 1D table); theta_o_deg: acos(cos theta_o) for LTC tables, else nan.
 * First line: provenance header.  The CSV goes to a temporary beside it (mfkit/io/mf_io.h), then is renamed over FILE; it is
 * generated, not committed.
 * Exit status: 0; 1 (an internal inconsistency); 2 (usage: bad option, unknown BRDF, no TABLE);
 * 3 (a table cannot be read, or the CSV cannot be written).
 */
#define _POSIX_C_SOURCE 200809L
#include <mfkit/mfkit.h>
#include <mfkit/io/mf_io.h>
#include <mfkit/io/mf_ltc_reference.h>
#include <mfkit/io/mf_table_io.h>
#include <mfkit/fit/mf_image_oiio.h>

#include "study_header.h"

#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define MAX_POLYGONS 256

static void usage(FILE *f)
{
    fprintf(f,
            "usage: study_half [--brdf NAME] [--seed S] [--polygons P] [--out FILE] TABLE...\n\n"
            "Rounds every value of each TABLE (.json, .exr, .dds, .npy, or the reference LTC CSV) to an IEEE\n"
            "half as mfkit's --half export does, and records per texel and field the absolute and relative\n"
            "rounding error; for LTC tables also the change of polygon shading, |m_h E(M_h) - m E(M)| / m, over\n"
            "P random polygons per texel (mf_ltc_gate_random_polygons, default 24, seed S, default 1) placed\n"
            "with the BRDF NAME (default: the table's \"brdf\" metadata if it names a model, else ggx).\n"
            "Writes FILE (default notebooks_data/half_error.csv): provenance header, then table, kind, i0, i1,\n"
            "p0, p1, theta_o_deg, field, value, half, abs_err, rel_err, shade_abs_worst, shade_rel_worst,\n"
            "shade_rel_mean.\n"
            "exit status: 0 success, 1 internal error, 2 usage error, 3 unreadable table or unwritable output\n");
}

/* The same dispatch as bench_ltc and `mfkit validate`: the reference CSV layout or an mfkit file. */
static mf_status load(const char *path, mf_table *t, char *msg, size_t size)
{
    mf_table_format fmt = mf_table_format_from_path(path);
    if (fmt == MF_TABLE_FORMAT_CSV)
        return mf_ltc_reference_read_csv(path, t, msg, size);
    if (!mf_table_format_readable(fmt)) {
        snprintf(msg, size, "%s: not a readable table format (.exr, .dds, .json, .npy, or a reference .csv)", path);
        return MF_ERR_UNSUPPORTED;
    }
    return mf_table_read(path, t, NULL, msg, size);
}

static double half_round(double x) { return mf_half_to_double(mf_half_from_double(x)); }

/* Non-zero for the LTC layout of mf_ltc_table.h; f[0..4] get the minv and magnitude fields. */
static int ltc_fields(const mf_table *t, int f[5])
{
    if (t->naxes != 2 || t->axes[0].mapping != MF_AXIS_SQUARE || t->axes[1].mapping != MF_AXIS_ONE_MINUS_SQUARE)
        return 0;
    for (int k = 0; k < 5; ++k)
        if ((f[k] = mf_table_field(t, mf_ltc_table_fields[k])) < 0)
            return 0;
    return 1;
}

typedef struct {
    double max_abs, max_rel, max_rel_normal;
    long n, n_zero, n_subnormal, n_underflow, n_overflow;
} field_stats;

int main(int argc, char **argv)
{
    mf_image_set_backend(mf_image_oiio_backend()); /* EXR files */
    const char *brdf = NULL, *out_path = "notebooks_data/half_error.csv";
    unsigned long long seed = 1;
    int npoly = 24;
    const char **paths = calloc((size_t)argc, sizeof *paths);
    int npaths = 0;
    if (!paths)
        return 1;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            free(paths);
            return 0;
        }
        int takes_value = !strcmp(a, "--brdf") || !strcmp(a, "--seed") || !strcmp(a, "--polygons") || !strcmp(a, "--out");
        if (takes_value && !v) {
            fprintf(stderr, "study_half: %s needs a value (see --help)\n", a);
            free(paths);
            return 2;
        }
        if (!strcmp(a, "--brdf")) {
            brdf = v;
        } else if (!strcmp(a, "--out")) {
            out_path = v;
        } else if (!strcmp(a, "--seed") || !strcmp(a, "--polygons")) {
            char *end;
            errno = 0;
            unsigned long long x = strtoull(v, &end, 10);
            int is_poly = !strcmp(a, "--polygons");
            if (errno || end == v || *end || v[0] == '-' || (is_poly && (x < 1 || x > MAX_POLYGONS))) {
                fprintf(stderr, is_poly ? "study_half: --polygons: '%s' is not an integer in [1, 256]\n"
                                        : "study_half: --seed: '%s' is not a non-negative integer\n",
                        v);
                free(paths);
                return 2;
            }
            if (is_poly)
                npoly = (int)x;
            else
                seed = x;
        } else if (a[0] == '-' && a[1] != '\0') {
            fprintf(stderr, "study_half: unknown option '%s' (see --help)\n", a);
            free(paths);
            return 2;
        } else {
            paths[npaths++] = a;
            continue;
        }
        ++i;
    }
    if (!npaths) {
        fprintf(stderr, "study_half: no TABLE given (see --help)\n");
        free(paths);
        return 2;
    }
    if (brdf && !mf_brdf_model_find(brdf)) {
        fprintf(stderr, "study_half: unknown BRDF '%s' (see 'mfkit fit ltc --help' for the names)\n", brdf);
        free(paths);
        return 2;
    }

    /* the one atomic write (mfkit/io/mf_io.h): a temporary beside the file, renamed at the end */
    mf_io_atomic out;
    char io_msg[1024];
    if (mf_io_atomic_begin(&out, out_path, io_msg, sizeof io_msg) != MF_OK) {
        fprintf(stderr, "study_half: %s\n", io_msg);
        free(paths);
        return 3;
    }
    FILE *f = out.file;
    char seed_text[32];
    snprintf(seed_text, sizeof seed_text, "%llu", seed);
    study_write_header(f, "study_half", argc, argv, seed_text);
    fprintf(f, "table,kind,i0,i1,p0,p1,theta_o_deg,field,value,half,abs_err,rel_err,shade_abs_worst,shade_rel_worst,"
               "shade_rel_mean\n");

    int status = 0;
    mf_polygon polys[MAX_POLYGONS];
    for (int ti = 0; ti < npaths && !status; ++ti) {
        const char *path = paths[ti];
        mf_table t;
        char msg[1024] = "";
        mf_status st = load(path, &t, msg, sizeof msg);
        if (st != MF_OK) {
            fprintf(stderr, "study_half: %s\n", msg[0] ? msg : mf_status_str(st));
            status = 3;
            break;
        }
        if (t.naxes > 2) {
            fprintf(stderr, "study_half: %s: %d axes; the study handles 1 or 2\n", path, t.naxes);
            mf_table_free(&t);
            status = 3;
            break;
        }
        /* the table name in the CSV: quotes and commas would break the simple CSV */
        if (strpbrk(path, "\",\n")) {
            fprintf(stderr, "study_half: %s: the path contains a quote, comma or newline\n", path);
            mf_table_free(&t);
            status = 2;
            break;
        }
        int lf[5];
        int is_ltc = ltc_fields(&t, lf);
        const mf_brdf_model *model = NULL;
        if (is_ltc) {
            const char *name = brdf ? brdf : mf_table_get_meta(&t, "brdf");
            model = name ? mf_brdf_model_find(name) : NULL;
            if (!model)
                model = mf_brdf_model_find("ggx");
        }
        int n0 = t.axes[0].size, n1 = t.naxes > 1 ? t.axes[1].size : 1;
        int nf = t.nfields;
        field_stats *fs = calloc((size_t)nf, sizeof *fs);
        if (!fs) {
            mf_table_free(&t);
            status = 1;
            break;
        }
        for (int k = 0; k < nf; ++k)
            fs[k].max_abs = fs[k].max_rel = fs[k].max_rel_normal = 0.0;
        double sh_worst = 0.0, sh_sum = 0.0, sh_abs_worst = 0.0;
        long sh_n = 0, sh_bad = 0;
        int sh_at[2] = {-1, -1};
        double tab_max_abs = 0.0, tab_max_rel = 0.0;
        for (int i1 = 0; i1 < n1; ++i1)
            for (int i0 = 0; i0 < n0; ++i0) {
                int idx[2] = {i0, i1};
                const double *rec = mf_table_record(&t, idx);
                double p0 = mf_table_axis_param(&t.axes[0], i0);
                double p1 = t.naxes > 1 ? mf_table_axis_param(&t.axes[1], i1) : NAN;
                double th = is_ltc ? acos(fmax(-1.0, fmin(1.0, mf_ltc_table_cos_theta(&t, i1)))) * (180.0 / MF_PI) : NAN;
                for (int k = 0; k < nf; ++k) {
                    double x = rec[k], h = half_round(x);
                    double ae = isfinite(x) ? fabs(h - x) : NAN;
                    double re = (isfinite(x) && x != 0.0) ? ae / fabs(x) : NAN;
                    fprintf(f, "%s,value,%d,%d,%.17g,%.17g,%.10g,%s,%.17g,%.17g,%.17g,%.17g,nan,nan,nan\n", path, i0, i1, p0,
                            p1, th, t.fields[k], x, h, ae, re);
                    field_stats *s = &fs[k];
                    if (!isfinite(x))
                        continue;
                    ++s->n;
                    if (x == 0.0) {
                        ++s->n_zero;
                        continue;
                    }
                    if (isinf(h))
                        ++s->n_overflow;
                    else if (h == 0.0)
                        ++s->n_underflow;
                    else if (fabs(x) < ldexp(1.0, -14))
                        ++s->n_subnormal;
                    s->max_abs = fmax(s->max_abs, ae);
                    s->max_rel = fmax(s->max_rel, re);
                    if (fabs(x) >= ldexp(1.0, -14) && !isinf(h))
                        s->max_rel_normal = fmax(s->max_rel_normal, re);
                    tab_max_abs = fmax(tab_max_abs, ae);
                    tab_max_rel = fmax(tab_max_rel, re);
                }
                if (!is_ltc)
                    continue;
                /* shading with the table's doubles and with their halves */
                double m4[4], m4h[4];
                for (int k = 0; k < 4; ++k) {
                    m4[k] = rec[lf[k]];
                    m4h[k] = half_round(m4[k]);
                }
                double mag = rec[lf[4]], magh = half_round(mag);
                mf_ltc ltc, ltch;
                int ok = mf_ltc_table_unpack(m4, &ltc) == MF_OK && mf_ltc_table_unpack(m4h, &ltch) == MF_OK && mag > 0.0 &&
                         isfinite(mag);
                double alpha = mf_ltc_table_alpha(&t, i0), cos_theta = mf_ltc_table_cos_theta(&t, i1);
                double worst = NAN, sum = 0.0, abs_worst = NAN;
                if (ok) {
                    mf_vec3 wo = mf_ltc_gate_view(cos_theta);
                    mf_ltc_gate_random_polygons(model, alpha, wo, seed, (uint64_t)(i0 + (long)n0 * i1), npoly, polys);
                    worst = abs_worst = 0.0;
                    for (int k = 0; k < npoly; ++k) {
                        double s64 = mag * mf_ltc_integrate_polygon(&ltc, &polys[k], MF_POLYGON_ONE_SIDED);
                        double s16 = magh * mf_ltc_integrate_polygon(&ltch, &polys[k], MF_POLYGON_ONE_SIDED);
                        double d = fabs(s16 - s64);
                        if (!isfinite(d)) {
                            worst = abs_worst = NAN;
                            break;
                        }
                        abs_worst = fmax(abs_worst, d);
                        worst = fmax(worst, d / mag);
                        sum += d / mag;
                    }
                }
                double mean = isfinite(worst) ? sum / npoly : NAN;
                fprintf(f, "%s,shading,%d,%d,%.17g,%.17g,%.10g,shading,%.17g,%.17g,nan,nan,%.17g,%.17g,%.17g\n", path, i0, i1,
                        p0, p1, th, mag, magh, abs_worst, worst, mean);
                if (!isfinite(worst)) {
                    ++sh_bad;
                    continue;
                }
                ++sh_n;
                sh_sum += mean;
                sh_abs_worst = fmax(sh_abs_worst, abs_worst);
                if (worst > sh_worst) {
                    sh_worst = worst;
                    sh_at[0] = i0;
                    sh_at[1] = i1;
                }
            }
        /* the writers' own report over the whole table must give the same maxima */
        mf_half_error he;
        mf_half_error_of(t.data, mf_table_texels(&t) * (size_t)nf, &he);
        printf("%s: %d x %d texels, %d fields%s\n", path, n0, n1, nf, is_ltc ? " (LTC layout)" : "");
        printf("  all values: max abs %.3g, max rel %.3g (mf_half_error_of: %.3g, %.3g); %zu half subnormals, %zu "
               "underflows, %zu overflows\n",
               tab_max_abs, tab_max_rel, he.max_abs_error, he.max_rel_error, he.subnormal_count, he.underflow_count,
               he.overflow_count);
        if (!(he.max_abs_error == tab_max_abs && he.max_rel_error == tab_max_rel)) {
            fprintf(stderr, "study_half: %s: per-value maxima disagree with mf_half_error_of\n", path);
            status = 1;
        }
        printf("  %-12s %10s %10s %14s %9s %9s %9s\n", "field", "max abs", "max rel", "max rel normal", "zeros", "subnorm",
               "underflow");
        for (int k = 0; k < nf; ++k)
            printf("  %-12s %10.3g %10.3g %14.3g %9ld %9ld %9ld%s\n", t.fields[k], fs[k].max_abs, fs[k].max_rel,
                   fs[k].max_rel_normal, fs[k].n_zero, fs[k].n_subnormal, fs[k].n_underflow,
                   fs[k].n_overflow ? "  OVERFLOW" : "");
        if (is_ltc) {
            printf("  shading (%s, %d polygons per texel, seed %llu): |m_h E(M_h) - m E(M)| / m worst %.3g at texel (%d, %d) "
                   "(alpha %.4g, theta_o %.2f deg), mean over texels and polygons %.3g; worst absolute %.3g",
                   model->name, npoly, seed, sh_worst, sh_at[0], sh_at[1],
                   sh_at[0] >= 0 ? mf_ltc_table_alpha(&t, sh_at[0]) : NAN,
                   sh_at[1] >= 0 ? acos(mf_ltc_table_cos_theta(&t, sh_at[1])) * (180.0 / MF_PI) : NAN,
                   sh_n ? sh_sum / sh_n : NAN, sh_abs_worst);
            if (sh_bad)
                printf("; %ld texels not shaded (singular matrix or magnitude <= 0)", sh_bad);
            printf("\n");
        } else {
            printf("  not an LTC table layout (mf_ltc_table.h): no shading rows\n");
        }
        free(fs);
        mf_table_free(&t);
    }
    free(paths);
    if (status) {
        mf_io_atomic_abort(&out);
        return status;
    }
    if (mf_io_atomic_commit(&out, io_msg, sizeof io_msg) != MF_OK) {
        fprintf(stderr, "study_half: %s\n", io_msg);
        return 3;
    }
    printf("wrote %s\n", out_path);
    return 0;
}
