/* cli_opt.c -- see cli_opt.h. */
#include "cli_opt.h"
#include "cli_util.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define USAGE_WIDTH 100 /* columns of the usage text */
#define HELP_COLUMN 26  /* where an option's help starts */

int cli_opt_index(const cli_command *cmd, const char *name)
{
    for (int k = 0; k < cmd->nopts; ++k)
        if (strcmp(cmd->opts[k].name, name) == 0)
            return k;
    return -1;
}

/* "a, b or c" of an enum's choices into buf. */
static void choices_text(const cli_opt *o, char *buf, size_t n, const char *sep_last)
{
    buf[0] = '\0';
    int count = 0;
    while (o->choices[count])
        ++count;
    size_t len = 0;
    for (int k = 0; k < count && len < n; ++k)
        len += (size_t)snprintf(buf + len, n - len, "%s%s", k == 0 ? "" : k + 1 == count ? sep_last : ", ",
                                o->choices[k]);
}

/* What a kind accepts, for "expected ...". */
static void expect_text(const cli_opt *o, char *buf, size_t n)
{
    if (o->expect) {
        snprintf(buf, n, "%s", o->expect);
        return;
    }
    switch (o->kind) {
    case CLI_OPT_INT:
        snprintf(buf, n, "%s in [%ld, %ld]", o->pow2 ? "a power of two" : "an integer", o->lo, o->hi);
        if (o->multiple > 0)
            snprintf(buf, n, "a multiple of %ld in [%ld, %ld]", o->multiple, o->lo, o->hi);
        break;
    case CLI_OPT_U64:
        snprintf(buf, n, "a non-negative integer below 2^64");
        break;
    case CLI_OPT_DOUBLE:
        if (isinf(o->dhi) && isinf(o->dlo))
            snprintf(buf, n, "a finite number");
        else if (isinf(o->dhi))
            snprintf(buf, n, "a finite number %s %g", o->lo_open ? ">" : ">=", o->dlo);
        else
            snprintf(buf, n, "a number in %c%g, %g]", o->lo_open ? '(' : '[', o->dlo, o->dhi);
        break;
    case CLI_OPT_RANGE:
        snprintf(buf, n, "LO:HI with %g <= LO < HI <= %g", o->dlo, o->dhi);
        break;
    case CLI_OPT_ENUM:
        choices_text(o, buf, n, " or ");
        break;
    default:
        snprintf(buf, n, "a value");
        break;
    }
}

static void metavar_text(const cli_opt *o, char *buf, size_t n);

static int bad_value(const cli_command *cmd, const cli_opt *o, const char *arg)
{
    char want[256];
    expect_text(o, want, sizeof want);
    return cli_error(cmd->name, "%s: expected %s, got '%s'", o->name, want, arg);
}

/* Parses one argument of option o; 0 on success, else the exit code after the message. */
static int parse_value(const cli_command *cmd, const cli_opt *o, const char *arg, cli_val *v)
{
    v->s = arg;
    switch (o->kind) {
    case CLI_OPT_FLAG:
        return 0;
    case CLI_OPT_INT: {
        long x;
        if (cli_parse_int(arg, o->lo, o->hi, &x) != 0 || (o->multiple > 0 && x % o->multiple != 0)
            || (o->pow2 && (x <= 0 || (x & (x - 1)) != 0)))
            return bad_value(cmd, o, arg);
        v->i = x;
        return 0;
    }
    case CLI_OPT_U64: {
        char *end;
        errno = 0;
        unsigned long long x = strtoull(arg, &end, 0);
        if (!*arg || *end || errno || arg[0] == '-' || arg[0] == '+' || arg[0] == ' ')
            return bad_value(cmd, o, arg);
        v->u = (uint64_t)x;
        return 0;
    }
    case CLI_OPT_DOUBLE: {
        double x;
        int pc = cli_parse_double(arg, &x);
        if (pc == CLI_NUM_RANGE)
            return cli_error(cmd->name, "%s: '%s' %s", o->name, arg, cli_num_error(pc));
        if (pc != 0 || !isfinite(x) || x < o->dlo || x > o->dhi || (o->lo_open && x == o->dlo))
            return bad_value(cmd, o, arg);
        v->d = x;
        return 0;
    }
    case CLI_OPT_STRING:
        if (!*arg && !o->allow_empty)
            return cli_error(cmd->name, "%s: expected %s, got an empty string", o->name,
                             o->metavar ? o->metavar : "a value");
        return 0;
    case CLI_OPT_ENUM:
        for (long k = 0; o->choices[k]; ++k)
            if (strcmp(arg, o->choices[k]) == 0) {
                v->i = k;
                return 0;
            }
        return bad_value(cmd, o, arg);
    case CLI_OPT_RANGE: {
        const char *c = strchr(arg, ':');
        char buf[64];
        size_t n = c ? (size_t)(c - arg) : 0;
        double lo, hi;
        if (!c || n == 0 || n >= sizeof buf)
            return bad_value(cmd, o, arg);
        memcpy(buf, arg, n);
        buf[n] = '\0';
        if (cli_parse_double(buf, &lo) || cli_parse_double(c + 1, &hi) || !(lo >= o->dlo && hi <= o->dhi && lo < hi))
            return bad_value(cmd, o, arg);
        v->lo = lo;
        v->hi = hi;
        return 0;
    }
    case CLI_OPT_CUSTOM:
        return o->parse(arg, v) == 0 ? 0 : bad_value(cmd, o, arg);
    }
    return bad_value(cmd, o, arg);
}

