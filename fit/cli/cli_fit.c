/*
 * cli_fit.c -- `mfkit fit ltc`: fit an isotropic LTC table to a BRDF model (mf_ltcfit.h), run the
 * gate (mf_ltc_gate.h), and export the table only if every check passed (or --force).
 * Exit code 0 success, 1 a gate check failed (nothing exported without --force), 2 usage error,
 * 3 I/O error, 4 fit failure, 130 interrupted (SIGINT/SIGTERM: no table written; the checkpoint
 * lets --resume continue).
 */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"
#include "cli_util.h"

#include "mfkit/mfkit.h"

#include <errno.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#ifdef MFKIT_HAVE_CXX_DEPS
#include "mfkit/mf_ltc_gate.h"
#include "mfkit/mf_ltcfit.h"
#include "mfkit/mf_proxyfit.h"
#include "mfkit/io/mf_table_io.h"
#endif

/* The registered models (mf_model.h): their names joined by ", " (usage, errors), or one per line
 * as "name<TAB>description" (`--list`). */
static void model_names(FILE *f)
{
    for (int i = 0; mf_brdf_models[i]; ++i)
        fprintf(f, "%s%s", i ? ", " : "", mf_brdf_models[i]->name);
}

static int list_models(void)
{
    for (int i = 0; mf_brdf_models[i]; ++i)
        printf("%s\t%s\n", mf_brdf_models[i]->name, mf_brdf_models[i]->description);
    return fflush(stdout) == 0 && !ferror(stdout) ? 0 : 3;
}

/* argv[2..] of `fit ltc` holds --list. */
static int wants_list(int argc, char **argv)
{
    for (int i = 2; i < argc; ++i)
        if (!strcmp(argv[i], "--list"))
            return 1;
    return 0;
}

static void usage(FILE *f)
{
    fprintf(f,
            "usage: mfkit fit ltc [--brdf NAME] [--size N | --size NRxNU] [--threads N] [--seed S]\n"
            "                     [--samples N] [--r-range LO:HI] [--u-range LO:HI] [--out DIR] [--resume]\n"
            "                     [--force] [--quiet]\n"
            "       mfkit fit ltc --list\n\n"
            "Fits the isotropic LTC table of a BRDF (Ceres, exact Jacobians, an objective of polygon-lit\n"
            "shading), runs the gate (energy, normalisation, polygon shading against Monte Carlo,\n"
            "smoothness), prints its report, and exports the table into DIR only if every check passed.\n\n"
            "options:\n"
            "  --brdf NAME     a registered model (default ggx): ");
    model_names(f);
    fprintf(f,
            "\n"
            "  --list          print the registered models, one per line: name, a tab, description\n"
            "  --size N        table size N x N (default 64), or NRxNU (roughness x view)\n"
            "  --threads N     worker threads (default: the number of online CPUs); the result does\n"
            "                  not depend on it, bit for bit\n"
            "  --seed S        scramble of the sample points and seed of the gate (default 1)\n"
            "  --samples N     directions per texel, a power of two (default 4096; 4 N at views\n"
            "                  beyond 78.5 deg)\n"
            "  --r-range LO:HI the roughness axis r (alpha = max(r^2, 1e-4)), default 0:1\n"
            "  --u-range LO:HI the view axis u = sqrt(1 - cos theta_o), default 0:1 (only the default\n"
            "                  ranges give the drop-in layout of existing renderers)\n"
            "  --out DIR       output directory (default out/; created if missing)\n"
            "  --resume        continue from DIR/ltc_<brdf>.checkpoint (same settings) if it exists\n"
            "  --force         export even if a gate check fails (metadata \"validated\" = \"false\")\n"
            "  --stop-after K  (testing) stop as if interrupted after fitting K columns\n"
            "  --quiet         no progress on stderr (shown only on a terminal anyway)\n\n"
            "files (in DIR, <p> = ltc_<brdf>): <p>.exr, <p>_half.exr (all fields), <p>_1.dds and\n"
            "<p>_2.dds (RGBA32F: ltc_1 = minv_00 minv_20 minv_02 minv_22, ltc_2 = magnitude fresnel\n"
            "zero sphere), <p>_1_f16.dds and <p>_2_f16.dds (RGBA16F), <p>.h, <p>.glsl, <p>.hlsl, <p>.json,\n"
            "<p>.npy, <p>_fit.json (the float64 fit: a b c d, residual, iterations), <p>_gate.json.\n\n"
            "exit status: 0 exported, 1 a gate check failed, 2 usage error, 3 I/O error, 4 fit failed,\n"
            "130 interrupted\n");
}

