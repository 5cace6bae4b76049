/*
 * cli_fit_aniso.c -- `mfkit fit ltc-aniso`: fit the 4-D anisotropic LTC table (mf_ltcfit_aniso.h),
 * run its gate (mf_ltc_aniso_table.h), export it (mf_table_write: JSON, NPY, EXR; and the
 * published layout <prefix>_kt.npy).
 */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"
#include "cli_opt.h"
#include "cli_util.h"

#include "mfkit/mfkit.h"

#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#ifdef MFKIT_CLI_HAVE_SOLVER
#include "mfkit/mf_ltc_aniso_table.h"
#include "mfkit/fit/mf_ltcfit_aniso.h"
#include "mfkit/io/mf_ltc_aniso_shader.h"
#include "mfkit/io/mf_table_io.h"

/* --size N or AxBxCxD, each 2..256: a packs the four sizes (8 bits - 1 each... stored in v->a as
 * base-257 digits) */
static int parse_size4(const char *s, cli_val *v)
{
    long n[4];
    int k = 0;
    const char *p = s;
    char buf[16];
    while (k < 4) {
        const char *x = strchr(p, 'x');
        size_t len = x ? (size_t)(x - p) : strlen(p);
        if (len == 0 || len >= sizeof buf)
            return -1;
        memcpy(buf, p, len);
        buf[len] = '\0';
        if (cli_parse_int(buf, 2, 256, &n[k]))
            return -1;
        ++k;
        if (!x)
            break;
        p = x + 1;
    }
    if (k == 1)
        n[1] = n[2] = n[3] = n[0];
    else if (k != 4 || strchr(p, 'x'))
        return -1;
    v->a = ((n[0] * 257 + n[1]) * 257 + n[2]) * 257 + n[3];
    return 0;
}

static const char *const k_params[] = {"alpha-xy", "alpha-lambda", NULL};
static const char *const k_objectives[] = {"default", "relative", NULL}; /* MF_LTCFIT_ANISO_OBJECTIVE_* */

enum { A_BRDF, A_SIZE, A_PARAM, A_THREADS, A_SEED, A_OUT, A_FORCE, A_QUIET, A_RESUME, A_STOP_AFTER, A_OBJECTIVE, A_NOPTS };
static const cli_opt k_opts[A_NOPTS] = {
    {.name = "--brdf", .metavar = "NAME", .kind = CLI_OPT_STRING, .def = "ggx",
     .help = "the BRDF model (an anisotropic one: it reads alpha_x and alpha_y)"},
    {.name = "--size", .metavar = "N|AxBxCxD", .kind = CLI_OPT_CUSTOM, .parse = parse_size4,
     .expect = "N or AxBxCxD with each in [2, 256]", .def = "8",
     .help = "entries along (alpha_x or alpha, alpha_y or lambda, theta, phi)"},
    {.name = "--param", .kind = CLI_OPT_ENUM, .choices = k_params, .def = "alpha-xy",
     .help = "the roughness axes: (alpha_x, alpha_y) or (alpha, lambda = alpha_y / alpha_x)"},
    {.name = "--threads", .metavar = "N", .kind = CLI_OPT_INT, .lo = 1, .hi = 256,
     .def = "the number of online CPUs", .help = "worker threads; the result does not depend on it, bit for bit"},
    {.name = "--seed", .metavar = "S", .kind = CLI_OPT_U64, .def = "1",
     .help = "scramble of the sample points and seed of the gate"},
    {.name = "--out", .metavar = "DIR", .kind = CLI_OPT_STRING, .def = "out/; created if missing",
     .help = "output directory"},
    {.name = "--force", .kind = CLI_OPT_FLAG,
     .help = "export even if a gate check fails (metadata \"validated\" = \"false\")"},
    {.name = "--quiet", .kind = CLI_OPT_FLAG, .help = "no summary on stderr"},
    {.name = "--resume", .kind = CLI_OPT_FLAG,
     .help = "continue from DIR/ltca_<brdf>.checkpoint (same settings) if it exists"},
    {.name = "--stop-after", .metavar = "K", .kind = CLI_OPT_INT, .lo = 1, .hi = 65536,
     .help = "(testing) stop as if interrupted after fitting K (alpha_x, alpha_y) pairs"},
    {.name = "--objective", .kind = CLI_OPT_ENUM, .choices = k_objectives, .def = "default",
     .help = "residual weights 1 / (I + 1 albedo) (default) or 1 / (I + 0.01 albedo) (relative; measured "
             "worse on the benchmark, docs/validation.md)"},
};
static const cli_command k_cmd = {
    .name = "fit ltc-aniso",
    .synopsis = "",
    .min_pos = 0,
    .max_pos = 0,
    .description = "Fits the 4-D anisotropic LTC table of a BRDF over (alpha_x, alpha_y, theta, phi in [0, pi/2]),\n"
                   "runs its gate and exports it into DIR only if every check passed.\n",
    .opts = k_opts,
    .nopts = A_NOPTS,
    .epilog = "files (in DIR, <p> = ltca_<brdf>): <p>.json, <p>.npy, <p>.exr (all fields; skipped with a note\n"
              "where this build cannot write 4-axis EXR), <p>_kt.npy (the published layout: forward M,\n"
              "(n0, n1, n2, n3, 3, 3) float32, divided by the norm of its last column), <p>.glsl and <p>.hlsl\n"
              "(the lookup snippet: any azimuth, all four axes interpolated, returns M^-1, M, magnitude and\n"
              "fresnel) and its three textures <p>_m0.dds, <p>_m1.dds, <p>_m2.dds (RGBA32F atlases).\n\n"
              "Every completed (alpha_x, alpha_y) pair is appended to DIR/ltca_<brdf>.checkpoint; after an\n"
              "interruption (SIGINT, SIGTERM, a kill) '--resume' fits only the missing pairs, and the table is\n"
              "the same, bit for bit.  The checkpoint is removed after a successful export.\n\n"
              "exit status: 0 exported, 1 a gate check failed, 2 usage error, 3 I/O error, 4 fit failed,\n"
              "130 interrupted\n",
};

