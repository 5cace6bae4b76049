/*
 * cli_compare.c -- `mfkit compare A B`: two tables of the same kind (mf_table_kind.h) on a common
 * grid, their per-field differences and, for LTC tables, the polygon-shading error of both against
 * one Monte Carlo reference on the same random lights, with a one-line verdict (docs/cli.md).
 *
 * The common grid: per axis the overlap of the two parameter ranges, with the larger of the two
 * texel counts; both tables are resampled onto it by their own interpolation (mf_table_lookup, the
 * multilinear lookup a shader's filtering does), which returns the stored records exactly at texel
 * centres, so a table of the common grid's size is not changed by the resampling.
 *
 * The shading error (ltc_isotropic only) reuses the LTC gate's machinery (mf_ltc_gate.h): at
 * N x N texels of the common grid, the gate's random polygons (mf_ltc_gate_random_polygons: quads
 * and triangles, a third across the horizon) and its Monte Carlo integrals of f cos over them
 * (mf_ltc_gate_polygon_mc, the model's sampler), both from the seed; each table's value is
 * magnitude * mf_ltc_integrate_polygon of its (resampled) record, as a renderer shades.  A and B
 * meet the same lights and the same Monte Carlo values, so their errors are paired.
 *
 * Exit status 0 when the comparison ran (whatever it found), 2 usage or mismatched tables, 3 I/O.
 */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"
#include "cli_opt.h"
#include "cli_plot.h"
#include "cli_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mfkit/mfkit.h"
#include "mfkit/io/mf_table_io.h"

static const char *const k_cmd = "compare";

enum { C_OUT, C_BRDF, C_SEED, C_TEXELS, C_LIGHTS, C_SAMPLES, C_NO_PLOTS, C_NOPTS };
static const cli_opt k_compare_opts[C_NOPTS] = {
    {.name = "--out", .metavar = "DIR", .kind = CLI_OPT_STRING,
     .help = "write the difference maps (compare_diff.csv, compare_diff.npy + .npy.json), the per-texel shading "
             "errors (compare_shading.csv, LTC tables), the report (compare.txt) and PNG heat maps there"},
    {.name = "--brdf", .metavar = "NAME", .kind = CLI_OPT_STRING,
     .help = "LTC tables: the BRDF both approximate (default: the tables' \"brdf\" metadata; the list: mfkit fit ltc "
             "--list)"},
    {.name = "--seed", .metavar = "S", .kind = CLI_OPT_U64, .def = "1",
     .help = "seed of the random lights and of the Monte Carlo reference"},
    {.name = "--texels", .metavar = "N", .kind = CLI_OPT_INT, .lo = 2, .hi = 256, .def = "16",
     .help = "LTC tables: shade at N x N texels of the common grid, spread evenly (corners included)"},
    {.name = "--lights", .metavar = "N", .kind = CLI_OPT_INT, .lo = 2, .hi = 1024, .multiple = 2, .def = "24",
     .help = "LTC tables: random polygon lights per texel (half quads, half triangles)"},
    {.name = "--samples", .metavar = "N", .kind = CLI_OPT_INT, .lo = 256, .hi = 1 << 24, .pow2 = 1, .def = "65536",
     .help = "LTC tables: Monte Carlo samples per texel (a power of two)"},
    {.name = "--no-plots", .kind = CLI_OPT_FLAG,
     .help = "with --out: no PNG (no python3 needed); the CSV, NPY and text files only"},
};
static const cli_command k_compare_cmd = {
    .name = "compare",
    .synopsis = "A B",
    .min_pos = 2,
    .max_pos = 2,
    .description =
        "Compares two tables of the same kind (mfkit table info shows a table's kind).  A and B are any\n"
        "tables 'mfkit validate' reads: .exr .dds .json .npy .ktx2, the three.js module <p>_three.js, the\n"
        "reference ltc_code .csv, or the two textures of an LTC table joined by '+' (P_1.dds+P_2.dds).\n"
        "Tables of different sizes are resampled onto a common grid (per axis: the overlap of the ranges,\n"
        "the larger texel count) by their own multilinear interpolation.  Prints each common field's\n"
        "difference B - A (largest and mean |B - A|, and where), and for LTC tables the polygon-shading error\n"
        "|LTC - MC| of both against one Monte Carlo reference on the same random lights (the LTC gate's\n"
        "polygons and sampler, fixed seed), then a one-line verdict:\n"
        "  identical                           every common field equal on the common grid\n"
        "  B is 0.52x A's mean shading error   (LTC) with both errors and the test sizes\n"
        "  B and A shade equally well          (LTC) the paired difference is within 3 standard errors\n"
        "  A and B differ: largest |B - A| ... (other kinds)\n",
    .opts = k_compare_opts,
    .nopts = C_NOPTS,
    .epilog = "exit status: 0 compared, 2 usage error or tables that cannot be compared, 3 I/O or format error\n",
};

