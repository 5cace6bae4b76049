/*
 * cli_eval.c -- `mfkit eval FUNCTION [options]`: CSV on stdin -> CSV on stdout.
 *
 * Every input column is echoed as read, then the outputs (%.17g).  Rows whose inputs are
 * outside the domain give nan outputs.  A missing required column, a field that is not a
 * number, or a bad option is an error: one line on stderr, exit code 2, nothing on stdout
 * (output is buffered until the whole input has been processed).  docs/cli.md lists the
 * functions; their names and columns are a public interface.
 *
 * The functions, their options and columns are the registry of mfkit/eval/mf_eval.h (shared
 * with the Python module); this file is the CSV front of it.  Polygon functions: an empty vertex
 * field is "unused" and goes to the evaluator as NaN, as does an absent optional column.
 */
#include "cli.h"
#include "cli_opt.h"
#include "cli_util.h"

#include "mfkit/eval/mf_eval.h"
#include "mfkit/mfkit.h"

#include <stdlib.h>
#include <string.h>

/* The options of eval: the registry's, spelled "--name" (built once, on the first call). */
static cli_opt g_eval_opts[MF_EVAL_NOPTS];
static char g_eval_opt_names[MF_EVAL_NOPTS][40];

static const cli_command *eval_command(void)
{
    static cli_command cmd = {
        .name = "eval",
        .synopsis = "FUNCTION",
        .min_pos = 0, /* "missing FUNCTION" below */
        .max_pos = 1,
        .description = "Reads CSV with a header from stdin and writes CSV to stdout (< in.csv > out.csv): every input\n"
                       "column echoed, then the outputs (%.17g). Rows outside the domain give nan. Directions are unit\n"
                       "vectors in the z-up shading frame, pointing away from the surface.\n",
        .opts = g_eval_opts,
        .nopts = MF_EVAL_NOPTS,
        .epilog = NULL, /* the function list: eval_usage */
    };
    static const cli_opt_kind kinds[] = {[MF_EVAL_KIND_ENUM] = CLI_OPT_ENUM, [MF_EVAL_KIND_INT] = CLI_OPT_INT,
                                         [MF_EVAL_KIND_DOUBLE] = CLI_OPT_DOUBLE};
    if (!g_eval_opts[0].name)
        for (int k = 0; k < MF_EVAL_NOPTS; ++k) {
            const mf_eval_option *e = mf_eval_option_at(k);
            snprintf(g_eval_opt_names[k], sizeof g_eval_opt_names[k], "--%s", e->name);
            g_eval_opts[k] = (cli_opt){.name = g_eval_opt_names[k], .metavar = e->metavar, .kind = kinds[e->kind],
                                       .lo = e->lo, .hi = e->hi, .multiple = e->multiple, .dlo = e->dlo,
                                       .dhi = e->dhi, .lo_open = e->lo_open, .choices = e->choices, .def = e->def,
                                       .help = e->help, .mask = 1u << k};
        }
    return &cmd;
}

/* The option mask (bit k: option k) a function takes, for cli_opt_parse. */
static unsigned takes_mask(const mf_eval_function *f)
{
    unsigned m = 0;
    for (int k = 0; k < MF_EVAL_NOPTS; ++k)
        if (mf_eval_function_takes(f, k))
            m |= 1u << k;
    return m;
}

static void print_list(FILE *f, const char *const *names, int n)
{
    for (int k = 0; k < n; ++k)
        fprintf(f, "%s%s", k ? "," : "", names[k]);
}

