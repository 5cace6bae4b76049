/* mf_table_io.c -- table files: EXR, DDS, C header, GLSL/HLSL, JSON, NPY, CSV (see mf_table_io.h
 * and docs/tables.md).  Plain C11; POSIX only for fsync/getpid where available. */
#if defined(__unix__) || defined(__APPLE__)
#define _POSIX_C_SOURCE 200809L
#include <unistd.h>
#define MF_TABLE_IO_POSIX 1
#endif

#include "mfkit/mf_table_io.h"

#include <ctype.h>
#include <errno.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mfkit/mf_image.h"

#define IO_MAX_FILE_BYTES ((size_t)1 << 30) /* larger inputs are refused, not read */
#define JSON_MAX_DEPTH 32
#define JSON_MAX_NODES ((size_t)1 << 26)
#define TEXEL_LIMIT ((size_t)1 << 32) /* mf_table_create's limit */

/* ---- messages ------------------------------------------------------------------------------ */

/* "path: reason" into msg, on one line. */
#if defined(__GNUC__)
__attribute__((format(printf, 4, 5)))
#endif
static void set_msg(char *msg, size_t msg_size, const char *path, const char *fmt, ...)
{
    if (!msg || msg_size == 0)
        return;
    int n = snprintf(msg, msg_size, "%s: ", path ? path : "(null)");
    if (n < 0 || (size_t)n >= msg_size)
        return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg + n, msg_size - (size_t)n, fmt, ap);
    va_end(ap);
    for (char *c = msg; *c; ++c)
        if (*c == '\n' || *c == '\r')
            *c = ' ';
}

static void clear_msg(char *msg, size_t msg_size)
{
    if (msg && msg_size)
        msg[0] = '\0';
}

/* ---- growable byte buffer ------------------------------------------------------------------ */

typedef struct sbuf {
    char *p;
    size_t len, cap;
    int failed; /* an allocation failed: everything after it is dropped */
} sbuf;

static int sb_reserve(sbuf *b, size_t add)
{
    if (b->failed)
        return 0;
    if (add <= b->cap - b->len)
        return 1;
    size_t cap = b->cap ? b->cap : 4096;
    while (cap - b->len < add) {
        if (cap > SIZE_MAX / 2) {
            b->failed = 1;
            return 0;
        }
        cap *= 2;
    }
    char *p = realloc(b->p, cap);
    if (!p) {
        b->failed = 1;
        return 0;
    }
    b->p = p;
    b->cap = cap;
    return 1;
}

static void sb_put(sbuf *b, const void *data, size_t n)
{
    if (n && sb_reserve(b, n)) {
        memcpy(b->p + b->len, data, n);
        b->len += n;
    }
}

static void sb_puts(sbuf *b, const char *s) { sb_put(b, s, strlen(s)); }

#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
static void sb_printf(sbuf *b, const char *fmt, ...)
{
    char small[256];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(small, sizeof small, fmt, ap);
    va_end(ap);
    if (n < 0) {
        b->failed = 1;
        return;
    }
    if ((size_t)n < sizeof small) {
        sb_put(b, small, (size_t)n);
        return;
    }
    if (!sb_reserve(b, (size_t)n + 1))
        return;
    va_start(ap, fmt);
    vsnprintf(b->p + b->len, (size_t)n + 1, fmt, ap);
    va_end(ap);
    b->len += (size_t)n;
}

static void sb_u16(sbuf *b, uint16_t v)
{
    unsigned char c[2] = {(unsigned char)(v & 0xff), (unsigned char)(v >> 8)};
    sb_put(b, c, 2);
}

static void sb_u32(sbuf *b, uint32_t v)
{
    unsigned char c[4] = {(unsigned char)(v & 0xff), (unsigned char)((v >> 8) & 0xff),
                          (unsigned char)((v >> 16) & 0xff), (unsigned char)(v >> 24)};
    sb_put(b, c, 4);
}

static void sb_f32(sbuf *b, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    sb_u32(b, u);
}

static void sb_free(sbuf *b)
{
    free(b->p);
    memset(b, 0, sizeof *b);
}

