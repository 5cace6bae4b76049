/*
 * mf_eval.c -- the functions of `mfkit eval` (mf_eval.h): the registry k_functions (names,
 * inputs, outputs, options) and the row-by-row evaluator behind the command line and Python.
 *
 * Every function gets the row's inputs in the order of mf_eval_inputs (NaN for an absent optional
 * column) and writes its outputs, which start as NaN: a row outside the domain leaves them so.
 */
#include "mfkit/eval/mf_eval.h"

#include "mfkit/mfkit.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    mf_ndf_type ndf;
    int have_ndf;
    mf_fresnel_type fresnel;
    mf_g2_form g2;
    long points;
    mf_polygon_sided sided;
    long grid;                      /* leadr: N of the N x N grid */
    double lambda;                  /* leadr: extent of the grid in standard deviations */
    mf_leadr_grid_layout layout;    /* leadr: end points or cell centres (docs/math.md, correction C-L7) */
} eval_opts;

/* Options a function accepts (eval_function.options). */
enum {
    OPT_NDF = 1,
    OPT_FRESNEL = 2,
    OPT_G2 = 4,
    OPT_POINTS = 8,
    OPT_SIDED = 16,
    OPT_GRID = 32 /* --grid, --lambda, --grid-layout */
};

typedef void (*eval_fn)(const eval_opts *o, const double *in, double *out);

struct mf_eval_function {
    const char *name;
    const char *summary;
    const char *inputs[12];
    const char *outputs[6];            /* outputs for GGX (or the only ones) */
    const char *outputs_beckmann[6];   /* when they differ for Beckmann, else {NULL} */
    eval_fn fn;
    int polygon;                       /* 1: the inputs are followed by the polygon's vertex columns */
    unsigned options;                  /* OPT_* the function accepts (OPT_NDF: required) */
};
typedef struct mf_eval_function eval_function;

/* Vertex columns of the polygon functions: the first 3 vertices required, the others optional. */
#define N_VERTEX_COLS (3 * MF_POLYGON_MAX_VERTICES)
#define N_REQUIRED_VERTEX_COLS 9
static const char *const k_vertex_cols[N_VERTEX_COLS] = {
    "v0_x", "v0_y", "v0_z", "v1_x", "v1_y", "v1_z", "v2_x", "v2_y", "v2_z", "v3_x", "v3_y", "v3_z",
    "v4_x", "v4_y", "v4_z", "v5_x", "v5_y", "v5_z", "v6_x", "v6_y", "v6_z", "v7_x", "v7_y", "v7_z"};

static mf_vec3 v3(const double *p) { return mf_vec3_make(p[0], p[1], p[2]); }

static void fn_ndf(const eval_opts *o, const double *in, double *out)
{
    out[0] = mf_ndf_d(mf_ndf_make(o->ndf, in[0], in[1]), v3(in + 2));
}

static void fn_slope_pdf(const eval_opts *o, const double *in, double *out)
{
    out[0] = mf_ndf_p22(mf_ndf_make(o->ndf, in[0], in[1]), in[2], in[3]);
}

static void fn_lambda(const eval_opts *o, const double *in, double *out)
{
    mf_vec3 w = v3(in + 2);
    out[0] = mf_smith_lambda(mf_ndf_make(o->ndf, in[0], in[1]), w);
    if (o->ndf == MF_NDF_BECKMANN)
        out[1] = mf_smith_lambda_beckmann_walter(in[0], in[1], w);
}

static void fn_lambda_gaussian(const eval_opts *o, const double *in, double *out)
{
    (void)o;
    mf_gaussian_slopes g = {in[0], in[1], in[2], in[3], in[4]};
    mf_vec3 w = v3(in + 5);
    out[0] = mf_smith_lambda_gaussian(&g, w);
    out[1] = mf_smith_lambda_gaussian_walter(&g, w);
}

static void fn_g2(const eval_opts *o, const double *in, double *out)
{
    mf_ndf ndf = mf_ndf_make(o->ndf, in[0], in[1]);
    mf_vec3 wo = v3(in + 2), wi = v3(in + 5);
    out[0] = mf_smith_g1(ndf, wo);
    out[1] = mf_smith_g1(ndf, wi);
    out[2] = mf_smith_g2(ndf, MF_G2_JOINT, wo, wi);
    out[3] = mf_smith_g2(ndf, MF_G2_SEPARABLE, wo, wi);
}

