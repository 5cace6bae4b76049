/* mf_energy.c -- DFG and Kulla-Conty energy tables and their gates (see mf_energy.h). */
#include "mfkit/mf_energy.h"
#include "mfkit/mf_quad.h"
#include "mfkit/mf_table_kind.h"
#include "mfkit/mf_walk.h"

#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int cmp_dbl(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

const char *const mf_dfg_table_fields[MF_DFG_NFIELDS] = {"dfg_scale", "dfg_bias", "dfg_scale_err", "dfg_bias_err",
                                                        "dfg_charlie", "dfg_charlie_err"};
const char *const mf_kulla_conty_table_fields[MF_KULLA_CONTY_NFIELDS] = {"E", "E_err", "E_avg", "E_avg_err"};

static int args_ok(mf_ndf_type ndf, mf_g2_form g2, double alpha, double mu)
{
    return (ndf == MF_NDF_GGX || ndf == MF_NDF_BECKMANN) && (g2 == MF_G2_JOINT || g2 == MF_G2_SEPARABLE)
           && alpha >= MF_ENERGY_ALPHA_MIN && alpha <= 1.0 && mu > 0.0 && mu <= 1.0;
}

static mf_vec3 view(double mu) { return mf_vec3_make(sqrt(fmax(0.0, 1.0 - mu * mu)), 0.0, mu); }

mf_status mf_energy_dfg(mf_ndf_type ndf, mf_g2_form g2, double alpha, double mu, mf_result *scale, mf_result *bias)
{
    scale->val = scale->err = bias->val = bias->err = NAN;
    if (!args_ok(ndf, g2, alpha, mu))
        return MF_ERR_DOMAIN;
    mf_microfacet m = {mf_ndf_make(ndf, alpha, alpha), g2, {MF_FRESNEL_NONE, 0.0, 0.0, 0.0}};
    return mf_albedo_microfacet_schlick(&m, view(mu), scale, bias);
}

mf_status mf_energy_e(mf_ndf_type ndf, mf_g2_form g2, double alpha, double mu, mf_result *e)
{
    e->val = e->err = NAN;
    if (!args_ok(ndf, g2, alpha, mu))
        return MF_ERR_DOMAIN;
    mf_microfacet m = {mf_ndf_make(ndf, alpha, alpha), g2, {MF_FRESNEL_NONE, 0.0, 0.0, 0.0}};
    return mf_albedo_microfacet(&m, view(mu), e);
}

/* 2 integral_0^1 E(mu) mu dmu = 4 integral_0^1 E(s^2) s^3 ds on the panels [0, 1/2], [1/2, 1]
 * with an n-point rule; *bound gets the propagated albedo bounds. */
static mf_status eavg_rule(mf_ndf_type ndf, mf_g2_form g2, double alpha, int n, double *val, double *bound)
{
    double x[16], w[16];
    if (mf_quad_gauss_legendre(n, x, w) != MF_OK)
        return MF_ERR_INTERNAL;
    double sum = 0.0, b = 0.0;
    for (int p = 0; p < 2; ++p)
        for (int j = 0; j < n; ++j) {
            double s = 0.25 * (2 * p + 1 + x[j]), wt = 0.25 * w[j] * 4.0 * s * s * s;
            mf_result e;
            mf_status st = mf_energy_e(ndf, g2, alpha, s * s, &e);
            if (st != MF_OK)
                return st;
            sum += wt * e.val;
            b += wt * e.err;
        }
    *val = sum;
    *bound = b;
    return MF_OK;
}

mf_status mf_energy_eavg(mf_ndf_type ndf, mf_g2_form g2, double alpha, mf_result *eavg)
{
    eavg->val = eavg->err = NAN;
    if (!args_ok(ndf, g2, alpha, 1.0))
        return MF_ERR_DOMAIN;
    double hi, lo, bhi, blo;
    mf_status st = eavg_rule(ndf, g2, alpha, 12, &hi, &bhi);
    if (st == MF_OK)
        st = eavg_rule(ndf, g2, alpha, 8, &lo, &blo);
    if (st != MF_OK)
        return st;
    eavg->val = hi;
    eavg->err = fabs(hi - lo) + bhi + blo;
    return MF_OK;
}

double mf_energy_favg_schlick(double f0)
{
    /* 2 integral (F0 + (1 - F0)(1 - mu)^5) mu dmu = F0 + (1 - F0) / 21 [Kulla and Conty 2017] */
    return (f0 >= 0.0 && f0 <= 1.0) ? (20.0 * f0 + 1.0) / 21.0 : NAN;
}

typedef struct {
    double eta, k;
} cond_ctx;

static double favg_integrand(double mu, void *user)
{
    const cond_ctx *c = user;
    return 2.0 * mu * mf_fresnel_conductor(c->eta, c->k, mu);
}

mf_status mf_energy_favg_conductor(double eta, double k, mf_result *out)
{
    out->val = out->err = NAN;
    if (!(eta > 0.0) || !(k >= 0.0) || !isfinite(eta) || !isfinite(k))
        return MF_ERR_DOMAIN;
    cond_ctx c = {eta, k};
    return mf_quad_adaptive(favg_integrand, &c, 0.0, 1.0, 1e-13, 0.0, MF_QUAD_MAX_INTERVALS, out);
}

/* F_avg of the exact dielectric: 2 integral_0^1 F(mu) mu dmu.  For eta < 1, F = 1 below the critical
 * cosine mu_c = sqrt(1 - eta^2) (that piece is mu_c^2 exactly) and F has a square-root kink at mu_c
 * (cos theta_t = sqrt(mu^2 - mu_c^2) / eta), so above it mu = mu_c + u^2 makes the integrand smooth. */
typedef struct {
    double eta, org;
} fdiel_ctx;

static double favg_diel_f(double u, void *user)
{
    const fdiel_ctx *c = user;
    double mu = fmin(1.0, c->org + u * u);
    return 2.0 * mu * mf_fresnel_dielectric(c->eta, mu) * 2.0 * u;
}

mf_status mf_energy_favg_dielectric(double eta, mf_result *out)
{
    out->val = out->err = NAN;
    if (!(eta > 0.0) || !isfinite(eta))
        return MF_ERR_DOMAIN;
    double mc2 = eta < 1.0 ? (1.0 - eta) * (1.0 + eta) : 0.0, mc = sqrt(mc2);
    fdiel_ctx c = {eta, mc};
    mf_status st = mf_quad_adaptive(favg_diel_f, &c, 0.0, sqrt(1.0 - mc), 1e-14, 0.0, MF_QUAD_MAX_INTERVALS, out);
    out->val += mc2;
    out->err += 4.0 * DBL_EPSILON;
    return st;
}

/* The split of Kulla and Conty 2017 (the dielectric part of their energy compensation): of the
 * compensation energy 1 - E(mu_o) on the view's side, the fraction t goes into transmission,
 *   t = (1 - F_avg(eta)) x,  x = A / (A + B),  A = eta^2 (1 - F_avg(1/eta)) (1 - E_avg(1/eta)),
 *   B = (1 - F_avg(eta)) (1 - E_avg(eta)),
 * which on the other side (eta -> 1/eta) gives x' = B / (A + B) = 1 - x, their pair (x, 1 - x); it makes
 * the compensation's transmitted flux balance: t (1 - E_avg(eta)) = eta^2 t' (1 - E_avg(1/eta))
 * (docs/math.md, "Splitting the dielectric compensation"). */
mf_status mf_energy_dielectric_ms_split(double eta, double eavg, double eavg_inv, double favg, double favg_inv,
                                        double *t)
{
    *t = NAN;
    if (!(eta > 0.0) || !isfinite(eta) || !(eavg >= 0.0 && eavg <= 1.0 + 1e-6) || !(eavg_inv >= 0.0 && eavg_inv <= 1.0 + 1e-6)
        || !(favg >= 0.0 && favg <= 1.0) || !(favg_inv >= 0.0 && favg_inv <= 1.0))
        return MF_ERR_DOMAIN;
    double a = eta * eta * (1.0 - favg_inv) * fmax(0.0, 1.0 - eavg_inv), b = (1.0 - favg) * fmax(0.0, 1.0 - eavg);
    /* no compensation energy on either side: any split is exact; take the Fresnel one (x = 1/2 of both) */
    double x = a + b > 0.0 ? a / (a + b) : 0.5;
    *t = (1.0 - favg) * x;
    return MF_OK;
}

double mf_energy_kc_lobe(double weight, double e_o, double e_i, double eavg_i)
{
    /* (1 - E(mu_o)) (1 - E(mu_i)) / (pi (1 - E_avg)) [Kulla and Conty 2017], times the split's weight;
     * each factor clamped at 0 (a nearly smooth surface's E may round above 1 within its bound), which
     * keeps the lobe symmetric and reciprocal */
    return eavg_i < 1.0 ? weight * fmax(0.0, 1.0 - e_o) * fmax(0.0, 1.0 - e_i) / (MF_PI * (1.0 - eavg_i)) : 0.0;
}

/* ---- tables --------------------------------------------------------------------------------- */

static mf_status make_table(mf_table *t, const char *kind, mf_ndf_type ndf, mf_g2_form g2, int n_mu, int n_r,
                            int nfields, const char *const *fields)
{
    memset(t, 0, sizeof *t);
    if (n_mu < 2 || n_r < 2 || n_mu > 4096 || n_r > 4096 || (ndf != MF_NDF_GGX && ndf != MF_NDF_BECKMANN)
        || (g2 != MF_G2_JOINT && g2 != MF_G2_SEPARABLE))
        return MF_ERR_DOMAIN;
    mf_table_axis ax[2];
    memset(ax, 0, sizeof ax);
    snprintf(ax[0].name, sizeof ax[0].name, "mu");
    snprintf(ax[0].physical, sizeof ax[0].physical, "cos_theta_o");
    ax[0].size = n_mu;
    ax[0].lo = 0.5 / n_mu;
    ax[0].hi = 1.0 - 0.5 / n_mu;
    ax[0].mapping = MF_AXIS_IDENTITY;
    ax[0].physical_min = -INFINITY;
    snprintf(ax[1].name, sizeof ax[1].name, "r");
    snprintf(ax[1].physical, sizeof ax[1].physical, "alpha");
    ax[1].size = n_r;
    ax[1].lo = 0.5 / n_r;
    ax[1].hi = 1.0 - 0.5 / n_r;
    ax[1].mapping = MF_AXIS_SQUARE;
    ax[1].physical_min = MF_ENERGY_ALPHA_MIN;
    mf_status st = mf_table_create(t, 2, ax, nfields, fields);
    if (st != MF_OK)
        return st;
    const mf_table_kind *k = mf_table_kind_find(kind);
    if (!k || mf_table_kind_tag(t, k) != MF_OK || mf_table_set_meta(t, "ndf", mf_ndf_type_name(ndf)) != MF_OK
        || mf_table_set_meta(t, "g2", g2 == MF_G2_JOINT ? "joint" : "separable") != MF_OK) {
        mf_table_free(t);
        return MF_ERR_INTERNAL;
    }
    return MF_OK;
}

static double texel_mu(const mf_table *t, int i) { return mf_table_axis_physical(&t->axes[0], mf_table_axis_param(&t->axes[0], i)); }
static double texel_alpha(const mf_table *t, int j) { return mf_table_axis_physical(&t->axes[1], mf_table_axis_param(&t->axes[1], j)); }

