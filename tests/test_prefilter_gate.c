/* test_prefilter_gate.c -- the prefilter gate's continuity checks against a reference
 * (mf_prefilter_gate_run_ref): good runs pass, single corrupted lobes are caught.
 *
 * Maps (generated here, 8-bit quantised and renormalised as `mfkit prefilter` decodes a PNG):
 *   constant  a tilted constant normal (0.3, 0.2) slope;
 *   vgroove   the README demo's V-grooves (30 deg, period 4 columns; tests/data/normalmaps/make_vgroove.py);
 *   bump      a smooth height field h = 0.6 (sin(2 pi x / P) cos(2 pi y / P') ...) with several normals in
 *             every level-1 footprint (tests/data/normalmaps/make_bump.py writes the same as a PNG).
 * Corruptions of one lobe (level, texel, view drawn with a fixed seed): one matrix entry (among those
 * >= 0.05 of the largest) scaled by 1 + s, and the lobe swapped with its phi neighbour.  A corruption
 * is caught when the gate fails; the power is the fraction caught, printed per kind and per check.
 *
 * Usage: test_prefilter_gate                       (the CTest run: small maps, few views, asserted)
 *        test_prefilter_gate measure W NT NP NCORR [SCALE [MAP [lambert]]]
 *                                   (the figures of docs/prefilter_log.md, "Gate"; not asserted;
 *                                   MAP 0, 1, 2, -1 all)
 *        test_prefilter_gate dump W H NT NP NCORR [lambert]
 *                                   (every field of the gate's results, exactly, for comparing builds) */
#include "mf_test.h"
#include "mf_test_prefilter_gate.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mfkit/fit/mf_prefilter.h"
#include "mfkit/mf_ltc.h"
#include "mfkit/mf_polygon.h"

static double q8(double x) /* unorm 8-bit round trip, as the PNG decoder sees it */
{
    double v = round((x * 0.5 + 0.5) * 255.0);
    return v / 255.0 * 2.0 - 1.0;
}

static void set_normal(double *p, double sx, double sy) /* n from slopes, quantised */
{
    double l = sqrt(sx * sx + sy * sy + 1.0);
    double n[3] = {q8(-sx / l), q8(-sy / l), q8(1.0 / l)};
    double m = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int i = 0; i < 3; ++i)
        p[i] = n[i] / m;
}

/* kind 0 constant, 1 vgroove, 2 bump */
static void make_map(int kind, int w, double *n)
{
    for (int j = 0; j < w; ++j)
        for (int i = 0; i < w; ++i) {
            double *p = n + 3 * ((size_t)j * w + i);
            if (kind == 0) {
                set_normal(p, 0.3, 0.2);
            } else if (kind == 1) {
                double s = tan(30.0 * MF_PI / 180.0);
                set_normal(p, (i % 4) < 2 ? -s : s, 0.0); /* n.x = +-sin 30 deg */
            } else {
                /* h = A sin(2 pi x / 8) cos(2 pi y / 16) + B sin(2 pi (x + y) / 5.3), slopes its gradient */
                double x = i + 0.5, y = j + 0.5, A = 0.6, B = 0.25, k1 = 2 * MF_PI / 8, k2 = 2 * MF_PI / 16, k3 = 2 * MF_PI / 5.3;
                double hx = A * k1 * cos(k1 * x) * cos(k2 * y) + B * k3 * cos(k3 * (x + y));
                double hy = -A * k2 * sin(k1 * x) * sin(k2 * y) + B * k3 * cos(k3 * (x + y));
                set_normal(p, hx, hy);
            }
        }
}

static const char *k_names[3] = {"constant", "vgroove", "bump"};

typedef struct {
    int caught, caught_old, caught_cont, caught_sep, noop, total;
    double good_t, good_v, good_g;
    double min_cont; /* the smallest continuity measure of a corrupted run (max of texel, view) */
    double cont[256]; /* the corrupted runs' measures (max of texel, view), for the quantiles */
    double good_c, good_ct;         /* the good run's cross measures (every axis; texel axes alone) */
    int sep_c, sep_ct, bound_c;     /* corrupted runs above the good run's (x 1.05); above the default bound */
    int vis, vis_old, vis_c, vis_bound, vis_either; /* visible corruptions (see corrupt_runs); of them caught
                                           by the gated checks, cross above good, cross above its bound, the
                                           gated checks or cross above its bound */
    int either;                     /* all corruptions: the gated checks or cross above its bound */
    double cross[256];              /* the corrupted runs' cross measure */
    double good_x;                  /* the good run's excess (gated) */
    int bound_x, vis_x;             /* corruptions with excess above its bound (gated); of the visible ones */
    double excess[256];             /* the corrupted runs' excess */
} power;

