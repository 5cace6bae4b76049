/* table_meta.c -- the metadata object of every table file, out (JSON text) and in (cJSON), the
 * sidecars, the JSON parser's messages, and the half-float helpers (mf_table_io.h). */
#include "io_internal.h"

#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

const char *io_base_name(const char *path)
{
    const char *s = strrchr(path, '/');
    return s ? s + 1 : path;
}

size_t io_texel_product(const int *sizes, int n)
{
    size_t t = 1;
    for (int k = 0; k < n; ++k) {
        if (sizes[k] < 1 || t > IO_TEXEL_LIMIT / (size_t)sizes[k])
            return 0;
        t *= (size_t)sizes[k];
    }
    return t;
}

/* ---- IEEE 754 binary16 --------------------------------------------------------------------- */

uint16_t mf_half_from_double(double x)
{
    uint16_t sign = signbit(x) ? 0x8000u : 0u;
    if (isnan(x))
        return (uint16_t)(sign | 0x7e00u);
    double a = fabs(x);
    /* 65520 = 65504 + half an ulp: the tie rounds to the even neighbour 2^16, i.e. infinity */
    if (a >= 65520.0)
        return (uint16_t)(sign | 0x7c00u);
    if (a < 0x1p-14) /* subnormal (or zero): a multiple of 2^-24; 1024 * 2^-24 = 2^-14 encodes itself */
        return (uint16_t)(sign | (uint16_t)rint(a * 0x1p24));
    int e;
    double m = frexp(a, &e);       /* a = m 2^e, 0.5 <= m < 1: the half's biased exponent is e - 1 + 15 */
    double q = rint(ldexp(m, 11)); /* 11 significant bits, ties to even: 1024 <= q <= 2048 */
    /* q = 2048 carries into the exponent by the addition, as the encoding is monotonic */
    return (uint16_t)(sign | (((unsigned)(e + 14) << 10) + ((unsigned)q - 1024u)));
}

uint16_t mf_half_from_float(float x) { return mf_half_from_double((double)x); }

double mf_half_to_double(uint16_t h)
{
    unsigned e = (h >> 10) & 0x1fu, m = h & 0x3ffu;
    double v;
    if (e == 0)
        v = ldexp((double)m, -24);
    else if (e == 31)
        v = m ? NAN : INFINITY;
    else
        v = ldexp((double)(m + 1024u), (int)e - 25);
    return (h & 0x8000u) ? -v : v;
}

void io_half_error_add(mf_half_error *e, double x, size_t index)
{
    e->count++;
    if (!isfinite(x))
        return; /* NaN and infinities are stored as such */
    double h = mf_half_to_double(mf_half_from_double(x));
    double err, rel;
    if (isinf(h)) {
        e->overflow_count++;
        err = rel = INFINITY;
    } else {
        err = fabs(h - x);
        rel = (x != 0.0) ? err / fabs(x) : 0.0;
        if (x != 0.0 && h == 0.0)
            e->underflow_count++;
        else if (h != 0.0 && fabs(h) < 0x1p-14)
            e->subnormal_count++;
    }
    if (err > e->max_abs_error)
        e->max_abs_error = err;
    if (rel > e->max_rel_error) {
        e->max_rel_error = rel;
        e->worst_rel_index = index;
    }
}

void mf_half_error_of(const double *x, size_t n, mf_half_error *out)
{
    memset(out, 0, sizeof *out);
    for (size_t i = 0; i < n; ++i)
        io_half_error_add(out, x[i], i);
}

void io_table_half_error(const mf_table *t, const int *fields, int nf, mf_half_error *e)
{
    memset(e, 0, sizeof *e);
    size_t texels = mf_table_texels(t);
    for (size_t i = 0; i < texels; ++i)
        for (int j = 0; j < (fields ? nf : t->nfields); ++j) {
            int f = fields ? fields[j] : j;
            if (f < 0)
                continue;
            size_t idx = i * (size_t)t->nfields + (size_t)f;
            io_half_error_add(e, t->data[idx], idx);
        }
}