int cli_opt_parse(const cli_command *cmd, int argc, char **argv, unsigned allowed, const char *context,
                  cli_val *vals, const char **pos, int *npos)
{
    if (cmd->nopts > 0)
        memset(vals, 0, sizeof *vals * (size_t)cmd->nopts);
    *npos = 0;
    int options_done = 0;
    /* --help anywhere wins over every other error */
    for (int i = 0; i < argc; ++i) {
        if (!strcmp(argv[i], "--"))
            break;
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h"))
            return CLI_PARSE_HELP;
    }
    for (int i = 0; i < argc; ++i) {
        const char *a = argv[i];
        if (!options_done && !strcmp(a, "--")) {
            options_done = 1;
            continue;
        }
        if (!options_done && a[0] == '-' && a[1] != '\0') {
            /* "--name=value" is accepted as "--name value" */
            const char *eq = strchr(a, '=');
            size_t nlen = eq ? (size_t)(eq - a) : strlen(a);
            int k = 0;
            while (k < cmd->nopts && !(strlen(cmd->opts[k].name) == nlen && !strncmp(cmd->opts[k].name, a, nlen)))
                ++k;
            if (k == cmd->nopts)
                return cli_error(cmd->name, "unknown option '%.*s' (see 'mfkit %s --help')", (int)nlen, a, cmd->name);
            const cli_opt *o = &cmd->opts[k];
            if (o->mask && !(o->mask & allowed))
                return cli_error(cmd->name, "%s: does not take %s", context ? context : cmd->name, o->name);
            if (vals[k].set)
                return cli_error(cmd->name, "%s given twice", o->name);
            const char *arg = NULL;
            if (o->kind == CLI_OPT_FLAG) {
                if (eq)
                    return cli_error(cmd->name, "%s takes no value, got '%s'", o->name, eq + 1);
            } else if (eq) {
                arg = eq + 1;
            } else if (i + 1 < argc) {
                arg = argv[++i];
            } else {
                char want[256];
                expect_text(o, want, sizeof want);
                return cli_error(cmd->name, "option %s needs a value (%s)", o->name, want);
            }
            int rc = parse_value(cmd, o, arg ? arg : "", &vals[k]);
            if (rc)
                return rc;
            vals[k].set = 1;
            continue;
        }
        if (*npos >= cmd->max_pos)
            return cli_error(cmd->name, "unexpected argument '%s' (usage: mfkit %s %s)", a, cmd->name, cmd->synopsis);
        pos[(*npos)++] = a;
    }
    for (int k = 0; k < cmd->nopts; ++k)
        if (cmd->opts[k].required && !vals[k].set) {
            char mv[220];
            metavar_text(&cmd->opts[k], mv, sizeof mv);
            return cli_error(cmd->name, "needs %s%s", cmd->opts[k].name, mv);
        }
    if (*npos < cmd->min_pos)
        return cli_error(cmd->name, "missing argument%s: usage: mfkit %s %s (see 'mfkit %s --help')",
                         cmd->min_pos - *npos > 1 ? "s" : "", cmd->name, cmd->synopsis, cmd->name);
    return CLI_PARSE_OK;
}