static int dbl_cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Corrupts one lobe of a copy of the levels, runs the gate, restores. */
static void corrupt_runs(mf_prefilter_level *lv, int nl, const double *n, int w, const mf_prefilter_options *o,
                         int ncorr, double scale, power *pw_scale, power *pw_swap)
{
    uint64_t seed = 12345;
    int nt = o->n_theta, np = o->n_phi;
    for (int c = 0; c < 2 * ncorr; ++c) {
        int swap = c % 2;
        power *pw = swap ? pw_swap : pw_scale;
        int l = (int)(lcg(&seed) % (uint64_t)nl);
        mf_prefilter_level *L = &lv[l];
        size_t ne = (size_t)L->width * L->height * nt * np;
        size_t e = lcg(&seed) % ne;
        int b = (int)(e % (size_t)np);
        size_t f = e - b + (size_t)((b + 1) % np);
        float save_e[11], save_f[11];
        memcpy(save_e, L->m + 9 * e, 36), save_e[9] = L->magnitude[e], save_e[10] = L->albedo[e];
        memcpy(save_f, L->m + 9 * f, 36), save_f[9] = L->magnitude[f], save_f[10] = L->albedo[f];
        double diff = 0.0;
        if (swap) {
            if (np < 2)
                continue;
            memcpy(L->m + 9 * e, save_f, 36), L->magnitude[e] = save_f[9];
            memcpy(L->m + 9 * f, save_e, 36), L->magnitude[f] = save_e[9];
            for (int i = 0; i < 9; ++i)
                diff = fmax(diff, fabs(save_e[i] - save_f[i]));
        } else {
            float big = 0.0f;
            for (int i = 0; i < 9; ++i)
                big = fmaxf(big, fabsf(save_e[i]));
            int cand[9], nc = 0;
            for (int i = 0; i < 9; ++i)
                if (fabsf(save_e[i]) >= 0.05f * big)
                    cand[nc++] = i;
            int i = cand[lcg(&seed) % (uint64_t)nc];
            L->m[9 * e + i] = (float)(save_e[i] * (1.0 + scale));
            diff = fabs(save_e[i] * scale);
        }
        if (diff < 1e-3) {
            pw->noop++;
        } else {
            mf_prefilter_gate g;
            mf_prefilter_gate_bounds_default(&g);
            CHECK(mf_prefilter_gate_run_ref(lv, nl, n, w, w, o, &g) == MF_OK);
            pw->total++;
            pw->caught += !g.pass;
            pw->caught_old += !(g.pass_energy && g.pass_nan && g.pass_level);
            double cm = fmax(g.worst_cont_texel, g.worst_cont_view);
            pw->caught_cont += !(g.pass_cont_texel && g.pass_cont_view && g.pass_cont_grazing);
            pw->caught_sep += g.worst_cont_texel > 1.05 * pw->good_t || g.worst_cont_view > 1.05 * pw->good_v ||
                              g.worst_cont_grazing > 1.05 * pw->good_g;
            if (cm < pw->min_cont)
                pw->min_cont = cm;
            pw->sep_c += g.worst_cont_cross > 1.05 * pw->good_c;
            pw->sep_ct += g.worst_cont_cross_texel > 1.05 * pw->good_ct;
            pw->bound_c += !g.pass_cont_cross;
            pw->bound_x += !g.pass_cont_excess;
            pw->either += !(g.pass_energy && g.pass_nan && g.pass_level) || !g.pass_cont_cross;
            /* visible: the corrupted lobe(s) change the shading of a gate light by more than 0.1 of the
             * albedo (lobe_change) */
            double ch = lobe_change(L, e, save_e, o);
            if (swap)
                ch = fmax(ch, lobe_change(L, f, save_f, o));
            if (ch > 0.1) {
                pw->vis++;
                pw->vis_old += !(g.pass_energy && g.pass_nan && g.pass_level);
                pw->vis_c += g.worst_cont_cross > 1.05 * pw->good_c;
                pw->vis_bound += !g.pass_cont_cross;
                pw->vis_either += !(g.pass_energy && g.pass_nan && g.pass_level) || !g.pass_cont_cross;
                pw->vis_x += !g.pass_cont_excess;
            }
            if (pw->total <= 256)
                pw->cross[pw->total - 1] = g.worst_cont_cross, pw->excess[pw->total - 1] = g.worst_cont_excess;
            if (pw->total <= 256)
                pw->cont[pw->total - 1] = cm;
        }
        memcpy(L->m + 9 * e, save_e, 36), L->magnitude[e] = save_e[9];
        memcpy(L->m + 9 * f, save_f, 36), L->magnitude[f] = save_f[9];
    }
}

/* Fits the map, gates the good run, then the corruptions.  Returns the good gate in *good. */
static int g_lambert = 0; /* measure mode: the diffuse table */

/* Every field of a gate result, exactly (dump mode: the streamed gate must give the same as before). */
static void dump_gate(const char *tag, const mf_prefilter_gate *g)
{
    printf("%s: pass %d (%d %d %d %d %d) nan %ld energy %.17g [%s] level %.17g [%s] view %.17g [%s] texel %.17g [%s]\n", tag,
           g->pass, g->pass_energy, g->pass_nan, g->pass_level, g->pass_view, g->pass_texel, g->nan_entries,
           g->worst_energy, g->where_energy, g->worst_level, g->where_level, g->worst_view_spike, g->where_view,
           g->worst_texel_spike, g->where_texel);
    if (g->has_ref)
        printf("%s: ref gated %d (%d %d %d) texel %.17g [%s] view %.17g [%s] grazing %.17g [%s] jump %.17g %.17g "
               "error %.17g\n",
               tag, g->cont_gated, g->pass_cont_texel, g->pass_cont_view, g->pass_cont_grazing, g->worst_cont_texel,
               g->where_cont_texel, g->worst_cont_view, g->where_cont_view, g->worst_cont_grazing, g->where_cont_grazing,
               g->worst_jump_texel, g->worst_jump_view, g->worst_ref_error);
}

/* dump mode: maps 0..2 (w x h, the top h rows of the w x w map), the good run and ncorr corruptions
 * of each kind, both gate entry points, every field printed. */
static void dump_map(int kind, int w, int h, int nt, int np, int ncorr)
{
    if (h > w) {
        printf("dump: h <= w only (the top h rows of the w x w map)\n");
        return;
    }
    double *n = malloc(sizeof(double) * 3 * (size_t)w * w);
    CHECK(n != NULL);
    make_map(kind, w, n);
    mf_prefilter_options o;
    if (g_lambert)
        mf_prefilter_options_default_diffuse(&o);
    else
        mf_prefilter_options_default(&o);
    o.n_theta = nt, o.n_phi = np, o.threads = 2, o.keep_albedo = 1;
    mf_prefilter_level *lv;
    int nl;
    char msg[256], tag[128];
    CHECK(mf_prefilter_run(n, w, h, &o, &lv, &nl, msg, sizeof msg) == MF_OK);
    uint64_t seed = 777;
    for (int c = -1; c < 2 * ncorr; ++c) {
        int l = 0;
        size_t e = 0, f = 0;
        float save_e[9], save_f[9];
        if (c >= 0) {
            l = (int)(lcg(&seed) % (uint64_t)nl);
            size_t ne = (size_t)lv[l].width * lv[l].height * nt * np;
            e = lcg(&seed) % ne;
            f = e - e % (size_t)np + (e % (size_t)np + 1) % (size_t)np;
            memcpy(save_e, lv[l].m + 9 * e, 36), memcpy(save_f, lv[l].m + 9 * f, 36);
            if (c % 2)
                memcpy(lv[l].m + 9 * e, save_f, 36), memcpy(lv[l].m + 9 * f, save_e, 36);
            else
                lv[l].m[9 * e + lcg(&seed) % 9] *= 1.5f;
        }
        mf_prefilter_gate g;
        mf_prefilter_gate_bounds_default(&g);
        CHECK(mf_prefilter_gate_run(lv, nl, &g) == MF_OK);
        snprintf(tag, sizeof tag, "%s %dx%d run %d plain", k_names[kind], w, h, c);
        dump_gate(tag, &g);
        mf_prefilter_gate_bounds_default(&g);
        CHECK(mf_prefilter_gate_run_ref(lv, nl, n, w, h, &o, &g) == MF_OK);
        snprintf(tag, sizeof tag, "%s %dx%d run %d ref", k_names[kind], w, h, c);
        dump_gate(tag, &g);
        if (c >= 0)
            memcpy(lv[l].m + 9 * e, save_e, 36), memcpy(lv[l].m + 9 * f, save_f, 36);
    }
    mf_prefilter_levels_free(lv, nl);
    free(n);
}