/* ---- metadata out -------------------------------------------------------------------------- */

static const char k_texel_centre_text[] =
    "texel i of an axis of n texels holds the parameter p_i = lo + (hi - lo) * i / (n - 1) (n = 1: p_0 = lo); "
    "a texture lookup of parameter p uses uv = (p - lo) / (hi - lo) * (n - 1) / n + 0.5 / n, so the grid "
    "points are the texel centres (i + 0.5) / n";

/* The record layout in words, e.g. "5 float32 fields per texel, texel-major, first axis fastest:
 * field f of texel (i0, i1) is value (i0 + 64 * i1) * 5 + f". */
static void layout_text(mf_buf *b, const mf_table *t, const char *storage)
{
    mf_buf_printf(b, "%d %s field%s per texel, texel-major, first axis fastest: field f of texel (", t->nfields,
                  storage, t->nfields == 1 ? "" : "s");
    for (int k = 0; k < t->naxes; ++k)
        mf_buf_printf(b, "%si%d", k ? ", " : "", k);
    mf_buf_puts(b, ") is value (");
    /* i0 + n0 * (i1 + n1 * (i2 ...)) */
    for (int k = 0; k < t->naxes; ++k) {
        if (k + 1 < t->naxes)
            mf_buf_printf(b, "i%d + %d * %s", k, t->axes[k].size, k + 2 < t->naxes ? "(" : "");
        else
            mf_buf_printf(b, "i%d", k);
    }
    for (int k = 0; k + 2 < t->naxes; ++k)
        mf_buf_puts(b, ")");
    mf_buf_printf(b, ") * %d + f", t->nfields);
}

void io_header_json(mf_buf *b, const mf_table *t, const io_header_extra *x, const char *indent)
{
    mf_buf_printf(b, "{\n%s  \"format\": \"mfkit-table\",\n%s  \"version\": 1,\n%s  \"storage\": \"%s\",\n", indent,
                  indent, indent, x->storage);
    mf_buf_printf(b, "%s  \"layout\": ", indent);
    mf_buf lay = {0};
    layout_text(&lay, t, x->storage);
    mf_buf_put(&lay, "", 1);
    if (lay.failed)
        b->failed = 1;
    else
        mf_json_string(b, lay.data);
    mf_buf_free(&lay);
    mf_buf_printf(b, ",\n%s  \"texel_centre\": ", indent);
    mf_json_string(b, k_texel_centre_text);
    mf_buf_printf(b, ",\n%s  \"axes\": [\n", indent);
    for (int k = 0; k < t->naxes; ++k) {
        const mf_table_axis *a = &t->axes[k];
        char desc[256];
        mf_axis_describe(a, desc, sizeof desc);
        mf_buf_printf(b, "%s    {\"name\": ", indent);
        mf_json_string(b, a->name);
        mf_buf_puts(b, ", \"physical\": ");
        mf_json_string(b, a->physical);
        mf_buf_printf(b, ", \"size\": %d, \"lo\": ", a->size);
        mf_json_number(b, a->lo);
        mf_buf_puts(b, ", \"hi\": ");
        mf_json_number(b, a->hi);
        mf_buf_printf(b, ", \"mapping\": \"%s\", \"physical_min\": ", mf_axis_mapping_name(a->mapping));
        if (isinf(a->physical_min) && a->physical_min < 0)
            mf_buf_puts(b, "null"); /* no clamp (a missing value, not a number) */
        else
            mf_json_number(b, a->physical_min);
        mf_buf_puts(b, ", \"parameterisation\": ");
        mf_json_string(b, desc);
        mf_buf_printf(b, "}%s\n", k + 1 < t->naxes ? "," : "");
    }
    mf_buf_printf(b, "%s  ],\n%s  \"fields\": [", indent, indent);
    for (int f = 0; f < t->nfields; ++f) {
        if (f)
            mf_buf_puts(b, ", ");
        mf_json_string(b, t->fields[f]);
    }
    mf_buf_printf(b, "],\n%s  \"meta\": {", indent);
    for (int i = 0; i < t->nmeta; ++i) {
        mf_buf_printf(b, "%s\n%s    ", i ? "," : "", indent);
        mf_json_string(b, t->meta[i].key);
        mf_buf_puts(b, ": ");
        mf_json_string(b, t->meta[i].value);
    }
    if (t->nmeta)
        mf_buf_printf(b, "\n%s  }", indent);
    else
        mf_buf_puts(b, "}");
    if (x->atlas) {
        const mf_table_atlas *a = x->atlas;
        mf_buf_printf(b, ",\n%s  \"atlas\": \"tiles_x=%d tiles_y=%d tile_w=%d tile_h=%d order=axis2_fastest\"", indent,
                      a->tiles_x, a->tiles_y, a->tile_w, a->tile_h);
        mf_buf_printf(b, ",\n%s  \"atlas_size\": [%d, %d]", indent, a->width, a->height);
    }
    if (x->dds_fields) {
        mf_buf_printf(b, ",\n%s  \"dds_channels\": [", indent);
        for (int c = 0; c < 4; ++c) {
            if (c)
                mf_buf_puts(b, ", ");
            if (x->dds_fields[c] < 0)
                mf_buf_puts(b, "null");
            else
                mf_json_string(b, t->fields[x->dds_fields[c]]);
        }
        mf_buf_puts(b, "]");
    }
    if (x->half) {
        mf_buf_printf(b, ",\n%s  \"half_max_abs_error\": ", indent);
        mf_json_number(b, x->half->max_abs_error);
        mf_buf_printf(b, ",\n%s  \"half_max_rel_error\": ", indent);
        mf_json_number(b, x->half->max_rel_error);
        mf_buf_printf(b, ",\n%s  \"half_overflow_count\": %zu", indent, x->half->overflow_count);
        mf_buf_printf(b, ",\n%s  \"half_underflow_count\": %zu", indent, x->half->underflow_count);
    }
    mf_buf_printf(b, "\n%s}", indent);
}

