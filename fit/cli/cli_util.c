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
    if (b->failed)
        return;
    for (;;) {
        va_list ap;
        va_start(ap, fmt);
        size_t room = b->cap - b->len;
        int n = vsnprintf(b->data ? b->data + b->len : NULL, room, fmt, ap);
        va_end(ap);
        if (n < 0) {
            b->failed = 1;
            return;
        }
        if ((size_t)n < room) {
            b->len += (size_t)n;
            return;
        }
        size_t cap = b->cap ? b->cap * 2 : 4096;
        while (cap < b->len + (size_t)n + 1)
            cap *= 2;
        char *p = realloc(b->data, cap);
        if (!p) {
            b->failed = 1;
            return;
        }
        b->data = p;
        b->cap = cap;
    }
}

void cli_buf_free(cli_buf *b)
{
    free(b->data);
    b->data = NULL;
    b->len = b->cap = 0;
}

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
    mf_buf m = {b->data, b->len, b->cap, b->failed}; /* a view: not freed here */
    return mf_io_write_buf_atomic(path, &m, msg, msg_size) == MF_OK ? 0 : -1;
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

/* The one JSON emitter (mf_json.h), appended through a scratch buffer. */
static void append_json(cli_buf *b, const mf_buf *m)
{
    if (m->failed)
        b->failed = 1;
    else
        cli_buf_printf(b, "%.*s", (int)m->len, m->data ? m->data : "");
}

void cli_buf_json_string(cli_buf *b, const char *s)
{
    mf_buf m = {0};
    mf_json_string(&m, s);
    append_json(b, &m);
    mf_buf_free(&m);
}

void cli_buf_json_number(cli_buf *b, double v)
{
    mf_buf m = {0};
    mf_json_number(&m, v);
    append_json(b, &m);
    mf_buf_free(&m);
}

void cli_buf_checks_json(cli_buf *b, const mf_check *c, int n)
{
    cli_buf_printf(b, "[\n");
    for (int i = 0; i < n; ++i) {
        cli_buf_printf(b, "    {\"name\": ");
        cli_buf_json_string(b, c[i].name);
        cli_buf_printf(b, ", \"what\": ");
        cli_buf_json_string(b, c[i].what);
        cli_buf_printf(b, ", \"worst\": ");
        cli_buf_json_number(b, c[i].worst);
        cli_buf_printf(b, ", \"bound\": ");
        cli_buf_json_number(b, c[i].bound);
        cli_buf_printf(b, ", \"passed\": %s, \"cases\": %ld, \"worst_at\": ", c[i].passed ? "true" : "false",
                       c[i].cases);
        cli_buf_json_string(b, c[i].worst_at);
        cli_buf_printf(b, "}%s\n", i + 1 < n ? "," : "");
    }
    cli_buf_printf(b, "  ]");
}

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

int cli_csv_read(FILE *in, cli_csv *csv, char *msg, size_t msg_size)
{
    memset(csv, 0, sizeof *csv);
    char *line = NULL;
    size_t cap = 0;
    ssize_t got;
    long lineno = 0;
    int cap_rows = 0;
    while ((got = getline(&line, &cap, in)) >= 0) {
        ++lineno;
        if (lineno == 1 && got >= 3 && memcmp(line, "\xEF\xBB\xBF", 3) == 0) {
            snprintf(msg, msg_size, "line 1: starts with a UTF-8 byte-order mark (BOM): save the CSV without it");
            goto fail;
        }
        for (ssize_t k = 0; k < got; ++k) {
            unsigned char c = (unsigned char)line[k];
            if ((c < 0x20 && c != '\t' && c != '\r' && c != '\n') || c == 0x7f) {
                snprintf(msg, msg_size, "line %ld: binary input, not CSV text (byte 0x%02x at column %ld)", lineno, c,
                         (long)k + 1);
                goto fail;
            }
        }
        char *t = trim(line);
        if (*t == '\0')
            continue;
        char **fields;
        int n = split(t, &fields);
        if (n < 0) {
            snprintf(msg, msg_size, "out of memory");
            goto fail;
        }
        if (!csv->header) {
            csv->header = fields;
            csv->ncols = n;
            for (int i = 0; i < n; ++i)
                if (!fields[i][0]) {
                    snprintf(msg, msg_size, "line %ld: header column %d is empty", lineno, i + 1);
                    goto fail;
                }
            if (build_index(csv) != 0) {
                snprintf(msg, msg_size, "out of memory");
                goto fail;
            }
            for (int i = 1; i < n; ++i)
                if (strcmp(csv->header[csv->sorted[i]], csv->header[csv->sorted[i - 1]]) == 0) {
                    snprintf(msg, msg_size, "line %ld: header names column '%s' twice", lineno,
                             csv->header[csv->sorted[i]]);
                    goto fail;
                }
            continue;
        }
        if (n != csv->ncols) {
            snprintf(msg, msg_size, "line %ld: %d fields, but the header has %d", lineno, n, csv->ncols);
            free_fields(fields, n);
            goto fail;
        }
        if (csv->nrows == cap_rows) {
            int nc = cap_rows ? 2 * cap_rows : 64;
            char ***p = realloc(csv->cells, sizeof(char **) * (size_t)nc);
            if (!p) {
                free_fields(fields, n);
                snprintf(msg, msg_size, "out of memory");
                goto fail;
            }
            csv->cells = p;
            cap_rows = nc;
        }
        csv->cells[csv->nrows++] = fields;
    }
    if (ferror(in)) {
        snprintf(msg, msg_size, "read error: %s", strerror(errno));
        goto fail;
    }
    free(line);
    if (!csv->header) {
        snprintf(msg, msg_size, "empty input: expected a CSV header line");
        return -1;
    }
    return 0;
fail:
    free(line);
    cli_csv_free(csv);
    return -1;
}

void cli_csv_free(cli_csv *csv)
{
    for (int r = 0; r < csv->nrows; ++r)
        free_fields(csv->cells[r], csv->ncols);
    free(csv->cells);
    free_fields(csv->header, csv->ncols);
    free(csv->sorted);
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
