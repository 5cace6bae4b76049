/*
 * mf_table.h -- n-dimensional regular grids of records with named, self-describing axes.
 *
 * This is the table type the fitters fill and the exporters write (docs/tables.md).
 *
 * Axes.  Axis k has `size` texels.  Texel i of the axis sits at the parameter value
 *     p_i = lo + (hi - lo) * i / (size - 1)              (size >= 2; size 1: p_0 = lo)
 * i.e. the grid points are the texel *centres*: a shader that stores the table in a texture of
 * `size` texels samples it at the texture coordinate  uv = (p - lo)/(hi - lo) * (size - 1)/size
 * + 0.5/size  (mf_table_uv_from_param).  The parameter maps to a physical quantity by the
 * axis' mapping (e.g. u = sqrt(1 - cos theta) -> cos theta = 1 - u^2), with an optional clamp
 * (e.g. alpha = max(r^2, 1e-4)), so a reader of any exported file can recover the exact
 * physical value of every texel from the metadata alone.
 *
 * Records.  Every texel holds `nfields` doubles with names.  Storage is texel-major with the
 * first axis fastest: record (i0, i1, ...) starts at data[(i0 + n0 (i1 + n1 (...))) * nfields].
 * (For a 2D table: index = i0 + n0 * i1; axis 0 is the texture's x/u axis, axis 1 its y/v.)
 *
 * Pure C11; allocation through malloc/free only.
 */
#ifndef MF_TABLE_H
#define MF_TABLE_H

#include <stddef.h>

#include "mfkit/mf_core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Up to 6 axes: the anisotropic LTC table needs 4 (roughness x, roughness y, view theta, view
 * phi), per-level normal-map tables 5; every function here takes any count up to this. */
#define MF_TABLE_MAX_AXES 6
#define MF_TABLE_MAX_FIELDS 32
#define MF_TABLE_NAME_LEN 32
#define MF_TABLE_TEXT_LEN 160
#define MF_TABLE_MAX_META 16

/* How an axis parameter p maps to its physical quantity x. */
typedef enum mf_axis_mapping {
    MF_AXIS_IDENTITY = 0,          /* x = p */
    MF_AXIS_ONE_MINUS_SQUARE = 1,  /* x = 1 - p^2   (u = sqrt(1 - cos theta) -> cos theta) */
    MF_AXIS_SQUARE = 2,            /* x = p^2       (r = roughness -> alpha = r^2) */
    MF_AXIS_COS = 3                /* x = cos(p)    (theta -> cos theta) */
} mf_axis_mapping;

typedef struct mf_table_axis {
    char name[MF_TABLE_NAME_LEN];     /* the parameter's name, e.g. "u" */
    char physical[MF_TABLE_NAME_LEN]; /* the physical quantity's name, e.g. "cos_theta_o" */
    int size;                         /* texels, >= 1 */
    double lo, hi;                    /* parameter at the first and the last texel centre */
    mf_axis_mapping mapping;
    double physical_min;              /* x is clamped to >= physical_min (-INFINITY: no clamp) */
} mf_table_axis;

typedef struct mf_table_meta {
    char key[MF_TABLE_NAME_LEN];
    char value[MF_TABLE_TEXT_LEN];
} mf_table_meta;

typedef struct mf_table {
    int naxes;
    mf_table_axis axes[MF_TABLE_MAX_AXES];
    int nfields;
    char fields[MF_TABLE_MAX_FIELDS][MF_TABLE_NAME_LEN];
    int nmeta;
    mf_table_meta meta[MF_TABLE_MAX_META]; /* free-form provenance: tool, brdf, validated, ... */
    double *data;                          /* texel-major records, owned */
} mf_table;

/* Names and parsing of the mappings ("identity", "one_minus_square", "square", "cos"). */
const char *mf_axis_mapping_name(mf_axis_mapping m);
int mf_axis_mapping_parse(const char *name, mf_axis_mapping *out); /* 0 on success */
/* A human-readable formula of the mapping, e.g. "cos_theta_o = 1 - u^2". */
void mf_axis_describe(const mf_table_axis *a, char *buf, size_t size);

/* Creates a table with zeroed records.  MF_ERR_DOMAIN for bad sizes, names (empty, too long,
 * duplicated, not [A-Za-z0-9_]), ranges (non-finite lo/hi, lo == hi with size > 1), or a
 * mapping outside the enum; MF_ERR_ALLOC.  On failure *t is zeroed. */
mf_status mf_table_create(mf_table *t, int naxes, const mf_table_axis *axes, int nfields,
                          const char *const *field_names) MF_WARN_UNUSED;
void mf_table_free(mf_table *t);
/* A deep copy.  MF_ERR_ALLOC on failure (*dst zeroed). */
mf_status mf_table_copy(mf_table *dst, const mf_table *src) MF_WARN_UNUSED;

/* Number of texels (product of the sizes). */
size_t mf_table_texels(const mf_table *t);
/* Record of the texel with indices idx[0..naxes-1] (no bounds check beyond an assert-free clamp:
 * out-of-range indices return NULL). */
double *mf_table_record(const mf_table *t, const int *idx);
/* Field index by name, or -1. */
int mf_table_field(const mf_table *t, const char *name);
/* Sets (or replaces) a metadata entry; MF_ERR_DOMAIN if the key is invalid or the table full. */
mf_status mf_table_set_meta(mf_table *t, const char *key, const char *value) MF_WARN_UNUSED;
/* The value of a metadata key, or NULL. */
const char *mf_table_get_meta(const mf_table *t, const char *key);

