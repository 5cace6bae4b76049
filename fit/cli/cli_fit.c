/*
 * cli_fit.c -- `mfkit fit ltc`: the options of mf_ltc_bake (fit an isotropic LTC table to a BRDF
 * model, run the gate, export only if every check passed or --force) and its report on the
 * terminal; `mfkit fit ggx-proxy`: the proxy-roughness fit (mf_proxyfit.h).
 * Exit code 0 success, 1 a gate check failed (nothing exported without --force), 2 usage error,
 * 3 I/O error, 4 fit failure, 130 interrupted (SIGINT/SIGTERM: no table written; the checkpoint
 * lets --resume continue).
 */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"
#include "cli_opt.h"
#include "cli_util.h"

#include "mfkit/mfkit.h"

#include <errno.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#ifdef MFKIT_CLI_HAVE_SOLVER
#include "mfkit/fit/mf_ltc_bake.h"
#include "mfkit/fit/mf_proxyfit.h"
#include "mfkit/io/mf_table_io.h"
#endif

/* --size N or NRxNU, each 2..4096: a = NR, b = NU */
static int parse_size(const char *s, cli_val *v)
{
    const char *x = strchr(s, 'x');
    char buf[32];
    long r, u;
    if (!x)
        return cli_parse_int(s, 2, 4096, &r) ? -1 : (v->a = v->b = r, 0);
    size_t n = (size_t)(x - s);
    if (n >= sizeof buf)
        return -1;
    memcpy(buf, s, n);
    buf[n] = '\0';
    if (cli_parse_int(buf, 2, 4096, &r) || cli_parse_int(x + 1, 2, 4096, &u))
        return -1;
    v->a = r;
    v->b = u;
    return 0;
}

/* The --brdf help lists the registry (mf_brdf_models), filled by brdf_help(). */
static char k_brdf_help[512];

enum { F_BRDF, F_LIST, F_SIZE, F_THREADS, F_SEED, F_SAMPLES, F_R_RANGE, F_U_RANGE, F_OUT, F_RESUME, F_FORCE, F_STOP_AFTER,
       F_QUIET, F_HDRP, F_NOPTS };
static const cli_opt k_fit_opts[F_NOPTS] = {
    {.name = "--brdf", .metavar = "NAME", .kind = CLI_OPT_STRING, .def = "ggx", .help = k_brdf_help},
    {.name = "--list", .kind = CLI_OPT_FLAG,
     .help = "print the registered models, one per line: name, a tab, description (nothing is fitted)"},
    {.name = "--size", .metavar = "N|NRxNU", .kind = CLI_OPT_CUSTOM, .parse = parse_size,
     .expect = "N or NRxNU with each in [2, 4096]", .def = "64",
     .help = "table size N x N, or NR x NU (roughness x view)"},
    {.name = "--threads", .metavar = "N", .kind = CLI_OPT_INT, .lo = 1, .hi = 256,
     .def = "the number of online CPUs", .help = "worker threads; the result does not depend on it, bit for bit"},
    {.name = "--seed", .metavar = "S", .kind = CLI_OPT_U64, .def = "1",
     .help = "scramble of the sample points and seed of the gate"},
    {.name = "--samples", .metavar = "N", .kind = CLI_OPT_INT, .lo = 64, .hi = 1 << 20, .pow2 = 1, .def = "4096",
     .help = "directions per texel, a power of two (4 N at views beyond 78.5 deg)"},
    {.name = "--r-range", .metavar = "LO:HI", .kind = CLI_OPT_RANGE, .dlo = 0.0, .dhi = 1.0, .def = "0:1",
     .help = "the roughness axis r (alpha = max(r^2, 1e-4))"},
    {.name = "--u-range", .metavar = "LO:HI", .kind = CLI_OPT_RANGE, .dlo = 0.0, .dhi = 1.0, .def = "0:1",
     .help = "the view axis u = sqrt(1 - cos theta_o) (only the default ranges give the drop-in layout of existing "
             "renderers)"},
    {.name = "--out", .metavar = "DIR", .kind = CLI_OPT_STRING, .def = "out/; created if missing",
     .help = "output directory"},
    {.name = "--resume", .kind = CLI_OPT_FLAG,
     .help = "continue from DIR/ltc_<brdf>.checkpoint (same settings) if it exists"},
    {.name = "--force", .kind = CLI_OPT_FLAG,
     .help = "export even if a gate check fails (metadata \"validated\" = \"false\")"},
    {.name = "--stop-after", .metavar = "K", .kind = CLI_OPT_INT, .lo = 1, .hi = 4096,
     .help = "(testing) stop as if interrupted after fitting K columns"},
    {.name = "--quiet", .kind = CLI_OPT_FLAG, .help = "no progress on stderr (shown only on a terminal anyway)"},
    {.name = "--hdrp", .kind = CLI_OPT_FLAG,
     .help = "also write <p>_hdrp.cs, Unity HDRP's LTC data fitted on HDRP's grid (a second fit as long as the "
             "table's; default 64 x 64 layout only)"},
};
static const cli_command k_fit_cmd = {
    .name = "fit ltc",
    .synopsis = "",
    .min_pos = 0,
    .max_pos = 0,
    .description = "Fits the isotropic LTC table of a BRDF (Ceres, exact Jacobians, an objective of polygon-lit\n"
                   "shading), runs the gate (energy, normalisation, polygon shading against Monte Carlo,\n"
                   "smoothness), prints its report, and exports the table into DIR only if every check passed\n"
                   "(mf_ltc_bake.h does the same from C).\n",
    .opts = k_fit_opts,
    .nopts = F_NOPTS,
    .epilog = "files (in DIR, <p> = ltc_<brdf>): <p>.exr, <p>_half.exr (all fields), <p>_1.dds and\n"
              "<p>_2.dds (RGBA32F: ltc_1 = minv_00 minv_20 minv_02 minv_22, ltc_2 = magnitude fresnel\n"
              "zero sphere), <p>_1_f16.dds and <p>_2_f16.dds (RGBA16F), <p>.h, <p>.glsl, <p>.hlsl, <p>.json,\n"
              "<p>.npy, <p>_fit.json (the float64 fit: a b c d, residual, iterations), <p>_gate.json; for\n"
              "engines (docs/tables.md \"Engines\"): <p>_legacy_1.dds, <p>_legacy_2.dds (legacy header),\n"
              "<p>.ktx2, <p>_f16.ktx2 (2-layer arrays, the latter Zstandard), <p>_1.exr, <p>_2.exr (R, G, B,\n"
              "A), and for 64 x 64 tables <p>_three.js (three.js) and <p>_eevee.h (Blender EEVEE); with\n"
              "--hdrp also <p>_hdrp.cs (Unity HDRP).\n\n"
              "exit status: 0 exported, 1 a gate check failed, 2 usage error, 3 I/O error, 4 fit failed,\n"
              "130 interrupted\n",
};