void io_header_text(mf_buf *b, const mf_table *t, const io_header_extra *x)
{
    io_header_json(b, t, x, "");
    mf_buf_puts(b, "\n");
}

mf_status io_write_with_sidecar(const char *path, const mf_buf *data, const mf_table *t, const io_header_extra *x,
                                char *msg, size_t msg_size)
{
    if (data->failed) {
        mf_io_msg(msg, msg_size, path, "out of memory");
        return MF_ERR_ALLOC;
    }
    mf_buf side = {0}, sp = {0};
    io_header_text(&side, t, x);
    mf_buf_printf(&sp, "%s.json", path);
    mf_buf_put(&sp, "", 1);
    mf_status st = MF_OK;
    mf_io_atomic at[2]; /* the sidecar, the data */
    memset(at, 0, sizeof at);
    if (side.failed || sp.failed) {
        mf_io_msg(msg, msg_size, path, "out of memory");
        st = MF_ERR_ALLOC;
    }
    if (st == MF_OK)
        st = mf_io_atomic_begin(&at[0], sp.data, msg, msg_size);
    if (st == MF_OK)
        st = mf_io_atomic_begin(&at[1], path, msg, msg_size);
    const mf_io_atomic *bad = NULL;
    errno = 0;
    if (st == MF_OK && side.len && fwrite(side.data, 1, side.len, at[0].file) != side.len)
        bad = &at[0];
    else if (st == MF_OK && data->len && fwrite(data->data, 1, data->len, at[1].file) != data->len)
        bad = &at[1];
    if (bad) {
        int err = errno;
        mf_io_msg(msg, msg_size, bad->path, "cannot write temporary file %s: %s", bad->tmp_path,
                  err ? strerror(err) : "write error");
        st = MF_ERR_IO;
    }
    /* both temporaries written and synced before either replaces its target, so a full disk
     * leaves neither file */
    if (st == MF_OK)
        st = mf_io_atomic_commit_all(at, 2, msg, msg_size);
    else
        mf_io_atomic_abort_all(at, 2);
    mf_buf_free(&side);
    mf_buf_free(&sp);
    return st;
}