/* ---- usage text ------------------------------------------------------------------------------ */

/* The metavar as shown: "N", or the enum's "a|b|c". */
static void metavar_text(const cli_opt *o, char *buf, size_t n)
{
    if (o->kind == CLI_OPT_FLAG)
        buf[0] = '\0';
    else if (o->metavar)
        snprintf(buf, n, " %s", o->metavar);
    else if (o->kind == CLI_OPT_ENUM) {
        char c[200];
        choices_text(o, c, sizeof c, "|");
        for (char *p = c; *p; ++p) /* "a, b|c" -> "a|b|c" */
            if (*p == ',' && p[1] == ' ')
                *p = '|', memmove(p + 1, p + 2, strlen(p + 2) + 1);
        snprintf(buf, n, " %s", c);
    } else
        snprintf(buf, n, " VALUE");
}

/* Prints text wrapped at USAGE_WIDTH, the first line from column `col` (already there), the
 * others indented by `indent`; '\n' in text forces a break. */
static void wrap(FILE *f, const char *text, int col, int indent)
{
    const char *p = text;
    while (*p) {
        if (*p == '\n') {
            fprintf(f, "\n%*s", indent, "");
            col = indent;
            ++p;
            continue;
        }
        const char *w = p;
        while (*w == ' ')
            ++w;
        const char *e = w;
        while (*e && *e != ' ' && *e != '\n')
            ++e;
        int len = (int)(e - w), lead = col > indent ? (int)(w - p) : 0;
        if (col > indent && col + lead + len > USAGE_WIDTH) {
            fprintf(f, "\n%*s", indent, "");
            col = indent;
            lead = 0;
        }
        fprintf(f, "%*s%.*s", lead, "", len, w);
        col += lead + len;
        p = e;
    }
}

void cli_opt_usage(const cli_command *cmd, FILE *f)
{
    char head[256];
    int n = snprintf(head, sizeof head, "usage: mfkit %s%s%s", cmd->name, cmd->synopsis[0] ? " " : "", cmd->synopsis);
    fputs(head, f);
    int col = n, indent = (int)strlen("usage: mfkit ") + (int)strlen(cmd->name) + 1;
    for (int k = 0; k < cmd->nopts; ++k) {
        char mv[220], item[300];
        metavar_text(&cmd->opts[k], mv, sizeof mv);
        int req = cmd->opts[k].required;
        int len = snprintf(item, sizeof item, "%s%s%s%s", req ? "" : "[", cmd->opts[k].name, mv, req ? "" : "]");
        if (col + 1 + len > USAGE_WIDTH) {
            fprintf(f, "\n%*s", indent, "");
            col = indent;
        } else {
            fputc(' ', f);
            ++col;
        }
        fputs(item, f);
        col += len;
    }
    fputs("\n\n", f);
    if (cmd->description)
        fputs(cmd->description, f);
    if (cmd->nopts > 0) {
        fputs(cmd->description ? "\noptions:\n" : "options:\n", f);
        for (int k = 0; k < cmd->nopts; ++k) {
            const cli_opt *o = &cmd->opts[k];
            char mv[220];
            metavar_text(o, mv, sizeof mv);
            int w = fprintf(f, "  %s%s", o->name, mv);
            if (w + 2 > HELP_COLUMN) {
                fprintf(f, "\n%*s", HELP_COLUMN, "");
            } else {
                fprintf(f, "%*s", HELP_COLUMN - w, "");
            }
            char text[1200];
            snprintf(text, sizeof text, "%s%s%s%s", o->help ? o->help : "", o->def ? " (default " : "",
                     o->def ? o->def : "", o->def ? ")" : "");
            wrap(f, text, HELP_COLUMN, HELP_COLUMN);
            fputc('\n', f);
        }
    }
    if (cmd->epilog) {
        fputc('\n', f);
        fputs(cmd->epilog, f);
    }
}

int cli_opt_unavailable(const cli_command *cmd, const char *context, const char *what, const char *option, int argc,
                        char **argv)
{
    for (int i = 1; i < argc; ++i)
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            cli_opt_usage(cmd, stdout);
            return 0;
        }
    return cli_error(context, "needs the %s build (configured with %s=OFF)", what, option);
}
