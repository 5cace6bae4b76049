/* cli_opt.h -- the table-driven option parser of the mfkit command line.
 *
 * Each command declares its options once, in a table of cli_opt (name, metavar, kind and its
 * limits, default, help); cli_opt_parse parses argv against it and cli_opt_usage prints the
 * command's usage text from the same table, so an option is named in exactly one place.
 * Errors are one line on stderr, "mfkit CMD: --opt: expected ..., got 'x'", and exit status 2.
 */
#ifndef MF_CLI_OPT_H
#define MF_CLI_OPT_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

typedef enum {
    CLI_OPT_FLAG,   /* no argument */
    CLI_OPT_INT,    /* an integer in [lo, hi], a multiple of `multiple` (if > 0), a power of two (if pow2) */
    CLI_OPT_U64,    /* a non-negative integer (decimal, 0x hex or 0 octal) that fits 64 bits */
    CLI_OPT_DOUBLE, /* a finite number in [dlo, dhi] ((dlo, dhi] with lo_open) */
    CLI_OPT_STRING, /* any non-empty text (empty allowed with allow_empty) */
    CLI_OPT_ENUM,   /* one of choices (NULL-terminated); the value is its index */
    CLI_OPT_RANGE,  /* LO:HI, two finite numbers with dlo <= LO < HI <= dhi */
    CLI_OPT_CUSTOM  /* parsed by `parse`; `expect` says what it accepts */
} cli_opt_kind;

/* A parsed value (which member: by the kind). */
typedef struct {
    int set;          /* given on the command line */
    long i;           /* INT, ENUM (the index) */
    uint64_t u;       /* U64 */
    double d, lo, hi; /* DOUBLE; RANGE */
    const char *s;    /* STRING, CUSTOM: the argument as given */
    long a, b;        /* CUSTOM: what parse stored */
} cli_val;

typedef struct cli_opt {
    const char *name;    /* "--size" */
    const char *metavar; /* "N"; NULL for flags, and for enums (the choices are shown) */
    cli_opt_kind kind;
    long lo, hi;         /* INT */
    long multiple;       /* INT: > 0 requires a multiple of it */
    int pow2;            /* INT: requires a power of two */
    double dlo, dhi;     /* DOUBLE, RANGE */
    int lo_open;         /* DOUBLE: dlo itself excluded */
    const char *const *choices; /* ENUM */
    int (*parse)(const char *arg, cli_val *v); /* CUSTOM: 0 on success */
    const char *expect;  /* CUSTOM (and optional override for the others): "N or NRxNU, 2..4096" */
    const char *def;     /* shown as "(default ...)"; NULL: none shown */
    const char *help;    /* one paragraph, wrapped by cli_opt_usage; '\n' forces a line break */
    unsigned mask;       /* command-specific applicability (see cli_opt_parse's allowed) */
    int allow_empty;     /* STRING: "" accepted */
    int required;        /* must be given ("needs --out PREFIX"); shown without brackets */
} cli_opt;

/* A command: "mfkit <name> <synopsis> [options]" with its options. */
typedef struct {
    const char *name;        /* "fit ltc": in the usage line and in every error */
    const char *synopsis;    /* positional arguments as shown, e.g. "IN OUT"; may be "" */
    int min_pos, max_pos;    /* positional argument counts accepted */
    const char *description; /* printed after the usage line (ends with '\n'), or NULL */
    const cli_opt *opts;
    int nopts;
    const char *epilog;      /* printed after the options (files, exit status), or NULL */
} cli_command;

/* Parse results of cli_opt_parse. */
enum { CLI_PARSE_OK = 0, CLI_PARSE_HELP = -1 };

/* Parses argv[0..argc) (argv[0] is the first argument after the command's words) into vals
 * (cmd->nopts entries, zeroed first) and the positional arguments into pos (at most
 * cmd->max_pos; *npos set).  "--" ends the options.  An option whose mask does not intersect
 * `allowed` is refused as "<context>: does not take --x" (allowed = ~0u: every option).
 * Returns CLI_PARSE_OK, CLI_PARSE_HELP (--help or -h seen: the caller prints the usage and exits 0)
 * or the exit code 2 after printing one line: unknown option, missing or bad value, an option
 * given twice, or the wrong number of positional arguments. */
int cli_opt_parse(const cli_command *cmd, int argc, char **argv, unsigned allowed, const char *context,
                  cli_val *vals, const char **pos, int *npos);

/* The usage text: "usage: mfkit NAME SYNOPSIS [--opt METAVAR] ...", the description, "options:"
 * with each option's help and default, and the epilog. */
void cli_opt_usage(const cli_command *cmd, FILE *f);

/* The command cmd where this build lacks what it needs: "--help" or "-h" among argv[1..argc) prints
 * the usage and returns 0; otherwise one line "mfkit CONTEXT: needs the WHAT build (configured
 * with OPTION=OFF)" and the usage exit status 2. */
int cli_opt_unavailable(const cli_command *cmd, const char *context, const char *what, const char *option, int argc,
                        char **argv);

/* Index of the option named `name` in cmd (or -1): for commands whose code reads vals by name. */
int cli_opt_index(const cli_command *cmd, const char *name);

#endif /* MF_CLI_OPT_H */