static void fn_brdf(const eval_opts *o, const double *in, double *out)
{
    mf_microfacet m = {mf_ndf_make(o->ndf, in[0], in[1]), o->g2, {o->fresnel, 0.0, 0.0, 0.0}};
    if (o->fresnel == MF_FRESNEL_SCHLICK)
        m.fresnel.f0 = in[8];
    out[0] = mf_brdf_microfacet(&m, v3(in + 2), v3(in + 5));
}

static void fn_albedo(const eval_opts *o, const double *in, double *out)
{
    double c = in[1];
    mf_microfacet m = {mf_ndf_make(o->ndf, in[0], in[0]), o->g2, {MF_FRESNEL_NONE, 0.0, 0.0, 0.0}};
    mf_result r;
    /* points 0 (no --points): the rule split at the horizon of wi (mf_albedo.h), whose albedo_err
     * bounds the error; --points N: the old N x N product rule */
    if (!(c > 0.0 && c <= 1.0) || mf_brdf_microfacet_albedo(&m, mf_vec3_make(sqrt(1.0 - c * c), 0.0, c),
                                                            (int)o->points, &r) != MF_OK) {
        out[0] = out[1] = NAN;
        return;
    }
    out[0] = r.val;
    out[1] = r.err;
}

static void fn_dfg(const eval_opts *o, const double *in, double *out)
{
    /* the split-sum DFG terms (mf_energy_dfg: the albedo rule of mf_albedo.h, both Schlick moments
     * in one pass); NaN outside alpha in [1e-4, 1], cos_theta_o in (0, 1] */
    mf_result s, b;
    if (mf_energy_dfg(o->ndf, o->g2, in[0], in[1], &s, &b) != MF_OK)
        return;
    out[0] = s.val;
    out[1] = b.val;
}

static void fn_dfg_charlie(const eval_opts *o, const double *in, double *out)
{
    (void)o;
    /* the DFG table's Charlie channel (mf_albedo_charlie); NaN outside alpha in [1e-4, 1],
     * cos_theta_o in (0, 1] */
    mf_result r;
    if (!(in[0] >= MF_ENERGY_ALPHA_MIN) || mf_albedo_charlie(in[0], in[1], &r) != MF_OK)
        return;
    out[0] = r.val;
    out[1] = r.err;
}

static void fn_dielectric(const eval_opts *o, const double *in, double *out)
{
    /* mf_albedo_dielectric; NaN outside alpha in [1e-4, 1], cos_theta_o in (0, 1], eta > 0 */
    mf_result r, t;
    if (!(in[0] >= MF_ENERGY_ALPHA_MIN && in[0] <= 1.0)
        || mf_albedo_dielectric(mf_ndf_make(o->ndf, in[0], in[0]), o->g2, in[1], in[2], &r, &t) != MF_OK)
        return;
    out[0] = r.val;
    out[1] = r.err;
    out[2] = t.val;
    out[3] = t.err;
}

/* A polygon from in[0] = n and in[1 + 3 i .. 3 + 3 i] = vertex i (NaN where unused); 0 if n is
 * not an integer in [3, MF_POLYGON_MAX_VERTICES] or a used vertex is missing or invalid. */
static int read_polygon(const double *in, mf_polygon *p)
{
    double n = in[0];
    if (!(n >= 3.0 && n <= MF_POLYGON_MAX_VERTICES && n == floor(n)))
        return 0;
    mf_vec3 v[MF_POLYGON_MAX_VERTICES];
    for (int i = 0; i < (int)n; ++i)
        v[i] = v3(in + 1 + 3 * i);
    *p = mf_polygon_make((int)n, v);
    return mf_polygon_valid(p);
}

static void fn_polygon_cosine(const eval_opts *o, const double *in, double *out)
{
    mf_polygon p;
    if (!read_polygon(in, &p))
        return;
    out[0] = mf_polygon_integrate_cosine(&p, o->sided);
    out[1] = mf_polygon_solid_angle(&p);
}

/* An LTC from in[0..8] = M row-major; 0 if M is not invertible (mf_ltc_init). */
static int read_ltc(const double *in, mf_ltc *l) { return mf_ltc_init(l, mf_ltc_matrix_general(in)) == MF_OK; }

static void fn_ltc(const eval_opts *o, const double *in, double *out)
{
    (void)o;
    mf_ltc l;
    if (read_ltc(in, &l))
        out[0] = mf_ltc_eval(&l, v3(in + 9));
}

static void fn_ltc_polygon(const eval_opts *o, const double *in, double *out)
{
    mf_ltc l;
    mf_polygon p;
    if (read_ltc(in, &l) && read_polygon(in + 9, &p))
        out[0] = mf_ltc_integrate_polygon(&l, &p, o->sided);
}