/* ---- JSON in ------------------------------------------------------------------------------- */

static void line_col(const char *s, size_t pos, size_t *line, size_t *col)
{
    *line = 1;
    *col = 1;
    for (size_t i = 0; i < pos; ++i) {
        if (s[i] == '\n') {
            ++*line;
            *col = 1;
        } else {
            ++*col;
        }
    }
}

/* Non-zero if the text ends inside a string or with an unclosed '[' or '{' (brackets matched by
 * kind; a mismatch means a syntax error, not a truncation). */
static int unbalanced_at_end(const char *s, size_t len)
{
    char stack[64];
    size_t depth = 0, deep = 0; /* deep: levels beyond the stack, counted only */
    int in_str = 0;
    for (size_t i = 0; i < len; ++i) {
        char c = s[i];
        if (in_str) {
            if (c == '\\')
                ++i;
            else if (c == '"')
                in_str = 0;
        } else if (c == '"') {
            in_str = 1;
        } else if (c == '[' || c == '{') {
            if (depth < sizeof stack)
                stack[depth++] = c;
            else
                ++deep;
        } else if (c == ']' || c == '}') {
            if (deep) {
                --deep;
                continue;
            }
            if (depth == 0 || stack[depth - 1] != (c == ']' ? '[' : '{'))
                return 0;
            --depth;
        }
    }
    return in_str || depth > 0 || deep > 0;
}

mf_status io_json_parse(const char *s, size_t len, cJSON **root, char *why, size_t why_size)
{
    *root = NULL;
    const char *nul = memchr(s, '\0', len);
    if (nul) {
        snprintf(why, why_size, "JSON: NUL byte at offset %zu", (size_t)(nul - s));
        return MF_ERR_FORMAT;
    }
    if (len == 0) {
        snprintf(why, why_size, "JSON: empty document");
        return MF_ERR_FORMAT;
    }
    const char *end = NULL;
    cJSON *r = cJSON_ParseWithLengthOpts(s, len, &end, 0);
    size_t pos = end && end >= s ? (size_t)(end - s) : 0;
    if (pos > len)
        pos = len;
    const char *what = NULL;
    if (!r && unbalanced_at_end(s, len)) {
        /* a truncated document: cJSON's error position lies where it backed off, not at the end */
        pos = len;
        what = "unexpected end of input";
    } else if (!r) {
        /* cJSON stops at the first byte it cannot take: name that byte */
        while (pos < len && (s[pos] == ' ' || s[pos] == '\t' || s[pos] == '\n' || s[pos] == '\r'))
            ++pos;
        what = pos >= len ? "unexpected end of input" : "syntax error";
    } else {
        while (pos < len && (s[pos] == ' ' || s[pos] == '\t' || s[pos] == '\n' || s[pos] == '\r'))
            ++pos;
        if (pos < len) {
            what = "trailing characters after the document";
            cJSON_Delete(r);
            r = NULL;
        }
    }
    if (!r) {
        size_t line, col;
        line_col(s, pos, &line, &col);
        if (pos < len && isprint((unsigned char)s[pos]))
            snprintf(why, why_size, "JSON: %s at line %zu, column %zu ('%c')", what, line, col, s[pos]);
        else
            snprintf(why, why_size, "JSON: %s at line %zu, column %zu", what, line, col);
        return MF_ERR_FORMAT;
    }
    *root = r;
    return MF_OK;
}

int io_json_double(const cJSON *v, double *out)
{
    if (cJSON_IsNumber(v)) {
        *out = v->valuedouble;
        return 1;
    }
    return cJSON_IsString(v) && mf_json_nonfinite(v->valuestring, out);
}

static const cJSON *jget(const cJSON *obj, const char *key)
{
    return cJSON_IsObject(obj) ? cJSON_GetObjectItemCaseSensitive(obj, key) : NULL;
}

static size_t jcount(const cJSON *v)
{
    size_t n = 0;
    for (const cJSON *c = v ? v->child : NULL; c; c = c->next)
        ++n;
    return n;
}

