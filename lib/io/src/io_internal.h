/* io_internal.h -- private to mfkit_io: the table of format operations and the helpers the
 * format files share (metadata JSON out and in, sidecars, little-endian reads, half reports). */
#ifndef MF_IO_INTERNAL_H
#define MF_IO_INTERNAL_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "mfkit/io/mf_io.h"
#include "mfkit/io/mf_json.h"
#include "mfkit/io/mf_table_io.h"

#define IO_TEXEL_LIMIT ((size_t)1 << 32) /* mf_table_create's limit */
#define IO_TEXELS_ANY ((size_t)-1)        /* io_header_to_table: the count is not known yet */

/* ---- the format operations ----------------------------------------------------------------- */

/* What mf_table_write has checked and prepared for a writer. */
typedef struct io_write_ctx {
    int half_float;            /* store halves (only for formats with IO_CAP_HALF) */
    int ch[4];                 /* IO_CAP_RGBA: the field of each channel R, G, B, A; -1 = zeros */
    const char *prefix;        /* IO_CAP_PREFIX: a valid identifier prefix */
    const mf_half_error *half; /* with half_float: the conversion report (stored in the metadata) */
    int ch_set;                /* ch was chosen (always for IO_CAP_RGBA; IO_CAP_RGBA_OPTIONAL: if given) */
    int zstd_level;            /* KTX2: Zstandard supercompression level, 0 = none */
    int dds_legacy;            /* DDS: the legacy header (FourCC 116/113, data at byte 128) */
} io_write_ctx;

enum {
    IO_CAP_HALF = 1u << 0,     /* can store IEEE binary16 */
    IO_CAP_METADATA = 1u << 1, /* keeps the metadata (in the file, a sidecar or a comment) */
    IO_CAP_SIDECAR = 1u << 2,  /* the metadata goes to "<file>.json" */
    IO_CAP_PREFIX = 1u << 3,   /* source code: needs an identifier prefix */
    IO_CAP_RGBA = 1u << 4,     /* exactly 4 channels chosen from the fields */
    IO_CAP_RGBA_OPTIONAL = 1u << 5 /* all fields, or 4 channels chosen from them (dds_fields_set) */
};

typedef struct io_format_ops {
    mf_table_format id;
    const char *name;              /* mf_table_format_name */
    const char *const *extensions; /* NULL-terminated, without the dot, matched case-insensitively */
    int max_axes;                  /* tables with more axes are refused (MF_ERR_UNSUPPORTED) */
    unsigned caps;                 /* IO_CAP_* */
    /* Writes t (valid, at most max_axes axes) to path atomically. */
    mf_status (*write)(const char *path, const mf_table *t, const io_write_ctx *c, char *msg, size_t msg_size);
    /* NULL for write-only formats.  On failure the dispatcher frees t and clears info. */
    mf_status (*read)(const char *path, mf_table *t, mf_table_file_info *info, char *msg, size_t msg_size);
} io_format_ops;

extern const io_format_ops io_format_exr, io_format_dds, io_format_c_header, io_format_glsl, io_format_hlsl,
    io_format_json, io_format_npy, io_format_csv, io_format_ktx2;

/* ---- small helpers ------------------------------------------------------------------------- */