/* set by the handler; an int is written atomically on every platform mfkit builds on */
static volatile int g_cancel_aniso = 0;

static void on_signal(int sig)
{
    (void)sig;
    g_cancel_aniso = 1;
}

static int make_dir(const char *dir)
{
    if (mkdir(dir, 0777) == 0 || errno == EEXIST)
        return 0;
    return -1;
}

int cli_fit_aniso(int argc, char **argv)
{
    const char *cmd = "fit ltc-aniso";
    cli_val v[A_NOPTS];
    const char *pos[1];
    int npos;
    int prc = cli_opt_parse(&k_cmd, argc - 2, argv + 2, ~0u, NULL, v, pos, &npos);
    if (prc == CLI_PARSE_HELP) {
        cli_opt_usage(&k_cmd, stdout);
        return 0;
    }
    if (prc)
        return prc;
    const char *brdf = v[A_BRDF].set ? v[A_BRDF].s : "ggx";
    const mf_brdf_model *model = mf_brdf_model_find(brdf);
    if (!model)
        return cli_error(cmd, "--brdf: unknown model '%s' (mfkit fit ltc --list)", brdf);
    if (!(model->flags & MF_MODEL_ANISOTROPIC))
        return cli_error(cmd, "--brdf: model '%s' is isotropic (it ignores alpha_y); use 'mfkit fit ltc'", brdf);
    mf_ltcfit_aniso_options o;
    mf_ltcfit_aniso_options_default(&o);
    if (v[A_SIZE].set) {
        long a = v[A_SIZE].a;
        for (int k = 3; k >= 0; --k) {
            o.n[k] = (int)(a % 257);
            a /= 257;
        }
    }
    o.param = v[A_PARAM].set ? (int)v[A_PARAM].i : MF_LTC_ANISO_PARAM_ALPHA_XY;
    o.objective = v[A_OBJECTIVE].set ? (int)v[A_OBJECTIVE].i : MF_LTCFIT_ANISO_OBJECTIVE_DEFAULT;
    long cpus = sysconf(_SC_NPROCESSORS_ONLN);
    o.threads = v[A_THREADS].set ? (int)v[A_THREADS].i : (int)(cpus >= 1 ? (cpus > 256 ? 256 : cpus) : 1);
    if (v[A_SEED].set)
        o.seed = v[A_SEED].u;
    const char *out = v[A_OUT].set ? v[A_OUT].s : "out";
    int quiet = v[A_QUIET].set, force = v[A_FORCE].set;
    if (make_dir(out) != 0)
        return cli_error(cmd, "%s: cannot create the output directory: %s", out, strerror(errno));
    char ckpt[4096];
    if (snprintf(ckpt, sizeof ckpt, "%s/ltca_%s.checkpoint", out, brdf) >= (int)sizeof ckpt)
        return cli_error(cmd, "--out: path too long");
    o.checkpoint = ckpt;
    o.resume = v[A_RESUME].set;
    if (v[A_STOP_AFTER].set)
        o.stop_after_pairs = (int)v[A_STOP_AFTER].i;
    g_cancel_aniso = 0;
    o.cancel = &g_cancel_aniso;
    struct sigaction sa, old_int, old_term;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &old_int);
    sigaction(SIGTERM, &sa, &old_term);
    mf_table t;
    mf_ltcfit_aniso_result r;
    char msg[1024];
    mf_status st = mf_ltcfit_aniso_table(model, &o, &t, &r, msg, sizeof msg);
    sigaction(SIGINT, &old_int, NULL);
    sigaction(SIGTERM, &old_term, NULL);
    if (st != MF_OK) {
        cli_error(cmd, "%s", msg[0] ? msg : mf_status_str(st));
        mf_ltcfit_aniso_result_free(&r);
        return cli_exit_code(st) == CLI_EXIT_IO || st == MF_ERR_FORMAT ? CLI_EXIT_IO : CLI_EXIT_FIT;
    }
    if (r.interrupted) {
        fprintf(stderr, "mfkit fit ltc-aniso: interrupted after %d of %d roughness pairs; no table written; '--resume' "
                        "continues from %s\n",
                r.pairs_done, o.n[0] * o.n[1], ckpt);
        mf_ltcfit_aniso_result_free(&r);
        return CLI_EXIT_INTERRUPTED;
    }
    printf("fit: %d x %d x %d x %d entries, worst residual %.4g (entry %d), not converged %d, max iterations %d, "
           "anchor fallbacks %d%s\n",
           o.n[0], o.n[1], o.n[2], o.n[3], r.worst_residual, r.worst_index, r.not_converged, r.max_iterations,
           r.anchor_fallbacks, r.pairs_resumed ? " (resumed)" : "");
    /* every unconverged entry (there should be none), with its indices, values and final cost */
    for (int i = 0, listed = 0; i < (int)mf_table_texels(&t) && listed < r.not_converged; ++i) {
        const mf_ltcfit_aniso_entry *e = &r.entries[i];
        if (e->converged)
            continue;
        int idx[4] = {i % o.n[0], i / o.n[0] % o.n[1], i / (o.n[0] * o.n[1]) % o.n[2], i / (o.n[0] * o.n[1] * o.n[2])};
        double ax, ay, th, ph;
        mf_ltc_aniso_entry_values(&t, idx, &ax, &ay, &th, &ph);
        printf("not converged: entry %d (%d, %d, %d, %d: alpha_x %.4g, alpha_y %.4g, theta %.2f deg, phi %.2f deg%s), "
               "residual %.4g after %d iterations\n",
               i, idx[0], idx[1], idx[2], idx[3], ax, ay, th * 180.0 / MF_PI, ph * 180.0 / MF_PI,
               e->anchor ? ", anchor: fitted at the cell midpoint" : "", e->residual, e->iterations);
        ++listed;
    }
    mf_ltc_aniso_gate_options go;
    mf_ltc_aniso_gate_options_default(&go);
    go.seed = o.seed;
    mf_check ch[MF_LTC_ANISO_GATE_MAX_CHECKS];
    int nc = 0;
    mf_status gs = mf_ltc_aniso_gate_run(&t, model, &go, ch, MF_LTC_ANISO_GATE_MAX_CHECKS, &nc);
    printf("%-20s %-12s %-10s %-6s %s\n", "check", "worst", "bound", "result", "worst case");
    for (int i = 0; i < nc; ++i)
        printf("%-20s %-12.4g %-10.3g %-6s %s\n", ch[i].name, ch[i].worst, ch[i].bound, ch[i].passed ? "pass" : "FAIL",
               ch[i].worst_at);
    int rc = 0;
    if (gs != MF_OK && gs != MF_ERR_CHECK_FAILED) {
        cli_error(cmd, "gate: %s", mf_status_str(gs));
        rc = CLI_EXIT_IO;
    } else if (gs == MF_ERR_CHECK_FAILED && !force) {
        fprintf(stderr, "mfkit fit ltc-aniso: the gate failed (see the report above); nothing exported (use --force to "
                        "export anyway)\n");
        rc = CLI_EXIT_CHECK_FAILED;
    }
    if (rc == 0 && mf_table_set_meta(&t, "validated", gs == MF_OK ? "true" : "false") != MF_OK)
        rc = CLI_EXIT_IO;
    if (rc == 0 && make_dir(out) != 0) {
        cli_error(cmd, "%s: cannot create the output directory: %s", out, strerror(errno));
        rc = CLI_EXIT_IO;
    }
    char path[4096];
    const char *exts[3] = {"json", "npy", "exr"};
    for (int k = 0; k < 3 && rc == 0; ++k) {
        snprintf(path, sizeof path, "%s/ltca_%s.%s", out, brdf, exts[k]);
        mf_table_write_options wo;
        mf_table_write_options_default(&wo);
        mf_status ws = mf_table_write(path, &t, &wo, NULL, msg, sizeof msg);
        if (ws == MF_ERR_UNSUPPORTED) {
            if (!quiet)
                fprintf(stderr, "note: %s skipped: %s\n", path, msg[0] ? msg : "unsupported for 4 axes in this build");
        } else if (ws != MF_OK) {
            cli_error(cmd, "%s (%s)", msg[0] ? msg : path, mf_status_str(ws));
            rc = CLI_EXIT_IO;
        }
    }
    if (rc == 0) {
        snprintf(path, sizeof path, "%s/ltca_%s_kt.npy", out, brdf);
        mf_status ws = mf_ltcfit_aniso_write_kt_npy(path, &t, msg, sizeof msg);
        if (ws != MF_OK) {
            cli_error(cmd, "%s (%s)", msg[0] ? msg : path, mf_status_str(ws));
            rc = CLI_EXIT_IO;
        }
    }
    /* the lookup snippet and the three textures it samples */
    for (int k = 0; k < 3 && rc == 0; ++k) {
        snprintf(path, sizeof path, "%s/ltca_%s_m%d.dds", out, brdf, k);
        mf_table_write_options wo;
        mf_table_write_options_default(&wo);
        memcpy(wo.dds_fields, mf_ltc_aniso_shader_fields[k], sizeof wo.dds_fields);
        wo.dds_fields_set = 1;
        mf_status ws = mf_table_write(path, &t, &wo, NULL, msg, sizeof msg);
        if (ws != MF_OK) {
            cli_error(cmd, "%s (%s)", msg[0] ? msg : path, mf_status_str(ws));
            rc = CLI_EXIT_IO;
        }
    }
    for (int hlsl = 0; hlsl <= 1 && rc == 0; ++hlsl) {
        char prefix[80];
        snprintf(prefix, sizeof prefix, "ltca_%s", brdf);
        for (char *c = prefix; *c; ++c)
            if (!((*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') || (*c >= '0' && *c <= '9')))
                *c = '_';
        snprintf(path, sizeof path, "%s/ltca_%s.%s", out, brdf, hlsl ? "hlsl" : "glsl");
        mf_status ws =
            mf_ltc_aniso_shader_write(path, &t, hlsl ? MF_SHADER_HLSL : MF_SHADER_GLSL, prefix, msg, sizeof msg);
        if (ws != MF_OK) {
            cli_error(cmd, "%s (%s)", msg[0] ? msg : path, mf_status_str(ws));
            rc = CLI_EXIT_IO;
        }
    }
    /* the area-light code (mf_ltc_shader.h): ltca_<brdf>_area.glsl, .hlsl, .wgsl */
    for (int l = MF_SHADER_GLSL; l <= MF_SHADER_WGSL && rc == 0; ++l) {
        char prefix[80];
        snprintf(prefix, sizeof prefix, "ltca_%s", brdf);
        for (char *c = prefix; *c; ++c)
            if (!((*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') || (*c >= '0' && *c <= '9')))
                *c = '_';
        snprintf(path, sizeof path, "%s/ltca_%s_area.%s", out, brdf, mf_shader_lang_name((mf_shader_lang)l));
        mf_status ws = mf_ltc_shader_write(path, &t, (mf_shader_lang)l, prefix, msg, sizeof msg);
        if (ws != MF_OK) {
            cli_error(cmd, "%s (%s)", msg[0] ? msg : path, mf_status_str(ws));
            rc = CLI_EXIT_IO;
        }
    }
    if (rc == 0)
        remove(ckpt);
    if (rc == 0 && !quiet)
        fprintf(stderr,
                "exported %s/ltca_%s.{json,npy,exr,glsl,hlsl}, %s/ltca_%s_m{0,1,2}.dds, %s/ltca_%s_kt.npy and "
                "%s/ltca_%s_area.{glsl,hlsl,wgsl}\n",
                out, brdf, out, brdf, out, brdf, out, brdf);
    mf_table_free(&t);
    mf_ltcfit_aniso_result_free(&r);
    return rc;
}
#else
int cli_fit_aniso(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    return cli_error("fit ltc-aniso", "this mfkit was built without the fitting dependencies");
}
#endif