static void fn_ggx_rect(const eval_opts *o, const double *in, double *out)
{
    (void)o;
    out[0] = (in[3] >= in[2] && in[5] >= in[4])
                 ? mf_filter_ggx_rect_mean_bounds(in[0], in[1], in[2], in[3], in[4], in[5])
                 : NAN;
}

static void fn_ggx_proxy(const eval_opts *o, const double *in, double *out)
{
    (void)o;
    out[0] = mf_filter_ggx_proxy_alpha(in[0], in[1]);
    out[1] = mf_filter_ggx_proxy_alpha_approx(in[0], in[1]);
    out[2] = mf_proxy_alpha_fit(in[0], in[1]);
}

static void fn_beckmann_filter(const eval_opts *o, const double *in, double *out)
{
    (void)o;
    mf_sym2 p = {in[2], in[3], in[4]};
    mf_gaussian_slopes g = mf_filter_beckmann(in[0], in[1], p);
    out[0] = g.var_x;
    out[1] = g.cov_xy;
    out[2] = g.var_y;
}

static void fn_bump_roughness(const eval_opts *o, const double *in, double *out)
{
    (void)o;
    mf_sym2 cov = {in[0], in[2], in[1]};
    mf_aniso_roughness r = mf_hery_bump_roughness(in[3], in[4], cov);
    out[0] = r.alpha1;
    out[1] = r.alpha2;
    out[2] = r.dir1[0];
    out[3] = r.dir1[1];
}

static void fn_sh_irradiance(const eval_opts *o, const double *in, double *out)
{
    (void)o;
    out[0] = mf_sh_irradiance(in, mf_vec3_make(in[9], in[10], in[11]));
}

static double leadr_one_light(mf_vec3 wn, void *user)
{
    const double *ctx = user; /* g (5), wo (3), wi (3) */
    mf_gaussian_slopes g = {ctx[0], ctx[1], ctx[2], ctx[3], ctx[4]};
    mf_leadr_light light = {mf_vec3_make(ctx[8], ctx[9], ctx[10]), 1.0};
    return mf_leadr_irradiance_lights(&g, mf_vec3_make(ctx[5], ctx[6], ctx[7]), &light, 1, wn);
}

static void fn_leadr(const eval_opts *o, const double *in, double *out)
{
    mf_gaussian_slopes g = {in[0], in[1], in[2], in[3], in[4]};
    mf_vec3 wo = mf_vec3_make(in[5], in[6], in[7]), wi = mf_vec3_make(in[8], in[9], in[10]);
    mf_fresnel none = {MF_FRESNEL_NONE, 0.0, 0.0, 0.0};
    out[0] = mf_leadr_specular(&g, none, wo, wi);
    mf_leadr_grid grid;
    double d;
    if (mf_leadr_grid_init(&grid, (int)o->grid, o->lambda, o->layout) != MF_OK
        || mf_leadr_diffuse(&grid, &g, wo, leadr_one_light, (void *)in, &d) != MF_OK)
        d = NAN;
    out[1] = d;
}

#define WO "wo_x", "wo_y", "wo_z"
#define WI "wi_x", "wi_y", "wi_z"
static void fn_dielectric_walk_split(const eval_opts *o, const double *in, double *out)
{
    /* mf_energy_dielectric_walk_split with this eta's E_avg and F_avg (mf_energy_dielectric_eavg,
     * mf_energy_favg_dielectric) on both sides; walks per side in [1000, 1e9], the generator stream as
     * in the table (2 x column, column = z index x n_r + r index), seed MF_ENERGY_WALK_SPLIT_SEED.  NaN
     * outside alpha in [1e-4, 1], eta > 0 */
    double alpha = in[0], eta = in[1], walks = in[2], stream = in[3];
    mf_result ea, eai, fa, fai;
    mf_energy_walk_split w;
    if (!(alpha >= MF_ENERGY_ALPHA_MIN && alpha <= 1.0) || !(eta > 0.0 && isfinite(eta)) || !(walks >= 1000.0 && walks <= 1e9)
        || walks != floor(walks) || !(stream >= 0.0 && stream <= 9007199254740992.0) || stream != floor(stream)
        || mf_energy_dielectric_eavg(o->ndf, o->g2, alpha, eta, &ea) != MF_OK
        || mf_energy_dielectric_eavg(o->ndf, o->g2, alpha, 1.0 / eta, &eai) != MF_OK
        || mf_energy_favg_dielectric(eta, &fa) != MF_OK || mf_energy_favg_dielectric(1.0 / eta, &fai) != MF_OK
        || mf_energy_dielectric_walk_split(o->ndf, alpha, eta, ea.val, eai.val, fa.val, fai.val, (long)walks,
                                           MF_ENERGY_WALK_SPLIT_SEED, (uint64_t)stream, &w) != MF_OK)
        return;
    out[0] = w.t_walk[0];
    out[1] = w.se[0];
    out[2] = w.t_walk[1];
    out[3] = w.se[1];
    out[4] = w.t[0];
    out[5] = w.t[1];
}