mf_status mf_energy_dfg_table(mf_table *t, mf_ndf_type ndf, mf_g2_form g2, int n_mu, int n_r,
                              mf_energy_progress progress, void *user)
{
    mf_status st = make_table(t, "dfg", ndf, g2, n_mu, n_r, MF_DFG_NFIELDS, mf_dfg_table_fields);
    if (st != MF_OK)
        return st;
    long total = (long)n_mu * n_r, done = 0;
    for (int j = 0; j < n_r; ++j)
        for (int i = 0; i < n_mu; ++i) {
            mf_result s, b;
            st = mf_energy_dfg(ndf, g2, texel_alpha(t, j), texel_mu(t, i), &s, &b);
            if (st != MF_OK) {
                mf_table_free(t);
                return st;
            }
            mf_result ch;
            st = mf_albedo_charlie(texel_alpha(t, j), texel_mu(t, i), &ch);
            if (st != MF_OK) {
                mf_table_free(t);
                return st;
            }
            double *r = t->data + ((size_t)j * n_mu + i) * MF_DFG_NFIELDS;
            r[0] = s.val, r[1] = b.val, r[2] = s.err, r[3] = b.err, r[4] = ch.val, r[5] = ch.err;
            if (progress)
                progress(user, ++done, total);
        }
    return MF_OK;
}

mf_status mf_energy_kulla_conty_table(mf_table *t, mf_ndf_type ndf, mf_g2_form g2, int n_mu, int n_r,
                                      mf_energy_progress progress, void *user)
{
    mf_status st = make_table(t, "kulla_conty", ndf, g2, n_mu, n_r, MF_KULLA_CONTY_NFIELDS, mf_kulla_conty_table_fields);
    if (st != MF_OK)
        return st;
    long total = (long)n_mu * n_r + n_r, done = 0;
    for (int j = 0; j < n_r; ++j) {
        mf_result avg;
        st = mf_energy_eavg(ndf, g2, texel_alpha(t, j), &avg);
        if (progress)
            progress(user, ++done, total);
        for (int i = 0; i < n_mu && st == MF_OK; ++i) {
            mf_result e;
            st = mf_energy_e(ndf, g2, texel_alpha(t, j), texel_mu(t, i), &e);
            double *r = t->data + ((size_t)j * n_mu + i) * MF_KULLA_CONTY_NFIELDS;
            r[0] = e.val, r[1] = e.err, r[2] = avg.val, r[3] = avg.err;
            if (progress)
                progress(user, ++done, total);
        }
        if (st != MF_OK) {
            mf_table_free(t);
            return st;
        }
    }
    return MF_OK;
}

/* ---- gates ---------------------------------------------------------------------------------- */

typedef struct {
    const mf_table *t;
    mf_ndf_type ndf;
    mf_g2_form g2;
    double u; /* storage unit roundoff: each stored value may be off by u |value| beyond its bound */
    struct diel_avgs *avgs; /* dielectric gate: the independent averages of the furnace columns (or NULL) */
} gate_ctx;

static int gate_setup(const mf_table *t, const char *kind, gate_ctx *g)
{
    const mf_table_kind *k = mf_table_kind_find(kind);
    if (!k || !k->layout_ok(t, NULL, 0))
        return -1;
    const char *ndf = mf_table_get_meta(t, "ndf"), *g2 = mf_table_get_meta(t, "g2");
    g->t = t;
    if (!ndf || mf_ndf_type_parse(ndf, &g->ndf) != 0 || !g2)
        return -1;
    if (!strcmp(g2, "joint"))
        g->g2 = MF_G2_JOINT;
    else if (!strcmp(g2, "separable"))
        g->g2 = MF_G2_SEPARABLE;
    else
        return -1;
    return 0;
}

static const double *rec(const mf_table *t, int i, int j) { return t->data + ((size_t)j * t->axes[0].size + i) * t->nfields; }

static void check_finite(void *vctx, mf_check *c)
{
    const gate_ctx *g = vctx;
    for (int j = 0; j < g->t->axes[1].size; ++j)
        for (int i = 0; i < g->t->axes[0].size; ++i) {
            const double *r = rec(g->t, i, j);
            int bad = 0;
            for (int f = 0; f < g->t->nfields; ++f)
                bad += !isfinite(r[f]);
            mf_check_recordf(c, bad, "texel (%d, %d)", i, j);
        }
}

/* dfg: max(0, -scale, -bias, scale + bias - 1) beyond the bounds */
static void dfg_range(void *vctx, mf_check *c)
{
    const gate_ctx *g = vctx;
    for (int j = 0; j < g->t->axes[1].size; ++j)
        for (int i = 0; i < g->t->axes[0].size; ++i) {
            const double *r = rec(g->t, i, j);
            double bs = r[2] + g->u * fabs(r[0]), bb = r[3] + g->u * fabs(r[1]);
            double bc = r[5] + g->u * fabs(r[4]);
            double v = fmax(fmax(fmax(0.0, -r[0] - bs), fmax(-r[1] - bb, r[0] + r[1] - 1.0 - bs - bb)), -r[4] - bc);
            mf_check_recordf(c, v, "texel (%d, %d)", i, j);
        }
}

#define DFG_REF_SAMPLES 3 /* per axis: the reference takes ~0.1 to 5 s per point */
#define REF_TOL 1e-10
#define REF_SLACK 1e-10 /* the reference's own tolerance, with a margin */

/* |stored - reference| / (stored bound + REF_SLACK) at a DFG_REF_SAMPLES^2 sample of texels (both
 * ends of each axis included): the bias against the reference with Schlick F0 = 0, scale + bias
 * against F = 1. */
static void dfg_reference(void *vctx, mf_check *c)
{
    const gate_ctx *g = vctx;
    int nm = g->t->axes[0].size, nr = g->t->axes[1].size;
    for (int b = 0; b < DFG_REF_SAMPLES; ++b)
        for (int a = 0; a < DFG_REF_SAMPLES; ++a) {
            int i = (int)((long)a * (nm - 1) / (DFG_REF_SAMPLES - 1)), j = (int)((long)b * (nr - 1) / (DFG_REF_SAMPLES - 1));
            const double *r = rec(g->t, i, j);
            double alpha = texel_alpha(g->t, j), mu = texel_mu(g->t, i);
            mf_microfacet m1 = {mf_ndf_make(g->ndf, alpha, alpha), g->g2, {MF_FRESNEL_NONE, 0.0, 0.0, 0.0}};
            mf_microfacet m0 = {mf_ndf_make(g->ndf, alpha, alpha), g->g2, {MF_FRESNEL_SCHLICK, 0.0, 0.0, 0.0}};
            mf_result q1, q0;
            /* an adaptive rule that ran out of intervals still returns its estimate: its error
             * estimate then joins the slack */
            mf_status s1 = mf_albedo_microfacet_reference(&m1, view(mu), REF_TOL, &q1);
            mf_status s0 = mf_albedo_microfacet_reference(&m0, view(mu), REF_TOL, &q0);
            if ((s1 != MF_OK && s1 != MF_ERR_NO_CONVERGENCE) || (s0 != MF_OK && s0 != MF_ERR_NO_CONVERGENCE)) {
                mf_check_fail(c, "the reference quadrature failed");
                continue;
            }
            double bs = r[2] + g->u * fabs(r[0]), bb = r[3] + g->u * fabs(r[1]);
            double v1 = fabs(r[0] + r[1] - q1.val) / (bs + bb + REF_SLACK + (s1 != MF_OK ? q1.err : 0.0));
            double v0 = fabs(r[1] - q0.val) / (bb + REF_SLACK + (s0 != MF_OK ? q0.err : 0.0));
            mf_check_recordf(c, fmax(v0, v1), "texel (%d, %d): alpha %.6g, mu %.6g", i, j, alpha, mu);
        }
}

/* |stored - independent reference| / (stored bound + reference bound) of the Charlie channel at the
 * same DFG_REF_SAMPLES^2 texels (mf_albedo_charlie_reference: other coordinates, no shared code
 * beyond the D V product) */
static void dfg_charlie_reference(void *vctx, mf_check *c)
{
    const gate_ctx *g = vctx;
    int nm = g->t->axes[0].size, nr = g->t->axes[1].size;
    for (int b = 0; b < DFG_REF_SAMPLES; ++b)
        for (int a = 0; a < DFG_REF_SAMPLES; ++a) {
            int i = (int)((long)a * (nm - 1) / (DFG_REF_SAMPLES - 1)), j = (int)((long)b * (nr - 1) / (DFG_REF_SAMPLES - 1));
            const double *r = rec(g->t, i, j);
            double alpha = texel_alpha(g->t, j), mu = texel_mu(g->t, i);
            mf_result q;
            mf_status s = mf_albedo_charlie_reference(alpha, mu, REF_TOL, &q);
            if (s != MF_OK && s != MF_ERR_NO_CONVERGENCE) {
                mf_check_fail(c, "the reference quadrature failed");
                continue;
            }
            double v = fabs(r[4] - q.val) / (r[5] + g->u * fabs(r[4]) + q.err);
            mf_check_recordf(c, v, "texel (%d, %d): alpha %.6g, mu %.6g", i, j, alpha, mu);
        }
}

/* |E(mu_o) + (1 - E(mu_o)) (1 - E_avg') / (1 - E_avg) - 1| / bound at every texel, E_avg' recomputed
 * by 16-point Gauss-Legendre in s = sqrt(mu) on [0, 1/3, 2/3, 1] (nodes unlike the table's) */
static void kc_furnace(void *vctx, mf_check *c)
{
    const gate_ctx *g = vctx;
    double x[16], w[16];
    if (mf_quad_gauss_legendre(16, x, w) != MF_OK) {
        mf_check_fail(c, "no Gauss-Legendre rule");
        return;
    }
    for (int j = 0; j < g->t->axes[1].size; ++j) {
        double alpha = texel_alpha(g->t, j), avg = 0.0, avg_b = 0.0;
        for (int p = 0; p < 3; ++p)
            for (int k = 0; k < 16; ++k) {
                double s = (p + 0.5 * (1.0 + x[k])) / 3.0, wt = 0.5 * w[k] / 3.0 * 4.0 * s * s * s;
                mf_result e;
                if (mf_energy_e(g->ndf, g->g2, alpha, s * s, &e) != MF_OK) {
                    mf_check_fail(c, "albedo failed");
                    return;
                }
                avg += wt * e.val;
                avg_b += wt * e.err;
            }
        for (int i = 0; i < g->t->axes[0].size; ++i) {
            const double *r = rec(g->t, i, j);
            double e = r[0], ea = r[2];
            double total = e + (1.0 - e) * (1.0 - avg) / (1.0 - ea);
            /* first-order propagation of the bounds of E, E_avg, E_avg' (and of the 16-point rule:
             * its difference from the table's 12-point one is within r[3] by construction) */
            double be = r[1] + g->u * fabs(e), bea = r[3] + g->u * fabs(ea);
            double bound = be + (1.0 - e) * (avg_b + bea + 1e-12) / (1.0 - ea) * (1.0 + (1.0 - avg) / (1.0 - ea));
            /* E_avg >= 1 leaves no energy to compensate: the lobe is undefined, a failure */
            double v = (ea < 1.0 && bound >= 0.0) ? fabs(total - 1.0) / (bound + 1e-13) : INFINITY;
            mf_check_recordf(c, v, "texel (%d, %d): alpha %.6g, 1 - total %.3g", i,
                             j, alpha, 1.0 - total);
        }
    }
}

