/*
 * cli_validate.c -- `mfkit validate`: the property checks of the core math (mf_validate.h), or,
 * with a file argument, the gate of the table's kind (mf_table_kind.h: the LTC gate of
 * mf_ltc_gate.h for LTC tables, the kind's own checks for GGX proxy and moment-map tables) on a
 * table file: an mfkit table (EXR, DDS, JSON, NPY through mf_table_read) or the reference CSV
 * layout of the LTC table (mf_ltc_reference.h).
 * Exit code 0 when every check passes, 1 when one fails, 2 for a usage error, 3 for an I/O error.
 */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"
#include "cli_opt.h"
#include "cli_plot.h"
#include "cli_util.h"

#include "mfkit/mfkit.h"
#ifdef MFKIT_CLI_HAVE_SOLVER
#include "mfkit/fit/mf_ltc_validate.h"
#endif
#include "mfkit/io/mf_ltc_export.h"
#include "mfkit/io/mf_ltc_reference.h"
#include "mfkit/io/mf_table_io.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

enum { V_BRDF, V_QUICK, V_SEED, V_JSON, V_JSON_FILE, V_QUIET, V_NOPTS };
static const cli_opt k_validate_opts[V_NOPTS] = {
    {.name = "--brdf", .metavar = "NAME", .kind = CLI_OPT_STRING,
     .help = "with TABLE: the BRDF the table approximates (ggx, beckmann, lambert, ...; the list: mfkit fit ltc "
             "--help); 'none': model-free checks only (default: the table's \"brdf\" metadata)"},
    {.name = "--quick", .kind = CLI_OPT_FLAG,
     .help = "with TABLE: model checks on an 8 x 8 grid of texels (default: every texel for the albedo, a 16 x 16 "
             "grid for polygons)"},
    {.name = "--seed", .metavar = "S", .kind = CLI_OPT_U64, .def = "1", .help = "seed of the Monte Carlo checks"},
    {.name = "--json", .kind = CLI_OPT_FLAG, .help = "print the report as JSON on stdout instead of the table"},
    {.name = "--json-file", .metavar = "PATH", .kind = CLI_OPT_STRING,
     .help = "also write the JSON report to PATH (atomically)"},
    {.name = "--quiet", .kind = CLI_OPT_FLAG, .help = "no progress on stderr (progress is shown only on a terminal anyway)"},
};
static const cli_command k_validate_cmd = {
    .name = "validate",
    .synopsis = "[TABLE | TABLE_1 TABLE_2]",
    .min_pos = 0,
    .max_pos = 2,
    .description =
        "Without TABLE: runs the property checks of the core math over a grid of the whole domain\n"
        "(alpha 1e-4..1, view angles up to 89.99 deg, anisotropy up to 1:100, non-centred means up to\n"
        "slope 2) and prints one row per check: name, worst value, bound, pass/FAIL, cases, where the\n"
        "worst was.\n\n"
        "With TABLE (.exr, .dds, .json, .npy written by mfkit, or a .csv in the layout of the reference\n"
        "ltc_code table, .ktx2, or the three.js module <p>_three.js; or the two RGBA textures of an LTC\n"
        "table, TABLE_1 TABLE_2: ltc_1 and ltc_2 as .dds (also the reference code's legacy DDS without\n"
        "sidecars), .exr or .ktx2): finds the table's kind (its \"kind\" metadata, else its layout) and runs that\n"
        "kind's gate (docs/validation.md).  LTC tables: finite values, energy, normalisation, smoothness\n"
        "and, with the BRDF (--brdf, else the table's \"brdf\" metadata), albedo by quadrature and Monte\n"
        "Carlo, polygon shading against Monte Carlo, and every texel against its neighbours' predictions\n"
        "(ltc_texel_neighbours).  GGX proxy and moment-map tables: their own\n"
        "model-free checks.\n",
    .opts = k_validate_opts,
    .nopts = V_NOPTS,
    .epilog = "exit status: 0 all checks passed, 1 a check failed, 2 usage error, 3 I/O error\n",
};

typedef struct {
    int show;
    struct timespec start;
} progress_state;

static double elapsed(const struct timespec *t0)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)(t.tv_sec - t0->tv_sec) + 1e-9 * (double)(t.tv_nsec - t0->tv_nsec);
}

static void progress(void *user, int done, int total, const mf_check *last)
{
    progress_state *p = user;
    if (p->show)
        fprintf(stderr, "\r[%d/%d] %-22s %s  (%.1f s)   %s", done, total, last->name, last->passed ? "pass" : "FAIL",
                elapsed(&p->start), done == total ? "\n" : "");
}