static uint32_t get_u32(const unsigned char *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static uint16_t get_u16(const unsigned char *p) { return (uint16_t)(p[0] | (p[1] << 8)); }

static float get_f32(const unsigned char *p)
{
    uint32_t u = get_u32(p);
    float f;
    memcpy(&f, &u, 4);
    return f;
}

/* ---- files --------------------------------------------------------------------------------- */

#if defined(__STDC_NO_ATOMICS__)
static unsigned long temp_counter;
#else
#include <stdatomic.h>
static atomic_ulong temp_counter;
#endif

/* Writes the buffer to path atomically: a fresh temporary "<path>.tmp<pid>_<n>" in the same
 * directory (created exclusively), flushed (and fsync'ed on POSIX), then renamed over path.  On
 * failure the temporary is removed and path untouched. */
static mf_status write_atomic(const char *path, const sbuf *b, char *msg, size_t msg_size)
{
    if (b->failed) {
        set_msg(msg, msg_size, path, "out of memory");
        return MF_ERR_ALLOC;
    }
    size_t n = strlen(path);
    char *tmp = malloc(n + 64);
    if (!tmp) {
        set_msg(msg, msg_size, path, "out of memory");
        return MF_ERR_ALLOC;
    }
    unsigned long pid = 0;
#ifdef MF_TABLE_IO_POSIX
    pid = (unsigned long)getpid();
#endif
    FILE *f = NULL;
    for (int attempt = 0; attempt < 100; ++attempt) {
        unsigned long k = temp_counter++;
        snprintf(tmp, n + 64, "%s.tmp%lu_%lu", path, pid, k);
        errno = 0;
        f = fopen(tmp, "wbx"); /* C11 exclusive mode: never reuse an existing file */
        if (f || errno != EEXIST)
            break;
    }
    if (!f) {
        int err = errno;
        set_msg(msg, msg_size, path, "cannot create temporary file %s: %s", tmp, err ? strerror(err) : "unknown error");
        free(tmp);
        return MF_ERR_IO;
    }
    int ok = (b->len == 0 || fwrite(b->p, 1, b->len, f) == b->len) && fflush(f) == 0;
    int err = errno;
#ifdef MF_TABLE_IO_POSIX
    if (ok && fsync(fileno(f)) != 0) {
        ok = 0;
        err = errno;
    }
#endif
    if (fclose(f) != 0 && ok) {
        ok = 0;
        err = errno;
    }
    if (!ok) {
        set_msg(msg, msg_size, path, "cannot write temporary file %s: %s", tmp, err ? strerror(err) : "write error");
        remove(tmp);
        free(tmp);
        return MF_ERR_IO;
    }
    if (rename(tmp, path) != 0) {
        err = errno;
        set_msg(msg, msg_size, path, "cannot rename %s to it: %s", tmp, strerror(err));
        remove(tmp);
        free(tmp);
        return MF_ERR_IO;
    }
    free(tmp);
    return MF_OK;
}

/* Reads a whole file (at most IO_MAX_FILE_BYTES) into a malloc'd buffer with a NUL after the
 * data.  `missing` (may be NULL) is set when the file does not exist (ENOENT), without a
 * message.  msg_path names the file in messages. */
static mf_status read_whole(const char *path, const char *msg_path, unsigned char **data, size_t *len, int *missing,
                            char *msg, size_t msg_size)
{
    *data = NULL;
    *len = 0;
    if (missing)
        *missing = 0;
    errno = 0;
    FILE *f = fopen(path, "rb");
    if (!f) {
        int err = errno;
        if (missing && err == ENOENT) {
            *missing = 1;
            return MF_ERR_IO;
        }
        if (strcmp(path, msg_path) == 0)
            set_msg(msg, msg_size, msg_path, "cannot open: %s", err ? strerror(err) : "unknown error");
        else
            set_msg(msg, msg_size, msg_path, "cannot open %s: %s", path, err ? strerror(err) : "unknown error");
        return MF_ERR_IO;
    }
    size_t cap = 1 << 16, n = 0;
    unsigned char *buf = malloc(cap + 1);
    if (!buf) {
        fclose(f);
        set_msg(msg, msg_size, msg_path, "out of memory");
        return MF_ERR_ALLOC;
    }
    for (;;) {
        if (n == cap) {
            if (cap >= IO_MAX_FILE_BYTES) {
                free(buf);
                fclose(f);
                set_msg(msg, msg_size, msg_path, "file larger than %zu bytes", IO_MAX_FILE_BYTES);
                return MF_ERR_FORMAT;
            }
            size_t nc = cap * 2;
            unsigned char *p = realloc(buf, nc + 1);
            if (!p) {
                free(buf);
                fclose(f);
                set_msg(msg, msg_size, msg_path, "out of memory");
                return MF_ERR_ALLOC;
            }
            buf = p;
            cap = nc;
        }
        size_t got = fread(buf + n, 1, cap - n, f);
        n += got;
        if (got == 0)
            break;
    }
    int bad = ferror(f);
    int err = errno;
    fclose(f);
    if (bad) {
        free(buf);
        set_msg(msg, msg_size, msg_path, "read error: %s", err ? strerror(err) : "unknown error");
        return MF_ERR_IO;
    }
    buf[n] = '\0';
    *data = buf;
    *len = n;
    return MF_OK;
}

/* ---- formats ------------------------------------------------------------------------------- */

static const char *const k_format_names[] = {"unknown", "exr", "dds", "h", "glsl", "hlsl", "json", "npy", "csv"};

const char *mf_table_format_name(mf_table_format f)
{
    return ((unsigned)f < sizeof k_format_names / sizeof *k_format_names) ? k_format_names[f] : "unknown";
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
    for (int f = 1; f < (int)(sizeof k_format_names / sizeof *k_format_names); ++f)
        if (ieq(dot + 1, k_format_names[f]))
            return (mf_table_format)f;
    return MF_TABLE_FORMAT_UNKNOWN;
}

int mf_table_format_readable(mf_table_format f)
{
    return f == MF_TABLE_FORMAT_EXR || f == MF_TABLE_FORMAT_DDS || f == MF_TABLE_FORMAT_JSON || f == MF_TABLE_FORMAT_NPY;
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
    double m = frexp(a, &e);     /* a = m 2^e, 0.5 <= m < 1: the half's biased exponent is e - 1 + 15 */
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

static void half_error_init(mf_half_error *e)
{
    memset(e, 0, sizeof *e);
}

static void half_error_add(mf_half_error *e, double x, size_t index)
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
    half_error_init(out);
    for (size_t i = 0; i < n; ++i)
        half_error_add(out, x[i], i);
}

/* ---- JSON output --------------------------------------------------------------------------- */

static void json_str(sbuf *b, const char *s)
{
    sb_puts(b, "\"");
    for (; *s; ++s) {
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\')
            sb_printf(b, "\\%c", c);
        else if (c == '\n')
            sb_puts(b, "\\n");
        else if (c == '\t')
            sb_puts(b, "\\t");
        else if (c < 0x20 || c == 0x7f)
            sb_printf(b, "\\u%04x", c);
        else
            sb_put(b, &c, 1);
    }
    sb_puts(b, "\"");
}

/* A double of the metadata: %.17g (reads back bitwise); NaN as null, infinities as +-1e999. */
static void json_double(sbuf *b, double v)
{
    if (isnan(v))
        sb_puts(b, "null");
    else if (isinf(v))
        sb_puts(b, v > 0 ? "1e999" : "-1e999");
    else
        sb_printf(b, "%.17g", v);
}

/* A stored float: %.9g of the float (9 significant digits identify every float). */
static void json_float(sbuf *b, float v)
{
    if (isnan(v))
        sb_puts(b, "null");
    else if (v == 0.0f && signbit(v))
        sb_puts(b, "-0.0"); /* "-0" reads as the integer 0 in some parsers (Python) */
    else if (isinf(v))
        sb_puts(b, v > 0 ? "1e999" : "-1e999");
    else
        sb_printf(b, "%.9g", (double)v);
}

static const char k_texel_centre_text[] =
    "texel i of an axis of n texels holds the parameter p_i = lo + (hi - lo) * i / (n - 1) (n = 1: p_0 = lo); "
    "a texture lookup of parameter p uses uv = (p - lo) / (hi - lo) * (n - 1) / n + 0.5 / n, so the grid "
    "points are the texel centres (i + 0.5) / n";

/* The record layout in words, e.g. "5 float32 fields per texel, texel-major, first axis fastest:
 * field f of texel (i0, i1) is value (i0 + 64 * i1) * 5 + f". */
static void layout_text(sbuf *b, const mf_table *t, const char *storage)
{
    sb_printf(b, "%d %s field%s per texel, texel-major, first axis fastest: field f of texel (", t->nfields, storage,
              t->nfields == 1 ? "" : "s");
    for (int k = 0; k < t->naxes; ++k)
        sb_printf(b, "%si%d", k ? ", " : "", k);
    sb_puts(b, ") is value (");
    /* i0 + n0 * (i1 + n1 * (i2 ...)) */
    for (int k = 0; k < t->naxes; ++k) {
        if (k + 1 < t->naxes)
            sb_printf(b, "i%d + %d * %s", k, t->axes[k].size, k + 2 < t->naxes ? "(" : "");
        else
            sb_printf(b, "i%d", k);
    }
    for (int k = 0; k + 2 < t->naxes; ++k)
        sb_puts(b, ")");
    sb_printf(b, ") * %d + f", t->nfields);
}

typedef struct header_extra {
    const char *storage;         /* "float32" or "float16" */
    const mf_half_error *half;   /* NULL: no half report */
    const int *dds_fields;       /* NULL, or the 4 DDS channel fields */
} header_extra;

/* The metadata object, pretty-printed; every line after the first starts with `indent`. */
static void header_json(sbuf *b, const mf_table *t, const header_extra *x, const char *indent)
{
    sb_printf(b, "{\n%s  \"format\": \"mfkit-table\",\n%s  \"version\": 1,\n%s  \"storage\": \"%s\",\n", indent, indent,
              indent, x->storage);
    sb_printf(b, "%s  \"layout\": ", indent);
    sbuf lay = {0};
    layout_text(&lay, t, x->storage);
    sb_put(&lay, "", 1);
    if (lay.failed)
        b->failed = 1;
    else
        json_str(b, lay.p);
    sb_free(&lay);
    sb_printf(b, ",\n%s  \"texel_centre\": ", indent);
    json_str(b, k_texel_centre_text);
    sb_printf(b, ",\n%s  \"axes\": [\n", indent);
    for (int k = 0; k < t->naxes; ++k) {
        const mf_table_axis *a = &t->axes[k];
        char desc[256];
        mf_axis_describe(a, desc, sizeof desc);
        sb_printf(b, "%s    {\"name\": ", indent);
        json_str(b, a->name);
        sb_puts(b, ", \"physical\": ");
        json_str(b, a->physical);
        sb_printf(b, ", \"size\": %d, \"lo\": ", a->size);
        json_double(b, a->lo);
        sb_puts(b, ", \"hi\": ");
        json_double(b, a->hi);
        sb_printf(b, ", \"mapping\": \"%s\", \"physical_min\": ", mf_axis_mapping_name(a->mapping));
        if (isinf(a->physical_min) && a->physical_min < 0)
            sb_puts(b, "null"); /* no clamp */
        else
            json_double(b, a->physical_min);
        sb_puts(b, ", \"parameterisation\": ");
        json_str(b, desc);
        sb_printf(b, "}%s\n", k + 1 < t->naxes ? "," : "");
    }
    sb_printf(b, "%s  ],\n%s  \"fields\": [", indent, indent);
    for (int f = 0; f < t->nfields; ++f) {
        if (f)
            sb_puts(b, ", ");
        json_str(b, t->fields[f]);
    }
    sb_printf(b, "],\n%s  \"meta\": {", indent);
    for (int i = 0; i < t->nmeta; ++i) {
        sb_printf(b, "%s\n%s    ", i ? "," : "", indent);
        json_str(b, t->meta[i].key);
        sb_puts(b, ": ");
        json_str(b, t->meta[i].value);
    }
    if (t->nmeta)
        sb_printf(b, "\n%s  }", indent);
    else
        sb_puts(b, "}");
    if (x->dds_fields) {
        sb_printf(b, ",\n%s  \"dds_channels\": [", indent);
        for (int c = 0; c < 4; ++c) {
            if (c)
                sb_puts(b, ", ");
            if (x->dds_fields[c] < 0)
                sb_puts(b, "null");
            else
                json_str(b, t->fields[x->dds_fields[c]]);
        }
        sb_puts(b, "]");
    }
    if (x->half) {
        sb_printf(b, ",\n%s  \"half_max_abs_error\": ", indent);
        json_double(b, x->half->max_abs_error);
        sb_printf(b, ",\n%s  \"half_max_rel_error\": ", indent);
        json_double(b, x->half->max_rel_error);
        sb_printf(b, ",\n%s  \"half_overflow_count\": %zu", indent, x->half->overflow_count);
        sb_printf(b, ",\n%s  \"half_underflow_count\": %zu", indent, x->half->underflow_count);
    }
    sb_printf(b, "\n%s}", indent);
}

/* The header as a NUL-terminated string in a fresh buffer (b->failed on allocation failure). */
static void header_string(sbuf *b, const mf_table *t, const header_extra *x)
{
    header_json(b, t, x, "");
    sb_puts(b, "\n");
    sb_put(b, "", 1);
}

/* ---- JSON input: a small DOM --------------------------------------------------------------- */

enum { JN_NULL, JN_FALSE, JN_TRUE, JN_NUM, JN_STR, JN_ARR, JN_OBJ };

typedef struct jnode {
    int type;
    double num;          /* JN_NUM: strtod of the token */
    float numf;          /* JN_NUM: strtof of the token (one rounding to float) */
    char *str;           /* JN_STR */
    char *key;           /* the member name, for members of an object */
    struct jnode *kids;  /* JN_ARR, JN_OBJ */
    size_t n;
} jnode;

typedef struct jparser {
    const char *s;
    size_t len, pos;
    size_t nodes;
    int oom;
    char err[160];
} jparser;

static void jfree(jnode *v)
{
    if (!v)
        return;
    for (size_t i = 0; i < v->n; ++i)
        jfree(&v->kids[i]);
    free(v->kids);
    free(v->str);
    free(v->key);
    memset(v, 0, sizeof *v);
}

static void jerror(jparser *p, const char *what)
{
    if (p->err[0])
        return;
    size_t line = 1, col = 1;
    for (size_t i = 0; i < p->pos && i < p->len; ++i) {
        if (p->s[i] == '\n') {
            ++line;
            col = 1;
        } else {
            ++col;
        }
    }
    snprintf(p->err, sizeof p->err, "JSON: %s at line %zu, column %zu", what, line, col);
}

static void jskip(jparser *p)
{
    while (p->pos < p->len) {
        char c = p->s[p->pos];
        if (c == ' ' || c == '\t' || c == '\n' || c == '\r')
            ++p->pos;
        else
            break;
    }
}

static int hexval(char c)
{
    if (c >= '0' && c <= '9')
        return c - '0';
    if (c >= 'a' && c <= 'f')
        return c - 'a' + 10;
    if (c >= 'A' && c <= 'F')
        return c - 'A' + 10;
    return -1;
}

static int read_hex4(jparser *p, unsigned *out)
{
    if (p->len - p->pos < 4)
        return 0;
    unsigned v = 0;
    for (int i = 0; i < 4; ++i) {
        int h = hexval(p->s[p->pos + (size_t)i]);
        if (h < 0)
            return 0;
        v = v * 16u + (unsigned)h;
    }
    p->pos += 4;
    *out = v;
    return 1;
}

/* A string starting at the opening quote; returns a malloc'd UTF-8 copy or NULL (error set). */
static char *jstring(jparser *p)
{
    ++p->pos; /* the quote */
    size_t start = p->pos;
    /* the decoded string is never longer than the source */
    size_t end = start;
    while (end < p->len && p->s[end] != '"') {
        if (p->s[end] == '\\')
            ++end;
        ++end;
    }
    if (end >= p->len) {
        p->pos = p->len;
        jerror(p, "unterminated string");
        return NULL;
    }
    char *out = malloc(end - start + 1);
    if (!out) {
        p->oom = 1;
        jerror(p, "out of memory");
        return NULL;
    }
    size_t n = 0;
    while (p->pos < p->len) {
        unsigned char c = (unsigned char)p->s[p->pos];
        if (c == '"') {
            ++p->pos;
            out[n] = '\0';
            return out;
        }
        if (c < 0x20) {
            jerror(p, "control character in string");
            break;
        }
        if (c != '\\') {
            out[n++] = (char)c;
            ++p->pos;
            continue;
        }
        ++p->pos;
        if (p->pos >= p->len) {
            jerror(p, "unterminated string");
            break;
        }
        char e = p->s[p->pos++];
        unsigned cp;
        switch (e) {
        case '"': out[n++] = '"'; continue;
        case '\\': out[n++] = '\\'; continue;
        case '/': out[n++] = '/'; continue;
        case 'b': out[n++] = '\b'; continue;
        case 'f': out[n++] = '\f'; continue;
        case 'n': out[n++] = '\n'; continue;
        case 'r': out[n++] = '\r'; continue;
        case 't': out[n++] = '\t'; continue;
        case 'u':
            if (!read_hex4(p, &cp)) {
                jerror(p, "bad \\u escape");
                goto fail;
            }
            if (cp >= 0xdc00 && cp <= 0xdfff) {
                jerror(p, "lone low surrogate");
                goto fail;
            }
            if (cp >= 0xd800 && cp <= 0xdbff) {
                unsigned lo;
                if (p->len - p->pos < 6 || p->s[p->pos] != '\\' || p->s[p->pos + 1] != 'u') {
                    jerror(p, "lone high surrogate");
                    goto fail;
                }
                p->pos += 2;
                if (!read_hex4(p, &lo) || lo < 0xdc00 || lo > 0xdfff) {
                    jerror(p, "bad surrogate pair");
                    goto fail;
                }
                cp = 0x10000u + ((cp - 0xd800u) << 10) + (lo - 0xdc00u);
            }
            if (cp == 0) {
                jerror(p, "NUL character in string");
                goto fail;
            }
            /* UTF-8: at most 4 bytes, never more than the 6 (or 12) source bytes of the escape */
            if (cp < 0x80) {
                out[n++] = (char)cp;
            } else if (cp < 0x800) {
                out[n++] = (char)(0xc0 | (cp >> 6));
                out[n++] = (char)(0x80 | (cp & 0x3f));
            } else if (cp < 0x10000) {
                out[n++] = (char)(0xe0 | (cp >> 12));
                out[n++] = (char)(0x80 | ((cp >> 6) & 0x3f));
                out[n++] = (char)(0x80 | (cp & 0x3f));
            } else {
                out[n++] = (char)(0xf0 | (cp >> 18));
                out[n++] = (char)(0x80 | ((cp >> 12) & 0x3f));
                out[n++] = (char)(0x80 | ((cp >> 6) & 0x3f));
                out[n++] = (char)(0x80 | (cp & 0x3f));
            }
            continue;
        default: jerror(p, "bad escape in string"); goto fail;
        }
    }
fail:
    jerror(p, "unterminated string");
    free(out);
    return NULL;
}

/* A number by the JSON grammar: -?(0|[1-9][0-9]*)(.[0-9]+)?([eE][+-]?[0-9]+)? */
static int jnumber(jparser *p, jnode *v)
{
    size_t i = p->pos;
    const char *s = p->s;
    if (i < p->len && s[i] == '-')
        ++i;
    if (i < p->len && s[i] == '0') {
        ++i;
    } else if (i < p->len && s[i] >= '1' && s[i] <= '9') {
        while (i < p->len && isdigit((unsigned char)s[i]))
            ++i;
    } else {
        jerror(p, "bad number");
        return 0;
    }
    if (i < p->len && s[i] == '.') {
        ++i;
        if (!(i < p->len && isdigit((unsigned char)s[i]))) {
            jerror(p, "bad number");
            return 0;
        }
        while (i < p->len && isdigit((unsigned char)s[i]))
            ++i;
    }
    if (i < p->len && (s[i] == 'e' || s[i] == 'E')) {
        ++i;
        if (i < p->len && (s[i] == '+' || s[i] == '-'))
            ++i;
        if (!(i < p->len && isdigit((unsigned char)s[i]))) {
            jerror(p, "bad number");
            return 0;
        }
        while (i < p->len && isdigit((unsigned char)s[i]))
            ++i;
    }
    char tok[512];
    size_t n = i - p->pos;
    if (n >= sizeof tok) {
        jerror(p, "number too long");
        return 0;
    }
    memcpy(tok, s + p->pos, n);
    tok[n] = '\0';
    v->type = JN_NUM;
    v->num = strtod(tok, NULL); /* overflow gives +-HUGE_VAL = +-inf: 1e999 is infinity */
    v->numf = strtof(tok, NULL);
    p->pos = i;
    return 1;
}

static int jvalue(jparser *p, jnode *v, int depth);

/* Appends a zeroed node to a growable array. */
static jnode *jpush(jparser *p, jnode **arr, size_t *n, size_t *cap)
{
    if (*n == *cap) {
        size_t nc = *cap ? *cap * 2 : 4;
        jnode *a = realloc(*arr, nc * sizeof *a);
        if (!a) {
            p->oom = 1;
            jerror(p, "out of memory");
            return NULL;
        }
        *arr = a;
        *cap = nc;
    }
    jnode *k = &(*arr)[(*n)++];
    memset(k, 0, sizeof *k);
    return k;
}

static int jcontainer(jparser *p, jnode *v, int depth, int is_obj)
{
    char close = is_obj ? '}' : ']';
    v->type = is_obj ? JN_OBJ : JN_ARR;
    ++p->pos;
    size_t cap = 0;
    jskip(p);
    if (p->pos < p->len && p->s[p->pos] == close) {
        ++p->pos;
        return 1;
    }
    for (;;) {
        jskip(p);
        char *key = NULL;
        if (is_obj) {
            if (p->pos >= p->len || p->s[p->pos] != '"') {
                jerror(p, p->pos >= p->len ? "unexpected end of input" : "expected a member name");
                return 0;
            }
            key = jstring(p);
            if (!key)
                return 0;
            jskip(p);
            if (p->pos >= p->len || p->s[p->pos] != ':') {
                free(key);
                jerror(p, p->pos >= p->len ? "unexpected end of input" : "expected ':'");
                return 0;
            }
            ++p->pos;
        }
        jnode *k = jpush(p, &v->kids, &v->n, &cap);
        if (!k) {
            free(key);
            return 0;
        }
        k->key = key;
        if (!jvalue(p, k, depth + 1))
            return 0;
        jskip(p);
        if (p->pos >= p->len) {
            jerror(p, "unexpected end of input");
            return 0;
        }
        char c = p->s[p->pos++];
        if (c == close)
            return 1;
        if (c != ',') {
            --p->pos;
            jerror(p, is_obj ? "expected ',' or '}'" : "expected ',' or ']'");
            return 0;
        }
    }
}

static int jliteral(jparser *p, const char *word, int type, jnode *v)
{
    size_t n = strlen(word);
    if (p->len - p->pos < n || memcmp(p->s + p->pos, word, n) != 0) {
        jerror(p, "unexpected character");
        return 0;
    }
    p->pos += n;
    v->type = type;
    return 1;
}

static int jvalue(jparser *p, jnode *v, int depth)
{
    if (depth > JSON_MAX_DEPTH) {
        jerror(p, "nesting too deep");
        return 0;
    }
    if (++p->nodes > JSON_MAX_NODES) {
        jerror(p, "too many values");
        return 0;
    }
    jskip(p);
    if (p->pos >= p->len) {
        jerror(p, "unexpected end of input");
        return 0;
    }
    char c = p->s[p->pos];
    switch (c) {
    case '{': return jcontainer(p, v, depth, 1);
    case '[': return jcontainer(p, v, depth, 0);
    case '"':
        v->type = JN_STR;
        v->str = jstring(p);
        return v->str != NULL;
    case 't': return jliteral(p, "true", JN_TRUE, v);
    case 'f': return jliteral(p, "false", JN_FALSE, v);
    case 'n': return jliteral(p, "null", JN_NULL, v);
    default:
        if (c == '-' || isdigit((unsigned char)c))
            return jnumber(p, v);
        jerror(p, "unexpected character");
        return 0;
    }
}

/* Parses a whole document (trailing whitespace only).  On failure root is freed and err set. */
static mf_status jparse(const char *s, size_t len, jnode *root, char *err, size_t err_size)
{
    jparser p = {s, len, 0, 0, 0, ""};
    memset(root, 0, sizeof *root);
    if (memchr(s, '\0', len) != NULL) {
        snprintf(err, err_size, "JSON: NUL byte at offset %zu", (size_t)((const char *)memchr(s, '\0', len) - s));
        return MF_ERR_FORMAT;
    }
    int ok = jvalue(&p, root, 0);
    if (ok) {
        jskip(&p);
        if (p.pos != p.len) {
            jerror(&p, "trailing characters after the document");
            ok = 0;
        }
    }
    if (!ok) {
        jfree(root);
        snprintf(err, err_size, "%s", p.err[0] ? p.err : "JSON: parse error");
        return p.oom ? MF_ERR_ALLOC : MF_ERR_FORMAT;
    }
    return MF_OK;
}

static const jnode *jget(const jnode *obj, const char *key)
{
    if (!obj || obj->type != JN_OBJ)
        return NULL;
    for (size_t i = 0; i < obj->n; ++i)
        if (obj->kids[i].key && strcmp(obj->kids[i].key, key) == 0)
            return &obj->kids[i];
    return NULL;
}

/* ---- metadata <-> table -------------------------------------------------------------------- */

/* Texel count of the sizes, or 0 on overflow past TEXEL_LIMIT. */
static size_t texel_product(const int *sizes, int n)
{
    size_t t = 1;
    for (int k = 0; k < n; ++k) {
        if (sizes[k] < 1 || t > TEXEL_LIMIT / (size_t)sizes[k])
            return 0;
        t *= (size_t)sizes[k];
    }
    return t;
}

static int jcopy_name(const jnode *v, char *dst, size_t size)
{
    if (!v || v->type != JN_STR || strlen(v->str) >= size)
        return 0;
    snprintf(dst, size, "%s", v->str);
    return 1;
}

static int jint(const jnode *v, long lo, long hi, long *out)
{
    if (!v || v->type != JN_NUM || !(v->num >= (double)lo && v->num <= (double)hi) || v->num != floor(v->num))
        return 0;
    *out = (long)v->num;
    return 1;
}

/* The metadata object -> a table (axes, fields, meta; zeroed data) and info.  The table must
 * have `texels` texels (from the data file) and, if nfields_expected > 0, that many fields; so
 * that a corrupt header cannot ask for a large allocation the file does not back.  On failure
 * `why` gets the reason and the table is zeroed. */
static mf_status header_to_table(const jnode *h, size_t texels, int nfields_expected, mf_table *t,
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
    if (!h || h->type != JN_OBJ)
        HFAIL("metadata: not a JSON object");
    const jnode *v = jget(h, "format");
    if (!v || v->type != JN_STR || strcmp(v->str, "mfkit-table") != 0)
        HFAIL("metadata: \"format\" is not \"mfkit-table\"");
    long version;
    if (!jint(jget(h, "version"), 1, 1, &version))
        HFAIL("metadata: unsupported \"version\" (this reader knows 1)");
    const jnode *ax = jget(h, "axes");
    if (!ax || ax->type != JN_ARR || ax->n < 1 || ax->n > MF_TABLE_MAX_AXES)
        HFAIL("metadata: \"axes\" must be an array of 1 to %d axes", MF_TABLE_MAX_AXES);
    int naxes = (int)ax->n;
    int sizes[MF_TABLE_MAX_AXES];
    for (int k = 0; k < naxes; ++k) {
        const jnode *a = &ax->kids[k];
        mf_table_axis *d = &axes[k];
        long size;
        if (a->type != JN_OBJ)
            HFAIL("metadata: axis %d is not an object", k);
        if (!jcopy_name(jget(a, "name"), d->name, sizeof d->name) ||
            !jcopy_name(jget(a, "physical"), d->physical, sizeof d->physical))
            HFAIL("metadata: axis %d: \"name\" and \"physical\" must be strings of < %d bytes", k, MF_TABLE_NAME_LEN);
        if (!jint(jget(a, "size"), 1, 1L << 20, &size))
            HFAIL("metadata: axis %d: \"size\" must be an integer in [1, 2^20]", k);
        d->size = sizes[k] = (int)size;
        const jnode *lo = jget(a, "lo"), *hi = jget(a, "hi"), *pm = jget(a, "physical_min"), *m = jget(a, "mapping");
        if (!lo || lo->type != JN_NUM || !hi || hi->type != JN_NUM || !isfinite(lo->num) || !isfinite(hi->num))
            HFAIL("metadata: axis %d: \"lo\" and \"hi\" must be finite numbers", k);
        d->lo = lo->num;
        d->hi = hi->num;
        if (!m || m->type != JN_STR || mf_axis_mapping_parse(m->str, &d->mapping) != 0)
            HFAIL("metadata: axis %d: unknown \"mapping\"", k);
        if (!pm || pm->type == JN_NULL)
            d->physical_min = -INFINITY;
        else if (pm->type == JN_NUM)
            d->physical_min = pm->num;
        else
            HFAIL("metadata: axis %d: \"physical_min\" must be a number or null", k);
    }
    size_t have = texel_product(sizes, naxes);
    if (have == 0)
        HFAIL("metadata: more than 2^32 texels");
    if (have != texels)
        HFAIL("metadata: the axes give %zu texels, the data has %zu", have, texels);
    const jnode *fl = jget(h, "fields");
    if (!fl || fl->type != JN_ARR || fl->n < 1 || fl->n > MF_TABLE_MAX_FIELDS)
        HFAIL("metadata: \"fields\" must be an array of 1 to %d names", MF_TABLE_MAX_FIELDS);
    int nfields = (int)fl->n;
    for (int f = 0; f < nfields; ++f) {
        if (fl->kids[f].type != JN_STR || strlen(fl->kids[f].str) >= MF_TABLE_NAME_LEN)
            HFAIL("metadata: field %d is not a string of < %d bytes", f, MF_TABLE_NAME_LEN);
        names[f] = fl->kids[f].str;
    }
    if (nfields_expected > 0 && nfields != nfields_expected)
        HFAIL("metadata: %d fields, the data has %d", nfields, nfields_expected);
    const jnode *meta = jget(h, "meta");
    if (meta && meta->type != JN_OBJ)
        HFAIL("metadata: \"meta\" is not an object");
    if (meta && meta->n > MF_TABLE_MAX_META)
        HFAIL("metadata: more than %d \"meta\" entries", MF_TABLE_MAX_META);
    if (meta)
        for (size_t i = 0; i < meta->n; ++i)
            if (meta->kids[i].type != JN_STR)
                HFAIL("metadata: meta \"%.40s\" is not a string", meta->kids[i].key);
    if (info) {
        const jnode *st = jget(h, "storage");
        if (st && st->type == JN_STR && strcmp(st->str, "float16") == 0)
            info->half_float = 1;
        const jnode *ea = jget(h, "half_max_abs_error"), *er = jget(h, "half_max_rel_error");
        if (ea && ea->type == JN_NUM && er && er->type == JN_NUM) {
            long c;
            info->has_half_error = 1;
            info->half_error.max_abs_error = ea->num;
            info->half_error.max_rel_error = er->num;
            if (jint(jget(h, "half_overflow_count"), 0, LONG_MAX, &c))
                info->half_error.overflow_count = (size_t)c;
            if (jint(jget(h, "half_underflow_count"), 0, LONG_MAX, &c))
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
    if (meta)
        for (size_t i = 0; i < meta->n; ++i)
            if (mf_table_set_meta(t, meta->kids[i].key, meta->kids[i].str) != MF_OK) {
                mf_table_free(t);
                HFAIL("metadata: invalid meta entry \"%.40s\"", meta->kids[i].key);
            }
    return MF_OK;
#undef HFAIL
}

/* A table with generic axes for a file without metadata (see mf_table_read). */
static mf_status generic_table(mf_table *t, int naxes, const int *sizes, int nfields, const char *const *names)
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

/* ---- writers ------------------------------------------------------------------------------- */

/* JSON: {"header": ..., "data": [[record], ...]} */
static void build_json(sbuf *b, const mf_table *t)
{
    header_extra x = {"float32", NULL, NULL};
    sb_puts(b, "{\n  \"header\": ");
    header_json(b, t, &x, "  ");
    sb_puts(b, ",\n  \"data\": [\n");
    size_t texels = mf_table_texels(t);
    for (size_t i = 0; i < texels && !b->failed; ++i) {
        sb_puts(b, "    [");
        for (int f = 0; f < t->nfields; ++f) {
            if (f)
                sb_puts(b, ", ");
            json_float(b, (float)t->data[i * (size_t)t->nfields + (size_t)f]);
        }
        sb_puts(b, i + 1 < texels ? "],\n" : "]\n");
    }
    sb_puts(b, "  ]\n}\n");
}

/* NumPy format 1.0: magic, version, little-endian header length, a Python dict literal padded
 * with spaces and a newline to a multiple of 64 bytes, then the raw little-endian float32s. */
static void build_npy(sbuf *b, const mf_table *t)
{
    sbuf h = {0};
    sb_puts(&h, "{'descr': '<f4', 'fortran_order': False, 'shape': (");
    for (int k = t->naxes - 1; k >= 0; --k)
        sb_printf(&h, "%d, ", t->axes[k].size);
    sb_printf(&h, "%d), }", t->nfields);
    size_t total = 10 + h.len + 1;
    size_t pad = (64 - total % 64) % 64;
    for (size_t i = 0; i < pad; ++i)
        sb_puts(&h, " ");
    sb_puts(&h, "\n");
    if (h.failed || h.len > 65535) {
        b->failed = 1;
        sb_free(&h);
        return;
    }
    sb_put(b, "\x93NUMPY\x01\x00", 8);
    sb_u16(b, (uint16_t)h.len);
    sb_put(b, h.p, h.len);
    sb_free(&h);
    size_t n = mf_table_texels(t) * (size_t)t->nfields;
    sb_reserve(b, n * 4);
    for (size_t i = 0; i < n && !b->failed; ++i)
        sb_f32(b, (float)t->data[i]);
}

/* DDS with the DX10 extended header (148 bytes), then rows top to bottom, RGBA interleaved. */
#define DDS_HEADER_BYTES 148
#define DXGI_R32G32B32A32_FLOAT 2u
#define DXGI_R16G16B16A16_FLOAT 10u

static void build_dds(sbuf *b, const mf_table *t, const int *ch, int half)
{
    uint32_t w = (uint32_t)t->axes[0].size, hgt = (uint32_t)(t->naxes > 1 ? t->axes[1].size : 1);
    uint32_t bpp = half ? 8u : 16u;
    sb_put(b, "DDS ", 4);
    sb_u32(b, 124);                           /* dwSize */
    sb_u32(b, 0x1u | 0x2u | 0x4u | 0x8u | 0x1000u); /* CAPS | HEIGHT | WIDTH | PITCH | PIXELFORMAT */
    sb_u32(b, hgt);
    sb_u32(b, w);
    sb_u32(b, w * bpp);                       /* pitch of a row in bytes */
    sb_u32(b, 0);                             /* depth */
    sb_u32(b, 1);                             /* mip levels (flag not set: one) */
    for (int i = 0; i < 11; ++i)
        sb_u32(b, 0);                         /* dwReserved1 */
    sb_u32(b, 32);                            /* DDS_PIXELFORMAT.dwSize */
    sb_u32(b, 0x4u);                          /* DDPF_FOURCC */
    sb_put(b, "DX10", 4);
    for (int i = 0; i < 5; ++i)
        sb_u32(b, 0);                         /* bit count and masks */
    sb_u32(b, 0x1000u);                       /* DDSCAPS_TEXTURE */
    for (int i = 0; i < 4; ++i)
        sb_u32(b, 0);                         /* caps2..4, reserved2 */
    sb_u32(b, half ? DXGI_R16G16B16A16_FLOAT : DXGI_R32G32B32A32_FLOAT);
    sb_u32(b, 3);                             /* D3D10_RESOURCE_DIMENSION_TEXTURE2D */
    sb_u32(b, 0);                             /* miscFlag */
    sb_u32(b, 1);                             /* arraySize */
    sb_u32(b, 0);                             /* miscFlags2: alpha mode unknown */
    size_t texels = mf_table_texels(t);
    sb_reserve(b, texels * bpp);
    for (size_t i = 0; i < texels && !b->failed; ++i)
        for (int c = 0; c < 4; ++c) {
            double v = ch[c] < 0 ? 0.0 : t->data[i * (size_t)t->nfields + (size_t)ch[c]];
            if (half)
                sb_u16(b, mf_half_from_double(v));
            else
                sb_f32(b, (float)v);
        }
}

/* CSV: indices, axis parameters, physical values, fields. */
static void csv_value(sbuf *b, double v, int digits)
{
    if (isnan(v))
        sb_puts(b, "nan");
    else if (isinf(v))
        sb_puts(b, v > 0 ? "inf" : "-inf");
    else
        sb_printf(b, "%.*g", digits, v);
}

static void build_csv(sbuf *b, const mf_table *t)
{
    for (int k = 0; k < t->naxes; ++k)
        sb_printf(b, "%si%d", k ? "," : "", k);
    for (int k = 0; k < t->naxes; ++k)
        sb_printf(b, ",%s", t->axes[k].name);
    for (int k = 0; k < t->naxes; ++k)
        if (strcmp(t->axes[k].physical, t->axes[k].name) != 0)
            sb_printf(b, ",%s", t->axes[k].physical);
    for (int f = 0; f < t->nfields; ++f)
        sb_printf(b, ",%s", t->fields[f]);
    sb_puts(b, "\n");
    size_t texels = mf_table_texels(t);
    int idx[MF_TABLE_MAX_AXES] = {0};
    for (size_t i = 0; i < texels && !b->failed; ++i) {
        for (int k = 0; k < t->naxes; ++k)
            sb_printf(b, "%s%d", k ? "," : "", idx[k]);
        for (int k = 0; k < t->naxes; ++k) {
            sb_puts(b, ",");
            csv_value(b, mf_table_axis_param(&t->axes[k], idx[k]), 17);
        }
        for (int k = 0; k < t->naxes; ++k)
            if (strcmp(t->axes[k].physical, t->axes[k].name) != 0) {
                sb_puts(b, ",");
                csv_value(b, mf_table_axis_physical(&t->axes[k], mf_table_axis_param(&t->axes[k], idx[k])), 17);
            }
        for (int f = 0; f < t->nfields; ++f) {
            sb_puts(b, ",");
            csv_value(b, (double)(float)t->data[i * (size_t)t->nfields + (size_t)f], 9);
        }
        sb_puts(b, "\n");
        for (int k = 0; k < t->naxes; ++k) { /* first axis fastest */
            if (++idx[k] < t->axes[k].size)
                break;
            idx[k] = 0;
        }
    }
}

/* The identifier prefix: opt->prefix, or the file's stem with non-identifier characters
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
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
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

/* Appends text with every line prefixed by `lead`, and "*" "/" or "/" "*" pairs broken apart so
 * that the text can sit in a C block comment. */
static void put_commented(sbuf *b, const char *text, const char *lead, int block_comment)
{
    sb_puts(b, lead);
    for (const char *s = text; *s; ++s) {
        if (*s == '\n') {
            if (s[1] != '\0') {
                sb_puts(b, "\n");
                sb_puts(b, lead);
            }
            continue;
        }
        sb_put(b, s, 1);
        if (block_comment && ((s[0] == '*' && s[1] == '/') || (s[0] == '/' && s[1] == '*')))
            sb_puts(b, " ");
    }
    sb_puts(b, "\n");
}

/* The program that made the table (its "tool" metadata, if it is a short printable mfkit command),
 * for the headers of generated source files. */
static const char *generator(const mf_table *t)
{
    const char *tool = mf_table_get_meta(t, "tool");
    if (!tool || strncmp(tool, "mfkit ", 6) != 0 || strlen(tool) > 64)
        return "mfkit";
    for (const char *p = tool; *p; ++p)
        if (!isalnum((unsigned char)*p) && *p != ' ' && *p != '-')
            return "mfkit";
    return tool;
}

/* A float literal for C (suffix "f"), GLSL and HLSL (no suffix): %.9g with a '.' or exponent. */
static void float_literal(sbuf *b, double v, const char *suffix)
{
    char s[64];
    snprintf(s, sizeof s, "%.9g", v);
    sb_puts(b, s);
    if (!strpbrk(s, ".eE"))
        sb_puts(b, ".0");
    sb_puts(b, suffix);
}

static void build_c_header(sbuf *b, const mf_table *t, const char *prefix, const char *file_name)
{
    char up[128];
    size_t n = strlen(prefix);
    for (size_t i = 0; i <= n; ++i)
        up[i] = (char)toupper((unsigned char)prefix[i]);
    size_t texels = mf_table_texels(t), count = texels * (size_t)t->nfields;
    int nonfinite = 0;
    for (size_t i = 0; i < count; ++i)
        if (!isfinite((float)t->data[i]))
            nonfinite = 1;
    sbuf h = {0};
    header_extra x = {"float32", NULL, NULL};
    header_string(&h, t, &x);
    if (h.failed) {
        b->failed = 1;
        return;
    }
    sb_printf(b, "/*\n * %s -- an mfkit lookup table (generated by %s; do not edit).\n *\n", file_name, generator(t));
    sb_printf(b, " * %s_data holds %zu texels x %d fields as float32, texel-major with the first axis fastest:\n",
              prefix, texels, t->nfields);
    sb_printf(b, " * field f of texel (");
    for (int k = 0; k < t->naxes; ++k)
        sb_printf(b, "%si%d", k ? ", " : "", k);
    sb_printf(b, ") is %s_data[(", prefix);
    for (int k = 0; k < t->naxes; ++k) {
        if (k + 1 < t->naxes)
            sb_printf(b, "i%d + %s_SIZE_%d * %s", k, up, k, k + 2 < t->naxes ? "(" : "");
        else
            sb_printf(b, "i%d", k);
    }
    for (int k = 0; k + 2 < t->naxes; ++k)
        sb_puts(b, ")");
    sb_printf(b, ") * %s_NFIELDS + f].\n", up);
    sb_puts(b, " * Texel i of an axis of n texels holds the parameter lo + (hi - lo) * i / (n - 1).\n");
    for (int k = 0; k < t->naxes; ++k) {
        char desc[256];
        mf_axis_describe(&t->axes[k], desc, sizeof desc);
        sb_printf(b, " * axis %d: %s, %d texels, %s in [%.17g, %.17g]; %s\n", k, t->axes[k].name, t->axes[k].size,
                  t->axes[k].name, t->axes[k].lo, t->axes[k].hi, desc);
    }
    sb_puts(b, " *\n * Metadata (the same JSON as in every mfkit table file):\n");
    put_commented(b, h.p, " * ", 1);
    sb_puts(b, " */\n");
    sb_free(&h);
    sb_printf(b, "#ifndef %s_TABLE_H\n#define %s_TABLE_H\n\n", up, up);
    if (nonfinite)
        sb_puts(b, "#include <math.h> /* NAN, INFINITY */\n\n");
    sb_printf(b, "#define %s_NAXES %d\n#define %s_NFIELDS %d\n#define %s_NTEXELS %zu\n", up, t->naxes, up,
              t->nfields, up, texels);
    for (int k = 0; k < t->naxes; ++k)
        sb_printf(b, "#define %s_SIZE_%d %d\n", up, k, t->axes[k].size);
    for (int f = 0; f < t->nfields; ++f)
        sb_printf(b, "#define %s_FIELD_%s %d\n", up, t->fields[f], f);
    sb_printf(b, "\nstatic const int %s_sizes[%d] = {", prefix, t->naxes);
    for (int k = 0; k < t->naxes; ++k)
        sb_printf(b, "%s%d", k ? ", " : "", t->axes[k].size);
    sb_printf(b, "};\nstatic const double %s_axis_lo[%d] = {", prefix, t->naxes);
    for (int k = 0; k < t->naxes; ++k)
        sb_printf(b, "%s%.17g", k ? ", " : "", t->axes[k].lo);
    sb_printf(b, "};\nstatic const double %s_axis_hi[%d] = {", prefix, t->naxes);
    for (int k = 0; k < t->naxes; ++k)
        sb_printf(b, "%s%.17g", k ? ", " : "", t->axes[k].hi);
    sb_printf(b, "};\n\nstatic const float %s_data[%zu] = {\n", prefix, count);
    for (size_t i = 0; i < texels && !b->failed; ++i) {
        sb_puts(b, "   ");
        for (int f = 0; f < t->nfields; ++f) {
            float v = (float)t->data[i * (size_t)t->nfields + (size_t)f];
            sb_puts(b, " ");
            if (isnan(v))
                sb_puts(b, "NAN");
            else if (isinf(v))
                sb_puts(b, v > 0 ? "INFINITY" : "-INFINITY");
            else
                float_literal(b, (double)v, "f");
            if (i + 1 < texels || f + 1 < t->nfields)
                sb_puts(b, ",");
        }
        sb_puts(b, "\n");
    }
    sb_printf(b, "};\n\n#endif /* %s_TABLE_H */\n", up);
}

/* GLSL and HLSL lookup snippets. */
static void build_shader(sbuf *b, const mf_table *t, const char *prefix, const char *file_name, int hlsl)
{
    char up[128];
    size_t n = strlen(prefix);
    for (size_t i = 0; i <= n; ++i)
        up[i] = (char)toupper((unsigned char)prefix[i]);
    const char *vec2 = hlsl ? "float2" : "vec2", *vec4 = hlsl ? "float4" : "vec4";
    /* the physical inputs are named after the axes' physical quantities, unless two share one */
    int distinct = 1;
    for (int k = 0; k < t->naxes; ++k)
        for (int j = 0; j < k; ++j)
            if (strcmp(t->axes[k].physical, t->axes[j].physical) == 0)
                distinct = 0;
    char in[MF_TABLE_MAX_AXES][MF_TABLE_NAME_LEN + 8];
    for (int k = 0; k < t->naxes; ++k) {
        if (distinct)
            snprintf(in[k], sizeof in[k], "%s", t->axes[k].physical);
        else
            snprintf(in[k], sizeof in[k], "x%d", k);
    }
    sbuf h = {0};
    header_extra x = {"float32", NULL, NULL};
    header_string(&h, t, &x);
    if (h.failed) {
        b->failed = 1;
        return;
    }
    sb_printf(b, "// %s -- %s lookup of an mfkit table (generated by %s; do not edit).\n//\n", file_name,
              hlsl ? "HLSL" : "GLSL", generator(t));
    sb_puts(b, "// The table is a texture (EXR or DDS written by mfkit): axis 0 runs along x (u), axis 1 along y (v),\n"
               "// texel (i0, i1) at uv = ((i0 + 0.5) / n0, (i1 + 0.5) / n1), row i1 = 0 first in the file.\n"
               "// EXR: one channel per field, named after it; DDS: R, G, B, A = the fields chosen at export.\n"
               "// Sample with bilinear filtering and clamp-to-edge.  Texel i of an axis of n texels holds the\n"
               "// parameter p_i = lo + (hi - lo) * i / (n - 1), so uv = (p - lo) / (hi - lo) * (n - 1) / n + 0.5 / n.\n");
    for (int k = 0; k < t->naxes; ++k) {
        char desc[256];
        mf_axis_describe(&t->axes[k], desc, sizeof desc);
        sb_printf(b, "// axis %d: %s, %d texels, %s in [%.9g, %.9g]; %s\n", k, t->axes[k].name, t->axes[k].size,
                  t->axes[k].name, t->axes[k].lo, t->axes[k].hi, desc);
    }
    sb_puts(b, "//\n// Metadata:\n");
    put_commented(b, h.p, "// ", 0);
    sb_free(&h);
    sb_printf(b, "#ifndef %s_LOOKUP\n#define %s_LOOKUP\n\n", up, up);
    for (int k = 0; k < t->naxes; ++k) {
        const mf_table_axis *a = &t->axes[k];
        /* physical -> parameter: the inverse of the mapping, after the same clamp as the table */
        sb_printf(b, "// axis %d: the parameter %s of the physical %s\n", k, a->name, a->physical);
        sb_printf(b, "float %s_param%d(float %s)\n{\n", prefix, k, in[k]);
        if (isfinite(a->physical_min)) {
            sb_printf(b, "    %s = max(%s, ", in[k], in[k]);
            float_literal(b, a->physical_min, "");
            sb_puts(b, ");\n");
        }
        switch (a->mapping) {
        case MF_AXIS_IDENTITY: sb_printf(b, "    return %s;\n", in[k]); break;
        case MF_AXIS_ONE_MINUS_SQUARE: sb_printf(b, "    return sqrt(max(1.0 - %s, 0.0));\n", in[k]); break;
        case MF_AXIS_SQUARE: sb_printf(b, "    return sqrt(max(%s, 0.0));\n", in[k]); break;
        case MF_AXIS_COS: sb_printf(b, "    return acos(clamp(%s, -1.0, 1.0));\n", in[k]); break;
        }
        sb_puts(b, "}\n");
        /* parameter -> texture coordinate at the texel centres */
        sb_printf(b, "// axis %d: the texture coordinate of %s (texel centres, clamped to the table)\n", k, a->name);
        sb_printf(b, "float %s_coord%d(float %s)\n{\n", prefix, k, a->name);
        if (a->size <= 1) {
            sb_printf(b, "    return 0.5 + 0.0 * %s;\n}\n\n", a->name);
            continue;
        }
        sb_printf(b, "    float p01 = clamp((%s - (", a->name);
        float_literal(b, a->lo, "");
        sb_puts(b, ")) / (");
        float_literal(b, a->hi - a->lo, "");
        sb_printf(b, "), 0.0, 1.0);\n    return p01 * (%d.0 / %d.0) + (0.5 / %d.0);\n}\n\n", a->size - 1, a->size,
                  a->size);
    }
    if (t->naxes > 2) {
        sb_printf(b, "// Tables with %d axes have no texture layout: use %s_param<k> and %s_coord<k> per axis.\n",
                  t->naxes, prefix, prefix);
    } else {
        sb_printf(b, "// The texture coordinate of the physical inputs.\n%s %s_uv(", vec2, prefix);
        for (int k = 0; k < t->naxes; ++k)
            sb_printf(b, "%sfloat %s", k ? ", " : "", in[k]);
        if (t->naxes == 1)
            sb_printf(b, ")\n{\n    return %s(%s_coord0(%s_param0(%s)), 0.5);\n}\n\n", vec2, prefix, prefix, in[0]);
        else
            sb_printf(b, ")\n{\n    return %s(%s_coord0(%s_param0(%s)), %s_coord1(%s_param1(%s)));\n}\n\n", vec2,
                      prefix, prefix, in[0], prefix, prefix, in[1]);
        sb_puts(b, "// The record at the physical inputs, bilinearly interpolated (mip level 0).\n");
        if (hlsl)
            sb_printf(b, "%s %s_lookup(Texture2D<float4> table, SamplerState samp", vec4, prefix);
        else
            sb_printf(b, "%s %s_lookup(sampler2D table", vec4, prefix);
        for (int k = 0; k < t->naxes; ++k)
            sb_printf(b, ", float %s", in[k]);
        sb_printf(b, ")\n{\n    %s uv = %s_uv(", vec2, prefix);
        for (int k = 0; k < t->naxes; ++k)
            sb_printf(b, "%s%s", k ? ", " : "", in[k]);
        if (hlsl)
            sb_puts(b, ");\n    return table.SampleLevel(samp, uv, 0.0);\n}\n\n");
        else
            sb_puts(b, ");\n    return textureLod(table, uv, 0.0);\n}\n\n");
    }
    sb_printf(b, "#endif // %s_LOOKUP\n", up);
}

static const char *base_name(const char *path)
{
    const char *s = strrchr(path, '/');
    return s ? s + 1 : path;
}

/* Writes data and sidecar "<path>.json" atomically (sidecar first). */
static mf_status write_with_sidecar(const char *path, const sbuf *data, const sbuf *side, char *msg, size_t msg_size)
{
    size_t n = strlen(path);
    char *sp = malloc(n + 6);
    if (!sp) {
        set_msg(msg, msg_size, path, "out of memory");
        return MF_ERR_ALLOC;
    }
    snprintf(sp, n + 6, "%s.json", path);
    if (data->failed) {
        free(sp);
        set_msg(msg, msg_size, path, "out of memory");
        return MF_ERR_ALLOC;
    }
    mf_status st = write_atomic(sp, side, msg, msg_size);
    free(sp);
    if (st != MF_OK)
        return st;
    return write_atomic(path, data, msg, msg_size);
}

/* The half-float report of the given fields (all when fields == NULL) of a table. */
static void table_half_error(const mf_table *t, const int *fields, int nf, mf_half_error *e)
{
    half_error_init(e);
    size_t texels = mf_table_texels(t);
    for (size_t i = 0; i < texels; ++i)
        for (int j = 0; j < (fields ? nf : t->nfields); ++j) {
            int f = fields ? fields[j] : j;
            if (f < 0)
                continue;
            size_t idx = i * (size_t)t->nfields + (size_t)f;
            half_error_add(e, t->data[idx], idx);
        }
}

static mf_status write_exr(const char *path, const mf_table *t, int half, mf_half_error *he, char *msg,
                           size_t msg_size)
{
    size_t count = mf_table_texels(t) * (size_t)t->nfields;
    float *px = NULL;
    uint16_t *hx = NULL;
    if (half)
        hx = malloc(count * sizeof *hx);
    else
        px = malloc(count * sizeof *px);
    if (!px && !hx) {
        set_msg(msg, msg_size, path, "out of memory");
        return MF_ERR_ALLOC;
    }
    for (size_t i = 0; i < count; ++i) {
        if (half)
            hx[i] = mf_half_from_double(t->data[i]);
        else
            px[i] = (float)t->data[i];
    }
    sbuf h = {0};
    header_extra x = {half ? "float16" : "float32", half ? he : NULL, NULL};
    header_string(&h, t, &x);
    if (h.failed) {
        free(px);
        free(hx);
        set_msg(msg, msg_size, path, "out of memory");
        return MF_ERR_ALLOC;
    }
    const char *names[MF_TABLE_MAX_FIELDS];
    for (int f = 0; f < t->nfields; ++f)
        names[f] = t->fields[f];
    const char *an[1] = {"mfkit:table"};
    const char *av[1] = {h.p};
    mf_image img = {t->axes[0].size, t->naxes > 1 ? t->axes[1].size : 1, t->nfields, px};
    mf_image_write_options o;
    memset(&o, 0, sizeof o);
    o.half_float = half;
    o.half_bits = hx;
    o.channel_names = names;
    o.nattribs = 1;
    o.attrib_names = an;
    o.attrib_values = av;
    mf_status st = mf_image_write_ex(path, &img, &o, msg, msg_size);
    free(px);
    free(hx);
    sb_free(&h);
    return st;
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
    return texel_product(sizes, t->naxes) != 0;
}

mf_status mf_table_write(const char *path, const mf_table *t, const mf_table_write_options *opt,
                         mf_half_error *half_out, char *msg, size_t msg_size)
{
    clear_msg(msg, msg_size);
    if (half_out)
        half_error_init(half_out);
    mf_table_write_options o;
    if (opt)
        o = *opt;
    else
        mf_table_write_options_default(&o);
    if (!path || !*path || !table_valid(t)) {
        set_msg(msg, msg_size, path, "invalid argument (NULL or empty path, or an invalid table)");
        return MF_ERR_DOMAIN;
    }
    mf_table_format fmt = o.format != MF_TABLE_FORMAT_UNKNOWN ? o.format : mf_table_format_from_path(path);
    if (fmt == MF_TABLE_FORMAT_UNKNOWN || (unsigned)fmt > MF_TABLE_FORMAT_CSV) {
        set_msg(msg, msg_size, path, "unknown table format (extensions: .exr .dds .h .glsl .hlsl .json .npy .csv)");
        return MF_ERR_UNSUPPORTED;
    }
    if (o.half_float && fmt != MF_TABLE_FORMAT_EXR && fmt != MF_TABLE_FORMAT_DDS) {
        set_msg(msg, msg_size, path, "half floats are stored only in .exr and .dds files, not .%s",
                mf_table_format_name(fmt));
        return MF_ERR_UNSUPPORTED;
    }
    if ((fmt == MF_TABLE_FORMAT_EXR || fmt == MF_TABLE_FORMAT_DDS) && t->naxes > 2) {
        set_msg(msg, msg_size, path, "a .%s image holds at most 2 axes, the table has %d", mf_table_format_name(fmt),
                t->naxes);
        return MF_ERR_UNSUPPORTED;
    }
    char prefix[64];
    if ((fmt == MF_TABLE_FORMAT_C_HEADER || fmt == MF_TABLE_FORMAT_GLSL || fmt == MF_TABLE_FORMAT_HLSL) &&
        !make_prefix(path, o.prefix, prefix, sizeof prefix)) {
        set_msg(msg, msg_size, path, "invalid identifier prefix '%s' (letters, digits, '_', not a leading digit, < 64)",
                o.prefix ? o.prefix : "");
        return MF_ERR_DOMAIN;
    }
    int ch[4];
    if (fmt == MF_TABLE_FORMAT_DDS) {
        for (int c = 0; c < 4; ++c) {
            ch[c] = o.dds_fields_set ? o.dds_fields[c] : (c < t->nfields ? c : -1);
            if (ch[c] < -1 || ch[c] >= t->nfields) {
                set_msg(msg, msg_size, path, "DDS channel %d: field index %d outside [-1, %d]", c, ch[c],
                        t->nfields - 1);
                return MF_ERR_DOMAIN;
            }
            for (int d = 0; d < c; ++d)
                if (ch[c] >= 0 && ch[c] == ch[d]) {
                    set_msg(msg, msg_size, path, "DDS channels %d and %d: the same field '%s'", d, c, t->fields[ch[c]]);
                    return MF_ERR_DOMAIN;
                }
        }
    }
    mf_half_error he;
    half_error_init(&he);
    if (o.half_float)
        table_half_error(t, fmt == MF_TABLE_FORMAT_DDS ? ch : NULL, 4, &he);

    mf_status st = MF_OK;
    sbuf b = {0}, side = {0};
    switch (fmt) {
    case MF_TABLE_FORMAT_EXR: st = write_exr(path, t, o.half_float, &he, msg, msg_size); break;
    case MF_TABLE_FORMAT_DDS: {
        header_extra x = {o.half_float ? "float16" : "float32", o.half_float ? &he : NULL, ch};
        build_dds(&b, t, ch, o.half_float);
        header_string(&side, t, &x);
        if (!side.failed)
            side.len--; /* the sidecar without the terminating NUL */
        st = write_with_sidecar(path, &b, &side, msg, msg_size);
        break;
    }
    case MF_TABLE_FORMAT_NPY: {
        header_extra x = {"float32", NULL, NULL};
        build_npy(&b, t);
        header_string(&side, t, &x);
        if (!side.failed)
            side.len--;
        st = write_with_sidecar(path, &b, &side, msg, msg_size);
        break;
    }
    case MF_TABLE_FORMAT_JSON: build_json(&b, t); st = write_atomic(path, &b, msg, msg_size); break;
    case MF_TABLE_FORMAT_CSV: build_csv(&b, t); st = write_atomic(path, &b, msg, msg_size); break;
    case MF_TABLE_FORMAT_C_HEADER:
        build_c_header(&b, t, prefix, base_name(path));
        st = write_atomic(path, &b, msg, msg_size);
        break;
    case MF_TABLE_FORMAT_GLSL:
    case MF_TABLE_FORMAT_HLSL:
        build_shader(&b, t, prefix, base_name(path), fmt == MF_TABLE_FORMAT_HLSL);
        st = write_atomic(path, &b, msg, msg_size);
        break;
    default: st = MF_ERR_UNSUPPORTED; break;
    }
    sb_free(&b);
    sb_free(&side);
    if (st == MF_OK && half_out && o.half_float)
        *half_out = he;
    return st;
}

/* ---- readers ------------------------------------------------------------------------------- */

/* Parses a sidecar "<path>.json" if it exists: *found = 0 when it does not.  The parsed root is
 * left in *root (jfree it) when found. */
static mf_status read_sidecar(const char *path, jnode *root, int *found, char *msg, size_t msg_size)
{
    *found = 0;
    memset(root, 0, sizeof *root);
    size_t n = strlen(path);
    char *sp = malloc(n + 6);
    if (!sp) {
        set_msg(msg, msg_size, path, "out of memory");
        return MF_ERR_ALLOC;
    }
    snprintf(sp, n + 6, "%s.json", path);
    unsigned char *data;
    size_t len;
    int missing;
    mf_status st = read_whole(sp, path, &data, &len, &missing, msg, msg_size);
    if (st != MF_OK) {
        free(sp);
        return missing ? MF_OK : st;
    }
    char why[200];
    st = jparse((const char *)data, len, root, why, sizeof why);
    free(data);
    if (st != MF_OK) {
        set_msg(msg, msg_size, path, "sidecar %s: %s", base_name(sp), why);
        free(sp);
        return st;
    }
    free(sp);
    *found = 1;
    return MF_OK;
}

static mf_status read_json(const char *path, mf_table *t, mf_table_file_info *info, char *msg, size_t msg_size)
{
    unsigned char *data;
    size_t len;
    mf_status st = read_whole(path, path, &data, &len, NULL, msg, msg_size);
    if (st != MF_OK)
        return st;
    jnode root;
    char why[200];
    st = jparse((const char *)data, len, &root, why, sizeof why);
    free(data);
    if (st != MF_OK) {
        set_msg(msg, msg_size, path, "%s", why);
        return st;
    }
    const jnode *h = jget(&root, "header"), *d = jget(&root, "data");
    if (root.type != JN_OBJ || !h || !d || d->type != JN_ARR) {
        jfree(&root);
        set_msg(msg, msg_size, path, "not an mfkit table: expected an object with \"header\" and \"data\" (an array)");
        return MF_ERR_FORMAT;
    }
    st = header_to_table(h, d->n, 0, t, info, why, sizeof why);
    if (st != MF_OK) {
        jfree(&root);
        set_msg(msg, msg_size, path, "%s", why);
        return st;
    }
    size_t nf = (size_t)t->nfields;
    for (size_t i = 0; i < d->n; ++i) {
        const jnode *r = &d->kids[i];
        if (r->type != JN_ARR || r->n != nf) {
            set_msg(msg, msg_size, path, "data record %zu: expected an array of %zu numbers", i, nf);
            goto bad;
        }
        for (size_t f = 0; f < nf; ++f) {
            const jnode *v = &r->kids[f];
            if (v->type == JN_NUM)
                t->data[i * nf + f] = (double)v->numf;
            else if (v->type == JN_NULL)
                t->data[i * nf + f] = NAN;
            else {
                set_msg(msg, msg_size, path, "data record %zu, field %zu: not a number or null", i, f);
                goto bad;
            }
        }
    }
    jfree(&root);
    return MF_OK;
bad:
    jfree(&root);
    mf_table_free(t);
    return MF_ERR_FORMAT;
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
                    if (v > TEXEL_LIMIT) {
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
    mf_status st = read_whole(path, path, &data, &len, NULL, msg, msg_size);
    if (st != MF_OK)
        return st;
    char why[200];
    npy_header h;
    size_t hl, off;
    if (len < 10 || memcmp(data, "\x93NUMPY", 6) != 0) {
        set_msg(msg, msg_size, path, "not a .npy file (no \\x93NUMPY magic)");
        goto bad;
    }
    if (data[6] == 1) {
        hl = get_u16(data + 8);
        off = 10;
    } else if ((data[6] == 2 || data[6] == 3) && len >= 12) {
        hl = get_u32(data + 8);
        off = 12;
    } else {
        set_msg(msg, msg_size, path, "unsupported .npy version %d.%d", data[6], data[7]);
        goto bad;
    }
    if (hl > len - off) {
        set_msg(msg, msg_size, path, "truncated .npy header (%zu bytes announced, %zu present)", hl, len - off);
        goto bad;
    }
    if (!npy_parse_header((const char *)data + off, hl, &h, why, sizeof why)) {
        set_msg(msg, msg_size, path, "%s", why);
        goto bad;
    }
    off += hl;
    if (strcmp(h.descr, "<f4") != 0 || h.fortran) {
        set_msg(msg, msg_size, path, "unsupported array: dtype '%s'%s (expected '<f4', C order)", h.descr,
                h.fortran ? ", Fortran order" : "");
        goto bad_unsupported;
    }
    if (h.ndim < 1 || h.ndim > MF_TABLE_MAX_AXES + 1) {
        set_msg(msg, msg_size, path, "unsupported shape with %d dimensions (expected 2 to %d)", h.ndim,
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
            set_msg(msg, msg_size, path, "axis %d: size %zu outside [1, 2^20]", k, s);
            goto bad;
        }
        sizes[k] = (int)s;
    }
    if (nf < 1 || nf > MF_TABLE_MAX_FIELDS) {
        set_msg(msg, msg_size, path, "%zu fields per texel (1 to %d supported)", nf, MF_TABLE_MAX_FIELDS);
        goto bad;
    }
    size_t texels = texel_product(sizes, naxes);
    if (texels == 0) {
        set_msg(msg, msg_size, path, "more than 2^32 texels");
        goto bad;
    }
    size_t count = texels * nf;
    if (len - off != count * 4) {
        set_msg(msg, msg_size, path, "%zu data bytes, the shape needs %zu (truncated or corrupt)", len - off,
                count * 4);
        goto bad;
    }
    jnode side;
    int found;
    st = read_sidecar(path, &side, &found, msg, msg_size);
    if (st != MF_OK) {
        free(data);
        return st;
    }
    if (found) {
        st = header_to_table(&side, texels, (int)nf, t, info, why, sizeof why);
        jfree(&side);
        if (st != MF_OK) {
            set_msg(msg, msg_size, path, "sidecar %s.json: %s", base_name(path), why);
            free(data);
            return st;
        }
        int match = (t->naxes == naxes);
        for (int k = 0; match && k < naxes; ++k)
            match = (t->axes[k].size == sizes[k]);
        if (!match) {
            set_msg(msg, msg_size, path, "sidecar %s.json: axes do not match the array shape", base_name(path));
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
        st = generic_table(t, naxes, sizes, (int)nf, np);
        if (st != MF_OK) {
            set_msg(msg, msg_size, path, "%s", st == MF_ERR_ALLOC ? "out of memory" : "invalid shape");
            free(data);
            return st;
        }
    }
    for (size_t i = 0; i < count; ++i)
        t->data[i] = (double)get_f32(data + off + 4 * i);
    free(data);
    return MF_OK;
bad:
    free(data);
    return MF_ERR_FORMAT;
bad_unsupported:
    free(data);
    return MF_ERR_UNSUPPORTED;
}

static mf_status read_dds(const char *path, mf_table *t, mf_table_file_info *info, char *msg, size_t msg_size)
{
    unsigned char *data;
    size_t len;
    mf_status st = read_whole(path, path, &data, &len, NULL, msg, msg_size);
    if (st != MF_OK)
        return st;
    char why[200];
    size_t off = 128;
    int half;
    if (len < 128 || memcmp(data, "DDS ", 4) != 0 || get_u32(data + 4) != 124 || get_u32(data + 76) != 32) {
        set_msg(msg, msg_size, path, "not a DDS file (bad magic or header sizes)");
        goto bad;
    }
    uint32_t height = get_u32(data + 12), width = get_u32(data + 16), flags = get_u32(data + 8),
             depth = get_u32(data + 24);
    uint32_t pf_flags = get_u32(data + 80), fourcc = get_u32(data + 84);
    if (!(pf_flags & 0x4u)) {
        set_msg(msg, msg_size, path, "unsupported DDS pixel format (only RGBA32F and RGBA16F are read)");
        goto bad_unsupported;
    }
    if (fourcc == get_u32((const unsigned char *)"DX10")) {
        if (len < DDS_HEADER_BYTES) {
            set_msg(msg, msg_size, path, "truncated DDS header (%zu bytes)", len);
            goto bad;
        }
        uint32_t fmt = get_u32(data + 128), dim = get_u32(data + 132), misc = get_u32(data + 136),
                 arr = get_u32(data + 140);
        if (fmt != DXGI_R32G32B32A32_FLOAT && fmt != DXGI_R16G16B16A16_FLOAT) {
            set_msg(msg, msg_size, path, "unsupported DXGI format %u (only 2 = R32G32B32A32_FLOAT, 10 = "
                    "R16G16B16A16_FLOAT are read)", (unsigned)fmt);
            goto bad_unsupported;
        }
        if ((dim != 3 && !(dim == 2 && height == 1)) || arr != 1 || (misc & 0x4u)) {
            set_msg(msg, msg_size, path, "unsupported DDS resource (dimension %u, array size %u, misc 0x%x): "
                    "only one 2D texture is read", (unsigned)dim, (unsigned)arr, (unsigned)misc);
            goto bad_unsupported;
        }
        half = (fmt == DXGI_R16G16B16A16_FLOAT);
        off = DDS_HEADER_BYTES;
    } else if (fourcc == 116u || fourcc == 113u) { /* D3DFMT_A32B32G32R32F, D3DFMT_A16B16G16R16F */
        half = (fourcc == 113u);
    } else {
        set_msg(msg, msg_size, path, "unsupported DDS pixel format (FourCC 0x%08x)", (unsigned)fourcc);
        goto bad_unsupported;
    }
    if ((flags & 0x800000u) && depth > 1) {
        set_msg(msg, msg_size, path, "volume DDS textures are not read");
        goto bad_unsupported;
    }
    if (width < 1 || height < 1 || width > (1u << 20) || height > (1u << 20)) {
        set_msg(msg, msg_size, path, "DDS size %u x %u outside [1, 2^20]", (unsigned)width, (unsigned)height);
        goto bad;
    }
    int sizes[2] = {(int)width, (int)height};
    int naxes = height > 1 ? 2 : 1;
    size_t texels = texel_product(sizes, 2);
    size_t bpp = half ? 8 : 16;
    if (texels == 0 || texels > (len - off) / bpp) {
        set_msg(msg, msg_size, path, "%zu data bytes, %u x %u RGBA%s needs %zu (truncated)", len - off,
                (unsigned)width, (unsigned)height, half ? "16F" : "32F", texels * bpp);
        goto bad;
    }
    jnode side;
    int found;
    st = read_sidecar(path, &side, &found, msg, msg_size);
    if (st != MF_OK) {
        free(data);
        return st;
    }
    if (found) {
        /* the sidecar describes the whole table; the file holds 4 of its fields */
        mf_table full;
        mf_table_file_info fi;
        memset(&fi, 0, sizeof fi);
        const jnode *dc = jget(&side, "dds_channels");
        st = header_to_table(&side, texels, 0, &full, &fi, why, sizeof why);
        if (st != MF_OK || !dc || dc->type != JN_ARR || dc->n != 4 || full.naxes > 2 || full.axes[0].size != sizes[0] ||
            (full.naxes == 2 ? full.axes[1].size != sizes[1] : sizes[1] != 1)) {
            if (st == MF_OK)
                snprintf(why, sizeof why, "\"dds_channels\" or the axes do not match the file");
            set_msg(msg, msg_size, path, "sidecar %s.json: %s", base_name(path), why);
            jfree(&side);
            if (st == MF_OK)
                mf_table_free(&full);
            free(data);
            return st == MF_OK || st == MF_ERR_FORMAT ? MF_ERR_FORMAT : st;
        }
        char names[4][MF_TABLE_NAME_LEN];
        const char *np[4];
        for (int c = 0; c < 4; ++c) {
            const jnode *v = &dc->kids[c];
            fi.dds_fields[c] = (v->type == JN_STR) ? mf_table_field(&full, v->str) : -1;
            if (v->type == JN_STR && fi.dds_fields[c] < 0) {
                set_msg(msg, msg_size, path, "sidecar %s.json: DDS channel %d names an unknown field", base_name(path), c);
                jfree(&side);
                mf_table_free(&full);
                goto bad;
            }
            if (fi.dds_fields[c] >= 0)
                snprintf(names[c], sizeof names[c], "%s", full.fields[fi.dds_fields[c]]);
            else
                snprintf(names[c], sizeof names[c], "zero%d", c);
            np[c] = names[c];
        }
        jfree(&side);
        fi.format = MF_TABLE_FORMAT_DDS;
        st = mf_table_create(t, full.naxes, full.axes, 4, np);
        if (st == MF_OK) {
            for (int i = 0; i < full.nmeta; ++i)
                t->meta[i] = full.meta[i];
            t->nmeta = full.nmeta;
        }
        mf_table_free(&full);
        if (st != MF_OK) {
            set_msg(msg, msg_size, path, "sidecar %s.json: %s", base_name(path),
                    st == MF_ERR_ALLOC ? "out of memory" : "channel names clash (a field named zero<c>?)");
            free(data);
            return st == MF_ERR_ALLOC ? st : MF_ERR_FORMAT;
        }
        if (info)
            *info = fi;
    } else {
        const char *np[4] = {"R", "G", "B", "A"};
        st = generic_table(t, naxes, sizes, 4, np);
        if (st != MF_OK) {
            set_msg(msg, msg_size, path, "out of memory");
            free(data);
            return st;
        }
        if (info)
            for (int c = 0; c < 4; ++c)
                info->dds_fields[c] = c;
    }
    for (size_t i = 0; i < texels * 4; ++i)
        t->data[i] = half ? mf_half_to_double(get_u16(data + off + 2 * i)) : (double)get_f32(data + off + 4 * i);
    if (info)
        info->half_float = half;
    free(data);
    return MF_OK;
bad:
    free(data);
    return MF_ERR_FORMAT;
bad_unsupported:
    free(data);
    return MF_ERR_UNSUPPORTED;
}

/* An EXR channel name as a field name: [A-Za-z0-9_] kept, others '_'; "c<j>" if empty or taken. */
static void sanitize_name(const char *in, int j, char *out, size_t size)
{
    size_t n = 0;
    for (; *in && n + 1 < size; ++in)
        out[n++] = (isalnum((unsigned char)*in) || *in == '_') ? *in : '_';
    out[n] = '\0';
    if (n == 0)
        snprintf(out, size, "c%d", j);
}

static mf_status read_exr(const char *path, mf_table *t, mf_table_file_info *info, char *msg, size_t msg_size)
{
    mf_image img;
    mf_image_info ii;
    mf_status st = mf_image_read_ex(path, &img, "mfkit:table", &ii, msg, msg_size);
    if (st != MF_OK)
        return st;
    char why[200];
    int sizes[2] = {img.width, img.height};
    int naxes = img.height > 1 ? 2 : 1;
    size_t texels = texel_product(sizes, 2);
    int perm[MF_TABLE_MAX_FIELDS]; /* field f is channel perm[f] */
    if (img.channels > MF_TABLE_MAX_FIELDS || texels == 0) {
        set_msg(msg, msg_size, path, "%d channels, %d x %d pixels: not a table (at most %d channels)", img.channels,
                img.width, img.height, MF_TABLE_MAX_FIELDS);
        st = MF_ERR_UNSUPPORTED;
        goto done;
    }
    if (info)
        info->half_float = strcmp(ii.pixel_type, "half") == 0;
    if (ii.attrib_value) {
        jnode h;
        st = jparse(ii.attrib_value, strlen(ii.attrib_value), &h, why, sizeof why);
        if (st == MF_OK) {
            int half = info ? info->half_float : 0;
            st = header_to_table(&h, texels, img.channels, t, info, why, sizeof why);
            if (info)
                info->half_float = half; /* what the file stores, whatever the header says */
            jfree(&h);
        }
        if (st != MF_OK) {
            set_msg(msg, msg_size, path, "attribute mfkit:table: %s", why);
            goto done;
        }
        if (t->naxes != naxes && !(t->naxes == 2 && t->axes[1].size == 1)) {
            set_msg(msg, msg_size, path, "attribute mfkit:table: %d axes do not fit a %d x %d image", t->naxes,
                    img.width, img.height);
            mf_table_free(t);
            st = MF_ERR_FORMAT;
            goto done;
        }
        if (t->axes[0].size != img.width) {
            set_msg(msg, msg_size, path, "attribute mfkit:table: axis 0 has %d texels, the image is %d wide",
                    t->axes[0].size, img.width);
            mf_table_free(t);
            st = MF_ERR_FORMAT;
            goto done;
        }
        for (int f = 0; f < t->nfields; ++f) {
            perm[f] = -1;
            for (int c = 0; c < img.channels; ++c)
                if (strcmp(ii.channel_names[c], t->fields[f]) == 0)
                    perm[f] = c;
            if (perm[f] < 0) {
                set_msg(msg, msg_size, path, "attribute mfkit:table: no channel named '%s'", t->fields[f]);
                mf_table_free(t);
                st = MF_ERR_FORMAT;
                goto done;
            }
        }
    } else {
        char names[MF_TABLE_MAX_FIELDS][MF_TABLE_NAME_LEN];
        const char *np[MF_TABLE_MAX_FIELDS];
        for (int c = 0; c < img.channels; ++c) {
            sanitize_name(ii.channel_names[c], c, names[c], sizeof names[c]);
            for (int d = 0; d < c; ++d)
                if (strcmp(names[c], names[d]) == 0)
                    snprintf(names[c], sizeof names[c], "c%d", c);
            np[c] = names[c];
            perm[c] = c;
        }
        st = generic_table(t, naxes, sizes, img.channels, np);
        if (st != MF_OK) {
            set_msg(msg, msg_size, path, "%s", st == MF_ERR_ALLOC ? "out of memory" : "cannot name the channels");
            goto done;
        }
    }
    for (size_t i = 0; i < texels; ++i)
        for (int f = 0; f < t->nfields; ++f)
            t->data[i * (size_t)t->nfields + (size_t)f] = (double)img.pixels[i * (size_t)img.channels + (size_t)perm[f]];
done:
    mf_image_free(&img);
    mf_image_info_free(&ii);
    return st;
}

mf_status mf_table_read(const char *path, mf_table *out, mf_table_file_info *info, char *msg, size_t msg_size)
{
    clear_msg(msg, msg_size);
    if (out)
        memset(out, 0, sizeof *out);
    if (info) {
        memset(info, 0, sizeof *info);
        for (int c = 0; c < 4; ++c)
            info->dds_fields[c] = -1;
    }
    if (!path || !out) {
        set_msg(msg, msg_size, path, "invalid argument (NULL path or table)");
        return MF_ERR_DOMAIN;
    }
    mf_table_format fmt = mf_table_format_from_path(path);
    if (info)
        info->format = fmt;
    mf_status st;
    switch (fmt) {
    case MF_TABLE_FORMAT_JSON: st = read_json(path, out, info, msg, msg_size); break;
    case MF_TABLE_FORMAT_NPY: st = read_npy(path, out, info, msg, msg_size); break;
    case MF_TABLE_FORMAT_DDS: st = read_dds(path, out, info, msg, msg_size); break;
    case MF_TABLE_FORMAT_EXR: st = read_exr(path, out, info, msg, msg_size); break;
    case MF_TABLE_FORMAT_UNKNOWN:
        set_msg(msg, msg_size, path, "unknown table format (readable: .exr .dds .json .npy)");
        return MF_ERR_UNSUPPORTED;
    default:
        set_msg(msg, msg_size, path, ".%s files are written, not read (readable: .exr .dds .json .npy)",
                mf_table_format_name(fmt));
        return MF_ERR_UNSUPPORTED;
    }
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