#define LTC_M "m00", "m01", "m02", "m10", "m11", "m12", "m20", "m21", "m22"
static const eval_function k_functions[] = {
    {"ndf", "D(wm), per steradian of micro-normal", {"alpha_x", "alpha_y", "m_x", "m_y", "m_z"}, {"D"}, {NULL},
     fn_ndf, 0, OPT_NDF},
    {"slope-pdf", "P22(slope), per unit slope area", {"alpha_x", "alpha_y", "slope_x", "slope_y"}, {"P22"}, {NULL},
     fn_slope_pdf, 0, OPT_NDF},
    {"lambda", "Smith Lambda(w) (Beckmann: also Walter's rational form)", {"alpha_x", "alpha_y", "w_x", "w_y", "w_z"},
     {"Lambda"}, {"Lambda", "Lambda_approx"}, fn_lambda, 0, OPT_NDF},
    {"lambda-gaussian", "Lambda of non-centred anisotropic Gaussian slopes (exact, Walter)",
     {"mean_x", "mean_y", "var_x", "var_y", "cov_xy", "w_x", "w_y", "w_z"}, {"Lambda", "Lambda_approx"}, {NULL},
     fn_lambda_gaussian, 0, 0},
    {"g2", "G1 of each direction and both masking-shadowing forms", {"alpha_x", "alpha_y", WO, WI},
     {"G1_o", "G1_i", "G2_joint", "G2_separable"}, {NULL}, fn_g2, 0, OPT_NDF},
    {"brdf", "microfacet reflection BRDF f(wo, wi), without the cosine", {"alpha_x", "alpha_y", WO, WI}, {"f"},
     {NULL}, fn_brdf, 0, OPT_NDF | OPT_FRESNEL | OPT_G2},
    {"albedo", "directional albedo (no Fresnel) by quadrature, with its error estimate", {"alpha", "cos_theta_o"},
     {"albedo", "albedo_err"}, {NULL}, fn_albedo, 0, OPT_NDF | OPT_G2 | OPT_POINTS},
    {"dfg", "split-sum DFG (Karis 2013): F0 dfg_scale + dfg_bias = the albedo with Schlick's Fresnel of o.h",
     {"alpha", "cos_theta_o"}, {"dfg_scale", "dfg_bias"}, {NULL}, fn_dfg, 0, OPT_NDF | OPT_G2},
    {"dielectric", "rough dielectric interface: reflected and transmitted energy (exact Fresnel, eta = beyond / view side)",
     {"alpha", "cos_theta_o", "eta"}, {"E_R", "E_R_err", "E_T", "E_T_err"}, {NULL}, fn_dielectric, 0, OPT_NDF | OPT_G2},
    {"dielectric-walk-split",
     "the dielectric table's --split walk fields: the random walk's transmitted fraction of its multiple scattering "
     "(both sides, cosine-averaged, with standard errors) and the balanced closure t_split (stream = 2 x column)",
     {"alpha", "eta", "walks", "stream"}, {"t_walk", "t_walk_se", "t_walk_inv", "t_walk_inv_se", "t_split", "t_split_inv"},
     {NULL}, fn_dielectric_walk_split, 0, OPT_NDF | OPT_G2},
    {"dfg-charlie", "the DFG table's Charlie sheen channel: albedo of Charlie D with Neubelt V, F = 1, and its bound",
     {"alpha", "cos_theta_o"}, {"dfg_charlie", "dfg_charlie_err"}, {NULL}, fn_dfg_charlie, 0, 0},
    {"polygon-cosine", "integral of max(0,z)/pi over a polygon (Lambert), and its solid angle (sr)", {"n"},
     {"E", "solid_angle"}, {NULL}, fn_polygon_cosine, 1, OPT_SIDED},
    {"ltc", "LTC density D(w) of the matrix M (row-major), per steradian", {LTC_M, "w_x", "w_y", "w_z"}, {"D"},
     {NULL}, fn_ltc, 0, 0},
    {"ltc-polygon", "integral of the LTC density of M over a polygon", {LTC_M, "n"}, {"integral"}, {NULL},
     fn_ltc_polygon, 1, OPT_SIDED},
    {"ggx-rect", "mean of the GGX slope density P22 over the rectangle [x0,x1] x [y0,y1] (Kaplanyan App. A)",
     {"alpha_x", "alpha_y", "x0", "x1", "y0", "y1"}, {"mean_P22"}, {NULL}, fn_ggx_rect, 0, 0},
    {"ggx-proxy", "GGX proxy roughness of the square slope footprint of full width dh (Kaplanyan Eq. 19)",
     {"alpha", "dh"}, {"alpha_eff", "alpha_eff_sqrt", "alpha_eff_fit"}, {NULL}, fn_ggx_proxy, 0, 0},
    {"beckmann-filter", "Beckmann filtered by a slope covariance: B' = diag(alpha^2/2) + P (Kaplanyan Eq. 14-15)",
     {"alpha_x", "alpha_y", "cov_xx", "cov_xy", "cov_yy"}, {"out_cov_xx", "out_cov_xy", "out_cov_yy"}, {NULL},
     fn_beckmann_filter, 0, 0},
    {"bump-roughness", "Hery's bump roughness: base alphas + slope covariance -> two roughnesses, first direction",
     {"var_u", "var_v", "cov_uv", "alpha_u", "alpha_v"}, {"alpha_1", "alpha_2", "dir_x", "dir_y"}, {NULL},
     fn_bump_roughness, 0, 0},
    {"sh-irradiance", "irradiance E(n) from 9 SH radiance coefficients (Ramamoorthi-Hanrahan)",
     {"L00", "L1m1", "L10", "L11", "L2m2", "L2m1", "L20", "L21", "L22", "n_x", "n_y", "n_z"}, {"E"}, {NULL},
     fn_sh_irradiance, 0, 0},
    {"leadr", "LEADR shading, one directional light: specular Eq. 17 (I/L), rough diffuse Eq. 21 by the grid",
     {"mean_x", "mean_y", "var_x", "var_y", "cov_xy", WO, WI}, {"specular", "diffuse"}, {NULL}, fn_leadr, 0,
     OPT_GRID},
};
#define N_FUNCTIONS ((int)(sizeof k_functions / sizeof k_functions[0]))

