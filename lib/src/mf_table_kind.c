/* mf_table_kind.c -- the registry of table kinds (see mf_table_kind.h). */
#include "mfkit/mf_table_kind.h"

#include "mfkit/mf_energy.h"
#include "mfkit/mf_filter.h"
#include "mfkit/mf_ltc_aniso_table.h"
#include "mfkit/mf_ltc_gate.h"
#include "mfkit/mf_ltc_table.h"
#include "mfkit/mf_proxy.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *const mf_ggx_proxy_table_fields[MF_GGX_PROXY_TABLE_NFIELDS] = {"alpha", "dh", "alpha_eff",
                                                                           "alpha_eff_sqrt", "alpha_eff_fit"};
const char *const mf_moment_table_fields[MF_MOMENT_TABLE_NFIELDS] = {"mean_x", "mean_y", "m_xx", "m_xy", "m_yy"};

/* ---- layouts ------------------------------------------------------------------------------- */

/* The axes (count, names, mappings) and the required fields of kind k. */
static int layout_by_declaration(const mf_table_kind *k, const mf_table *t, char *why, size_t why_size)
{
    char tmp[8];
    if (!why || !why_size) {
        why = tmp;
        why_size = sizeof tmp;
    }
    if (!t || !t->data) {
        snprintf(why, why_size, "no table data");
        return 0;
    }
    if (t->naxes != k->naxes) {
        snprintf(why, why_size, "%d axes, a %s table has %d", t->naxes, k->name, k->naxes);
        return 0;
    }
    for (int a = 0; a < k->naxes; ++a)
        if (strcmp(t->axes[a].name, k->axes[a].name) || t->axes[a].mapping != k->axes[a].mapping) {
            snprintf(why, why_size, "axis %d is '%s' (%s), a %s table has '%s' (%s)", a, t->axes[a].name,
                     mf_axis_mapping_name(t->axes[a].mapping), k->name, k->axes[a].name,
                     mf_axis_mapping_name(k->axes[a].mapping));
            return 0;
        }
    for (int f = 0; f < k->required_fields; ++f)
        if (mf_table_field(t, k->fields[f]) < 0) {
            snprintf(why, why_size, "no field '%s'", k->fields[f]);
            return 0;
        }
    return 1;
}

static int ltc_layout_ok(const mf_table *t, char *why, size_t why_size)
{
    return mf_ltc_gate_layout_ok(t, why, why_size);
}

static mf_status ltc_gate(const mf_table *t, const mf_brdf_model *model, const void *options, mf_check *checks, int cap,
                          int *count)
{
    return mf_ltc_gate_run(t, model, (const mf_ltc_gate_options *)options, checks, cap, count);
}

/* ---- the GGX proxy table's gate ------------------------------------------------------------ */

#define PROXY_EXACT_REL 1e-12

double mf_table_storage_roundoff(int half_float) { return half_float ? 0x1p-11 : 0x1p-24; }

/* The storage unit roundoff u of a gate's options (NULL: a table in memory, u = 2^-53). */
static double storage_u(const void *options)
{
    const mf_table_storage_options *o = options;
    return o && o->unit_roundoff > 0.0 ? o->unit_roundoff : 0x1p-53;
}

typedef struct proxy_ctx {
    const mf_table *t;
    int f[MF_GGX_PROXY_TABLE_NFIELDS];
} proxy_ctx;

static void proxy_record(mf_check *c, const proxy_ctx *p, size_t texel, double v)
{
    const double *r = p->t->data + texel * (size_t)p->t->nfields;
    mf_check_recordf(c, v, "texel %zu: alpha %.6g, dh %.6g", texel, r[p->f[0]], r[p->f[1]]);
}

static void proxy_finite(void *ctx, mf_check *c)
{
    const proxy_ctx *p = ctx;
    size_t n = mf_table_texels(p->t);
    for (size_t i = 0; i < n; ++i) {
        const double *r = p->t->data + i * (size_t)p->t->nfields;
        int bad = 0;
        for (int f = 0; f < MF_GGX_PROXY_TABLE_NFIELDS; ++f)
            bad += !isfinite(r[p->f[f]]);
        proxy_record(c, p, i, bad);
    }
}

static void proxy_exact(void *ctx, mf_check *c)
{
    const proxy_ctx *p = ctx;
    size_t n = mf_table_texels(p->t);
    for (size_t i = 0; i < n; ++i) {
        const double *r = p->t->data + i * (size_t)p->t->nfields;
        double exact = mf_filter_ggx_proxy_alpha(r[p->f[0]], r[p->f[1]]);
        proxy_record(c, p, i, fabs(r[p->f[2]] / exact - 1.0));
    }
}

