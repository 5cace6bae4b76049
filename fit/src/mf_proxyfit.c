/*
 * mf_proxyfit.c -- tabulate the exact GGX proxy roughness and fit mf_proxy.h's form with Ceres
 * (see mf_proxyfit.h; derivation in docs/math.md, "GGX proxy: fitted form").
 */
#include "mfkit/fit/mf_proxyfit.h"
#include "mfkit/mf_filter.h"
#include "mfkit/io/mf_io.h"
#include "mfkit/io/mf_json.h"
#include "mfkit/io/mf_table_io.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define CHECK_REFINE 4   /* check grid: 4x finer than the table along each axis */
#define SWEEP_UNIFORM 20000

void mf_proxyfit_options_default(mf_proxyfit_options *o)
{
    if (!o)
        return;
    o->size = 64;
    o->alpha_lo = 1e-3;
    o->alpha_hi = 1.0;
    o->dh_lo = 1e-3;
    o->dh_hi = 10.0;
}

static int options_valid(const mf_proxyfit_options *o)
{
    return o->size >= 2 && o->size <= 4096 && o->alpha_lo > 0.0 && o->alpha_hi > o->alpha_lo &&
           isfinite(o->alpha_hi) && o->dh_lo > 0.0 && o->dh_hi > o->dh_lo && isfinite(o->dh_hi);
}

/* Point i of n log-spaced from lo to hi (both ends exact). */
static double log_point(double lo, double hi, int i, int n)
{
    if (i == 0)
        return lo;
    if (i == n - 1)
        return hi;
    return pow(10.0, log10(lo) + (log10(hi) - log10(lo)) * i / (n - 1));
}

static double rel_err(double approx, double exact) { return fabs(approx / exact - 1.0); }

/* (alpha, dh) with dh^2/(alpha^2 + dh^2) = x, the larger of the two equal to 1. */
static void point_of_x(double x, double *alpha, double *dh)
{
    if (x <= 0.5) {
        *alpha = 1.0;
        *dh = sqrt(x / (1.0 - x));
    } else {
        *dh = 1.0;
        *alpha = sqrt((1.0 - x) / x);
    }
}

static void error_init(mf_proxyfit_error *e)
{
    memset(e, 0, sizeof *e);
    e->worst_alpha = e->worst_dh = NAN;
}

static void error_add(mf_proxyfit_error *e, double err, double alpha, double dh)
{
    if (!(err <= e->max_rel)) { /* also records a NaN */
        e->max_rel = err;
        e->worst_alpha = alpha;
        e->worst_dh = dh;
    }
    e->mean_rel += err;
}

/* Max relative error over the sweep of x: uniform steps plus x = 10^-k and 1 - 10^-k. */
static double sweep_max(const double coef[MF_PROXY_NCOEF], int use_sqrt)
{
    double worst = 0.0;
    for (int i = 0; i <= SWEEP_UNIFORM + 32; ++i) {
        double x;
        if (i <= SWEEP_UNIFORM)
            x = (double)i / SWEEP_UNIFORM;
        else if (i < SWEEP_UNIFORM + 17)
            x = pow(10.0, -(double)(i - SWEEP_UNIFORM));
        else
            x = 1.0 - pow(10.0, -(double)(i - SWEEP_UNIFORM - 16));
        double a, d;
        if (x >= 1.0) { /* alpha -> 0: alpha' -> dh/sqrt(pi) */
            a = 1e-150;
            d = 1.0;
        } else {
            point_of_x(x, &a, &d);
        }
        double ex = mf_filter_ggx_proxy_alpha(a, d);
        double ap = use_sqrt ? mf_filter_ggx_proxy_alpha_approx(a, d) : mf_proxy_alpha_fit_coef(coef, a, d);
        double e = rel_err(ap, ex);
        if (!(e <= worst))
            worst = e;
    }
    return worst;
}

