/*
 * cli_prefilter_eval.c -- `mfkit prefilter-eval PREFILTER_DIR`: the shading error of the
 * prefiltered lobes of `mfkit prefilter` against ground truth, beside the baselines a renderer
 * would otherwise use (issue 13, "Ground truth and evaluation").
 *
 * For every evaluated footprint (level k >= 1, texel (row, col)), every tabulated view
 * (theta_i, phi_j) and every square light, all in the view-azimuth-aligned frame the prefilter
 * uses (the footprint's normals rotated by -phi about z, view wo = (sin theta, 0, cos theta);
 * docs/prefilter.md), with unit radiance on the light:
 *
 *   truth    (1/N) sum_q integral_light f(R_q^T wo, R_q^T wi) (R_q^T wi).z dwi
 *            [Nahmias 2022, Eq. 2.36], wi.z > 0, with the prefilter's below-horizon rule
 *            (mf_prefilter.h); Monte Carlo with its standard error (fixed seed): half the
 *            points uniform on the light's area, half from the footprint's mixture, combined by
 *            the balance heuristic (mf_prefilter_quad_mis_sample; before, uniform points alone,
 *            whose noise grows as the lobe narrows);
 *   truth_ltc the thesis' reference [Nahmias 2022, Sec. 4.1]: (1/N) sum_q of the per-texel LTC
 *            shading, the base GGX's isotropic LTC at the texel-frame view elevation rotated to
 *            n(q), integrated over the light in closed form (mf_prefilter_texel_ltc); the table is
 *            --ltc-table, or by default one fitted here by mfkit's isotropic fitter (mf_ltcfit.h)
 *            at the manifest's alpha over 64 view elevations;
 *   mfkit    magnitude * integral_light D_M (the stored forward M; mf_ltc_integrate_polygon);
 *   naive    the base GGX rotated to the footprint's normalised mean normal;
 *   toksvig  the same with alpha' = sqrt(alpha^2 + 2 (1 - |n_a|) / |n_a|), |n_a| the length of the
 *            mean normal [Toksvig 2005, "Mipmapping normal maps", JGT 10(3): 1/s' = 1/s + (1 - |n_a|)/|n_a|
 *            for a Blinn-Phong exponent s, with s = 2/alpha^2 - 2 read as slope variance alpha^2/2]
 *            (mf_toksvig_beckmann_alpha, applied to GGX's alpha as renderers do);
 *   leadr    mfkit's LEADR specular [Dupuy 2013, Eq. 17], Fresnel 1: Gaussian slopes with the
 *            footprint's mean and covariance of the texel slopes (-n.x/n.z, -n.y/n.z) plus the base
 *            roughness as a Beckmann slope variance alpha^2/2 per axis;
 *   naive_ltc, toksvig_ltc  naive and Toksvig as a real-time renderer shades them under a polygonal
 *            light: the isotropic LTC (the per-texel truth's table) at the normalised mean normal, at the
 *            base's alpha and at Toksvig's alpha' (clamped to 1; without --ltc-table from a second table
 *            of 16 roughness columns over [alpha, 1]): Nahmias 2022's own naive baseline [Sec. 4.1: "a
 *            naive baseline that also use[s] LTC for area light integration"].  The exact naive and
 *            Toksvig above are what those filters could give with an exact area-light integral; these are
 *            what a renderer gets.  They are reported beside the others (records: the last two columns;
 *            summary: mse_, relrms_, mse_ltc_, relrms_ltc_ of each, last) and have their own level line.
 *
 * A diffuse (Lambert) table (manifest base_brdf {"model": "lambert"}) gets its own methods:
 *   truth    (1/N) sum_q integral_light max(0, n_q.wi) / pi dwi over wi.z > 0: the diffuse mixture of
 *            mf_prefilter.c (view independent; the geometric horizon and each texel's), exact in
 *            closed form (mf_prefilter_texel_lambert: the light clipped to z >= 0, Lambert's formula);
 *   mfkit    as above;
 *   naive    the same formula at the footprint's normalised mean normal;
 *   leadr    mfkit's LEADR diffuse (mf_model_leadr_diffuse [Dupuy 2013, Eq. 21], centred isotropic
 *            Beckmann slopes) in the mean normal's frame with alpha^2 = var_x + var_y of the texel
 *            slopes; Monte Carlo over the light (leadr_se its standard error).
 *   The records: level, row, col, i_theta, theta, i_phi, phi, light_half_side, truth, truth_se (0: the
 *   truth is exact), mfkit, naive, leadr, leadr_se; the summary: mse_ and relrms_ of mfkit, naive,
 *   leadr, then mean_leadr_se.  --ltc-table is refused for such a table.
 *
 * Every method's error is reported against both truths (GGX).  Against the Monte Carlo truth the
 * summary also gives mse_unbiased_<method>: the mean over the cell's records of (est - truth)^2 -
 * dse^2, dse the standard error of est - truth (pe_rec), an unbiased estimate of the squared error
 * against the exact truth (E (x + e)^2 = x^2 + var e); it can read below 0 where a method is exact or
 * nearly (the records' se_diff_<baseline> columns give dse; mfkit's is truth_se).
 * The baselines are integrated with the same samples and weights as the truth (so their differences
 * from it carry little Monte Carlo noise); mfkit's lobe is integrated in closed form, so its error
 * against the truth includes the truth's own noise (truth_se; docs/prefilter.md, "The evaluation's
 * Monte Carlo truth").
 * The light: a square of half side h at distance 1, facing the origin, centred on the mirror
 * direction of the view, its elevation clamped to at most --light-elevation-max (default 75 deg, so
 * the lights of grazing views stay mostly above the horizon; 90: every light on the mirror
 * direction, as the gate's and the fit's ladder); what lies below the geometric horizon contributes
 * nothing.
 */
#include "cli.h"
#include "cli_opt.h"
#include "cli_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const k_cmd = "prefilter-eval";
static const char *const k_green_names[] = {"up", "down", NULL};
static const char *const k_encoding_names[] = {"auto", "unorm", "raw", NULL};

