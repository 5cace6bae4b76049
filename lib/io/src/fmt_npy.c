/* fmt_npy.c -- .npy tables: NumPy format 1.0, <f4, C order; metadata in "<file>.npy.json". */
#include "io_internal.h"

#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>

/* NumPy format 1.0: magic, version, little-endian header length, a Python dict literal padded
 * with spaces and a newline to a multiple of 64 bytes, then the raw little-endian float32s. */
static void build_npy(mf_buf *b, const mf_table *t)
{
    mf_buf h = {0};
    mf_buf_puts(&h, "{'descr': '<f4', 'fortran_order': False, 'shape': (");
    for (int k = t->naxes - 1; k >= 0; --k)
        mf_buf_printf(&h, "%d, ", t->axes[k].size);
    mf_buf_printf(&h, "%d), }", t->nfields);
    size_t total = 10 + h.len + 1;
    size_t pad = (64 - total % 64) % 64;
    for (size_t i = 0; i < pad; ++i)
        mf_buf_puts(&h, " ");
    mf_buf_puts(&h, "\n");
    if (h.failed || h.len > 65535) {
        b->failed = 1;
        mf_buf_free(&h);
        return;
    }
    mf_buf_put(b, "\x93NUMPY\x01\x00", 8);
    mf_buf_u16le(b, (uint16_t)h.len);
    mf_buf_put(b, h.data, h.len);
    mf_buf_free(&h);
    size_t n = mf_table_texels(t) * (size_t)t->nfields;
    mf_buf_reserve(b, n * 4);
    for (size_t i = 0; i < n && !b->failed; ++i)
        mf_buf_f32le(b, (float)t->data[i]);
}

/* The dict of a .npy header: {'descr': '<f4', 'fortran_order': False, 'shape': (a, b, c), } */
typedef struct npy_header {
    char descr[16];
    int fortran, have_descr, have_fortran, have_shape;
    int ndim;
    size_t shape[8];
} npy_header;

static const char *npy_skip(const char *s, const char *end)
{
    while (s < end && (*s == ' ' || *s == '\t' || *s == '\n' || *s == '\r'))
        ++s;
    return s;
}

/* A quoted Python string ('...' or "...", no escapes) into out; NULL on error. */
static const char *npy_string(const char *s, const char *end, char *out, size_t size)
{
    if (s >= end || (*s != '\'' && *s != '"'))
        return NULL;
    char q = *s++;
    size_t n = 0;
    while (s < end && *s != q) {
        if (*s == '\\' || n + 1 >= size)
            return NULL;
        out[n++] = *s++;
    }
    if (s >= end)
        return NULL;
    out[n] = '\0';
    return s + 1;
}