static void run_map(int kind, int w, int nt, int np, int ncorr, double scale, mf_prefilter_gate *good, power *ps,
                    power *pv)
{
    double *n = malloc(sizeof(double) * 3 * (size_t)w * w);
    CHECK(n != NULL);
    make_map(kind, w, n);
    mf_prefilter_options o;
    if (g_lambert)
        mf_prefilter_options_default_diffuse(&o);
    else
        mf_prefilter_options_default(&o);
    o.n_theta = nt, o.n_phi = np, o.threads = 2, o.keep_albedo = 1;
    mf_prefilter_level *lv;
    int nl;
    char msg[256];
    CHECK(mf_prefilter_run(n, w, w, &o, &lv, &nl, msg, sizeof msg) == MF_OK);
    mf_prefilter_gate_bounds_default(good);
    CHECK(mf_prefilter_gate_run_ref(lv, nl, n, w, w, &o, good) == MF_OK);
    printf("%-8s %2dx%-2d views %dx%-2d good: pass %d energy %.3g level %.3g | cont texel %.4f (%s) view %.4f (%s) | "
           "grazing %.4f (%s) | jump texel %.4f view %.4f | ref error %.4f | old spikes view %.3f texel %.3f\n",
           k_names[kind], w, w, nt, np, good->pass, good->worst_energy, good->worst_level, good->worst_cont_texel,
           good->where_cont_texel, good->worst_cont_view, good->where_cont_view, good->worst_cont_grazing, good->where_cont_grazing, good->worst_jump_texel,
           good->worst_jump_view, good->worst_ref_error, good->worst_view_spike, good->worst_texel_spike);
    memset(ps, 0, sizeof *ps), memset(pv, 0, sizeof *pv);
    ps->min_cont = pv->min_cont = INFINITY;
    ps->good_t = pv->good_t = good->worst_cont_texel, ps->good_v = pv->good_v = good->worst_cont_view;
    ps->good_g = pv->good_g = good->worst_cont_grazing;
    ps->good_c = pv->good_c = good->worst_cont_cross, ps->good_ct = pv->good_ct = good->worst_cont_cross_texel;
    ps->good_x = pv->good_x = good->worst_cont_excess;
    printf("%-8s good: cross %.4f (%s) texel axes %.4f; excess %.4f (%s)\n", k_names[kind], good->worst_cont_cross,
           good->where_cont_cross, good->worst_cont_cross_texel, good->worst_cont_excess, good->where_cont_excess);
    corrupt_runs(lv, nl, n, w, &o, ncorr, scale, ps, pv);
    printf("%-8s corrupted: scale entry by %.2f: caught %d / %d (energy/nan/level %d, cont at default bounds %d, cont above this good run's %d), no-ops %d; "
           "phi swap: caught %d / %d (energy/nan/level %d, cont %d, above good %d), no-ops %d\n",
           k_names[kind], 1.0 + scale, ps->caught, ps->total, ps->caught_old, ps->caught_cont, ps->caught_sep, ps->noop, pv->caught,
           pv->total, pv->caught_old, pv->caught_cont, pv->caught_sep, pv->noop);
    for (int t = 0; t < 2; ++t) {
        power *pw = t ? pv : ps;
        int m = pw->total < 256 ? pw->total : 256;
        qsort(pw->cont, (size_t)m, sizeof(double), dbl_cmp);
        printf("%-8s %s: corrupted cont quantiles 0, .1, .25, .5:", k_names[kind], t ? "phi swap" : "scaled entry");
        for (int q = 0; q < 4 && m > 0; ++q)
            printf(" %.4f", pw->cont[(int)((q == 0 ? 0 : q == 1 ? 0.1 : q == 2 ? 0.25 : 0.5) * (m - 1))]);
        qsort(pw->cross, (size_t)m, sizeof(double), dbl_cmp);
        printf("; cross above good: every axis %d, texel axes %d, above bound %d / %d, gated checks or cross above "
               "bound %d; visible %d: gated checks %d, cross above good %d, above bound %d, either %d; cross quantiles "
               "0, .1, .25, .5, .75, .9, 1:",
               pw->sep_c, pw->sep_ct, pw->bound_c, pw->total, pw->either, pw->vis, pw->vis_old, pw->vis_c, pw->vis_bound,
               pw->vis_either);
        static const double qs[7] = {0.0, 0.1, 0.25, 0.5, 0.75, 0.9, 1.0};
        for (int q = 0; q < 7 && m > 0; ++q)
            printf(" %.4f", pw->cross[(int)(qs[q] * (m - 1))]);
        printf("\n");
        qsort(pw->excess, (size_t)m, sizeof(double), dbl_cmp);
        printf("%-8s %s: excess above its bound (gated) %d / %d, visible %d / %d; excess quantiles 0, .1, .25, .5, .75, "
               ".9, 1:", k_names[kind], t ? "phi swap" : "scaled entry", pw->bound_x, pw->total, pw->vis_x, pw->vis);
        for (int q = 0; q < 7 && m > 0; ++q)
            printf(" %.4f", pw->excess[(int)(qs[q] * (m - 1))]);
        printf("\n");
    }
    fflush(stdout);
    mf_prefilter_levels_free(lv, nl);
    free(n);
}

/* The LTC density of the forward matrix m (row-major) at the unit direction w [Heitz 2016, Eq. 1 and
 * the Jacobian of Eq. 18]: D_o(w_o) / (|det M| |M^-1 w|^3), w_o = M^-1 w / |M^-1 w|, D_o = max(0, z) / pi. */