const mf_check_def mf_energy_dfg_checks[] = {
    {"dfg_finite", "number of NaN or infinite fields per texel", 0.0, 0, check_finite},
    {"dfg_range", "how far scale, bias, charlie >= 0 and scale + bias <= 1 are violated beyond the stored bounds", 0.0, 0,
     dfg_range},
    {"dfg_reference", "|stored - independent nested Gauss-Kronrod| / (stored bound + 1e-10), 9 texels", 1.0, 0,
     dfg_reference},
    {"dfg_charlie_ref", "|stored Charlie - independent nested Gauss-Kronrod in wi| / (both bounds), 9 texels", 1.0, 0,
     dfg_charlie_reference},
};
const int mf_energy_dfg_nchecks = MF_ENERGY_DFG_NCHECKS;

const mf_check_def mf_energy_kulla_conty_checks[] = {
    {"kc_finite", "number of NaN or infinite fields per texel", 0.0, 0, check_finite},
    {"kc_furnace", "|1 - (E + compensation lobe) with F = 1| / its propagated bound (white furnace)", 1.0, 0,
     kc_furnace},
};
const int mf_energy_kulla_conty_nchecks = 2;

/* Runs the n checks defs of an energy table of the given kind. */
static mf_status run_gate(const mf_table *t, const char *kind, const mf_check_def *defs, int n, double storage_u,
                          mf_check *checks, int cap, int *count)
{
    if (count)
        *count = 0;
    gate_ctx g;
    if (gate_setup(t, kind, &g) != 0)
        return MF_ERR_DOMAIN;
    g.u = storage_u > 0.0 ? storage_u : 0.0;
    g.avgs = NULL;
    return mf_check_run_defs(defs, n, &g, 0, checks, cap, count);
}

mf_status mf_energy_dfg_gate(const mf_table *t, double storage_u, mf_check *checks, int cap, int *count)
{
    return run_gate(t, "dfg", mf_energy_dfg_checks, mf_energy_dfg_nchecks, storage_u, checks, cap, count);
}

mf_status mf_energy_kulla_conty_gate(const mf_table *t, double storage_u, mf_check *checks, int cap, int *count)
{
    return run_gate(t, "kulla_conty", mf_energy_kulla_conty_checks, mf_energy_kulla_conty_nchecks, storage_u, checks,
                    cap, count);
}

/* ---- the rough dielectric: E_R, E_T over (mu, alpha, eta) and its E_avg -------------------- */

const char *const mf_dielectric_table_fields[MF_DIELECTRIC_WALK_NFIELDS] = {
    "E_r", "E_r_err", "E_t", "E_t_err", "E", "E_avg", "E_avg_err",
    "E_r_inv", "E_r_inv_err", "E_t_inv", "E_t_inv_err", "E_inv", "E_avg_inv", "E_avg_inv_err",
    "t_walk", "t_walk_se", "t_walk_inv", "t_walk_inv_se", "t_split", "t_split_inv"};

/* the walk split's fields, after the 14 */
enum { WF_T = MF_DIELECTRIC_NFIELDS, WF_SE, WF_T_INV, WF_SE_INV, WF_SPLIT, WF_SPLIT_INV };

double mf_energy_dielectric_eta(double z) { return 1.0 + 2.0 * z * z; }

static int diel_args_ok(mf_ndf_type ndf, mf_g2_form g2, double alpha, double eta)
{
    return args_ok(ndf, g2, alpha, 1.0) && eta > 0.0 && isfinite(eta);
}

/* E = E_R + E_T at mu (bound: the sum of both bounds). */
static mf_status diel_total(mf_ndf_type ndf, mf_g2_form g2, double alpha, double mu, double eta, mf_result *e)
{
    mf_result r, t;
    mf_status st = mf_albedo_dielectric(mf_ndf_make(ndf, alpha, alpha), g2, mu, eta, &r, &t);
    e->val = r.val + t.val;
    e->err = r.err + t.err;
    return st;
}

/* The kinks of E(mu) in (0, 1) as panel ends (ascending, with 0 and 1), in mu, for eta < 1: where the
 * domain of the integrand changes its shape.  With beta_c = asin(eta) the critical angle's cone about
 * wo (wo.h > sqrt(1 - eta^2) transmits): it reaches the normal at mu = sqrt(1 - eta^2); it touches
 * the horizon of h at mu = eta; and its reflected cone (angle 2 beta_c about wo) touches the horizon
 * of wi at mu = sin(2 beta_c) = 2 eta sqrt(1 - eta^2) (measured on a 400-point second difference of
 * E at alpha 0.77, eta 0.6: kinks at mu 0.6 and 0.96, nothing else away from 0). */
static int diel_panels(double eta, double *bp)
{
    int n = 0;
    bp[n++] = 0.0;
    if (eta < 1.0) {
        double mc = sqrt((1.0 - eta) * (1.0 + eta)), k[3] = {eta, mc, 2.0 * eta * mc};
        for (int i = 0; i < 3; ++i)
            if (k[i] > 1e-6 && k[i] < 1.0 - 1e-9)
                bp[n++] = k[i];
        qsort(bp, (size_t)n, sizeof bp[0], cmp_dbl);
        int m = 1; /* drop repeats (eta = 1/sqrt 2 gives 2 eta mc = 1) */
        for (int i = 1; i < n; ++i)
            if (bp[i] > bp[m - 1])
                bp[m++] = bp[i];
        n = m;
    }
    bp[n++] = 1.0;
    return n;
}

typedef struct {
    mf_ndf_type ndf;
    mf_g2_form g2;
    double alpha, eta, max_err;
    int smooth, failed; /* the map of the current panel: smooth (cubic) or one-sided square */
    double org, len;    /* the panel (smooth: [org, org + len]) or the kink it is mapped towards */
    int dir;            /* one-sided: mu = org + dir u^2 */
    int trans_only;     /* integrate E_t alone instead of E = E_r + E_t */
} eavg_ctx;

/* the integrand of E_avg = int 2 mu E(mu) dmu in the panel's variable:
 *   smooth:    mu = org + len (3 t^2 - 2 t^3), t in [0, 1], dmu = 6 len t (1 - t) dt (flat at both ends,
 *              so (mu - kink)^(k/2) at either end becomes a polynomial in t);
 *   one-sided: mu = org + dir u^2, dmu = 2 u du (flat at the kink org). */
static double eavg_f(double x, void *user)
{
    eavg_ctx *c = user;
    double mu, w;
    if (c->smooth) {
        mu = c->org + c->len * (x * x * (3.0 - 2.0 * x));
        w = 6.0 * c->len * x * (1.0 - x);
    } else {
        mu = c->org + c->dir * x * x;
        w = 2.0 * x;
    }
    if (!(mu > 0.0) || !(w > 0.0))
        return 0.0;
    mf_result e, r;
    if (c->trans_only ? mf_albedo_dielectric(mf_ndf_make(c->ndf, c->alpha, c->alpha), c->g2, fmin(mu, 1.0), c->eta, &r, &e)
                      : diel_total(c->ndf, c->g2, c->alpha, fmin(mu, 1.0), c->eta, &e)) {
        c->failed = 1;
        return NAN;
    }
    if (e.err > c->max_err)
        c->max_err = e.err;
    return 2.0 * mu * w * e.val;
}

/* E_avg by global-adaptive Gauss-Kronrod (mf_quad_adaptive, |K15 - G7| per interval) on the panels
 * of diel_panels (E(mu) has kinks of half-integer powers there and a square root at mu = 0):
 * smooth = 0 (the table's rule) cuts each panel at its middle and maps each half with a square
 * towards its kink, which E is smooth in (measured: one K15 per half, |K15 - G7| <= 1.1e-10, at
 * alpha 0.25, eta 0.47 and alpha 0.77, eta 0.6, where the adaptive rule in sqrt(mu) on the same
 * panels took 150 points and the whole panel under the cubic map also 150); smooth = 1 (the gate's
 * independent recomputation, other nodes) maps each panel whole with the cubic map.  err = the
 * rules' estimates + the largest albedo bound met (the weight 2 mu integrates to 1). */
static mf_status diel_avg_adaptive(mf_ndf_type ndf, mf_g2_form g2, double alpha, double eta, int smooth, int trans_only,
                                   double tol, double *val, double *bound)
{
    double bp[5];
    int nb = diel_panels(eta, bp);
    eavg_ctx c = {ndf, g2, alpha, eta, 0.0, smooth, 0, 0.0, 0.0, 0, trans_only};
    double sum = 0.0, err = 0.0;
    int pieces = smooth ? nb - 1 : 2 * (nb - 1);
    for (int p = 0; p + 1 < nb; ++p)
        for (int h = 0; h < (smooth ? 1 : 2); ++h) {
            double len = bp[p + 1] - bp[p], hi;
            if (smooth)
                c.org = bp[p], c.len = len, hi = 1.0;
            else
                c.org = h ? bp[p + 1] : bp[p], c.dir = h ? -1 : 1, hi = sqrt(0.5 * len);
            mf_result q;
            mf_status st = mf_quad_adaptive(eavg_f, &c, 0.0, hi, tol / pieces, 0.0, 200, &q);
            if (c.failed || (st != MF_OK && st != MF_ERR_NO_CONVERGENCE))
                return c.failed ? MF_ERR_INTERNAL : st;
            sum += q.val;
            err += q.err;
        }
    *val = sum;
    *bound = err + c.max_err;
    return MF_OK;
}

static mf_status diel_eavg_adaptive(mf_ndf_type ndf, mf_g2_form g2, double alpha, double eta, int smooth, double tol,
                                    double *val, double *bound)
{
    return diel_avg_adaptive(ndf, g2, alpha, eta, smooth, 0, tol, val, bound);
}

#define DIEL_EAVG_TOL 1e-8

mf_status mf_energy_dielectric_eavg(mf_ndf_type ndf, mf_g2_form g2, double alpha, double eta, mf_result *eavg)
{
    eavg->val = eavg->err = NAN;
    if (!diel_args_ok(ndf, g2, alpha, eta))
        return MF_ERR_DOMAIN;
    return diel_eavg_adaptive(ndf, g2, alpha, eta, 0, DIEL_EAVG_TOL, &eavg->val, &eavg->err);
}

mf_status mf_energy_dielectric_table_init(mf_table *t, mf_ndf_type ndf, mf_g2_form g2, int n_mu, int n_r, int n_z)
{
    memset(t, 0, sizeof *t);
    if (n_mu < 2 || n_r < 2 || n_z < 2 || n_mu > 1024 || n_r > 1024 || n_z > 1024
        || (ndf != MF_NDF_GGX && ndf != MF_NDF_BECKMANN) || (g2 != MF_G2_JOINT && g2 != MF_G2_SEPARABLE))
        return MF_ERR_DOMAIN;
    mf_table_axis ax[3];
    memset(ax, 0, sizeof ax);
    const char *names[3] = {"mu", "r", "z"}, *phys[3] = {"cos_theta_o", "alpha", "eta_z"};
    int n[3] = {n_mu, n_r, n_z};
    for (int a = 0; a < 3; ++a) {
        snprintf(ax[a].name, sizeof ax[a].name, "%s", names[a]);
        snprintf(ax[a].physical, sizeof ax[a].physical, "%s", phys[a]);
        ax[a].size = n[a];
        ax[a].lo = 0.5 / n[a];
        ax[a].hi = 1.0 - 0.5 / n[a];
        ax[a].mapping = MF_AXIS_IDENTITY;
        ax[a].physical_min = -INFINITY;
    }
    ax[1].mapping = MF_AXIS_SQUARE;
    ax[1].physical_min = MF_ENERGY_ALPHA_MIN;
    mf_status st = mf_table_create(t, 3, ax, MF_DIELECTRIC_NFIELDS, mf_dielectric_table_fields);
    if (st != MF_OK)
        return st;
    const mf_table_kind *k = mf_table_kind_find("dielectric");
    if (!k || mf_table_kind_tag(t, k) != MF_OK || mf_table_set_meta(t, "ndf", mf_ndf_type_name(ndf)) != MF_OK
        || mf_table_set_meta(t, "g2", g2 == MF_G2_JOINT ? "joint" : "separable") != MF_OK
        || mf_table_set_meta(t, "eta", "eta = 1 + 2 z^2 (outside: view in the medium of index 1); the _inv fields "
                                       "are at 1 / eta (inside)") != MF_OK) {
        mf_table_free(t);
        return MF_ERR_INTERNAL;
    }
    return MF_OK;
}