/* Parameter at texel centre i; and the physical quantity there (mapping + clamp). */
double mf_table_axis_param(const mf_table_axis *a, int i);
double mf_table_axis_physical(const mf_table_axis *a, double param);
/* The texture coordinate of a parameter value (texel centres at (i + 0.5) / size), and back. */
double mf_table_uv_from_param(const mf_table_axis *a, double param);
double mf_table_param_from_uv(const mf_table_axis *a, double uv);

/* Multilinear interpolation at axis parameters p[0..naxes-1], clamped to [lo, hi] per axis (the
 * shader's clamp-to-edge).  A coordinate within 8 ulp of a texel centre is that centre, so the
 * lookup returns the stored record exactly at texel centres.  out gets nfields values.
 * MF_ERR_DOMAIN for NaN coordinates. */
mf_status mf_table_lookup(const mf_table *t, const double *p, double *out) MF_WARN_UNUSED;

/* Extremes of a field over the table (NaN-aware: NaNs are counted in *nan_count, may be NULL). */
void mf_table_field_range(const mf_table *t, int field, double *min, double *max, size_t *nan_count);

/* ---- a 2D atlas of a table with more than two axes ------------------------------------------
 *
 * A renderer that cannot sample a texture of 3 or more dimensions stores the table as one 2D
 * texture of tiles.  Axis 0 runs along x within a tile and axis 1 along y (tile_w = size of
 * axis 0, tile_h = size of axis 1; a table of one axis has tile_h = 1); every combination of
 * the further axes (i2, ..., i_{n-1}) is one tile, numbered with axis 2 fastest:
 *     tile = i2 + n2 (i3 + n3 (i4 + ...)),
 * placed at tile column tile % tiles_x, tile row tile / tiles_x.  Atlas texel (x, y), row y
 * from the top (y = 0 first), holds the record of
 *     i0 = x % tile_w, i1 = y % tile_h, tile = (x / tile_w) + tiles_x (y / tile_h);
 * texels of unused tiles (when tiles_x does not divide the tile count) are 0.
 *
 * A shader looks it up (mf_table_atlas_lookup is its C twin, tested against mf_table_lookup):
 * per further axis k, x_k = (p_k - lo_k)/(hi_k - lo_k) (n_k - 1) clamped to [0, n_k - 1],
 * i_k = min(floor(x_k), n_k - 2), w_k = x_k - i_k; over the 2^(naxes - 2) corners it samples the
 * tile of (i_k or i_k + 1) with the hardware's bilinear filter at
 *     atlas uv = ((col + uv0) tile_w / width, (row + uv1) tile_h / height),
 * uv0, uv1 the in-tile coordinates of mf_table_uv_from_param (the parameter clamped to [lo, hi]
 * first, so the filter never reaches a neighbouring tile), and blends the samples with the
 * weights prod_k (w_k or 1 - w_k).  The layout is recorded in the metadata key "atlas"
 * (mf_table_atlas_record) so a reader of an exported file finds it. */
typedef struct mf_table_atlas {
    int tile_w, tile_h;   /* texels of a tile: the sizes of axes 0 and 1 */
    int tiles;            /* number of tiles: the product of the sizes of axes 2.. (1 for <= 2 axes) */
    int tiles_x, tiles_y; /* tile columns and rows: tiles_x * tiles_y >= tiles */
    int width, height;    /* atlas texels: tile_w tiles_x, tile_h tiles_y */
} mf_table_atlas;

/* The atlas of t with tiles_x tile columns (0: the size of axis 2, i.e. one tile row per
 * combination of axes 3..; 1 for a table of <= 2 axes).  MF_ERR_DOMAIN for tiles_x < 0 or an
 * atlas wider or higher than 65536 texels. */
mf_status mf_table_atlas_layout(const mf_table *t, int tiles_x, mf_table_atlas *a) MF_WARN_UNUSED;
/* Writes the atlas texels of t into out[(y * width + x) * nfields + f] (width * height * nfields
 * doubles). */
void mf_table_atlas_fill(const mf_table *t, const mf_table_atlas *a, double *out);
/* Records the layout in t's metadata: key "atlas", value
 * "tiles_x=X tiles_y=Y tile_w=W tile_h=H order=axis2_fastest".  MF_ERR_DOMAIN if the metadata
 * is full. */
mf_status mf_table_atlas_record(mf_table *t, const mf_table_atlas *a) MF_WARN_UNUSED;
/* The layout recorded in t's metadata, checked against t's axes.  MF_ERR_DOMAIN if there is none
 * or it does not fit t. */
mf_status mf_table_atlas_from_meta(const mf_table *t, mf_table_atlas *a) MF_WARN_UNUSED;
/* The shader's lookup of the atlas image (as mf_table_atlas_fill writes it) of a table with
 * t's axes and fields at parameters p[0..naxes-1]: bilinear within a tile, linear across the
 * further axes (see above).  Equals mf_table_lookup up to rounding.  MF_ERR_DOMAIN for NaN
 * coordinates. */
mf_status mf_table_atlas_lookup(const mf_table *t, const mf_table_atlas *a, const double *image, const double *p,
                                double *out) MF_WARN_UNUSED;

#ifdef __cplusplus
}
#endif
#endif /* MF_TABLE_H */