enum { E_OUT, E_LIGHTS, E_SAMPLES, E_TEXELS, E_SEED, E_MAP, E_GREEN, E_ENCODING, E_LTC_TABLE, E_LIGHT_ELEV, E_LOBES, E_NOPTS };
static const cli_opt k_opts[E_NOPTS] = {
    {.name = "--out", .metavar = "DIR", .kind = CLI_OPT_STRING, .required = 1,
     .help = "output directory (created if missing): prefilter_eval.csv (every record) and "
             "prefilter_eval_summary.csv (per level, light and elevation)"},
    {.name = "--lights", .metavar = "H,H,...", .kind = CLI_OPT_STRING, .def = "0.05,0.2,0.5",
     .help = "half sides of the square lights at distance 1 (1 to 8 values in (0, 10])"},
    {.name = "--samples", .metavar = "N", .kind = CLI_OPT_INT, .lo = 16, .hi = 1 << 24, .def = "4096",
     .help = "Monte Carlo points per record (even: half uniform on the light, half from the footprint's BRDF)"},
    {.name = "--texels", .metavar = "N", .kind = CLI_OPT_INT, .lo = 1, .hi = 1 << 24, .def = "16",
     .help = "at most N texels per level, evenly spaced in row-major order"},
    {.name = "--seed", .metavar = "S", .kind = CLI_OPT_INT, .lo = 0, .hi = 1L << 30, .def = "1",
     .help = "Monte Carlo seed"},
    {.name = "--map", .metavar = "NORMALMAP", .kind = CLI_OPT_STRING, .def = "the manifest's map",
     .help = "the normal map the prefilter was run on"},
    {.name = "--green", .kind = CLI_OPT_ENUM, .choices = k_green_names, .def = "up",
     .help = "as given to mfkit prefilter"},
    {.name = "--encoding", .kind = CLI_OPT_ENUM, .choices = k_encoding_names, .def = "auto",
     .help = "as given to mfkit prefilter"},
    {.name = "--ltc-table", .metavar = "FILE", .kind = CLI_OPT_STRING,
     .def = "a 64-elevation column fitted here at the base's alpha",
     .help = "isotropic GGX LTC table (an mfkit table file or the reference CSV layout) for the per-texel LTC "
             "truth and the baselines naive_ltc and toksvig_ltc (GGX tables only; without it, toksvig_ltc's "
             "roughnesses from a second table fitted here, 16 columns from the base's alpha to 1)"},
    {.name = "--light-elevation-max", .metavar = "DEG", .kind = CLI_OPT_DOUBLE, .dlo = 0.0, .dhi = 90.0, .lo_open = 1,
     .def = "75",
     .help = "the lights' centres follow the view's mirror direction up to this elevation from the normal (90: "
             "at every view, so the lights of grazing views sit on the horizon and partly below it)"},
    {.name = "--lobes", .metavar = "N", .kind = CLI_OPT_INT, .lo = 1, .hi = 2, .def = "1",
     .help = "2: mfkit's shading is the sum of the two-lobe tables PREFILTER_DIR/lobe_a and lobe_b (mfkit prefilter "
             "--lobes 2) instead of the one-lobe table (GGX tables only)"},
};
static const cli_command k_eval_cmd = {
    .name = "prefilter-eval",
    .synopsis = "PREFILTER_DIR",
    .min_pos = 1,
    .max_pos = 1,
    .description =
        "Shading error of the prefiltered lobes (magnitude x LTC integral over square lights) against the\n"
        "ground truth (the footprint average of the exact base-GGX integral, Monte Carlo with its standard\n"
        "error: light and BRDF samples, balance heuristic) and against the thesis' per-texel LTC shading,\n"
        "beside the baselines naive (mean normal), Toksvig (mean normal, widened roughness) and LEADR, each\n"
        "an exact integral, and naive and Toksvig as a renderer shades them under an area light (the isotropic\n"
        "LTC at the mean normal: naive_ltc, toksvig_ltc; Nahmias 2022's naive baseline).\n"
        "A diffuse (Lambert) table (mfkit prefilter's DIR/diffuse, or --base lambert) is compared with the exact\n"
        "truth (the footprint average of each texel's Lambert integral over the light, in closed form), beside\n"
        "naive (Lambert at the mean normal) and LEADR's diffuse; its files have their own columns.\n"
        "Reads PREFILTER_DIR/prefilter.json, ltc_mip<k>.npy, magnitude_mip<k>.npy and the normal map (with\n"
        "--lobes 2 also those of PREFILTER_DIR/lobe_a and lobe_b, whose summed shading is mfkit's).\n"
        "Prints two lines per level: each method's mean MSE over the level's cells (light x elevation), the\n"
        "cells where mfkit's lobes beat every baseline, and whether their level mean does; then the same\n"
        "against naive_ltc and toksvig_ltc (GGX tables; a Lambert table has the first line only).\n",
    .opts = k_opts,
    .nopts = E_NOPTS,
    .epilog = "exit status: 0 success, 2 usage or input error, 3 I/O error\n",
};

#if !defined(MFKIT_CLI_HAVE_IMAGE) || !defined(MFKIT_CLI_HAVE_SOLVER)

int cli_prefilter_eval(int argc, char **argv)
{
    return cli_opt_unavailable(&k_eval_cmd, k_cmd, "Ceres and OpenImageIO", "MFKIT_WITH_CERES/MFKIT_WITH_OIIO",
                               argc, argv);
}

#else

#include "mfkit/fit/mf_ltcfit.h"
#include "mfkit/fit/mf_prefilter.h"
#include "mfkit/fit/mf_prefilter_lookup.h"
#include "mfkit/io/mf_image.h"
#include "mfkit/io/mf_ltc_reference.h"
#include "mfkit/io/mf_table_io.h"
#include "mfkit/mf_brdf.h"
#include "mfkit/mf_ltc.h"
#include "mfkit/mf_moments.h"
#include "mfkit/mf_polygon.h"
#include "mfkit/mf_rng.h"

#include <errno.h>
#include <sys/stat.h>
#include <unistd.h>

#define PE_MAX_LIGHTS 8

/* A level's .npy (mf_prefilter_read_npy), refused when a value is not finite. */
static float *read_npy(const char *path, int rank, long *dims, char *msg, size_t msz)
{
    float *out = mf_prefilter_read_npy(path, rank, dims, msg, msz);
    if (!out)
        return NULL;
    size_t count = 1;
    for (int i = 0; i < rank; ++i)
        count *= (size_t)dims[i];
    for (size_t i = 0; i < count; ++i)
        if (!isfinite(out[i])) {
            snprintf(msg, msz, "%s: value %zu is not finite", path, i);
            free(out);
            return NULL;
        }
    return out;
}

static int parse_lights(const char *s, double *h, int *n)
{
    *n = 0;
    const char *p = s;
    for (;;) {
        char *end;
        double v = strtod(p, &end);
        if (end == p || !(v > 0.0 && v <= 10.0) || *n >= PE_MAX_LIGHTS)
            return -1;
        h[(*n)++] = v;
        if (*end == 0)
            return 0;
        if (*end != ',')
            return -1;
        p = end + 1;
    }
}

typedef struct pe_acc {
    double se2[5], sr[5], st, sse, cnt, se2l[4], stl, sll, un[4];
    double re2[2], re2l[2]; /* naive_ltc, toksvig_ltc: squared errors against the truth and truth_ltc */
} pe_acc;

enum { M_MFKIT, M_NAIVE, M_TOKSVIG, M_LEADR, M_TRUTH_SE, M_N };
static const char *const k_method[4] = {"mfkit", "naive", "toksvig", "leadr"};
static const char *const k_method_lambert[3] = {"mfkit", "naive", "leadr"}; /* a Lambert table's methods */
static const char *const k_rend[2] = {"naive_ltc", "toksvig_ltc"};           /* pe_rec.rend */

/* The level's line on stdout: per method the level mean of the cells' MSE against the truth (GGX: Monte
 * Carlo; Lambert: exact)
 * (a cell: one light and one elevation, ncell = lights x elevations, as the summary file's rows), the
 * cells where mfkit's MSE is below every baseline's, and whether its level mean is (the target,
 * docs/prefilter.md, "Evaluation"; analysis/prefilter_eval_cells.py reads the file the same way), appended
 * to buf (bsz bytes; printed once the files are written, so a failed run prints none). */