static double axis_value(const mf_table *t, int a, int i)
{
    return mf_table_axis_physical(&t->axes[a], mf_table_axis_param(&t->axes[a], i));
}

static mf_status diel_gate_setup_kind(const mf_table *t, mf_ndf_type *ndf, mf_g2_form *g2);
static mf_status diel_walk_meta(const mf_table *t, long *walks, unsigned long long *seed);

mf_status mf_energy_dielectric_column(mf_table *t, long column)
{
    mf_ndf_type ndf;
    mf_g2_form g2;
    if (!t || !t->data || t->naxes != 3 || diel_gate_setup_kind(t, &ndf, &g2) != MF_OK)
        return MF_ERR_DOMAIN;
    int n_mu = t->axes[0].size, n_r = t->axes[1].size, n_z = t->axes[2].size;
    if (column < 0 || column >= (long)n_r * n_z)
        return MF_ERR_DOMAIN;
    int j = (int)(column % n_r), k = (int)(column / n_r);
    double alpha = axis_value(t, 1, j), eta = mf_energy_dielectric_eta(axis_value(t, 2, k));
    for (int side = 0; side < 2; ++side) {
        double e = side ? 1.0 / eta : eta;
        mf_result avg;
        mf_status st = mf_energy_dielectric_eavg(ndf, g2, alpha, e, &avg);
        if (st != MF_OK)
            return st;
        for (int i = 0; i < n_mu; ++i) {
            mf_result r, tr;
            st = mf_albedo_dielectric(mf_ndf_make(ndf, alpha, alpha), g2, axis_value(t, 0, i), e, &r, &tr);
            if (st != MF_OK)
                return st;
            double *rec = t->data + ((size_t)column * n_mu + i) * t->nfields + 7 * side;
            rec[0] = r.val, rec[1] = r.err, rec[2] = tr.val, rec[3] = tr.err, rec[4] = r.val + tr.val;
            rec[5] = avg.val, rec[6] = avg.err;
        }
    }
    if (t->nfields == MF_DIELECTRIC_WALK_NFIELDS) {
        long walks;
        unsigned long long seed;
        if (diel_walk_meta(t, &walks, &seed) != MF_OK)
            return MF_ERR_DOMAIN;
        const double *r0 = t->data + (size_t)column * n_mu * t->nfields;
        mf_result fa, fai;
        mf_energy_walk_split ws;
        mf_status st = mf_energy_favg_dielectric(eta, &fa);
        if (st == MF_OK)
            st = mf_energy_favg_dielectric(1.0 / eta, &fai);
        if (st == MF_OK)
            st = mf_energy_dielectric_walk_split(ndf, alpha, eta, r0[5], r0[12], fa.val, fai.val, walks, seed,
                                                 2u * (uint64_t)column, &ws);
        if (st != MF_OK)
            return st;
        for (int i = 0; i < n_mu; ++i) {
            double *rec = t->data + ((size_t)column * n_mu + i) * t->nfields;
            rec[WF_T] = ws.t_walk[0], rec[WF_SE] = ws.se[0], rec[WF_T_INV] = ws.t_walk[1], rec[WF_SE_INV] = ws.se[1];
            rec[WF_SPLIT] = ws.t[0], rec[WF_SPLIT_INV] = ws.t[1];
        }
    }
    return MF_OK;
}

/* ---- the split closed by the random walk ------------------------------------------------------ */

static mf_status diel_walk_meta(const mf_table *t, long *walks, unsigned long long *seed)
{
    const char *s = mf_table_get_meta(t, "split"), *w = mf_table_get_meta(t, "split_walks"),
               *d = mf_table_get_meta(t, "split_seed");
    char *end;
    if (!s || strcmp(s, "walk") || !w || !d)
        return MF_ERR_DOMAIN;
    *walks = strtol(w, &end, 10);
    if (*end || *walks < 1000)
        return MF_ERR_DOMAIN;
    *seed = strtoull(d, &end, 10);
    return *end || !*d ? MF_ERR_DOMAIN : MF_OK;
}

void mf_energy_walk_split_project(const double t_walk[2], const double se[2], double a, double b, double t[2],
                                  double *chi)
{
    /* weighted least squares of (t_walk, t_walk') on the line (lambda a, lambda b): the balanced pairs */
    double w0 = 1.0 / (se[0] * se[0]), w1 = 1.0 / (se[1] * se[1]);
    double den = w0 * a * a + w1 * b * b;
    double lam = den > 0.0 ? (w0 * a * t_walk[0] + w1 * b * t_walk[1]) / den : 0.0;
    double m = fmax(lam * a, lam * b);
    if (m > 1.0)
        lam /= m;
    t[0] = fmin(1.0, lam * a);
    t[1] = fmin(1.0, lam * b);
    if (chi)
        *chi = sqrt(w0 * (t_walk[0] - t[0]) * (t_walk[0] - t[0]) + w1 * (t_walk[1] - t[1]) * (t_walk[1] - t[1]));
}

mf_status mf_energy_dielectric_walk_split(mf_ndf_type ndf, double alpha, double eta, double eavg, double eavg_inv,
                                          double favg, double favg_inv, long walks, uint64_t seed, uint64_t stream,
                                          mf_energy_walk_split *out)
{
    memset(out, 0, sizeof *out);
    if (!diel_args_ok(ndf, MF_G2_JOINT, alpha, eta) || walks < 1)
        return MF_ERR_DOMAIN;
    double kc[2];
    mf_status st = mf_energy_dielectric_ms_split(eta, eavg, eavg_inv, favg, favg_inv, &kc[0]);
    if (st == MF_OK)
        st = mf_energy_dielectric_ms_split(1.0 / eta, eavg_inv, eavg, favg_inv, favg, &kc[1]);
    if (st != MF_OK)
        return st;
    for (int side = 0; side < 2; ++side) {
        mf_walk_split w;
        /* 100000 bounces: a cut walk is counted (out->stopped) and none was met in the study */
        st = mf_walk_dielectric_split(mf_ndf_make(ndf, alpha, alpha), side ? 1.0 / eta : eta, walks, 100000, seed,
                                      stream + (uint64_t)side, &w);
        if (st != MF_OK)
            return st;
        out->ms[side] = w.ms;
        out->stopped += w.stopped;
        out->e1[side] = w.e1;
        out->t_walk[side] = w.ms > 0 ? w.t : kc[side];
        out->se[side] = w.ms > 0 ? w.t_se : 0.5;
    }
    double a = eta * eta * fmax(0.0, 1.0 - eavg_inv), b = fmax(0.0, 1.0 - eavg);
    if (!(a + b > 0.0)) { /* no compensation energy on either side: nothing to split */
        out->t[0] = kc[0], out->t[1] = kc[1], out->chi = 0.0;
        return MF_OK;
    }
    mf_energy_walk_split_project(out->t_walk, out->se, a, b, out->t, &out->chi);
    return MF_OK;
}

mf_status mf_energy_dielectric_table_init_walk(mf_table *t, mf_ndf_type ndf, mf_g2_form g2, int n_mu, int n_r,
                                               int n_z, long walks)
{
    memset(t, 0, sizeof *t);
    if (walks < 1000 || walks > 1000000000L)
        return MF_ERR_DOMAIN;
    mf_table tmp;
    mf_status st = mf_energy_dielectric_table_init(&tmp, ndf, g2, n_mu, n_r, n_z);
    if (st != MF_OK)
        return st;
    mf_table_axis ax[3];
    for (int a = 0; a < 3; ++a)
        ax[a] = tmp.axes[a];
    st = mf_table_create(t, 3, ax, MF_DIELECTRIC_WALK_NFIELDS, mf_dielectric_table_fields);
    char w[32], sd[32];
    snprintf(w, sizeof w, "%ld", walks);
    snprintf(sd, sizeof sd, "%u", MF_ENERGY_WALK_SPLIT_SEED);
    const mf_table_kind *k = mf_table_kind_find("dielectric");
    for (int i = 0; st == MF_OK && i < tmp.nmeta; ++i)
        st = mf_table_set_meta(t, tmp.meta[i].key, tmp.meta[i].value);
    if (st == MF_OK && (!k || mf_table_kind_tag(t, k) != MF_OK || mf_table_set_meta(t, "split", "walk") != MF_OK
                        || mf_table_set_meta(t, "split_walks", w) != MF_OK || mf_table_set_meta(t, "split_seed", sd) != MF_OK
                        || mf_table_set_meta(t, "split_fields", "t_walk(_inv): the walk's transmitted fraction of its multiple "
                                             "scattering (_se: std. error; 0.5: no data, Kulla-Conty's); t_split(_inv): the "
                                             "balanced closure") != MF_OK))
        st = MF_ERR_INTERNAL;
    mf_table_free(&tmp);
    if (st != MF_OK)
        mf_table_free(t);
    return st;
}

mf_status mf_energy_dielectric_table(mf_table *t, mf_ndf_type ndf, mf_g2_form g2, int n_mu, int n_r, int n_z,
                                     mf_energy_progress progress, void *user)
{
    mf_status st = mf_energy_dielectric_table_init(t, ndf, g2, n_mu, n_r, n_z);
    if (st != MF_OK)
        return st;
    long total = (long)n_r * n_z;
    for (long c = 0; c < total; ++c) {
        st = mf_energy_dielectric_column(t, c);
        if (st != MF_OK) {
            mf_table_free(t);
            return st;
        }
        if (progress)
            progress(user, c + 1, total);
    }
    return MF_OK;
}

/* ---- independent reference of E_T: nested adaptive Gauss-Kronrod over the transmitted direction */

/* E_T = int over wt (wt.z < 0) of D(h) (1 - F(wo.h)) G2(wo, wt) (wo.h) / wo.z J dwt with the
 * refraction half vector h = -(wo + eta wt) / |.| (oriented up) and its Jacobian
 * J = dh / dwt = eta^2 |wt.h| / (wo.h + eta wt.h)^2 [Walter 2007, Eq. 16, 17]: the integrand of
 * mf_albedo_dielectric in the other variable (wt, not h), so the two share only D, F, Lambda. */
typedef struct {
    mf_ndf ndf;
    mf_g2_form g2;
    mf_vec3 wo;
    double eta, lambda_o, phi, tol_in, peak, alpha;
    int fail;
} tref_ctx;