/* Fills k_brdf_help from the model registry: "ggx, beckmann, ..." */
static void brdf_help(void)
{
    size_t len = (size_t)snprintf(k_brdf_help, sizeof k_brdf_help, "the BRDF model: ");
    for (int i = 0; mf_brdf_models[i] && len < sizeof k_brdf_help; ++i)
        len += (size_t)snprintf(k_brdf_help + len, sizeof k_brdf_help - len, "%s%s", i ? ", " : "",
                                mf_brdf_models[i]->name);
}

/* `--list`: the registered models (mf_model.h), one per line as "name<TAB>description". */
static int list_models(void)
{
    for (int i = 0; mf_brdf_models[i]; ++i)
        printf("%s\t%s\n", mf_brdf_models[i]->name, mf_brdf_models[i]->description);
    return fflush(stdout) == 0 && !ferror(stdout) ? 0 : CLI_EXIT_IO;
}

static void usage(FILE *f)
{
    brdf_help();
    cli_opt_usage(&k_fit_cmd, f);
}

enum { P_OUT, P_SIZE, P_QUIET, P_NOPTS };
static const cli_opt k_proxy_opts[P_NOPTS] = {
    {.name = "--out", .metavar = "DIR", .kind = CLI_OPT_STRING, .def = "out/; created if missing",
     .help = "output directory"},
    {.name = "--size", .metavar = "N", .kind = CLI_OPT_INT, .lo = 2, .hi = 1024, .def = "64",
     .help = "grid points per axis (the shipped coefficients of mf_proxy.h come from the default)"},
    {.name = "--quiet", .kind = CLI_OPT_FLAG, .help = "no summary on stderr"},
};
static const cli_command k_proxy_cmd = {
    .name = "fit ggx-proxy",
    .synopsis = "",
    .min_pos = 0,
    .max_pos = 0,
    .description =
        "Tabulates the exact GGX proxy roughness alpha'(alpha, dh) of Kaplanyan 2016 Eq. 19 (docs/math.md)\n"
        "on an N x N grid log-spaced in alpha in [1e-3, 1] and dh in [1e-3, 10], fits (Ceres, analytic\n"
        "Jacobian, least squares of the relative error of alpha') the shader form\n"
        "  alpha'^2 = alpha^2 + dh^2 R(x), x = dh^2/(alpha^2 + dh^2), R = (1-x)/3 + x/pi + x(1-x) c/(1+q x)\n"
        "(limits dh << alpha and dh >> alpha built in), prints the coefficients and the max and mean\n"
        "relative errors of the fit and of sqrt(alpha^2 + dh^2), and writes into DIR (each file atomically):\n"
        "ggx_proxy_table.json, ggx_proxy_table.h (the table), ggx_proxy_fit.h, ggx_proxy_fit.glsl,\n"
        "ggx_proxy_fit.json (the coefficients and the error report).\n",
    .opts = k_proxy_opts,
    .nopts = P_NOPTS,
    .epilog = "exit status: 0 written, 2 usage error, 3 I/O error, 4 fit failed\n",
};