static double ltc_density(const float *m, const double *w)
{
    double a[9], inv[9];
    for (int i = 0; i < 9; ++i)
        a[i] = m[i];
    double det = a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6]) + a[2] * (a[3] * a[7] - a[4] * a[6]);
    inv[0] = (a[4] * a[8] - a[5] * a[7]) / det, inv[1] = (a[2] * a[7] - a[1] * a[8]) / det;
    inv[2] = (a[1] * a[5] - a[2] * a[4]) / det, inv[3] = (a[5] * a[6] - a[3] * a[8]) / det;
    inv[4] = (a[0] * a[8] - a[2] * a[6]) / det, inv[5] = (a[2] * a[3] - a[0] * a[5]) / det;
    inv[6] = (a[3] * a[7] - a[4] * a[6]) / det, inv[7] = (a[1] * a[6] - a[0] * a[7]) / det;
    inv[8] = (a[0] * a[4] - a[1] * a[3]) / det;
    double v[3];
    for (int r = 0; r < 3; ++r)
        v[r] = inv[3 * r] * w[0] + inv[3 * r + 1] * w[1] + inv[3 * r + 2] * w[2];
    double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    return fmax(v[2] / l, 0.0) / MF_PI / (fabs(det) * l * l * l);
}

/* Facet choice along phi (mf_prefilter.h, "continuity rule"): the V-groove map (8-bit, as decoded from
 * a PNG: its zero component decodes to 1/255, so the groove is symmetric only to the map's precision),
 * levels >= 2 (both facets in every footprint).  Per view, the facet score of the lobe
 * (D_A - D_B) / (D_A + D_B), D the lobe's density at the mirror directions of the view about the two
 * facet normals (tangent frame (+-sin 30 deg, 0, cos 30 deg), turned into the view's aligned frame).
 * A flip is a sign change between neighbouring azimuths with |score| > 0.5 on both sides: a lobe on
 * one facet next to a lobe on the other, which the bilinear view filter blends into a lobe between
 * them.  Measured on the demo map (16 x 16, 4 x 8 views) before the rule: 84 flips in 504 pairs of
 * levels 2-4 (4 per texel and elevation row); with it 0.  Asserted here: 0 (8 x 8, 3 x 8 views).
 * Also: the groove is its own half-turn, so the rows phi + pi are the rows phi, bit for bit. */
static void test_facet_continuity(void)
{
    const int w = 8, nt = 3, np = 8;
    double *n = malloc(sizeof(double) * 3 * w * w);
    CHECK(n != NULL);
    make_map(1, w, n);
    mf_prefilter_options o;
    mf_prefilter_options_default(&o);
    o.n_theta = nt, o.n_phi = np, o.threads = 2;
    mf_prefilter_level *lv;
    int nl;
    char msg[256];
    CHECK(mf_prefilter_run(n, w, w, &o, &lv, &nl, msg, sizeof msg) == MF_OK);
    double sx = sin(30.0 * MF_PI / 180.0), cz = cos(30.0 * MF_PI / 180.0);
    int flips = 0, pairs = 0, halfturn_diff = 0;
    for (int l = 1; l < nl; ++l) {
        const mf_prefilter_level *L = &lv[l];
        for (int t = 0; t < L->width * L->height; ++t)
            for (int a = 1; a < nt; ++a) {
                double th = mf_prefilter_theta(&o, a), wo[3] = {sin(th), 0.0, cos(th)}, score[256];
                for (int b = 0; b < np; ++b) {
                    double ph = mf_prefilter_phi(&o, b), d[2];
                    size_t e = ((size_t)t * nt + a) * np + b;
                    for (int f = 0; f < 2; ++f) {
                        double fx = f ? -sx : sx, nn[3] = {cos(ph) * fx, -sin(ph) * fx, cz}, r[3];
                        double c = nn[0] * wo[0] + nn[1] * wo[1] + nn[2] * wo[2];
                        for (int i = 0; i < 3; ++i)
                            r[i] = 2.0 * c * nn[i] - wo[i];
                        d[f] = r[2] > 0.0 ? ltc_density(L->m + 9 * e, r) : 0.0;
                    }
                    score[b] = d[0] + d[1] > 0.0 ? (d[0] - d[1]) / (d[0] + d[1]) : 0.0;
                    if (b >= np / 2)
                        halfturn_diff += memcmp(L->m + 9 * e, L->m + 9 * (e - np / 2), 9 * sizeof(float)) != 0;
                }
                for (int b = 0; b < np; ++b) {
                    double s0 = score[b], s1 = score[(b + 1) % np];
                    flips += s0 * s1 < 0.0 && fabs(s0) > 0.5 && fabs(s1) > 0.5;
                    ++pairs;
                }
            }
    }
    printf("vgroove facet continuity: %d flips in %d neighbouring-azimuth pairs, %d half-turn rows differing\n", flips,
           pairs, halfturn_diff);
    CHECKF(flips == 0, "vgroove: %d facet flips between neighbouring azimuths (of %d pairs)", flips, pairs);
    CHECKF(halfturn_diff == 0, "vgroove: %d entries of the rows phi + pi differ from the rows phi", halfturn_diff);
    mf_prefilter_levels_free(lv, nl);
    free(n);
}

/* The streamed gate (mf_prefilter_gate_stream_*): the row order (level l's row r right after rows 2r,
 * 2r + 1 of level l - 1), rows out of order and a stream ended early refused, and rows fed by hand
 * giving mf_prefilter_gate_run_ref's result byte for byte (bump map 8 x 8, 2 x 2 views). */