static double tref_point(const tref_ctx *c, double th) /* th: polar angle of wt from -z */
{
    double st = sin(th), ct = cos(th);
    mf_vec3 wt = mf_vec3_make(st * cos(c->phi), st * sin(c->phi), -ct);
    mf_vec3 h = mf_vec3_make(-(c->wo.x + c->eta * wt.x), -(c->wo.y + c->eta * wt.y), -(c->wo.z + c->eta * wt.z));
    double len = sqrt(h.x * h.x + h.y * h.y + h.z * h.z);
    if (!(len > 0.0))
        return 0.0;
    double sg = h.z < 0.0 ? -1.0 : 1.0;
    h = mf_vec3_make(sg * h.x / len, sg * h.y / len, sg * h.z / len);
    double oh = c->wo.x * h.x + c->wo.y * h.y + c->wo.z * h.z, th_ = wt.x * h.x + wt.y * h.y + wt.z * h.z;
    if (!(oh > 0.0) || !(th_ < 0.0) || !(h.z > 0.0))
        return 0.0;
    double F = mf_fresnel_dielectric(c->eta, oh);
    if (!(F < 1.0))
        return 0.0;
    double lt = mf_smith_lambda(c->ndf, mf_vec3_make(wt.x, wt.y, -wt.z));
    double g2 = c->g2 == MF_G2_SEPARABLE ? 1.0 / ((1.0 + c->lambda_o) * (1.0 + lt)) : 1.0 / (1.0 + c->lambda_o + lt);
    double den = oh + c->eta * th_;
    double J = c->eta * c->eta * fabs(th_) / (den * den);
    return mf_ndf_d(c->ndf, h) * (1.0 - F) * g2 * oh / c->wo.z * J * st;
}

static double tref_inner_f(double th, void *user) { return tref_point(user, th); }

/* breakpoints of [a, b] at x0 +- w 2^j (inside), sorted, ends included */
static int graded_around(double a, double b, double x0, double w, double *bp, int cap)
{
    int n = 0;
    bp[n++] = a;
    if (x0 > a && x0 < b)
        bp[n++] = x0;
    for (double d = w; d < b - a && n + 2 < cap - 1; d *= 2.0) {
        if (x0 - d > a)
            bp[n++] = x0 - d;
        if (x0 + d < b)
            bp[n++] = x0 + d;
    }
    /* and a uniform mesh of 16 panels, so that no feature narrower than the rules' node spacing
     * away from x0 hides between the first nodes (measured without it: E_t 2.1e-6 low at alpha
     * 0.5625, mu 0.25, eta 1/1.125, the rule converged to the wrong value) */
    for (int u = 1; u < 16 && n < cap - 1; ++u)
        bp[n++] = a + (b - a) * u / 16.0;
    bp[n++] = b;
    qsort(bp, (size_t)n, sizeof bp[0], cmp_dbl);
    return n;
}

static double tref_outer_f(double phi, void *user)
{
    tref_ctx *c = user;
    c->phi = phi;
    double bp[120], sum = 0.0;
    int nb = graded_around(0.0, 0.5 * MF_PI, c->peak, 0.25 * c->alpha, bp, 120);
    for (int i = 0; i + 1 < nb; ++i) {
        mf_result q;
        mf_status st = mf_quad_adaptive(tref_inner_f, c, bp[i], bp[i + 1], c->tol_in / nb, 0.0, MF_QUAD_MAX_INTERVALS, &q);
        if (st != MF_OK)
            c->fail = 1;
        sum += q.val;
    }
    return sum;
}

mf_status mf_energy_dielectric_transmission_reference(mf_ndf ndf, mf_g2_form g2, double mu, double eta, double tol,
                                                      mf_result *out)
{
    out->val = out->err = NAN;
    if (!mf_ndf_valid(ndf) || ndf.alpha_x != ndf.alpha_y || (g2 != MF_G2_JOINT && g2 != MF_G2_SEPARABLE)
        || !(mu > 0.0 && mu <= 1.0) || !(eta > 0.0) || !isfinite(eta) || !(tol > 0.0))
        return MF_ERR_DOMAIN;
    tref_ctx c;
    c.ndf = ndf;
    c.g2 = g2;
    c.wo = mf_vec3_make(sqrt(fmax(0.0, 1.0 - mu * mu)), 0.0, mu);
    c.eta = eta;
    c.lambda_o = mf_smith_lambda(ndf, c.wo);
    c.alpha = ndf.alpha_x;
    c.fail = 0;
    /* the smooth refraction (h = n): sin theta_t = sin theta_o / eta, at phi = pi; beyond the
     * critical angle the lobe hugs the horizon */
    double s = c.wo.x / eta;
    c.peak = s < 1.0 ? asin(s) : 0.5 * MF_PI;
    /* the outer integral over phi in [0, pi] (symmetric: x 2) adds at most pi tol_in */
    c.tol_in = tol / (4.0 * MF_PI);
    double bp[120], sum = 0.0, err = 0.0;
    int nb = graded_around(0.0, MF_PI, MF_PI, 0.25 * c.alpha, bp, 120);
    for (int i = 0; i + 1 < nb; ++i) {
        mf_result q;
        mf_status st = mf_quad_adaptive(tref_outer_f, &c, bp[i], bp[i + 1], 0.25 * tol / nb, 0.0, MF_QUAD_MAX_INTERVALS, &q);
        if (st != MF_OK)
            c.fail = 1;
        sum += q.val;
        err += q.err;
    }
    out->val = 2.0 * sum;
    out->err = 2.0 * err + 0.5 * tol + 1e-13 * fabs(out->val);
    return c.fail ? MF_ERR_NO_CONVERGENCE : MF_OK;
}

/* ---- independent reference of E_R and E_T: micro-normal angles about wo, every kink a panel end - */

/* The micro-normal h in polar angles (beta, psi) about wo = (s, 0, c) itself, not about the normal:
 *   h = cos(beta) wo + sin(beta) (cos(psi) e1 + sin(psi) e2),  e1 = (c, 0, -s), e2 = (0, 1, 0),
 * dh = sin(beta) dbeta dpsi, wo.h = cos(beta).  Then the Fresnel factor depends on beta alone, and its
 * kink, total internal reflection at wo.h = sqrt(1 - eta^2) (eta < 1), is the constant line
 * beta_c = asin(eta).  The other kinks are curves known in closed form or as roots on each psi:
 *   h.z = c cos(beta) - s sin(beta) cos(psi) = 0   at beta_h(psi) = atan2(c, s cos psi)  (GGX's D jumps),
 *   wi.z = c cos(2 beta) - s sin(2 beta) cos(psi) = 0 at beta_k(psi) = beta_h(psi) / 2  (end of E_R),
 *   wt.z = 0 (end of E_T; for eta < 1 only), the roots of a 64-point scan, bisected to the last bit.
 * E_R = int D(h) F(wo.h) G2(wo, wi) (wo.h) / wo.z dh and E_T = the same with 1 - F and G2(wo, wt
 * mirrored) [Walter 2007, Eq. 14, 17, 20, 21], the forms of mf_albedo_dielectric, in other coordinates,
 * through the library's D, Lambda, G2 and Fresnel (mf_ndf_d, mf_smith_g2, mf_fresnel_dielectric).
 * Inner (beta) panels end on beta_c, beta_k, min(beta_h, pi/2) and the wt.z roots, graded around the
 * peak of D on the ray (beta_0 = atan2(-s cos psi, c) when > 0); beside beta_c the transmitted side
 * has 1 - F ~ sqrt(beta_c - beta), so that panel is integrated in u with beta = beta_c - u^2 (smooth).
 * Outer (psi) panels end wherever the order of these curves on a ray changes (found on a 512-point
 * scan, bisected), at pi/2 (where beta_h crosses pi/2) and graded towards psi = pi (the peak of D at
 * h = n); a panel beside such an event is integrated in u with psi = event +- u^2, since the inner
 * integral has half-integer powers of the distance there.  Nested mf_quad_adaptive (QK21). */
typedef struct {
    mf_ndf ndf;
    mf_g2_form g2;
    mf_vec3 wo;
    double s, c, eta, bc; /* bc: beta_c, or pi/2 when eta >= 1 (no total internal reflection) */
    int trans;            /* 0: E_R, 1: E_T */
    double cps, sps;      /* the current psi */
    double pa, pb;        /* the current panel, and its map: 0 beta itself, 1 beta = pb - u^2, */
    int map;              /*   -1 beta = pa + u^2 */
    double tol_in;        /* inner tolerance per unit psi */
    int fail;
} dref_ctx;

static mf_vec3 dref_h(const dref_ctx *r, double beta)
{
    double cb = cos(beta), sb = sin(beta);
    return mf_vec3_make(cb * r->s + sb * r->cps * r->c, sb * r->sps, cb * r->c - sb * r->cps * r->s);
}

/* wt.z of the refraction through h(beta) (NaN where there is none) */
static double dref_wtz(const dref_ctx *r, double beta)
{
    double cb = cos(beta), sb = sin(beta), ct2 = (r->eta - sb) * (r->eta + sb);
    if (!(ct2 > 0.0) || !(cb > 0.0))
        return NAN;
    mf_vec3 h = dref_h(r, beta);
    double k = (cb - sqrt(ct2)) / r->eta;
    return -r->c / r->eta + k * h.z;
}

static double dref_point(const dref_ctx *r, double beta)
{
    double cb = cos(beta), sb = sin(beta);
    mf_vec3 h = dref_h(r, beta);
    if (!(cb > 0.0) || !(h.z > 0.0))
        return 0.0;
    double F = mf_fresnel_dielectric(r->eta, cb);
    double base = mf_ndf_d(r->ndf, h) * cb / r->c * sb;
    if (!r->trans) {
        mf_vec3 wi = mf_vec3_make(2.0 * cb * h.x - r->wo.x, 2.0 * cb * h.y, 2.0 * cb * h.z - r->c);
        if (!(wi.z > 0.0))
            return 0.0;
        return base * F * mf_smith_g2(r->ndf, r->g2, r->wo, wi);
    }
    double ct2 = (r->eta - sb) * (r->eta + sb);
    if (!(F < 1.0) || !(ct2 > 0.0))
        return 0.0;
    double k = (cb - sqrt(ct2)) / r->eta;
    mf_vec3 wt = mf_vec3_make(-r->wo.x / r->eta + k * h.x, k * h.y, -r->c / r->eta + k * h.z);
    if (!(wt.z < 0.0))
        return 0.0;
    return base * (1.0 - F) * mf_smith_g2(r->ndf, r->g2, r->wo, mf_vec3_make(wt.x, wt.y, -wt.z));
}

static double dref_inner_f(double u, void *user)
{
    const dref_ctx *r = user;
    if (r->map == 0)
        return dref_point(r, u);
    double b = r->map > 0 ? r->pb - u * u : r->pa + u * u;
    return 2.0 * u * dref_point(r, b);
}

/* the kinks on the ray psi: beta_c (label 1), beta_k (2), beta_h (3) or pi/2 (4), wt.z roots (5);
 * returns the count, values ascending with their labels */