static void eval_usage(FILE *f)
{
    cli_opt_usage(eval_command(), f);
    fprintf(f, "\nPolygons: n (3..8) vertices v0..v7 (positions relative to the shading point); columns v3..v7\n"
               "may be absent and empty vertex fields are unused.\n\n"
               "functions (inputs -> outputs):\n");
    for (int i = 0; i < mf_eval_function_count(); ++i) {
        const mf_eval_function *e = mf_eval_function_at(i);
        const char *in[MF_EVAL_MAX_INPUTS], *out[MF_EVAL_MAX_OUTPUTS], *out_b[MF_EVAL_MAX_OUTPUTS];
        int nin = mf_eval_inputs(e, NULL, in, NULL);
        if (mf_eval_function_polygon(e))
            nin -= 3 * MF_POLYGON_MAX_VERTICES;
        fprintf(f, "  %-16s%s %s\n    ", mf_eval_function_name(e),
                mf_eval_function_requires(e, MF_EVAL_OPT_NDF) ? "*" : " ", mf_eval_function_summary(e));
        print_list(f, in, nin);
        if (mf_eval_function_takes(e, MF_EVAL_OPT_FRESNEL))
            fprintf(f, "[,f0]");
        if (mf_eval_function_polygon(e))
            fprintf(f, ",v0_x,v0_y,v0_z,...,v2_z[,v3_x,...,v7_z]");
        fprintf(f, " -> ");
        int nout = mf_eval_outputs(e, NULL, out);
        print_list(f, out, nout);
        mf_eval_value beckmann[MF_EVAL_NOPTS] = {{0}};
        beckmann[MF_EVAL_OPT_NDF] = (mf_eval_value){1, 1, 0.0};
        int nout_b = mf_eval_outputs(e, beckmann, out_b);
        if (nout_b != nout || memcmp(out, out_b, sizeof(char *) * (size_t)nout) != 0) {
            fprintf(f, " (beckmann: ");
            print_list(f, out_b, nout_b);
            fprintf(f, ")");
        }
        fprintf(f, "\n");
    }
    fprintf(f, "\nexit status: 0 success, 2 usage or input error, 3 I/O error\n");
}