static void test_stream(void)
{
    const int w = 8;
    double n[3 * 64];
    make_map(2, w, n);
    mf_prefilter_options o;
    mf_prefilter_options_default(&o);
    o.n_theta = 2, o.n_phi = 2, o.threads = 2, o.keep_albedo = 1;
    mf_prefilter_level *lv;
    int nl;
    char msg[256];
    CHECK(mf_prefilter_run(n, w, w, &o, &lv, &nl, msg, sizeof msg) == MF_OK && nl == 3);
    mf_prefilter_gate ga, gb;
    mf_prefilter_gate_bounds_default(&ga);
    mf_prefilter_gate_bounds_default(&gb);
    CHECK(mf_prefilter_gate_run_ref(lv, nl, n, w, w, &o, &ga) == MF_OK);
    mf_prefilter_gate_stream *s;
    CHECK(mf_prefilter_gate_stream_begin(lv, nl, n, w, w, &o, &gb, &s) == MF_OK);
    /* level 1 is 4 x 4, level 2 2 x 2, level 3 1 x 1: the order, as (level index, row) */
    static const int want[][2] = {{0, 0}, {0, 1}, {1, 0}, {0, 2}, {0, 3}, {1, 1}, {2, 0}};
    int li, r, k = 0, bad_order = 0;
    while (mf_prefilter_gate_stream_next(s, &li, &r)) {
        const mf_prefilter_level *L = &lv[li];
        size_t off = (size_t)r * L->width * o.n_theta * o.n_phi;
        bad_order += k >= 7 || li != want[k][0] || r != want[k][1];
        if (k == 1) /* a row out of order is refused and changes nothing */
            CHECK(mf_prefilter_gate_stream_row(s, 0, 2, L->m, L->magnitude, L->albedo) == MF_ERR_DOMAIN);
        CHECK(mf_prefilter_gate_stream_row(s, li, r, L->m + 9 * off, L->magnitude + off, L->albedo + off) == MF_OK);
        ++k;
    }
    CHECKF(k == 7 && bad_order == 0, "stream: %d rows, %d out of the documented order", k, bad_order);
    CHECK(mf_prefilter_gate_stream_end(s) == MF_OK);
    CHECKF(memcmp(&ga, &gb, sizeof ga) == 0, "stream: rows fed by hand differ from mf_prefilter_gate_run_ref "
           "(energy %.17g / %.17g, cross %.17g / %.17g)", ga.worst_energy, gb.worst_energy, ga.worst_cont_cross,
           gb.worst_cont_cross);
    /* ended before its last row: refused (and freed) */
    CHECK(mf_prefilter_gate_stream_begin(lv, nl, n, w, w, &o, &gb, &s) == MF_OK);
    CHECK(mf_prefilter_gate_stream_row(s, 0, 0, lv[0].m, lv[0].magnitude, lv[0].albedo) == MF_OK);
    CHECK(mf_prefilter_gate_stream_end(s) == MF_ERR_DOMAIN);
    mf_prefilter_levels_free(lv, nl);
}

/* The own-fit check (mf_prefilter_gate_own_fit) on values worked by hand: s = S / albedo, r = R / albedo,
 * |.| the largest over the lights.  A lobe copied from neighbour j (s = s_j, which fits r_j to 0.02)
 * reads owner |s - r| - |s - r_j| = 0.38 - 0.02; a swap (j now holds the entry's own good lobe) reads
 * dominated |s - r| - |s_j - r| = 0.38; a lobe fitting its own reference reads 0; a non-finite entry
 * is skipped (0, -1), a non-finite neighbour ignored.  Tolerance 1e-15: a few roundings of numbers
 * near 1. */
static void test_own_fit_values(void)
{
    const double R[2] = {0.25, 0.25}, Rj[2] = {0.45, 0.25}, Sj[2] = {0.44, 0.25}; /* albedo 0.5 and 0.5 */
    const double *nS[2] = {Sj, Sj}, *nR[2] = {Rj, Rj}, na[2] = {0.5, 0.5};
    mf_prefilter_gate_own o;
    mf_prefilter_gate_own_fit(2, Sj, R, 0.5, 1, nS, nR, na, &o); /* copied: the entry holds s_j */
    CHECKF(o.owner_at == 0 && fabs(o.owner - 0.36) < 1e-15 && o.dominated == 0.0 && o.dominated_at == -1,
           "own fit, copy: owner %.17g at %d (want 0.36 at 0), dominated %.17g at %d (want 0, -1)", o.owner, o.owner_at,
           o.dominated, o.dominated_at);
    const double *sS[1] = {R}; /* swapped: the neighbour holds a lobe that shades r exactly */
    mf_prefilter_gate_own_fit(2, Sj, R, 0.5, 1, sS, nR, na, &o);
    CHECKF(o.owner_at == 0 && fabs(o.owner - 0.36) < 1e-15 && o.dominated_at == 0 && fabs(o.dominated - 0.38) < 1e-15,
           "own fit, swap: owner %.17g at %d (want 0.36), dominated %.17g at %d (want 0.38 at 0)", o.owner, o.owner_at,
           o.dominated, o.dominated_at);
    mf_prefilter_gate_own_fit(2, R, R, 0.5, 2, nS, nR, na, &o); /* a lobe shading its own reference exactly */
    CHECKF(o.owner == 0.0 && o.owner_at == -1 && o.dominated == 0.0 && o.dominated_at == -1,
           "own fit, exact lobe: owner %g at %d, dominated %g at %d (want 0, -1)", o.owner, o.owner_at, o.dominated,
           o.dominated_at);
    const double bad[2] = {NAN, 0.25}, *bS[2] = {bad, Sj};
    mf_prefilter_gate_own_fit(2, bad, R, 0.5, 1, nS, nR, na, &o);
    CHECKF(o.owner == 0.0 && o.owner_at == -1, "own fit, NaN entry: owner %g at %d (want 0, -1)", o.owner, o.owner_at);
    mf_prefilter_gate_own_fit(2, Sj, R, 0.5, 2, bS, nR, na, &o); /* neighbour 0 non-finite: neighbour 1 counts */
    CHECKF(o.owner_at == 1 && fabs(o.owner - 0.36) < 1e-15, "own fit, NaN neighbour: owner %.17g at %d (want 0.36 at 1)",
           o.owner, o.owner_at);
}

/* Own fit across elevations (mf_prefilter_gate_own_fit_cross) on values worked by hand, lights that
 * differ between the entry and its neighbour: the entry's lobe fits its own reference to 0.38
 * (s = 0.44, r = 0.06 at light 0 of its view) but j's to 0.02 (x_j = 0.50 under j's lights, r_j = 0.52):
 * owner = 0.38 - 0.02 = 0.36; j's lobe under the entry's lights (y_j = 0.10) misses r by 0.04: dominated
 * 0.38 - 0.04 = 0.34.  The same-lights function is this one with xS = S (the same bits on the fitted
 * bump map below).  Tolerance 1e-15: a few roundings of numbers near 1. */