static void proxy_fit(void *ctx, mf_check *c)
{
    const proxy_ctx *p = ctx;
    size_t n = mf_table_texels(p->t);
    for (size_t i = 0; i < n; ++i) {
        const double *r = p->t->data + i * (size_t)p->t->nfields;
        proxy_record(c, p, i, fabs(r[p->f[4]] / r[p->f[2]] - 1.0));
    }
}

/* Storage.  Each stored value carries a relative rounding of at most u.  alpha' is homogeneous of
 * degree 1 in (alpha, dh) and increasing in both, so its logarithmic sensitivities are >= 0 and sum
 * to 1 (Euler): rounding alpha and dh moves the exact alpha' by at most u relative; with the
 * stored alpha_eff's own u, proxy_exact can grow by 2 u (+ O(u^2)), proxy_fit (two stored values)
 * by 2 u.  The bounds add 3 u. */
static const mf_check_def k_proxy_checks[] = {
    {"proxy_finite", "number of NaN or infinite fields per texel", 0.0, 0, proxy_finite},
    {"proxy_exact", "|alpha_eff / exact proxy roughness(alpha, dh) - 1| (Kaplanyan 2016, Eq. 19), bound 1e-12 + 3 u",
     PROXY_EXACT_REL, 0, proxy_exact},
    {"proxy_fit", "|alpha_eff_fit / alpha_eff - 1|, bound MF_PROXY_FIT_MAX_REL_ERROR + 3 u", MF_PROXY_FIT_MAX_REL_ERROR,
     0, proxy_fit},
};

static const mf_table_kind *kind_named(const char *name);

static mf_status proxy_gate(const mf_table *t, const mf_brdf_model *model, const void *options, mf_check *checks,
                            int cap, int *count)
{
    (void)model;
    if (count)
        *count = 0;
    const mf_table_kind *k = kind_named("ggx_proxy");
    if (!k->layout_ok(t, NULL, 0))
        return MF_ERR_DOMAIN;
    proxy_ctx p;
    p.t = t;
    for (int f = 0; f < MF_GGX_PROXY_TABLE_NFIELDS; ++f)
        p.f[f] = mf_table_field(t, mf_ggx_proxy_table_fields[f]);
    mf_check_def defs[3];
    memcpy(defs, k_proxy_checks, sizeof defs);
    defs[1].bound += 3.0 * storage_u(options);
    defs[2].bound += 3.0 * storage_u(options);
    return mf_check_run_defs(defs, 3, &p, 0, checks, cap, count);
}

static int proxy_layout_ok(const mf_table *t, char *why, size_t why_size)
{
    return layout_by_declaration(kind_named("ggx_proxy"), t, why, why_size);
}

/* ---- the moment map's gate ------------------------------------------------------------------ */

#define MOMENT_PSD_REL 1e-12

typedef struct moment_ctx {
    const mf_table *t;
    int f[MF_MOMENT_TABLE_NFIELDS];
} moment_ctx;

static void moment_record(mf_check *c, const moment_ctx *m, size_t texel, double v)
{
    int w = m->t->axes[0].size;
    mf_check_recordf(c, v, "texel (%d, %d)", (int)(texel % (size_t)w), (int)(texel / (size_t)w));
}

static void moment_finite(void *ctx, mf_check *c)
{
    const moment_ctx *m = ctx;
    size_t n = mf_table_texels(m->t);
    for (size_t i = 0; i < n; ++i) {
        const double *r = m->t->data + i * (size_t)m->t->nfields;
        int bad = 0;
        for (int f = 0; f < MF_MOMENT_TABLE_NFIELDS; ++f)
            bad += !isfinite(r[m->f[f]]);
        moment_record(c, m, i, bad);
    }
}

static void moment_covariance(void *ctx, mf_check *c)
{
    const moment_ctx *m = ctx;
    size_t n = mf_table_texels(m->t);
    for (size_t i = 0; i < n; ++i) {
        const double *r = m->t->data + i * (size_t)m->t->nfields;
        double mx = r[m->f[0]], my = r[m->f[1]], xx = r[m->f[2]], xy = r[m->f[3]], yy = r[m->f[4]];
        double vx = xx - mx * mx, vy = yy - my * my, cv = xy - mx * my;
        /* smallest eigenvalue of [[vx, cv], [cv, vy]] */
        double h = 0.5 * (vx + vy), d = hypot(0.5 * (vx - vy), cv);
        double lmin = h - d;
        double scale = xx + yy;
        moment_record(c, m, i, scale > 0.0 ? -lmin / scale : (lmin < 0.0 ? INFINITY : 0.0));
    }
}