/* ---- the common grid ---------------------------------------------------------------------------- */

/* Builds the common grid g (axes only, fields = the common fields, in A's order) of a and b. */
static int common_grid(const mf_table *a, const mf_table *b, const char *na, const char *nb, mf_table *g,
                       int *fa, int *fb)
{
    if (a->naxes != b->naxes)
        return cli_error(k_cmd, "%s has %d axes, %s has %d: cannot compare", na, a->naxes, nb, b->naxes);
    mf_table_axis ax[MF_TABLE_MAX_AXES];
    for (int k = 0; k < a->naxes; ++k) {
        const mf_table_axis *x = &a->axes[k], *y = &b->axes[k];
        if (x->mapping != y->mapping)
            return cli_error(k_cmd, "axis %d: %s maps it by %s, %s by %s: cannot compare", k, na,
                             mf_axis_mapping_name(x->mapping), nb, mf_axis_mapping_name(y->mapping));
        ax[k] = *x;
        double xlo = fmin(x->lo, x->hi), xhi = fmax(x->lo, x->hi), ylo = fmin(y->lo, y->hi), yhi = fmax(y->lo, y->hi);
        ax[k].lo = fmax(xlo, ylo);
        ax[k].hi = fmin(xhi, yhi);
        ax[k].size = x->size > y->size ? x->size : y->size;
        if (!(ax[k].lo < ax[k].hi) && ax[k].size > 1)
            return cli_error(k_cmd, "axis %d (%s): the ranges [%g, %g] of %s and [%g, %g] of %s do not overlap", k,
                             x->name, xlo, xhi, na, ylo, yhi, nb);
        if (y->physical_min > ax[k].physical_min)
            ax[k].physical_min = y->physical_min;
    }
    const char *names[MF_TABLE_MAX_FIELDS];
    int n = 0;
    for (int f = 0; f < a->nfields; ++f) {
        int j = mf_table_field(b, a->fields[f]);
        if (j < 0)
            continue;
        names[n] = a->fields[f];
        fa[n] = f;
        fb[n] = j;
        ++n;
    }
    if (n == 0)
        return cli_error(k_cmd, "%s and %s have no field in common", na, nb);
    if (mf_table_create(g, a->naxes, ax, n, names) != MF_OK)
        return cli_error(k_cmd, "out of memory (common grid)"), CLI_EXIT_IO;
    return 0;
}

/* r: the table t resampled onto the grid g (fields fidx of t). */
static int resample(const mf_table *t, const int *fidx, const mf_table *g, mf_table *r)
{
    if (mf_table_copy(r, g) != MF_OK)
        return -1;
    double *rec = malloc(sizeof *rec * (size_t)t->nfields);
    if (!rec) {
        mf_table_free(r);
        return -1;
    }
    size_t n = mf_table_texels(g);
    int idx[MF_TABLE_MAX_AXES] = {0};
    for (size_t i = 0; i < n; ++i) {
        double p[MF_TABLE_MAX_AXES];
        for (int k = 0; k < g->naxes; ++k)
            p[k] = mf_table_axis_param(&g->axes[k], idx[k]);
        if (mf_table_lookup(t, p, rec) != MF_OK)
            for (int f = 0; f < t->nfields; ++f)
                rec[f] = NAN;
        for (int f = 0; f < g->nfields; ++f)
            r->data[i * (size_t)g->nfields + (size_t)f] = rec[fidx[f]];
        for (int k = 0; k < g->naxes; ++k) {
            if (++idx[k] < g->axes[k].size)
                break;
            idx[k] = 0;
        }
    }
    free(rec);
    return 0;
}