static void test_own_fit_cross_values(void)
{
    const double S[2] = {0.22, 0.125}, R[2] = {0.03, 0.125};        /* albedo 0.5: s = (0.44, 0.25), r = (0.06, 0.25) */
    const double X[2] = {0.25, 0.125}, Rj[2] = {0.13, 0.0625};      /* x_j = (0.50, 0.25); albedo_j 0.25: r_j = (0.52, 0.25) */
    const double Y[2] = {0.025, 0.0625};                             /* y_j = (0.10, 0.25) */
    const double *xS[1] = {X}, *nR[1] = {Rj}, *yS[1] = {Y}, na[1] = {0.25};
    mf_prefilter_gate_own o;
    mf_prefilter_gate_own_fit_cross(2, S, R, 0.5, 1, xS, nR, yS, na, &o);
    CHECKF(o.owner_at == 0 && fabs(o.owner - 0.36) < 1e-15 && o.dominated_at == 0 && fabs(o.dominated - 0.34) < 1e-15,
           "own fit across lights: owner %.17g at %d (want 0.36 at 0), dominated %.17g at %d (want 0.34 at 0)", o.owner,
           o.owner_at, o.dominated, o.dominated_at);
    /* the same-lights function reads |s - r_j| instead: 0.38 - max(0.08, 0) = 0.30 */
    const double *nS[1] = {Y};
    mf_prefilter_gate_own_fit(2, S, R, 0.5, 1, nS, nR, na, &o);
    CHECKF(o.owner_at == 0 && fabs(o.owner - 0.30) < 1e-15, "own fit, same lights: owner %.17g at %d (want 0.30 at 0)",
           o.owner, o.owner_at);
    const double bad[2] = {0.25, NAN}, *bX[1] = {bad};
    mf_prefilter_gate_own_fit_cross(2, S, R, 0.5, 1, bX, nR, yS, na, &o);
    CHECKF(o.owner_at == -1 && o.dominated_at == -1, "own fit across lights, a non-finite x_j: owner at %d, dominated at "
           "%d (want -1: the neighbour is skipped)", o.owner_at, o.dominated_at);
}

/* The first entry of level L from `start` on, in storage order, whose copy from its neighbour (theta 0: texel x + 1,
 * periodic, at the same view; 1: view a + 1, a - 1 on the last row) changes a gate light's shading by
 * at least 0.5 of the albedo (lobe_change; the magnitude scaled to keep the entry's albedo); its
 * neighbour in *from.  L is left as it was; the level's entry count when there is none. */
static size_t first_big_copy(mf_prefilter_level *L, int nt, int np, int theta, size_t start,
                             const mf_prefilter_options *o, size_t *from)
{
    const size_t nv = (size_t)nt * np, ne = (size_t)L->width * L->height * nv;
    float se[10];
    for (size_t i = start; i < ne; ++i) {
        size_t t = i / nv, row = t / (size_t)L->width, col = t % (size_t)L->width;
        int a = (int)(i / np % nt);
        size_t j = theta ? (a + 1 < nt ? i + np : i - np)
                         : (row * (size_t)L->width + (col + 1) % (size_t)L->width) * nv + i % nv;
        memcpy(se, L->m + 9 * i, 36), se[9] = L->magnitude[i];
        memcpy(L->m + 9 * i, L->m + 9 * j, 36), L->magnitude[i] = L->albedo[i] / L->albedo[j] * L->magnitude[j];
        int big = lobe_change(L, i, se, o) >= 0.5;
        memcpy(L->m + 9 * i, se, 36), L->magnitude[i] = se[9];
        if (big) {
            *from = j;
            return i;
        }
    }
    return ne;
}

/* The good run's own fit across elevations: passes, above 0 (the check ran). */
static int good_theta(const mf_prefilter_level *lv, int nl, const double *n, int w, const mf_prefilter_options *o)
{
    mf_prefilter_gate g;
    mf_prefilter_gate_bounds_default(&g);
    if (mf_prefilter_gate_run_ref(lv, nl, n, w, w, o, &g) != MF_OK)
        return 0;
    printf("bump 8x8 4x8 good: own fit across elevations %.4f (%s), dominated %.4f\n", g.worst_cont_owner_theta,
           g.where_cont_owner_theta, g.worst_cont_dominated_theta);
    return g.pass && g.pass_cont_owner_theta && g.worst_cont_owner_theta > 0.0;
}

/* The own-fit check on fitted lobes (bump map 8 x 8, 4 x 8 views; GGX): the good run passes with owner
 * below its bound, and a planted copy and swap of level-1 texel neighbours (x + 1, the same view;
 * magnitudes scaled to keep each entry's albedo, so the energy check cannot see them) are caught by it.
 * The planted entry: the first level-1 entry, in storage order, whose copy changes a gate light's
 * shading by at least 0.5 of the albedo (lobe_change) -- a change the gate must not let through.
 * Also the constant map (8 x 8): every footprint is the same, so owner is 0 but for rounding. */