static const mf_check_def k_moment_checks[] = {
    {"moment_finite", "number of NaN or infinite moments per texel", 0.0, 0, moment_finite},
    {"moment_covariance", "-(smallest eigenvalue of the slope covariance) / (m_xx + m_yy), bound 1e-12 + 5 u",
     MOMENT_PSD_REL, 0, moment_covariance},
};

static mf_status moment_gate(const mf_table *t, const mf_brdf_model *model, const void *options, mf_check *checks,
                             int cap, int *count)
{
    (void)model;
    if (count)
        *count = 0;
    const mf_table_kind *k = kind_named("moment_map");
    if (!k->layout_ok(t, NULL, 0))
        return MF_ERR_DOMAIN;
    moment_ctx m;
    m.t = t;
    for (int f = 0; f < MF_MOMENT_TABLE_NFIELDS; ++f)
        m.f[f] = mf_table_field(t, mf_moment_table_fields[f]);
    /* Storage: with every moment off by at most u relative, and mean^2 <= m_xx (a PSD level),
     * var_x moves by <= 3 u m_xx, var_y by <= 3 u m_yy and the covariance by <= 3 u sqrt(m_xx m_yy)
     * <= 1.5 u (m_xx + m_yy); the smallest eigenvalue moves by at most the perturbation's norm,
     * <= 4.5 u (m_xx + m_yy).  The bound adds 5 u. */
    mf_check_def defs[2];
    memcpy(defs, k_moment_checks, sizeof defs);
    defs[1].bound += 5.0 * storage_u(options);
    return mf_check_run_defs(defs, 2, &m, 0, checks, cap, count);
}

static int moment_layout_ok(const mf_table *t, char *why, size_t why_size)
{
    return layout_by_declaration(kind_named("moment_map"), t, why, why_size);
}

/* ---- the energy tables (mf_energy.h) ------------------------------------------------------- */

static int dfg_layout_ok(const mf_table *t, char *why, size_t why_size)
{
    return layout_by_declaration(kind_named("dfg"), t, why, why_size);
}

static int kc_layout_ok(const mf_table *t, char *why, size_t why_size)
{
    return layout_by_declaration(kind_named("kulla_conty"), t, why, why_size);
}

static int diel_layout_ok(const mf_table *t, char *why, size_t why_size)
{
    return layout_by_declaration(kind_named("dielectric"), t, why, why_size);
}

static mf_status diel_gate(const mf_table *t, const mf_brdf_model *model, const void *options, mf_check *checks,
                           int cap, int *count)
{
    (void)model;
    const mf_table_storage_options *o = options;
    return mf_energy_dielectric_gate(t, o ? o->unit_roundoff : 0.0, checks, cap, count);
}

static mf_status dfg_gate(const mf_table *t, const mf_brdf_model *model, const void *options, mf_check *checks, int cap,
                          int *count)
{
    (void)model;
    const mf_table_storage_options *o = options;
    return mf_energy_dfg_gate(t, o ? o->unit_roundoff : 0.0, checks, cap, count);
}

static mf_status kc_gate(const mf_table *t, const mf_brdf_model *model, const void *options, mf_check *checks, int cap,
                         int *count)
{
    (void)model;
    const mf_table_storage_options *o = options;
    return mf_energy_kulla_conty_gate(t, o ? o->unit_roundoff : 0.0, checks, cap, count);
}

/* Through the registry the options are a generic mf_table_storage_options (what `mfkit validate`
 * passes to every kind): the anisotropic gate runs with its defaults and that storage rounding;
 * callers that want its other options call mf_ltc_aniso_gate_run. */
static mf_status ltca_gate(const mf_table *t, const mf_brdf_model *model, const void *options, mf_check *checks,
                           int cap, int *count)
{
    const mf_table_storage_options *so = options;
    mf_ltc_aniso_gate_options o;
    mf_ltc_aniso_gate_options_default(&o);
    o.unit_roundoff = so ? so->unit_roundoff : 0.0;
    return mf_ltc_aniso_gate_run(t, model, &o, checks, cap, count);
}

/* ---- the registry ---------------------------------------------------------------------------- */

