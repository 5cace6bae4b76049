/* fmt_json.c -- .json tables: {"header": <metadata>, "data": [[record], ...]} (mf_table_io.h). */
#include "io_internal.h"

#include <math.h>
#include <stdlib.h>

/* JSON: {"header": ..., "data": [[record], ...]} */
static void build_json(mf_buf *b, const mf_table *t)
{
    io_header_extra x = {"float32", NULL, NULL, NULL};
    mf_buf_puts(b, "{\n  \"header\": ");
    io_header_json(b, t, &x, "  ");
    mf_buf_puts(b, ",\n  \"data\": [\n");
    size_t texels = mf_table_texels(t);
    for (size_t i = 0; i < texels && !b->failed; ++i) {
        mf_buf_puts(b, "    [");
        for (int f = 0; f < t->nfields; ++f) {
            if (f)
                mf_buf_puts(b, ", ");
            mf_json_float(b, (float)t->data[i * (size_t)t->nfields + (size_t)f]);
        }
        mf_buf_puts(b, i + 1 < texels ? "],\n" : "]\n");
    }
    mf_buf_puts(b, "  ]\n}\n");
}

/* A record value: a number, one of the non-finite strings of mf_json_number, or null (NaN, as
 * files before the one JSON emitter wrote it).  Numbers are parsed as doubles, then rounded to
 * float: exact for the "%.9g" of a float, which lies far from a float rounding boundary. */
static int record_value(const cJSON *v, double *out)
{
    double d;
    if (cJSON_IsNull(v)) {
        *out = NAN;
        return 1;
    }
    if (!io_json_double(v, &d))
        return 0;
    *out = (double)(float)d;
    return 1;
}

static mf_status read_json(const char *path, mf_table *t, mf_table_file_info *info, char *msg, size_t msg_size)
{
    unsigned char *data;
    size_t len;
    mf_status st = mf_io_read_file(path, path, &data, &len, NULL, msg, msg_size);
    if (st != MF_OK)
        return st;
    cJSON *root;
    char why[200];
    st = io_json_parse((const char *)data, len, &root, why, sizeof why);
    free(data);
    if (st != MF_OK) {
        mf_io_msg(msg, msg_size, path, "%s", why);
        return st;
    }
    const cJSON *h = cJSON_GetObjectItemCaseSensitive(root, "header");
    const cJSON *d = cJSON_GetObjectItemCaseSensitive(root, "data");
    if (!cJSON_IsObject(root) || !h || !cJSON_IsArray(d)) {
        cJSON_Delete(root);
        mf_io_msg(msg, msg_size, path, "not an mfkit table: expected an object with \"header\" and \"data\" (an array)");
        return MF_ERR_FORMAT;
    }
    size_t nrec = 0;
    for (const cJSON *r = d->child; r; r = r->next)
        ++nrec;
    st = io_header_to_table(h, nrec, 0, t, info, why, sizeof why);
    if (st != MF_OK) {
        cJSON_Delete(root);
        mf_io_msg(msg, msg_size, path, "%s", why);
        return st;
    }
    size_t nf = (size_t)t->nfields, i = 0;
    for (const cJSON *r = d->child; r; r = r->next, ++i) {
        size_t f = 0;
        const cJSON *v = cJSON_IsArray(r) ? r->child : NULL;
        for (; v && f < nf; v = v->next, ++f)
            if (!record_value(v, &t->data[i * nf + f])) {
                mf_io_msg(msg, msg_size, path, "data record %zu, field %zu: not a number, null or \"NaN\"/\"Infinity\"/\"-Infinity\"", i, f);
                goto bad;
            }
        if (!cJSON_IsArray(r) || v || f != nf) {
            mf_io_msg(msg, msg_size, path, "data record %zu: expected an array of %zu numbers", i, nf);
            goto bad;
        }
    }
    cJSON_Delete(root);
    return MF_OK;
bad:
    cJSON_Delete(root);
    mf_table_free(t);
    return MF_ERR_FORMAT;
}

static mf_status write_json(const char *path, const mf_table *t, const io_write_ctx *c, char *msg, size_t msg_size)
{
    (void)c;
    mf_buf b = {0};
    build_json(&b, t);
    mf_status st = mf_io_write_buf_atomic(path, &b, msg, msg_size);
    mf_buf_free(&b);
    return st;
}

static const char *const k_ext[] = {"json", NULL};
const io_format_ops io_format_json = {MF_TABLE_FORMAT_JSON, "json", k_ext, MF_TABLE_MAX_AXES, IO_CAP_METADATA,
                                      write_json, read_json};
