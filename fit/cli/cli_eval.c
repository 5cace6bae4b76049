/*
 * cli_eval.c -- `mfkit eval FUNCTION [options]`: CSV on stdin -> CSV on stdout.
 *
 * Every input column is echoed as read, then the outputs (%.17g).  Rows whose inputs are
 * outside the domain give nan outputs.  A missing required column, a field that is not a
 * number, or a bad option is an error: one line on stderr, exit code 2, nothing on stdout
 * (output is buffered until the whole input has been processed).  docs/cli.md lists the
 * functions; their names and columns are a public interface.
 *
 * Polygon functions take the vertex count n and the columns v0_x, v0_y, v0_z, ..., v7_z:
 * v0..v2 are required columns, v3..v7 may be absent; an empty vertex field (or an absent column)
 * means "unused", so rows with different n can share one file.  A row whose n is not an integer
 * in [3, 8] or whose first n vertices are not all given gives nan.
 */
#include "cli.h"
#include "cli_opt.h"
#include "cli_util.h"

#include "mfkit/mfkit.h"

#include <stdlib.h>
#include <string.h>

typedef struct {
    mf_ndf_type ndf;
    int have_ndf;
    mf_fresnel_type fresnel;
    mf_g2_form g2;
    long points;
    int points_set;
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

typedef struct {
    const char *name;
    const char *summary;
    const char *inputs[12];
    const char *outputs[6];            /* outputs for GGX (or the only ones) */
    const char *outputs_beckmann[6];   /* when they differ for Beckmann, else {NULL} */
    eval_fn fn;
    int polygon;                       /* 1: the inputs are followed by the polygon's vertex columns */
    unsigned options;                  /* OPT_* the function accepts (OPT_NDF: required) */
} eval_function;

/* Vertex columns of the polygon functions: the first 3 vertices required, the others optional. */
#define N_VERTEX_COLS (3 * MF_POLYGON_MAX_VERTICES)
#define N_REQUIRED_VERTEX_COLS 9
static const char *const k_vertex_cols[N_VERTEX_COLS] = {
    "v0_x", "v0_y", "v0_z", "v1_x", "v1_y", "v1_z", "v2_x", "v2_y", "v2_z", "v3_x", "v3_y", "v3_z",
    "v4_x", "v4_y", "v4_z", "v5_x", "v5_y", "v5_z", "v6_x", "v6_y", "v6_z", "v7_x", "v7_y", "v7_z"};
#define MAX_INPUTS (13 + N_VERTEX_COLS) /* 12 listed, f0, the vertices */

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
    /* --points N: the old n x n product rule; by default the rule split at the horizon of wi
     * (mf_albedo.h), whose albedo_err bounds the error */
    if (!(c > 0.0 && c <= 1.0) || mf_brdf_microfacet_albedo(&m, mf_vec3_make(sqrt(1.0 - c * c), 0.0, c),
                                                            o->points_set ? (int)o->points : 0, &r) != MF_OK) {
        out[0] = out[1] = NAN;
        return;
    }
    out[0] = r.val;
    out[1] = r.err;
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

static const char *const k_ndf_names[] = {"ggx", "beckmann", NULL};
static const char *const k_fresnel_names[] = {"none", "schlick", NULL};
static const char *const k_g2_names[] = {"joint", "separable", NULL};
static const char *const k_sided_names[] = {"one", "two", NULL};
static const char *const k_layout_names[] = {"end-points", "cell-centres", NULL};

/* The options of eval, in the order of k_eval_opts. */
enum { E_NDF, E_FRESNEL, E_G2, E_POINTS, E_SIDED, E_GRID, E_LAMBDA, E_LAYOUT, E_NOPTS };
static const cli_opt k_eval_opts[E_NOPTS] = {
    {.name = "--ndf", .kind = CLI_OPT_ENUM, .choices = k_ndf_names, .mask = OPT_NDF,
     .help = "the NDF (required by the functions marked *)"},
    {.name = "--fresnel", .kind = CLI_OPT_ENUM, .choices = k_fresnel_names, .mask = OPT_FRESNEL, .def = "none",
     .help = "brdf only; schlick adds the input column f0"},
    {.name = "--g2", .kind = CLI_OPT_ENUM, .choices = k_g2_names, .mask = OPT_G2, .def = "joint",
     .help = "masking-shadowing of brdf and albedo"},
    {.name = "--points", .metavar = "N", .kind = CLI_OPT_INT, .lo = 16, .hi = 2048, .multiple = 8, .mask = OPT_POINTS,
     .help = "albedo only: use the old N x N product rule (a multiple of 8 in [16, 2048]) instead of the default "
             "rule split at the horizon of wi, whose albedo_err bounds its error"},
    {.name = "--sided", .kind = CLI_OPT_ENUM, .choices = k_sided_names, .mask = OPT_SIDED, .def = "two",
     .help = "polygon functions: two counts the polygon from either side; one only when it faces the shading "
             "point (vertices clockwise seen from it)"},
    {.name = "--grid", .metavar = "N", .kind = CLI_OPT_INT, .lo = 1, .hi = MF_LEADR_GRID_MAX, .mask = OPT_GRID,
     .def = "5", .help = "leadr: the N x N Gaussian grid of LEADR Sec. 5.1"},
    {.name = "--lambda", .metavar = "L", .kind = CLI_OPT_DOUBLE, .dlo = 0.0, .dhi = INFINITY, .lo_open = 1,
     .mask = OPT_GRID, .def = "1.8", .help = "leadr: the grid covers [-L, L] standard deviations"},
    {.name = "--grid-layout", .kind = CLI_OPT_ENUM, .choices = k_layout_names, .mask = OPT_GRID, .def = "end-points",
     .help = "leadr: the two readings of Sec. 5.1 (docs/math.md, correction C-L7)"},
};

static const cli_command k_eval_cmd = {
    .name = "eval",
    .synopsis = "FUNCTION",
    .min_pos = 0, /* "missing FUNCTION" below */
    .max_pos = 1,
    .description = "Reads CSV with a header from stdin and writes CSV to stdout (< in.csv > out.csv): every input\n"
                   "column echoed, then the outputs (%.17g). Rows outside the domain give nan. Directions are unit\n"
                   "vectors in the z-up shading frame, pointing away from the surface.\n",
    .opts = k_eval_opts,
    .nopts = E_NOPTS,
    .epilog = NULL, /* the function list: eval_usage */
};

static void eval_usage(FILE *f)
{
    cli_opt_usage(&k_eval_cmd, f);
    fprintf(f, "\nPolygons: n (3..8) vertices v0..v7 (positions relative to the shading point); columns v3..v7\n"
               "may be absent and empty vertex fields are unused.\n\n"
               "functions (inputs -> outputs):\n");
    for (int i = 0; i < N_FUNCTIONS; ++i) {
        const eval_function *e = &k_functions[i];
        fprintf(f, "  %-16s%s %s\n    ", e->name, (e->options & OPT_NDF) ? "*" : " ", e->summary);
        for (int k = 0; k < count(e->inputs, 12); ++k)
            fprintf(f, "%s%s", k ? "," : "", e->inputs[k]);
        if (strcmp(e->name, "brdf") == 0)
            fprintf(f, "[,f0]");
        if (e->polygon)
            fprintf(f, ",v0_x,v0_y,v0_z,...,v2_z[,v3_x,...,v7_z]");
        fprintf(f, " -> ");
        for (int k = 0; k < count(e->outputs, 6); ++k)
            fprintf(f, "%s%s", k ? "," : "", e->outputs[k]);
        if (e->outputs_beckmann[0]) {
            fprintf(f, " (beckmann: ");
            for (int k = 0; k < count(e->outputs_beckmann, 6); ++k)
                fprintf(f, "%s%s", k ? "," : "", e->outputs_beckmann[k]);
            fprintf(f, ")");
        }
        fprintf(f, "\n");
    }
    fprintf(f, "\nexit status: 0 success, 2 usage or input error, 3 I/O error\n");
}

int cli_eval(int argc, char **argv)
{
    const char *cmd = "eval";
    const eval_function *e = NULL;
    /* the function first: it decides which options apply */
    if (argc >= 2 && argv[1][0] != '-') {
        for (int i = 0; i < N_FUNCTIONS; ++i)
            if (strcmp(argv[1], k_functions[i].name) == 0)
                e = &k_functions[i];
        if (!e)
            return cli_error(cmd, "unknown function '%s' (see 'mfkit eval --help')", argv[1]);
    }
    cli_val v[E_NOPTS];
    const char *pos[1];
    int npos;
    int rc = cli_opt_parse(&k_eval_cmd, argc - 1, argv + 1, e ? e->options : ~0u, e ? e->name : cmd, v, pos, &npos);
    if (rc == CLI_PARSE_HELP) {
        eval_usage(stdout);
        return 0;
    }
    if (rc)
        return rc;
    if (!e)
        return cli_error(cmd, "missing FUNCTION (see 'mfkit eval --help')");

    eval_opts o = {MF_NDF_GGX, 0, MF_FRESNEL_NONE, MF_G2_JOINT, 256, 0, MF_POLYGON_TWO_SIDED,
                   5, 1.8, MF_LEADR_GRID_END_POINTS};
    static const mf_ndf_type ndfs[] = {MF_NDF_GGX, MF_NDF_BECKMANN};
    static const mf_fresnel_type fresnels[] = {MF_FRESNEL_NONE, MF_FRESNEL_SCHLICK};
    static const mf_g2_form g2s[] = {MF_G2_JOINT, MF_G2_SEPARABLE};
    static const mf_polygon_sided sideds[] = {MF_POLYGON_ONE_SIDED, MF_POLYGON_TWO_SIDED};
    static const mf_leadr_grid_layout layouts[] = {MF_LEADR_GRID_END_POINTS, MF_LEADR_GRID_CELL_CENTRES};
    if (v[E_NDF].set)
        o.ndf = ndfs[v[E_NDF].i], o.have_ndf = 1;
    if (v[E_FRESNEL].set)
        o.fresnel = fresnels[v[E_FRESNEL].i];
    if (v[E_G2].set)
        o.g2 = g2s[v[E_G2].i];
    if (v[E_POINTS].set)
        o.points = v[E_POINTS].i, o.points_set = 1;
    if (v[E_SIDED].set)
        o.sided = sideds[v[E_SIDED].i];
    if (v[E_GRID].set)
        o.grid = v[E_GRID].i;
    if (v[E_LAMBDA].set)
        o.lambda = v[E_LAMBDA].d;
    if (v[E_LAYOUT].set)
        o.layout = layouts[v[E_LAYOUT].i];
    if ((e->options & OPT_NDF) && !o.have_ndf)
        return cli_error(cmd, "%s: --ndf ggx|beckmann is required", e->name);

    /* input columns: required ones, then (polygon functions) the vertex columns, of which only the
     * first N_REQUIRED_VERTEX_COLS are required */
    const char *inputs[MAX_INPUTS];
    int required[MAX_INPUTS];
    int nin = count(e->inputs, 12);
    memcpy(inputs, e->inputs, sizeof(char *) * (size_t)nin);
    if (!strcmp(e->name, "brdf") && o.fresnel == MF_FRESNEL_SCHLICK)
        inputs[nin++] = "f0";
    int first_vertex = nin;
    if (e->polygon)
        for (int k = 0; k < N_VERTEX_COLS; ++k)
            inputs[nin++] = k_vertex_cols[k];
    for (int k = 0; k < nin; ++k)
        required[k] = !e->polygon || k < first_vertex + N_REQUIRED_VERTEX_COLS;
    const char *const *outputs = (o.ndf == MF_NDF_BECKMANN && e->outputs_beckmann[0]) ? e->outputs_beckmann : e->outputs;
    int nout = count(outputs, 6);

    cli_csv csv;
    char msg[256];
    if (cli_csv_read(stdin, &csv, msg, sizeof msg) != 0)
        return cli_error(cmd, "%s: stdin: %s", e->name, msg);
    int col[MAX_INPUTS];
    for (int k = 0; k < nin; ++k) {
        col[k] = cli_csv_column(&csv, inputs[k]);
        if (col[k] < 0 && required[k]) {
            cli_csv_free(&csv);
            return cli_error(cmd, "%s: stdin: missing required column '%s'", e->name, inputs[k]);
        }
    }
    for (int k = 0; k < nout; ++k)
        if (cli_csv_column(&csv, outputs[k]) >= 0) {
            cli_csv_free(&csv);
            return cli_error(cmd, "%s: stdin: input already has a column named '%s' (an output)", e->name, outputs[k]);
        }

    cli_buf out = {0};
    for (int c = 0; c < csv.ncols; ++c)
        cli_buf_printf(&out, "%s%s", c ? "," : "", csv.header[c]);
    for (int k = 0; k < nout; ++k)
        cli_buf_printf(&out, ",%s", outputs[k]);
    cli_buf_printf(&out, "\n");
    int status = 0;
    for (int r = 0; r < csv.nrows && status == 0; ++r) {
        double in[MAX_INPUTS], res[6];
        for (int k = 0; k < nin; ++k) {
            if (col[k] < 0) {
                in[k] = NAN; /* an absent optional (vertex) column: unused */
                continue;
            }
            const char *s = csv.cells[r][col[k]];
            if (e->polygon && k >= first_vertex && s[0] == '\0') {
                in[k] = NAN; /* an empty vertex field: unused */
                continue;
            }
            int pc = cli_parse_double(s, &in[k]);
            if (pc != 0) {
                status = cli_error(cmd, "%s: stdin: data row %d, column '%s': '%s' %s", e->name, r + 1, inputs[k], s,
                                   cli_num_error(pc));
                break;
            }
        }
        if (status)
            break;
        for (int k = 0; k < nout; ++k)
            res[k] = NAN;
        e->fn(&o, in, res);
        for (int c = 0; c < csv.ncols; ++c)
            cli_buf_printf(&out, "%s%s", c ? "," : "", csv.cells[r][c]);
        for (int k = 0; k < nout; ++k) {
            cli_buf_printf(&out, ",");
            cli_buf_double(&out, res[k]);
        }
        cli_buf_printf(&out, "\n");
    }
    cli_csv_free(&csv);
    if (status == 0 && out.failed)
        status = cli_error(cmd, "%s: out of memory", e->name);
    if (status == 0 && cli_buf_write(&out, stdout) != 0)
        status = cli_error(cmd, "%s: stdout: write failed", e->name);
    cli_buf_free(&out);
    return status;
}