static void report_json(cli_buf *b, const mf_check *c, int n, int all_passed)
{
    cli_buf_printf(b, "{\n  \"tool\": \"mfkit validate\",\n  \"version\": \"%s\",\n  \"passed\": %s,\n  \"checks\": ",
                   MFKIT_VERSION, all_passed ? "true" : "false");
    cli_buf_checks_json(b, c, n);
    cli_buf_printf(b, "\n}\n");
}

/* Writes the JSON report to json_file (atomically) if given, then the JSON or the text report to
 * stdout; frees both buffers.  rc is the status so far; returns the final exit status. */
static int emit_report(const char *cmd, int rc, cli_buf *jb, cli_buf *tb, int json, const char *json_file)
{
    char msg[1024];
    if (json_file && cli_buf_write_file_atomic(jb, json_file, msg, sizeof msg) != 0)
        rc = CLI_EXIT_IO, cli_error(cmd, "--json-file %s", msg);
    if (rc != CLI_EXIT_IO && cli_buf_write(json ? jb : tb, stdout) != 0)
        rc = CLI_EXIT_IO, cli_error(cmd, "stdout: write failed");
    cli_buf_free(jb);
    cli_buf_free(tb);
    return rc;
}

/* The gate of a table kind other than the LTC table's (model-free: GGX proxy, moment maps, ...). */
static int validate_kind(const char *path, const mf_table *t, const mf_table_kind *kind, double storage_u,
                         const char *brdf, int quick, uint64_t seed, int json, const char *json_file, int quiet)
{
    const char *cmd = "validate";
    if (brdf || quick)
        return cli_error(cmd, "%s: --brdf and --quick apply to LTC tables, this is a %s table", path, kind->name);
    int cap = kind->nchecks + 8, n = 0;
    mf_check *checks = calloc((size_t)cap, sizeof *checks);
    if (!checks)
        return cli_error(cmd, "out of memory"), CLI_EXIT_IO;
    struct timespec t0;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    if (!quiet && isatty(fileno(stderr)))
        fprintf(stderr, "mfkit validate: running the %s gate on %s...\n", kind->name, path);
    /* the model-free gates' bounds include the rounding of the file's storage (mf_table_kind.h) */
    mf_table_storage_options so = {storage_u};
    mf_status st = kind->gate(t, NULL, &so, checks, cap, &n);
    double secs = elapsed(&t0);
    if (st != MF_OK && st != MF_ERR_CHECK_FAILED) {
        free(checks);
        return cli_error(cmd, "%s: %s gate: %s", path, kind->name, mf_status_str(st)), CLI_EXIT_IO;
    }
    int all = (st == MF_OK);
    cli_buf jb = {0}, tb = {0};
    cli_buf_printf(&jb, "{\n  \"tool\": \"mfkit validate\",\n  \"version\": \"%s\",\n  \"table\": ", MFKIT_VERSION);
    cli_buf_json_string(&jb, path);
    cli_buf_printf(&jb, ",\n  \"kind\": \"%s\",\n  \"size\": [", kind->name);
    for (int k = 0; k < t->naxes; ++k)
        cli_buf_printf(&jb, "%s%d", k ? ", " : "", t->axes[k].size);
    cli_buf_printf(&jb, "],\n  \"brdf\": null,\n  \"seed\": %llu,\n  \"seconds\": %.3f,\n", (unsigned long long)seed,
                   secs);
    cli_buf body = {0};
    report_json(&body, checks, n, all);
    mf_buf_put(&body, "", 1); /* a C string for strstr (mf_buf holds bytes, no terminating NUL) */
    const char *p = body.failed ? NULL : strstr(body.data, "  \"passed\"");
    cli_buf_printf(&jb, "%s", p ? p : "}\n");
    cli_buf_free(&body);
    cli_buf_printf(&tb, "%s gate: %s (", kind->name, path);
    for (int k = 0; k < t->naxes; ++k)
        cli_buf_printf(&tb, "%s%d", k ? " x " : "", t->axes[k].size);
    cli_buf_printf(&tb, ", %s), model-free checks, %.2f s\n", kind->description, secs);
    cli_buf_checks_table(&tb, checks, n, all);
    free(checks);
    int rc = all ? CLI_EXIT_OK : CLI_EXIT_CHECK_FAILED;
    return emit_report(cmd, rc, &jb, &tb, json, json_file);
}