void mf_proxyfit_measure(const mf_proxyfit_options *o, const double coef[MF_PROXY_NCOEF], mf_proxyfit_error *fit,
                         mf_proxyfit_error *sq, long *points)
{
    mf_proxyfit_options def;
    if (!o) {
        mf_proxyfit_options_default(&def);
        o = &def;
    }
    int n = CHECK_REFINE * (o->size - 1) + 1;
    error_init(fit);
    if (sq)
        error_init(sq);
    for (int j = 0; j < n; ++j) {
        double d = log_point(o->dh_lo, o->dh_hi, j, n);
        for (int i = 0; i < n; ++i) {
            double a = log_point(o->alpha_lo, o->alpha_hi, i, n);
            double ex = mf_filter_ggx_proxy_alpha(a, d);
            error_add(fit, rel_err(mf_proxy_alpha_fit_coef(coef, a, d), ex), a, d);
            if (sq)
                error_add(sq, rel_err(mf_filter_ggx_proxy_alpha_approx(a, d), ex), a, d);
        }
    }
    double count = (double)n * (double)n;
    fit->mean_rel /= count;
    fit->max_rel_all = sweep_max(coef, 0);
    if (sq) {
        sq->mean_rel /= count;
        sq->max_rel_all = sweep_max(coef, 1);
    }
    if (points)
        *points = (long)n * n;
}

/* ---- the least-squares problem ----------------------------------------------------------- */
typedef struct fit_data {
    int n;           /* points */
    double *u, *v;   /* alpha^2, dh^2 */
    double *exact;   /* alpha' */
} fit_data;

/* r_i = fit_i / exact_i - 1,  fit = sqrt(alpha^2 + dh^2 R(x)):
 * d r_i / d p_k = dh^2 (dR/dp_k) / (2 fit_i exact_i). */
static int residuals(void *user, const double *p, double *r, double *jac)
{
    const fit_data *f = user;
    for (int i = 0; i < f->n; ++i) {
        double u = f->u[i], v = f->v[i];
        double x = v / (u + v);
        double g[MF_PROXY_NCOEF];
        double rr = mf_proxy_fit_r(p, x, jac ? g : NULL);
        double a2 = u + v * rr;
        if (!(a2 > 0.0))
            return 1;
        double fit = sqrt(a2);
        r[i] = fit / f->exact[i] - 1.0;
        if (jac)
            for (int k = 0; k < MF_PROXY_NCOEF; ++k)
                jac[i * MF_PROXY_NCOEF + k] = v * g[k] / (2.0 * fit * f->exact[i]);
    }
    return 0;
}

static const char *const k_fields[] = {"alpha", "dh", "alpha_eff", "alpha_eff_sqrt", "alpha_eff_fit"};
#define N_FIELDS 5