static void proxy_usage(FILE *f) { cli_opt_usage(&k_proxy_cmd, f); }

#ifndef MFKIT_CLI_HAVE_SOLVER
/* Without the solver (the front end, or mfkit-full of a build without Ceres): the usage texts and
 * `fit ltc --list`, as the full version prints them; everything else needs Ceres. */
int cli_fit(int argc, char **argv)
{
    if (argc < 2 || !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h")) {
        usage(argc < 2 ? stderr : stdout);
        return argc < 2 ? CLI_EXIT_USAGE : 0;
    }
    int help = 0, list = 0;
    for (int i = 2; i < argc; ++i) {
        help |= !strcmp(argv[i], "--help") || !strcmp(argv[i], "-h");
        list |= !strcmp(argv[i], "--list");
    }
    int ltc = !strcmp(argv[1], "ltc"), proxy = !strcmp(argv[1], "ggx-proxy");
    if (ltc && help) {
        usage(stdout);
        return 0;
    }
    if (ltc && list)
        return list_models();
    if (proxy && help) {
        proxy_usage(stdout);
        return 0;
    }
    return cli_error("fit", "needs the Ceres build (configured with MFKIT_WITH_CERES=OFF)");
}
#else

/* set by the handler; an int is written atomically on every platform mfkit builds on (sig_atomic_t is int) */
static volatile int g_cancel_int = 0;

static void on_signal(int sig)
{
    (void)sig;
    g_cancel_int = 1;
}

typedef struct {
    int show;
    struct timespec start;
    int last_pct;
} progress_state;

static double elapsed(const struct timespec *t0)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)(t.tv_sec - t0->tv_sec) + 1e-9 * (double)(t.tv_nsec - t0->tv_nsec);
}

static void progress(void *user, int done, int total)
{
    progress_state *p = user;
    if (!p->show)
        return;
    int pct = (int)(100.0 * done / total);
    if (pct == p->last_pct && done != total)
        return;
    p->last_pct = pct;
    int bar = pct / 4;
    fprintf(stderr, "\rfit [%.*s%*s] %3d%%  %d/%d  %.1f s%s", bar, "#########################", 25 - bar, "", pct,
            done, total, elapsed(&p->start), done == total ? "\n" : "");
}

