/* cli_util.c -- see cli_util.h. */
#define _POSIX_C_SOURCE 200809L
#include "cli_util.h"

#include "mfkit/io/mf_io.h"
#include "mfkit/io/mf_json.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

int cli_error(const char *cmd, const char *fmt, ...)
{
    va_list ap;
    fprintf(stderr, "mfkit%s%s: ", cmd ? " " : "", cmd ? cmd : "");
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    return 2;
}

int cli_exit_code(mf_status st)
{
    switch (st) {
    case MF_OK:
        return CLI_EXIT_OK;
    case MF_ERR_CHECK_FAILED:
        return CLI_EXIT_CHECK_FAILED;
    case MF_ERR_DOMAIN:
    case MF_ERR_UNSUPPORTED:
        return CLI_EXIT_USAGE;
    case MF_ERR_IO:
    case MF_ERR_FORMAT:
    case MF_ERR_ALLOC:
        return CLI_EXIT_IO;
    default:
        return CLI_EXIT_FIT;
    }
}

int cli_parse_double(const char *s, double *out)
{
    if (!s || !*s)
        return CLI_NUM_INVALID;
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (end == s || *end != '\0')
        return CLI_NUM_INVALID;
    if (errno == ERANGE && isinf(v))
        return CLI_NUM_RANGE; /* overflow: 1e400 is a number, but not one a double holds */
    *out = v;
    return 0;
}

const char *cli_num_error(int code)
{
    return code == CLI_NUM_RANGE ? "is out of the range of a double (|x| > 1.8e308)" : "is not a number";
}

int cli_parse_int(const char *s, long lo, long hi, long *out)
{
    if (!s || !*s)
        return -1;
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (end == s || *end != '\0' || errno == ERANGE || v < lo || v > hi)
        return -1;
    *out = v;
    return 0;
}

void cli_buf_printf(cli_buf *b, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    mf_buf_vprintf(b, fmt, ap);
    va_end(ap);
}

void cli_buf_free(cli_buf *b) { mf_buf_free(b); }

int cli_buf_write(const cli_buf *b, FILE *f)
{
    if (b->failed)
        return -1;
    if (b->len && fwrite(b->data, 1, b->len, f) != b->len)
        return -1;
    return fflush(f) == 0 ? 0 : -1;
}

int cli_buf_write_file_atomic(const cli_buf *b, const char *path, char *msg, size_t msg_size)
{
    return mf_io_write_buf_atomic(path, b, msg, msg_size) == MF_OK ? 0 : -1;
}

void cli_buf_double(cli_buf *b, double v)
{
    if (isnan(v))
        cli_buf_printf(b, "nan");
    else if (isinf(v))
        cli_buf_printf(b, v > 0 ? "inf" : "-inf");
    else
        cli_buf_printf(b, "%.17g", v);
}

void cli_buf_json_string(cli_buf *b, const char *s) { mf_json_string(b, s); }

void cli_buf_json_number(cli_buf *b, double v) { mf_json_number(b, v); }

void cli_buf_checks_json(cli_buf *b, const mf_check *c, int n) { mf_json_checks(b, c, n); }

void cli_buf_checks_table(cli_buf *b, const mf_check *c, int n, int all_passed)
{
    cli_buf_printf(b, "%-22s %-12s %-12s %-6s %8s  %s\n", "check", "worst", "bound", "result", "cases", "worst case");
    for (int i = 0; i < n; ++i)
        cli_buf_printf(b, "%-22s %-12.4g %-12.4g %-6s %8ld  %s\n", c[i].name, c[i].worst, c[i].bound,
                       c[i].passed ? "pass" : "FAIL", c[i].cases, c[i].worst_at);
    cli_buf_printf(b, "%s\n", all_passed ? "all checks passed" : "SOME CHECKS FAILED");
}

/* ---- CSV ----------------------------------------------------------------------------------- */
static char *trim(char *s)
{
    while (*s == ' ' || *s == '\t')
        ++s;
    size_t n = strlen(s);
    while (n && (s[n - 1] == ' ' || s[n - 1] == '\t' || s[n - 1] == '\r' || s[n - 1] == '\n'))
        s[--n] = '\0';
    return s;
}

static char *dup_str(const char *s)
{
    size_t n = strlen(s) + 1;
    char *p = malloc(n);
    if (p)
        memcpy(p, s, n);
    return p;
}

/* Splits line in place at commas; returns the number of fields or -1 on allocation failure. */
static int split(char *line, char ***fields)
{
    int n = 1;
    for (char *p = line; *p; ++p)
        n += (*p == ',');
    char **f = malloc(sizeof(char *) * (size_t)n);
    if (!f)
        return -1;
    int i = 0;
    char *start = line;
    for (char *p = line;; ++p) {
        if (*p == ',' || *p == '\0') {
            int end = (*p == '\0');
            *p = '\0';
            f[i] = dup_str(trim(start));
            if (!f[i]) {
                for (int k = 0; k < i; ++k)
                    free(f[k]);
                free(f);
                return -1;
            }
            ++i;
            if (end)
                break;
            start = p + 1;
        }
    }
    *fields = f;
    return n;
}

static void free_fields(char **f, int n)
{
    if (!f)
        return;
    for (int i = 0; i < n; ++i)
        free(f[i]);
    free(f);
}

/* The header's column indices sorted by name (ties by index), for duplicate detection and
 * cli_csv_column: O(n log n) instead of comparing every pair (100k columns took 30 s). */
static const cli_csv *g_sort_csv; /* qsort has no user pointer in C11 */

static int cmp_col(const void *a, const void *b)
{
    int i = *(const int *)a, j = *(const int *)b;
    int c = strcmp(g_sort_csv->header[i], g_sort_csv->header[j]);
    return c ? c : (i > j) - (i < j);
}