/* The gate of the table's kind on a table file: the LTC gate for LTC tables. */
static int validate_table(const char *path, const char *path2, const char *brdf, int quick, uint64_t seed, int json,
                          const char *json_file, int quiet)
{
    const char *cmd = "validate";
    mf_table t;
    mf_status st;
    int half = 0;
    /* a pair of LTC textures is read as "P_1+P_2", as every other command spells it */
    char pair_name[2048];
    if (path2) {
        if ((size_t)snprintf(pair_name, sizeof pair_name, "%s+%s", path, path2) >= sizeof pair_name)
            return cli_error(cmd, "%s: path too long", path);
    }
    int is_ref = !path2 && mf_table_format_from_path(path) == MF_TABLE_FORMAT_CSV;
    int rrc = cli_read_any_table(cmd, path2 ? pair_name : path, &t, &half);
    if (rrc)
        return rrc;
    if (path2) {
        snprintf(pair_name, sizeof pair_name, "%s + %s", path, path2);
        path = pair_name;
    }
    mf_table_file_info info = {0};
    info.half_float = half;
    /* the table's kind decides the gate; the LTC gate below keeps its own report */
    char why[256];
    const mf_table_kind *kind = mf_table_kind_of(&t, why, sizeof why);
    if (!kind) {
        int n0 = t.axes[0].size, n1 = t.naxes > 1 ? t.axes[1].size : 0, na = t.naxes, nf = t.nfields;
        mf_table_free(&t);
        return cli_error(cmd, "%s: not a table of a known kind (%d axes, first %d x %d, %d fields): %s", path, na, n0,
                         n1, nf, why), CLI_EXIT_IO;
    }
    if (strcmp(kind->name, "ltc_isotropic") != 0) {
        int rc = validate_kind(path, &t, kind, mf_table_storage_roundoff(info.half_float), brdf, quick, seed, json,
                               json_file, quiet);
        mf_table_free(&t);
        return rc;
    }
    const mf_brdf_model *model = NULL;
    const char *name = brdf ? brdf : mf_table_get_meta(&t, "brdf");
    if (name && strcmp(name, "none") != 0) {
        model = mf_brdf_model_find(name);
        if (!model) {
            mf_table_free(&t);
            return cli_error(cmd, "unknown BRDF '%s' (see 'mfkit fit ltc --help' for the names)", name);
        }
    }
    mf_ltc_gate_options o;
    mf_ltc_gate_options_default(&o);
    o.seed = seed;
    o.quick = quick;
    mf_ltc_gate_stats stats;
    memset(&stats, 0, sizeof stats);
    o.stats = &stats;
    mf_check checks[MF_LTC_VALIDATE_MAX_CHECKS]; /* the gate and the neighbour check */
    int n = 0;
    struct timespec t0;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    if (!quiet && isatty(fileno(stderr)))
        fprintf(stderr, "mfkit validate: running the LTC gate on %s (%s)...\n", path, model ? model->name : "no model");
    /* the gate, then with a model every texel against its neighbours' predictions
     * (ltc_texel_neighbours; the Python module's validate() runs the same function) */
#ifdef MFKIT_CLI_HAVE_SOLVER
    /* a table mfkit's fitter made: the neighbour check's candidate texels refitted (mf_ltc_validate.h) */
    st = mf_ltc_validate_fitted(&t, model, &o, checks, MF_LTC_VALIDATE_MAX_CHECKS, &n, NULL);
#else
    st = mf_ltc_gate_validate(&t, model, &o, checks, MF_LTC_VALIDATE_MAX_CHECKS, &n);
#endif
    double secs = elapsed(&t0);
    int n_r = t.axes[0].size, n_u = t.naxes > 1 ? t.axes[1].size : 0;
    mf_table_free(&t);
    if (st == MF_ERR_DOMAIN)
        return cli_error(cmd, "%s: not an LTC table layout (two axes r: alpha = r^2 and u: cos = 1 - u^2, fields "
                              "minv_00, minv_20, minv_02, minv_22, magnitude)", path), CLI_EXIT_IO;
    if (st != MF_OK && st != MF_ERR_CHECK_FAILED)
        return cli_error(cmd, "%s: %s", path, mf_status_str(st)), CLI_EXIT_IO;
    int all = (st == MF_OK);
    cli_buf jb = {0}, tb = {0};
    cli_buf_printf(&jb, "{\n  \"tool\": \"mfkit validate\",\n  \"version\": \"%s\",\n  \"table\": ", MFKIT_VERSION);
    cli_buf_json_string(&jb, path);
    cli_buf_printf(&jb, ",\n  \"layout\": \"%s\",\n  \"size\": [%d, %d],\n  \"brdf\": ",
                   is_ref ? "reference-csv" : "mfkit", n_r, n_u);
    if (model)
        cli_buf_json_string(&jb, model->name);
    else
        cli_buf_printf(&jb, "null");
    cli_buf_printf(&jb, ",\n  \"seed\": %llu,\n  \"quick\": %s,\n  \"seconds\": %.3f,\n", (unsigned long long)seed,
                   quick ? "true" : "false", secs);
    if (model) {
        cli_buf_printf(&jb, "  \"polygon_errors\": {\"polygons\": %ld, \"texels\": %ld, \"mean_abs\": ", stats.polygons,
                       stats.entries);
        cli_buf_json_number(&jb, stats.mean_abs);
        cli_buf_printf(&jb, ", \"p95_abs\": ");
        cli_buf_json_number(&jb, stats.p95_abs);
        cli_buf_printf(&jb, ", \"worst_abs\": ");
        cli_buf_json_number(&jb, stats.worst_abs);
        cli_buf_printf(&jb, ", \"mean_rel\": ");
        cli_buf_json_number(&jb, stats.mean_rel);
        cli_buf_printf(&jb, ", \"p95_rel\": ");
        cli_buf_json_number(&jb, stats.p95_rel);
        cli_buf_printf(&jb, ", \"worst_rel\": ");
        cli_buf_json_number(&jb, stats.worst_rel);
        cli_buf_printf(&jb, ", \"mean_mc_se\": ");
        cli_buf_json_number(&jb, stats.mean_se);
        cli_buf_printf(&jb, "},\n");
    }
    /* The checks, as for the core report (drop its opening lines). */
    cli_buf body = {0};
    report_json(&body, checks, n, all);
    mf_buf_put(&body, "", 1); /* a C string for strstr */
    const char *p = body.failed ? NULL : strstr(body.data, "  \"passed\"");
    cli_buf_printf(&jb, "%s", p ? p : "}\n");
    cli_buf_free(&body);

    cli_buf_printf(&tb, "LTC gate: %s (%d x %d, %s), BRDF %s, seed %llu, %s, %.2f s\n", path, n_r, n_u,
                   is_ref ? "reference CSV layout" : "mfkit table", model ? model->name : "none (model-free checks)",
                   (unsigned long long)seed, quick ? "quick" : "full", secs);
    cli_buf_checks_table(&tb, checks, n, all);
    if (model)
        cli_buf_printf(&tb,
                       "polygon shading vs Monte Carlo (%ld polygons at %ld texels): |error| mean %.4g, p95 %.4g, worst "
                       "%.4g; relative mean %.4g, p95 %.4g, worst %.4g (MC se mean %.2g)\n",
                       stats.polygons, stats.entries, stats.mean_abs, stats.p95_abs, stats.worst_abs, stats.mean_rel,
                       stats.p95_rel, stats.worst_rel, stats.mean_se);
    int rc = all ? CLI_EXIT_OK : CLI_EXIT_CHECK_FAILED;
    return emit_report(cmd, rc, &jb, &tb, json, json_file);
}

