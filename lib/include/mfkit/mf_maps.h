/*
 * mf_maps.h -- images of slope moments: slopes from height or normal maps, the five LEAN/LEADR
 * moments per texel, and a box-filtered MIP chain in double precision.
 *
 * This is the pure C part of `mfkit maps` (docs/cli.md); the per-texel math is mf_moments.h.
 *
 * Images.  An mf_map is a 2D array of doubles, row-major from the top row, channels interleaved:
 * channel c of texel (i, j) (column i, row j, row 0 at the top) is
 * data[((size_t)j * width + i) * channels + c].
 *
 * Frame.  The tangent frame of every map here is x = +i (columns to the right) and y = up the
 * image (towards row 0), the OpenGL texture convention (v = 1 - row/height).  Slopes are mfkit's
 * height gradients (s_x, s_y) = (dh/dx, dh/dy) = (-n.x/n.z, -n.y/n.z) (docs/conventions.md);
 * LEAN's stored B = n.xy/n.z is -s (docs/math.md, correction C-N4, mf_moments.h).
 *
 * MIP chain.  Level 0 is the input; level k + 1 has size (mf_map_mip_dim(w_k), mf_map_mip_dim(h_k))
 * with mf_map_mip_dim(n) = max(1, floor(n/2)), until 1 x 1 (1 + floor(log2(max(w, h))) levels).
 * Each texel of level k + 1 is the exact area average of level k over its footprint (a box
 * filter): along an axis of n texels reduced to m, output texel i covers the input interval
 * [i n/m, (i + 1) n/m).  For even n that is the usual 2-texel average; for odd n the footprint is
 * 2 + 1/m texels wide and the texels it cuts contribute the fraction they overlap.  The weights of
 * every output texel sum to 1 and every input texel contributes m/n in total, so the mean of
 * each channel over the whole image is the same at every level (up to rounding): moments filter
 * linearly [Olano 2010, Sec. 3.3], so each level holds the moments of its footprint.
 *
 * Height maps.  Slopes by central differences, h scaled by height_scale, texels texel_size
 * apart (both in the same length unit; the slope is dimensionless):
 *   s_x(i, j) = height_scale (h(i + 1, j) - h(i - 1, j)) / (2 texel_size),
 *   s_y(i, j) = height_scale (h(i, j - 1) - h(i, j + 1)) / (2 texel_size)   (y up: row j - 1).
 * Edges: MF_MAP_EDGE_WRAP (periodic, for tiling textures) or MF_MAP_EDGE_CLAMP (one-sided
 * differences (h(1) - h(0)) / texel_size at the first and last texel of a row or column).  An axis
 * of one texel has slope 0.  For h = A sin(w x + p) the central difference is exactly
 * A w cos(w x + p) sinc(w T) with sinc(u) = sin(u)/u: the discretisation scales a sine's slope by
 * sinc(w T) ~ 1 - (w T)^2/6 (tests/test_maps.c uses this).
 *
 * Errors: mf_status; MF_ERR_DOMAIN for invalid arguments (NULL, sizes < 1, non-finite values)
 * with the index of the first offending texel where it applies; MF_ERR_ALLOC.
 *
 * References: [Olano 2010] Olano, Baker. LEAN Mapping. I3D 2010, Eq. 3-6; [Dupuy 2013] Dupuy et al.
 * LEADR Mapping. ACM TOG 32(6) 2013, Sec. 4.1-4.2; [Toksvig 2005] (see mf_moments.h).
 */
#ifndef MF_MAPS_H
#define MF_MAPS_H

#include <stddef.h>

#include "mfkit/mf_moments.h"
#include "mfkit/mf_table.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A multi-channel image of doubles (see the header comment for the layout). */
typedef struct mf_map {
    int width, height, channels; /* >= 1 when allocated */
    double *data;                /* owned; free with mf_map_free */
} mf_map;

/* Channels of a moments map (mf_map_moments_from_slopes): E[x], E[y], E[x^2], E[xy], E[y^2]. */
enum { MF_MAP_MEAN_X = 0, MF_MAP_MEAN_Y = 1, MF_MAP_M_XX = 2, MF_MAP_M_XY = 3, MF_MAP_M_YY = 4, MF_MAP_MOMENTS = 5 };

typedef enum mf_map_edge {
    MF_MAP_EDGE_WRAP = 0, /* periodic: texel -1 is texel n - 1 */
    MF_MAP_EDGE_CLAMP = 1 /* one-sided differences at the border */
} mf_map_edge;