#ifndef MFKIT_HAVE_CXX_DEPS
int cli_fit(int argc, char **argv)
{
    if (argc >= 2 && !strcmp(argv[1], "ltc") && wants_list(argc, argv))
        return list_models();
    if (argc >= 2 && (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h"))) {
        usage(stdout);
        return 0;
    }
    return cli_error("fit", "not available: mfkit was built without Ceres and OpenImageIO");
}
#else

/* "LO:HI" with 0 <= LO < HI <= 1; 0 on success. */
static int parse_range(const char *s, double *lo, double *hi)
{
    const char *c = strchr(s, ':');
    char buf[64];
    size_t n = c ? (size_t)(c - s) : 0;
    if (!c || n == 0 || n >= sizeof buf)
        return 1;
    memcpy(buf, s, n);
    buf[n] = '\0';
    if (cli_parse_double(buf, lo) || cli_parse_double(c + 1, hi))
        return 1;
    return !(*lo >= 0.0 && *hi <= 1.0 && *lo < *hi);
}

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

static void gate_json(cli_buf *b, const char *brdf, const mf_check *c, int n, int all, const mf_ltcfit_result *r,
                      double fit_wall)
{
    cli_buf_printf(b, "{\n  \"tool\": \"mfkit fit ltc\",\n  \"version\": \"%s\",\n  \"brdf\": ", MFKIT_VERSION);
    cli_buf_json_string(b, brdf);
    cli_buf_printf(b, ",\n  \"passed\": %s,\n  \"fit\": {\"wall_s\": ", all ? "true" : "false");
    cli_buf_json_number(b, fit_wall);
    cli_buf_printf(b, ", \"worst_residual\": ");
    cli_buf_json_number(b, r->worst_residual);
    cli_buf_printf(b, ", \"max_iterations\": %d, \"total_iterations\": %ld, \"not_converged\": %d},\n  \"checks\": ",
                   r->max_iterations, r->total_iterations, r->not_converged);
    cli_buf_checks_json(b, c, n);
    cli_buf_printf(b, "\n}\n");
}

/* mkdir -p: creates dir and its missing parents; 0 if dir is (now) a directory, else -1 with errno
 * set (ENOTDIR when it exists as something else). */
static int make_dir(const char *dir)
{
    char path[4096];
    size_t n = strlen(dir);
    if (n == 0 || n >= sizeof path) {
        errno = ENAMETOOLONG;
        return -1;
    }
    memcpy(path, dir, n + 1);
    for (size_t i = 1; i <= n; ++i)
        if (path[i] == '/' || path[i] == '\0') {
            char c = path[i];
            path[i] = '\0';
            if (mkdir(path, 0777) != 0 && errno != EEXIST)
                return -1;
            path[i] = c;
        }
    struct stat st;
    if (stat(dir, &st) != 0)
        return -1;
    if (!S_ISDIR(st.st_mode)) {
        errno = ENOTDIR;
        return -1;
    }
    return 0;
}

static int export_all(const char *cmd, const char *dir, const char *stem, const mf_table *t, const mf_brdf_model *model,
                      const mf_ltcfit_options *fo, const mf_ltcfit_result *r, const cli_buf *gate)
{
    char path[4096], msg[1024];
    struct {
        const char *suffix;
        int half;
        int dds_set; /* 0 all fields, 1 ltc_1, 2 ltc_2 */
    } files[] = {{".exr", 0, 0},     {"_half.exr", 1, 0},   {"_1.dds", 0, 1}, {"_2.dds", 0, 2},
                 {"_1_f16.dds", 1, 1}, {"_2_f16.dds", 1, 2}, {".h", 0, 0},     {".glsl", 0, 0},
                 {".hlsl", 0, 0},    {".json", 0, 0},       {".npy", 0, 0}};
    for (size_t i = 0; i < sizeof files / sizeof files[0]; ++i) {
        snprintf(path, sizeof path, "%s/%s%s", dir, stem, files[i].suffix);
        mf_table_write_options wo;
        mf_table_write_options_default(&wo);
        wo.half_float = files[i].half;
        wo.prefix = stem;
        if (files[i].dds_set) {
            wo.dds_fields_set = 1;
            int base = files[i].dds_set == 1 ? MF_LTC_F_MINV_00 : MF_LTC_F_MAGNITUDE;
            for (int c = 0; c < 4; ++c)
                wo.dds_fields[c] = base + c;
        }
        mf_status st = mf_table_write(path, t, &wo, NULL, msg, sizeof msg);
        if (st != MF_OK) {
            cli_error(cmd, "%s (%s)", msg[0] ? msg : path, mf_status_str(st));
            return 3;
        }
    }
    snprintf(path, sizeof path, "%s/%s_fit.json", dir, stem);
    mf_status st = mf_ltcfit_write_sidecar(path, model, fo, t, r, msg, sizeof msg);
    if (st != MF_OK) {
        cli_error(cmd, "%s", msg);
        return 3;
    }
    snprintf(path, sizeof path, "%s/%s_gate.json", dir, stem);
    if (cli_buf_write_file_atomic(gate, path, msg, sizeof msg) != 0) {
        cli_error(cmd, "%s", msg);
        return 3;
    }
    return 0;
}

static void proxy_usage(FILE *f)
{
    fprintf(f,
            "usage: mfkit fit ggx-proxy [--out DIR] [--size N] [--quiet]\n\n"
            "Tabulates the exact GGX proxy roughness alpha'(alpha, dh) of Kaplanyan 2016 Eq. 19 (docs/math.md, correction C-K3)\n"
            "on an N x N grid log-spaced in alpha in [1e-3, 1] and dh in [1e-3, 10], fits (Ceres, analytic\n"
            "Jacobian, least squares of the relative error of alpha') the shader form\n"
            "  alpha'^2 = alpha^2 + dh^2 R(x), x = dh^2/(alpha^2 + dh^2), R = (1-x)/3 + x/pi + x(1-x) c/(1+q x)\n"
            "(limits dh << alpha and dh >> alpha built in), prints the coefficients and the max and mean\n"
            "relative errors of the fit and of sqrt(alpha^2 + dh^2), and writes into DIR (each file atomically):\n"
            "ggx_proxy_table.json, ggx_proxy_table.h (the table), ggx_proxy_fit.h, ggx_proxy_fit.glsl,\n"
            "ggx_proxy_fit.json (the coefficients and the error report).\n\n"
            "options:\n"
            "  --out DIR   output directory (default out/; created if missing)\n"
            "  --size N    grid points per axis, 2..1024 (default 64; the shipped coefficients of\n"
            "              mf_proxy.h come from the default)\n"
            "  --quiet     no summary on stderr\n\n"
            "exit status: 0 written, 2 usage error, 3 I/O error, 4 fit failed\n");
}

static int fit_ggx_proxy(int argc, char **argv)
{
    const char *cmd = "fit ggx-proxy", *out = "out";
    int quiet = 0;
    mf_proxyfit_options po;
    mf_proxyfit_options_default(&po);
    for (int i = 2; i < argc; ++i) {
        const char *a = argv[i];
        long v;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            proxy_usage(stdout);
            return 0;
        } else if (!strcmp(a, "--quiet")) {
            quiet = 1;
        } else if (i + 1 >= argc && (!strcmp(a, "--out") || !strcmp(a, "--size"))) {
            return cli_error(cmd, "option %s needs a value", a);
        } else if (!strcmp(a, "--out")) {
            out = argv[++i];
            if (!*out)
                return cli_error(cmd, "--out: empty path");
        } else if (!strcmp(a, "--size")) {
            if (cli_parse_int(argv[++i], 2, 1024, &v))
                return cli_error(cmd, "--size: bad value '%s' (2..1024)", argv[i]);
            po.size = (int)v;
        } else {
            return cli_error(cmd, "unknown option '%s' (see 'mfkit fit ggx-proxy --help')", a);
        }
    }
    mf_proxyfit_result r;
    mf_table t;
    mf_status st = mf_proxyfit_run(&po, &r, &t);
    if (st != MF_OK) {
        if (st == MF_ERR_NO_CONVERGENCE)
            mf_table_free(&t);
        cli_error(cmd, "%s%s%s", mf_status_str(st), st == MF_ERR_NO_CONVERGENCE ? ": " : "",
                  st == MF_ERR_NO_CONVERGENCE ? r.solver.message : "");
        return 4;
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
    if (make_dir(out) != 0) {
        cli_error(cmd, "%s: cannot create the output directory: %s", out, strerror(errno));
        rc = 3;
    }
    char msg[1024];
    if (rc == 0) {
        mf_status ws = mf_proxyfit_write(out, &po, &r, &t, "mfkit fit ggx-proxy " MFKIT_VERSION, msg, sizeof msg);
        if (ws != MF_OK) {
            cli_error(cmd, "%s (%s)", msg[0] ? msg : out, mf_status_str(ws));
            rc = 3;
        }
    }
    if (rc == 0 && cli_buf_write(&b, stdout) != 0)
        rc = 3;
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
        return argc < 2 ? 2 : 0;
    }
    if (!strcmp(argv[1], "ggx-proxy"))
        return fit_ggx_proxy(argc, argv);
    if (strcmp(argv[1], "ltc"))
        return cli_error("fit", "unknown table kind '%s' ('ltc' or 'ggx-proxy')", argv[1]);
    if (wants_list(argc, argv))
        return list_models();
    const char *brdf = "ggx", *out = "out";
    int force = 0, quiet = 0, resume = 0;
    mf_ltcfit_options fo;
    mf_ltcfit_options_default(&fo);
    long online = sysconf(_SC_NPROCESSORS_ONLN);
    fo.threads = online >= 1 ? (int)(online > 256 ? 256 : online) : 1;
    for (int i = 2; i < argc; ++i) {
        const char *a = argv[i];
        long v;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(a, "--force")) {
            force = 1;
        } else if (!strcmp(a, "--quiet")) {
            quiet = 1;
        } else if (!strcmp(a, "--resume")) {
            resume = 1;
        } else if (i + 1 >= argc && (!strcmp(a, "--brdf") || !strcmp(a, "--size") || !strcmp(a, "--threads") ||
                                     !strcmp(a, "--seed") || !strcmp(a, "--out") || !strcmp(a, "--samples") ||
                                     !strcmp(a, "--stop-after") || !strcmp(a, "--r-range") ||
                                     !strcmp(a, "--u-range"))) {
            return cli_error(cmd, "option %s needs a value", a);
        } else if (!strcmp(a, "--brdf")) {
            brdf = argv[++i];
        } else if (!strcmp(a, "--out")) {
            out = argv[++i];
            if (!*out)
                return cli_error(cmd, "--out: empty path");
        } else if (!strcmp(a, "--size")) {
            const char *s = argv[++i];
            const char *x = strchr(s, 'x');
            if (x) {
                char buf[32];
                size_t n = (size_t)(x - s);
                if (n >= sizeof buf)
                    return cli_error(cmd, "--size: bad value '%s'", s);
                memcpy(buf, s, n);
                buf[n] = '\0';
                long nu;
                if (cli_parse_int(buf, 2, 4096, &v) || cli_parse_int(x + 1, 2, 4096, &nu))
                    return cli_error(cmd, "--size: bad value '%s' (N or NRxNU, 2..4096)", s);
                fo.n_r = (int)v;
                fo.n_u = (int)nu;
            } else {
                if (cli_parse_int(s, 2, 4096, &v))
                    return cli_error(cmd, "--size: bad value '%s' (2..4096)", s);
                fo.n_r = fo.n_u = (int)v;
            }
        } else if (!strcmp(a, "--threads")) {
            if (cli_parse_int(argv[++i], 1, 256, &v))
                return cli_error(cmd, "--threads: bad value '%s' (1..256)", argv[i]);
            fo.threads = (int)v;
        } else if (!strcmp(a, "--samples")) {
            if (cli_parse_int(argv[++i], 64, 1 << 20, &v) || (v & (v - 1)))
                return cli_error(cmd, "--samples: bad value '%s' (a power of two, 64..1048576)", argv[i]);
            fo.samples = (int)v;
        } else if (!strcmp(a, "--r-range") || !strcmp(a, "--u-range")) {
            double lo, hi;
            if (parse_range(argv[++i], &lo, &hi))
                return cli_error(cmd, "%s: bad value '%s' (LO:HI with 0 <= LO < HI <= 1)", a, argv[i]);
            if (a[2] == 'r')
                fo.r_lo = lo, fo.r_hi = hi;
            else
                fo.u_lo = lo, fo.u_hi = hi;
        } else if (!strcmp(a, "--stop-after")) {
            if (cli_parse_int(argv[++i], 1, 4096, &v))
                return cli_error(cmd, "--stop-after: bad value '%s'", argv[i]);
            fo.stop_after_columns = (int)v;
        } else if (!strcmp(a, "--seed")) {
            char *end;
            errno = 0;
            unsigned long long s = strtoull(argv[++i], &end, 0);
            if (errno || *end || !*argv[i] || argv[i][0] == '-')
                return cli_error(cmd, "--seed: bad value '%s'", argv[i]);
            fo.seed = (uint64_t)s;
        } else {
            return cli_error(cmd, "unknown option '%s' (see 'mfkit fit ltc --help')", a);
        }
    }
    const mf_brdf_model *model = mf_brdf_model_find(brdf);
    if (!model)
        return cli_error(cmd, "unknown BRDF '%s' (see 'mfkit fit ltc --list')", brdf);
    if (make_dir(out) != 0) {
        cli_error(cmd, "%s: cannot create the output directory: %s", out, strerror(errno));
        return 3;
    }
    char stem[96], ckpt[4096];
    snprintf(stem, sizeof stem, "ltc_%s", model->name);
    for (char *s = stem; *s; ++s)
        if (*s == '-')
            *s = '_';
    snprintf(ckpt, sizeof ckpt, "%s/%s.checkpoint", out, stem);
    fo.checkpoint = ckpt;
    fo.resume = resume;
    fo.cancel = &g_cancel_int;
    progress_state ps = {!quiet && isatty(fileno(stderr)), {0, 0}, -1};
    clock_gettime(CLOCK_MONOTONIC, &ps.start);
    fo.progress = progress;
    fo.progress_user = &ps;
    if (!resume)
        remove(ckpt); /* a fresh fit never mixes with an old checkpoint */

    struct sigaction sa, old_int, old_term;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &old_int);
    sigaction(SIGTERM, &sa, &old_term);

    mf_table t;
    mf_ltcfit_result r;
    char msg[1024];
    mf_status st = mf_ltcfit_table(model, &fo, &t, &r, msg, sizeof msg);
    sigaction(SIGINT, &old_int, NULL);
    sigaction(SIGTERM, &old_term, NULL);
    double fit_wall = elapsed(&ps.start);
    if (st != MF_OK) {
        mf_ltcfit_result_free(&r);
        cli_error(cmd, "%s%s%s", mf_status_str(st), msg[0] ? ": " : "", msg);
        return st == MF_ERR_IO ? 3 : (st == MF_ERR_FORMAT || st == MF_ERR_DOMAIN) ? 2 : 4;
    }
    if (r.interrupted) {
        if (ps.show)
            fprintf(stderr, "\n");
        fprintf(stderr, "mfkit fit ltc: interrupted after %d of %d columns; no table written; '--resume' continues from %s\n",
                r.columns_done, fo.n_r, ckpt);
        mf_ltcfit_result_free(&r);
        return 130;
    }
    if (!quiet)
        fprintf(stderr, "fit: %s %dx%d in %.2f s (%d threads); worst residual %.4g; iterations max %d, mean %.1f; %d not converged%s\n",
                model->name, fo.n_r, fo.n_u, fit_wall, fo.threads, r.worst_residual, r.max_iterations,
                (double)r.total_iterations / ((double)fo.n_r * fo.n_u), r.not_converged,
                r.columns_resumed ? " (resumed)" : "");

    /* the gate */
    mf_ltc_gate_options go;
    mf_ltc_gate_options_default(&go);
    go.seed = fo.seed;
    go.threads = fo.threads;
    mf_check checks[MF_LTC_GATE_MAX_CHECKS + 4];
    int nchecks = 0;
    mf_status gs = mf_ltc_gate_run(&t, model, &go, checks, (int)(sizeof checks / sizeof checks[0]), &nchecks);
    if (gs != MF_OK && gs != MF_ERR_CHECK_FAILED) {
        mf_table_free(&t);
        mf_ltcfit_result_free(&r);
        cli_error(cmd, "gate: %s", mf_status_str(gs));
        return 4;
    }
    int all = gs == MF_OK;
    cli_buf tb = {0}, jb = {0};
    cli_buf_checks_table(&tb, checks, nchecks, all);
    gate_json(&jb, model->name, checks, nchecks, all, &r, fit_wall);
    int rc = 0;
    if (cli_buf_write(&tb, stdout) != 0)
        rc = 3;
    if (rc == 0 && !all && !force) {
        fprintf(stderr, "mfkit fit ltc: the gate failed (see the report above); nothing exported (use --force to export "
                        "anyway, marked unvalidated)\n");
        rc = 1;
    }
    if (rc == 0) {
        mf_status ms = mf_table_set_meta(&t, "validated", all ? "true" : "false");
        if (ms != MF_OK) {
            cli_error(cmd, "metadata: %s", mf_status_str(ms));
            rc = 4;
        }
    }
    if (rc == 0) {
        rc = export_all(cmd, out, stem, &t, model, &fo, &r, &jb);
        if (rc == 0) {
            remove(ckpt);
            if (!quiet)
                fprintf(stderr, "exported %s/%s.* %s\n", out, stem, all ? "(validated)" : "(NOT validated: --force)");
        }
    }
    cli_buf_free(&tb);
    cli_buf_free(&jb);
    mf_table_free(&t);
    mf_ltcfit_result_free(&r);
    return rc;
}
#endif