static int fit_ggx_proxy(int argc, char **argv)
{
    const char *cmd = "fit ggx-proxy";
    cli_val v[P_NOPTS];
    const char *pos[1];
    int npos;
    int prc = cli_opt_parse(&k_proxy_cmd, argc - 2, argv + 2, ~0u, NULL, v, pos, &npos);
    if (prc == CLI_PARSE_HELP) {
        proxy_usage(stdout);
        return 0;
    }
    if (prc)
        return prc;
    const char *out = v[P_OUT].set ? v[P_OUT].s : "out";
    int quiet = v[P_QUIET].set;
    mf_proxyfit_options po;
    mf_proxyfit_options_default(&po);
    if (v[P_SIZE].set)
        po.size = (int)v[P_SIZE].i;
    mf_proxyfit_result r;
    mf_table t;
    mf_status st = mf_proxyfit_run(&po, &r, &t);
    if (st != MF_OK) {
        if (st == MF_ERR_NO_CONVERGENCE)
            mf_table_free(&t);
        cli_error(cmd, "%s%s%s", mf_status_str(st), st == MF_ERR_NO_CONVERGENCE ? ": " : "",
                  st == MF_ERR_NO_CONVERGENCE ? r.solver.message : "");
        return CLI_EXIT_FIT;
    }
    cli_buf b = {0};
    cli_buf_printf(&b, "form: alpha'^2 = alpha^2 + dh^2 R(x), x = dh^2/(alpha^2+dh^2), R = (1-x)/3 + x/pi + x(1-x) c/(1+q x)\n");
    cli_buf_printf(&b, "c = %.17g\nq = %.17g\n", r.coef[0], r.coef[1]);
    cli_buf_printf(&b, "domain: alpha [%g, %g], dh [%g, %g], %dx%d log grid; errors over a %ld-point check grid\n",
                   po.alpha_lo, po.alpha_hi, po.dh_lo, po.dh_hi, po.size, po.size, r.check_points);
    cli_buf_printf(&b, "%-24s %-11s %-11s %-14s %s\n", "approximation", "max_rel", "mean_rel", "max_rel_all_x",
                   "worst (alpha, dh)");
    const mf_proxyfit_error *e[2] = {&r.fit, &r.sqrt_approx};
    const char *names[2] = {"fit", "sqrt(alpha^2+dh^2)"};
    for (int k = 0; k < 2; ++k)
        cli_buf_printf(&b, "%-24s %-11.3e %-11.3e %-14.3e (%.4g, %.4g)\n", names[k], e[k]->max_rel, e[k]->mean_rel,
                       e[k]->max_rel_all, e[k]->worst_alpha, e[k]->worst_dh);
    cli_buf_printf(&b, "improvement (max_rel): %.4g x\n", r.sqrt_approx.max_rel / r.fit.max_rel);
    int rc = 0;
    char msg[1024];
    mf_status ds = mf_io_make_dirs(out, msg, sizeof msg);
    if (ds != MF_OK)
        rc = cli_exit_code(ds), cli_error(cmd, "%s", msg);
    if (rc == 0) {
        mf_status ws = mf_proxyfit_write(out, &po, &r, &t, "mfkit fit ggx-proxy " MFKIT_VERSION, msg, sizeof msg);
        if (ws != MF_OK) {
            cli_error(cmd, "%s (%s)", msg[0] ? msg : out, mf_status_str(ws));
            rc = CLI_EXIT_IO;
        }
    }
    if (rc == 0 && cli_buf_write(&b, stdout) != 0)
        rc = CLI_EXIT_IO;
    if (rc == 0 && !quiet)
        fprintf(stderr, "exported %s/ggx_proxy_table.{json,h} and %s/ggx_proxy_fit.{h,glsl,json}\n", out, out);
    cli_buf_free(&b);
    mf_table_free(&t);
    return rc;
}