static const mf_table_kind_axis k_ltc_axes[2] = {
    {"r", "alpha", MF_AXIS_SQUARE, MF_LTC_ALPHA_MIN, 64, 0.0, 1.0},
    {"u", "cos_theta_o", MF_AXIS_ONE_MINUS_SQUARE, 0.00079632671073326335 /* cos(1.57) */, 64, 0.0, 1.0},
};
/* mfkit fit ggx-proxy's defaults: alpha in [1e-3, 1], dh in [1e-3, 10], 64 x 64 */
static const mf_table_kind_axis k_proxy_axes[2] = {
    {"log10_alpha", "log10_alpha", MF_AXIS_IDENTITY, -INFINITY, 64, -3.0, 0.0},
    {"log10_dh", "log10_dh", MF_AXIS_IDENTITY, -INFINITY, 64, -3.0, 1.0},
};
static const mf_table_kind_axis k_moment_axes[2] = {
    {"u", "tex_u", MF_AXIS_IDENTITY, -INFINITY, 0, 0.0, 1.0},
    {"v", "tex_v", MF_AXIS_IDENTITY, -INFINITY, 0, 1.0, 0.0},
};

static const mf_table_kind_axis k_dfg_axes[2] = {
    {"mu", "cos_theta_o", MF_AXIS_IDENTITY, -INFINITY, MF_DFG_DEFAULT_SIZE, 0.5 / MF_DFG_DEFAULT_SIZE,
     1.0 - 0.5 / MF_DFG_DEFAULT_SIZE},
    {"r", "alpha", MF_AXIS_SQUARE, MF_ENERGY_ALPHA_MIN, MF_DFG_DEFAULT_SIZE, 0.5 / MF_DFG_DEFAULT_SIZE,
     1.0 - 0.5 / MF_DFG_DEFAULT_SIZE},
};
static const mf_table_kind_axis k_kc_axes[2] = {
    {"mu", "cos_theta_o", MF_AXIS_IDENTITY, -INFINITY, MF_KULLA_CONTY_DEFAULT_SIZE, 0.5 / MF_KULLA_CONTY_DEFAULT_SIZE,
     1.0 - 0.5 / MF_KULLA_CONTY_DEFAULT_SIZE},
    {"r", "alpha", MF_AXIS_SQUARE, MF_ENERGY_ALPHA_MIN, MF_KULLA_CONTY_DEFAULT_SIZE, 0.5 / MF_KULLA_CONTY_DEFAULT_SIZE,
     1.0 - 0.5 / MF_KULLA_CONTY_DEFAULT_SIZE},
};
#define DS MF_DIELECTRIC_DEFAULT_SIZE
static const mf_table_kind_axis k_diel_axes[3] = {
    {"mu", "cos_theta_o", MF_AXIS_IDENTITY, -INFINITY, DS, 0.5 / DS, 1.0 - 0.5 / DS},
    {"r", "alpha", MF_AXIS_SQUARE, MF_ENERGY_ALPHA_MIN, DS, 0.5 / DS, 1.0 - 0.5 / DS},
    {"z", "eta_z", MF_AXIS_IDENTITY, -INFINITY, DS, 0.5 / DS, 1.0 - 0.5 / DS},
};
#undef DS
/* the published axes [Kt et al. 2022]: alpha = max(i/7, 1e-4), theta = i/7 0.9999 pi/2, phi = i/7 pi/2
 * (the (alpha, lambda) parameterisation has axes "a", "lambda" instead of "ax", "ay") */
static const mf_table_kind_axis k_ltca_axes[4] = {
    {"ax", "alpha_x", MF_AXIS_IDENTITY, MF_LTC_ANISO_ALPHA_MIN, 8, 0.0, 1.0},
    {"ay", "alpha_y", MF_AXIS_IDENTITY, MF_LTC_ANISO_ALPHA_MIN, 8, 0.0, 1.0},
    {"theta", "theta_o", MF_AXIS_IDENTITY, -INFINITY, 8, 0.0, MF_LTC_ANISO_THETA_MAX},
    {"phi", "phi_o", MF_AXIS_IDENTITY, -INFINITY, 8, 0.0, 0.5 * MF_PI},
};