static int count(const char *const *list, int max)
{
    int n = 0;
    while (n < max && list[n])
        ++n;
    return n;
}

/* ---- the options ----------------------------------------------------------------------------- */

static const char *const k_ndf_names[] = {"ggx", "beckmann", NULL};
static const char *const k_fresnel_names[] = {"none", "schlick", NULL};
static const char *const k_g2_names[] = {"joint", "separable", NULL};
static const char *const k_sided_names[] = {"one", "two", NULL};
static const char *const k_layout_names[] = {"end-points", "cell-centres", NULL};

static const mf_eval_option k_options[MF_EVAL_NOPTS] = {
    {.name = "ndf", .kind = MF_EVAL_KIND_ENUM, .choices = k_ndf_names, .mask = OPT_NDF,
     .help = "the NDF (required by the functions marked *)"},
    {.name = "fresnel", .kind = MF_EVAL_KIND_ENUM, .choices = k_fresnel_names, .mask = OPT_FRESNEL, .def = "none",
     .help = "brdf only; schlick adds the input column f0"},
    {.name = "g2", .kind = MF_EVAL_KIND_ENUM, .choices = k_g2_names, .mask = OPT_G2, .def = "joint",
     .help = "masking-shadowing of brdf, albedo, dfg, dielectric and dielectric-walk-split"},
    {.name = "points", .metavar = "N", .kind = MF_EVAL_KIND_INT, .lo = 16, .hi = 2048, .multiple = 8,
     .mask = OPT_POINTS, .optional = 1,
     .help = "albedo only: use the old N x N product rule (a multiple of 8 in [16, 2048]) instead of the default "
             "rule split at the horizon of wi, whose albedo_err bounds its error"},
    {.name = "sided", .kind = MF_EVAL_KIND_ENUM, .choices = k_sided_names, .mask = OPT_SIDED, .def = "two",
     .help = "polygon functions: two counts the polygon from either side; one only when it faces the shading "
             "point (vertices clockwise seen from it)"},
    {.name = "grid", .metavar = "N", .kind = MF_EVAL_KIND_INT, .lo = 1, .hi = MF_LEADR_GRID_MAX, .mask = OPT_GRID,
     .def = "5", .help = "leadr: the N x N Gaussian grid of LEADR Sec. 5.1"},
    {.name = "lambda", .metavar = "L", .kind = MF_EVAL_KIND_DOUBLE, .dlo = 0.0, .dhi = INFINITY, .lo_open = 1,
     .mask = OPT_GRID, .def = "1.8", .help = "leadr: the grid covers [-L, L] standard deviations"},
    {.name = "grid-layout", .kind = MF_EVAL_KIND_ENUM, .choices = k_layout_names, .mask = OPT_GRID,
     .def = "end-points", .help = "leadr: the two readings of Sec. 5.1 (docs/math.md, correction C-L7)"},
};