/* Allocates a zeroed width x height x channels map (all >= 1).  MF_ERR_DOMAIN, MF_ERR_ALLOC
 * (also when the size overflows); *m is zeroed on failure. */
mf_status mf_map_alloc(mf_map *m, int width, int height, int channels) MF_WARN_UNUSED;
/* Frees and zeroes; NULL and zeroed maps are accepted. */
void mf_map_free(mf_map *m);

/* Size of the next MIP level along an axis of n >= 1 texels: max(1, n/2) rounded down; 0 for n < 1. */
int mf_map_mip_dim(int n);
/* Number of levels of the full chain down to 1 x 1, level 0 included: 1 + floor(log2(max(w, h)));
 * 0 for a size < 1. */
int mf_map_mip_count(int width, int height);

/* The next MIP level of in by the exact box filter of the header comment; out is allocated
 * (mf_map_mip_dim of each side, same channels) and must be freed by the caller.  Any finite or
 * non-finite values (NaN propagates to the texels whose footprint holds it). */
mf_status mf_map_box_downsample(const mf_map *in, mf_map *out) MF_WARN_UNUSED;

/* Slopes (2 channels s_x, s_y, mfkit sign, y-up frame) of channel `channel` of a height map by
 * central differences (header comment).  height_scale finite, texel_size > 0 and finite.
 * MF_ERR_DOMAIN for invalid arguments or a non-finite height (*bad = its texel index j*w + i,
 * if bad is not NULL); out is allocated on success. */
mf_status mf_map_slopes_from_heights(const mf_map *heights, int channel, double height_scale, double texel_size,
                                     mf_map_edge edge, mf_map *out, size_t *bad) MF_WARN_UNUSED;

/* Slopes (2 channels) of a map of normals (channels 0..2 = n.x, n.y, n.z in the y-up frame, any
 * length): s = (-n.x/n.z, -n.y/n.z) [Dupuy 2013, Sec. 4.1].  MF_ERR_DOMAIN if a normal is not
 * finite or has n.z <= 0 (*bad = its texel index).  out is allocated on success. */
mf_status mf_map_slopes_from_normals(const mf_map *normals, mf_map *out, size_t *bad) MF_WARN_UNUSED;

/* Moments (MF_MAP_MOMENTS channels, order of the MF_MAP_* enum) of a 2-channel slope map: each
 * texel holds mf_moments_from_slope(s_x, s_y) [Olano 2010, Eq. 3-4].  out is allocated. */
mf_status mf_map_moments_from_slopes(const mf_map *slopes, mf_map *out) MF_WARN_UNUSED;

/* The moments of texel (i, j) of a moments map as a struct (for mf_moments_to_gaussian etc.). */
mf_slope_moments mf_map_moments_at(const mf_map *moments, int i, int j);

/* ---- moment maps as tables (the "moment_map" kind of mf_table_kind.h) ---------------------------
 * A level of a moments map becomes an mf_table, so every table exporter writes it: axes
 * "u" = tex_u = (i + 0.5)/w and "v" = tex_v = 1 - (j + 0.5)/h (identity mappings; v runs from the
 * top row down, so record (i, j) of the table is texel (i, j) of the map, the same order), fields
 * mean_x, mean_y, m_xx, m_xy, m_yy (the MF_MAP_* channels), metadata kind = "moment_map",
 * level = the MIP level, slopes = the sign and frame convention.  The values are copied bit
 * for bit. */

/* The table of one level (a moments map of MF_MAP_MOMENTS channels; level >= 0 is recorded in
 * the metadata).  MF_ERR_DOMAIN for another channel count, MF_ERR_ALLOC. */
mf_status mf_map_moments_to_table(const mf_map *moments, int level, mf_table *out) MF_WARN_UNUSED;
/* The tables of a whole MIP chain levels[0 .. nlevels - 1] into out[0 .. nlevels - 1] (one table
 * per level: the levels differ in size).  On failure every table is freed and zeroed. */
mf_status mf_map_chain_to_tables(const mf_map *levels, int nlevels, mf_table *out) MF_WARN_UNUSED;
/* The moments map of a "moment_map" table (the inverse of mf_map_moments_to_table, bit for
 * bit).  MF_ERR_DOMAIN if the table does not have that layout, MF_ERR_ALLOC. */
mf_status mf_map_moments_from_table(const mf_table *t, mf_map *out) MF_WARN_UNUSED;

#ifdef __cplusplus
}
#endif
#endif /* MF_MAPS_H */