static void test_own_fit_planted(void)
{
    const int w = 8, nt = 4, np = 8;
    double *n = malloc(sizeof(double) * 3 * w * w);
    CHECK(n != NULL);
    mf_prefilter_options o;
    mf_prefilter_options_default(&o);
    o.n_theta = nt, o.n_phi = np, o.threads = 2, o.keep_albedo = 1;
    mf_prefilter_level *lv;
    int nl;
    char msg[256];
    make_map(2, w, n);
    CHECK(mf_prefilter_run(n, w, w, &o, &lv, &nl, msg, sizeof msg) == MF_OK);
    mf_prefilter_gate g;
    mf_prefilter_gate_bounds_default(&g);
    CHECK(mf_prefilter_gate_run_ref(lv, nl, n, w, w, &o, &g) == MF_OK);
    printf("bump 8x8 4x8 good: own fit %.4f (%s), azimuths %.4f, dominated %.4f\n", g.worst_cont_owner,
           g.where_cont_owner, g.worst_cont_owner_view, g.worst_cont_dominated);
    CHECKF(g.pass && g.pass_cont_owner && g.worst_cont_owner > 0.0,
           "bump: good run: pass %d, own fit %.4g (bound %.3g; 0 would mean the check saw nothing)", g.pass,
           g.worst_cont_owner, g.max_cont_owner);
    mf_prefilter_level *L = &lv[0];
    const size_t nv = (size_t)nt * np, ne = (size_t)L->width * L->height * nv;
    size_t f = 0, e = first_big_copy(L, nt, np, 0, 0, &o, &f);
    float se[10], sf[10];
    CHECKF(e < ne, "bump: no level-1 texel copy changes the shading by 0.5 of the albedo (the plant needs one)");
    if (e < ne) {
        memcpy(se, L->m + 9 * e, 36), se[9] = L->magnitude[e];
        memcpy(sf, L->m + 9 * f, 36), sf[9] = L->magnitude[f];
        /* the copy: entry e gets f's lobe */
        memcpy(L->m + 9 * e, sf, 36), L->magnitude[e] = L->albedo[e] / L->albedo[f] * sf[9];
        double ch = lobe_change(L, e, se, &o);
        mf_prefilter_gate_bounds_default(&g);
        CHECK(mf_prefilter_gate_run_ref(lv, nl, n, w, w, &o, &g) == MF_OK);
        printf("bump: planted copy at level 1, entry %zu (change %.3f): own fit %.4f (%s); excess %.4f, energy %.3g, "
               "level %.3f\n", e, ch, g.worst_cont_owner, g.where_cont_owner, g.worst_cont_excess, g.worst_energy,
               g.worst_level);
        CHECKF(!g.pass && !g.pass_cont_owner, "bump: a copied level-1 lobe (change %.3f of the albedo) passes: own fit "
               "%.4g (bound %.3g), pass %d", ch, g.worst_cont_owner, g.max_cont_owner, g.pass);
        /* the swap: f gets e's lobe too */
        memcpy(L->m + 9 * f, se, 36), L->magnitude[f] = L->albedo[f] / L->albedo[e] * se[9];
        mf_prefilter_gate_bounds_default(&g);
        CHECK(mf_prefilter_gate_run_ref(lv, nl, n, w, w, &o, &g) == MF_OK);
        printf("bump: planted swap: own fit %.4f (%s); dominated %.4f; excess %.4f\n", g.worst_cont_owner,
               g.where_cont_owner, g.worst_cont_dominated, g.worst_cont_excess);
        CHECKF(!g.pass && !g.pass_cont_owner, "bump: swapped level-1 lobes pass: own fit %.4g (bound %.3g), pass %d",
               g.worst_cont_owner, g.max_cont_owner, g.pass);
        memcpy(L->m + 9 * e, se, 36), L->magnitude[e] = se[9];
        memcpy(L->m + 9 * f, sf, 36), L->magnitude[f] = sf[9];
    }
    /* own fit across elevations: the good run passes it (and reads above 0: the check ran); a planted
     * copy from the theta neighbour (a + 1, a - 1 on the last row) and the swap are caught by it, while
     * every other gated check passes (the gate before it let them through).  The planted entry: the first
     * level-1 entry whose copy changes a gate light's shading by >= 0.5 of the albedo and passes the
     * other checks (with fitter revision 10's lobes the first such copy, entry 15, is also caught by
     * excess; the test is about what only this check sees) */
    CHECKF(good_theta(lv, nl, n, w, &o), "bump: good run fails own fit across elevations or reads 0");
    for (int swap = 0; swap < 2; ++swap) {
        size_t ft = 0, et = ne;
        double ch = 0.0;
        for (size_t start = 0; start < ne;) {
            et = first_big_copy(L, nt, np, 1, start, &o, &ft);
            if (et == ne)
                break;
            memcpy(se, L->m + 9 * et, 36), se[9] = L->magnitude[et];
            memcpy(sf, L->m + 9 * ft, 36), sf[9] = L->magnitude[ft];
            memcpy(L->m + 9 * et, sf, 36), L->magnitude[et] = L->albedo[et] / L->albedo[ft] * sf[9];
            if (swap)
                memcpy(L->m + 9 * ft, se, 36), L->magnitude[ft] = L->albedo[ft] / L->albedo[et] * se[9];
            ch = lobe_change(L, et, se, &o);
            mf_prefilter_gate_bounds_default(&g);
            CHECK(mf_prefilter_gate_run_ref(lv, nl, n, w, w, &o, &g) == MF_OK);
            if (g.pass_energy && g.pass_nan && g.pass_level && g.pass_cont_excess && g.pass_cont_owner)
                break; /* planted: the other checks pass */
            memcpy(L->m + 9 * et, se, 36), L->magnitude[et] = se[9];
            memcpy(L->m + 9 * ft, sf, 36), L->magnitude[ft] = sf[9];
            start = et + 1, et = ne;
        }
        CHECKF(et < ne, "bump: no level-1 theta %s changes the shading by 0.5 of the albedo and passes the other checks "
               "(the plant needs one)", swap ? "swap" : "copy");
        if (et == ne)
            break;
        printf("bump: planted theta %s at level 1, entry %zu (change %.3f): own fit across elevations %.4f (%s), "
               "dominated %.4f; texels %.4f, azimuths %.4f, excess %.4f, energy %.3g, level %.3f\n",
               swap ? "swap" : "copy", et, ch, g.worst_cont_owner_theta, g.where_cont_owner_theta,
               g.worst_cont_dominated_theta, g.worst_cont_owner, g.worst_cont_owner_view, g.worst_cont_excess,
               g.worst_energy, g.worst_level);
        CHECKF(!g.pass && !g.pass_cont_owner_theta && strstr(g.where_cont_owner_theta, "theta") &&
                   g.pass_energy && g.pass_nan && g.pass_level && g.pass_cont_excess && g.pass_cont_owner,
               "bump: a theta %s at level 1 (change %.3f of the albedo): own fit across elevations %.4g (bound %.3g), "
               "pass %d; the other gated checks should pass (energy %d nan %d level %d excess %d own fit %d)",
               swap ? "swap" : "copy", ch, g.worst_cont_owner_theta, g.max_cont_owner_theta, g.pass, g.pass_energy,
               g.pass_nan, g.pass_level, g.pass_cont_excess, g.pass_cont_owner);
        memcpy(L->m + 9 * et, se, 36), L->magnitude[et] = se[9];
        memcpy(L->m + 9 * ft, sf, 36), L->magnitude[ft] = sf[9];
    }
    mf_prefilter_levels_free(lv, nl);
    make_map(0, w, n);
    CHECK(mf_prefilter_run(n, w, w, &o, &lv, &nl, msg, sizeof msg) == MF_OK);
    mf_prefilter_gate_bounds_default(&g);
    CHECK(mf_prefilter_gate_run_ref(lv, nl, n, w, w, &o, &g) == MF_OK);
    /* 1e-12: the footprints and their lobes are the same; what is left is rounding (measured 9.0e-17) */
    CHECKF(g.pass && g.worst_cont_owner < 1e-12, "constant: own fit %.4g on the good run (want 0: every footprint is "
           "the same), pass %d", g.worst_cont_owner, g.pass);
    printf("constant 8x8 4x8: own fit across elevations %.4f (%s)\n", g.worst_cont_owner_theta, g.where_cont_owner_theta);
    mf_prefilter_levels_free(lv, nl);
    free(n);
}