const mf_eval_option *mf_eval_option_at(int k) { return k >= 0 && k < MF_EVAL_NOPTS ? &k_options[k] : NULL; }

int mf_eval_option_find(const char *name)
{
    for (int k = 0; name && k < MF_EVAL_NOPTS; ++k)
        if (strcmp(k_options[k].name, name) == 0)
            return k;
    return -1;
}

static mf_status fail(char *msg, size_t msg_size, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
static mf_status fail(char *msg, size_t msg_size, const char *fmt, ...)
{
    if (msg && msg_size > 0) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(msg, msg_size, fmt, ap);
        va_end(ap);
    }
    return MF_ERR_DOMAIN;
}

static void ok(char *msg, size_t msg_size)
{
    if (msg && msg_size > 0)
        msg[0] = '\0';
}

/* What option o accepts, for "expected ...". */
static void expect_text(const mf_eval_option *o, char *buf, size_t n)
{
    switch (o->kind) {
    case MF_EVAL_KIND_ENUM: {
        size_t len = 0;
        int c = count(o->choices, 64);
        buf[0] = '\0';
        for (int k = 0; k < c && len < n; ++k)
            len += (size_t)snprintf(buf + len, n - len, "%s%s", k == 0 ? "" : k + 1 == c ? " or " : ", ",
                                    o->choices[k]);
        break;
    }
    case MF_EVAL_KIND_INT:
        if (o->multiple > 0)
            snprintf(buf, n, "a multiple of %ld in [%ld, %ld]", o->multiple, o->lo, o->hi);
        else
            snprintf(buf, n, "an integer in [%ld, %ld]", o->lo, o->hi);
        break;
    case MF_EVAL_KIND_DOUBLE:
        if (isinf(o->dhi))
            snprintf(buf, n, "a finite number %s %g", o->lo_open ? ">" : ">=", o->dlo);
        else
            snprintf(buf, n, "a number in %c%g, %g]", o->lo_open ? '(' : '[', o->dlo, o->dhi);
        break;
    }
}

/* Non-zero if v is a valid value of o. */
static int value_valid(const mf_eval_option *o, const mf_eval_value *v)
{
    switch (o->kind) {
    case MF_EVAL_KIND_ENUM:
        return v->i >= 0 && v->i < count(o->choices, 64);
    case MF_EVAL_KIND_INT:
        return v->i >= o->lo && v->i <= o->hi && (o->multiple <= 0 || v->i % o->multiple == 0);
    case MF_EVAL_KIND_DOUBLE:
        return isfinite(v->d) && v->d >= o->dlo && v->d <= o->dhi && !(o->lo_open && v->d == o->dlo);
    }
    return 0;
}

mf_status mf_eval_option_parse(int k, const char *text, mf_eval_value *v, char *msg, size_t msg_size)
{
    const mf_eval_option *o = mf_eval_option_at(k);
    if (!o || !text || !v)
        return fail(msg, msg_size, "mf_eval_option_parse: invalid arguments");
    mf_eval_value x = {1, 0, 0.0};
    int parsed = 0;
    if (o->kind == MF_EVAL_KIND_ENUM) {
        for (long c = 0; o->choices[c]; ++c)
            if (strcmp(text, o->choices[c]) == 0)
                x.i = c, parsed = 1;
    } else if (*text) {
        char *end;
        errno = 0;
        if (o->kind == MF_EVAL_KIND_INT) {
            x.i = strtol(text, &end, 10);
            parsed = *end == '\0' && errno != ERANGE;
        } else {
            x.d = strtod(text, &end);
            if (*end == '\0' && errno == ERANGE && isinf(x.d))
                return fail(msg, msg_size, "%s: '%s' is out of the range of a double (|x| > 1.8e308)", o->name, text);
            parsed = *end == '\0';
        }
    }
    if (!parsed || !value_valid(o, &x)) {
        char want[200];
        expect_text(o, want, sizeof want);
        return fail(msg, msg_size, "%s: expected %s, got '%s'", o->name, want, text);
    }
    *v = x;
    ok(msg, msg_size);
    return MF_OK;
}

/* ---- the registry ---------------------------------------------------------------------------- */

int mf_eval_function_count(void) { return N_FUNCTIONS; }

const mf_eval_function *mf_eval_function_at(int i) { return i >= 0 && i < N_FUNCTIONS ? &k_functions[i] : NULL; }