static const mf_table_kind k_kinds[] = {
    {"ltc_isotropic", "isotropic LTC table: inverse-matrix fields, magnitude, fresnel, sphere over (r, u)", 2,
     k_ltc_axes, MF_LTC_NFIELDS, mf_ltc_table_fields, MF_LTC_F_MAGNITUDE + 1, ltc_layout_ok,
     mf_ltc_gate_check_table, MF_LTC_GATE_MAX_CHECKS, ltc_gate},
    {"ggx_proxy", "GGX proxy roughness alpha'(alpha, dh): exact, sqrt form and fitted form", 2, k_proxy_axes,
     MF_GGX_PROXY_TABLE_NFIELDS, mf_ggx_proxy_table_fields, MF_GGX_PROXY_TABLE_NFIELDS, proxy_layout_ok, k_proxy_checks,
     3, proxy_gate},
    {"moment_map", "one MIP level of a LEAN/LEADR moment map: E[s], E[s s^T] of the slopes per texel", 2, k_moment_axes,
     MF_MOMENT_TABLE_NFIELDS, mf_moment_table_fields, MF_MOMENT_TABLE_NFIELDS, moment_layout_ok, k_moment_checks, 2,
     moment_gate},
    {"dfg", "split-sum DFG: Schlick scale and bias of the microfacet albedo over (cos theta_o, sqrt alpha)", 2,
     k_dfg_axes, MF_DFG_NFIELDS, mf_dfg_table_fields, MF_DFG_NFIELDS, dfg_layout_ok, mf_energy_dfg_checks, MF_ENERGY_DFG_NCHECKS, dfg_gate},
    {"kulla_conty", "Kulla-Conty energy compensation: E(mu, alpha), E_avg(alpha) with F = 1", 2, k_kc_axes,
     MF_KULLA_CONTY_NFIELDS, mf_kulla_conty_table_fields, MF_KULLA_CONTY_NFIELDS, kc_layout_ok,
     mf_energy_kulla_conty_checks, 2, kc_gate},
    {"dielectric", "rough dielectric energy: E_r, E_t, E_avg over (cos theta_o, sqrt alpha, eta = 1 + 2 z^2), outside and "
     "inside (optional: the split closed by the random walk, t_walk, t_split)", 3, k_diel_axes, MF_DIELECTRIC_WALK_NFIELDS,
     mf_dielectric_table_fields, MF_DIELECTRIC_NFIELDS, diel_layout_ok,
     mf_energy_dielectric_checks, MF_ENERGY_DIELECTRIC_NCHECKS, diel_gate},
    {"ltc_anisotropic", "anisotropic LTC table: forward and inverse 3x3 matrices, magnitude, fresnel over (alpha_x, "
     "alpha_y, theta, phi)", 4, k_ltca_axes, MF_LTCA_NFIELDS, mf_ltc_aniso_table_fields, MF_LTCA_NFIELDS - 1,
     mf_ltc_aniso_layout_ok, mf_ltc_aniso_gate_check_table, MF_LTC_ANISO_GATE_MAX_CHECKS, ltca_gate},
};
#define N_KINDS ((int)(sizeof k_kinds / sizeof k_kinds[0]))

static const mf_table_kind *kind_named(const char *name)
{
    for (int i = 0; i < N_KINDS; ++i)
        if (!strcmp(k_kinds[i].name, name))
            return &k_kinds[i];
    return NULL;
}

int mf_table_kind_count(void) { return N_KINDS; }

const mf_table_kind *mf_table_kind_at(int i) { return (i >= 0 && i < N_KINDS) ? &k_kinds[i] : NULL; }

const mf_table_kind *mf_table_kind_find(const char *name)
{
    for (int i = 0; name && i < N_KINDS; ++i)
        if (!strcmp(k_kinds[i].name, name))
            return mf_table_kind_at(i);
    return NULL;
}

const mf_table_kind *mf_table_kind_of(const mf_table *t, char *why, size_t why_size)
{
    if (why && why_size)
        why[0] = '\0';
    if (!t) {
        if (why && why_size)
            snprintf(why, why_size, "no table");
        return NULL;
    }
    const char *tag = mf_table_get_meta(t, "kind");
    if (tag) {
        const mf_table_kind *k = mf_table_kind_find(tag);
        if (!k) {
            if (why && why_size)
                snprintf(why, why_size, "unknown kind '%s' in the metadata", tag);
            return NULL;
        }
        char r[160];
        if (!k->layout_ok(t, r, sizeof r)) {
            if (why && why_size)
                snprintf(why, why_size, "metadata says kind '%s' but %s", tag, r);
            return NULL;
        }
        return k;
    }
    for (int i = 0; i < N_KINDS; ++i)
        if (k_kinds[i].layout_ok(t, NULL, 0))
            return mf_table_kind_at(i);
    if (why && why_size)
        snprintf(why, why_size, "no \"kind\" metadata and the layout matches no registered kind");
    return NULL;
}

mf_status mf_table_kind_tag(mf_table *t, const mf_table_kind *k)
{
    if (!t || !k)
        return MF_ERR_DOMAIN;
    return mf_table_set_meta(t, "kind", k->name);
}

mf_status mf_table_kind_gate(const mf_table *t, const mf_brdf_model *model, const void *options, mf_check *checks,
                             int cap, int *count)
{
    if (count)
        *count = 0;
    const mf_table_kind *k = mf_table_kind_of(t, NULL, 0);
    if (!k)
        return MF_ERR_DOMAIN;
    return k->gate(t, model, options, checks, cap, count);
}