int main(int argc, char **argv)
{
    if (argc >= 7 && !strcmp(argv[1], "dump")) { /* dump W H NT NP NCORR [lambert] */
        g_lambert = argc >= 8 && !strcmp(argv[7], "lambert");
        for (int k = 0; k < 3; ++k)
            dump_map(k, atoi(argv[2]), atoi(argv[3]), atoi(argv[4]), atoi(argv[5]), atoi(argv[6]));
        return mf_test_failures ? 1 : 0;
    }
    if (argc >= 6 && !strcmp(argv[1], "measure")) {
        int w = atoi(argv[2]), nt = atoi(argv[3]), np = atoi(argv[4]), nc = atoi(argv[5]);
        double scale = argc >= 7 ? atof(argv[6]) : 0.5;
        int only = argc >= 8 ? atoi(argv[7]) : -1;
        g_lambert = argc >= 9 && !strcmp(argv[8], "lambert");
        for (int k = 0; k < 3; ++k) {
            if (only >= 0 && k != only)
                continue;
            mf_prefilter_gate g;
            power ps, pv;
            run_map(k, w, nt, np, nc, scale, &g, &ps, &pv);
        }
        return mf_test_failures ? 1 : 0;
    }
    /* CTest (about 16 s of CPU): the constant map (8 x 8, 4 x 8 views) and the bump map (4 x 4, 3 x 8
     * views), 10 corruptions of each kind.  The error spikes and cross are reported, not gated (they do
     * not separate good from corrupted runs on the V-groove and the bump map: docs/prefilter.md); excess
     * is gated for both tables ("Gating continuity across texels"); what is asserted is what holds:
     *   - every good run passes the gate and its reference measures are finite;
     *   - constant map: every texel's lobes and reference are the same, so the texel measure is exactly
     *     0; a phi swap raises the continuity measures above the good run's (measured 10 / 10 with
     *     revision 5's lobes, 9 / 10 with revision 6's; asserted >= 9 / 10), a scaled entry less often (measured 4 / 10, asserted >= 3: the 1 x 1 level has no
     *     texel neighbours, and the view measures of this map are dominated by the grazing row);
     *   - bump map: the good run passes (no false alarm of the gated checks); the power is printed, not
     *     asserted (weak: docs/prefilter_log.md, "Gate"). */
    {
        mf_prefilter_gate g;
        power ps, pv;
        run_map(0, 8, 4, 8, 10, 0.5, &g, &ps, &pv);
        CHECKF(g.pass && g.has_ref && g.worst_cont_texel == 0.0 && isfinite(g.worst_cont_view) &&
                   isfinite(g.worst_cont_grazing) && isfinite(g.worst_ref_error),
               "constant: good run: pass %d, cont texel %.4g view %.4g grazing %.4g, ref error %.4g", g.pass,
               g.worst_cont_texel, g.worst_cont_view, g.worst_cont_grazing, g.worst_ref_error);
        CHECKF(ps.total == 10 && ps.caught_sep >= 3, "constant: scaled entries above the good run: %d / %d",
               ps.caught_sep, ps.total);
        /* measured 10 / 10 with fitter revision 5's lobes, 9 / 10 with revision 6's (the fits' ladder of
         * base-lobe-sized lights: other lobes, so other corruptions stand out); every swap is still
         * caught by the gated checks or cross (pv.either == 10 below) */
        CHECKF(pv.total == 10 && pv.caught_sep >= 9, "constant: phi swaps above the good run: %d / %d",
               pv.caught_sep, pv.total);
        /* the lone extreme of e along every axis (cross, reported): exactly 0 on the good run (every
         * texel's e is the same, so no entry is a lone extreme along x and y); with it, the gated checks
         * catch every phi swap (measured 10 / 10 together, 8 / 10 without it; the fits are bitwise
         * reproducible, so the counts are exact) and it sees scaled entries (measured 3 / 10 above 0) */
        CHECKF(g.worst_cont_cross == 0.0 && pv.either == 10 && pv.caught_old < pv.either && ps.sep_c >= 3,
               "constant: cross %.4g on the good run; phi swaps caught with it %d / 10 (without %d); scaled entries "
               "above 0: %d / 10", g.worst_cont_cross, pv.either, pv.caught_old, ps.sep_c);
        /* excess (gated, bound 0.2): exactly 0 on the good run (every texel's lobe and reference are the
         * same, so no lobe is a lone extreme across texels); it catches large phi swaps (measured 2 / 10
         * here, the changes of 0.40 of the albedo; the smaller swaps change a light's shading by less
         * than the bound) */
        CHECKF(g.worst_cont_excess == 0.0 && g.pass_cont_excess && pv.bound_x >= 2,
               "constant: excess %.4g on the good run; phi swaps above its bound %d / 10", g.worst_cont_excess,
               pv.bound_x);
        run_map(2, 4, 3, 8, 10, 0.5, &g, &ps, &pv);
        /* the good run passes, excess included (measured 0.0445 against the bound 0.2) */
        CHECKF(g.pass && g.pass_cont_excess && isfinite(g.worst_cont_texel) && isfinite(g.worst_cont_view) &&
                   isfinite(g.worst_ref_error),
               "bump: good run: pass %d, excess %.4g, cont texel %.4g view %.4g, ref error %.4g", g.pass,
               g.worst_cont_excess, g.worst_cont_texel, g.worst_cont_view, g.worst_ref_error);
        /* the diffuse table, where the continuity spikes are gated (bound 0.03): V-groove 8 x 8, 2 x 4
         * views: the good run passes (measured 0.0117), and the gate catches scaled entries the other
         * checks miss (measured with these 10: 5 / 10 by the continuity checks, 1 / 10 by energy, nan
         * and level; asserted >= 4 and more than without them) */
        g_lambert = 1;
        run_map(1, 8, 2, 4, 10, 0.5, &g, &ps, &pv);
        g_lambert = 0;
        CHECKF(g.pass && g.cont_gated && g.worst_cont_grazing <= 0.03 && g.worst_cont_cross == 0.0 &&
                   g.worst_cont_excess == 0.0,
               "lambert vgroove: good run: pass %d, grazing %.4g, cross %.4g, excess %.4g (the groove's texels along y "
               "are the same)",
               g.pass, g.worst_cont_grazing, g.worst_cont_cross, g.worst_cont_excess);
        CHECKF(ps.total == 10 && ps.caught_cont >= 4 && ps.caught > ps.caught_old,
               "lambert vgroove: scaled entries caught by the continuity checks %d / %d (all checks %d, without them %d)",
               ps.caught_cont, ps.total, ps.caught, ps.caught_old);
    }
    test_facet_continuity();
    test_stream();
    test_own_fit_values();
    test_own_fit_cross_values();
    test_own_fit_planted();
    MF_TEST_MAIN_END();
}
