/* table_io.c -- mf_table_write and mf_table_read: the table of formats and the checks every
 * format shares; the formats themselves are in fmt_*.c (mf_table_io.h, docs/tables.md). */
#include "io_internal.h"

#include <ctype.h>
#include <stdio.h>

/* In the order of mf_table_format (index = id). */
static const io_format_ops *const k_formats[] = {
    NULL,           &io_format_exr,  &io_format_dds, &io_format_c_header, &io_format_glsl,
    &io_format_hlsl, &io_format_json, &io_format_npy, &io_format_csv, &io_format_ktx2,
};
#define NFORMATS ((int)(sizeof k_formats / sizeof k_formats[0]))

static const io_format_ops *format_ops(mf_table_format f)
{
    return ((int)f > 0 && (int)f < NFORMATS) ? k_formats[f] : NULL;
}

const char *mf_table_format_name(mf_table_format f)
{
    const io_format_ops *o = format_ops(f);
    return o ? o->name : "unknown";
}

static int ieq(const char *a, const char *b)
{
    for (; *a && *b; ++a, ++b)
        if (tolower((unsigned char)*a) != tolower((unsigned char)*b))
            return 0;
    return *a == *b;
}

mf_table_format mf_table_format_from_path(const char *path)
{
    if (!path)
        return MF_TABLE_FORMAT_UNKNOWN;
    const char *slash = strrchr(path, '/');
    const char *bslash = strrchr(path, '\\');
    if (bslash && (!slash || bslash > slash))
        slash = bslash;
    const char *base = slash ? slash + 1 : path;
    const char *dot = strrchr(base, '.');
    if (!dot || dot == base)
        return MF_TABLE_FORMAT_UNKNOWN;
    for (int f = 1; f < NFORMATS; ++f)
        for (const char *const *e = k_formats[f]->extensions; *e; ++e)
            if (ieq(dot + 1, *e))
                return k_formats[f]->id;
    return MF_TABLE_FORMAT_UNKNOWN;
}

int mf_table_format_readable(mf_table_format f)
{
    const io_format_ops *o = format_ops(f);
    return o && o->read != NULL;
}

/* ".exr .dds ..." of the formats with (readable) or without a reader, into buf. */
static const char *extension_list(int readable_only, char *buf, size_t size)
{
    size_t n = 0;
    buf[0] = '\0';
    for (int f = 1; f < NFORMATS; ++f)
        if (!readable_only || k_formats[f]->read)
            for (const char *const *e = k_formats[f]->extensions; *e && n < size; ++e) {
                int w = snprintf(buf + n, size - n, "%s.%s", n ? " " : "", *e);
                if (w < 0)
                    break;
                n += (size_t)w;
            }
    return buf;
}

void mf_table_write_options_default(mf_table_write_options *opt)
{
    memset(opt, 0, sizeof *opt);
    opt->format = MF_TABLE_FORMAT_UNKNOWN;
    for (int c = 0; c < 4; ++c)
        opt->dds_fields[c] = -1;
}

static int table_valid(const mf_table *t)
{
    if (!t || !t->data || t->naxes < 1 || t->naxes > MF_TABLE_MAX_AXES || t->nfields < 1 ||
        t->nfields > MF_TABLE_MAX_FIELDS)
        return 0;
    int sizes[MF_TABLE_MAX_AXES];
    for (int k = 0; k < t->naxes; ++k)
        sizes[k] = t->axes[k].size;
    return io_texel_product(sizes, t->naxes) != 0;
}

/* The identifier prefix: the given one, or the file's stem with non-identifier characters
 * replaced by '_' (and "t_" before a leading digit). */
static int make_prefix(const char *path, const char *given, char *out, size_t size)
{
    if (given) {
        size_t n = strlen(given);
        if (n == 0 || n >= size || isdigit((unsigned char)given[0]))
            return 0;
        for (size_t i = 0; i < n; ++i)
            if (!(isalnum((unsigned char)given[i]) || given[i] == '_'))
                return 0;
        memcpy(out, given, n + 1);
        return 1;
    }
    const char *base = io_base_name(path);
    const char *dot = strrchr(base, '.');
    size_t n = dot && dot > base ? (size_t)(dot - base) : strlen(base);
    size_t o = 0;
    if (n == 0 || isdigit((unsigned char)base[0])) {
        memcpy(out, "t_", 2);
        o = 2;
    }
    for (size_t i = 0; i < n && o + 1 < size; ++i)
        out[o++] = (isalnum((unsigned char)base[i]) || base[i] == '_') ? base[i] : '_';
    out[o] = '\0';
    if (o == 2 && n == 0)
        snprintf(out, size, "table");
    return 1;
}