mf_status mf_proxyfit_run(const mf_proxyfit_options *o, mf_proxyfit_result *result, mf_table *table)
{
    mf_proxyfit_options def;
    if (!o) {
        mf_proxyfit_options_default(&def);
        o = &def;
    }
    if (table)
        memset(table, 0, sizeof *table);
    if (!result || !options_valid(o))
        return MF_ERR_DOMAIN;
    memset(result, 0, sizeof *result);
    int n = o->size;
    fit_data f;
    f.n = n * n;
    f.u = malloc(sizeof(double) * (size_t)f.n);
    f.v = malloc(sizeof(double) * (size_t)f.n);
    f.exact = malloc(sizeof(double) * (size_t)f.n);
    if (!f.u || !f.v || !f.exact) {
        free(f.u);
        free(f.v);
        free(f.exact);
        return MF_ERR_ALLOC;
    }
    for (int j = 0; j < n; ++j) {
        double d = log_point(o->dh_lo, o->dh_hi, j, n);
        for (int i = 0; i < n; ++i) {
            double a = log_point(o->alpha_lo, o->alpha_hi, i, n);
            int k = i + n * j;
            f.u[k] = a * a;
            f.v[k] = d * d;
            f.exact[k] = mf_filter_ggx_proxy_alpha(a, d);
        }
    }
    /* Start at the plain blend of the limits (c = 0); q in [-0.95, 10] keeps 1 + q x >= 0.05. */
    double p[MF_PROXY_NCOEF] = {0.0, 0.0};
    const double lower[MF_PROXY_NCOEF] = {-INFINITY, -0.95}, upper[MF_PROXY_NCOEF] = {INFINITY, 10.0};
    mf_solver_options so;
    mf_solver_options_default(&so);
    so.max_iterations = 200;
    mf_status st = mf_solver_least_squares(MF_PROXY_NCOEF, f.n, residuals, &f, p, lower, upper, &so, &result->solver);
    free(f.u);
    free(f.v);
    free(f.exact);
    if (st != MF_OK && st != MF_ERR_NO_CONVERGENCE)
        return st;
    memcpy(result->coef, p, sizeof p);
    mf_proxyfit_measure(o, p, &result->fit, &result->sqrt_approx, &result->check_points);

    mf_table t;
    mf_table_axis axes[2];
    memset(axes, 0, sizeof axes);
    snprintf(axes[0].name, sizeof axes[0].name, "log10_alpha");
    snprintf(axes[0].physical, sizeof axes[0].physical, "log10_alpha");
    axes[0].size = n;
    axes[0].lo = log10(o->alpha_lo);
    axes[0].hi = log10(o->alpha_hi);
    axes[0].mapping = MF_AXIS_IDENTITY;
    axes[0].physical_min = -INFINITY;
    axes[1] = axes[0];
    snprintf(axes[1].name, sizeof axes[1].name, "log10_dh");
    snprintf(axes[1].physical, sizeof axes[1].physical, "log10_dh");
    axes[1].lo = log10(o->dh_lo);
    axes[1].hi = log10(o->dh_hi);
    mf_status ts = mf_table_create(&t, 2, axes, N_FIELDS, k_fields);
    if (ts != MF_OK)
        return ts;
    double tmax = 0.0;
    for (int j = 0; j < n; ++j) {
        double d = log_point(o->dh_lo, o->dh_hi, j, n);
        for (int i = 0; i < n; ++i) {
            double a = log_point(o->alpha_lo, o->alpha_hi, i, n);
            double *rec = t.data + (size_t)(i + n * j) * N_FIELDS;
            rec[0] = a;
            rec[1] = d;
            rec[2] = mf_filter_ggx_proxy_alpha(a, d);
            rec[3] = mf_filter_ggx_proxy_alpha_approx(a, d);
            rec[4] = mf_proxy_alpha_fit_coef(p, a, d);
            double e = rel_err(rec[4], rec[2]);
            if (!(e <= tmax))
                tmax = e;
        }
    }
    result->table_fit_max_rel = tmax;
    char buf[MF_TABLE_TEXT_LEN];
    snprintf(buf, sizeof buf, "%.17g %.17g", p[0], p[1]);
    if (mf_table_set_meta(&t, "tool", "mfkit fit ggx-proxy") != MF_OK ||
        mf_table_set_meta(&t, "quantity", "GGX proxy roughness alpha' (Kaplanyan 2016 Eq. 19, docs/math.md, correction C-K3)") != MF_OK ||
        mf_table_set_meta(&t, "axes", "alpha = 10^log10_alpha, dh = 10^log10_dh (full width of the square)") != MF_OK ||
        mf_table_set_meta(&t, "fit_form", "a'^2 = a^2 + dh^2 R(x), x = dh^2/(a^2+dh^2), R = (1-x)/3 + x/pi + x(1-x) c/(1+q x)") != MF_OK ||
        mf_table_set_meta(&t, "fit_coefficients_c_q", buf) != MF_OK) {
        mf_table_free(&t);
        return MF_ERR_INTERNAL;
    }
    if (table)
        *table = t;
    else
        mf_table_free(&t);
    return st;
}

/* ---- output ------------------------------------------------------------------------------ */
static void set_msg(char *msg, size_t size, const char *fmt, ...)
{
    if (!msg || !size)
        return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, size, fmt, ap);
    va_end(ap);
}

