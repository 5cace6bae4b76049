/* fmt_csv.c -- .csv tables (write-only): one row per texel. */
#include "io_internal.h"

#include <math.h>

/* CSV: indices, axis parameters, physical values, fields. */
static void csv_value(mf_buf *b, double v, int digits)
{
    if (isnan(v))
        mf_buf_puts(b, "nan");
    else if (isinf(v))
        mf_buf_puts(b, v > 0 ? "inf" : "-inf");
    else
        mf_buf_printf(b, "%.*g", digits, v);
}

static void build_csv(mf_buf *b, const mf_table *t)
{
    for (int k = 0; k < t->naxes; ++k)
        mf_buf_printf(b, "%si%d", k ? "," : "", k);
    for (int k = 0; k < t->naxes; ++k)
        mf_buf_printf(b, ",%s", t->axes[k].name);
    for (int k = 0; k < t->naxes; ++k)
        if (strcmp(t->axes[k].physical, t->axes[k].name) != 0)
            mf_buf_printf(b, ",%s", t->axes[k].physical);
    for (int f = 0; f < t->nfields; ++f)
        mf_buf_printf(b, ",%s", t->fields[f]);
    mf_buf_puts(b, "\n");
    size_t texels = mf_table_texels(t);
    int idx[MF_TABLE_MAX_AXES] = {0};
    for (size_t i = 0; i < texels && !b->failed; ++i) {
        for (int k = 0; k < t->naxes; ++k)
            mf_buf_printf(b, "%s%d", k ? "," : "", idx[k]);
        for (int k = 0; k < t->naxes; ++k) {
            mf_buf_puts(b, ",");
            csv_value(b, mf_table_axis_param(&t->axes[k], idx[k]), 17);
        }
        for (int k = 0; k < t->naxes; ++k)
            if (strcmp(t->axes[k].physical, t->axes[k].name) != 0) {
                mf_buf_puts(b, ",");
                csv_value(b, mf_table_axis_physical(&t->axes[k], mf_table_axis_param(&t->axes[k], idx[k])), 17);
            }
        for (int f = 0; f < t->nfields; ++f) {
            mf_buf_puts(b, ",");
            csv_value(b, (double)(float)t->data[i * (size_t)t->nfields + (size_t)f], 9);
        }
        mf_buf_puts(b, "\n");
        for (int k = 0; k < t->naxes; ++k) { /* first axis fastest */
            if (++idx[k] < t->axes[k].size)
                break;
            idx[k] = 0;
        }
    }
}


static mf_status write_csv(const char *path, const mf_table *t, const io_write_ctx *c, char *msg, size_t msg_size)
{
    (void)c;
    mf_buf b = {0};
    build_csv(&b, t);
    mf_status st = mf_io_write_buf_atomic(path, &b, msg, msg_size);
    mf_buf_free(&b);
    return st;
}

static const char *const k_ext[] = {"csv", NULL};
const io_format_ops io_format_csv = {MF_TABLE_FORMAT_CSV, "csv", k_ext, MF_TABLE_MAX_AXES, 0, write_csv, NULL};