int cli_eval(int argc, char **argv)
{
    const char *cmd = "eval";
    const cli_command *ecmd = eval_command();
    const mf_eval_function *e = NULL;
    /* the function first: it decides which options apply */
    if (argc >= 2 && argv[1][0] != '-') {
        e = mf_eval_function_find(argv[1]);
        if (!e)
            return cli_error(cmd, "unknown function '%s' (see 'mfkit eval --help')", argv[1]);
    }
    cli_val v[MF_EVAL_NOPTS];
    const char *pos[1];
    int npos;
    int rc = cli_opt_parse(ecmd, argc - 1, argv + 1, e ? takes_mask(e) : ~0u, e ? mf_eval_function_name(e) : cmd, v,
                           pos, &npos);
    if (rc == CLI_PARSE_HELP) {
        eval_usage(stdout);
        return 0;
    }
    if (rc)
        return rc;
    if (!e)
        return cli_error(cmd, "missing FUNCTION (see 'mfkit eval --help')");
    const char *name = mf_eval_function_name(e);

    mf_eval_value opts[MF_EVAL_NOPTS];
    for (int k = 0; k < MF_EVAL_NOPTS; ++k)
        opts[k] = (mf_eval_value){v[k].set, v[k].i, v[k].d};
    if (mf_eval_function_requires(e, MF_EVAL_OPT_NDF) && !opts[MF_EVAL_OPT_NDF].set)
        return cli_error(cmd, "%s: --ndf ggx|beckmann is required", name);
    char msg[256];
    if (mf_eval_check_options(e, opts, msg, sizeof msg) != MF_OK) /* cli_opt_parse checked the same limits */
        return cli_error(cmd, "%s", msg);

    /* input columns: required ones, then (polygon functions) the vertex columns, of which only the
     * first three vertices are required */
    const char *inputs[MF_EVAL_MAX_INPUTS], *outputs[MF_EVAL_MAX_OUTPUTS];
    int required[MF_EVAL_MAX_INPUTS];
    int nin = mf_eval_inputs(e, opts, inputs, required), nout = mf_eval_outputs(e, opts, outputs);
    int polygon = mf_eval_function_polygon(e);
    int first_vertex = polygon ? nin - 3 * MF_POLYGON_MAX_VERTICES : nin;

    cli_csv csv;
    if (cli_csv_read(stdin, &csv, msg, sizeof msg) != 0)
        return cli_error(cmd, "%s: stdin: %s", name, msg);
    int col[MF_EVAL_MAX_INPUTS];
    for (int k = 0; k < nin; ++k) {
        col[k] = cli_csv_column(&csv, inputs[k]);
        if (col[k] < 0 && required[k]) {
            cli_csv_free(&csv);
            return cli_error(cmd, "%s: stdin: missing required column '%s'", name, inputs[k]);
        }
    }
    for (int k = 0; k < nout; ++k)
        if (cli_csv_column(&csv, outputs[k]) >= 0) {
            cli_csv_free(&csv);
            return cli_error(cmd, "%s: stdin: input already has a column named '%s' (an output)", name, outputs[k]);
        }

    /* the present input columns as doubles, then one vectorised evaluation */
    size_t nrows = (size_t)csv.nrows;
    const char *names[MF_EVAL_MAX_INPUTS];
    const double *cols[MF_EVAL_MAX_INPUTS];
    double *colv[MF_EVAL_MAX_INPUTS];
    double *outs[MF_EVAL_MAX_OUTPUTS];
    int ncols = 0, status = 0;
    double *store = malloc(sizeof(double) * (nrows ? nrows : 1) * (size_t)(nin + nout));
    if (!store) {
        cli_csv_free(&csv);
        return cli_error(cmd, "%s: out of memory", name);
    }
    int src[MF_EVAL_MAX_INPUTS]; /* the CSV column of each evaluator column */
    for (int k = 0; k < nin; ++k)
        if (col[k] >= 0) { /* an absent optional (vertex) column is left out: unused */
            src[ncols] = k;
            names[ncols] = inputs[k];
            colv[ncols] = store + (size_t)ncols * nrows;
            cols[ncols] = colv[ncols];
            ++ncols;
        }
    /* row by row, so the first bad field reported is the first in reading order */
    for (int r = 0; r < csv.nrows && status == 0; ++r)
        for (int j = 0; j < ncols; ++j) {
            int k = src[j];
            const char *s = csv.cells[r][col[k]];
            double *c = colv[j];
            if (polygon && k >= first_vertex && s[0] == '\0') {
                c[r] = NAN; /* an empty vertex field: unused */
                continue;
            }
            int pc = cli_parse_double(s, &c[r]);
            if (pc != 0) {
                status = cli_error(cmd, "%s: stdin: data row %d, column '%s': '%s' %s", name, r + 1, inputs[k], s,
                                   cli_num_error(pc));
                break;
            }
        }
    for (int k = 0; k < nout; ++k)
        outs[k] = store + (size_t)(nin + k) * nrows;
    if (status == 0 && mf_eval_run_function(e, opts, ncols, names, cols, nrows, outs, msg, sizeof msg) != MF_OK)
        status = cli_error(cmd, "%s", msg);

    cli_buf out = {0};
    if (status == 0) {
        for (int c = 0; c < csv.ncols; ++c)
            cli_buf_printf(&out, "%s%s", c ? "," : "", csv.header[c]);
        for (int k = 0; k < nout; ++k)
            cli_buf_printf(&out, ",%s", outputs[k]);
        cli_buf_printf(&out, "\n");
        for (int r = 0; r < csv.nrows; ++r) {
            for (int c = 0; c < csv.ncols; ++c)
                cli_buf_printf(&out, "%s%s", c ? "," : "", csv.cells[r][c]);
            for (int k = 0; k < nout; ++k) {
                cli_buf_printf(&out, ",");
                cli_buf_double(&out, outs[k][r]);
            }
            cli_buf_printf(&out, "\n");
        }
    }
    free(store);
    cli_csv_free(&csv);
    if (status == 0 && out.failed)
        status = cli_error(cmd, "%s: out of memory", name);
    if (status == 0 && cli_buf_write(&out, stdout) != 0)
        status = cli_error(cmd, "%s: stdout: write failed", name);
    cli_buf_free(&out);
    return status;
}