/* "r = 0.5, u = 0.25" of texel i of g. */
static void where_texel(char *buf, size_t size, const mf_table *g, size_t i)
{
    size_t off = 0;
    buf[0] = '\0';
    for (int k = 0; k < g->naxes && off < size; ++k) {
        int ik = (int)(i % (size_t)g->axes[k].size);
        i /= (size_t)g->axes[k].size;
        double p = mf_table_axis_param(&g->axes[k], ik);
        int w = snprintf(buf + off, size - off, "%s%s = %.4g", k ? ", " : "", g->axes[k].name, p);
        if (w < 0)
            break;
        off += (size_t)w;
    }
}

typedef struct {
    double max_abs, mean_abs;
    size_t at;
    size_t differ; /* texels where the values differ (NaN vs NaN counts as equal) */
} field_diff;

/* ---- the shading comparison (ltc_isotropic) ---------------------------------------------------- */

typedef struct {
    int nt;                  /* texels per axis tested */
    int npoly, nsamples;
    long n;                  /* lights in all */
    double mean[2], p95[2], worst[2];
    double mean_se;          /* mean Monte Carlo standard error */
    double dmean, dse;       /* paired difference |e_B| - |e_A|: mean and its standard error */
    /* per tested texel: ir, iu, mean |e_A|, mean |e_B|, mean se, MC albedo */
    int *ir, *iu;
    double *ta, *tb, *tse, *talb;
} shade_stats;