mf_status mf_table_write(const char *path, const mf_table *t, const mf_table_write_options *opt,
                         mf_half_error *half_out, char *msg, size_t msg_size)
{
    mf_io_msg_clear(msg, msg_size);
    if (half_out)
        memset(half_out, 0, sizeof *half_out);
    mf_table_write_options o;
    if (opt)
        o = *opt;
    else
        mf_table_write_options_default(&o);
    if (!path || !*path || !table_valid(t)) {
        mf_io_msg(msg, msg_size, path, "invalid argument (NULL or empty path, or an invalid table)");
        return MF_ERR_DOMAIN;
    }
    mf_table_format fmt = o.format != MF_TABLE_FORMAT_UNKNOWN ? o.format : mf_table_format_from_path(path);
    const io_format_ops *ops = format_ops(fmt);
    if (!ops) {
        char list[128];
        mf_io_msg(msg, msg_size, path, "unknown table format (extensions: %s)", extension_list(0, list, sizeof list));
        return MF_ERR_UNSUPPORTED;
    }
    if (o.half_float && !(ops->caps & IO_CAP_HALF)) {
        mf_io_msg(msg, msg_size, path, "half floats are stored only in .exr, .dds and .ktx2 files, not .%s", ops->name);
        return MF_ERR_UNSUPPORTED;
    }
    if (t->naxes > ops->max_axes) {
        mf_io_msg(msg, msg_size, path, "a .%s image holds at most %d axes, the table has %d", ops->name, ops->max_axes,
                  t->naxes);
        return MF_ERR_UNSUPPORTED;
    }
    io_write_ctx c;
    memset(&c, 0, sizeof c);
    c.half_float = o.half_float;
    char prefix[64];
    if (ops->caps & IO_CAP_PREFIX) {
        if (!make_prefix(path, o.prefix, prefix, sizeof prefix)) {
            mf_io_msg(msg, msg_size, path,
                      "invalid identifier prefix '%s' (letters, digits, '_', not a leading digit, < 64)",
                      o.prefix ? o.prefix : "");
            return MF_ERR_DOMAIN;
        }
        c.prefix = prefix;
    }
    c.zstd_level = o.zstd_level;
    c.dds_legacy = o.dds_legacy;
    if (o.zstd_level < 0 || o.zstd_level > 22 || (o.zstd_level && fmt != MF_TABLE_FORMAT_KTX2)) {
        mf_io_msg(msg, msg_size, path, "Zstandard level %d: only .ktx2 files are supercompressed, levels 1 to 22",
                  o.zstd_level);
        return MF_ERR_DOMAIN;
    }
    if (o.dds_legacy && fmt != MF_TABLE_FORMAT_DDS) {
        mf_io_msg(msg, msg_size, path, "the legacy DDS header applies to .dds files only");
        return MF_ERR_DOMAIN;
    }
    if ((ops->caps & IO_CAP_RGBA) || ((ops->caps & IO_CAP_RGBA_OPTIONAL) && o.dds_fields_set)) {
        c.ch_set = 1;
        for (int k = 0; k < 4; ++k) {
            c.ch[k] = o.dds_fields_set ? o.dds_fields[k] : (k < t->nfields ? k : -1);
            if (c.ch[k] < -1 || c.ch[k] >= t->nfields) {
                mf_io_msg(msg, msg_size, path, "DDS channel %d: field index %d outside [-1, %d]", k, c.ch[k],
                          t->nfields - 1);
                return MF_ERR_DOMAIN;
            }
            for (int d = 0; d < k; ++d)
                if (c.ch[k] >= 0 && c.ch[k] == c.ch[d]) {
                    mf_io_msg(msg, msg_size, path, "DDS channels %d and %d: the same field '%s'", d, k,
                              t->fields[c.ch[k]]);
                    return MF_ERR_DOMAIN;
                }
        }
    }
    mf_half_error he;
    memset(&he, 0, sizeof he);
    if (o.half_float)
        io_table_half_error(t, c.ch_set ? c.ch : NULL, 4, &he);
    c.half = &he;
    mf_status st = ops->write(path, t, &c, msg, msg_size);
    if (st == MF_OK && half_out && o.half_float)
        *half_out = he;
    return st;
}

mf_status mf_table_read(const char *path, mf_table *out, mf_table_file_info *info, char *msg, size_t msg_size)
{
    mf_io_msg_clear(msg, msg_size);
    if (out)
        memset(out, 0, sizeof *out);
    if (info) {
        memset(info, 0, sizeof *info);
        for (int c = 0; c < 4; ++c)
            info->dds_fields[c] = -1;
    }
    if (!path || !out) {
        mf_io_msg(msg, msg_size, path, "invalid argument (NULL path or table)");
        return MF_ERR_DOMAIN;
    }
    mf_table_format fmt = mf_table_format_from_path(path);
    if (info)
        info->format = fmt;
    const io_format_ops *ops = format_ops(fmt);
    char list[128];
    if (!ops) {
        mf_io_msg(msg, msg_size, path, "unknown table format (readable: %s)", extension_list(1, list, sizeof list));
        return MF_ERR_UNSUPPORTED;
    }
    if (!ops->read) {
        mf_io_msg(msg, msg_size, path, ".%s files are written, not read (readable: %s)", ops->name,
                  extension_list(1, list, sizeof list));
        return MF_ERR_UNSUPPORTED;
    }
    mf_status st = ops->read(path, out, info, msg, msg_size);
    if (st != MF_OK) {
        if (out->data)
            mf_table_free(out);
        memset(out, 0, sizeof *out);
        if (info) {
            memset(info, 0, sizeof *info);
            info->format = fmt;
            for (int c = 0; c < 4; ++c)
                info->dds_fields[c] = -1;
        }
    }
    return st;
}
