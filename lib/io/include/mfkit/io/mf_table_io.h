/*
 * mf_table_io.h -- write an mf_table to the files renderers and tools read, and read it back.
 *
 * Formats (docs/tables.md has the byte layouts):
 *   .exr   OpenEXR through the image API (mf_image.h: needs the OpenImageIO backend installed,
 *          else MF_ERR_UNSUPPORTED), float32 or half, bitwise the same between runs; axis 0 = width (x), axis 1 = height (y,
 *          row 0 first), 1D tables have height 1; one channel per field, named after it; the
 *          metadata JSON in the string attribute "mfkit:table".  Tables of 3 to 6 axes as their
 *          2D atlas (mf_table_atlas_layout), the layout in the metadata's "atlas" entry.
 *   .dds   DirectDraw Surface with the DX10 header, DXGI_FORMAT_R32G32B32A32_FLOAT (2) or
 *          R16G16B16A16_FLOAT (10), one mip level, the same x/y layout as EXR; 4 channels chosen
 *          from the fields (default the first 4; -1 = a channel of zeros).  DDS has no room for
 *          metadata, so the metadata JSON goes to the sidecar "<file>.dds.json".  Tables of 3 to
 *          6 axes as their 2D atlas, as EXR.
 *          OpenImageIO 2.4 can neither write nor read uncompressed float DDS ("Unsupported
 *          compression type"), so mfkit writes and reads these files itself.
 *   .h     C header: `static const float <prefix>_data[N]`, dimensions as macros and
 *          `static const int` arrays, the metadata in a comment; compiles as C and C++ with
 *          -Wall -Wextra -pedantic.
 *   .glsl, .hlsl  lookup snippets (no data): physical inputs -> axis parameters -> texture
 *          coordinates with the texel-centre mapping, and a lookup of any number of axes
 *          (3 to 6: the atlas, bilinear in a tile and linear across tiles, as
 *          mf_table_atlas_lookup).
 *   .json  {"header": <metadata>, "data": [[record 0], [record 1], ...]}, records in storage
 *          order, each value "%.9g" of its float32 (exact round trip); NaN and infinities as the
 *          strings "NaN", "Infinity", "-Infinity" (the rule of mf_json.h); null and +-1e999, the
 *          older spellings, still read.
 *   .npy   NumPy 1.0 format, dtype '<f4', C order, shape (n_{k-1}, ..., n_1, n_0, nfields), so
 *          a[i1, i0, f] is field f of texel (i0, i1); the metadata JSON in "<file>.npy.json"
 *          (numpy.load refuses extra keys in the .npy header).
 *   .csv   one row per texel: i0,i1,...,<axis parameters>,<physical values>,<fields>; field
 *          values "%.9g" of their float32, axis values "%.17g"; write-only, no other metadata.
 *
 * Metadata.  One JSON object everywhere (the JSON file's "header", the EXR attribute, the
 * sidecars, the C/GLSL/HLSL comments): "format": "mfkit-table", "version": 1, "storage"
 * ("float32" or "float16"), "layout" and "texel_centre" (the conventions in words), "axes"
 * (name, physical, size, lo, hi, mapping, physical_min -- null for no clamp --, and the
 * human-readable "parameterisation" of mf_axis_describe), "fields", "meta" (the table's
 * key/values) and, for half-float files, "half_max_abs_error", "half_max_rel_error",
 * "half_overflow_count", "half_underflow_count" (see mf_half_error).  Numbers of the
 * metadata are printed with %.17g, so they read back bitwise.
 *
 * Data.  Every writer stores float32 ((float)value, round to nearest even) or, with half_float,
 * IEEE binary16 rounded to nearest even directly from the double (one rounding).  Readers give
 * a table whose doubles are those float32 (or half) values exactly.
 *
 * Errors.  Every function that touches a file fills msg (may be NULL) with "path: reason" on
 * failure and the empty string on success.  Writes are atomic (mf_io.h): each file goes to a
 * temporary in its directory, is synced, then renamed over the target; on failure the temporary
 * is removed and the target is neither created nor changed (a full disk gives MF_ERR_IO).  A
 * data file and its sidecar are both written and synced before either is renamed, the sidecar
 * first; only a failing rename between the two (the directory changed under us) leaves a new
 * sidecar beside the old data file.  Corrupt or truncated inputs, and inputs with bytes after the
 * data, give MF_ERR_FORMAT, never a crash.
 *
 * Plain C11; the formats are in lib/io/src/fmt_*.c behind a table of format operations.
 */
