/* mf_energy.c -- DFG and Kulla-Conty energy tables and their gates (see mf_energy.h). */
#include "mfkit/mf_energy.h"
#include "mfkit/mf_quad.h"
#include "mfkit/mf_table_kind.h"

#include <stdio.h>
#include <string.h>

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