const mf_eval_function *mf_eval_function_find(const char *name)
{
    for (int i = 0; name && i < N_FUNCTIONS; ++i)
        if (strcmp(name, k_functions[i].name) == 0)
            return &k_functions[i];
    return NULL;
}

const char *mf_eval_function_name(const mf_eval_function *f) { return f ? f->name : NULL; }
const char *mf_eval_function_summary(const mf_eval_function *f) { return f ? f->summary : NULL; }
int mf_eval_function_polygon(const mf_eval_function *f) { return f ? f->polygon : 0; }

int mf_eval_function_takes(const mf_eval_function *f, int k)
{
    const mf_eval_option *o = mf_eval_option_at(k);
    return f && o && (o->mask & f->options) != 0;
}

int mf_eval_function_requires(const mf_eval_function *f, int k)
{
    const mf_eval_option *o = mf_eval_option_at(k);
    return mf_eval_function_takes(f, k) && !o->def && !o->optional;
}

mf_status mf_eval_check_options(const mf_eval_function *f, const mf_eval_value *opts, char *msg, size_t msg_size)
{
    if (!f)
        return fail(msg, msg_size, "mf_eval: no function");
    for (int k = 0; k < MF_EVAL_NOPTS; ++k) {
        const mf_eval_option *o = &k_options[k];
        int set = opts && opts[k].set;
        if (set && !mf_eval_function_takes(f, k))
            return fail(msg, msg_size, "%s: does not take the option %s", f->name, o->name);
        if (!set && mf_eval_function_requires(f, k)) {
            char want[200];
            expect_text(o, want, sizeof want);
            return fail(msg, msg_size, "%s: the option %s (%s) is required", f->name, o->name, want);
        }
        if (set && !value_valid(o, &opts[k])) {
            char want[200];
            expect_text(o, want, sizeof want);
            if (o->kind == MF_EVAL_KIND_DOUBLE)
                return fail(msg, msg_size, "%s: %s: expected %s, got %.17g", f->name, o->name, want, opts[k].d);
            return fail(msg, msg_size, "%s: %s: expected %s, got %ld", f->name, o->name, want, opts[k].i);
        }
    }
    ok(msg, msg_size);
    return MF_OK;
}

/* The resolved options: each option's value, or where not set its default (k_options' text, the
 * one place defaults are written; ndf has none: GGX, have_ndf 0). */
static eval_opts resolve(const mf_eval_value *opts)
{
    static const mf_ndf_type ndfs[] = {MF_NDF_GGX, MF_NDF_BECKMANN};
    static const mf_fresnel_type fresnels[] = {MF_FRESNEL_NONE, MF_FRESNEL_SCHLICK};
    static const mf_g2_form g2s[] = {MF_G2_JOINT, MF_G2_SEPARABLE};
    static const mf_polygon_sided sideds[] = {MF_POLYGON_ONE_SIDED, MF_POLYGON_TWO_SIDED};
    static const mf_leadr_grid_layout layouts[] = {MF_LEADR_GRID_END_POINTS, MF_LEADR_GRID_CELL_CENTRES};
    mf_eval_value v[MF_EVAL_NOPTS];
    for (int k = 0; k < MF_EVAL_NOPTS; ++k) {
        v[k] = (mf_eval_value){0, 0, 0.0};
        if (opts && opts[k].set)
            v[k] = opts[k]; /* valid: mf_eval_check_options ran */
        else if (k_options[k].def && mf_eval_option_parse(k, k_options[k].def, &v[k], NULL, 0) != MF_OK)
            abort(); /* a default that is not a value of its option: a bug in k_options */
    }
    eval_opts o;
    o.ndf = ndfs[v[MF_EVAL_OPT_NDF].i];
    o.have_ndf = opts && opts[MF_EVAL_OPT_NDF].set;
    o.fresnel = fresnels[v[MF_EVAL_OPT_FRESNEL].i];
    o.g2 = g2s[v[MF_EVAL_OPT_G2].i];
    o.points = opts && opts[MF_EVAL_OPT_POINTS].set ? v[MF_EVAL_OPT_POINTS].i : 0; /* 0: the split rule */
    o.sided = sideds[v[MF_EVAL_OPT_SIDED].i];
    o.grid = v[MF_EVAL_OPT_GRID].i;
    o.lambda = v[MF_EVAL_OPT_LAMBDA].d;
    o.layout = layouts[v[MF_EVAL_OPT_GRID_LAYOUT].i];
    return o;
}