#ifndef MF_TABLE_IO_H
#define MF_TABLE_IO_H

#include <stddef.h>
#include <stdint.h>

#include <mfkit/mf_core.h>
#include <mfkit/mf_table.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef enum mf_table_format {
    MF_TABLE_FORMAT_UNKNOWN = 0,
    MF_TABLE_FORMAT_EXR,
    MF_TABLE_FORMAT_DDS,
    MF_TABLE_FORMAT_C_HEADER, /* .h */
    MF_TABLE_FORMAT_GLSL,
    MF_TABLE_FORMAT_HLSL,
    MF_TABLE_FORMAT_JSON,
    MF_TABLE_FORMAT_NPY,
    MF_TABLE_FORMAT_CSV,
    MF_TABLE_FORMAT_KTX2
} mf_table_format;

/* The format of a file name's extension (case-insensitive), or MF_TABLE_FORMAT_UNKNOWN. */
mf_table_format mf_table_format_from_path(const char *path);
/* "exr", "dds", "h", "glsl", "hlsl", "json", "npy", "csv", "ktx2"; "unknown". */
const char *mf_table_format_name(mf_table_format f);
/* Non-zero for the formats mf_table_read reads (EXR, DDS, JSON, NPY, KTX2). */
int mf_table_format_readable(mf_table_format f);

/* ---- IEEE 754 binary16 ------------------------------------------------------------------ */

/* The half nearest to x, ties to even (IEEE 754 roundTiesToEven), as its bit pattern: magnitudes
 * >= 65520 become infinite, magnitudes <= 2^-25 become (signed) zero, half subnormals are rounded
 * as such; NaN gives a quiet NaN of the same sign.  Uses rint, so it assumes the default rounding
 * mode. */
uint16_t mf_half_from_double(double x);
/* The same for a float (exact conversion to double first, so one rounding). */
uint16_t mf_half_from_float(float x);
/* The exact value of a half. */
double mf_half_to_double(uint16_t h);

/* What the float64 -> half conversion of a table did to it, over all values (NaN and infinite
 * inputs are stored as such and left out).  Errors are relative to the table's doubles: the
 * float64 fit when the fitter writes, the values read from the input file when converting. */
typedef struct mf_half_error {
    double max_abs_error;   /* max |half(x) - x|; +inf if a finite value overflowed */
    double max_rel_error;   /* max |half(x) - x| / |x| over x != 0 (1 for a value flushed to zero) */
    size_t worst_rel_index; /* texel-major index (texel * nfields + field) of max_rel_error */
    size_t overflow_count;  /* finite values that became infinite (|x| >= 65520) */
    size_t underflow_count; /* non-zero values that became zero (|x| <= 2^-25) */
    size_t subnormal_count; /* non-zero values stored as half subnormals (|x| < 2^-14): relative
                             * error up to 2^-25 / |x| */
    size_t count;           /* values converted */
} mf_half_error;

/* The conversion errors of n doubles, without writing anything. */
void mf_half_error_of(const double *x, size_t n, mf_half_error *out);

/* ---- writing ---------------------------------------------------------------------------- */