static void print_level(int lev, int lambert, const pe_acc *acc, int ncell, char *buf, size_t bsz)
{
    size_t o = strlen(buf);
    const int nm = lambert ? 3 : 4;
    const char *const *name = lambert ? k_method_lambert : k_method;
    double mean[4] = {0.0, 0.0, 0.0, 0.0};
    int won = 0;
    for (int c = 0; c < ncell; ++c) {
        int best = 1;
        for (int k = 0; k < nm; ++k) {
            double mse = acc[c].se2[k] / acc[c].cnt;
            mean[k] += mse / ncell;
            if (k > 0 && !(acc[c].se2[0] < acc[c].se2[k]))
                best = 0;
        }
        won += best;
    }
    int level_best = 1;
    o += (size_t)snprintf(buf + o, o < bsz ? bsz - o : 0, "level %d: mean MSE against the %s truth:", lev,
                          lambert ? "exact" : "Monte Carlo");
    for (int k = 0; k < nm; ++k) {
        o += (size_t)snprintf(buf + o, o < bsz ? bsz - o : 0, " %s %.3g%s", name[k], mean[k], k + 1 < nm ? "," : ";");
        if (k > 0 && !(mean[0] < mean[k]))
            level_best = 0;
    }
    o += (size_t)snprintf(buf + o, o < bsz ? bsz - o : 0,
                          " mfkit best in %d of %d cells (light x elevation), best level mean: %s\n", won, ncell,
                          level_best ? "yes" : "no");
    if (lambert)
        return;
    /* the baselines as a renderer shades them (isotropic LTC): the same reading against naive_ltc and
     * toksvig_ltc */
    double rmean[2] = {0.0, 0.0};
    won = 0;
    for (int c = 0; c < ncell; ++c) {
        int best = 1;
        for (int k = 0; k < 2; ++k) {
            rmean[k] += acc[c].re2[k] / acc[c].cnt / ncell;
            if (!(acc[c].se2[0] < acc[c].re2[k]))
                best = 0;
        }
        won += best;
    }
    snprintf(buf + o, o < bsz ? bsz - o : 0,
             "level %d: the baselines shaded with the isotropic LTC as a renderer does: naive_ltc %.3g, toksvig_ltc "
             "%.3g; mfkit best in %d of %d cells, best level mean: %s\n",
             lev, rmean[0], rmean[1], won, ncell, mean[0] < rmean[0] && mean[0] < rmean[1] ? "yes" : "no");
}

/* One record: truth (MC), truth_ltc (per-texel LTC) and the four estimates; dse[k] the standard error of
 * est[k] - truth (mfkit's: the truth's se, its lobe being exact; a baseline's: of the per-sample
 * differences, the two sharing the samples). */
typedef struct pe_rec {
    double truth, se, truth_ltc, est[4], dse[4];
    double rend[2]; /* naive_ltc, toksvig_ltc: the baselines as a renderer shades them (isotropic LTC) */
} pe_rec;

/* The per-texel LTC table and its field indices; wide: the table of toksvig_ltc (roughness from the
 * base's alpha to 1; the same table as t with --ltc-table), wfield its field indices. */
typedef struct pe_itab {
    mf_table t, wide;
    int field[5], wfield[5], own_wide;
} pe_itab;

/* A record's view wo (in the xz plane at elevation theta), its light (a square of half side hside
 * facing the origin, centred on the mirror direction at elevation <= 75 deg: centre c, edges e1, e2,
 * corners v) and the stored lobe m9 as an LTC (an error status when the matrix is singular). */
typedef struct {
    mf_vec3 wo, c, e1, e2, v[4];
    mf_polygon poly;
    mf_ltc ltc;
} pe_setup;

static mf_status record_setup(double theta, double hside, double lmax, const float *m9, pe_setup *q)
{
    q->wo = mf_vec3_make(sin(theta), 0.0, cos(theta));
    double tl = theta < lmax ? theta : lmax;
    q->c = mf_vec3_make(-sin(tl), 0.0, cos(tl)), q->e1 = mf_vec3_make(cos(tl), 0.0, sin(tl));
    q->e2 = mf_vec3_make(0.0, 1.0, 0.0);
    mf_vec3 c = q->c, e1 = q->e1, e2 = q->e2;
    for (int k = 0; k < 4; ++k) {
        double a = (k == 0 || k == 3) ? -hside : hside, b = (k < 2) ? -hside : hside;
        q->v[k] = mf_vec3_make(c.x + a * e1.x + b * e2.x, c.y + a * e1.y + b * e2.y, c.z + a * e1.z + b * e2.z);
    }
    q->poly = mf_polygon_make(4, q->v);
    mf_mat3 M;
    for (int i = 0; i < 9; ++i)
        M.m[i / 3][i % 3] = m9[i];
    return mf_ltc_init(&q->ltc, M);
}