static int dref_kinks(const dref_ctx *r, double *v, int *lab)
{
    int n = 0;
    double bh = atan2(r->c, r->s * r->cps);
    if (r->bc < 0.5 * MF_PI)
        v[n] = r->bc, lab[n++] = 1;
    v[n] = 0.5 * bh, lab[n++] = 2;
    if (bh < 0.5 * MF_PI)
        v[n] = bh, lab[n++] = 3;
    else
        v[n] = 0.5 * MF_PI, lab[n++] = 4;
    if (r->eta < 1.0) {
        double end = fmin(r->bc, fmin(bh, 0.5 * MF_PI)), prev = dref_wtz(r, 0.0);
        for (int i = 1; i <= 64 && n < 12; ++i) {
            double a = end * (i - 1) / 64.0, b = end * i / 64.0, fb = dref_wtz(r, b);
            /* on the critical angle itself there is no refraction (NaN): take the sign just inside,
             * or a root in the last cell is missed (measured: E_t 4.3e-10 high at alpha 0.0625,
             * mu 0.8, eta 0.47, where the root on the rays near psi = pi is within 7e-3 of beta_c) */
            if (i == 64 && isnan(fb))
                fb = dref_wtz(r, end - 1e-9 * end);
            /* only between transmitting points: the end on the critical angle is no root */
            if (!isnan(prev) && !isnan(fb) && (prev < 0.0) != (fb < 0.0)) {
                double lo = a, hi = b, flo = prev;
                for (int it = 0; it < 64; ++it) {
                    double mid = 0.5 * (lo + hi), fm = dref_wtz(r, mid);
                    if (!(mid > lo && mid < hi) || isnan(fm))
                        break;
                    if ((fm < 0.0) == (flo < 0.0))
                        lo = mid, flo = fm;
                    else
                        hi = mid;
                }
                v[n] = 0.5 * (lo + hi), lab[n++] = 5;
            }
            prev = fb;
        }
    }
    for (int i = 1; i < n; ++i) /* insertion sort, carrying the labels */
        for (int j = i; j > 0 && v[j] < v[j - 1]; --j) {
            double t = v[j];
            v[j] = v[j - 1], v[j - 1] = t;
            int l = lab[j];
            lab[j] = lab[j - 1], lab[j - 1] = l;
        }
    return n;
}

static unsigned long long dref_signature(dref_ctx *r, double psi)
{
    r->cps = cos(psi), r->sps = sin(psi);
    double v[16];
    int lab[16], n = dref_kinks(r, v, lab);
    unsigned long long sig = 0;
    for (int i = 0; i < n; ++i)
        sig = sig * 8u + (unsigned)lab[i];
    return sig;
}

static double dref_outer_at(dref_ctx *r, double psi)
{
    r->cps = cos(psi), r->sps = sin(psi);
    double v[16], bp[128];
    int lab[16], nk = dref_kinks(r, v, lab);
    /* the end of the integrand on this ray: E_R ends on beta_k, E_T on min(beta_c, beta_h, pi/2) */
    double bh = atan2(r->c, r->s * r->cps);
    double end = r->trans ? fmin(r->bc, fmin(bh, 0.5 * MF_PI)) : 0.5 * bh;
    int nb = 0;
    bp[nb++] = 0.0;
    for (int i = 0; i < nk; ++i)
        if (v[i] > 0.0 && v[i] < end)
            bp[nb++] = v[i];
    /* graded around the peak of D on this ray, beta_0, down to alpha / 4 */
    double b0 = fmax(0.0, atan2(-r->s * r->cps, r->c)), w = 0.25 * r->ndf.alpha_x;
    if (b0 > 0.0 && b0 < end)
        bp[nb++] = b0;
    for (double d = w; d < end && nb < 120; d *= 2.0) {
        if (b0 - d > 0.0 && b0 - d < end)
            bp[nb++] = b0 - d;
        if (b0 + d < end)
            bp[nb++] = b0 + d;
    }
    bp[nb++] = end;
    qsort(bp, (size_t)nb, sizeof bp[0], cmp_dbl);
    double sum = 0.0;
    for (int i = 0; i + 1 < nb; ++i) {
        if (!(bp[i + 1] > bp[i]))
            continue;
        r->pa = bp[i], r->pb = bp[i + 1];
        /* the transmitted side of the critical angle: 1 - F ~ sqrt(beta_c - beta) */
        r->map = (r->eta < 1.0 && bp[i + 1] == r->bc) ? 1 : 0;
        double a = r->map ? 0.0 : bp[i], b = r->map ? sqrt(bp[i + 1] - bp[i]) : bp[i + 1];
        mf_result q;
        if (mf_quad_adaptive(dref_inner_f, r, a, b, r->tol_in / nb, 1e-14, MF_QUAD_MAX_INTERVALS, &q) != MF_OK)
            r->fail = 1;
        sum += q.val;
    }
    return 2.0 * sum; /* psi in [0, pi] is half of the symmetric circle */
}

typedef struct {
    dref_ctx *r;
    double pa, pb;
    int map; /* as dref_ctx.map, in psi */
} dref_outer_ctx;

static double dref_outer_f(double u, void *user)
{
    const dref_outer_ctx *o = user;
    if (o->map == 0)
        return dref_outer_at(o->r, u);
    double psi = o->map > 0 ? o->pb - u * u : o->pa + u * u;
    return 2.0 * u * dref_outer_at(o->r, psi);
}

#define DREF_SCAN 512

static mf_status dref_component(dref_ctx *r, double tol, mf_result *out)
{
    /* outer breakpoints: 0, pi/2, pi, the events, and graded towards pi */
    double bp[DREF_SCAN + 160];
    int ev[DREF_SCAN + 160], nb = 0;
    bp[nb] = 0.0, ev[nb++] = 0;
    bp[nb] = 0.5 * MF_PI, ev[nb++] = 0;
    bp[nb] = MF_PI, ev[nb++] = 0;
    unsigned long long prev = dref_signature(r, 0.0);
    for (int i = 1; i <= DREF_SCAN && nb < DREF_SCAN + 100; ++i) {
        double a = MF_PI * (i - 1) / DREF_SCAN, b = MF_PI * i / DREF_SCAN;
        unsigned long long sb = dref_signature(r, b);
        if (sb != prev) {
            double lo = a, hi = b;
            for (int it = 0; it < 64; ++it) {
                double mid = 0.5 * (lo + hi);
                if (!(mid > lo && mid < hi))
                    break;
                if (dref_signature(r, mid) == prev)
                    lo = mid;
                else
                    hi = mid;
            }
            bp[nb] = 0.5 * (lo + hi), ev[nb++] = 1;
        }
        prev = sb;
    }
    double w = r->s > 0.0 ? fmin(0.5 * MF_PI, 0.25 * r->ndf.alpha_x / r->s) : 0.5 * MF_PI;
    for (double d = w; d < MF_PI && nb < DREF_SCAN + 150; d *= 2.0)
        bp[nb] = MF_PI - d, ev[nb++] = 0;
    /* sort with the event flags; an event wins over a plain breakpoint at the same place */
    for (int i = 1; i < nb; ++i)
        for (int j = i; j > 0 && (bp[j] < bp[j - 1] || (bp[j] == bp[j - 1] && ev[j] > ev[j - 1])); --j) {
            double t = bp[j];
            bp[j] = bp[j - 1], bp[j - 1] = t;
            int e = ev[j];
            ev[j] = ev[j - 1], ev[j - 1] = e;
        }
    double sum = 0.0, err = 0.0;
    int fail = 0, npan = 0;
    for (int i = 0; i + 1 < nb; ++i)
        npan += bp[i + 1] > bp[i] ? 1 + (ev[i] && ev[i + 1]) : 0;
    for (int i = 0; i + 1 < nb; ++i) {
        if (!(bp[i + 1] > bp[i]))
            continue;
        /* a panel beside an event is mapped towards it; between two events, split at the middle */
        double pieces[3] = {bp[i], bp[i + 1], bp[i + 1]};
        int np = 1;
        if (ev[i] && ev[i + 1])
            pieces[1] = 0.5 * (bp[i] + bp[i + 1]), np = 2;
        for (int p = 0; p < np; ++p) {
            dref_outer_ctx o = {r, pieces[p], pieces[p + 1], 0};
            int left_ev = p == 0 ? ev[i] : 0, right_ev = p == np - 1 ? ev[i + 1] : 0;
            o.map = left_ev ? -1 : right_ev ? 1 : 0;
            double a = o.map ? 0.0 : o.pa, b = o.map ? sqrt(o.pb - o.pa) : o.pb;
            mf_result q;
            mf_status st = mf_quad_adaptive(dref_outer_f, &o, a, b, 0.5 * tol / npan, 0.0, MF_QUAD_MAX_INTERVALS, &q);
            if (st != MF_OK && st != MF_ERR_NO_CONVERGENCE)
                return st;
            fail |= st != MF_OK;
            sum += q.val;
            err += q.err;
        }
    }
    out->val = sum;
    out->err = err + 0.25 * tol + 1e-13 * fabs(sum);
    return fail || r->fail ? MF_ERR_NO_CONVERGENCE : MF_OK;
}

mf_status mf_energy_dielectric_reference(mf_ndf ndf, mf_g2_form g2, double mu, double eta, double tol,
                                         mf_result *refl, mf_result *trans)
{
    refl->val = refl->err = trans->val = trans->err = NAN;
    if (!mf_ndf_valid(ndf) || ndf.alpha_x != ndf.alpha_y || (g2 != MF_G2_JOINT && g2 != MF_G2_SEPARABLE)
        || !(mu > 0.0 && mu <= 1.0) || !(eta > 0.0) || !isfinite(eta) || !(tol > 0.0))
        return MF_ERR_DOMAIN;
    dref_ctx r;
    memset(&r, 0, sizeof r);
    r.ndf = ndf;
    r.g2 = g2;
    r.s = sqrt(fmax(0.0, (1.0 - mu) * (1.0 + mu)));
    r.c = mu;
    r.wo = mf_vec3_make(r.s, 0.0, r.c);
    r.eta = eta;
    r.bc = eta < 1.0 ? asin(eta) : 0.5 * MF_PI;
    /* the inner rules' errors add at most 2 pi tol_in = tol / 4 over psi in [0, pi], twice */
    r.tol_in = tol / (8.0 * MF_PI);
    mf_status worst = MF_OK;
    mf_result *outs[2] = {refl, trans};
    for (int q = 0; q < 2; ++q) {
        r.trans = q;
        r.fail = 0;
        mf_status st = dref_component(&r, tol, outs[q]);
        if (st != MF_OK && st != MF_ERR_NO_CONVERGENCE)
            return st;
        if (st != MF_OK)
            worst = st;
    }
    return worst;
}

/* ---- the dielectric table's gate ------------------------------------------------------------ */

static mf_status diel_gate_setup_kind(const mf_table *t, mf_ndf_type *ndf, mf_g2_form *g2)
{
    const char *n = mf_table_get_meta(t, "ndf"), *g = mf_table_get_meta(t, "g2");
    if (!n || mf_ndf_type_parse(n, ndf) != 0 || !g || (*ndf != MF_NDF_GGX && *ndf != MF_NDF_BECKMANN))
        return MF_ERR_DOMAIN;
    if (!strcmp(g, "joint"))
        *g2 = MF_G2_JOINT;
    else if (!strcmp(g, "separable"))
        *g2 = MF_G2_SEPARABLE;
    else
        return MF_ERR_DOMAIN;
    return MF_OK;
}

static const double *drec(const mf_table *t, int i, int j, int k)
{
    return t->data + (((size_t)k * t->axes[1].size + j) * t->axes[0].size + i) * t->nfields;
}

static void diel_finite(void *vctx, mf_check *c)
{
    const gate_ctx *g = vctx;
    size_t n = (size_t)g->t->axes[0].size * g->t->axes[1].size * g->t->axes[2].size;
    for (size_t x = 0; x < n; ++x) {
        int bad = 0;
        for (int f = 0; f < g->t->nfields; ++f)
            bad += !isfinite(g->t->data[x * g->t->nfields + f]);
        mf_check_recordf(c, bad, "texel %zu", x);
    }
}

/* single scattering at a lossless interface: E_r, E_t >= 0, E_r + E_t <= 1 (the rest is the energy
 * of the paths that hit the surface again), E = E_r + E_t; violations beyond the stored bounds */