static int jcopy_name(const cJSON *v, char *dst, size_t size)
{
    if (!cJSON_IsString(v) || strlen(v->valuestring) >= size)
        return 0;
    snprintf(dst, size, "%s", v->valuestring);
    return 1;
}

static int jint(const cJSON *v, double lo, double hi, long *out)
{
    if (!cJSON_IsNumber(v) || !(v->valuedouble >= lo && v->valuedouble <= hi) || v->valuedouble != floor(v->valuedouble))
        return 0;
    *out = (long)v->valuedouble;
    return 1;
}

mf_status io_header_to_table(const cJSON *h, size_t texels, int nfields_expected, mf_table *t,
                             mf_table_file_info *info, char *why, size_t why_size)
{
    memset(t, 0, sizeof *t);
    mf_table_axis axes[MF_TABLE_MAX_AXES];
    const char *names[MF_TABLE_MAX_FIELDS];
    memset(axes, 0, sizeof axes);
#define HFAIL(...)                                                                                                 \
    do {                                                                                                           \
        snprintf(why, why_size, __VA_ARGS__);                                                                      \
        return MF_ERR_FORMAT;                                                                                      \
    } while (0)
    if (!cJSON_IsObject(h))
        HFAIL("metadata: not a JSON object");
    const cJSON *v = jget(h, "format");
    if (!cJSON_IsString(v) || strcmp(v->valuestring, "mfkit-table") != 0)
        HFAIL("metadata: \"format\" is not \"mfkit-table\"");
    long version;
    if (!jint(jget(h, "version"), 1, 1, &version))
        HFAIL("metadata: unsupported \"version\" (this reader knows 1)");
    const cJSON *ax = jget(h, "axes");
    size_t nax = jcount(ax);
    if (!cJSON_IsArray(ax) || nax < 1 || nax > MF_TABLE_MAX_AXES)
        HFAIL("metadata: \"axes\" must be an array of 1 to %d axes", MF_TABLE_MAX_AXES);
    int naxes = (int)nax;
    int sizes[MF_TABLE_MAX_AXES];
    const cJSON *a = ax->child;
    for (int k = 0; k < naxes; ++k, a = a->next) {
        mf_table_axis *d = &axes[k];
        long size;
        if (!cJSON_IsObject(a))
            HFAIL("metadata: axis %d is not an object", k);
        if (!jcopy_name(jget(a, "name"), d->name, sizeof d->name) ||
            !jcopy_name(jget(a, "physical"), d->physical, sizeof d->physical))
            HFAIL("metadata: axis %d: \"name\" and \"physical\" must be strings of < %d bytes", k, MF_TABLE_NAME_LEN);
        if (!jint(jget(a, "size"), 1, (double)(1L << 20), &size))
            HFAIL("metadata: axis %d: \"size\" must be an integer in [1, 2^20]", k);
        d->size = sizes[k] = (int)size;
        const cJSON *lo = jget(a, "lo"), *hi = jget(a, "hi"), *pm = jget(a, "physical_min"), *m = jget(a, "mapping");
        if (!cJSON_IsNumber(lo) || !cJSON_IsNumber(hi) || !isfinite(lo->valuedouble) || !isfinite(hi->valuedouble))
            HFAIL("metadata: axis %d: \"lo\" and \"hi\" must be finite numbers", k);
        d->lo = lo->valuedouble;
        d->hi = hi->valuedouble;
        if (!cJSON_IsString(m) || mf_axis_mapping_parse(m->valuestring, &d->mapping) != 0)
            HFAIL("metadata: axis %d: unknown \"mapping\"", k);
        if (!pm || cJSON_IsNull(pm))
            d->physical_min = -INFINITY;
        else if (!io_json_double(pm, &d->physical_min))
            HFAIL("metadata: axis %d: \"physical_min\" must be a number or null", k);
    }
    size_t have = io_texel_product(sizes, naxes);
    if (have == 0)
        HFAIL("metadata: more than 2^32 texels");
    if (texels != IO_TEXELS_ANY && have != texels)
        HFAIL("metadata: the axes give %zu texels, the data has %zu", have, texels);
    const cJSON *fl = jget(h, "fields");
    size_t nfl = jcount(fl);
    if (!cJSON_IsArray(fl) || nfl < 1 || nfl > MF_TABLE_MAX_FIELDS)
        HFAIL("metadata: \"fields\" must be an array of 1 to %d names", MF_TABLE_MAX_FIELDS);
    int nfields = (int)nfl;
    const cJSON *fv = fl->child;
    for (int f = 0; f < nfields; ++f, fv = fv->next) {
        if (!cJSON_IsString(fv) || strlen(fv->valuestring) >= MF_TABLE_NAME_LEN)
            HFAIL("metadata: field %d is not a string of < %d bytes", f, MF_TABLE_NAME_LEN);
        names[f] = fv->valuestring;
    }
    if (nfields_expected > 0 && nfields != nfields_expected)
        HFAIL("metadata: %d fields, the data has %d", nfields, nfields_expected);
    const cJSON *meta = jget(h, "meta");
    if (meta && !cJSON_IsObject(meta))
        HFAIL("metadata: \"meta\" is not an object");
    if (meta && jcount(meta) > MF_TABLE_MAX_META)
        HFAIL("metadata: more than %d \"meta\" entries", MF_TABLE_MAX_META);
    for (const cJSON *e = meta ? meta->child : NULL; e; e = e->next)
        if (!cJSON_IsString(e))
            HFAIL("metadata: meta \"%.40s\" is not a string", e->string);
    if (info) {
        const cJSON *st = jget(h, "storage");
        if (cJSON_IsString(st) && strcmp(st->valuestring, "float16") == 0)
            info->half_float = 1;
        double ea, er;
        if (io_json_double(jget(h, "half_max_abs_error"), &ea) && io_json_double(jget(h, "half_max_rel_error"), &er)) {
            long c;
            info->has_half_error = 1;
            info->half_error.max_abs_error = ea;
            info->half_error.max_rel_error = er;
            if (jint(jget(h, "half_overflow_count"), 0, (double)LONG_MAX, &c))
                info->half_error.overflow_count = (size_t)c;
            if (jint(jget(h, "half_underflow_count"), 0, (double)LONG_MAX, &c))
                info->half_error.underflow_count = (size_t)c;
        }
        info->has_metadata = 1;
    }
    mf_status st = mf_table_create(t, naxes, axes, nfields, names);
    if (st == MF_ERR_ALLOC) {
        snprintf(why, why_size, "out of memory for %zu texels", texels);
        return st;
    }
    if (st != MF_OK)
        HFAIL("metadata: invalid axes or field names (names must be [A-Za-z0-9_], distinct; lo != hi)");
    for (const cJSON *e = meta ? meta->child : NULL; e; e = e->next)
        if (mf_table_set_meta(t, e->string, e->valuestring) != MF_OK) {
            mf_table_free(t);
            HFAIL("metadata: invalid meta entry \"%.40s\"", e->string);
        }
    return MF_OK;
#undef HFAIL
}