static int eval_record(const mf_brdf_model *ggx, const pe_itab *itab, double alpha, const double *nrm, int count,
                       double theta,
                       double hside, double lmax, const float *m9, float magnitude, const float *const *two,
                       const float *two_mag, int samples, uint64_t seed, pe_rec *r, char *msg, size_t msz)
{
    pe_setup su;
    if (record_setup(theta, hside, lmax, m9, &su) != MF_OK) {
        snprintf(msg, msz, "a stored LTC matrix is singular");
        return CLI_EXIT_USAGE;
    }
    const mf_vec3 wo = su.wo, c = su.c, e1 = su.e1, e2 = su.e2, *v = su.v;
    const mf_polygon poly = su.poly;
    const mf_ltc ltc = su.ltc;
    /* mfkit: the one lobe, or with --lobes 2 the sum of the two halves' lobes */
    r->est[M_MFKIT] = two ? 0.0 : (double)magnitude * mf_ltc_integrate_polygon(&ltc, &poly, MF_POLYGON_TWO_SIDED);
    if (two) {
        for (int k = 0; k < 2; ++k) {
            pe_setup sk;
            if (record_setup(theta, hside, lmax, two[k], &sk) != MF_OK) {
                snprintf(msg, msz, "a stored LTC matrix of lobe_%c is singular", "ab"[k]);
                return CLI_EXIT_USAGE;
            }
            r->est[M_MFKIT] += (double)two_mag[k] * mf_ltc_integrate_polygon(&sk.ltc, &poly, MF_POLYGON_TWO_SIDED);
        }
    }

    /* the thesis' reference: the footprint average of the per-texel LTC shading */
    double sl = 0.0;
    for (int q = 0; q < count; ++q)
        sl += mf_prefilter_texel_ltc(&itab->t, itab->field, mf_vec3_make(nrm[3 * q], nrm[3 * q + 1], nrm[3 * q + 2]),
                                     alpha, wo, v, 4);
    r->truth_ltc = sl / count;

    /* the footprint's statistics */
    double mean[3] = {0, 0, 0}, sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
    for (int q = 0; q < count; ++q) {
        const double *n = nrm + 3 * q;
        for (int k = 0; k < 3; ++k)
            mean[k] += n[k] / count;
        double px = -n[0] / n[2], py = -n[1] / n[2];
        sx += px, sy += py, sxx += px * px, syy += py * py, sxy += px * py;
    }
    double len = sqrt(mean[0] * mean[0] + mean[1] * mean[1] + mean[2] * mean[2]);
    double nbar[3] = {mean[0] / len, mean[1] / len, mean[2] / len};
    if (len > 1.0)
        len = 1.0;
    double alpha_t = mf_toksvig_beckmann_alpha(len, alpha);
    /* the baselines as a real-time renderer shades them under a polygonal light [Nahmias 2022, Sec. 4.1:
     * "a naive baseline that also use[s] LTC for area light integration": the MIP-averaged normal shaded
     * with the standard technique of Heitz et al. 2016]: the isotropic LTC of the per-texel truth at the
     * normalised mean normal, at the base's alpha (naive_ltc) and at Toksvig's alpha', clamped to 1, the
     * table's end (toksvig_ltc; the table interpolates between its roughness columns as a renderer's) */
    mf_vec3 nb = mf_vec3_make(nbar[0], nbar[1], nbar[2]);
    r->rend[0] = mf_prefilter_texel_ltc(&itab->t, itab->field, nb, alpha, wo, v, 4);
    r->rend[1] = mf_prefilter_texel_ltc(&itab->wide, itab->wfield, nb, fmin(alpha_t, 1.0), wo, v, 4);
    mf_gaussian_slopes g;
    g.mean_x = sx / count, g.mean_y = sy / count;
    g.var_x = sxx / count - g.mean_x * g.mean_x + 0.5 * alpha * alpha;
    g.var_y = syy / count - g.mean_y * g.mean_y + 0.5 * alpha * alpha;
    g.cov_xy = sxy / count - g.mean_x * g.mean_y;
    mf_fresnel fr;
    memset(&fr, 0, sizeof fr);
    fr.type = MF_FRESNEL_NONE;

    mf_prefilter_mix truth, naive;
    if (mf_prefilter_mix_init(&truth, ggx, nrm, count) != MF_OK) {
        snprintf(msg, msz, "the footprint's normals are not valid unit normals with n.z > 0");
        return CLI_EXIT_USAGE;
    }
    if (mf_prefilter_mix_init(&naive, ggx, nbar, 1) != MF_OK) {
        mf_prefilter_mix_free(&truth);
        snprintf(msg, msz, "out of memory");
        return CLI_EXIT_IO;
    }
    mf_brdf_params p = mf_brdf_params_iso(alpha), pt = mf_brdf_params_iso(alpha_t);
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, seed, 0);
    /* the truth's samples, shared by the baselines: half uniform points of the light, half from the
     * footprint's mixture, weighted by the balance heuristic (mf_prefilter_quad_mis_sample) */
    const mf_prefilter_quad quad = {c, e1, e2, hside};
    double s[4] = {0, 0, 0, 0}, n2[2] = {0, 0}, s1[2] = {0, 0}, sq[2] = {0, 0};
    double d1[3][2] = {{0, 0}, {0, 0}, {0, 0}}, d2[3][2] = {{0, 0}, {0, 0}, {0, 0}}; /* baseline - truth terms */
    for (int i = 0; i < samples; ++i) {
        double u[2] = {mf_pcg32_next_double(&rng), mf_pcg32_next_double(&rng)}, ft;
        mf_vec3 wi;
        int k = i & 1;
        double w = mf_prefilter_quad_mis_sample(&truth, &p, wo, &quad, k, u, &wi, &ft);
        n2[k] += 1.0;
        if (!(w > 0.0))
            continue; /* off the light or below the geometric horizon: 0 for every method */
        ft *= w;
        s1[k] += ft, sq[k] += ft * ft;
        double gb[3] = {naive.model.eval_cos(&naive.model, &p, wo, wi) * w,
                        naive.model.eval_cos(&naive.model, &pt, wo, wi) * w, mf_leadr_specular(&g, fr, wo, wi) * w};
        for (int m = 0; m < 3; ++m) {
            s[m + 1] += gb[m];
            d1[m][k] += gb[m] - ft, d2[m][k] += (gb[m] - ft) * (gb[m] - ft);
        }
    }
    mf_prefilter_mix_free(&truth);
    mf_prefilter_mix_free(&naive);
    mf_prefilter_quad_mis_mean(n2, s1, sq, &r->truth, &r->se);
    r->dse[M_MFKIT] = r->se;
    for (int m = 0; m < 3; ++m) {
        double dm;
        mf_prefilter_quad_mis_mean(n2, d1[m], d2[m], &dm, &r->dse[m + 1]);
    }
    r->est[M_NAIVE] = s[1] / samples;
    r->est[M_TOKSVIG] = s[2] / samples;
    r->est[M_LEADR] = s[3] / samples;
    for (int k = 0; k < 6; ++k)
        if (!isfinite(k < 4 ? r->est[k] : r->rend[k - 4]) || !isfinite(r->truth) || !isfinite(r->truth_ltc)) {
            snprintf(msg, msz, "a non-finite shading value (%s)", k < 4 ? k_method[k] : k_rend[k - 4]);
            return CLI_EXIT_IO;
        }
    return 0;
}

/* One record of a diffuse (Lambert) table: truth (exact, mf_prefilter_texel_lambert averaged over the
 * footprint), mfkit's lobe, naive (the same formula at the normalised mean normal: Lambert at the mean
 * normal with the same geometric horizon) and LEADR's diffuse (Monte Carlo over the light; est[2] and
 * r->se its standard error).  The light is eval_record's.  est[0] mfkit, est[1] naive, est[2] leadr. */