static int build_index(cli_csv *csv)
{
    csv->sorted = malloc(sizeof(int) * (size_t)csv->ncols);
    if (!csv->sorted)
        return -1;
    for (int i = 0; i < csv->ncols; ++i)
        csv->sorted[i] = i;
    g_sort_csv = csv;
    qsort(csv->sorted, (size_t)csv->ncols, sizeof(int), cmp_col);
    g_sort_csv = NULL;
    return 0;
}

/* "line N: ..." (name NULL) or "name:N: ..." into msg, on one line (mf_io_msg). */
#if defined(__GNUC__)
__attribute__((format(printf, 5, 6)))
#endif
static void csv_msg(char *msg, size_t msg_size, const char *name, long line, const char *fmt, ...)
{
    char where[4096 + 32]; /* a path and a line number */
    if (name)
        snprintf(where, sizeof where, "%s:%ld", name, line);
    else
        snprintf(where, sizeof where, "line %ld", line);
    va_list ap;
    va_start(ap, fmt);
    mf_io_vmsg(msg, msg_size, where, fmt, ap);
    va_end(ap);
}

int cli_csv_read(FILE *in, cli_csv *csv, char *msg, size_t msg_size)
{
    return cli_csv_read_named(in, NULL, csv, msg, msg_size);
}

int cli_csv_read_named(FILE *in, const char *name, cli_csv *csv, char *msg, size_t msg_size)
{
    memset(csv, 0, sizeof *csv);
    char *line = NULL;
    size_t cap = 0;
    ssize_t got;
    long lineno = 0;
    int cap_rows = 0, rc = CLI_CSV_INPUT;
    while ((got = getline(&line, &cap, in)) >= 0) {
        ++lineno;
        if (lineno == 1 && got >= 3 && memcmp(line, "\xEF\xBB\xBF", 3) == 0) {
            csv_msg(msg, msg_size, name, 1, "starts with a UTF-8 byte-order mark (BOM): save the CSV without it");
            goto fail;
        }
        for (ssize_t k = 0; k < got; ++k) {
            unsigned char c = (unsigned char)line[k];
            if ((c < 0x20 && c != '\t' && c != '\r' && c != '\n') || c == 0x7f) {
                csv_msg(msg, msg_size, name, lineno, "binary input, not CSV text (byte 0x%02x at column %ld)", c,
                        (long)k + 1);
                goto fail;
            }
        }
        char *t = trim(line);
        if (*t == '\0')
            continue;
        char **fields;
        int n = split(t, &fields);
        if (n < 0)
            goto out_of_memory;
        if (!csv->header) {
            csv->header = fields;
            csv->ncols = n;
            csv->header_line = lineno;
            for (int i = 0; i < n; ++i)
                if (!fields[i][0]) {
                    csv_msg(msg, msg_size, name, lineno, "header column %d is empty", i + 1);
                    goto fail;
                }
            if (build_index(csv) != 0)
                goto out_of_memory;
            for (int i = 1; i < n; ++i)
                if (strcmp(csv->header[csv->sorted[i]], csv->header[csv->sorted[i - 1]]) == 0) {
                    csv_msg(msg, msg_size, name, lineno, "header names column '%s' twice", csv->header[csv->sorted[i]]);
                    goto fail;
                }
            continue;
        }
        if (n != csv->ncols) {
            csv_msg(msg, msg_size, name, lineno, "%d fields, but the header has %d", n, csv->ncols);
            free_fields(fields, n);
            goto fail;
        }
        if (csv->nrows == cap_rows) {
            int nc = cap_rows ? 2 * cap_rows : 64;
            char ***p = realloc(csv->cells, sizeof(char **) * (size_t)nc);
            long *pl = p ? realloc(csv->row_line, sizeof(long) * (size_t)nc) : NULL;
            if (p)
                csv->cells = p;
            if (!pl) {
                free_fields(fields, n);
                goto out_of_memory;
            }
            csv->row_line = pl;
            cap_rows = nc;
        }
        csv->row_line[csv->nrows] = lineno;
        csv->cells[csv->nrows++] = fields;
    }
    if (ferror(in)) {
        int err = errno;
        if (name)
            snprintf(msg, msg_size, "%s: read error: %s", name, strerror(err));
        else
            snprintf(msg, msg_size, "read error: %s", strerror(err));
        rc = CLI_CSV_IO;
        goto fail;
    }
    free(line);
    if (!csv->header) {
        if (name)
            snprintf(msg, msg_size, "%s: empty input: expected a CSV header line", name);
        else
            snprintf(msg, msg_size, "empty input: expected a CSV header line");
        return CLI_CSV_INPUT;
    }
    return 0;
out_of_memory:
    snprintf(msg, msg_size, "out of memory");
    rc = CLI_CSV_IO;
fail:
    free(line);
    cli_csv_free(csv);
    return rc;
}

void cli_csv_free(cli_csv *csv)
{
    for (int r = 0; r < csv->nrows; ++r)
        free_fields(csv->cells[r], csv->ncols);
    free(csv->cells);
    free_fields(csv->header, csv->ncols);
    free(csv->sorted);
    free(csv->row_line);
    memset(csv, 0, sizeof *csv);
}

int cli_csv_column(const cli_csv *csv, const char *name)
{
    int lo = 0, hi = csv->ncols - 1; /* binary search of the sorted index; names are unique */
    while (lo <= hi) {
        int mid = lo + (hi - lo) / 2, i = csv->sorted[mid];
        int c = strcmp(csv->header[i], name);
        if (c == 0)
            return i;
        if (c < 0)
            lo = mid + 1;
        else
            hi = mid - 1;
    }
    return -1;
}