static int npy_parse_header(const char *s, size_t len, npy_header *h, char *why, size_t why_size)
{
    const char *end = s + len;
    memset(h, 0, sizeof *h);
    s = npy_skip(s, end);
    if (s >= end || *s++ != '{') {
        snprintf(why, why_size, "header is not a dict");
        return 0;
    }
    for (;;) {
        s = npy_skip(s, end);
        if (s < end && *s == '}') {
            ++s;
            break;
        }
        char key[32];
        s = npy_string(s, end, key, sizeof key);
        if (!s) {
            snprintf(why, why_size, "header: expected a quoted key");
            return 0;
        }
        s = npy_skip(s, end);
        if (s >= end || *s++ != ':') {
            snprintf(why, why_size, "header: expected ':' after '%s'", key);
            return 0;
        }
        s = npy_skip(s, end);
        if (strcmp(key, "descr") == 0) {
            s = npy_string(s, end, h->descr, sizeof h->descr);
            if (!s) {
                snprintf(why, why_size, "header: 'descr' is not a short string");
                return 0;
            }
            h->have_descr = 1;
        } else if (strcmp(key, "fortran_order") == 0) {
            if ((size_t)(end - s) >= 4 && memcmp(s, "True", 4) == 0) {
                h->fortran = 1;
                s += 4;
            } else if ((size_t)(end - s) >= 5 && memcmp(s, "False", 5) == 0) {
                s += 5;
            } else {
                snprintf(why, why_size, "header: 'fortran_order' is not True or False");
                return 0;
            }
            h->have_fortran = 1;
        } else if (strcmp(key, "shape") == 0) {
            if (s >= end || *s++ != '(') {
                snprintf(why, why_size, "header: 'shape' is not a tuple");
                return 0;
            }
            for (;;) {
                s = npy_skip(s, end);
                if (s < end && *s == ')') {
                    ++s;
                    break;
                }
                if (s >= end || !isdigit((unsigned char)*s) || h->ndim >= 8) {
                    snprintf(why, why_size, "header: bad 'shape' tuple");
                    return 0;
                }
                size_t v = 0;
                while (s < end && isdigit((unsigned char)*s)) {
                    v = v * 10 + (size_t)(*s++ - '0');
                    if (v > IO_TEXEL_LIMIT) {
                        snprintf(why, why_size, "header: 'shape' dimension too large");
                        return 0;
                    }
                }
                h->shape[h->ndim++] = v;
                s = npy_skip(s, end);
                if (s < end && *s == ',')
                    ++s;
                else if (!(s < end && *s == ')')) {
                    snprintf(why, why_size, "header: bad 'shape' tuple");
                    return 0;
                }
            }
            h->have_shape = 1;
        } else {
            snprintf(why, why_size, "header: unknown key '%s'", key);
            return 0;
        }
        s = npy_skip(s, end);
        if (s < end && *s == ',')
            ++s;
        else if (!(s < end && *s == '}')) {
            snprintf(why, why_size, "header: expected ',' or '}'");
            return 0;
        }
    }
    s = npy_skip(s, end);
    if (s != end) {
        snprintf(why, why_size, "header: characters after the dict");
        return 0;
    }
    if (!h->have_descr || !h->have_fortran || !h->have_shape) {
        snprintf(why, why_size, "header: missing 'descr', 'fortran_order' or 'shape'");
        return 0;
    }
    return 1;
}