static int eval_record_lambert(const mf_brdf_model *leadr, const double *nrm, int count, double theta, double hside,
                               double lmax, const float *m9, float magnitude, int samples, uint64_t seed, pe_rec *r,
                               char *msg, size_t msz)
{
    pe_setup su;
    if (record_setup(theta, hside, lmax, m9, &su) != MF_OK) {
        snprintf(msg, msz, "a stored LTC matrix is singular");
        return CLI_EXIT_USAGE;
    }
    const mf_vec3 wo = su.wo, c = su.c, e1 = su.e1, e2 = su.e2, *v = su.v;
    const mf_polygon poly = su.poly;
    const mf_ltc ltc = su.ltc;
    memset(r, 0, sizeof *r);
    r->est[0] = (double)magnitude * mf_ltc_integrate_polygon(&ltc, &poly, MF_POLYGON_TWO_SIDED);

    /* the truth: the footprint average of each texel's exact integral [Nahmias 2022, Eq. 2.36] */
    double st = 0.0, mean[3] = {0, 0, 0}, sx = 0, sy = 0, sxx = 0, syy = 0;
    for (int q = 0; q < count; ++q) {
        const double *n = nrm + 3 * q;
        st += mf_prefilter_texel_lambert(mf_vec3_make(n[0], n[1], n[2]), v, 4);
        for (int k = 0; k < 3; ++k)
            mean[k] += n[k] / count;
        double px = -n[0] / n[2], py = -n[1] / n[2];
        sx += px, sy += py, sxx += px * px, syy += py * py;
    }
    r->truth = st / count;
    r->se = 0.0;

    /* naive: Lambert at the normalised mean normal, the same horizons */
    double len = sqrt(mean[0] * mean[0] + mean[1] * mean[1] + mean[2] * mean[2]);
    mf_vec3 nbar = mf_vec3_make(mean[0] / len, mean[1] / len, mean[2] / len);
    r->est[1] = mf_prefilter_texel_lambert(nbar, v, 4);

    /* LEADR's diffuse [Dupuy 2013, Eq. 21] as mfkit has it (mf_model_leadr_diffuse: centred isotropic
     * Beckmann slopes) in the frame of the mean normal, with alpha^2 = var_x + var_y of the footprint's
     * slopes (the isotropic Beckmann of the same total slope variance, alpha^2 / 2 per axis; floored at
     * 1e-4, where the model is Lambert to O(alpha^2)); the view in that frame clamped as the
     * prefilter clamps it (MF_PREFILTER_COS_MIN at the same azimuth); light directions below the
     * geometric horizon count 0, as for every method */
    double mx = sx / count, my = sy / count;
    double var = (sxx / count - mx * mx) + (syy / count - my * my);
    double alpha = sqrt(var > 1e-8 ? var : 1e-8);
    mf_frame fr = mf_frame_from_normal(nbar);
    mf_vec3 wl = mf_prefilter_clamp_view(mf_frame_to_local(fr, wo));
    mf_brdf_params p = mf_brdf_params_iso(alpha);
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, seed, 0);
    double area = 4.0 * hside * hside, s1 = 0.0, s2 = 0.0;
    for (int i = 0; i < samples; ++i) {
        double a = (2.0 * mf_pcg32_next_double(&rng) - 1.0) * hside;
        double b = (2.0 * mf_pcg32_next_double(&rng) - 1.0) * hside;
        mf_vec3 x = mf_vec3_make(c.x + a * e1.x + b * e2.x, c.y + a * e1.y + b * e2.y, c.z + a * e1.z + b * e2.z);
        double r2 = x.x * x.x + x.y * x.y + x.z * x.z, rl = sqrt(r2);
        mf_vec3 wi = mf_vec3_make(x.x / rl, x.y / rl, x.z / rl);
        if (!(wi.z > 0.0))
            continue;
        double jac = area * fabs(wi.x * c.x + wi.y * c.y + wi.z * c.z) / r2;
        double f = leadr->eval_cos(leadr, &p, wl, mf_frame_to_local(fr, wi)) * jac;
        s1 += f, s2 += f * f;
    }
    r->est[2] = s1 / samples;
    double vs = (s2 / samples - r->est[2] * r->est[2]) * samples / (samples - 1.0);
    r->se = sqrt(vs > 0.0 ? vs / samples : 0.0); /* LEADR's standard error (the truth is exact) */
    for (int k = 0; k < 3; ++k)
        if (!isfinite(r->est[k]) || !isfinite(r->truth)) {
            snprintf(msg, msz, "a non-finite shading value (%s)", k == 0 ? "mfkit" : k == 1 ? "naive" : "leadr");
            return CLI_EXIT_IO;
        }
    return 0;
}

/* An isotropic GGX LTC table of n_r roughness columns r in [r_lo, r_hi] (alpha = r^2) x 64 view elevations,
 * fitted by mfkit's isotropic fitter on 2 threads (the fit does not depend on them). */
static mf_status pe_fit_table(const mf_brdf_model *ggx, int n_r, double r_lo, double r_hi, mf_table *t, char *msg,
                              size_t msz)
{
    mf_ltcfit_options o;
    mf_ltcfit_options_default(&o);
    o.n_r = n_r, o.n_u = 64, o.threads = 2;
    o.r_lo = r_lo, o.r_hi = r_hi;
    mf_ltcfit_result res;
    memset(&res, 0, sizeof res);
    mf_status st = mf_ltcfit_table(ggx, &o, t, &res, msg, msz);
    int interrupted = res.interrupted;
    mf_ltcfit_result_free(&res);
    return st == MF_OK && interrupted ? MF_ERR_INTERNAL : st;
}

/* Prefixes msg (the failed step's own message, or st's text when it left none) with "<what><name>: ". */
static void pe_table_error(char *msg, size_t msz, const char *what, const char *name, mf_status st)
{
    char m2[1200];
    snprintf(m2, sizeof m2, "%s", msg[0] ? msg : mf_status_str(st));
    snprintf(msg, msz, "%s%s: %s", what, name, m2);
}

/* The isotropic LTC table of the per-texel truth: FILE, or (path NULL) a 2 x 64 table fitted by
 * mf_ltcfit_table whose first roughness texel is the base's alpha (the lookup lands on it exactly). */
static int pe_itab_make(pe_itab *it, const char *path, const mf_brdf_model *ggx, double alpha, char *msg, size_t msz)
{
    memset(it, 0, sizeof *it);
    mf_status st;
    msg[0] = 0;
    if (path) {
        st = mf_table_format_from_path(path) == MF_TABLE_FORMAT_CSV ? mf_ltc_reference_read_csv(path, &it->t, msg, msz)
                                                                     : mf_table_read(path, &it->t, NULL, msg, msz);
    } else {
        double r = sqrt(alpha);
        st = r + 1e-3 > 1.0 ? pe_fit_table(ggx, 2, 1.0 - 1e-3, 1.0, &it->t, msg, msz)
                            : pe_fit_table(ggx, 2, r, r + 1e-3, &it->t, msg, msz);
    }
    if (st != MF_OK) {
        pe_table_error(msg, msz, "--ltc-table ", path ? path : "(fitted)", st);
        return CLI_EXIT_IO;
    }
    int ok = it->t.naxes == 2 && it->t.axes[0].mapping == MF_AXIS_SQUARE &&
             it->t.axes[1].mapping == MF_AXIS_ONE_MINUS_SQUARE && it->t.nfields <= 64;
    for (int k = 0; k < 5 && ok; ++k)
        ok = (it->field[k] = mf_table_field(&it->t, mf_ltc_table_fields[k])) >= 0;
    if (!ok) {
        snprintf(msg, msz, "--ltc-table %s: not an isotropic LTC table layout (mf_ltc_table.h)", path ? path : "");
        mf_table_free(&it->t);
        return CLI_EXIT_USAGE;
    }
    /* toksvig_ltc's table: a given table covers every roughness; the fitted column does not, so a second
     * table of 16 roughness columns from the base's alpha to 1 (r = sqrt(alpha) evenly spaced: 0.046 apart at
     * alpha 0.1, about three times a 64-column table's spacing; about 1.4 s of CPU) */
    if (path) {
        it->wide = it->t;
        memcpy(it->wfield, it->field, sizeof it->field);
        return 0;
    }
    st = pe_fit_table(ggx, 16, sqrt(alpha) < 1.0 - 1e-3 ? sqrt(alpha) : 1.0 - 1e-3, 1.0, &it->wide, msg, msz);
    for (int k = 0; k < 5 && st == MF_OK; ++k)
        if ((it->wfield[k] = mf_table_field(&it->wide, mf_ltc_table_fields[k])) < 0)
            st = MF_ERR_INTERNAL;
    if (st != MF_OK) {
        pe_table_error(msg, msz, "the toksvig_ltc table ", "(fitted)", st);
        mf_table_free(&it->t);
        mf_table_free(&it->wide);
        return CLI_EXIT_IO;
    }
    it->own_wide = 1;
    return 0;
}