static void diel_range(void *vctx, mf_check *c)
{
    const gate_ctx *g = vctx;
    for (int k = 0; k < g->t->axes[2].size; ++k)
        for (int j = 0; j < g->t->axes[1].size; ++j)
            for (int i = 0; i < g->t->axes[0].size; ++i)
                for (int side = 0; side < 2; ++side) {
                    const double *r = drec(g->t, i, j, k) + 7 * side;
                    double br = r[1] + g->u * fabs(r[0]), bt = r[3] + g->u * fabs(r[2]);
                    double v = fmax(fmax(0.0, -r[0] - br), fmax(-r[2] - bt, r[0] + r[2] - 1.0 - br - bt));
                    /* E is the double sum of E_r and E_t, each stored value rounded once */
                    double se = fabs(r[4] - (r[0] + r[2])) - 2.0 * g->u * (fabs(r[4]) + fabs(r[0]) + fabs(r[2])) - 1e-15;
                    mf_check_recordf(c, fmax(v, fmax(0.0, se)), "texel (%d, %d, %d)%s", i, j, k, side ? " inside" : "");
                }
}

/* |stored - independent reference| / (stored bound + reference bound + REF_SLACK) of E_r and E_t,
 * both sides, against mf_energy_dielectric_reference (micro-normal angles about wo, every kink a panel
 * end; ~0.03 s per texel and side): every mu of the 4 corner (alpha, eta) columns, and in every other
 * column the texel i = (j + 3 k) mod n_mu, so that every column, every mu and every eta slice is
 * sampled (for 16^3: 316 texels, 632 texel-sides, about 15 s of CPU). */
static void diel_ref_texel(const gate_ctx *g, mf_check *c, int i, int j, int k)
{
    const mf_table *t = g->t;
    double mu = axis_value(t, 0, i), alpha = axis_value(t, 1, j), eta0 = mf_energy_dielectric_eta(axis_value(t, 2, k));
    for (int side = 0; side < 2; ++side) {
        const double *r = drec(t, i, j, k) + 7 * side;
        double eta = side ? 1.0 / eta0 : eta0;
        mf_result qr, qt;
        mf_status st = mf_energy_dielectric_reference(mf_ndf_make(g->ndf, alpha, alpha), g->g2, mu, eta, REF_TOL, &qr, &qt);
        if (st != MF_OK && st != MF_ERR_NO_CONVERGENCE) {
            mf_check_fail(c, "the reference quadrature failed");
            continue;
        }
        /* a rule that ran out of intervals still returns its estimate, whose error joins the slack */
        double vr = fabs(r[0] - qr.val) / (r[1] + g->u * fabs(r[0]) + qr.err + REF_SLACK);
        double vt = fabs(r[2] - qt.val) / (r[3] + g->u * fabs(r[2]) + qt.err + REF_SLACK);
        mf_check_recordf(c, fmax(vr, vt), "texel (%d, %d, %d)%s: alpha %.6g, mu %.6g, eta %.6g: E_r %.3g, E_t %.3g%s", i, j,
                         k, side ? " inside" : "", alpha, mu, eta, vr, vt, st != MF_OK ? " (reference unconverged)" : "");
    }
}

static void diel_reference(void *vctx, mf_check *c)
{
    const gate_ctx *g = vctx;
    int nm = g->t->axes[0].size, nr = g->t->axes[1].size, nz = g->t->axes[2].size;
    for (int k = 0; k < nz; ++k)
        for (int j = 0; j < nr; ++j) {
            int corner = (j == 0 || j == nr - 1) && (k == 0 || k == nz - 1);
            for (int i = 0; i < nm; ++i)
                if (corner || i == (j + 3 * k) % nm)
                    diel_ref_texel(g, c, i, j, k);
        }
}

/* The furnace columns: a 3 x 3 sample of (alpha, eta) columns (both ends and the middle of each axis),
 * each with its independent averages (other nodes and intervals than the table's), computed once for
 * diel_furnace and diel_split. */
#define DIEL_NCOLS 9
struct diel_avgs {
    int have[DIEL_NCOLS][2][2];                       /* [column][side][0: E, 1: E_t] */
    double val[DIEL_NCOLS][2][2], bound[DIEL_NCOLS][2][2];
};

/* column index cj + 3 ck -> (j, k); 0 if it repeats an earlier column (tables smaller than 3) */
static int diel_col(const mf_table *t, int col, int *j, int *k)
{
    int nr = t->axes[1].size, nz = t->axes[2].size, cj = col % 3, ck = col / 3;
    *j = cj * (nr - 1) / 2, *k = ck * (nz - 1) / 2;
    return !((cj > 0 && *j == (cj - 1) * (nr - 1) / 2) || (ck > 0 && *k == (ck - 1) * (nz - 1) / 2));
}

/* 2 integral_0^1 X(mu) mu dmu (X = E or, trans, E_t) of the column's side, recomputed by the adaptive
 * rule in mu with each kink panel mapped whole by the smooth cubic (other nodes than the table's) */
static int diel_col_avg(const gate_ctx *g, int col, int side, int trans, double *val, double *bound)
{
    struct diel_avgs *a = g->avgs;
    if (!a->have[col][side][trans]) {
        int j, k;
        diel_col(g->t, col, &j, &k);
        double alpha = axis_value(g->t, 1, j), eta0 = mf_energy_dielectric_eta(axis_value(g->t, 2, k));
        if (diel_avg_adaptive(g->ndf, g->g2, alpha, side ? 1.0 / eta0 : eta0, 1, trans, 0.5 * DIEL_EAVG_TOL,
                              &a->val[col][side][trans], &a->bound[col][side][trans]) != MF_OK)
            return -1;
        a->have[col][side][trans] = 1;
    }
    *val = a->val[col][side][trans];
    *bound = a->bound[col][side][trans];
    return 0;
}

/* the white furnace of the Kulla-Conty lobe built on the total single scattering E = E_r + E_t (F
 * exact; the interface is lossless, so the compensation must restore 1):
 * |E(mu_o) + (1 - E(mu_o)) (1 - E_avg') / (1 - E_avg) - 1| / bound at every mu of the furnace columns,
 * both sides, E_avg' recomputed by the adaptive rule in mu instead of sqrt(mu) (other nodes and
 * intervals than the table's) from fresh albedos */
static void diel_furnace(void *vctx, mf_check *c)
{
    const gate_ctx *g = vctx;
    const mf_table *t = g->t;
    for (int col = 0; col < DIEL_NCOLS; ++col) {
        int j, k;
        if (!diel_col(t, col, &j, &k))
            continue; /* a column already checked (small tables) */
        double alpha = axis_value(t, 1, j), eta0 = mf_energy_dielectric_eta(axis_value(t, 2, k));
        for (int side = 0; side < 2; ++side) {
            double eta = side ? 1.0 / eta0 : eta0, avg, avg_b;
            if (diel_col_avg(g, col, side, 0, &avg, &avg_b) != 0) {
                mf_check_fail(c, "albedo failed");
                return;
            }
            for (int i = 0; i < t->axes[0].size; ++i) {
                const double *r = drec(t, i, j, k) + 7 * side;
                double e = r[4], ea = r[5];
                double total = e + (1.0 - e) * (1.0 - avg) / (1.0 - ea);
                double be = r[1] + r[3] + g->u * (fabs(r[0]) + fabs(r[2]) + fabs(e)), bea = r[6] + g->u * fabs(ea);
                double bound = be + (1.0 - e) * (avg_b + bea + 1e-12) / (1.0 - ea) * (1.0 + (1.0 - avg) / (1.0 - ea));
                double v = (ea < 1.0 && bound >= 0.0) ? fabs(total - 1.0) / (bound + 1e-13) : INFINITY;
                mf_check_recordf(c, v, "texel (%d, %d, %d)%s: alpha %.6g, eta %.6g, 1 - total %.3g", i, j, k,
                                 side ? " inside" : "", alpha, eta, 1.0 - total);
            }
        }
    }
}

/* The split of the compensation between reflection and transmission [Kulla and Conty 2017]
 * (mf_energy_dielectric_ms_split), at the furnace columns, with the exact Fresnel:
 * (1) the white furnace of the whole BSDF seen from each side: E_r + E_t + the reflected lobe (1 - t)
 *     (1 - E(mu_o)) (1 - E(mu_i)) / (pi (1 - E_avg)) integrated over the view's hemisphere + the
 *     transmitted lobe t (1 - E(mu_o)) (1 - E_inv(mu_i)) / (pi (1 - E_avg_inv)) integrated over the
 *     other one must be 1 at every mu, both sides.  The lobes' integrals use the averages recomputed
 *     independently (their E_avg' / E_avg_inv'), so the transmitted lobe reads the other side's column:
 *     a wrong or swapped E_avg_inv fails here;
 * (2) reciprocity of the transmission: in equilibrium the radiance inside is eta^2 times the radiance
 *     outside, so the flux each side sends through the interface balances, T(eta) = eta^2 T(1/eta),
 *     where T = the cosine-weighted average of the transmitted energy, single scattering (E_t averaged,
 *     recomputed from fresh albedos) plus the transmitted lobe's t (1 - E_avg') (1 - E_avg_inv') /
 *     (1 - E_avg_inv): one value per column;
 * (3) 0 <= t <= 1 on both sides.
 * Each value is |residual| / its bound, the bound propagated (exactly, not to first order) from the
 * stored bounds, the storage rounding and the recomputed averages' bounds. */
