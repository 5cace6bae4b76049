/* mf_ltc_reference.c -- the reference LTC table's CSV as an mfkit LTC table (mf_ltc_reference.h). */
#include "mfkit/io/mf_ltc_reference.h"

#include "mfkit/mf_ltc_table.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define LINE_MAX_LEN 16384
#define MAX_COLS 128

enum { C_IA, C_IT, C_ROUGH, C_XT, C_00, C_20, C_02, C_22, C_MAG, C_FRES, C_SPHERE, C_COUNT };
static const char *const col_names[C_COUNT] = {"i_alpha",    "i_theta",    "roughness",  "x_theta",
                                               "invMn_r0c0", "invMn_r2c0", "invMn_r0c2", "invMn_r2c2",
                                               "magnitude",  "fresnel",    "sphere"};
/* The mfkit field of each value column C_00 .. C_SPHERE. */
static const int col_field[C_COUNT] = {-1, -1, -1, -1, MF_LTC_F_MINV_00, MF_LTC_F_MINV_20, MF_LTC_F_MINV_02,
                                       MF_LTC_F_MINV_22, MF_LTC_F_MAGNITUDE, MF_LTC_F_FRESNEL, MF_LTC_F_SPHERE};

static mf_status fail(char *msg, size_t size, mf_status st, const char *path, const char *fmt, ...)
{
    if (msg && size) {
        int k = snprintf(msg, size, "%s: ", path);
        if (k >= 0 && (size_t)k < size) {
            va_list ap;
            va_start(ap, fmt);
            vsnprintf(msg + k, size - (size_t)k, fmt, ap);
            va_end(ap);
        }
    }
    return st;
}

/* Splits line in place at commas (no quoting in this format); returns the count. */
static int split(char *line, char **cols)
{
    int n = 0;
    char *p = line;
    size_t len = strlen(p);
    while (len && (p[len - 1] == '\n' || p[len - 1] == '\r'))
        p[--len] = '\0';
    for (;;) {
        if (n == MAX_COLS)
            return -1;
        cols[n++] = p;
        char *c = strchr(p, ',');
        if (!c)
            break;
        *c = '\0';
        p = c + 1;
    }
    return n;
}

/* Column index of each needed name, or -1 if one is missing (*missing gets its name). */
static int header_map(char *line, int *idx, const char **missing)
{
    char *cols[MAX_COLS];
    int n = split(line, cols);
    if (n < 0)
        return -1;
    for (int k = 0; k < C_COUNT; ++k) {
        idx[k] = -1;
        for (int j = 0; j < n; ++j)
            if (!strcmp(cols[j], col_names[k]))
                idx[k] = j;
        if (idx[k] < 0) {
            *missing = col_names[k];
            return -1;
        }
    }
    return n;
}

int mf_ltc_reference_is_csv(const char *path)
{
    if (!path)
        return 0;
    FILE *f = fopen(path, "rb");
    if (!f)
        return 0;
    char *line = malloc(LINE_MAX_LEN);
    int ok = 0;
    if (line && fgets(line, LINE_MAX_LEN, f)) {
        int idx[C_COUNT];
        const char *missing = NULL;
        ok = header_map(line, idx, &missing) > 0;
    }
    free(line);
    fclose(f);
    return ok;
}

static int parse_num(const char *s, double *v)
{
    char *end;
    errno = 0;
    *v = strtod(s, &end);
    return end != s && *end == '\0' && errno != ERANGE;
}

typedef struct row {
    int ia, it;
    double v[C_COUNT];
} row;