typedef struct mf_table_write_options {
    mf_table_format format; /* MF_TABLE_FORMAT_UNKNOWN: from the path's extension */
    int half_float;         /* EXR, DDS and KTX2: 16-bit halves instead of float32 (other formats:
                             * MF_ERR_UNSUPPORTED) */
    int dds_fields[4];      /* DDS and KTX2: the field of each channel R, G, B, A; -1 = zeros */
    int dds_fields_set;     /* 0: dds_fields ignored; DDS takes the first min(4, nfields) fields,
                             * KTX2 all fields, four per array layer */
    const char *prefix;     /* .h/.glsl/.hlsl identifier prefix ([A-Za-z_][A-Za-z0-9_]*); NULL:
                             * the file name's stem, with other characters replaced by '_' */
    int zstd_level;         /* KTX2: Zstandard supercompression at this level (1..22); 0 = none */
    int dds_legacy;         /* DDS: the legacy header without DX10 extension (FourCC 116 =
                             * A32B32G32R32F or 113 = A16B16G16R16F, data at byte 128), which the
                             * reference LTC code writes and some loaders assume */
} mf_table_write_options;

/* Defaults: format from the extension, float32, first 4 fields to DDS, prefix from the name. */
void mf_table_write_options_default(mf_table_write_options *opt);

/*
 * Write t to path.
 *   t         a table made by mf_table_create (naxes, sizes, names valid; data non-NULL).
 *   opt       NULL for the defaults.
 *   half_out  may be NULL; filled for half-float writes (zeroed otherwise).  The same numbers are
 *             stored in the file's metadata.
 * Returns MF_OK; MF_ERR_DOMAIN (NULL or invalid arguments, bad DDS field index, bad prefix);
 * MF_ERR_UNSUPPORTED (unknown extension; an EXR or DDS atlas (tables of more than 2 axes, see
 * docs/tables.md) wider or higher than 65536 texels; half_float for a format without halves); MF_ERR_IO (the file or its temporary cannot be created, written or
 * renamed); MF_ERR_ALLOC; MF_ERR_INTERNAL (from the OpenImageIO bridge).
 */
mf_status mf_table_write(const char *path, const mf_table *t, const mf_table_write_options *opt,
                         mf_half_error *half_out, char *msg, size_t msg_size) MF_WARN_UNUSED;

/* ---- reading ---------------------------------------------------------------------------- */

/* What mf_table_read learnt about the file beyond the table. */
typedef struct mf_table_file_info {
    mf_table_format format;
    int half_float;        /* the file stores halves */
    int has_metadata;      /* the mfkit metadata was found (else generic axes, see below) */
    int has_half_error;    /* the metadata holds a half-float error report */
    mf_half_error half_error; /* as stored in the metadata (worst_rel_index and counts of
                                 * subnormals are not stored: 0) */
    int dds_fields[4];     /* DDS with metadata: the original field of each channel (-1 = zeros) */
} mf_table_file_info;

/*
 * Read a table written by mf_table_write (EXR, DDS, JSON, NPY; format from the extension).
 *   out   on success a table owned by the caller (mf_table_free); on failure zeroed.
 *   info  may be NULL.
 * Files without mfkit metadata (an EXR from elsewhere, a .npy or .dds without its sidecar) read
 * with generic axes: axis k named "x<k>" (physical "uv<k>", identity mapping) whose parameter is
 * the texture coordinate of the texel centre, lo = 0.5/n, hi = 1 - 0.5/n; fields named after the
 * channels (EXR), "R", "G", "B", "A" (DDS) or "f<j>" (NPY).  A DDS file with metadata gives the
 * 4 channels as fields named after the fields they came from (zero channels as "zero<c>").
 * Returns MF_OK; MF_ERR_DOMAIN (NULL arguments); MF_ERR_UNSUPPORTED (a format that is not read,
 * or unknown extension); MF_ERR_IO (cannot open or read); MF_ERR_FORMAT (malformed, truncated or
 * inconsistent with its metadata: the message says where); MF_ERR_ALLOC.
 */
mf_status mf_table_read(const char *path, mf_table *out, mf_table_file_info *info, char *msg,
                        size_t msg_size) MF_WARN_UNUSED;

#ifdef __cplusplus
}
#endif
#endif /* MF_TABLE_IO_H */