static void diel_split(void *vctx, mf_check *c)
{
    const gate_ctx *g = vctx;
    const mf_table *t = g->t;
    for (int col = 0; col < DIEL_NCOLS; ++col) {
        int j, k;
        if (!diel_col(t, col, &j, &k))
            continue;
        double alpha = axis_value(t, 1, j), eta0 = mf_energy_dielectric_eta(axis_value(t, 2, k)), e2 = eta0 * eta0;
        double av[2], avb[2], tv[2], tvb[2], ea[2], bea[2], ts[2];
        mf_result fa[2];
        int bad = 0;
        for (int side = 0; side < 2; ++side) {
            const double *r = drec(t, 0, j, k) + 7 * side;
            ea[side] = r[5];
            bea[side] = r[6] + g->u * fabs(r[5]);
            bad |= diel_col_avg(g, col, side, 0, &av[side], &avb[side]) != 0;
            bad |= diel_col_avg(g, col, side, 1, &tv[side], &tvb[side]) != 0;
            bad |= mf_energy_favg_dielectric(side ? 1.0 / eta0 : eta0, &fa[side]) != MF_OK;
        }
        int walk = t->nfields == MF_DIELECTRIC_WALK_NFIELDS;
        for (int side = 0; side < 2 && !bad; ++side)
            if (walk) /* the split the table ships (the walk's closure) */
                ts[side] = drec(t, 0, j, k)[side ? WF_SPLIT_INV : WF_SPLIT];
            else
                bad |= mf_energy_dielectric_ms_split(side ? 1.0 / eta0 : eta0, ea[side], ea[1 - side], fa[side].val,
                                                     fa[1 - side].val, &ts[side]) != MF_OK;
        if (bad || !(ea[0] < 1.0) || !(ea[1] < 1.0)) {
            mf_check_recordf(c, INFINITY, "column (%d, %d): alpha %.6g, eta %.6g: %s", j, k, alpha, eta0,
                             bad ? "an average or the split failed" : "E_avg >= 1 leaves no lobe");
            continue;
        }
        for (int side = 0; side < 2; ++side) {
            int o = 1 - side;
            mf_check_recordf(c, (ts[side] >= 0.0 && ts[side] <= 1.0) ? 0.0 : INFINITY,
                             "column (%d, %d)%s: transmitted fraction %.6g", j, k, side ? " inside" : "", ts[side]);
            /* the lobes' integrals relative to 1 - E(mu_o) and their bounds: (1 - A') / (1 - A) with
             * |A' - A| <= dA, so |(1 - A') / (1 - A) - 1| <= dA / (1 - A) */
            double ls = (1.0 - av[side]) / (1.0 - ea[side]), lo = (1.0 - av[o]) / (1.0 - ea[o]);
            double dls = (avb[side] + bea[side] + 1e-12) / (1.0 - ea[side]), dlo = (avb[o] + bea[o] + 1e-12) / (1.0 - ea[o]);
            for (int i = 0; i < t->axes[0].size; ++i) {
                const double *r = drec(t, i, j, k) + 7 * side;
                double e = r[4];
                double total = e + (1.0 - e) * ((1.0 - ts[side]) * ls + ts[side] * lo);
                double be = r[1] + r[3] + g->u * (fabs(r[0]) + fabs(r[2]) + fabs(e));
                double bound = be * fabs(1.0 - ((1.0 - ts[side]) * ls + ts[side] * lo)) + (1.0 - e) * ((1.0 - ts[side]) * dls + ts[side] * dlo);
                mf_check_recordf(c, fabs(total - 1.0) / (bound + 1e-13), "texel (%d, %d, %d)%s: alpha %.6g, eta %.6g, t %.6g, 1 - total %.3g",
                                 i, j, k, side ? " inside" : "", alpha, side ? 1.0 / eta0 : eta0, ts[side], 1.0 - total);
            }
        }
        /* (2): the transmitted flux; ms - t (1 - E_avg) = t [(E_avg - A') (1 - B') + (1 - E_avg) (E_avg_inv - B')] /
         * (1 - E_avg_inv) with A', B' the recomputed averages, and t_out (1 - E_avg) = eta^2 t_in (1 - E_avg_inv)
         * by the split's construction (to rounding: 1e-15 relative) */
        double flux[2], fb[2];
        for (int side = 0; side < 2; ++side) {
            int o = 1 - side;
            double ms = ts[side] * (1.0 - av[side]) * (1.0 - av[o]) / (1.0 - ea[o]);
            double msb = ts[side] * ((avb[side] + bea[side]) * (1.0 - av[o]) + (1.0 - ea[side]) * (avb[o] + bea[o])) / (1.0 - ea[o]);
            flux[side] = tv[side] + ms;
            fb[side] = tvb[side] + msb + 1e-15 * (tv[side] + ms);
        }
        double bound = fb[0] + e2 * fb[1] + 2.0 * (fa[0].err + e2 * fa[1].err) + 1e-13;
        if (walk) /* stored t_split (balanced to rounding in double) rounded by the storage: u t on each side */
            bound += g->u * (fabs(flux[0] - tv[0]) + e2 * fabs(flux[1] - tv[1])) * 2.0;
        mf_check_recordf(c, fabs(flux[0] - e2 * flux[1]) / bound,
                         "column (%d, %d): alpha %.6g, eta %.6g: transmitted flux %.12g out, eta^2 x %.12g in", j, k, alpha,
                         eta0, flux[0], e2 * flux[1]);
    }
}

/* The split closed by the walk (tables with its fields only; mf_energy_dielectric_walk_split):
 * (1) every column: t_split, t_split_inv in [0, 1], constant along mu, and equal to the projection of the
 *     stored t_walk, se onto the balance with the stored E_avg, E_avg_inv (mf_energy_walk_split_project),
 *     to 1e-12 plus the storage rounding propagated (below); its balance t (1 - E_avg) = eta^2 t' (1 - E_avg_inv) is then exact to rounding;
 * (2) at the 3 x 3 gate columns, both sides: the stored t_walk against a fresh walk with another seed
 *     (the recorded seed + 1, the same count), |t_walk - t_fresh| / (4.5 sqrt(se^2 + se_fresh^2)) <= 1:
 *     4.5 standard errors, 18 pairs of independent estimates, a false alarm about once in 3e4 gates.
 * The values are the residuals over their bounds (<= 1 passes). */
static void diel_walk(void *vctx, mf_check *c)
{
    const gate_ctx *g = vctx;
    const mf_table *t = g->t;
    long walks;
    unsigned long long seed;
    if (diel_walk_meta(t, &walks, &seed) != MF_OK) {
        mf_check_fail(c, "the split fields without their metadata (split, split_walks, split_seed)");
        return;
    }
    int n_mu = t->axes[0].size, n_r = t->axes[1].size, n_z = t->axes[2].size;
    for (int k = 0; k < n_z; ++k)
        for (int j = 0; j < n_r; ++j) {
            const double *r0 = drec(t, 0, j, k);
            double eta = mf_energy_dielectric_eta(axis_value(t, 2, k)), alpha = axis_value(t, 1, j);
            double tw[2] = {r0[WF_T], r0[WF_T_INV]}, se[2] = {r0[WF_SE], r0[WF_SE_INV]}, tp[2];
            double a = eta * eta * fmax(0.0, 1.0 - r0[12]), b = fmax(0.0, 1.0 - r0[5]);
            int flat = 1;
            for (int i = 1; i < n_mu; ++i)
                for (int f = WF_T; f <= WF_SPLIT_INV; ++f)
                    flat &= drec(t, i, j, k)[f] == r0[f];
            double v;
            if (!flat || !(se[0] > 0.0) || !(se[1] > 0.0)) {
                v = INFINITY;
            } else if (a + b > 0.0) {
                mf_energy_walk_split_project(tw, se, a, b, tp, NULL);
                /* storage rounding u of every input: a = eta^2 (1 - E_avg_inv) and b = 1 - E_avg carry the
                 * relative error ra = u (1 + E_avg_inv / (1 - E_avg_inv)) + 2u, rb likewise; t_walk, se u each.
                 * lambda = N / D (N linear in a, b, t_walk; D quadratic in a, b, in 1/se^2) moves by at most
                 * 3 (ra + rb) + 6 u relative (first order, times 1.5), t = lambda a by ra more, and the stored
                 * t_split by u: the bound t (4 (ra + rb) + 12 u) + 1e-12 */
                double ra = g->u * (1.0 + r0[12] / fmax(1.0 - r0[12], 1e-300)) + 2.0 * g->u;
                double rb = g->u * (1.0 + r0[5] / fmax(1.0 - r0[5], 1e-300)) + 2.0 * g->u;
                double rel = 4.0 * (ra + rb) + 12.0 * g->u;
                v = fmax(fabs(tp[0] - r0[WF_SPLIT]) / (tp[0] * rel + 1e-12), fabs(tp[1] - r0[WF_SPLIT_INV]) / (tp[1] * rel + 1e-12));
            } else {
                v = 0.0; /* nothing to split: the fallback pair (Kulla-Conty's) */
            }
            if (!(r0[WF_SPLIT] >= 0.0 && r0[WF_SPLIT] <= 1.0 && r0[WF_SPLIT_INV] >= 0.0 && r0[WF_SPLIT_INV] <= 1.0))
                v = INFINITY;
            mf_check_recordf(c, v, "column (%d, %d): alpha %.6g, eta %.6g: t_split %.6g, %.6g (projection %s)", j, k,
                             alpha, eta, r0[WF_SPLIT], r0[WF_SPLIT_INV], flat ? "recomputed" : "not constant along mu");
        }
    for (int col = 0; col < DIEL_NCOLS; ++col) {
        int j, k;
        if (!diel_col(t, col, &j, &k))
            continue;
        const double *r0 = drec(t, 0, j, k);
        double eta = mf_energy_dielectric_eta(axis_value(t, 2, k)), alpha = axis_value(t, 1, j);
        for (int side = 0; side < 2; ++side) {
            mf_walk_split w;
            long column = (long)k * n_r + j;
            if (mf_walk_dielectric_split(mf_ndf_make(g->ndf, alpha, alpha), side ? 1.0 / eta : eta, walks, 100000,
                                         seed + 1u, 2u * (uint64_t)column + (uint64_t)side, &w) != MF_OK) {
                mf_check_fail(c, "the walk failed");
                return;
            }
            double ts = r0[side ? WF_T_INV : WF_T], ss = r0[side ? WF_SE_INV : WF_SE];
            if (w.ms == 0 || ss >= 0.5) /* no multiply scattered walk in one of them: nothing to compare */
                continue;
            double v = fabs(ts - w.t) / (4.5 * sqrt(ss * ss + w.t_se * w.t_se));
            mf_check_recordf(c, v, "column (%d, %d)%s: alpha %.6g, eta %.6g: t_walk %.6g +- %.2g, fresh %.6g +- %.2g", j, k,
                             side ? " inside" : "", alpha, side ? 1.0 / eta : eta, ts, ss, w.t, w.t_se);
        }
    }
}

const mf_check_def mf_energy_dielectric_checks[] = {
    {"diel_finite", "number of NaN or infinite fields per texel", 0.0, 0, diel_finite},
    {"diel_range", "how far E_r, E_t >= 0, E_r + E_t <= 1, E = E_r + E_t are violated beyond the stored bounds", 0.0, 0,
     diel_range},
    {"diel_reference",
     "|stored - independent nested Gauss-Kronrod about wo| / (both bounds + 1e-10), E_r and E_t, both sides: all mu of the 4 "
     "corner columns, one mu of every other column",
     1.0, 0, diel_reference},
    {"diel_furnace", "|1 - (E_r + E_t + compensation lobe)| / its propagated bound (white furnace), 3 x 3 columns x 2 sides", 1.0, 0,
     diel_furnace},
    {"diel_split",
     "the compensation split into reflection and transmission (Kulla-Conty): |1 - (E_r + E_t + both lobes)| and "
     "|T(eta) - eta^2 T(1/eta)| of the transmitted flux / their propagated bounds, 3 x 3 columns x 2 sides",
     1.0, 0, diel_split},
    {"diel_walk",
     "the split closed by the random walk: t_split = the balanced projection of t_walk (every column), t_walk against a "
     "fresh walk within 4.5 se (3 x 3 columns x 2 sides); only in tables with those fields",
     1.0, 0, diel_walk},
};
const int mf_energy_dielectric_nchecks = MF_ENERGY_DIELECTRIC_NCHECKS;

mf_status mf_energy_dielectric_gate(const mf_table *t, double storage_u, mf_check *checks, int cap, int *count)
{
    if (count)
        *count = 0;
    gate_ctx g;
    const mf_table_kind *k = mf_table_kind_find("dielectric");
    if (!t || !k || !k->layout_ok(t, NULL, 0) || diel_gate_setup_kind(t, &g.ndf, &g.g2) != MF_OK)
        return MF_ERR_DOMAIN;
    g.t = t;
    g.u = storage_u > 0.0 ? storage_u : 0.0;
    struct diel_avgs avgs;
    memset(&avgs, 0, sizeof avgs);
    g.avgs = &avgs;
    /* the walk split's check runs only on tables that have its fields (the default table's gate is unchanged) */
    int n = t->nfields == MF_DIELECTRIC_WALK_NFIELDS ? mf_energy_dielectric_nchecks : mf_energy_dielectric_nchecks - 1;
    return mf_check_run_defs(mf_energy_dielectric_checks, n, &g, 0, checks, cap, count);
}
