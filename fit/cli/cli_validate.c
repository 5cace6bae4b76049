/*
 * cli_validate.c -- `mfkit validate`: the property checks of the core math (mf_validate.h).
 * Exit code 0 when every check passes, 1 when one fails, 2 for a usage error, 3 for an I/O error.
 */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"
#include "cli_util.h"

#include "mfkit/mfkit.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static void usage(FILE *f)
{
    fprintf(f,
            "usage: mfkit validate [--json] [--json-file PATH] [--quiet]\n\n"
            "Runs the property checks of the core math over a grid of the whole domain (alpha 1e-4..1,\n"
            "view angles up to 89.99 deg, anisotropy up to 1:100, non-centred means up to slope 2) and\n"
            "prints one row per check: name, worst value, bound, pass/FAIL, cases, where the worst was.\n\n"
            "options:\n"
            "  --json            print the report as JSON on stdout instead of the table\n"
            "  --json-file PATH  also write the JSON report to PATH (atomically)\n"
            "  --quiet           no progress on stderr (progress is shown only on a terminal anyway)\n\n"
            "exit status: 0 all checks passed, 1 a check failed, 2 usage error, 3 I/O error\n");
}

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

static void json_string(cli_buf *b, const char *s)
{
    cli_buf_printf(b, "\"");
    for (; *s; ++s) {
        if (*s == '"' || *s == '\\')
            cli_buf_printf(b, "\\%c", *s);
        else if ((unsigned char)*s < 0x20)
            cli_buf_printf(b, "\\u%04x", (unsigned char)*s);
        else
            cli_buf_printf(b, "%c", *s);
    }
    cli_buf_printf(b, "\"");
}

static void json_number(cli_buf *b, double v)
{
    if (isfinite(v))
        cli_buf_printf(b, "%.17g", v);
    else
        cli_buf_printf(b, "null"); /* JSON has no NaN */
}

static void report_json(cli_buf *b, const mf_check *c, int n, int all_passed)
{
    cli_buf_printf(b, "{\n  \"tool\": \"mfkit validate\",\n  \"version\": \"%s\",\n  \"passed\": %s,\n  \"checks\": [\n",
                   MFKIT_VERSION, all_passed ? "true" : "false");
    for (int i = 0; i < n; ++i) {
        cli_buf_printf(b, "    {\"name\": ");
        json_string(b, c[i].name);
        cli_buf_printf(b, ", \"what\": ");
        json_string(b, c[i].what);
        cli_buf_printf(b, ", \"worst\": ");
        json_number(b, c[i].worst);
        cli_buf_printf(b, ", \"bound\": ");
        json_number(b, c[i].bound);
        cli_buf_printf(b, ", \"passed\": %s, \"cases\": %ld, \"worst_at\": ", c[i].passed ? "true" : "false", c[i].cases);
        json_string(b, c[i].worst_at);
        cli_buf_printf(b, "}%s\n", i + 1 < n ? "," : "");
    }
    cli_buf_printf(b, "  ]\n}\n");
}

static void report_table(cli_buf *b, const mf_check *c, int n, int all_passed)
{
    cli_buf_printf(b, "%-22s %-12s %-12s %-6s %8s  %s\n", "check", "worst", "bound", "result", "cases", "worst case");
    for (int i = 0; i < n; ++i)
        cli_buf_printf(b, "%-22s %-12.4g %-12.4g %-6s %8ld  %s\n", c[i].name, c[i].worst, c[i].bound,
                       c[i].passed ? "pass" : "FAIL", c[i].cases, c[i].worst_at);
    cli_buf_printf(b, "%s\n", all_passed ? "all checks passed" : "SOME CHECKS FAILED");
}

int cli_validate(int argc, char **argv)
{
    const char *cmd = "validate";
    int json = 0, quiet = 0;
    const char *json_file = NULL;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(argv[i], "--json")) {
            json = 1;
        } else if (!strcmp(argv[i], "--quiet")) {
            quiet = 1;
        } else if (!strcmp(argv[i], "--json-file")) {
            if (i + 1 >= argc)
                return cli_error(cmd, "option --json-file needs a value");
            json_file = argv[++i];
            if (!*json_file)
                return cli_error(cmd, "--json-file: empty path");
        } else if (argv[i][0] == '-') {
            return cli_error(cmd, "unknown option '%s' (see 'mfkit validate --help')", argv[i]);
        } else {
            return cli_error(cmd, "unexpected argument '%s' (checking a table file arrives with the LTC tables)",
                             argv[i]);
        }
    }
    int n = mf_validate_core_count();
    mf_check *checks = calloc((size_t)n, sizeof *checks);
    if (!checks)
        return cli_error(cmd, "out of memory");
    progress_state ps = {!quiet && isatty(fileno(stderr)), {0, 0}};
    clock_gettime(CLOCK_MONOTONIC, &ps.start);
    mf_status st = mf_validate_core(checks, n, progress, &ps);
    if (st != MF_OK && st != MF_ERR_CHECK_FAILED) {
        free(checks);
        return cli_error(cmd, "%s", mf_status_str(st));
    }
    int all = (st == MF_OK);
    cli_buf jb = {0}, tb = {0};
    report_json(&jb, checks, n, all);
    report_table(&tb, checks, n, all);
    free(checks);
    int rc = all ? 0 : 1;
    char msg[512];
    if (json_file && cli_buf_write_file_atomic(&jb, json_file, msg, sizeof msg) != 0)
        rc = 3, cli_error(cmd, "--json-file %s", msg);
    if (rc != 3 && cli_buf_write(json ? &jb : &tb, stdout) != 0)
        rc = 3, cli_error(cmd, "stdout: write failed");
    cli_buf_free(&jb);
    cli_buf_free(&tb);
    return rc;
}