mf_status io_generic_table(mf_table *t, int naxes, const int *sizes, int nfields, const char *const *names)
{
    mf_table_axis axes[MF_TABLE_MAX_AXES];
    memset(axes, 0, sizeof axes);
    for (int k = 0; k < naxes; ++k) {
        mf_table_axis *a = &axes[k];
        snprintf(a->name, sizeof a->name, "x%d", k);
        snprintf(a->physical, sizeof a->physical, "uv%d", k);
        a->size = sizes[k];
        double n = (double)sizes[k];
        a->lo = 0.5 / n;
        a->hi = (sizes[k] > 1) ? 1.0 - 0.5 / n : a->lo;
        a->mapping = MF_AXIS_IDENTITY;
        a->physical_min = -INFINITY;
    }
    return mf_table_create(t, naxes, axes, nfields, names);
}

mf_status io_read_sidecar(const char *path, cJSON **root, char *msg, size_t msg_size)
{
    *root = NULL;
    mf_buf sp = {0};
    mf_buf_printf(&sp, "%s.json", path);
    mf_buf_put(&sp, "", 1);
    if (sp.failed) {
        mf_io_msg(msg, msg_size, path, "out of memory");
        return MF_ERR_ALLOC;
    }
    unsigned char *data;
    size_t len;
    int missing;
    mf_status st = mf_io_read_file(sp.data, path, &data, &len, &missing, msg, msg_size);
    if (st != MF_OK) {
        mf_buf_free(&sp);
        return missing ? MF_OK : st;
    }
    char why[200];
    st = io_json_parse((const char *)data, len, root, why, sizeof why);
    free(data);
    if (st != MF_OK)
        mf_io_msg(msg, msg_size, path, "sidecar %s: %s", io_base_name(sp.data), why);
    mf_buf_free(&sp);
    return st;
}