static mf_status read_npy(const char *path, mf_table *t, mf_table_file_info *info, char *msg, size_t msg_size)
{
    unsigned char *data;
    size_t len;
    mf_status st = mf_io_read_file(path, path, &data, &len, NULL, msg, msg_size);
    if (st != MF_OK)
        return st;
    char why[200];
    npy_header h;
    size_t hl, off;
    if (len < 10 || memcmp(data, "\x93NUMPY", 6) != 0) {
        mf_io_msg(msg, msg_size, path, "not a .npy file (no \\x93NUMPY magic)");
        goto bad;
    }
    if (data[6] == 1) {
        hl = io_get_u16(data + 8);
        off = 10;
    } else if ((data[6] == 2 || data[6] == 3) && len >= 12) {
        hl = io_get_u32(data + 8);
        off = 12;
    } else {
        mf_io_msg(msg, msg_size, path, "unsupported .npy version %d.%d", data[6], data[7]);
        goto bad;
    }
    if (hl > len - off) {
        mf_io_msg(msg, msg_size, path, "truncated .npy header (%zu bytes announced, %zu present)", hl, len - off);
        goto bad;
    }
    if (!npy_parse_header((const char *)data + off, hl, &h, why, sizeof why)) {
        mf_io_msg(msg, msg_size, path, "%s", why);
        goto bad;
    }
    off += hl;
    if (strcmp(h.descr, "<f4") != 0 || h.fortran) {
        mf_io_msg(msg, msg_size, path, "unsupported array: dtype '%s'%s (expected '<f4', C order)", h.descr,
                h.fortran ? ", Fortran order" : "");
        goto bad_unsupported;
    }
    if (h.ndim < 1 || h.ndim > MF_TABLE_MAX_AXES + 1) {
        mf_io_msg(msg, msg_size, path, "unsupported shape with %d dimensions (expected 2 to %d)", h.ndim,
                MF_TABLE_MAX_AXES + 1);
        goto bad_unsupported;
    }
    /* shape (n_{k-1}, ..., n_0, nfields); a 1-D array is one axis of one field */
    int naxes = h.ndim > 1 ? h.ndim - 1 : 1;
    size_t nf = h.ndim > 1 ? h.shape[h.ndim - 1] : 1;
    int sizes[MF_TABLE_MAX_AXES];
    for (int k = 0; k < naxes; ++k) {
        size_t s = h.ndim > 1 ? h.shape[h.ndim - 2 - k] : h.shape[0];
        if (s < 1 || s > (1u << 20)) {
            mf_io_msg(msg, msg_size, path, "axis %d: size %zu outside [1, 2^20]", k, s);
            goto bad;
        }
        sizes[k] = (int)s;
    }
    if (nf < 1 || nf > MF_TABLE_MAX_FIELDS) {
        mf_io_msg(msg, msg_size, path, "%zu fields per texel (1 to %d supported)", nf, MF_TABLE_MAX_FIELDS);
        goto bad;
    }
    size_t texels = io_texel_product(sizes, naxes);
    if (texels == 0) {
        mf_io_msg(msg, msg_size, path, "more than 2^32 texels");
        goto bad;
    }
    size_t count = texels * nf;
    if (len - off < count * 4) {
        mf_io_msg(msg, msg_size, path, "%zu data bytes, the shape needs %zu (truncated or corrupt)", len - off,
                  count * 4);
        goto bad;
    }
    if (len - off > count * 4) {
        mf_io_msg(msg, msg_size, path, "%zu bytes after the %zu data bytes of the shape (trailing data)",
                  len - off - count * 4, count * 4);
        goto bad;
    }
    cJSON *side;
    st = io_read_sidecar(path, &side, msg, msg_size);
    if (st != MF_OK) {
        free(data);
        return st;
    }
    if (side) {
        st = io_header_to_table(side, texels, (int)nf, t, info, why, sizeof why);
        cJSON_Delete(side);
        if (st != MF_OK) {
            mf_io_msg(msg, msg_size, path, "sidecar %s.json: %s", io_base_name(path), why);
            free(data);
            return st;
        }
        int match = (t->naxes == naxes);
        for (int k = 0; match && k < naxes; ++k)
            match = (t->axes[k].size == sizes[k]);
        if (!match) {
            mf_io_msg(msg, msg_size, path, "sidecar %s.json: axes do not match the array shape", io_base_name(path));
            mf_table_free(t);
            goto bad;
        }
    } else {
        char names[MF_TABLE_MAX_FIELDS][8];
        const char *np[MF_TABLE_MAX_FIELDS];
        for (size_t f = 0; f < nf; ++f) {
            snprintf(names[f], sizeof names[f], "f%zu", f);
            np[f] = names[f];
        }
        st = io_generic_table(t, naxes, sizes, (int)nf, np);
        if (st != MF_OK) {
            mf_io_msg(msg, msg_size, path, "%s", st == MF_ERR_ALLOC ? "out of memory" : "invalid shape");
            free(data);
            return st;
        }
    }
    for (size_t i = 0; i < count; ++i)
        t->data[i] = (double)io_get_f32(data + off + 4 * i);
    free(data);
    return MF_OK;
bad:
    free(data);
    return MF_ERR_FORMAT;
bad_unsupported:
    free(data);
    return MF_ERR_UNSUPPORTED;
}

static mf_status write_npy(const char *path, const mf_table *t, const io_write_ctx *c, char *msg, size_t msg_size)
{
    (void)c;
    io_header_extra x = {"float32", NULL, NULL, NULL};
    mf_buf b = {0};
    build_npy(&b, t);
    mf_status st = io_write_with_sidecar(path, &b, t, &x, msg, msg_size);
    mf_buf_free(&b);
    return st;
}

static const char *const k_ext[] = {"npy", NULL};
const io_format_ops io_format_npy = {MF_TABLE_FORMAT_NPY,
                                     "npy",
                                     k_ext,
                                     MF_TABLE_MAX_AXES,
                                     IO_CAP_METADATA | IO_CAP_SIDECAR,
                                     write_npy,
                                     read_npy};