static void emit_c_header(mf_buf *b, const mf_proxyfit_result *r, const char *tool)
{
    mf_buf_printf(b,
              "/* ggx_proxy_fit.h -- GGX proxy roughness alpha'(alpha, dh), fitted form (generated by %s).\n"
              " *   alpha'^2 = alpha^2 + dh^2 R(x),  x = dh^2 / (alpha^2 + dh^2),\n"
              " *   R(x) = (1 - x)/3 + x/pi + x (1 - x) c / (1 + q x)\n"
              " * dh: full width of the square slope footprint centred on the peak (Kaplanyan 2016 Eq. 16, 19).\n"
              " * Max relative error of alpha': %.3g (all alpha > 0, dh >= 0); sqrt(alpha^2 + dh^2): %.3g.\n"
              " * Evaluated with one division: u = alpha^2, v = dh^2, s = u + v, D = s + q v,\n"
              " *   alpha'^2 = u + v [(u/3 + v/pi) D + c u v] / (s D). */\n"
              "#ifndef GGX_PROXY_FIT_H\n#define GGX_PROXY_FIT_H\n\n#include <math.h>\n\n"
              "static const double ggx_proxy_fit_c = %.17g;\n"
              "static const double ggx_proxy_fit_q = %.17g;\n\n"
              "/* alpha > 0, dh >= 0 (use a scaled form for inputs beyond ~1e150). */\n"
              "static inline double ggx_proxy_alpha_fit(double alpha, double dh)\n{\n"
              "    double u = alpha * alpha, v = dh * dh, s = u + v;\n"
              "    double den = s + ggx_proxy_fit_q * v;\n"
              "    double r = ((u / 3.0 + v * 0.31830988618379067) * den + ggx_proxy_fit_c * u * v) / (s * den);\n"
              "    return sqrt(u + v * r);\n}\n\n#endif\n",
              tool ? tool : "mfkit fit ggx-proxy", r->fit.max_rel_all, r->sqrt_approx.max_rel_all, r->coef[0],
              r->coef[1]);
}

static void emit_glsl(mf_buf *b, const mf_proxyfit_result *r, const char *tool)
{
    mf_buf_printf(b,
              "// ggx_proxy_fit.glsl -- GGX proxy roughness alpha'(alpha, dh), fitted form (generated by %s).\n"
              "//   alpha'^2 = alpha^2 + dh^2 R(x), x = dh^2/(alpha^2 + dh^2), R = (1-x)/3 + x/pi + x(1-x) c/(1+q x)\n"
              "// dh: full width of the square slope footprint (Kaplanyan 2016 Eq. 16, 19).  Max relative error %.3g\n"
              "// (sqrt(alpha^2 + dh^2): %.3g).  Cost: one division, one sqrt, ~10 multiply-adds.\n"
              "// alpha > 0, dh >= 0; in float32 keep alpha, dh >= 1e-9 (squares stay normal).\n"
              "const float MF_GGX_PROXY_C = %.9g;\n"
              "const float MF_GGX_PROXY_Q = %.9g;\n\n"
              "float mf_ggx_proxy_alpha(float alpha, float dh)\n{\n"
              "    float u = alpha * alpha, v = dh * dh, s = u + v;\n"
              "    float den = s + MF_GGX_PROXY_Q * v;\n"
              "    float r = ((u * (1.0 / 3.0) + v * 0.318309886) * den + MF_GGX_PROXY_C * u * v) / (s * den);\n"
              "    return sqrt(u + v * r);\n}\n",
              tool ? tool : "mfkit fit ggx-proxy", r->fit.max_rel_all, r->sqrt_approx.max_rel_all, r->coef[0],
              r->coef[1]);
}

static void json_err(mf_buf *b, const char *name, const mf_proxyfit_error *e, int last)
{
    const char *keys[] = {"max_rel", "mean_rel", "worst_alpha", "worst_dh", "max_rel_all_x"};
    const double vals[] = {e->max_rel, e->mean_rel, e->worst_alpha, e->worst_dh, e->max_rel_all};
    mf_buf_printf(b, "    \"%s\": {", name);
    for (int k = 0; k < 5; ++k) {
        mf_buf_printf(b, "%s\"%s\": ", k ? ", " : "", keys[k]);
        mf_json_number(b, vals[k]);
    }
    mf_buf_printf(b, "}%s\n", last ? "" : ",");
}

