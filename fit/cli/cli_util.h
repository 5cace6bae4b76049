/* cli_util.h -- argument parsing, CSV input and buffered output for the mfkit command line. */
#ifndef MF_CLI_UTIL_H
#define MF_CLI_UTIL_H

#include <stddef.h>
#include <stdio.h>

#include "mfkit/io/mf_io.h"
#include "mfkit/mf_validate.h"

/* The exit status of every mfkit command (docs/cli.md, "Exit status"). */
enum {
    CLI_EXIT_OK = 0,
    CLI_EXIT_CHECK_FAILED = 1, /* a validation check (core properties, the LTC gate) failed */
    CLI_EXIT_USAGE = 2,        /* usage or input error: bad option, bad CSV field, out-of-domain request */
    CLI_EXIT_IO = 3,           /* I/O error: a file missing, unreadable, corrupt or unwritable; out of memory */
    CLI_EXIT_FIT = 4,          /* a fit failed (no convergence) */
    CLI_EXIT_INTERRUPTED = 130 /* SIGINT / SIGTERM (128 + 2, the shell's convention) */
};
/* The one mapping from a library status to an exit status: MF_OK 0, MF_ERR_CHECK_FAILED 1,
 * MF_ERR_DOMAIN and MF_ERR_UNSUPPORTED 2, MF_ERR_IO, MF_ERR_FORMAT and MF_ERR_ALLOC 3,
 * MF_ERR_NO_CONVERGENCE (and any other) 4. */
int cli_exit_code(mf_status st);

/* Prints "mfkit <cmd>: <message>" on one line of stderr. Always returns 2 (usage/input error). */
int cli_error(const char *cmd, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* Strict number parsing: the whole string must be a finite or NaN/Inf number ("nan", "inf").
 * Returns 0 on success, CLI_NUM_INVALID for text that is not a number, CLI_NUM_RANGE for a
 * number too large for a double (1e400; an underflow such as 1e-400 gives 0 or a subnormal). */
enum { CLI_NUM_INVALID = -1, CLI_NUM_RANGE = -2 };
int cli_parse_double(const char *s, double *out);
/* The reason for a non-zero cli_parse_double code: "is not a number", "is out of the range ...". */
const char *cli_num_error(int code);
/* Strict integer parsing in [lo, hi]. Returns 0 on success. */
int cli_parse_int(const char *s, long lo, long hi, long *out);

/* A growable text buffer (mf_buf of mf_io.h): output is written only when a command has fully
 * succeeded. */
typedef mf_buf cli_buf;

void cli_buf_printf(cli_buf *b, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
void cli_buf_free(cli_buf *b);
/* Writes the buffer to f and flushes; returns 0 on success. */
int cli_buf_write(const cli_buf *b, FILE *f);
/* Writes the buffer to path atomically (mf_io_write_buf_atomic).  On failure fills msg and
 * returns non-zero; no file is left behind. */
int cli_buf_write_file_atomic(const cli_buf *b, const char *path, char *msg, size_t msg_size);

/* CSV table read whole from a stream: a header row and data rows of the same width. */
typedef struct {
    int ncols, nrows;
    char **header;   /* ncols names */
    char ***cells;   /* nrows x ncols strings */
    int *sorted;     /* the column indices sorted by name (cli_csv_column) */
    long header_line; /* the line of the header (1-based; blank lines are counted) */
    long *row_line;   /* the line of each data row */
} cli_csv;

/* Reads a CSV (comma-separated, no quoting; surrounding spaces and CR are trimmed; blank lines
 * skipped).  A UTF-8 byte-order mark and control bytes (binary input) are errors that say so.
 * On error fills msg ("line N: ...") and returns CLI_CSV_INPUT (the text is not a valid CSV
 * table) or CLI_CSV_IO (a read error, out of memory). */
enum { CLI_CSV_INPUT = -1, CLI_CSV_IO = -2 };
int cli_csv_read(FILE *f, cli_csv *csv, char *msg, size_t msg_size);
/* cli_csv_read of the file called name: messages "name:N: ..." (name: the file's path). */
int cli_csv_read_named(FILE *f, const char *name, cli_csv *csv, char *msg, size_t msg_size);
void cli_csv_free(cli_csv *csv);
/* Index of the column named `name`, or -1. */
int cli_csv_column(const cli_csv *csv, const char *name);

/* Formats a double with %.17g ("nan", "inf", "-inf" for non-finite values). */
void cli_buf_double(cli_buf *b, double v);

/* JSON (mf_json.h): a quoted, escaped string; a number with %.17g, or "NaN" / "Infinity" /
 * "-Infinity". */
void cli_buf_json_string(cli_buf *b, const char *s);
void cli_buf_json_number(cli_buf *b, double v);
/* A report of checks: the JSON array of mf_json_checks, and the plain-text table with its verdict. */
void cli_buf_checks_json(cli_buf *b, const mf_check *c, int n);
void cli_buf_checks_table(cli_buf *b, const mf_check *c, int n, int all_passed);

#endif /* MF_CLI_UTIL_H */