mf_status mf_ltc_reference_read_csv(const char *path, mf_table *out, char *msg, size_t msg_size)
{
    if (msg && msg_size)
        msg[0] = '\0';
    if (out)
        memset(out, 0, sizeof *out);
    if (!path || !out)
        return MF_ERR_DOMAIN;
    FILE *f = fopen(path, "rb");
    if (!f)
        return fail(msg, msg_size, MF_ERR_IO, path, "cannot open: %s", strerror(errno));
    char *line = malloc(LINE_MAX_LEN);
    row *rows = NULL;
    size_t nrows = 0, caprows = 0;
    mf_status st = MF_OK;
    int idx[C_COUNT], ncols = 0, max_a = -1, max_t = -1;
    long lineno = 1;
    const char *missing = "?";
    if (!line) {
        st = MF_ERR_ALLOC;
        goto done;
    }
    if (!fgets(line, LINE_MAX_LEN, f)) {
        st = fail(msg, msg_size, ferror(f) ? MF_ERR_IO : MF_ERR_FORMAT, path, ferror(f) ? "read error" : "empty file");
        goto done;
    }
    ncols = header_map(line, idx, &missing);
    if (ncols < 0) {
        st = fail(msg, msg_size, MF_ERR_FORMAT, path, "line 1: not a reference LTC CSV header (no column '%s')", missing);
        goto done;
    }
    while (fgets(line, LINE_MAX_LEN, f)) {
        ++lineno;
        if (!strchr(line, '\n') && !feof(f)) {
            st = fail(msg, msg_size, MF_ERR_FORMAT, path, "line %ld: longer than %d bytes", lineno, LINE_MAX_LEN - 1);
            goto done;
        }
        if (line[0] == '\n' || line[0] == '\r' || line[0] == '\0')
            continue;
        char *cols[MAX_COLS];
        int n = split(line, cols);
        if (n != ncols) {
            st = fail(msg, msg_size, MF_ERR_FORMAT, path, "line %ld: %d columns, the header has %d", lineno, n, ncols);
            goto done;
        }
        row r;
        for (int k = 0; k < C_COUNT; ++k)
            if (!parse_num(cols[idx[k]], &r.v[k])) {
                st = fail(msg, msg_size, MF_ERR_FORMAT, path, "line %ld: column %s: bad number '%s'", lineno, col_names[k],
                          cols[idx[k]]);
                goto done;
            }
        if (!(r.v[C_IA] >= 0 && r.v[C_IA] < 65536 && r.v[C_IA] == floor(r.v[C_IA]) && r.v[C_IT] >= 0 &&
              r.v[C_IT] < 65536 && r.v[C_IT] == floor(r.v[C_IT]))) {
            st = fail(msg, msg_size, MF_ERR_FORMAT, path, "line %ld: bad texel indices", lineno);
            goto done;
        }
        r.ia = (int)r.v[C_IA];
        r.it = (int)r.v[C_IT];
        if (r.ia > max_a)
            max_a = r.ia;
        if (r.it > max_t)
            max_t = r.it;
        if (nrows == caprows) {
            size_t nc = caprows ? 2 * caprows : 4096;
            row *nr = realloc(rows, nc * sizeof *nr);
            if (!nr) {
                st = MF_ERR_ALLOC;
                goto done;
            }
            rows = nr;
            caprows = nc;
        }
        rows[nrows++] = r;
    }
    if (ferror(f)) {
        st = fail(msg, msg_size, MF_ERR_IO, path, "read error");
        goto done;
    }
    if (max_a < 1 || max_t < 1) {
        st = fail(msg, msg_size, MF_ERR_FORMAT, path, "fewer than 2 x 2 texels");
        goto done;
    }
    int n_r = max_a + 1, n_u = max_t + 1;
    if (nrows != (size_t)n_r * (size_t)n_u) {
        st = fail(msg, msg_size, MF_ERR_FORMAT, path, "%zu rows for a %d x %d grid", nrows, n_r, n_u);
        goto done;
    }
    st = mf_ltc_table_create(out, n_r, n_u);
    if (st != MF_OK) {
        st = fail(msg, msg_size, st, path, "cannot create the table: %s", mf_status_str(st));
        goto done;
    }
    out->axes[0].physical_min = MF_LTC_REFERENCE_ALPHA_MIN;
    unsigned char *seen = calloc((size_t)n_r * (size_t)n_u, 1);
    if (!seen) {
        st = MF_ERR_ALLOC;
        goto done;
    }
    for (size_t i = 0; i < nrows && st == MF_OK; ++i) {
        const row *r = &rows[i];
        size_t texel = (size_t)r->ia + (size_t)n_r * (size_t)r->it;
        if (seen[texel]++) {
            st = fail(msg, msg_size, MF_ERR_FORMAT, path, "texel (i_alpha %d, i_theta %d) appears twice", r->ia, r->it);
            break;
        }
        if (fabs(r->v[C_ROUGH] - (double)r->ia / (n_r - 1)) > 1e-6 || fabs(r->v[C_XT] - (double)r->it / (n_u - 1)) > 1e-6) {
            st = fail(msg, msg_size, MF_ERR_FORMAT, path,
                      "texel (i_alpha %d, i_theta %d): roughness %g / x_theta %g off the grid a/%d, t/%d", r->ia, r->it,
                      r->v[C_ROUGH], r->v[C_XT], n_r - 1, n_u - 1);
            break;
        }
        double *d = out->data + texel * (size_t)out->nfields;
        for (int k = C_00; k < C_COUNT; ++k)
            d[col_field[k]] = r->v[k];
        d[MF_LTC_F_ZERO] = 0.0;
    }
    free(seen);
    if (st == MF_OK) {
        mf_status m1 = mf_table_set_meta(out, "source", "ltc_code reference table (Heitz et al. 2016), CSV");
        mf_status m2 = mf_table_set_meta(out, "alpha_min", "1e-5");
        mf_status m3 = mf_table_set_meta(out, "brdf", "ggx");
        if (m1 != MF_OK || m2 != MF_OK || m3 != MF_OK)
            st = fail(msg, msg_size, MF_ERR_INTERNAL, path, "cannot set the metadata");
    }
done:
    if (st != MF_OK && out)
        mf_table_free(out), memset(out, 0, sizeof *out);
    free(rows);
    free(line);
    fclose(f);
    return st;
}