/* Every number and string through the one JSON emitter (mf_json.h). */
static void emit_json(mf_buf *b, const mf_proxyfit_options *o, const mf_proxyfit_result *r, const char *tool)
{
    mf_buf_printf(b, "{\n  \"tool\": ");
    mf_json_string(b, tool ? tool : "mfkit fit ggx-proxy");
    mf_buf_printf(b, ",\n");
    mf_buf_printf(b, "  \"quantity\": \"GGX proxy roughness alpha'(alpha, dh), Kaplanyan 2016 Eq. 19 (docs/math.md, correction C-K3)\",\n");
    mf_buf_printf(b, "  \"form\": \"alpha'^2 = alpha^2 + dh^2 R(x), x = dh^2/(alpha^2 + dh^2), "
                 "R(x) = (1 - x)/3 + x/pi + x (1 - x) c / (1 + q x)\",\n");
    mf_buf_printf(b, "  \"coefficients\": {\"c\": ");
    mf_json_number(b, r->coef[0]);
    mf_buf_printf(b, ", \"q\": ");
    mf_json_number(b, r->coef[1]);
    mf_buf_printf(b, "},\n  \"domain\": {\"alpha\": [");
    mf_json_number(b, o->alpha_lo);
    mf_buf_printf(b, ", ");
    mf_json_number(b, o->alpha_hi);
    mf_buf_printf(b, "], \"dh\": [");
    mf_json_number(b, o->dh_lo);
    mf_buf_printf(b, ", ");
    mf_json_number(b, o->dh_hi);
    mf_buf_printf(b, "], \"grid\": \"%d x %d, log-spaced\", \"check_grid_points\": %ld},\n", o->size, o->size,
                  r->check_points);
    mf_buf_printf(b, "  \"objective\": \"least squares of alpha_fit/alpha_exact - 1 over the grid (Ceres, analytic Jacobian)\",\n");
    mf_buf_printf(b, "  \"errors\": {\n");
    json_err(b, "fit", &r->fit, 0);
    json_err(b, "sqrt", &r->sqrt_approx, 0);
    mf_buf_printf(b, "    \"fit_on_table_points_max_rel\": ");
    mf_json_number(b, r->table_fit_max_rel);
    mf_buf_printf(b, "\n  },\n  \"solver\": {\"converged\": %s, \"iterations\": %d, \"final_cost\": ",
                  r->solver.converged ? "true" : "false", r->solver.iterations);
    mf_json_number(b, r->solver.final_cost);
    mf_buf_printf(b, ", \"message\": ");
    mf_json_string(b, r->solver.message);
    mf_buf_printf(b, "}\n}\n");
}

mf_status mf_proxyfit_write(const char *dir, const mf_proxyfit_options *o, const mf_proxyfit_result *r,
                            const mf_table *table, const char *tool, char *msg, size_t msg_size)
{
    set_msg(msg, msg_size, "%s", "");
    mf_proxyfit_options def;
    if (!o) {
        mf_proxyfit_options_default(&def);
        o = &def;
    }
    if (!dir || !r || !table)
        return MF_ERR_DOMAIN;
    char path[4096];
    static const char *const table_ext[] = {".json", ".h"};
    for (int i = 0; i < 2; ++i) {
        snprintf(path, sizeof path, "%s/ggx_proxy_table%s", dir, table_ext[i]);
        mf_table_write_options wo;
        mf_table_write_options_default(&wo);
        wo.prefix = "ggx_proxy_table";
        mf_status st = mf_table_write(path, table, &wo, NULL, msg, msg_size);
        if (st != MF_OK)
            return st;
    }
    static const char *const coef_ext[] = {".h", ".glsl", ".json"};
    for (int i = 0; i < 3; ++i) {
        mf_buf b = {0};
        if (i == 0)
            emit_c_header(&b, r, tool);
        else if (i == 1)
            emit_glsl(&b, r, tool);
        else
            emit_json(&b, o, r, tool);
        snprintf(path, sizeof path, "%s/ggx_proxy_fit%s", dir, coef_ext[i]);
        mf_status st = mf_io_write_buf_atomic(path, &b, msg, msg_size);
        mf_buf_free(&b);
        if (st != MF_OK)
            return st;
    }
    return MF_OK;
}