/* ---- tables of more than two axes in images ------------------------------------------------- */

mf_status io_image_layout(const char *path, const mf_table *t, mf_table_atlas *a, char *msg, size_t msg_size)
{
    if (t->naxes <= 2)
        return mf_table_atlas_layout(t, 1, a) == MF_OK ? MF_OK : MF_ERR_DOMAIN;
    if (mf_table_atlas_from_meta(t, a) == MF_OK || mf_table_atlas_layout(t, 0, a) == MF_OK)
        return MF_OK;
    mf_io_msg(msg, msg_size, path, "the %d-axis table does not fit a 2D atlas of at most 65536 x 65536 texels "
                                   "(record another tile layout with mf_table_atlas_record)", t->naxes);
    return MF_ERR_UNSUPPORTED;
}

mf_status io_image_header_to_table(const cJSON *h, int width, int height, int nfields_expected, mf_table *t,
                                   mf_table_file_info *info, mf_table_atlas *a, char *why, size_t why_size)
{
    memset(a, 0, sizeof *a);
    const cJSON *at = cJSON_IsObject(h) ? jget(h, "atlas") : NULL;
    mf_status st;
    if (!at) {
        st = io_header_to_table(h, (size_t)width * (size_t)height, nfields_expected, t, info, why, why_size);
        if (st != MF_OK)
            return st;
        if (t->naxes > 2 || t->axes[0].size != width || (t->naxes == 2 ? t->axes[1].size : 1) != height) {
            snprintf(why, why_size, "metadata: %d axes (axis 0 of %d texels) do not fit a %d x %d image%s", t->naxes,
                     t->axes[0].size, width, height, t->naxes > 2 ? " without an \"atlas\" layout" : "");
            mf_table_free(t);
            return MF_ERR_FORMAT;
        }
        return mf_table_atlas_layout(t, 1, a) == MF_OK ? MF_OK : MF_ERR_FORMAT;
    }
    int tx, ty, tw, th, used = 0;
    if (!cJSON_IsString(at) ||
        sscanf(at->valuestring, "tiles_x=%d tiles_y=%d tile_w=%d tile_h=%d order=axis2_fastest%n", &tx, &ty, &tw,
               &th, &used) != 4 || used == 0 || at->valuestring[used] != '\0' || tx < 1) {
        snprintf(why, why_size, "metadata: \"atlas\" is not \"tiles_x=X tiles_y=Y tile_w=W tile_h=H "
                                "order=axis2_fastest\"");
        return MF_ERR_FORMAT;
    }
    st = io_header_to_table(h, IO_TEXELS_ANY, nfields_expected, t, info, why, why_size);
    if (st != MF_OK)
        return st;
    if (t->naxes < 3 || mf_table_atlas_layout(t, tx, a) != MF_OK || a->tiles_x != tx || a->tiles_y != ty ||
        a->tile_w != tw || a->tile_h != th || a->width != width || a->height != height) {
        snprintf(why, why_size, "metadata: the atlas (%d x %d tiles of %d x %d) does not fit the %d axes and the "
                                "%d x %d image", tx, ty, tw, th, t->naxes, width, height);
        mf_table_free(t);
        memset(a, 0, sizeof *a);
        return MF_ERR_FORMAT;
    }
    return MF_OK;
}