static int pe_main(int argc, char **argv)
{
    cli_val v[E_NOPTS];
    const char *pos[1];
    int npos = 0;
    int prc = cli_opt_parse(&k_eval_cmd, argc - 1, argv + 1, ~0u, k_cmd, v, pos, &npos);
    if (prc == CLI_PARSE_HELP) {
        cli_opt_usage(&k_eval_cmd, stdout);
        return 0;
    }
    if (prc != CLI_PARSE_OK)
        return prc;
    const char *dir = pos[0], *out = v[E_OUT].s;
    double hs[PE_MAX_LIGHTS];
    int nlights = 0;
    if (parse_lights(v[E_LIGHTS].set ? v[E_LIGHTS].s : "0.05,0.2,0.5", hs, &nlights) != 0)
        return cli_error(k_cmd, "--lights %s: expected 1 to %d comma-separated half sides in (0, 10]", v[E_LIGHTS].s,
                         PE_MAX_LIGHTS);
    int samples = v[E_SAMPLES].set ? (int)v[E_SAMPLES].i : 4096;
    if (samples % 2)
        return cli_error(k_cmd, "--samples %d: must be even (half the points are drawn on the light, half from the "
                                "footprint's BRDF)", samples);
    long max_texels = v[E_TEXELS].set ? v[E_TEXELS].i : 16;
    uint64_t seed = v[E_SEED].set ? (uint64_t)v[E_SEED].i : 1;
    const double lmax = (v[E_LIGHT_ELEV].set ? v[E_LIGHT_ELEV].d : 75.0) * MF_PI / 180.0;

    char msg[8800], path[4200];
    size_t jl;
    snprintf(path, sizeof path, "%s/prefilter.json", dir);
    char *js = mf_prefilter_read_file(path, &jl, msg, sizeof msg);
    if (!js)
        return cli_error(k_cmd, "%s", msg), CLI_EXIT_IO;
    char mapbuf[4096];
    const char *map = v[E_MAP].set ? v[E_MAP].s : NULL;
    if (!map) {
        if (!mf_prefilter_json_string(js, "map", mapbuf, sizeof mapbuf)) {
            free(js);
            return cli_error(k_cmd, "%s: no \"map\" entry (not a manifest of mfkit prefilter?)", path);
        }
        map = mapbuf;
    }
    double alpha = 0.1;
    int lambert = strstr(js, "\"base_brdf\": {\"model\": \"lambert\"}") != NULL;
    const char *ap = strstr(js, "\"base_brdf\": {\"model\": \"ggx\", \"alpha\": ");
    if (!lambert && (!ap || sscanf(ap + strlen("\"base_brdf\": {\"model\": \"ggx\", \"alpha\": "), "%lf", &alpha) != 1 ||
                     !(alpha > 0.0 && alpha <= 1.0))) {
        free(js);
        return cli_error(k_cmd, "%s: base_brdf is neither GGX with an alpha in (0, 1] nor Lambert", path);
    }
    /* --lobes 2: the halves must be of this run (the same map, base BRDF, axes and fit settings: the
     * manifest's lines of those keys compared as text) */
    const char *const same_keys[4] = {"\"map\": ", "\"base_brdf\": ", "\"axes\": ", "\"fit\": "};
    static char own_lines[4][16384]; /* a longer line (views beyond about 256 x 256) compares its start */
    for (int k = 0; k < 4; ++k) {
        const char *at = strstr(js, same_keys[k]);
        size_t n = at ? strcspn(at, "\n") : 0;
        n = n < sizeof own_lines[k] - 1 ? n : sizeof own_lines[k] - 1;
        memcpy(own_lines[k], at ? at : "", n), own_lines[k][n] = '\0';
    }
    free(js);
    if (lambert && v[E_LTC_TABLE].set)
        return cli_error(k_cmd, "--ltc-table: only for a GGX table (%s is a Lambert table)", dir);
    int two_lobes = v[E_LOBES].set && v[E_LOBES].i == 2;
    if (two_lobes && lambert)
        return cli_error(k_cmd, "--lobes 2: two-lobe tables are specular (GGX) only (%s is a Lambert table)", dir);
    for (int k = 0; k < 2 && two_lobes; ++k) { /* the halves' manifests: written by mfkit prefilter --lobes 2 */
        char hp[4300], want[64];
        snprintf(hp, sizeof hp, "%s/lobe_%c/prefilter.json", dir, "ab"[k]);
        char *hj = mf_prefilter_read_file(hp, &jl, msg, sizeof msg);
        if (!hj)
            return cli_error(k_cmd, "--lobes 2: %s (run mfkit prefilter --lobes 2)", msg), CLI_EXIT_IO;
        snprintf(want, sizeof want, "\"two_lobes\": {\"half\": \"%c\"", "ab"[k]);
        int good = strstr(hj, want) != NULL, same = 1;
        for (int q = 0; q < 4; ++q)
            same &= own_lines[q][0] && strstr(hj, own_lines[q]) != NULL;
        free(hj);
        if (!good || !same)
            return cli_error(k_cmd, "--lobes 2: %s is not half %c of this table's two-lobe table%s", hp, "ab"[k],
                             good ? " (another map, base BRDF, views or fit settings)" : "");
    }

    /* the normal map, decoded as mfkit prefilter does */
    mf_image img;
    mf_image_info info;
    mf_status st = mf_image_read_ex(map, &img, NULL, &info, msg, sizeof msg);
    if (st != MF_OK) {
        cli_error(k_cmd, "%s", msg[0] ? msg : mf_status_str(st));
        return st == MF_ERR_UNSUPPORTED ? CLI_EXIT_USAGE : CLI_EXIT_IO;
    }
    int rc = 0;
    double *normals = NULL, *foot = NULL;
    float *lm = NULL, *mg = NULL, *tm[2] = {NULL, NULL}, *tg[2] = {NULL, NULL};
    FILE *fr = NULL, *fs = NULL;
    pe_acc *acc = NULL;
    char levtxt[8192] = ""; /* the level lines (print_level) */
    pe_itab itab;
    int have_itab = 0;
    char rpath[4200], spath[4200], rtmp[4300], stmp[4300];
    int created = 0; /* --out made here: removed again on failure (no partial output) */
    const int W = img.width, H = img.height;
    int is_int = !strncmp(info.pixel_type, "uint", 4); /* as mfkit prefilter decides */
    int enc = v[E_ENCODING].set ? (int)v[E_ENCODING].i : 0;
    int unorm = enc == 1 || (enc == 0 && is_int);
    int green_down = v[E_GREEN].set && v[E_GREEN].i == 1;
    if (img.channels != 3 && img.channels != 4) {
        rc = cli_error(k_cmd, "%s: a normal map needs 3 or 4 channels, it has %d", map, img.channels);
        goto done;
    }
    normals = malloc(sizeof(double) * 3 * (size_t)W * H);
    foot = malloc(sizeof(double) * 3 * (size_t)W * H);
    if (!normals || !foot) {
        rc = CLI_EXIT_IO, cli_error(k_cmd, "out of memory");
        goto done;
    }
    for (size_t t = 0; t < (size_t)W * H; ++t) {
        const float *px = img.pixels + t * (size_t)img.channels;
        double n[3];
        for (int c = 0; c < 3; ++c)
            n[c] = unorm ? 2.0 * (double)px[c] - 1.0 : (double)px[c];
        if (green_down)
            n[1] = -n[1];
        double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (!(len > 0.5 && len < 1.5) || !(n[2] > 0.0)) {
            rc = cli_error(k_cmd, "%s: texel (%zu, %zu): not a unit normal with n.z > 0", map, t % (size_t)W,
                           t / (size_t)W);
            goto done;
        }
        for (int c = 0; c < 3; ++c)
            normals[3 * t + c] = n[c] / len;
    }
    const mf_brdf_model *ggx = mf_brdf_model_find("ggx"), *leadr = mf_brdf_model_find("leadr-diffuse");
    if (!ggx || !leadr) {
        rc = CLI_EXIT_IO, cli_error(k_cmd, "the model registry has no %s", ggx ? "leadr-diffuse" : "ggx");
        goto done;
    }

    if (!lambert) {
        if ((rc = pe_itab_make(&itab, v[E_LTC_TABLE].set ? v[E_LTC_TABLE].s : NULL, ggx, alpha, msg, sizeof msg)) != 0) {
            cli_error(k_cmd, "%s", msg);
            goto done;
        }
        have_itab = 1;
    }

    /* the levels present */
    int nlev = 0;
    for (int k = 1; (W >> k) >= 1 || (H >> k) >= 1; ++k)
        if ((W >> (k - 1)) > 1 || (H >> (k - 1)) > 1)
            nlev = k;
    if (nlev < 1) {
        rc = cli_error(k_cmd, "%s: %d x %d has no level >= 1", map, W, H);
        goto done;
    }
    if (mkdir(out, 0777) == 0)
        created = 1;
    else if (errno != EEXIST) {
        rc = CLI_EXIT_IO, cli_error(k_cmd, "--out %s: cannot create: %s", out, strerror(errno));
        goto done;
    }
    snprintf(rpath, sizeof rpath, "%s/prefilter_eval.csv", out);
    snprintf(spath, sizeof spath, "%s/prefilter_eval_summary.csv", out);
    snprintf(rtmp, sizeof rtmp, "%s.tmp", rpath);
    snprintf(stmp, sizeof stmp, "%s.tmp", spath);
    fr = fopen(rtmp, "w");
    fs = fr ? fopen(stmp, "w") : NULL;
    if (!fr || !fs) {
        rc = CLI_EXIT_IO, cli_error(k_cmd, "%s: cannot write: %s", fr ? stmp : rtmp, strerror(errno));
        goto done;
    }
    if (lambert) {
        fprintf(fr, "level,row,col,i_theta,theta,i_phi,phi,light_half_side,truth,truth_se,mfkit,naive,leadr,leadr_se\n");
        fprintf(fs, "level,light_half_side,i_theta,theta,records,mean_truth,mean_truth_se");
        for (int k = 0; k < 3; ++k)
            fprintf(fs, ",mse_%s,relrms_%s", k_method_lambert[k], k_method_lambert[k]);
        fprintf(fs, ",mean_leadr_se\n");
    } else {
        fprintf(fr, "level,row,col,i_theta,theta,i_phi,phi,light_half_side,truth,truth_se,mfkit,naive,toksvig,leadr,"
                    "truth_ltc,se_diff_naive,se_diff_toksvig,se_diff_leadr,naive_ltc,toksvig_ltc\n");
        fprintf(fs, "level,light_half_side,i_theta,theta,records,mean_truth,mean_truth_se");
        for (int k = 0; k < 4; ++k)
            fprintf(fs, ",mse_%s,relrms_%s", k_method[k], k_method[k]);
        fprintf(fs, ",mean_truth_ltc,mse_truth_ltc");
        for (int k = 0; k < 4; ++k)
            fprintf(fs, ",mse_ltc_%s,relrms_ltc_%s", k_method[k], k_method[k]);
        for (int k = 0; k < 4; ++k)
            fprintf(fs, ",mse_unbiased_%s", k_method[k]);
        for (int k = 0; k < 2; ++k)
            fprintf(fs, ",mse_%s,relrms_%s,mse_ltc_%s,relrms_ltc_%s", k_rend[k], k_rend[k], k_rend[k], k_rend[k]);
        fprintf(fs, "\n");
    }

    for (int lev = 1; lev <= nlev && rc == 0; ++lev) {
        long d[6], dm[4];
        snprintf(path, sizeof path, "%s/ltc_mip%d.npy", dir, lev);
        lm = read_npy(path, 6, d, msg, sizeof msg);
        if (!lm) {
            rc = CLI_EXIT_IO, cli_error(k_cmd, "%s", msg);
            break;
        }
        snprintf(path, sizeof path, "%s/magnitude_mip%d.npy", dir, lev);
        mg = read_npy(path, 4, dm, msg, sizeof msg);
        if (!mg) {
            rc = CLI_EXIT_IO, cli_error(k_cmd, "%s", msg);
            break;
        }
        int fw = 1 << lev, fh = 1 << lev;
        if (fw > W)
            fw = W;
        if (fh > H)
            fh = H;
        int lw = W / fw, lh = H / fh;
        if (d[0] != lh || d[1] != lw || d[4] != 3 || d[5] != 3 || dm[0] != lh || dm[1] != lw || dm[2] != d[2] ||
            dm[3] != d[3] || d[2] < 2) {
            rc = cli_error(k_cmd, "%s/ltc_mip%d.npy: shape does not match a %d x %d map's level %d (%d x %d)", dir, lev,
                           W, H, lev, lw, lh);
            break;
        }
        for (int k = 0; k < 2 && two_lobes && rc == 0; ++k) {
            long d2[6], dm2[4];
            snprintf(path, sizeof path, "%s/lobe_%c/ltc_mip%d.npy", dir, "ab"[k], lev);
            tm[k] = read_npy(path, 6, d2, msg, sizeof msg);
            if (tm[k]) {
                snprintf(path, sizeof path, "%s/lobe_%c/magnitude_mip%d.npy", dir, "ab"[k], lev);
                tg[k] = read_npy(path, 4, dm2, msg, sizeof msg);
            }
            if (!tm[k] || !tg[k])
                rc = CLI_EXIT_IO, cli_error(k_cmd, "%s", msg);
            else if (memcmp(d, d2, sizeof d) || memcmp(dm, dm2, sizeof dm))
                rc = cli_error(k_cmd, "%s/lobe_%c: level %d's shape differs from %s's", dir, "ab"[k], lev, dir);
        }
        if (rc)
            break;
        mf_prefilter_options o;
        mf_prefilter_options_default(&o);
        o.n_theta = (int)d[2], o.n_phi = (int)d[3];
        long ntex = (long)lw * lh, step = ntex > max_texels ? ntex / max_texels : 1;
        free(acc);
        acc = calloc((size_t)nlights * o.n_theta, sizeof *acc);
        if (!acc) {
            rc = CLI_EXIT_IO, cli_error(k_cmd, "out of memory");
            break;
        }
        for (long t = 0, used = 0; t < ntex && used < max_texels && rc == 0; t += step, ++used) {
            int row = (int)(t / lw), col = (int)(t % lw), count = fw * fh;
            for (int b = 0; b < o.n_phi && rc == 0; ++b) {
                double phi = mf_prefilter_phi(&o, b), cp = cos(phi), sp = sin(phi);
                int q = 0;
                for (int y = row * fh; y < (row + 1) * fh; ++y)
                    for (int x = col * fw; x < (col + 1) * fw; ++x, ++q) {
                        const double *n = normals + 3 * ((size_t)y * W + x);
                        foot[3 * q] = cp * n[0] + sp * n[1];
                        foot[3 * q + 1] = -sp * n[0] + cp * n[1];
                        foot[3 * q + 2] = n[2];
                    }
                for (int a = 0; a < o.n_theta && rc == 0; ++a) {
                    double theta = mf_prefilter_theta(&o, a);
                    size_t idx = (((size_t)row * lw + col) * o.n_theta + a) * o.n_phi + b;
                    for (int l = 0; l < nlights; ++l) {
                        pe_rec r;
                        uint64_t rs = seed * 0x9e3779b97f4a7c15ull + ((((uint64_t)lev * 4096 + t) * 256 + a) * 256 + b) * 8 + l;
                        rc = lambert ? eval_record_lambert(leadr, foot, count, theta, hs[l], lmax, lm + 9 * idx,
                                                           mg[idx], samples, rs, &r, msg, sizeof msg)
                                     : eval_record(ggx, &itab, alpha, foot, count, theta, hs[l], lmax, lm + 9 * idx,
                                                   mg[idx], two_lobes ? (const float *const[2]){tm[0] + 9 * idx, tm[1] + 9 * idx} : NULL,
                                                   two_lobes ? (const float[2]){tg[0][idx], tg[1][idx]} : NULL,
                                                   samples, rs, &r, msg, sizeof msg);
                        if (rc) {
                            cli_error(k_cmd, "%s: level %d texel (%d, %d): %s", dir, lev, col, row, msg);
                            break;
                        }
                        pe_acc *A = &acc[l * o.n_theta + a];
                        if (lambert) { /* truth exact (truth_se 0); r.se is LEADR's standard error */
                            fprintf(fr, "%d,%d,%d,%d,%.17g,%d,%.17g,%.17g,%.17g,0,%.17g,%.17g,%.17g,%.17g\n", lev, row, col, a,
                                    theta, b, phi, hs[l], r.truth, r.est[0], r.est[1], r.est[2], r.se);
                            for (int k = 0; k < 3; ++k)
                                A->se2[k] += (r.est[k] - r.truth) * (r.est[k] - r.truth);
                            A->st += r.truth, A->sse += r.se, A->cnt += 1;
                            continue;
                        }
                        fprintf(fr,
                                "%d,%d,%d,%d,%.17g,%d,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,"
                                "%.17g,%.17g,%.17g,%.17g,%.17g\n",
                                lev, row, col, a, theta, b, phi, hs[l], r.truth, r.se, r.est[0], r.est[1], r.est[2],
                                r.est[3], r.truth_ltc, r.dse[1], r.dse[2], r.dse[3], r.rend[0], r.rend[1]);
                        for (int k = 0; k < 2; ++k) {
                            A->re2[k] += (r.rend[k] - r.truth) * (r.rend[k] - r.truth);
                            A->re2l[k] += (r.rend[k] - r.truth_ltc) * (r.rend[k] - r.truth_ltc);
                        }
                        for (int k = 0; k < 4; ++k) {
                            double e2 = (r.est[k] - r.truth) * (r.est[k] - r.truth);
                            A->se2[k] += e2, A->un[k] += e2 - r.dse[k] * r.dse[k];
                            A->se2l[k] += (r.est[k] - r.truth_ltc) * (r.est[k] - r.truth_ltc);
                        }
                        A->st += r.truth, A->sse += r.se, A->cnt += 1;
                        A->stl += r.truth_ltc, A->sll += (r.truth_ltc - r.truth) * (r.truth_ltc - r.truth);
                    }
                }
            }
        }
        for (int l = 0; l < nlights && rc == 0; ++l)
            for (int a = 0; a < o.n_theta; ++a) {
                pe_acc *A = &acc[l * o.n_theta + a];
                double mt = A->st / A->cnt;
                if (lambert) {
                    fprintf(fs, "%d,%.17g,%d,%.17g,%.0f,%.17g,0", lev, hs[l], a, mf_prefilter_theta(&o, a), A->cnt, mt);
                    for (int k = 0; k < 3; ++k) {
                        double mse = A->se2[k] / A->cnt;
                        fprintf(fs, ",%.17g,%.17g", mse, mt > 0.0 ? sqrt(mse) / mt : 0.0);
                    }
                    fprintf(fs, ",%.17g\n", A->sse / A->cnt);
                    continue;
                }
                fprintf(fs, "%d,%.17g,%d,%.17g,%.0f,%.17g,%.17g", lev, hs[l], a, mf_prefilter_theta(&o, a), A->cnt, mt,
                        A->sse / A->cnt);
                for (int k = 0; k < 4; ++k) {
                    double mse = A->se2[k] / A->cnt;
                    fprintf(fs, ",%.17g,%.17g", mse, mt > 0.0 ? sqrt(mse) / mt : 0.0);
                }
                double mtl = A->stl / A->cnt;
                fprintf(fs, ",%.17g,%.17g", mtl, A->sll / A->cnt);
                for (int k = 0; k < 4; ++k) {
                    double mse = A->se2l[k] / A->cnt;
                    fprintf(fs, ",%.17g,%.17g", mse, mtl > 0.0 ? sqrt(mse) / mtl : 0.0);
                }
                for (int k = 0; k < 4; ++k)
                    fprintf(fs, ",%.17g", A->un[k] / A->cnt);
                for (int k = 0; k < 2; ++k) {
                    double mse = A->re2[k] / A->cnt, msel = A->re2l[k] / A->cnt;
                    fprintf(fs, ",%.17g,%.17g,%.17g,%.17g", mse, mt > 0.0 ? sqrt(mse) / mt : 0.0, msel,
                            mtl > 0.0 ? sqrt(msel) / mtl : 0.0);
                }
                fprintf(fs, "\n");
            }
        if (rc == 0)
            print_level(lev, lambert, acc, nlights * o.n_theta, levtxt, sizeof levtxt);
        free(lm), lm = NULL;
        free(mg), mg = NULL;
        for (int k = 0; k < 2; ++k)
            free(tm[k]), free(tg[k]), tm[k] = tg[k] = NULL;
    }
done:
    if (fr && fclose(fr) != 0 && rc == 0)
        rc = CLI_EXIT_IO, cli_error(k_cmd, "%s: write error", rtmp);
    if (fs && fclose(fs) != 0 && rc == 0)
        rc = CLI_EXIT_IO, cli_error(k_cmd, "%s: write error", stmp);
    if (fr && fs && rc == 0) {
        if (rename(rtmp, rpath) != 0 || rename(stmp, spath) != 0)
            rc = CLI_EXIT_IO, cli_error(k_cmd, "%s: cannot commit: %s", rpath, strerror(errno));
    }
    if (rc != 0 && fr)
        remove(rtmp), remove(stmp);
    if (rc != 0 && created)
        rmdir(out);
    free(acc), free(lm), free(mg), free(normals), free(foot);
    for (int k = 0; k < 2; ++k)
        free(tm[k]), free(tg[k]);
    if (have_itab) {
        mf_table_free(&itab.t);
        if (itab.own_wide)
            mf_table_free(&itab.wide);
    }
    mf_image_free(&img);
    mf_image_info_free(&info);
    if (rc == 0)
        printf("%s%swrote %s and %s\n", two_lobes ? "mfkit: the two-lobe table (lobe_a + lobe_b)\n" : "", levtxt, rpath,
               spath);
    return rc;
}

int cli_prefilter_eval(int argc, char **argv) { return pe_main(argc, argv); }

#endif