static inline uint32_t io_get_u32(const unsigned char *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static inline uint16_t io_get_u16(const unsigned char *p) { return (uint16_t)(p[0] | (p[1] << 8)); }

static inline float io_get_f32(const unsigned char *p)
{
    uint32_t u = io_get_u32(p);
    float f;
    memcpy(&f, &u, 4);
    return f;
}

/* The part after the last '/'. */
const char *io_base_name(const char *path);
/* Texel count of the sizes, or 0 if a size is < 1 or the count passes IO_TEXEL_LIMIT. */
size_t io_texel_product(const int *sizes, int n);

/* ---- metadata out -------------------------------------------------------------------------- */

typedef struct io_header_extra {
    const char *storage;       /* "float32" or "float16" */
    const mf_half_error *half; /* NULL: no half report */
    const int *dds_fields;     /* NULL, or the 4 DDS channel fields */
    const mf_table_atlas *atlas; /* NULL, or the 2D atlas an image file stores the table as */
} io_header_extra;

/* The metadata object, pretty-printed; every line after the first starts with `indent`. */
void io_header_json(mf_buf *b, const mf_table *t, const io_header_extra *x, const char *indent);
/* The metadata object and a newline (no NUL). */
void io_header_text(mf_buf *b, const mf_table *t, const io_header_extra *x);
/* Writes data and its sidecar "<path>.json" (the metadata), each atomically, the sidecar first. */
mf_status io_write_with_sidecar(const char *path, const mf_buf *data, const mf_table *t, const io_header_extra *x,
                                char *msg, size_t msg_size);

/* ---- tables of more than two axes in images (EXR, DDS) ------------------------------------- */

/* The image layout of t: for <= 2 axes the table itself (one tile: width = size of axis 0,
 * height = size of axis 1 or 1); for more axes the 2D atlas of mf_table.h, with the layout of t's
 * "atlas" metadata when it has a valid one, else the default (tiles_x = size of axis 2).
 * MF_ERR_UNSUPPORTED (message set) when the atlas would be wider or higher than 65536 texels. */
mf_status io_image_layout(const char *path, const mf_table *t, mf_table_atlas *a, char *msg, size_t msg_size);
/* The texel-major index of the table texel at image pixel `pixel` (row-major, row 0 first) of the
 * layout a, or -1 for a pixel of an unused tile (stored as 0). */
static inline long long io_atlas_texel(const mf_table_atlas *a, size_t pixel)
{
    size_t x = pixel % (size_t)a->width, y = pixel / (size_t)a->width;
    size_t tile = x / (size_t)a->tile_w + (size_t)a->tiles_x * (y / (size_t)a->tile_h);
    if (tile >= (size_t)a->tiles)
        return -1;
    return (long long)(x % (size_t)a->tile_w +
                       (size_t)a->tile_w * (y % (size_t)a->tile_h + (size_t)a->tile_h * tile));
}
/* The metadata h of an image of width x height pixels -> the table (zeroed data) and its image
 * layout: with an "atlas" entry the table's axes must give that atlas of exactly this size,
 * else the table must have at most 2 axes of sizes width (x height).  On failure why gets the
 * reason and the table is zeroed. */
mf_status io_image_header_to_table(const cJSON *h, int width, int height, int nfields_expected, mf_table *t,
                                   mf_table_file_info *info, mf_table_atlas *a, char *why, size_t why_size);

/* ---- metadata in --------------------------------------------------------------------------- */

/* Parses a whole JSON document of len bytes (no NUL inside; trailing whitespace only).  On
 * failure *root is NULL and why holds "JSON: <reason> at line L, column C". */
mf_status io_json_parse(const char *s, size_t len, cJSON **root, char *why, size_t why_size);
/* A number, or one of the strings mf_json_number writes for non-finite values. */
int io_json_double(const cJSON *v, double *out);
/* The metadata object -> a table (axes, fields, meta; zeroed data) and info.  The table must have
 * `texels` texels (unless IO_TEXELS_ANY) and, if nfields_expected > 0, that many fields.  On failure why gets the reason
 * and the table is zeroed. */
mf_status io_header_to_table(const cJSON *h, size_t texels, int nfields_expected, mf_table *t,
                             mf_table_file_info *info, char *why, size_t why_size);
/* A table with generic axes for a file without metadata (see mf_table_read). */
mf_status io_generic_table(mf_table *t, int naxes, const int *sizes, int nfields, const char *const *names);
/* Parses "<path>.json" if it exists (*root NULL when it does not). */
mf_status io_read_sidecar(const char *path, cJSON **root, char *msg, size_t msg_size);

/* ---- generated source (io_source.c) ------------------------------------------------------- */

/* Appends text with every line prefixed by `lead` ("*" "/" pairs broken apart in block comments). */
void io_put_commented(mf_buf *b, const char *text, const char *lead, int block_comment);
/* prefix in upper case into up (up_size >= the prefix's length + 1; prefixes are < 64). */
void io_upper_prefix(char *up, size_t up_size, const char *prefix);
/* One comment line per axis: "<lead>axis k: name, n texels, name in [lo, hi]; mapping", lo and hi
 * with `digits` significant digits. */
void io_put_axes_comment(mf_buf *b, const mf_table *t, const char *lead, int digits);
/* The table's metadata (io_header_text) as comment lines after `lead`; b->failed if it cannot be
 * built. */
void io_put_metadata_comment(mf_buf *b, const mf_table *t, const char *lead, int block_comment);
/* The "tool" metadata if it is a short printable mfkit command, else "mfkit". */
const char *io_generator(const mf_table *t);
/* The lookup functions of the .glsl/.hlsl snippet of t (fmt_shader.c; hlsl 0 or 1), every name
 * prefixed <prefix>_ (and <PREFIX>_ATLAS_* for an atlas): <prefix>_param<k>, _coord0/1, _pos<k>,
 * _tile, _lookup_params(table, p0, ...) (one texture of 4 fields), _lookup(table, physical ...). */
void io_shader_lookup_functions(mf_buf *b, const mf_table *t, const char *prefix, int hlsl);
/* The shortest float literal that reads back as v exactly (io_source.c). */
void io_shader_literal(mf_buf *b, double v);
/* %.9g with a '.' or an exponent, then the suffix ("f" for C). */
void io_float_literal(mf_buf *b, double v, const char *suffix);

/* ---- halves -------------------------------------------------------------------------------- */

void io_half_error_add(mf_half_error *e, double x, size_t index);
/* The report of the given fields (all when fields == NULL; -1 entries skipped). */
void io_table_half_error(const mf_table *t, const int *fields, int nf, mf_half_error *e);

#endif /* MF_IO_INTERNAL_H */