static int inputs_of(const eval_function *e, const eval_opts *o, const char **names, int *required)
{
    int nin = count(e->inputs, 12);
    for (int k = 0; k < nin; ++k)
        names[k] = e->inputs[k];
    if (!strcmp(e->name, "brdf") && o->fresnel == MF_FRESNEL_SCHLICK)
        names[nin++] = "f0";
    int first_vertex = nin;
    if (e->polygon)
        for (int k = 0; k < N_VERTEX_COLS; ++k)
            names[nin++] = k_vertex_cols[k];
    if (required)
        for (int k = 0; k < nin; ++k)
            required[k] = !e->polygon || k < first_vertex + N_REQUIRED_VERTEX_COLS;
    return nin;
}

static int outputs_of(const eval_function *e, const eval_opts *o, const char **names)
{
    const char *const *outputs = (o->ndf == MF_NDF_BECKMANN && e->outputs_beckmann[0]) ? e->outputs_beckmann : e->outputs;
    int nout = count(outputs, 6);
    for (int k = 0; k < nout; ++k)
        names[k] = outputs[k];
    return nout;
}

int mf_eval_inputs(const mf_eval_function *f, const mf_eval_value *opts, const char **names, int *required)
{
    if (!f || !names)
        return 0;
    eval_opts o = resolve(opts);
    return inputs_of(f, &o, names, required);
}

int mf_eval_outputs(const mf_eval_function *f, const mf_eval_value *opts, const char **names)
{
    if (!f || !names)
        return 0;
    eval_opts o = resolve(opts);
    return outputs_of(f, &o, names);
}

mf_status mf_eval_run_function(const mf_eval_function *f, const mf_eval_value *opts, int ncols,
                               const char *const *col_names, const double *const *cols, size_t n,
                               double *const *outs, char *msg, size_t msg_size)
{
    if (!f || ncols < 0 || (ncols > 0 && (!col_names || !cols)) || !outs)
        return fail(msg, msg_size, "mf_eval_run: invalid arguments");
    mf_status st = mf_eval_check_options(f, opts, msg, msg_size);
    if (st != MF_OK)
        return st;
    eval_opts o = resolve(opts);
    const char *inputs[MF_EVAL_MAX_INPUTS], *outputs[MF_EVAL_MAX_OUTPUTS];
    int required[MF_EVAL_MAX_INPUTS], src[MF_EVAL_MAX_INPUTS];
    int nin = inputs_of(f, &o, inputs, required), nout = outputs_of(f, &o, outputs);
    for (int k = 0; k < nin; ++k)
        src[k] = -1;
    for (int j = 0; j < ncols; ++j) {
        int k = 0;
        if (!col_names[j])
            return fail(msg, msg_size, "%s: column %d has no name", f->name, j);
        while (k < nin && strcmp(inputs[k], col_names[j]) != 0)
            ++k;
        if (k == nin)
            return fail(msg, msg_size, "%s: '%s' is not an input column (inputs: %s, ...)", f->name, col_names[j],
                        inputs[0]);
        if (src[k] >= 0)
            return fail(msg, msg_size, "%s: column '%s' given twice", f->name, col_names[j]);
        if (n > 0 && !cols[j])
            return fail(msg, msg_size, "%s: column '%s' has no data", f->name, col_names[j]);
        src[k] = j;
    }
    for (int k = 0; k < nin; ++k)
        if (src[k] < 0 && required[k])
            return fail(msg, msg_size, "%s: missing required column '%s'", f->name, inputs[k]);
    for (int k = 0; k < nout; ++k)
        if (n > 0 && !outs[k])
            return fail(msg, msg_size, "%s: output '%s' has no array", f->name, outputs[k]);
    for (size_t r = 0; r < n; ++r) {
        double in[MF_EVAL_MAX_INPUTS], res[MF_EVAL_MAX_OUTPUTS];
        for (int k = 0; k < nin; ++k)
            in[k] = src[k] >= 0 ? cols[src[k]][r] : NAN; /* an absent optional (vertex) column: unused */
        for (int k = 0; k < nout; ++k)
            res[k] = NAN;
        f->fn(&o, in, res);
        for (int k = 0; k < nout; ++k)
            outs[k][r] = res[k];
    }
    ok(msg, msg_size);
    return MF_OK;
}

mf_status mf_eval_run(const char *function, const mf_eval_value *opts, int ncols, const char *const *col_names,
                      const double *const *cols, size_t n, double *const *outs, char *msg, size_t msg_size)
{
    const mf_eval_function *f = mf_eval_function_find(function);
    if (!f)
        return fail(msg, msg_size, "unknown function '%s'", function ? function : "(null)");
    return mf_eval_run_function(f, opts, ncols, col_names, cols, n, outs, msg, msg_size);
}