int cli_fit(int argc, char **argv)
{
    const char *cmd = "fit ltc";
    if (argc < 2 || !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h")) {
        usage(argc < 2 ? stderr : stdout);
        return argc < 2 ? CLI_EXIT_USAGE : 0;
    }
    if (!strcmp(argv[1], "ggx-proxy"))
        return fit_ggx_proxy(argc, argv);
    if (!strcmp(argv[1], "ltc-aniso"))
        return cli_fit_aniso(argc, argv);
    if (strcmp(argv[1], "ltc"))
        return cli_error("fit", "unknown table kind '%s' ('ltc' or 'ggx-proxy')", argv[1]);
    brdf_help();
    cli_val v[F_NOPTS];
    const char *pos[1];
    int npos;
    int prc = cli_opt_parse(&k_fit_cmd, argc - 2, argv + 2, ~0u, NULL, v, pos, &npos);
    if (prc == CLI_PARSE_HELP) {
        usage(stdout);
        return 0;
    }
    if (prc)
        return prc;
    if (v[F_LIST].set)
        return list_models();

    mf_ltc_bake_options bo;
    mf_ltc_bake_options_default(&bo);
    const char *brdf = v[F_BRDF].set ? v[F_BRDF].s : "ggx";
    bo.model = mf_brdf_model_find(brdf);
    if (!bo.model)
        return cli_error(cmd, "--brdf: unknown BRDF '%s' (%s)", brdf, k_brdf_help + strlen("the BRDF model: "));
    mf_ltcfit_options *fo = &bo.fit;
    long online = sysconf(_SC_NPROCESSORS_ONLN);
    fo->threads = online >= 1 ? (int)(online > 256 ? 256 : online) : 1;
    if (v[F_SIZE].set)
        fo->n_r = (int)v[F_SIZE].a, fo->n_u = (int)v[F_SIZE].b;
    if (v[F_THREADS].set)
        fo->threads = (int)v[F_THREADS].i;
    if (v[F_SEED].set)
        fo->seed = v[F_SEED].u;
    if (v[F_SAMPLES].set)
        fo->samples = (int)v[F_SAMPLES].i;
    if (v[F_R_RANGE].set)
        fo->r_lo = v[F_R_RANGE].lo, fo->r_hi = v[F_R_RANGE].hi;
    if (v[F_U_RANGE].set)
        fo->u_lo = v[F_U_RANGE].lo, fo->u_hi = v[F_U_RANGE].hi;
    if (v[F_STOP_AFTER].set)
        fo->stop_after_columns = (int)v[F_STOP_AFTER].i;
    int quiet = v[F_QUIET].set;
    bo.out_dir = v[F_OUT].set ? v[F_OUT].s : "out";
    bo.resume = v[F_RESUME].set;
    bo.force = v[F_FORCE].set;
    bo.hdrp = v[F_HDRP].set;
    if (bo.hdrp && !(fo->n_r == 64 && fo->n_u == 64 && fo->r_lo == 0.0 && fo->r_hi == 1.0 && fo->u_lo == 0.0 &&
                     fo->u_hi == 1.0))
        return cli_error(cmd, "--hdrp: Unity HDRP's file needs the default layout (--size 64, default --r-range "
                              "and --u-range)");
    bo.tool = "mfkit fit ltc";
    bo.version = MFKIT_VERSION;
    bo.cancel = &g_cancel_int;
    progress_state ps = {!quiet && isatty(fileno(stderr)), {0, 0}, -1};
    clock_gettime(CLOCK_MONOTONIC, &ps.start);
    bo.progress = progress;
    bo.progress_user = &ps;

    struct sigaction sa, old_int, old_term;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &old_int);
    sigaction(SIGTERM, &sa, &old_term);
    mf_ltc_bake_report r;
    mf_status st = mf_ltc_bake(&bo, &r);
    sigaction(SIGINT, &old_int, NULL);
    sigaction(SIGTERM, &old_term, NULL);

    int rc;
    if (r.interrupted) {
        if (ps.show)
            fprintf(stderr, "\n");
        fprintf(stderr, "mfkit fit ltc: interrupted after %d of %d columns; no table written; '--resume' continues from %s\n",
                r.fit.columns_done, fo->n_r, r.checkpoint);
        mf_ltc_bake_report_free(&r);
        return CLI_EXIT_INTERRUPTED;
    }
    if (r.stage == MF_LTC_BAKE_STAGE_FIT && st != MF_OK) {
        cli_error(cmd, "%s", r.message);
        rc = cli_exit_code(st);
        mf_ltc_bake_report_free(&r);
        return rc;
    }
    if (!quiet)
        fprintf(stderr, "fit: %s %dx%d in %.2f s (%d threads); worst residual %.4g; iterations max %d, mean %.1f; %d not converged%s\n",
                bo.model->name, fo->n_r, fo->n_u, r.fit_seconds, fo->threads, r.fit.worst_residual,
                r.fit.max_iterations, (double)r.fit.total_iterations / ((double)fo->n_r * fo->n_u),
                r.fit.not_converged, r.fit.columns_resumed ? " (resumed)" : "");
    if (r.stage == MF_LTC_BAKE_STAGE_GATE && st != MF_OK && st != MF_ERR_CHECK_FAILED) {
        cli_error(cmd, "%s", r.message);
        mf_ltc_bake_report_free(&r);
        return CLI_EXIT_FIT;
    }
    /* the gate report on stdout */
    cli_buf tb = {0};
    cli_buf_checks_table(&tb, r.checks, r.nchecks, r.gate_passed);
    rc = cli_buf_write(&tb, stdout) == 0 ? CLI_EXIT_OK : CLI_EXIT_IO;
    cli_buf_free(&tb);
    if (st == MF_ERR_CHECK_FAILED) {
        fprintf(stderr, "mfkit fit ltc: the gate failed (see the report above); nothing exported (use --force to export "
                        "anyway, marked unvalidated)\n");
        rc = CLI_EXIT_CHECK_FAILED;
    } else if (st != MF_OK) {
        cli_error(cmd, "%s", r.message);
        rc = cli_exit_code(st);
    } else if (rc == CLI_EXIT_OK && !quiet) {
        fprintf(stderr, "exported %s/%s.* %s\n", bo.out_dir, r.stem,
                r.gate_passed ? "(validated)" : "(NOT validated: --force)");
    }
#ifndef MFKIT_CLI_HAVE_IMAGE
    if (st == MF_OK)
        fprintf(stderr, "mfkit fit ltc: %s/%s.exr and %s_half.exr not written: EXR is unsupported (configured with "
                        "MFKIT_WITH_OIIO=OFF)\n", bo.out_dir, r.stem, r.stem);
#endif
    mf_ltc_bake_report_free(&r);
    return rc;
}
#endif