static void shade_free(shade_stats *s)
{
    free(s->ir);
    free(s->ta);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Texel k of n spread evenly over an axis of size texels (first and last included). */
static int spread(int k, int n, int size)
{
    if (n >= size)
        return k < size ? k : size - 1;
    return (int)floor((double)k * (double)(size - 1) / (double)(n - 1) + 0.5);
}

/* The LTC (and magnitude) of texel i of a resampled LTC table; 0 if it cannot be unpacked. */
static int texel_ltc(const mf_table *t, size_t i, mf_ltc *ltc, double *mag)
{
    int f[5];
    for (int k = 0; k <= MF_LTC_F_MAGNITUDE; ++k)
        f[k] = mf_table_field(t, mf_ltc_table_fields[k]);
    const double *r = t->data + i * (size_t)t->nfields;
    double m4[4] = {r[f[0]], r[f[1]], r[f[2]], r[f[3]]};
    *mag = r[f[4]];
    for (int k = 0; k < 4; ++k)
        if (!isfinite(m4[k]))
            return 0;
    return isfinite(*mag) && mf_ltc_table_unpack(m4, ltc) == MF_OK;
}

static int shade(const mf_table *ra, const mf_table *rb, const mf_brdf_model *model, uint64_t seed, int nt,
                 int npoly, int nsamples, shade_stats *s)
{
    int nr = ra->axes[0].size, nu = ra->axes[1].size;
    int tr = nt < nr ? nt : nr, tu = nt < nu ? nt : nu;
    memset(s, 0, sizeof *s);
    s->nt = nt;
    s->npoly = npoly;
    s->nsamples = nsamples;
    long ntex = (long)tr * tu, maxl = ntex * npoly;
    s->ir = malloc(sizeof *s->ir * (size_t)ntex * 2);
    s->ta = malloc(sizeof *s->ta * (size_t)ntex * 4);
    mf_polygon *poly = malloc(sizeof *poly * (size_t)npoly);
    double *mc = malloc(sizeof *mc * (size_t)npoly * 2);
    double *e[2] = {malloc(sizeof(double) * (size_t)maxl), malloc(sizeof(double) * (size_t)maxl)};
    if (!s->ir || !s->ta || !poly || !mc || !e[0] || !e[1]) {
        free(poly), free(mc), free(e[0]), free(e[1]);
        shade_free(s);
        return cli_error(k_cmd, "out of memory (shading)"), CLI_EXIT_IO;
    }
    s->iu = s->ir + ntex;
    s->tb = s->ta + ntex;
    s->tse = s->tb + ntex;
    s->talb = s->tse + ntex;
    double *se = mc + npoly, sum_se = 0.0, sd = 0.0, sd2 = 0.0;
    long n = 0, k = 0;
    for (int b = 0; b < tu; ++b)
        for (int a = 0; a < tr; ++a, ++k) {
            int ir = spread(a, tr, nr), iu = spread(b, tu, nu);
            size_t texel = (size_t)ir + (size_t)nr * (size_t)iu;
            double alpha = mf_ltc_table_alpha(ra, ir), ct = mf_ltc_table_cos_theta(ra, iu);
            mf_vec3 wo = mf_ltc_gate_view(ct);
            /* the gate's streams: purpose 2 polygons, 3 Monte Carlo, keyed by the texel */
            mf_ltc_gate_random_polygons(model, alpha, wo, seed, ((uint64_t)texel << 4) | 2u, npoly, poly);
            mf_result alb = {0, 0};
            s->ir[k] = ir;
            s->iu[k] = iu;
            if (mf_ltc_gate_polygon_mc(model, alpha, wo, poly, npoly, nsamples, seed, ((uint64_t)texel << 4) | 3u, mc,
                                       se, &alb) != MF_OK) {
                free(poly), free(mc), free(e[0]), free(e[1]);
                shade_free(s);
                return cli_error(k_cmd, "the BRDF %s gives a non-finite Monte Carlo weight at alpha %g, cos theta %g",
                                 model->name, alpha, ct);
            }
            mf_ltc ltc[2];
            double mag[2];
            int ok[2] = {texel_ltc(ra, texel, &ltc[0], &mag[0]), texel_ltc(rb, texel, &ltc[1], &mag[1])};
            double tsum[2] = {0, 0}, tse = 0;
            for (int i = 0; i < npoly; ++i, ++n) {
                double d[2];
                for (int x = 0; x < 2; ++x) {
                    double v = ok[x] ? mag[x] * mf_ltc_integrate_polygon(&ltc[x], &poly[i], MF_POLYGON_ONE_SIDED) : NAN;
                    d[x] = fabs(v - mc[i]);
                    if (!isfinite(d[x]))
                        d[x] = INFINITY; /* an unusable texel counts as an infinite error */
                    e[x][n] = d[x];
                    tsum[x] += d[x];
                }
                double dd = d[1] - d[0];
                sd += dd;
                sd2 += dd * dd;
                tse += se[i];
            }
            sum_se += tse;
            s->ta[k] = tsum[0] / npoly;
            s->tb[k] = tsum[1] / npoly;
            s->tse[k] = tse / npoly;
            s->talb[k] = alb.val;
        }
    s->n = n;
    s->mean_se = sum_se / (double)n;
    for (int x = 0; x < 2; ++x) {
        double sum = 0.0;
        for (long i = 0; i < n; ++i)
            sum += e[x][i];
        s->mean[x] = sum / (double)n;
        qsort(e[x], (size_t)n, sizeof(double), cmp_double);
        s->worst[x] = e[x][n - 1];
        s->p95[x] = e[x][(long)floor(0.95 * (double)(n - 1))];
    }
    s->dmean = sd / (double)n;
    double var = sd2 / (double)n - s->dmean * s->dmean;
    s->dse = sqrt((var > 0 ? var : 0) / (double)(n > 1 ? n - 1 : 1));
    free(poly), free(mc), free(e[0]), free(e[1]);
    return 0;
}

/* ---- output files ---------------------------------------------------------------------------- */

static void csv_provenance(cli_buf *b, const char *na, const char *nb, const char *kind, const char *verdict)
{
    cli_buf_printf(b, "# command=mfkit compare, mfkit=%s\n# A: %s\n# B: %s\n# kind: %s\n# verdict: %s\n", MFKIT_VERSION,
                   na, nb, kind, verdict);
}

/* compare_diff.csv: per texel of the common grid, the indices, parameters, physical values, and
 * a_F, b_F, d_F = b_F - a_F of every common field (%.17g). */
static void diff_csv(cli_buf *b, const mf_table *ra, const mf_table *rb)
{
    const mf_table *g = ra;
    for (int k = 0; k < g->naxes; ++k)
        cli_buf_printf(b, "%si%d", k ? "," : "", k);
    for (int k = 0; k < g->naxes; ++k)
        cli_buf_printf(b, ",%s", g->axes[k].name);
    for (int k = 0; k < g->naxes; ++k)
        cli_buf_printf(b, ",phys_%s", g->axes[k].physical);
    for (int f = 0; f < g->nfields; ++f)
        cli_buf_printf(b, ",a_%s,b_%s,d_%s", g->fields[f], g->fields[f], g->fields[f]);
    cli_buf_printf(b, "\n");
    size_t n = mf_table_texels(g);
    int idx[MF_TABLE_MAX_AXES] = {0};
    for (size_t i = 0; i < n; ++i) {
        for (int k = 0; k < g->naxes; ++k)
            cli_buf_printf(b, "%s%d", k ? "," : "", idx[k]);
        for (int k = 0; k < g->naxes; ++k) {
            cli_buf_printf(b, ",");
            cli_buf_double(b, mf_table_axis_param(&g->axes[k], idx[k]));
        }
        for (int k = 0; k < g->naxes; ++k) {
            cli_buf_printf(b, ",");
            cli_buf_double(b, mf_table_axis_physical(&g->axes[k], mf_table_axis_param(&g->axes[k], idx[k])));
        }
        for (int f = 0; f < g->nfields; ++f) {
            double x = ra->data[i * (size_t)g->nfields + (size_t)f], y = rb->data[i * (size_t)g->nfields + (size_t)f];
            cli_buf_printf(b, ",");
            cli_buf_double(b, x);
            cli_buf_printf(b, ",");
            cli_buf_double(b, y);
            cli_buf_printf(b, ",");
            cli_buf_double(b, y - x);
        }
        cli_buf_printf(b, "\n");
        for (int k = 0; k < g->naxes; ++k) {
            if (++idx[k] < g->axes[k].size)
                break;
            idx[k] = 0;
        }
    }
}

static void shading_csv(cli_buf *b, const mf_table *g, const shade_stats *s)
{
    cli_buf_printf(b, "ir,iu,r,u,alpha,theta_o_deg,a_mean_abs,b_mean_abs,mc_mean_se,albedo_mc\n");
    long nt = (long)(s->n / s->npoly);
    for (long k = 0; k < nt; ++k) {
        double r = mf_table_axis_param(&g->axes[0], s->ir[k]), u = mf_table_axis_param(&g->axes[1], s->iu[k]);
        cli_buf_printf(b, "%d,%d,", s->ir[k], s->iu[k]);
        double v[8] = {r, u, mf_ltc_table_alpha(g, s->ir[k]), acos(mf_ltc_table_cos_theta(g, s->iu[k])) * 180.0 / MF_PI,
                       s->ta[k], s->tb[k], s->tse[k], s->talb[k]};
        for (int j = 0; j < 8; ++j) {
            cli_buf_double(b, v[j]);
            cli_buf_printf(b, j < 7 ? "," : "\n");
        }
    }
}

/* ---- the command --------------------------------------------------------------------------------- */

static const char *table_size(char *buf, size_t size, const mf_table *t)
{
    size_t off = 0;
    for (int k = 0; k < t->naxes && off < size; ++k) {
        int w = snprintf(buf + off, size - off, "%s%d", k ? " x " : "", t->axes[k].size);
        if (w < 0)
            break;
        off += (size_t)w;
    }
    return buf;
}

/* log2 of a power of two (for "MC 2^16"). */
static int log2i(int n)
{
    int k = 0;
    while ((1 << k) < n)
        ++k;
    return k;
}

static int run_compare(const char *na, const char *nb, mf_table *a, mf_table *b, cli_val *v)
{
    const char *out = v[C_OUT].set ? v[C_OUT].s : NULL;
    int plots = out && !v[C_NO_PLOTS].set;
    char why[256];
    const mf_table_kind *ka = mf_table_kind_of(a, why, sizeof why);
    if (!ka)
        return cli_error(k_cmd, "%s: not a table of a known kind: %s", na, why);
    const mf_table_kind *kb = mf_table_kind_of(b, why, sizeof why);
    if (!kb)
        return cli_error(k_cmd, "%s: not a table of a known kind: %s", nb, why);
    if (ka != kb)
        return cli_error(k_cmd, "%s is a table of kind %s, %s of kind %s: compare needs two tables of the same kind", na,
                         ka->name, nb, kb->name);
    int is_ltc = strcmp(ka->name, "ltc_isotropic") == 0;
    if (!is_ltc && (v[C_BRDF].set || v[C_TEXELS].set || v[C_LIGHTS].set || v[C_SAMPLES].set))
        return cli_error(k_cmd, "--brdf, --texels, --lights and --samples apply to ltc_isotropic tables, these are %s",
                         ka->name);
    /* the BRDF of the shading comparison */
    const mf_brdf_model *model = NULL;
    if (is_ltc) {
        const char *ma = mf_table_get_meta(a, "brdf"), *mb = mf_table_get_meta(b, "brdf");
        const char *name = v[C_BRDF].set ? v[C_BRDF].s : ma ? ma : mb;
        if (!v[C_BRDF].set && ma && mb && strcmp(ma, mb) != 0)
            return cli_error(k_cmd, "%s approximates %s, %s approximates %s: give --brdf NAME to compare them anyway", na,
                             ma, nb, mb);
        if (!name)
            return cli_error(k_cmd, "neither %s nor %s names its BRDF (\"brdf\" metadata): give --brdf NAME", na, nb);
        model = mf_brdf_model_find(name);
        if (!model)
            return cli_error(k_cmd, "unknown BRDF '%s' (see 'mfkit fit ltc --list' for the names)", name);
    }
    if (plots) {
        int rc = cli_plot_available(k_cmd);
        if (rc)
            return rc;
    }
    /* the common grid and both tables on it */
    mf_table g, ra, rb;
    int fa[MF_TABLE_MAX_FIELDS], fb[MF_TABLE_MAX_FIELDS];
    int rc = common_grid(a, b, na, nb, &g, fa, fb);
    if (rc)
        return rc;
    if (resample(a, fa, &g, &ra) != 0) {
        mf_table_free(&g);
        return cli_error(k_cmd, "out of memory (resampling)"), CLI_EXIT_IO;
    }
    if (resample(b, fb, &g, &rb) != 0) {
        mf_table_free(&g);
        mf_table_free(&ra);
        return cli_error(k_cmd, "out of memory (resampling)"), CLI_EXIT_IO;
    }
    /* field differences */
    size_t n = mf_table_texels(&g);
    int nf = g.nfields, identical = 1;
    field_diff fd[MF_TABLE_MAX_FIELDS];
    for (int f = 0; f < nf; ++f) {
        field_diff *d = &fd[f];
        memset(d, 0, sizeof *d);
        double sum = 0;
        for (size_t i = 0; i < n; ++i) {
            double x = ra.data[i * (size_t)nf + (size_t)f], y = rb.data[i * (size_t)nf + (size_t)f];
            if (isnan(x) && isnan(y))
                continue;
            if (x == y)
                continue;
            ++d->differ;
            double e = fabs(y - x);
            if (!(e <= d->max_abs)) { /* NaN against a number: the largest */
                d->max_abs = isnan(e) ? INFINITY : e;
                d->at = i;
            }
            sum += isnan(e) ? INFINITY : e;
        }
        d->mean_abs = sum / (double)n;
        if (d->differ)
            identical = 0;
    }
    /* shading */
    shade_stats ss;
    memset(&ss, 0, sizeof ss);
    int have_shade = 0;
    if (is_ltc) {
        rc = shade(&ra, &rb, model, v[C_SEED].set ? v[C_SEED].u : 1, (int)v[C_TEXELS].i, (int)v[C_LIGHTS].i,
                   (int)v[C_SAMPLES].i, &ss);
        if (rc) {
            mf_table_free(&g), mf_table_free(&ra), mf_table_free(&rb);
            return rc;
        }
        have_shade = 1;
    }
    /* the verdict */
    char verdict[512], sa[64], sb[64], sg[64];
    int nlit = have_shade ? (int)(ss.n / ss.npoly) : 0;
    if (identical) {
        if (have_shade)
            snprintf(verdict, sizeof verdict,
                     "identical: every common field of A and B is equal on the common grid (mean shading error %.2g "
                     "for both; %d lights x %d texels, MC 2^%d)", ss.mean[0], ss.npoly, nlit, log2i(ss.nsamples));
        else
            snprintf(verdict, sizeof verdict, "identical: every common field of A and B is equal on the common grid");
    } else if (have_shade) {
        double ratio = ss.mean[0] > 0 ? ss.mean[1] / ss.mean[0] : INFINITY;
        const char *tail = "";
        char t[320];
        snprintf(t, sizeof t, "(A %.2g, B %.2g; %d lights x %d texels, MC 2^%d)", ss.mean[0], ss.mean[1], ss.npoly,
                 nlit, log2i(ss.nsamples));
        if (fabs(ss.dmean) <= 3.0 * ss.dse)
            tail = ", within 3 standard errors of the paired difference: B and A shade equally well at this precision";
        snprintf(verdict, sizeof verdict, "B is %.2fx A's mean shading error %s%s", ratio, t, tail);
    } else {
        int w = 0;
        for (int f = 1; f < nf; ++f)
            if (fd[f].max_abs > fd[w].max_abs)
                w = f;
        char at[256];
        where_texel(at, sizeof at, &g, fd[w].at);
        snprintf(verdict, sizeof verdict, "A and B differ: largest |B - A| %.3g in field %s at %s", fd[w].max_abs,
                 g.fields[w], at);
    }
    /* the report */
    cli_buf rep = {0};
    cli_buf_printf(&rep, "A: %s (%s, %s)\nB: %s (%s, %s)\n", na, ka->name, table_size(sa, sizeof sa, a), nb, kb->name,
                   table_size(sb, sizeof sb, b));
    cli_buf_printf(&rep, "common grid: %s (", table_size(sg, sizeof sg, &g));
    for (int k = 0; k < g.naxes; ++k)
        cli_buf_printf(&rep, "%s%s in [%.6g, %.6g]", k ? ", " : "", g.axes[k].name, g.axes[k].lo, g.axes[k].hi);
    cli_buf_printf(&rep, "), %d common fields; both resampled by multilinear interpolation\n", nf);
    cli_buf_printf(&rep, "field differences B - A on the common grid:\n  %-12s %-12s %-12s %-10s %s\n", "field",
                   "max |B-A|", "mean |B-A|", "texels", "largest at");
    for (int f = 0; f < nf; ++f) {
        char at[256] = "-";
        if (fd[f].differ)
            where_texel(at, sizeof at, &g, fd[f].at);
        cli_buf_printf(&rep, "  %-12s %-12.4g %-12.4g %-10zu %s\n", g.fields[f], fd[f].max_abs, fd[f].mean_abs,
                       fd[f].differ, at);
    }
    if (have_shade) {
        cli_buf_printf(&rep,
                       "polygon shading |LTC - MC| (BRDF %s, seed %llu; %d random lights at each of %d texels, the LTC "
                       "gate's polygons; MC 2^%d samples per texel, mean standard error %.2g):\n",
                       model->name, (unsigned long long)(v[C_SEED].set ? v[C_SEED].u : 1), ss.npoly, nlit,
                       log2i(ss.nsamples), ss.mean_se);
        cli_buf_printf(&rep, "  A: mean %.4g, p95 %.4g, worst %.4g\n  B: mean %.4g, p95 %.4g, worst %.4g\n", ss.mean[0],
                       ss.p95[0], ss.worst[0], ss.mean[1], ss.p95[1], ss.worst[1]);
        cli_buf_printf(&rep, "  paired |e_B| - |e_A| per light: mean %+.3g, standard error %.2g\n", ss.dmean, ss.dse);
    } else if (!is_ltc) {
        cli_buf_printf(&rep, "shading: not measured (polygon shading is defined for ltc_isotropic tables, this is %s)\n",
                       ka->name);
    }
    cli_buf_printf(&rep, "verdict: %s\n", verdict);

    /* files */
    if (out) {
        cli_outdir od;
        rc = cli_outdir_open(k_cmd, &od, out);
        char msg[1024];
        const char *p;
        if (!rc) {
            cli_buf cb = {0};
            csv_provenance(&cb, na, nb, ka->name, verdict);
            diff_csv(&cb, &ra, &rb);
            p = cli_outdir_path(&od, "compare_diff.csv");
            if (cli_buf_write_file_atomic(&cb, p, msg, sizeof msg) != 0)
                rc = CLI_EXIT_IO, cli_error(k_cmd, "%s", msg);
            cli_buf_free(&cb);
        }
        if (!rc) {
            /* the differences as a table of fields d_F (NumPy + sidecar) */
            mf_table d;
            const char *names[MF_TABLE_MAX_FIELDS];
            char nb2[MF_TABLE_MAX_FIELDS][MF_TABLE_NAME_LEN];
            for (int f = 0; f < nf; ++f) {
                snprintf(nb2[f], sizeof nb2[f], "d_%.29s", g.fields[f]);
                names[f] = nb2[f];
            }
            if (mf_table_create(&d, g.naxes, g.axes, nf, names) != MF_OK) {
                rc = CLI_EXIT_IO, cli_error(k_cmd, "out of memory");
            } else {
                for (size_t i = 0; i < n * (size_t)nf; ++i)
                    d.data[i] = rb.data[i] - ra.data[i];
                if (mf_table_set_meta(&d, "tool", "mfkit compare") != MF_OK ||
                    mf_table_set_meta(&d, "what", "B - A per field on the common grid (compare_diff.csv names A, B)") !=
                        MF_OK)
                    rc = CLI_EXIT_IO, cli_error(k_cmd, "metadata full");
                p = cli_outdir_path(&od, "compare_diff.npy");
                cli_outdir_path(&od, "compare_diff.npy.json");
                mf_status st = rc ? MF_OK : mf_table_write(p, &d, NULL, NULL, msg, sizeof msg);
                if (st != MF_OK)
                    rc = cli_exit_code(st), cli_error(k_cmd, "%s", msg);
                mf_table_free(&d);
            }
        }
        if (!rc && have_shade) {
            cli_buf cb = {0};
            csv_provenance(&cb, na, nb, ka->name, verdict);
            shading_csv(&cb, &g, &ss);
            p = cli_outdir_path(&od, "compare_shading.csv");
            if (cli_buf_write_file_atomic(&cb, p, msg, sizeof msg) != 0)
                rc = CLI_EXIT_IO, cli_error(k_cmd, "%s", msg);
            cli_buf_free(&cb);
        }
        if (!rc) {
            p = cli_outdir_path(&od, "compare.txt");
            if (cli_buf_write_file_atomic(&rep, p, msg, sizeof msg) != 0)
                rc = CLI_EXIT_IO, cli_error(k_cmd, "%s", msg);
        }
        if (!rc && plots) {
            char dcsv[1300], scsv[1300];
            snprintf(dcsv, sizeof dcsv, "%s/compare_diff.csv", od.dir);
            snprintf(scsv, sizeof scsv, "%s/compare_shading.csv", od.dir);
            cli_outdir_path(&od, "compare_diff.png");
            if (have_shade)
                cli_outdir_path(&od, "compare_shading.png");
            const char *args[] = {"compare", dcsv, have_shade ? scsv : "-", od.dir, NULL};
            rc = cli_plot_run(k_cmd, args);
        }
        if (rc)
            cli_outdir_abort(&od);
    }
    if (!rc && cli_buf_write(&rep, stdout) != 0)
        rc = CLI_EXIT_IO, cli_error(k_cmd, "stdout: write failed");
    cli_buf_free(&rep);
    shade_free(&ss);
    mf_table_free(&g), mf_table_free(&ra), mf_table_free(&rb);
    return rc;
}

int cli_compare(int argc, char **argv)
{
    cli_val v[C_NOPTS];
    const char *pos[2];
    int npos;
    int prc = cli_opt_parse(&k_compare_cmd, argc - 1, argv + 1, ~0u, NULL, v, pos, &npos);
    if (prc == CLI_PARSE_HELP) {
        cli_opt_usage(&k_compare_cmd, stdout);
        return 0;
    }
    if (prc)
        return prc;
    if (!v[C_TEXELS].set)
        v[C_TEXELS].i = 16;
    if (!v[C_LIGHTS].set)
        v[C_LIGHTS].i = 24;
    if (!v[C_SAMPLES].set)
        v[C_SAMPLES].i = 65536;
    if (v[C_NO_PLOTS].set && !v[C_OUT].set)
        return cli_error(k_cmd, "--no-plots needs --out DIR");
    mf_table a, b;
    int rc = cli_read_any_table(k_cmd, pos[0], &a, NULL);
    if (rc)
        return rc;
    rc = cli_read_any_table(k_cmd, pos[1], &b, NULL);
    if (rc) {
        mf_table_free(&a);
        return rc;
    }
    rc = run_compare(pos[0], pos[1], &a, &b, v);
    mf_table_free(&a);
    mf_table_free(&b);
    return rc;
}