int cli_validate(int argc, char **argv)
{
    const char *cmd = "validate";
    cli_val v[V_NOPTS];
    const char *pos[2];
    int npos;
    int prc = cli_opt_parse(&k_validate_cmd, argc - 1, argv + 1, ~0u, NULL, v, pos, &npos);
    if (prc == CLI_PARSE_HELP) {
        cli_opt_usage(&k_validate_cmd, stdout);
        return 0;
    }
    if (prc)
        return prc;
    int json = v[V_JSON].set, quiet = v[V_QUIET].set, quick = v[V_QUICK].set;
    const char *json_file = v[V_JSON_FILE].set ? v[V_JSON_FILE].s : NULL;
    const char *table_path = npos ? pos[0] : NULL, *table2 = npos > 1 ? pos[1] : NULL, *brdf = v[V_BRDF].set ? v[V_BRDF].s : NULL;
    unsigned long long seed = v[V_SEED].set ? v[V_SEED].u : 1;
    if (!table_path && (quick || brdf))
        return cli_error(cmd, "--quick and --brdf need a TABLE argument");
    if (table_path)
        return validate_table(table_path, table2, brdf, quick, (uint64_t)seed, json, json_file, quiet);
    int n = mf_validate_core_count();
    mf_check *checks = calloc((size_t)n, sizeof *checks);
    if (!checks)
        return cli_error(cmd, "out of memory"), CLI_EXIT_IO;
    progress_state ps = {!quiet && isatty(fileno(stderr)), {0, 0}};
    clock_gettime(CLOCK_MONOTONIC, &ps.start);
    mf_status st = mf_validate_core(checks, n, progress, &ps);
    if (st != MF_OK && st != MF_ERR_CHECK_FAILED) {
        free(checks);
        cli_error(cmd, "%s", mf_status_str(st));
        return cli_exit_code(st);
    }
    int all = (st == MF_OK);
    cli_buf jb = {0}, tb = {0};
    report_json(&jb, checks, n, all);
    cli_buf_checks_table(&tb, checks, n, all);
    free(checks);
    int rc = all ? CLI_EXIT_OK : CLI_EXIT_CHECK_FAILED;
    return emit_report(cmd, rc, &jb, &tb, json, json_file);
}
